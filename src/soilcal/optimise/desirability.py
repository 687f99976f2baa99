"""Derringer-Suich desirability and its numerical optimisation over a fitted response surface.

Individual desirabilities (Derringer & Suich 1980, J. Qual. Technol. 12:214, Eqs. 3-5; the
forms and defaults Design-Expert uses), for a predicted response y with lower limit L, upper
limit U, weights w (w_L, w_U on either side of a target T):

    maximize:  d = 0                      y <= L
               d = ((y - L)/(U - L))^w    L < y < U
               d = 1                      y >= U
    minimize:  d = 1                      y <= L
               d = ((U - y)/(U - L))^w    L < y < U
               d = 0                      y >= U
    target:    d = ((y - L)/(T - L))^w_L  L <= y <= T
               d = ((U - y)/(U - T))^w_U  T <= y <= U
               d = 0                      y < L or y > U
    in_range:  d = 1 if L <= y <= U else 0

Overall desirability with importances r_i (1..5, Design-Expert's "+" to "+++++"):

    D = (prod_i d_i^{r_i})^{1 / sum_i r_i}

Limits not given default to the observed range of the response (Design-Expert's default); in
particular a "target" goal given only its value uses [min(observed), max(observed)].

Search (as Design-Expert's numerical optimisation): many seeded random starts in the coded box
plus the centre point, each refined with the bounded Nelder-Mead simplex of scipy.optimize;
the converged points are clustered (coded distance < ``tol``) and the distinct optima listed
by decreasing D. Where D = 0 (a response outside its limits) the objective adds the normalised
distance to the limits, so the simplex is led out of the flat zero region; it is continuous
with -D at the limits.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping, Protocol, Sequence, runtime_checkable

import numpy as np
import pandas as pd
from scipy import optimize

from soilcal.errors import InputError

GOALS = ("target", "minimize", "maximize", "in_range")
_GOAL_ALIASES = {"minimise": "minimize", "maximise": "maximize", "range": "in_range", "in range": "in_range"}
_GOAL_KEYS = {"goal", "value", "target", "low", "high", "weight", "weight_low", "weight_high", "importance"}


@runtime_checkable
class ResponseModel(Protocol):
    """What the optimiser needs of a fitted model (satisfied by :class:`soilcal.rsm.RSMFit`)."""

    factors: list[str]
    low: np.ndarray
    high: np.ndarray

    def predict(self, X_coded: np.ndarray) -> np.ndarray: ...


# --------------------------------------------------------------------------- single d


def d_maximize(y, low: float, high: float, weight: float = 1.0) -> np.ndarray:
    """Derringer-Suich one-sided desirability for a response to maximise."""
    y = np.asarray(y, dtype=float)
    z = np.clip((y - low) / (high - low), 0.0, 1.0)
    return z**weight


def d_minimize(y, low: float, high: float, weight: float = 1.0) -> np.ndarray:
    """Derringer-Suich one-sided desirability for a response to minimise."""
    y = np.asarray(y, dtype=float)
    z = np.clip((high - y) / (high - low), 0.0, 1.0)
    return z**weight


def d_target(y, target: float, low: float, high: float, weight_low: float = 1.0, weight_high: float = 1.0) -> np.ndarray:
    """Derringer-Suich two-sided desirability: 1 at the target, 0 at and beyond the limits."""
    y = np.asarray(y, dtype=float)
    out = np.zeros_like(y)
    lo = (y >= low) & (y <= target)
    hi = (y > target) & (y <= high)
    if target > low:
        out = np.where(lo, np.clip((y - low) / (target - low), 0.0, 1.0) ** weight_low, out)
    else:
        out = np.where(y == target, 1.0, out)
    if high > target:
        out = np.where(hi, np.clip((high - y) / (high - target), 0.0, 1.0) ** weight_high, out)
    return out


def d_in_range(y, low: float, high: float) -> np.ndarray:
    """1 inside [low, high], 0 outside."""
    y = np.asarray(y, dtype=float)
    return ((y >= low) & (y <= high)).astype(float)


def overall_desirability(d: Sequence[np.ndarray] | np.ndarray, importance: Sequence[float] | None = None) -> np.ndarray:
    """D = (prod d_i^{r_i})^{1/sum r_i}; ``d`` has one row (or entry) per response, columns are
    points; returns one D per point (an array)."""
    d = np.atleast_1d(np.asarray(d, dtype=float))
    if d.ndim == 1:
        d = d[:, None]
    r = np.ones(d.shape[0]) if importance is None else np.asarray(importance, dtype=float)
    if r.shape[0] != d.shape[0]:
        raise InputError(None, "importance", f"{d.shape[0]} values", len(r))
    shape = (-1,) + (1,) * (d.ndim - 1)
    with np.errstate(divide="ignore"):
        logd = np.where(d > 0, np.log(np.where(d > 0, d, 1.0)), -np.inf)
    s = np.sum(r.reshape(shape) * logd, axis=0) / r.sum()
    return np.exp(s)


# --------------------------------------------------------------------------- goal spec


@dataclass(frozen=True)
class Goal:
    """One response (or factor) goal with resolved limits."""

    name: str
    goal: str
    low: float
    high: float
    target: float | None = None
    weight_low: float = 1.0
    weight_high: float = 1.0
    importance: float = 3.0

    def d(self, y) -> np.ndarray:
        if self.goal == "maximize":
            return d_maximize(y, self.low, self.high, self.weight_low)
        if self.goal == "minimize":
            return d_minimize(y, self.low, self.high, self.weight_high)
        if self.goal == "target":
            return d_target(y, self.target, self.low, self.high, self.weight_low, self.weight_high)
        return d_in_range(y, self.low, self.high)

    def d_scalar(self, y: float) -> float:
        """Same as :meth:`d` for one float (the optimiser's inner loop)."""
        lo, hi = self.low, self.high
        if self.goal == "maximize":
            return 0.0 if y <= lo else 1.0 if y >= hi else ((y - lo) / (hi - lo)) ** self.weight_low
        if self.goal == "minimize":
            return 1.0 if y <= lo else 0.0 if y >= hi else ((hi - y) / (hi - lo)) ** self.weight_high
        if self.goal == "target":
            t = self.target
            if y < lo or y > hi:
                return 0.0
            if y <= t:
                return ((y - lo) / (t - lo)) ** self.weight_low if t > lo else float(y == t)
            return ((hi - y) / (hi - t)) ** self.weight_high
        return 1.0 if lo <= y <= hi else 0.0

    def violation_scalar(self, y: float) -> float:
        span = self.high - self.low if self.high > self.low else 1.0
        below = max(self.low - y, 0.0) / span
        above = max(y - self.high, 0.0) / span
        if self.goal == "maximize":
            return below
        if self.goal == "minimize":
            return above
        return below + above

    def violation(self, y) -> np.ndarray:
        """Normalised distance by which y lies on the zero-desirability side of its limits."""
        y = np.asarray(y, dtype=float)
        span = self.high - self.low if self.high > self.low else 1.0
        below = np.maximum(self.low - y, 0.0) / span
        above = np.maximum(y - self.high, 0.0) / span
        if self.goal == "maximize":
            return below
        if self.goal == "minimize":
            return above
        return below + above


def _num(spec: Mapping, key: str, where: str, default=None):
    v = spec.get(key, default)
    if v is None:
        return None
    try:
        v = float(v)
    except (TypeError, ValueError):
        raise InputError(None, f"{where}.{key}", "a number", v) from None
    if not np.isfinite(v):
        raise InputError(None, f"{where}.{key}", "a finite number", v)
    return v


def make_goal(name: str, spec: Mapping[str, Any], observed=None) -> Goal:
    """Resolve a goal spec ``{goal, value, low, high, weight, weight_low, weight_high, importance}``.

    ``value`` (or a numeric ``target``) is the target of a "target" goal; missing ``low``/``high``
    default to the observed range of the response (Design-Expert's default).
    """
    where = f"goals.{name}"
    if not isinstance(spec, Mapping):
        raise InputError(None, where, "a mapping with key 'goal'", spec)
    unknown = set(spec) - _GOAL_KEYS
    if unknown:
        raise InputError(None, where, f"keys among {sorted(_GOAL_KEYS)}", sorted(unknown))
    kind = spec.get("goal")
    kind = _GOAL_ALIASES.get(kind, kind) if isinstance(kind, str) else kind
    if kind not in GOALS:
        raise InputError(None, f"{where}.goal", f"one of {list(GOALS)}", spec.get("goal"))
    target = _num(spec, "value", where)
    if target is None and not isinstance(spec.get("target"), str):
        target = _num(spec, "target", where)
    if kind == "target" and target is None:
        raise InputError(None, f"{where}.value", "the target value of a 'target' goal", None)
    low = _num(spec, "low", where)
    high = _num(spec, "high", where)
    low_given, high_given = low is not None, high is not None
    if low is None or high is None:
        if observed is None or len(np.atleast_1d(observed)) == 0:
            raise InputError(None, f"{where}.low/high", "limits, or a model with observed responses", None)
        obs = np.asarray(observed, dtype=float)
        low = float(np.min(obs)) if low is None else low
        high = float(np.max(obs)) if high is None else high
    if kind == "target":
        # a defaulted (observed-range) limit that does not bracket the target is widened to it
        low = low if low_given else min(low, target)
        high = high if high_given else max(high, target)
        if not low <= target <= high:
            raise InputError(None, f"{where}.value", f"a target within [low, high] = [{low}, {high}]", target)
    if not high > low and kind != "target":
        raise InputError(None, f"{where}.low/high", "low < high", (low, high))
    w = _num(spec, "weight", where, 1.0)
    wl = _num(spec, "weight_low", where, w)
    wh = _num(spec, "weight_high", where, w)
    for key, v in (("weight", w), ("weight_low", wl), ("weight_high", wh)):
        if not 0.1 <= v <= 10.0:
            raise InputError(None, f"{where}.{key}", "a weight in [0.1, 10] (Design-Expert's range)", v)
    imp = _num(spec, "importance", where, 3.0)
    if not 1.0 <= imp <= 5.0:
        raise InputError(None, f"{where}.importance", "an importance from 1 to 5", imp)
    return Goal(name, kind, float(low), float(high), target, float(wl), float(wh), float(imp))


# --------------------------------------------------------------------------- optimiser


def _check_models(models: Mapping[str, Any]) -> tuple[list[str], np.ndarray, np.ndarray]:
    if not isinstance(models, Mapping) or not models:
        raise InputError(None, "models", "a non-empty mapping response name -> fitted model", type(models).__name__)
    first = None
    for name, m in models.items():
        for attr in ("factors", "low", "high", "predict"):
            if not hasattr(m, attr):
                raise InputError(None, f"models.{name}", f"a fitted model with .{attr}", type(m).__name__)
        sig = (list(m.factors), np.asarray(m.low, float), np.asarray(m.high, float))
        if first is None:
            first = sig
        elif sig[0] != first[0] or not (np.allclose(sig[1], first[1]) and np.allclose(sig[2], first[2])):
            raise InputError(None, f"models.{name}", f"the same factors and bounds as the others {first[0]}", sig[0])
    return first


def _coded_bounds(bounds, factors: list[str]) -> np.ndarray:
    k = len(factors)
    if bounds is None:
        return np.tile([-1.0, 1.0], (k, 1))
    if isinstance(bounds, Mapping):
        b = np.tile([-1.0, 1.0], (k, 1))
        for s, v in bounds.items():
            if s not in factors:
                raise InputError(None, "bounds", f"factor symbols among {factors}", s)
            b[factors.index(s)] = v
    else:
        b = np.asarray(bounds, dtype=float)
    if b.shape != (k, 2) or not np.all(np.isfinite(b)) or np.any(b[:, 1] <= b[:, 0]):
        raise InputError(None, "bounds", f"{k} coded (low, high) pairs with low < high", bounds)
    return b


def _search(models: Mapping[str, Any], goals: Mapping[str, Mapping[str, Any]], bounds):
    """The checked factors and coded box, resolved goals and importances, and the vectorised
    ``evaluate`` and one-point ``objective`` (-D, or the distance to the limits where D = 0) of
    a desirability search."""
    factors, low, high = _check_models(models)
    if not isinstance(goals, Mapping) or not goals:
        raise InputError(None, "goals", "a non-empty mapping name -> goal spec", goals)
    for name in goals:
        if name not in models and name not in factors:
            raise InputError(None, f"goals.{name}", f"a response among {list(models)} or a factor among {factors}", name)
    box = _coded_bounds(bounds, factors)
    centre, half = (low + high) / 2.0, (high - low) / 2.0

    resolved: list[tuple[Goal, str | None, int | None]] = []
    for name, spec in goals.items():
        if name in models:
            obs = getattr(models[name], "observed", None)
            resolved.append((make_goal(name, spec, obs), name, None))
        else:
            j = factors.index(name)
            resolved.append((make_goal(name, spec, [low[j], high[j]]), None, j))
    importance = np.array([g.importance for g, _, _ in resolved])

    def evaluate(X: np.ndarray) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray]:
        X = np.atleast_2d(X)
        preds = {r: np.asarray(m.predict(X), dtype=float).reshape(-1) for r, m in models.items()}
        ds, viol = [], np.zeros(X.shape[0])
        for g, resp, j in resolved:
            y = preds[resp] if resp is not None else centre[j] + X[:, j] * half[j]
            ds.append(g.d(y))
            viol += g.violation(y)
        return preds, np.vstack(ds), viol

    rsum = float(importance.sum())

    def objective(x: np.ndarray) -> float:
        xr = x[None, :]
        preds = {r: float(np.asarray(m.predict(xr), dtype=float).reshape(-1)[0]) for r, m in models.items()}
        logD, viol, zero = 0.0, 0.0, False
        for g, resp, j in resolved:
            y = preds[resp] if resp is not None else float(centre[j] + x[j] * half[j])
            d = g.d_scalar(y)
            if d <= 0.0:
                zero = True
                viol += g.violation_scalar(y)
            else:
                logD += g.importance * math.log(d)
        return viol if zero else -math.exp(logD / rsum)

    return factors, centre, half, box, resolved, importance, evaluate, objective


def search_ends(models: Mapping[str, Any], goals: Mapping[str, Mapping[str, Any]], bounds=None,
                n_starts: int = 60, seed: int = 0) -> np.ndarray:
    """The end points (coded, clipped to the box) of the seeded multi-start search of
    :func:`desirability_optimise`: row 0 refined from the centre point (clipped to the box),
    rows 1 .. ``n_starts`` from the random starts, drawn in order from ``default_rng(seed)``,
    so that the first ``n + 1`` rows of a search with more starts are those of a search with
    ``n`` starts.  A caller running the search at several start counts (the calibration's
    solutions and its near-optimal sets) computes them once and passes them as ``ends``."""
    if int(n_starts) < 1:
        raise InputError(None, "n_starts", "a positive integer", n_starts)
    factors, _, _, box, _, _, _, objective = _search(models, goals, bounds)
    rng = np.random.default_rng(seed)
    starts = np.vstack([np.clip(np.zeros(len(factors)), box[:, 0], box[:, 1]),
                        rng.uniform(box[:, 0], box[:, 1], size=(int(n_starts), len(factors)))])
    ends = []
    for x0 in starts:
        res = optimize.minimize(objective, x0, method="Nelder-Mead", bounds=box,
                                options={"xatol": 1e-7, "fatol": 1e-10, "maxiter": 4000, "adaptive": True})
        ends.append(np.clip(res.x, box[:, 0], box[:, 1]))
    return np.array(ends)


def desirability_optimise(
    models: Mapping[str, Any],
    goals: Mapping[str, Mapping[str, Any]],
    bounds=None,
    n_starts: int = 60,
    seed: int = 0,
    n_solutions: int = 10,
    tol: float = 0.05,
    min_desirability: float = 0.0,
    ends: np.ndarray | None = None,
) -> pd.DataFrame:
    """Distinct maxima of the overall desirability, sorted by decreasing D.

    models: response name -> fitted model (``.factors``, ``.low``, ``.high``,
    ``.predict(X_coded)``), all on the same factors. goals: response name (or factor symbol,
    goal on the factor's actual level) -> goal spec, see :func:`make_goal`. bounds: coded search
    box, None = [-1, 1] for every factor, or (k, 2) pairs, or {symbol: (lo, hi)}.
    n_starts random starts (seeded) plus the centre point; solutions within ``tol`` (Euclidean,
    coded) of a better one are dropped; at most ``n_solutions`` rows.  ``ends``: the
    :func:`search_ends` of these models, goals, bounds and seed with at least ``n_starts``
    starts, where the caller has them already (their first ``n_starts + 1`` rows are used, the
    end points this call would compute); None: the search runs here.

    Columns: solution, <f>_coded..., <f>..., <response>..., d_<goal>..., desirability. The
    search settings (seed, n_starts, tol) are in ``df.attrs``.
    """
    if int(n_starts) < 1 or int(n_solutions) < 1:
        raise InputError(None, "n_starts/n_solutions", "positive integers", (n_starts, n_solutions))
    factors, centre, half, box, resolved, importance, evaluate, _ = _search(models, goals, bounds)
    if ends is None:
        ends = search_ends(models, goals, bounds, n_starts, seed)
    else:
        ends = np.asarray(ends, dtype=float)
        if ends.ndim != 2 or ends.shape[1] != len(factors) or ends.shape[0] < int(n_starts) + 1:
            raise InputError(None, "ends", f"the end points of a search with at least {int(n_starts)} starts: "
                             f"({int(n_starts) + 1} or more, {len(factors)}) coded values", ends.shape)
        ends = ends[: int(n_starts) + 1]
    preds, ds, _ = evaluate(ends)
    D = overall_desirability(ds, importance)
    order = np.argsort(-np.round(D, 10), kind="stable")

    keep: list[int] = []
    for i in order:
        if D[i] < min_desirability:
            continue
        if all(np.linalg.norm(ends[i] - ends[k]) >= tol for k in keep):
            keep.append(int(i))
        if len(keep) >= n_solutions:
            break

    rows = []
    for n, i in enumerate(keep, start=1):
        row: dict[str, Any] = {"solution": n}
        for j, s in enumerate(factors):
            row[f"{s}_coded"] = float(ends[i, j])
        for j, s in enumerate(factors):
            row[s] = float(centre[j] + ends[i, j] * half[j])
        for r in models:
            row[r] = float(preds[r][i])
        for gi, (g, _, _) in enumerate(resolved):
            row[f"d_{g.name}"] = float(ds[gi, i])
        row["desirability"] = float(D[i])
        rows.append(row)
    cols = (["solution"] + [f"{s}_coded" for s in factors] + list(factors) + list(models)
            + [f"d_{g.name}" for g, _, _ in resolved] + ["desirability"])
    out = pd.DataFrame(rows, columns=cols)
    out.attrs.update({"seed": seed, "n_starts": int(n_starts), "tol": tol,
                      "goals": {g.name: g.__dict__.copy() for g, _, _ in resolved}})
    return out


__all__ = [
    "GOALS",
    "Goal",
    "ResponseModel",
    "d_in_range",
    "d_maximize",
    "d_minimize",
    "d_target",
    "desirability_optimise",
    "make_goal",
    "overall_desirability",
]
