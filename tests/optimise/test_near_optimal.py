"""Near-optimal parameter sets, the calibrated choice and per-factor identifiability, against
analytic models whose sets of optimal parameters are known in closed form."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from soilcal.errors import InputError
from soilcal.optimise.desirability import desirability_optimise
from soilcal.optimise.near_optimal import calibrated_choice, identifiability, near_optimal_sets


class Lin:
    """Tiny analytic model in coded units, y = f(X_coded), with actual bounds low/high."""

    def __init__(self, f, low, high):
        self.f = f
        self.low = np.asarray(low, float)
        self.high = np.asarray(high, float)
        self.factors = ["x1", "x2", "x3"][: len(self.low)]

    def predict(self, X):
        return self.f(np.atleast_2d(np.asarray(X, float)))


LOW3, HIGH3 = [10.0, 100.0, 0.0], [20.0, 300.0, 1.0]


def _one_factor_model():
    # y = 30 + 2 x1 ; x2, x3 have no effect
    return Lin(lambda X: 30.0 + 2.0 * X[:, 0], LOW3, HIGH3)


# target 31 with limits [29, 33]: d = 1 - |y - 31| / 2 ; y = 31 <=> x1 = 0.5 (coded) exactly.
# D >= 1 - window (window 0.01) <=> |y - 31| <= 0.02 <=> |x1 - 0.5| <= 0.01.
GOAL_31 = {"y": {"goal": "target", "value": 31.0, "low": 29.0, "high": 33.0}}


@pytest.fixture(scope="module")
def one_factor_sets():
    return near_optimal_sets({"y": _one_factor_model()}, GOAL_31, seed=0)


def _pairwise_min(df, cols):
    pts = df[cols].to_numpy(float)
    dist = np.linalg.norm(pts[:, None] - pts[None], axis=2) + np.eye(len(pts)) * 1e9
    return dist.min()


def test_one_effective_factor_is_pinned_the_others_are_not(one_factor_sets):
    df = one_factor_sets
    assert len(df) > 10  # a whole plane of optima, not one point
    # every kept set lies within the analytic window band |x1 - 0.5| <= 0.01
    assert np.all(np.abs(df["x1_coded"] - 0.5) <= 0.01 + 1e-9)
    assert (df["desirability"] >= 1.0 - 0.01 - 1e-9).all()
    # actual = centre + coded * half range: x1 = 15 + 0.5 * 5 = 17.5
    assert np.allclose(df["x1"], 15.0 + 5.0 * df["x1_coded"])
    # distinct sets (coded distance >= tol) and the added columns
    assert _pairwise_min(df, ["x1_coded", "x2_coded", "x3_coded"]) >= 0.05
    assert df["near_optimal"].all()
    assert np.allclose(df["distance_to_centre"],
                       np.sqrt(df["x1_coded"] ** 2 + df["x2_coded"] ** 2 + df["x3_coded"] ** 2))

    ident = identifiability(df, ["x1", "x2", "x3"], LOW3, HIGH3).set_index("factor")
    # x1: span at most 0.02 coded (the band above) <= 2 * 0.1
    assert ident.loc["x1", "pinned"]
    assert ident.loc["x1", "spread_coded"] <= 0.02 + 1e-9
    assert ident.loc["x1", "note"].startswith("pinned: the near-optimal sets span")
    # x2, x3: any value in [-1, 1] is optimal; the random starts cover most of the range
    for f in ("x2", "x3"):
        assert not ident.loc[f, "pinned"]
        assert ident.loc[f, "spread_coded"] > 1.0
        assert ident.loc[f, "note"].startswith("not pinned down by the data")
    assert (ident["n_sets"] == len(df)).all()


def test_one_factor_calibrated_choice_is_nearest_the_centre(one_factor_sets):
    choice = calibrated_choice(one_factor_sets)
    # the optimal point nearest the centre of the plane x1 = 0.5 is (0.5, 0, 0), at distance 0.5
    assert choice["x1_coded"] == pytest.approx(0.5, abs=0.01)
    assert abs(choice["x2_coded"]) < 0.1 and abs(choice["x3_coded"]) < 0.1
    assert choice["distance_to_centre"] == one_factor_sets["distance_to_centre"].min()
    assert choice["distance_to_centre"] == pytest.approx(0.5, abs=0.1)


def test_line_of_optima():
    # y = 30 + x1 + x2, target 30 in [28, 32]: d = 1 - |x1 + x2| / 2, optimal on the line
    # x1 + x2 = 0 ; within the window: |x1 + x2| <= 2 * (0.01 + (1 - D_best)).
    m = Lin(lambda X: 30.0 + X[:, 0] + X[:, 1], LOW3[:2], HIGH3[:2])
    df = near_optimal_sets({"y": m}, {"y": {"goal": "target", "value": 30.0, "low": 28.0, "high": 32.0}}, seed=1)
    assert df.attrs["best_desirability"] == pytest.approx(1.0, abs=1e-6)
    assert len(df) > 5
    assert np.all(np.abs(df["x1_coded"] + df["x2_coded"]) <= 2 * (0.01 + 1e-6))
    ident = identifiability(df, ["x1", "x2"], {"x1": 10.0, "x2": 100.0}, {"x1": 20.0, "x2": 300.0})
    assert not ident["pinned"].any()
    # the line runs from corner (-1, 1) to corner (1, -1): the sets span most of each range
    assert (ident["spread_coded"] > 1.0).all()
    # the point of the line nearest the centre is the centre itself, D = 1 there
    choice = calibrated_choice(df)
    assert choice["x1_coded"] == pytest.approx(0.0, abs=0.05)
    assert choice["x2_coded"] == pytest.approx(0.0, abs=0.05)


def _two_peaks():
    # y = 1 - (x1^2 - 1/2)^2 + 0.1 x1 - x2^2 : two local maxima in x1 near +-1/sqrt(2), x2 = 0.
    # dy/dx1 = -4 x1 (x1^2 - 1/2) + 0.1 ; linearised about x0 = +-1/sqrt(2): -4 (x1 - x0) + 0.1,
    # so the peaks sit at x0 + 0.025: x1 ~ 0.732 (y ~ 1.072) and x1 ~ -0.682 (y ~ 0.931).
    # maximize with limits [0, 1.2]: d = y / 1.2, D ~ 0.893 and ~ 0.776, 0.12 apart.
    return Lin(lambda X: 1.0 - (X[:, 0] ** 2 - 0.5) ** 2 + 0.1 * X[:, 0] - X[:, 1] ** 2, LOW3[:2], HIGH3[:2])


MAX_GOAL = {"y": {"goal": "maximize", "low": 0.0, "high": 1.2}}


def test_window_keeps_only_sets_close_to_the_best():
    m = _two_peaks()
    narrow = near_optimal_sets({"y": m}, MAX_GOAL, seed=2, n_starts=40, window=0.01)
    # every start converges to one of the two peaks; only the higher one is within 0.01
    assert len(narrow) == 1
    assert narrow.loc[0, "x1_coded"] == pytest.approx(0.732, abs=0.01)
    assert narrow.loc[0, "x2_coded"] == pytest.approx(0.0, abs=1e-3)
    assert narrow.loc[0, "desirability"] == pytest.approx(1.072 / 1.2, abs=2e-3)
    one = identifiability(narrow, ["x1", "x2"], LOW3[:2], HIGH3[:2])
    assert one["pinned"].all()
    assert one["note"].str.contains("only one near-optimal set").all()
    assert (one["spread"] == 0.0).all()

    wide = near_optimal_sets({"y": m}, MAX_GOAL, seed=2, n_starts=40, window=0.2)
    # both peaks are within 0.2 of the best, and they are the only distinct optima
    assert len(wide) == 2
    best = wide["desirability"].max()
    assert (wide["desirability"] >= best - 0.2).all()
    assert list(wide["desirability"]) == sorted(wide["desirability"], reverse=True)
    assert sorted(wide["x1_coded"]) == pytest.approx([-0.682, 0.732], abs=0.01)
    assert list(wide["solution"]) == [1, 2]
    assert wide.attrs["window"] == 0.2 and wide.attrs["n_found"] == 2
    ident = identifiability(wide, ["x1", "x2"], LOW3[:2], HIGH3[:2]).set_index("factor")
    # min / max / spread consistency, actual units (half range of x1 = 5, of x2 = 100)
    for f, half in (("x1", 5.0), ("x2", 100.0)):
        assert ident.loc[f, "min"] == pytest.approx(wide[f].min())
        assert ident.loc[f, "max"] == pytest.approx(wide[f].max())
        assert ident.loc[f, "spread"] == pytest.approx(ident.loc[f, "max"] - ident.loc[f, "min"])
        assert ident.loc[f, "spread_coded"] == pytest.approx(ident.loc[f, "spread"] / half)
    # x1 jumps between the peaks (~1.41 coded, 71 % of the range); x2 = 0 at both
    assert not ident.loc["x1", "pinned"]
    assert ident.loc["x1", "spread_coded"] == pytest.approx(1.414, abs=0.02)
    assert "71 %" in ident.loc["x1", "note"]
    assert ident.loc["x2", "pinned"]
    # both peaks are near-optimal for this window, so the choice follows the distance rule:
    # the lower peak, |x| = 0.682 < 0.732, is nearer the centre
    choice = calibrated_choice(wide)
    assert choice["x1_coded"] == pytest.approx(-0.682, abs=0.01)


def test_pinned_fraction_threshold():
    # two hand-made sets, x1 spread 1 actual on range [10, 20]: coded 0.2, i.e. 10 % of the range
    sets = pd.DataFrame({"x1": [14.0, 15.0], "near_optimal": [True, True]})
    assert identifiability(sets, ["x1"], [10.0], [20.0], pinned_fraction=0.1)["pinned"].iloc[0]
    assert not identifiability(sets, ["x1"], [10.0], [20.0], pinned_fraction=0.05)["pinned"].iloc[0]
    row = identifiability(sets, ["x1"], [10.0], [20.0]).iloc[0]
    assert row["spread_coded"] == pytest.approx(0.2)
    assert row["note"] == "pinned: the near-optimal sets span 10 % of the range"


def test_calibrated_choice_ties():
    sets = pd.DataFrame({"solution": [1, 2, 3, 4], "desirability": [0.99, 0.98, 0.995, 0.995],
                         "distance_to_centre": [0.3, 0.2, 0.2, 0.2], "near_optimal": [True] * 4})
    # distance 0.2 ties among 2, 3, 4 -> higher desirability (3, 4) -> first in order (3)
    assert calibrated_choice(sets)["solution"] == 3
    sets.loc[2, "near_optimal"] = False
    assert calibrated_choice(sets)["solution"] == 4


def test_max_sets_keeps_the_nearest_to_centre():
    model = {"y": _one_factor_model()}
    full = near_optimal_sets(model, GOAL_31, seed=4, n_starts=60, max_sets=1000)
    cut = near_optimal_sets(model, GOAL_31, seed=4, n_starts=60, max_sets=5)
    assert full.attrs["n_found"] == len(full) > 5
    assert len(cut) == 5 and cut.attrs["n_found"] == len(full)
    cols = ["x1_coded", "x2_coded", "x3_coded"]
    assert np.allclose(calibrated_choice(cut)[cols].to_numpy(float), calibrated_choice(full)[cols].to_numpy(float))


def test_same_columns_as_the_search_plus_two():
    model = {"y": _one_factor_model()}
    base = desirability_optimise(model, GOAL_31, n_starts=5, seed=0)
    df = near_optimal_sets(model, GOAL_31, n_starts=5, seed=0)
    assert list(df.columns) == list(base.columns) + ["near_optimal", "distance_to_centre"]
    assert df["near_optimal"].dtype == bool


def test_deterministic_for_a_seed():
    model = {"y": _one_factor_model()}
    a = near_optimal_sets(model, GOAL_31, seed=7, n_starts=50)
    b = near_optimal_sets(model, GOAL_31, seed=7, n_starts=50)
    pd.testing.assert_frame_equal(a, b)
    assert {k: a.attrs[k] for k in ("seed", "n_starts", "tol", "window")} == {
        "seed": 7, "n_starts": 50, "tol": 0.05, "window": 0.01}


def test_unreachable_goal_gives_no_near_optimal_set():
    # y = 30 + 2 x1 lies in [28, 32]: a target of 40 in [39, 41] is met nowhere (D = 0)
    df = near_optimal_sets({"y": _one_factor_model()}, {"y": {"goal": "target", "value": 40.0, "low": 39.0, "high": 41.0}},
                           n_starts=5)
    assert df.empty
    with pytest.raises(InputError, match="sets"):
        calibrated_choice(df)


@pytest.mark.parametrize("kwargs, field", [
    ({"window": -0.1}, "window"),
    ({"window": float("nan")}, "window"),
    ({"max_sets": 0}, "max_sets"),
    ({"tol": -1.0}, "tol"),
    ({"n_starts": 0}, "n_starts"),
])
def test_bad_search_settings(kwargs, field):
    with pytest.raises(InputError) as e:
        near_optimal_sets({"y": _one_factor_model()}, GOAL_31, **kwargs)
    assert e.value.field == field


def test_bad_inputs_are_named():
    with pytest.raises(InputError, match="goals.z"):
        near_optimal_sets({"y": _one_factor_model()}, {"z": {"goal": "maximize"}}, n_starts=2)
    with pytest.raises(InputError, match="sets"):
        calibrated_choice(pd.DataFrame(columns=["desirability", "distance_to_centre"]))
    with pytest.raises(InputError, match="sets"):
        calibrated_choice(pd.DataFrame({"x1": [1.0]}))
    sets = pd.DataFrame({"x1": [14.0, 15.0]})
    with pytest.raises(InputError, match="factors"):
        identifiability(sets, ["x9"], [0.0], [1.0])
    with pytest.raises(InputError, match="low"):
        identifiability(sets, ["x1"], [0.0, 1.0], [1.0])
    with pytest.raises(InputError, match="low/high"):
        identifiability(sets, ["x1"], [2.0], [1.0])
    with pytest.raises(InputError, match="pinned_fraction"):
        identifiability(sets, ["x1"], [0.0], [20.0], pinned_fraction=1.5)
    with pytest.raises(InputError, match="sets"):
        identifiability(sets.iloc[:0], ["x1"], [0.0], [20.0])


def test_a_target_out_of_reach_is_said_in_every_note():
    """y = 30 + 2 x1 reaches at most 32 in the box; target 33 with limits [29, 35]: below the
    target d = (y - 29) / (33 - 29) (Derringer-Suich), so the best set is x1 = +1 with
    d = 3/4, no set meets the goal and every factor's note says so (the sets mark where the
    surface comes closest, not a calibrated match)."""
    goal = {"y": {"goal": "target", "value": 33.0, "low": 29.0, "high": 35.0}}
    sets = near_optimal_sets({"y": _one_factor_model()}, goal, seed=0)
    assert sets["desirability"].max() == pytest.approx(0.75, abs=1e-6)
    assert sets["x1"].min() == pytest.approx(20.0, abs=1e-6)  # x1 = +1 coded = 20 actual
    ident = identifiability(sets, ["x1", "x2", "x3"], LOW3, HIGH3)
    assert all(n.startswith("the goals are not met inside the design region (best desirability 0.75)")
               for n in ident["note"])
    # a goal that is met leaves the notes as they were
    ok = identifiability(near_optimal_sets({"y": _one_factor_model()}, GOAL_31, seed=0), ["x1", "x2", "x3"],
                         LOW3, HIGH3)
    assert not any("not met" in n for n in ok["note"])


def test_a_factor_held_by_a_bound_of_the_region_is_at_bound_not_pinned():
    """y = 30 + 2 x1 cannot reach 35 inside the region (its best is 32 at x1 = +1): every
    near-optimal set has x1 on its high bound 20, where the region stops the search, not the
    data; x2 and x3 do nothing and spread."""
    goal = {"y": {"goal": "target", "value": 35.0, "low": 29.0, "high": 36.0}}
    sets = near_optimal_sets({"y": _one_factor_model()}, goal, seed=0)
    assert len(sets) > 1 and np.allclose(sets["x1"], 20.0)
    ident = identifiability(sets, ["x1", "x2", "x3"], LOW3, HIGH3).set_index("factor")
    assert ident.loc["x1", "pinned"] == "at bound"
    assert ident.loc["x1", "note"].endswith("at bound: every near-optimal set has it at its high bound 20: held "
                                            "there by the design region, not pinned down by the data")
    assert ident.loc["x1", "note"].startswith("the goals are not met inside the design region")
    assert ident.loc["x2", "pinned"] == False  # noqa: E712  (object column: bools beside "at bound")


def test_sets_piled_against_a_bound_are_at_bound_and_sets_inside_are_pinned():
    # x1 on [10, 20]: 10 and 10.5 are coded -1 and -0.9, within 5 % of the range of the low
    # bound and one on it; 10.5 and 11 (coded -0.9, -0.8) are pinned inside the region
    on = pd.DataFrame({"x1": [10.0, 10.5], "near_optimal": [True, True], "desirability": [1.0, 1.0]})
    row = identifiability(on, ["x1"], [10.0], [20.0]).iloc[0]
    assert row["pinned"] == "at bound"
    assert row["note"] == ("at bound: the near-optimal sets lie within 5 % of the range of its low bound 10, some on "
                           "it: held there by the design region, not pinned down by the data")
    inside = pd.DataFrame({"x1": [10.5, 11.0], "near_optimal": [True, True], "desirability": [1.0, 1.0]})
    assert identifiability(inside, ["x1"], [10.0], [20.0])["pinned"].iloc[0] == True  # noqa: E712
