"""Scale on paper: what a full DEM calibration of each soil costs at the ``paper`` preset.

Nothing is simulated.  For every soil config with a ``simulation`` block
(``config/soils/*.yaml``, loaded with :func:`soilcal.config.load.load_soil`), the DEM jobs
of its calibration at the papers' recipe (``simulation.design: recipe``, the default) are
formed with the chain's own helpers and sized with :func:`soilcal.dem.cost.estimate_spec`,
once with every scenario at the ``paper`` preset and once at ``quick``.

Jobs counted (one job = one :func:`soilcal.chain.sources.point_spec`, each response group
run ``simulation.replicates`` times):

* **design stages** the DEM source runs (:func:`soilcal.chain.derive.dem_stage_ids`), one job
  per design point: a Plackett-Burman screening's rows (its ``runs``); a steepest-ascent path
  of ``simulation.path.steps`` steps, else the config's level count, else
  :data:`soilcal.chain.derive.DEFAULT_STEPS`; a Box-Behnken design of 2k(k - 1) +
  ``center_points`` runs.  A stage derived from an earlier DEM stage (``from_stage``) gets
  its factors from the DEM results, which do not exist on paper: the config's stage (the
  paper's factors and levels) stands in for it, so a path keeps the paper's factors and a
  Box-Behnken design the paper's k (the screening may select between
  ``simulation.screening.min_factors`` and ``max_factors``).  The points' DEM parameters
  (:func:`soilcal.chain.sources.point_spec`) are those of the config's design, which sets
  each point's time step through its stiffness, restitution and surface energy;
* **verification**: every optimisation case of those stages
  (:func:`soilcal.chain.verify.verification_cases`), ``simulation.verification.replicates``
  seeds (default 4) at the stage's centre levels (standing in for the calibrated set), the
  responses the case aims at; the second round (:mod:`soilcal.chain.refine`, at most as many
  jobs again, only where the first round misses a target) and the measured-data loop
  (:mod:`soilcal.loop`, sized by its diagnosis) depend on results and are not counted;
* **tool tests**: the soil's ``measurements`` conditions
  (:func:`soilcal.config.measurements.conditions`), one job per distinct scenario, setup and
  parameters (conditions that need the same runs share one, as
  :func:`soilcal.chain.verify.tool_key` merges them), each ``replicates`` runs of one seed.

Cost: spheres x steps summed over each run's phases (the steps are the estimate's upper
bound of the simulated time), at the measured one-thread throughput
:data:`soilcal.dem.cost.THROUGHPUT` (``benchmarks/results/throughput.md``) and the model's
per-run and start-up overheads (:meth:`soilcal.dem.cost.Cost.wall_s`); core-hours on one
thread per job.  Cluster: N nodes of 32 cores and ``--node-gb`` GB each; the stages run one
after another (each is derived from the one before; verification and tool tests follow the
calibration), the jobs of a stage side by side; a stage takes the longer of its longest job
and its summed job time over the job slots (list scheduling, no queue wait), with every
job of the stage on the same thread count, 1, 2, 4 or 8, whichever finishes the stage first
(t threads run at 1 + (t - 1) x :data:`soilcal.dem.cost.PARALLEL_EFFICIENCY` times one;
jobs the engine keeps on one thread, under 1024 spheres, take one core).  A job needing
more memory than a node is flagged and left out of the cluster time.

Writes ``benchmarks/results/paper_scale.csv`` (one row per soil, preset and job group) and
``paper_scale.md``; notes below the page's marker are kept.

    python benchmarks/paper_scale.py
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

from _report import commit, write_page, write_rows

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
OUT = HERE / "results"
NODES = (1, 4, 16, 64)
CORES = 32
THREADS = (1, 2, 4, 8)
FIELDS = ["utc", "commit", "soil", "preset", "group", "stage", "kind", "jobs", "runs",
          "particles_min", "particles_max", "steps_min", "steps_max", "sim_time_max_s",
          "particle_steps", "core_hours", "job_wall_max_h", "mem_max_gb", "error"]


def _stage_points(soil, stage: dict, sim: dict):
    """(run, levels) of every design point of a DEM stage on paper (module docstring)."""
    import pandas as pd

    from soilcal.chain import derive
    from soilcal.chain.sources import design_points
    from soilcal.chain.stage import design_frame

    st = dict(stage)
    if st["kind"] == "steepest_ascent":
        n_cfg = {len(f.get("levels") or []) for f in st["factors"].values()} - {0}
        steps = int((sim.get("path") or {}).get("steps")
                    or (n_cfg.pop() if len(n_cfg) == 1 else derive.DEFAULT_STEPS))
        factors = {}
        for s, f in st["factors"].items():
            lv = list(f.get("levels") or [])
            if len(lv) != steps:
                raise ValueError(f"stage {st['id']}: factor {s} has {len(lv)} levels on paper, "
                                 f"the path {steps} steps")
            factors[s] = dict(f, levels=lv)
        st["factors"] = factors
    df, _ = design_frame(st, None)
    return st, design_points(st, pd.DataFrame(df))


def _with_preset(spec: dict, preset: str) -> dict:
    out = json.loads(json.dumps(spec, default=str))
    for rs in out["responses"].values():
        rs["preset"] = preset
    return out


def _centre_levels(stage: dict) -> dict:
    from soilcal.chain.derive import _centre

    if stage["kind"] == "steepest_ascent":
        return {s: float(f["levels"][len(f["levels"]) // 2]) for s, f in stage["factors"].items()}
    return {s: _centre(f) for s, f in stage["factors"].items()}


def soil_groups(soil, preset: str) -> list[dict]:
    """The job groups of a soil's calibration at ``preset``: design stages, verification,
    tool tests; each ``dict(group, stage, kind, costs=[Cost...], error)``."""
    from soilcal.chain import derive, verify
    from soilcal.chain.sources import point_spec
    from soilcal.config.measurements import conditions
    from soilcal.dem import cost

    data = soil.data
    sim = data.get("simulation") or {}
    seed = int(data.get("seed", 0))
    reps = int(sim.get("replicates", 1))
    groups = []
    stages = derive.dem_stage_ids(data)
    for sid in stages:
        stage = soil.stage(sid)
        g = dict(group="design", stage=sid, kind=stage["kind"], costs=[], error="")
        try:
            st, pts = _stage_points(soil, stage, sim)
            if stage["kind"] == "box_behnken" and "from" in derive.dependencies(data, sid):
                k = len(st["factors"])
                assert len(pts) == 2 * k * (k - 1) + int(st.get("center_points", 0))
            for i, (run, lev) in enumerate(pts):
                spec = point_spec(soil, st, lev, run, seed + reps * i, reps)
                g["costs"].append(cost.estimate_spec(_with_preset(spec, preset)))
        except Exception as exc:  # noqa: BLE001 - reported in the row
            g["error"] = f"{type(exc).__name__}: {exc}"
        groups.append(g)
    v = verify.verify_settings(data)
    g = dict(group="verification", stage=" ".join(stages), kind="", costs=[], error="")
    try:
        for sid, case in verify.verification_cases(data, stages):
            stage = soil.stage(sid)
            goals = next(c for c in stage["optimise"]["cases"] if c["id"] == case)["goals"]
            lev = _centre_levels(stage)
            for k in range(int(v["replicates"])):
                spec = point_spec(soil, stage, lev, k, seed + int(v["seed_offset"]) + k, 1,
                                  responses=list(goals))
                g["costs"].append(cost.estimate_spec(_with_preset(spec, preset)))
    except Exception as exc:  # noqa: BLE001
        g["error"] = f"{type(exc).__name__}: {exc}"
    groups.append(g)
    g = dict(group="tools", stage="", kind="", costs=[], error="")
    try:
        seen = {}
        for c in conditions(soil):
            key = json.dumps([c.scenario, c.setup, c.params], sort_keys=True, default=str)
            seen.setdefault(key, c)
        for c in seen.values():
            # the job's runs differ only in their seed: one estimate, replicates times
            g["costs"].append(cost.estimate(c.scenario, c.setup, cost_params(soil, c), preset,
                                            int(c.replicates),
                                            f"{soil.name}/{c.measurement}/{c.row}"))
    except Exception as exc:  # noqa: BLE001
        g["error"] = f"{type(exc).__name__}: {exc}"
    if g["costs"] or g["error"]:
        groups.append(g)
    return groups


def cost_params(soil, cond) -> dict:
    """DEM parameters of a tool condition: the soil's printed values and block params, the
    condition's own parameters over them (the calibrated set is not known on paper)."""
    from soilcal.dem.scenarios.base import DemParams, stage_params

    sim = soil.data.get("simulation") or {}
    stage = soil.stage(cond.stage) if cond.stage else soil.stages[-1]
    dem = stage_params(soil, stage["id"], _centre_levels(stage),
                       params=dict(sim.get("params") or {}))
    return DemParams.from_mapping(dict(cond.params or {}), "<tool>", base=dem).as_dict()


def wave_wall(costs, nodes: int, node_gb: float) -> tuple[float, int, int]:
    """(hours, threads, jobs left out) of one stage on ``nodes`` nodes (module docstring):
    the jobs that fit a node's memory, on the thread count that finishes them first."""
    fit = [c for c in costs if c.mem_mb / 1e3 <= node_gb]
    if not fit:
        return math.nan, 0, len(costs)
    mem_gb = max(c.mem_mb for c in fit) / 1e3
    best = (math.inf, 1)
    for t in THREADS:
        walls = [c.wall_s(threads=t) for c in fit]
        slots = nodes * max(1, min(CORES // t, int(node_gb // mem_gb)))
        h = max(max(walls), sum(walls) / slots) / 3600.0
        if h < best[0] * (1 - 1e-9):
            best = (h, t)
    return best[0], best[1], len(costs) - len(fit)


def main(argv=None) -> int:
    from soilcal.config.load import load_soil

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--node-gb", type=float, default=128.0)
    args = ap.parse_args(argv)
    rev = commit()
    utc = time.strftime("%Y-%m-%d %H:%M", time.gmtime())
    rows, cluster = [], []
    for path in sorted((ROOT / "config" / "soils").glob("*.yaml")):
        soil = load_soil(path, resources_root=ROOT / "resources")
        if not soil.data.get("simulation"):
            continue
        for preset in ("paper", "quick"):
            groups = soil_groups(soil, preset)
            for g in groups:
                cs = g["costs"]
                row = dict(utc=utc, commit=rev, soil=soil.name, preset=preset, group=g["group"],
                           stage=g["stage"], kind=g["kind"], jobs=len(cs),
                           runs=sum(c.runs for c in cs), error=g["error"])
                if cs:
                    row.update(
                        particles_min=min(c.n_particles for c in cs),
                        particles_max=max(c.peak_particles for c in cs),
                        steps_min=min(c.steps for c in cs), steps_max=max(c.steps for c in cs),
                        sim_time_max_s=round(max(c.sim_time_s for c in cs), 3),
                        particle_steps=f"{sum(c.particle_steps for c in cs):.4g}",
                        core_hours=f"{sum(c.wall_s() for c in cs) / 3600:.4g}",
                        job_wall_max_h=f"{max(c.wall_s() for c in cs) / 3600:.4g}",
                        mem_max_gb=f"{max(c.mem_mb for c in cs) / 1e3:.4g}")
                rows.append(row)
            for nodes in NODES:
                total, threads, out = 0.0, [], 0
                for g in groups:
                    if not g["costs"]:
                        continue
                    h, t, left = wave_wall(g["costs"], nodes, args.node_gb)
                    out += left
                    total += 0.0 if math.isnan(h) else h
                    threads.append(str(t) if t else "-")
                cluster.append(dict(soil=soil.name, preset=preset, nodes=nodes,
                                    hours=total, threads="/".join(threads), left_out=out))
    write_rows(OUT / "paper_scale.csv", rows, FIELDS)
    write_page(OUT / "paper_scale.md", page(rows, cluster, args, rev, utc))
    return 0


def _h(x) -> str:
    x = float(x)
    if not math.isfinite(x):
        return "n/a"
    if x < 1:
        return f"{x * 60:.0f} min"
    if x < 48:
        return f"{x:.1f} h"
    if x < 24 * 730:
        return f"{x / 24:.0f} d"
    return f"{x / 24 / 365:.0f} yr"


def measured() -> dict:
    """What the page extrapolates from, read from ``throughput.csv``: the one-thread
    whole-run rates, the share of the bound's steps the runs took, the two-thread speed-up."""
    import csv

    import numpy as np

    path = OUT / "throughput.csv"
    if not path.exists():
        return {}
    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    one = [r for r in rows if r["threads"] == "1" and r["steps_bound"]
           and r["case"] not in ("incline-rolling", "memory", "threads-bed")]
    out = {}
    if one:
        rates = [float(r["particle_steps_per_s"]) for r in one]
        share = {}
        for r in one:
            share.setdefault(r["case"], []).append(float(r["steps"]) / float(r["steps_bound"]))
        share = {k: max(v) for k, v in share.items()}
        out.update(rate_min=min(rates), rate_max=max(rates), rate_median=float(np.median(rates)),
                   share=share,
                   when=min(r["utc"] for r in one) + " to " + max(r["utc"] for r in one))
    bed = {}
    for r in rows:
        if r["case"] == "threads-bed":
            bed.setdefault(r["utc"], {})[r["threads"]] = r
    out["speedups"] = [(utc, float(b["1"]["engine_s"]) / float(b["2"]["engine_s"]),
                        b["2"]["load_1min"], b["2"].get("nice") or "0")
                       for utc, b in sorted(bed.items()) if "1" in b and "2" in b]
    return out


def page(rows, cluster, args, rev, utc) -> list[str]:
    from soilcal.dem import cost

    m = measured()
    share = m.get("share", {})
    share_txt = ", ".join(f"{k} {100 * v:.0f} %" for k, v in share.items())
    rate_txt = (f" (measured {m['when']} UTC: {m['rate_min']:.3g} to {m['rate_max']:.3g}, "
                f"median {m['rate_median']:.3g})" if m.get("rate_min") else "")
    speed_txt = ", ".join(f"{q:.2f} times at load {load}"
                          for utc, q, load, nice in m.get("speedups", [])) or "n/a"

    lines = [
        "# Scale on paper: the DEM calibration of each soil at the paper preset", "",
        f"Generated {utc} UTC at commit {rev} by `python benchmarks/paper_scale.py"
        f"{'' if args.node_gb == 128.0 else f' --node-gb {args.node_gb:g}'}` (nothing simulated; "
        "rows in `paper_scale.csv`).  Job sizes from `soilcal.dem.cost` "
        "(`src/soilcal/dem/cost.py`: particle counts from the scenarios' own sizing, time "
        "steps from the engine's rule, simulated time an upper bound of each run); how the "
        "jobs are counted is in the docstring of `benchmarks/paper_scale.py`.", "",
        "## Assumptions", "",
        f"* Throughput {cost.THROUGHPUT:.3g} particle-steps per second on one thread "
        f"(`soilcal.dem.cost.THROUGHPUT`), about 60 % of the lowest whole-run rate of the "
        f"quick-preset scenario runs of `throughput.md`{rate_txt}; 500 to 6,500 spheres of "
        "near-uniform size, on a shared two-core machine.  Runs of the papers' size "
        "distributions (radii 1:2 to 1:8) "
        "list more partners per sphere, because the neighbour skin follows the largest sphere: "
        "the memory model counts those list slots, the rate does not, so their time is likely "
        "higher than shown.",
        f"* Thread speed-up 1 + (t - 1) x {cost.PARALLEL_EFFICIENCY:g} "
        "(`soilcal.dem.cost.PARALLEL_EFFICIENCY`): two threads ran a 32,000-sphere bed 1.86 "
        "times as fast as one on the shared machine at load 1.5 (`throughput.md`, notes), "
        "`settle.md` has 1.56-1.94 times for 5,000-20,000 spheres; under load 5-7 two "
        f"threads ran slower than one ({speed_txt}), so each job needs the cores of its "
        "threads to itself.  Beyond two threads an extrapolation, likely optimistic.",
        f"* Per job: start-up {cost.STARTUP_S:g} s and {cost.RUN_OVERHEAD_S:g} s per run "
        "(measured on small runs; insertion and measurement of million-sphere runs take "
        "longer), no cold kernel compilation, no queue wait.",
        "* Simulated time: the upper bound of each run (every settling phase to its time "
        "limit, a compression to the floor): a run that comes to rest earlier is shorter.  "
        f"The quick runs of `throughput.md` took this share of their bound's steps: {share_txt}"
        " (the bench-top heaps came to rest long before `max_settle_time`; the soil bins ran "
        "their settling to the limit).",
        f"* Cluster: N nodes of {CORES} cores and {args.node_gb:g} GB; the stages of a soil one "
        "after another, the jobs of a stage side by side on t threads each (the t that "
        "finishes the stage first, listed per stage: design stages, verification, tools).",
        "* Design stages derived from DEM results use the config's (the paper's) factors "
        "and levels; verification at the stage's centre levels; the second verification "
        "round and the measured-data loop are not counted.", "",
        "## Jobs and cost per soil", "",
        "particles: spheres of a job's measured phase (min) to the most alive at once (max); "
        "steps: bound per run; particle-steps summed over the group's jobs and runs; "
        "core-hours on one thread per job; memory: the largest job's request "
        "(`Cost.mem_mb`).", ""]
    fields = ["soil", "preset", "group", "stage", "kind", "jobs", "runs", "particles_min",
              "particles_max", "steps_min", "steps_max", "sim_time_max_s", "particle_steps",
              "core_hours", "job_wall_max_h", "mem_max_gb", "error"]
    from _report import runs_table

    lines += runs_table(rows, fields)
    lines += ["", "## Totals", "", "| soil | preset | jobs | runs | particle-steps | "
              "core-hours | largest job (1 thread) | largest memory |",
              "|---|---|---:|---:|---:|---:|---:|---:|"]
    tot = {}
    for r in rows:
        key = (r["soil"], r["preset"])
        t = tot.setdefault(key, dict(jobs=0, runs=0, ps=0.0, ch=0.0, wall=0.0, mem=0.0))
        t["jobs"] += int(r["jobs"])
        t["runs"] += int(r["runs"])
        if r.get("particle_steps"):
            t["ps"] += float(r["particle_steps"])
            t["ch"] += float(r["core_hours"])
            t["wall"] = max(t["wall"], float(r["job_wall_max_h"]))
            t["mem"] = max(t["mem"], float(r["mem_max_gb"]))
    for (soil, preset), t in tot.items():
        lines.append(f"| {soil} | {preset} | {t['jobs']} | {t['runs']} | {t['ps']:.3g} | "
                     f"{t['ch']:.3g} | {_h(t['wall'])} | {t['mem']:.3g} GB |")
    lines += ["", f"## Wall time on a cluster of N nodes x {CORES} cores", "",
              "Per soil (alone on the cluster).  `threads`: per job, for N = 1, 4, 16, 64 "
              "(separated by `;`), per stage in order (design stages, verification, tools; "
              "separated by `/`; `-`: no job of the stage fits a node).  `left out`: jobs "
              "larger than a node's memory, not in the time.", "",
              "| soil | preset | " + " | ".join(f"N = {n}" for n in NODES)
              + " | threads (N = 1 .. 64) | left out |",
              "|---|---|" + "---:|" * len(NODES) + "---|---:|"]
    by = {}
    for c in cluster:
        by.setdefault((c["soil"], c["preset"]), []).append(c)
    for (soil, preset), cs in by.items():
        cs = sorted(cs, key=lambda c: c["nodes"])
        lines.append(f"| {soil} | {preset} | " + " | ".join(_h(c["hours"]) for c in cs)
                     + " | " + "; ".join(c["threads"] for c in cs) + f" | {cs[0]['left_out']} |")
    return lines


if __name__ == "__main__":
    sys.exit(main())
