"""Figures of a calibration: response surfaces, Pareto chart of effects, steepest-ascent path,
regression diagnostics and optimiser convergence.

Every function writes ``<stem>.png`` (150 dpi) and ``<stem>.pdf`` and returns both paths.
Figures are drawn on :class:`matplotlib.figure.Figure` objects with the Agg canvas (no pyplot
state, safe in worker processes).

Statistics drawn:
- Pareto chart: standardized effect t_j = effect_j / se(effect_j) = sign(b_j) sqrt(F_j) for a
  one-degree-of-freedom term (Montgomery, Design and Analysis of Experiments, ch. 6), with the
  two-sided critical value t_{alpha/2, df_res} and the Bonferroni limit t_{alpha/(2m), df_res}
  for m terms (as Design-Expert draws them).
- Normal probability plot: ordered studentized residuals against the normal quantiles
  Phi^-1((i - 0.375)/(n + 0.25)) (Blom positions, as in scipy.stats.probplot), the y axis
  labelled in normal % probability.
- Studentized residuals against run and predicted value with +-3 limits; Cook's distance
  D_i = r_i^2 h_ii / (p (1 - h_ii)) against run with the 4/n reference, marker size from leverage.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
import pandas as pd
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from soilcal.errors import InputError

DPI = 150


# --------------------------------------------------------------------------- helpers


def _figure(w: float, h: float, **kw) -> Figure:
    fig = Figure(figsize=(w, h), **kw)
    FigureCanvasAgg(fig)
    return fig


def save_figure(fig: Figure, stem, tight_bbox: bool = False) -> tuple[Path, Path]:
    """Write ``<stem>.png`` (150 dpi) and ``<stem>.pdf``; returns (png, pdf). ``tight_bbox``
    crops to the drawn artists (needed for 3-D axes, whose labels tight_layout ignores)."""
    stem = Path(stem)
    if stem.suffix.lower() in (".png", ".pdf"):
        stem = stem.with_suffix("")
    stem.parent.mkdir(parents=True, exist_ok=True)
    png, pdf = stem.parent / f"{stem.name}.png", stem.parent / f"{stem.name}.pdf"
    bbox = "tight" if tight_bbox else None
    fig.savefig(png, dpi=DPI, bbox_inches=bbox)
    fig.savefig(pdf, bbox_inches=bbox)
    return png, pdf


def factor_label(symbol: str, label=None) -> str:
    """'A: <name> (<unit>)' from a (name, unit) pair, a 'name (unit)' string or nothing."""
    if label is None or label == "" or label == symbol:
        return symbol
    if isinstance(label, (tuple, list)):
        name, unit = (list(label) + [None])[:2]
        text = f"{name} ({unit})" if unit else f"{name}"
    else:
        text = str(label)
    return text if text.startswith(f"{symbol}:") else f"{symbol}: {text}"


def _factor_labels(factors: Sequence[str], labels) -> list[str]:
    if labels is None:
        return [factor_label(s) for s in factors]
    if isinstance(labels, Mapping):
        return [factor_label(s, labels.get(s)) for s in factors]
    labels = list(labels)
    if len(labels) != len(factors):
        raise InputError(None, "labels", f"{len(factors)} factor labels {list(factors)}", len(labels))
    return [factor_label(s, lab) for s, lab in zip(factors, labels)]


def _need(model, attrs: Sequence[str], what: str) -> None:
    for a in attrs:
        if not hasattr(model, a):
            raise InputError(None, "model", f"a fitted model with .{a} ({what})", type(model).__name__)


def _diagnostics(model) -> pd.DataFrame:
    """run, observed, fitted, residual, studentized, leverage, cooks_distance of a fitted model."""
    if hasattr(model, "diagnostics") and callable(model.diagnostics):
        d = model.diagnostics()
        if isinstance(d, pd.DataFrame) and {"studentized", "leverage", "cooks_distance"} <= set(d.columns):
            d = d.copy()
            if hasattr(model, "fitted_transformed"):
                d["fitted_scale"] = np.asarray(model.fitted_transformed, float)
            else:
                d["fitted_scale"] = d["fitted"]
            return d
    _need(model, ("observed", "fitted", "residuals", "studentized_residuals", "leverage", "cooks_distance"),
          "regression diagnostics")
    n = len(np.asarray(model.observed))
    fitted = np.asarray(model.fitted, float)
    return pd.DataFrame({
        "run": np.arange(1, n + 1),
        "observed": np.asarray(model.observed, float),
        "fitted": fitted,
        "residual": np.asarray(model.residuals, float),
        "studentized": np.asarray(model.studentized_residuals, float),
        "leverage": np.asarray(model.leverage, float),
        "cooks_distance": np.asarray(model.cooks_distance, float),
        "fitted_scale": np.asarray(getattr(model, "fitted_transformed", fitted), float),
    })


# --------------------------------------------------------------------------- response surface


def _fixed_levels(fixed_coded, factors: list[str]) -> np.ndarray:
    k = len(factors)
    if isinstance(fixed_coded, Mapping):
        x = np.zeros(k)
        for s, v in fixed_coded.items():
            if s not in factors:
                raise InputError(None, "fixed_coded", f"factor symbols among {factors}", s)
            x[factors.index(s)] = float(v)
        return x
    x = np.asarray(fixed_coded, dtype=float)
    if x.ndim == 0:
        return np.full(k, float(x))
    if x.shape != (k,):
        raise InputError(None, "fixed_coded", f"a number, {k} coded levels or a mapping", x.tolist())
    return x


def response_surface(
    model,
    i: int,
    j: int,
    fixed_coded=0.0,
    stem="response_surface",
    labels=None,
    design_points=None,
    response_label: str | None = None,
    grid: int = 41,
) -> tuple[Path, Path]:
    """3-D surface and contour plot of the response over factors i and j (0-based), the other
    factors held at ``fixed_coded`` (coded level(s)). Axes in actual units.

    design_points: (n, k) coded design, projected onto the (i, j) plane of the contour plot;
    replicated points are annotated with their count.
    """
    _need(model, ("factors", "low", "high", "predict"), "response surface")
    factors = list(model.factors)
    k = len(factors)
    for name, v in (("i", i), ("j", j)):
        if not isinstance(v, (int, np.integer)) or not 0 <= v < k:
            raise InputError(None, name, f"a factor index in 0..{k - 1} ({factors})", v)
    if i == j:
        raise InputError(None, "j", "a factor index different from i", j)
    x0 = _fixed_levels(fixed_coded, factors)
    low, high = np.asarray(model.low, float), np.asarray(model.high, float)
    centre, half = (low + high) / 2, (high - low) / 2
    labs = _factor_labels(factors, labels)
    rlab = response_label or getattr(model, "response", "response")

    u = np.linspace(-1, 1, grid)
    U, V = np.meshgrid(u, u)
    X = np.tile(x0, (U.size, 1))
    X[:, i], X[:, j] = U.ravel(), V.ravel()
    Z = np.asarray(model.predict(X), float).reshape(U.shape)
    if not np.all(np.isfinite(Z)):
        raise InputError(None, "model", "finite predictions over the coded box", "NaN/inf")
    XA, YA = centre[i] + U * half[i], centre[j] + V * half[j]

    fig = _figure(12.5, 5.2)
    ax3 = fig.add_subplot(1, 2, 1, projection="3d")
    surf = ax3.plot_surface(XA, YA, Z, cmap="viridis", linewidth=0.2, edgecolor="k", alpha=0.9, antialiased=True)
    ax3.set_xlabel(labs[i], labelpad=8)
    ax3.set_ylabel(labs[j], labelpad=8)
    ax3.set_zlabel(rlab, labelpad=8)
    ax3.view_init(elev=25, azim=-130)
    fig.colorbar(surf, ax=ax3, shrink=0.6, pad=0.12, label=rlab)

    ax = fig.add_subplot(1, 2, 2)
    cf = ax.contourf(XA, YA, Z, levels=15, cmap="viridis")
    cs = ax.contour(XA, YA, Z, levels=8, colors="k", linewidths=0.7)
    ax.clabel(cs, fmt="%.3g", fontsize=8)
    fig.colorbar(cf, ax=ax, label=rlab)
    if design_points is not None:
        P = np.asarray(design_points, float)
        if P.ndim != 2 or P.shape[1] != k:
            raise InputError(None, "design_points", f"an (n, {k}) array of coded levels", P.shape)
        pts, counts = np.unique(np.round(P[:, [i, j]], 9), axis=0, return_counts=True)
        pa = centre[[i, j]] + pts * half[[i, j]]
        ax.scatter(pa[:, 0], pa[:, 1], s=36, c="red", edgecolors="white", zorder=5, label="design points")
        for (xa, ya), c in zip(pa, counts):
            if c > 1:
                ax.annotate(str(c), (xa, ya), xytext=(5, 5), textcoords="offset points", color="red", fontsize=9)
        ax.legend(loc="upper right", fontsize=8, framealpha=0.8)
    ax.set_xlabel(labs[i])
    ax.set_ylabel(labs[j])
    others = [f"{factors[m]} = {centre[m] + x0[m] * half[m]:.4g}" for m in range(k) if m not in (i, j)]
    title = f"{rlab} vs {factors[i]}, {factors[j]}"
    if others:
        title += "  (" + ", ".join(others) + ")"
    fig.suptitle(title)
    fig.tight_layout()
    return save_figure(fig, stem, tight_bbox=True)


# --------------------------------------------------------------------------- Pareto chart


def standardized_effects(effects: pd.DataFrame, df_resid: float | None = None) -> pd.DataFrame:
    """[term, t] from a table with 't' (or 't_value'), or 'effect' with 'F' or 'p'."""
    from scipy import stats  # here, not at module import: the DEM summary figures need no scipy.stats

    if not isinstance(effects, pd.DataFrame) or "term" not in effects.columns or effects.empty:
        raise InputError(None, "effects", "a non-empty DataFrame with column 'term'", type(effects).__name__)
    cols = set(effects.columns)
    if "t" in cols or "t_value" in cols:
        t = effects["t" if "t" in cols else "t_value"].to_numpy(float)
    elif "effect" in cols and "F" in cols:
        t = np.sign(effects["effect"].to_numpy(float)) * np.sqrt(effects["F"].to_numpy(float))
    elif "effect" in cols and "p" in cols and df_resid:
        t = np.sign(effects["effect"].to_numpy(float)) * stats.t.isf(effects["p"].to_numpy(float) / 2, df_resid)
    else:
        raise InputError(None, "effects", "columns 't', or 'effect' with 'F' (or 'p' and df_resid)", sorted(cols))
    if not np.all(np.isfinite(t)):
        raise InputError(None, "effects", "finite standardized effects", t.tolist())
    return pd.DataFrame({"term": effects["term"].astype(str).to_numpy(), "t": t})


def pareto_effects(
    effects: pd.DataFrame,
    stem="pareto",
    alpha: float = 0.05,
    bonferroni: bool = True,
    df_resid: float | None = None,
    response_label: str | None = None,
    reference: pd.DataFrame | None = None,
    reference_label: str = "paper",
) -> tuple[Path, Path]:
    """Pareto chart of |standardized effects| with the t critical and Bonferroni limits.

    ``df_resid`` defaults to ``effects.attrs['residual']['df']`` (as
    :func:`soilcal.rsm.screening_effects` records it).

    reference: published standardized effects, columns term and t (as the paper prints them or
    as computed from its ANOVA table), drawn as black diamonds at |t| on the rows of the same
    terms; terms missing from either side, and NaN t, are skipped.
    """
    fig = _pareto_figure(effects, alpha, bonferroni, df_resid, response_label, reference, reference_label)
    return save_figure(fig, stem)


def _reference_effects(reference, terms) -> pd.DataFrame:
    """[term, t] of a published effects table, restricted to ``terms`` (NaN t dropped)."""
    if not isinstance(reference, pd.DataFrame):
        raise InputError(None, "reference", "a DataFrame with columns term, t", type(reference).__name__)
    missing = [c for c in ("term", "t") if c not in reference.columns]
    if missing:
        raise InputError(None, "reference", "columns ['term', 't']", f"missing {missing}")
    ref = pd.DataFrame({"term": reference["term"].astype(str).to_numpy(),
                        "t": pd.to_numeric(reference["t"], errors="coerce").to_numpy(float)})
    ref = ref[np.isfinite(ref["t"]) & ref["term"].isin(list(terms))]
    return ref.drop_duplicates("term", keep="first")


def _pareto_figure(effects, alpha, bonferroni, df_resid, response_label, reference=None,
                   reference_label: str = "paper") -> Figure:
    from scipy import stats  # here, not at module import: the DEM summary figures need no scipy.stats

    if not 0 < alpha < 1:
        raise InputError(None, "alpha", "a significance level in (0, 1)", alpha)
    if df_resid is None:
        df_resid = (getattr(effects, "attrs", {}) or {}).get("residual", {}).get("df")
    if df_resid is None or not df_resid > 0:
        raise InputError(None, "df_resid", "residual degrees of freedom > 0 (argument or effects.attrs)", df_resid)
    tab = standardized_effects(effects, df_resid).assign(abs_t=lambda d: d["t"].abs())
    tab = tab.sort_values("abs_t", ascending=True, kind="stable")
    m = len(tab)
    t_crit = float(stats.t.isf(alpha / 2, df_resid))
    t_bonf = float(stats.t.isf(alpha / (2 * m), df_resid))

    fig = _figure(7.5, 0.45 * m + 2.0)
    ax = fig.add_subplot(1, 1, 1)
    colours = np.where(tab["t"] >= 0, "#d95f02", "#1b9e77")
    ax.barh(tab["term"], tab["abs_t"], color=colours, edgecolor="k")
    ref = None if reference is None else _reference_effects(reference, tab["term"])
    ax.axvline(t_crit, color="k", ls="-", lw=1.2, label=f"t critical = {t_crit:.3f} (alpha = {alpha:g}, df = {df_resid:g})")
    if bonferroni:
        ax.axvline(t_bonf, color="k", ls="--", lw=1.2, label=f"Bonferroni limit = {t_bonf:.3f}")
    if ref is not None and not ref.empty:
        # category axis: the term strings land on the rows of the bars
        ax.plot(ref["t"].abs().to_numpy(), ref["term"].to_numpy(), "D", color="k", mfc="k", ms=7, ls="none",
                zorder=4, label=f"{reference_label} |t|")
    from matplotlib.patches import Patch

    handles, _ = ax.get_legend_handles_labels()
    handles += [Patch(color="#d95f02", label="positive effect"), Patch(color="#1b9e77", label="negative effect")]
    ax.legend(handles=handles, loc="lower right", fontsize=8)
    ax.set_xlabel("|standardized effect| (t-value)")
    ax.set_ylabel("term")
    ax.set_title(f"Pareto chart{': ' + response_label if response_label else ''}")
    xmax = max(float(tab["abs_t"].max()), t_bonf if bonferroni else t_crit)
    if ref is not None and not ref.empty:
        xmax = max(xmax, float(ref["t"].abs().max()))
    ax.set_xlim(0, xmax * 1.1)
    fig.tight_layout()
    return fig


# --------------------------------------------------------------------------- steepest ascent


def steepest_ascent(
    df: pd.DataFrame,
    factors: Sequence[str],
    response: str,
    target: float | None,
    stem="steepest_ascent",
    response_label: str | None = None,
    reference: pd.DataFrame | None = None,
    reference_label: str = "paper",
    trend=None,
) -> tuple[Path, Path]:
    """Response against step of a steepest-ascent (climbing) path, with the target line and the
    relative error |y - target| / target (%) on a second axis; factor levels under each step.

    reference: the published path, columns step and ``response``, drawn as a second line
    (orange squares, dashed) on the response axis; NaN responses are skipped.
    trend: the trend through the runs, one value per step, that chooses the Box-Behnken
    centre (:func:`soilcal.doe.steepest.path_trend`): drawn as a green line, and the error
    bars and the marked step are the trend's."""
    fig = _steepest_ascent_figure(df, factors, response, target, response_label, reference, reference_label,
                                  trend)
    return save_figure(fig, stem)


def _steepest_ascent_figure(df, factors, response, target, response_label=None, reference=None,
                            reference_label: str = "paper", trend=None) -> Figure:
    if not isinstance(df, pd.DataFrame):
        raise InputError(None, "df", "a DataFrame with columns step, factors, response", type(df).__name__)
    missing = [c for c in ["step", *factors, response] if c not in df.columns]
    if missing:
        raise InputError(None, "df", f"columns {['step', *factors, response]}", f"missing {missing}")
    if df.empty:
        raise InputError(None, "df", "at least one step", 0)
    if reference is not None:
        if not isinstance(reference, pd.DataFrame):
            raise InputError(None, "reference", f"a DataFrame with columns step, {response}", type(reference).__name__)
        missing = [c for c in ("step", response) if c not in reference.columns]
        if missing:
            raise InputError(None, "reference", f"columns {['step', response]}", f"missing {missing}")
    steps = df["step"].to_numpy()
    y = df[response].to_numpy(float)
    if trend is not None:
        trend = np.asarray(trend, dtype=float).reshape(-1)
        if trend.size != y.size:
            raise InputError(None, "trend", f"{y.size} values (one per step)", trend.size)
    rlab = response_label or response
    fig = _figure(7.5, 5.0)
    ax = fig.add_subplot(1, 1, 1)
    ax.plot(steps, y, "o-" if trend is None else "o:", color="C0", label=rlab)
    if trend is not None:
        ax.plot(steps, trend, "-", color="C2", lw=2, label="trend through the runs")
    judged = y if trend is None else trend
    if reference is not None:
        rs = pd.to_numeric(reference["step"], errors="coerce").to_numpy(float)
        ry = pd.to_numeric(reference[response], errors="coerce").to_numpy(float)
        keep = np.isfinite(rs) & np.isfinite(ry)
        if keep.any():
            ax.plot(rs[keep], ry[keep], "s--", color="C1", mec="k", label=f"{reference_label}: {rlab}")
    if target is not None and np.isfinite(target):
        ax.axhline(target, color="C3", ls="--", label=f"target = {target:g}")
        if target != 0:
            err = np.abs(judged - target) / abs(target) * 100
            err = np.where(np.isfinite(y), err, np.nan)
            ax2 = ax.twinx()
            ax2.bar(steps, err, width=0.35, color="0.6", alpha=0.5,
                    label="relative error" if trend is None else "relative error of the trend")
            ax2.set_ylabel("relative error (%)")
            ax2.set_ylim(0, max(float(np.nanmax(err)) * 1.3, 1.0) if np.isfinite(err).any() else 1.0)
            if np.isfinite(err).any():
                best = int(np.nanargmin(err))
                ax.annotate(f"{err[best]:.2f} %", (steps[best], judged[best]), xytext=(0, 12),
                            textcoords="offset points", ha="center", color="C3", fontsize=9)
            ax.set_zorder(ax2.get_zorder() + 1)
            ax.patch.set_visible(False)
            h1, l1 = ax.get_legend_handles_labels()
            h2, l2 = ax2.get_legend_handles_labels()
            ax.legend(h1 + h2, l1 + l2, loc="best", fontsize=8)
    else:
        ax.legend(loc="best", fontsize=8)
    ticks = [f"{s}\n" + "\n".join(f"{f}={df[f].iloc[n]:.4g}" for f in factors) for n, s in enumerate(steps)]
    ax.set_xticks(steps)
    ax.set_xticklabels(ticks, fontsize=7)
    ax.set_xlabel("step (factor levels)")
    ax.set_ylabel(rlab)
    ax.set_title("Steepest ascent path")
    fig.tight_layout()
    return fig


# --------------------------------------------------------------------------- diagnostics


def predicted_vs_actual(model, stem="predicted_vs_actual", response_label: str | None = None) -> tuple[Path, Path]:
    """Predicted (fitted) against actual (observed) responses with the 1:1 line."""
    _need(model, ("observed", "fitted"), "predicted vs actual")
    obs = np.asarray(model.observed, float)
    fit = np.asarray(model.fitted, float)
    if obs.shape != fit.shape or obs.size < 2:
        raise InputError(None, "model", "observed and fitted of equal length >= 2", (obs.shape, fit.shape))
    rlab = response_label or getattr(model, "response", "response")
    fig = _figure(5.5, 5.0)
    ax = fig.add_subplot(1, 1, 1)
    ax.scatter(obs, fit, s=30, c="C0", edgecolors="k", zorder=3)
    lo, hi = float(min(obs.min(), fit.min())), float(max(obs.max(), fit.max()))
    pad = 0.05 * (hi - lo if hi > lo else 1.0)
    ax.plot([lo - pad, hi + pad], [lo - pad, hi + pad], "k--", lw=1, label="1:1")
    ax.set_xlim(lo - pad, hi + pad)
    ax.set_ylim(lo - pad, hi + pad)
    text = ""
    if hasattr(model, "fit_statistics"):
        s = model.fit_statistics()
        parts = [f"{name} = {s[key]:.4f}" for key, name in (("R2", "R²"), ("adj_R2", "adj. R²"), ("pred_R2", "pred. R²"))
                 if key in s and s[key] is not None and np.isfinite(s[key])]
        text = "\n".join(parts)
    if text:
        ax.text(0.04, 0.96, text, transform=ax.transAxes, va="top", fontsize=9,
                bbox={"facecolor": "white", "alpha": 0.8, "edgecolor": "0.7"})
    ax.set_xlabel(f"actual {rlab}")
    ax.set_ylabel(f"predicted {rlab}")
    ax.set_title("Predicted vs actual")
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    return save_figure(fig, stem)


def residual_diagnostics(model, stem="residuals", response_label: str | None = None) -> tuple[Path, Path]:
    """2 x 2 panel: normal probability plot of studentized residuals, studentized residuals vs
    predicted, vs run order, and Cook's distance vs run (marker size from leverage)."""
    from scipy import stats  # here, not at module import: the DEM summary figures need no scipy.stats

    d = _diagnostics(model)
    n = len(d)
    if n < 3:
        raise InputError(None, "model", "at least 3 runs for residual diagnostics", n)
    r = d["studentized"].to_numpy(float)
    run = d["run"].to_numpy()
    rlab = response_label or getattr(model, "response", "response")
    fig = _figure(11, 8.5)
    axs = fig.subplots(2, 2)

    ax = axs[0, 0]
    (osm, osr), (slope, intercept, _) = stats.probplot(r, dist="norm")
    ax.plot(osr, osm, "o", color="C0", mec="k")
    zz = np.array([osm.min(), osm.max()])
    if slope != 0:
        ax.plot(slope * zz + intercept, zz, "r-", lw=1)
    probs = np.array([1, 5, 10, 20, 30, 50, 70, 80, 90, 95, 99])
    zt = stats.norm.ppf(probs / 100)
    keep = (zt >= osm.min() - 0.5) & (zt <= osm.max() + 0.5)
    ax.set_yticks(zt[keep])
    ax.set_yticklabels([f"{p:g}" for p in probs[keep]])
    ax.set_xlabel("studentized residual")
    ax.set_ylabel("normal % probability")
    ax.set_title("Normal plot of residuals")

    ax = axs[0, 1]
    ax.scatter(d["fitted_scale"], r, c="C0", edgecolors="k")
    for y0 in (-3, 3):
        ax.axhline(y0, color="r", lw=1)
    ax.axhline(0, color="k", lw=0.8, ls=":")
    ax.set_xlabel(f"predicted {rlab}")
    ax.set_ylabel("studentized residual")
    ax.set_title("Residuals vs predicted")

    ax = axs[1, 0]
    ax.plot(run, r, "o-", color="C0", mec="k")
    for y0 in (-3, 3):
        ax.axhline(y0, color="r", lw=1)
    ax.axhline(0, color="k", lw=0.8, ls=":")
    ax.set_xlabel("run number")
    ax.set_ylabel("studentized residual")
    ax.set_title("Residuals vs run")

    ax = axs[1, 1]
    cd = d["cooks_distance"].to_numpy(float)
    lev = d["leverage"].to_numpy(float)
    ax.vlines(run, 0, cd, color="0.5")
    ax.scatter(run, cd, s=12 + 80 * lev, c="C0", edgecolors="k", zorder=3, label="size ~ leverage")
    ax.axhline(4.0 / n, color="r", ls="--", lw=1, label=f"4/n = {4.0 / n:.3f}")
    ax.set_xlabel("run number")
    ax.set_ylabel("Cook's distance")
    ax.set_title("Cook's distance")
    ax.legend(fontsize=8, loc="upper right")

    fig.suptitle(f"Diagnostics: {rlab}")
    fig.tight_layout()
    return save_figure(fig, stem)


# --------------------------------------------------------------------------- convergence


def _history(h) -> tuple[np.ndarray, int | None]:
    if hasattr(h, "history"):
        return np.asarray(h.history, float), getattr(h, "converged_at", None)
    if isinstance(h, Mapping) and "history" in h:
        return np.asarray(h["history"], float), h.get("converged_at")
    return np.asarray(h, float), None


def convergence(
    history,
    stem="convergence",
    ylabel: str = "global best objective",
    title: str = "PSO convergence",
    log: bool | None = None,
) -> tuple[Path, Path]:
    """Global best against iteration (iteration 0 = initial swarm).

    history: an array, a :class:`soilcal.optimise.PSOResult` (its convergence iteration is
    marked), or a mapping label -> either (several cases on one plot).
    """
    series: dict[str, Any]
    if isinstance(history, Mapping) and "history" not in history:
        series = dict(history)
    else:
        series = {"": history}
    if not series:
        raise InputError(None, "history", "at least one convergence history", 0)
    fig = _figure(7, 4.5)
    ax = fig.add_subplot(1, 1, 1)
    allpos = True
    for n, (name, h) in enumerate(series.items()):
        y, conv = _history(h)
        if y.ndim != 1 or y.size < 1 or not np.all(np.isfinite(y)):
            raise InputError(None, f"history{('.' + str(name)) if name else ''}", "a 1-D finite sequence", y.shape)
        allpos &= bool(np.all(y > 0))
        ax.plot(np.arange(y.size), y, "-", color=f"C{n}", lw=1.5, label=name or None)
        if conv is not None and 0 <= conv < y.size:
            ax.plot([conv], [y[conv]], "o", color=f"C{n}", mec="k")
            ax.annotate(f"converged at {conv}", (conv, y[conv]), xytext=(8, 8), textcoords="offset points", fontsize=8)
    if log is None:
        ys = np.concatenate([_history(h)[0] for h in series.values()])
        log = allpos and ys.max() / ys.min() > 100
    if log:
        ax.set_yscale("log")
    ax.set_xlabel("iteration")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    if any(series):
        ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return save_figure(fig, stem)


__all__ = [
    "convergence",
    "factor_label",
    "pareto_effects",
    "predicted_vs_actual",
    "residual_diagnostics",
    "response_surface",
    "save_figure",
    "standardized_effects",
    "steepest_ascent",
]
