"""Inclined-plane soil-steel friction: static (sliding block) and rolling (soil ball).

Procedure (Yangtze clay loam, 000 Sec. 2.2.2, Figs. 5-6): a 300 mm x 500 mm 65Mn steel
plate is tilted slowly (probe raised at 10 mm/min) until a cylindrical soil block starts to
slide (Table 1) or a soil ball of radius 10 mm starts to roll (Table 2); from the angle
(Eqs. 1-2)::

    mu = tan(alpha)        (static friction, block slides)
    k  = tan(beta)         (rolling friction, ball rolls)

Printed angles: Table 1: 34.2, 35.3, 36.4 deg (mu = 0.68, 0.71, 0.74, mean 0.71); Table 2:
5.6, 5.2, 5.8 deg (k = 0.098, 0.091, 0.102, mean 0.097).

Simulation: the plate is the plane z = 0 (steel) and the tilt is applied by rotating gravity,
g = 9.81 (sin theta, 0, -cos theta) m/s^2, which in the plate frame is the same load as a
tilted plate.  The angle rises in a staircase: ``step_deg`` increments, each held for
``hold_time`` seconds; the object has started to move when its centroid travels more than
``move_fraction`` (5 %) of a particle radius down the slope during one hold.  Below the onset
the objects creep: elastic and partial slip of the block (micrometres), and about 1-2 % of
the radius per hold for the ball, because the constant-torque rolling model switches its
direction with the sign of the (nearly zero) angular velocity every step.  The onset angle is
the middle of the last stuck and the first moving step (uncertainty +/- step_deg/2).

* ``sliding``: the block is a monolayer of non-rotating spheres (hexagonal, in a disc of
  ``block_diameter``), ``layers`` high; each sphere slides on the plate when
  tan(theta) > mu_s (Coulomb, with JKR adhesion to the plate adding to the normal force when
  the soil-steel surface energy is > 0).
* ``rolling``: one free sphere of radius ``ball_radius``; with the constant-torque rolling
  model (tau_r = mu_r F_n R, contact.py) the rolling onset is tan(beta) = mu_r.

``quick``: 0.25 deg steps (sliding) / 0.1 deg (rolling), 0.1 s / 0.2 s holds, shear modulus
capped at 5e5 Pa; ``paper``: 0.1 deg / 0.05 deg steps, unscaled modulus.

Responses: ``onset_deg``, ``coefficient`` = tan(onset), ``last_stuck_deg``,
``first_moving_deg``.
"""

from __future__ import annotations

import math

import numpy as np

from soilcal.dem.scenarios.base import (DemParams, Frames, Result, check, check_preset,
                                        check_rolling, make_simulation, rng, setup_number,
                                        threads_used)

NAME = "incline"
#: writes and reads restart files (soilcal.dem.restart)
RESTARTABLE = True
#: every response a run reports (``Result.responses``)
RESPONSES = (
    "onset_deg", "coefficient", "last_stuck_deg", "first_moving_deg", "moved", "peak_overlap",
)
#: the responses a soil's ``simulation`` block may measure (numbers a design point yields)
MEASURES = (
    "onset_deg", "coefficient",
)
G = 9.81


def setups() -> dict:
    common = dict(start_deg=0.0, max_deg=60.0, step_deg=None, hold_time=None, move_fraction=0.05,
                  stiffness_scale=None, dt_fraction=None, plate_material="steel",
                  rolling_model=None, contact_conventions=None)
    return {
        # 000 Sec. 2.2.2 (1), Table 1: cylindrical soil block on the 300 x 500 mm 65Mn plate.
        # Block size not printed: 40 mm across, one layer of 4 mm spheres.
        "yangtze-static": dict(common, kind="sliding", block_diameter=0.040, sphere_radius=0.004,
                               layers=1, ball_radius=None),
        # 000 Sec. 2.2.2 (2), Table 2: soil ball of radius 10 mm.
        "yangtze-rolling": dict(common, kind="rolling", ball_radius=0.010, block_diameter=None,
                                sphere_radius=None, layers=None),
    }


STEPS = {("quick", "sliding"): (0.25, 0.1), ("quick", "rolling"): (0.1, 0.2),
         ("paper", "sliding"): (0.1, 0.2), ("paper", "rolling"): (0.05, 0.3)}




def validate(setup, preset="quick", source="<input>", params=None):
    """Bad settings raise InputError before the run (``params``: no check needs them)."""
    check_preset(preset, source)
    kind = setup.get("kind")
    check(kind in ("sliding", "rolling"), source, "setup.kind", "'sliding' or 'rolling'", kind)
    a0 = setup_number(setup, "start_deg", source, 0.0, inclusive=True)
    a1 = setup_number(setup, "max_deg", source)
    check(a1 < 90 and a0 < a1, source, "setup.max_deg", f"an angle in ({a0}, 90) deg", a1)
    setup_number(setup, "step_deg", source, allow_none=True)
    setup_number(setup, "hold_time", source, allow_none=True)
    setup_number(setup, "move_fraction", source)
    setup_number(setup, "stiffness_scale", source, allow_none=True)
    f = setup_number(setup, "dt_fraction", source, allow_none=True)
    if f is not None:
        check(f <= 1, source, "setup.dt_fraction", "a fraction of the Rayleigh time in (0, 1]", f)
    check(setup.get("plate_material") in ("steel", "soil"), source, "setup.plate_material",
          "'steel' or 'soil'", setup.get("plate_material"))
    check_rolling(setup, source)
    if kind == "sliding":
        d = setup_number(setup, "block_diameter", source)
        r = setup_number(setup, "sphere_radius", source)
        n = setup.get("layers")
        check(isinstance(n, int) and not isinstance(n, bool) and 1 <= n <= 5, source,
              "setup.layers", "an integer in [1, 5]", n)
        check(d >= 4 * r, source, "setup.block_diameter", f"at least 2 sphere diameters ({4 * r} m)", d)
    else:
        setup_number(setup, "ball_radius", source)


def _block(setup):
    """Hexagonal monolayer(s) of spheres inside a disc of block_diameter, resting on z = 0."""
    r = setup["sphere_radius"]
    R = setup["block_diameter"] / 2
    a = 2.0 * r
    pts = []
    for layer in range(setup["layers"]):
        z = r + layer * a * math.sqrt(2.0 / 3.0)
        off = np.array([0.0, a / math.sqrt(3.0)]) if layer % 2 else np.zeros(2)
        n = int(R / a) + 2
        for j in range(-n, n + 1):
            for i in range(-n, n + 1):
                xy = np.array([a * (i + 0.5 * (j % 2)), a * math.sqrt(3) / 2 * j]) + off
                if np.hypot(*xy) <= R - r:
                    pts.append((xy[0], xy[1], z))
    x = np.array(pts)
    return x, np.full(len(x), r)


def run(setup, params: DemParams, preset="quick", seed=0, threads=None, vtk_dir=None,
        source="<incline>", restart=None) -> Result:
    """One tilting-plate test (module docstring).  ``restart``: a
    :class:`soilcal.dem.restart.Restart` that the run resumes from and writes every few
    minutes (phases ``seat``, ``tilt``); the numbers are those of an uninterrupted run."""
    from soilcal.dem import restart as rst

    validate(setup, preset, source)
    nthreads = threads_used(threads)
    kind = setup["kind"]
    step_deg, hold = STEPS[(preset, kind)]
    step_deg = setup.get("step_deg") or step_deg
    hold = setup.get("hold_time") or hold
    frames = Frames(vtk_dir, NAME)
    prog = rst.Progress(restart, frames)
    if not prog.resume():
        gen = rng(seed, NAME)
        sim, scale = make_simulation(params, setup, preset, source)
        sim.add_plane((0, 0, 0), (0, 0, 1), setup["plate_material"], name="plate")
        if kind == "sliding":
            x, r = _block(setup)
            # seeded sub-micrometre lateral jitter: the seed changes the contact network only
            x[:, :2] += gen.uniform(-1e-7, 1e-7, (len(x), 2))
            sim.add_particles(x, r, "soil", lock_rotation=True)
        else:
            rb = setup["ball_radius"]
            sim.add_particles([[gen.uniform(-1e-7, 1e-7), 0.0, rb]], rb, "soil")
        th = math.radians(setup["start_deg"])
        sim.gravity[:] = (G * math.sin(th), 0.0, -G * math.cos(th))
        sim.run(0)
        prog.begin(sim, "seat", scale=scale)
    sim, st = prog.sim, prog.vars
    if prog.at("seat"):
        prog.checkpoint()
        prog.advance(max(1, int(0.05 / sim.dt)), "seat_steps")  # normal contacts settle
        frames(sim)
        prog.next("tilt", angle=setup["start_deg"], last_stuck=None, first_moving=None,
                  history=[], x0=None)
    scale = st["scale"]
    r_ref = float(sim.p.r.min())
    thr = setup["move_fraction"] * r_ref
    nhold = max(1, int(round(hold / sim.dt)))
    while st["angle"] <= setup["max_deg"] + 1e-9:
        prog.checkpoint()
        if st["x0"] is None:  # the step's start (a resumed step keeps its own)
            th = math.radians(st["angle"])
            sim.gravity[:] = (G * math.sin(th), 0.0, -G * math.cos(th))
            st["x0"] = float(sim.x[:, 0].mean())
        prog.advance(nhold, "hold_steps")
        dx = float(sim.x[:, 0].mean()) - st["x0"]
        st.update(hold_steps=0, x0=None)
        st["history"].append((st["angle"], dx))
        if dx > thr:
            st["first_moving"] = st["angle"]
            break
        st["last_stuck"] = st["angle"]
        st["angle"] = round(st["angle"] + step_deg, 10)
    last_stuck, first_moving, history = st["last_stuck"], st["first_moving"], st["history"]
    frames(sim)
    frames.close()
    prog.finish()
    if first_moving is None:
        onset = float("nan")
    elif last_stuck is None:
        onset = first_moving
    else:
        onset = 0.5 * (last_stuck + first_moving)
    responses = dict(onset_deg=onset, coefficient=math.tan(math.radians(onset)),
                     last_stuck_deg=float("nan") if last_stuck is None else last_stuck,
                     first_moving_deg=float("nan") if first_moving is None else first_moving,
                     moved=int(first_moving is not None), peak_overlap=sim.peak_overlap)
    h = np.array(history)
    setup_out = dict(setup)
    setup_out.update(stiffness_scale=scale, dt=sim.dt, step_deg=step_deg, hold_time=hold)
    return Result(scenario=NAME, preset=preset, seed=int(seed), n_particles=int(sim.n),
                  steps=int(sim.step), sim_time_s=float(sim.step * sim.dt), wall_s=prog.wall_s,
                  threads=nthreads, params=params.as_dict(), setup=setup_out,
                  responses=responses, series=dict(angle_deg=h[:, 0], dx_m=h[:, 1]))
