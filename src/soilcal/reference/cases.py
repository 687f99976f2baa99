"""Identical cases for soilcal and a reference engine: the same spheres, walls and phases.

``rotating_drum``: the vineyard paper's drum (100 mm across, 100 mm long, 25 % fill, 7 r/min)
as one closed triangle mesh (``N_SEG`` facets around, end caps included) turning about its
horizontal axis (y).  Spheres placed at random in the drum settle in soilcal (the initial
data of both engines); the drum then turns for ``transient`` s, and a frame is taken every
``frame_every`` s up to ``spin`` s; every frame's free-surface angle is measured by
:func:`soilcal.dem.measure.drum_surface_angle` and the run's angle is their mean.  With
``wall="smooth"`` the drum is the engine's analytic cylinder with two end planes instead
(LAMMPS's ``region cylinder``); :class:`JkrDrumCase` is that drum with JKR cohesion between
the spheres, for LAMMPS.

``lifted_tube``: a non-cohesive pile by cylinder lifting.  Spheres (radii uniform by number
in ``radii``) are placed at random (solid fraction 0.3) in a tube of ``N_SEG`` facets
standing on the plane z = 0, and settle in soilcal until their mean speed is below 5 mm/s
(at most ``fill_time`` s).  That state is the initial data of both engines.  The phases: the
tube rises at ``lift_speed`` until its rim is 2 r_max above the fill's top, then stops, and
the heap settles for ``settle_time`` s, a fixed time (no rest criterion, which an engine
would evaluate at its own moments).  The tube's inner diameter is chosen so that the settled
fill is about as tall as it is wide (solid fraction 0.6), as in the papers' cylinder tests.
Every sphere, the tube and the plate share one material; the contact law is Hertz-Mindlin
with viscoelastic damping and constant-torque rolling resistance with the chosen
``conventions`` (:mod:`soilcal.dem.contact`).

The angle is measured on the final state of each engine by the same estimators
(:func:`soilcal.dem.measure.repose_angle_bins` and
:func:`~soilcal.dem.measure.repose_angle_surface`, about the tube's axis).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from soilcal.errors import InputError

N_SEG = 24  # facets around the tube (vertices at R / cos(pi / N_SEG): facet mid-lines on R)
PHI_SETTLED = 0.6
PHI_PLACED = 0.3
#: the engine's overlap check: soft spheres placed at random hit the plate at about 1.4 m/s
#: in the fill (Hertz: about 14 % of the radius at E = 5 MPa); the phases are gentle
MAX_OVERLAP = 0.25


def _numbers(case, keys, source, zero=True) -> None:
    """Each named field a finite number, >= 0 (``zero``) or > 0; InputError naming it."""
    for key in keys:
        v = getattr(case, key)
        ok = isinstance(v, (int, float)) and math.isfinite(v) and (v >= 0 if zero else v > 0)
        if not ok:
            raise InputError(source, key, "a number >= 0" if zero else "a number > 0", v)


@dataclass
class Spheres:
    """The spheres and the one material of a case (spheres, walls and plate)."""

    n: int = 1000
    radii: tuple = (1.8e-3, 2.2e-3)
    rolling_friction: float = 0.1
    friction: float = 0.5
    restitution: float = 0.5
    youngs: float = 5e6
    poisson: float = 0.3
    density: float = 2600.0
    dt_fraction: float = 0.15
    seed: int = 0

    def check(self, source="<case>") -> None:
        if isinstance(self.n, bool) or not isinstance(self.n, (int, np.integer)) or self.n < 20:
            raise InputError(source, "n", "an integer >= 20 spheres", self.n)
        lo, hi = self.radii
        if not 0 < lo <= hi:
            raise InputError(source, "radii", "0 < r_min <= r_max [m]", self.radii)


@dataclass
class TubeCase(Spheres):
    """The lifted-tube pile."""

    n: int = 2000
    lift_speed: float = 0.05
    settle_time: float = 1.0
    fill_time: float = 1.5

    def check(self, source="<case>") -> None:
        super().check(source)
        _numbers(self, ("youngs", "density", "lift_speed", "settle_time", "fill_time"), source,
                 zero=False)

    def tube_radius(self) -> float:
        lo, hi = self.radii
        r3 = (hi ** 4 - lo ** 4) / (4 * (hi - lo)) if hi > lo else lo ** 3  # <r^3>, uniform
        vol = self.n * 4 / 3 * math.pi * r3 / PHI_SETTLED
        return 0.5 * (4 * vol / math.pi) ** (1 / 3)


def _materials(case: Spheres, rolling_friction=None, drum_wall: bool = False):
    """The one soil of a case: its restitution, friction, rolling friction (``rolling_friction``
    overrides it) and surface energy (0 for a case without one).  With ``drum_wall`` a second
    material ``drum``, the soil's without adhesion or rolling resistance (LAMMPS's region walls
    end a JKR contact where the surfaces part: lammps.py)."""
    from soilcal.dem.materials import Material, MaterialTable

    mu_r = case.rolling_friction if rolling_friction is None else rolling_friction
    mats = MaterialTable()
    mats.add(Material("soil", case.density, case.poisson, youngs=case.youngs))
    mats.set_pair("soil", "soil", case.restitution, case.friction, mu_r,
                  getattr(case, "surface_energy", 0.0))
    if drum_wall:
        mats.add(Material("drum", case.density, case.poisson, youngs=case.youngs))
        mats.set_pair("soil", "drum", case.restitution, case.friction, 0.0, 0.0)
        mats.set_pair("drum", "drum", case.restitution, case.friction, 0.0, 0.0)
    return mats


def _filled_tube(case, mats, contact_model: dict, source: str):
    """Spheres placed at random (solid fraction 0.3) in the tube of ``case`` standing on the
    plate z = 0, settled in soilcal (mean speed below 5 mm/s, at most ``fill_time`` s):
    (sim, tube radius, tube height, settled, fill time, top of the fill)."""
    from soilcal.dem.engine import Simulation
    from soilcal.dem.factories import CylinderRegion, UniformRadius, insert_random
    from soilcal.dem.geometry import cone_mesh
    from soilcal.dem.scenarios.base import settle

    lo, hi = case.radii
    R = TubeCase.tube_radius(case)
    dist = UniformRadius(lo, hi)
    vol = case.n * dist.mean_volume()
    h_ins = vol / (PHI_PLACED * math.pi * (R - hi) ** 2)
    tube_h = h_ins + 4 * hi
    sim = Simulation(mats, dt_fraction=case.dt_fraction, contact_model=contact_model,
                     skin=0.6 * hi, max_overlap=MAX_OVERLAP, source=source)
    k = 1.0 / math.cos(math.pi / N_SEG)
    tv, tt = cone_mesh(k * R, k * R, 0.0, tube_h, N_SEG)
    sim.add_mesh(tv, tt, "soil", name="tube")
    sim.add_plane((0, 0, 0), (0, 0, 1), "soil", name="plate")
    gen = np.random.default_rng(case.seed)
    x, r = insert_random(CylinderRegion(R - 1.001 * hi, 1.001 * hi, h_ins), dist, n=case.n,
                         rng=gen, max_fraction=0.35, source=source, field="particles")
    order = np.argsort(x[:, 2], kind="stable")
    sim.add_particles(x[order], r[order], "soil")
    settled, t_fill = settle(sim, 0.005, case.fill_time)
    top = float((sim.x[:, 2] + sim.p.r).max())
    return sim, R, tube_h, settled, t_fill, top


def lifted_tube(case: TubeCase, conventions="liggghts", threads=None):
    """The filled, settled tube as a soilcal Simulation with the given conventions, and
    (phases, bounds, info) for :func:`soilcal.reference.liggghts.run` and
    :func:`~soilcal.reference.liggghts.run_phases`.  The fill is computed once per seed and
    conventions; a comparison of two conventions starts both from :func:`restart`."""
    case.check()
    hi = case.radii[1]
    sim, R, tube_h, settled, t_fill, top = _filled_tube(
        case, _materials(case), dict(rolling="constant_torque", conventions=conventions),
        "<lifted tube>")
    lift_steps = int(math.ceil((top + 2 * hi) / case.lift_speed / sim.dt))
    settle_steps = int(math.ceil(case.settle_time / sim.dt))
    phases = [(lift_steps, {"tube": (0.0, 0.0, case.lift_speed)}), (settle_steps, {})]
    spread = 0.5 * tube_h + 4 * R  # a heap spreads to about the fill height beyond the tube
    bounds = (-spread - R, spread + R, -spread - R, spread + R, -0.01, tube_h * 1.1 + top
              + case.lift_speed * (lift_steps + settle_steps) * sim.dt)
    info = dict(fill_settled=int(settled), fill_time_s=t_fill, fill_top_m=top, dt=sim.dt,
                lift_steps=lift_steps, settle_steps=settle_steps, tube_height=tube_h)
    return sim, phases, bounds, info


def restart(sim, conventions, contact_model: dict | None = None, walls=None):
    """A copy of ``sim``'s state (spheres by insertion id, walls) under other conventions:
    the contact model ``contact_model`` (default: constant-torque rolling) with the named
    set ``conventions``, and the walls named in ``walls`` (default: all).  Contact histories
    are not copied: every contact of the copy starts new, in soilcal as in a reference
    engine reading the same data."""
    from soilcal.dem.engine import Simulation

    model = dict(contact_model if contact_model is not None else dict(rolling="constant_torque"),
                 conventions=conventions)
    copy = Simulation(sim.materials, dt=sim.dt, gravity=tuple(sim.gravity),
                      contact_model=model, skin=sim.skin_user, max_overlap=sim.max_overlap,
                      source=sim.source)
    rows = sim.index(np.arange(sim.n))
    mat = sim.p.mat[rows]
    for k in np.unique(mat):
        sel = rows[mat == k]
        copy.add_particles(sim.x[sel], sim.p.r[sel] / sim.coarse_grain, int(k),
                                v=sim.v[sel], omega=sim.p.omega[sel])
    a = sim._warr
    for w, name in enumerate(sim.walls.names):
        if walls is not None and name not in walls:
            continue
        # the wall's primitives as they stand, about the same centre
        prim = np.flatnonzero(a["prim_wall"] == w)
        copy.add_wall(name, int(a["prim_mat"][prim[0]]),
                      [(int(a["prim_kind"][q]), a["prim_par"][q].copy(), int(a["prim_pts"][q]),
                        int(a["prim_dirs"][q])) for q in prim], centre=a["wall_centre"][w].copy())
    return copy


@dataclass
class ColumnCase(Spheres):
    """The cohesive column: JKR spheres settled in the tube, the tube then removed."""

    n: int = 1000
    rolling_friction: float = 0.0
    #: surface energy [J/m^2] in the LAMMPS convention (pull-off 3 pi gamma R*, w = 2 gamma)
    surface_energy: float = 0.1
    #: viscous_radius damping [1/(m s)]: 0.17 of critical at an overlap of 1 % of R*
    #: between two 2 mm spheres of E = 5 MPa
    damping_eta: float = 1.2e7
    settle_time: float = 1.0
    fill_time: float = 1.5

    def check(self, source="<case>") -> None:
        super().check(source)
        _numbers(self, ("surface_energy", "damping_eta", "settle_time", "fill_time"), source)

    def contact_model(self) -> dict:
        return dict(cohesion="jkr", damping="viscous_radius", damping_eta=self.damping_eta,
                    jkr_convention="lammps")


def collapsed_column(case: ColumnCase, conventions="lammps"):
    """The cohesive column of :class:`ColumnCase`: spheres placed at random in the tube (as
    :func:`lifted_tube`) settle in soilcal under JKR cohesion; the returned Simulation is
    that state on the plate with the tube removed (the initial data of every engine, no
    contact carried over), and (phases, bounds, info): the column collapses and settles for
    ``settle_time`` s.  Without rolling resistance the heap that stays is held by the
    adhesion and the sliding friction."""
    case.check("<column case>")
    mats = _materials(case, rolling_friction=0.0)
    model = case.contact_model()
    sim, R, tube_h, settled, t_fill, top = _filled_tube(
        case, mats, dict(model, conventions=conventions), "<cohesive column>")
    free = restart(sim, conventions, model, walls=("plate",))
    free.run(0)
    steps = int(math.ceil(case.settle_time / free.dt))
    # spheres rolling off the heap beyond the box are lost in LAMMPS, and are not counted
    # in soilcal either (:func:`inside`)
    spread = 0.5 * tube_h + 4 * R + 0.1
    bounds = (-spread, spread, -spread, spread, -0.01, 2 * top + 0.01)
    info = dict(fill_settled=int(settled), fill_time_s=t_fill, fill_top_m=top, dt=free.dt,
                settle_steps=steps, tube_height=tube_h)
    return free, [(steps, {})], bounds, info


def inside(x, bounds) -> np.ndarray:
    """Which positions lie in the box (xlo, xhi, ylo, yhi, zlo, zhi)."""
    b = np.asarray(bounds, dtype=float).reshape(3, 2)
    return np.all((x >= b[:, 0]) & (x <= b[:, 1]), axis=1)


def heap_angles(x, r, present=None) -> dict:
    """Radial-bin and surface-scan angles of a final state about the tube's axis."""
    from soilcal.dem import measure

    if present is not None:
        x, r = x[present], r[present]
    keep = x[:, 2] > -0.5 * r  # on the plate
    b = measure.repose_angle_bins(x[keep], r[keep], 0.0, centre=(0.0, 0.0))
    s = measure.repose_angle_surface(x[keep], r[keep], 0.0, centre=(0.0, 0.0))
    return dict(angle_bins_deg=b["angle_deg"], angle_surface_deg=s["angle_deg"],
                height_m=b["height_m"], n_on_plate=int(keep.sum()))


@dataclass
class DrumCase(Spheres):
    """The rotating drum: ``wall`` "mesh" (``N_SEG`` flat facets and two end caps, as
    LIGGGHTS reads an STL drum) or "smooth" (the engine's analytic cylinder with two end
    planes, one rigid wall, as a LAMMPS cylinder region)."""

    diameter: float = 0.1
    length: float = 0.1
    rpm: float = 7.0
    transient: float = 1.0
    spin: float = 4.0
    frame_every: float = 0.05
    fill_time: float = 2.0
    wall: str = "mesh"

    def check(self, source="<case>") -> None:
        super().check(source)
        if self.wall not in ("mesh", "smooth"):
            raise InputError(source, "wall", "'mesh' or 'smooth'", self.wall)

    def contact_model(self) -> dict:
        return dict(rolling="constant_torque")


@dataclass
class JkrDrumCase(DrumCase):
    """The rotating drum with JKR cohesion between the spheres and no rolling resistance
    (LAMMPS has none of soilcal's rolling laws), smooth walls without adhesion (LAMMPS's
    granular walls are analytic, and its region walls end a JKR contact where the surfaces
    part), the surface energy in the LAMMPS convention and viscous_radius damping as the
    cohesive column's (:class:`ColumnCase`)."""

    rolling_friction: float = 0.0
    surface_energy: float = 0.1
    damping_eta: float = 1.2e7
    wall: str = "smooth"

    def check(self, source="<case>") -> None:
        super().check(source)
        _numbers(self, ("surface_energy", "damping_eta"), source)
        if self.rolling_friction != 0:
            raise InputError(source, "rolling_friction", "0 (no rolling resistance)",
                             self.rolling_friction)

    def contact_model(self) -> dict:
        return dict(cohesion="jkr", damping="viscous_radius", damping_eta=self.damping_eta,
                    jkr_convention="lammps")


def add_smooth_drum(sim, radius, length, material, name="drum"):
    """A closed drum as one rigid wall: the analytic cylinder of ``radius`` about the y axis
    from y = 0 to ``length`` and two end planes facing inwards; it turns about its axis
    (centre (0, length/2, 0))."""
    from soilcal.dem.walls import CYLINDER, PLANE

    h = length / 2
    cyl = np.array([0.0, h, 0.0, 0.0, 1.0, 0.0, radius, h, 1.0])
    lo = np.array([0.0, 0.0, 0.0, 0.0, 1.0, 0.0])
    hi = np.array([0.0, length, 0.0, 0.0, -1.0, 0.0])
    return sim.add_wall(name, material, [(CYLINDER, cyl, 0b1, 0b10), (PLANE, lo, 0b1, 0b10),
                                         (PLANE, hi, 0b1, 0b10)], centre=(0.0, h, 0.0))


def rotating_drum(case: DrumCase, conventions="liggghts"):
    """The settled drum as a soilcal Simulation, and (phases, bounds, info): the transient
    turn, then one phase per frame (``snapshots`` of :func:`soilcal.reference.liggghts.run`
    and :func:`~soilcal.reference.liggghts.run_phases` give the frames)."""
    from soilcal.dem.engine import Simulation
    from soilcal.dem.factories import CylinderRegion, UniformRadius, insert_random
    from soilcal.dem.geometry import drum_mesh
    from soilcal.dem.scenarios.base import settle

    case.check("<drum case>")
    lo, hi = case.radii
    R, L = case.diameter / 2, case.length
    sim = Simulation(_materials(case, drum_wall=isinstance(case, JkrDrumCase)),
                     dt_fraction=case.dt_fraction,
                     contact_model=dict(case.contact_model(), conventions=conventions),
                     skin=0.5 * hi, max_overlap=MAX_OVERLAP, source="<rotating drum>")
    if case.wall == "smooth":
        add_smooth_drum(sim, R, L, "drum" if isinstance(case, JkrDrumCase) else "soil")
    else:
        k = 1.0 / math.cos(math.pi / N_SEG)
        dv, dt_ = drum_mesh(k * R, L, N_SEG, axis_point=(0, 0, 0), axis_dir=(0, 1, 0))
        sim.add_mesh(dv, dt_, "soil", name="drum", centre=(0, L / 2, 0))
    gen = np.random.default_rng(case.seed)
    region = CylinderRegion(R - 1.001 * hi, 1.001 * hi, L - 1.001 * hi, axis_point=(0, 0, 0),
                            axis_dir=(0, 1, 0))
    x, r = insert_random(region, UniformRadius(lo, hi), n=case.n, rng=gen, max_fraction=0.35,
                         source="<rotating drum>", field="particles")
    order = np.argsort(x[:, 2], kind="stable")
    sim.add_particles(x[order], r[order], "soil")
    settled, t_fill = settle(sim, 0.005, case.fill_time)
    w = (0.0, 2 * math.pi * case.rpm / 60.0, 0.0)
    turn = {"drum": {"omega": w}}
    n_frames = int(math.floor((case.spin - case.transient) / case.frame_every + 1e-9)) + 1
    frame = int(round(case.frame_every / sim.dt))
    phases = [(int(round(case.transient / sim.dt)), turn)] + [(frame, turn)] * (n_frames - 1)
    m = 1.5 * max(R, L)
    bounds = (-m, m, -m + L / 2, m + L / 2, -m, m)
    return sim, phases, bounds, dict(fill_settled=int(settled), fill_time_s=t_fill, dt=sim.dt,
                                     frames=n_frames)


def drum_angles(states, case: DrumCase) -> dict:
    """Mean and SD of the frames' free-surface angles (mid-section slab of 3 mean radii or a
    tenth of the length, as the drum scenario)."""
    from soilcal.dem import measure

    L = case.length
    out = []
    for s in states:
        keep = s["present"]
        slab = max(3.0 * float(np.mean(s["r"][keep])), 0.1 * L)
        out.append(measure.drum_surface_angle(s["x"][keep], s["r"][keep], (0, L / 2, 0),
                                              (0, 1, 0), slab_half=slab)["angle_deg"])
    a = np.asarray(out)
    return dict(angle_deg=float(a.mean()), angle_frames_sd_deg=float(a.std(ddof=1)),
                frames=int(a.size))
