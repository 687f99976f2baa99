"""Bulldozing-plate scenario: printed measurements, validation, a quick run."""

import math

import pytest

from soilcal.dem.scenarios import bulldozing
from soilcal.errors import InputError


def test_printed_cutting_resistances():
    m = bulldozing.measured()
    # Sec. 4.3: horizontal / vertical ratios 29.31, 6.58, 18.03, 9.97 (line, arc, parabola,
    # bionic)
    for shape, ratio in (("line", 29.31), ("arc", 6.58), ("parabola", 18.03),
                         ("bionic", 9.97)):
        h, v = m[shape]
        assert h / v == pytest.approx(ratio, abs=0.01)


def test_setups_cover_table9():
    assert sorted(s["shape"] for s in bulldozing.setups().values()) == sorted(
        ["line", "arc", "parabola", "bionic"])
    s = bulldozing.setups()["plate-arc"]
    assert (s["depth"], s["speed"], s["duration"]) == (0.030, 0.16, 4.5)


@pytest.mark.parametrize("field,value,match", [
    ("depth", 0.25, "setup.depth"),      # deeper than the bin
    ("speed", 0.0, "setup.speed"),
    ("speed", -1.0, "setup.speed"),
    ("shape", "wavy", "setup.shape"),
])
def test_impossible_settings(field, value, match):
    s = dict(bulldozing.setups()["plate-line"])
    s[field] = value
    with pytest.raises(InputError, match=match):
        bulldozing.validate(s, "paper", "test")
    with pytest.raises(InputError, match=match):
        bulldozing.run(s, bulldozing.paper_params(), "paper", use_cache=False)


def test_quick_bin_shallower_than_cut_fails():
    s = dict(bulldozing.setups()["plate-line"], depth=0.07)
    with pytest.raises(InputError, match="setup.depth"):
        bulldozing.validate(s, "quick", "test")


@pytest.mark.slow
def test_quick_run_resists_motion(tmp_path, monkeypatch):
    monkeypatch.setenv("SOILCAL_SCENARIO_CACHE", str(tmp_path))
    res = bulldozing.run(bulldozing.setups()["plate-line"], bulldozing.paper_params(), "quick",
                         seed=0, threads=1, vtk_dir=tmp_path / "vtk")
    assert len(list((tmp_path / "vtk").glob("*.vtu"))) == 5
    assert len(list((tmp_path / "vtk").glob("*.vtp"))) == 5
    r = res.responses
    assert all(math.isfinite(r[k]) for k in ("horizontal_force_N", "vertical_force_N",
                                             "horizontal_force_sd_N"))
    assert r["horizontal_force_N"] > 0
    assert r["horizontal_force_sd_N"] >= 0
    # same soil, other plate and soil-steel friction: the settled bin is reused
    res2 = bulldozing.run(bulldozing.setups()["plate-arc"],
                          bulldozing.paper_params().replace(soil_steel_static_friction=0.3),
                          "quick", seed=0, threads=1)
    assert res2.responses["bin_from_cache"] and not r["bin_from_cache"]
    # VTK frames split the pass into chunks; the forces do not depend on it
    res3 = bulldozing.run(bulldozing.setups()["plate-line"], bulldozing.paper_params(), "quick",
                          seed=0, threads=1)
    assert res3.responses["horizontal_force_N"] == pytest.approx(r["horizontal_force_N"],
                                                                 rel=1e-9)
