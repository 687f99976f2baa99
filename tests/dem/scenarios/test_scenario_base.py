"""Scenario base: parameter names and ranges, stiffness scaling, result rows, statistics."""

import csv
import math

import numpy as np
import pytest

from soilcal.dem.materials import P_ESTAR, P_GSTAR, P_MUR, P_MUS, P_W
from soilcal.dem.scenarios import SCENARIOS, get
from soilcal.dem.scenarios.base import (PRESETS, DemParams, Result, build_materials, check,
                                        combine_replicates, merge_setup, rng, run_replicates,
                                        stable_mean, stage_params, write_row)
from soilcal.errors import InputError


def test_names_follow_pair_and_kind():
    names = DemParams.names()
    for pair in ("soil_soil", "soil_steel"):
        for kind in ("restitution", "static_friction", "rolling_friction", "surface_energy"):
            assert f"{pair}_{kind}" in names
    p = DemParams()
    assert (p.steel_density, p.steel_poisson, p.steel_shear_modulus) == (7850.0, 0.3, 7.9e10)
    assert PRESETS == ("quick", "paper")


def test_from_mapping_rejects_unknown_and_out_of_range():
    with pytest.raises(InputError) as e:
        DemParams.from_mapping({"soil_soil_rolling": 0.1}, "cfg.yaml")
    assert e.value.path == "cfg.yaml" and e.value.field == "params.soil_soil_rolling"
    with pytest.raises(InputError, match="restitution"):
        DemParams.from_mapping({"soil_soil_restitution": 1.5}, "cfg.yaml")
    with pytest.raises(InputError, match="params.soil_poisson"):
        DemParams.from_mapping({"soil_poisson": 0.5}, "cfg.yaml")
    with pytest.raises(InputError, match="a number"):
        DemParams.from_mapping({"soil_density": "heavy"}, "cfg.yaml")
    p = DemParams.from_mapping({"soil_soil_rolling_friction": "0.2"}, "cfg.yaml")
    assert p.soil_soil_rolling_friction == 0.2
    assert p.as_dict()["soil_soil_static_friction"] == DemParams().soil_soil_static_friction


def test_stiffness_scaling_and_surface_energy_rule():
    p = DemParams(soil_soil_surface_energy=0.5, soil_steel_surface_energy=0.2)
    t1 = build_materials(p, 1.0).table(1.0)
    s = 0.01
    ts = build_materials(p, s).table(1.0)
    # G* and E* scale with s; w = gamma (G_mod/G)^(2/5) (vineyard paper, Eq. 6)
    for i, j in ((0, 0), (0, 1)):
        assert ts[i, j, P_GSTAR] == pytest.approx(s * t1[i, j, P_GSTAR], rel=1e-12)
        assert ts[i, j, P_ESTAR] == pytest.approx(s * t1[i, j, P_ESTAR], rel=1e-12)
        assert ts[i, j, P_W] == pytest.approx(t1[i, j, P_W] * s**0.4, rel=1e-12)
    assert t1[0, 0, P_W] == 0.5 and t1[0, 1, P_W] == 0.2
    assert t1[0, 1, P_MUS] == p.soil_steel_static_friction
    assert t1[0, 0, P_MUR] == p.soil_soil_rolling_friction
    with pytest.raises(InputError, match="stiffness_scale"):
        build_materials(p, 0.0)


def test_result_row_and_atomic_write(tmp_path):
    res = Result("repose", "quick", 3, 100, 2000, 0.5, 1.25, 1, params=DemParams().as_dict(),
                 setup=dict(tube_diameter=0.06, method="cylinder", psd=[1, 2], none=None),
                 responses=dict(angle_deg=np.float64(31.5)), series=dict(t=np.arange(3)))
    row = res.row()
    assert row["p:soil_soil_restitution"] == DemParams().soil_soil_restitution
    assert row["s:tube_diameter"] == 0.06 and row["s:method"] == "cylinder"
    assert "s:psd" not in row  # non-scalar setup values stay out of the row
    assert row["r:angle_deg"] == 31.5 and type(row["r:angle_deg"]) is float
    out = write_row(tmp_path / "sub" / "row.csv", res)
    rows = list(csv.DictReader(open(out)))
    assert len(rows) == 1 and float(rows[0]["r:angle_deg"]) == 31.5
    assert rows[0]["seed"] == "3"
    assert [p.name for p in (tmp_path / "sub").iterdir()] == ["row.csv"]  # no temp file left


def _run_result(seed, angle, settled, reason, params=None, peak=0.1):
    return Result("compression", "quick", seed, 100 + seed, 1000, 0.5, 2.0, 1,
                  params=params or DemParams().as_dict(), setup=dict(tube_diameter=0.1),
                  responses=dict(angle_deg=angle, settled=settled, stop_reason=reason,
                                 peak_overlap=peak),
                  series=dict(t=np.arange(2) + seed))


def test_replicates_are_averaged_with_their_standard_deviation(tmp_path):
    runs = [_run_result(4, 30.0, 1, "max_strain", peak=0.12),
            _run_result(5, 31.0, 1, "max_strain", peak=0.31),
            _run_result(6, 35.0, 0, "overlap", peak=0.2)]
    res = combine_replicates(runs)
    assert res.responses["peak_overlap"] == 0.31  # the largest peak, not the mean 0.21
    # mean of 30, 31, 35 is 32; deviations -2, -1, 3: s^2 = (4 + 1 + 9) / 2 = 7
    assert res.responses["angle_deg"] == pytest.approx(32.0, abs=1e-12)
    assert res.responses["angle_deg_rep_sd"] == pytest.approx(math.sqrt(7.0), rel=1e-12)
    assert res.responses["settled"] == pytest.approx(2.0 / 3.0)
    assert res.responses["stop_reason"] == "max_strain|overlap"
    assert res.seed == 4 and res.n_particles == 105 and res.steps == 3000
    assert res.wall_s == pytest.approx(6.0) and res.sim_time_s == pytest.approx(1.5)
    assert res.setup["replicates"] == 3 and res.setup["replicate_seeds"] == "4 5 6"
    assert [r["seed"] for r in res.per_run] == [4, 5, 6] and res.per_run[2]["angle_deg"] == 35.0
    assert sorted(res.series) == ["seed4:t", "seed5:t", "seed6:t"]
    row = list(csv.DictReader(open(write_row(tmp_path / "row.csv", res))))[0]
    assert float(row["r:angle_deg"]) == 32.0 and row["s:replicate_seeds"] == "4 5 6"
    other = _run_result(7, 30.0, 1, "x", params=DemParams(soil_density=1500.0).as_dict())
    with pytest.raises(InputError, match="differ only in the seed"):
        combine_replicates([runs[0], other])
    # a setup value derived per run (the time step from the smallest sphere) is averaged;
    # a text setup value that differs means another setup
    a, b = _run_result(8, 30.0, 1, "x"), _run_result(9, 31.0, 1, "x")
    a.setup, b.setup = dict(method="cylinder", dt=1e-4), dict(method="cylinder", dt=2e-4)
    assert combine_replicates([a, b]).setup["dt"] == pytest.approx(1.5e-4)
    b.setup = dict(method="funnel", dt=1e-4)
    with pytest.raises(InputError, match="differ only in the seed"):
        combine_replicates([a, b])
    with pytest.raises(InputError, match="distinct seeds"):
        combine_replicates([runs[0], runs[0]])
    with pytest.raises(InputError, match="at least two runs"):
        combine_replicates(runs[:1])


def test_run_replicates_uses_consecutive_seeds(tmp_path):
    calls = []

    class Fake:
        @staticmethod
        def run(setup, params, preset, seed, threads, vtk_dir):
            calls.append((seed, vtk_dir))
            return _run_result(seed, 10.0 * seed, 1, "max_strain")

    one = run_replicates(Fake, {}, DemParams(), seed=3, vtk_dir=tmp_path)
    assert calls == [(3, tmp_path)] and one.responses["angle_deg"] == 30.0
    assert "angle_deg_rep_sd" not in one.responses
    calls.clear()
    res = run_replicates(Fake, {}, DemParams(), seed=3, replicates=2, vtk_dir=tmp_path)
    assert calls == [(3, tmp_path / "seed3"), (4, tmp_path / "seed4")]
    assert res.responses["angle_deg"] == 35.0
    assert res.responses["angle_deg_rep_sd"] == pytest.approx(math.sqrt(50.0))
    for bad in (0, 1.5, True):
        with pytest.raises(InputError, match="replicates"):
            run_replicates(Fake, {}, DemParams(), replicates=bad, source="soil.yaml")


def test_stage_params_map_a_design_row_to_dem_parameters():
    from pathlib import Path

    from soilcal.config.load import load_soil

    root = Path(__file__).resolve().parents[3]
    soil = load_soil(root / "config/soils/xinjiang-vineyard.yaml", root / "resources")
    # 003 Table 7 run 22: B 0.63, D 0.08, F 0.5, H 0.1; fixed (Sec. Steepest Ascent Test):
    # G 10 MPa, soil-soil mu 0.68, soil-steel e 0.45, soil-steel mu_r 0.30; Table 2:
    # Poisson 0.33, density 175.7567 (as printed)
    p = stage_params(soil, "bbd", dict(B=0.63, D=0.08, F=0.5, H=0.1))
    assert p.soil_soil_restitution == 0.63 and p.soil_soil_rolling_friction == 0.08
    assert p.soil_steel_static_friction == 0.5 and p.soil_soil_surface_energy == 0.1
    assert p.soil_shear_modulus == 1.0e7  # 10 MPa
    assert p.soil_soil_static_friction == 0.68 and p.soil_steel_restitution == 0.45
    assert p.soil_steel_rolling_friction == 0.30
    assert p.soil_poisson == 0.33 and p.soil_density == 175.7567
    assert p.soil_steel_surface_energy == 0.0  # not a parameter of that study
    with pytest.raises(InputError, match="stages.bbd.factors"):
        stage_params(soil, "bbd", dict(Z=1.0))
    with pytest.raises(InputError, match=r"stages\.bbd\.factors\.B: expected a coefficient of restitution"):
        stage_params(soil, "bbd", dict(B=1.5))
    # coded Plackett-Burman levels decode to the Table 2 range ends: B 0.15-0.75, H 0.1-0.3
    lo = stage_params(soil, "pb", dict(B=-1, H=-1), coded=True)
    hi = stage_params(soil, "pb", dict(B=1, H=1), coded=True)
    assert (lo.soil_soil_restitution, hi.soil_soil_restitution) == pytest.approx((0.15, 0.75))
    assert (lo.soil_soil_surface_energy, hi.soil_soil_surface_energy) == pytest.approx((0.1, 0.3))
    # a unit the mapping does not know is an error naming the entry
    import copy

    from soilcal.config.load import Soil

    data = copy.deepcopy(soil.data)
    data["parameters"]["soil_shear_modulus"]["unit"] = "psi"
    with pytest.raises(InputError, match=r"parameters\.soil_shear_modulus\.unit"):
        stage_params(Soil(soil.path, data, soil.resources_root), "bbd", {})


def test_stable_mean_of_a_known_signal():
    t = np.linspace(0, 2, 201)
    y = np.where(t < 0.5, 10 * t, 5.0 + np.sin(2 * np.pi * 10 * t))
    m, sd = stable_mean(t, y, 0.5, 1.5)
    # ten full periods of a unit sine on [0.5, 1.5] (101 samples, ends equal)
    assert m == pytest.approx(5.0, abs=1e-9)
    # sample SD (ddof = 1): sum of sin^2 over the 101 samples is 50, over n - 1 = 100
    assert sd == pytest.approx(math.sqrt(50 / 100), rel=1e-9)
    with pytest.raises(InputError, match="t_start"):
        stable_mean(t, y, 3.0)


def test_check_rng_and_merge_setup():
    with pytest.raises(InputError) as e:
        check(False, "run.yaml", "setup.fill_fraction", "<= 1", 1.2)
    assert str(e.value) == "run.yaml: setup.fill_fraction: expected <= 1, got 1.2"
    a = rng(7, "repose").uniform(size=3)
    assert np.array_equal(a, rng(7, "repose").uniform(size=3))
    assert not np.array_equal(a, rng(8, "repose").uniform(size=3))
    assert not np.array_equal(a, rng(7, "drum").uniform(size=3))
    with pytest.raises(InputError, match="seed"):
        rng(-1)
    s = merge_setup({"a": {"x": 1}}, "a", {"x": 2}, "cli")
    # the keys the user set are recorded, so presets never replace them
    assert s == {"x": 2, "name": "a", "overrides": ["x"]}
    assert merge_setup({"a": {"x": 1}}, "a", None, "cli") == {"x": 1, "name": "a"}
    with pytest.raises(InputError, match="setup.y"):
        merge_setup({"a": {"x": 1}}, "a", {"y": 2}, "cli")
    with pytest.raises(InputError, match="setup"):
        merge_setup({"a": {"x": 1}}, "b", {}, "cli")


def test_registry_and_named_setups_validate():
    for name in ("repose", "drum", "incline", "compression"):
        mod = SCENARIOS[name]
        assert mod.NAME == name
        for sname, setup in mod.setups().items():
            for preset in PRESETS:
                mod.validate(dict(setup, name=sname), preset, "test")
    with pytest.raises(InputError, match="scenario"):
        get("no-such-scenario")
    for mod in set(SCENARIOS.values()):  # what a soil may measure is a response of the run
        assert set(mod.MEASURES) <= set(mod.RESPONSES), mod.NAME


def test_sauter_radius_of_the_size_distributions():
    from soilcal.dem.factories import PSD, UniformRadius
    from soilcal.dem.scenarios.base import sauter_radius

    a, b = 1.0e-3, 3.0e-3
    # uniform by number: <r^3>/<r^2> = (b^4 - a^4)/4 / ((b^3 - a^3)/3)
    assert sauter_radius(UniformRadius(a, b)) == pytest.approx(
        3 * (b**4 - a**4) / (4 * (b**3 - a**3)), rel=1e-14)
    assert sauter_radius(UniformRadius(a, a)) == a
    # discrete sizes with mass fractions f: r32 = 1 / sum(f / r)
    d = PSD((1e-3, 2e-3), (1e-3, 2e-3), (0.25, 0.75))
    assert sauter_radius(d) == pytest.approx(1 / (0.25 / 1e-3 + 0.75 / 2e-3), rel=1e-14)
    # a bin [a, b] as the factory draws it: compare with a large seeded sample
    binned = PSD((a,), (b,), (1.0,))
    r = binned.sample_iid(400_000, np.random.default_rng(1))
    assert sauter_radius(binned) == pytest.approx((r**3).sum() / (r**2).sum(), rel=5e-3)


def test_cohesion_scale_follows_the_particle_size():
    from soilcal.dem.factories import UniformRadius
    from soilcal.dem.scenarios.base import cohesion_scale

    model, ref = UniformRadius(2.7e-3, 3.3e-3), UniformRadius(0.9e-3, 1.1e-3)
    assert cohesion_scale(model, ref) == pytest.approx(3.0, rel=1e-12)
    assert cohesion_scale(model, ref, dict(scale_cohesion=False)) == 1.0
    assert cohesion_scale(model, None) == 1.0
    with pytest.raises(InputError, match="setup.scale_cohesion"):
        cohesion_scale(model, ref, dict(scale_cohesion="yes"), "s.yaml")
    p = DemParams()
    w = build_materials(p, 0.1, "t", cohesion_scale=3.0).table(1.0)[0, 0, P_W]
    assert w == pytest.approx(p.soil_soil_surface_energy * 0.1**0.4 * 3.0, rel=1e-12)
    with pytest.raises(InputError, match="cohesion_scale"):
        build_materials(p, 1.0, "t", cohesion_scale=0.0)


@pytest.mark.parametrize("name, setup", [
    ("repose", "cinnamon-soil"), ("repose", "xinjiang-vineyard-40mm"),
    ("drum", "xinjiang-vineyard"), ("compression", "guangxi-cohesive")])
@pytest.mark.parametrize("n", [None, 1000, 2500])
def test_a_quick_fill_holds_the_requested_number_of_spheres(name, setup, n):
    """A fill of volume V split into N spheres of radii uniform on [0.9, 1.1] r_q has
    N <v> = phi V with <v> = 4/3 pi <r^3>, <r^3> = r_q^3 (1.1^4 - 0.9^4) / 0.8 = 1.01 r_q^3
    (not r_q^3): the count comes out as asked (1000 by default), not 1 % short."""
    mod = get(name)
    s = dict(mod.setups()[setup], n_particles=n)
    sz = mod.sizing(s, "quick")
    rq = 0.5 * (sz["dist"].r_min + sz["dist"].r_max)
    assert sz["dist"].r_min == pytest.approx(0.9 * rq) and sz["r_max"] == pytest.approx(1.1 * rq)
    assert sz["n"] == (n or 1000)
    assert sz["dist"].mean_volume() == pytest.approx(4 / 3 * math.pi * 1.01 * rq ** 3, rel=1e-12)
