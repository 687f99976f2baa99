"""Bias correction of a response surface (soilcal.optimise.correction) on analytic models whose
corrected sets are known in closed form: for a linear surface y = a + g.x the smallest move
from x0 that changes y by -b is the projection dx = -b g / |g|^2."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from soilcal.errors import InputError
from soilcal.optimise.correction import Shifted, corrected_set, significant_bias


class Lin:
    """y = f(X_coded) on three factors with actual bounds [10, 20], [100, 300], [0, 1]."""

    factors = ["x1", "x2", "x3"]
    low = np.array([10.0, 100.0, 0.0])
    high = np.array([20.0, 300.0, 1.0])
    observed = np.array([28.0, 32.0])

    def __init__(self, f):
        self.f = f

    def predict(self, X):
        return self.f(np.atleast_2d(np.asarray(X, float)))

    def predict_actual(self, X):
        X = np.atleast_2d(np.asarray(X, float))
        return self.predict((X - (self.low + self.high) / 2) / ((self.high - self.low) / 2))


def test_significant_bias_two_standard_errors():
    # mean 32 of 4 runs with sd 0.5: standard error 0.25, two of them 0.5 < |32 - 31| = 1
    assert significant_bias(32.0, 0.5, 4, 31.0) == pytest.approx(1.0)
    assert significant_bias(30.0, 0.5, 4, 31.0) == pytest.approx(-1.0)
    # sd 1.0: two standard errors 1.0, not exceeded by the bias 1.0
    assert significant_bias(32.0, 1.0, 4, 31.0) == 0.0
    # one run has no scatter estimate; NaNs are no evidence
    assert significant_bias(32.0, 0.1, 1, 31.0) == 0.0
    assert significant_bias(float("nan"), 0.1, 4, 31.0) == 0.0
    assert significant_bias(32.0, float("nan"), 4, 31.0) == 0.0


def test_significant_bias_counts_the_surfaces_own_error():
    # the surface's prediction of standard error 0.5 beside the mean's 0.25: the difference's
    # standard error is sqrt(0.25^2 + 0.5^2) = 0.559, two of them 1.118 > |32 - 31|: no bias
    assert 2 * math.sqrt(0.25 ** 2 + 0.5 ** 2) > 1.0
    assert significant_bias(32.0, 0.5, 4, 31.0, 0.5) == 0.0
    # 0.3: sqrt(0.0625 + 0.09) = 0.39, two of them 0.78 < 1: a bias
    assert significant_bias(32.0, 0.5, 4, 31.0, 0.3) == pytest.approx(1.0)
    # numbers of numpy's types count as numbers
    assert significant_bias(np.float32(32.0), np.float64(0.5), np.int64(4), np.int64(31), np.float32(0.3)) \
        == pytest.approx(1.0)
    assert significant_bias(32.0, 0.5, 4, 31.0, float("nan")) == 0.0


def test_shifted_model_adds_the_bias_everywhere():
    m = Lin(lambda X: 30.0 + 2.0 * X[:, 0])
    s = Shifted(m, 1.5)
    assert s.predict([[0.5, 0, 0]])[0] == pytest.approx(32.5)
    assert s.predict_actual([[17.5, 200.0, 0.5]])[0] == pytest.approx(32.5)  # x1 = 17.5 is coded 0.5
    assert np.allclose(s.observed, [29.5, 33.5])
    assert (s.factors, list(s.low), list(s.high)) == (m.factors, list(m.low), list(m.high))


def test_one_effective_factor_moves_alone():
    # y = 30 + 2 x1 predicts the target 31 at x0 = (0.5, 0.3, -0.2); the runs there average 32
    # (bias +1): the corrected surface 31 + 2 x1 meets 31 at x1 = 0, the inert x2, x3 stay put
    m = Lin(lambda X: 30.0 + 2.0 * X[:, 0])
    res = corrected_set({"y": m}, {"y": 31.0}, {"y": 1.0}, [0.5, 0.3, -0.2])
    assert res["success"]
    assert np.allclose(res["x_coded"], [0.0, 0.3, -0.2], atol=1e-6)
    assert res["move"] == pytest.approx(0.5, abs=1e-6)
    assert res["predicted"]["y"] == pytest.approx(31.0, abs=1e-6)


def test_the_move_is_the_projection_onto_the_gradient():
    # y = 30 + 2 x1 + x2, x0 = (0.5, 0, 0) predicts 31; bias +1 asks y to drop by 1:
    # dx = -1 (2, 1, 0) / 5 = (-0.4, -0.2, 0), |dx| = 1/sqrt(5)
    m = Lin(lambda X: 30.0 + 2.0 * X[:, 0] + X[:, 1])
    res = corrected_set({"y": m}, {"y": 31.0}, {"y": 1.0}, [0.5, 0.0, 0.0])
    assert res["success"]
    assert np.allclose(res["x_coded"], [0.1, -0.2, 0.0], atol=1e-6)
    assert res["move"] == pytest.approx(1 / math.sqrt(5), abs=1e-6)


def test_two_targets_meet_at_the_intersection_nearest_x0():
    # static y1 = 30 + 2 x1, dynamic y2 = 40 + 2 x2, both on target at x0 = (0.5, 0.5, 0);
    # biases +1 and -1: y1 needs x1 = 0, y2 needs x2 = 1; x3 is free and stays at 0
    models = {"s": Lin(lambda X: 30.0 + 2.0 * X[:, 0]), "d": Lin(lambda X: 40.0 + 2.0 * X[:, 1])}
    res = corrected_set(models, {"s": 31.0, "d": 41.0}, {"s": 1.0, "d": -1.0}, [0.5, 0.5, 0.0])
    assert res["success"]
    assert np.allclose(res["x_coded"], [0.0, 1.0, 0.0], atol=1e-6)
    assert res["move"] == pytest.approx(math.sqrt(0.5), abs=1e-6)


def test_a_target_out_of_reach_is_not_met():
    # bias +5: 35 + 2 x1 = 31 needs x1 = -2, outside the coded box
    m = Lin(lambda X: 30.0 + 2.0 * X[:, 0])
    res = corrected_set({"y": m}, {"y": 31.0}, {"y": 5.0}, [0.5, 0.2, 0.0])
    assert not res["success"]
    assert np.allclose(res["x_coded"], [-1.0, 0.2, 0.0], atol=1e-4)  # the closest the box allows
    assert res["residual"] == pytest.approx(2.0, abs=1e-4)  # 35 - 2 = 33 vs 31


def test_two_targets_pulling_apart_meet_in_the_least_squares_compromise():
    # y1 = 30 + 2 x1 (target 31, bias +1) needs x1 = 0, y2 = 40 + 2 x1 (target 41, bias -1)
    # needs x1 = 1.  Residuals scaled by the targets: minimise (2 x1 / 31)^2 + ((2 x1 - 2) / 41)^2,
    # x1 / 31^2 + (x1 - 1) / 41^2 = 0, x1 = 31^2 / (31^2 + 41^2) = 961 / 2642; x2, x3 stay put
    models = {"s": Lin(lambda X: 30.0 + 2.0 * X[:, 0]), "d": Lin(lambda X: 40.0 + 2.0 * X[:, 0])}
    res = corrected_set(models, {"s": 31.0, "d": 41.0}, {"s": 1.0, "d": -1.0}, [0.5, 0.3, -0.4])
    assert not res["success"]
    assert np.allclose(res["x_coded"], [961 / 2642, 0.3, -0.4], atol=1e-3)
    assert res["predicted"]["s"] == pytest.approx(31.0 + 2 * 961 / 2642, abs=2e-3)


def test_bad_inputs_are_named():
    m = Lin(lambda X: 30.0 + 2.0 * X[:, 0])
    with pytest.raises(InputError, match="targets"):
        corrected_set({"y": m}, {}, {}, [0, 0, 0])
    with pytest.raises(InputError, match="targets"):
        corrected_set({"y": m}, {"z": 31.0}, {}, [0, 0, 0])


def _bowl(transform="none"):
    """y = 1 + 2 A - A^2 + B^2 (coded A, B), fitted exactly to a 3 x 3 grid (ln transform: the
    grid's exp(y)).  Over A, B in [-1, 1] it ranges over [-2, 3]: 2 A - A^2 rises from -3 to 1
    and B^2 from 0 to 1, so the lowest value lies on the face A = -1 at B = 0, where no
    vertex is (the vertices give -1, -1, 3, 3)."""
    from soilcal.rsm.model import fit_response_surface

    a, b = np.meshgrid([-1.0, 0.0, 1.0], [-1.0, 0.0, 1.0])
    df = pd.DataFrame({"A": a.ravel(), "B": b.ravel()})
    y = 1 + 2 * df["A"] - df["A"] ** 2 + df["B"] ** 2
    df["y"] = np.exp(y) if transform == "ln" else y
    return fit_response_surface(df, ["A", "B"], "y", [-1.0, -1.0], [1.0, 1.0], transform=transform)


def test_a_quadratic_s_range_over_a_box_reaches_the_extremes_inside_its_faces():
    m = _bowl()
    assert m.extremes([-1.0, -1.0], [1.0, 1.0]) == pytest.approx((-2.0, 3.0), abs=1e-9)
    # past the box: A over -1 .. 2 peaks at its stationary point A = 1 (2 A - A^2 = 1), B over
    # -0.5 .. 2 gives B^2 from 0 to 4: [1 - 3 + 0, 1 + 1 + 4]
    assert m.extremes([-1.0, -0.5], [2.0, 2.0]) == pytest.approx((-2.0, 6.0), abs=1e-9)
    # an increasing back-transform keeps the places of the extremes
    assert _bowl("ln").extremes([-1.0, -1.0], [1.0, 1.0]) == pytest.approx((math.exp(-2.0), math.exp(3.0)),
                                                                            rel=1e-9)
    # a decreasing or non-monotone one (1 / y) has no range this way
    assert _bowl("inverse").extremes([-1.0, -1.0], [1.0, 1.0]) is None


def test_a_target_met_only_inside_a_face_is_found_and_one_past_the_range_is_not():
    # y = -1.9 lies within the range [-2, 3] only near A = -1, B = 0: the sets meeting it have
    # B^2 = A^2 - 2 A - 2.9, A <= 1 - sqrt(3.9) = -0.9748, at squared distance 2 A^2 - 2 A - 2.9
    # from (0, 0), least at the largest A: the nearest is (1 - sqrt(3.9), 0)
    m = _bowl()
    res = corrected_set({"y": m}, {"y": -1.9}, {}, [0.0, 0.0])
    assert res["success"] and res["x_coded"] == pytest.approx([1 - math.sqrt(3.9), 0.0], abs=1e-5)
    # y = -2.5 is below the whole range: no set meets it, the compromise is the lowest point
    res = corrected_set({"y": m}, {"y": -2.5}, {}, [0.0, 0.0])
    assert not res["success"] and res["x_coded"] == pytest.approx([-1.0, 0.0], abs=1e-4)
    assert res["predicted"]["y"] == pytest.approx(-2.0, abs=1e-6)


def test_the_bias_shifts_the_range_a_target_is_judged_against():
    # the corrected surface y + b: with b = +10 it ranges over [8, 13], so 10 is met where
    # 11 + 2 A - A^2 + B^2 = 10; the sets have B^2 = A^2 - 2 A - 1 >= 0, A <= 1 - sqrt(2), at
    # squared distance 2 A^2 - 2 A - 1 from (0, 0), least at the largest A: (1 - sqrt(2), 0)
    m = _bowl()
    res = corrected_set({"y": m}, {"y": 10.0}, {"y": 10.0}, [0.0, 0.0])
    assert res["success"] and res["x_coded"] == pytest.approx([1 - math.sqrt(2.0), 0.0], abs=1e-5)
    # b = -10: [-12, -7] holds -8.5, met where 2 A - A^2 + B^2 = 0.5, nearest at (1 - sqrt(0.5), 0)
    res = corrected_set({"y": m}, {"y": -8.5}, {"y": -10.0}, [0.0, 0.0])
    assert res["success"] and res["x_coded"] == pytest.approx([1 - math.sqrt(0.5), 0.0], abs=1e-5)


def test_a_target_past_the_range_goes_to_the_compromise_without_the_search(monkeypatch):
    # -2.5 lies below the range [-2, 3]: no SLSQP start is run (each would end at its
    # iteration limit), the least-squares compromise (L-BFGS-B) is the answer
    from scipy import optimize

    import soilcal.optimise.correction as correction

    def minimize(*args, method=None, **kw):
        assert method != "SLSQP", "a search was run for a target past the surface's range"
        return optimize.minimize(*args, method=method, **kw)

    monkeypatch.setattr(correction, "optimize", type("Opt", (), {"minimize": staticmethod(minimize)}))
    res = corrected_set({"y": _bowl()}, {"y": -2.5}, {}, [0.0, 0.0])
    assert not res["success"] and res["x_coded"] == pytest.approx([-1.0, 0.0], abs=1e-4)
    # a target within the range is searched for
    with pytest.raises(AssertionError, match="a search was run"):
        corrected_set({"y": _bowl()}, {"y": -1.9}, {}, [0.0, 0.0])


def test_a_start_or_box_of_another_size_than_the_factors_is_named():
    m = _bowl()
    for x0 in ([0.0, 0.0, 0.0], [0.0]):
        with pytest.raises(InputError) as e:
            corrected_set({"y": m}, {"y": 10.0}, {}, x0)
        assert e.value.field == "x0_coded" and "['A', 'B']" in e.value.expected
    with pytest.raises(InputError) as e:
        m.extremes([-1.0], [1.0, 1.0])
    assert e.value.field == "lower/upper"
