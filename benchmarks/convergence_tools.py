"""Convergence of the tool scenarios: response vs particle size (count), stiffness scaling, seed.

For each tool scenario (furrow opener, bulldozing plate, rotary tiller) the quick preset is
run at its own settings and with one factor changed at a time:

* particle radius x ``radius_factors`` (particle count ~ factor^-3),
* shear-modulus scale x ``stiffness_factors`` relative to the quick preset's scale (the JKR
  surface energy follows gamma s^(2/5), soilcal.dem.scenarios.base.build_materials),
* seed in ``seeds`` (bin packing and radii).

Each run writes one row (scenario, factor, value, seed, particle count, steps, wall time,
responses) to ``benchmarks/results/convergence/convergence_tools.csv``; the figure
``convergence_tools.png`` plots each scenario's responses against the three factors and
``convergence_tools.md`` tabulates the rows, with each response's spread over the seeds
beside its range over the particle sizes and over the stiffness scales, and the particle
count the ``paper`` preset's bin would hold (none of them is run here: 1e5-1e8 spheres).

    python benchmarks/convergence_tools.py --level reduced   # a few minutes on 2 cores
    python benchmarks/convergence_tools.py --level full      # more levels and seeds
    python benchmarks/convergence_tools.py --plot-only       # figure and page from the CSV
    python benchmarks/convergence_tools.py --setups          # every plate and speed once
"""

from __future__ import annotations

import argparse
import csv
import os
import sys
import tempfile
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from _report import commit, seed_and_ranges, write_page  # noqa: E402

from soilcal.dem.scenarios import bulldozing, furrow, rotary  # noqa: E402

OUT = Path(__file__).resolve().parent / "results" / "convergence"

CASES = {
    "furrow": (furrow, "yangtze-opener", ("traction_N", "area_difference_dm2")),
    "bulldozing": (bulldozing, "plate-line", ("horizontal_force_N", "vertical_force_N")),
    "rotary": (rotary, "rpm-250", ("power_kW", "flatness_mm")),
}
LEVELS = {
    "reduced": dict(radius=(1.0, 0.85), stiffness=(1.0, 3.0), seeds=(0, 1)),
    "full": dict(radius=(1.25, 1.0, 0.85, 0.7), stiffness=(0.3, 1.0, 3.0, 10.0),
                 seeds=(0, 1, 2, 3, 4)),
}


def _run(mod, setup_name, overrides, seed, threads):
    setup = dict(mod.setups()[setup_name])
    setup.update(overrides)
    res = mod.run(setup, mod.paper_params(), "quick", seed=seed, threads=threads)
    return res


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--level", choices=sorted(LEVELS), default="reduced")
    ap.add_argument("--scenarios", default=",".join(CASES))
    ap.add_argument("--out", default=str(OUT))
    ap.add_argument("--plot-only", action="store_true",
                    help="redraw the figure and the page from the existing CSV")
    ap.add_argument("--threads", type=int, default=1,
                    help="numba threads (1: a shared machine's second core stays free)")
    ap.add_argument("--setups", action="store_true",
                    help="run every named bulldozing and rotary setup once (seed 0) into "
                         "convergence_tools_setups.csv instead")
    args = ap.parse_args(argv)
    lev = LEVELS[args.level]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    os.environ.setdefault("SOILCAL_SCENARIO_CACHE", tempfile.mkdtemp(prefix="soilcal-bins-"))
    path = out / "convergence_tools.csv"
    todo = args.scenarios.split(",")
    rows = []
    if path.exists():  # keep the rows of scenarios not rerun now
        with open(path, newline="") as fh:
            for r in csv.DictReader(fh):
                if r["scenario"] not in todo:
                    rows.append({k: _num(k, v) for k, v in r.items()})
    if args.setups:
        return every_setup(out / "convergence_tools_setups.csv", args.threads)
    if args.plot_only:
        with open(path, newline="") as fh:
            rows = [{k: _num(k, v) for k, v in r.items()} for r in csv.DictReader(fh)]
        plot(rows, out / "convergence_tools.png")
        table(rows, out / "convergence_tools.md", None)
        return 0
    rev = commit()  # the code this process runs
    for name in todo:
        mod, setup_name, keys = CASES[name]
        base = mod.PRESET_SETTINGS["quick"]
        plan = [("base", 1.0, {}, 0)]
        plan += [("radius", f, {"particle_radius": base["particle_radius"] * f}, 0)
                 for f in lev["radius"] if f != 1.0]
        plan += [("stiffness", f, {"stiffness_scale": base["stiffness_scale"] * f}, 0)
                 for f in lev["stiffness"] if f != 1.0]
        plan += [("seed", s, {}, s) for s in lev["seeds"] if s != 0]
        for factor, value, ov, seed in plan:
            t0 = time.perf_counter()
            cpu0 = time.process_time()
            try:
                res = _run(mod, setup_name, ov, seed, args.threads)
                resp = {k: res.responses[k] for k in keys}
                n, steps, err = res.n_particles, res.steps, ""
            except Exception as exc:  # record a failed point (e.g. blow-up) and go on
                resp = {k: float("nan") for k in keys}
                n, steps, err = 0, 0, f"{type(exc).__name__}: {exc}"
            row = dict(scenario=name, setup=setup_name, factor=factor, value=value, seed=seed,
                       particle_radius=ov.get("particle_radius", base["particle_radius"]),
                       stiffness_scale=ov.get("stiffness_scale", base["stiffness_scale"]),
                       n_particles=n, steps=steps, threads=args.threads,
                       wall_s=round(time.perf_counter() - t0, 2),
                       cpu_s=round(time.process_time() - cpu0, 2), error=err,
                       utc=time.strftime("%Y-%m-%d %H:%M", time.gmtime()), commit=rev)
            row.update({f"r:{k}": v for k, v in resp.items()})
            rows.append(row)
            print({k: row[k] for k in ("scenario", "factor", "value", "n_particles", "wall_s")},
                  resp, err, flush=True)
            _write(path, rows)
    plot(rows, out / "convergence_tools.png")
    table(rows, out / "convergence_tools.md",
          "python benchmarks/convergence_tools.py "
          + " ".join(sys.argv[1:] if argv is None else argv))
    print(path)
    return 0


def _spread(v):
    v = np.asarray([x for x in v if isinstance(x, (int, float)) and np.isfinite(x)], float)
    return v


def table(rows, path, cmd):
    """The results page: every run, then per scenario and response the mean and sample SD
    over the seeds beside the range (max - min, base run included) over the particle sizes
    and over the stiffness scales, each also as a multiple of the seed SD."""
    lines = ["# Convergence of the tool scenarios (quick preset, one factor at a time)", ""]
    if cmd:
        ended = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
        lines += [f"Last command: `{cmd}`, ended {ended}"
                  f"; load_avg_1min at the end {os.getloadavg()[0]:.2f}.  Rows: "
                  "`convergence_tools.csv` (utc and commit per row), figure "
                  "`convergence_tools.png`.", ""]
    elif path.exists():  # a page redrawn from the CSV keeps the line of the last run
        lines += [x for x in path.read_text().splitlines()[2:3] if x.startswith("Last command:")]
        lines += [""] if len(lines) > 2 else []
    lines += ["| scenario | factor | value | seed | radius mm | G scale | particles | steps | "
              "threads | wall s | response 1 | response 2 | error |",
              "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    for r in rows:
        keys = CASES[r["scenario"]][2]
        vals = []
        for k in keys:
            v = r.get(f"r:{k}", "")
            vals.append(f"{k} {v:.4g}" if isinstance(v, float) and np.isfinite(v) else "")
        lines.append(f"| {r['scenario']} | {r['factor']} | {r['value']} | {r['seed']} | "
                     f"{1000 * float(r['particle_radius']):.3g} | "
                     f"{float(r['stiffness_scale']):.3g} | {r['n_particles']} | {r['steps']} | "
                     f"{r.get('threads', '')} | {r['wall_s']} | "
                     f"{vals[0]} | {vals[1]} | {str(r.get('error', ''))[:80]} |")
    lines += ["", "Spread over seeds against the range over each factor (base run included in "
              "every group; ratio = range / seed SD).  The seed alone gives an expected range "
              "of 1.13, 1.69, 2.06 and 2.33 SD over 2, 3, 4 and 5 levels (normal scatter), so "
              "a ratio near those does not tell the factor from the seed:", "",
              "| scenario | response | seeds | mean | seed SD | radius range (ratio) | "
              "stiffness range (ratio) |", "|---|---|---:|---:|---:|---:|---:|"]
    for name in dict.fromkeys(r["scenario"] for r in rows):
        rs = [r for r in rows if r["scenario"] == name and not r.get("error")]
        base = [r for r in rs if r["factor"] == "base"]
        for k in CASES[name][2]:
            seed = _spread([r[f"r:{k}"] for r in base + [r for r in rs if r["factor"] == "seed"]])
            if seed.size < 2:
                continue
            groups = [_spread([r[f"r:{k}"] for r in base + [r for r in rs if r["factor"] == fac]])
                      for fac in ("radius", "stiffness")]
            lines.append("| " + " | ".join([name, k, *seed_and_ranges(seed, groups, ".4g")]) + " |")
    lines += paper_lines(rows)
    write_page(path, lines)


def bed(name, preset):
    """The BinSpec of a scenario's preset (no run)."""
    mod, setup_name, _ = CASES[name]
    return mod._bin(mod._settings(dict(mod.setups()[setup_name]), preset))


def paper_lines(rows) -> list[str]:
    """Quick against paper preset: the paper bed's particle count estimated from the quick
    run's count at the same packing (count x bin volume ratio / particle volume ratio)."""
    lines = ["", "Quick against paper preset (no paper run: the count is the quick base "
             "run's, scaled by the ratio of bin volumes over the ratio of mean particle "
             "volumes, i.e. at the quick bed's packing):", "",
             "| scenario | quick bin m | quick radii mm | quick N | paper bin m | "
             "paper radii mm | paper N (about) | paper / quick |",
             "|---|---|---|---:|---|---|---:|---:|"]
    for name in dict.fromkeys(r["scenario"] for r in rows):
        base = [r for r in rows if r["scenario"] == name and r["factor"] == "base"
                and not r.get("error")]
        if not base:
            continue
        nq = int(base[0]["n_particles"])
        sq, sp = bed(name, "quick"), bed(name, "paper")
        vq, vp = (b.length * b.width * b.height for b in (sq, sp))
        npp = nq * (vp / vq) / (sp.dist.mean_volume() / sq.dist.mean_volume())
        lines.append(
            f"| {name} | {sq.length:.3g} x {sq.width:.3g} x {sq.height:.3g} | "
            f"{1e3 * sq.r_min:.3g}-{1e3 * sq.r_max:.3g} | {nq} | "
            f"{sp.length:.3g} x {sp.width:.3g} x {sp.height:.3g} | "
            f"{1e3 * sp.r_min:.3g}-{1e3 * sp.r_max:.3g} | {npp:.3g} | {npp / nq:.3g} |")
    return lines


def every_setup(path, threads):
    """Each named setup of the plate and the rotor scenarios at the quick preset, seed 0,
    the paper's parameters; one row each with every numeric response."""
    rev = commit()
    rows = []
    for mod in (bulldozing, rotary):
        for name, setup in mod.setups().items():
            t0 = time.perf_counter()
            res = mod.run(dict(setup), mod.paper_params(), "quick", seed=0, threads=threads)
            row = dict(utc=time.strftime("%Y-%m-%d %H:%M", time.gmtime()), commit=rev,
                       scenario=mod.NAME, setup=name, n_particles=res.n_particles,
                       steps=res.steps, threads=threads,
                       wall_s=round(time.perf_counter() - t0, 2))
            row.update({f"r:{k}": v for k, v in res.responses.items()
                        if isinstance(v, (int, float))})
            rows.append(row)
            print({k: row[k] for k in ("scenario", "setup", "wall_s")}, flush=True)
            _write(path, rows)
    print(path)
    return 0


def _num(key, text):
    if key in ("utc", "commit", "error", "scenario", "setup", "factor"):
        return text
    try:
        return int(text)
    except ValueError:
        try:
            return float(text)
        except ValueError:
            return text


def _write(path, rows):
    fields = []
    for r in rows:
        fields += [k for k in r if k not in fields]
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=fields)
        w.writeheader()
        w.writerows(rows)


def plot(rows, path):
    """One row of panels per scenario: its two responses (left and right axes) against
    the particle count, the shear-modulus scale and the seed, the base run in each panel;
    the band is the first response's mean +- SD over the seeds."""
    names = list(dict.fromkeys(r["scenario"] for r in rows))
    fig, axes = plt.subplots(len(names), 3, figsize=(12, 3.2 * len(names)), squeeze=False)
    for i, name in enumerate(names):
        rs = [r for r in rows if r["scenario"] == name and not r.get("error")]
        keys = CASES[name][2]
        base = [r for r in rs if r["factor"] == "base"]
        seed = _spread([r[f"r:{keys[0]}"] for r in base + [r for r in rs if r["factor"] == "seed"]])
        for j, (factor, xkey, label) in enumerate((
                ("radius", "n_particles", "particles"),
                ("stiffness", "stiffness_scale", "shear-modulus scale"),
                ("seed", "seed", "seed"))):
            ax = axes[i, j]
            if seed.size > 1:  # the first response's seed scatter, mean +- 1 SD
                ax.axhspan(seed.mean() - seed.std(ddof=1), seed.mean() + seed.std(ddof=1),
                           color="C0", alpha=0.12, zorder=0)
            pts = sorted(base + [r for r in rs if r["factor"] == factor], key=lambda r: r[xkey])
            xs = [r[xkey] for r in pts]
            ax.plot(xs, [r[f"r:{keys[0]}"] for r in pts], "o-", color="C0")
            ax.set_ylabel(keys[0], color="C0", fontsize=8)
            ax2 = ax.twinx()
            ax2.plot(xs, [r[f"r:{keys[1]}"] for r in pts], "s--", color="C1")
            ax2.set_ylabel(keys[1], color="C1", fontsize=8)
            ax.set_xlabel(label)
            if factor == "stiffness":
                ax.set_xscale("log")
            ax.set_title(f"{name}: vs {label}", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    raise SystemExit(main())
