"""Pile benchmark: a non-cohesive heap of about 5,000 spheres from a 60 mm tube lifted at
0.05 m/s (the cinnamon-soil cylinder-lifting test, 002 Sec. 2.4), run until it is at rest.

The case is ``soilcal scenario run repose --setup cinnamon-soil`` with ``n_particles`` =
5,000 (radii uniform in [0.9, 1.1] r, r from the 60 mm x 60 mm fill at solid fraction 0.6),
no JKR cohesion (surface energies 0), soil-soil rolling friction 0.1, the quick preset's
stiffness (shear modulus capped at 5e5 Pa) and time step (30 % of the Rayleigh time).  The
run fills the tube, settles, lifts the tube by the fill height plus two diameters and runs
until the translational kinetic energy is below 1/2 M (2 mm/s)^2.

Reported: wall time of the whole run (compile excluded: a small warm-up run first), steps,
simulated time, particle-steps per second, the time to rest after the lift, the angle by
radial bins and by silhouette, and the machine load (other processes share the cores).
Each run adds a row to benchmarks/results/pile.csv and regenerates pile.md (notes below its
marker are kept; ``--out`` elsewhere).

    python benchmarks/pile.py [--n 5000] [--threads 2] [--out DIR]
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

from _report import commit, kept_notes, read_rows, write_rows

HERE = Path(__file__).resolve().parent


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=5000)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default=str(HERE / "results"))
    args = ap.parse_args(argv)

    from soilcal.dem.scenarios import repose
    from soilcal.dem.scenarios.base import DemParams

    params = DemParams(soil_soil_surface_energy=0.0, soil_steel_surface_energy=0.0,
                       soil_soil_rolling_friction=0.1)
    setup = dict(repose.setups()["cinnamon-soil"], name="cinnamon-soil")
    t0 = time.perf_counter()
    repose.run(dict(setup, n_particles=300, fill_height=0.02, image=False), params, "quick", 0,
               args.threads)  # compile / warm-up
    warm = time.perf_counter() - t0
    c0 = time.process_time()
    res = repose.run(dict(setup, n_particles=args.n), params, "quick", args.seed, args.threads)
    cpu = time.process_time() - c0
    r = res.responses
    row = dict(n=res.n_particles, threads=res.threads, steps=res.steps,
               sim_time_s=round(res.sim_time_s, 4), wall_s=round(res.wall_s, 2),
               cpu_s=round(cpu, 2),
               particle_steps_per_s=f"{res.n_particles * res.steps / res.wall_s:.3g}",
               rest_after_lift_s=round(r["settle_time_s"], 4), settled=r["settled"],
               angle_deg=round(r["angle_deg"], 2), angle_image_deg=round(r["angle_image_deg"], 2),
               height_mm=round(1e3 * r["height_m"], 2), dt_s=f"{res.setup['dt']:.4g}",
               stiffness_scale=round(res.setup["stiffness_scale"], 4),
               warmup_s=round(warm, 1), load_avg_1min=round(os.getloadavg()[0], 2))
    row = dict(utc=time.strftime("%Y-%m-%d %H:%M", time.gmtime()), commit=commit(), **row)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = read_rows(out / "pile.csv", list(row)) + [row]
    write_rows(out / "pile.csv", rows, list(row))
    md_path = out / "pile.md"
    md = [
        "# Pile benchmark (cylinder lifting, non-cohesive)",
        "",
        f"Machine: {platform.machine()}, {os.cpu_count()} logical CPUs, Python "
        f"{platform.python_version()}.  Every run of `python benchmarks/pile.py` adds a row "
        "(utc, commit); the last was `python benchmarks/pile.py " + " ".join(sys.argv[1:]) + "`.",
        "",
        "| " + " | ".join(row) + " |",
        "|" + "---|" * len(row),
        *("| " + " | ".join(str(r.get(k, "")) for k in row) + " |" for r in rows),
        "",
        "Setup: 60 mm steel tube, fill 60 mm, lifted at 0.05 m/s (002 Sec. 2.4), 65Mn plate; "
        "Hertz-Mindlin + constant-torque rolling (mu_r 0.1), no cohesion; quick-preset "
        "stiffness and time step.  wall_s covers filling, settling in the tube, the lift and "
        "the rest (compile excluded); load_avg_1min is the machine load at the end (other "
        "processes share the two cores).",
        "",
        kept_notes(md_path),
    ]
    md_path.write_text("\n".join(md) + "\n")
    print(row)


if __name__ == "__main__":
    main()
