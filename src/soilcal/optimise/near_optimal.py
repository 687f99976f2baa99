"""Near-optimal parameter sets of a desirability calibration, and which factors they pin down.

When one or two target responses are fitted with three or four factors, the targets are met on
a whole surface (or curve) of parameter sets rather than at one point: the calibration is not
unique. :func:`near_optimal_sets` lists the distinct optima of the multi-start desirability
search (:func:`soilcal.optimise.desirability_optimise`) whose overall desirability is within
``window`` of the best one; :func:`calibrated_choice` picks the one the workflow adopts (the
one nearest the design centre); :func:`identifiability` tells, factor by factor, whether the
near-optimal sets agree on its value (pinned) or spread over much of its range (not pinned
down by the data), or whether a bound of the design region holds them (at bound: the sets
pile up against the bound, where the search stops, so the region and not the data fixes the
value; beyond it the surface is not known).
"""

from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd

from soilcal.doe.designs import ON_BOUND, at_bound
from soilcal.errors import InputError
from soilcal.optimise.desirability import desirability_optimise

#: overall desirability from which the goals count as met (a target goal's d is 1 at the
#: target and falls off towards its limits)
REACHED = 0.99
#: random starts of the near-optimal search (its default)
NEAR_OPTIMAL_STARTS = 200


def near_optimal_sets(
    models: Mapping[str, Any],
    goals: Mapping[str, Mapping[str, Any]],
    bounds=None,
    seed: int = 0,
    n_starts: int = NEAR_OPTIMAL_STARTS,
    tol: float = 0.05,
    window: float = 0.01,
    max_sets: int = 50,
    ends: np.ndarray | None = None,
) -> pd.DataFrame:
    """Every distinct parameter set whose overall desirability is within ``window`` of the best.

    Runs the seeded multi-start search of :func:`~soilcal.optimise.desirability_optimise`
    (``n_starts`` random starts plus the centre point, all distinct optima kept) and keeps the
    solutions with ``D >= D_best - window`` and ``D > 0`` (a set that misses a goal's limits is
    never near-optimal; if the goals cannot be met anywhere the frame is empty). Solutions are
    distinct: each lies at coded Euclidean distance >= ``tol`` from every kept one.
    ``ends``: the search's end points where the caller has them already
    (:func:`~soilcal.optimise.desirability.search_ends` of these models, goals, bounds and seed
    with at least ``n_starts`` starts); None: the search runs here.

    Columns: those of :func:`~soilcal.optimise.desirability_optimise` (solution, <f>_coded...,
    <f>..., <response>..., d_<goal>..., desirability) plus ``near_optimal`` (True) and
    ``distance_to_centre`` (coded Euclidean norm). Rows are sorted by decreasing desirability
    (rounded to 10 digits, as the search does), then increasing distance_to_centre, and
    ``solution`` is renumbered 1.. in that order. At most ``max_sets`` rows: the first
    ``max_sets`` in that order, except that the set nearest the design centre is always kept
    (it is the :func:`calibrated_choice`) in place of the last one.

    ``df.attrs``: seed, n_starts, tol, window, max_sets, goals (resolved), best_desirability and
    n_found (near-optimal sets before the ``max_sets`` cut).
    """
    try:
        window_f = float(window)
    except (TypeError, ValueError):
        raise InputError(None, "window", "a number >= 0", window) from None
    if not (math.isfinite(window_f) and window_f >= 0.0):
        raise InputError(None, "window", "a finite number >= 0", window)
    try:
        tol_f = float(tol)
    except (TypeError, ValueError):
        raise InputError(None, "tol", "a number >= 0", tol) from None
    if not (math.isfinite(tol_f) and tol_f >= 0.0):
        raise InputError(None, "tol", "a finite number >= 0", tol)
    if isinstance(max_sets, bool) or not isinstance(max_sets, (int, np.integer)) or max_sets < 1:
        raise InputError(None, "max_sets", "a positive integer", max_sets)
    if isinstance(n_starts, bool) or not isinstance(n_starts, (int, np.integer)) or n_starts < 1:
        raise InputError(None, "n_starts", "a positive integer", n_starts)

    # n_starts + 1 end points at most (random starts plus the centre): keep them all
    df = desirability_optimise(models, goals, bounds=bounds, n_starts=int(n_starts), seed=seed,
                               n_solutions=int(n_starts) + 1, tol=tol_f, min_desirability=0.0, ends=ends)
    coded = [f"{s}_coded" for s in next(iter(models.values())).factors]
    D = df["desirability"].to_numpy(dtype=float)
    best = float(D.max()) if len(D) else 0.0
    out = df[(D > 0.0) & (D >= best - window_f)].copy()
    out["near_optimal"] = True
    out["distance_to_centre"] = np.linalg.norm(out[coded].to_numpy(dtype=float), axis=1) if len(out) else []
    out["_d_key"] = -np.round(out["desirability"].to_numpy(dtype=float), 10)
    out = out.sort_values(["_d_key", "distance_to_centre"], kind="stable")
    n_found = len(out)
    if n_found > max_sets:
        nearest = int(np.argmin(out["distance_to_centre"].to_numpy()))
        rows = list(range(max_sets))
        if nearest >= max_sets:
            rows[-1] = nearest
        out = out.iloc[rows]
    out = out.drop(columns="_d_key").reset_index(drop=True)
    out["solution"] = np.arange(1, len(out) + 1)
    out["near_optimal"] = out["near_optimal"].astype(bool)
    out["distance_to_centre"] = out["distance_to_centre"].astype(float)
    out.attrs.update(df.attrs)
    out.attrs.update({"seed": seed, "n_starts": int(n_starts), "tol": tol, "window": window,
                      "max_sets": int(max_sets), "best_desirability": best if n_found else None,
                      "n_found": n_found})
    return out


def calibrated_choice(sets: pd.DataFrame) -> pd.Series:
    """The parameter set the workflow adopts as "the calibrated parameters".

    Among the near-optimal sets (rows of :func:`near_optimal_sets`; rows with
    ``near_optimal`` False, if any, are ignored) the one nearest the design centre: smallest
    ``distance_to_centre`` (coded), ties broken by higher desirability, then solution order.

    Rationale: every near-optimal set meets the targets equally well (within the desirability
    window), so the data cannot prefer one; the set nearest the centre of the design region is
    the one whose predicted responses rest on the best-supported part of the response surface:
    the prediction variance of a rotatable (or near-rotatable) design grows with the distance
    from the centre, so it is smallest there.

    Raises InputError on an empty frame or one without the needed columns.
    """
    if not isinstance(sets, pd.DataFrame):
        raise InputError(None, "sets", "a DataFrame from near_optimal_sets", type(sets).__name__)
    missing = [c for c in ("distance_to_centre", "desirability") if c not in sets.columns]
    if missing:
        raise InputError(None, "sets", "the columns of near_optimal_sets", f"missing {missing}")
    rows = sets[sets["near_optimal"].astype(bool)] if "near_optimal" in sets.columns else sets
    if rows.empty:
        raise InputError(None, "sets", "at least one near-optimal parameter set", "an empty frame")
    order = np.arange(len(rows))
    key = np.lexsort((order, -rows["desirability"].to_numpy(dtype=float),
                      rows["distance_to_centre"].to_numpy(dtype=float)))
    return rows.iloc[int(key[0])].copy()


def _factor_bounds(values, factors: Sequence[str], name: str) -> np.ndarray:
    if isinstance(values, Mapping):
        missing = [f for f in factors if f not in values]
        if missing:
            raise InputError(None, name, f"a value for each factor {list(factors)}", f"missing {missing}")
        values = [values[f] for f in factors]
    try:
        arr = np.asarray(values, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise InputError(None, name, f"{len(factors)} numbers, one per factor", values) from None
    if arr.size != len(factors):
        raise InputError(None, name, f"{len(factors)} values, one per factor {list(factors)}", arr.size)
    if not np.all(np.isfinite(arr)):
        raise InputError(None, name, "finite numbers", list(arr))
    return arr


def identifiability(
    sets: pd.DataFrame,
    factors: list[str],
    low,
    high,
    pinned_fraction: float = 0.1,
) -> pd.DataFrame:
    """Per factor, whether the near-optimal sets pin its value down.

    sets: rows of :func:`near_optimal_sets` (rows with ``near_optimal`` False are ignored);
    factors: factor symbols (actual-unit columns of ``sets``); low/high: the factor's full
    actual range (sequence aligned with ``factors`` or mapping symbol -> value, as for
    :func:`soilcal.rsm.fit_response_surface`).

    One row per factor: factor, n_sets, min, max, spread (max - min, actual units),
    spread_coded (spread / half range), pinned (spread_coded <= 2 * pinned_fraction, i.e. the
    near-optimal sets span at most ``pinned_fraction`` of the full range) and a note. With a
    single near-optimal set every factor is pinned and the note says so.  A factor that would
    be pinned but whose sets all lie within that band of one bound, at least one of them on
    it (:func:`soilcal.doe.at_bound`, coded distance :data:`soilcal.doe.ON_BOUND`), is
    ``"at bound"`` instead of True: the region's bound holds it, not the data.
    """
    if not isinstance(sets, pd.DataFrame):
        raise InputError(None, "sets", "a DataFrame from near_optimal_sets", type(sets).__name__)
    if isinstance(factors, str) or not isinstance(factors, Sequence) or len(factors) == 0:
        raise InputError(None, "factors", "a non-empty list of factor symbols", factors)
    factors = list(factors)
    missing = [f for f in factors if f not in sets.columns]
    if missing:
        raise InputError(None, "factors", f"columns of sets {list(sets.columns)}", missing)
    lo = _factor_bounds(low, factors, "low")
    hi = _factor_bounds(high, factors, "high")
    if np.any(hi <= lo):
        raise InputError(None, "low/high", "low < high for every factor", list(zip(lo.tolist(), hi.tolist())))
    try:
        pf = float(pinned_fraction)
    except (TypeError, ValueError):
        raise InputError(None, "pinned_fraction", "a number in [0, 1]", pinned_fraction) from None
    if not (math.isfinite(pf) and 0.0 <= pf <= 1.0):
        raise InputError(None, "pinned_fraction", "a number in [0, 1]", pinned_fraction)
    rows_df = sets[sets["near_optimal"].astype(bool)] if "near_optimal" in sets.columns else sets
    if rows_df.empty:
        raise InputError(None, "sets", "at least one near-optimal parameter set", "an empty frame")

    n = len(rows_df)
    best = float(rows_df["desirability"].max()) if "desirability" in rows_df else float("nan")
    # below 0.99 no set meets every goal: the sets mark where the surface comes closest
    short = (f"the goals are not met inside the design region (best desirability {best:.2f}); "
             if best < REACHED else "")
    rows = []
    for j, f in enumerate(factors):
        v = rows_df[f].to_numpy(dtype=float)
        vmin, vmax = float(v.min()), float(v.max())
        spread = vmax - vmin
        spread_coded = spread / ((hi[j] - lo[j]) / 2.0)
        pct = 100.0 * spread_coded / 2.0
        coded = (v - (lo[j] + hi[j]) / 2.0) / ((hi[j] - lo[j]) / 2.0)
        bound = None
        if at_bound(coded.min(), "low") and at_bound(coded.max(), "low", tol=2.0 * pf):
            bound = ("low", lo[j])
        elif at_bound(coded.max(), "high") and at_bound(coded.min(), "high", tol=2.0 * pf):
            bound = ("high", hi[j])
        if bound is not None:
            pinned = "at bound"
            where = f"its {bound[0]} bound {bound[1]:g}"
            if spread_coded <= ON_BOUND:
                sets = "the near-optimal set has" if n == 1 else "every near-optimal set has"
                note = f"at bound: {sets} it at {where}"
            else:
                far = 100.0 * float(np.max(np.abs(np.abs(coded) - 1.0))) / 2.0
                note = f"at bound: the near-optimal sets lie within {far:.0f} % of the range of {where}, some on it"
            note += ": held there by the design region, not pinned down by the data"
        elif n == 1:
            pinned = True
            note = "pinned: only one near-optimal set was found, so the spread is not assessed"
        elif spread_coded <= 2.0 * pf:
            pinned = True
            note = f"pinned: the near-optimal sets span {pct:.0f} % of the range"
        else:
            pinned = False
            note = f"not pinned down by the data: the near-optimal sets span {pct:.0f} % of the range"
        rows.append({"factor": f, "n_sets": n, "min": vmin, "max": vmax, "spread": spread,
                     "spread_coded": spread_coded, "pinned": pinned, "note": short + note})
    out = pd.DataFrame(rows, columns=["factor", "n_sets", "min", "max", "spread", "spread_coded", "pinned", "note"])
    out.attrs["pinned_fraction"] = pf
    return out


__all__ = ["calibrated_choice", "identifiability", "near_optimal_sets"]
