"""How the Box-Behnken centre is chosen on a DEM path: the papers' rule against the trend.

For each soil, the DEM calibration (`snakemake --cores N` on a fresh copy of the workflow,
that soil alone) runs twice, once with ``simulation.path.choose: fitted`` (the trend through
the path's runs, the default) and once with ``closest`` (each step's own run, the papers'
rule); everything else (engine, preset, seeds) is the same, so the screening and the path
runs are identical and only the centre of the Box-Behnken design and what follows can
differ.  Per soil, rule and verified response: the chosen path step, the trend's residual
scatter, the verification mean, SD and error, and the surface's prediction at the calibrated
set.  Rows go to ``benchmarks/results/path_choice.csv``; ``path_choice.md`` is the page.

    python benchmarks/path_choice.py --soils cinnamon-soil xinjiang-vineyard
    python benchmarks/path_choice.py --collect      # rebuild the rows from finished work dirs
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path

import pandas as pd
import yaml
from _report import commit, read_rows, write_page, write_rows
from calibration import copy_workflow, snakemake

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
OUT = HERE / "results"
RULES = ("fitted", "closest")
FIELDS = ["utc", "commit", "soil", "rule", "elapsed_s", "rc", "stage", "case", "round", "response",
          "chosen_step", "trend_degree", "trend_residual_sd", "target", "simulated_mean", "simulated_sd",
          "n", "relative_error_percent", "within_2_percent", "predicted_minus_target", "note"]


def prepare(workdir: Path, soil: str, rule: str) -> Path:
    copy_workflow(workdir, [soil])
    p = workdir / "config/soils" / f"{soil}.yaml"
    data = yaml.safe_load(p.read_text())
    sim = data.setdefault("simulation", {})
    sim["path"] = {**(sim.get("path") or {}), "choose": rule}
    p.write_text(yaml.safe_dump(data, sort_keys=False, allow_unicode=True))
    return workdir


def collect(workdir: Path, soil: str, rule: str, utc: str, rev: str, elapsed: float | None, rc: int | None) -> list[dict]:
    res = workdir / "results" / soil / "dem"
    ver = res / "verification.csv"
    if not ver.is_file():
        return [{"utc": utc, "commit": rev, "soil": soil, "rule": rule, "elapsed_s": elapsed, "rc": rc,
                 "note": f"no verification.csv under {res}"}]
    chosen, degree, sd = {}, {}, {}
    for sj in res.glob("*/stage.json"):
        st = json.loads(sj.read_text())
        der = st.get("derivation") or {}
        if der.get("kind") == "path":
            chosen[st["id"]] = der.get("chosen_step")
            trends = der.get("trend") or {}
            degree[st["id"]] = ";".join(f"{r}:{t.get('degree')}" for r, t in trends.items())
            sd[st["id"]] = ";".join(f"{r}:{t.get('residual_sd'):.2f}" for r, t in trends.items()
                                    if t.get("residual_sd") is not None)
            if not trends:  # the papers' rule: the trend is not fitted, recompute it for the table
                sd[st["id"]] = _trend_sd(res, st)
    rows = []
    for r in pd.read_csv(ver).to_dict("records"):
        rows.append({"utc": utc, "commit": rev, "soil": soil, "rule": rule, "elapsed_s": elapsed, "rc": rc,
                     "stage": r["stage"], "case": r["case"], "round": r["round"], "response": r["response"],
                     "chosen_step": chosen.get(r["stage"]), "trend_degree": degree.get(r["stage"], ""),
                     "trend_residual_sd": sd.get(r["stage"], ""), "target": r["target"],
                     "simulated_mean": r["simulated_mean"], "simulated_sd": r["simulated_sd"], "n": r["n"],
                     "relative_error_percent": r["relative_error_percent"],
                     "within_2_percent": r["within_2_percent"],
                     "predicted_minus_target": r["predicted_minus_target"],
                     "note": r.get("note") if isinstance(r.get("note"), str) else ""})
    return rows


def _trend_sd(res: Path, bbd_stage: dict) -> str:
    from soilcal.doe.steepest import path_trend

    path_id = (bbd_stage.get("derivation") or {}).get("from_stage")
    tab = res / str(path_id) / "responses.csv"
    if not tab.is_file():
        return ""
    df = pd.read_csv(tab).sort_values("step")
    out = []
    for r in (json.loads((res / str(path_id) / "stage.json").read_text()).get("path_targets") or {}):
        if r in df.columns:
            t = path_trend(df["step"].to_numpy(float), df[r].to_numpy(float))
            out.append(f"{r}:{t['residual_sd']:.2f}")
    return ";".join(out)


def page(rows: list[dict]) -> list[str]:
    df = pd.DataFrame(rows)
    lines = ["# The Box-Behnken centre on a DEM path: the trend through the runs against each run",
             "",
             f"Machine: {platform.machine()}, Python {platform.python_version()}.  Command: "
             "`python benchmarks/path_choice.py` (rows: `path_choice.csv`, utc and commit per row).  "
             "Each soil's DEM calibration from an empty `results/` under `choose: fitted` and under "
             "`choose: closest`; the same engine, preset and seeds.", "",
             "| utc | commit | soil | rule | elapsed min | stage | case | round | response | path step | trend SD | "
             "target | mean | SD | n | error % | surface - target |",
             "|---|---|---|---|---:|---|---|---:|---|---:|---|---:|---:|---:|---:|---:|---:|"]

    def f(x, fmt):
        try:
            return format(float(x), fmt) if pd.notna(x) and x != "" else ""
        except (TypeError, ValueError):
            return str(x)

    for r in df.to_dict("records"):
        mins = float(r["elapsed_s"]) / 60 if r.get("elapsed_s") not in (None, "") else None
        lines.append(f"| {r['utc']} | {r['commit']} | {r['soil']} | {r['rule']} | {f(mins, '.1f') if mins else ''} "
                     f"| {r.get('stage', '')} | {r.get('case', '')} | {r.get('round', '')} | {r.get('response', '')} "
                     f"| {r.get('chosen_step', '')} "
                     f"| {r.get('trend_residual_sd', '')} | {f(r.get('target'), '.2f')} | {f(r.get('simulated_mean'), '.2f')} "
                     f"| {f(r.get('simulated_sd'), '.2f')} | {r.get('n', '')} | {f(r.get('relative_error_percent'), '.1f')} "
                     f"| {f(r.get('predicted_minus_target'), '.2f')} |")
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--soils", nargs="*", default=["cinnamon-soil", "xinjiang-vineyard"])
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--workdir", default="/tmp/soilcal-path-choice")
    ap.add_argument("--collect", action="store_true", help="only read finished work dirs")
    args = ap.parse_args(argv)
    OUT.mkdir(exist_ok=True)
    rev = commit()
    csv = OUT / "path_choice.csv"
    rows = read_rows(csv, FIELDS)
    for soil in args.soils:
        for rule in RULES:
            wd = Path(args.workdir) / f"{soil}-{rule}"
            utc = time.strftime("%Y-%m-%d %H:%M", time.gmtime())
            elapsed = rc = None
            if not args.collect:
                prepare(wd, soil, rule)
                rc, elapsed, log, _ = snakemake(wd, args.cores)
                (wd / "snakemake.out").write_text(log)
            new = collect(wd, soil, rule, utc, rev, elapsed, rc)
            rows = [r for r in rows if not (r["soil"] == soil and r["rule"] == rule and r["commit"] == rev)] + new
            write_rows(csv, rows, FIELDS)
            print(f"{soil} {rule}: {len(new)} rows", file=sys.stderr)
    write_page(OUT / "path_choice.md", page(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
