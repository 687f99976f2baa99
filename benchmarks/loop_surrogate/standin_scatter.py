"""The whole loop on the stand-in blade with the DEM plate's seed scatter: how often it names
the hidden effect, and how often one that is not there.

``benchmarks/loop.py``'s stand-in runs scatter by 1 % per run, each seed's deviation shared by
every parameter value (common random numbers), far quieter than the DEM's quick plate.  Here
each run of the stand-in (:mod:`soilcal.loop.standin`, 18 soil-bin conditions of
:func:`soilcal.loop.standin.grid` with moisture, three measured repeats with 2 % noise, three
seeds per design point) is multiplied by exp(s z), z drawn anew for every condition, seed and
parameter set (a bed settled anew at each density or friction, as the DEM's are), s = 0.14
(``uniform``) or rising with the working depth from 0.10 at 0.05 m to 0.28 at 0.15 m
(``depth``: the DEM plate's SD of log force from 20 to 40 mm, ``benchmarks/results/loop.md``).
Cases: no hidden effect, depth_compaction g 0.6, rate_friction beta 0.4; campaigns 0..N-1; the
loop's surrogates (``loop.surrogate``): ``pooled`` (its default: one shape per measured
quantity through the effect's dose where it passes its lack-of-fit test) and ``rows`` (one
surrogate per row), on the same campaigns.  Column ``surrogate_used``: the hidden effect's
surrogate as the loop's files name it (``rate_friction``'s where nothing is hidden).

    python benchmarks/loop_surrogate/standin_scatter.py [CAMPAIGNS] [SURROGATES]   # default 40 pooled,rows

Writes ``benchmarks/results/loop_surrogate/standin_scatter.{csv,md}``.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from _report import run_header, write_rows_page  # noqa: E402

OUT = HERE.parent / "results" / "loop_surrogate"
REF = {"tool_speed": 1.75, "working_depth": 0.1, "moisture_content": 16.0}
CASES = {"none": {}, "depth_compaction": {"depth_compaction": {"g": 0.6}},
         "rate_friction": {"rate_friction": {"beta": 0.4}}}


def simulator(scatter: str):
    from soilcal.loop import standin as S

    def run(cond, params, seed):
        out = S.simulate(cond, params, seed)
        d = float(cond.quantities["working_depth"])
        s = 0.14 if scatter == "uniform" else 0.10 + 0.18 * (d - 0.05) / 0.10
        h = int(hashlib.sha1(json.dumps(params, sort_keys=True).encode()).hexdigest()[:8], 16)
        z = np.random.default_rng([int(seed), int(cond.row), h]).standard_normal(len(out))
        return {k: v * float(np.exp(s * e)) for (k, v), e in zip(out.items(), z)}

    return run


def main(argv=None) -> None:
    from soilcal.loop import core
    from soilcal.loop import standin as S
    from soilcal.loop import synthesize as sy

    args = sys.argv[1:] if argv is None else argv
    n = int(args[0]) if args else 40
    kinds = (args[1] if len(args) > 1 else "pooled,rows").split(",")
    rows = []
    t0 = time.perf_counter()
    for kind, scatter in itertools.product(kinds, ("uniform", "depth")):
        sim = simulator(scatter)
        for case, hidden in CASES.items():
            for c in range(n):
                conds = S.conditions(S.grid(c, 18, moisture=True), measures=("horizontal_force_N",))
                table = sy.synthesize(conds, S.base_params, sim, hidden, REF, {}, noise=0.02, seed=c + 10)
                out = core.run_inprocess("bin", sy.with_measured(conds, table), S.base_params, sim,
                                         core.Settings(reference=REF, bootstrap=0, surrogate=kind))
                truth = next((v for th in hidden.values() for v in th.values()), None)
                theta = next(iter(out.theta.values()), None) if out.chosen == list(hidden) else None
                ed = (out.effect_data or {}).get(next(iter(hidden), "rate_friction"))
                rows.append({"surrogate": kind, "surrogate_used": ed.surrogate.kind() if ed is not None else "",
                             "scatter": scatter, "case": case, "campaign": c, "chosen": "+".join(out.chosen),
                             "correct": out.chosen == list(hidden),
                             "false_attribution": bool(set(out.chosen) - set(hidden)),
                             "parameter_error_percent": (100 * abs(theta - truth) / truth
                                                         if theta is not None and truth else np.nan),
                             "verdict": out.verdict})
    wall = time.perf_counter() - t0
    df = pd.DataFrame(rows)
    OUT.mkdir(parents=True, exist_ok=True)
    df.to_csv(OUT / "standin_scatter.csv", index=False)
    lines = ["# The loop on the stand-in blade with the DEM plate's seed scatter", "",
             run_header("loop_surrogate/standin_scatter.py", [n, ",".join(kinds)], f"{wall:.0f} s")
             + "; the campaigns and the scatter are in the script's docstring.  Shape shared: the campaigns whose "
             "hidden effect (rate_friction where none) was fitted through one shape shared by the rows.", "",
             "| loop.surrogate | scatter | hidden | campaigns | correct | false attribution | median parameter error, % "
             "| shape shared |", "|---|---|---|---:|---:|---:|---:|---:|"]
    for (kind, scatter, case), g in df.groupby(["surrogate", "scatter", "case"], sort=False):
        med = g["parameter_error_percent"].median()
        shared = int(g["surrogate_used"].astype(str).str.startswith("pooled through the dose").sum())
        lines.append(f"| {kind} | {scatter} | {case} | {len(g)} | {int(g['correct'].sum())} | "
                     f"{int(g['false_attribution'].sum())} | {'' if np.isnan(med) else f'{med:.1f}'} | {shared} |")
    write_rows_page(OUT / "standin_scatter.md", lines, "standin_scatter.csv")


if __name__ == "__main__":
    main()
