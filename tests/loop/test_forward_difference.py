"""The loop's fits hand scipy's ``least_squares`` their own forward-difference Jacobian
(:func:`soilcal.loop.select.forward_difference`): every fit must be the one scipy gives with
its default ``jac='2-point'``, bit for bit (parameters, cost, residuals, Jacobian, gradient,
evaluation counts, status), on problems of the loop's shapes: one to three parameters, one
residual or many, minima inside the bounds, on a bound and beyond it, starts on a bound,
negative and zero parameters, and residuals that turn non-finite in part of the box."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import least_squares

from soilcal.loop import select as sl


def _problems():
    rng = np.random.default_rng(3)
    t = np.linspace(-1.0, 2.0, 9)
    y = 1.3 * np.exp(-0.7 * t) + 0.01 * rng.standard_normal(len(t))
    yield "exp decay", lambda x: x[0] * np.exp(-x[1] * t) - y, np.array([0.1, -2.0]), np.array([5.0, 3.0]), [
        np.array([1.0, 0.0]), np.array([0.1, -2.0]), np.array([5.0, 3.0])]
    # the minimum beyond the upper bound of the first parameter: the fit ends on it
    yield "beyond a bound", lambda x: np.array([x[0] - 4.0, 2.0 * (x[1] + 0.3), x[0] * x[1] - 1.0]), \
        np.array([-1.0, -1.0]), np.array([2.5, 1.0]), [np.array([0.0, 0.0]), np.array([2.5, -1.0])]
    # one residual, one parameter, a quartic
    yield "one residual", lambda x: np.array([(x[0] - 0.2) ** 2 * (x[0] + 3.0) - 0.05]), \
        np.array([-0.9]), np.array([9.0]), [np.array([0.0]), np.array([-0.5]), np.array([9.0])]
    # three parameters, a quadratic surrogate-like surface with a relative error
    m = 1.0 + 0.1 * rng.standard_normal(12)
    A = rng.standard_normal((12, 3))
    yield "three parameters", lambda x: (m - (1.0 + A @ x + 0.3 * (A ** 2) @ (x ** 2))) / np.abs(m), \
        np.array([-0.3, -0.3, 0.0]), np.array([0.6, 0.3, 0.8]), [np.zeros(3), np.array([0.6, -0.3, 0.4])]
    # residuals that are not finite in part of the box: the trust region shrinks there
    yield "not finite", lambda x: np.array([np.log(x[0]) - 0.5 if x[0] > 0.05 else np.nan, x[0] - 1.0]), \
        np.array([-1.0]), np.array([3.0]), [np.array([2.9]), np.array([0.5])]


@pytest.mark.parametrize("name, fun, lo, hi, starts", list(_problems()), ids=[p[0] for p in _problems()])
def test_a_fit_with_the_forward_difference_is_scipys_own(name, fun, lo, hi, starts):
    for x0 in starts:
        ref = least_squares(fun, x0, bounds=(lo, hi), method="trf")
        residuals, jac = sl.forward_difference(fun, lo, hi)
        got = least_squares(residuals, x0, jac=jac, bounds=(lo, hi), method="trf")
        for k in ("x", "cost", "fun", "jac", "grad", "optimality", "active_mask", "nfev", "njev", "status"):
            a, b = np.asarray(ref[k]), np.asarray(got[k])
            assert a.shape == b.shape and a.tobytes() == b.tobytes(), (name, x0, k, ref[k], got[k])
            assert a.flags.c_contiguous == b.flags.c_contiguous, (name, x0, k)  # the same layout for BLAS


def test_the_jacobian_away_from_the_last_point_is_scipys_too():
    # a Jacobian asked at a point other than the last one evaluated computes its residuals
    from scipy.optimize._numdiff import approx_derivative

    def fun(x):
        return np.array([x[0] ** 2 - x[1], np.sin(x[0]) * x[1], x[1] ** 3])

    lo, hi = np.array([-1.0, 0.0]), np.array([1.0, 2.0])
    residuals, jac = sl.forward_difference(fun, lo, hi)
    residuals(np.array([0.3, 0.3]))
    for x in (np.array([0.9999999999, 1.9999999999]), np.array([-1.0, 0.0]), np.array([-0.2, 1.0])):
        ref = approx_derivative(fun, x, method="2-point", bounds=(lo, hi))
        assert jac(x).tobytes() == ref.tobytes()
