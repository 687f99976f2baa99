"""Engine throughput of whole scenario runs, and the cost model's estimates beside them.

Each case is one scenario run at the quick preset (some at a reduced size, so that each
takes seconds to a minute), in a fresh process on the threads asked for (one by default):
the process imports soilcal and runs a one-sphere incline first (kernel loading, the
``startup_s`` column), then the case.  Every call of the engine's time loop
(:meth:`soilcal.dem.engine.Simulation.run`) is counted: steps, spheres x steps, simulated
time and the time spent inside it.  Beside each run the estimate of
:func:`soilcal.dem.cost.estimate` for the same scenario, setup, parameters and preset:
spheres (the run's measured phase; the most alive at once), steps and simulated time
(upper bounds), time step and memory.

Columns of ``benchmarks/results/throughput.csv`` (one row per case, thread count and run:
reruns add rows, so the scatter of a shared machine stays visible):

* ``particles_est`` / ``particles``: spheres of the run's measured phase (``Result.n_particles``);
  ``peak_est`` / ``peak``: the most spheres in one simulation;
* ``steps_bound`` / ``steps``, ``sim_time_bound_s`` / ``sim_time_s``: every step of the run
  (settling included) and the simulated time they cover;
* ``dt_est`` / ``dt``: the smallest time step;
* ``wall_s``: the run (insertion, time loop, measurement); ``engine_s``: inside the time
  loop; ``particle_steps``; ``particle_steps_per_s`` = particle_steps / wall_s (what a job
  pays) and ``engine_particle_steps_per_s`` = particle_steps / engine_s;
* ``rss_base_mb``: resident memory after the imports and the one-sphere run;
  ``rss_mb``: the process's peak; ``mem_est_mb``: :attr:`soilcal.dem.cost.Cost.mem_mb`;
* ``bed_est`` / ``bed``: soil bins, spheres of the bed trimmed to its fill height;
  ``bed_fraction``: their number x mean sphere volume / (length x width x fill height);
  ``wall_slots``: the widest wall list the engine needed;
* ``nice``: the priority change the case ran with (``--nice``); ``load_1min``: the
  machine's load average when the case ended.

The ``threads-bed`` case runs one bed (a soil bin of about 32,000 spheres) in bursts of 100
steps on 1, 2, 2 and 1 threads, eight times: the parallel efficiency of the second thread.
On a machine shared with other jobs a two-thread burst that finds the other core busy waits
at every parallel region; run it with ``--nice -10`` (as root) so that it gets both cores.
The ``memory`` case fills a soil bin of about 94,000 spheres and runs it 400 steps, for the
memory per sphere (peak RSS less the base over the spheres) against the cost model's
allocated bytes (``bytes_per_particle``, allocation-based, column ``mem_est_mb``).

    python benchmarks/throughput.py                      # every case, one thread
    python benchmarks/throughput.py --cases threads-bed --nice -10
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
OUT = HERE / "results"
FIELDS = ["utc", "commit", "case", "scenario", "setup", "preset", "overrides", "threads",
          "particles_est", "particles", "peak_est", "peak", "steps_bound", "steps",
          "sim_time_bound_s", "sim_time_s", "dt_est", "dt", "wall_s", "engine_s",
          "particle_steps", "particle_steps_per_s", "engine_particle_steps_per_s",
          "startup_s", "rss_base_mb", "rss_mb", "mem_est_mb", "bed_est", "bed", "bed_fraction",
          "wall_slots", "nice", "load_1min"]

# name -> (scenario, setup, setup overrides, DEM parameters: a soil's density or a module's
# paper_params)
CASES = {
    "repose-funnel": ("repose", "black-soil-stage2", {"load_mass": 0.1}, {"soil_density": 1560.0}),
    "repose-cylinder": ("repose", "cinnamon-soil", {"n_particles": 500}, {}),
    "drum": ("drum", "xinjiang-vineyard", {"n_particles": 500, "spin_time": 2.0,
                                          "transient_time": 0.5}, {"soil_density": 1757.567}),
    "compression": ("compression", "guangxi-cohesive", {"n_particles": 500},
                    {"soil_density": 1802.0}),
    "incline-rolling": ("incline", "yangtze-rolling", {}, {}),
    "bulldozing": ("bulldozing", "plate-line", {}, "paper_params"),
    "furrow": ("furrow", "yangtze-opener", {}, "paper_params"),
    "rotary": ("rotary", "rpm-250", {}, "paper_params"),
    "memory": ("memory", "", {}, {}),
    "threads-bed": ("threads", "", {}, {}),
}
THREAD_REPEATS = 8  # blocks of the threads-bed case (bursts on 1, 2, 2, 1 threads)
BURST = 100  # steps per burst
THREAD_WARM = 600  # steps of the bed before the bursts


def _rss_mb() -> float:
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _counting():
    """Wrap Simulation.run to count steps, particle-steps, simulated and loop time."""
    from soilcal.dem.engine import Simulation

    acc = dict(steps=0, ps=0.0, sim_t=0.0, engine_s=0.0, peak=0, dt=float("inf"), kw=0, ns=[])
    # ns: spheres of each Simulation in the order they first ran (tagged on the object: ids
    # of freed simulations are reused)
    orig = Simulation.run

    def run(self, steps, *a, **k):
        t = time.perf_counter()
        done = orig(self, steps, *a, **k)
        acc["engine_s"] += time.perf_counter() - t
        acc["steps"] += done
        acc["ps"] += float(self.n) * done
        acc["sim_t"] += done * self.dt
        acc["peak"] = max(acc["peak"], self.n)
        acc["dt"] = min(acc["dt"], self.dt)
        acc["kw"] = max(acc["kw"], self._kw)
        if done and not hasattr(self, "_throughput_k"):
            self._throughput_k = len(acc["ns"])
            acc["ns"].append(int(self.n))
        return done

    Simulation.run = run
    return acc


def _params(spec, mod):
    from soilcal.dem.scenarios.base import DemParams

    return mod.paper_params() if spec == "paper_params" else DemParams.from_mapping(spec)


def _memory_case(acc, threads):
    """A lattice-filled soil bin of about 94,000 spheres, 400 steps from the fill."""
    import numpy as np

    from soilcal.dem import cost
    from soilcal.dem.scenarios import soilbin
    from soilcal.dem.scenarios.base import DemParams

    spec = soilbin.BinSpec(length=1.0, width=0.37, height=0.21 / soilbin.FILL_FACTOR,
                           radius=0.0051 / 1.1, settle_time=0.1)
    params = DemParams()
    t0 = time.perf_counter()
    x, r = soilbin.fill_bin(spec, np.random.default_rng(0), "<memory>")
    sim = soilbin.new_sim(spec, params, soilbin.soil_time_step(spec, params), "<memory>")
    sim.add_particles(x, r, "soil")
    sim.run(400)
    wall = time.perf_counter() - t0
    n = len(r)
    bpp = cost.bytes_per_particle(cost.pair_slots(spec.dist, spec.skin_fraction * spec.r_max))
    return dict(scenario="soil bin (fill + 400 steps)", setup="1.0 x 0.37 x 0.16 m, r 4.6 mm",
                particles=n, particles_est=cost.lattice_sites(
                    (0, 0, 0), (spec.length, spec.width, soilbin.FILL_FACTOR * spec.height),
                    spec.r_max),
                peak=n, peak_est=n, steps=acc["steps"], steps_bound=400,
                wall_s=wall, mem_est_mb=int(cost.BASE_MB + n * bpp / 1e6),
                dt=acc["dt"], dt_est=soilbin.soil_time_step(spec, params))


def _threads_case(acc) -> list[dict]:
    """One and two threads on the same bed: a lattice-filled soil bin of about 32,000
    spheres settles ``THREAD_WARM`` steps, then ``THREAD_REPEATS`` blocks of bursts of
    ``BURST`` steps on 1, 2, 2 and 1 threads (the order cancels the drift of the cost per
    step as the bed settles); each row sums the bursts of its thread count."""
    import numba
    import numpy as np

    from soilcal.dem.scenarios import soilbin
    from soilcal.dem.scenarios.base import DemParams

    spec = soilbin.BinSpec(length=0.5, width=0.25, height=0.12 / soilbin.FILL_FACTOR,
                           radius=0.0042 / 1.1, settle_time=0.1)
    params = DemParams()
    x, r = soilbin.fill_bin(spec, np.random.default_rng(0), "<threads>")
    sim = soilbin.new_sim(spec, params, soilbin.soil_time_step(spec, params), "<threads>")
    sim.add_particles(x, r, "soil")
    numba.set_num_threads(2)
    sim.run(THREAD_WARM)
    total = {1: 0.0, 2: 0.0}
    ratios = []
    for _ in range(THREAD_REPEATS):
        block = {1: 0.0, 2: 0.0}
        for t in (1, 2, 2, 1):
            numba.set_num_threads(t)
            t0 = time.perf_counter()
            sim.run(BURST)
            block[t] += time.perf_counter() - t0
        ratios.append(block[1] / block[2])
        for t in (1, 2):
            total[t] += block[t]
    n = sim.n
    note = (f"{THREAD_REPEATS} blocks of {BURST}-step bursts on 1, 2, 2, 1 threads after "
            f"{THREAD_WARM} steps; block speed-ups " + " ".join(f"{q:.2f}" for q in ratios))
    rows = []
    for t in (1, 2):
        k = 2 * THREAD_REPEATS * BURST
        rows.append(dict(case="threads-bed", scenario="soil bin (settling bed)",
                         setup="0.5 x 0.25 x 0.09 m, r 3.8-4.2 mm", preset="", threads=t,
                         overrides=note, particles=n, peak=n, steps=k, wall_s=total[t],
                         engine_s=total[t], particle_steps=n * k, dt=sim.dt))
    return rows


def one_case(name: str, threads: int) -> dict:
    """Run one case in this process; the row's measured and estimated fields."""
    import numba

    t0 = time.perf_counter()
    from soilcal.dem import cost
    from soilcal.dem.scenarios import get, incline
    from soilcal.dem.scenarios.base import DemParams, merge_setup

    numba.set_num_threads(threads)
    incline.run(merge_setup(incline.setups(), "yangtze-rolling", {"max_deg": 0.5}, "warm-up"),
                DemParams(), "quick", seed=0, threads=threads)
    startup = time.perf_counter() - t0
    base = _rss_mb()
    acc = _counting()
    scenario, setup_name, over, pspec = CASES[name]
    row = dict(case=name, preset="quick", threads=threads, startup_s=round(startup, 2),
               rss_base_mb=round(base, 1),
               overrides=" ".join(f"{k}={v}" for k, v in over.items()))
    if scenario == "threads":
        out = []
        for r in _threads_case(acc):
            r.update(startup_s=row["startup_s"], rss_base_mb=row["rss_base_mb"],
                     rss_mb=round(_rss_mb(), 1), load_1min=round(os.getloadavg()[0], 2))
            r["particle_steps_per_s"] = f"{r['particle_steps'] / r['wall_s']:.4g}"
            r["engine_particle_steps_per_s"] = r["particle_steps_per_s"]
            r["wall_s"] = round(r["wall_s"], 3)
            r["engine_s"] = r["wall_s"]
            r["dt"] = f"{r['dt']:.5g}"
            out.append(r)
        return out
    if scenario == "memory":
        row.update(_memory_case(acc, threads))
    else:
        mod = get(scenario)
        params = _params(pspec, mod)
        setup = merge_setup(mod.setups(), setup_name, over, "<throughput>")
        est = cost.estimate(scenario, setup, params, "quick")
        kw = {"use_cache": False} if scenario in cost.SOIL_BIN else {}
        t = time.perf_counter()
        res = mod.run(setup, params, "quick", seed=0, threads=threads, **kw)
        wall = time.perf_counter() - t
        row.update(scenario=scenario, setup=setup_name, particles=res.n_particles,
                   particles_est=est.n_particles, peak=acc["peak"], peak_est=est.peak_particles,
                   steps=acc["steps"], steps_bound=est.steps,
                   sim_time_s=round(acc["sim_t"], 4), sim_time_bound_s=round(est.sim_time_s, 4),
                   dt=acc["dt"], dt_est=est.dt_s, wall_s=wall, mem_est_mb=est.mem_mb)
        if scenario in cost.SOIL_BIN and len(acc["ns"]) >= 3:
            # the trimmed bed: the second settling simulation (fill, trimmed bed, tool pass)
            _, spec = cost.soil_bin(scenario, setup, "quick")
            bed = acc["ns"][1]
            row.update(bed_est=est.phases[1].n_particles, bed=bed, bed_fraction=round(
                bed * spec.dist.mean_volume() / (spec.length * spec.width * spec.height), 4))
    row.update(engine_s=round(acc["engine_s"], 3), particle_steps=int(acc["ps"]),
               rss_mb=round(_rss_mb(), 1), wall_slots=acc["kw"],
               load_1min=round(os.getloadavg()[0], 2))
    row["particle_steps_per_s"] = f"{acc['ps'] / row['wall_s']:.4g}"
    row["engine_particle_steps_per_s"] = f"{acc['ps'] / max(acc['engine_s'], 1e-9):.4g}"
    row["wall_s"] = round(row["wall_s"], 3)
    for k in ("dt", "dt_est"):
        row[k] = f"{row[k]:.5g}"
    return row


def _child(name, threads, nice=0) -> list:
    cache = os.environ.get("SOILCAL_SCENARIO_CACHE", "/tmp/soilcal-throughput-bins")
    env = dict(os.environ, NUMBA_NUM_THREADS=str(max(threads, 2)), SOILCAL_SCENARIO_CACHE=cache)
    out = subprocess.run([sys.executable, __file__, "--child", name, "--threads", str(threads),
                          "--nice", str(nice)],
                         capture_output=True, text=True, env=env, check=False)
    if out.returncode != 0:
        raise SystemExit(f"case {name} failed:\n{out.stderr[-3000:]}")
    got = json.loads(out.stdout.strip().splitlines()[-1])
    return got if isinstance(got, list) else [got]


def _fmt(v, spec):
    try:
        return format(float(v), spec)
    except (TypeError, ValueError):
        return ""


def page(rows, argv) -> list[str]:
    import numpy as np

    lines = ["# Engine throughput of whole runs, and the cost model beside them", "",
             f"Machine: {platform.machine()}, {os.cpu_count()} logical CPUs, Python "
             f"{platform.python_version()}.  Last command: `python benchmarks/throughput.py "
             f"{' '.join(argv)}`" + (" (the page from the rows)" if "" in argv else "") + ".  "
             "Rows: `throughput.csv` (utc and commit per row); the cases ran as `python "
             "benchmarks/throughput.py` and `... --cases threads-bed --nice -10` (as root).  "
             "Each case "
             "runs in a fresh process at the quick preset (`benchmarks/throughput.py` lists "
             "the cases and their reduced sizes); other jobs shared the two cores "
             "(`load` column).", "",
             "## Estimate against the run", "",
             "Spheres of the measured phase and the most in one simulation, every step of the "
             "run and the simulated time they cover (the estimate's are upper bounds), the "
             "smallest time step (the estimate takes the distribution's smallest radius, a run "
             "its smallest drawn sphere):", ""]
    fields = ["utc", "case", "scenario", "threads", "particles_est", "particles", "peak_est",
              "peak", "steps_bound", "steps", "sim_time_bound_s", "sim_time_s", "dt_est", "dt"]
    lines += runs_table(rows, fields)
    lines += ["", "## Throughput", "",
              "particle-steps per second of the whole run (`wall`, what a job pays: insertion "
              "and measurement included) and of the time loop alone (`engine`); start-up of "
              "the process (imports, loading the cached kernels, a one-sphere run); memory "
              "(peak RSS of the process and the estimate):", ""]
    t = [dict(r, per_s=_fmt(r["particle_steps_per_s"], ".3g"),
              eng=_fmt(r["engine_particle_steps_per_s"], ".3g")) for r in rows]
    lines += runs_table(t, ["utc", "commit", "case", "threads", "particle_steps", "wall_s",
                            "engine_s", "per_s", "eng", "startup_s", "rss_base_mb", "rss_mb",
                            "mem_est_mb", "wall_slots", "bed_est", "bed", "bed_fraction", "nice",
                            "load_1min"])
    one = [r for r in rows if str(r["threads"]) == "1"
           and r["case"] not in ("memory", "incline-rolling", "threads-bed")]
    if one:
        rates = np.array([float(r["particle_steps_per_s"]) for r in one])
        lines += ["", f"One thread, cases of 500 spheres or more: whole-run throughput "
                      f"{rates.min():.3g} to {rates.max():.3g} particle-steps/s (median "
                      f"{np.median(rates):.3g})."]
    pairs = {}
    for r in rows:
        pairs.setdefault((r["case"], r["utc"]), {})[str(r["threads"])] = r
    for (case, utc), by in pairs.items():
        if "1" in by and "2" in by:
            s = float(by["1"]["engine_s"]) / float(by["2"]["engine_s"])
            lines += ["", f"Threads, {case} ({utc} UTC, priority change {by['2'].get('nice') or 0},"
                      f" load {by['2']['load_1min']}): two threads ran {s:.2f} times as fast as "
                      f"one: parallel efficiency of the second thread {s - 1:.2f}.  "
                      f"{by['2']['overrides']}."]
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--threads", default="1")
    ap.add_argument("--nice", type=int, default=0,
                    help="scheduling priority change of the case processes (os.nice; a "
                         "negative value needs root): on a machine shared with other jobs a "
                         "raised priority keeps both cores for a two-thread case")
    ap.add_argument("--child", default=None)
    args = ap.parse_args(argv)
    if args.child:
        if args.nice:
            os.nice(args.nice)
        row = one_case(args.child, int(args.threads))
        for r in (row if isinstance(row, list) else [row]):
            r["nice"] = args.nice
        print(json.dumps(row, default=str))
        return 0
    csv_path = OUT / "throughput.csv"
    rows = read_rows(csv_path, FIELDS)
    rev = commit()
    for name in [c for c in args.cases.split(",") if c]:  # --cases "": the page only
        if name not in CASES:
            raise SystemExit(f"unknown case {name!r}: one of {', '.join(CASES)}")
        counts = [1] if CASES[name][0] == "threads" else [int(t) for t in args.threads.split(",")]
        for th in counts:
            for row in _child(name, th, args.nice):
                row.update(utc=time.strftime("%Y-%m-%d %H:%M", time.gmtime()), commit=rev)
                rows = [r for r in rows if not (r["utc"] == row["utc"] and r["case"] == name
                                                and str(r["threads"]) == str(row["threads"]))]
                rows.append(row)
                print(f"{name} threads={row['threads']}: {row['particle_steps_per_s']} "
                      f"p-steps/s (wall {row['wall_s']} s)", flush=True)
            write_rows(csv_path, rows, FIELDS)
    order = {c: i for i, c in enumerate(CASES)}
    rows.sort(key=lambda r: (order.get(r["case"], 99), r["utc"], int(r["threads"])))
    write_rows(csv_path, rows, FIELDS)
    write_page(OUT / "throughput.md", page(rows, sys.argv[1:] if argv is None else argv))
    return 0


if __name__ == "__main__":
    sys.exit(main())
