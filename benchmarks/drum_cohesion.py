"""How the quick drum's dynamic angle responds to the JKR surface energy (vineyard soil, 003).

003's Plackett-Burman screening (Table 5) gives the surface energy H (0.1 -> 0.3 J/m^2) an
effect of +7.3 deg on the dynamic angle, among the largest.  This benchmark sweeps H alone at
fixed values of the other factors and measures the soil's drum response
(``angle_avalanche_deg``, the angle before collapse) and the time mean of the frame angles,
several seeds per level, at the quick preset:

* ``pb-centre``: every other screening factor at the centre of its Plackett-Burman range;
* ``pb-centre C-low`` / ``C-high``: the same with the soil-soil static friction C at its
  screening ends (0.2, 1.16), where the screening's H effect is averaged;
* ``bbd-centre``: the Box-Behnken centre of the paper (Table 7's other factors);
* ``pb-centre lammps-JKR``: as ``pb-centre`` with w = 2 gamma (the LAMMPS convention, the
  force law the EDEM guide prints; ``soilcal.dem.contact``), i.e. twice the adhesion;
* ``pb-centre gap-JKR``: as ``pb-centre`` with ``jkr_approach: gap``: spheres attract across
  a gap within the JKR separation range before they touch, as the EDEM guide describes its
  JKR ("the same solution ... for both loading and unloading phases");
* ``pb-centre paper-PSD``: as ``pb-centre`` with 003's particle sizes (2.5, 5 and 10 mm in
  equal mass, about 5,500 spheres) instead of the quick preset's 1,000 equal ones, with the
  quick preset's softened shear modulus (half its time-step fraction, which the smallest
  spheres need), so the surface energy is not rescaled by the size rule: the particle scale;
* ``pb-centre stiff`` / ``pb-centre paper-PSD stiff``: the quick spheres / 003's sizes with
  the shear modulus capped at ``STIFF_G`` (ten times the quick cap) instead of the quick cap;
* ``pb-centre paper-G``: the quick spheres at the paper's own shear modulus (no cap, so the
  surface energy is not weakened by the stiffness rule gamma s^(2/5) of
  :mod:`soilcal.dem.scenarios.base`; the size rule still applies), the quick step fraction.

Per base and H: mean and SD over the seeds; per base: the least-squares slope of the angle on
H (deg per 0.1 J/m^2) with its standard error, beside the paper's effect over its range
(7.3 deg / 0.2 J/m^2 = 3.65 deg per 0.1 J/m^2).  Rows: ``benchmarks/results/drum_cohesion.csv``;
page ``drum_cohesion.md`` (notes below its marker are kept).

    python benchmarks/drum_cohesion.py --jobs 2 --seeds 0-2
"""

from __future__ import annotations

import argparse
import math
import platform
import sys
import time
from pathlib import Path

import numpy as np
from _report import commit, run_cases, runs_table, seed_list, write_page

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
SOIL = ROOT / "config" / "soils" / "xinjiang-vineyard.yaml"
FIELDS = ["utc", "commit", "base", "H", "seed", "levels", "conventions", "n_frames", "n_avalanches",
          "angle_avalanche_deg", "angle_deg", "steps", "wall_s", "particles"]
H_LEVELS = (0.1, 0.15, 0.2, 0.25, 0.3)
PAPER_EFFECT = 7.3  # 003 Table 5: dynamic angle, H effect over 0.1 -> 0.3 J/m^2 (SS 160.02, 12 runs)
BASES = ("pb-centre", "pb-centre C-low", "pb-centre C-high", "bbd-centre", "pb-centre lammps-JKR",
         "pb-centre gap-JKR", "pb-centre paper-PSD", "pb-centre stiff", "pb-centre paper-PSD stiff", "pb-centre paper-G")
#: the conventions a base changes from EDEM's (only the JKR terms)
BASE_CONVENTIONS = {"pb-centre lammps-JKR": {"jkr_convention": "lammps"},
                    "pb-centre gap-JKR": {"jkr_approach": "gap"}}
#: shear-modulus cap of the ``stiff`` bases [Pa]: ten times the quick preset's (base.py)
STIFF_G = 5.0e6
#: shear-modulus cap [Pa] by a base's last word: ``stiff`` ten times the quick preset's,
#: ``paper-G`` none (the paper's own modulus)
MODULUS_CAP = {"stiff": STIFF_G, "paper-G": math.inf}




def levels_of(soil, base: str, h: float) -> tuple[str, dict]:
    """(stage, factor levels) of a base point with the surface energy at ``h``."""
    if base.startswith("bbd"):
        st = soil.stage("bbd")
        lev = {s: float(f["centre"]) for s, f in st["factors"].items()}
        sym = next(s for s, f in st["factors"].items() if f["parameter"] == "jkr_surface_energy")
        lev[sym] = h
        return "bbd", lev
    st = soil.stage("pb")
    lev = {s: (float(f["low"]) + float(f["high"])) / 2 for s, f in st["factors"].items()}
    if "C-low" in base:
        lev["C"] = float(st["factors"]["C"]["low"])
    if "C-high" in base:
        lev["C"] = float(st["factors"]["C"]["high"])
    lev["H"] = h
    return "pb", lev


def one(base, h, seed, rev):
    import numba

    from soilcal.config.load import load_soil
    from soilcal.dem.scenarios import design, drum

    numba.set_num_threads(1)
    soil = load_soil(SOIL, ROOT / "resources")
    stage, lev = levels_of(soil, base, h)
    sim = design.spec(soil, "dynamic_angle")
    params = design.design_params(soil, stage, lev, sim)
    conv = BASE_CONVENTIONS.get(base)
    setup = dict(sim.setup, contact_conventions=conv) if conv else dict(sim.setup)
    preset = "quick"
    cap = MODULUS_CAP.get(base.rsplit(" ", 1)[-1])
    if cap is not None:
        from soilcal.dem.scenarios.base import PRESET_DEFAULTS
        from soilcal.dem.scenarios.drum import PRESET_TIMES

        spin, trans = PRESET_TIMES["quick"]
        preset = "paper" if "paper-PSD" in base else "quick"
        setup.update(stiffness_scale=min(1.0, cap / params.soil_shear_modulus),
                     dt_fraction=PRESET_DEFAULTS["quick"]["dt_fraction"], spin_time=spin,
                     transient_time=trans)
    elif "paper-PSD" in base:
        from soilcal.dem.scenarios.base import PRESET_DEFAULTS, stiffness_scale_for

        # its particle sizes with the quick modulus; half the quick step fraction: at the
        # quick 0.3 a 2.5 mm sphere under the 10 mm ones overlapped by more than 30 % of its
        # radius while the fill settled (SimulationError at step 1,384)
        preset = "paper"
        setup.update(stiffness_scale=stiffness_scale_for(params, "quick"),
                     dt_fraction=0.5 * PRESET_DEFAULTS["quick"]["dt_fraction"])
    res = drum.run(setup, params, preset, seed, 1)
    r = res.responses
    return dict(utc=time.strftime("%Y-%m-%d %H:%M", time.gmtime()), commit=rev, base=base, H=h, seed=seed,
                levels=" ".join(f"{k}={v:g}" for k, v in lev.items()),
                conventions=" ".join(f"{k}={v}" for k, v in conv.items()) if conv else "edem",
                n_frames=r["n_frames"], n_avalanches=r["n_avalanches"],
                angle_avalanche_deg=round(r["angle_avalanche_deg"], 4), angle_deg=round(r["angle_deg"], 4),
                steps=res.steps, wall_s=round(res.wall_s, 2), particles=res.n_particles)


def slope(hs, ys):
    """Least-squares slope of y on H in deg per 0.1 J/m^2 and its standard error
    (``scipy.stats.linregress``)."""
    from scipy.stats import linregress

    hs, ys = np.asarray(hs, float), np.asarray(ys, float)
    ok = np.isfinite(ys)
    hs, ys = hs[ok], ys[ok]
    if len(set(hs)) < 2 or hs.size < 3:
        return float("nan"), float("nan")
    fit = linregress(hs, ys)
    return float(fit.slope) * 0.1, float(fit.stderr) * 0.1


def page(rows, md, cmd):
    lines = ["# The quick drum's dynamic angle against the JKR surface energy (vineyard soil)", "",
             f"Machine: {platform.machine()}, Python {platform.python_version()}.  Last command: `{cmd}`.  "
             "Rows: `drum_cohesion.csv` (utc and commit per row).  003 Table 5: H effect "
             f"{PAPER_EFFECT} deg over 0.1 -> 0.3 J/m^2, i.e. {PAPER_EFFECT / 2:.2f} deg per 0.1 J/m^2.", "",
             "Slope of the angle on H (least squares over every run of the base; deg per 0.1 J/m^2, "
             "+- standard error):", "",
             "| base | runs | angle before collapse | time mean |", "|---|---:|---:|---:|"]
    for base in BASES:
        g = [r for r in rows if r["base"] == base]
        if not g:
            continue
        hs = [float(r["H"]) for r in g]
        a, sa = slope(hs, [float(r["angle_avalanche_deg"]) for r in g])
        t, st = slope(hs, [float(r["angle_deg"]) for r in g])
        lines.append(f"| {base} | {len(g)} | {a:+.2f} +- {sa:.2f} | {t:+.2f} +- {st:.2f} |")
    lines += ["", "Per level (mean and SD over the seeds):", "",
              "| base | H J/m^2 | seeds | angle before collapse | SD | time mean | SD | collapses |",
              "|---|---:|---:|---:|---:|---:|---:|---|"]
    for base in BASES:
        for h in sorted({float(r["H"]) for r in rows if r["base"] == base}):
            g = [r for r in rows if r["base"] == base and float(r["H"]) == h]
            av = np.array([float(r["angle_avalanche_deg"]) for r in g])
            tm = np.array([float(r["angle_deg"]) for r in g])
            na = [int(r["n_avalanches"]) for r in g]
            sd = (lambda v: f"{v.std(ddof=1):.2f}" if v.size > 1 else "")
            lines.append(f"| {base} | {h:g} | {len(g)} | {av.mean():.2f} | {sd(av)} | {tm.mean():.2f} | {sd(tm)} | "
                         f"{min(na)}-{max(na)} |")
    lines += ["", "Runs:", ""]
    lines += runs_table(sorted(rows, key=lambda r: (BASES.index(r["base"]), float(r["H"]), int(r["seed"]))), FIELDS)
    write_page(md, lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bases", default=",".join(BASES), help="comma list of " + ", ".join(BASES))
    ap.add_argument("--levels", default=",".join(f"{h:g}" for h in H_LEVELS))
    ap.add_argument("--seeds", default="0-2")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--out", default=str(HERE / "results"))
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    csv_path, md = out / "drum_cohesion.csv", out / "drum_cohesion.md"
    bases = [b.strip() for b in args.bases.split(",") if b.strip()]
    unknown = [b for b in bases if b not in BASES]
    if unknown:
        ap.error(f"--bases: expected some of {', '.join(BASES)}, got {unknown}")
    cases = [(b, float(h), s) for b in bases for h in args.levels.split(",") for s in seed_list(args.seeds)]
    rows = run_cases(one, cases, commit(), csv_path, FIELDS, lambda r: (r["base"], float(r["H"]), int(r["seed"])),
                     args.jobs, show=("base", "H", "seed", "angle_avalanche_deg", "angle_deg", "wall_s"))
    page(rows, md, "python benchmarks/drum_cohesion.py " + " ".join(
        sys.argv[1:] if argv is None else argv))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
