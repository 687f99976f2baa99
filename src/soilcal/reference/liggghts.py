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
    contact law     pair_style gran model hertz tangential history [rolling_friction cdt]
                    (``tangential_damping off`` when soilcal's is off)
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
``cdt`` (rolling_model_cdt.h), which soilcal computes exactly with the ``liggghts``
conventions (:mod:`soilcal.dem.contact`).  :func:`write_case` records in ``case.json``
whether the simulation's conventions are LIGGGHTS's; with any other conventions the two runs
differ by the conventions, which is what a comparison then measures.

Not translated (an :class:`~soilcal.errors.InputError` names the part): JKR cohesion
(LIGGGHTS 3.8 has only ``sjkr``, a different law), the ``epsd`` and ``bounded`` rolling
models, undamped or frictionless laws, periodic boundaries, cylinders, cones, discs,
rectangles, planes not normal to an axis, moving planes, a wall translating and rotating in
one phase, coarse graining, and fixed or rotation-locked spheres.
"""

from __future__ import annotations

import json
import math
import os
import re
import shutil
import signal
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from soilcal.errors import InputError

SOURCE = "<liggghts case>"
_LIGGGHTS_CONV = (1, 1, 1)  # rolling lever, force, axis of the ``liggghts`` set (contact.py)
_LIGGGHTS_WALL = 1  # rolling against a wall: the sphere's own rotation


def binary() -> str | None:
    """Path of the LIGGGHTS executable (``liggghts`` or ``lmp_liggghts``), or None."""
    for name in ("liggghts", "lmp_liggghts"):
        p = shutil.which(name)
        if p:
            return p
    return None


def available() -> tuple[bool, str]:
    """(True, binary) when LIGGGHTS and mpirun are installed, else (False, what is missing)."""
    b = binary()
    if b is None:
        return False, "LIGGGHTS is not installed (no 'liggghts' on PATH; Debian: apt install liggghts)"
    if shutil.which("mpirun") is None:
        return False, "mpirun is not installed (Debian: apt install openmpi-bin)"
    return True, b


def _wall_id(sim, wall) -> int:
    names = sim.walls.names
    if isinstance(wall, str):
        if wall not in names:
            raise InputError(SOURCE, "phases.wall", f"one of {names}", wall)
        return names.index(wall)
    if not 0 <= int(wall) < len(names):
        raise InputError(SOURCE, "phases.wall", f"a wall index < {len(names)}", wall)
    return int(wall)


def _motion(value, where):
    """A phase's motion of one wall: a velocity [m/s], or {"velocity": .., "omega": ..}."""
    if isinstance(value, dict):
        bad = set(value) - {"velocity", "omega"}
        if bad:
            raise InputError(SOURCE, where, "a mapping of velocity and omega", sorted(bad))
        v, w = value.get("velocity", (0, 0, 0)), value.get("omega", (0, 0, 0))
    else:
        v, w = value, (0, 0, 0)
    out = []
    for name, vec in (("velocity", v), ("omega", w)):
        try:
            a = np.asarray(vec, dtype=np.float64).reshape(3)
        except (TypeError, ValueError):
            raise InputError(SOURCE, f"{where}.{name}", "three numbers", vec) from None
        if not np.all(np.isfinite(a)):
            raise InputError(SOURCE, f"{where}.{name}", "finite numbers", tuple(a))
        out.append(a)
    return out[0], out[1]


def check_phases(sim, phases) -> list[tuple[int, dict[int, tuple[np.ndarray, np.ndarray]]]]:
    """[(steps, {wall index: (velocity, omega)})] with whole step counts >= 0; a phase names
    each moving wall with its velocity, or with {"velocity": .., "omega": ..} (rotation about
    the wall's centre)."""
    out = []
    for k, ph in enumerate(phases):
        try:
            steps, motion = ph
        except (TypeError, ValueError):
            raise InputError(SOURCE, f"phases[{k}]", "(steps, {wall: velocity})", ph) from None
        if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)) or steps < 0:
            raise InputError(SOURCE, f"phases[{k}].steps", "a whole number of steps >= 0", steps)
        out.append((int(steps), {_wall_id(sim, w): _motion(v, f"phases[{k}].{w}")
                                 for w, v in (motion or {}).items()}))
    return out


def _state(sim) -> dict:
    rows = sim.index(np.arange(sim.n))
    return dict(x=sim.x[rows].copy(), v=sim.v[rows].copy(), omega=sim.p.omega[rows].copy(),
                r=sim.p.r[rows].copy(), present=np.ones(sim.n, dtype=bool))


def run_phases(sim, phases, snapshots: bool = False):
    """Run the phases in soilcal: each phase sets every wall's velocity and rotation (those
    it does not name to rest) and runs its steps; walls end at rest, as in the LIGGGHTS deck.
    With ``snapshots``, returns the state at the end of every phase by insertion id (``x``,
    ``v``, ``omega``, ``r``), as :func:`run` does."""
    ph = check_phases(sim, phases)
    if sim.dt is None:
        sim.run(0)
    nw = len(sim.walls.names)
    states = []
    zero = (np.zeros(3), np.zeros(3))
    for steps, motion in ph:
        for w in range(nw):
            v, om = motion.get(w, zero)
            sim.set_wall_motion(w, velocity=v, omega=om)
        sim.run(steps)
        if snapshots:
            states.append(_state(sim))
    for w in range(nw):
        sim.set_wall_motion(w, velocity=np.zeros(3), omega=np.zeros(3))
    return states if snapshots else None


def _law(sim) -> tuple[str, str, bool]:
    """The LIGGGHTS contact model, its options and whether soilcal's conventions are
    LIGGGHTS's."""
    from soilcal.dem.contact import COHESION, DAMPING, ROLLING, TANGENTIAL

    c = [int(v) for v in sim.codes]
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
    if rolling not in ("none", "constant_torque"):
        raise InputError(SOURCE, "contact_model.rolling",
                         "'none' or 'constant_torque' (LIGGGHTS cdt)", rolling)
    law = "gran model hertz tangential history"
    same = True
    if rolling == "constant_torque":
        law += " rolling_friction cdt"
        same = tuple(c[5:8]) == _LIGGGHTS_CONV and c[9] == _LIGGGHTS_WALL
    opts = " tangential_damping off" if c[8] == 1 else ""  # after the walls' own arguments
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


def _f(value) -> str:
    """A number as the shortest text that reads back to the same double."""
    return repr(float(value))


def _pairs(n, value) -> str:
    return " ".join(f"{_f(value(i, j))}" for i in range(n) for j in range(n))


def write_case(sim, workdir, phases, bounds) -> dict:
    """Write the LIGGGHTS input (``in.case``, ``data.case``, one STL per mesh wall and
    ``case.json``) into ``workdir``; ``bounds`` = (xlo, xhi, ylo, yhi, zlo, zhi) of the
    box (fixed boundaries; spheres leaving it are lost in LIGGGHTS).  Returns case.json."""
    from soilcal.dem.contact import ROLLING

    ph = check_phases(sim, phases)
    if sim.dt is None:
        sim.run(0)
    if np.any(sim.periodic):
        raise InputError(SOURCE, "periodic", "fixed boundaries (no periodic axis)",
                         tuple(sim.periodic))
    if sim.coarse_grain != 1.0:
        raise InputError(SOURCE, "coarse_grain", "1 (LIGGGHTS's coarse graining is another model)",
                         sim.coarse_grain)
    p = sim.p
    if np.any(p.inv_m == 0) or np.any(p.inv_i == 0):
        raise InputError(SOURCE, "particles", "free spheres (none fixed or rotation-locked)",
                         None)
    b = np.asarray(bounds, dtype=np.float64).reshape(6)
    if not (b[0] < b[1] and b[2] < b[3] and b[4] < b[5]):
        raise InputError(SOURCE, "bounds", "xlo < xhi, ylo < yhi, zlo < zhi", tuple(b))
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
    x, r, v, om = p.x, p.r, p.v, p.omega
    dens = p.m / (4.0 / 3.0 * math.pi * r ** 3)
    lines = [f"soilcal case ({sim.n} spheres, {len(walls)} walls)", "",
             f"{sim.n} atoms", f"{nm} atom types",
             f"{_f(b[0])} {_f(b[1])} xlo xhi", f"{_f(b[2])} {_f(b[3])} ylo yhi",
             f"{_f(b[4])} {_f(b[5])} zlo zhi", "", "Atoms", ""]
    pid = p.id + 1  # LIGGGHTS atom ids: soilcal insertion ids + 1
    lines += [f"{pid[i]} {int(p.mat[i]) + 1} {_f(2.0 * r[i])} {_f(dens[i])} {_f(x[i, 0])} "
              f"{_f(x[i, 1])} {_f(x[i, 2])}" for i in range(sim.n)]
    lines += ["", "Velocities", ""]
    lines += [f"{pid[i]} {_f(v[i, 0])} {_f(v[i, 1])} {_f(v[i, 2])} {_f(om[i, 0])} {_f(om[i, 1])} "
              f"{_f(om[i, 2])}" for i in range(sim.n)]
    (work / "data.case").write_text("\n".join(lines) + "\n")
    g = float(np.linalg.norm(sim.gravity))
    deck = ["units si", "atom_style sphere", "atom_modify map array", "boundary f f f",
            "newton off", "communicate single vel yes", "read_data data.case",
            f"neighbor {_f(sim.skin)} bin", "neigh_modify delay 0 every 1 check yes",
            "fix m1 all property/global youngsModulus peratomtype "
            + " ".join(f"{_f(e)}" for e in youngs),
            "fix m2 all property/global poissonsRatio peratomtype "
            + " ".join(f"{_f(m.poisson)}" for m in mats.materials),
            f"fix m3 all property/global coefficientRestitution peratomtypepair {nm} "
            + _pairs(nm, lambda i, j: pair[(i, j)].restitution),
            f"fix m4 all property/global coefficientFriction peratomtypepair {nm} "
            + _pairs(nm, lambda i, j: pair[(i, j)].friction)]
    if int(sim.codes[3]) == ROLLING["constant_torque"]:
        deck.append(f"fix m5 all property/global coefficientRollingFriction peratomtypepair {nm} "
                    + _pairs(nm, lambda i, j: pair[(i, j)].rolling_friction))
    deck += [f"pair_style {law}{opts}", "pair_coeff * *", f"timestep {_f(sim.dt)}"]
    meshes = []
    for k, w in enumerate(walls):
        if w["kind"] == "plane":
            deck.append(f"fix wall{k} all wall/gran {law.split(' ', 1)[1]} primitive type "
                        f"{w['mat'] + 1} {w['axis']}plane {_f(w['at'])}{opts}")
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
        deck.append(f"fix grav all gravity {_f(g)} vector {_f(gx)} {_f(gy)} {_f(gz)}")
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
                            + " ".join(f"{_f(c)}" for c in v))
            else:
                rate = float(np.linalg.norm(om))
                deck.append(f"fix move{n_ph}_{w} all move/mesh mesh wall{w} rotate origin "
                            + " ".join(f"{_f(c)}" for c in centre[w]) + " axis "
                            + " ".join(f"{_f(c / rate)}" for c in om)
                            + f" period {_f(2 * math.pi / rate)}")
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


def read_dump(path) -> dict:
    """The last snapshot of a LIGGGHTS custom dump as arrays by column name, sorted by id."""
    text = Path(path).read_text()
    k = text.rfind("ITEM: ATOMS")
    if k < 0:
        raise InputError(path, "ITEM: ATOMS", "a LIGGGHTS custom dump", None)
    head, _, body = text[k:].partition("\n")
    cols = head.split()[2:]
    data = np.loadtxt(body.splitlines(), ndmin=2) if body.strip() else np.zeros((0, len(cols)))
    data = data[np.argsort(data[:, cols.index("id")])]
    return {c: data[:, i] for i, c in enumerate(cols)}


def launch(args, work, ranks: int = 1, timeout: float | None = None, prefix=()) -> tuple[int, str]:
    """Run ``prefix + mpirun -np ranks + args`` in ``work`` with one OpenMP thread per rank,
    in its own process group (a timeout ends mpirun and its ranks together, then raises);
    returns (exit status, stdout and stderr), the output also kept in ``work/stdout.txt``."""
    cmd = [*prefix, "mpirun", "--allow-run-as-root", "--oversubscribe", "--bind-to", "none",
           "-np", str(int(ranks)), *args]
    env = dict(os.environ, OMP_NUM_THREADS="1")
    proc = subprocess.Popen(cmd, cwd=work, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, errors="replace",
                            start_new_session=True)
    try:
        out, _ = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        raise RuntimeError(f"{Path(args[0]).name} timed out after {timeout:.0f} s in {work}") \
            from None
    Path(work, "stdout.txt").write_text(out)
    return proc.returncode, out


def _read_state(path, n) -> dict:
    d = read_dump(path)
    idx = d["id"].astype(np.int64) - 1
    present = np.zeros(n, dtype=bool)
    present[idx] = True
    out = dict(present=present)
    for key, cols in (("x", ("x", "y", "z")), ("v", ("vx", "vy", "vz")),
                      ("omega", ("omegax", "omegay", "omegaz"))):
        arr = np.full((n, 3), np.nan)
        arr[idx] = np.column_stack([d[c] for c in cols])
        out[key] = arr
    rr = np.full(n, np.nan)
    rr[idx] = d["radius"]
    out["r"] = rr
    return out


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
    work = Path(workdir) if workdir else Path(tempfile.mkdtemp(prefix="soilcal-liggghts-"))
    try:
        info = write_case(sim, work, phases, bounds)
        rc, out = launch([exe, "-in", "in.case", "-log", "log.case"], work, ranks, timeout)
        last = work / f"phase{len(phases) - 1}.dump"
        if rc != 0 or not last.exists():
            tail = "\n".join(out.splitlines()[-12:])
            raise RuntimeError(f"LIGGGHTS failed (rc {rc}) in {work}:\n{tail}")
        states = [_read_state(work / f"phase{k}.dump", info["n"]) for k in range(len(phases))]
        res = dict(states[-1], case=info)
        if snapshots:
            res["states"] = states
        loops = re.findall(r"Loop time of ([0-9.eE+-]+) on", out)
        res["loop_s"] = float(sum(float(s) for s in loops))
        vm = re.search(r"^(LIGGGHTS \(Version[^)]*\))", out, re.M)
        res["version"] = vm.group(1) if vm else ""
        return res
    finally:
        if not workdir:
            shutil.rmtree(work, ignore_errors=True)
