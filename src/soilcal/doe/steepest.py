"""Path of steepest ascent (descent) from a first-order model.

Montgomery, Design and Analysis of Experiments, sec. 11.2: for a fitted first-order model
y = b0 + sum_j b_j x_j in coded units, the path moves from the design centre in steps
proportional to the coefficients. Choose a base factor i and its step in actual units
Delta_i; in coded units Delta x_i = Delta_i / h_i (h = half range). The other coded steps are
Delta x_j = b_j / |b_i| * |Delta x_i| (ascent) or its negative (descent), and in actual
units Delta_j = Delta x_j * h_j. Step s is start + s * Delta.
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


__all__ = ["steepest_ascent_path"]
