"""The loop's diagnosis of a two-measure DEM campaign, measure by measure: the residual table a
``benchmarks/loop.py --responses horizontal_force_N,vertical_force_N`` run wrote (its
``loop_dem/<case>[_campaign<seed>]_horizontal_vertical_residuals.csv``) diagnosed as the loop
did (both measures, one inverse-variance mean relative residual per test), and on each measure's rows alone
(``soilcal.loop.diagnose.diagnose``, no new DEM run).  Per table: the speed trend's and
curvature's raw and Holm p, the smallest Holm p of any test, and the RMS relative residual of
the rows; per measure, the mean relative residual of the conditions below 0.25 m/s and above.

    python benchmarks/loop_rate/per_measure.py RESIDUALS.csv...
"""
import sys

import numpy as np
import pandas as pd

from soilcal.loop import diagnose as dg

QUANTITY_OF = {"directrix": "tool", "speed_m_s": "tool_speed", "depth_mm": "working_depth",
               "position_m": "position", "day": "day", "moisture_pct": "moisture_content"}

for path in sys.argv[1:]:
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
