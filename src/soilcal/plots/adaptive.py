"""Figures of an adaptive design (``design: adaptive``): how its runs approached the targets.

:func:`adaptive_progress` draws, for one case, each response of every run against the run's
number (start, proposal and verification runs marked apart; the target and its tolerance band
shaded), and below it the best candidate's probability of consistency per iteration with the
verification threshold.  Input: the case's ``runs.csv`` and ``result.json`` and the
``best_p`` of each iteration (from the ``step/<it>.json`` records).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from soilcal.errors import InputError
from soilcal.plots.figures import _figure, save_figure

MARKERS = {"start": ("s", "0.45"), "proposal": ("o", "C0"), "verification": ("D", "C3")}


def tolerance_band(t: dict) -> tuple[float, float, str]:
    """The band a response's runs aim at, from a record's ``problem.targets`` entry: target
    +- tolerance, or from the best level up (``minimize``) or down (``maximize``) by the
    tolerance; and its legend label."""
    goal, v, tol = t.get("goal", "target"), float(t["value"]), float(t["tolerance"])
    if goal == "minimize":
        return v, v + tol, f"minimize: best {v:.4g}, tolerance {tol:.2g}"
    if goal == "maximize":
        return v - tol, v, f"maximize: best {v:.4g}, tolerance {tol:.2g}"
    return v - tol, v + tol, f"target {v:.4g} +- {tol:.2g}"


def adaptive_progress(runs: pd.DataFrame, result: dict, best_p: list[tuple[int, float]], stem) -> list[Path]:
    targets = result["problem"]["targets"]
    missing = [r for r in targets if r not in runs.columns]
    if missing:
        raise InputError("runs.csv", missing[0], "a column for every target response", "missing")
    n = len(targets)
    fig = _figure(7.0, 2.4 * n + 2.2)
    axes = [fig.add_subplot(n + 1, 1, i + 1) for i in range(n + 1)]
    x = np.arange(1, len(runs) + 1)
    for ax, (rid, t) in zip(axes, targets.items()):
        lo, hi, label = tolerance_band(t)
        ax.axhspan(lo, hi, color="0.85", zorder=0, label=label)
        ax.axhline(t["value"], color="0.4", lw=1, zorder=1)
        for kind, (m, c) in MARKERS.items():
            sel = (runs["kind"] == kind).to_numpy()
            if sel.any():
                ax.plot(x[sel], runs.loc[sel, rid].to_numpy(float), m, color=c, ms=5, ls="none", label=kind)
        ax.set_ylabel(rid)
        ax.legend(fontsize=7, loc="best", framealpha=0.6)
    ax = axes[-1]
    if best_p:
        it, p = zip(*best_p)
        ax.plot(it, p, "o-", color="C2", label="best candidate")
    ax.axhline(result["settings"]["p_verify"], color="C3", ls="--", lw=1, label="verified from here")
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlabel("iteration (upper panels: run number)")
    ax.set_ylabel("P(all within tolerance)")
    ax.legend(fontsize=7, loc="best", framealpha=0.6)
    axes[0].set_title(f"{result['stage']} / {result['case']}: {result['status']} after {result['runs']} runs",
                      fontsize=9)
    fig.tight_layout()
    return list(save_figure(fig, stem))


__all__ = ["adaptive_progress"]
