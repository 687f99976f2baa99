"""``soilcal loop synthesize`` and ``soilcal loop run``: the measured-data loop from the command line.

``synthesize`` writes a copy of a soil's measured table whose measured values come from
soilcal's DEM with hidden effects switched on (:mod:`soilcal.loop.synthesize`): a table with
an effect nobody declared, to prove the loop on.  ``run`` runs the whole loop of a soil in
one process on the DEM (what the workflow does job by job) and writes the loop's tables.

Both simulate each condition at its own parameters: the soil's ``simulation.params``, the
measurement's ``params`` and its ``param`` covariates (:class:`~soilcal.config.measurements.Condition`),
the DEM defaults for the rest; ``--param NAME=VALUE`` sets a parameter for every condition
(a calibrated set).  The workflow instead starts from the calibrated optimum of the stage the
measurement names.
"""

from __future__ import annotations

import math
from pathlib import Path


def _kv(text: str, what: str) -> tuple[str, dict]:
    """``name:k=v,k=v`` -> (name, {k: float(v)})."""
    from soilcal.errors import InputError

    name, _, rest = text.partition(":")
    out = {}
    for part in filter(None, rest.split(",")):
        k, eq, v = part.partition("=")
        try:
            out[k.strip()] = float(v)
        except ValueError:
            raise InputError("<command line>", what, "name:key=number[,key=number]", text) from None
        if not eq:
            raise InputError("<command line>", what, "name:key=number[,key=number]", text)
    return name.strip(), out


def dem_simulator(threads=None):
    """``simulate(cond, params, seed)`` on soilcal's DEM: one run of the condition's scenario
    and setup at its preset; measure -> value (NaN where the run failed)."""
    from soilcal.chain.sources import simulate

    def run(cond, params, seed):
        spec = {"soil": "loop", "stage": cond.stage, "run": int(cond.row), "levels": {}, "seed": int(seed),
                "replicates": 1, "params": dict(params),
                "responses": {r["measure"]: {"scenario": cond.scenario, "setup": dict(cond.setup),
                                             "measure": r["measure"], "preset": cond.preset} for r in cond.responses}}
        df = simulate(spec, threads=threads)
        return {r["measure"]: (float(r["value"]) if r["status"] == "ok" else math.nan) for r in df.to_dict("records")}

    return run


def condition_params(overrides: dict):
    from soilcal.dem.scenarios.base import DemParams

    def base(cond):
        return DemParams.from_mapping({**cond.params, **overrides}, f"{cond.measurement} row {cond.row}").as_dict()

    return base


def _params(args) -> dict:
    return dict(_kv("p:" + ",".join(args.param or []), "--param")[1]) if args.param else {}


def _conditions(args):
    from soilcal.config.load import load_soil
    from soilcal.config.measurements import conditions
    from soilcal.errors import InputError

    soil = load_soil(args.soil, args.resources)
    conds = conditions(soil)
    if getattr(args, "measurement", None):
        known = sorted({c.measurement for c in conds})
        conds = [c for c in conds if c.measurement == args.measurement]
        if not conds:
            raise InputError(args.soil, "measurements", "the id of a measured table (" + ", ".join(known) + ")",
                             args.measurement)
    return soil, conds


def _synthesize(args) -> int:
    import numpy as np
    import pandas as pd

    from soilcal.atomic import write_text
    from soilcal.config.measurements import measurements_dir
    from soilcal.loop import synthesize as sy

    soil, conds = _conditions(args)
    hidden = dict(_kv(e, "--effect") for e in args.effect or [])
    dist = dict(_kv(d, "--disturbance") for d in args.disturbance or [])
    reference = dict(_kv("r:" + ",".join(args.reference), "--reference")[1]) if args.reference else {}
    table = sy.synthesize(conds, condition_params(_params(args)), dem_simulator(args.threads), hidden, reference, dist,
                          noise=args.noise, seed=args.seed, seeds=tuple(range(1000, 1000 + args.repeats)))
    entry = soil.data["measurements"][args.measurement]
    src = measurements_dir(soil.resources_root, soil.name) / entry["table"]
    df = pd.read_csv(src)
    for j, r in enumerate(entry["responses"]):
        t = table[table["measure"] == r["measure"]].sort_values("row")
        if r.get("value") is None:
            continue
        df[r["value"]] = np.round(t["value"].to_numpy(float), 6)
        if r.get("sd"):
            df[r["sd"]] = np.round(t["sd"].to_numpy(float), 6)
        if r.get("n"):
            df[r["n"]] = t["n"].to_numpy(int)
    write_text(args.out, df.to_csv(index=False))
    truth = Path(args.out).with_suffix(".truth.csv")
    write_text(truth, table.to_csv(index=False))
    print(f"{len(df)} rows -> {args.out} (truth: {truth}; hidden {hidden or 'none'}, disturbances {dist or 'none'}, "
          f"seed {args.seed})")
    return 0


def _run(args) -> int:
    from dataclasses import replace

    from soilcal.chain.files import write_csv
    from soilcal.loop import core

    soil, conds = _conditions(args)
    settings = core.settings_from(soil.data, soil.path)
    if args.reference:
        settings = replace(settings, reference={**settings.reference,
                                                **_kv("r:" + ",".join(args.reference), "--reference")[1]})
    out = core.run_inprocess(soil.name, conds, condition_params(_params(args)), dem_simulator(args.threads), settings,
                             seeds=tuple(range(args.seed, args.seed + args.sim_seeds)))
    d = Path(args.out)
    for name, df in (("residuals", out.residuals), ("diagnosis", out.diagnosis), ("selection", out.selection),
                     ("predictions", out.predictions), ("loop_summary", out.summary)):
        write_csv(df, d / f"{name}.csv")
    print(out.verdict)
    return 0


def register(sub) -> None:
    p = sub.add_parser("loop", help="the measured-data loop: synthesize a measured table, run the loop")
    cmds = p.add_subparsers(dest="loop_cmd", required=True)
    s = cmds.add_parser("synthesize", help="a measured table from the DEM with hidden effects")
    s.add_argument("soil", help="soil YAML file")
    s.add_argument("--measurement", required=True, help="id of the measured table (measurements block)")
    s.add_argument("--effect", action="append", help="hidden effect, e.g. rate_friction:beta=0.2 (repeatable)")
    s.add_argument("--disturbance", action="append",
                   help="periodic:amplitude=0.1,wavelength=7 | stones:fraction=0.3 | day_offset:sd=0.1")
    s.add_argument("--reference", action="append", help="quantity=value where the hidden effect is off")
    s.add_argument("--param", action="append", help="DEM parameter NAME=VALUE for every condition")
    s.add_argument("--noise", type=float, default=0.02, help="relative SD of the instrument noise of one repeat")
    s.add_argument("--repeats", type=int, default=3, help="measured repeats per condition, one DEM seed each")
    s.add_argument("--seed", type=int, default=0, help="seed of the noise and disturbance draws")
    s.add_argument("--threads", type=int, default=None)
    s.add_argument("--resources", default="resources")
    s.add_argument("--out", required=True, help="CSV to write (and <out>.truth.csv)")
    s.set_defaults(func=_synthesize)
    r = cmds.add_parser("run", help="the whole loop of a soil in one process on the DEM")
    r.add_argument("soil", help="soil YAML file")
    r.add_argument("--measurement", help="only this measured table")
    r.add_argument("--reference", action="append", help="quantity=value where the calibrated parameters hold")
    r.add_argument("--param", action="append", help="DEM parameter NAME=VALUE for every condition")
    r.add_argument("--sim-seeds", type=int, default=2, help="DEM seeds per condition and design point")
    r.add_argument("--seed", type=int, default=0, help="first DEM seed")
    r.add_argument("--threads", type=int, default=None)
    r.add_argument("--resources", default="resources")
    r.add_argument("--out", required=True, help="folder for the loop's tables")
    r.set_defaults(func=_run)
