"""``soilcal loop synthesize`` and ``soilcal loop run``: the measured-data loop from the command line.

``synthesize`` writes a copy of a soil's measured table whose measured values come from
soilcal's DEM with hidden effects switched on (:mod:`soilcal.loop.synthesize`): a table with
an effect nobody declared, to prove the loop on.  ``run`` runs the whole loop of a soil in
one process on the DEM (what the workflow does job by job) and writes the loop's tables.

Both simulate each condition at its own parameters: the soil's ``simulation.params``, the
measurement's ``params`` and its ``param`` covariates (:class:`~soilcal.config.measurements.Condition`),
the DEM defaults for the rest; ``--param NAME=VALUE`` sets a parameter for every condition
(a calibrated set).  With ``--results DIR`` each condition starts instead from what the
workflow's tool job for it runs at (:func:`calibrated_params`): the calibrated set of the
condition's stage and case in the DEM results under ``DIR``, read as the workflow reads it,
with ``--param`` still on top.  ``synthesize`` records the parameters of every condition in
its truth file (``params_source``, ``base:<parameter>``), ``run`` in ``parameters.csv``.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

from soilcal.loop import ERROR_KEY


def _kv(text: str, what: str, form: str = "name:key=number[,key=number]", shown: str | None = None
        ) -> tuple[str, dict]:
    """``name:k=v,k=v`` -> (name, {k: float(v)}); an InputError shows ``form`` and the value
    as typed (``shown``, default ``text``)."""
    from soilcal.errors import InputError

    name, _, rest = text.partition(":")
    out = {}
    for part in filter(None, rest.split(",")):
        k, eq, v = part.partition("=")
        try:
            out[k.strip()] = float(v)
        except ValueError:
            raise InputError("<command line>", what, form, text if shown is None else shown) from None
        if not eq:
            raise InputError("<command line>", what, form, text if shown is None else shown)
    return name.strip(), out


def _pairs(values, what: str, form: str) -> dict:
    """``NAME=VALUE`` options (``--param``, ``--reference``), each checked as typed."""
    out = {}
    for v in values or []:
        out.update(_kv("x:" + v, what, form, v)[1])
    return out


def dem_simulator(threads=None):
    """``simulate(cond, params, seed)`` on soilcal's DEM: one run of the condition's scenario
    and setup at its preset, with the condition's own DEM seed for ``seed``
    (:func:`soilcal.config.measurements.condition_seed`: each measured test a sample of its own,
    the same samples at every effect parameter); measure -> value (NaN where the run failed)."""
    from soilcal.chain.sources import simulate
    from soilcal.config.measurements import condition_seed

    def run(cond, params, seed):
        spec = {"soil": "loop", "stage": cond.stage, "run": int(cond.row), "levels": {},
                "seed": condition_seed(cond, int(seed)),
                "replicates": 1, "params": dict(params),
                "responses": {r["measure"]: {"scenario": cond.scenario, "setup": dict(cond.setup),
                                             "measure": r["measure"], "preset": cond.preset} for r in cond.responses}}
        df = simulate(spec, threads=threads)
        out = {r["measure"]: (float(r["value"]) if r["status"] == "ok" else math.nan) for r in df.to_dict("records")}
        why = [str(r.get(ERROR_KEY) or "") for r in df.to_dict("records") if r["status"] != "ok"]
        if any(why):
            # every failed measure's reason (each names its measure where only some failed)
            out[ERROR_KEY] = "; ".join(dict.fromkeys(w for w in why if w))
        return out

    return run


def condition_params(overrides: dict):
    from soilcal.dem.scenarios.base import DemParams

    def base(cond):
        return DemParams.from_mapping({**cond.params, **overrides}, f"{cond.measurement} row {cond.row}").as_dict()

    return base


def _calibration(soil, results: Path, stage_id: str):
    """(stage, calibrated sets, path of the sets) of one DEM stage under ``results``, read as
    the workflow reads them (``_calibration(final=True)`` in ``workflow/rules/common.smk``):
    the stage from ``<soil>/dem/<stage>/stage.json``, the sets from the file the soil ends
    with (:func:`soilcal.chain.refine.set_file`)."""
    import json

    import pandas as pd

    from soilcal.chain.files import read_stage
    from soilcal.chain.refine import set_file
    from soilcal.errors import InputError

    d = results / soil.name / "dem" / stage_id
    stage_path, set_name = d / "stage.json", set_file(soil.data)
    set_path = d / set_name
    if not stage_path.is_file():
        raise InputError(stage_path, "<file>", f"the DEM stage {stage_id} as the workflow writes it (stage.json; "
                         "run the workflow's DEM stage first)", "no such file")
    why = ("written by the workflow's final_set step once the stage's second verification round is in; "
           "simulation.verification.refine is on" if set_name == "final.csv" else
           "written by the workflow's optimum step")
    if not set_path.is_file():
        raise InputError(set_path, "<file>", f"the calibrated sets of DEM stage {stage_id} that the workflow's tool "
                         f"jobs use ({set_name}, {why})", "no such file")
    try:
        stage = read_stage(stage_path)
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise InputError(stage_path, "<file>", "a stage written by the workflow (JSON)", str(exc)) from None
    if not isinstance(stage, dict) or not isinstance(stage.get("factors"), dict):
        raise InputError(stage_path, "factors", "a stage with its factors", None)
    try:
        optimum = pd.read_csv(set_path)
    except (pd.errors.EmptyDataError, pd.errors.ParserError, UnicodeDecodeError) as exc:
        raise InputError(set_path, "<file>", f"a table of calibrated sets ({set_name})", str(exc)) from None
    missing = [c for c in ("case", *stage["factors"]) if c not in optimum.columns]
    if missing:
        raise InputError(set_path, "columns", "case and a column per factor of the stage ("
                         + ", ".join(stage["factors"]) + ")", missing)
    return stage, optimum, set_path


def calibrated_params(soil, conds, results) -> dict:
    """``(measurement, row)`` -> the DEM parameters (name -> SI value) that the workflow's tool
    job for that condition runs at (:func:`soilcal.chain.verify.tool_point`): the calibrated
    set of the condition's stage and case (:func:`soilcal.chain.stage.calibrated_levels`) in
    the DEM results under ``results`` (the workflow's ``results/``), the stage's fixed values
    and the soil's properties and ``simulation.params`` below it, the condition's parameters
    over it.  InputError naming the file when a stage has no stage.json or set file, or a
    condition's case no calibrated set; every condition is checked before any is simulated."""
    from soilcal.chain.stage import calibrated_levels
    from soilcal.chain.verify import tool_point
    from soilcal.errors import InputError

    root = Path(results)
    if not str(results) or not root.is_dir():
        raise InputError("<command line>", "--results", "a results folder (holding <soil>/dem/<stage>/)",
                         str(results))
    cals, out = {}, {}
    for c in conds:
        if c.stage not in cals:
            cals[c.stage] = _calibration(soil, root, c.stage)
        stage, optimum, path = cals[c.stage]
        where = f"measurement {c.measurement} row {c.row}: stage {c.stage}, case {c.case or '(the first)'}"
        try:
            calibrated_levels(stage, optimum, c.case or None)
        except InputError as exc:
            if exc.field == "optimise":  # the stage names no case
                raise InputError(path.with_name("stage.json"), exc.field, exc.expected, exc.got, note=where) from None
            raise InputError(path, exc.field, exc.expected + " (a row with calibrated = True)", exc.got,
                             note=where) from None
        job = tool_point(soil, c, stage, optimum)
        if "not_run" in job or not job["specs"]:
            raise InputError(path, f"case {c.case}", "a calibrated set", job.get("not_run"), note=where)
        out[(c.measurement, int(c.row))] = dict(job["specs"][0]["params"])  # the specs differ by seed only
    return out


def base_parameters(soil, conds, overrides: dict, results=None) -> dict:
    """``(measurement, row)`` -> the DEM parameters each condition is simulated at before any
    effect: without ``results`` :func:`condition_params`, with it :func:`calibrated_params`;
    ``overrides`` (``--param``) on top of either."""
    from soilcal.dem.scenarios.base import DemParams

    if results is None:
        base = condition_params(overrides)
        return {(c.measurement, int(c.row)): base(c) for c in conds}
    return {k: DemParams.from_mapping({**p, **overrides}, f"{k[0]} row {k[1]}").as_dict()
            for k, p in calibrated_params(soil, conds, results).items()}


def params_source(args, overrides: dict) -> str:
    """Where the base parameters come from, as the outputs record it."""
    src = (f"--results {args.results}" if args.results else
           "not a calibrated set (--results reads one): the engine's defaults (soilcal.dem.scenarios.base.DemParams) "
           "under the soil's simulation.params and the measured table's params")
    return src + "".join(f" + --param {k}={v:.12g}" for k, v in overrides.items())


def _lookup(table: dict):
    return lambda cond: dict(table[(cond.measurement, int(cond.row))])


def _params(args) -> dict:
    from soilcal.dem.scenarios.base import DemParams
    from soilcal.errors import InputError

    pairs = _pairs(args.param, "--param", "NAME=NUMBER, a DEM parameter and its SI value")
    # the names checked here, where the user typed them: later they are checked per measured row
    # (and an unknown one would be reported against the table's first row)
    known = DemParams.names()
    for key in pairs:
        if key not in known:
            raise InputError("<command line>", "--param", f"NAME=NUMBER with NAME one of {', '.join(known)}", key)
    return pairs


def _conditions(args, every: bool = False):
    """(soil, the conditions of --measurement or of every table[, every table's conditions])."""
    from soilcal.config.load import load_soil
    from soilcal.config.measurements import conditions
    from soilcal.errors import InputError

    soil = load_soil(args.soil, args.resources)
    conds = all_conds = conditions(soil)
    if getattr(args, "measurement", None):
        known = sorted({c.measurement for c in conds})
        conds = [c for c in conds if c.measurement == args.measurement]
        if not conds:
            raise InputError(args.soil, "measurements", "the id of a measured table (" + ", ".join(known) + ")",
                             args.measurement)
    return (soil, conds, all_conds) if every else (soil, conds)


def _named(items, what: str) -> dict:
    """``--effect`` / ``--disturbance`` values, ``name:key=value,...``, one per name."""
    from soilcal.errors import InputError

    out = {}
    for text in items or []:
        name, kv = _kv(text, what)
        if name in out:
            raise InputError("<command line>", what, f"each name once (merge its keys: {name}:k=v,k=v)", text)
        out[name] = kv
    return out


def _reference(args) -> dict:
    return _pairs(args.reference, "--reference", "QUANTITY=NUMBER, a quantity and its value in its SI unit")


def _synthesize(args) -> int:
    import numpy as np
    import pandas as pd

    from soilcal.atomic import write_text
    from soilcal.config.load import read_table
    from soilcal.errors import InputError
    from soilcal.config.measurements import measurements_dir, unit_factor
    from soilcal.loop import synthesize as sy

    soil, conds, every = _conditions(args, every=True)
    hidden = _named(args.effect, "--effect")
    dist = sy.check_disturbances(_named(args.disturbance, "--disturbance"), conds, "--disturbance")
    sy.check_hidden(hidden, "--effect")
    # where the calibrated parameters hold: the soil's loop.reference, --reference over it, else
    # the mean over every measured table of the soil, as the loop of the whole soil takes it
    from soilcal.loop import core

    given = _reference(args)
    declared = {**core.settings_from(soil.data, soil.path).reference, **given}
    sy.default_reference(conds, given, "--reference", strict=True)  # a name no row carries: refused
    core.check_reference(every, given, "--reference", "reference")  # a value far from every row
    reference = sy.default_reference(conds, declared, "--reference", over=every)
    if not (math.isfinite(args.noise) and args.noise >= 0):
        raise InputError("<command line>", "--noise", "a relative SD >= 0 of the instrument noise (0.02: 2 %)",
                         args.noise)
    if args.repeats < 1:
        raise InputError("<command line>", "--repeats", "at least 1 measured repeat", args.repeats)
    overrides = _params(args)
    params = base_parameters(soil, conds, overrides, args.results)
    sy.check_acts(hidden, dist, conds, _lookup(params), reference, "--effect", "--disturbance")
    folder = measurements_dir(soil.resources_root, soil.name)
    table = sy.synthesize(conds, _lookup(params), dem_simulator(args.threads), hidden, reference, dist,
                          noise=args.noise, seed=args.seed, seeds=tuple(range(1000, 1000 + args.repeats)),
                          table_of=lambda m: folder / soil.data["measurements"][m]["table"])
    source = params_source(args, overrides)
    keys = list(zip(table["measurement"], table["row"].astype(int)))
    table["params_source"] = source
    # each row's DEM seeds, one a repeat: the condition's own (dem_simulator, condition_seed)
    from soilcal.config.measurements import condition_seed

    by_key = {(c.measurement, int(c.row)): c for c in conds}
    table["dem_seeds"] = [" ".join(str(condition_seed(by_key[k], s)) for s in range(1000, 1000 + args.repeats))
                          for k in keys]
    table = table.join(pd.DataFrame([params[k] for k in keys], index=table.index).add_prefix("base:"))
    entry = soil.data["measurements"][args.measurement]
    src = measurements_dir(soil.resources_root, soil.name) / entry["table"]
    # every cell as the user's table writes it (a tool NA, 007), only the responses replaced
    df = read_table(src, text_columns=True)
    for j, r in enumerate(entry["responses"]):
        t = table[table["measure"] == r["measure"]].sort_values("row")
        if r.get("value") is None:
            continue
        # the simulation gives the measure's own unit (N, mm); the table's columns are in the
        # unit the response declares (kN, cm), which reading it converts back from
        per = 1.0 / unit_factor(r["unit"], r["measure"])
        df[r["value"]] = _significant(t["value"].to_numpy(float) * per)
        if r.get("sd"):
            # an SD of 0 (one repeat, or a run without seed scatter) is not known: a blank cell,
            # as a measured table gives it (an SD of 0 would call the value exact)
            sd = _significant(t["sd"].to_numpy(float) * per)
            df[r["sd"]] = np.where(sd > 0, sd, np.nan)
        if r.get("n"):
            df[r["n"]] = t["n"].to_numpy(int)
    write_text(args.out, df.to_csv(index=False))
    truth = Path(args.out).with_suffix(".truth.csv")
    write_text(truth, table.to_csv(index=False))
    from soilcal.loop.effects import EFFECTS

    for name, theta in hidden.items():
        for k, v in theta.items():
            lo, hi = EFFECTS[name].bounds()[k]
            if not lo <= v <= hi:
                print(f"note: the hidden {name}.{k} {v:g} lies outside the bounds the loop fits it over ({lo:g} to "
                      f"{hi:g}; loop.bounds widens them): the loop will find it at a bound", file=sys.stderr)
    print(f"{len(df)} rows -> {args.out} (truth: {truth}; parameters: {source}; hidden {hidden or 'none'}, "
          f"disturbances {dist or 'none'}, seed {args.seed}; reference {reference or 'none'}; the truth in SI units, "
          "the table in its declared units)")
    return 0


def _significant(x, digits: int = 8):
    """``x`` to ``digits`` significant digits (a force in N and an area in m^2 alike)."""
    import numpy as np

    return np.array([float(f"{v:.{digits}g}") if np.isfinite(v) else np.nan for v in x], float)


def _run(args) -> int:
    from dataclasses import replace

    from soilcal.chain.files import write_csv
    from soilcal.loop import core

    from soilcal.errors import InputError
    from soilcal.loop import synthesize as sy

    soil, conds, every = _conditions(args, every=True)
    settings = core.settings_from(soil.data, soil.path)
    core.check_fold_by(soil, conds, settings, args.measurement)
    if args.reference:
        given = _reference(args)
        sy.default_reference(conds, given, "--reference", strict=True)  # names the conditions carry, values
        core.check_reference(every, given, "--reference", "reference")  # a value far from every row
        settings = replace(settings, reference={**settings.reference, **given})
    if args.measurement:  # one table: the reference of the whole soil's loop, not of this table's rows
        settings = replace(settings, reference=sy.default_reference(conds, settings.reference, "--reference",
                                                                    over=every))
    seeds = args.sim_seeds if args.sim_seeds is not None else max(int(c.replicates) for c in conds)
    if seeds < 1:
        raise InputError("<command line>", "--sim-seeds", "at least 1 DEM seed per condition", seeds)
    overrides = _params(args)
    params = base_parameters(soil, conds, overrides, args.results)
    out = core.run_inprocess(soil.name, conds, _lookup(params), dem_simulator(args.threads), settings,
                             seeds=tuple(range(args.seed, args.seed + seeds)))
    d = Path(args.out)
    for name, df in (("residuals", out.residuals), ("diagnosis", out.diagnosis), ("ranking", out.ranking),
                     ("selection", out.selection), ("predictions", out.predictions), ("loop_summary", out.summary),
                     ("detectable", out.detectable), ("parameters", parameters_frame(params))):
        write_csv(df, d / f"{name}.csv")
    _report(soil, conds, settings, out, d)
    print(f"parameters: {params_source(args, overrides)} ({d / 'parameters.csv'})")
    print(out.verdict)
    return 0


def _report(soil, conds, settings, out, d: Path) -> None:
    """``report.md`` and the residual figures of an in-process run, as the workflow writes
    them (the plan rebuilt from the outcome: its candidates, reference and settings)."""
    import json

    from soilcal.atomic import write_text
    from soilcal.loop import core, files
    from soilcal.plots.loop import residual_figures

    qcols = core.quantity_of(conds)
    reference = json.loads(out.summary["reference"].iloc[0] or "{}")
    plan = files._plan(soil.name, out.candidates, reference, settings, qcols, out.skipped,
                       out.residuals)
    residual_figures(out.residuals, None, d / "figures" / "residuals", title=f"{soil.name}: calibrated model")
    residual_figures(out.residuals, out.predictions if out.chosen else None, d / "figures" / "after",
                     title=f"{soil.name}: " + (" + ".join(out.chosen) if out.chosen else "no effect chosen"))
    write_text(d / "report.md", files.report(soil.name, out, [plan]))


def parameters_frame(params: dict):
    """``parameters.csv`` of ``soilcal loop run``: measurement, row and one column per DEM
    parameter (SI), the base parameters of every condition (:func:`base_parameters`)."""
    import pandas as pd

    from soilcal.dem.scenarios.base import DemParams

    return pd.DataFrame([{"measurement": m, "row": r, **p} for (m, r), p in params.items()],
                        columns=["measurement", "row", *DemParams.names()])


RESULTS_HELP = ("results folder of the workflow (e.g. results): start every condition from the calibrated set "
                "of its stage and case there, as the workflow's tool jobs do (--param still on top)")


def _si_units() -> str:
    from soilcal.config.quantities import QUANTITIES

    return ", ".join(f"{q} {u[0]}" for q, u in QUANTITIES.items() if u).replace("%", "%%")  # argparse formats help


SI_UNITS = _si_units()


def register(sub) -> None:
    p = sub.add_parser("loop", help="the measured-data loop: synthesize a measured table, run the loop")
    cmds = p.add_subparsers(dest="loop_cmd", required=True)
    s = cmds.add_parser("synthesize", help="a measured table from the DEM with hidden effects")
    s.add_argument("soil", help="soil YAML file")
    s.add_argument("--measurement", required=True, help="id of the measured table (measurements block)")
    s.add_argument("--effect", action="append", help="hidden effect, e.g. rate_friction:beta=0.2 (repeatable)")
    s.add_argument("--disturbance", action="append",
                   help="periodic:amplitude=0.1,wavelength=7 | stones:fraction=0.3 | day_offset:sd=0.1")
    s.add_argument("--reference", action="append", help="quantity=value where the hidden effect is off, in the "
                   "quantity's SI unit (" + SI_UNITS + "); default: the soil's loop.reference, else the mean over the "
                   "measured rows of every table of the soil, as the loop takes it")
    s.add_argument("--param", action="append", help="DEM parameter NAME=VALUE for every condition")
    s.add_argument("--results", help=RESULTS_HELP)
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
    r.add_argument("--reference", action="append", help="quantity=value where the calibrated parameters hold, in "
                   "the quantity's SI unit (" + SI_UNITS + "); default: the soil's loop.reference, else the mean over "
                   "the measured rows of every table of the soil")
    r.add_argument("--param", action="append", help="DEM parameter NAME=VALUE for every condition")
    r.add_argument("--results", help=RESULTS_HELP)
    r.add_argument("--sim-seeds", type=int, default=None, help="DEM seeds per condition and design point "
                   "(default: the largest `replicates` of the measured tables, 3 where they give none)")
    r.add_argument("--seed", type=int, default=0, help="first DEM seed")
    r.add_argument("--threads", type=int, default=None)
    r.add_argument("--resources", default="resources")
    r.add_argument("--out", required=True, help="folder for the loop's tables")
    r.set_defaults(func=_run)
