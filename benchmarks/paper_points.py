"""Design points of a paper's table rerun through a DEM scenario, beside the paper's printed
(EDEM) response.

Each chosen run of a soil's design table (``resources/published/<soil>/<table>``) becomes a
parameter set by :func:`soilcal.dem.scenarios.base.stage_params` (the row's factor levels,
the stage's fixed values, the soil's printed Poisson ratio and density; ``--param`` overrides
any of them, e.g. a density printed with a unit slip), runs ``--replicates`` seeds of the
scenario, and is written as one row of ``benchmarks/results/paper_points.csv`` (a rerun of
the same soil, stage, run, scenario, setup, preset, overrides, measure and response replaces
its row).  Coded tables (``table_coding: coded``) are decoded to actual levels.
``paper_points.md`` lists the rows and, per group of runs, the spread of the printed and of
the simulated response (max - min over the runs) and their Pearson correlation.

    python benchmarks/paper_points.py --soil xinjiang-vineyard --stage bbd --runs 22,12,26,11,4 \\
        --scenario drum --response dynamic_angle --measure angle_deg --replicates 3 \\
        --param soil_density=1757.6
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np
from _report import (commit, read_rows, runs_table, spread_and_correlation, write_page,
                     write_rows)

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
FIELDS = ["utc", "commit", "soil", "stage", "run", "levels", "scenario", "setup", "preset",
          "overrides", "replicates", "threads", "response", "printed", "measure", "simulated",
          "rep_sd", "per_seed", "particles", "wall_s"]


def _pairs(items):
    out = {}
    for it in items or []:
        k, _, v = it.partition("=")
        try:
            out[k.strip()] = float(v)
        except ValueError:
            raise SystemExit(f"--param: expected NAME=NUMBER, got {it!r}") from None
    return out


def run_point(soil, stage_id, row, args, overrides, rev):
    from soilcal.dem.scenarios import get, measures_of
    from soilcal.dem.scenarios.base import DemParams, merge_setup, run_replicates, stage_params

    stage = soil.stage(stage_id)
    levels = {k: float(row[k]) for k in stage["factors"] if k in row}
    params = stage_params(soil, stage_id, levels, coded=stage.get("table_coding") == "coded")
    params = DemParams.from_mapping(overrides, "--param", base=params)
    mod = get(args.scenario)
    setup = merge_setup(mod.setups(), args.setup or soil.name, {}, "--setup")
    mod.validate(setup, args.preset, "--setup", params=params)
    allowed = measures_of(mod, setup)
    if args.measure not in allowed:
        raise SystemExit(f"--measure: expected a measured response of {args.scenario} "
                         f"({', '.join(allowed)}), got {args.measure!r}")
    res = run_replicates(mod, setup, params, preset=args.preset, seed=args.seed,
                         replicates=args.replicates, threads=args.threads)
    sims = [r[args.measure] for r in res.per_run] if res.per_run else [res.responses[args.measure]]
    return dict(utc=time.strftime("%Y-%m-%d %H:%M", time.gmtime()), commit=rev, soil=soil.name,
                stage=stage_id, run=int(row["run"]),
                levels=" ".join(f"{k}={v:g}" for k, v in levels.items()),
                scenario=args.scenario, setup=setup["name"], preset=args.preset,
                overrides=" ".join(f"{k}={v:g}" for k, v in sorted(overrides.items())),
                replicates=args.replicates, threads=res.threads, response=args.response,
                printed=float(row[args.response]), measure=args.measure,
                simulated=round(float(np.mean(sims)), 3),
                rep_sd=round(float(np.std(sims, ddof=1)), 3) if len(sims) > 1 else "",
                per_seed=" ".join(f"{v:.2f}" for v in sims), particles=res.n_particles,
                wall_s=round(res.wall_s, 1))


def _group(r):
    return (r["soil"], r["stage"], r["scenario"], r["setup"], r["preset"], r["overrides"],
            r["measure"], r["response"])


def _key(r):
    return (*_group(r), int(r["run"]))


def main(argv=None):
    from soilcal.config.load import load_soil, read_table

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--soil", required=True)
    ap.add_argument("--stage", required=True)
    ap.add_argument("--runs", default="",
                    help="comma list of run numbers of the table (none: rewrite the page only)")
    ap.add_argument("--scenario", required=True)
    ap.add_argument("--setup", default=None, help="named setup (default: the soil's name)")
    ap.add_argument("--response", required=True, help="column of the printed table")
    ap.add_argument("--measure", required=True, help="response of the scenario")
    ap.add_argument("--preset", default="quick")
    ap.add_argument("--replicates", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--param", action="append", metavar="NAME=VALUE")
    ap.add_argument("--out", default=str(HERE / "results"))
    args = ap.parse_args(argv)
    soil = load_soil(ROOT / "config" / "soils" / f"{args.soil}.yaml", ROOT / "resources")
    table = read_table(soil.table_path(args.stage))
    if args.response not in table.columns:
        raise SystemExit(f"--response: expected a column of {soil.table_path(args.stage)} "
                         f"({', '.join(table.columns)}), got {args.response!r}")
    overrides = _pairs(args.param)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    csv_path, md_path = out / "paper_points.csv", out / "paper_points.md"
    rows = read_rows(csv_path, FIELDS)
    rev = commit()
    for run in (int(x) for x in args.runs.split(",") if x.strip()):
        sel = table[table["run"] == run]
        if len(sel) != 1:
            raise SystemExit(f"--runs: run {run} is not a row of {soil.table_path(args.stage)}")
        new = run_point(soil, args.stage, sel.iloc[0].to_dict(), args, overrides, rev)
        print(new, flush=True)
        rows = [r for r in rows if _key(r) != _key(new)] + [new]
        rows.sort(key=_key)
        write_rows(csv_path, rows, FIELDS)
    md = ["# Paper design points rerun through the DEM scenarios", "",
          f"Machine: {platform.machine()}, {os.cpu_count()} logical CPUs, Python "
          f"{platform.python_version()}.  Last command: `python benchmarks/paper_points.py "
          + " ".join(sys.argv[1:]) + "`.  Rows: `paper_points.csv` (utc and commit per row).",
          "", "Per group: spread (max - min over the runs) of the printed and of the simulated "
          "response, and their Pearson correlation over the runs:", "",
          "| soil | stage | scenario | setup | preset | overrides | measure vs printed | runs | "
          "printed spread | simulated spread | correlation |",
          "|---|---|---|---|---|---|---|---:|---:|---:|---:|"]
    for g in sorted({_group(r) for r in rows}):
        sel = [r for r in rows if _group(r) == g]
        p_spread, s_spread, corr = spread_and_correlation([float(r["printed"]) for r in sel],
                                                          [float(r["simulated"]) for r in sel])
        md.append(f"| {g[0]} | {g[1]} | {g[2]} | {g[3]} | {g[4]} | {g[5]} | {g[6]} vs {g[7]} | {len(sel)} | "
                  f"{p_spread} | {s_spread} | {corr} |")
    md += ["", "Runs:", "", *runs_table(rows, FIELDS)]
    write_page(md_path, md)


if __name__ == "__main__":
    main()
