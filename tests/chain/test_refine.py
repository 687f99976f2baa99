"""The second calibration round (soilcal.chain.refine) and its verification rows, on a
Box-Behnken stage whose responses are exactly y = 30 + 2 A (A coded), so that the fitted
surface and every corrected set are known in closed form."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from bbd_stand_in import box_behnken_3
from soilcal.chain.refine import refine_frame, write_refined
from soilcal.chain.sources import RUN_COLUMNS
from soilcal.chain.verify import VERIFICATION_COLUMNS, summary_frame, verification_frame

CASES = ("biased", "met", "scatter", "far", "edge", "lost")


def _stage():
    goal = {"y": {"goal": "target", "target": "y"}}
    return {"id": "bbd", "kind": "box_behnken", "table_coding": "actual",
            "factors": {"A": {"parameter": "soil_soil_rolling_friction", "low": 0.0, "centre": 0.5, "high": 1.0},
                        "B": {"parameter": "soil_soil_static_friction", "low": 10.0, "centre": 15.0, "high": 20.0},
                        "C": {"parameter": "soil_steel_restitution", "low": 100.0, "centre": 200.0, "high": 300.0}},
            "responses": [{"id": "y", "name": "angle", "unit": "deg"}],
            "optimise": {"method": "desirability", "model": "full",
                         "cases": [{"id": c, "goals": dict(goal) if c != "lost" else
                                    {"y": {"goal": "target", "target": "lost"}}} for c in CASES]}}


def _table():
    # the 12 edge midpoints of a 3-factor Box-Behnken design and 3 centre points
    X = box_behnken_3()[1]
    y = 30.0 + 2.0 * X[:, 0]
    y[-3:] += [-0.01, 0.0, 0.01]  # pure error; the centre mean stays 30, so the fit is exactly 30 + 2 A
    return pd.DataFrame({"run": np.arange(1, 16), "A": 0.5 + 0.5 * X[:, 0], "B": 15 + 5 * X[:, 1],
                         "C": 200 + 100 * X[:, 2], "y": y})


# every case calibrated at A, B, C coded (0.5, 0.3, -0.2), where the surface predicts 31, but
# "edge" at A coded -1 (the surface's 28)
X0 = {"A": 0.75, "B": 16.5, "C": 180.0, "A_coded": 0.5, "B_coded": 0.3, "C_coded": -0.2}
EDGE = dict(X0, A=0.0, A_coded=-1.0)
OPTIMUM = pd.DataFrame([{"case": c, "method": "near_optimal", **(EDGE if c == "edge" else X0),
                         "y": 28.0 if c == "edge" else 31.0, "calibrated": c != "lost"} for c in CASES])
TARGETS = {"y": {"value": 31.0, "source": "image"}, "lost": {"value": None}}


def _runs(values, stage="bbd", seed0=11000):
    rows = [{c: "" for c in RUN_COLUMNS} | {"stage": stage, "run": k, "response": "y", "value": v, "sd": np.nan,
                                            "n": 1, "status": "ok", "error": "", "seed": seed0 + k,
                                            "preset": "quick"} for k, v in enumerate(values)]
    return [pd.DataFrame([r], columns=RUN_COLUMNS) for r in rows]


RUNS = {
    "biased": _runs([32.1, 31.9, 32.0, 32.0]),  # mean 32, sd 0.082: bias +1 >> 2 SE = 0.082
    "met": _runs([31.2, 31.3, 31.1, 31.2]),     # 0.65 % off: met
    "scatter": _runs([30.0, 34.0, 31.0, 33.0]),  # mean 32, 3.2 % off, but 2 SE = 1.83 > 1
    "far": _runs([38.0, 38.1, 37.9, 38.0]),     # bias +7: 37 + 2 A = 31 needs A = -3
    "edge": _runs([35.0, 35.1, 34.9, 35.0]),    # bias +7 at A = -1 already: nothing closer
}


@pytest.fixture(scope="module")
def refined():
    return refine_frame(_stage(), _table(), TARGETS, OPTIMUM, RUNS).set_index("case")


def test_a_significant_bias_moves_the_set_by_the_projection(refined):
    r = refined.loc["biased"]
    assert (r["round"], bool(r["refined"]), bool(r["calibrated"])) == (2, True, True)
    # 31 + 2 A = 31: A coded 0 (actual 0.5), B and C have no effect and stay where they were
    assert r["A_coded"] == pytest.approx(0.0, abs=1e-6) and r["A"] == pytest.approx(0.5, abs=1e-6)
    assert (r["B_coded"], r["C_coded"]) == pytest.approx((0.3, -0.2), abs=1e-6)
    assert (r["B"], r["C"]) == pytest.approx((16.5, 180.0), abs=1e-4)
    assert r["bias_y"] == pytest.approx(1.0) and r["y"] == pytest.approx(31.0, abs=1e-6)
    assert r["move_coded"] == pytest.approx(0.5, abs=1e-6)
    assert r["note"].startswith("bias-corrected")


def test_other_cases_keep_their_set_and_say_why(refined):
    for c in ("met", "scatter"):
        r = refined.loc[c]
        assert (r["round"], bool(r["refined"]), bool(r["calibrated"])) == (1, False, True)
        assert r["A_coded"] == pytest.approx(0.5) and r["A"] == pytest.approx(0.75)
    assert "meets every target within 2 %" in refined.loc["met", "note"]
    assert "seed scatter" in refined.loc["scatter", "note"]
    # bias +7 at the box's edge A = -1: the corrected surface's best, 35 + 2 (-1)... is x0 itself
    edge = refined.loc["edge"]
    assert (edge["round"], bool(edge["refined"])) == (1, False) and edge["A_coded"] == pytest.approx(-1.0)
    assert "does not reach" in edge["note"] and edge["bias_y"] == pytest.approx(7.0)
    assert not bool(refined.loc["lost", "calibrated"]) and "no calibrated set" in refined.loc["lost", "note"]


def test_an_unreachable_target_moves_to_the_compromise_when_it_promises_better(refined):
    # bias +7 at A = 0.5: the corrected surface 37 + 2 A is 38 there (22.6 % off 31) and 35 at
    # A = -1 (12.9 %), the closest the box allows: verified as a compromise
    far = refined.loc["far"]
    assert (far["round"], bool(far["refined"])) == (2, True)
    assert (far["A_coded"], far["B_coded"], far["C_coded"]) == pytest.approx((-1.0, 0.3, -0.2), abs=1e-4)
    assert far["y"] == pytest.approx(35.0, abs=1e-3) and far["bias_y"] == pytest.approx(7.0)
    assert far["note"].startswith("bias-corrected compromise") and "13 % against 23 %" in far["note"]


def test_second_round_rows_in_the_verification_and_the_summary(refined, tmp_path):
    ref = refined.reset_index()
    soil = {"targets": {"y": {"value": 31.0}, "lost": {"value": None}}}
    runs2 = {"biased": _runs([31.1, 30.9, 31.0, 31.2], seed0=11004), "far": _runs([34.9, 35.1], seed0=11004)}
    df = verification_frame(soil, _stage(), OPTIMUM, TARGETS, RUNS, ref, runs2)
    assert list(df.columns) == VERIFICATION_COLUMNS
    two = df[df["round"] == 2]
    assert list(two["case"]) == ["biased", "far"]
    r = two.iloc[0]
    assert r["simulated_mean"] == pytest.approx(31.05) and bool(r["within_2_percent"])
    assert r["predicted"] == pytest.approx(31.0, abs=1e-6) and r["seeds"] == "11004 11005 11006 11007"
    assert r["note"].startswith("bias-corrected")
    first = df[(df["round"] == 1) & (df["case"] == "biased")].iloc[0]
    assert first["simulated_mean"] == pytest.approx(32.0) and not bool(first["within_2_percent"])
    # the summary keeps the set each case ends with: round 2 for "biased" and "far"
    s = summary_frame({"soil": df}, {})
    assert sorted(zip(s["case"], s["round"])) == [("biased", 2), ("edge", 1), ("far", 2), ("lost", 1),
                                                  ("met", 1), ("scatter", 1)]


def test_a_second_round_says_whether_the_dem_moved_as_the_surface_promised(refined):
    # "biased": y = 30 + 2 A, the set moved A coded 0.5 -> 0: the surface promised -1.00; the
    # fit is almost exact (pure error 0.01 on the centre points), so its own SE is ~0.003
    ref = refined.reset_index()
    soil = {"targets": {"y": {"value": 31.0}, "lost": {"value": None}}}
    assert 0 < ref.set_index("case").loc["biased", "surface_change_se_y"] < 0.01

    def note(values):
        df = verification_frame(soil, _stage(), OPTIMUM, TARGETS, RUNS, ref,
                                {"biased": _runs(values, seed0=11004)})
        return df[(df["round"] == 2) & (df["case"] == "biased")].iloc[0]["note"]

    # the DEM fell by 0.95 from the first round's 32.0: as promised (2 SE = 2 sqrt(0.0067/4 +
    # 0.0167/4) = 0.153)
    n = note([31.1, 30.9, 31.0, 31.2])
    assert "the DEM changed by -0.95 where the surface promised -1.00 (two standard errors of their " \
           "difference 0.15, seeds and surface)" in n
    assert n.endswith(": as the surface said")
    # the DEM did not move (32.0 again, 2 SE = 2 sqrt(2 x 0.0067/4) = 0.115): the surface's
    # slope is wrong along the move, and the round missed (3.2 %)
    n = note([32.1, 31.9, 32.0, 32.0])
    assert "the DEM changed by +0.00 where the surface promised -1.00 (two standard errors of their " \
           "difference 0.12" in n
    assert "slope along the move is not the DEM's here, so shifting it by a constant cannot aim" in n
    # it fell by 0.5 only, but 31.5 meets the target (1.6 %): the slope is still said to differ,
    # without claiming the set cannot be aimed
    n = note([31.6, 31.4, 31.5, 31.5])
    assert n.endswith("the surface's slope along the move is not the DEM's here (the target is met nonetheless)")
    # one seed in the second round: no standard error, nothing said
    assert "the DEM changed" not in note([31.0])


def test_a_far_move_counts_the_surfaces_own_uncertainty(refined):
    # "far" moved A coded 0.5 -> -1 (1.5 coded): the promised change -3.00; its SE from the fit
    # is written, and taken into the two standard errors
    ref = refined.reset_index().copy()
    i = ref.index[ref["case"] == "far"][0]
    soil = {"targets": {"y": {"value": 31.0}, "lost": {"value": None}}}
    runs2 = {"far": _runs([36.9, 37.1, 37.0, 37.0], seed0=11004)}  # -1.0 from 38, 2 seed SE = 0.115
    ref.loc[i, "surface_change_se_y"] = 1.5  # a surface that knows its change to +-1.5 only
    df = verification_frame(soil, _stage(), OPTIMUM, TARGETS, RUNS, ref, runs2)
    n = df[(df["round"] == 2) & (df["case"] == "far")].iloc[0]["note"]
    # 2 sqrt(0.0067/4 + 0.0067/4 + 1.5^2) = 3.002 > |-1 - (-3)| = 2: as the surface said
    assert "(two standard errors of their difference 3.00, seeds and surface): as the surface said" in n
    ref.loc[i, "surface_change_se_y"] = 0.0
    df = verification_frame(soil, _stage(), OPTIMUM, TARGETS, RUNS, ref, runs2)
    assert "not the DEM's" in df[(df["round"] == 2) & (df["case"] == "far")].iloc[0]["note"]


def test_written_from_files(tmp_path):
    import json

    (tmp_path / "stage.json").write_text(json.dumps(_stage()))
    _table().to_csv(tmp_path / "responses.csv", index=False)
    OPTIMUM.to_csv(tmp_path / "optimum.csv", index=False)
    pd.DataFrame([{"target_id": "y", "value": 31.0, "source": "image"}]).to_csv(tmp_path / "targets.csv", index=False)
    paths = []
    for case, frames in RUNS.items():
        d = tmp_path / "verify" / "quick" / "bbd" / case
        d.mkdir(parents=True)
        for k, f in enumerate(frames):
            f.to_csv(d / f"{k}.csv", index=False)
            paths.append(d / f"{k}.csv")
    out = write_refined(tmp_path / "stage.json", tmp_path / "responses.csv", tmp_path / "targets.csv",
                        tmp_path / "optimum.csv", paths, tmp_path / "refined.csv")
    back = pd.read_csv(tmp_path / "refined.csv")
    assert list(back["case"]) == list(CASES)
    assert back.loc[back["case"] == "biased", "A_coded"].iloc[0] == pytest.approx(0.0, abs=1e-6)
    assert len(out) == len(CASES)


def test_a_miss_larger_than_the_seed_scatter_is_not_called_seed_scatter():
    """No bias (the seeds agree with the surface's prediction) does not make every miss seed
    scatter: at A's low bound the surface predicts 28 for the target 31, and four seeds of mean
    28 and SD sqrt(2/3) (two standard errors 0.816) miss by 3, far beyond their scatter: the
    note names the bound instead.  One seed has no standard error to tell anything."""
    stage = _stage()
    goal = {"y": {"goal": "target", "target": "y"}}
    stage["optimise"]["cases"] = [{"id": c, "goals": dict(goal)} for c in ("limit", "one", "scatter")]
    optimum = pd.DataFrame([{"case": "limit", "method": "near_optimal", **EDGE, "y": 28.0, "calibrated": True},
                            {"case": "one", "method": "near_optimal", **X0, "y": 31.0, "calibrated": True},
                            {"case": "scatter", "method": "near_optimal", **X0, "y": 31.0, "calibrated": True}])
    runs = {"limit": _runs([27.0, 28.0, 29.0, 28.0]), "one": _runs([29.0]), "scatter": RUNS["scatter"]}
    df = refine_frame(stage, _table(), TARGETS, optimum, runs).set_index("case")
    assert not df["refined"].astype(bool).any()
    limit = df.loc["limit", "note"]
    assert "seed scatter)" not in limit and "no bias to correct" in limit
    two_se = 2 * np.sqrt(2 / 3) / 2
    assert f"the miss -3 is more than seed scatter (two standard errors {two_se:.3g} of 4 seeds)" in limit
    assert "the surface itself predicts 28 at this set, -3 from the target; A at its low bound 0: the target " \
           "lies outside the design region" in limit
    assert "1 verification seed, no standard error" in df.loc["one", "note"]
    # mean 32, 1 from the target, two standard errors 2 sd / 2 = sd of 30, 34, 31, 33 = 1.83: seed scatter
    two_se = np.std([30.0, 34.0, 31.0, 33.0], ddof=1)
    assert f"the miss +1 is within two standard errors ({two_se:.3g}) of the mean of 4 seeds (seed scatter)" in \
        df.loc["scatter", "note"]


def test_unbiased_miss_note_by_hand():
    """Each missed response's reason, computed by hand: y1 four seeds of SD 1 miss by 1, two
    standard errors 2 * 1 / sqrt(4) = 1 exactly (seed scatter); y2 four seeds of SD 2 miss by
    3, beyond two standard errors 2 (the surface's own 32.5 is 2.5 off); y3 one seed."""
    from soilcal.chain.refine import _unbiased_miss

    stage = {"factors": {"A": {"low": 0.3, "high": 0.8}, "B": {"low": 10.0, "high": 20.0}}}
    tgt = {"y1": 30.0, "y2": 30.0, "y3": 30.0}
    stats = {"y1": (31.0, 1.0, 4), "y2": (33.0, 2.0, 4), "y3": (40.0, np.nan, 1)}
    pred = {"y1": 31.0, "y2": 32.5, "y3": 40.0}
    head = ("missed, but the verification means differ from the surface's prediction by no more than two "
            "standard errors of the seeds' mean and the surface's prediction together (no bias to correct); ")
    y1 = "y1: the miss +1 is within two standard errors (1) of the mean of 4 seeds (seed scatter)"
    y2 = ("y2: the miss +3 is more than seed scatter (two standard errors 2 of 4 seeds): the surface itself "
          "predicts 32.5 at this set, +2.5 from the target")
    y3 = "y3: 1 verification seed, no standard error: seed scatter and bias cannot be told apart"
    on_bound = pd.DataFrame([{"A_coded": -1.0, "B_coded": 0.2}])
    inside = pd.DataFrame([{"A_coded": 0.5, "B_coded": 0.2}])
    note = _unbiased_miss(stage, on_bound, tgt, stats, pred, ["y1", "y2", "y3"])
    assert note == head + "; ".join([y1, y2 + "; A at its low bound 0.3: the target lies outside the design "
                                     "region", y3])
    note = _unbiased_miss(stage, inside, tgt, stats, pred, ["y2"])
    assert note == head + y2 + ": the surface does not reach the target there"


def test_a_target_of_zero_is_kept_with_its_reason():
    # a target of 0 has no relative 2 % band (the verification gives it no relative error):
    # the case keeps its set and says why, instead of dividing by it
    zero = {"y": {"value": 0.0, "source": "measurement"}, "lost": {"value": None}}
    df = refine_frame(_stage(), _table(), zero, OPTIMUM, RUNS).set_index("case")
    r = df.loc["biased"]
    assert (r["round"], bool(r["refined"])) == (1, False)
    assert "a target of 0" in r["note"]


def test_a_bias_within_the_surfaces_own_error_is_not_corrected():
    """The "biased" case's seeds (mean 32, SD 0.082) at a set where the surface fitted to a
    scattered table is uncertain: the table's edge points carry +-1.5 about 30 + 2 A, so the
    full quadratic's prediction at the set has a standard error (its covariance, checked here
    against the formula MSE f'(X'X)^-1 f) that makes the difference +1 no bias."""
    from soilcal.chain.stage import fit_stage

    t = _table()
    t.loc[:11, "y"] += 1.5 * np.where(np.arange(12) % 2 == 0, 1.0, -1.0)
    fit = fit_stage(_stage(), t)[0].full
    x0 = np.array([0.5, 0.3, -0.2])
    X = fit.X_coded
    F = np.column_stack([np.ones(len(X)), X, X[:, 0] * X[:, 1], X[:, 0] * X[:, 2], X[:, 1] * X[:, 2], X ** 2])
    f = np.concatenate([[1.0], x0, [x0[0] * x0[1], x0[0] * x0[2], x0[1] * x0[2]], x0 ** 2])
    se = math.sqrt(fit.mse * f @ np.linalg.inv(F.T @ F) @ f)
    assert fit.predict_se(x0) == pytest.approx(se, rel=1e-6)
    pred = float(fit.predict(x0[None, :])[0])
    sd = float(np.std([32.1, 31.9, 32.0, 32.0], ddof=1))
    # the seeds alone would call it a bias, the seeds and the surface together do not
    assert abs(32.0 - pred) > 2 * sd / 2 and abs(32.0 - pred) <= 2 * math.sqrt(sd ** 2 / 4 + se ** 2)
    opt = OPTIMUM.copy()
    opt.loc[opt["case"] == "biased", "y"] = pred
    r = refine_frame(_stage(), t, TARGETS, opt, RUNS).set_index("case").loc["biased"]
    assert (r["round"], bool(r["refined"])) == (1, False)
    assert "no bias to correct" in r["note"]
