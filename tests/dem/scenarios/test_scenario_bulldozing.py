"""Bulldozing-plate scenario: printed measurements, validation, a quick run."""

import math

import numpy as np
import pytest

from soilcal.dem.scenarios import bulldozing
from soilcal.dem.scenarios.soilbin import BinSpec, fill_bin, psd_field
from soilcal.errors import InputError


def test_paper_preset_uses_printed_mass_split():
    # Sec. 3.1: sizes 3, 2, 1 mm (read as diameters) with 8.85, 8.2, 82.95 % of the mass
    s = bulldozing._settings(bulldozing.setups()["plate-line"], "paper")
    psd = bulldozing.size_distribution(s)
    assert psd.lower == psd.upper == pytest.approx((0.0015, 0.0010, 0.0005))
    assert psd.mass_fraction == pytest.approx((0.0885, 0.0820, 0.8295))
    spec = bulldozing._bin(s)
    assert (spec.r_min, spec.r_max) == pytest.approx((0.0005, 0.0015))
    # the quick preset keeps uniform radii (7 mm, 0.9-1.1)
    q = bulldozing._bin(bulldozing._settings(bulldozing.setups()["plate-line"], "quick"))
    assert q.psd is None and (q.r_min, q.r_max) == pytest.approx((0.0063, 0.0077))


def test_psd_bin_fill_has_the_printed_mass_split():
    # the paper's distribution, three times coarser so that the fill stays small
    s = bulldozing._settings(bulldozing.setups()["plate-line"], "paper")
    psd = bulldozing.size_distribution(s).scaled(3.0)
    spec = BinSpec(0.06, 0.04, 0.03, 0.002, psd=psd_field(psd))
    x, r = fill_bin(spec, np.random.default_rng(0), "test")
    m = r**3
    # each size is filled to the nearest particle: every bin's mass is off by at most one
    # of its particles, so a fraction is off by at most one particle of every size
    tol = sum(rk**3 for rk in psd.lower) / m.sum()
    for rk, fk in zip(psd.lower, psd.mass_fraction):
        assert m[np.isclose(r, rk)].sum() / m.sum() == pytest.approx(fk, abs=tol)
    # no overlaps
    d = np.linalg.norm(x[:, None, :] - x[None, :, :], axis=2) + np.eye(len(r))
    assert np.all(d >= (r[:, None] + r[None, :]) * (1 - 1e-9))


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


@pytest.mark.parametrize("preset,depth", [("quick", 0.015), ("paper", 0.0029)])
def test_cut_shallower_than_a_particle_diameter_fails(preset, depth):
    # quick: 2 r_max = 2 x 7.7 mm; paper: 2 r_max = 3 mm (largest printed size)
    s = dict(bulldozing.setups()["plate-line"], depth=depth)
    with pytest.raises(InputError, match="setup.depth"):
        bulldozing.validate(s, preset, "test")
    bulldozing.validate(dict(s, depth=0.0155 if preset == "quick" else 0.0031), preset, "t")


@pytest.mark.slow
def test_quick_run_resists_motion(tmp_path, monkeypatch):
    """The quick preset on a 0.1 m pass (the preset's is 0.2 m): over seeds 0-2 the plate
    line's stable-stage horizontal force was 23.6-34.0 N (SD over the stage 9.6-12.2 N)."""
    monkeypatch.setenv("SOILCAL_SCENARIO_CACHE", str(tmp_path))

    def setup(name):
        return dict(bulldozing.setups()[name], travel=0.1, overrides=["travel"])

    res = bulldozing.run(setup("plate-line"), bulldozing.paper_params(), "quick",
                         seed=0, threads=1, vtk_dir=tmp_path / "vtk")
    assert res.setup["travel"] == 0.1
    assert len(list((tmp_path / "vtk").glob("*.vtu"))) == 5
    assert len(list((tmp_path / "vtk").glob("*.vtp"))) == 5
    r = res.responses
    assert all(math.isfinite(r[k]) for k in ("horizontal_force_N", "vertical_force_N",
                                             "horizontal_force_sd_N"))
    assert r["horizontal_force_N"] > 0
    # same soil, other plate and soil-steel friction: the settled bin is reused
    res2 = bulldozing.run(setup("plate-arc"),
                          bulldozing.paper_params().replace(soil_steel_static_friction=0.3),
                          "quick", seed=0, threads=1)
    assert res2.responses["bin_from_cache"] and not r["bin_from_cache"]
    # VTK frames split the pass into chunks; the forces do not depend on it
    res3 = bulldozing.run(setup("plate-line"), bulldozing.paper_params(), "quick",
                          seed=0, threads=1)
    assert res3.responses["horizontal_force_N"] == pytest.approx(r["horizontal_force_N"],
                                                                 rel=1e-9)


def test_tool_step_respects_the_damped_soil_steel_bound():
    """A heavily damped soil-steel contact (restitution 0.2, as a calibrated set may have)
    lowers the damped-contact bound of the tool's contacts below the settling step: the tool
    pass must step within it (the engine refuses a step above the bound)."""
    from soilcal.dem.engine import Simulation
    from soilcal.dem.scenarios import soilbin
    from soilcal.dem.scenarios.base import build_materials, contact_model

    s = bulldozing._settings(bulldozing.setups()["plate-arc"], "quick")
    spec = bulldozing._bin(s)
    params = bulldozing.paper_params().replace(soil_steel_restitution=0.2, soil_soil_restitution=0.6)
    settle_dt, tool_dt = soilbin.soil_time_step(spec, params), soilbin.tool_time_step(spec, params)
    assert tool_dt < settle_dt
    mats = build_materials(params, spec.stiffness_scale, "t", spec.cohesion_scale)
    sim = Simulation(mats, dt=tool_dt, contact_model=contact_model(params), max_overlap=spec.max_overlap)
    sim.add_particles(np.array([[0.0, 0.0, spec.r_min]]), np.array([spec.r_min]), "soil")
    sim.add_plane((0, 0, 0), (0, 0, 1), "steel")
    sim.run(1)
    assert sim.dt == tool_dt
    with pytest.raises(InputError, match="damped-contact bound"):
        over = Simulation(mats, dt=settle_dt, contact_model=contact_model(params), max_overlap=spec.max_overlap)
        over.add_particles(np.array([[0.0, 0.0, spec.r_min]]), np.array([spec.r_min]), "soil")
        over.add_plane((0, 0, 0), (0, 0, 1), "steel")
        over.run(1)
