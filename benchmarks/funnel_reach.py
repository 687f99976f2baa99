"""How low the cohesive soil's funnel heap can go, and where its steps go.

One point of the guangxi-cohesive Box-Behnken stage (A soil-soil restitution, B soil-soil
static friction, G JKR surface energy; the other parameters from ``simulation.params``) is run
as the workflow's verification jobs run it: scenario ``repose``, setup ``guangxi-cohesive``
with the soil's own ``n_particles``, the ``quick`` preset, one seed per process on one
thread (the verification seeds are 340462 + 10000 + k, k = 0..3).  The heap's settle phase is
traced: every ``--trace`` steps (a whole multiple of the rest check's 200 steps, so the
trajectory is the plain run's, as a restart file's chunks are) the translational kinetic energy
as an rms speed, the fastest sphere, the spheres still in the funnel, and the heap's angle read
on its current state (silhouettes, ``angle_image_deg``, as the soil measures it; radial bins).
The row of a seed gives the run's steps by phase: the load settling on the cover (``fill``),
the cover's withdrawal (``cover``), the discharge (until the first trace with no sphere left
in the funnel: resolved to ``--trace`` steps) and the heap's rest after it; CPU seconds by
phase exclude the traces' measurements.

``--rest V`` (m/s, at most the scenario's ``rest_speed``) lets the heap's settle go on past the
scenario's own stop (kinetic energy below 1/2 M rest_speed^2) to 1/2 M V^2, within the same
bound (``max_settle_time``): the trajectory up to that stop is the plain run's, and the row
records the step and the angle there (``shipped_stop_step``, ``angle_image_at_shipped_stop_deg``)
besides the angle, the rms speed and the spheres left in the funnel at the end.  ``--rolling`` sets the setup's ``rolling_model``.  Both are
recorded in the row (``rest_mm_s``, ``rolling``).  ``--until T`` runs the heap's phase on to
T simulated seconds after the release (the cover starts to move: the origin of the setup's
``read_time``), with no rest stop after the scenario's own (``rest_mm_s`` 0): the trace then
shows the heap's angle against time out to a paper's reading time (the cohesive soil's
``read_time``); the JSON's ``trace`` holds every traced state (``t``: seconds into the heap's
phase, ``image``: the silhouette angle).  The script always runs the heap's phase to its own
stop (the rest rule, ``--rest`` or ``--until``), so it sets the soil's ``read_time`` to None
(:func:`point_setup`).

    python benchmarks/funnel_reach.py run --tag reach --A 0.39 --B 0.584 --G 0.02 \\
        --seeds 350462-350465 --workdir /tmp/funnel-reach
    python benchmarks/funnel_reach.py run --tag centre-rest1 --A 0.33 --B 0.488 --G 0.06 \\
        --rest 0.001 --seeds 350462-350465 --workdir /tmp/funnel-reach
    python benchmarks/funnel_reach.py table --workdir /tmp/funnel-reach

``table`` writes ``benchmarks/results/funnel_reach.csv`` (one row per seed: tag, levels, seed,
angles, steps and CPU per phase) and ``funnel_reach.md`` (mean and SD per point; notes below
its marker are kept).
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
FIELDS = ["utc", "commit", "tag", "A", "B", "G", "rolling", "rest_mm_s", "seed", "particles", "angle_image_deg",
          "angle_deg", "settled", "steps", "fill_steps", "cover_steps", "discharge_steps", "rest_steps",
          "dt_s", "discharge_end_s", "heap_end_s", "cpu_s", "fill_cpu_s", "heap_cpu_s",
          "angle_image_at_discharge_end_deg", "shipped_stop_step", "angle_image_at_shipped_stop_deg",
          "v_rms_end_mm_s", "retained_end"]
SHIPPED_REST = 0.005  # the repose scenario's rest_speed [m/s], the runs' before --rest was recorded
SHIPPED_ROLLING = "constant_torque"  # its rolling model then (DEFAULT_ROLLING)


def settle_traced(sim, max_steps, ke_tol, ke_rest, check_every, chunk, observe):
    """The heap's settle as ``restart.run_to_rest`` runs it (kinetic energy checked every
    ``check_every`` steps against ``ke_tol``, at most ``max_steps``), in chunks of ``chunk`` steps
    (a whole multiple of ``check_every``: the same checks, the same trajectory), calling
    ``observe()`` after each chunk and at the stop.  Where ``ke_tol`` is met the plain run would
    stop; if ``ke_rest`` is lower the run goes on from there, within the same bound, until
    ``ke_rest`` is met.  Returns (steps done, settled against the last tolerance, the row
    ``observe`` returned at the ``ke_tol`` stop or None if it was never met)."""
    done, stopped, tol, shipped = 0, False, ke_tol, None
    while done < max_steps and not stopped:
        n = min(chunk, max_steps - done)
        k = sim.run(n, ke_tol=tol, ke_every=check_every)
        done += k
        stopped = k < n or (sim.step % check_every == 0 and sim.kinetic_energy() < tol)
        at_ship = stopped and tol == ke_tol
        if at_ship and ke_rest < tol:
            tol, stopped = ke_rest, sim.kinetic_energy() < ke_rest
        row = observe()
        if at_ship:
            shipped = row
    return done, bool(done < max_steps or sim.kinetic_energy() < tol), shipped


def point_setup(A, B, G, seed, rolling=None, rest=None, until=None):
    """``(scenario module, setup, DemParams, heap rest speed)`` of one Box-Behnken point as the
    workflow's job runs it, with ``read_time`` None: the script runs the heap's phase to its
    own stop (the rest rule at ``rest``, or the time ``until`` after the release, rest 0), which
    a shipped ``read_time`` would bypass (the scenario then advances the heap without the rest
    check the trace hooks into)."""
    from soilcal.chain.sources import point_spec
    from soilcal.config.load import load_soil
    from soilcal.dem.scenarios import get, setup_for_measures
    from soilcal.dem.scenarios.base import DemParams

    soil = load_soil(ROOT / "config/soils/guangxi-cohesive.yaml", resources_root=ROOT / "resources")
    st = next(s for s in soil.data["stages"] if s["id"] == "bbd")
    spec = point_spec(soil, st, {"A": A, "B": B, "G": G}, 0, seed, replicates=1, responses=["angle_of_repose"])
    params = DemParams.from_mapping(spec["params"], "<point>", plausible=False)
    rs = spec["responses"]["angle_of_repose"]
    mod = get(rs["scenario"])
    setup = setup_for_measures(mod, rs["setup"], ["angle_image_deg"])
    setup["read_time"] = None  # the heap's stop is the script's (docstring)
    if rolling is not None:
        setup["rolling_model"] = rolling  # checked by the scenario (ROLLING_MODELS)
    if until is not None:
        return mod, setup, params, 0.0  # the heap's settle runs on to --until after the release
    rest = setup["rest_speed"] if rest is None else rest
    if not 0 < rest <= setup["rest_speed"]:
        raise SystemExit(f"funnel_reach.py: --rest: a heap rest speed in (0, {setup['rest_speed']}] m/s "
                         f"(the scenario's) expected, got {rest}")
    return mod, setup, params, rest


def until_steps(until: float, dt: float, step: int, release_step: int) -> int:
    """Steps left in the heap's phase at ``step`` for it to end ``until`` simulated seconds
    after the release (the cover starts to move at ``release_step``), the origin the setup's
    ``read_time`` counts from: round(until / dt) steps after the release, none if past it."""
    return max(0, int(round(until / dt)) - (int(step) - int(release_step)))


def one_seed(a) -> None:
    """Run one seed (module docstring) and write its JSON."""
    import numba

    numba.set_num_threads(1)
    from soilcal.dem import measure, restart
    from soilcal.dem.scenarios.base import DEFAULT_ROLLING

    mod, setup, params, rest = point_setup(a.A, a.B, a.G, a.seed, a.rolling, a.rest, a.until)
    phases, trace, meas, shipped = [], [], [0.0], {}
    orig = restart.run_to_rest

    def traced(sim, max_steps, ke_tol, check_every, st_, key, checkpoint=None):
        c0, s0 = time.process_time(), sim.step
        if key != "heap_steps":
            out = orig(sim, max_steps, ke_tol, check_every, st_, key, checkpoint)
        else:
            z_out, half = setup["outlet_height"], setup["plate_size"] / 2
            r_max, mass = float(sim.p.r.max()), float(sim.p.m.sum())

            def observe():
                x, r, v = sim.x.copy(), sim.p.r.copy(), sim.v
                inside = (np.abs(x[:, 0]) <= half) & (np.abs(x[:, 1]) <= half)
                on = inside & (x[:, 2] < z_out - 0.5 * r_max)
                row = dict(t=(sim.step - s0) * sim.dt, step=int(sim.step),
                           v_rms=math.sqrt(2 * sim.kinetic_energy() / mass),
                           v_max=float(np.sqrt((v ** 2).sum(1)).max()),
                           retained=int((x[:, 2] >= z_out - 0.5 * r_max).sum()))
                m0 = time.process_time()
                try:
                    row["bins"] = measure.repose_angle_bins(x[on], r[on], 0.0, centre=(0.0, 0.0))["angle_deg"]
                    row["image"] = measure.repose_angle_image(x[on], r[on], 0.0, views=8)["angle_deg"]
                except Exception as exc:  # noqa: BLE001 - a heap not yet readable is a trace row
                    row["err"] = str(exc)[:200]
                meas[0] += time.process_time() - m0
                trace.append(row)
                return row

            chunk = max(1, a.trace // check_every) * check_every
            if a.until is not None:  # no rest stop: the heap runs to a.until after the release
                max_steps = until_steps(a.until, sim.dt, sim.step, st_["move_step0"])
            done, ok, ship = settle_traced(sim, max_steps, ke_tol, 0.5 * mass * rest ** 2, check_every,
                                           chunk, observe)
            shipped.update(ship or {})
            out = (done, ok)
        phases.append(dict(key=key, steps=int(sim.step - s0), cpu=time.process_time() - c0 - meas[0]))
        return out

    restart.run_to_rest = traced
    c0 = time.process_time()
    res = mod.run(setup, params, preset="quick", seed=a.seed, threads=1, source="funnel_reach")
    from _report import commit

    out = dict(utc=time.strftime("%Y-%m-%d %H:%M", time.gmtime()), commit=commit(), tag=a.tag, levels=dict(A=a.A, B=a.B, G=a.G), seed=a.seed, n=res.n_particles,
               steps=res.steps, dt=res.setup["dt"], cpu_s=time.process_time() - c0 - meas[0],
               rest_speed=rest, rolling=setup.get("rolling_model") or DEFAULT_ROLLING, shipped_stop=shipped,
               phases=phases, trace=trace, responses={k: res.responses[k] for k in
                                                       ("angle_image_deg", "angle_deg", "settled", "settle_time_s")})
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    Path(a.out).write_text(json.dumps(out, indent=1, default=float))


def row_of(d: dict, rev: str) -> dict:
    """A table row from one seed's JSON (``commit``: the run's, else ``rev``; ``utc``: when the
    run ended, empty where the JSON does not record it)."""
    ph = {p["key"]: p for p in d["phases"]}
    fill, heap = ph["fill_steps"]["steps"], ph["heap_steps"]["steps"]
    step0 = d["steps"] - heap  # the heap's settle starts here
    end = next((t for t in d["trace"] if t["retained"] == 0), None)
    dis = (end["step"] - step0) if end else heap
    rest = d.get("rest_speed", SHIPPED_REST)
    # the scenario's own stop: recorded when --rest went past it, else the run's end if it settled
    ship = d.get("shipped_stop") or ({} if rest < SHIPPED_REST or not d["responses"]["settled"] else
                                     dict(step=d["steps"], image=d["responses"]["angle_image_deg"]))
    last = d["trace"][-1] if d["trace"] else {}
    return dict(utc=d.get("utc", ""), commit=d.get("commit", rev), tag=d["tag"], **d["levels"],
                rolling=d.get("rolling", SHIPPED_ROLLING), rest_mm_s=round(1e3 * rest, 3), seed=d["seed"], particles=d["n"], angle_image_deg=round(d["responses"]["angle_image_deg"], 2),
                angle_deg=round(d["responses"]["angle_deg"], 2), settled=d["responses"]["settled"],
                steps=d["steps"], fill_steps=fill, cover_steps=d["steps"] - fill - heap, discharge_steps=dis,
                rest_steps=heap - dis, dt_s=f"{d['dt']:.4g}",
                discharge_end_s=round((end["step"] if end else d["steps"]) * d["dt"], 3),
                heap_end_s=round(d["steps"] * d["dt"], 3), cpu_s=round(d["cpu_s"], 1),
                fill_cpu_s=round(ph["fill_steps"]["cpu"], 1), heap_cpu_s=round(ph["heap_steps"]["cpu"], 1),
                angle_image_at_discharge_end_deg=round(end["image"], 2) if end and "image" in end else "",
                shipped_stop_step=ship.get("step", ""),
                angle_image_at_shipped_stop_deg=round(ship["image"], 2) if "image" in ship else "",
                v_rms_end_mm_s=round(1e3 * last["v_rms"], 2) if "v_rms" in last else "",
                retained_end=last.get("retained", ""))


def table(workdir: Path) -> None:
    from _report import commit, runs_table, write_page, write_rows

    rev = commit()
    rows = [row_of(json.loads(p.read_text()), rev) for p in sorted(Path(workdir).glob("*/*.json"))]
    write_rows(HERE / "results" / "funnel_reach.csv", rows, FIELDS)
    lines = ["# The cohesive soil's funnel heap: how low it goes, where its steps go", "",
             f"Machine: {platform.machine()}, Python {platform.python_version()}.  Command: "
             "`python benchmarks/funnel_reach.py table --workdir DIR`, DIR the seeds' JSON files of "
             "`run --workdir DIR` (module docstring).  Rows: `funnel_reach.csv`; utc: when the seed's run "
             "ended, recorded in its JSON (empty for seeds run before the JSON recorded it).  CPU: process "
             "seconds on one thread, the traces' measurements left out.",
             "", "## Points (mean +- SD over seeds, silhouette angle)", "",
             "| tag | A | B | G J/m^2 | rolling | rest mm/s | seeds | settled | angle deg | SD | "
             "angle at the scenario's stop | SD | rms speed at the end mm/s | steps | discharge steps | rest steps | CPU s |",
             "|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]

    def mean_sd(vals):
        v = np.array([x for x in vals if x != ""], float)
        return (f"{v.mean():.2f}" if len(v) else "", f"{v.std(ddof=1):.2f}" if len(v) > 1 else "")

    for tag in dict.fromkeys(r["tag"] for r in rows):
        g = [r for r in rows if r["tag"] == tag]
        ang, sd = mean_sd([r["angle_image_deg"] for r in g])
        ship, ship_sd = mean_sd([r["angle_image_at_shipped_stop_deg"] for r in g])
        lines.append(f"| {tag} | {g[0]['A']} | {g[0]['B']} | {g[0]['G']} | {g[0]['rolling']} | {g[0]['rest_mm_s']} | "
                     f"{len(g)} | {sum(int(r['settled']) for r in g)} | {ang} | {sd} | {ship} | {ship_sd} | "
                     f"{mean_sd([r['v_rms_end_mm_s'] for r in g])[0]} | "
                     f"{np.mean([r['steps'] for r in g]):.0f} | {np.mean([r['discharge_steps'] for r in g]):.0f} | "
                     f"{np.mean([r['rest_steps'] for r in g]):.0f} | {np.mean([r['cpu_s'] for r in g]):.1f} |")
    lines += ["", "## Seeds", "", *runs_table(rows, FIELDS)]
    lines += trace_lines([json.loads(p.read_text()) for p in sorted(Path(workdir).glob("*/*.json"))])
    write_page(HERE / "results" / "funnel_reach.md", lines)


def trace_lines(runs: list) -> list:
    """The traced angle against time of the runs without a rest stop (``--until``): time
    after the release (the cover starts to move), silhouette angle, rms speed."""
    out = []
    for d in (d for d in runs if d.get("rest_speed", SHIPPED_REST) == 0):
        fill = next(p["steps"] for p in d["phases"] if p["key"] == "fill_steps")
        out += ["", f"## Trace: {d['tag']}, seed {d['seed']} (A {d['levels']['A']}, B {d['levels']['B']}, "
                f"G {d['levels']['G']}, {d.get('rolling', SHIPPED_ROLLING)}, no rest stop)", "",
                "| s after the release | step | silhouette angle deg | radial bins deg | rms speed mm/s | in the funnel |",
                "|---:|---:|---:|---:|---:|---:|"]
        out += [f"| {(t['step'] - fill) * d['dt']:.3f} | {t['step']} | {t.get('image', float('nan')):.2f} | "
                f"{t.get('bins', float('nan')):.2f} | {1e3 * t['v_rms']:.2f} | {t['retained']} |" for t in d["trace"]]
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    for name in ("run", "seed"):
        p = sub.add_parser(name)
        p.add_argument("--tag", required=True)
        p.add_argument("--A", type=float, required=True)
        p.add_argument("--B", type=float, required=True)
        p.add_argument("--G", type=float, required=True)
        p.add_argument("--trace", type=int, default=4000, help="steps between traces of the heap")
        p.add_argument("--rest", type=float, default=None,
                       help="rest speed of the heap phase [m/s] (default: the scenario's)")
        p.add_argument("--rolling", default=None, help="setup rolling_model (default: the scenario's)")
        p.add_argument("--until", type=float, default=None,
                       help="run the heap phase on to this simulated time after the release [s], no rest stop")
        if name == "run":
            p.add_argument("--seeds", required=True, help="e.g. 350462-350465")
            p.add_argument("--workdir", required=True)
        else:
            p.add_argument("--seed", type=int, required=True)
            p.add_argument("--out", required=True)
    t = sub.add_parser("table")
    t.add_argument("--workdir", required=True)
    a = ap.parse_args(argv)
    if a.cmd == "seed":
        one_seed(a)
    elif a.cmd == "table":
        table(Path(a.workdir))
    else:
        from _report import seed_list

        for s in seed_list(a.seeds):
            subprocess.run([sys.executable, __file__, "seed", "--tag", a.tag, "--A", str(a.A), "--B", str(a.B),
                            "--G", str(a.G), "--trace", str(a.trace), "--seed", str(s),
                            *([] if a.rest is None else ["--rest", str(a.rest)]),
                            *([] if a.rolling is None else ["--rolling", a.rolling]),
                            *([] if a.until is None else ["--until", str(a.until)]),
                            "--out", str(Path(a.workdir) / a.tag / f"{s}.json")], check=True)


if __name__ == "__main__":
    main()
