"""Parity with LIGGGHTS 3.8 and LAMMPS on identical cases (``soilcal.reference``).

1. Few-body cases: the trajectories of soilcal (``liggghts`` conventions) and LIGGGHTS from
   the same spheres and walls, compared particle by particle (largest position, velocity
   and angular-velocity difference after the run).
2. The lifted-tube pile (:mod:`soilcal.reference.cases`) at rolling frictions 0.05, 0.1 and
   0.2, each seed's settled fill run three ways: LIGGGHTS, soilcal with LIGGGHTS's
   conventions, soilcal with EDEM's (the default); the same angle estimators on every final
   state.  The mean angles are compared against the combined seed scatter (standard error
   of the difference of two means).
3. With ``--drum``: the rotating drum (vineyard dimensions), the same three ways, the mean
   free-surface angle of its frames per run.
4. With ``--lammps-few``: the JKR few-body cases (``soilcal.reference.few.JKR_CASES``) against
   LAMMPS ``pair granular jkr``, soilcal with the ``lammps`` conventions, and with each of
   LAMMPS's terms switched back to EDEM's in turn.
5. With ``--column``: the cohesive column (:func:`soilcal.reference.cases.collapsed_column`)
   at the surface energies ``--gammas``, each seed's settled fill run three ways: LAMMPS,
   soilcal with LAMMPS's conventions, soilcal with EDEM's (the same work of adhesion and
   damping); ``--jobs`` runs at a time, one thread each.
6. With ``--jkr-drum``: the rotating drum with JKR cohesion between the spheres
   (:class:`soilcal.reference.cases.JkrDrumCase`: smooth walls without adhesion, no rolling
   resistance) at the surface energies ``--drum-gammas``, the same three ways as the column,
   the mean free-surface angle of its frames per run.

Rows go to ``benchmarks/results/parity.csv`` (commit and time per row), the page to
``parity.md``.

Usage: python benchmarks/parity.py [--n 2000] [--seeds 0-4] [--mur 0.05,0.1,0.2]
       [--ranks 2] [--threads 2] [--skip-few] [--skip-pile] [--drum] [--drum-spin 2.0]
       [--lammps-few] [--column] [--column-n 1000] [--gammas 0.25,0.5,1.0] [--jobs 2]
       [--jkr-drum] [--drum-gammas 0,0.5,1.0]
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import (HERE, commit, read_rows, run_cases, runs_table, seed_list,  # noqa: E402
                     write_page, write_rows)

OUT = HERE / "results"
PILE_FIELDS = ["utc", "commit", "engine", "conventions", "n", "seed", "rolling_friction",
               "tube_diameter", "dt", "steps", "wall_s", "n_on_plate", "angle_bins_deg",
               "angle_surface_deg", "height_m", "fill_settled", "version"]
DRUM_FIELDS = ["utc", "commit", "engine", "conventions", "n", "seed", "rolling_friction", "rpm",
               "spin", "transient", "frames", "dt", "steps", "wall_s", "angle_deg",
               "angle_frames_sd_deg", "fill_settled", "version"]
FEW_FIELDS = ["utc", "commit", "case", "rolling", "steps", "max_dx_m", "max_dv_m_s",
              "max_dw_rad_s", "travel_m", "vmax_m_s", "wmax_rad_s", "version"]
JKR_FEW_FIELDS = ["utc", "commit", "case", "conventions", "steps", "max_dx_m", "max_dv_m_s",
                  "max_dw_rad_s", "travel_m", "vmax_m_s", "wmax_rad_s", "version"]
COLUMN_FIELDS = ["utc", "commit", "engine", "conventions", "n", "seed", "surface_energy",
                 "damping_eta", "dt", "steps", "wall_s", "n_on_plate", "angle_bins_deg",
                 "angle_surface_deg", "height_m", "fill_settled", "version"]
JKR_DRUM_FIELDS = ["utc", "commit", "engine", "conventions", "n", "seed", "surface_energy",
                   "damping_eta", "rpm", "spin", "transient", "frames", "dt", "steps", "wall_s",
                   "angle_deg", "angle_frames_sd_deg", "fill_settled", "version"]
#: LAMMPS's terms (contact.py) switched back to EDEM's one at a time in the JKR few-body table
LAMMPS_TERMS = (("jkr_break", "displacement"), ("coulomb_force", "total"),
                ("tangential_slip", "spring"), ("history_rotation", "project"),
                ("contact_lever", "contact_point"))




def few_body():
    from soilcal.reference.few import CASES, compare

    rows = []
    for name in CASES:
        for rolling in ("none", "constant_torque"):
            r = compare(name, rolling)
            rows.append(dict(case=name, rolling=rolling, steps=r["steps"],
                             max_dx_m=f"{r['dx']:.3g}", max_dv_m_s=f"{r['dv']:.3g}",
                             max_dw_rad_s=f"{r['dw']:.3g}", travel_m=f"{r['travel']:.3g}",
                             vmax_m_s=f"{r['vmax']:.3g}", wmax_rad_s=f"{r['wmax']:.3g}",
                             version=r["version"]))
            print(name, rolling, rows[-1], flush=True)
    return rows


def pile(n, seeds, murs, ranks, threads):
    import numba

    from soilcal.reference import cases as C
    from soilcal.reference import liggghts as L

    numba.set_num_threads(threads)
    rows = []
    for mur in murs:
        for seed in seeds:
            case = C.TubeCase(n=n, seed=seed, rolling_friction=mur)
            sim, phases, bounds, info = C.lifted_tube(case, "liggghts")
            steps = sum(s for s, _ in phases)
            base = dict(n=n, seed=seed, rolling_friction=mur,
                        tube_diameter=f"{2 * case.tube_radius():.4f}", dt=f"{info['dt']:.4g}",
                        steps=steps, fill_settled=info["fill_settled"])
            t0 = time.perf_counter()
            res = L.run(C.restart(sim, "liggghts"), phases, bounds, ranks=ranks)
            wall = time.perf_counter() - t0
            ang = C.heap_angles(res["x"], res["r"], res["present"])
            rows.append(dict(base, engine="liggghts", conventions="liggghts",
                             wall_s=f"{wall:.1f}", version=res["version"], **_fmt(ang)))
            print(rows[-1], flush=True)
            for conv in ("liggghts", "edem"):
                s = C.restart(sim, conv)
                t0 = time.perf_counter()
                L.run_phases(s, phases)
                wall = time.perf_counter() - t0
                rr = s.index(np.arange(s.n))
                ang = C.heap_angles(s.x[rr], s.p.r[rr])
                rows.append(dict(base, engine="soilcal", conventions=conv,
                                 wall_s=f"{wall:.1f}", version="", **_fmt(ang)))
                print(rows[-1], flush=True)
    return rows


def drum(n, seeds, mur, spin, ranks, threads):
    import numba

    from soilcal.reference import cases as C
    from soilcal.reference import liggghts as L

    numba.set_num_threads(threads)
    rows = []
    for seed in seeds:
        case = C.DrumCase(n=n, seed=seed, rolling_friction=mur, spin=spin)
        sim, phases, bounds, info = C.rotating_drum(case, "liggghts")
        base = dict(n=n, seed=seed, rolling_friction=mur, rpm=case.rpm, spin=spin,
                    transient=case.transient, frames=info["frames"], dt=f"{info['dt']:.4g}",
                    steps=sum(s for s, _ in phases), fill_settled=info["fill_settled"])
        t0 = time.perf_counter()
        res = L.run(C.restart(sim, "liggghts"), phases, bounds, ranks=ranks, snapshots=True)
        rows.append(dict(base, engine="liggghts", conventions="liggghts",
                         wall_s=f"{time.perf_counter() - t0:.1f}", version=res["version"],
                         **_fmt(C.drum_angles(res["states"], case))))
        print(rows[-1], flush=True)
        for conv in ("liggghts", "edem"):
            s = C.restart(sim, conv)
            t0 = time.perf_counter()
            states = L.run_phases(s, phases, snapshots=True)
            rows.append(dict(base, engine="soilcal", conventions=conv,
                             wall_s=f"{time.perf_counter() - t0:.1f}", version="",
                             **_fmt(C.drum_angles(states, case))))
            print(rows[-1], flush=True)
    return rows


def jkr_few_body():
    from soilcal.reference.few import JKR_CASES, compare_lammps

    rows = []
    for name in JKR_CASES:
        for option, value in ((None, None), *LAMMPS_TERMS):
            kw = {option: value} if option else {}
            r = compare_lammps(name, **kw)
            label = "lammps" + (f", {option}: {value}" if option else "")
            rows.append(dict(case=name, conventions=label, steps=r["steps"],
                             max_dx_m=f"{r['dx']:.3g}", max_dv_m_s=f"{r['dv']:.3g}",
                             max_dw_rad_s=f"{r['dw']:.3g}", travel_m=f"{r['travel']:.3g}",
                             vmax_m_s=f"{r['vmax']:.3g}", wmax_rad_s=f"{r['wmax']:.3g}",
                             version=r["version"]))
            print(rows[-1], flush=True)
    return rows


def column_one(n, gamma, seed, engine, conventions, rev):
    """One run of the cohesive column from the fill of (n, gamma, seed): LAMMPS, or soilcal
    with the named conventions."""
    import numba

    from soilcal.reference import cases as C
    from soilcal.reference import lammps as LM
    from soilcal.reference.deck import run_phases

    numba.set_num_threads(1)
    case = C.ColumnCase(n=n, seed=seed, surface_energy=gamma)
    sim, phases, bounds, info = C.collapsed_column(case)
    model = case.contact_model()
    row = dict(utc=datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M"), commit=rev, n=n,
               seed=seed, surface_energy=gamma, damping_eta=case.damping_eta,
               dt=f"{info['dt']:.4g}", steps=sum(s for s, _ in phases),
               fill_settled=info["fill_settled"])
    t0 = time.perf_counter()
    if engine == "lammps":
        res = LM.run(C.restart(sim, "lammps", model), phases, bounds)
        ang = C.heap_angles(res["x"], res["r"], res["present"])
        row.update(engine="lammps", conventions="lammps", version=res["version"])
    else:
        s = C.restart(sim, conventions, model)
        run_phases(s, phases)
        rr = s.index(np.arange(s.n))
        ang = C.heap_angles(s.x[rr], s.p.r[rr], C.inside(s.x[rr], bounds))
        row.update(engine="soilcal", conventions=conventions, version="")
    row["wall_s"] = f"{time.perf_counter() - t0:.1f}"
    return dict(row, **_fmt(ang))


def jkr_drum_one(n, gamma, seed, engine, conventions, spin, rev):
    """One run of the JKR drum from the fill of (n, gamma, seed): LAMMPS, or soilcal with the
    named conventions; the mean free-surface angle of its frames."""
    import numba

    from soilcal.reference import cases as C
    from soilcal.reference import lammps as LM
    from soilcal.reference.deck import run_phases

    numba.set_num_threads(1)
    case = C.JkrDrumCase(n=n, seed=seed, surface_energy=gamma, spin=spin)
    sim, phases, bounds, info = C.rotating_drum(case, "lammps")
    model = case.contact_model()
    row = dict(utc=datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M"), commit=rev, n=n,
               seed=seed, surface_energy=gamma, damping_eta=case.damping_eta, rpm=case.rpm,
               spin=spin, transient=case.transient, frames=info["frames"],
               dt=f"{info['dt']:.4g}", steps=sum(s for s, _ in phases),
               fill_settled=info["fill_settled"])
    t0 = time.perf_counter()
    if engine == "lammps":
        res = LM.run(C.restart(sim, "lammps", model), phases, bounds, snapshots=True)
        states = res["states"]
        row.update(engine="lammps", conventions="lammps", version=res["version"])
    else:
        states = run_phases(C.restart(sim, conventions, model), phases, snapshots=True)
        row.update(engine="soilcal", conventions=conventions, version="")
    row["wall_s"] = f"{time.perf_counter() - t0:.1f}"
    return dict(row, **_fmt(C.drum_angles(states, case)))


def _fmt(ang):
    return {k: (f"{v:.3f}" if isinstance(v, float) else v) for k, v in ang.items()}


def summary(rows, cols=("angle_bins_deg", "angle_surface_deg"),
            names=("radial bins", "surface scan"), ref_engine="liggghts",
            key=("rolling_friction", "mu_r")):
    """Mean, SD and seeds per (n, key column, engine, conventions); the differences to the
    reference engine with their combined standard error."""
    import pandas as pd

    df = pd.DataFrame(rows)
    if df.empty:
        return []
    for c in (*cols, key[0], "n", "seed"):
        df[c] = pd.to_numeric(df[c], errors="coerce")
    label = {"liggghts": "LIGGGHTS", "lammps": "LAMMPS"}[ref_engine]
    lines = [f"| spheres | {key[1]} | engine (conventions) | seeds | "
             + " | ".join(f"{n} [deg]" for n in names) + " | "
             + " | ".join(f"{n} - {label} (SE)" for n in names) + " |",
             "|---:|---:|---|---:|" + "---|" * (2 * len(cols))]
    for (n, mur), g in df.groupby(["n", key[0]]):
        ref = g[g.engine == ref_engine]
        for (eng, conv), h in g.groupby(["engine", "conventions"], sort=False):
            cells = []
            for col in cols:
                a = h[col].dropna()
                cells.append(f"{a.mean():.2f} +- {a.std(ddof=1):.2f}")
            diffs = []
            for col in cols:
                a, b = h[col].dropna(), ref[col].dropna()
                if eng == ref_engine or len(a) < 2 or len(b) < 2:
                    diffs.append("")
                    continue
                se = math.sqrt(a.var(ddof=1) / len(a) + b.var(ddof=1) / len(b))
                diffs.append(f"{a.mean() - b.mean():+.2f} ({se:.2f})")
            lines.append(f"| {n} | {mur:g} | {eng} ({conv}) | {h.seed.nunique()} | "
                         + " | ".join(cells) + " | " + " | ".join(diffs) + " |")
    return lines


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=2000)
    ap.add_argument("--seeds", default="0-4")
    ap.add_argument("--mur", default="0.05,0.1,0.2")
    ap.add_argument("--ranks", type=int, default=2)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--skip-few", action="store_true")
    ap.add_argument("--skip-pile", action="store_true")
    ap.add_argument("--drum", action="store_true")
    ap.add_argument("--drum-n", type=int, default=1000)
    ap.add_argument("--drum-mur", type=float, default=0.1)
    ap.add_argument("--drum-spin", type=float, default=2.0)
    ap.add_argument("--lammps-few", action="store_true")
    ap.add_argument("--column", action="store_true")
    ap.add_argument("--column-n", type=int, default=1000)
    ap.add_argument("--gammas", default="0.25,0.5,1.0")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--jkr-drum", action="store_true")
    ap.add_argument("--drum-gammas", default="0,0.5,1.0")
    args = ap.parse_args(argv)
    from soilcal.reference import lammps as LM
    from soilcal.reference import liggghts as L

    if not (args.skip_few and args.skip_pile) or args.drum:
        ok, why = L.available()
        if not ok:
            sys.exit(f"parity: {why}")
    if args.lammps_few or args.column or args.jkr_drum:
        ok, why = LM.available()
        if not ok:
            sys.exit(f"parity: {why}")
    stamp = dict(utc=datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M"), commit=commit())
    few_path, pile_path = OUT / "parity_few.csv", OUT / "parity.csv"
    few_rows = read_rows(few_path, FEW_FIELDS)
    drum_path = OUT / "parity_drum.csv"
    drum_rows = read_rows(drum_path, DRUM_FIELDS)
    pile_rows = read_rows(pile_path, PILE_FIELDS)
    jkr_path, column_path = OUT / "parity_jkr_few.csv", OUT / "parity_column.csv"
    jkr_rows = read_rows(jkr_path, JKR_FEW_FIELDS)
    column_rows = read_rows(column_path, COLUMN_FIELDS)
    jkr_drum_path = OUT / "parity_jkr_drum.csv"
    jkr_drum_rows = read_rows(jkr_drum_path, JKR_DRUM_FIELDS)
    if not args.skip_few:
        few_rows = [dict(stamp, **r) for r in few_body()]
        write_rows(few_path, few_rows, FEW_FIELDS)
    if not args.skip_pile:
        new = pile(args.n, seed_list(args.seeds), [float(m) for m in args.mur.split(",")],
                   args.ranks, args.threads)
        keep = [r for r in pile_rows if not (str(r["n"]) == str(args.n) and float(r["rolling_friction"])
                                             in [float(m) for m in args.mur.split(",")])]
        pile_rows = keep + [dict(stamp, **r) for r in new]
        write_rows(pile_path, pile_rows, PILE_FIELDS)
    if args.drum:
        new = drum(args.drum_n, seed_list(args.seeds), args.drum_mur, args.drum_spin,
                   args.ranks, args.threads)
        keep = [r for r in drum_rows if not (str(r["n"]) == str(args.drum_n) and
                                             float(r["rolling_friction"]) == args.drum_mur)]
        drum_rows = keep + [dict(stamp, **r) for r in new]
        write_rows(drum_path, drum_rows, DRUM_FIELDS)
    if args.lammps_few:
        jkr_rows = [dict(stamp, **r) for r in jkr_few_body()]
        write_rows(jkr_path, jkr_rows, JKR_FEW_FIELDS)
    if args.column:
        cases = [(args.column_n, float(g), seed, engine, conv) for g in args.gammas.split(",")
                 for seed in seed_list(args.seeds)
                 for engine, conv in (("lammps", "lammps"), ("soilcal", "lammps"),
                                      ("soilcal", "edem"))]
        column_rows = run_cases(
            column_one, cases, stamp["commit"], column_path, COLUMN_FIELDS,
            lambda r: (str(r["n"]), float(r["surface_energy"]), str(r["seed"]), r["engine"],
                       r["conventions"]), args.jobs,
            show=("engine", "conventions", "surface_energy", "seed", "angle_bins_deg",
                  "angle_surface_deg", "wall_s"))
    if args.jkr_drum:
        cases = [(args.drum_n, float(g), seed, engine, conv, args.drum_spin)
                 for g in args.drum_gammas.split(",") for seed in seed_list(args.seeds)
                 for engine, conv in (("lammps", "lammps"), ("soilcal", "lammps"),
                                      ("soilcal", "edem"))]
        jkr_drum_rows = run_cases(
            jkr_drum_one, cases, stamp["commit"], jkr_drum_path, JKR_DRUM_FIELDS,
            lambda r: (str(r["n"]), float(r["surface_energy"]), str(r["seed"]), r["engine"],
                       r["conventions"], float(r["spin"])), args.jobs,
            show=("engine", "conventions", "surface_energy", "seed", "angle_deg", "wall_s"))
    lines = ["# Parity with LIGGGHTS 3.8 and LAMMPS on identical cases", "",
             f"Machine: {os.uname().machine}, {os.cpu_count()} logical CPUs.  Last command: "
             f"`python benchmarks/parity.py {' '.join(argv or sys.argv[1:])}`.  Rows: "
             "`parity_few.csv`, `parity.csv`, `parity_drum.csv`, `parity_jkr_few.csv`, "
             "`parity_column.csv`, `parity_jkr_drum.csv`.", "",
             "## Few-body cases: largest difference after the run (soilcal with the "
             "`liggghts` conventions)", "",
             *runs_table(few_rows, ["case", "rolling", "steps", "travel_m", "max_dx_m",
                                    "vmax_m_s", "max_dv_m_s", "wmax_rad_s", "max_dw_rad_s",
                                    "commit"]), "",
             "## Lifted-tube pile (same settled fill for every engine)", "",
             *summary(pile_rows), "", "Runs:", "",
             *runs_table(pile_rows, PILE_FIELDS), "",
             "## Rotating drum (same settled fill for every engine; mean of the frames)", "",
             *summary(drum_rows, ("angle_deg",), ("frame mean",)), "", "Runs:", "",
             *runs_table(drum_rows, DRUM_FIELDS), "",
             "## JKR few-body cases against LAMMPS: largest difference after the run", "",
             *runs_table(jkr_rows, ["case", "conventions", "steps", "travel_m", "max_dx_m",
                                    "vmax_m_s", "max_dv_m_s", "wmax_rad_s", "max_dw_rad_s",
                                    "version", "commit"]), "",
             "## Cohesive column against LAMMPS (JKR; same settled fill for every engine)", "",
             *summary(column_rows, ref_engine="lammps",
                      key=("surface_energy", "gamma [J/m^2]")), "", "Runs:", "",
             *runs_table(column_rows, COLUMN_FIELDS), "",
             "## Rotating drum with JKR against LAMMPS (smooth walls without adhesion, no "
             "rolling resistance; same settled fill for every engine; mean of the frames)", "",
             *summary(jkr_drum_rows, ("angle_deg",), ("frame mean",), ref_engine="lammps",
                      key=("surface_energy", "gamma [J/m^2]")), "", "Runs:", "",
             *runs_table(jkr_drum_rows, JKR_DRUM_FIELDS)]
    write_page(OUT / "parity.md", lines)


if __name__ == "__main__":
    main()
