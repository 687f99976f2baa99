"""Residual figures of the measured-data loop: relative residual (%) against every covariate,
the calibrated model and, where the loop chose effects, the model with them (held out)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd

from soilcal.loop.residuals import scale_of
from soilcal.plots.figures import _figure, save_figure


def _slug(s) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", str(s)).strip("_") or "x"


def residual_figures(res: pd.DataFrame, pred: pd.DataFrame | None, outdir, title: str = "") -> list[Path]:
    """One figure per covariate column (``cov:<name>``) of the usable rows of a residual
    table; ``pred`` (measurement, row, measure, heldout_prediction) adds the residual of the
    model with the chosen effects, each row predicted with the parameters fitted without its
    group.  Returns the PNG paths."""
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    u = res[np.isfinite(res["relative_residual"].astype(float))].reset_index(drop=True)
    after = None
    if pred is not None and "heldout_prediction" in pred.columns and len(u):
        m = u.merge(pred[["measurement", "row", "measure", "heldout_prediction"]],
                    on=["measurement", "row", "measure"], how="left")
        meas = m["measured"].astype(float)
        after = ((meas - m["heldout_prediction"].astype(float)) / scale_of(m) * 100).to_numpy()
    out = []
    cols = [c for c in u.columns if c.startswith("cov:")] + (["measure"] if u["measure"].nunique() > 1 else [])
    for col in cols:
        name = col[4:] if col.startswith("cov:") else col
        x = u[col]
        numeric = pd.to_numeric(x, errors="coerce").notna().all() and col != "measure"
        if numeric:
            xv = pd.to_numeric(x).to_numpy(float)
            ticks = None
        else:
            levels = list(dict.fromkeys(x.astype(str)))
            xv = np.array([levels.index(v) for v in x.astype(str)], float)
            ticks = levels
        fig = _figure(5.0, 3.4)
        ax = fig.add_subplot(111)
        ax.axhline(0, color="0.6", lw=0.8)
        shift = 0.08 if ticks is not None and after is not None else 0.0
        rel = u["relative_residual"].astype(float).to_numpy() * 100
        for k, measure in enumerate(dict.fromkeys(u["measure"])):  # one marker per measured quantity
            sel = (u["measure"] == measure).to_numpy()
            mk = "osD^v"[k % 5]
            ax.plot(xv[sel] - shift, rel[sel], mk, color="C3", ms=5, label=f"{measure}: calibrated model")
            if after is not None:
                ax.plot(xv[sel] + shift, after[sel], mk, color="C0", ms=5, mfc="none",
                        label=f"{measure}: with the chosen effects (held out)")
        if ticks is not None:
            ax.set_xticks(range(len(ticks)))
            ax.set_xticklabels(ticks, rotation=30 if len(ticks) > 4 else 0, fontsize=8)
        ax.set_xlabel(name)
        by_rms = not np.allclose(scale_of(u), u["measured"].abs().to_numpy(float))  # a quantity near zero
        ax.set_ylabel("(measured - simulated) / scale, %" if by_rms else "(measured - simulated) / |measured|, %")
        if title:
            ax.set_title(title, fontsize=9)
        ax.legend(fontsize=7, frameon=True, framealpha=0.8, loc="best")
        fig.tight_layout()
        png, _ = save_figure(fig, outdir / _slug(name))
        out.append(png)
    return out
