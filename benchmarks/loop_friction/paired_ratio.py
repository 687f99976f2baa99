"""Paired change of the plate force against the calibrated friction (same seeds, same beds:
the variants of friction_split.py run with 'cal'): mean of log(F_variant / F_cal) over the
seeds, its standard error and a t-interval, as a percentage change of the geometric mean.  The
reference is the file's first variant with both factors 1 (its bed as written in the line);
the seeds are paired by position.

    python benchmarks/loop_friction/paired_ratio.py benchmarks/results/loop_friction/split_v1_paired.jsonl
"""
import json
import math
import sys
import numpy as np
from scipy import stats
rows = [json.loads(l) for l in open(sys.argv[1]) if l.startswith("{")]
seen, uniq = set(), []
for r in rows:
    k = (r["speed"], r["fss"], r["fst"], r["bed"], r.get("fr", 1.0))
    if k not in seen:
        seen.add(k); uniq.append(r)
base = next(r for r in uniq if r["fss"] == 1.0 and r["fst"] == 1.0)
for r in uniq:
    if r is base:
        continue
    d = np.log(np.array(r["F"])) - np.log(np.array(base["F"]))
    n = len(d); m = d.mean(); se = d.std(ddof=1) / math.sqrt(n); t = stats.t.ppf(0.975, n - 1)
    print(f"v {r['speed']} x{r['fss']}/{r['fst']} (mu_ss {r['mu_ss']}, mu_st {r['mu_st']}), {n} seeds: "
          f"{100 * math.expm1(m):+.1f} % (95 % CI {100 * math.expm1(m - t * se):+.1f} to {100 * math.expm1(m + t * se):+.1f}); "
          f"SD of the paired log change {d.std(ddof=1):.3f}")
