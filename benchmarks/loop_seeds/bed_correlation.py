"""How much of a soil-bin run's seed scatter its settled bed carries: the cinnamon soil's quick
line plate (the loop benchmark's DEM campaign plate) at three conditions, each run on the same
seeds, so that the runs of one seed share its settled bin (cached by seed, as every condition's
runs did before each measured condition got seeds of its own,
:func:`soilcal.config.measurements.condition_seed`).  Writes per seed the three horizontal
forces, then each condition's mean and relative SD and the correlations of the logarithms
between the conditions (with their 95 % Fisher intervals) to
``benchmarks/results/loop_seeds/bed_correlation.{csv,md}``.

    python benchmarks/loop_seeds/bed_correlation.py [SEEDS]     # default 30 seeds, seeds 0..SEEDS-1
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from _report import run_header, write_rows_page  # noqa: E402

OUT = HERE.parent / "results" / "loop_seeds"
#: (speed m/s, depth m) of the three conditions
CONDITIONS = ((0.2, 0.025), (0.8, 0.035), (0.4, 0.030))


def main(argv=None) -> None:
    from soilcal.dem.scenarios import bulldozing as B
    from soilcal.dem.scenarios.base import DemParams

    args = sys.argv[1:] if argv is None else argv
    n = int(args[0]) if args else 30
    params = DemParams.from_mapping({}, "bed_correlation")
    rows = []
    t0 = time.perf_counter()
    for seed in range(n):
        for speed, depth in CONDITIONS:
            r = B.run(dict(B._setup("line"), speed=speed, depth=depth), params, "quick", seed)
            rows.append({"seed": seed, "speed_m_s": speed, "depth_m": depth,
                         "horizontal_force_N": r.responses["horizontal_force_N"],
                         "bin_from_cache": bool(r.responses["bin_from_cache"])})
        print(seed, [round(x["horizontal_force_N"], 1) for x in rows[-3:]], flush=True)
    wall = time.perf_counter() - t0
    df = pd.DataFrame(rows)
    OUT.mkdir(parents=True, exist_ok=True)
    df.to_csv(OUT / "bed_correlation.csv", index=False)
    wide = np.log(df.pivot(index="seed", columns=["speed_m_s", "depth_m"], values="horizontal_force_N")
                  [list(CONDITIONS)].to_numpy(float))
    corr = np.corrcoef(wide.T)
    lines = ["# Seed scatter a soil-bin run shares with the other runs of its seed", "",
             run_header("loop_seeds/bed_correlation.py", [n], f"{wall:.0f} s") + ".  The cinnamon soil's quick "
             "line plate, calibrated parameters of the soil file, seeds 0..{0}: each seed's settled bin is shared by "
             "the three conditions (its cache key holds the seed, not the tool's speed or depth).".format(n - 1), "",
             "| condition | mean horizontal force, N | relative SD per run |", "|---|---:|---:|"]
    for j, (v, d) in enumerate(CONDITIONS):
        f = np.exp(wide[:, j])
        lines.append(f"| {v} m/s, {1000 * d:g} mm | {f.mean():.1f} | {f.std(ddof=1) / f.mean():.3f} |")
    lines += ["", "| pair | correlation of log force | 95 % interval (Fisher) |", "|---|---:|---|"]
    for a in range(len(CONDITIONS)):
        for b in range(a + 1, len(CONDITIONS)):
            r = corr[a, b]
            z, se = math.atanh(r), 1.0 / math.sqrt(n - 3)
            lines.append(f"| {CONDITIONS[a][0]} m/s {1000 * CONDITIONS[a][1]:g} mm - {CONDITIONS[b][0]} m/s "
                         f"{1000 * CONDITIONS[b][1]:g} mm | {r:.3f} | {math.tanh(z - 1.96 * se):.2f} to "
                         f"{math.tanh(z + 1.96 * se):.2f} |")
    write_rows_page(OUT / "bed_correlation.md", lines, "bed_correlation.csv")


if __name__ == "__main__":
    main()
