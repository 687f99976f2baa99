"""Summarise depth_response.py's runs: per g and seed set, the geometric-mean horizontal force
at 20 and 40 mm and the log ratio F(40)/F(20); the correlation over seeds of a run's log force
deviation at one g with the same seed's at another (common random numbers: 1 when a seed's
packing sets the force at every g, 0 when each run is a new draw); the SD of log force per run.
    python benchmarks/loop_depth/depth_response_summary.py benchmarks/results/loop_depth/depth_response.jsonl
"""
import json, sys
import numpy as np
rows = [json.loads(l) for l in open(sys.argv[1])]
gs = sorted({r["g"] for r in rows}); seeds = sorted({r["seed"] for r in rows})
F = {(r["depth"], r["g"], r["seed"]): r["F"] for r in rows}
for sset, name in (((0, 1, 2), "seeds 0-2"), ((1000, 1001, 1002), "seeds 1000-1002"), (tuple(seeds), "all")):
    for g in gs:
        have = [s for s in sset if (0.02, g, s) in F and (0.04, g, s) in F]
        if not have:
            continue
        l20 = np.log([F[0.02, g, s] for s in have]); l40 = np.log([F[0.04, g, s] for s in have])
        print(f"{name:16s} g {g:4.2f} n {len(have)}: F20 {np.exp(l20.mean()):6.1f} F40 {np.exp(l40.mean()):6.1f} "
              f"ln(F40/F20) {np.mean(l40 - l20):.3f} +- {np.std(l40 - l20, ddof=1) / np.sqrt(len(have)) if len(have) > 1 else np.nan:.3f}")
# per depth: deviation of each run's log force from the mean over seeds at its g; correlation across g pairs
for d in (0.02, 0.04):
    full = [s for s in seeds if all((d, g, s) in F for g in gs)]
    M = np.log(np.array([[F[d, g, s] for s in full] for g in gs]))
    dev = M - M.mean(axis=1, keepdims=True)
    c = np.corrcoef(dev)
    off = c[np.triu_indices(len(gs), 1)]
    print(f"depth {d*1000:.0f} mm, {len(full)} seeds: SD of log force per run {np.sqrt(np.mean(dev.var(axis=1, ddof=1))):.3f}; "
          f"correlation of a seed's deviations between g values: mean {off.mean():+.2f} (pairs {np.round(off, 2).tolist()})")
