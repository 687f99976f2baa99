"""Seed scatter of the drum's dynamic angle against the length of the rotation.

The case is a design point of the vineyard soil (003; ``config/soils/xinjiang-vineyard.yaml``,
response ``dynamic_angle``): its factor levels and the soil's simulation block give the DEM
parameters (:func:`soilcal.dem.scenarios.design.design_params`), and the drum runs at the
quick preset with the rotation ``--spins`` seconds long (frames every 0.05 s after the
preset's transient).  Each seed is one run; each run reports the angle before collapse
(``angle_avalanche_deg``, the soil's measure), the time mean of the frame angles
(``angle_deg``), the number of collapses and of lone frames replaced (``n_spikes``).

Rows go to ``benchmarks/results/drum_seeds.csv`` (a rerun of the same point, spin and seed
replaces its row); ``drum_seeds.md`` tabulates per point and spin the mean and sample
standard deviation over the seeds of both angles (notes below its marker are kept).

    python benchmarks/drum_seeds.py --run 5 --spins 4,8 --seeds 0-5 --jobs 2
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path

import numpy as np
from _report import commit, run_cases, runs_table, seed_list, write_page

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
SOIL = ROOT / "config" / "soils" / "xinjiang-vineyard.yaml"
FIELDS = ["utc", "commit", "stage", "run", "levels", "spin_time_s", "seed", "n_frames",
          "n_avalanches", "n_spikes", "angle_avalanche_deg", "angle_deg", "steps", "wall_s"]




def one(stage, run, spin, seed, rev):
    """One drum run of design point ``run`` of ``stage``: a row of the table."""
    import numba

    from soilcal.config.load import load_soil
    from soilcal.dem.scenarios import design, drum

    numba.set_num_threads(1)
    soil = load_soil(SOIL, ROOT / "resources")
    df = design.design_levels(soil, stage)
    row = df[df.run == run].iloc[0]
    lev = {c: float(row[c]) for c in soil.stage(stage)["factors"]}
    sim = design.spec(soil, "dynamic_angle")
    params = design.design_params(soil, stage, lev, sim)
    res = drum.run(dict(sim.setup, spin_time=spin), params, "quick", seed, 1)
    r = res.responses
    return dict(utc=time.strftime("%Y-%m-%d %H:%M", time.gmtime()), commit=rev, stage=stage,
                run=run, levels=" ".join(f"{k}={v:g}" for k, v in lev.items()),
                spin_time_s=spin, seed=seed, n_frames=r["n_frames"],
                n_avalanches=r["n_avalanches"], n_spikes=r["n_spikes"],
                angle_avalanche_deg=round(r["angle_avalanche_deg"], 4),
                angle_deg=round(r["angle_deg"], 4), steps=res.steps, wall_s=round(res.wall_s, 2))


def page(rows, md, cmd):
    lines = ["# Seed scatter of the drum's dynamic angle (vineyard soil, quick preset)", "",
             f"Machine: {platform.machine()}, Python {platform.python_version()}.  Last command: "
             f"`{cmd}`.  Rows: `drum_seeds.csv` (utc and commit per row).", "",
             "| stage | run | spin s | seeds | collapses per run | angle before collapse: mean | "
             "SD | time mean: mean | SD |", "|---|---:|---:|---:|---|---:|---:|---:|---:|"]
    groups = sorted({(r["stage"], int(r["run"]), float(r["spin_time_s"])) for r in rows})
    for st, run, spin in groups:
        g = [r for r in rows
             if (r["stage"], int(r["run"]), float(r["spin_time_s"])) == (st, run, spin)]
        av = np.array([float(r["angle_avalanche_deg"]) for r in g])
        tm = np.array([float(r["angle_deg"]) for r in g])
        na = [int(r["n_avalanches"]) for r in g]
        sd = (lambda v: f"{v.std(ddof=1):.2f}" if v.size > 1 else "")
        lines.append(f"| {st} | {run} | {spin:g} | {len(g)} | {min(na)}-{max(na)} | "
                     f"{av.mean():.2f} | {sd(av)} | {tm.mean():.2f} | {sd(tm)} |")
    lines += ["", "Runs:", ""]
    key = (lambda r: (r["stage"], int(r["run"]), float(r["spin_time_s"]), int(r["seed"])))
    lines += runs_table(sorted(rows, key=key), FIELDS)
    write_page(md, lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--stage", default="bbd")
    ap.add_argument("--run", type=int, default=5, help="design run (default: a BBD centre point)")
    ap.add_argument("--spins", default="4,8", help="comma list of rotation times (s)")
    ap.add_argument("--seeds", default="0-5", help="e.g. 0-5 or 0,2,4")
    ap.add_argument("--jobs", type=int, default=2, help="runs at a time (one thread each)")
    ap.add_argument("--out", default=str(HERE / "results"))
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    csv_path, md = out / "drum_seeds.csv", out / "drum_seeds.md"
    spins = [float(s) for s in args.spins.split(",") if s]
    cases = [(args.stage, args.run, sp, sd) for sp in spins for sd in seed_list(args.seeds)]
    keyof = (lambda r: (r["stage"], int(r["run"]), float(r["spin_time_s"]), int(r["seed"])))
    rows = run_cases(one, cases, commit(), csv_path, FIELDS, keyof, args.jobs,
                     show=("spin_time_s", "seed", "n_avalanches", "angle_avalanche_deg", "angle_deg", "wall_s"))
    page(rows, md, "python benchmarks/drum_seeds.py " + " ".join(
        sys.argv[1:] if argv is None else argv))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
