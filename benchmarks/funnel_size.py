"""Seed scatter and cost of the cohesive soil's funnel heap against its sphere count.

One heap at the guangxi-cohesive Box-Behnken centre (every factor of stage ``bbd`` at the
middle of its printed range; the other parameters from ``simulation.params``), run as a
workflow design point runs it (:func:`soilcal.dem.scenarios.design.simulate_point`, the
response ``angle_of_repose`` with the soil's own ``set``, ``read_time`` included, the
``quick`` preset, one replicate, one thread) with the response's ``set.n_particles`` replaced
by ``--particles``.  The funnel's load keeps its mass, so more spheres are finer spheres.
Each heap is a row of ``benchmarks/results/funnel_size.csv`` (a rerun of the same size and
seed replaces its row): the silhouette angle the soil calibrates on, the process CPU seconds
of the heap, and the one-minute load average when it ended (other work on the machine makes
CPU seconds a little larger, not the angle different).

    python benchmarks/funnel_size.py run --particles 3980 --seeds 1-6
    python benchmarks/funnel_size.py run --particles 8000 --seeds 1,2
    python benchmarks/funnel_size.py table

``table`` writes ``funnel_size.md``: mean and sample SD of the angle per size, the CPU per
heap, and for every pair of sizes the two-sided F test of their variances and Welch's t test
of their means (scipy.stats).  Notes below the page's marker are kept.
"""

from __future__ import annotations

import argparse
import copy
import itertools
import os
import platform
import sys
import time
from pathlib import Path

from _report import commit, read_rows, seed_list, write_page, write_rows

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
CSV = HERE / "results" / "funnel_size.csv"
MD = HERE / "results" / "funnel_size.md"
FIELDS = ["utc", "commit", "soil", "stage", "response", "particles", "read_time_s", "seed",
          "angle_deg", "cpu_s", "load_1min"]
SOIL = "guangxi-cohesive"
STAGE = "bbd"
RESPONSE = "angle_of_repose"


def one_heap(n_particles: int, seed: int) -> dict:
    """Run one heap of ``n_particles`` spheres at the Box-Behnken centre; its row."""
    import numba

    from soilcal.config.load import Soil, load_soil
    from soilcal.dem.scenarios import design

    numba.set_num_threads(1)
    soil = load_soil(ROOT / "config" / "soils" / f"{SOIL}.yaml")
    data = copy.deepcopy(soil.data)
    spec = data["simulation"]["responses"][RESPONSE]
    spec.setdefault("set", {})["n_particles"] = int(n_particles)
    soil = Soil(soil.path, data, soil.resources_root)
    factors = soil.stage(STAGE)["factors"]
    centre = {c: 0.5 * (f["low"] + f["high"]) for c, f in factors.items()}
    t0 = time.process_time()
    value, _ = design.simulate_point(soil, STAGE, centre, RESPONSE, seed=seed, replicates=1,
                                     threads=1)
    cpu = time.process_time() - t0
    return {"utc": time.strftime("%Y-%m-%d %H:%M", time.gmtime()), "commit": commit(),
            "soil": SOIL, "stage": STAGE, "response": RESPONSE, "particles": int(n_particles),
            "read_time_s": spec["set"].get("read_time", ""), "seed": seed,
            "angle_deg": round(float(value), 2), "cpu_s": round(cpu, 1),
            "load_1min": round(os.getloadavg()[0], 2)}


def run(args) -> None:
    for seed in seed_list(args.seeds):
        row = one_heap(args.particles, seed)
        rows = [r for r in read_rows(CSV, FIELDS)
                if not (int(r["particles"]) == row["particles"] and int(r["seed"]) == seed)]
        write_rows(CSV, rows + [row], FIELDS)
        print(f"{row['particles']} spheres, seed {seed}: {row['angle_deg']} deg, {row['cpu_s']} CPU-s",
              flush=True)


def table(args) -> None:
    import numpy as np
    from scipy import stats

    rows = read_rows(CSV, FIELDS)
    sizes = sorted({int(r["particles"]) for r in rows})
    angles = {n: np.array([float(r["angle_deg"]) for r in rows if int(r["particles"]) == n])
              for n in sizes}
    cpus = {n: np.array([float(r["cpu_s"]) for r in rows if int(r["particles"]) == n]) for n in sizes}
    lines = [f"# The cohesive soil's funnel heap: seed scatter and cost against the sphere count",
             "",
             f"Machine: {platform.machine()}, {os.cpu_count()} logical CPUs, Python "
             f"{platform.python_version()}.  Command: `python benchmarks/funnel_size.py run "
             f"--particles N --seeds S`, then `table`.  Rows: `funnel_size.csv` (utc, commit and "
             f"load per row).  Case: {SOIL}, stage {STAGE} centre, response {RESPONSE} with the "
             f"soil's own `set` (read_time included), quick preset, one thread.",
             "",
             "| spheres | heaps | angle deg, mean +- SD | min | max | CPU s per heap, median (range) |",
             "|---:|---:|---|---:|---:|---|"]
    for n in sizes:
        a, c = angles[n], cpus[n]
        sd = f"{a.std(ddof=1):.2f}" if len(a) > 1 else "nan"
        lines.append(f"| {n} | {len(a)} | {a.mean():.2f} +- {sd} | {a.min():.2f} | {a.max():.2f} | "
                     f"{np.median(c):.1f} ({c.min():.1f}-{c.max():.1f}) |")
    lines += ["", "Pairs of sizes: F = SD(first)^2 / SD(second)^2, two-sided p; Welch's t test of the means:",
              "", "| spheres | against | F | df | p (variances) | mean difference deg | p (means) |",
              "|---:|---:|---:|---|---:|---:|---:|"]
    for m, n in itertools.combinations(sizes, 2):
        a, b = angles[m], angles[n]
        if len(a) < 2 or len(b) < 2:
            continue
        f = a.var(ddof=1) / b.var(ddof=1)
        d1, d2 = len(a) - 1, len(b) - 1
        p_f = min(1.0, 2 * min(stats.f.sf(f, d1, d2), stats.f.cdf(f, d1, d2)))
        t = stats.ttest_ind(a, b, equal_var=False)
        lines.append(f"| {m} | {n} | {f:.2f} | {d1}, {d2} | {p_f:.3f} | {a.mean() - b.mean():+.2f} | "
                     f"{t.pvalue:.3f} |")
    write_page(MD, lines)
    print(MD.read_text())


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("--particles", type=int, required=True)
    r.add_argument("--seeds", required=True, help="e.g. 1-6 or 1,2")
    sub.add_parser("table")
    args = ap.parse_args(argv)
    (run if args.cmd == "run" else table)(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
