"""Figures of the DEM verification: soilcal's own engine at the calibrated optimum against the
targets, the tool measurements and the papers' printed simulations.

Input frames are the tables the calibration writes (extra columns are ignored):

- ``verification.csv`` (one row per case and response): :func:`verification_bars`;
- ``tool_verification.csv`` (one row per measured condition and quantity): :func:`tool_curves`
  for the (measurement, measure) groups whose covariate is numeric (e.g. rotor speed),
  :func:`tool_bars` for the others (e.g. the bulldozing plates arc / parabola / bionic / line);
- ``summary.csv`` (one row per soil, case and response): :func:`summary_figure`.

Paper columns (``paper_simulated``, ``paper_relative_error_percent``) and ``measured_sd`` /
``unit`` are optional: absent or empty cells draw nothing. Relative errors are drawn as the
tables give them (``relative_error_percent``); the summary's error bars are the SD of the
relative error, 100 * simulated_sd / |target|.

Every function draws on :class:`matplotlib.figure.Figure` objects with the Agg canvas (no
pyplot), writes ``<stem>.png`` (150 dpi) and ``<stem>.pdf`` through
:func:`soilcal.plots.figures.save_figure` and returns the list of every file written.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Sequence

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from soilcal.errors import InputError
from soilcal.plots.figures import _figure, save_figure

C_TARGET = "0.65"  # target / measured bars
C_SIM = "C0"  # soilcal's DEM
C_PAPER = "C1"  # the paper's printed simulation

VERIFICATION_COLUMNS = ["case", "response", "target", "simulated_mean", "simulated_sd", "relative_error_percent"]
TOOL_COLUMNS = ["measurement", "covariate", "covariate_value", "measure", "measured", "simulated_mean", "simulated_sd"]
TOOL_BAR_COLUMNS = [*TOOL_COLUMNS, "relative_error_percent"]
SUMMARY_COLUMNS = ["soil", "case", "response", "target", "simulated_sd", "relative_error_percent"]


# --------------------------------------------------------------------------- helpers


def _require(df, columns: Sequence[str], field: str = "df") -> None:
    if not isinstance(df, pd.DataFrame):
        raise InputError(None, field, f"a DataFrame with columns {list(columns)}", type(df).__name__)
    missing = [c for c in columns if c not in df.columns]
    if missing:
        raise InputError(None, field, f"columns {list(columns)}", f"missing {missing}")
    if df.empty:
        raise InputError(None, field, "at least one row", 0)


def _num(df: pd.DataFrame, column: str) -> np.ndarray:
    """A column as floats (empty cells and text -> NaN); all NaN when the column is absent."""
    if column not in df.columns:
        return np.full(len(df), np.nan)
    return pd.to_numeric(df[column], errors="coerce").to_numpy(float)


def _text(v) -> str:
    return "" if v is None or (isinstance(v, float) and np.isnan(v)) else str(v)


def _first(df: pd.DataFrame, column: str) -> str:
    """First non-empty text of a column ('' when absent or empty)."""
    if column not in df.columns:
        return ""
    vals = [_text(v).strip() for v in df[column]]
    return next((v for v in vals if v and v.lower() != "nan"), "")


def _slug(s) -> str:
    return re.sub(r"[^A-Za-z0-9_-]+", "_", _text(s)).strip("_") or "na"


def _numeric_covariate(values: pd.Series) -> bool:
    """True when every covariate value of a group reads as a finite number."""
    x = pd.to_numeric(values.astype(str).str.strip(), errors="coerce").to_numpy(float)
    return bool(x.size) and bool(np.all(np.isfinite(x)))


def _tool_groups(df: pd.DataFrame):
    """(measurement, measure, rows) in first-appearance order."""
    for (measurement, measure), g in df.groupby(["measurement", "measure"], sort=False, dropna=False):
        yield _text(measurement), _text(measure), g


def _ylabel(measure: str, unit: str) -> str:
    return f"{measure} ({unit})" if unit else measure


def _fmt_err(v: float) -> str:
    return f"{v:.2f} %"


def _bar_label(ax, x: float, top: float, text: str, colour="k", size: float = 7) -> None:
    """A label standing upright over its bar: written level, a label is wider than a bar and
    runs into its neighbour's when the two bars are of about the same height."""
    ax.annotate(text, (x, top), xytext=(0, 3), textcoords="offset points", ha="center", va="bottom",
                fontsize=size, color=colour, rotation=90)


def _three_bars(ax, first, first_sd, first_label, sim, sd, err, paper, paper_err, status) -> set:
    """Per row i: the measured/target bar, soilcal's mean +- SD with its relative error above
    (or the row's status where nothing was simulated), the paper's simulated bar (with its
    relative error when given).  Returns the legend labels used."""
    n = len(sim)
    w = 0.26
    xs = np.arange(n, dtype=float)
    seen: set[str] = set()

    def lab(name: str) -> str | None:
        if name in seen:
            return None
        seen.add(name)
        return name

    for i in range(n):
        if np.isfinite(first[i]):
            e = first_sd[i] if first_sd is not None and np.isfinite(first_sd[i]) else None
            ax.bar(xs[i] - w, first[i], w, color=C_TARGET, edgecolor="k", yerr=e, capsize=3 if e else 0,
                   label=lab(first_label))
        if np.isfinite(sim[i]):
            e = sd[i] if np.isfinite(sd[i]) else None
            ax.bar(xs[i], sim[i], w, color=C_SIM, edgecolor="k", yerr=e, capsize=3,
                   error_kw={"elinewidth": 1}, label=lab("soilcal DEM (mean ± SD)"))
            if np.isfinite(err[i]):
                _bar_label(ax, xs[i], sim[i] + (e or 0.0), _fmt_err(err[i]), C_SIM)
        else:
            why = status[i] if status[i] and status[i] != "ok" else "not simulated"
            ax.annotate(why[:40], (xs[i], 0), xytext=(0, 3), textcoords="offset points", ha="center",
                        va="bottom", fontsize=7, rotation=90, color="C3")
        if np.isfinite(paper[i]):
            ax.bar(xs[i] + w, paper[i], w, color=C_PAPER, edgecolor="k", hatch="//", label=lab("paper simulated"))
            if paper_err is not None and np.isfinite(paper_err[i]):
                _bar_label(ax, xs[i] + w, paper[i], _fmt_err(paper_err[i]), C_PAPER)
    ax.set_xticks(xs)
    ax.set_xlim(-0.6, n - 0.4)
    ax.margins(y=0.25)
    return seen


def _legend_above(ax, title: str) -> None:
    """The bars' legend in one row between the title and the axes, where no bar label can be
    under it (``loc='best'`` places it on the labels, which it does not see)."""
    ax.legend(loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=3, fontsize=8, frameon=False)
    ax.set_title(title, pad=22)


# --------------------------------------------------------------------------- verification


def _verification_figure(df: pd.DataFrame, title: str | None = None) -> Figure:
    _require(df, VERIFICATION_COLUMNS)
    target = _num(df, "target")
    sim, sd = _num(df, "simulated_mean"), _num(df, "simulated_sd")
    err = _num(df, "relative_error_percent")
    paper, paper_err = _num(df, "paper_simulated"), _num(df, "paper_relative_error_percent")
    status = [_text(v) for v in df["status"]] if "status" in df.columns else [""] * len(df)
    stages = [_text(v) for v in df["stage"]] if "stage" in df.columns else [""] * len(df)
    several_stages = len({s for s in stages if s}) > 1
    rounds = pd.to_numeric(df["round"], errors="coerce").fillna(1).astype(int).tolist() \
        if "round" in df.columns else [1] * len(df)
    presets = [_text(v) for v in df["preset"]] if "preset" in df.columns else [""] * len(df)
    # the y axis names the responses' unit where they share one; otherwise each label names its own
    units = [_text(v) for v in df["unit"]] if "unit" in df.columns else [""] * len(df)
    shared = units[0] if len(set(units)) == 1 else None
    labels = [(f"{st}:\n" if several_stages and st else "") + f"{_text(c)}\n{_text(r)}"
              + (f" ({u})" if shared is None and u else "")
              + (f"\nround {k}" if k > 1 else "") + (f"\n{p} preset" if p == "paper" else "")
              for st, c, r, u, k, p in zip(stages, df["case"], df["response"], units, rounds, presets)]

    n = len(df)
    # a group as wide as its longest label line (about 0.075 in per character at 8 pt)
    widest = max((len(line) for lab in labels for line in lab.split("\n")), default=0)
    fig = _figure(max(6.5, max(1.25, 0.075 * widest) * n + 2.0), 5.0)
    ax = fig.add_subplot(1, 1, 1)
    # the target's own scatter (a column older tables lack) as its error bar
    tsd = _num(df, "target_sd") if "target_sd" in df.columns else None
    seen = _three_bars(ax, target, tsd, "target (± its SD where known)" if tsd is not None
                       and np.isfinite(tsd).any() else "target", sim, sd, err, paper, paper_err, status)
    ax.set_xticklabels(labels, fontsize=8)
    ax.set_ylabel(_ylabel("response", shared or ""))
    ax.set_xlabel("case / response")
    if title is None:
        title = "Verification at the calibrated optimum"
        stage = {s for s in stages if s}
        if len(stage) == 1:
            title += f" ({stage.pop()})"
    if seen:
        _legend_above(ax, title)
    else:
        ax.set_title(title)
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    return fig


def verification_bars(df: pd.DataFrame, stem="verification", title: str | None = None) -> list[Path]:
    """Grouped bars per (case, response) row: target (with its own SD, ``target_sd``, as error
    bars where known), soilcal's simulated mean with SD error
    bars and its relative error (%) above, and the paper's simulated value where printed (with
    the paper's relative error when given). Rows without a target (a 'minimize' goal) show the
    simulated bars only; a row without a simulated mean shows its status text."""
    return list(save_figure(_verification_figure(df, title), stem))


# --------------------------------------------------------------------------- tools


def _tool_title(measurement: str, measure: str, g: pd.DataFrame) -> str:
    setup = _first(g, "setup") if "setup" in g.columns and g["setup"].nunique(dropna=True) == 1 else ""
    return f"{measurement}: {measure}" + (f" ({setup})" if setup else "")


def _tool_curve_figure(g: pd.DataFrame, measurement: str, measure: str) -> Figure:
    x = pd.to_numeric(g["covariate_value"].astype(str).str.strip(), errors="coerce").to_numpy(float)
    order = np.argsort(x, kind="stable")
    x = x[order]
    meas, meas_sd = _num(g, "measured")[order], _num(g, "measured_sd")[order]
    sim, sd = _num(g, "simulated_mean")[order], _num(g, "simulated_sd")[order]
    paper = _num(g, "paper_simulated")[order]

    fig = _figure(7.0, 4.8)
    ax = fig.add_subplot(1, 1, 1)
    ok = np.isfinite(meas)
    if ok.any():
        ax.plot(x[ok], meas[ok], "o", color="k", mfc="white", mew=1.5, ms=7, ls="none", zorder=4, label="measured")
        has = ok & np.isfinite(meas_sd)
        if has.any():
            ax.errorbar(x[has], meas[has], yerr=meas_sd[has], fmt="none", ecolor="k", capsize=3, zorder=4)
    ok = np.isfinite(sim)
    if ok.any():
        yerr = np.where(np.isfinite(sd[ok]), sd[ok], 0.0)
        ax.errorbar(x[ok], sim[ok], yerr=yerr, fmt="s-", color=C_SIM, mec="k", capsize=3,
                    label="soilcal DEM (mean ± SD)")
    ok = np.isfinite(paper)
    if ok.any():
        ax.plot(x[ok], paper[ok], "^--", color=C_PAPER, mec="k", label="paper simulated")
    ax.set_xlabel(_first(g, "covariate") or "covariate")
    ax.set_ylabel(_ylabel(measure, _first(g, "unit")))
    ax.set_title(_tool_title(measurement, measure, g))
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="best", fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def _tool_bar_figure(g: pd.DataFrame, measurement: str, measure: str) -> Figure:
    cats = [_text(v).strip() or "(none)" for v in g["covariate_value"]]
    meas, meas_sd = _num(g, "measured"), _num(g, "measured_sd")
    sim, sd = _num(g, "simulated_mean"), _num(g, "simulated_sd")
    paper, err = _num(g, "paper_simulated"), _num(g, "relative_error_percent")
    paper_err = _num(g, "paper_relative_error_percent") if "paper_relative_error_percent" in g.columns else None
    status = [_text(v) for v in g["status"]] if "status" in g.columns else [""] * len(g)

    n = len(g)
    fig = _figure(max(6.0, 1.2 * n + 2.0), 4.8)
    ax = fig.add_subplot(1, 1, 1)
    seen = _three_bars(ax, meas, meas_sd, "measured", sim, sd, err, paper, paper_err, status)
    ax.set_xticklabels(cats, fontsize=8)
    ax.set_xlabel(_first(g, "covariate") or "covariate")
    ax.set_ylabel(_ylabel(measure, _first(g, "unit")))
    if seen:
        _legend_above(ax, _tool_title(measurement, measure, g))
    else:
        ax.set_title(_tool_title(measurement, measure, g))
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    return fig


def _tool_stem(stem_prefix, measurement: str, measure: str) -> Path:
    p = Path(stem_prefix)
    return p.parent / f"{p.name}_{_slug(measurement)}_{_slug(measure)}"


def tool_curves(df: pd.DataFrame, stem_prefix="tool") -> list[Path]:
    """One figure ``<stem_prefix>_<measurement>_<measure>`` per (measurement, measure) group
    whose covariate values are all numeric: measured (open markers, measured_sd error bars where
    given), soilcal's simulated mean ± SD (line) and the paper's simulated (dashed) against the
    covariate. Groups with a categorical covariate are left to :func:`tool_bars`."""
    _require(df, TOOL_COLUMNS)
    out: list[Path] = []
    for measurement, measure, g in _tool_groups(df):
        if _numeric_covariate(g["covariate_value"]):
            fig = _tool_curve_figure(g, measurement, measure)
            out += save_figure(fig, _tool_stem(stem_prefix, measurement, measure))
    return out


def tool_bars(df: pd.DataFrame, stem_prefix="tool") -> list[Path]:
    """One figure ``<stem_prefix>_<measurement>_<measure>`` per (measurement, measure) group
    whose covariate values are not all numeric (e.g. plate shapes): grouped bars per covariate
    value of measured (± measured_sd), soilcal's simulated ± SD with its relative error above,
    and the paper's simulated where printed, with its relative error to the measured value above
    it where the table gives one (``paper_relative_error_percent``). Numeric groups are left to :func:`tool_curves`."""
    _require(df, TOOL_BAR_COLUMNS)
    out: list[Path] = []
    for measurement, measure, g in _tool_groups(df):
        if not _numeric_covariate(g["covariate_value"]):
            fig = _tool_bar_figure(g, measurement, measure)
            out += save_figure(fig, _tool_stem(stem_prefix, measurement, measure))
    return out


# --------------------------------------------------------------------------- summary


def _summary_figure(df: pd.DataFrame, title: str | None = None) -> Figure:
    _require(df, SUMMARY_COLUMNS)
    err = _num(df, "relative_error_percent")
    target, sd = _num(df, "target"), _num(df, "simulated_sd")
    with np.errstate(divide="ignore", invalid="ignore"):
        err_sd = 100.0 * sd / np.abs(target)
    err_sd = np.where(np.isfinite(err_sd), err_sd, 0.0)
    soils = [_text(v) for v in df["soil"]]
    labels = [f"{s}: {_text(c)} / {_text(r)}" for s, c, r in zip(soils, df["case"], df["response"])]
    palette = {s: f"C{k % 10}" for k, s in enumerate(dict.fromkeys(soils))}

    n = len(df)
    fig = _figure(8.0, 0.32 * n + 2.0)
    ax = fig.add_subplot(1, 1, 1)
    y = np.arange(n)[::-1].astype(float)  # first row on top
    ax.axvspan(-2, 2, color="0.5", alpha=0.18, lw=0, label="±2 % acceptance")
    ax.axvline(0, color="k", lw=0.8)
    seen: set[str] = set()
    for i in range(n):
        if np.isfinite(err[i]):
            lab = None if soils[i] in seen else soils[i]
            seen.add(soils[i])
            ax.barh(y[i], err[i], 0.7, color=palette[soils[i]], edgecolor="k", xerr=err_sd[i] or None,
                    capsize=2, error_kw={"elinewidth": 0.8}, label=lab)
        else:
            ax.annotate("no target", (0, y[i]), xytext=(4, 0), textcoords="offset points", va="center",
                        fontsize=7, color="0.4")
    ax.set_yticks(y)
    ax.set_yticklabels(labels, fontsize=8)
    ax.set_ylim(-0.7, n - 0.3)
    lim = np.nanmax(np.abs(np.concatenate([err + err_sd, err - err_sd, [2.5]])))
    ax.set_xlim(-1.1 * lim, 1.1 * lim)
    ax.set_xlabel("relative error at the calibrated optimum (%)")
    # over the figure, not the axes: long row labels leave the axes narrower than the title
    fig.suptitle(title or "Relative error of every target at the calibrated optimum")
    ax.legend(loc="best", fontsize=8)
    ax.grid(axis="x", alpha=0.3)
    fig.tight_layout()
    return fig


def summary_figure(df: pd.DataFrame, stem="summary") -> list[Path]:
    """Relative error (%) of every soil's targets at the calibrated optimum: one horizontal bar
    per (soil, case, response), coloured by soil, SD of the relative error
    (100 * simulated_sd / |target|) as error bars, the ±2 % band shaded and a line at 0."""
    return list(save_figure(_summary_figure(df), stem))


__all__ = ["summary_figure", "tool_bars", "tool_curves", "verification_bars"]
