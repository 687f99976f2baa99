"""Derringer-Suich desirability: formulas against hand computation, optimiser against models
whose optimal sets are known in closed form."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from soilcal.errors import InputError
from soilcal.optimise import (
    d_in_range,
    d_maximize,
    d_minimize,
    d_target,
    desirability_optimise,
    make_goal,
    overall_desirability,
)


class Poly:
    """Tiny analytic model in coded units: y = f(x)."""

    def __init__(self, f, k, low=None, high=None, observed=None, response="y"):
        self.f = f
        self.factors = ["A", "B", "C", "D"][:k]
        self.low = np.zeros(k) if low is None else np.asarray(low, float)
        self.high = 2 * np.ones(k) if high is None else np.asarray(high, float)
        self.response = response
        self.observed = observed

    def predict(self, X):
        return self.f(np.atleast_2d(np.asarray(X, float)))


# --------------------------------------------------------------------------- formulas


def test_maximize_minimize_hand_values():
    # ((5 - 0)/(10 - 0))^2 = 0.25 ; below L -> 0 ; above U -> 1
    assert d_maximize([5.0, -1.0, 11.0], 0.0, 10.0, 2.0) == pytest.approx([0.25, 0.0, 1.0])
    # ((10 - 2.5)/10)^0.5 = sqrt(0.75) ; below L -> 1 ; above U -> 0
    assert d_minimize([2.5, -3.0, 12.0], 0.0, 10.0, 0.5) == pytest.approx([np.sqrt(0.75), 1.0, 0.0])


def test_target_two_sided_hand_values():
    y = [2.5, 5.0, 7.5, 10.0, -0.1, 10.1]
    # left: (2.5 - 0)/(5 - 0) = 0.5 ; right: ((10 - 7.5)/(10 - 5))^3 = 0.125
    assert d_target(y, 5.0, 0.0, 10.0, 1.0, 3.0) == pytest.approx([0.5, 1.0, 0.125, 0.0, 0.0, 0.0])


def test_in_range():
    assert list(d_in_range([0.9, 1.0, 2.0, 2.1], 1.0, 2.0)) == [0.0, 1.0, 1.0, 0.0]


def test_overall_is_weighted_geometric_mean():
    # (0.25^1 * 1^3)^(1/4) = 0.25^0.25
    assert overall_desirability([0.25, 1.0], [1, 3])[0] == pytest.approx(0.25**0.25)
    # equal importances: plain geometric mean (0.5 * 0.8)^(1/2)
    assert overall_desirability(np.array([[0.5], [0.8]]))[0] == pytest.approx(np.sqrt(0.4))
    assert overall_desirability([0.0, 1.0])[0] == 0.0


def test_scalar_path_equals_vector_path():
    g = make_goal("y", {"goal": "target", "value": 4.0, "low": 1.0, "high": 9.0, "weight_low": 0.5, "weight_high": 2.0})
    ys = np.linspace(0, 10, 41)
    assert np.allclose(g.d(ys), [g.d_scalar(float(y)) for y in ys])
    for kind in ("maximize", "minimize", "in_range"):
        g = make_goal("y", {"goal": kind, "low": 1.0, "high": 9.0, "weight": 3.0})
        assert np.allclose(g.d(ys), [g.d_scalar(float(y)) for y in ys])


def test_target_without_limits_uses_observed_range():
    g = make_goal("y", {"goal": "target", "value": 3.0}, observed=[1.0, 2.0, 6.0])
    assert (g.low, g.target, g.high) == (1.0, 3.0, 6.0)
    # a target outside the observed range widens the defaulted limit to the target
    g = make_goal("y", {"goal": "target", "value": 8.0}, observed=[1.0, 6.0])
    assert (g.low, g.high) == (1.0, 8.0)


@pytest.mark.parametrize(
    "spec, field",
    [
        ({"goal": "hit"}, "goals.y.goal"),
        ({"goal": "target"}, "goals.y.value"),
        ({"goal": "maximize", "low": 0, "high": 1, "importance": 6}, "goals.y.importance"),
        ({"goal": "maximize", "low": 0, "high": 1, "weight": 0}, "goals.y.weight"),
        ({"goal": "maximize", "low": 2, "high": 1}, "goals.y.low/high"),
        ({"goal": "target", "value": 5, "low": 0, "high": 1}, "goals.y.value"),
        ({"goal": "maximize", "lo": 0}, "goals.y"),
    ],
)
def test_bad_goal_names_field(spec, field):
    with pytest.raises(InputError) as e:
        make_goal("y", spec, observed=[0.0, 10.0])
    assert e.value.field == field


# --------------------------------------------------------------------------- optimiser


def _circle_model():
    return Poly(lambda X: X[:, 0] ** 2 + X[:, 1] ** 2, 2, observed=[0.0, 2.0])


def test_target_level_set_circle_several_distinct_solutions():
    df = desirability_optimise({"y": _circle_model()}, {"y": {"goal": "target", "value": 0.5}},
                               n_starts=30, seed=3, n_solutions=8, tol=0.1)
    r = np.hypot(df["A_coded"], df["B_coded"])
    assert np.allclose(r, np.sqrt(0.5), atol=1e-4)
    assert np.allclose(df["y"], 0.5, atol=1e-4)
    assert (df["desirability"] > 0.999).all()
    assert len(df) >= 5
    pts = df[["A_coded", "B_coded"]].to_numpy()
    dist = np.linalg.norm(pts[:, None] - pts[None], axis=2) + np.eye(len(pts))
    assert dist.min() >= 0.1
    # actual = centre + coded * half-range, with low 0, high 2
    assert np.allclose(df["A"], 1.0 + df["A_coded"])
    assert list(df.columns[:5]) == ["solution", "A_coded", "B_coded", "A", "B"]
    assert list(df["solution"]) == list(range(1, len(df) + 1))


def test_bounds_restrict_the_search_to_a_quadrant():
    df = desirability_optimise({"y": _circle_model()}, {"y": {"goal": "target", "value": 0.5}},
                               bounds={"A": (0, 1), "B": (0, 1)}, n_starts=12, seed=0, n_solutions=5)
    assert (df[["A_coded", "B_coded"]] >= -1e-12).all().all()
    assert np.allclose(np.hypot(df["A_coded"], df["B_coded"]), np.sqrt(0.5), atol=1e-4)


def test_multi_response_joint_target():
    # y1 = x1 + x2 -> 0.5, y2 = x1 - x2 -> 0.1 : unique joint solution x = (0.3, 0.2)
    m1 = Poly(lambda X: X[:, 0] + X[:, 1], 2, observed=[-2.0, 2.0])
    m2 = Poly(lambda X: X[:, 0] - X[:, 1], 2, observed=[-2.0, 2.0])
    df = desirability_optimise({"static": m1, "dynamic": m2},
                               {"static": {"goal": "target", "value": 0.5},
                                "dynamic": {"goal": "target", "value": 0.1}},
                               n_starts=15, seed=1)
    assert len(df) == 1  # every start converges to the one point
    assert df.loc[0, "A_coded"] == pytest.approx(0.3, abs=1e-4)
    assert df.loc[0, "B_coded"] == pytest.approx(0.2, abs=1e-4)
    assert df.loc[0, "desirability"] == pytest.approx(1.0, abs=1e-4)
    assert {"static", "dynamic", "d_static", "d_dynamic"} <= set(df.columns)


def test_importance_moves_the_compromise():
    # d1 = (1 + x)/2 (maximize), d2 = (1 - x)/2 (minimize) on limits [-1, 1]:
    # D maximal where r1/(1 + x) = r2/(1 - x), i.e. x = (r1 - r2)/(r1 + r2) = 0.5 for r = (3, 1)
    m = Poly(lambda X: X[:, 0], 1)
    goals = {"up": {"goal": "maximize", "low": -1, "high": 1, "importance": 3},
             "down": {"goal": "minimize", "low": -1, "high": 1, "importance": 1}}
    df = desirability_optimise({"up": m, "down": m}, goals, n_starts=10, seed=0)
    assert df.loc[0, "A_coded"] == pytest.approx(0.5, abs=1e-4)
    assert df.loc[0, "desirability"] == pytest.approx((0.75**3 * 0.25) ** 0.25, rel=1e-6)


def test_maximize_peak_and_factor_goal():
    # y = 10 - (x1 - 0.3)^2 - (x2 + 0.4)^2 ; maximise y with U = 10 -> peak (0.3, -0.4)
    m = Poly(lambda X: 10 - (X[:, 0] - 0.3) ** 2 - (X[:, 1] + 0.4) ** 2, 2, observed=[0.0, 10.0])
    df = desirability_optimise({"y": m}, {"y": {"goal": "maximize", "weight": 1}}, n_starts=10, seed=2)
    assert df.loc[0, "A_coded"] == pytest.approx(0.3, abs=1e-3)
    assert df.loc[0, "B_coded"] == pytest.approx(-0.4, abs=1e-3)
    # add a goal on factor A (actual units, low 0 high 2): target A = 0.5 (coded -0.5)
    df = desirability_optimise({"y": m}, {"y": {"goal": "maximize", "low": 9.0, "high": 10.0},
                                          "A": {"goal": "target", "value": 0.5, "low": 0.0, "high": 2.0}},
                               n_starts=10, seed=2)
    # maximise ((y - 9) * (1 - |A_c + 0.5| / ...)): B stays at its optimum, A between -0.5 and 0.3
    assert df.loc[0, "B_coded"] == pytest.approx(-0.4, abs=1e-3)
    assert -0.5 - 1e-6 <= df.loc[0, "A_coded"] <= 0.3 + 1e-6
    assert "d_A" in df.columns


def test_infeasible_start_region_is_left():
    # target 1.9 near the corner: most random starts sit in d = 0 territory (limits [1.8, 2.0])
    m = _circle_model()
    df = desirability_optimise({"y": m}, {"y": {"goal": "target", "value": 1.9, "low": 1.8, "high": 2.0}},
                               n_starts=8, seed=5, n_solutions=3)
    assert np.allclose(df["y"], 1.9, atol=1e-4)


def test_deterministic_for_a_seed():
    g = {"y": {"goal": "target", "value": 0.5}}
    a = desirability_optimise({"y": _circle_model()}, g, n_starts=10, seed=11)
    b = desirability_optimise({"y": _circle_model()}, g, n_starts=10, seed=11)
    pd.testing.assert_frame_equal(a, b)
    assert a.attrs["seed"] == 11


def test_a_longer_search_s_first_ends_are_the_shorter_search_s():
    # the random starts are drawn in order from one generator, so the end points of a search
    # with 10 starts are the first 11 of one with 40 (the centre first): handed those, the
    # 10-start optimisation and the near-optimal sets are the ones they compute themselves
    from soilcal.optimise.desirability import search_ends
    from soilcal.optimise.near_optimal import near_optimal_sets

    g = {"y": {"goal": "target", "value": 0.5}}
    ends = search_ends({"y": _circle_model()}, g, n_starts=40, seed=11)
    assert ends.shape == (41, 2)
    a = desirability_optimise({"y": _circle_model()}, g, n_starts=10, seed=11)
    b = desirability_optimise({"y": _circle_model()}, g, n_starts=10, seed=11, ends=ends)
    pd.testing.assert_frame_equal(a, b, check_exact=True)
    a = near_optimal_sets({"y": _circle_model()}, g, n_starts=40, seed=11)
    b = near_optimal_sets({"y": _circle_model()}, g, n_starts=40, seed=11, ends=ends)
    pd.testing.assert_frame_equal(a, b, check_exact=True)
    # fewer end points than the starts asked for, or of another number of factors: refused
    with pytest.raises(InputError) as e:
        desirability_optimise({"y": _circle_model()}, g, n_starts=60, seed=11, ends=ends)
    assert e.value.field == "ends" and "at least 60 starts" in e.value.expected
    with pytest.raises(InputError) as e:
        desirability_optimise({"y": _circle_model()}, g, n_starts=10, seed=11, ends=ends[:, :1])
    assert e.value.field == "ends"


def test_bad_inputs_are_named():
    m = _circle_model()
    with pytest.raises(InputError, match="goals.z"):
        desirability_optimise({"y": m}, {"z": {"goal": "maximize"}})
    other = Poly(lambda X: X[:, 0], 2, low=[0, 0], high=[3, 3])
    with pytest.raises(InputError, match="models.w"):
        desirability_optimise({"y": m, "w": other}, {"y": {"goal": "maximize"}})
    with pytest.raises(InputError, match="bounds"):
        desirability_optimise({"y": m}, {"y": {"goal": "maximize"}}, bounds=[[0, 1]])
    with pytest.raises(InputError, match="low/high"):
        desirability_optimise({"y": Poly(lambda X: X[:, 0], 2)}, {"y": {"goal": "maximize"}})


def test_on_a_fitted_response_surface():
    """Exact quadratic data on a 3-factor Box-Behnken: the fitted model reproduces it, and every
    target solution predicts the target."""
    from soilcal.doe import box_behnken
    from soilcal.rsm import fit_response_surface

    X = box_behnken(3, 3)
    y = 27 + 2 * X[:, 0] - 3 * X[:, 1] + 1.5 * X[:, 2] + X[:, 0] * X[:, 1] + 2 * X[:, 1] ** 2
    data = pd.DataFrame({"A": X[:, 0], "B": X[:, 1], "C": X[:, 2], "angle": y})
    fit = fit_response_surface(data, ["A", "B", "C"], "angle", [0.1, 0.2, 0.3], [0.5, 0.6, 0.9])
    df = desirability_optimise({"angle": fit}, {"angle": {"goal": "target", "value": 27.69}},
                               n_starts=20, seed=0, n_solutions=5)
    assert len(df) >= 2
    assert np.allclose(df["angle"], 27.69, atol=1e-3)
    Xc = df[["A_coded", "B_coded", "C_coded"]].to_numpy()
    exact = 27 + 2 * Xc[:, 0] - 3 * Xc[:, 1] + 1.5 * Xc[:, 2] + Xc[:, 0] * Xc[:, 1] + 2 * Xc[:, 1] ** 2
    assert np.allclose(exact, 27.69, atol=1e-3)
    assert np.allclose(df["C"], 0.6 + 0.3 * df["C_coded"])
