"""How often the adaptive design's stopping rules decide right, on analytic stand-ins for the DEM.

A target inside the box's reach must not be called ``unreachable`` (a false stop ends a
calibration that could have met its target); one beyond it should be, before the budget is
spent.  Both are hardest when one seed's scatter is of the order of the distance between the
target and the reach: among many runs, some single seed always reads near the target.

Cases (two factors a, b on [0, 1], seeded Gaussian seed scatter of SD ``sd``, tolerance 2 %):

* reachable: y = 10 + 3 a b (the target met only in a corner) and y = 10 + 3 a, target 12.5;
* unreachable: y = 10 + a against 13.5 (2.2 seed SDs beyond the band at sd 1) and
  y = 10 + 3 a b against 14.5 (1.2 SDs beyond).

Each case runs ``--designs`` designs (design seeds 0, 1, ...) of budget ``--budget`` and counts
how each stopped.  Rows: ``benchmarks/results/adaptive_stopping.csv`` (one per case and
commit, with the UTC time), replacing a row of the same case and commit; run from a checkout of
an earlier commit (with this script copied in, ``--out`` this file) to compare the rules of two
commits.

    python benchmarks/adaptive_stopping.py
    python benchmarks/adaptive_stopping.py --designs 40 --budget 60
"""

from __future__ import annotations

import argparse
import csv
import subprocess
import time
import warnings
from collections import Counter
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from soilcal.doe import adaptive as ad

HERE = Path(__file__).resolve().parent
OUT = HERE / "results" / "adaptive_stopping.csv"
FIELDS = ["case", "reachable", "sd", "target", "designs", "budget", "target_met", "unreachable",
          "budget_spent", "other", "mean_runs", "commit", "utc", "elapsed_s"]

CASES = {
    "corner_sd1": (lambda lv: 10.0 + 3.0 * lv["a"] * lv["b"], 12.5, 1.0, True),
    "linear_sd1": (lambda lv: 10.0 + 3.0 * lv["a"], 12.5, 1.0, True),
    "corner_sd0.5": (lambda lv: 10.0 + 3.0 * lv["a"] * lv["b"], 12.5, 0.5, True),
    "beyond_linear_sd1": (lambda lv: 10.0 + lv["a"], 13.5, 1.0, False),
    "beyond_corner_sd1": (lambda lv: 10.0 + 3.0 * lv["a"] * lv["b"], 14.5, 1.0, False),
}


def commit() -> str:
    try:
        rev = subprocess.run(["git", "rev-parse", "--short=7", "HEAD"], cwd=HERE, capture_output=True,
                             text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--", "src"], cwd=HERE.parent, capture_output=True,
                               text=True, check=True).stdout.strip()
        return rev + ("+dirty" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def run_case(fn, target: float, sd: float, designs: int, budget: int) -> tuple[Counter, float]:
    problem = ad.Problem([ad.Factor("a", 0, 1), ad.Factor("b", 0, 1)], [ad.Target("y", target, tol_pct=2.0)])

    def evaluate(levels, seed):
        return {"y": fn(levels) + sd * np.random.default_rng(seed).standard_normal()}

    stops, runs = Counter(), []
    for seed in range(designs):
        r, st = ad.run(problem, evaluate, ad.Settings(seed=seed, budget=budget))
        stops[st.status] += 1
        runs.append(len(r))
    return stops, float(np.mean(runs))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--designs", type=int, default=20)
    ap.add_argument("--budget", type=int, default=40)
    ap.add_argument("--cases", default=",".join(CASES), help="comma-separated, of: " + ", ".join(CASES))
    ap.add_argument("--out", type=Path, default=OUT, help="the rows' file (default: %(default)s)")
    a = ap.parse_args(argv)
    out = a.out
    warnings.filterwarnings("ignore", module="sklearn")
    rows = []
    if out.is_file():
        with out.open() as f:
            rows = list(csv.DictReader(f))
    rev = commit()
    for name in a.cases.split(","):
        if name not in CASES:
            raise SystemExit(f"--cases: unknown case {name!r}; expected one of {', '.join(CASES)}")
        fn, target, sd, reachable = CASES[name]
        t0 = time.perf_counter()
        stops, mean_runs = run_case(fn, target, sd, a.designs, a.budget)
        known = ("target met", "unreachable", "budget spent")
        row = {"case": name, "reachable": reachable, "sd": sd, "target": target, "designs": a.designs,
               "budget": a.budget, "target_met": stops["target met"], "unreachable": stops["unreachable"],
               "budget_spent": stops["budget spent"],
               "other": "; ".join(f"{k} {v}" for k, v in sorted(stops.items()) if k not in known),
               "mean_runs": f"{mean_runs:.1f}", "commit": rev,
               "utc": datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M"),
               "elapsed_s": f"{time.perf_counter() - t0:.1f}"}
        rows = [r for r in rows if (r["case"], r["commit"]) != (name, rev)] + [row]
        print(", ".join(f"{k}={v}" for k, v in row.items()), flush=True)
    out.parent.mkdir(parents=True, exist_ok=True)
    with out.open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=FIELDS)
        w.writeheader()
        w.writerows(rows)


if __name__ == "__main__":
    main()
