"""Figures of an adaptive design (``design: adaptive``): how its runs approached the targets.

* :func:`adaptive_progress` draws, for one case, each response of every run against the run's
  number (start, proposal and verification runs marked apart; the target and its tolerance
  band shaded), and below it the best candidate's probability of consistency per iteration
  with the verification threshold.  Input: the case's ``runs.csv`` and ``result.json`` and
  the ``best_p`` of each iteration (from the ``step/<it>.json`` records).
* :func:`error_against_runs`: the error of the best verified set against the runs spent, per
  method (the adaptive design's step curve; the recipe's and other methods' verified sets as
  single points at their run counts).  Input: rows of
  :data:`soilcal.chain.adaptive.PROGRESS_COLUMNS`.
* :func:`proposals_over_region`: per iteration, the surrogate's consistent region (a sample of
  the candidates with P > 1/2, as that iteration saw it) projected on pairs of factors, the
  runs made before it and the runs it asked for.  Input: the ``step/<it>.json`` records and the
  case's ``runs.csv``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from soilcal.errors import InputError
from soilcal.plots.figures import _figure, save_figure

MARKERS = {"start": ("s", "0.45"), "proposal": ("o", "C0"), "verification": ("D", "C3")}
#: legends beside the axes, where they hide no run
OUTSIDE = dict(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, frameon=False)


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
    fig = _figure(8.6, 2.4 * n + 2.2)
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
        ax.legend(**OUTSIDE)
    ax = axes[-1]
    if best_p:
        it, p = zip(*best_p)
        ax.plot(it, p, "o-", color="C2", label="best candidate")
    ax.axhline(result["settings"]["p_verify"], color="C3", ls="--", lw=1, label="verified from here")
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlabel("iteration (upper panels: run number)")
    ax.set_ylabel("P(all within tolerance)")
    ax.legend(**OUTSIDE)
    axes[0].set_title(f"{result['stage']} / {result['case']}: {result['status']} after {result['runs']} runs",
                      fontsize=9)
    fig.tight_layout()
    return list(save_figure(fig, stem))


#: the markers of the methods of :func:`error_against_runs` (other methods: grey triangles)
METHOD_STYLE = {"adaptive": ("o", "C0"), "recipe": ("s", "C3"), "grainlearning": ("^", "C2")}


def error_against_runs(df: pd.DataFrame, stem, title: str = "", band_pct: float | None = None) -> list[Path]:
    """One panel per response: the signed relative error (percent) of the best verified set
    against the runs spent, per method, with the tolerance band; a minimised (maximised)
    response, which has no target, shows its verified mean instead.  ``df``: rows of
    ``soilcal.chain.adaptive.PROGRESS_COLUMNS`` (one per method, response and point of the
    curve; a method with one row is one point).  ``band_pct``: the band to shade where no row
    gives a target's tolerance (a comparison's common criterion, such as 2 %)."""
    need = ["method", "runs", "response", "goal", "target", "tolerance", "verified_mean", "error_pct"]
    missing = [c for c in need if c not in df.columns]
    if missing:
        raise InputError("progress", missing[0], f"columns {', '.join(need)}", "missing")
    responses = list(dict.fromkeys(df["response"]))
    fig = _figure(8.0, 2.3 * max(len(responses), 1) + 0.8)
    axes = [fig.add_subplot(len(responses), 1, i + 1) for i in range(len(responses))] or [fig.add_subplot(1, 1, 1)]
    for ax, rid in zip(axes, responses):
        g = df[df["response"] == rid]
        aimed = str(g["goal"].iloc[0]) == "target"
        if aimed:
            t = g.dropna(subset=["target", "tolerance"])
            t = t[t["target"].astype(float) != 0.0]  # a target of 0 has no relative band
            band = 100.0 * float(t["tolerance"].iloc[-1]) / abs(float(t["target"].iloc[-1])) if len(t) else band_pct
            if band is not None:
                ax.axhspan(-band, band, color="0.88", zorder=0, label=f"tolerance +- {band:.2g} %")
            ax.axhline(0.0, color="0.4", lw=1, zorder=1)
        else:  # the level the design held the response to, and how much worse it accepts
            a = g[g["method"] == "adaptive"].dropna(subset=["target", "tolerance"]).sort_values("runs", kind="stable")
            if len(a):
                x, lv, tol = a["runs"].to_numpy(float), a["target"].to_numpy(float), a["tolerance"].to_numpy(float)
                # the last level holds to the end of the axis's data
                end = max(float(g["runs"].max()), x[-1]) + max(1.0, 0.02 * float(g["runs"].max()))
                x, lv, tol = np.append(x, end), np.append(lv, lv[-1]), np.append(tol, tol[-1])
                sign = 1.0 if str(g["goal"].iloc[0]) == "minimize" else -1.0
                ax.fill_between(x, lv, lv + sign * tol, step="post", color="0.88", zorder=0,
                                label="best predicted level, + tolerance")
                ax.plot(x, lv, color="0.4", lw=1, ls="--", drawstyle="steps-post", zorder=1)
        col = "error_pct" if aimed else "verified_mean"
        for method, m in g.groupby("method", sort=False):
            m = m.sort_values("runs", kind="stable")
            mk, c = METHOD_STYLE.get(method, ("v", "0.4"))
            y = m[col].to_numpy(float)
            x = m["runs"].to_numpy(float)
            if len(m) > 1:
                ax.plot(x, y, mk + "-", color=c, ms=4, lw=1.2, drawstyle="steps-post", label=method)
            else:
                ax.plot(x, y, mk, color=c, ms=7, ls="none", label=f"{method} ({int(x[0])} runs)")
        ax.set_ylabel("relative error, %" if aimed else "verified mean")
        ax.set_title(rid if aimed else f"{rid} ({g['goal'].iloc[0]})", fontsize=8, loc="left")
        ax.set_xlim(left=0)  # the run counts against none spent
        ax.legend(**OUTSIDE)
    axes[-1].set_xlabel("DEM runs spent (one seed each)")
    fig.suptitle(title or "best verified set against runs spent", fontsize=9)
    fig.tight_layout()
    return list(save_figure(fig, stem))


def factor_pairs(d: int) -> list[tuple[int, int]]:
    """Pairs of factor indices that show every factor once: (0, 1), (2, 3), ..., and for an odd
    count the last factor with the one before it; one factor: [(0, 0)]."""
    if d <= 1:
        return [(0, 0)]
    pairs = [(i, i + 1) for i in range(0, d - 1, 2)]
    if d % 2:
        pairs.append((d - 2, d - 1))
    return pairs


def proposals_over_region(steps: list[dict], runs: pd.DataFrame, stem, max_rows: int = 6) -> list[Path]:
    """Per iteration (at most ``max_rows``, evenly spaced, the last one included) and pair of
    factors (:func:`factor_pairs`): the sample of the consistent region the iteration saw
    (its record's ``consistent``), the case's runs before it (grey) and the runs it asked for
    (proposals, verification)."""
    steps = sorted(steps, key=lambda r: r["iteration"])
    if not steps:
        raise InputError("step", "records", "at least one step record", "none")
    factors = steps[0]["problem"]["factors"]
    names = list(factors)
    missing = [n for n in names if n not in runs.columns]
    if missing:
        raise InputError("runs.csv", missing[0], "a column for every factor", "missing")
    shown = [r for r in steps if r["runs"] or r.get("consistent")]
    if len(shown) > max_rows:
        idx = np.unique(np.round(np.linspace(0, len(shown) - 1, max_rows)).astype(int))
        shown = [shown[i] for i in idx]
    pairs = factor_pairs(len(names))
    fig = _figure(2.6 * len(pairs) + 0.6, 2.4 * max(len(shown), 1) + 0.4)
    for r_i, rec in enumerate(shown):
        it = int(rec["iteration"])
        region = np.asarray(rec.get("consistent") or [], float).reshape(-1, len(names))
        before = runs[runs["iteration"] < it]
        asked = pd.DataFrame([{**x["levels"], "kind": x["kind"]} for x in rec["runs"]])
        for c_i, (i, j) in enumerate(pairs):
            ax = fig.add_subplot(len(shown), len(pairs), r_i * len(pairs) + c_i + 1)
            xi, xj = names[i], names[j]
            one = i == j  # a single factor: its levels on one line
            if len(region):
                ax.plot(region[:, i], region[:, j] if not one else np.zeros(len(region)), ".", color="C2",
                        ms=2, alpha=0.35, label="consistent (P > 1/2)")
            if len(before):
                ax.plot(before[xi], before[xj] if not one else np.zeros(len(before)), ".", color="0.55", ms=4,
                        label="runs before")
            for kind, (m, c) in MARKERS.items():
                sel = asked[asked["kind"] == kind] if len(asked) else asked
                if len(sel):
                    ax.plot(sel[xi], sel[xj] if not one else np.zeros(len(sel)), m, color=c, ms=6,
                            mfc="none" if kind == "verification" else c, ls="none", label=f"{kind} asked")
            ax.set_xlim(*factors[xi])
            if not one:
                ax.set_ylim(*factors[xj])
                ax.set_ylabel(xj, fontsize=8)
            else:
                ax.set_yticks([])
            ax.set_xlabel(xi, fontsize=8)
            ax.tick_params(labelsize=7)
            ax.set_title(f"iteration {it}: {rec['status']}" if c_i == 0 else "", fontsize=8, loc="left")
    # one legend for the figure: every kind of mark drawn in any panel
    handles = {}
    for ax in fig.axes:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(lab, h)
    if handles:
        ncol = min(len(handles), 3)
        fig.legend(list(handles.values()), list(handles), fontsize=7, loc="upper center", ncol=ncol, frameon=False)
    rows = -(-len(handles) // 3) if handles else 0
    fig.tight_layout(rect=(0, 0, 1, 1 - (0.1 + 0.18 * rows) / fig.get_figheight()))
    return list(save_figure(fig, stem))


__all__ = ["METHOD_STYLE", "adaptive_progress", "error_against_runs", "factor_pairs", "proposals_over_region"]
