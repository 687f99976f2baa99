"""Convergence of the bench-top scenarios: response vs particle count, stiffness, seed.

After the cohesive-soil paper's own check (004 Sec. 3.6, Table 12: the simulated angle of
repose for generated masses 0.1-0.3 kg, 31.3-32.2 deg, converged from 0.15 kg), each bench-top
scenario runs at its quick-preset settings and with one factor changed at a time:

* particle count ``n_particles`` (repose, drum, compression; radii follow from the fill),
* shear-modulus scale relative to the quick preset's (``stiffness_scale``; the JKR surface
  energy follows gamma s^(2/5)),
* seed (random insertion).

``--paper`` adds one run of each scenario at its ``paper`` preset (seed 0; factor
``preset``), when that preset's particle count is at most ``--paper-max-n``; the page lists
every scenario's quick and paper particle counts (from the scenario's own sizing, before any
run) and where the paper run lies against the quick preset's seed scatter.

The incline scenario has no particle-count axis (one block or ball); its stiffness and seed
axes are run.  Each run is one row of ``benchmarks/results/convergence/convergence.csv``
(scenario, setup, factor, value, seed, particle count, steps, wall time, responses); the
figure ``convergence.png`` / ``convergence.pdf`` plots the main response of every scenario
against the three factors (the quick preset's seed scatter, mean +- SD, shaded), and
``convergence.md`` tabulates the rows with the spread over seeds beside the range over
each factor.

    python benchmarks/convergence.py --level reduced      # a few CPU-minutes
    python benchmarks/convergence.py --level full         # more levels, paper-like counts
    python benchmarks/convergence.py --scenarios repose,incline   # other rows are kept
    python benchmarks/convergence.py --report-only   # figure and page from the CSV
    python benchmarks/convergence.py --level full --scenarios drum --paper   # + paper run
    python benchmarks/convergence.py --paper-only    # only the paper runs, rows kept
"""

from __future__ import annotations

import argparse
import csv
import os
import sys
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402
import numpy as np  # noqa: E402
from _report import read_rows, seed_and_ranges, write_page  # noqa: E402

HERE = Path(__file__).resolve().parent
OUT = HERE / "results" / "convergence"

# scenario -> (setup, main response, extra setup for every run)
CASES = {
    "repose": ("cinnamon-soil", "angle_deg", {}),
    "drum": ("xinjiang-vineyard", "angle_avalanche_deg", {}),  # the vineyard soil's measure
    "incline": ("yangtze-static", "onset_deg", {}),
    "compression": ("guangxi-cohesive", "stress_10_kpa", {}),
}
LEVELS = {
    "reduced": dict(n=[500, 1000, 2000], stiff=[1.0, 4.0], seeds=[0, 1, 2]),
    "full": dict(n=[500, 1000, 2000, 4000, 8000], stiff=[0.5, 1.0, 2.0, 4.0, 8.0],
                 seeds=[0, 1, 2, 3, 4]),
}
QUICK_N = 1000  # the quick preset's particle count (base.PRESET_DEFAULTS)
PAPER_MAX_N = 20000  # --paper runs a scenario's paper preset up to this many spheres
FIELDS = ["scenario", "setup", "factor", "value", "seed", "n_particles", "steps", "sim_time_s",
          "wall_s", "stiffness_scale", "cohesion_scale", "response", "value_response",
          "responses"]


def runs(level, scenarios, paper=(), quick=True):
    lv = LEVELS[level]
    for sc in scenarios:
        if sc in paper:
            yield sc, "preset", "paper", 0
        if not quick:
            continue
        if sc != "incline":
            for n in lv["n"]:
                yield sc, "n_particles", n, 0
        for f in lv["stiff"]:
            yield sc, "stiffness", f, 0
        for s in lv["seeds"]:
            yield sc, "seed", s, s


def _case(sc):
    """Scenario module, setup (image off) and DEM parameters of a scenario's runs."""
    from soilcal.dem.scenarios import SCENARIOS
    from soilcal.dem.scenarios.base import DemParams

    mod = SCENARIOS[sc]
    setup_name, _, extra = CASES[sc]
    setup = dict(mod.setups()[setup_name], name=setup_name, **extra)
    if "image" in setup:
        setup["image"] = False
    params = DemParams()
    if sc == "incline":
        params = DemParams(soil_steel_static_friction=0.71, soil_soil_surface_energy=0.0)
    return mod, setup, params


def preset_count(sc, preset):
    """Particle count of a scenario's run at ``preset``, from the scenario's own sizing
    (no run); None for the incline (one block or ball)."""
    mod, setup, _ = _case(sc)
    if not hasattr(mod, "sizing"):
        return None
    return int(mod.sizing(setup, preset)["n"])


def one(sc, factor, value, seed, threads):
    from soilcal.dem.scenarios.base import stiffness_scale_for

    mod, setup, params = _case(sc)
    setup_name, resp, _ = CASES[sc]
    preset = value if factor == "preset" else "quick"
    base_scale = stiffness_scale_for(params, preset)
    if factor == "n_particles":
        setup["n_particles"] = int(value)
    elif factor == "stiffness":
        setup["stiffness_scale"] = base_scale * float(value)
    res = mod.run(setup, params, preset, seed=int(seed), threads=threads)
    return dict(scenario=sc, setup=setup_name, factor=factor, value=value, seed=seed,
                n_particles=res.n_particles, steps=res.steps, sim_time_s=round(res.sim_time_s, 4),
                wall_s=round(res.wall_s, 2), stiffness_scale=res.setup["stiffness_scale"],
                cohesion_scale=round(float(res.setup.get("cohesion_scale", 1.0)), 4),
                response=resp, value_response=res.responses[resp],
                responses=";".join(f"{k}={v:.6g}" for k, v in res.responses.items()
                                   if isinstance(v, (int, float))))


def figure(rows, out):
    scen = sorted({r["scenario"] for r in rows}, key=list(CASES).index)
    facs = ["n_particles", "stiffness", "seed"]
    fig, axes = plt.subplots(len(scen), 3, figsize=(11, 2.6 * len(scen)), squeeze=False)
    for i, sc in enumerate(scen):
        for j, fac in enumerate(facs):
            ax = axes[i, j]
            sel = [r for r in rows if r["scenario"] == sc and r["factor"] == fac]
            if not sel:
                ax.axis("off")
                continue
            x = [float(r["value"]) for r in sel]
            y = [float(r["value_response"]) for r in sel]
            seeds = _finite([r["value_response"] for r in rows
                             if r["scenario"] == sc and r["factor"] == "seed"])
            if seeds.size > 1:  # the quick preset's seed scatter, mean +- 1 SD
                m, sd = seeds.mean(), seeds.std(ddof=1)
                ax.axhspan(m - sd, m + sd, color="0.85", zorder=0,
                           label=f"seeds: mean +- SD ({seeds.size})")
            ax.plot(x, y, "o-" if fac != "seed" else "o", color="C%d" % j)
            paper = [r for r in rows if r["scenario"] == sc and r["factor"] == "preset"]
            if fac == "n_particles" and paper and paper[0]["n_particles"] != "":
                ax.plot([float(paper[0]["n_particles"])], [float(paper[0]["value_response"])],
                        "*", ms=11, color="C3", label="paper preset (seed 0)")
                ax.legend(fontsize=7, loc="best")
            if fac in ("stiffness", "n_particles"):
                ax.set_xscale("log", base=2)
            if fac == "n_particles":
                ax.set_xticks(x)
                ax.xaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
                ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
            if i == 0 and j == 0 and seeds.size > 1:
                ax.legend(fontsize=7, loc="best")
            ax.set_xlabel({"n_particles": "particle count", "stiffness":
                           "G scale / quick preset's", "seed": "seed"}[fac])
            if j == 0 or (sc == "incline" and j == 1):
                ax.set_ylabel(f"{sc}: {sel[0]['response']}")
            ax.grid(alpha=0.3)
    fig.tight_layout()
    for ext in ("png", "pdf"):
        fig.savefig(out / f"convergence.{ext}", dpi=120)
    plt.close(fig)


def _finite(values):
    v = np.asarray([float(x) for x in values], float)
    return v[np.isfinite(v)]


def table(rows, out, cmd):
    md = out / "convergence.md"
    head = [f"Command: `{cmd}`; {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; "
            f"load_avg_1min at the end {os.getloadavg()[0]:.2f} (shared machine).", ""]
    if cmd is None:  # a page redrawn from the CSV keeps the line of the run
        old = md.read_text().splitlines() if md.exists() else []
        head = [x for x in old[2:3] if x.startswith("Command:")] + [""]
    lines = ["# Convergence of the bench-top scenarios (quick preset, one factor at a time)", "",
             *head,
             "| scenario | factor | value | seed | N | steps | wall s | G scale | gamma scale | "
             "response | value |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---|---:|"]
    for r in rows:
        lines.append(f"| {r['scenario']} | {r['factor']} | {r['value']} | {r['seed']} | "
                     f"{r['n_particles']} | {r['steps']} | {r['wall_s']} | "
                     f"{float(r['stiffness_scale']):.4g} | {r['cohesion_scale']} | "
                     f"{r['response']} | "
                     f"{float(r['value_response']):.3f} |")
    lines += ["", "Spread over seeds (sample standard deviation) against the range (max - min) "
              "over each factor's levels; ratio = range / seed SD.  The seed alone gives an "
              "expected range of 1.13, 1.69, 2.06 and 2.33 SD over 2, 3, 4 and 5 levels "
              "(normal scatter), so a ratio near those does not tell the factor from the "
              "seed:", "",
              "| scenario | response | seeds | mean | seed SD | particle-count range (ratio) | "
              "stiffness range (ratio) |", "|---|---|---:|---:|---:|---:|---:|"]
    for sc in CASES:
        v = _finite([r["value_response"] for r in rows
                     if r["scenario"] == sc and r["factor"] == "seed"])
        if v.size < 2:
            continue
        groups = [_finite([r["value_response"] for r in rows
                           if r["scenario"] == sc and r["factor"] == fac])
                  for fac in ("n_particles", "stiffness")]
        lines.append("| " + " | ".join([sc, CASES[sc][1], *seed_and_ranges(v, groups)]) + " |")
    lines += paper_lines(rows)
    write_page(md, lines)


def paper_lines(rows) -> list[str]:
    """Quick against paper preset: particle counts from the scenarios' sizing, and the
    paper-preset runs (factor ``preset``) against the quick preset's seed scatter."""
    lines = ["", "Quick against paper preset: particle counts from each scenario's sizing "
             "(no run); a paper run (`--paper`, seed 0) against the quick preset's seeds, "
             "as (paper - seed mean) / seed SD:", "",
             "| scenario | quick N | paper N | paper / quick | response | quick seeds: mean "
             "(SD) | paper run | in seed SDs | paper wall s |",
             "|---|---:|---:|---:|---|---|---:|---:|---:|"]
    for sc in CASES:
        if not any(r["scenario"] == sc for r in rows):
            continue
        nq, npp = preset_count(sc, "quick"), preset_count(sc, "paper")
        v = _finite([r["value_response"] for r in rows
                     if r["scenario"] == sc and r["factor"] == "seed"])
        p = [r for r in rows if r["scenario"] == sc and r["factor"] == "preset"]
        m, sd = (v.mean(), v.std(ddof=1)) if v.size > 1 else (float("nan"), float("nan"))
        cells = [sc, "-" if nq is None else str(nq), "-" if npp is None else str(npp),
                 "-" if nq is None else f"{npp / nq:.3g}", CASES[sc][1],
                 f"{m:.3f} ({sd:.3f})" if v.size > 1 else "-"]
        if p:
            pv = float(p[0]["value_response"])
            z = (pv - m) / sd if sd > 0 else float("nan")
            cells += [f"{pv:.3f}", f"{z:+.1f}" if np.isfinite(z) else "-", str(p[0]["wall_s"])]
        else:
            cells += ["not run", "-", "-"]
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--level", choices=sorted(LEVELS), default="reduced")
    ap.add_argument("--scenarios", default=",".join(CASES))
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--out", default=str(OUT))
    ap.add_argument("--report-only", action="store_true",
                    help="redraw the figure and the page from the CSV, run nothing")
    ap.add_argument("--paper", action="store_true",
                    help="also run each scenario once at its paper preset (seed 0)")
    ap.add_argument("--paper-only", action="store_true",
                    help="run only the paper-preset points; every other row is kept")
    ap.add_argument("--paper-max-n", type=int, default=PAPER_MAX_N,
                    help="largest paper-preset particle count --paper runs "
                         f"(default {PAPER_MAX_N}); larger ones are listed, not run")
    args = ap.parse_args(argv)
    scenarios = [s for s in args.scenarios.split(",") if s]
    for s in scenarios:
        if s not in CASES:
            ap.error(f"--scenarios: expected names from {sorted(CASES)}, got {s!r}")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    from soilcal.errors import SimulationError

    path = out / "convergence.csv"
    if args.report_only:
        rows = read_rows(path, FIELDS)
        for r in rows:
            r["value_response"] = float(r["value_response"] or "nan")
        figure(rows, out)
        table(rows, out, None)
        return
    # rows of the scenarios not run this time are kept, and of those run, the quick rows
    # with --paper-only and the paper-preset rows without --paper
    paper_run = args.paper or args.paper_only
    rows = [r for r in read_rows(path, FIELDS) if r["scenario"] not in scenarios
            or (args.paper_only and r["factor"] != "preset")
            or (not paper_run and r["factor"] == "preset")]
    for r in rows:
        r["value_response"] = float(r["value_response"] or "nan")
    cache = {}
    paper = ()
    if paper_run:
        paper = [sc for sc in scenarios
                 if (preset_count(sc, "paper") or 0) <= args.paper_max_n]
        print("paper preset runs:", paper or "none", flush=True)
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=FIELDS)
        w.writeheader()
        w.writerows(rows)
        for case in runs(args.level, scenarios, paper, quick=not args.paper_only):
            sc, factor, value, seed = case
            # the quick-preset point (1000 spheres, scale 1, seed 0) is run once per scenario
            key = (sc, value if factor == "n_particles" else QUICK_N,
                   value if factor == "stiffness" else 1.0, seed)
            if factor == "preset":
                key = (sc, value)
            if key not in cache:
                try:
                    cache[key] = one(*case, threads=args.threads)
                except SimulationError as e:  # a blow-up is a result: one row, no response
                    cache[key] = dict(scenario=sc, setup=CASES[sc][0], factor=factor,
                                      value=value, seed=seed, n_particles="", steps="",
                                      sim_time_s="", wall_s="", stiffness_scale=float("nan"),
                                      cohesion_scale="",
                                      response=CASES[sc][1], value_response=float("nan"),
                                      responses=f"error={e}")
            row = dict(cache[key], factor=factor, value=value)
            rows.append(row)
            w.writerow(row)
            fh.flush()
            print({k: row[k] for k in ("scenario", "factor", "value", "seed", "n_particles",
                                       "wall_s", "value_response")}, flush=True)
    figure(rows, out)
    table(rows, out, "python benchmarks/convergence.py " + " ".join(sys.argv[1:]))


if __name__ == "__main__":
    main()
