"""Reference engines for the settle benchmark: LIGGGHTS 3.8 and LAMMPS ``pair granular``.

Writes the identical initial configuration of ``soilcal.dem.bench.settle_simulation`` (same nx
and seed: positions, radii, density 2600 kg/m^3) to a LAMMPS/LIGGGHTS data file, generates the
input deck, runs it under ``mpirun -np RANKS`` (OMP_NUM_THREADS=1) and returns a row with the
fields of the soilcal rows of ``benchmarks/settle.py``: particle-steps/s = N * steps / loop time
(the "Loop time of X on P procs for S steps with N atoms" line, i.e. set-up and file reading
excluded, like soilcal's compile and list build), peak RSS of all ranks (GNU time %M of the
largest rank times the number of ranks), kinetic energy and bed top max(z + r) at the end.

Contact laws (soilcal: Hertz + viscoelastic damping with beta = ln e / sqrt(ln^2 e + pi^2),
F_n^d = -2 sqrt(5/6) |beta| sqrt(S_n m*) v_n, S_n = 2 E* a; Mindlin S_t = 8 G* a with damping
ratio sqrt(S_t/S_n); Coulomb limit mu_s |F_n,tot|; constant rolling torque
mu_r |F_n,tot| R_i omega_rel/|omega_rel|; JKR with work of adhesion w = gamma, pull-off
1.5 pi w R*):

* LIGGGHTS ``model hertz tangential history``: the same normal/tangential law and damping
  (it is the law soilcal's ``viscoelastic`` damping copies).  ``rolling_friction cdt`` applies
  mu_r k_n delta R_eff (elastic normal force only, R_eff = R_i R_j/(R_i + R_j) between
  particles, R_i on walls), so its particle-particle torque at equal mu_r is about half of
  soilcal's; the deck sets mu_r' = ROLLING_PAIR_FACTOR * mu_r between particles (2 for equal
  radii: R_i/R_eff = 2) and mu_r on the floor (a second atom type carries the floor material).
  Cohesion: LIGGGHTS 3.8 has only ``cohesion sjkr`` (simplified JKR: F = k A, A the geometric
  overlap area, acting only while the spheres overlap, no hysteresis, no pull-off neck); it is
  NOT the JKR law.  k (cohesionEnergyDensity, J/m^3) is chosen so that k A equals the JKR
  adhesive term sqrt(8 pi w E* a^3) at the settled overlap (2.4 % of the mean radius).
* LAMMPS ``pair granular hertz/material`` (or ``jkr``) + ``damping tsuji`` + ``tangential
  mindlin`` + ``rolling sds``: tsuji damping is eta_n = alpha(e) sqrt(m* 4/3 E* a), the same
  form as soilcal's; the deck passes the restitution e' for which alpha(e') = sqrt(5) |beta(e)|,
  so the damping coefficient is identical (e' = 0.367 for e = 0.5).  The tangential stiffness
  8 G* and damping ratio sqrt(4 G*/E*) are given explicitly.  LAMMPS keeps the tangential
  displacement length when rotating it into the tangent plane and, while sliding, resets it so
  that spring plus damping force equals the Coulomb limit (soilcal: projection, spring force
  alone at the limit) - small differences.  There is no constant-torque rolling model in
  pair granular: ``rolling sds`` is an elastic-plastic spring-dashpot-slider (like EDEM
  type C / soilcal ``epsd``) whose torque saturates at mu_roll F_n,crit R_eff; the deck uses
  a stiff undamped spring (k_roll = S_n at the settled overlap) so it saturates after at most
  about 1e-3 rad of relative rolling (bottom of the bed), and mu_roll = ROLLING_PAIR_FACTOR *
  mu_r between particles, mu_r on the floor.  ``jkr`` is the full JKR law with the same pull-off
  convention as soilcal (Fncrit = |F_ne + 2 F_pulloff|); LAMMPS's gamma is the surface energy
  of each surface (w = 2 gamma), so the deck passes gamma/2.  ``fix wall/gran ... jkr`` of the
  Debian build returns NaN forces at the first sphere-floor contact, so with JKR the floor
  stays ``hertz/material`` (cohesionless floor; soilcal's floor is cohesive).
* The Debian LAMMPS build (29 Sep 2021) mixes the floor modulus of ``fix wall/gran
  hertz/material|jkr`` as E/(2(1 - nu)) instead of E/(2(1 - nu^2)) (checked with one sphere
  resting on the floor); the deck passes E/(1 + nu) to the wall so that E* = E/(2(1 - nu^2)).

Both decks: units si, periodic x y, fixed z (``boundary p p f``), floor z = 0, ``neighbor``
skin 0.2 r_max (0.44 mm) ``bin``, ``neigh_modify delay 0 every 1 check yes``, dt 2e-5 s,
``fix nve/sphere``, ``fix gravity``; the MPI grid splits only x and y (``processors * * 1``),
since a z split leaves the upper ranks empty once the bed has fallen.

Usage (one case): python benchmarks/reference.py --engine liggghts --n 5000 --steps 2000
    --ranks 2 [--cohesion jkr] [--keep DIR]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import shutil
import sys
import tempfile
import time
from pathlib import Path

from soilcal.reference.liggghts import launch

# Case parameters (must equal soilcal.dem.bench.settle_simulation).
E = 2.6e7
NU = 0.3
RHO = 2600.0
REST = 0.5
MU_S = 0.5
MU_R = 0.1
GAMMA = 0.3  # soilcal surface energy, used as the work of adhesion w (EDEM convention)
DT = 2e-5
G = 9.81
R_MAX = 2.2e-3
R_MEAN = 2.0e-3
SKIN = 0.2 * R_MAX
SETTLED_OVERLAP = 0.024  # of the radius (bench.py docstring)
ROLLING_PAIR_FACTOR = 2.0  # R_i / R_eff for equal radii (see module docstring)
THERMO_EVERY = 1000

ESTAR = E / (2.0 * (1.0 - NU * NU))  # identical spheres
GSTAR = E / (4.0 * (1.0 + NU) * (2.0 - NU))
KT = 8.0 * GSTAR  # Mindlin S_t = KT * a
TDAMP_RATIO = math.sqrt(4.0 * GSTAR / ESTAR)  # soilcal P_TRATIO
BETA = math.log(REST) / math.sqrt(math.log(REST) ** 2 + math.pi ** 2)
_RSTAR = 0.5 * R_MEAN
_DELTA_REF = SETTLED_OVERLAP * R_MEAN
_A_REF = math.sqrt(_RSTAR * _DELTA_REF)  # Hertz contact radius at the settled overlap
K_ROLL = 2.0 * ESTAR * _A_REF  # S_n at the settled overlap [N/m]
# sJKR: k * A_geo = sqrt(8 pi w E* a^3) at the settled overlap; A_geo ~ 2 pi R* delta
SJKR_K = (math.sqrt(8.0 * math.pi * GAMMA * ESTAR * _A_REF ** 3)
          / (2.0 * math.pi * _RSTAR * _DELTA_REF))


def tsuji_alpha(e: float) -> float:
    """LAMMPS ``damping tsuji`` coefficient for a restitution e (pair_granular.cpp)."""
    return (1.2728 - 4.2783 * e + 11.087 * e**2 - 22.348 * e**3 + 27.467 * e**4
            - 18.022 * e**5 + 4.8218 * e**6)


def tsuji_restitution_matching() -> float:
    """e' with alpha(e') sqrt(4/3) = 2 sqrt(5/6) |beta| sqrt(2), i.e. alpha = sqrt(5) |beta|."""
    target = math.sqrt(5.0) * abs(BETA)
    lo, hi = 0.01, 0.99  # alpha decreases with e on this interval
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        if tsuji_alpha(mid) > target:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


E_TSUJI = tsuji_restitution_matching()


def nx_for(n: int) -> int:
    from soilcal.dem.bench import LAYERS

    return max(3, int(round(math.sqrt(n / LAYERS))))


def write_data(path: Path, nx: int, seed: int = 2024, ntypes: int = 1) -> tuple[int, float]:
    """Data file of the settle configuration; returns (N, side)."""
    from soilcal.dem.bench import SPACING, settle_simulation

    sim = settle_simulation(nx, "none", seed)
    x = sim.x
    r = sim.p.r
    side = nx * SPACING
    zhi = float((x[:, 2] + r).max()) + 0.02
    lines = ["settle benchmark configuration (soilcal.dem.bench.settle_simulation, "
             f"nx={nx}, seed={seed})", "", f"{len(r)} atoms", f"{ntypes} atom types",
             f"0.0 {side:.17g} xlo xhi", f"0.0 {side:.17g} ylo yhi",
             f"-0.001 {zhi:.17g} zlo zhi", "",
             "Atoms", ""]
    lines += [f"{i + 1} 1 {2.0 * r[i]:.17g} {RHO:.17g} {x[i, 0]:.17g} {x[i, 1]:.17g} "
              f"{x[i, 2]:.17g}" for i in range(len(r))]
    path.write_text("\n".join(lines) + "\n")
    return len(r), side


def _common_tail(steps: int) -> list[str]:
    return ["timestep 2e-5", "fix grav all gravity 9.81 vector 0.0 0.0 -1.0",
            "fix integr all nve/sphere",
            "compute ket all ke", "compute erot all erotate/sphere",
            "compute rad all property/atom radius", "variable ztop atom z+c_rad",
            "compute zmax all reduce max v_ztop",
            "thermo_style custom step atoms c_ket c_erot c_zmax",
            f"thermo {THERMO_EVERY}", "thermo_modify format float %.8g",
            f"run {steps}"]


def liggghts_deck(data: str, steps: int, cohesion: str) -> tuple[str, str]:
    """LIGGGHTS 3.8 deck; atom type 1 = spheres, type 2 = floor material."""
    coh = " cohesion sjkr" if cohesion == "jkr" else ""
    law = "gran model hertz tangential history" + coh + " rolling_friction cdt"
    mur_pp = ROLLING_PAIR_FACTOR * MU_R
    deck = [
        "units si", "atom_style sphere", "atom_modify map array", "boundary p p f",
        "newton off", "communicate single vel yes", "processors * * 1",
        f"read_data {data}",
        f"neighbor {SKIN:.6g} bin", "neigh_modify delay 0 every 1 check yes",
        f"fix m1 all property/global youngsModulus peratomtype {E!r} {E!r}",
        f"fix m2 all property/global poissonsRatio peratomtype {NU!r} {NU!r}",
        f"fix m3 all property/global coefficientRestitution peratomtypepair 2 "
        f"{REST} {REST} {REST} {REST}",
        f"fix m4 all property/global coefficientFriction peratomtypepair 2 "
        f"{MU_S} {MU_S} {MU_S} {MU_S}",
        f"fix m5 all property/global coefficientRollingFriction peratomtypepair 2 "
        f"{mur_pp!r} {MU_R!r} {MU_R!r} {MU_R!r}",
    ]
    if cohesion == "jkr":
        k = f"{SJKR_K:.6g}"
        deck.append(f"fix m6 all property/global cohesionEnergyDensity peratomtypepair 2 "
                    f"{k} {k} {k} {k}")
    deck += [f"pair_style {law}", "pair_coeff * *",
             f"fix floor all wall/gran model hertz tangential history{coh} rolling_friction cdt "
             "primitive type 2 zplane 0.0"]
    deck += _common_tail(steps)
    desc = (f"LIGGGHTS pair_style {law}; mu_r {mur_pp:g} particle-particle (x R_eff), "
            f"{MU_R:g} floor")
    if cohesion == "jkr":
        desc += f"; sJKR k = {SJKR_K:.3g} J/m^3 (simplified JKR, not the JKR law)"
    return "\n".join(deck) + "\n", desc


def lammps_deck(data: str, steps: int, cohesion: str) -> tuple[str, str]:
    """LAMMPS pair granular deck as close as available to soilcal's laws."""
    ep = f"{E_TSUJI:.6g}"
    kt = f"{KT:.6g}"
    xg = f"{TDAMP_RATIO:.6g}"
    kr = f"{K_ROLL:.6g}"
    mur_pp = ROLLING_PAIR_FACTOR * MU_R
    e_wall = E / (1.0 + NU)  # wall/gran mixes E/(2(1-nu)) in this build (module docstring)
    if cohesion == "jkr":
        normal = f"jkr {E!r} {ep} {NU} {0.5 * GAMMA!r}"
        # fix wall/gran ... jkr of this build gives NaN forces at the first floor contact
        # (tested with and without tangential/rolling history): the floor is cohesionless.
        normal_w = f"hertz/material {e_wall!r} {ep} {NU}"
    else:
        normal = f"hertz/material {E!r} {ep} {NU}"
        normal_w = f"hertz/material {e_wall!r} {ep} {NU}"
    rest = f"damping tsuji tangential mindlin {kt} {xg} {MU_S}"
    pair = f"{normal} {rest} rolling sds {kr} 0.0 {mur_pp!r}"
    wall = f"{normal_w} {rest} rolling sds {kr} 0.0 {MU_R!r}"
    deck = [
        "units si", "atom_style sphere", "atom_modify map array", "boundary p p f",
        "comm_modify vel yes", "processors * * 1", f"read_data {data}",
        f"neighbor {SKIN:.6g} bin", "neigh_modify delay 0 every 1 check yes",
        "pair_style granular", f"pair_coeff * * {pair}",
        f"fix floor all wall/gran granular {wall} zplane 0.0 NULL",
    ]
    deck += _common_tail(steps)
    desc = (f"LAMMPS pair_style granular {pair.split()[0]} + damping tsuji (e'={E_TSUJI:.3f}: "
            f"same eta_n as soilcal) + tangential mindlin + rolling sds (k_roll {K_ROLL:.3g} "
            f"N/m, undamped, mu_roll {mur_pp:g} x R_eff; spring-slider, not constant torque)")
    if cohesion == "jkr":
        desc += (f"; JKR gamma {0.5 * GAMMA:g} (w = {GAMMA:g}, same pull-off as soilcal) "
                 "between particles, floor without cohesion (wall/gran jkr unusable here)")
    return "\n".join(deck) + "\n", desc


def find_binary(engine: str) -> str | None:
    names = {"liggghts": ["liggghts", "lmp_liggghts"],
             "lammps": ["lmp", "lmp_openmpi", "lmp_mpi", "lmp_serial"]}[engine]
    for name in names:
        p = shutil.which(name)
        if p:
            return p
    return None


def available(engine: str) -> tuple[bool, str]:
    """(usable, note): binary and mpirun present."""
    b = find_binary(engine)
    if b is None:
        return False, f"{engine} binary not found"
    if shutil.which("mpirun") is None:
        return False, "mpirun not found"
    return True, b


_LOOP = re.compile(r"Loop time of ([0-9.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms")
_MEM_LMP = re.compile(r"Per MPI rank memory allocation \(min/avg/max\) = ([0-9.]+) \| ([0-9.]+) \| "
                      r"([0-9.]+) Mbytes")
_MEM_LIG = re.compile(r"Memory usage per processor = ([0-9.]+) Mbytes")


def parse_log(text: str) -> dict:
    """Loop time, atoms, engine-reported memory and the last thermo row of the run."""
    m = _LOOP.search(text)
    if not m:
        raise RuntimeError("no 'Loop time' line in the output")
    out = dict(loop_s=float(m.group(1)), procs=int(m.group(2)), steps=int(m.group(3)),
               n=int(m.group(4)))
    mm = _MEM_LMP.search(text)
    if mm:
        out["engine_mem_mb"] = float(mm.group(3))
    else:
        mm = _MEM_LIG.search(text)
        out["engine_mem_mb"] = float(mm.group(1)) if mm else None
    head = text[:m.start()]
    lines = head.splitlines()
    hdr = max(i for i, ln in enumerate(lines) if ln.split()[:1] == ["Step"])
    cols = lines[hdr].split()
    last = None
    for ln in lines[hdr + 1:]:
        parts = ln.split()
        if len(parts) == len(cols):
            try:
                last = [float(p) for p in parts]
            except ValueError:
                break
        else:
            break
    if last is not None:
        row = {c[2:] if c.startswith("c_") else c: v for c, v in zip(cols, last)}
        out["ke_final_J"] = row.get("ket")
        out["erot_final_J"] = row.get("erot")
        out["bed_top_m"] = row.get("zmax")
        out["atoms_final"] = int(row.get("Atoms", out["n"]))
    return out


def run_reference(engine: str, n: int, steps: int, ranks: int, cohesion: str = "none",
                  seed: int = 2024, keep: str | Path | None = None,
                  timeout: float | None = None) -> dict:
    """Run one case with LIGGGHTS or LAMMPS; returns a row like ``soilcal bench settle``."""
    ok, binary = available(engine)
    if not ok:
        raise RuntimeError(binary)
    nx = nx_for(n)
    work = Path(keep) if keep else Path(tempfile.mkdtemp(prefix=f"settle-{engine}-"))
    work.mkdir(parents=True, exist_ok=True)
    try:
        ntypes = 2 if engine == "liggghts" else 1
        natoms, _side = write_data(work / "data.settle", nx, seed, ntypes)
        make = liggghts_deck if engine == "liggghts" else lammps_deck
        deck, law = make("data.settle", steps, cohesion)
        (work / "in.settle").write_text(deck)
        prefix = (["/usr/bin/time", "-f", "MAXRSS_KB %M", "-o", "time.txt"]
                  if Path("/usr/bin/time").exists() else [])
        t0 = time.perf_counter()
        rc, stdout = launch([binary, "-in", "in.settle", "-log", "log.settle"], work, ranks,
                            timeout, prefix)
        total_s = time.perf_counter() - t0
        if rc != 0:
            tail = "\n".join(stdout.splitlines()[-15:])
            raise RuntimeError(f"{engine} failed (rc {rc}):\n{tail}")
        res = parse_log(stdout)
        rank_rss = None
        tf = work / "time.txt"
        if tf.exists():
            m = re.search(r"MAXRSS_KB (\d+)", tf.read_text())
            rank_rss = int(m.group(1)) / 1024.0 if m else None
        version = ""
        vm = re.search(r"^(LIGGGHTS \(Version[^)]*\)|LAMMPS \([^)]*\))", stdout, re.M)
        if vm:
            version = vm.group(1)
        wall_s = res["loop_s"]
        return dict(
            case="settle", engine=engine, n=res["n"], steps=res["steps"], threads=res["procs"],
            cohesion=cohesion, wall_s=round(wall_s, 4), total_s=round(total_s, 2),
            particle_steps_per_s=res["n"] * res["steps"] / wall_s if wall_s > 0 else None,
            peak_rss_mb=round(rank_rss * ranks, 1) if rank_rss else None,
            rank_rss_mb=round(rank_rss, 1) if rank_rss else None,
            engine_mem_mb=res.get("engine_mem_mb"), ke_final_J=res.get("ke_final_J"),
            erot_final_J=res.get("erot_final_J"), bed_top_m=res.get("bed_top_m"),
            atoms_final=res.get("atoms_final"), load_avg_1min=os.getloadavg()[0],
            skin_m=SKIN, law=law, version=version, binary=binary, natoms_written=natoms)
    finally:
        if not keep:
            shutil.rmtree(work, ignore_errors=True)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--engine", choices=["liggghts", "lammps"], required=True)
    ap.add_argument("--n", type=int, default=5000)
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--ranks", type=int, default=1)
    ap.add_argument("--cohesion", choices=["none", "jkr"], default="none")
    ap.add_argument("--seed", type=int, default=2024)
    ap.add_argument("--keep", default=None, help="work directory to keep (data, deck, log)")
    ap.add_argument("--deck-only", action="store_true", help="write data and deck, do not run")
    args = ap.parse_args(argv)
    if args.deck_only:
        work = Path(args.keep or ".")
        work.mkdir(parents=True, exist_ok=True)
        write_data(work / "data.settle", nx_for(args.n), args.seed,
                   2 if args.engine == "liggghts" else 1)
        make = liggghts_deck if args.engine == "liggghts" else lammps_deck
        deck, law = make("data.settle", args.steps, args.cohesion)
        (work / "in.settle").write_text(deck)
        print(law)
        return 0
    print(json.dumps(run_reference(args.engine, args.n, args.steps, args.ranks, args.cohesion,
                                   args.seed, args.keep)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
