"""Response transformation advice (Design-Expert "Transform" and Box-Cox plot).

Ratio rule: Design-Expert advises a transformation when max(y)/min(y) > 10 (a ratio above 10
usually indicates one is needed; below 3 it has little effect).

Box-Cox (Box & Cox 1964; Montgomery sec. 15.1.1): for a model matrix X and positive y, the
geometric-mean-scaled power transform

    y(lambda) = (y^lambda - 1) / (lambda * g^(lambda-1)),  lambda != 0;   g ln y, lambda = 0,

with g the geometric mean of y, makes residual sums of squares comparable across lambda.
The best lambda minimises SS_E(lambda); the approximate 100(1-alpha)% confidence interval is
{lambda : SS_E(lambda) <= SS* (1 + t^2_{alpha/2, nu} / nu)}, SS* = min SS_E, nu = residual
df -- the interval Design-Expert draws on its Box-Cox plot (as ln SS_E).
Standard lambdas map to Design-Expert names: 1 none, 0.5 sqrt, 0 ln, -0.5 inverse_sqrt,
-1 inverse. The recommendation is "none" when 1 lies inside the interval, otherwise the
standard lambda inside the interval closest to the best one (or ('power', lambda_best)).
"""

from __future__ import annotations

import numpy as np
from scipy import optimize, stats

from soilcal.errors import InputError

STANDARD_LAMBDAS = {1.0: "none", 0.5: "sqrt", 0.0: "ln", -0.5: "inverse_sqrt", -1.0: "inverse"}


def transform_suggestion(y, threshold: float = 10.0) -> dict:
    """max/min ratio rule: recommend 'sqrt' when the ratio exceeds ``threshold``."""
    y = np.asarray(y, dtype=float).reshape(-1)
    if y.size == 0 or not np.all(np.isfinite(y)):
        raise InputError(None, "y", "finite response values", y)
    lo, hi = float(y.min()), float(y.max())
    if lo <= 0:
        return {
            "ratio": float("nan"),
            "recommend": "none",
            "reason": f"min(y) = {lo:g} <= 0: power transforms need a positive response (add a constant first)",
        }
    ratio = hi / lo
    if ratio > threshold:
        return {"ratio": ratio, "recommend": "sqrt", "reason": f"max/min = {ratio:.3g} > {threshold:g}: a transformation is advised"}
    return {"ratio": ratio, "recommend": "none", "reason": f"max/min = {ratio:.3g} <= {threshold:g}: no transformation needed"}


def _sse_lambda(X: np.ndarray, y: np.ndarray, lam: float) -> float:
    g = np.exp(np.mean(np.log(y)))
    if abs(lam) < 1e-12:
        z = g * np.log(y)
    else:
        z = (y**lam - 1.0) / (lam * g ** (lam - 1.0))
    beta, *_ = np.linalg.lstsq(X, z, rcond=None)
    r = z - X @ beta
    return float(r @ r)


def boxcox(fit_or_X, y=None, alpha: float = 0.05, lambdas=None) -> dict:
    """Box-Cox analysis of a fitted model (RSMFit, uses its model matrix and observed y)
    or of an explicit model matrix ``X`` (with intercept column) and response ``y``.

    Returns lambda_best, ci_low, ci_high, recommended_transform, the lambda grid and
    ln SS_E on it (for the plot), the threshold line and ``ci_note``: where the 95 % interval
    reaches past an end of the searched lambda range its limit is -inf or inf and the note
    says so (empty otherwise).
    """
    if y is None:
        X = np.asarray(fit_or_X.model_matrix, dtype=float)
        yy = np.asarray(fit_or_X.observed, dtype=float) + getattr(fit_or_X, "transform_constant", 0.0)
    else:
        X = np.atleast_2d(np.asarray(fit_or_X, dtype=float))
        yy = np.asarray(y, dtype=float).reshape(-1)
    if np.any(yy <= 0):
        raise InputError(None, "y", "positive response values for Box-Cox", float(yy.min()))
    n, p = X.shape
    nu = n - p
    if nu < 1:
        raise InputError(None, "X", "more runs than model parameters", (n, p))
    grid = np.linspace(-3, 3, 601) if lambdas is None else np.asarray(lambdas, dtype=float)
    sse = np.array([_sse_lambda(X, yy, l) for l in grid])
    i = int(np.argmin(sse))
    lo_b, hi_b = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
    if hi_b > lo_b:
        res = optimize.minimize_scalar(lambda l: _sse_lambda(X, yy, l), bounds=(lo_b, hi_b), method="bounded")
        lam_best, sse_min = float(res.x), float(res.fun)
    else:
        lam_best, sse_min = float(grid[i]), float(sse[i])
    t = stats.t.ppf(1 - alpha / 2, nu)
    thresh = sse_min * (1.0 + t**2 / nu)
    f = lambda l: _sse_lambda(X, yy, l) - thresh  # noqa: E731
    def edge(a, b):
        try:
            return float(optimize.brentq(f, a, b))
        except ValueError:
            return float("nan")
    ci_low = edge(grid[0], lam_best) if f(grid[0]) > 0 else float("-inf")
    ci_high = edge(lam_best, grid[-1]) if f(grid[-1]) > 0 else float("inf")
    open_ends = [side for side, v in (("below", ci_low), ("above", ci_high)) if np.isinf(v)]
    if len(open_ends) == 2:
        ci_note = (f"the 95 % interval of lambda covers the whole searched range {grid[0]:g} to {grid[-1]:g}: "
                   "the data do not tell a transform apart")
    elif open_ends:
        end = grid[0] if open_ends[0] == "below" else grid[-1]
        ci_note = f"the 95 % interval of lambda reaches past {end:g}, the end of the searched range"
    else:
        ci_note = ""
    inside = [l for l in STANDARD_LAMBDAS if ci_low <= l <= ci_high]
    if 1.0 in inside:
        rec = "none"
    elif inside:
        rec = STANDARD_LAMBDAS[min(inside, key=lambda l: abs(l - lam_best))]
    else:
        rec = ("power", round(lam_best, 2))
    return {
        "lambda_best": lam_best,
        "ci_low": ci_low,
        "ci_high": ci_high,
        "recommended_transform": rec,
        "lambda_grid": grid,
        "ln_sse": np.log(sse),
        "ln_sse_threshold": float(np.log(thresh)),
        "alpha": alpha,
        "ci_note": ci_note,
    }


__all__ = ["transform_suggestion", "boxcox", "STANDARD_LAMBDAS"]
