"""Does the stiffness-scaling rule for the surface energy keep a cohesive heap's response?

The quick preset lowers the soil shear modulus to at most 5e5 Pa (G_mod = s G) and, after
the vineyard-soil paper (003, after Lommen et al. 2014 and Thakur et al. 2014), scales the
JKR surface energy as gamma_mod = gamma s^(2/5) (``base.build_materials``).  The JKR
pull-off force 1.5 pi gamma R* does not depend on the stiffness, so the rule weakens the
adhesive force by s^(2/5): 0.12 for the black soil (printed G = 1e8 Pa, s = 0.005).

This benchmark runs one design point of a soil's first stage (the midpoints of its factors unless
levels are given) through the soil's simulation block (scenario, setup, measure) at shear
modulus factors ``--scales`` with two surface-energy rules:

* ``paper``: gamma s^(2/5) (what the quick preset does);
* ``none``: gamma kept (the pull-off force kept), by passing gamma s^(-2/5) to the rule.

At s = 1 (the printed modulus, the reference) the two rules coincide and only ``paper`` is
run.  ``--set`` overrides setup values (a finer ``radius``, ``scale_cohesion=false``).
Everything else is the quick preset (particle size, cohesion scaling with particle
size, time step).  ``gamma_soil_soil`` in a row is the surface energy handed to the rule
(the design point's, or s^(-2/5) times it for ``none``); the contact's is that times
s^(2/5) and the size factor ``cohesion_scale`` of the run (base.py).  One row per run in ``benchmarks/results/stiffness_rule.csv`` (a rerun of
the same soil, levels, scale, rule and seed replaces its row); ``stiffness_rule.md``
tabulates them with the mean per case.

    python benchmarks/stiffness_rule.py --soil black-soil --scales 1,0.005 --seeds 0-3
    python benchmarks/stiffness_rule.py --soil black-soil --levels x1=0.4 --jobs 2
    python benchmarks/stiffness_rule.py --levels x1=0.4 --scales 1 --seeds 0-1 \
        --set radius=0.0015625,n_particles=8000      # half the quick radius
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from _report import commit, read_rows, runs_table, seed_list, write_page, write_rows

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
FIELDS = ["utc", "commit", "soil", "stage", "response", "levels", "set", "scale", "G_Pa", "rule",
          "gamma_soil_soil", "seed", "particles", "steps", "dt_fraction", "wall_s", "measure",
          "value", "n_retained", "n_on_plate", "peak_overlap", "settled", "measure_errors"]




def centre_levels(stage, overrides):
    """Midpoints of the low and high levels of the factors not in ``overrides``."""
    levels = {}
    for k, v in stage["factors"].items():
        if k in overrides:
            continue
        if v.get("low") is None or v.get("high") is None:
            raise SystemExit(f"stages.{stage['id']}.factors.{k}: no low/high levels for the "
                             "midpoint; give it with --levels")
        levels[k] = 0.5 * (float(v["low"]) + float(v["high"]))
    return levels


def one(job):
    """Run one (soil, levels, scale, rule, seed) point; returns a row."""
    soil_name, overrides, setup_set, s, rule, seed = job
    import numba

    from soilcal.config.load import load_soil
    from soilcal.dem.scenarios import design, get
    from soilcal.dem.scenarios.base import DemParams

    numba.set_num_threads(1)
    soil = load_soil(ROOT / "config" / "soils" / f"{soil_name}.yaml", ROOT / "resources")
    stage = soil.data["stages"][0]
    rid = stage["responses"][0]["id"]
    merged = dict(centre_levels(stage, overrides), **overrides)
    levels = {k: merged[k] for k in stage["factors"]}  # the stage's order: one key per point
    sim = design.spec(soil, rid)
    d = design.design_params(soil, stage["id"], levels, sim).as_dict()
    if rule == "none":  # undo build_materials' gamma s^(2/5)
        d["soil_soil_surface_energy"] /= s ** 0.4
        d["soil_steel_surface_energy"] /= s ** 0.4
    params = DemParams.from_mapping(d, "<stiffness_rule>")
    t0 = time.perf_counter()
    res = get(sim.scenario).run(dict(sim.setup, stiffness_scale=s, **setup_set), params,
                                preset=sim.preset,
                                seed=seed, threads=1, source=str(soil.path))
    r = res.responses
    value = float(r.get(sim.measure, math.nan))
    return dict(utc=time.strftime("%Y-%m-%d %H:%M", time.gmtime()), soil=soil_name,
                stage=stage["id"], response=rid,
                levels=" ".join(f"{k}={v:g}" for k, v in levels.items()),
                set=" ".join(f"{k}={v}" for k, v in setup_set.items()), scale=s,
                G_Pa=f"{d['soil_shear_modulus'] * s:.4g}", rule=rule,
                gamma_soil_soil=round(d["soil_soil_surface_energy"], 6), seed=seed,
                particles=res.n_particles, steps=res.steps,
                dt_fraction=round(float(res.setup.get("dt_fraction", math.nan)), 4),
                wall_s=round(time.perf_counter() - t0, 1), measure=sim.measure,
                value="" if not math.isfinite(value) else round(value, 3),
                n_retained=r.get("n_retained", ""), n_on_plate=r.get("n_on_plate", ""),
                peak_overlap=round(float(r.get("peak_overlap", math.nan)), 4),
                settled=r.get("settled", ""),
                measure_errors=str(r.get("measure_errors", ""))[:240].replace("|", "/"))


def _key(r):
    return (r["soil"], r["levels"], r["set"], float(r["scale"]), r["rule"], int(r["seed"]))


def report(rows, md_path, argv):
    md = ["# Stiffness scaling of the surface energy: does the heap keep its response?", "",
          f"Machine: {platform.machine()}, {os.cpu_count()} logical CPUs.  Last command: "
          f"`python benchmarks/stiffness_rule.py {' '.join(argv)}`.  Rows: `stiffness_rule.csv`.",
          "", "Per case (soil, design point, shear-modulus factor s, rule): the runs, how many "
          "gave a value (a funnel load with more than the setup's max_retained of its spheres left "
          "in the funnel gives none), the mean and "
          "sample SD of the values, the share of the spheres left in the funnel.", "",
          "| soil | levels | setup set | s | G (Pa) | rule | runs | with a value | mean | SD | retained % (min-max) |",
          "|---|---|---|---:|---:|---|---:|---:|---:|---:|---:|"]
    cases = {}
    for r in rows:
        cases.setdefault((r["soil"], r["levels"], r["set"], float(r["scale"]), r["rule"]), []).append(r)
    for (soil, lv, st, s, rule), rs in sorted(cases.items(),
                                             key=lambda kv: (kv[0][0], kv[0][1], kv[0][2], -kv[0][3], kv[0][4])):
        v = np.array([float(r["value"]) for r in rs if r["value"] not in ("", None)])
        ret = [100.0 * float(r["n_retained"]) / float(r["particles"]) for r in rs
               if r["n_retained"] not in ("", None)]
        md.append(f"| {soil} | {lv} | {st} | {s:g} | {rs[0]['G_Pa']} | {rule} | {len(rs)} | {len(v)} | "
                  + (f"{v.mean():.1f}" if len(v) else "") + " | "
                  + (f"{v.std(ddof=1):.1f}" if len(v) > 1 else "") + " | "
                  + (f"{min(ret):.1f}-{max(ret):.1f}" if ret else "") + " |")
    md += ["", "Runs:", "", *runs_table(rows, FIELDS)]
    write_page(md_path, md)


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--soil", default="black-soil")
    ap.add_argument("--levels", default="", help="factor overrides, e.g. x1=0.4,x2=0.3")
    ap.add_argument("--scales", default="1,0.005", help="shear-modulus factors s")
    ap.add_argument("--rules", default="paper,none")
    ap.add_argument("--seeds", default="0-3")
    ap.add_argument("--set", default="", help="setup overrides, e.g. radius=0.0015625,n_particles=8000")
    ap.add_argument("--jobs", type=int, default=2, help="runs in parallel (one thread each)")
    ap.add_argument("--report-only", action="store_true")
    ap.add_argument("--out", default=str(HERE / "results"))
    args = ap.parse_args(argv)
    overrides = {}
    for kv in filter(None, args.levels.split(",")):
        k, v = kv.split("=")
        overrides[k.strip()] = float(v)
    setup_set = {}
    for kv in filter(None, args.set.split(",")):
        k, v = kv.split("=")
        v = v.strip()
        setup_set[k.strip()] = (v.lower() == "true" if v.lower() in ("true", "false")
                                else int(v) if v.isdigit() else float(v))
    if not args.report_only:  # levels checked here, before any worker starts
        from soilcal.config.load import load_soil

        soil = load_soil(ROOT / "config" / "soils" / f"{args.soil}.yaml", ROOT / "resources")
        stage = soil.data["stages"][0]
        unknown = sorted(set(overrides) - set(stage["factors"]))
        if unknown:
            raise SystemExit(f"--levels: expected factors of stage {stage['id']} "
                             f"({', '.join(stage['factors'])}), got {', '.join(unknown)}")
        centre_levels(stage, overrides)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    csv_path, md_path = out / "stiffness_rule.csv", out / "stiffness_rule.md"
    rows = read_rows(csv_path, FIELDS)
    if not args.report_only:
        jobs = []
        for s in (float(v) for v in args.scales.split(",")):
            for rule in args.rules.split(","):
                if s == 1.0 and rule != "paper":
                    continue  # the rules coincide at the printed modulus
                for seed in seed_list(args.seeds):
                    jobs.append((args.soil, overrides, setup_set, s, rule, seed))
        rev = commit()
        with ProcessPoolExecutor(max_workers=max(1, args.jobs)) as ex:
            for new in ex.map(one, jobs):
                new["commit"] = rev
                print(json.dumps({k: new[k] for k in ("levels", "scale", "rule", "seed", "value",
                                                      "n_retained", "wall_s")}), flush=True)
                rows = [r for r in rows if _key(r) != _key(new)] + [new]
                rows.sort(key=lambda r: (r["soil"], r["levels"], r["set"], -float(r["scale"]),
                                         r["rule"], int(r["seed"])))
                write_rows(csv_path, rows, FIELDS)
    report(rows, md_path, argv)


if __name__ == "__main__":
    main()
