"""Static angle of repose: cylinder lifting and funnel discharge onto a plate.

Procedures (dimensions and speeds cited in :func:`setups`)
----------------------------------------------------------
Cylinder lifting (cinnamon soil, 002 Sec. 2.4; vineyard soil, 003 "Static angle of repose"):
a steel tube standing on the plate is filled with loose soil, then lifted vertically at a
constant speed until all soil has left it; the heap on the plate is measured at rest.  In the
simulation the spheres are placed at random in the tube (random sequential addition, at most
30 % solid fraction) and settle under gravity inside it; the tube is then moved up at
``lift_speed`` by the settled fill height plus d_max (the largest diameter), or until its rim
is a radius above the highest sphere (nothing touches it any more), stopped, and the heap
settles.

Funnel discharge (black soil, 001 Sec. 2.2.1; cohesive soil, 004 Sec. 2.2 / Fig. 4): soil is
loaded into a funnel whose outlet is covered, the cover is removed and the soil flows onto
the plate.  In the simulation the spheres are placed at random above a disc covering the
outlet, in the frustum of the funnel just tall enough to hold them at 30 % solid fraction
(at least four radii tall; a cylinder above the funnel's top takes what the whole funnel
cannot hold), and settle, so that no sphere falls much more than half that height onto
the cover or the spheres below (the quick preset's soft spheres take large overlaps on
impact).  The disc is pulled sideways at ``cover_speed`` (1 m/s) until clear of the outlet,
and the heap settles.  The cover is a smooth gate (:data:`GATE`, :func:`_add_gate`): the
funnel's own material in mass and stiffness, with the restitution of the soil against it, but
no sliding or rolling friction and no cohesion with the soil, so that pulling it away lets
the load fall and does not drag the bottom layer sideways.  The papers do not model the
cover (they only open the outlet), and a rough one is an artefact of the procedure: pulled
at 1 m/s under a black-soil load with the soil's own friction (stage 1, soil walls), the
cover dragged the bottom spheres against the others at up to 0.7 m/s, and at a soil-soil
friction of 1.0, the stage's high level, 3 of the 8 Box-Behnken points of that level stopped
with an overlap above 30 % of a radius while the cover moved; with the smooth gate the same
three points (same seeds) ran to a heap.

Rest: the translational kinetic energy falls below 1/2 M v_rest^2 with M the total mass and
v_rest = ``rest_speed`` (a mean speed of 5 mm/s by default: resting beds keep a
jitter of about 1/2 M (3 mm/s)^2 with the constant-torque rolling model, whose torque flips
with the sign of a vanishing angular velocity), checked every 200 steps, with
``max_settle_time`` as an upper bound (the run then reports ``settled = 0``).  With
``read_time`` (seconds, None by default) the heap is instead read that long after the release
starts (the cover starts to move, the tube starts to lift), whatever it is doing then: a
paper's fixed simulated duration, for a heap that has no resting state to stop at; the fill's
settle keeps the rest rule, ``settled`` then says whether the heap's kinetic energy is below
the rest threshold at the reading, and a release that takes longer than ``read_time`` is an
error naming ``setup.read_time`` (for the funnel at start-up, from the cover's travel; for
the cylinder, whose lift depends on the settled fill, at the release).

Rolling resistance: the setup's ``rolling_model`` (base.py; ``constant_torque`` by default,
under which the heap keeps creeping after the rest criterion; ``bounded`` stops the
rotation of every sphere whose resistance suffices).

Number of particles for a fill volume V (tube: pi D^2/4 h_fill; funnel: load mass /
(rho_p phi)) at the settled solid fraction phi = 0.6::

    N = phi V / <v_p>,      <v_p> = 4/3 pi <r^3>

``quick``: radii uniform in [0.9, 1.1] r_q with r_q from N = ``n_particles`` (1000 spheres by
default) for cylinders; funnels keep the setup's ``load_mass`` with r_q = outlet diameter / 16
(8 diameters across the outlet), or the larger r_q that splits the load into
``QUICK_FUNNEL_MAX`` = 8000 spheres (black soil, 0.5 kg at 1560 kg/m^3: 2482 spheres;
cohesive soil, 0.2 kg at 1802 kg/m^3: 3980).  The heap needs the load: 1000 spheres of
black soil (0.2 kg) left the outlet as a thin stream and spread into a layer two or three
spheres deep on the plate.  Soil shear modulus capped at 5e5 Pa (stiffness scaling,
base.py); surface energies times r32(quick) / r32(paper PSD) (cohesion scaling, base.py;
``cohesion_scale`` in the run's setup).  ``paper``: the papers' particle sizes and masses,
unscaled moduli.  A setup's
``n_particles`` or ``radius`` (either preset) splits the tube fill or the funnel's
``load_mass`` into that many spheres or spheres of that radius.

Walls: the tube is the engine's analytic cylinder; the funnel and its cover are triangle
meshes (``N_SEG`` = 24 facets around, vertices at R / cos(pi/24) so the facet mid-lines lie
on the nominal radius R).  Cylinders, cones, discs and triangles push from both sides.

Plate: the plane z = 0 (steel, 65Mn, or soil for the black-soil stage 1); spheres beyond the
square plate's outline would have fallen off it: they are counted as ``n_lost`` and excluded
from the measurement.

Responses: ``angle_deg`` (radial bins, eight directions, :mod:`soilcal.dem.measure`),
``angle_sd_deg`` (spread of the eight directions), ``angle_surface_deg`` and
``angle_surface_sd_deg`` (surface scan: sector profiles of the height map traced by a probe
of one mean radius, eight directions; scatter over seeds of the three estimators:
``benchmarks/repose_seeds.py``), ``angle_image_deg`` (side silhouettes through the photo
pipeline: ``image_views`` views, default ``IMAGE_VIEWS`` = 8, at azimuths 180 k / n deg, two
flanks each; ``angle_image_sd_deg`` their spread; a view the pipeline cannot measure is left
out and named in ``measure_errors``, more than half of the views must measure; a soil's
workflow job renders them only when it measures this angle, :func:`for_measures`),
``height_m``, ``n_on_plate``, ``n_lost``, ``n_retained`` and ``retained_fraction`` (funnel),
``settled``, ``settle_time_s``.  An estimator that cannot read the heap (a load spread flat
over the plate has no flank the silhouette pipeline can find; too few spheres stayed on the
plate) reports NaN and its reason in ``measure_errors`` (empty when all three read the heap,
the silhouettes from every view); the run itself does not fail.  A cohesive load can arch
over the funnel's outlet and stay in the funnel: when more than ``max_retained`` (default
20 %, by sphere count) of the spheres are still above the outlet when the run stops, every
angle is NaN and ``measure_errors`` says so (the spheres on the plate are not the test's
heap).  The default: quick black-soil loads of 1000 spheres
that discharged kept 0.2-9 % of their spheres on the funnel walls (design points of stage
1, before commit ff7f5f6), those that arched 60-98 %; full 2482-sphere loads kept
0.2-3.4 % with the quick preset and 79-99 % when they arched or stopped unsettled (two
design points, ``benchmarks/results/stiffness_rule.md``).
"""

from __future__ import annotations

import math

import numpy as np

from soilcal.dem import measure
from soilcal.dem.factories import ConeRegion, CylinderRegion, UniformRadius, insert_random
from soilcal.dem.geometry import cone_mesh, disk_mesh
from soilcal.dem.scenarios.base import (DemParams, Frames, Result, check, check_discretisation,
                                        check_preset, make_simulation, paper_cohesion, paper_psd,
                                        rest_tolerance, rng, run_time, setup_number,
                                        threads_used)
from soilcal.errors import InputError

NAME = "repose"
#: writes and reads restart files (soilcal.dem.restart)
RESTARTABLE = True
#: every response a run reports (``Result.responses``)
RESPONSES = (
    "angle_deg", "angle_sd_deg", "height_m", "angle_surface_deg", "angle_surface_sd_deg",
    "angle_image_deg", "angle_image_sd_deg", "n_on_plate", "n_lost", "n_retained",
    "retained_fraction", "settled", "settle_time_s", "peak_overlap", "measure_errors",
)
#: the responses a soil's ``simulation`` block may measure (numbers a design point yields)
MEASURES = (
    "angle_deg", "angle_sd_deg", "height_m", "angle_surface_deg", "angle_surface_sd_deg",
    "angle_image_deg", "angle_image_sd_deg",
)
PHI = 0.6  # settled solid fraction used to size the fill
FILL_FRACTION = 0.30  # solid fraction of the random placement before the load settles
QUICK_FUNNEL_MAX = 8000  # most spheres of a quick funnel load (module docstring)
MAX_RETAINED = 0.2  # share of a funnel's spheres that may stay in it (module docstring)
IMAGE_VIEWS = 8  # side views of the silhouette angle (module docstring)
N_SEG = 24  # facets of the funnel and cover meshes (facet mid-lines on the nominal radius)
GATE = "gate"  # material of the funnel's cover (module docstring, "Funnel discharge")


def measures(setup: dict) -> tuple:
    """MEASURES a run of ``setup`` yields (the silhouette angle needs ``image``)."""
    return tuple(m for m in MEASURES
                 if not (m.startswith("angle_image") and not setup.get("image", True)))


def for_measures(setup: dict, measures: tuple) -> dict:
    """The silhouettes (``image``) only when a silhouette angle is measured: rendering and
    measuring ``image_views`` views costs about 0.2 s per view (a 2,348-sphere heap); the
    other estimators read the same final state, so their numbers do not change."""
    if setup.get("image", True) and not any(m.startswith("angle_image") for m in measures):
        return dict(setup, image=False)
    return setup


def setups() -> dict:
    """Named setups; every number with the section of the paper it comes from."""
    common = dict(rest_speed=0.005, max_settle_time=4.0, image=True, image_views=IMAGE_VIEWS,
                  n_particles=None,
                  radius=None, stiffness_scale=None, dt_fraction=None, rolling_model=None,
                  contact_conventions=None, seed_stream="repose", scale_cohesion=True,
                  read_time=None)
    cyl = dict(common, method="cylinder", wall_material="steel", plate_material="steel")
    fun = dict(common, method="funnel", wall_material="steel", plate_material="steel",
               cover_speed=1.0, max_retained=MAX_RETAINED)
    return {
        # 002 Sec. 2.4: steel cylinder 60 mm diameter, lifted at 0.05 m/s, square steel plate.
        # Tube height, fill and plate size are not printed: fill height = diameter, 0.3 m plate.
        # 002 Sec. 3.1: model particle sizes 3, 2, 1 mm (mass 8.85, 8.2, 82.95 %); reading them
        # as diameters is an assumption (the paper says only 'particle size').
        "cinnamon-soil": dict(cyl, tube_diameter=0.060, tube_height=0.120, fill_height=0.060,
                              lift_speed=0.05, plate_size=0.30,
                              paper_psd=[[0.0015, 8.85], [0.0010, 8.20], [0.0005, 82.95]]),
        # 003 "Test apparatus": cylinder 1, inner diameter 40 mm, height 100 mm; 65Mn sheet;
        # "Static angle of repose": lifted at 25 mm/s, cylinder filled with the soil.
        # 003 "Discrete element simulation modeling": scaled particles 2.5, 5, 10 mm (taken as
        # diameters; their mass split is not printed: equal thirds).  Plate size not printed.
        "xinjiang-vineyard-40mm": dict(cyl, tube_diameter=0.040, tube_height=0.100,
                                       fill_height=0.100, lift_speed=0.025, plate_size=0.30,
                                       paper_psd=[[0.00125, 33.34], [0.0025, 33.33],
                                                  [0.005, 33.33]]),
        # 003 "Test apparatus": cylinder 2, inner diameter 100 mm, height 100 mm.
        "xinjiang-vineyard-100mm": dict(cyl, tube_diameter=0.100, tube_height=0.100,
                                        fill_height=0.100, lift_speed=0.025, plate_size=0.40,
                                        paper_psd=[[0.00125, 33.34], [0.0025, 33.33],
                                                   [0.005, 33.33]]),
        # 001 Sec. 2.2.1: funnel top 192 mm, bottom 50 mm, height 274 mm, 400 x 400 mm base
        # plate; particle diameters 2-4 mm; stage 1: every entity has the soil's properties.
        # Outlet height above the plate and load mass not printed: 100 mm, 0.5 kg.  The mass
        # split over the 2-4 mm range is not printed either: 50 % at each end is an assumption.
        "black-soil-stage1": dict(fun, wall_material="soil", plate_material="soil",
                                  funnel_top_diameter=0.192, funnel_bottom_diameter=0.050,
                                  funnel_height=0.274, outlet_height=0.100, plate_size=0.40,
                                  load_mass=0.5, paper_psd=[[0.0010, 50.0], [0.0020, 50.0]]),
        # 001 Sec. 2.2.2: same apparatus, 65Mn steel base plate (stage 2).
        "black-soil-stage2": dict(fun, funnel_top_diameter=0.192, funnel_bottom_diameter=0.050,
                                  funnel_height=0.274, outlet_height=0.100, plate_size=0.40,
                                  load_mass=0.5, paper_psd=[[0.0010, 50.0], [0.0020, 50.0]]),
        # 004 Sec. 2.2 / Fig. 4: funnel top 150 mm, bottom 30 mm, height 130 mm, outlet 70 mm
        # above the receiving plate; 200-250 g per test; Sec. 2.6: 0.2 kg generated in the
        # simulation; sizes 2.5 (14 %), 1.25 (14 %), 0.63 (22 %), 0.315 mm (50 %) (diameters).
        # Plate size not printed: 0.3 m.
        "guangxi-cohesive": dict(fun, funnel_top_diameter=0.150, funnel_bottom_diameter=0.030,
                                 funnel_height=0.130, outlet_height=0.070, plate_size=0.30,
                                 load_mass=0.2,
                                 paper_psd=[[0.00125, 14.0], [0.000625, 14.0],
                                            [0.000315, 22.0], [0.0001575, 50.0]]),
    }




def _fill_volume(setup, params: DemParams | None):
    if setup["method"] == "cylinder":
        return math.pi * setup["tube_diameter"] ** 2 / 4 * setup["fill_height"]
    rho = (params or DemParams()).soil_density
    return setup["load_mass"] / (rho * PHI)


def _funnel_volume(setup):
    R, r, h = setup["funnel_top_diameter"] / 2, setup["funnel_bottom_diameter"] / 2, setup["funnel_height"]
    return math.pi * h / 3 * (R * R + R * r + r * r)


def sizing(setup, preset, params: DemParams | None = None) -> dict:
    """Radius distribution, particle count and load of a run (before any simulation)."""
    d = check_preset(preset)
    n_set = setup.get("n_particles")
    r_set = setup.get("radius")
    vol = _fill_volume(setup, params)
    if setup["method"] == "funnel" and preset == "quick" and r_set is None and n_set is None:
        # the setup's load, 8 diameters across the outlet, at most QUICK_FUNNEL_MAX spheres
        r_cap = UniformRadius.splitting(PHI * vol, QUICK_FUNNEL_MAX)
        r_set = max(setup["funnel_bottom_diameter"] / 16.0, r_cap.r_mid)
    if preset == "paper" and r_set is None and n_set is None:
        dist = paper_psd(setup, "<setup>")
    elif r_set is None:
        dist = UniformRadius.splitting(PHI * vol, int(n_set or d["n_particles"]))
    else:
        dist = UniformRadius.about(r_set)
    vmean = dist.mean_volume()
    if n_set is not None and setup["method"] == "funnel":
        n = int(n_set)
        rho = (params or DemParams()).soil_density
        load_mass = n * vmean * rho
    else:
        n = int(round(PHI * vol / vmean))
        load_mass = setup.get("load_mass")
    return dict(dist=dist, n=n, r_max=float(dist.r_max), r_mean=float((3 * vmean / (4 * math.pi)) ** (1 / 3)),
                load_mass=load_mass)


def validate(setup: dict, preset: str = "quick", source: str = "<input>",
             params: DemParams | None = None) -> None:
    """Bad geometry or impossible settings raise InputError before anything runs."""
    check_preset(preset, source)
    method = setup.get("method")
    check(method in ("cylinder", "funnel"), source, "setup.method", "'cylinder' or 'funnel'", method)
    for key in ("plate_material", "wall_material"):
        check(setup.get(key) in ("steel", "soil"), source, f"setup.{key}", "'steel' or 'soil'",
              setup.get(key))
    plate = setup_number(setup, "plate_size", source)
    setup_number(setup, "rest_speed", source)
    setup_number(setup, "max_settle_time", source)
    rt = setup.get("read_time")
    check(rt is None or (isinstance(rt, (int, float)) and not isinstance(rt, bool) and math.isfinite(rt)
                         and rt > 0), source, "setup.read_time",
          "a simulated time > 0 s after the release (cover or lift) to read the heap at, or None to read "
          "it when it comes to rest", rt)
    views = setup.get("image_views", IMAGE_VIEWS)
    check(isinstance(views, int) and not isinstance(views, bool) and views >= 1, source,
          "setup.image_views", "a number of side views >= 1", views)
    check_discretisation(setup, source)
    if method == "cylinder":
        dia = setup_number(setup, "tube_diameter", source)
        h = setup_number(setup, "tube_height", source)
        fill = setup_number(setup, "fill_height", source)
        setup_number(setup, "lift_speed", source)
        check(dia < plate, source, "setup.tube_diameter",
              f"a tube narrower than the plate ({plate} m)", dia)
        check(fill <= h, source, "setup.fill_height", f"at most the tube height {h} m", fill)
    else:
        top = setup_number(setup, "funnel_top_diameter", source)
        bot = setup_number(setup, "funnel_bottom_diameter", source)
        setup_number(setup, "funnel_height", source)
        setup_number(setup, "outlet_height", source, inclusive=True)
        setup_number(setup, "cover_speed", source)
        setup_number(setup, "load_mass", source)
        keep = setup.get("max_retained", MAX_RETAINED)
        check(isinstance(keep, (int, float)) and not isinstance(keep, bool) and 0 <= keep < 1,
              source, "setup.max_retained", "a fraction of the fill in [0, 1)", keep)
        check(bot < top, source, "setup.funnel_bottom_diameter",
              f"an outlet narrower than the funnel top ({top} m)", bot)
        check(top < plate, source, "setup.funnel_top_diameter",
              f"a funnel narrower than the plate ({plate} m)", top)
    sz = sizing(setup, preset, params)
    if method == "funnel":  # before the outlet check: a quick load's spheres grow with it
        rho = (params or DemParams()).soil_density
        for m in {setup["load_mass"], sz["load_mass"]}:
            check(m / (rho * PHI) <= _funnel_volume(setup), source, "setup.load_mass",
                  f"a load that fits the funnel ({_funnel_volume(setup) * 1e3:.3g} L at "
                  f"{rho:g} kg/m^3, solid fraction {PHI})", m)
    check(sz["n"] >= 20, source, "setup", "a fill holding at least 20 particles", sz["n"])
    if method == "cylinder":
        check(setup["tube_diameter"] >= 4 * 2 * sz["r_max"], source, "setup.tube_diameter",
              f"at least 4 particle diameters ({8 * sz['r_max']:.4g} m)", setup["tube_diameter"])
    else:
        check(setup["funnel_bottom_diameter"] >= 5 * 2 * sz["r_max"], source,
              "setup.funnel_bottom_diameter",
              f"an outlet of at least 5 particle diameters ({10 * sz['r_max']:.4g} m)",
              setup["funnel_bottom_diameter"])
        travel = cover_travel_time(setup, sz["r_max"])
        rt = setup.get("read_time")
        check(rt is None or rt > travel, source, "setup.read_time",
              f"more than the {travel:.3g} s the cover takes to clear the outlet (the release)", rt)


def _add_gate(sim, setup: dict) -> str:
    """Add the cover's material :data:`GATE` to the run's table (module docstring, "Funnel
    discharge"): the density, Poisson ratio and (scaled) shear modulus of the setup's
    ``wall_material``, against the soil the restitution of the soil on that material and no
    sliding friction, rolling friction or surface energy; against the walls' materials a
    placeholder pair (walls never touch each other, but the engine's table wants every
    pair).  Returns the material's name."""
    from soilcal.dem.materials import Material

    mats = sim.materials
    wall = mats.materials[mats.index(setup["wall_material"])]
    mats.add(Material(GATE, density=wall.density, poisson=wall.poisson, shear=wall.shear,
                      source=mats.source))
    e = mats.pairs[(mats.index("soil"), mats.index(setup["wall_material"]))].restitution
    for m in mats.materials:  # the gate itself among them
        if m.name != "soil":
            mats.set_pair(m.name, GATE, restitution=0.5, friction=0.3)
    mats.set_pair("soil", GATE, restitution=e, friction=0.0)
    return GATE


def cover_travel_time(setup: dict, r_max: float) -> float:
    """Seconds the funnel's cover is pulled for: 2.5 outlet radii and a particle diameter at
    ``cover_speed``, until it is clear of the outlet (the release; :func:`run`, the start-up
    check of ``read_time`` and the job cost estimate, :mod:`soilcal.dem.cost`)."""
    return (2.5 * (setup["funnel_bottom_diameter"] / 2) + 2 * r_max) / setup["cover_speed"]


def _plate(sim, setup):
    """The plate as the plane z = 0 (unbounded, so spheres rolling past the plate's edge do
    not fall); spheres beyond the plate's outline are counted as lost."""
    sim.add_plane((0.0, 0.0, 0.0), (0, 0, 1), setup["plate_material"], name="plate")


def _insert(sim, region, dist, n, gen, source):
    x, r = insert_random(region, dist, n=n, rng=gen, max_fraction=0.35, source=source,
                         field="particles")
    _add_by_height(sim, x, r)


def _add_by_height(sim, x, r):
    # spheres carry no per-particle id from the factory; sorting by height keeps memory local
    order = np.argsort(x[:, 2], kind="stable")
    sim.add_particles(x[order], r[order], "soil")


def _fill_funnel(sim, setup, sz, gen, source):
    """Spheres placed at random (solid fraction ``FILL_FRACTION``) in the funnel from the
    cover up, in the frustum just tall enough to hold them, so that the load falls at most
    about half that height onto the cover; a load the whole funnel cannot hold at that
    fraction has its rest placed in a cylinder above the funnel's top."""
    Rt, Rb = setup["funnel_top_diameter"] / 2, setup["funnel_bottom_diameter"] / 2
    hf, z_out = setup["funnel_height"], setup["outlet_height"]
    vmean = sz["dist"].mean_volume()
    need = sz["n"] * vmean / FILL_FRACTION
    gap = 0.002 * sz["r_max"]  # clear of the walls' facets

    def frustum(h):
        return ConeRegion(Rb - gap, Rb - gap + (Rt - Rb) * h / hf, z_out, z_out + h)

    h_min = min(4 * sz["r_max"], hf)  # the shortest frustum a load is placed in
    whole = frustum(hf).volume
    if whole <= need:  # the whole funnel, the rest above it
        h = hf
        in_cone = min(sz["n"], int(FILL_FRACTION * whole / vmean))
    else:
        if frustum(h_min).volume >= need:
            h = h_min
        else:
            # here, not at module import: scipy.optimize costs every other DEM job ~0.5 s
            from scipy.optimize import brentq

            h = brentq(lambda q: frustum(q).volume - need, h_min, hf)
        in_cone = sz["n"]
    cone = frustum(h)
    x, r = insert_random(cone, sz["dist"], n=in_cone, rng=gen, max_fraction=0.35,
                         source=source, field="particles")
    if in_cone < sz["n"]:
        rest = sz["n"] - in_cone
        ra = Rt - 1.001 * sz["r_max"]
        h_ins = rest * vmean / (FILL_FRACTION * math.pi * ra * ra) + 2.002 * sz["r_max"]
        x2, r2 = insert_random(CylinderRegion(ra, z_out + hf, z_out + hf + h_ins), sz["dist"],
                               n=rest, rng=gen, max_fraction=0.35, existing_positions=x,
                               existing_radii=r, source=source, field="particles")
        x, r = np.vstack([x, x2]), np.concatenate([r, r2])
    _add_by_height(sim, x, r)


def run(setup: dict, params: DemParams, preset: str = "quick", seed: int = 0, threads=None,
        vtk_dir=None, source: str = "<repose>", restart=None) -> Result:
    """One heap (module docstring).  ``restart``: a :class:`soilcal.dem.restart.Restart`
    whose file the run resumes from when it holds this run's state, and writes every few
    minutes; the run's numbers are the same either way (its phases: ``settle_fill``, then
    ``lift`` (cylinder) or ``cover`` (funnel), then ``settle_heap``)."""
    from soilcal.dem import restart as rst

    validate(setup, preset, source, params)
    nthreads = threads_used(threads)
    sz = sizing(setup, preset, params)
    coh = paper_cohesion(setup, sz["dist"], source)
    frames = Frames(vtk_dir, NAME)
    dmax = 2 * sz["r_max"]
    cylinder = setup["method"] == "cylinder"
    prog = rst.Progress(restart, frames)
    if not prog.resume():
        gen = rng(seed, setup.get("seed_stream", NAME))
        # a neighbour skin of 0.6 r_max: falling spheres would otherwise rebuild the lists
        # every few steps (the engine default is 0.2 r_max, tuned for packed beds)
        sim, scale = make_simulation(params, setup, preset, source, cohesion=coh,
                                     skin=0.6 * sz["r_max"])
        if cylinder:
            R = setup["tube_diameter"] / 2
            vol = sz["n"] * sz["dist"].mean_volume()
            h_ins = vol / (FILL_FRACTION * math.pi * (R - sz["r_max"]) ** 2)
            tube_h = max(setup["tube_height"], h_ins + dmax)
            sim.add_cylinder((0, 0, tube_h / 2), (0, 0, 1), R, tube_h / 2,
                             setup["wall_material"], inner=True, name="tube")
            _plate(sim, setup)
            _insert(sim, CylinderRegion(R - 1.001 * sz["r_max"], 1.001 * sz["r_max"], h_ins),
                    sz["dist"], sz["n"], gen, source)
        else:
            Rt, Rb = setup["funnel_top_diameter"] / 2, setup["funnel_bottom_diameter"] / 2
            k = 1.0 / math.cos(math.pi / N_SEG)
            fv, ft = cone_mesh(k * Rb, k * Rt, setup["outlet_height"],
                               setup["outlet_height"] + setup["funnel_height"], N_SEG)
            sim.add_mesh(fv, ft, setup["wall_material"], name="funnel")
            # the cover is a triangulated disc (triangles are two-sided, a disc wall is not)
            cv, ct = disk_mesh(1.25 * Rb, 24, centre=(0, 0, setup["outlet_height"]))
            sim.add_mesh(cv, ct, _add_gate(sim, setup), name="cover")
            _plate(sim, setup)
            _fill_funnel(sim, setup, sz, gen, source)
        frames(sim)
        prog.begin(sim, "settle_fill", info={}, scale=scale)
    sim, st = prog.sim, prog.vars
    info = st["info"]

    if prog.at("settle_fill"):
        prog.checkpoint()
        ok0, _ = prog.settle(setup["rest_speed"], setup["max_settle_time"], "fill_steps")
        info["fill_settled"] = int(ok0)
        if cylinder:
            info["fill_height_m"] = float((sim.x[:, 2] + sim.p.r).max())
        frames(sim)
        prog.next("lift" if cylinder else "cover", move_step0=sim.step, bottom=0.0)
    if cylinder and prog.at("lift"):
        tube = sim.walls.names.index("tube")
        lift = info["fill_height_m"] + dmax
        v = setup["lift_speed"]
        sim.set_wall_motion(tube, velocity=(0, 0, v))
        chunk = max(sim.dt, min(0.05, 0.5 * sz["r_max"] / v))  # rim moves half a radius
        while st["bottom"] < lift:
            prog.checkpoint()
            run_time(sim, min(chunk, (lift - st["bottom"]) / v))
            st["bottom"] = v * (sim.step - st["move_step0"]) * sim.dt  # the rim's translation
            if st["bottom"] > float((sim.x[:, 2] + sim.p.r).max()) + sz["r_max"]:
                break  # every sphere is below the rim: the rest of the lift touches nothing
        info["lift_m"] = st["bottom"]
        sim.set_wall_motion(tube, velocity=(0, 0, 0))
        frames(sim)
        prog.next("settle_heap")
    if not cylinder and prog.at("cover"):
        cover = sim.walls.names.index("cover")
        sim.set_wall_motion(cover, velocity=(setup["cover_speed"], 0, 0))
        prog.checkpoint()
        steps = max(1, int(round(cover_travel_time(setup, sz["r_max"]) / sim.dt)))
        prog.advance(steps, "cover_steps")  # run_time's steps
        sim.set_wall_motion(cover, velocity=(0, 0, 0))
        frames(sim)
        prog.next("settle_heap")
    prog.checkpoint()
    read_time = setup.get("read_time")
    if read_time is None:
        ok, t_rest = prog.settle(setup["rest_speed"], setup["max_settle_time"], "heap_steps")
    else:  # read at a fixed time after the release, whatever the heap is doing then
        # steps of the release (a resumed run has done st["heap_steps"] of the heap's already)
        released = sim.step - st.get("heap_steps", 0) - st["move_step0"]
        check(released * sim.dt < read_time, source, "setup.read_time",
              f"more than the {released * sim.dt:.3g} s the release (cover or lift) took", read_time)
        t_rest = prog.advance(int(round(read_time / sim.dt)) - released, "heap_steps") * sim.dt
        ok = sim.kinetic_energy() < rest_tolerance(sim, setup["rest_speed"])
    frames(sim)
    frames.close()
    scale = st["scale"]
    z_out = math.inf if cylinder else setup["outlet_height"]
    x, r = sim.x.copy(), sim.p.r.copy()
    half = setup["plate_size"] / 2
    inside = (np.abs(x[:, 0]) <= half) & (np.abs(x[:, 1]) <= half)
    on = inside & (x[:, 2] < z_out - 0.5 * sz["r_max"])
    responses = dict(n_on_plate=int(on.sum()), n_lost=int((~inside).sum()),
                     n_retained=int((x[:, 2] >= z_out - 0.5 * sz["r_max"]).sum())
                     if math.isfinite(z_out) else 0,
                     settled=int(ok), settle_time_s=float(t_rest))
    failed = []
    arched = ""
    if math.isfinite(z_out):
        frac = responses["n_retained"] / max(1, int(sim.n))
        responses["retained_fraction"] = frac
        keep = setup.get("max_retained", MAX_RETAINED)
        if frac > keep:
            why = ("held by cohesion: arched over the outlet or stuck to the walls" if ok else
                   f"still there when the run stopped unsettled after {t_rest:.3g} s")
            arched = (f"funnel: {responses['n_retained']} of {int(sim.n)} spheres "
                      f"({100 * frac:.0f} %) stayed in the funnel ({why}), more than "
                      f"max_retained = {keep:g} of the spheres: the plate holds no heap of the "
                      f"test's load")
            failed.append(arched)

    def measured(name, fn, *args, **kw):
        # a heap an estimator cannot read (spread flat, too few spheres on the plate, the
        # load arched in the funnel) is a result of the run, not an error of it: that
        # estimator's angle is NaN
        if not arched:
            try:
                return fn(*args, **kw)
            except InputError as exc:
                failed.append(f"{name}: {exc.field}: expected {exc.expected}, got {exc.got}")
        return dict(angle_deg=math.nan, spread_deg=math.nan, height_m=math.nan,
                    per_direction_deg=[])

    bins = measured("bins", measure.repose_angle_bins, x[on], r[on], 0.0, centre=(0.0, 0.0),
                    source=source)
    responses.update(angle_deg=bins["angle_deg"], angle_sd_deg=bins["spread_deg"],
                     height_m=bins["height_m"])
    scan = measured("surface", measure.repose_angle_surface, x[on], r[on], 0.0,
                    centre=(0.0, 0.0), source=source)
    responses.update(angle_surface_deg=scan["angle_deg"], angle_surface_sd_deg=scan["spread_deg"])
    if setup.get("image", True):
        views = setup.get("image_views", IMAGE_VIEWS)
        img = measured("image", measure.repose_angle_image, x[on], r[on], 0.0, views=views)
        responses.update(angle_image_deg=img["angle_deg"], angle_image_sd_deg=img["spread_deg"])
        lost = img.get("views_failed") or []
        if lost:  # measured on the other views (more than half): said, not hidden
            failed.append(f"image: {len(lost)} of {views} views not measured "
                          f"(view {lost[0][0]:g} deg: {lost[0][1]})")
    responses["measure_errors"] = "; ".join(failed)
    responses["peak_overlap"] = sim.peak_overlap
    setup_out = dict(setup)
    setup_out.pop("paper_psd", None)
    setup_out.update(stiffness_scale=scale, cohesion_scale=coh, dt=sim.dt,
                     dt_fraction=sim.dt / sim.rayleigh, r_mean=sz["r_mean"], r_max=sz["r_max"], load_mass=sz["load_mass"], **info)
    prog.finish()
    return Result(scenario=NAME, preset=preset, seed=int(seed), n_particles=int(sim.n),
                  steps=int(sim.step), sim_time_s=float(sim.step * sim.dt), wall_s=prog.wall_s,
                  threads=nthreads, params=params.as_dict(), setup=setup_out,
                  responses=responses,
                  series=dict(per_direction_deg=np.asarray(bins["per_direction_deg"]), x=x, r=r))
