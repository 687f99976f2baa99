"""Compile the DEM engine's kernels into Numba's on-disk cache once, before many jobs start.

Every kernel is compiled with ``cache=True``: the first process that calls it compiles it (about
two minutes on one core for the whole engine) and writes the machine code to the cache
(``NUMBA_CACHE_DIR``, else ``__pycache__`` beside the sources); every later process loads it in
a second.  Processes started side by side before the cache exists each compile the same kernels:
the first two design-point jobs of ``snakemake --cores 2``, the jobs of a cluster run submitted at
once, the workers of the test suite.  :func:`compile_kernels` runs a few-sphere case of every
scenario (each contact law, wall kind, moving mesh and measurement the scenarios use) on one
thread, so that one process compiles and the others load.  Each case is kept short but runs
every phase of its scenario (the rotating tool's two settling rounds, pass, lift and rest; the
incline's seating and one hold): about 1,100 steps (the incline's 19 spheres) to 12,000
(compression's 120).  Numba compiles a kernel whole at its first call, whatever branches that
call takes, so a shorter phase reaches the same kernels.  Their numbers are not results and
are not kept.

While it compiles it holds a lock file in the kernel cache's directory
(:mod:`soilcal.dem._kernel_cache`, ``soilcal-dem-kernels.lock``) exclusively, and a process
that reaches the engine's time loop (``integrator.run_loop``) for the first time waits for that
lock, then loads the kernels from the cache.  So DEM jobs may start while it runs: they wait
rather than compile too.  A job that started its time loop before the compile took the lock
compiles for itself, and kernels the scenarios call before the time loop (the packing and
geometry helpers, seconds to compile) are not waited for.

    soilcal scenario compile            # the workflow's rule dem_kernels runs it before any DEM job
    soilcal scenario compile &          # or in the background, and start the DEM jobs at once
"""

from __future__ import annotations

import time


#: the rotating-tool case's settings that replace the quick preset's
ROTARY_OVERRIDES = ["travel", "forward_speed", "depth", "bin_length", "bin_height",
                    "flatness_points", "settle_time", "lift_time", "rest_time"]


def cases() -> list[tuple[str, object, dict, object, dict]]:
    """(label, scenario module, setup, parameters, run keywords): the smallest runs that reach
    every kernel the scenarios call (the soil-bin tools without the bed cache, which would
    skip the bed's settling)."""
    from soilcal.dem.scenarios import bulldozing, compression, drum, incline, repose, rotary
    from soilcal.dem.scenarios.base import DemParams

    dry = DemParams(soil_soil_surface_energy=0.0)
    sticky = DemParams(soil_soil_surface_energy=0.5)
    rep = repose.setups()
    return [
        ("repose cylinder (image measurement)", repose,
         dict(rep["cinnamon-soil"], n_particles=120), dry, {}),
        ("repose funnel (JKR cohesion, meshes)", repose,
         dict(rep["guangxi-cohesive"], load_mass=0.008), sticky, {}),
        ("drum", drum, dict(drum.setups()["xinjiang-vineyard"], n_particles=100, spin_time=0.1,
                            transient_time=0.05, frame_every=0.05), dry, {}),
        # the staircase starts 1.6 deg above the block's Coulomb onset atan(0.54) = 28.4 deg
        ("incline", incline, dict(incline.setups()["yangtze-static"], start_deg=30.0), dry, {}),
        ("compression", compression, dict(compression.setups()["guangxi-cohesive"],
                                          n_particles=120, max_strain=0.05), sticky, {}),
        ("soil bin, translating tool", bulldozing,
         dict(bulldozing.setups()["plate-line"], travel=0.02, settle_time=0.05,
              overrides=["travel", "settle_time"]), bulldozing.paper_params(),
         dict(use_cache=False)),
        # a 0.06 m pass at 2 m/s through a 0.09 m bed 0.62 m long (the shortest the rotor's
        # diameter, the pass and the margin allow), cut 50 mm deep, two flatness points
        ("soil bin, rotating tool", rotary,
         dict(rotary.setups()["rpm-250"], travel=0.06, forward_speed=2.0, depth=0.05,
              bin_length=0.62, bin_height=0.09, flatness_points=2, settle_time=0.01,
              lift_time=0.002, rest_time=0.002, overrides=ROTARY_OVERRIDES),
         rotary.paper_params(), dict(use_cache=False)),
    ]


def compile_kernels(log=print) -> list[dict]:
    """Run :func:`cases` one after another on one thread, holding the kernel cache's lock
    exclusively (:func:`soilcal.dem._kernel_cache.compiling`); returns one row per case (label,
    steps, spheres, wall seconds: the first rows carry the compilation)."""
    from soilcal.dem import _kernel_cache as kc

    rows = []
    with kc.compiling():
        for label, mod, setup, params, kw in cases():
            t0 = time.perf_counter()
            res = mod.run(setup, params, "quick", 0, threads=1, **kw)
            row = dict(case=label, scenario=mod.NAME, particles=int(res.n_particles),
                       steps=int(res.steps), wall_s=round(time.perf_counter() - t0, 2))
            log(f"{label}: {row['particles']} spheres, {row['steps']} steps, {row['wall_s']} s")
            rows.append(row)
    return rows


def compile_and_record(out=None, log=print) -> list[dict]:
    """:func:`compile_kernels`, and with ``out`` a CSV of what was compiled (case, scenario,
    spheres, steps) with the Numba version and the digest of the engine's sources, without
    wall times: the same sources and Numba give the same file."""
    rows = compile_kernels(log)
    if out:
        import numba
        import pandas as pd

        from soilcal.atomic import write_text
        from soilcal.dem import _kernel_cache as kc

        df = pd.DataFrame([{k: v for k, v in r.items() if k != "wall_s"} for r in rows])
        df["numba"] = numba.__version__
        df["dem_sources_sha256"] = kc.source_digest(kc.source_files())
        write_text(out, df.to_csv(index=False))
    return rows
