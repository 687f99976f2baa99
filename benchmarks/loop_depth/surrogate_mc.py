"""The effect parameter's estimate through the one-parameter surrogate: interpolated (monotone
cubic through the design's seed means, the loop's surrogate before) against the surrogate now
(per row, a least-squares quadratic where the row's own lack-of-fit test against its seed
scatter passes and the quadratic does not turn over inside the bounds where the row's means are
monotone: soilcal.loop.select.smooth_fits, Surrogate).  The linear stand-in of tests/loop/test_bootstrap.py:
18 conditions, y_i = 100 (1 + a_i beta), a_i evenly over [-1, 1], design beta in
{-0.3, -0.075, 0.15, 0.375, 0.6} (5 levels, 0 added), three seeds per point; per run scatter
SCATTER of which a share CRN is the seed's own (shared by every design point: common random
numbers), the rest independent; measured: three repeats with the same scatter, independent.
Prints bias, SD and RMS error of the fitted beta over CAMPAIGNS campaigns, and how often the
quadratic was taken (rows of all campaigns).
    python benchmarks/loop_depth/surrogate_mc.py [CAMPAIGNS] [TRUE] [SCATTER] [CRN] [LEVELS] [AMP]   (default 400 0.3 0.14 0.0 5 1.0;
    LEVELS: design levels of beta over its bounds, AMP: a_i evenly over [-AMP, AMP])
"""
import sys
import numpy as np
import pandas as pd
from soilcal.loop import select as sl
from soilcal.loop.effects import EFFECTS

C = int(sys.argv[1]) if len(sys.argv) > 1 else 400
TRUE = float(sys.argv[2]) if len(sys.argv) > 2 else 0.3
SC = float(sys.argv[3]) if len(sys.argv) > 3 else 0.14
CRN = float(sys.argv[4]) if len(sys.argv) > 4 else 0.0
EFF, BOUNDS = EFFECTS["rate_friction"], {"beta": (-0.3, 0.6)}
LEVELS = int(sys.argv[5]) if len(sys.argv) > 5 else 5
AMP = float(sys.argv[6]) if len(sys.argv) > 6 else 1.0
DESIGN = sl.theta_design(EFF, BOUNDS, LEVELS)
N, SEEDS = 18, 3
A = np.linspace(-AMP, AMP, N)
rng = np.random.default_rng(12345)
est = {"interpolated": [], "now": []}
smooth = 0
for c in range(C):
    shared = rng.standard_normal((N, SEEDS))
    rows = []
    for d in DESIGN:
        z = np.sqrt(CRN) * shared + np.sqrt(1 - CRN) * rng.standard_normal((N, SEEDS))
        v = 100.0 * (1 + A * d["beta"])[:, None] * (1 + SC * z)
        for i in range(N):
            for s in range(SEEDS):
                rows.append({"measurement": "m", "row": i + 1, "measure": "F_N", "seed": s, "value": v[i, s],
                             "status": "ok", "t:beta": d["beta"]})
    runs = pd.DataFrame(rows)
    reps = 100.0 * (1 + A * TRUE)[:, None] * (1 + SC * rng.standard_normal((N, SEEDS)))
    obs = pd.DataFrame({"measurement": "m", "row": np.arange(1, N + 1), "measure": "F_N", "measured": reps.mean(1)})
    ed = sl.build_effect_data(obs, runs, EFF, BOUNDS)
    smooth += int(ed.surrogate.quadratic.sum())
    interp = sl.EffectData(EFF, BOUNDS, sl.Surrogate(EFF, BOUNDS, ed.thetas(), ed.means), ed.design)
    y0 = ed.means[[d["beta"] for d in ed.design].index(0.0)]
    for key, e in (("interpolated", interp), ("now", ed)):
        est[key].append(float(sl.Model([e], y0, obs["measured"].to_numpy(float)).fit()[0][0]))
print(f"{C} campaigns, beta {TRUE}, scatter {SC}, CRN share {CRN}, {LEVELS} levels, a_i up to {AMP}: quadratic taken in {smooth} of {C * N} rows")
for k, v in est.items():
    v = np.array(v)
    print(f"  {k:12s} mean {v.mean():.4f} bias {v.mean() - TRUE:+.4f} SD {v.std(ddof=1):.4f} "
          f"RMS error {np.sqrt(np.mean((v - TRUE) ** 2)):.4f}  median |error| / beta {np.median(np.abs(v - TRUE)) / TRUE:.3f}")
