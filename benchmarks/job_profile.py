"""Where a DEM design-point job's CPU goes: fixed per-job cost against the time loop, and
the time loop split into pair forces, wall contacts, kick-drift and list builds.

Each case is one design point of the workflow's rule dem_point at the quick preset, the
centre of the soil's first DEM stage (the factor midpoints of ``stages[].factors``, the
spec :func:`soilcal.chain.sources.point_spec` builds), run in a fresh process on one thread
(the rule's default, ``simulation.threads``) with :func:`soilcal.chain.sources.simulate`:

* ``heap``: black-soil stage soil-soil, a funnel heap (scenario repose, setup black-soil-stage1);
* ``funnel``: guangxi-cohesive stage bbd, the cohesive funnel heap (the soil's own ``n_particles``);
* ``drum``: xinjiang-vineyard stage pb, the rotating drum's dynamic angle.

Every figure is process CPU time (``time.process_time``), not wall time: the machine is
shared, and a job's CPU is what the workflow pays.  Columns:

* ``import_s``: importing numba, pandas and soilcal's DEM job modules (what every job pays;
  the snakemake script wrapper's own import comes on top);
* ``load_s``: loading the time loop (integrator.run_loop) from Numba's cache;
* ``setup_measure_s``: the rest of the run outside the time loop (packing, walls, the
  other kernels' loading, measurement);
* ``loop_s``: every call of integrator.run_loop; ``steps``, ``builds`` (pair lists, with
  the wall lists), ``wall_builds`` (wall lists alone) and ``full_passes`` (pair passes over
  every listed pair, which write the near list; the other steps visit the near list only:
  integrator.run_loop, "Near list") are the run's counts.  ``full_passes`` includes the
  setup passes, one in each run_loop call that starts from forces not yet evaluated (the
  forces of a phase's initial state, before its first step), so full_passes - steps may be
  positive in a run without a near-list pass; the estimate below charges no more full
  passes to a call than it has steps;
* ``pair_s``, ``walls_s``, ``kick_drift_s``, ``build_s`` (list builds without the cell
  grid and triangle bins), ``grid_s``, ``bins_s``, ``wall_build_s``: estimates of the loop's
  parts.  After a run_loop call (at most every 20 s of loop time) the state is probed on
  copies of every array: one force pass over every listed pair and one over the near list
  (the three colours of pair_forces, then gather and reduce_wall_forces with the wall lists
  emptied), the near one again with the wall lists (the difference is the wall contacts),
  one kick-drift, one pair-list build, its grid and bins alone and one wall-list build, each
  the median of 3-5 repetitions; each call's steps, full passes and builds are charged at
  the last probe's unit costs.  Their sum is an estimate: it differs from ``loop_s`` by the
  probes' sampling (``estimate_over_loop``).

    python benchmarks/job_profile.py [--cases heap,drum,funnel] [--seed 1]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

from _report import commit, read_rows, runs_table, write_page, write_rows

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
OUT = HERE / "results"
CASES = {  # case -> (soil, response)
    "heap": ("black-soil", "accumulation_angle"),
    "funnel": ("guangxi-cohesive", "angle_of_repose"),
    "drum": ("xinjiang-vineyard", "dynamic_angle"),
}
PARTS = ["pair_s", "walls_s", "kick_drift_s", "build_s", "grid_s", "bins_s", "wall_build_s"]
FIELDS = ["utc", "commit", "case", "soil", "stage", "seed", "particles", "steps", "builds",
          "wall_builds", "full_passes", "value", "total_cpu_s", "import_s", "load_s", "setup_measure_s", "loop_s",
          *PARTS, "estimate_over_loop", "load_1min"]
PROBE_EVERY = 20.0


def point(case, seed):
    """The spec of the case's design point (module docstring)."""
    from soilcal.chain.sources import point_spec
    from soilcal.config.load import load_soil

    soil_name, rid = CASES[case]
    soil = load_soil(ROOT / "config" / "soils" / f"{soil_name}.yaml", resources_root=ROOT / "resources")
    stages = soil.data["stages"]
    first = ((soil.data.get("simulation") or {}).get("stages") or [stages[0]["id"]])[0]
    st = next(s for s in stages if s["id"] == first)
    levels = {s: 0.5 * (float(f["low"]) + float(f["high"])) for s, f in st["factors"].items()
              if "low" in f and "high" in f}
    return point_spec(soil, st, levels, 0, seed, responses=[rid])


def _median_cpu(fn, reps, prep):
    import numpy as np

    out = []
    for _ in range(reps):
        a = prep()
        t = time.process_time()
        fn(a)
        out.append(time.process_time() - t)
    return float(np.median(out))


def _probe(names, args):
    """Unit costs (CPU s) of the loop's parts on the state run_loop left (copies of it)."""
    import numpy as np

    from soilcal.dem import integrator as itg
    from soilcal.dem import neighbour as nb

    A = dict(zip(names, args))

    def fresh():
        return {k: (v.copy() if isinstance(v, np.ndarray) else v) for k, v in A.items()}

    def nowall():
        c = fresh()
        c["wcnt_a"][:] = 0
        return c

    dt = A["dt"]
    pair_forces, gather, kick = itg.pair_forces, itg.gather, itg._kick_drift

    cutn = itg.NEAR_SKIN * A["skin"] + A["extra"]

    def pairs(c, mode):
        for col in range(3):
            pair_forces(col, c["xr"], c["vw"], c["pair"], c["codes"], c["box"], c["periodic"], dt,
                        c["start_a"], c["nbr_a"], c["hist_a"], c["act_a"], c["sorder"], c["sgroup"],
                        c["f"], c["t"], c["ovr"], c["mroll"], c["near"], c["ncnt"], mode, cutn)

    def walls(c):
        gather(c["x"], c["v"], c["om"], c["r"], c["inv_m"], c["inv_i"], c["mat"], c["f"], c["t"],
               c["ovr"], c["peak"], c["mroll"], dt, True, c["max_ovr"], c["pair"], c["codes"],
               c["prim_kind"], c["prim_wall"], c["prim_mat"], c["prim_par"], c["wall_vel"],
               c["wall_omega"], c["wall_centre"], c["wnbr_a"], c["wcnt_a"], c["whist_a"], c["wslot"])
        itg.reduce_wall_forces(c["wcnt_a"], c["wnbr_a"], c["wslot"], c["prim_wall"], c["wall_force"],
                               c["wall_torque"])

    def full(c):  # every listed pair (the near list written), then the wall pass
        pairs(c, 1)
        walls(c)

    def near(c):  # the near list's pairs, then the wall pass
        pairs(c, 2)
        walls(c)

    def near_of(prep):  # the near list of the state written first
        def made():
            c = prep()
            pairs(c, 1)
            return c
        return made

    def kick_drift(c):
        kick(c["x"], c["v"], c["om"], c["f"], c["t"], c["r"], c["m"], c["inv_m"], c["inv_i"],
             c["mat"], c["disp"], c["ovr"], c["mroll"], c["xr"], c["vw"], c["gravity"], dt,
             c["box"], c["periodic"], 0.25 * c["skin"] ** 2, True, c["dref"], 0.0)

    def build(c):
        nb.build_lists(c["x"], c["r"], c["box"], c["periodic"], c["skin"], c["extra"], c["cell_start"],
                       c["cell_idx"], c["cell_of"], c["cpos"], c["start_a"], c["nbr_a"], c["hist_a"],
                       c["act_a"], c["start_b"], c["nbr_b"], c["hist_b"], c["act_b"], c["groups"],
                       c["sorder"], c["sgroup"], c["scratch"], c["hits"], False, c["perm"], c["prim_kind"],
                       c["prim_par"], c["wcell_start"], c["wcell_idx"], c["glob"], c["wnbr_a"], c["wcnt_a"],
                       c["whist_a"], c["wnbr_b"], c["wcnt_b"], c["whist_b"])

    def grid(c):
        nb._grid(c["x"], c["r"], c["box"], c["periodic"], c["skin"], c["extra"], c["cell_start"],
                 c["cell_idx"], c["cell_of"], c["cpos"])

    def grid_bins(c):
        nb._grid_and_bins(c["x"], c["r"], c["box"], c["periodic"], c["skin"], c["extra"], c["cell_start"],
                          c["cell_idx"], c["cell_of"], c["cpos"], c["prim_kind"], c["prim_par"],
                          c["wcell_start"], c["wcell_idx"], c["glob"])

    def wall_build(c):
        nb.build_wall_lists(c["x"], c["r"], c["box"], c["periodic"], c["skin"], c["extra"], c["cell_start"],
                            c["cell_idx"], c["cell_of"], c["cpos"], c["prim_kind"], c["prim_par"],
                            c["wcell_start"], c["wcell_idx"], c["glob"], c["wnbr_a"], c["wcnt_a"],
                            c["whist_a"], c["wnbr_b"], c["wcnt_b"], c["whist_b"])

    full_s = _median_cpu(full, 5, nowall)
    f, fw = _median_cpu(near, 5, near_of(fresh)), _median_cpu(near, 5, near_of(nowall))
    g, gb, b = _median_cpu(grid, 3, fresh), _median_cpu(grid_bins, 3, fresh), _median_cpu(build, 3, fresh)
    return {"pair_s": fw, "pair_full_s": full_s, "walls_s": max(f - fw, 0.0),
            "kick_drift_s": _median_cpu(kick_drift, 5, fresh),
            "build_s": max(b - gb, 0.0), "grid_s": g, "bins_s": max(gb - g, 0.0),
            "wall_build_s": _median_cpu(wall_build, 3, fresh)}


def one(case, seed) -> dict:
    """Profile one case in this process (a fresh one: the import time is part of it)."""
    t0 = time.process_time()
    import inspect

    import numba

    from soilcal.chain.sources import simulate
    from soilcal.dem import integrator as itg
    import soilcal.dem.scenarios  # noqa: F401  - the scenario registry a job imports
    t_import = time.process_time() - t0
    numba.set_num_threads(1)
    sp = point(case, seed)
    real = itg.run_loop
    names = list(inspect.signature(real.py_func).parameters)
    acc = {k: 0.0 for k in ["loop_s", "load_s", "steps", "builds", "wall_builds", "full_passes",
                            "probe_s", *PARTS]}
    state = {"unit": None, "since": float("inf"), "pending": [], "calls": 0}

    def charge(unit, steps, builds, wall_builds, fulls):
        fulls = min(fulls, steps)  # a call's first pass of the forces as they stand is no step
        acc["pair_s"] += fulls * unit["pair_full_s"] + (steps - fulls) * unit["pair_s"]
        for k in ("walls_s", "kick_drift_s"):
            acc[k] += steps * unit[k]
        for k in ("build_s", "grid_s", "bins_s"):
            acc[k] += builds * unit[k]
        acc["wall_build_s"] += wall_builds * unit["wall_build_s"]

    def timed(*args):
        fstate = dict(zip(names, args))["fstate"]
        b0, w0, p0 = fstate[1], fstate[2], fstate[4]
        if state["calls"] == 0:
            t = time.process_time()
            real.compile(tuple(numba.typeof(a) for a in args))
            acc["load_s"] = time.process_time() - t
        state["calls"] += 1
        t = time.process_time()
        done = real(*args)
        spent = time.process_time() - t
        acc["loop_s"] += spent
        counts = (done, fstate[1] - b0, fstate[2] - w0, fstate[4] - p0)
        acc["steps"] += counts[0]
        acc["builds"] += counts[1]
        acc["wall_builds"] += counts[2]
        acc["full_passes"] += counts[3]
        state["since"] += spent
        if done > 50 and state["since"] >= PROBE_EVERY:
            t = time.process_time()
            state["unit"] = _probe(names, args)
            acc["probe_s"] += time.process_time() - t
            state["since"] = 0.0
            for c in state["pending"]:
                charge(state["unit"], *c)
            state["pending"].clear()
        if state["unit"] is None:
            state["pending"].append(counts)
        else:
            charge(state["unit"], *counts)
        return done

    itg.run_loop = timed
    t = time.process_time()
    df = simulate(sp, threads=1, rev="-")
    sim_s = time.process_time() - t - acc["probe_s"]
    est = sum(acc[k] for k in PARTS)
    row = {"case": case, "soil": sp["soil"], "stage": sp["stage"], "seed": seed,
           "particles": int(df["particles"].iloc[0]), "steps": int(acc["steps"]),
           "builds": int(acc["builds"]), "wall_builds": int(acc["wall_builds"]),
           "full_passes": int(acc["full_passes"]),
           "value": f"{float(df['value'].iloc[0]):.4f}",
           "total_cpu_s": round(t_import + sim_s, 2), "import_s": round(t_import, 2),
           "load_s": round(acc["load_s"], 2),
           "setup_measure_s": round(sim_s - acc["loop_s"] - acc["load_s"], 2),
           "loop_s": round(acc["loop_s"], 2),
           **{k: round(acc[k], 2) for k in PARTS},
           "estimate_over_loop": round(est / acc["loop_s"], 2) if acc["loop_s"] else ""}
    return row


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--one", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.one:
        print(json.dumps(one(args.one, args.seed)))
        return 0
    csv_path, md_path = OUT / "job_profile.csv", OUT / "job_profile.md"
    rows = read_rows(csv_path, FIELDS)
    rev = commit()
    for case in args.cases.split(","):
        if case not in CASES:
            raise SystemExit(f"--cases: one of {', '.join(CASES)}, not {case!r}")
        res = subprocess.run([sys.executable, __file__, "--one", case, "--seed", str(args.seed)],
                             capture_output=True, text=True, check=True)
        row = json.loads(res.stdout.strip().splitlines()[-1])
        row.update(utc=time.strftime("%Y-%m-%d %H:%M", time.gmtime()), commit=rev,
                   load_1min=f"{os.getloadavg()[0]:.2f}")
        rows.append(row)
        write_rows(csv_path, rows, FIELDS)
        write_page(md_path, page(rows, argv))
        print(json.dumps(row))
    return 0


def page(rows, argv) -> list[str]:
    """The lines of job_profile.md: every run, then the shares of each run's CPU."""
    shares = []
    for r in rows:
        tot, loop = float(r["total_cpu_s"]), float(r["loop_s"])
        est = sum(float(r[k]) for k in PARTS) or 1.0
        shares.append({"utc": r["utc"], "case": r["case"], "total_cpu_s": r["total_cpu_s"],
                       "fixed %": f"{100 * (tot - loop) / tot:.1f}", "loop %": f"{100 * loop / tot:.1f}",
                       **{f"{k[:-2]} %": f"{100 * float(r[k]) / est:.1f}" for k in PARTS},
                       "steps per build": f"{int(r['steps']) / max(1, int(r['builds'])):.1f}"})
    lines = ["# Where a DEM design-point job's CPU goes", "",
             f"Machine: {platform.machine()}, {os.cpu_count()} logical CPUs, Python "
             f"{platform.python_version()}.  Last command: `python benchmarks/job_profile.py "
             f"{' '.join(argv if argv is not None else sys.argv[1:])}`.  Rows: `job_profile.csv`.  "
             "Process CPU seconds on one thread (other jobs shared the cores: `load_1min`); "
             "the script's docstring says how each column is measured.", "",
             "## Runs", "", *runs_table(rows, FIELDS), "",
             "## Shares", "",
             "Fixed: the job's CPU outside the time loop (imports, cache loading, set-up, "
             "measurement); loop parts as shares of their estimated sum:", "",
             *runs_table(shares, list(shares[0]) if shares else []), ""]
    return lines


if __name__ == "__main__":
    sys.exit(main())
