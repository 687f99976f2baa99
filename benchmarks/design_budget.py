"""Every design point of every soil through its DEM scenario: the cost of a calibration pass.

For each soil config with a ``simulation`` block, each response it maps to a scenario and
each stage that has that response, every run of the stage's design
(:func:`soilcal.dem.scenarios.design.design_levels`: the printed table, or the design generated
from the factor levels when the paper's table is lost) is simulated once
(:func:`~soilcal.dem.scenarios.design.simulate_point`, the block's preset, the seed of
:func:`~soilcal.dem.scenarios.design.design_seeds`: the soil's seed, the next one for each
repetition of a point).
One row per design point goes to ``benchmarks/results/design_budget.csv`` (written after each
point, so an interrupted sweep keeps its rows; a rerun skips the points already there with
the same seed unless ``--fresh``); ``design_budget.md`` sums the wall time per soil, stage
and response, projects the whole pass from the points run (``--every k`` runs every k-th row only), and sets the
simulated response beside the printed (EDEM) one (spread and Pearson correlation).

``--jobs k`` runs k points at a time (``--threads`` each), one process per point, as a
workflow with one DEM job per design point runs them on k cores; the elapsed time of each
sweep, beside the sum of its runs' wall times, goes to ``design_budget_sweeps.csv`` and the
page.  The page summarises every soil, stage and response, whatever ``--soils``,
``--responses`` and ``--stages`` chose to run.

    python benchmarks/design_budget.py --jobs 2 --threads 1 --fresh
    python benchmarks/design_budget.py --threads 2
    python benchmarks/design_budget.py --soils cinnamon-soil --every 3
    python benchmarks/design_budget.py --report-only
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import numpy as np
from _report import (commit, read_rows, runs_table, spread_and_correlation, write_page,
                     write_rows)

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
FIELDS = ["utc", "commit", "soil", "stage", "response", "run", "design_runs", "levels", "scenario",
          "setup", "measure", "preset", "seed", "threads", "particles", "steps", "wall_s", "printed",
          "simulated", "peak_overlap", "error"]
SWEEP_FIELDS = ["utc", "commit", "soils", "jobs", "threads", "points", "elapsed_s", "runs_wall_s"]


def _key(r):
    return (r["soil"], r["stage"], r["response"], int(r["run"]))


def plan(soils, only_responses=None, only_stages=None):
    """(soil, stage id, response id, design rows | error text) for every simulated response."""
    from soilcal.dem.scenarios import design
    from soilcal.errors import InputError

    out = []
    for soil in soils:
        sim = soil.data.get("simulation") or {}
        for rid in sim.get("responses", {}):
            if only_responses and rid not in only_responses:
                continue
            for st in soil.stages:
                if rid not in [r["id"] for r in st["responses"]]:
                    continue
                if only_stages and st["id"] not in only_stages:
                    continue
                try:
                    rows = design.design_levels(soil, st["id"])
                except InputError as exc:
                    rows = str(exc)
                out.append((soil, st["id"], rid, rows))
    return out


_SOILS: dict = {}


def _init_worker(threads):
    import numba

    numba.set_num_threads(threads)


def _point(task):
    """:func:`run_point` in a worker process (the soil is loaded there, once per process)."""
    from soilcal.config.load import load_soil

    name, stage_id, rid, row, n_runs, seed, threads, rev = task
    if name not in _SOILS:
        _SOILS[name] = load_soil(ROOT / "config" / "soils" / f"{name}.yaml", ROOT / "resources")
    return run_point(_SOILS[name], stage_id, rid, row, n_runs, seed, threads, rev)


def run_point(soil, stage_id, rid, row, n_runs, seed, threads, rev):
    from soilcal.dem.scenarios import design

    stage = soil.stage(stage_id)
    letters = list(stage["factors"])
    levels = {k: float(row[k]) for k in letters}
    spec = design.spec(soil, rid)
    col = next(r.get("column", r["id"]) for r in stage["responses"] if r["id"] == rid)
    printed = row.get(col, "")
    out = dict(utc=time.strftime("%Y-%m-%d %H:%M", time.gmtime()), commit=rev, soil=soil.name,
               stage=stage_id, response=rid, run=int(row["run"]), design_runs=n_runs,
               levels=" ".join(f"{k}={v:g}" for k, v in levels.items()), scenario=spec.scenario,
               setup=spec.setup["name"], measure=spec.measure, preset=spec.preset,
               seed=int(seed),
               printed="" if printed == "" or not np.isfinite(float(printed)) else float(printed))
    t0 = time.perf_counter()
    try:
        value, res = design.simulate_point(soil, stage_id, levels, rid, seed=seed, replicates=1,
                                           threads=threads)
    except Exception as exc:  # a failed point is a row of the table, not the end of the sweep
        out.update(wall_s=round(time.perf_counter() - t0, 1), simulated="",
                   error=f"{type(exc).__name__}: {exc}"[:300].replace("|", "/"), threads=threads)
        return out
    out.update(threads=res.threads, particles=res.n_particles, steps=res.steps,
               wall_s=round(res.wall_s, 1), simulated=round(value, 3),
               peak_overlap=round(float(res.responses.get("peak_overlap", float("nan"))), 3),
               error=str(res.responses.get("measure_errors", ""))[:300].replace("|", "/"))
    return out


def _f(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return float("nan")


def report(rows, planned, md_path, argv, sweeps=()):
    md = ["# A calibration pass: every design point of every soil through its DEM scenario", "",
          f"Machine: {platform.machine()}, {os.cpu_count()} logical CPUs, Python "
          f"{platform.python_version()}.  Last command: `python benchmarks/design_budget.py "
          + " ".join(argv) + "`.  Rows: `design_budget.csv` (utc, commit and threads per row).", "",
          "Per soil, stage and response: the design's runs, the runs simulated (one seed each), "
          "their wall time (sum and mean), the projected wall time of the whole stage (mean x runs), "
          "and the simulated against the printed (EDEM) response over the runs simulated: spread "
          "(max - min) and Pearson correlation.  Failed runs count in the time and are listed "
          "below the table.", "",
          "| soil | stage | response | scenario / setup / measure | runs | simulated | wall s (sum) | "
          "wall s (mean) | projected s | printed spread | simulated spread | correlation |",
          "|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    total, total_proj = 0.0, 0.0
    for soil, sid, rid, design_rows in planned:
        if isinstance(design_rows, str):
            md.append(f"| {soil.name} | {sid} | {rid} | not simulated: {design_rows.split(': ', 1)[-1]} "
                      "| | 0 | | | | | | |")
            continue
        sel = [r for r in rows if (r["soil"], r["stage"], r["response"]) == (soil.name, sid, rid)]
        n = len(design_rows)
        w = np.array([_f(r["wall_s"]) for r in sel])
        # a run with a value counts even when another estimator wrote to measure_errors
        p_spread, s_spread, corr = spread_and_correlation([_f(r["printed"]) for r in sel],
                                                          [_f(r["simulated"]) for r in sel])
        mean = float(w.mean()) if len(w) else float("nan")
        proj = mean * n if len(w) else float("nan")
        total += float(w.sum())
        total_proj += proj if np.isfinite(proj) else 0.0
        sc = f"{sel[0]['scenario']} / {sel[0]['setup']} / {sel[0]['measure']}" if sel else ""
        md.append(f"| {soil.name} | {sid} | {rid} | {sc} | {n} | {len(sel)} | {w.sum():.0f} | "
                  f"{mean:.1f} | {proj:.0f} | {p_spread} | {s_spread} | {corr} |")
    md += ["", f"Sum of the wall times of the runs in the table: {total:.0f} s "
           f"({total / 60:.1f} min); projected for every design point with one seed: "
           f"{total_proj:.0f} s ({total_proj / 60:.1f} min).  Runs made with --jobs k > 1 shared "
           "the cores with k - 1 others: their sum is not the time the pass took; the sweeps "
           "table gives that.", ""]
    if sweeps:
        md += ["Sweeps (elapsed: the sweep's wall-clock time; runs: the sum of its runs' wall "
               "times, each run measured while the other jobs ran):", "",
               "| utc | commit | soils | jobs | threads per job | points | elapsed min | "
               "runs min |",
               "|---|---|---|---:|---:|---:|---:|---:|"]
        md += [f"| {w['utc']} | {w['commit']} | {w['soils']} | {w['jobs']} | {w['threads']} | "
               f"{w['points']} | {_f(w['elapsed_s']) / 60:.1f} | "
               f"{_f(w['runs_wall_s']) / 60:.1f} |" for w in sweeps] + [""]
    failed = [r for r in rows if r["error"]]
    if failed:
        md += ["Runs with errors (a value in the table's simulated column means the measured "
               "estimator read the heap and another one did not):", ""] + [f"* {r['soil']} {r['stage']} run {r['run']} ({r['response']}): "
                                      f"{r['error']}" for r in failed] + [""]
    md += ["Runs:", "", *runs_table(rows, FIELDS)]
    write_page(md_path, md)


def main(argv=None):
    from soilcal.config.load import load_soil

    argv = sys.argv[1:] if argv is None else argv
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--soils", default="", help="comma list (default: every soil with a simulation block)")
    ap.add_argument("--responses", default="", help="comma list of response ids (default: all)")
    ap.add_argument("--stages", default="", help="comma list of stage ids (default: all)")
    ap.add_argument("--every", type=int, default=1, help="run every k-th row of each design")
    ap.add_argument("--threads", type=int, default=2, help="threads per run")
    ap.add_argument("--jobs", type=int, default=1, help="runs at a time (processes)")
    ap.add_argument("--fresh", action="store_true", help="rerun points already in the CSV")
    ap.add_argument("--report-only", action="store_true", help="rewrite the page, run nothing")
    ap.add_argument("--out", default=str(HERE / "results"))
    args = ap.parse_args(argv)
    if args.every < 1:
        raise SystemExit(f"--every: expected an integer >= 1, got {args.every}")
    if args.jobs < 1 or args.threads < 1:
        raise SystemExit(f"--jobs, --threads: expected integers >= 1, got {args.jobs}, "
                         f"{args.threads}")
    every = sorted(p.stem for p in (ROOT / "config" / "soils").glob("*.yaml"))
    names = [s for s in args.soils.split(",") if s] or every
    for nm in names:
        if nm not in every:
            raise SystemExit(f"--soils: no soil file {ROOT / 'config' / 'soils' / nm}.yaml")
    loaded = {nm: load_soil(ROOT / "config" / "soils" / f"{nm}.yaml", ROOT / "resources")
              for nm in every}
    simulated = [s for s in loaded.values() if s.data.get("simulation")]
    soils = [loaded[nm] for nm in names if loaded[nm].data.get("simulation")]
    planned = plan(soils, set(filter(None, args.responses.split(","))),
                   set(filter(None, args.stages.split(","))))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    csv_path, md_path = out / "design_budget.csv", out / "design_budget.md"
    sweep_path = out / "design_budget_sweeps.csv"
    rows = read_rows(csv_path, FIELDS)
    sweeps = read_rows(sweep_path, SWEEP_FIELDS)
    rev = commit()
    if not args.report_only:
        from soilcal.dem.scenarios import design

        tasks = []
        for soil, sid, rid, design_rows in planned:
            if isinstance(design_rows, str):
                print(f"{soil.name} {sid} {rid}: not simulated: {design_rows}", flush=True)
                continue
            seeds = design.design_seeds(soil, sid, design_rows)
            for i, (_, row) in enumerate(design_rows.iterrows()):
                if i % args.every:
                    continue
                key = (soil.name, sid, rid, int(row["run"]))
                if not args.fresh and any(_key(r) == key and int(r["seed"]) == seeds[i] for r in rows):
                    continue
                tasks.append((soil.name, sid, rid, row.to_dict(), len(design_rows), seeds[i],
                              args.threads, rev))
        t0, runs_wall = time.perf_counter(), 0.0
        with ProcessPoolExecutor(max_workers=args.jobs, initializer=_init_worker,
                                 initargs=(args.threads,)) as ex:
            for fut in as_completed([ex.submit(_point, t) for t in tasks]):
                new = fut.result()
                runs_wall += _f(new["wall_s"])
                print({k: new[k] for k in ("soil", "stage", "response", "run", "printed", "simulated",
                                           "wall_s", "error")}, flush=True)
                rows = [r for r in rows if _key(r) != _key(new)] + [new]
                rows.sort(key=_key)
                write_rows(csv_path, rows, FIELDS)
        if tasks:
            sweeps.append(dict(utc=time.strftime("%Y-%m-%d %H:%M", time.gmtime()), commit=rev,
                               soils=" ".join(sorted({t[0] for t in tasks})), jobs=args.jobs,
                               threads=args.threads, points=len(tasks),
                               elapsed_s=round(time.perf_counter() - t0, 1),
                               runs_wall_s=round(runs_wall, 1)))
            write_rows(sweep_path, sweeps, SWEEP_FIELDS)
    report(rows, plan(simulated), md_path, argv, sweeps)


if __name__ == "__main__":
    main()
