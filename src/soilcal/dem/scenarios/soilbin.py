"""Soil bin shared by the tool scenarios (furrow opener, bulldozing plate, rotary tiller).

Filling and settling -------------------- The bin ``[0, L] x [0, W] x [0, H]`` is filled
with spheres on a jittered hexagonal close-packed lattice
(:func:`soilcal.dem.factories.lattice_fill`, spacing 2.02 r_max) with radii uniform by
number on ``[r (1 - spread), r (1 + spread)]`` (Yangtze clay loam: 8 mm, 0.9-1.1 times, Sec.
2.2.4 of Zeng et al. 2023).  A bin with a mass-fraction size distribution (``psd``, e.g.
the printed 3/2/1 mm split of the cinnamon soil) is filled instead by random sequential
addition (:func:`soilcal.dem.factories.insert_random`) of the distribution's mass at a
solid fraction of ``PSD_FILL_FRACTION`` in a region ``PSD_FILL_FACTOR`` times the fill
height (a lattice sized for the largest particle would hold mostly small ones and collapse
far below the fill height).  The bin is then settled under gravity against a floor and side walls
(periodic in y when the bin is a slab of a wider tool, see the scenarios) for 70 % of
``settle_time`` (or until the translational kinetic energy per particle falls below ``0.5
m_mean (1e-3 m/s)^2``); the lattice region is 1.3 times the fill height, and the particles
whose top is above the fill height (plus half a radius) are then removed and the rest
settles for the remaining 30 %, so the surface ends close to the fill height.  The bin walls
are of the soil material, so a settled bin depends on the soil-soil parameters and the
soil's intrinsic properties only: design points that change only soil-steel parameters reuse
it.

The soil surface level is the median over lateral columns (width 2 r_max) of the highest
particle top ``z_i + r_i`` (:func:`surface_level`); a tool's working depth is measured from
it.

Reuse
-----
A settled bin is saved as an npz snapshot (:func:`soilcal.dem.io.write_snapshot`) under
``$SOILCAL_SCENARIO_CACHE`` (default ``results/cache/soil_bins``) named by the SHA-1 of
the bin geometry, preset, seed, stiffness scale and the soil parameters; the full key is
stored in the snapshot's metadata and compared on load, so a bin is reused only when all
of them match, and settled afresh otherwise.  The tool phase always starts from the
snapshot's positions with zero velocities, so a reused and a fresh bin give the same run.

Trench
------
As in the soil-tank test of the opener, which starts in a trench "slightly greater than
the opener" (Zeng et al. 2023, Sec. 2.1.2), particles inside the tool's starting envelope
(plus one particle diameter) are removed before the tool moves, so the tool never starts
overlapping particles.

Passes refused
--------------
:func:`check_pass` refuses before anything is settled a pass of more than
:data:`MAX_PASS_STEPS` steps and a pushing tool (plate, opener) faster than the speed at
which the soil it pushes reaches the run's ``max_overlap`` (:func:`push_overlap`; 6.2 m/s
for the cinnamon soil of the bulldozing quick preset, whose bed failed at 8.3 m/s (30
km/h) at the same simulated time with the step halved and quartered).

Forces
------
The engine reports, for each wall, the force of the particles on the wall and the torque
about the wall centre every ``log_every`` steps.  Stable-stage statistics are
:func:`soilcal.dem.scenarios.base.stable_mean` over a time window.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from soilcal.dem.contact import model_codes
from soilcal.dem.engine import Simulation
from soilcal.dem.factories import PSD, BoxRegion, UniformRadius, insert_random, lattice_fill
from soilcal.dem.io import read_snapshot, write_particles_vtu, write_mesh_vtp, write_snapshot
from soilcal.dem.materials import DAMPING_DT_SAFETY, rayleigh_time
from soilcal.dem.scenarios.base import (DemParams, build_materials, check, cohesion_scale,
                                        contact_model, paper_psd, rng)

CACHE_VERSION = 2  # 2: settling step capped by the damped-contact bound
FILL_FACTOR = 1.3  # lattice region height / fill height (the bed compacts when it settles)
PSD_FILL_FRACTION = 0.3  # solid fraction of a random (PSD) fill
PSD_FILL_FACTOR = 2.2    # random-fill region height / fill height (0.3 -> about 0.6 settled)
SOIL_KEYS = ("soil_soil_restitution", "soil_soil_static_friction", "soil_soil_rolling_friction",
             "soil_soil_surface_energy", "soil_density", "soil_poisson", "soil_shear_modulus")


@dataclass(frozen=True)
class BinSpec:
    """Soil bin: length (x), width (y), fill height (z), radius and spread, periodic y.

    ``psd``: optional mass-fraction size distribution ``(lower radii, upper radii, mass
    fractions)`` (the fields of :class:`soilcal.dem.factories.PSD`); when given it sets the
    radii (``radius`` is then the nominal radius and ``spread`` is unused).

    ``cohesion_scale``: factor on the surface energies for particles larger than the ones
    the soil's surface energy was calibrated for (base.py, "Cohesion scaling")."""

    length: float
    width: float
    height: float
    radius: float
    spread: float = 0.1
    periodic_y: bool = False
    settle_time: float = 0.5
    stiffness_scale: float = 1.0
    dt_fraction: float = 0.2
    max_overlap: float = 0.5
    skin_fraction: float = 0.6
    psd: tuple | None = None
    cohesion_scale: float = 1.0

    @property
    def dist(self):
        """Radius distribution: the PSD if given, else uniform by number."""
        if self.psd is not None:
            return PSD(*(tuple(float(v) for v in col) for col in self.psd))
        return UniformRadius(self.r_min, self.r_max)

    @property
    def r_min(self):
        if self.psd is not None:
            return float(min(self.psd[0]))
        return self.radius * (1.0 - self.spread)

    @property
    def r_max(self):
        if self.psd is not None:
            return float(max(self.psd[1]))
        return self.radius * (1.0 + self.spread)


def psd_field(psd: PSD) -> tuple:
    """``BinSpec.psd`` value of a :class:`soilcal.dem.factories.PSD`."""
    return (tuple(float(v) for v in psd.lower), tuple(float(v) for v in psd.upper),
            tuple(float(v) for v in psd.mass_fraction))


def apply_preset(setup: dict, defaults: dict, settings: dict, overrides=None) -> dict:
    """Setup with the preset's discretisation: a preset value replaces the setup's value
    unless the user set it; keys the preset leaves at None keep the setup's value.

    User-set keys are those whose value differs from the named setup ``defaults`` or that
    the named setup does not have (e.g. ``stiffness_scale``), plus the keys listed in
    ``overrides`` (an iterable of key names; when None, the setup's own ``"overrides"``
    entry).  A value equal to the named setup's default cannot be told apart from the
    default by comparison, so it counts as set by the user only when listed: with
    ``overrides=["tank_length"]``, ``tank_length=3.0`` under the quick preset stays 3.0.
    Callers that take user overrides should pass their keys."""
    if overrides is None:
        overrides = setup.get("overrides")
    if isinstance(overrides, str):
        overrides = [overrides]
    user_keys = {k for k in setup if k not in defaults or setup[k] != defaults[k]}
    user_keys |= {str(k) for k in (overrides or ())} & set(setup)
    s = dict(setup)
    for k, v in settings.items():
        if v is not None and k not in user_keys:
            s[k] = v
        elif k not in s:
            s[k] = v
    return s


def validate_bin(spec: BinSpec, source: str, prefix: str = "bin"):
    for k in ("length", "width", "height", "radius", "settle_time", "stiffness_scale",
              "dt_fraction"):
        v = getattr(spec, k)
        check(isinstance(v, (int, float)) and math.isfinite(v) and v > 0, source,
              f"{prefix}.{k}", "a number > 0", v)
    check(isinstance(spec.cohesion_scale, (int, float)) and math.isfinite(spec.cohesion_scale)
          and spec.cohesion_scale > 0, source, f"{prefix}.cohesion_scale",
          "a surface-energy factor > 0", spec.cohesion_scale)
    check(0.0 <= spec.spread < 1.0, source, f"{prefix}.spread", "a radius spread in [0, 1)",
          spec.spread)
    check(spec.dt_fraction <= 1.0, source, f"{prefix}.dt_fraction",
          "a fraction of the Rayleigh time in (0, 1]", spec.dt_fraction)
    lim = 3.0 * 2.02 * spec.r_max
    for k in ("length", "width", "height"):
        check(getattr(spec, k) >= lim, source, f"{prefix}.{k}",
              f">= 3 particle diameters ({lim:.4g} m) for radius {spec.radius:g} m",
              getattr(spec, k))


def soil_time_step(spec: BinSpec, params: DemParams) -> float:
    """dt_fraction x the Rayleigh time of the smallest particle (stiffness-scaled soil),
    capped with JKR at the zero-load JKR bound (materials.py) of its soil-soil and
    soil-steel contacts, and at DAMPING_DT_SAFETY x the damped-contact bound (materials.py)
    at the bin's ``max_overlap`` (soil-soil and soil-wall contacts: the settled bin depends
    on the soil parameters only)."""
    g = params.soil_shear_modulus * spec.stiffness_scale
    dt = spec.dt_fraction * rayleigh_time(spec.r_min, params.soil_density, g,
                                          params.soil_poisson)
    mats = build_materials(params, spec.stiffness_scale, "<bin>", spec.cohesion_scale)
    model = contact_model(params)
    rmin, tab = {mats.index("soil"): spec.r_min}, mats.table(model_codes(**model)[1])
    if model["cohesion"] == "jkr":
        dt = min(dt, mats.jkr_dt(rmin, tab))
    # soil walls only: the settled bin (cached) must not depend on the tool's steel
    return min(dt, DAMPING_DT_SAFETY * mats.damping_dt(rmin, tab, spec.max_overlap,
                                                       wall_materials={mats.index("soil")}))


def tool_time_step(spec: BinSpec, params: DemParams) -> float:
    """:func:`soil_time_step` also capped at DAMPING_DT_SAFETY x the damped-contact bound of
    the soil-steel contacts: the tool is a steel wall, and a low soil-steel restitution (a
    heavily damped contact) lowers the bound below the settling step's."""
    mats = build_materials(params, spec.stiffness_scale, "<bin>", spec.cohesion_scale)
    model = contact_model(params)
    rmin, tab = {mats.index("soil"): spec.r_min}, mats.table(model_codes(**model)[1])
    return min(soil_time_step(spec, params),
               DAMPING_DT_SAFETY * mats.damping_dt(rmin, tab, spec.max_overlap))


#: Peak overlap of a line of touching Hertz spheres (mass m, pair law F = k delta^(3/2), no
#: damping) that a rigid wall pushes at a constant speed v, in units of (m v^2 / k)^(2/5):
#: the wave the wall starts overshoots the steady compression (m v^2 / k)^(2/5) of mass and
#: momentum balance; integrating the dimensionless chain gives 1.73, 1.75 and 1.76 for 60,
#: 120 and 200 spheres (tests/dem/scenarios/test_tool_limits.py integrates it again).
CHAIN_PEAK = 1.76
#: Most steps one tool pass may take: 6 times the longest pass of the papers' presets (the
#: bulldozing plate's 4.5 s at 5.3 us, 849,000 steps).  A slower tool takes proportionally
#: more steps (a speed typed in km/h as m/s/1000 or so would grind for hours).
MAX_PASS_STEPS = 5_000_000


def push_overlap(params: DemParams, stiffness_scale: float, speed: float) -> float:
    """Peak soil-soil overlap, as a fraction of the radius, of a bed a tool pushes at
    ``speed`` [m/s]: :data:`CHAIN_PEAK` (m v^2 / k)^(2/5) / r for two equal spheres
    (m = 4/3 pi r^3 rho, k = 4/3 E* sqrt(r/2)), i.e. CHAIN_PEAK (sqrt(2) pi rho v^2 /
    E*)^(2/5), the same for every radius (E* = E / (2 (1 - nu^2)) of the soil, its shear
    modulus scaled by ``stiffness_scale``).  The quick bulldozing bed pushed at 1, 4, 6 and
    7 m/s peaked at 1.0, 0.93, 0.89 and 0.87 times this value (restitution 0.45)."""
    g = params.soil_shear_modulus * stiffness_scale
    nu = params.soil_poisson
    estar = 2.0 * g * (1.0 + nu) / (2.0 * (1.0 - nu * nu))
    return CHAIN_PEAK * (math.sqrt(2.0) * math.pi * params.soil_density * speed ** 2
                         / estar) ** 0.4


def push_speed_limit(params: DemParams, stiffness_scale: float, max_overlap: float) -> float:
    """Tool speed [m/s] at which :func:`push_overlap` reaches ``max_overlap``."""
    return math.sqrt((max_overlap / push_overlap(params, stiffness_scale, 1.0)) ** 2.5)


def check_pass(spec: BinSpec, params: DemParams, source: str, field: str, speed: float,
               travel: float, dt: float, pushes: bool = True, duration_field: str | None = None) -> None:
    """Refuse, before the bin is settled, a tool pass the run could not finish: one of more
    than :data:`MAX_PASS_STEPS` steps of ``dt`` (``travel`` at ``speed``), or (``pushes``: a
    tool that pushes the soil ahead of it) a speed at which the pushed bed's overlaps reach
    the run's ``max_overlap`` (:func:`push_overlap`: the run would stop with a blow-up
    whatever its time step).  ``field`` names the speed's setting; ``duration_field`` the
    duration's, where the travel is the speed times that duration (the step count is then
    the duration's, whatever the speed)."""
    steps = math.ceil(travel / speed / dt)
    if duration_field is not None:
        check(steps <= MAX_PASS_STEPS, source, duration_field,
              f"a pass of at most {MAX_PASS_STEPS:,} steps: a duration <= {MAX_PASS_STEPS * dt:.4g} s at the "
              f"pass's time step of {dt:.4g} s (or a setup.travel of its own)",
              f"{travel / speed:.4g} s of pass, {steps:,} steps")
    else:
        check(steps <= MAX_PASS_STEPS, source, field,
              f"a speed whose pass of setup.travel = {travel:.4g} m takes at most "
              f"{MAX_PASS_STEPS:,} steps (>= {travel / (MAX_PASS_STEPS * dt):.3g} m/s at the "
              f"pass's time step of {dt:.4g} s)",
              f"{speed:.4g} m/s: {travel / speed:.4g} s of pass, {steps:,} steps")
    if pushes:
        vmax = push_speed_limit(params, spec.stiffness_scale, spec.max_overlap)
        check(speed <= vmax, source, field,
              f"a speed <= {vmax:.3g} m/s, where the soil the tool pushes reaches overlaps of "
              f"max_overlap = {100 * spec.max_overlap:g} % of a radius (soil density "
              f"{params.soil_density:g} kg/m^3, shear modulus "
              f"{params.soil_shear_modulus * spec.stiffness_scale:.4g} Pa; a stiffer soil "
              "carries a faster tool)",
              f"{speed:.4g} m/s ({3.6 * speed:.3g} km/h): overlaps of about "
              f"{100 * push_overlap(params, spec.stiffness_scale, speed):.3g} %")


#: the soil-bin keys of every named setup: the particle sizes the surface energy is for
#: (None: the paper preset's bin of the named setup) and the particle-size rule's switch
COHESION_KEYS = dict(paper_psd=None, scale_cohesion=True)


def reference_dist(spec: BinSpec, reference: BinSpec, setup: dict, source: str):
    """The particle sizes a bin's surface energy is for: the setup's ``paper_psd`` rows
    ``[radius_m, mass_percent]`` (:func:`soilcal.dem.scenarios.base.paper_psd`), radii the
    run's bin ``spec`` holds as it holds its own spheres (every side at least three diameters,
    :func:`validate_bin`), or, where the setup leaves it at None, the distribution of
    ``reference``, the paper preset's bin of the named setup."""
    if setup.get("paper_psd") is None:
        return reference.dist
    ref = paper_psd(setup, source)
    side = min(spec.length, spec.width, spec.height)
    lim = side / (3.0 * 2.02)
    check(max(ref.upper) <= lim, source, "setup.paper_psd",
          f"particle radii in metres that the bin holds (at most {lim:.4g} m: three diameters across its "
          f"{side:g} m side)", setup.get("paper_psd"))
    return ref


def reference_cohesion(spec: BinSpec, reference: BinSpec, setup: dict, source: str) -> float:
    """Surface-energy factor of a bin against the particle sizes its surface energy is for
    (:func:`reference_dist`; base.py, "Cohesion scaling"): 1 with ``scale_cohesion: false``."""
    return cohesion_scale(spec.dist, reference_dist(spec, reference, setup, source), setup, source)


def new_sim(spec: BinSpec, params: DemParams, dt: float, source: str) -> Simulation:
    mats = build_materials(params, spec.stiffness_scale, source, spec.cohesion_scale)
    box = (0.0, spec.length, 0.0, spec.width)
    sim = Simulation(mats, dt=dt, box=box, periodic=(False, spec.periodic_y),
                     contact_model=contact_model(params), max_overlap=spec.max_overlap,
                     skin=spec.skin_fraction * spec.r_max, source=source)
    # static planes; their centres (used by the engine only to bound how far a moving
    # wall can sweep per step) sit at the bin centre
    c = (0.5 * spec.length, 0.5 * spec.width, 0.5 * spec.height)
    sim.add_plane((0, 0, 0), (0, 0, 1), "soil", name="floor", centre=c)
    sim.add_plane((0, 0, 0), (1, 0, 0), "soil", name="x_lo", centre=c)
    sim.add_plane((spec.length, 0, 0), (-1, 0, 0), "soil", name="x_hi", centre=c)
    if not spec.periodic_y:
        sim.add_plane((0, 0, 0), (0, 1, 0), "soil", name="y_lo", centre=c)
        sim.add_plane((0, spec.width, 0), (0, -1, 0), "soil", name="y_hi", centre=c)
    return sim


def cache_key(spec: BinSpec, params: DemParams, preset: str, seed: int) -> dict:
    p = params.as_dict()
    b = asdict(spec)
    if b["psd"] is None:
        del b["psd"]  # uniform bins keep the key they had before PSD bins existed
    key = dict(version=CACHE_VERSION, bin=b, preset=preset, seed=int(seed),
               soil={k: p[k] for k in SOIL_KEYS})
    return json.loads(json.dumps(key))  # as stored in (and read back from) the snapshot


def fill_bin(spec: BinSpec, g, source: str):
    """Unsettled positions and radii of the bin's fill (see the module notes)."""
    if spec.psd is None:
        region = BoxRegion((0.0, 0.0, 0.0),
                           (spec.length, spec.width, FILL_FACTOR * spec.height))
        return lattice_fill(region, dist=spec.dist, kind="hcp", jitter=0.5, rng=g,
                            source=source, field="bin")
    h = PSD_FILL_FACTOR * spec.height
    region = BoxRegion((0.0, 0.0, 0.0), (spec.length, spec.width, h))
    # any density works: the mass only sets the solid volume
    vol = PSD_FILL_FRACTION * spec.length * spec.width * h
    return insert_random(region, spec.dist, mass=vol, density=1.0, rng=g, source=source,
                         field="bin")


def cache_dir() -> Path:
    return Path(os.environ.get("SOILCAL_SCENARIO_CACHE", "results/cache/soil_bins"))


def surface_level(x, r, spec: BinSpec) -> float:
    """Median over lateral columns of the highest particle top z + r."""
    tops = column_tops(x, r, 2.0 * spec.r_max, (0.0, spec.length), (0.0, spec.width))
    return float(np.nanmedian(tops))


def column_tops(x, r, cell, xr, yr):
    """Highest particle top z + r in each (x, y) column of size ``cell``; NaN if empty."""
    nx = max(1, int((xr[1] - xr[0]) / cell))
    ny = max(1, int((yr[1] - yr[0]) / cell))
    ix = np.clip(((x[:, 0] - xr[0]) / (xr[1] - xr[0]) * nx).astype(int), 0, nx - 1)
    iy = np.clip(((x[:, 1] - yr[0]) / (yr[1] - yr[0]) * ny).astype(int), 0, ny - 1)
    ok = ((x[:, 0] >= xr[0]) & (x[:, 0] <= xr[1]) & (x[:, 1] >= yr[0]) & (x[:, 1] <= yr[1]))
    tops = np.full(nx * ny, -np.inf)
    np.maximum.at(tops, (ix * ny + iy)[ok], (x[:, 2] + r)[ok])
    tops[~np.isfinite(tops)] = np.nan
    return tops.reshape(nx, ny)


def settled_bin(spec: BinSpec, params: DemParams, preset: str, seed: int, source: str,
                use_cache: bool = True, progress=None) -> dict:
    """Positions and radii of a settled bin (from the cache when the key matches).

    Returns dict(x, r, surface, settle_steps, settle_wall_s, from_cache, n).  ``progress``: the
    run's :class:`soilcal.dem.restart.Progress`; the two settling rounds are its phases
    ``bin_0`` and ``bin_1``, and a run resumed past them gets the bin's numbers without
    ``x`` and ``r`` (None: its simulation holds the particles)."""
    from soilcal.dem import restart as rst

    prog = progress if progress is not None else rst.Progress()
    if "bed" in prog.vars:
        return dict(prog.vars["bed"], x=None, r=None)
    key = cache_key(spec, params, preset, seed)
    text = json.dumps(key, sort_keys=True)
    path = cache_dir() / f"bin-{hashlib.sha1(text.encode()).hexdigest()[:20]}.npz"
    if use_cache and path.exists() and not prog.phase:
        try:
            snap = read_snapshot(path)
        except Exception:  # unreadable cache file: settle afresh
            snap = None
        if snap is not None and snap["metadata"].get("key") == key:
            md = snap["metadata"]
            bed = dict(surface=md["surface"], settle_steps=int(snap["step"]),
                       settle_wall_s=md["settle_wall_s"], from_cache=True,
                       n=len(snap["radii"]))
            prog.vars["bed"] = bed
            return dict(bed, x=snap["positions"], r=snap["radii"])
    dt = soil_time_step(spec, params)
    if prog.phase not in ("bin_0", "bin_1"):
        g = rng(seed, "soil-bin")
        # fill a taller region, settle, trim to the fill height, settle again
        x, r = fill_bin(spec, g, source)
        sim = new_sim(spec, params, dt, source)
        sim.add_particles(x, r, "soil")
        prog.begin(sim, "bin_0", bin_steps=0, bin_wall0=prog.wall_s,
                   bin_m_mean=float(np.mean(params.soil_density * 4.0 / 3.0 * math.pi * r**3)))
    st = prog.vars
    for i, frac in enumerate((0.7, 0.3)):
        if not prog.at(f"bin_{i}"):
            continue
        sim = prog.sim
        ke_tol = int(sim.n) * 0.5 * st["bin_m_mean"] * 1e-6
        max_steps = int(math.ceil(frac * spec.settle_time / dt))
        first = max(1, max_steps // 5)
        prog.checkpoint()
        prog.advance(first, f"bin_{i}_first")
        if max_steps > first:
            prog.run_to_rest(max_steps - first, ke_tol, 50, f"bin_{i}_rest")
        st["bin_steps"] += int(sim.step)
        x, r = sim.x.copy(), sim.p.r.copy()
        if i == 0:
            keep = x[:, 2] + r <= spec.height + 0.5 * spec.radius
            nxt = new_sim(spec, params, dt, source)
            nxt.add_particles(x[keep], r[keep], "soil")
            prog.begin(nxt, "bin_1")
    xs, rs = x, r
    surf = surface_level(xs, rs, spec)
    wall = prog.wall_s - st["bin_wall0"]
    steps = st["bin_steps"]
    if use_cache:
        write_snapshot(path, xs, np.zeros_like(xs), rs, np.zeros(len(rs), dtype=np.int32),
                       steps * dt, steps,
                       metadata=dict(key=key, surface=surf, settle_wall_s=wall))
    bed = dict(surface=surf, settle_steps=int(steps), settle_wall_s=wall, from_cache=False,
               n=len(rs))
    prog.next("bin_done", bed=bed)
    return dict(bed, x=xs, r=rs)


def dig(x, r, inside) -> np.ndarray:
    """Boolean mask of particles to keep: ``inside(x, r)`` True marks the trench."""
    return ~np.asarray(inside(x, r), dtype=bool)


def force_series(sim: Simulation, wall: int, log_every: int, step0: int, dt: float,
                 start: int | None = None):
    """(t, force[n, 3], torque[n, 3]) of one wall from the last run's wall log, whose rows
    are counted from the run call's first step ``start`` (default ``step0``); t is the time
    since ``step0``, from whole step counts (the same numbers however a pass is split into
    calls)."""
    wl = sim.wall_log
    n = wl.shape[0]
    start = step0 if start is None else start
    steps = start + (np.arange(n) + 1) * log_every
    return (steps - step0) * dt, wl[:, wall, 0:3].copy(), wl[:, wall, 3:6].copy()


def tool_pass(spec: BinSpec, params: DemParams, preset: str, seed: int, source: str,
              vertices, triangles, velocity, duration: float, trench, omega=(0.0, 0.0, 0.0),
              centre=None, dt_max: float | None = None, log_dt: float = 0.01,
              vtk_dir=None, stem: str = "tool", n_frames: int = 5, use_cache: bool = True,
              tool_pose=None, bed=None, extra_walls=None, progress=None):
    """Settled (or cached) bin, trench dug by ``trench(x, r) -> bool``, the tool mesh
    (steel) moved with ``velocity``/``omega`` about ``centre`` for ``duration`` s.

    Returns dict(sim, t, force, torque, dt, steps, settle_steps, peak_overlap,
    wall_forces, n, from_cache, surface, log_every); ``force``/``torque`` are the particles'
    force on the tool and its torque about the (moving) tool centre, sampled every
    ``log_every`` steps; ``wall_forces[k, w]`` the particles' force on every wall w (in the
    order of ``sim.walls.names``) at the same samples; ``peak_overlap`` is the largest
    overlap of the pass as a fraction of a radius.  ``progress``: the run's
    :class:`soilcal.dem.restart.Progress` (phase ``pass``, then ``pass_done``); with a restart
    file the pass runs in pieces of about ``CHUNK_STEPS`` steps (whole log intervals), the
    same samples as one piece."""
    from soilcal.dem import restart as rst

    prog = progress if progress is not None else rst.Progress()
    if "pass_out" in prog.vars:
        return dict(prog.vars["pass_out"], sim=prog.sim)
    if bed is None:
        bed = settled_bin(spec, params, preset, seed, source, use_cache, progress=prog)
    dt = tool_time_step(spec, params)
    if dt_max is not None:
        dt = min(dt, float(dt_max))
    log_every = max(1, int(round(log_dt / dt)))
    steps = int(math.ceil(duration / dt / log_every)) * log_every
    vtk = VtkWriter(vtk_dir, stem)
    chunks = max(1, int(n_frames) - 1) if vtk.folder else 1
    per = int(math.ceil(steps / log_every / chunks)) * log_every
    if not prog.at("pass"):
        keep = dig(bed["x"], bed["r"], trench)
        sim = new_sim(spec, params, dt, source)
        sim.add_particles(bed["x"][keep], bed["r"][keep], "soil")
        sim.add_mesh(vertices, triangles, "steel", name=stem, velocity=velocity,
                     omega=omega, centre=centre)
        if extra_walls is not None:
            extra_walls(sim)
        if vtk.folder:
            vtk.frame(sim, *(tool_pose(0.0) if tool_pose else (None, None)))
        prog.begin(sim, "pass", pass_step0=sim.step, pass_done=0, pass_n=int(keep.sum()),
                   ts=[], qs=[], fa=[], vtk_k=vtk.k)
    sim, st = prog.sim, prog.vars
    vtk.k = st["vtk_k"]
    wall = sim.walls.names.index(stem)
    step0 = st["pass_step0"]
    piece = steps if prog.restart is None else max(1, rst.CHUNK_STEPS // log_every) * log_every
    while st["pass_done"] < steps:
        prog.checkpoint()
        frame_end = min(steps, (st["pass_done"] // per + 1) * per)
        k = min(piece, frame_end - st["pass_done"])
        s0 = sim.step
        sim.run(k, wall_log_every=log_every)  # log rows counted from the start of this call
        t, _, q = force_series(sim, wall, log_every, step0, dt, start=s0)
        st["ts"].append(t)
        st["fa"].append(sim.wall_log[:, :, 0:3].copy())
        st["qs"].append(q)
        st["pass_done"] += k
        if vtk.folder and st["pass_done"] == frame_end:
            tt = (sim.step - step0) * dt
            vtk.frame(sim, *(tool_pose(tt) if tool_pose else (None, None)))
            st["vtk_k"] = vtk.k
    wall_forces = np.concatenate(st["fa"])
    out = dict(t=np.concatenate(st["ts"]), force=wall_forces[:, wall].copy(),
               torque=np.concatenate(st["qs"]), dt=dt, steps=steps,
               settle_steps=bed["settle_steps"], peak_overlap=sim.peak_overlap,
               wall_forces=wall_forces, n=st["pass_n"], from_cache=bed["from_cache"],
               surface=bed["surface"], log_every=log_every, wall=wall)
    for name in ("ts", "qs", "fa"):
        del st[name]
    prog.next("pass_done", pass_out=out)
    return dict(out, sim=sim)


class VtkWriter:
    """Particle (.vtu) and tool (.vtp) frames into a folder (no-op without a folder)."""

    def __init__(self, folder, stem):
        self.folder = Path(folder) if folder else None
        self.stem = stem
        self.k = 0
        if self.folder:
            self.folder.mkdir(parents=True, exist_ok=True)

    def frame(self, sim: Simulation, tool_vertices=None, tool_triangles=None):
        if not self.folder:
            return
        write_particles_vtu(self.folder / f"{self.stem}_particles_{self.k:04d}.vtu",
                            sim.x, sim.p.r, velocities=sim.v, ids=sim.p.id)
        if tool_vertices is not None:
            write_mesh_vtp(self.folder / f"{self.stem}_tool_{self.k:04d}.vtp", tool_vertices,
                           tool_triangles)
        self.k += 1
