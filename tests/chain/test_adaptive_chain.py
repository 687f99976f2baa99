"""The adaptive design's problem per soil case: factors and ranges from the soil config, fixed
values, targets, and the cases it cannot run."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from soilcal.chain import adaptive
from soilcal.config.load import load_soil
from soilcal.errors import InputError

ROOT = Path(__file__).resolve().parents[2]


def soil(name):
    return load_soil(ROOT / f"config/soils/{name}.yaml", ROOT / "resources")


FIXED_332 = {"soil_soil_restitution": 0.45, "soil_soil_static_friction": 0.56,
             "soil_steel_restitution": 0.45, "soil_steel_rolling_friction": 0.125}


def test_cinnamon_problem_is_the_screening_ranges_of_the_box_behnken_factors():
    s = soil("cinnamon-soil")
    st = adaptive.stage_for(s.data, "bbd")
    pb = adaptive.problem_for(s.data, st, "stacking_angle", {"stacking_angle": {"value": 27.7}})
    # A, B, C are X3, X7, X5 of the screening, at its Table 2 levels (low, high); the four other
    # parameters as fixed in Sec. 3.3.2
    assert [(f.name, f.low, f.high) for f in pb.factors] == [("A", 0.05, 0.2), ("B", 0.1, 0.8), ("C", 0.3, 0.9)]
    assert st["factors"]["B"]["centre"] == pytest.approx(0.45)
    assert pb.fixed == FIXED_332
    assert "screening stage pb" in st["derivation"]["text"] and "A (0.08-0.14 -> 0.05-0.2)" in st["derivation"]["text"]
    (t,) = pb.targets
    assert t.value == 27.7 and t.tolerance == pytest.approx(0.02 * 27.7)  # default 2 %


def test_cinnamon_problem_on_the_stage_ranges_is_the_box_behnken_levels():
    s = soil("cinnamon-soil")
    s.data["simulation"]["adaptive"] = {"ranges": "stage"}
    st = adaptive.stage_for(s.data, "bbd")
    pb = adaptive.problem_for(s.data, st, "stacking_angle", {"stacking_angle": {"value": 27.7}})
    # Table 6 levels (low, high) of A, B, C
    assert [(f.name, f.low, f.high) for f in pb.factors] == [("A", 0.08, 0.14), ("B", 0.24, 0.52), ("C", 0.42, 0.66)]
    assert pb.fixed == FIXED_332
    assert adaptive.settings_for(s.data).budget == 60  # the key is the stage's, not the design's
    s.data["simulation"]["adaptive"] = {"ranges": "pb"}
    with pytest.raises(InputError, match="simulation.adaptive.ranges"):
        adaptive.stage_for(s.data, "bbd")


def test_a_stage_without_a_screening_keeps_its_ranges():
    s = soil("black-soil")  # the single-factor tests of 001 chose its ranges: no screening stage
    assert adaptive.screening_of(s.data, "soil-soil") is None
    st = adaptive.stage_for(s.data, "soil-soil")
    assert (st["factors"]["x3"]["low"], st["factors"]["x3"]["high"]) == (0.2, 1.0)


def test_tolerances_per_response():
    s = soil("xinjiang-vineyard")
    s.data["simulation"]["adaptive"] = {"tolerance_pct": 3, "tolerances": {"dynamic_angle": {"abs": 1.5}}}
    st = adaptive.stage_for(s.data, "bbd")
    pb = adaptive.problem_for(s.data, st, "upper", {"static_angle_upper": {"value": 30.0},
                                                     "dynamic_angle_upper": {"value": 40.0}})
    tol = {t.response: t.tolerance for t in pb.targets}
    assert tol == {"static_angle": pytest.approx(0.9), "dynamic_angle": 1.5}


def test_a_missing_target_value_is_named():
    s = soil("cinnamon-soil")
    st = adaptive.stage_for(s.data, "bbd")
    with pytest.raises(InputError, match="targets.stacking_angle"):
        adaptive.problem_for(s.data, st, "stacking_angle", {"stacking_angle": {"value": None}})


def test_cases_without_a_target_are_listed_with_the_reason():
    g = soil("guangxi-cohesive")
    run = adaptive.adaptive_cases(g.data, ["bbd"])
    out = adaptive.excluded_cases(g.data, ["bbd"])
    # the 5 % and 15 % moisture targets were lost in the paper's extraction
    assert [c for _, c in run] == ["mc00", "mc10", "mc20"]
    assert [e["case"] for e in out] == ["mc05", "mc15"]
    assert all("no value and no photo group" in e["why"] for e in out)
    # a response to minimise runs with an absolute tolerance and is listed without one
    y = soil("yangtze-clay-loam")
    stages = [s["id"] for s in y.data["stages"]]
    assert adaptive.adaptive_cases(y.data, stages) == [("bbd", "area_difference")]
    (t,) = adaptive.problem_for(y.data, adaptive.stage_for(y.data, "bbd"), "area_difference", {}).targets
    assert (t.goal, t.tolerance) == ("minimize", 0.1) and t.value != t.value  # its level: set per iteration
    del y.data["simulation"]["adaptive"]
    (e,) = adaptive.excluded_cases(y.data, stages)
    assert "goal minimize needs an absolute tolerance" in e["why"]
    assert "simulation.adaptive.tolerances.area_difference.abs" in e["why"]
    with pytest.raises(InputError, match="tolerances.area_difference.abs"):
        adaptive.problem_for(y.data, adaptive.stage_for(y.data, "bbd"), "area_difference", {})
    summ = adaptive.summary_frame("yangtze-clay-loam", [], [e])
    assert summ["stopped_because"].tolist() == ["not run"] and list(summ.columns) == adaptive.SUMMARY_COLUMNS


def test_a_stage_fixed_from_an_earlier_one_takes_its_adaptive_set():
    s = soil("black-soil")
    up = pd.DataFrame([{"case": "accumulation_angle", "method": "adaptive", "x1": 0.5, "x2": 0.4, "x3": 0.7,
                        "x4": 0.2, "calibrated": True}])
    st = adaptive.stage_for(s.data, "soil-65mn", up)
    assert {k: st["fixed"][k] for k in ("soil_soil_surface_energy", "soil_soil_restitution",
                                         "soil_soil_static_friction", "soil_soil_rolling_friction")} == \
        {"soil_soil_surface_energy": 0.5, "soil_soil_restitution": 0.4, "soil_soil_static_friction": 0.7,
         "soil_soil_rolling_friction": 0.2}
    with pytest.raises(InputError, match="fixed_from"):
        adaptive.stage_for(s.data, "soil-65mn")


def test_progress_figure_is_written_and_refuses_a_missing_response(tmp_path):
    from soilcal.plots.adaptive import adaptive_progress

    runs = pd.DataFrame({"iteration": [0, 0, 1, 1], "kind": ["start", "start", "proposal", "verification"],
                         "point": [0, 0, 1, 2], "seed": [0, 1, 2, 3], "A": [0.1, 0.1, 0.2, 0.3],
                         "y": [30.0, 31.0, 28.0, 27.5]})
    res = {"stage": "bbd", "case": "c", "status": "budget spent", "runs": 4,
           "problem": {"targets": {"y": {"value": 27.7, "tolerance": 0.55}}}, "settings": {"p_verify": 0.5}}
    paths = adaptive_progress(runs, res, [(1, 0.2), (2, 0.7)], tmp_path / "p")
    assert [p.name for p in paths] == ["p.png", "p.pdf"] and all(p.stat().st_size > 0 for p in paths)
    with pytest.raises(InputError, match="runs.csv"):
        adaptive_progress(runs.drop(columns="y"), res, [], tmp_path / "q")


def test_optimum_rows_take_the_verified_set_else_the_best_candidate():
    stage = {"factors": {"A": {"low": 0.08, "high": 0.14}, "B": {"low": 0.24, "high": 0.52}}}
    problem = {"factors": {"A": [0.08, 0.14], "B": [0.24, 0.52]},
               "targets": {"y": {"value": 27.7, "tolerance": 0.554}}}
    verified = {"problem": problem, "case": "v", "status": "target met", "message": "met", "runs": 20,
                "best": {"levels": {"A": 0.1, "B": 0.3}, "predicted": {"y": 27.5}, "p": 0.9},
                "verified": {"met": True, "levels": {"A": 0.11, "B": 0.45},
                             "responses": {"y": {"mean": 27.9}}}}
    best = dict(verified, case="b", status="budget spent", message="60 runs spent", verified=None,
                best={"levels": {"A": 0.14, "B": 0.24}, "predicted": {"y": 30.1}, "p": 0.001, "closest": True})
    opt = adaptive.optimum_frame(stage, [verified, best]).set_index("case")
    # coded = (actual - centre) / half range
    assert opt.loc["v", "A_coded"] == pytest.approx(0.0) and opt.loc["v", "B_coded"] == pytest.approx(0.5)
    assert opt.loc["v", "y"] == 27.9 and opt.loc["v", "note"] == "verified within tolerance"
    assert opt.loc["b", "A_coded"] == pytest.approx(1.0) and opt.loc["b", "B_coded"] == pytest.approx(-1.0)
    assert opt.loc["b", "y"] == 30.1 and opt.loc["b", "note"].startswith("closest reachable point")
    assert opt["calibrated"].all()


def test_optimum_row_without_a_met_verification_is_the_best_verified_point():
    # verified at A = 0.11, B = 0.45 (mean 29.0, off the band); the surrogate's best candidate
    # at A = 0.14, B = 0.24 was never run: optimum.csv gives the measured point, so that
    # verification.csv compares that point with its own runs
    stage = {"factors": {"A": {"low": 0.08, "high": 0.14}, "B": {"low": 0.24, "high": 0.52}}}
    problem = {"factors": {"A": [0.08, 0.14], "B": [0.24, 0.52]},
               "targets": {"y": {"value": 27.7, "tolerance": 0.554}}}
    res = {"problem": problem, "case": "c", "status": "budget spent", "message": "60 runs spent", "runs": 60,
           "best": {"levels": {"A": 0.14, "B": 0.24}, "predicted": {"y": 27.6}, "p": 0.4},
           "verified": {"met": False, "levels": {"A": 0.11, "B": 0.45}, "responses": {"y": {"mean": 29.0}}}}
    row = adaptive.optimum_frame(stage, [res]).set_index("case").loc["c"]
    assert (row["A"], row["B"]) == (0.11, 0.45) and np.isnan(row["y"])  # no surface prediction there
    assert row["A_coded"] == pytest.approx(0.0) and row["B_coded"] == pytest.approx(0.5)
    assert row["note"].startswith("the best verified point") and "60 runs spent" in row["note"]


def test_a_broken_run_file_is_named(tmp_path):
    pb = adaptive.ad.Problem([adaptive.ad.Factor("A", 0, 1)], [adaptive.ad.Target("y", 1.0)])
    steps = [{"iteration": 0, "runs": [{"kind": "start", "point": 0, "seed": 0, "levels": {"A": 0.5}}]}]
    d = tmp_path / "runs/0"
    d.mkdir(parents=True)
    (d / "0.csv").write_bytes(b"")
    with pytest.raises(InputError, match="0.csv"):
        adaptive.read_runs(pb, steps, [d / "0.csv"])
    (d / "0.csv").write_text("a,b\n1,2\n")
    with pytest.raises(InputError, match="response"):
        adaptive.read_runs(pb, steps, [d / "0.csv"])
    with pytest.raises(InputError, match="file name"):
        adaptive.read_runs(pb, steps, [tmp_path / "runs/x/0.csv"])


def test_progress_figure_of_a_minimised_response(tmp_path):
    from soilcal.plots.adaptive import adaptive_progress

    runs = pd.DataFrame({"iteration": [0, 0, 1], "kind": ["start", "start", "verification"], "point": [0, 0, 1],
                         "seed": [0, 1, 2], "A": [0.1, 0.1, 0.3], "y": [0.9, 1.0, 0.45]})
    res = {"stage": "bbd", "case": "c", "status": "optimum verified", "runs": 3,
           "problem": {"targets": {"y": {"value": 0.4, "tolerance": 0.1, "goal": "minimize"}}},
           "settings": {"p_verify": 0.5}}
    paths = adaptive_progress(runs, res, [(1, 0.7)], tmp_path / "m")
    assert all(p.stat().st_size > 0 for p in paths)


def test_tolerance_bands_of_each_goal():
    from soilcal.plots.adaptive import tolerance_band

    assert tolerance_band({"value": 30.0, "tolerance": 0.6})[:2] == (29.4, 30.6)
    assert tolerance_band({"value": 0.4, "tolerance": 0.1, "goal": "minimize"})[:2] == (0.4, 0.5)
    lo, hi, label = tolerance_band({"value": 2.0, "tolerance": 0.5, "goal": "maximize"})
    assert (lo, hi) == (1.5, 2.0) and label.startswith("maximize: best 2")


def test_summary_of_a_minimised_response_has_a_best_level_and_no_target():
    res = {"stage": "bbd", "case": "c", "status": "optimum verified", "runs": 22, "iterations": 3,
           "message": "m", "problem": {"targets": {"y": {"value": 0.8, "tolerance": 0.1, "goal": "minimize"}}},
           "verified": {"responses": {"y": {"mean": 0.83, "sd": 0.07, "n": 4, "error_pct": None, "within": True}}}}
    (row,) = adaptive.summary_frame("s", [res]).to_dict("records")
    assert row["goal"] == "minimize" and row["best_level"] == 0.8 and pd.isna(row["target"])
    assert pd.isna(row["verification_rel_error_pct"]) and row["within_tolerance"]


def _steps():
    """Three step records: a start of 3 runs, an iteration of 2 proposals and a verification
    of 4 seeds, then a stop; the verified set first appears in the stop's record."""
    ver = {"point": 3, "met": True, "levels": {"A": 0.2},
           "responses": {"y": {"target": 30.0, "goal": "target", "tolerance": 0.6, "mean": 30.3, "sd": 0.5, "n": 4,
                               "error_pct": 1.0, "within": True}}}
    prob = {"factors": {"A": [0.0, 0.5]}, "targets": {"y": {"value": 30.0, "tolerance": 0.6, "goal": "target"}}}
    run = (lambda k, pt, a: {"kind": k, "point": pt, "seed": 0, "levels": {"A": a}})
    return [{"iteration": 0, "status": "continue", "runs": [run("start", 0, 0.25)] * 2 + [run("start", 1, 0.1)],
             "verified": None, "problem": prob, "consistent": []},
            {"iteration": 1, "status": "continue", "runs": [run("proposal", 2, 0.3)] + [run("verification", 3, 0.2)] * 4,
             "verified": None, "problem": prob, "consistent": [[0.18], [0.21], [0.24]]},
            {"iteration": 2, "status": "target met", "runs": [], "verified": ver, "problem": prob,
             "consistent": [[0.19], [0.22]]}]


def test_progress_counts_the_runs_made_before_each_verified_set():
    res = {"stage": "bbd", "case": "c"}
    prog = adaptive.progress_frame(res, _steps())
    # the verified set of the stop's record rests on the 3 + 5 runs of the iterations before it
    assert prog[["iteration", "runs", "response", "error_pct"]].values.tolist() == [[2, 8, "y", 1.0]]
    assert list(prog.columns) == adaptive.PROGRESS_COLUMNS
    assert adaptive.progress_frame(res, _steps()[:2]).empty  # nothing verified yet


def test_error_and_region_figures_are_written_and_refuse_missing_columns(tmp_path):
    from soilcal.plots.adaptive import error_against_runs, proposals_over_region

    prog = adaptive.progress_frame({"stage": "bbd", "case": "c"}, _steps())
    other = pd.DataFrame([{"method": "recipe", "runs": 29, "response": "y", "goal": "target", "target": np.nan,
                           "tolerance": np.nan, "verified_mean": 33.0, "error_pct": 10.0}])
    paths = error_against_runs(pd.concat([prog, other], ignore_index=True), tmp_path / "e")
    assert [p.name for p in paths] == ["e.png", "e.pdf"] and all(p.stat().st_size > 0 for p in paths)
    with pytest.raises(InputError, match="runs"):
        error_against_runs(prog.drop(columns="runs"), tmp_path / "e2")
    # a target of 0 (an absolute tolerance) has no relative band, and no division by it
    zero = prog.assign(target=0.0, error_pct=np.nan, verified_mean=0.1)
    assert all(p.stat().st_size > 0 for p in error_against_runs(zero, tmp_path / "e0", band_pct=2.0))
    runs = pd.DataFrame({"iteration": [0, 0, 0, 1, 1], "kind": ["start"] * 3 + ["proposal", "verification"],
                         "point": [0, 0, 1, 2, 3], "seed": range(5), "A": [0.25, 0.25, 0.1, 0.3, 0.2],
                         "y": [31.0, 31.5, 28.0, 30.9, 30.3]})
    paths = proposals_over_region(_steps(), runs, tmp_path / "r")
    assert all(p.stat().st_size > 0 for p in paths)
    with pytest.raises(InputError, match="runs.csv"):
        proposals_over_region(_steps(), runs.drop(columns="A"), tmp_path / "r2")


def test_factor_pairs_show_every_factor():
    from soilcal.plots.adaptive import factor_pairs

    assert factor_pairs(1) == [(0, 0)]
    assert factor_pairs(2) == [(0, 1)]
    assert factor_pairs(3) == [(0, 1), (1, 2)]
    assert factor_pairs(4) == [(0, 1), (2, 3)]
    assert factor_pairs(5) == [(0, 1), (2, 3), (3, 4)]
