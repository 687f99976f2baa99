"""Response sources (soilcal.chain.sources): DEM point specs, seeds, gathering run rows into a
response table, comparison with the printed table; and the regression's refusal of a table
with too few points (soilcal.chain.stage._enough_points).

No DEM run: the run rows are frames built by hand in the layout of ``RUN_COLUMNS``.
"""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from soilcal.chain.sources import (
    RUN_COLUMNS,
    design_points,
    gather_runs,
    point_seeds,
    point_spec,
    printed_comparison,
    published_responses,
    simulate,
    soil_with_stage,
)
from soilcal.chain.stage import _enough_points, design_frame, fit_stage
from soilcal.config.load import load_soil
from soilcal.errors import InputError

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def cinnamon():
    return load_soil(ROOT / "config" / "soils" / "cinnamon-soil.yaml", ROOT / "resources")


@pytest.fixture(scope="module")
def vineyard():
    return load_soil(ROOT / "config" / "soils" / "xinjiang-vineyard.yaml", ROOT / "resources")


# --------------------------------------------------------------------------- seeds


def test_point_seeds_are_distinct_per_point_and_replicate():
    pts = [(1, {"A": 0.0, "B": 0.0}), (2, {"A": 1.0, "B": 0.0}), (3, {"A": 0.0, "B": 0.0}),
           (4, {"A": 0.0, "B": 0.0}), (5, {"A": 1.0, "B": 0.0})]
    # point k (in design order) starts at seed + replicates * k: its replicates run the next seeds
    assert point_seeds(pts, 100, replicates=3) == {1: 100, 2: 103, 3: 106, 4: 109, 5: 112}
    assert point_seeds(pts, 100) == {1: 100, 2: 101, 3: 102, 4: 103, 5: 104}
    seeds = point_seeds(pts, 100, replicates=3)
    used = [s + k for s in seeds.values() for k in range(3)]
    assert len(set(used)) == len(used)


def test_every_point_of_the_cinnamon_bbd_draws_its_own_packing(cinnamon):
    stage = cinnamon.stage("bbd")
    design, _ = design_frame(stage, None)
    pts = design_points(stage, design)
    assert len(pts) == 17  # 12 edge midpoints + 5 centre points (Table 6)
    seeds = point_seeds(pts, 1082, replicates=2)
    assert sorted(seeds.values()) == list(range(1082, 1082 + 2 * 17, 2))


# --------------------------------------------------------------------------- design points


def test_design_points_steepest_and_bbd():
    steep = {"kind": "steepest_ascent", "factors": {"A": {}, "B": {}}}
    design = pd.DataFrame({"step": [1, 2, 3], "A": [0.05, 0.08, 0.11], "B": [0.1, 0.24, 0.38]})
    assert design_points(steep, design) == [(1, {"A": 0.05, "B": 0.1}), (2, {"A": 0.08, "B": 0.24}),
                                            (3, {"A": 0.11, "B": 0.38})]
    bbd = {"kind": "box_behnken", "factors": {"A": {}, "B": {}}}
    # coded columns are ignored: the point is at its actual levels
    design = pd.DataFrame({"run": [4, 9], "A": [-1, 0], "B": [1, 0],
                           "A_actual": [0.08, 0.11], "B_actual": [0.52, 0.38]})
    assert design_points(bbd, design) == [(4, {"A": 0.08, "B": 0.52}), (9, {"A": 0.11, "B": 0.38})]


# --------------------------------------------------------------------------- gathering runs


def _run_rows(run: int, rows: list[dict]) -> pd.DataFrame:
    base = {c: "" for c in RUN_COLUMNS} | {"soil": "s", "stage": "st", "run": run, "seed": 100, "replicates": 2,
                                           "seeds": "100 101", "n": 2, "status": "ok", "error": ""}
    return pd.DataFrame([base | r for r in rows], columns=RUN_COLUMNS)


STAGE = {"id": "st", "kind": "box_behnken", "factors": {"A": {}, "B": {}},
         "responses": [{"id": "y1"}, {"id": "y2"}]}
DESIGN = pd.DataFrame({"run": [1, 2], "A": [-1, 1], "B": [0, 0], "A_actual": [0.1, 0.3], "B_actual": [5.0, 5.0]})


def test_gather_runs_ok_and_failed_points():
    runs = {
        1: _run_rows(1, [{"response": "y1", "value": 30.0, "sd": 0.4},
                         {"response": "y2", "value": 40.0, "sd": np.nan, "n": 1}]),
        2: _run_rows(2, [{"response": "y2", "value": np.nan, "sd": np.nan, "n": 0, "status": "failed",
                          "error": "SimulationError: blow-up at step 12", "seed": 100},
                         {"response": "y1", "value": 31.0, "sd": 0.2}]),
    }
    t = gather_runs(STAGE, DESIGN, runs)
    assert list(t.columns) == ["run", "A", "B", "y1", "y1_sd", "y1_n", "y2", "y2_sd", "y2_n",
                               "seed", "status", "error"]
    r1, r2 = t.iloc[0], t.iloc[1]
    assert (r1["run"], r1["A"], r1["B"]) == (1, 0.1, 5.0)  # the actual levels, not the coded ones
    assert (r1["y1"], r1["y1_sd"], r1["y1_n"]) == (30.0, 0.4, 2)
    assert r1["y2"] == 40.0 and np.isnan(r1["y2_sd"]) and r1["y2_n"] == 1
    assert r1["status"] == "ok" and r1["error"] == ""
    # the failed response: NaN, n 0, the point failed with its error; the other response kept
    assert np.isnan(r2["y2"]) and np.isnan(r2["y2_sd"]) and r2["y2_n"] == 0
    assert r2["y1"] == 31.0 and r2["y1_n"] == 2
    assert r2["status"] == "failed" and r2["error"] == "y2: SimulationError: blow-up at step 12"
    assert r2["seed"] == 100


def test_gather_runs_steepest_key_is_step():
    stage = {"id": "p", "kind": "steepest_ascent", "factors": {"A": {}}, "responses": [{"id": "y"}]}
    design = pd.DataFrame({"step": [1, 2], "A": [0.05, 0.08]})
    runs = {k: _run_rows(k, [{"response": "y", "value": 20.0 + k, "sd": 0.1}]) for k in (1, 2)}
    t = gather_runs(stage, design, runs)
    assert list(t["step"]) == [1, 2] and list(t["y"]) == [21.0, 22.0] and list(t["A"]) == [0.05, 0.08]


def test_gather_runs_missing_run_file_or_response_is_named():
    runs = {1: _run_rows(1, [{"response": "y1", "value": 30.0, "sd": 0.4},
                             {"response": "y2", "value": 40.0, "sd": 0.1}])}
    with pytest.raises(InputError, match="run 2") as exc:
        gather_runs(STAGE, DESIGN, runs)
    assert exc.value.field == "run 2"
    runs[2] = _run_rows(2, [{"response": "y1", "value": 30.0, "sd": 0.4}])
    with pytest.raises(InputError, match="a row for y2"):
        gather_runs(STAGE, DESIGN, runs)


def test_gather_runs_reads_back_a_csv_round_trip(tmp_path):
    # run files are CSV: "ok"/"failed" strings, empty error cells read as NaN
    runs = {}
    for k in (1, 2):
        p = tmp_path / f"{k}.csv"
        _run_rows(k, [{"response": "y1", "value": 10.0 * k, "sd": 0.5},
                      {"response": "y2", "value": 1.0 * k, "sd": 0.1}]).to_csv(p, index=False)
        runs[k] = pd.read_csv(p)
    t = gather_runs(STAGE, DESIGN, runs)
    assert list(t["y1"]) == [10.0, 20.0] and list(t["status"]) == ["ok", "ok"]


# --------------------------------------------------------------------------- too few points


def _bbd3_table(n_failed: int) -> pd.DataFrame:
    """A 3-factor BBD response table (12 edge midpoints + 5 centre points = 17 points) with
    the last ``n_failed`` points failed."""
    stage = {"kind": "box_behnken", "factors": {s: {"low": 0.0, "high": 1.0} for s in "ABC"}, "center_points": 5}
    design, _ = design_frame(stage, None)
    t = design[["run"]].copy()
    for s in "ABC":
        t[s] = design[f"{s}_actual"]
    t["y"] = 20.0 + design["A"] + 2 * design["B"] ** 2
    t["status"], t["error"] = "ok", ""
    for i in range(len(t) - n_failed, len(t)):
        t.loc[i, "y"] = np.nan
        t.loc[i, "status"] = "failed"
        t.loc[i, "error"] = f"y: SimulationError: blow-up in run {i + 1}"
    return t


BBD3 = {"id": "bbd", "kind": "box_behnken", "table": "responses.csv", "table_coding": "actual",
        "factors": {s: {"parameter": s, "low": 0.0, "high": 1.0} for s in "ABC"},
        "responses": [{"id": "y"}], "center_points": 5}


def test_enough_points_refuses_ten_responses_for_ten_terms():
    # full quadratic in 3 factors: 1 + 3 + 3 + 3 = 10 terms; 17 - 7 = 10 responses leave no residual df
    t = _bbd3_table(7)
    with pytest.raises(InputError) as exc:
        _enough_points(BBD3, t, "y", int(t["y"].notna().sum()), 3)
    msg = str(exc.value)
    assert "at least 11 design points" in msg and "10 terms" in msg
    for run in range(11, 18):
        assert f"run {run}: y: SimulationError: blow-up in run {run}" in msg
    assert "run 10" not in msg
    assert exc.value.field == "y"
    # 11 responses leave one residual degree of freedom
    t = _bbd3_table(6)
    _enough_points(BBD3, t, "y", int(t["y"].notna().sum()), 3)


def test_enough_points_plackett_burman_and_missing_error_column():
    pb = {"id": "pb", "kind": "plackett_burman", "responses": [{"id": "y"}]}
    # 7 main effects + intercept = 8 terms: 8 points are refused, 9 accepted
    t = pd.DataFrame({"run": np.arange(1, 10), "y": [1.0] * 8 + [np.nan]})
    with pytest.raises(InputError, match="run 9: no response"):
        _enough_points(pb, t, "y", 8, 7)
    _enough_points(pb, t, "y", 9, 7)


def test_fit_stage_refuses_a_gathered_table_with_too_many_failed_points():
    with pytest.raises(InputError, match="run 17: y: SimulationError"):
        fit_stage(BBD3, _bbd3_table(7))


# --------------------------------------------------------------------------- printed comparison


def test_printed_comparison_constant_offset():
    stage = {"kind": "steepest_ascent", "responses": [{"id": "y"}]}
    printed_stage = {"responses": [{"id": "y", "column": "Y (deg)"}]}
    printed = pd.DataFrame({"step": [1, 2, 3, 4], "Y (deg)": [20.0, 22.0, 27.0, 31.0]})
    resp = pd.DataFrame({"step": [1, 2, 3, 4], "y": [21.0, 23.0, 28.0, 32.0]})  # printed + 1 exactly
    out = printed_comparison(stage, printed_stage, resp, printed)
    s = out["summary"].iloc[0]
    assert s["runs"] == 4
    assert s["bias"] == pytest.approx(1.0) and s["rms_difference"] == pytest.approx(1.0)
    assert s["correlation"] == pytest.approx(1.0)
    assert s["printed_spread"] == pytest.approx(11.0) and s["simulated_spread"] == pytest.approx(11.0)
    pts = out["points"]
    assert list(pts["step"]) == [1, 2, 3, 4] and list(pts["difference"]) == pytest.approx([1.0] * 4)


def test_printed_comparison_mixed_differences_and_failed_point():
    stage = {"kind": "box_behnken", "responses": [{"id": "y"}]}
    printed_stage = {"responses": [{"id": "y"}]}
    printed = pd.DataFrame({"run": [1, 2, 3, 4, 5], "y": [10.0, 12.0, 14.0, 16.0, 18.0]})
    # differences +1, -1, +3, -1, failed: bias (1 - 1 + 3 - 1)/4 = 0.5, rms sqrt((1+1+9+1)/4) = sqrt(3)
    resp = pd.DataFrame({"run": [1, 2, 3, 4, 5], "y": [11.0, 11.0, 17.0, 15.0, np.nan]})
    s = printed_comparison(stage, printed_stage, resp, printed)["summary"].iloc[0]
    assert s["runs"] == 4
    assert s["bias"] == pytest.approx(0.5) and s["rms_difference"] == pytest.approx(np.sqrt(3.0))
    # Pearson r of (10,12,14,16) and (11,11,17,15): deviations (-3,-1,1,3) and (-2.5,-2.5,3.5,1.5):
    # sum xy = 7.5 + 2.5 + 3.5 + 4.5 = 18, sum x^2 = 20, sum y^2 = 6.25+6.25+12.25+2.25 = 27
    assert s["correlation"] == pytest.approx(18 / np.sqrt(20 * 27))
    # a flat printed column has no correlation
    flat = printed.assign(y=15.0)
    assert np.isnan(printed_comparison(stage, printed_stage, resp, flat)["summary"].iloc[0]["correlation"])


# --------------------------------------------------------------------------- published source


def test_published_responses_copies_the_bytes(tmp_path):
    src = tmp_path / "bbd.csv"
    data = b"run,A,B,C,stacking_angle\r\n1,-1,-1,0,25.7\n2,1,-1,0,29.80\n"
    src.write_bytes(data)
    out = published_responses(src, tmp_path / "a" / "b" / "responses.csv")
    assert out == tmp_path / "a" / "b" / "responses.csv"
    assert out.read_bytes() == data


# --------------------------------------------------------------------------- point specs


def test_point_spec_cinnamon_fixed_values_and_levels(cinnamon):
    stage = copy.deepcopy(cinnamon.stage("bbd"))
    # a derived stage whose fixed values differ from the DemParams defaults (the cinnamon values),
    # and which also fixes a parameter that one of its factors varies
    stage["fixed"] = {"soil_soil_restitution": 0.6, "soil_steel_restitution": 0.3,
                      "soil_steel_rolling_friction": 0.2, "soil_soil_static_friction": 0.7,
                      "soil_soil_rolling_friction": 0.3}
    spec = point_spec(cinnamon, stage, {"A": 0.09, "B": 0.3, "C": 0.5}, run=7, seed=1090, replicates=4)
    p = spec["params"]
    # fixed values of the stage
    assert p["soil_soil_restitution"] == 0.6 and p["soil_steel_restitution"] == 0.3
    assert p["soil_steel_rolling_friction"] == 0.2 and p["soil_soil_static_friction"] == 0.7
    # the point's levels; A overrides the fixed rolling friction 0.3 of the same parameter
    assert p["soil_soil_rolling_friction"] == 0.09
    assert p["soil_soil_surface_energy"] == 0.3      # B: jkr_surface_energy, pair soil-soil, J/m^2
    assert p["soil_steel_static_friction"] == 0.5    # C
    # printed properties: Poisson 0.311 (Sec. 2.2), shear modulus 3.814 MPa (Sec. 2.3) in Pa
    assert p["soil_poisson"] == pytest.approx(0.311)
    assert p["soil_shear_modulus"] == pytest.approx(3.814e6)
    assert spec["levels"] == {"A": 0.09, "B": 0.3, "C": 0.5}
    assert (spec["soil"], spec["stage"], spec["run"], spec["seed"], spec["replicates"]) == \
        ("cinnamon-soil", "bbd", 7, 1090, 4)
    r = spec["responses"]["stacking_angle"]
    assert (r["scenario"], r["measure"], r["setup"]["name"]) == ("repose", "angle_image_deg", "cinnamon-soil")
    # the loaded soil is not changed by the derived stage
    assert cinnamon.stage("bbd")["fixed"]["soil_soil_restitution"] == 0.45
    assert "soil_soil_rolling_friction" not in cinnamon.stage("bbd")["fixed"]


def test_point_spec_defaults_and_extra_params(cinnamon):
    stage = cinnamon.stage("bbd")
    spec = point_spec(cinnamon, stage, {"A": 0.14, "B": 0.52, "C": 0.66}, run=1, seed=1082,
                      extra_params={"soil_steel_static_friction": 0.8}, responses=[])
    assert spec["replicates"] == 1  # no simulation.replicates in the config
    assert spec["responses"] == {}
    assert spec["params"]["soil_steel_static_friction"] == 0.8  # extra params go over the level 0.66
    assert spec["params"]["soil_soil_rolling_friction"] == 0.14
    assert spec["params"]["soil_steel_rolling_friction"] == 0.125  # the stage's fixed value


def test_point_spec_params_over_properties_under_fixed(vineyard):
    stage = copy.deepcopy(vineyard.stage("bbd"))
    spec = point_spec(vineyard, stage, {"B": 0.63, "D": 0.08, "F": 0.56, "H": 0.14}, run=1, seed=3)
    p = spec["params"]
    # simulation.params soil_density 1757.567 over the printed particle density 175.7567 kg/m^3
    assert p["soil_density"] == pytest.approx(1757.567)
    # fixed soil_shear_modulus 10 MPa (parameters.soil_shear_modulus.unit) in Pa
    assert p["soil_shear_modulus"] == pytest.approx(1.0e7)
    assert p["soil_poisson"] == pytest.approx(0.33)
    assert p["soil_steel_rolling_friction"] == pytest.approx(0.30)
    assert p["soil_soil_restitution"] == 0.63 and p["soil_soil_surface_energy"] == 0.14
    # a fixed value over simulation.params
    stage["fixed"]["soil_shear_modulus"] = 20
    eff = soil_with_stage(vineyard, stage)
    assert eff.stage("bbd")["fixed"]["soil_shear_modulus"] == 20
    assert vineyard.stage("bbd")["fixed"]["soil_shear_modulus"] == 10
    p = point_spec(vineyard, stage, {"B": 0.63, "D": 0.08, "F": 0.56, "H": 0.14}, run=1, seed=3)["params"]
    assert p["soil_shear_modulus"] == pytest.approx(2.0e7)


def test_point_spec_refuses_an_unknown_factor(cinnamon):
    with pytest.raises(InputError, match="stages.bbd.factors"):
        point_spec(cinnamon, cinnamon.stage("bbd"), {"Z": 0.1}, run=1, seed=1)


# --------------------------------------------------------------------------- printed design points


def test_printed_design_points_keep_the_printed_actual_levels():
    from soilcal.chain.stage import printed_design

    soil = load_soil(ROOT / "config" / "soils" / "yangtze-clay-loam.yaml", ROOT / "resources")
    stage = soil.stage("bbd")
    table = pd.read_csv(ROOT / "resources" / "published" / "yangtze-clay-loam" / "bbd.csv")
    d = printed_design(stage, table)
    assert len(d) == 29 and list(d["run"]) == list(range(1, 30))
    # run 1 printed A 0.30, B 0.20, C 0.17, D 7.00: coded -1, -1, then C (0.17 - 0.175)/0.125 = -0.04,
    # print rounding of the 0.175 centre, snapped to 0; its actual level stays as printed
    r1 = d.iloc[0]
    assert (r1["A"], r1["B"], r1["C"], r1["D"]) == (-1.0, -1.0, 0.0, 0.0)
    assert r1["C_actual"] == 0.17 and r1["D_actual"] == 7.0
    pts = design_points(stage, d)
    assert pts[0] == (1, {"A": 0.3, "B": 0.2, "C": 0.17, "D": 7.0})
    assert pts[4] == (5, {"A": 0.45, "B": 0.4, "C": 0.05, "D": 5.0})


def test_printed_design_of_a_coded_table_is_decoded(cinnamon):
    from soilcal.chain.stage import printed_design

    stage = cinnamon.stage("bbd")
    table = pd.read_csv(ROOT / "resources" / "published" / "cinnamon-soil" / "bbd.csv")
    d = printed_design(stage, table)
    # run 1 printed coded (-1, -1, 0): A 0.08, B 0.24, C 0.54 (Table 6 levels)
    assert (d.iloc[0]["A_actual"], d.iloc[0]["B_actual"], d.iloc[0]["C_actual"]) == \
        pytest.approx((0.08, 0.24, 0.54), abs=1e-12)
    assert (d.iloc[1]["A_actual"], d.iloc[1]["B_actual"]) == pytest.approx((0.14, 0.24), abs=1e-12)


def test_simulate_renders_silhouettes_only_for_a_silhouette_angle(cinnamon, vineyard, monkeypatch):
    from types import SimpleNamespace

    from soilcal.dem.scenarios import base

    seen = {}

    def fake_run(module, setup, params, **kw):
        seen[module.NAME, setup["name"]] = setup
        return SimpleNamespace(n_particles=1, steps=1, wall_s=0.0, per_run=[],
                               responses={"angle_deg": 30.0, "angle_image_deg": 31.0,
                                          "angle_avalanche_deg": 40.0})

    monkeypatch.setattr(base, "run_replicates", fake_run)
    # vineyard: the static angle by radial bins (no silhouettes), the drum as configured
    spec = point_spec(vineyard, vineyard.stage("bbd"), {"B": 0.63, "D": 0.08, "F": 0.56, "H": 0.14}, run=1, seed=3)
    df = simulate(spec, rev="test")
    assert set(df["status"]) == {"ok"}
    assert seen["repose", "xinjiang-vineyard-100mm"]["image"] is False
    assert seen["drum", "xinjiang-vineyard"] == spec["responses"]["dynamic_angle"]["setup"]
    # cinnamon: the stacking angle is the silhouette angle, so the run renders them
    spec = point_spec(cinnamon, cinnamon.stage("bbd"), {"A": 0.11, "B": 0.38, "C": 0.54}, run=1, seed=3)
    simulate(spec, rev="test")
    assert seen["repose", "cinnamon-soil"]["image"] is True
    assert spec["responses"]["stacking_angle"]["setup"]["image"] is True  # the spec itself is not changed
