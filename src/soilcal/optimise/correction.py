"""Bias correction of a response surface from verification runs at its optimum.

A response surface yhat(x) fitted to the design points predicts the target at the calibrated
set x0; the mean ybar of n verification runs there may still differ from yhat(x0) by more than
the run-to-run scatter explains, where the quadratic misrepresents the simulation near x0.
The bias-corrected surface

    yhat_c(x) = yhat(x) + b,    b = ybar(x0) - yhat(x0),

agrees with the verification mean at x0 and keeps the fitted slopes: the zeroth-order
correction of space mapping (Bandler et al., IEEE Trans. MTT 52 (2004) 337) and of a
constant model discrepancy (Kennedy & O'Hagan, JRSS B 63 (2001) 425).  A bias is applied only
when it exceeds two standard errors of the difference ybar - yhat(x0), the verification mean's
and the surface's own at x0 together (:func:`significant_bias`): a smaller one is scatter of
the seeds or of the fit, and correcting by it would chase noise.

The corrected set (:func:`corrected_set`) is the smallest move from x0 (coded Euclidean
distance) at which every corrected surface meets its target, within the factor box: the bias
was measured at x0 and holds best near it.  Solved with scipy's SLSQP (equality constraints
yhat_c,r(x) = T_r) from x0 and from the corrected surfaces' own desirability optima; when no
start reaches every target the corrected surfaces cannot meet them inside the design region
and the result says so, with their least-squares compromise inside the box instead.  Where a
target lies beyond its corrected surface's range over the bounds (a quadratic's exact range,
:meth:`soilcal.rsm.model.RSMFit.extremes`) no start can reach it, and the search goes straight
to the compromise.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from scipy import optimize

from soilcal.errors import InputError

#: a bias counts when |ybar - yhat(x0)| exceeds this many standard errors of that difference
SIGNIFICANCE = 2.0


def _number(v) -> float:
    try:
        return float(v)
    except (TypeError, ValueError):
        return math.nan


def significant_bias(mean: float, sd: float, n: int, predicted: float, predicted_se: float = 0.0,
                     k: float = SIGNIFICANCE) -> float:
    """``mean - predicted`` when it exceeds ``k`` standard errors of that difference,
    sqrt(sd^2 / n + predicted_se^2): the mean of ``n >= 2`` runs of SD ``sd`` and the surface's
    prediction of standard error ``predicted_se`` (:meth:`soilcal.rsm.model.RSMFit.predict_se`;
    0 for a prediction known exactly) are independent estimates of the response at the set;
    otherwise 0 (no evidence of a bias).  Numbers of any numeric type; NaN inputs give 0."""
    m, s, p, ps = _number(mean), _number(sd), _number(predicted), _number(predicted_se)
    if n < 2 or not all(math.isfinite(v) for v in (m, s, p, ps)):
        return 0.0
    b = m - p
    return b if abs(b) > k * math.sqrt(s * s / n + ps * ps) else 0.0


class Shifted:
    """A fitted model plus a constant: ``predict(X) = model.predict(X) + bias`` (coded input),
    ``predict_actual`` likewise; ``observed`` shifted too, so that a goal's default limits
    (the observed range) keep their place relative to the predictions."""

    def __init__(self, model: Any, bias: float):
        self.model, self.bias = model, float(bias)
        self.factors, self.low, self.high = model.factors, model.low, model.high
        obs = getattr(model, "observed", None)
        self.observed = None if obs is None else np.asarray(obs, float) + self.bias

    def predict(self, X_coded) -> np.ndarray:
        return np.asarray(self.model.predict(X_coded), float) + self.bias

    def predict_actual(self, X_actual) -> np.ndarray:
        return np.asarray(self.model.predict_actual(X_actual), float) + self.bias


def corrected_set(models: Mapping[str, Any], targets: Mapping[str, float], bias: Mapping[str, float],
                  x0_coded, starts=(), tol: float = 1e-6, lower=None, upper=None) -> dict:
    """The smallest coded move from ``x0_coded`` at which ``models[r] + bias[r]`` equals
    ``targets[r]`` for every r in ``targets``, inside the coded box [-1, 1]^k, or inside
    ``lower`` .. ``upper`` (coded, per factor) where given (a region reaching past the box,
    :func:`soilcal.chain.refine.refine_frame`).

    ``starts``: further starting points (coded), e.g. the corrected surfaces' desirability
    optima.  Returns dict(success, x_coded, predicted {r: corrected prediction}, move (coded
    distance from x0), residual (largest |prediction - target|)); when no start meets every
    target within ``tol`` times max(1, |target|), ``success`` is False and ``x_coded`` is the
    least-squares compromise of the corrected surfaces (:func:`compromise`; residuals scaled by
    max(1, |target|)).
    """
    if not targets:
        raise InputError(None, "targets", "at least one response with a target value", targets)
    missing = [r for r in targets if r not in models]
    if missing:
        raise InputError(None, "targets", f"responses among the models {list(models)}", missing)
    x0 = np.asarray(x0_coded, float).reshape(-1)
    k = x0.size
    for r in targets:
        factors = list(models[r].factors)
        if len(factors) != k:
            raise InputError(None, "x0_coded", f"{len(factors)} coded values, one per factor {factors} of {r}", k)
    shifted = {r: Shifted(models[r], bias.get(r, 0.0)) for r in targets}
    scale = {r: max(1.0, abs(float(t))) for r, t in targets.items()}

    def residuals(x):
        return np.array([(float(shifted[r].predict(x[None, :])[0]) - float(t)) / scale[r]
                         for r, t in targets.items()])

    cons = [{"type": "eq", "fun": residuals}]
    lo = np.full(k, -1.0) if lower is None else np.asarray(lower, float).reshape(-1)
    hi = np.full(k, 1.0) if upper is None else np.asarray(upper, float).reshape(-1)
    if lo.size != k or hi.size != k or np.any(lo > hi):
        raise InputError(None, "lower/upper", f"{k} coded bounds with lower <= upper", (lo, hi))
    box = list(zip(lo, hi))
    best = None
    pts = [x0, *(np.asarray(p, float).reshape(-1) for p in starts)]
    # a target farther from a surface's range over the bounds than the tolerance is met by no
    # set there, so no start can succeed: the least-squares compromise below is the answer
    # (surfaces without a closed-form range, models without .extremes, are searched as ever)
    for s in ([] if _out_of_reach(shifted, targets, scale, lo, hi, tol) else pts):
        s = np.clip(s, lo, hi)
        res = optimize.minimize(lambda x: float(np.sum((x - x0) ** 2)), s, jac=lambda x: 2.0 * (x - x0),
                                method="SLSQP", bounds=box, constraints=cons,
                                options={"ftol": 1e-12, "maxiter": 500})
        x = np.clip(res.x, lo, hi)
        worst = float(np.max(np.abs(residuals(x))))
        key = (worst > tol, float(np.linalg.norm(x - x0)) if worst <= tol else worst)
        if best is None or key < best[0]:
            best = (key, x, worst)
    _, x, worst = best if best is not None else (None, None, math.inf)
    if worst > tol:
        x = compromise(residuals, x0, pts, lo, hi)
    pred = {r: float(shifted[r].predict(x[None, :])[0]) for r in targets}
    return {"success": worst <= tol, "x_coded": x, "predicted": pred,
            "move": float(np.linalg.norm(x - x0)),
            "residual": max(abs(pred[r] - float(t)) for r, t in targets.items())}


def _out_of_reach(shifted: Mapping[str, Shifted], targets: Mapping[str, float], scale: Mapping[str, float],
                  lo: np.ndarray, hi: np.ndarray, tol: float) -> bool:
    """Whether some response's target lies farther than ``tol`` (scaled) beyond the range of its
    corrected surface over ``lo`` .. ``hi`` (:meth:`soilcal.rsm.model.RSMFit.extremes`), by a
    margin of 1e-9 (scaled) over the rounding of that range."""
    for r, t in targets.items():
        ext = getattr(shifted[r].model, "extremes", None)
        rng = ext(lo, hi) if ext is not None else None
        if rng is None:
            continue
        low, high = rng[0] + shifted[r].bias, rng[1] + shifted[r].bias
        gap = max(low - float(t), float(t) - high) / scale[r]
        if gap > tol + 1e-9 * max(1.0, abs(low) / scale[r], abs(high) / scale[r]):
            return True
    return False


def compromise(residuals, x0, starts, lo, hi, step_weight: float = 1e-6) -> np.ndarray:
    """Where the targets cannot all be met: the set within the coded bounds ``lo`` .. ``hi``
    minimising the sum of squared scaled residuals (plus ``step_weight`` |x - x0|^2, which picks
    the least move among equally good sets), by L-BFGS-B from every start."""
    x0 = np.asarray(x0, float)

    def f(x):
        return float(np.sum(residuals(x) ** 2) + step_weight * np.sum((x - x0) ** 2))

    ends = [optimize.minimize(f, np.clip(s, lo, hi), method="L-BFGS-B", bounds=list(zip(lo, hi))).x
            for s in starts]
    return np.clip(min(ends, key=f), lo, hi)
