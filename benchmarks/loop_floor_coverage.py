"""Coverage of the noise floor's 95 % interval (``soilcal.loop.residuals.floor_interval``).

The floor sqrt(mean((sd_m^2 / n_m + sd_s^2 / n_s) / scale^2)) is computed from SDs that are
themselves estimates, so the loop's report gives its interval.  Here seeded residual tables of
one measured force, each row its own condition, draw every measured SD from n_m repeats and
every seed SD from n_s seeds about known true SDs (measured 2 % and 5 % of the value on
alternate rows, seed 4 %: each sample variance sigma^2 chi-square(n - 1) / (n - 1)); the true
floor is sqrt(mean((sigma_m^2 / n_m + sigma_s^2 / n_s) / value^2)), and the page counts the
tables whose interval covers it (binomial standard error about 0.5 % at 2000 tables).  No DEM
runs; about 30 CPU-seconds per configuration.

    python benchmarks/loop_floor_coverage.py [--tables 2000] [--seed 2026]

Writes ``benchmarks/results/loop_floor_coverage.csv`` and ``.md``.
"""

from __future__ import annotations

import argparse
import math
import platform
import time
from pathlib import Path

import numpy as np
import pandas as pd
from _report import commit, write_page, write_rows

from soilcal.loop import residuals as rs

HERE = Path(__file__).resolve().parent
FIELDS = ["rows", "repeats", "seeds", "tables", "covered", "coverage_percent", "below", "above", "cpu_s", "commit"]
#: (rows, measured repeats, seeds) per configuration
CONFIGS = [(6, 3, 3), (18, 3, 3), (18, 2, 3), (40, 5, 3), (12, 4, 3)]


def table(rng, n, nm, ns):
    """One seeded residual table of ``n`` conditions and its true floor."""
    t = rng.uniform(50.0, 500.0, n)
    sig_m = np.where(np.arange(n) % 2, 0.02, 0.05) * t
    sig_s = 0.04 * t
    df = pd.DataFrame({"measurement": "bin", "measure": "F_N", "simulation": [f"c{i}" for i in range(n)],
                       "measured": t, "scale": t,
                       "measured_sd": sig_m * np.sqrt(rng.chisquare(nm - 1, n) / (nm - 1)), "measured_n": float(nm),
                       "simulated_sd": sig_s * np.sqrt(rng.chisquare(ns - 1, n) / (ns - 1)), "simulated_n": float(ns)})
    return df, math.sqrt(float(np.mean((sig_m ** 2 / nm + sig_s ** 2 / ns) / t ** 2)))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tables", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=2026)
    ap.add_argument("--out", default=str(HERE / "results"))
    args = ap.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    rows, rev = [], commit()
    for n, nm, ns in CONFIGS:
        t0 = time.process_time()
        below = above = 0
        for _ in range(args.tables):
            df, true = table(rng, n, nm, ns)
            lo, hi, _ = rs.floor_interval(df)
            below += true < lo
            above += true > hi
        covered = args.tables - below - above
        rows.append({"rows": n, "repeats": nm, "seeds": ns, "tables": args.tables, "covered": covered,
                     "coverage_percent": round(100 * covered / args.tables, 1), "below": below, "above": above,
                     "cpu_s": round(time.process_time() - t0, 1), "commit": rev})
        print(rows[-1], flush=True)
    out = Path(args.out)
    write_rows(out / "loop_floor_coverage.csv", rows, FIELDS)
    se = 100 * math.sqrt(0.95 * 0.05 / args.tables)
    write_page(out / "loop_floor_coverage.md", [
        "# Coverage of the noise floor's 95 % interval", "",
        f"Machine: {platform.machine()}, Python {platform.python_version()}; commit {rev}, "
        f"{time.strftime('%Y-%m-%d %H:%M', time.gmtime())} UTC; `python benchmarks/loop_floor_coverage.py "
        f"--tables {args.tables} --seed {args.seed}`.", "",
        "Seeded residual tables (module docstring): measured SDs 2 % and 5 % of the value on alternate rows, seed SD "
        "4 %, each SD drawn from its repeats or seeds; the share of tables whose interval covers the true floor "
        f"(binomial standard error {se:.1f} % about 95 %), and how many missed it below (true floor under the "
        "interval) or above.", "",
        "| rows | measured repeats | seeds | tables | covered, % | true floor below | above | CPU s |",
        "|---|---|---|---|---|---|---|---|",
        *(f"| {r['rows']} | {r['repeats']} | {r['seeds']} | {r['tables']} | {r['coverage_percent']} | {r['below']} "
          f"| {r['above']} | {r['cpu_s']} |" for r in rows)])


if __name__ == "__main__":
    main()
