"""Summary of ``sensitivity.py``'s runs: per plate measure, the mean and seed SD at each friction
factor f, the pooled seed SD (within f), and the least-squares slope of the value on ln f (over
the factors 0.7-1.3 the brief of the measurement names, over 0.5-1.0 and 1.0-1.3 apart, and over
all) with its standard error, the slope in units of the pooled seed SD of one run, and the
slope over the campaign's span of ln f (0.45-1.37 at beta 0.4: 1.12) against the standard error
of one residual of the loop (three seeds a side: SD sqrt(2/3)).  Relative values are over the
mean at f = 1.

Then what a second measure adds beside the horizontal force.  The loop's diagnosis takes one
value per measured test, the inverse-variance mean of the relative residuals of the measures
the test records (``soilcal.loop.diagnose.per_test``), so a test of the horizontal force and a
second measure carries (r_h / v_h + r_2 / v_2) / (1 / v_h + 1 / v_2), v the relative variances
(before, the equal-weight mean (r_h + r_2) / 2).  From the runs over all f: each measure's
relative slope per unit ln f (the slope over the mean at f = 1) and relative seed SD (the
pooled SD over the same mean), the within-f correlation of the two measures' seed deviations,
and the ratio of slope to seed SD of the horizontal force alone, of the equal-weight mean, of
the inverse-variance mean the diagnosis takes (weights 1 / SD^2, the correlation counted in
its SD: sqrt(w' C w)), and of the best linear combination (sqrt(s' C^-1 s), s the relative
slopes, C their seed covariance).

    python benchmarks/loop_rate/sensitivity_summary.py benchmarks/results/loop_rate/sensitivity.jsonl
"""
import json
import math
import sys

import numpy as np
from scipy import stats

MEASURES = ("horizontal_force_N", "vertical_force_N", "resultant_angle_deg")
SPAN = math.log(1 + 0.4 * math.log(1.0 / 0.4)) - math.log(1 + 0.4 * math.log(0.1 / 0.4))  # ln f over 0.1-1.0 m/s

rows = [json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")]
fs = sorted({r["f"] for r in rows})
seeds = sorted({r["seed"] for r in rows})
print(f"{len(rows)} runs; f {fs}; seeds {seeds[0]}-{seeds[-1]}; campaign span of ln f {SPAN:.3f}\n")
print("| measure | f | n | mean | seed SD |")
print("|---|---|---|---|---|")
for m in MEASURES:
    for f in fs:
        v = np.array([r[m] for r in rows if r["f"] == f])
        print(f"| {m} | {f} | {len(v)} | {v.mean():.2f} | {v.std(ddof=1):.2f} |")
print()
print("| measure | f range | slope per unit ln f (SE) | relative to the mean at f=1 | pooled seed SD (df) | "
      "slope / SD | campaign span x slope / SE of a residual |")
print("|---|---|---|---|---|---|---|")
def _fit(m, sel):
    """Over the runs ``sel``: the least-squares slope of measure ``m`` on ln f with its standard
    error (scipy's linregress), each run's deviation from its f's mean, and the pooled seed SD
    (those deviations over the runs less the number of f levels) with its degrees of freedom."""
    line = stats.linregress(np.log([r["f"] for r in sel]), [r[m] for r in sel])
    levels = {r["f"] for r in sel}
    dev = np.array([r[m] - np.mean([q[m] for q in sel if q["f"] == r["f"]]) for r in sel])
    dof = len(sel) - len(levels)
    return line.slope, line.stderr, dev, math.sqrt(float(dev @ dev) / dof), dof


for m in MEASURES:
    m1 = np.mean([r[m] for r in rows if r["f"] == 1.0])
    for lo, hi in ((0.7, 1.3), (0.5, 1.0), (1.0, 1.3), (min(fs), max(fs))):
        slope, se, _, sd, dof = _fit(m, [r for r in rows if lo <= r["f"] <= hi])
        se_res = sd * math.sqrt(2 / 3)
        print(f"| {m} | {lo}-{hi} | {slope:.2f} ({se:.2f}) | {slope / m1:+.2f} | {sd:.2f} ({dof}) | {slope / sd:.2f} | "
              f"{SPAN * slope / se_res:.2f} |")


def _rel(m):
    """(relative slope per unit ln f over all f, relative pooled seed SD, within-f deviations)."""
    m1 = np.mean([r[m] for r in rows if r["f"] == 1.0])
    slope, _, dev, sd, _ = _fit(m, rows)
    return slope / m1, sd / m1, dev / m1


print()
print("| second measure | relative slope h, 2 | relative seed SD h, 2 | correlation | slope / SD: horizontal alone | "
      "equal-weight mean | inverse-variance mean (the diagnosis) | best combination |")
print("|---|---|---|---|---|---|---|---|")
sh, dh, eh = _rel("horizontal_force_N")
for m in MEASURES[1:]:
    s2, d2, e2 = _rel(m)
    rho = float(np.corrcoef(eh, e2)[0, 1])
    C = np.array([[dh * dh, rho * dh * d2], [rho * dh * d2, d2 * d2]])
    s = np.array([sh, s2])
    mean_snr = (sh + s2) / 2 / math.sqrt((dh * dh + d2 * d2 + 2 * rho * dh * d2) / 4)
    w = np.array([1 / (dh * dh), 1 / (d2 * d2)])
    w /= w.sum()
    inv_snr = float(w @ s) / math.sqrt(float(w @ C @ w))
    best = math.sqrt(float(s @ np.linalg.solve(C, s)))
    print(f"| {m} | {sh:+.2f}, {s2:+.2f} | {dh:.2f}, {d2:.2f} | {rho:+.2f} | {sh / dh:.2f} | {mean_snr:.2f} | "
          f"{inv_snr:.2f} | {best:.2f} |")
