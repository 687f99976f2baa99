"""Path of steepest ascent (descent) from a first-order model.

Montgomery, Design and Analysis of Experiments, sec. 11.2: for a fitted first-order model
y = b0 + sum_j b_j x_j in coded units, the path moves from the design centre in steps
proportional to the coefficients. Choose a base factor i and its step in actual units
Delta_i; in coded units Delta x_i = Delta_i / h_i (h = half range). The other coded steps are
Delta x_j = b_j / |b_i| * |Delta x_i| (ascent) or its negative (descent), and in actual
units Delta_j = Delta x_j * h_j. Step s is start + s * Delta.

Deriving the climbing stage from our own screening (instead of copying the papers' levels):

1. :func:`select_factors` picks the factors of the Plackett-Burman screening that are
   significant for any response (p < alpha), topped up to the three factors a Box-Behnken
   design needs.
2. :func:`path_direction` turns the coded first-order coefficients of every targeted response
   into one direction: the negative gradient of the summed squared relative error to the
   targets (Montgomery sec. 11.2 with the response replaced by that error).
3. :func:`derive_path` lays the steps out in actual units, either the papers' way (every factor
   walks its whole screening range), Montgomery's (steps proportional to the coefficients), or
   aimed at several targets at once (``target``: Montgomery's layout along the line through
   the point where the first-order models meet every target together, :func:`path_target`).
4. :func:`chosen_step` picks the simulated step closest to the targets: the step whose own
   run is closest (``closest``, the papers' rule), or the step whose value on the trend
   fitted through all the path's runs is closest (``fitted``, :func:`path_trend`), which a
   single seed's scatter cannot pull onto a lucky step.
5. :func:`bbd_levels` takes that step as the Box-Behnken centre and its neighbours as the low
   and high levels.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np
import pandas as pd

from soilcal.errors import InputError


def _lookup(values, symbols: list[str], name: str) -> dict[str, float]:
    if isinstance(values, Mapping):
        missing = [s for s in symbols if s not in values]
        if missing:
            raise InputError(None, name, f"a value for each of {symbols}", f"missing {missing}")
        return {s: float(values[s]) for s in symbols}
    arr = np.asarray(values, dtype=float).reshape(-1)
    if arr.size != len(symbols):
        raise InputError(None, name, f"{len(symbols)} values (one per factor {symbols})", arr.size)
    return dict(zip(symbols, map(float, arr)))


def steepest_ascent_path(
    coefficients: Mapping[str, float],
    low,
    high,
    base: str,
    base_step_actual: float,
    n_steps: int,
    start=None,
    direction: str = "ascent",
) -> pd.DataFrame:
    """Actual factor levels along the path of steepest ascent/descent.

    coefficients: factor symbol -> coded main-effect coefficient b_j.
    low, high: per-factor bounds (mapping or sequence in the order of ``coefficients``).
    base: factor whose actual step size is ``base_step_actual`` (sign ignored; the
    direction follows the sign of its coefficient and ``direction``).
    start: actual levels of step 0 (default: the centre of the ranges).
    Returns a DataFrame with column "step" (0..n_steps) and one column per factor in
    actual units; ``df.attrs["coded_step"]`` / ``["actual_step"]`` hold the increments.
    """
    symbols = list(coefficients)
    if base not in coefficients:
        raise InputError(None, "base", f"one of the factors {symbols}", base)
    if direction not in ("ascent", "descent"):
        raise InputError(None, "direction", "'ascent' or 'descent'", direction)
    if int(n_steps) != n_steps or n_steps < 0:
        raise InputError(None, "n_steps", "a non-negative integer", n_steps)
    b = {s: float(coefficients[s]) for s in symbols}
    if b[base] == 0.0:
        raise InputError(None, f"coefficients[{base}]", "a non-zero coefficient for the base factor", 0.0)
    lo = _lookup(low, symbols, "low")
    hi = _lookup(high, symbols, "high")
    half = {s: (hi[s] - lo[s]) / 2.0 for s in symbols}
    if any(h == 0 for h in half.values()):
        raise InputError(None, "low/high", "high != low for every factor", half)
    centre = {s: (hi[s] + lo[s]) / 2.0 for s in symbols}
    origin = centre if start is None else _lookup(start, symbols, "start")
    sign = 1.0 if direction == "ascent" else -1.0
    dx_base = abs(float(base_step_actual)) / half[base]
    coded_step = {s: sign * b[s] / abs(b[base]) * dx_base for s in symbols}
    actual_step = {s: coded_step[s] * half[s] for s in symbols}
    steps = np.arange(int(n_steps) + 1)
    df = pd.DataFrame({"step": steps})
    for s in symbols:
        df[s] = origin[s] + steps * actual_step[s]
    df.attrs["coded_step"] = coded_step
    df.attrs["actual_step"] = actual_step
    df.attrs["direction"] = direction
    return df



# --------------------------------------------------------------------------- derivation
def _fmt(x: float) -> str:
    """Short number for notes and reasons: 3 significant digits, no trailing zeros."""
    return f"{x:.3g}"


def _check_int(value, field: str, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise InputError(None, field, f"an integer >= {minimum}", value)
    return int(value)


def select_factors(
    effects: pd.DataFrame,
    alpha: float = 0.05,
    min_factors: int = 3,
    max_factors: int | None = None,
) -> pd.DataFrame:
    """Factors of a two-level screening to carry into the climbing and Box-Behnken stages.

    ``effects`` has columns response, term, coefficient, p: one block of rows per response,
    e.g. :func:`soilcal.rsm.screening_effects` of each response with a ``response`` column
    added. A factor is significant when p < ``alpha`` for ANY response (the papers carry a
    factor forward when it is significant for at least one measured angle; Montgomery ch. 8
    for the screening F tests). Factors are ranked by their smallest p over the responses
    (``p_min``; ties: larger max |coefficient|, then order of first appearance; a factor
    whose p is NaN for every response ranks last).

    Selected: every significant factor, at most ``max_factors`` of them (best ranked kept);
    when fewer than ``min_factors`` are significant, the best-ranked non-significant factors
    are added up to ``min_factors`` (a Box-Behnken design needs at least 3 factors).

    Returns one row per factor in rank order: term, rank (1 = best), p_min, significant,
    selected, reason, then ``b_<response>`` (coded coefficient) and ``p_<response>`` per
    response (NaN where a response has no row for the factor).
    """
    if not isinstance(effects, pd.DataFrame):
        raise InputError(None, "effects", "a pandas DataFrame", type(effects).__name__)
    need = ["response", "term", "coefficient", "p"]
    missing = [c for c in need if c not in effects.columns]
    if missing:
        raise InputError(None, "effects", f"columns {need}", f"missing {missing}")
    try:
        alpha_f = float(alpha)
    except (TypeError, ValueError):
        raise InputError(None, "alpha", "a number in (0, 1)", alpha) from None
    if not 0.0 < alpha_f < 1.0:
        raise InputError(None, "alpha", "a number in (0, 1)", alpha)
    min_factors = _check_int(min_factors, "min_factors", 1)
    if max_factors is not None:
        max_factors = _check_int(max_factors, "max_factors", 1)
        if max_factors < min_factors:
            raise InputError(None, "max_factors", f"None or an integer >= min_factors = {min_factors}",
                             max_factors)
    tab = effects[need].copy()
    for c in ("coefficient", "p"):
        try:
            tab[c] = pd.to_numeric(tab[c], errors="raise").astype(float)
        except (TypeError, ValueError):
            raise InputError(None, f"effects.{c}", "numbers", list(effects[c])) from None
    dup = tab.duplicated(["response", "term"])
    if dup.any():
        raise InputError(None, "effects", "one row per (response, term)",
                         tab.loc[dup, ["response", "term"]].values.tolist())
    terms = list(dict.fromkeys(tab["term"]))
    responses = list(dict.fromkeys(tab["response"]))
    if len(terms) < min_factors:
        raise InputError(None, "effects.term", f"at least min_factors = {min_factors} factors", terms)

    b = tab.pivot(index="term", columns="response", values="coefficient").reindex(index=terms, columns=responses)
    p = tab.pivot(index="term", columns="response", values="p").reindex(index=terms, columns=responses)
    p_arr = p.to_numpy(dtype=float)
    b_arr = np.abs(b.to_numpy(dtype=float))
    with np.errstate(all="ignore"):
        all_nan_p = np.isnan(p_arr).all(axis=1)
        p_min = np.where(all_nan_p, np.nan, np.nanmin(np.where(np.isnan(p_arr), np.inf, p_arr), axis=1))
        b_max = np.where(np.isnan(b_arr).all(axis=1), -np.inf,
                         np.nanmax(np.where(np.isnan(b_arr), -np.inf, b_arr), axis=1))
    # sort key: p_min ascending (NaN last), then max |b| descending, then first appearance
    order = sorted(range(len(terms)),
                   key=lambda i: (np.isnan(p_min[i]), 0.0 if np.isnan(p_min[i]) else p_min[i], -b_max[i], i))

    rows = []
    n_sig_kept = 0
    for i in order:
        sig = bool(p_min[i] < alpha_f)  # NaN compares False
        rows.append({"i": i, "term": terms[i], "p_min": float(p_min[i]), "significant": sig})
    for r in rows:
        if not r["significant"]:
            continue
        if max_factors is None or n_sig_kept < max_factors:
            n_sig_kept += 1
            j = int(np.nanargmin(np.where(np.isnan(p_arr[r["i"]]), np.inf, p_arr[r["i"]])))
            r["selected"] = True
            r["reason"] = f"p = {_fmt(p_arr[r['i'], j])} < {alpha_f:g} ({responses[j]})"
        else:
            r["selected"] = False
            r["reason"] = f"significant but beyond max_factors = {max_factors}"
    n_sel = n_sig_kept
    for r in rows:
        if r["significant"]:
            continue
        if n_sel < min_factors:
            n_sel += 1
            r["selected"] = True
            r["reason"] = ("added: a Box-Behnken design needs at least 3 factors" if min_factors == 3
                           else f"added: min_factors = {min_factors} (p_min = {_fmt(r['p_min'])})")
        else:
            r["selected"] = False
            r["reason"] = f"not significant (p_min = {_fmt(r['p_min'])})"

    out = pd.DataFrame({
        "term": [r["term"] for r in rows],
        "rank": np.arange(1, len(rows) + 1),
        "p_min": [r["p_min"] for r in rows],
        "significant": [r["significant"] for r in rows],
        "selected": [r["selected"] for r in rows],
        "reason": [r["reason"] for r in rows],
    })
    idx = [terms[r["i"]] for r in rows]
    for resp in responses:
        out[f"b_{resp}"] = b.loc[idx, resp].to_numpy(dtype=float)
        out[f"p_{resp}"] = p.loc[idx, resp].to_numpy(dtype=float)
    out.attrs["alpha"] = alpha_f
    out.attrs["min_factors"] = min_factors
    out.attrs["max_factors"] = max_factors
    return out


def path_direction(
    coefficients: dict[str, dict[str, float]],
    intercepts: dict[str, float],
    targets: dict[str, float],
) -> dict[str, float]:
    """Coded direction of the climbing path towards the measured targets.

    Montgomery (Design and Analysis of Experiments, sec. 11.2) moves along the gradient of the
    fitted first-order model y = b0 + sum_j b_j x_j. Here the quantity to improve is the
    distance to the targets, so the path descends the summed squared relative error of the
    first-order models, f(x) = sum_r ((y_r(x) - t_r) / t_r)^2. Its negative half-gradient at
    the design centre x = 0 is

        d_j = sum_r (t_r - b0_r) / t_r^2 * b_rj,

    which for one response is |t - b0| / t^2 * sign(t - b0) * b_j: steepest ascent when the
    centre response b0 is below the target, steepest descent when above. Relative errors keep
    responses of different units and sizes comparable.

    coefficients: response -> {factor: coded b_j}; intercepts: response -> b0 (the response
    predicted at the centre, for a two-level screening the mean response); targets: response
    -> target. Responses without a target are ignored; every targeted response needs
    coefficients and an intercept, and all targeted responses the same factors.
    Returns {factor: d_j}, unnormalised, in the factor order of the first targeted response.
    """
    if not isinstance(targets, Mapping) or not targets:
        raise InputError(None, "targets", "at least one response -> target value", targets)
    if not isinstance(coefficients, Mapping):
        raise InputError(None, "coefficients", "a mapping response -> {factor: coefficient}",
                         type(coefficients).__name__)
    if not isinstance(intercepts, Mapping):
        raise InputError(None, "intercepts", "a mapping response -> intercept", type(intercepts).__name__)
    factors: list[str] | None = None
    d: dict[str, float] = {}
    for r, t in targets.items():
        t = float(t)
        if not np.isfinite(t) or t == 0.0:
            raise InputError(None, f"targets[{r}]", "a finite non-zero target (errors are relative to it)", t)
        if r not in coefficients:
            raise InputError(None, "coefficients", f"coefficients for the targeted response {r!r}",
                             sorted(coefficients))
        if r not in intercepts:
            raise InputError(None, "intercepts", f"an intercept for the targeted response {r!r}",
                             sorted(intercepts))
        b0 = float(intercepts[r])
        if not np.isfinite(b0):
            raise InputError(None, f"intercepts[{r}]", "a finite number", b0)
        br = coefficients[r]
        if not isinstance(br, Mapping) or not br:
            raise InputError(None, f"coefficients[{r}]", "a non-empty mapping factor -> coefficient", br)
        if factors is None:
            factors = list(br)
            d = {f: 0.0 for f in factors}
        elif set(br) != set(factors):
            raise InputError(None, f"coefficients[{r}]", f"the same factors as the other responses {factors}",
                             list(br))
        w = (t - b0) / t**2
        for f in factors:
            bj = float(br[f])
            if not np.isfinite(bj):
                raise InputError(None, f"coefficients[{r}][{f}]", "a finite number", bj)
            d[f] += w * bj
    if all(v == 0.0 for v in d.values()):
        raise InputError(None, "coefficients/intercepts",
                         "a non-zero path direction (some target different from its centre "
                         "response and some factor with a non-zero coefficient)", d)
    return d


def path_target(
    coefficients: dict[str, dict[str, float]],
    intercepts: dict[str, float],
    targets: dict[str, float],
) -> dict[str, float]:
    """Coded point where the first-order models meet every target together.

    The gradient of :func:`path_direction` sums the responses' pulls, so where two targeted
    responses need different moves (one angle too low, the other already high enough) it walks
    both the same way. Solving the first-order models for the targets instead, in relative
    terms,

        sum_j b_rj / t_r * x_j = (t_r - b0_r) / t_r     for every targeted response r,

    gives the move x* (coded units from the design centre) the linear models predict meets all
    targets: the minimum-norm solution when there are fewer responses than factors (the
    Gauss-Newton step of the relative errors), the least-squares one when there are more. For
    one response it lies on Montgomery's path of steepest ascent (sec. 11.2), where the line
    reaches the target: x* = b (t - b0) / |b|^2.

    Same arguments and checks as :func:`path_direction`. Returns {factor: x*_j}; raises
    InputError when every target equals its centre response (no move to aim at).
    """
    d = path_direction(coefficients, intercepts, targets)  # validates; zero gradient -> InputError
    factors = list(d)
    rows, rhs = [], []
    for r, t in targets.items():
        t = float(t)
        rows.append([float(coefficients[r][f]) / t for f in factors])
        rhs.append((t - float(intercepts[r])) / t)
    x, *_ = np.linalg.lstsq(np.asarray(rows), np.asarray(rhs), rcond=None)
    if not np.all(np.isfinite(x)) or np.max(np.abs(x)) == 0.0:
        raise InputError(None, "coefficients/intercepts", "a finite, non-zero move to the targets", x.tolist())
    return {f: float(v) for f, v in zip(factors, x)}


def _factor_bounds(direction, low, high) -> tuple[list[str], dict, dict, dict]:
    if not isinstance(direction, Mapping) or not direction:
        raise InputError(None, "direction", "a non-empty mapping factor -> direction component", direction)
    factors = list(direction)
    for name, m in (("low", low), ("high", high)):
        if not isinstance(m, Mapping) or set(m) != set(factors):
            got = sorted(m) if isinstance(m, Mapping) else m
            raise InputError(None, name, f"a value for exactly the factors {factors}", got)
    d = {f: float(direction[f]) for f in factors}
    lo = {f: float(low[f]) for f in factors}
    hi = {f: float(high[f]) for f in factors}
    for f in factors:
        if not np.isfinite(d[f]):
            raise InputError(None, f"direction[{f}]", "a finite number", d[f])
        if not (np.isfinite(lo[f]) and np.isfinite(hi[f]) and lo[f] < hi[f]):
            raise InputError(None, f"low/high[{f}]", "finite bounds with low < high", (lo[f], hi[f]))
    return factors, d, lo, hi


def derive_path(
    direction: dict[str, float],
    low: dict[str, float],
    high: dict[str, float],
    n_steps: int,
    rule: str = "range",
    base: str | None = None,
    base_step: float | None = None,
) -> pd.DataFrame:
    """Factor levels (actual units) of the climbing path, steps 1..n_steps.

    direction: factor -> coded direction component d_j (e.g. from :func:`path_direction`);
    low/high: the factors' screening ranges (actual units), half range h_j.

    rule "range" (the papers' practice; cinnamon soil, Table 5: A 0.05 -> 0.2, B 0.1 -> 0.8,
    C 0.3 -> 0.9 in 6 steps): every factor with d_j != 0 walks its whole screening range in
    n_steps equal steps, from the end opposite to its direction to the other end (d_j > 0:
    low -> high; d_j < 0: high -> low). Only the signs of d are used. A factor with d_j == 0
    stays at its centre.

    rule "proportional" (Montgomery, Design and Analysis of Experiments, sec. 11.2): the base
    factor (default: the largest |d_j|, first on ties) moves ``base_step`` actual units per step
    (sign ignored; default: its full range / (n_steps - 1)), i.e. a coded step
    Delta x_base = sign(d_base) * base_step / h_base; every other factor moves the coded step
    Delta x_j = d_j / |d_base| * |Delta x_base|, i.e. h_j * Delta x_j actual units. The path is
    centred on the screening centre: step 1 is the centre shifted back by (n_steps - 1) / 2
    steps, so the middle of the path (a step for odd n_steps, between two steps for even) is the
    centre. With the default base_step the base factor walks exactly its screening range, as in
    the "range" rule; other factors may leave their screening ranges (no clipping).

    rule "target" (several targeted responses, :func:`path_target`): ``direction`` is the coded
    point x* where the first-order models meet every target together, and the path is laid out
    as "proportional" along the line from the centre through it: the factor of largest |x*_j|
    (the base) walks its whole screening range, every other factor x*_j / |x*_base| of its own,
    so the path stays inside the screening box the models were fitted in (from one face to the
    opposite one, through the centre and, where x* lies inside the box, through x*). Where two
    responses pull apart, x* moves a factor only one of them needs (the summed gradient of
    "range" walks every factor the same way). Because the steps' spacing per factor follows
    x*, a factor x* hardly moves would get almost no range from the steps' neighbours;
    ``attrs["box_half_width"]`` therefore gives every factor the half width the "range" rule's
    neighbours would (its screening range / (n_steps - 1)), for :func:`bbd_levels`.

    Returns columns step and one per factor; ``attrs["rule"]``, ``attrs["step"]`` (signed
    actual increment per factor), ``attrs["direction"]`` (sign per factor: +1, -1 or 0) and,
    for "proportional" and "target", ``attrs["base"]`` and ``attrs["coded_step"]``; for
    "target" also ``attrs["target_coded"]`` (x*) and ``attrs["box_half_width"]``.
    """
    factors, d, lo, hi = _factor_bounds(direction, low, high)
    n = _check_int(n_steps, "n_steps", 2)
    if rule not in ("range", "proportional", "target"):
        raise InputError(None, "rule", "'range', 'proportional' or 'target'", rule)
    if all(v == 0.0 for v in d.values()):
        raise InputError(None, "direction", "at least one non-zero component", d)
    sign = {f: int(np.sign(d[f])) for f in factors}
    half = {f: (hi[f] - lo[f]) / 2.0 for f in factors}
    centre = {f: (hi[f] + lo[f]) / 2.0 for f in factors}
    steps = np.arange(1, n + 1)
    out = pd.DataFrame({"step": steps})
    step_actual: dict[str, float] = {}
    if rule == "range":
        if base is not None or base_step is not None:
            raise InputError(None, "base/base_step", "None with rule 'range' (they apply to 'proportional')",
                             (base, base_step))
        for f in factors:
            if sign[f] > 0:
                out[f] = np.linspace(lo[f], hi[f], n)
            elif sign[f] < 0:
                out[f] = np.linspace(hi[f], lo[f], n)
            else:
                out[f] = np.full(n, centre[f])
            step_actual[f] = sign[f] * (hi[f] - lo[f]) / (n - 1)
    else:
        if rule == "target" and (base is not None or base_step is not None):
            raise InputError(None, "base/base_step", "None with rule 'target' (its base is the largest move)",
                             (base, base_step))
        if base is None:
            base = max(factors, key=lambda f: abs(d[f]))  # max() keeps the first on ties
        elif base not in d:
            raise InputError(None, "base", f"one of the factors {factors}", base)
        if d[base] == 0.0:
            raise InputError(None, "base", "a factor with a non-zero direction component", base)
        if base_step is None:
            base_step_f = (hi[base] - lo[base]) / (n - 1)
        else:
            base_step_f = abs(float(base_step))
            if not np.isfinite(base_step_f) or base_step_f == 0.0:
                raise InputError(None, "base_step", "a finite non-zero step in actual units", base_step)
        dx_base = base_step_f / half[base]
        coded = {f: d[f] / abs(d[base]) * dx_base for f in factors}
        shift = (n - 1) / 2.0
        for f in factors:
            step_actual[f] = coded[f] * half[f]
            out[f] = centre[f] + (steps - 1 - shift) * step_actual[f]
        out.attrs["base"] = base
        out.attrs["coded_step"] = coded
        if rule == "target":
            out.attrs["target_coded"] = dict(d)
            out.attrs["box_half_width"] = {f: 2.0 * half[f] / (n - 1) for f in factors}
    out.attrs["rule"] = rule
    out.attrs["step"] = step_actual
    out.attrs["direction"] = sign
    return out


def _path_steps(path) -> np.ndarray:
    if not isinstance(path, pd.DataFrame) or "step" not in path.columns:
        raise InputError(None, "path", "a DataFrame with a 'step' column", type(path).__name__)
    if len(path) == 0:
        raise InputError(None, "path", "at least one step", 0)
    return path["step"].to_numpy()


#: rules that choose a path step (:func:`chosen_step`)
PATH_CHOICES = ("closest", "fitted")
TREND_ALPHA = 0.05  # level of the test that keeps a trend's quadratic term


def path_trend(steps, values, alpha: float = TREND_ALPHA) -> dict:
    """The trend of one response along a climbing path, fitted through every step's run.

    Along a steepest-ascent path the response is expected to change smoothly with the step
    (first order, bending near an optimum); one DEM run per step adds its seed scatter.  An
    ordinary least-squares fit (statsmodels) of the finite values on the step,

        y_s = b0 + b1 u_s (+ b2 u_s^2) + e_s,   u_s = (s - mean s) / (half the step range),

    keeps the quadratic term when the path has at least five finite steps and its t-test
    gives p < ``alpha`` (a curvature the runs show beyond their scatter); otherwise the
    line.  With fewer than three finite steps no trend is fitted (``degree`` None, the
    fitted values are the runs themselves).

    Returns ``{"fitted": array per step (NaN where the run failed), "degree", "n",
    "residual_sd" (the runs' scatter about the trend, NaN without residual degrees of
    freedom), "p_quadratic" (NaN when not tested), "p_slope" (the line's t-test of its slope,
    NaN without residual degrees of freedom), "r2"}``.  A trend with neither its slope nor its
    curvature significant does not establish which step is closest to a target
    (:func:`trend_caution`).
    """
    # the OLS class itself, not statsmodels.api (which imports every model family: about
    # 0.3 s more of each job that draws or chooses on a path's trend)
    from statsmodels.regression.linear_model import OLS

    s = np.asarray(steps, dtype=float).reshape(-1)
    y = np.asarray(values, dtype=float).reshape(-1)
    if s.size != y.size:
        raise InputError(None, "values", f"{s.size} values (one per path step)", y.size)
    ok = np.isfinite(y)
    n = int(ok.sum())
    out = {"fitted": np.where(ok, y, np.nan), "degree": None, "n": n, "residual_sd": float("nan"),
           "p_quadratic": float("nan"), "p_slope": float("nan"), "r2": float("nan")}
    if n < 3:
        return out
    half = (s[ok].max() - s[ok].min()) / 2.0
    u = (s - s[ok].mean()) / (half if half > 0 else 1.0)

    def fit(deg):
        X = np.column_stack([u ** k for k in range(deg + 1)])
        return X, OLS(y[ok], X[ok]).fit()

    X, res = fit(1)
    deg = 1
    ps = float(res.pvalues[1])  # n >= 3: the line has a residual degree of freedom
    out["p_slope"] = ps if np.isfinite(ps) else float("nan")
    if n >= 5:
        X2, res2 = fit(2)
        p2 = float(res2.pvalues[2])
        out["p_quadratic"] = p2
        if np.isfinite(p2) and p2 < alpha:
            X, res, deg = X2, res2, 2
    fitted = X @ res.params
    out["fitted"] = np.where(ok, fitted, np.nan)
    out["degree"] = deg
    dof = n - (deg + 1)
    if dof > 0:
        out["residual_sd"] = float(np.sqrt(np.sum(res.resid ** 2) / dof))
    out["r2"] = float(res.rsquared) if np.isfinite(res.rsquared) else float("nan")
    return out


def trend_caution(trend: dict, alpha: float = TREND_ALPHA) -> str:
    """A sentence saying that a path's trend (:func:`path_trend`) does not tell its steps
    apart (a line whose slope's p-value is at least ``alpha``), or "" where it does or was not
    tested."""
    ps = trend.get("p_slope", float("nan"))
    if trend.get("degree") != 1 or ps is None or not np.isfinite(ps) or ps < alpha:
        return ""
    r2 = trend.get("r2", float("nan"))
    sd = trend.get("residual_sd", float("nan"))
    return (f"the trend through the path's runs has no significant slope (p = {ps:.2g}, R^2 = {r2:.2f}, "
            f"the runs scattering {sd:.3g} about it), so the path's runs do not establish which step is "
            "closest to the target nor show the screening's effects along it (more seeds per step, or "
            "larger samples, would)")


def chosen_step(
    path: pd.DataFrame,
    responses: dict[str, np.ndarray | list],
    targets: dict[str, float],
    rule: str = "closest",
    alpha: float = TREND_ALPHA,
) -> tuple[int, pd.DataFrame]:
    """Step of the climbing path whose simulated responses are closest to the targets.

    responses: response -> simulated value per path step (row order of ``path``; NaN for a
    failed step). targets: response -> measured target; every targeted response must be in
    ``responses`` (responses without a target are reported but do not count).  ``rule``:
    ``closest`` (the papers') compares each step's own run with the target; ``fitted``
    compares the value of the response's trend through all the path's runs
    (:func:`path_trend`, column ``fitted_<response>``) at each step whose run did not fail.
    Combined error

        E_s = 100 * sqrt(mean_r ((y_rs - t_r) / t_r)^2)   (%),

    over the targeted responses; for one response this is the papers' relative error
    |y - t| / |t| * 100. A step where any targeted response is NaN has E_s = NaN and is skipped.
    The chosen step has the smallest finite E_s (ties: the earlier step) and becomes the
    Box-Behnken centre (see :func:`bbd_levels`).

    Returns (chosen step number, frame with columns step, one per response,
    ``fitted_<response>`` per targeted response under ``fitted``,
    ``error_<response>_percent`` per targeted response, error_percent, chosen); under
    ``fitted`` the frame's ``attrs["trend"]`` holds each targeted response's trend
    (:func:`path_trend`'s degree, n, residual_sd, p_quadratic, r2).
    """
    if rule not in PATH_CHOICES:
        raise InputError(None, "rule", f"one of {', '.join(PATH_CHOICES)}", rule)
    steps = _path_steps(path)
    if not isinstance(responses, Mapping) or not responses:
        raise InputError(None, "responses", "a mapping response -> values per path step", responses)
    if not isinstance(targets, Mapping) or not targets:
        raise InputError(None, "targets", "at least one response -> target value", targets)
    out = pd.DataFrame({"step": steps})
    for r, v in responses.items():
        arr = np.asarray(v, dtype=float).reshape(-1)
        if arr.size != len(steps):
            raise InputError(None, f"responses[{r}]", f"{len(steps)} values (one per path step)", arr.size)
        out[r] = arr
    rel, trends = [], {}
    for r, t in targets.items():
        if r not in responses:
            raise InputError(None, "targets", f"targets only for given responses {list(responses)}", r)
        t = float(t)
        if not np.isfinite(t) or t == 0.0:
            raise InputError(None, f"targets[{r}]", "a finite non-zero target (errors are relative to it)", t)
        y = out[r].to_numpy()
        if rule == "fitted":
            trends[r] = path_trend(out["step"].to_numpy(float), y, alpha)
            y = trends[r]["fitted"]
            out[f"fitted_{r}"] = y
        e = (y - t) / t
        out[f"error_{r}_percent"] = np.abs(e) * 100.0
        rel.append(e)
    with np.errstate(invalid="ignore"):
        err = np.sqrt(np.mean(np.square(np.vstack(rel)), axis=0)) * 100.0
    err = np.where(np.isfinite(err), err, np.nan)
    out["error_percent"] = err
    if not np.isfinite(err).any():
        raise InputError(None, "responses", "at least one step with finite responses for every target",
                         "no finite error")
    i = int(np.nanargmin(err))  # first occurrence on ties
    out["chosen"] = np.arange(len(out)) == i
    # each targeted response's trend under ``fitted`` (path_trend without the fitted values)
    out.attrs["trend"] = {r: {k: v for k, v in tr.items() if k != "fitted"} for r, tr in trends.items()}
    best = steps[i]
    return (int(best) if float(best).is_integer() else best), out


def bbd_levels(
    path: pd.DataFrame,
    step: int,
    factors: list[str],
    bounds: dict[str, tuple[float, float]] | None = None,
    half_width: dict[str, float] | None = None,
) -> dict[str, dict[str, float]]:
    """Box-Behnken low / centre / high levels from the chosen step of the climbing path.

    The papers take the chosen step as the centre and its neighbours on the path as the low
    and high levels ("levels of no. 2, no. 3 and no. 4 were selected as low, medium and high",
    cinnamon soil; vineyard soil: step 2 centre, steps 1 and 3 low/high, with B descending
    along the path so step 1 is its HIGH level). For each factor the centre is its level at
    ``step`` and the other two levels are those of the previous and next rows of ``path``
    (sorted by step), sorted so low < high. At the first or last step the missing neighbour is
    the centre mirrored: centre -/+ the distance to the one existing neighbour.

    half_width: optional factor -> half width (actual units, > 0): the low and high levels are
    the centre -/+ it instead of the neighbours (the "target" rule's path, whose steps' spacing
    per factor follows its direction; :func:`derive_path`'s ``attrs["box_half_width"]``).

    bounds: optional physical limits factor -> (lower, upper), closed, None for no limit on a
    side (e.g. restitution (1e-6, 1), friction (0, None)). A triple with a level outside is
    shifted as a whole inside the violated bound, keeping its spacing (so the coded
    -1/0/+1 levels stay equally spaced); if the spacing high - low does not fit between the
    bounds, InputError. A factor without three distinct levels around ``step`` (e.g. d_j == 0,
    constant along the path) raises InputError.

    Returns {factor: {"low", "centre", "high", "note"}}; the note names the steps that gave
    the levels and any mirroring or shift.
    """
    _path_steps(path)
    if not isinstance(factors, (list, tuple)) or not factors:
        raise InputError(None, "factors", "a non-empty list of path columns", factors)
    missing = [f for f in factors if f not in path.columns or f == "step"]
    if missing:
        raise InputError(None, "factors", f"factor columns of the path {[c for c in path.columns if c != 'step']}",
                         missing)
    if len(path) < 2:
        raise InputError(None, "path", "at least 2 steps (the centre needs a neighbour)", len(path))
    p = path.sort_values("step", kind="stable").reset_index(drop=True)
    steps = p["step"].tolist()
    if len(set(steps)) != len(steps):
        raise InputError(None, "path.step", "unique step numbers", steps)
    if step not in steps:
        raise InputError(None, "step", f"one of the path steps {steps}", step)
    i = steps.index(step)
    bounds = {} if bounds is None else bounds
    if not isinstance(bounds, Mapping):
        raise InputError(None, "bounds", "a mapping factor -> (lower, upper)", bounds)
    half_width = {} if half_width is None else half_width
    if not isinstance(half_width, Mapping):
        raise InputError(None, "half_width", "a mapping factor -> half width", half_width)
    out: dict[str, dict[str, float]] = {}
    for f in factors:
        vals = p[f].to_numpy(dtype=float)
        c = vals[i]
        prev = vals[i - 1] if i > 0 else None
        nxt = vals[i + 1] if i + 1 < len(vals) else None
        if f in half_width:
            hw = float(half_width[f])
            if not (np.isfinite(hw) and hw > 0.0):
                raise InputError(None, f"half_width[{f}]", "a finite half width > 0", half_width[f])
            prev, nxt = c - hw, c + hw
            note = f"centre = step {steps[i]}, low/high = centre -/+ {_fmt(hw)} (the path's box half width)"
        elif prev is None:
            prev = 2.0 * c - nxt
            note = (f"centre = step {steps[i]}, other level = step {steps[i + 1]}, "
                    f"mirrored level = 2 * centre - step {steps[i + 1]} (first step of the path)")
        elif nxt is None:
            nxt = 2.0 * c - prev
            note = (f"centre = step {steps[i]}, other level = step {steps[i - 1]}, "
                    f"mirrored level = 2 * centre - step {steps[i - 1]} (last step of the path)")
        else:
            lo_s, hi_s = (steps[i - 1], steps[i + 1]) if prev < nxt else (steps[i + 1], steps[i - 1])
            note = f"low = step {lo_s}, centre = step {steps[i]}, high = step {hi_s}"
        lo, hi = min(prev, nxt), max(prev, nxt)
        if not all(np.isfinite([lo, c, hi])):
            raise InputError(None, f"path.{f}", "finite levels around the chosen step", (prev, c, nxt))
        if not lo < c < hi:
            raise InputError(None, f"path.{f}",
                             f"three distinct levels around step {step} with the centre between its "
                             "neighbours (a Box-Behnken factor needs low < centre < high; a factor "
                             "constant along the path cannot be one)", (prev, c, nxt))
        if f in bounds and bounds[f] is not None:
            bl, bu = _bound_pair(bounds[f], f)
            if hi - lo > bu - bl:
                raise InputError(None, f"bounds[{f}]",
                                 f"room for the level spacing high - low = {_fmt(hi - lo)}", (bl, bu))
            shift = 0.0
            if lo < bl:
                shift = bl - lo
            elif hi > bu:
                shift = bu - hi
            if shift != 0.0:
                lo, c, hi = lo + shift, c + shift, hi + shift
                if shift > 0:
                    lo = bl  # exact bound (avoid round-off just outside)
                else:
                    hi = bu
                note += f"; shifted by {shift:+.3g} to stay within bounds [{_fmt(bl)}, {_fmt(bu)}]"
        out[f] = {"low": float(lo), "centre": float(c), "high": float(hi), "note": note}
    return out


def _bound_pair(b, f: str) -> tuple[float, float]:
    try:
        bl, bu = b
    except (TypeError, ValueError):
        raise InputError(None, f"bounds[{f}]", "a pair (lower, upper), None for no limit", b) from None
    bl = -np.inf if bl is None else float(bl)
    bu = np.inf if bu is None else float(bu)
    if np.isnan(bl) or np.isnan(bu) or not bl < bu:
        raise InputError(None, f"bounds[{f}]", "lower < upper", (bl, bu))
    return bl, bu


__all__ = [
    "PATH_CHOICES",
    "path_trend",
    "bbd_levels",
    "chosen_step",
    "derive_path",
    "path_direction",
    "path_target",
    "select_factors",
    "steepest_ascent_path",
]
