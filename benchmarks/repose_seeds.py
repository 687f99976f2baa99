"""Seed scatter of the static angle of repose: repeated cylinder-lift heaps that differ only
in the seed of the random insertion, measured three ways.

The case is the cinnamon-soil cylinder lift (002 Sec. 2.4: 60 mm steel tube, 0.05 m/s, fill
height = diameter) at the quick preset with ``n_particles`` spheres, for two soils:

* ``noncohesive``: the cinnamon soil's BBD centre (rolling friction 0.11, sliding 0.56,
  restitution 0.45; ``DemParams()``) without surface energy;
* ``cohesive``: the same with the JKR surface energy 0.38 J/m^2 (BBD centre, Table 6),
  scaled by the Sauter-radius ratio of the quick to the paper particles (base.py).

Each heap gives the angle by radial bins (``angle_deg``, the papers' EDEMpy method), by the
surface scan (``angle_surface_deg``) and by side silhouettes (``angle_image_deg``, from
``--views`` side views: each number given measures the same heap again, one row each; rows
without the column had 2).  Every run is a row of ``benchmarks/results/repose_seeds.csv``
(``--rolling`` chooses the rolling-resistance model, a column of its own; a rerun of the same
case, model, size, views and seed replaces its row); ``repose_seeds.md`` tabulates mean and sample standard deviation over
the seeds of each case, model and estimator, and the scatter of the mean of ``--group``
consecutive seeds (the replicate mean of ``soilcal scenario run --replicates``; notes below
its marker are kept).

    python benchmarks/repose_seeds.py                       # 5 seeds, the default cases
    python benchmarks/repose_seeds.py --cases noncohesive:5000 --seeds 0,1,2,3,4,5,6,7
    python benchmarks/repose_seeds.py --cases noncohesive:5000 --rolling bounded
    python benchmarks/repose_seeds.py --cases noncohesive:5000 --seeds 10-39 --group 4
    python benchmarks/repose_seeds.py --cases cohesive:1000 --seeds 0-11 --views 2,8
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np
from _report import commit, kept_notes, read_rows, write_rows

from soilcal.dem.scenarios.base import DEFAULT_ROLLING, ROLLING_MODELS

HERE = Path(__file__).resolve().parent
ESTIMATORS = ("angle_deg", "angle_surface_deg", "angle_image_deg")
FIELDS = ["utc", "commit", "case", "rolling", "n", "views", "seed", "particles", "threads", "steps",
          "wall_s",
          "settled", "cohesion_scale", *ESTIMATORS, "height_mm", "load_avg_1min"]
DEFAULT_CASES = "noncohesive:1000,noncohesive:5000,cohesive:1000,cohesive:5000"


def params(case):
    from soilcal.dem.scenarios.base import DemParams

    if case == "noncohesive":
        return DemParams(soil_soil_surface_energy=0.0, soil_steel_surface_energy=0.0)
    if case == "cohesive":
        return DemParams()
    raise SystemExit(f"--cases: expected noncohesive:N or cohesive:N, got {case!r}")


def run_one(case, n, seed, threads, rev, rolling, views):
    """One heap, measured with each number of side views in ``views`` (one row each; the
    scenario's own run measures the first, the others measure its final state again)."""
    from soilcal.dem import measure
    from soilcal.dem.scenarios import repose

    setup = dict(repose.setups()["cinnamon-soil"], name="cinnamon-soil", n_particles=n,
                 rolling_model=rolling, image_views=views[0])
    res = repose.run(setup, params(case), "quick", seed, threads)
    r = res.responses
    base = dict(utc=time.strftime("%Y-%m-%d %H:%M", time.gmtime()), commit=rev, case=case,
                rolling=rolling, n=n, seed=seed, particles=res.n_particles, threads=res.threads,
                steps=res.steps,
                wall_s=round(res.wall_s, 2), settled=r["settled"],
                cohesion_scale=round(res.setup["cohesion_scale"], 4),
                **{k: round(r[k], 3) for k in ESTIMATORS},
                height_mm=round(1e3 * r["height_m"], 2), load_avg_1min=round(os.getloadavg()[0], 2))
    x, rad = res.series["x"], res.series["r"]
    half = setup["plate_size"] / 2
    on = (np.abs(x[:, 0]) <= half) & (np.abs(x[:, 1]) <= half)  # the run's spheres on the plate
    rows = [dict(base, views=views[0])]
    for v in views[1:]:
        img = measure.repose_angle_image(x[on], rad[on], 0.0, views=v)
        rows.append(dict(base, views=v, angle_image_deg=round(img["angle_deg"], 3)))
    return rows


def _key(r):
    return r["case"], r["rolling"] or DEFAULT_ROLLING, int(r["n"]), int(r.get("views") or 2)


def summary(rows):
    """(case, rolling model, n, seeds, mean and SD of every estimator) per case, model and
    size."""
    out = []
    for key in sorted({_key(r) for r in rows}):
        sel = [r for r in rows if _key(r) == key]
        line = dict(case=key[0], rolling=key[1], n=key[2], views=key[3], seeds=len(sel))
        for k in ESTIMATORS:
            v = np.array([float(r[k]) for r in sel], float)
            v = v[np.isfinite(v)]
            line[k] = (float(v.mean()), float(v.std(ddof=1)) if v.size > 1 else math.nan)
        out.append(line)
    return out


def replicate_means(rows, k):
    """Scatter of the mean of k replicates: the seeds of each case, model and size in
    consecutive groups of k (0..k-1, k..2k-1, ...; full groups only, at least five), each
    group's mean angle, and the sample SD of those means beside the single-seed SD of the
    same runs over sqrt(k)."""
    out = []
    for key in sorted({_key(r) for r in rows}):
        by_seed = {int(r["seed"]): r for r in rows if _key(r) == key}
        groups = [[by_seed[s] for s in range(g * k, g * k + k)]
                  for g in range(max(by_seed) // k + 1)
                  if all(s in by_seed for s in range(g * k, g * k + k))]
        if len(groups) < 5:
            continue
        line = dict(case=key[0], rolling=key[1], n=key[2], views=key[3], k=k, groups=len(groups))
        for e in ESTIMATORS:
            means = np.array([np.mean([float(r[e]) for r in g]) for g in groups])
            single = np.array([float(r[e]) for g in groups for r in g])
            line[e] = (float(means.std(ddof=1)), float(single.std(ddof=1) / math.sqrt(k)))
        out.append(line)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default=DEFAULT_CASES)
    ap.add_argument("--seeds", default="0,1,2,3,4", help="comma list; a-b is a range")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--rolling", default=DEFAULT_ROLLING, choices=ROLLING_MODELS,
                    help="rolling-resistance model (setup.rolling_model)")
    ap.add_argument("--group", type=int, default=4,
                    help="replicates per mean in the replicate-mean table (default 4)")
    ap.add_argument("--views", default=None,
                    help="side views of the silhouette angle, comma list (default: the scenario's)")
    ap.add_argument("--out", default=str(HERE / "results"))
    args = ap.parse_args(argv)
    from soilcal.dem.scenarios.repose import IMAGE_VIEWS

    views = [int(v) for v in args.views.split(",")] if args.views else [IMAGE_VIEWS]
    cases = []
    for item in args.cases.split(","):
        case, _, n = item.partition(":")
        params(case)
        cases.append((case, int(n)))
    if args.group < 2:
        raise SystemExit(f"--group: expected an integer >= 2, got {args.group}")
    seeds = []
    for item in args.seeds.split(","):
        lo, _, hi = item.partition("-")
        if int(hi or lo) < int(lo):
            raise SystemExit(f"--seeds: expected a range a-b with a <= b, got {item!r}")
        seeds += list(range(int(lo), int(hi or lo) + 1))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    csv_path, md_path = out / "repose_seeds.csv", out / "repose_seeds.md"
    rows = read_rows(csv_path, FIELDS)
    rev = commit()  # the code this process runs, whatever is committed meanwhile
    for case, n in cases:
        for seed in seeds:
            for row in run_one(case, n, seed, args.threads, rev, args.rolling, views):
                print(row, flush=True)
                rows = [r for r in rows if (*_key(r), int(r["seed"])) != (*_key(row), seed)]
                rows.append(row)
            rows.sort(key=lambda r: (*_key(r), int(r["seed"])))
            write_rows(csv_path, rows, FIELDS)
    md = ["# Seed scatter of the static angle of repose (cinnamon-soil cylinder lift, quick preset)",
          "",
          f"Machine: {platform.machine()}, {os.cpu_count()} logical CPUs, Python "
          f"{platform.python_version()}.  Last command: `python benchmarks/repose_seeds.py "
          + " ".join(sys.argv[1:]) + "`.  Rows: `repose_seeds.csv` (utc and commit per row).",
          "",
          "Mean and sample standard deviation over the seeds [deg]:",
          "",
          "| case | rolling model | spheres | views | seeds | radial bins | surface scan | silhouette |",
          "|---|---|---:|---:|---:|---|---|---|"]
    for s in summary(rows):
        cells = [f"{s[k][0]:.2f} +- {s[k][1]:.2f}" for k in ESTIMATORS]
        md.append(f"| {s['case']} | {s['rolling']} | {s['n']} | {s['views']} | {s['seeds']} | "
                  + " | ".join(cells) + " |")
    groups = replicate_means(rows, args.group)
    if groups:
        md += ["", f"Scatter of the mean of {args.group} replicates (`soilcal scenario run ... "
               f"--replicates {args.group}`): seeds in consecutive groups of {args.group}, sample "
               f"SD of the group means, and beside it the single-seed SD of the same runs over "
               f"sqrt({args.group}) [deg]:", "",
               "| case | rolling model | spheres | views | groups | radial bins | surface scan | silhouette |",
               "|---|---|---:|---:|---:|---|---|---|"]
        for s in groups:
            cells = [f"{s[k][0]:.2f} ({s[k][1]:.2f})" for k in ESTIMATORS]
            md.append(f"| {s['case']} | {s['rolling']} | {s['n']} | {s['views']} | {s['groups']} | "
                      + " | ".join(cells) + " |")
    md += ["", "Runs:", "",
           "| " + " | ".join(FIELDS) + " |", "|" + "---|" * len(FIELDS),
           *("| " + " | ".join(str(r.get(k, "")) for k in FIELDS) + " |" for r in rows),
           "", kept_notes(md_path)]
    md_path.write_text("\n".join(md) + "\n")


if __name__ == "__main__":
    main()
