"""The loop's diagnosis of a two-measure DEM campaign, measure by measure: the residual table a
``benchmarks/loop.py --responses horizontal_force_N,vertical_force_N`` run wrote (its
``loop_dem/<stem>_residuals.csv``, the stem by ``loop.detail_stem``:
``<case>[_campaign<seed>][_uniform]_horizontal_vertical``) diagnosed as the loop did (both
measures, one inverse-variance mean relative residual per test), and on each measure's rows alone
(``soilcal.loop.diagnose.diagnose``, no new DEM run).  Per table: the speed trend's and
curvature's raw and Holm p, the smallest Holm p of any test, and the RMS relative residual of
the rows; per measure, the mean relative residual of the conditions below 0.25 m/s and above.
Then the weights the effect selection gives each measure's rows (``soilcal.loop.select.row_weights``:
the inverse of the relative residual's variance, mean 1) and, where the campaign's saved
predictions (``<stem>_predictions.csv``) are beside the table, the RMS relative error before and
held out after, plain (``loop_summary.csv``'s) and weighted by those weights: the run's own
held-out predictions, from the fit of the code that ran the campaign (the effects' design runs
are not saved, so no fit is repeated here).

A campaign is given as CASE:CAMPAIGN[:SPACING] (spacing ``log``, the default, or ``uniform``),
its table looked up in ``benchmarks/results/loop_dem/`` (``--detail DIR``) under the measures of
``--responses`` (default the two forces), or as the path of a residual table (``*.csv``).

    python benchmarks/loop_rate/per_measure.py rate_friction:0 rate_friction:1 rate_friction:2 none:0
    python benchmarks/loop_rate/per_measure.py RESIDUALS.csv...
"""
import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

if str(Path(__file__).resolve().parents[1]) not in sys.path:
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # benchmarks/loop.py
import loop as B
from soilcal.loop import diagnose as dg
from soilcal.loop import residuals as rs
from soilcal.loop import select as sl

QUANTITY_OF = {"directrix": "tool", "speed_m_s": "tool_speed", "depth_mm": "working_depth",
               "position_m": "position", "day": "day", "moisture_pct": "moisture_content"}

TWO_FORCES = ("horizontal_force_N", "vertical_force_N")


def residual_table(spec, detail=B.HERE / "results" / "loop_dem", responses=TWO_FORCES) -> Path:
    """The residual table of a campaign ``spec``: a path ending in ``.csv`` as given, else
    ``CASE:CAMPAIGN[:SPACING]`` named as ``benchmarks/loop.py`` names it (``loop.detail_stem``)
    in ``detail``; a spec that names no table is refused, with the file looked for."""
    if spec.endswith(".csv"):
        path = Path(spec)
    else:
        parts = spec.split(":")
        if len(parts) not in (2, 3) or not parts[1].isdigit():
            raise ValueError(f"campaign {spec!r}: expected CASE:CAMPAIGN[:SPACING] (rate_friction:1:uniform) "
                             "or the path of a residual table (*.csv)")
        case, seed, speeds = parts[0], int(parts[1]), (parts[2] if len(parts) == 3 else "log")
        try:
            stem = B.detail_stem(case, seed, speeds, tuple(responses))
        except ValueError as e:  # an unknown spacing
            raise ValueError(f"campaign {spec!r}: {e}") from None
        path = Path(detail) / f"{stem}_residuals.csv"
    if not path.is_file():
        raise ValueError(f"campaign {spec!r}: no residual table {path}")
    return path


def report(path):
    """Print the diagnosis of the residual table at ``path``, both measures and each alone."""
    res = pd.read_csv(path)
    print(path)
    for label, sel in (("both measures (the loop)", res),
                       *((m, res[res["measure"] == m]) for m in sorted(res["measure"].unique()))):
        d = dg.diagnose(sel.reset_index(drop=True), QUANTITY_OF)
        sp = d[d["covariate"] == "speed_m_s"].set_index("test")
        r = sel["relative_residual"].astype(float)
        print(f"  {label}: speed trend p {sp.loc['trend', 'p']:.3f} (Holm {sp.loc['trend', 'p_adjusted']:.3f}), "
              f"curvature p {sp.loc['curvature', 'p']:.3f} (Holm {sp.loc['curvature', 'p_adjusted']:.3f}); "
              f"smallest Holm p {d['p_adjusted'].min():.3f} ({d.loc[d['p_adjusted'].idxmin(), 'test']} "
              f"{d.loc[d['p_adjusted'].idxmin(), 'covariate']}); RMS relative residual {100 * np.sqrt(np.mean(r ** 2)):.1f} %")
    for m in sorted(res["measure"].unique()):
        g = res[res["measure"] == m]
        slow = g["cov:speed_m_s"] < 0.25
        print(f"  {m}: mean relative residual below 0.25 m/s {g.loc[slow, 'relative_residual'].mean():+.3f} "
              f"({int(slow.sum())} conditions), above {g.loc[~slow, 'relative_residual'].mean():+.3f}")
    weights(path, res)


def weights(path, res):
    """Print the selection's weight of each measure's rows and the RMS relative error before and
    held out after, plain and weighted, from the campaign's saved predictions beside ``path``."""
    u = rs.usable(res)
    w = sl.row_weights(u)
    measures = sorted(u["measure"].unique())
    if w is None:
        print("  selection weights: every row alike (a variance unknown, of different parts, or all equal)")
        w = np.ones(len(u))
    else:
        print("  selection weights (mean 1): " + ", ".join(
            f"{m} {w[(u['measure'] == m).to_numpy()].mean():.4g}" for m in measures))
    preds = path.with_name(path.name.replace("_residuals.csv", "_predictions.csv"))
    if not preds.is_file():
        return
    keys = ["measurement", "row", "measure"]
    p = u[keys].merge(pd.read_csv(preds), on=keys, how="left", validate="one_to_one")
    before = u["relative_residual"].to_numpy(float)
    after = ((p["measured"] - p["heldout_prediction"]).to_numpy(float) / rs.scale_of(u)
             if "heldout_prediction" in p else before)  # nothing chosen: the model as calibrated
    ok = np.isfinite(before) & np.isfinite(after)

    def rms(x, wt):
        return 100 * np.sqrt(np.sum(wt[ok] * x[ok] ** 2) / np.sum(wt[ok]))

    print(f"  held-out RMS relative error, before -> after ({preds.name}): plain {rms(before, np.ones(len(u))):.2f} "
          f"-> {rms(after, np.ones(len(u))):.2f} %, weighted {rms(before, w):.2f} -> {rms(after, w):.2f} %")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("campaigns", nargs="+", metavar="CASE:CAMPAIGN[:SPACING] or RESIDUALS.csv")
    ap.add_argument("--responses", default=",".join(TWO_FORCES),
                    help="the campaigns' measures, comma-separated (default: the two forces)")
    ap.add_argument("--detail", default=str(B.HERE / "results" / "loop_dem"), help="the detail tables' directory")
    args = ap.parse_args(argv)
    try:
        paths = [residual_table(c, args.detail, args.responses.split(",")) for c in args.campaigns]
    except ValueError as e:
        ap.error(str(e))
    for path in paths:
        report(path)


if __name__ == "__main__":
    main()
