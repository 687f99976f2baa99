"""Dynamic angle of repose in a rotating drum (vineyard soil, 003).

Apparatus and procedure (003, "Dynamic angle of repose measurement" and "Discrete element
simulation modeling"): a drum 100 mm in diameter and 100 mm long with a steel sheet on its
inner wall, filled to 25 % of its volume (0.209 kg in the paper's simulation), rotated at
7 r/min after the particles have settled; the angle of the free surface is read from video
(five repeats averaged), the dynamic angle being "the maximum angle between the slope of the
soil mass and the horizontal plane before collapse occurs".

Simulation: the drum axis is horizontal along y through the origin, from y = 0 to y = L.
The shell is the engine's cylinder wall (inner side) and the two end plates are disc walls,
all rotating at omega = 2 pi n / 60 rad/s about the axis (the shell is steel, 003; the end
plates' material is not printed: steel).  Spheres are placed at random in the drum (at 15 %
solid fraction for a 25 % fill), settle (translational kinetic energy below
1/2 M v_rest^2), then the drum turns for ``spin_time`` seconds; after ``transient_time`` a
frame is measured every ``frame_every`` seconds in the mid-section slab
|y - L/2| <= max(1.5 d, 0.1 L) (:func:`soilcal.dem.measure.drum_surface_angle`: highest
particle per one-diameter bin across the section, straight line on the central 60 % of the
chord, theta = atan|slope|).

Number of spheres for fill fraction f at settled solid fraction phi = 0.6::

    N = phi f pi R^2 L / <v_p>

``quick``: 1000 spheres (radii uniform in [0.9, 1.1] r_q), shear modulus capped at
5e5 Pa, 8 s of rotation (0.93 turn) with frames from 1.0 s; ``paper``: scaled particles
2.5, 5, 10 mm (003, taken as diameters, equal mass thirds), unscaled modulus, 10 s of
rotation (1.17 turns) with frames from 3 s.  Frames every ``frame_every`` = 0.05 s (the drum
turns 2.1 deg between frames at 7 r/min).  The quick rotation is long enough to see several
collapses: at the vineyard soil's BBD centre point the angle before collapse scattered over
six seeds with an SD of 1.69 deg after 4 s of rotation (3 collapses each) and 1.27 deg after
8 s (7-9 collapses), where the time mean scattered by 0.53 and 0.32 deg
(benchmarks/results/drum_seeds.md).

Responses: ``angle_deg`` (time mean of the frame angles), ``angle_sd_deg`` (their sample
standard deviation), ``angle_max_deg`` (largest frame angle), ``angle_avalanche_deg`` (the
paper's "maximum angle before collapse": the mean of the frame angles just before each
collapse of at least ``min_drop`` degrees, :func:`soilcal.dem.measure.avalanche_angle`;
the time mean when the surface flows without collapses, said in ``measure_errors``) and
``n_avalanches``, ``n_spikes``, ``n_frames``.  The quick drum slumps: at the vineyard soil's
BBD centre point the angle before collapse lies about 10 deg above the time mean
(drum_seeds.md), and the design points where no collapse of 10 deg was seen are listed on
benchmarks/results/design_budget.md.  The fitted line of a
1000-sphere surface also jitters from frame to frame by several degrees (rotation alone
turns it 2.1 deg between frames), so ``min_drop`` = 10 deg; a lone frame that far above
(or below) both neighbours is taken as a misfit and replaced before the peaks are sought
(``n_spikes``).
"""

from __future__ import annotations

import math

import numpy as np

from soilcal.dem import measure
from soilcal.dem.factories import CylinderRegion, UniformRadius, insert_random
from soilcal.dem.scenarios.base import (DemParams, Frames, Result, check, check_discretisation,
                                        check_preset, make_simulation, paper_cohesion, paper_psd,
                                        rng, setup_number, threads_used)

NAME = "drum"
#: writes and reads restart files (soilcal.dem.restart)
RESTARTABLE = True
#: every response a run reports (``Result.responses``)
RESPONSES = (
    "angle_deg", "angle_sd_deg", "angle_max_deg", "angle_avalanche_deg", "n_avalanches",
    "n_spikes", "n_frames", "fill_settled", "peak_overlap", "measure_errors",
)
#: the responses a soil's ``simulation`` block may measure (numbers a design point yields)
MEASURES = (
    "angle_deg", "angle_sd_deg", "angle_max_deg", "angle_avalanche_deg",
)
PHI = 0.6


def setups() -> dict:
    return {
        # 003 "Dynamic angle of repose measurement": drum 100 mm diameter, 100 mm long, steel
        # sheet on the inner wall, 25 % fill, 7 r/min.  "Discrete element simulation
        # modeling": scaled particles 2.5, 5, 10 mm, 0.209 kg for the 25 % fill.
        "xinjiang-vineyard": dict(drum_diameter=0.100, drum_length=0.100, fill_fraction=0.25,
                                  rpm=7.0, wall_material="steel", end_material="steel",
                                  rest_speed=0.005, max_settle_time=3.0,
                                  spin_time=None, transient_time=None, frame_every=0.05,
                                  min_drop=10.0,
                                  n_particles=None, radius=None, stiffness_scale=None,
                                  dt_fraction=None, rolling_model=None, contact_conventions=None,
                                  scale_cohesion=True, paper_psd=[[0.00125, 33.34], [0.0025, 33.33], [0.005, 33.33]]),
    }


PRESET_TIMES = {"quick": (8.0, 1.0), "paper": (10.0, 3.0)}




def sizing(setup, preset, source="<input>"):
    d = check_preset(preset)
    R, L = setup["drum_diameter"] / 2, setup["drum_length"]
    vol = setup["fill_fraction"] * math.pi * R * R * L
    r_set, n_set = setup.get("radius"), setup.get("n_particles")
    if preset == "paper" and r_set is None and n_set is None:
        dist = paper_psd(setup, source)
    elif r_set is None:
        dist = UniformRadius.splitting(PHI * vol, int(n_set or d["n_particles"]))
    else:
        dist = UniformRadius.about(r_set)
    n = int(round(PHI * vol / dist.mean_volume()))
    return dict(dist=dist, n=n, r_max=float(dist.r_max), vol=vol)


def validate(setup, preset="quick", source="<input>", params=None):
    """Bad settings raise InputError before the run (``params``: no check needs them)."""
    check_preset(preset, source)
    D = setup_number(setup, "drum_diameter", source)
    L = setup_number(setup, "drum_length", source)
    f = setup.get("fill_fraction")
    check(isinstance(f, (int, float)) and not isinstance(f, bool) and 0 < f <= 1.0, source,
          "setup.fill_fraction", "a fill fraction in (0, 1] (0.25 = 25 % of the drum volume)", f)
    check(f <= 0.5, source, "setup.fill_fraction",
          "at most half the drum (a free surface across the mid-section)", f)
    setup_number(setup, "rpm", source)
    setup_number(setup, "rest_speed", source)
    setup_number(setup, "max_settle_time", source)
    setup_number(setup, "frame_every", source)
    setup_number(setup, "min_drop", source)
    st = setup_number(setup, "spin_time", source, allow_none=True)
    tt = setup_number(setup, "transient_time", source, allow_none=True)
    spin, trans = PRESET_TIMES[preset]
    spin, trans = st or spin, tt or trans
    check(trans < spin, source, "setup.transient_time",
          f"shorter than the rotation time {spin} s", trans)
    for key in ("wall_material", "end_material"):
        check(setup.get(key) in ("steel", "soil"), source, f"setup.{key}", "'steel' or 'soil'",
              setup.get(key))
    check_discretisation(setup, source)
    # the bounded model resists absolute rotation, so it would brake spheres that the drum
    # merely carries round (contact.py)
    check(setup.get("rolling_model") != "bounded", source, "setup.rolling_model",
          "constant_torque or epsd (bounded resists the rotation the drum imposes)", "bounded")
    sz = sizing(setup, preset, source)
    check(2 * sz["r_max"] * 6 <= min(D, L), source, "setup.drum_diameter",
          f"a drum at least 6 particle diameters across ({12 * sz['r_max']:.4g} m)", (D, L))


def run(setup, params: DemParams, preset="quick", seed=0, threads=None, vtk_dir=None,
        source="<drum>", restart=None) -> Result:
    """One drum (module docstring).  ``restart``: a :class:`soilcal.dem.restart.Restart` that
    the run resumes from and writes every few minutes (phases ``settle_fill``, ``transient``,
    ``frames``); the numbers are those of an uninterrupted run."""
    from soilcal.dem import restart as rst

    validate(setup, preset, source)
    nthreads = threads_used(threads)
    sz = sizing(setup, preset)
    R, L = setup["drum_diameter"] / 2, setup["drum_length"]
    coh = paper_cohesion(setup, sz["dist"], source)
    w = 2 * math.pi * setup["rpm"] / 60.0
    frames = Frames(vtk_dir, NAME)
    prog = rst.Progress(restart, frames)
    if not prog.resume():
        gen = rng(seed, NAME)
        sim, scale = make_simulation(params, setup, preset, source, cohesion=coh,
                                     skin=0.5 * sz["r_max"])
        sim.add_cylinder((0, L / 2, 0), (0, 1, 0), R, L / 2, setup["wall_material"],
                         inner=True, name="shell", centre=(0, L / 2, 0))
        sim.add_disk((0, 0, 0), (0, 1, 0), R, setup["end_material"], name="end0")
        sim.add_disk((0, L, 0), (0, -1, 0), R, setup["end_material"], name="end1")
        rm = sz["r_max"]
        region = CylinderRegion(R - 1.001 * rm, 1.001 * rm, L - 1.001 * rm,
                                axis_point=(0, 0, 0), axis_dir=(0, 1, 0))
        x, r = insert_random(region, sz["dist"], n=sz["n"], rng=gen, max_fraction=0.35,
                             source=source, field="particles")
        order = np.argsort(x[:, 2], kind="stable")
        sim.add_particles(x[order], r[order], "soil")
        frames(sim)
        prog.begin(sim, "settle_fill", scale=scale)
    sim, st = prog.sim, prog.vars
    spin, trans = PRESET_TIMES[preset]
    spin = setup.get("spin_time") or spin
    trans = setup.get("transient_time") or trans
    n_fr = int(math.floor((spin - trans) / setup["frame_every"] + 1e-9)) + 1
    if prog.at("settle_fill"):
        prog.checkpoint()
        ok0, _ = prog.settle(setup["rest_speed"], setup["max_settle_time"], "fill_steps")
        frames(sim)
        for name in ("shell", "end0", "end1"):
            sim.set_wall_motion(sim.walls.names.index(name), omega=(0, w, 0))
        prog.next("transient", fill_settled=int(ok0))
    if prog.at("transient"):
        prog.checkpoint()
        prog.advance(max(1, int(round(trans / sim.dt))), "transient_steps")  # run_time's steps
        prog.next("frames", k=0, angles=[], t_frames=[])
    slab = max(3.0 * float(np.mean(sim.p.r)), 0.1 * L)
    every = max(1, int(round(setup["frame_every"] / sim.dt)))  # run_time's steps
    while st["k"] < n_fr:
        prog.checkpoint()
        if st["k"]:
            prog.advance(every, "frame_steps")
        fr = measure.drum_surface_angle(sim.x, sim.p.r, (0, L / 2, 0), (0, 1, 0), slab_half=slab,
                                        source=source)
        st["angles"].append(fr["angle_deg"])
        st["t_frames"].append(sim.step * sim.dt)
        st["k"] += 1
        st["frame_steps"] = 0
        frames(sim)
    ok0, scale = st["fill_settled"], st["scale"]
    angles, t_frames = st["angles"], st["t_frames"]
    frames.close()
    prog.finish()
    a = np.asarray(angles)
    mean, sd = measure.mean_sd(a)
    av = measure.avalanche_angle(a, setup["min_drop"], source)
    note = ("" if av["n_avalanches"] else
            f"avalanche: no collapse of at least {setup['min_drop']:g} deg in {a.size} frames "
            f"(a flowing surface, or too few frames): angle_avalanche_deg is the time mean")
    responses = dict(angle_deg=mean, angle_sd_deg=sd, angle_max_deg=float(a.max()),
                     angle_avalanche_deg=av["angle_deg"], n_avalanches=av["n_avalanches"],
                     n_spikes=av["n_spikes"], n_frames=int(a.size), fill_settled=int(ok0),
                     measure_errors=note, peak_overlap=sim.peak_overlap)
    setup_out = dict(setup)
    setup_out.pop("paper_psd", None)
    setup_out.update(stiffness_scale=scale, cohesion_scale=coh, dt=sim.dt,
                     dt_fraction=sim.dt / sim.rayleigh, spin_time=spin, transient_time=trans,
                     r_max=sz["r_max"], omega_rad_s=w, slab_half=slab)
    return Result(scenario=NAME, preset=preset, seed=int(seed), n_particles=int(sim.n),
                  steps=int(sim.step), sim_time_s=float(sim.step * sim.dt), wall_s=prog.wall_s,
                  threads=nthreads, params=params.as_dict(), setup=setup_out,
                  responses=responses,
                  series=dict(t=np.asarray(t_frames), angle_deg=a, x=sim.x.copy(), r=sim.p.r.copy()))
