"""Rotary tillage: power and surface flatness of a blade set (black soil, 150-350 rpm).

Source: Qi et al., Sustainability 2025, 17, 8126, Sec. 2.1 (2), 2.3, 3.3
(``config/soils/black-soil.yaml``).

Test (Sec. 2.3): the 1GKN-160 rotary tiller (36 IT225 blades, working width 1.6 m, Table 1;
blade set geometry :func:`soilcal.dem.tools.rotary_blade_set`) advances at 1 km/h with the
blade shaft at 150, 200, 250, 300 or 350 r/min.  The blade shaft turns down-cut (like the
tractor wheels): ``omega = +2 pi n / 60 e_y`` with travel along +x.  The tillage depth is
not printed; 120 mm is assumed (``depth``); validation requires depth <= 225 - 100 mm so
that the blade holders (radius 100 mm, assumed) stay above the soil.

Power (Sec. 3.3, Figure 10): the torque of the particles on the blade set about the shaft,
``tau_y``, opposes the rotation; the shaft power is::

    P = -tau_y omega

reported as the stable-stage mean and sample SD (``stable_from`` of the pass to its end),
in kW for the full working width.  The draft ``-F_x`` (positive when the soil resists the
advance) and the advance power ``-F_x v`` are reported too.  The paper prints only the
absolute differences between simulated and measured power (0.138-0.460 kW,
``tillage_power_difference.csv``), not the powers.

Surface flatness (Eqs. 3-4; five equidistant points on the tilled surface, Sec. 2.3)::

    d_mean = (1/n) sum d_i,     Sd = sqrt( sum (d_i - d_mean)^2 / (n - 1) )

``d_i`` the height of the tilled surface above the undisturbed surface at point i (mm). The
tiller's hood is a steel ceiling ``hood_clearance`` above the blade tips at the start (it
keeps thrown soil in the bin, as the hood of a tiller does; its height is an assumption).
After the pass the rotor stops turning and is lifted out of the soil with the hood (2 m/s
for ``lift_time``), the soil settles for ``rest_time``, and the surface height at a point is
the upper envelope of the particles (highest sphere top ``z_i + sqrt(r_i^2 - rho^2)`` over
spheres whose horizontal distance rho to the point is below r_i) averaged over the lateral
samples across the tilled width that a sphere covers; a point no sphere covers at any
lateral sample has no surface height (NaN) and is left out of Eqs. (3)-(4) (the number of
such points is reported as ``flatness_empty_points``; with fewer than two covered points
the flatness is NaN).  The points lie equidistant along the travel direction
(:func:`flatness_region`) outside the starting trench (dug as a circle of radius R + 2
r_max about the starting shaft position, so its footprint ``|x - x0| <= R + 2 r_max``):
behind the rotor's final position over ground its whole footprint passed, or, for passes
shorter than the rotor diameter plus 0.1 m (the quick preset), from the trench's front
edge to the front of the rotor's final footprint.  Validation requires that stretch to
hold the ``flatness_points`` at least one particle diameter (2 r_max) apart (a pass too
short for the rotor radius fails on ``setup.travel``).  Measured Sd: 159.2, 134.4, 120.6,
109.8, 102.1 mm at 150-350 r/min (``surface_flatness.csv``).  A dense version over
``dense_points`` points is reported as ``flatness_dense_mm``.

Presets: ``paper`` simulates the whole 1.6 m blade set between side walls with particles of
1.5 mm radius (the printed 2-4 mm diameters, +-33 %); ``quick`` simulates one flange of
three blades in a periodic slab of one flange spacing (1.6 m / 12), 12 mm particles
(0.9-1.1) in a 0.19 m deep bed, the paper's shear modulus unscaled, a 0.3 m pass, and
scales the torque to the full working width by ``n_flanges`` (the helix repeats every
flange up to a phase).  The convergence study
(``benchmarks/results/convergence/convergence_tools.md``) set the pass and the modulus: a
0.15 m pass averaged the power over about 1.4 turns of the rotor at 250 r/min and the power
scattered over seeds by a quarter of its mean (SD 0.61 of 2.55 kW, five seeds), the 0.3 m
pass by 0.27 of 2.39 kW; with the modulus scaled by 0.1 (1e8 -> 1e7 Pa, surface energies
by 0.1^0.4) the 0.3 m pass gave 2.39 kW against 3.34 kW (SD 0.38) unscaled, while the
unscaled run takes about 10 s on one thread (the rows of the earlier presets are in
convergence_tools_replaced.csv).  The time step is the
smaller of ``dt_fraction`` x the Rayleigh time and the time the blade tip needs to move a
tenth of the smallest radius (tip speed ``omega R + v``)."""

from __future__ import annotations

import csv
import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from soilcal.dem import tools
from soilcal.dem.scenarios.base import (PRESETS, DemParams, Result, check, stable_mean,
                                        threads_used)
from soilcal.dem.scenarios.soilbin import (COHESION_KEYS, BinSpec, apply_preset, check_pass,
                                           reference_cohesion, settled_bin, tool_pass, tool_time_step,
                                           validate_bin)

NAME = "rotary"
#: writes and reads restart files (soilcal.dem.restart)
RESTARTABLE = True
#: every response a run reports (``Result.responses``)
RESPONSES = (
    "power_kW", "power_sd_kW", "torque_Nm", "draft_N", "draft_sd_N", "advance_power_kW",
    "flatness_mm", "flatness_dense_mm", "surface_change_mm", "flatness_empty_points",
    "flatness_measured_mm", "power_scale", "peak_overlap", "bin_from_cache",
)
#: the responses a soil's ``simulation`` block may measure (numbers a design point yields)
MEASURES = (
    "power_kW", "torque_Nm", "draft_N", "advance_power_kW", "flatness_mm", "flatness_dense_mm",
    "surface_change_mm",
)
MEASURED = (Path(__file__).resolve().parents[4] / "resources" / "measurements"
            / "black-soil")
RPMS = (150, 200, 250, 300, 350)  # Sec. 2.3


def _setup(rpm):
    return dict(
        rpm=float(rpm),                   # Sec. 2.3: blade shaft speed, r/min
        forward_speed=1.0 / 3.6,          # Sec. 2.3: 1 km/h in m/s
        depth=0.12,                       # assumption (not printed)
        working_width=tools.ROTOR["working_width"],  # Table 1: 160 cm
        n_flanges=tools.ROTOR["n_flanges"],          # assumption (36 = 12 x 3 blades)
        blades_per_flange=tools.ROTOR["blades_per_flange"],
        radius=tools.ROTOR["radius"],     # IT225: 225 mm
        hub_radius=tools.ROTOR["hub_radius"],
        flatness_points=5,                # Sec. 2.3: five equidistant points
        dense_points=20,
        stable_from=0.4,
        lift_time=0.08,
        hood_clearance=0.05,              # assumption: hood 50 mm above the blade tips
        rest_time=0.05,
        particle_radius=None,             # the bin's spheres: None, the preset's; a soil's
        radius_spread=None,               # set: gives its own (radius_spread beside it)
        **COHESION_KEYS,                  # surface energy for the paper preset's particles (base.py)
    )


def setups() -> dict:
    return {f"rpm-{n}": _setup(n) for n in RPMS}


PRESET_SETTINGS = {
    "quick": dict(periodic=True, bin_length=0.85, bin_height=0.19, particle_radius=0.012,
                  radius_spread=0.1, stiffness_scale=1.0, dt_fraction=0.2, travel=0.3,
                  settle_time=0.25, flanges_simulated=1, skin_fraction=1.0),
    "paper": dict(periodic=False, bin_length=2.5, bin_height=0.25, particle_radius=0.0015,
                  radius_spread=1.0 / 3.0, stiffness_scale=1.0, dt_fraction=0.2, travel=1.0,
                  settle_time=1.0, flanges_simulated=None, skin_fraction=0.6),
}


def paper_params() -> DemParams:
    """Black soil at the printed optima: stage 1 soil-soil (x1-x4 = 0.46 J/m^2, 0.51, 0.65,
    0.13; Sec. 3.1.2), stage 2 soil-65Mn (x5-x8 = 0.29 J/m^2, 0.55, 0.64, 0.07; Sec. 3.2.2);
    particle density 1560 kg/m^3 (liquid displacement), Poisson 0.46 and the printed shear
    modulus G = 1e8 Pa (triaxial test, Sec. 2.1 (1); it contradicts the printed E = 1 MPa and
    nu, see the soil config, but it is the only G printed); 65Mn 7865 kg/m^3, 0.3,
    7.9e10 Pa (Sec. 2.1)."""
    return DemParams.from_mapping(dict(
        soil_soil_surface_energy=0.46, soil_soil_restitution=0.51,
        soil_soil_static_friction=0.65, soil_soil_rolling_friction=0.13,
        soil_steel_surface_energy=0.29, soil_steel_restitution=0.55,
        soil_steel_static_friction=0.64, soil_steel_rolling_friction=0.07,
        soil_density=1560.0, soil_poisson=0.46, soil_shear_modulus=1.0e8,
        steel_density=7865.0, steel_poisson=0.3, steel_shear_modulus=7.9e10,
    ), "<rotary.paper_params>")


def measured_flatness() -> dict:
    with open(MEASURED / "surface_flatness.csv", newline="") as fh:
        return {float(r["rotor_speed_rpm"]): float(r["Sd_measured_mm"])
                for r in csv.DictReader(fh)}


def flatness(d) -> tuple[float, float]:
    """(d_mean, Sd) of Eqs. (3)-(4): mean and sample standard deviation (n - 1) over the
    points with a surface height (NaN points, which no particle covers, are left out)."""
    d = np.asarray(d, dtype=float)
    d = d[np.isfinite(d)]
    if d.size < 2:
        raise ValueError(f"surface flatness needs at least two points with a surface "
                         f"height, got {d.size}")
    return float(d.mean()), float(d.std(ddof=1))


def flatness_or_nan(d) -> tuple[float, float, int]:
    """(d_mean, Sd, number of empty points); NaN, NaN when fewer than two points have a
    surface height."""
    d = np.asarray(d, dtype=float)
    empty = int(np.count_nonzero(~np.isfinite(d)))
    if d.size - empty < 2:
        return float("nan"), float("nan"), empty
    m, sd = flatness(d)
    return m, sd, empty


def shaft_power(torque_axis, omega) -> np.ndarray:
    """P = -tau omega (W): power the shaft delivers against the soil's torque tau."""
    return -np.asarray(torque_axis, dtype=float) * float(omega)


def surface_heights(x, r, px, py, lateral_half):
    """Envelope height at points (px, py): highest sphere top over spheres within their
    radius horizontally, averaged over the 9 lateral samples in py +- lateral_half that a
    sphere covers; NaN at a point where no sphere covers any lateral sample."""
    out = np.empty(len(px))
    offs = np.linspace(-lateral_half, lateral_half, 9)
    for k, (a, b) in enumerate(zip(px, py)):
        near = np.abs(x[:, 0] - a) < r
        xs, rs = x[near], r[near]
        hs = []
        for o in offs:
            rho2 = (xs[:, 0] - a) ** 2 + (xs[:, 1] - (b + o)) ** 2
            h2 = rs**2 - rho2
            ok = h2 > 0
            hs.append(np.max(xs[ok, 2] + np.sqrt(h2[ok])) if ok.any() else np.nan)
        hs = np.asarray(hs)
        out[k] = float(np.mean(hs[np.isfinite(hs)])) if np.isfinite(hs).any() else np.nan
    return out


def flatness_region(x0, travel, radius, trench_half=None, min_length=0.1):
    """Stretch of the travel axis where the flatness points lie, outside the starting
    trench ``|x - x0| <= trench_half`` (default R): the ground behind the rotor's final
    position that its whole footprint passed over, ``[x0 + max(R, trench_half), x0 + travel
    - R]``, when ``travel - 2 R >= min_length``; otherwise (short passes) the disturbed
    footprint ahead of the trench, ``[x0 + trench_half, x0 + travel + R]``.  The stretch
    may be empty or reversed (``b <= a``) when the pass is too short."""
    th = radius if trench_half is None else float(trench_half)
    if travel - 2.0 * radius >= min_length:
        return x0 + max(radius, th), x0 + travel - radius
    return x0 + th, x0 + travel + radius


def _trench_half(s, spec) -> float:
    """Half-length along x of the starting trench (circle of radius R + 2 r_max)."""
    return s["radius"] + 2.0 * spec.r_max


def _settings(setup, preset, source="<rotary>"):
    # a soil gives its own sphere sizes whole: a radius alone would run at the preset's spread
    given = [k for k in ("particle_radius", "radius_spread") if setup.get(k) is not None]
    if len(given) == 1:
        other = "radius_spread" if given[0] == "particle_radius" else "particle_radius"
        check(False, source, f"setup.{given[0]}", f"setup.{other} beside it (a soil's own sphere sizes "
              "are given whole: particle_radius and radius_spread)", setup[given[0]])
    s = apply_preset(setup, _setup(setup.get("rpm", 250)), PRESET_SETTINGS[preset])
    if s.get("flanges_simulated") is None:
        s["flanges_simulated"] = s["n_flanges"]
    spacing = s["working_width"] / s["n_flanges"]
    s["slab_width"] = (s["flanges_simulated"] * spacing if s["periodic"]
                       else s["working_width"] + 0.2)
    return s


def validate(setup: dict, preset: str = "quick", source: str = "<rotary>",
             params=None) -> dict:
    """Bad settings raise InputError before the run; with ``params``, also a pass the run
    could not finish (:func:`soilcal.dem.scenarios.soilbin.check_pass`).  Returns the run's
    settings, with the surface-energy factor ``cohesion_scale``
    (:func:`soilcal.dem.scenarios.soilbin.reference_cohesion`)."""
    check(preset in PRESETS, source, "preset", f"one of {PRESETS}", preset)
    s = _settings(setup, preset, source)
    for k in ("rpm", "forward_speed", "depth", "working_width", "radius", "hub_radius",
              "bin_length", "bin_height", "travel", "lift_time", "rest_time",
              "hood_clearance"):
        v = s.get(k)
        check(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
              and v > 0, source, f"setup.{k}", "a number > 0", v)
    for k in ("n_flanges", "blades_per_flange", "flatness_points", "dense_points"):
        v = s.get(k)
        check(isinstance(v, int) and v >= (2 if "points" in k else 1), source, f"setup.{k}",
              "an integer >= 2" if "points" in k else "an integer >= 1", v)
    check(s["depth"] < s["bin_height"], source, "setup.depth",
          f"a tillage depth below the soil height of the bin ({s['bin_height']} m)", s["depth"])
    check(s["depth"] <= s["radius"] - s["hub_radius"], source, "setup.depth",
          f"<= rotary radius - holder radius = {s['radius'] - s['hub_radius']:.3g} m "
          "(blade holders stay above the soil)", s["depth"])
    need = 2 * s["radius"] + s["travel"] + 0.1
    check(need <= s["bin_length"], source, "setup.bin_length",
          f">= rotor diameter + pass + margin = {need:.3g} m", s["bin_length"])
    check(0.0 <= s["stable_from"] < 1.0, source, "setup.stable_from",
          "a fraction of the pass in [0, 1)", s["stable_from"])
    r, spread = s.get("particle_radius"), s.get("radius_spread")
    check(isinstance(r, (int, float)) and not isinstance(r, bool) and math.isfinite(r) and r > 0,
          source, "setup.particle_radius", "a sphere radius > 0 m", r)
    check(isinstance(spread, (int, float)) and not isinstance(spread, bool) and 0.0 <= spread < 1.0,
          source, "setup.radius_spread", "a radius spread in [0, 1)", spread)
    spec = _bin(s)
    validate_bin(spec, source, "setup")
    # flatness points outside the starting trench, at least a particle diameter apart
    th = _trench_half(s, spec)
    xa, xb = flatness_region(0.0, s["travel"], s["radius"], th)
    need = (s["flatness_points"] - 1) * 2.0 * spec.r_max
    check(xb - xa >= need, source, "setup.travel",
          f"a pass long enough for the rotor radius: the flatness stretch outside the "
          f"starting trench (|x - x0| <= R + 2 r_max = {th:.3g} m) is {xb - xa:.3g} m, "
          f"needs >= {need:.3g} m for {s['flatness_points']} points one particle diameter "
          "apart", s["travel"])
    s["cohesion_scale"] = reference_cohesion(spec, _bin(_settings(_setup(s["rpm"]), "paper")), setup, source)
    if params is not None:
        # the blades slice the soil rather than push it: only the pass's step count
        spec = replace(spec, cohesion_scale=s["cohesion_scale"])
        check_pass(spec, params, source, "setup.forward_speed", s["forward_speed"],
                   s["travel"], pass_time_step(s, spec, params), pushes=False)
    return s


def pass_time_step(s, spec: BinSpec, params: DemParams) -> float:
    """Time step of the pass: the tool step, capped so the blade tip (speed omega R + v)
    moves at most a tenth of the smallest radius per step."""
    omega = 2.0 * math.pi * s["rpm"] / 60.0
    return min(tool_time_step(spec, params),
               0.1 * spec.r_min / (omega * s["radius"] + s["forward_speed"]))


def _bin(s) -> BinSpec:
    return BinSpec(length=s["bin_length"], width=s["slab_width"], height=s["bin_height"],
                   radius=s["particle_radius"], spread=s["radius_spread"],
                   periodic_y=bool(s["periodic"]), settle_time=s["settle_time"],
                   stiffness_scale=s["stiffness_scale"], dt_fraction=s["dt_fraction"],
                   skin_fraction=s["skin_fraction"], cohesion_scale=s.get("cohesion_scale", 1.0))


def run(setup: dict, params: DemParams, preset: str = "quick", seed: int = 0, threads=None,
        vtk_dir=None, source: str = "<rotary>", use_cache: bool = True, restart=None) -> Result:
    """One tiller pass (module docstring).  ``restart``: a :class:`soilcal.dem.restart.Restart`
    that the run resumes from and writes every few minutes (phases ``bin_0``, ``bin_1``,
    ``pass`` (:func:`soilcal.dem.scenarios.soilbin.tool_pass`), ``lift``, ``rest``); the
    numbers are those of an uninterrupted run."""
    from soilcal.dem import restart as rst

    s = validate(setup, preset, source, params=params)
    nthreads = threads_used(threads)
    prog = rst.Progress(restart)
    prog.resume()
    spec = _bin(s)
    bed = settled_bin(spec, params, preset, seed, source, use_cache, progress=prog)
    omega = 2.0 * math.pi * s["rpm"] / 60.0
    R = s["radius"]
    spacing = s["working_width"] / s["n_flanges"]
    nf = s["flanges_simulated"]
    v, t = tools.rotary_blade_set(n_flanges=nf, blades_per_flange=s["blades_per_flange"],
                                  width=nf * spacing, radius=R, hub_radius=s["hub_radius"],
                                  source=source)
    x0 = R + 0.05
    axis = np.array([x0, 0.5 * s["slab_width"], bed["surface"] - s["depth"] + R])
    v = v + axis
    pad = 2.0 * spec.r_max  # trench radius R + pad (see _trench_half)

    def trench(x, r):
        return (x[:, 0] - axis[0]) ** 2 + (x[:, 2] - axis[2]) ** 2 <= (R + pad) ** 2

    hood_z = axis[2] + R + s["hood_clearance"]

    def hood(sim):
        # the tiller's hood: a steel ceiling over the rotor that keeps thrown soil in the bin
        sim.add_plane((0.0, 0.0, hood_z), (0.0, 0.0, -1.0), "steel", name="hood",
                      centre=(0.5 * s["bin_length"], 0.5 * s["slab_width"], hood_z))

    vf = s["forward_speed"]
    duration = s["travel"] / vf
    dt_max = pass_time_step(s, spec, params)  # the step validate() counted the pass in
    from soilcal.dem.geometry import rotation_matrix

    def pose(tt):
        rot = rotation_matrix(np.array([0.0, 1.0, 0.0]), omega * tt)
        c = axis + np.array([vf * tt, 0, 0])
        return (v - axis) @ rot.T + c, t

    out = tool_pass(spec, params, preset, seed, source, v, t, (vf, 0.0, 0.0), duration, trench,
                    omega=(0.0, omega, 0.0), centre=axis, dt_max=dt_max, log_dt=0.005,
                    vtk_dir=vtk_dir, stem="rotary", use_cache=use_cache, tool_pose=pose,
                    bed=bed, extra_walls=hood, progress=prog)
    sim, dt = out["sim"], out["dt"]
    tt = out["t"]
    scale = s["n_flanges"] / nf if s["periodic"] else 1.0
    power = shaft_power(out["torque"][:, 1], omega) * scale
    ts = s["stable_from"] * duration
    p_mean, p_sd = stable_mean(tt, power, ts)
    draft, draft_sd = stable_mean(tt, -out["force"][:, 0] * scale, ts)
    # lift the rotor out, let the soil come to rest, measure the surface
    wall = out["wall"]
    hood_w = wall + 1
    n_lift = int(math.ceil(s["lift_time"] / dt))
    n_rest = int(math.ceil(s["rest_time"] / dt))
    if prog.at("pass_done"):
        sim.set_wall_motion(wall, velocity=(0.0, 0.0, 2.0), omega=(0.0, 0.0, 0.0))
        sim.set_wall_motion(hood_w, velocity=(0.0, 0.0, 2.0))
        prog.next("lift")
    if prog.at("lift"):
        prog.checkpoint()
        prog.advance(n_lift, "lift_steps")
        sim.set_wall_motion(wall, velocity=(0.0, 0.0, 0.0))
        sim.set_wall_motion(hood_w, velocity=(0.0, 0.0, 0.0))
        prog.next("rest")
    if prog.at("rest"):
        prog.checkpoint()
        prog.advance(n_rest, "rest_steps")
        prog.next("done")
    prog.finish()
    x, r = sim.x, sim.p.r
    yc = 0.5 * s["slab_width"]
    lat = 0.5 * min(s["slab_width"], nf * spacing) - spec.r_max
    xa, xb = flatness_region(x0, s["travel"], R, _trench_half(s, spec))
    pts = np.linspace(xa, xb, s["flatness_points"])
    d = 1e3 * (surface_heights(x, r, pts, np.full(len(pts), yc), lat) - bed["surface"])
    d_mean, sd, n_empty = flatness_or_nan(d)
    dense = np.linspace(xa, xb, s["dense_points"])
    dd = 1e3 * (surface_heights(x, r, dense, np.full(len(dense), yc), lat) - bed["surface"])
    meas = measured_flatness().get(float(s["rpm"]), float("nan"))
    resp = dict(power_kW=p_mean / 1e3, power_sd_kW=p_sd / 1e3,
                torque_Nm=p_mean / omega, draft_N=draft, draft_sd_N=draft_sd,
                advance_power_kW=draft * vf / 1e3,
                flatness_mm=sd, flatness_dense_mm=flatness_or_nan(dd)[1],
                surface_change_mm=d_mean, flatness_empty_points=n_empty,
                flatness_measured_mm=meas, power_scale=scale,
                peak_overlap=float(out["peak_overlap"]),
                bin_from_cache=bool(out["from_cache"]))
    steps = out["steps"] + out["settle_steps"] + n_lift + n_rest
    return Result(scenario=NAME, preset=preset, seed=int(seed), n_particles=out["n"],
                  steps=int(steps), sim_time_s=(out["steps"] + n_lift + n_rest) * dt,
                  wall_s=prog.wall_s, threads=nthreads, params=params.as_dict(),
                  setup=dict(s), responses=resp,
                  series=dict(t=tt, power_W=power, torque_Nm=out["torque"][:, 1] * scale,
                              flatness_points_mm=d))
