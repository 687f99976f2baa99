"""What every reference-engine translation shares: the phases of a case, the same phases run
in soilcal, the initial data file (LIGGGHTS and LAMMPS ``atom_style sphere``), the engine's
process and its custom dumps read back by soilcal insertion id.

A case is a soilcal :class:`~soilcal.dem.engine.Simulation` as it stands plus ``phases``
[(steps, {wall: motion})]: each phase sets every wall's motion (those it does not name to rest)
and runs its steps; a motion is a velocity [m/s] or {"velocity": .., "omega": ..} (rotation
about the wall's centre).
"""

from __future__ import annotations

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

SOURCE = "<reference case>"


def wall_id(sim, wall) -> int:
    names = sim.walls.names
    if isinstance(wall, str):
        if wall not in names:
            raise InputError(SOURCE, "phases.wall", f"one of {names}", wall)
        return names.index(wall)
    if not 0 <= int(wall) < len(names):
        raise InputError(SOURCE, "phases.wall", f"a wall index < {len(names)}", wall)
    return int(wall)


def motion_of(value, where):
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
        out.append((int(steps), {wall_id(sim, w): motion_of(v, f"phases[{k}].{w}")
                                 for w, v in (motion or {}).items()}))
    return out


def state_of(sim) -> dict:
    """The state by insertion id: ``x``, ``v``, ``omega``, ``r``, ``present``."""
    rows = sim.index(np.arange(sim.n))
    return dict(x=sim.x[rows].copy(), v=sim.v[rows].copy(), omega=sim.p.omega[rows].copy(),
                r=sim.p.r[rows].copy(), present=np.ones(sim.n, dtype=bool))


def run_phases(sim, phases, snapshots: bool = False):
    """Run the phases in soilcal: each phase sets every wall's velocity and rotation (those
    it does not name to rest) and runs its steps; walls end at rest, as in the engines' decks.
    Every phase starts as a ``run`` command of LIGGGHTS and LAMMPS does: the forces are
    evaluated anew on the state as it stands with every wall at rest (no time passes, the
    contact histories are not advanced, a sliding spring is cut to its Coulomb limit), and
    the first half step kicks with them.  The engines' walls carry no velocity into that
    evaluation: LIGGGHTS sets a mesh's node velocities in its first step (an unfixed
    ``move/mesh`` leaves them zero), LAMMPS takes a region's from the change of its angle
    since the last evaluation.  Without it, the tangential damping of a wall contact at a
    phase boundary would differ, and the trajectories after a wall stops or starts part by
    1e-4 to 1e-3 of the speed (tests/reference).
    With ``snapshots``, returns the state at the end of every phase by insertion id
    (:func:`state_of`), as the engines' ``run`` do."""
    ph = check_phases(sim, phases)
    if sim.dt is None:
        sim.run(0)
    nw = len(sim.walls.names)
    states = []
    zero = (np.zeros(3), np.zeros(3))
    for steps, motion in ph:
        for w in range(nw):
            sim.set_wall_motion(w, velocity=np.zeros(3), omega=np.zeros(3))
        sim.compute_forces()
        for w in range(nw):
            v, om = motion.get(w, zero)
            sim.set_wall_motion(w, velocity=v, omega=om)
        sim.run(steps)
        if snapshots:
            states.append(state_of(sim))
    for w in range(nw):
        sim.set_wall_motion(w, velocity=np.zeros(3), omega=np.zeros(3))
    return states if snapshots else None


def num(value) -> str:
    """A number as the shortest text that reads back to the same double."""
    return repr(float(value))


def check_case(sim, bounds, source: str, engine: str) -> np.ndarray:
    """The checks every translation makes (fixed boundaries, no coarse graining, free
    spheres, a box); returns the box (xlo, xhi, ylo, yhi, zlo, zhi)."""
    if np.any(sim.periodic):
        raise InputError(source, "periodic", "fixed boundaries (no periodic axis)",
                         tuple(sim.periodic))
    if sim.coarse_grain != 1.0:
        raise InputError(source, "coarse_grain",
                         f"1 ({engine}'s coarse graining is another model)", sim.coarse_grain)
    p = sim.p
    if np.any(p.inv_m == 0) or np.any(p.inv_i == 0):
        raise InputError(source, "particles", "free spheres (none fixed or rotation-locked)",
                         None)
    b = np.asarray(bounds, dtype=np.float64).reshape(6)
    if not (b[0] < b[1] and b[2] < b[3] and b[4] < b[5]):
        raise InputError(source, "bounds", "xlo < xhi, ylo < yhi, zlo < zhi", tuple(b))
    return b


def write_data(sim, path, b, n_walls: int) -> None:
    """The initial data file (``atom_style sphere``: id type diameter density x y z, then
    the velocities and spins); atom ids are soilcal insertion ids + 1, atom types material
    indices + 1."""
    p = sim.p
    nm = len(sim.materials.materials)
    x, r, v, om = p.x, p.r, p.v, p.omega
    dens = p.m / (4.0 / 3.0 * math.pi * r ** 3)
    lines = [f"soilcal case ({sim.n} spheres, {n_walls} walls)", "",
             f"{sim.n} atoms", f"{nm} atom types",
             f"{num(b[0])} {num(b[1])} xlo xhi", f"{num(b[2])} {num(b[3])} ylo yhi",
             f"{num(b[4])} {num(b[5])} zlo zhi", "", "Atoms", ""]
    pid = p.id + 1
    lines += [f"{pid[i]} {int(p.mat[i]) + 1} {num(2.0 * r[i])} {num(dens[i])} {num(x[i, 0])} "
              f"{num(x[i, 1])} {num(x[i, 2])}" for i in range(sim.n)]
    lines += ["", "Velocities", ""]
    lines += [f"{pid[i]} {num(v[i, 0])} {num(v[i, 1])} {num(v[i, 2])} {num(om[i, 0])} "
              f"{num(om[i, 1])} {num(om[i, 2])}" for i in range(sim.n)]
    Path(path).write_text("\n".join(lines) + "\n")


def run_process(cmd, work, timeout: float | None = None, name: str = "engine") -> tuple[int, str]:
    """Run ``cmd`` in ``work`` with one OpenMP thread, in its own process group (a timeout
    ends it and its children together, then raises); returns (exit status, stdout and
    stderr), the output also kept in ``work/stdout.txt``."""
    env = dict(os.environ, OMP_NUM_THREADS="1")
    proc = subprocess.Popen(cmd, cwd=work, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, errors="replace",
                            start_new_session=True)
    try:
        out, _ = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        raise RuntimeError(f"{name} timed out after {timeout:.0f} s in {work}") from None
    Path(work, "stdout.txt").write_text(out)
    return proc.returncode, out


def read_dump(path) -> dict:
    """The last snapshot of a custom dump as arrays by column name, sorted by id."""
    text = Path(path).read_text()
    k = text.rfind("ITEM: ATOMS")
    if k < 0:
        raise InputError(path, "ITEM: ATOMS", "a custom dump", None)
    head, _, body = text[k:].partition("\n")
    cols = head.split()[2:]
    data = np.loadtxt(body.splitlines(), ndmin=2) if body.strip() else np.zeros((0, len(cols)))
    data = data[np.argsort(data[:, cols.index("id")])]
    return {c: data[:, i] for i, c in enumerate(cols)}


def read_state(path, n) -> dict:
    """A dump's state by soilcal insertion id (atom id - 1); ``present`` False for spheres the
    engine lost through its box."""
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


def run_case(engine: str, write_case, launch, version_pattern: str, sim, phases, bounds,
             workdir=None, snapshots: bool = False) -> dict:
    """Write a case with ``write_case(sim, work, phases, bounds)`` (its ``phase<k>.dump`` at
    the end of every phase), run it with ``launch(work)`` -> (exit status, output) and read
    it back: the final state by soilcal insertion id (``x``, ``v``, ``omega``, ``r``,
    ``present``: False for spheres the engine lost through its box), the ``loop_s`` it
    reports, its ``version`` (``version_pattern``'s first group in its output) and the
    ``case`` record; with ``snapshots``, ``states``: the state at the end of every phase.
    Without ``workdir`` the files go to a temporary folder, removed afterwards."""
    work = Path(workdir) if workdir else Path(tempfile.mkdtemp(prefix=f"soilcal-{engine.lower()}-"))
    try:
        info = write_case(sim, work, phases, bounds)
        rc, out = launch(work)
        last = work / f"phase{len(phases) - 1}.dump"
        if rc != 0 or not last.exists():
            tail = "\n".join(out.splitlines()[-12:])
            raise RuntimeError(f"{engine} failed (rc {rc}) in {work}:\n{tail}")
        states = [read_state(work / f"phase{k}.dump", info["n"]) for k in range(len(phases))]
        res = dict(states[-1], case=info)
        if snapshots:
            res["states"] = states
        loops = re.findall(r"Loop time of ([0-9.eE+-]+) on", out)
        res["loop_s"] = float(sum(float(t) for t in loops))
        vm = re.search(version_pattern, out, re.M)
        res["version"] = vm.group(1) if vm else ""
        return res
    finally:
        if not workdir:
            shutil.rmtree(work, ignore_errors=True)
