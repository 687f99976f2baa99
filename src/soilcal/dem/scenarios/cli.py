"""``soilcal scenario ...``: list and run the DEM test scenarios.

    soilcal scenario list
    soilcal scenario setups NAME
    soilcal scenario run NAME --setup S --preset quick|paper --seed N --threads T \\
        --set key=value ... --param name=value ... --out row.csv [--vtk DIR] [--replicates K]
        [--restart DIR] [--restart-every SECONDS]
    soilcal scenario compile [--out kernels.csv]

``--set`` overrides a value of the named setup (numbers are parsed as numbers), ``--param``
sets a :class:`soilcal.dem.scenarios.base.DemParams` field; the run writes one CSV row
(:func:`soilcal.dem.scenarios.base.write_row`) and prints the responses as JSON.
``--replicates K`` runs the seeds N .. N+K-1 and reports the mean of each response with the
replicates' standard deviation (:func:`soilcal.dem.scenarios.base.run_replicates`).
``--restart DIR`` keeps a restart file per seed in DIR (scenarios that write them:
:func:`soilcal.dem.restart.supports`), every ``--restart-every`` seconds (default 300): the
same command started again after the run was killed resumes from it.
``compile`` compiles every engine kernel into Numba's cache once
(:mod:`soilcal.dem.scenarios.compile`), so that jobs started side by side load it instead of
each compiling it.
"""

from __future__ import annotations

import json

from soilcal.errors import InputError


def _value(text: str):
    low = text.strip().lower()
    if low in ("true", "false"):
        return low == "true"
    if low in ("none", "null"):
        return None
    try:
        return int(text)
    except ValueError:
        pass
    try:
        return float(text)
    except ValueError:
        return text


def _pairs(items, flag):
    out = {}
    for it in items or []:
        if "=" not in it:
            raise InputError("<command line>", flag, "key=value", it)
        k, v = it.split("=", 1)
        out[k.strip()] = _value(v)
    return out


def _list(args) -> int:
    from soilcal.dem.scenarios import SCENARIOS

    for name, mod in sorted(SCENARIOS.items()):
        doc = (mod.__doc__ or "").strip().splitlines()
        print(f"{name:14s} {doc[0] if doc else ''}  setups: {', '.join(mod.setups())}")
    return 0


def _setups(args) -> int:
    from soilcal.dem.scenarios import get

    mod = get(args.name, "<command line>")
    print(json.dumps(mod.setups(), indent=1, default=str))
    return 0


def _run(args) -> int:
    from soilcal.dem.scenarios import get
    from soilcal.dem.scenarios.base import (PRESETS, DemParams, merge_setup, run_replicates,
                                            threads_used, write_row)

    src = "<command line>"
    mod = get(args.name, src)
    setups = mod.setups()
    name = args.setup or next(iter(setups))
    setup = merge_setup(setups, name, _pairs(args.set, "--set"), src)
    if args.preset not in PRESETS:
        raise InputError(src, "--preset", f"one of {PRESETS}", args.preset)
    if args.replicates < 1:
        raise InputError(src, "--replicates", "an integer >= 1", args.replicates)
    if args.seed < 0:
        raise InputError(src, "--seed", "an integer >= 0", args.seed)
    params = DemParams.from_mapping(_pairs(args.param, "--param"), src)
    mod.validate(setup, args.preset, src, params=params)
    if args.restart_every < 0:
        raise InputError(src, "--restart-every", "a number of seconds >= 0", args.restart_every)
    if args.threads is not None:
        threads_used(args.threads, src, "--threads")
    res = run_replicates(mod, setup, params, preset=args.preset, seed=args.seed,
                         replicates=args.replicates, threads=args.threads, vtk_dir=args.vtk,
                         source=src, restart_dir=args.restart, restart_every=args.restart_every)
    if args.out:
        write_row(args.out, res)
    print(json.dumps(dict(scenario=res.scenario, setup=name, preset=res.preset, seed=res.seed,
                          n_particles=res.n_particles, steps=res.steps,
                          wall_s=round(res.wall_s, 2), responses=res.responses,
                          **({"per_run": res.per_run} if res.per_run else {})), default=float))
    return 0


def _compile(args) -> int:
    from soilcal.dem.scenarios.compile import compile_and_record

    compile_and_record(args.out)
    return 0


def register(subparsers) -> None:
    p = subparsers.add_parser("scenario", help="DEM scenarios of the papers' physical tests")
    sub = p.add_subparsers(dest="scenario_cmd", required=True)
    s = sub.add_parser("list", help="list the scenarios and their named setups")
    s.set_defaults(func=_list)
    s = sub.add_parser("setups", help="print the named setups of a scenario")
    s.add_argument("name")
    s.set_defaults(func=_setups)
    s = sub.add_parser("run", help="run one scenario and write one CSV row")
    s.add_argument("name")
    s.add_argument("--setup", default=None, help="named setup (default: the first)")
    s.add_argument("--preset", default="quick", help="quick (default) or paper")
    s.add_argument("--seed", type=int, default=0)
    s.add_argument("--threads", type=int, default=None,
                   help="Numba threads for the run (default: every core; give 1 to each of several "
                        "runs started side by side, or their threads share the cores and all slow down)")
    s.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a setup value")
    s.add_argument("--param", action="append", metavar="NAME=VALUE", help="DEM parameter")
    s.add_argument("--out", default=None, help="CSV file for the result row")
    s.add_argument("--vtk", default=None, help="directory for VTK frames")
    s.add_argument("--replicates", type=int, default=1,
                   help="runs with seeds SEED .. SEED+K-1, responses averaged (default 1)")
    s.add_argument("--restart", default=None, metavar="DIR",
                   help="keep restart files in DIR and resume from them when started again")
    s.add_argument("--restart-every", type=float, default=300.0, metavar="SECONDS",
                   help="wall time between two restart files (default 300)")
    s.set_defaults(func=_run)
    s = sub.add_parser("compile", help="compile the DEM engine's kernels into Numba's cache "
                                       "(once, before many jobs start side by side)")
    s.add_argument("--out", default=None, metavar="CSV",
                   help="write the cases run (spheres, steps) with the Numba version and the "
                        "digest of the engine's sources")
    s.set_defaults(func=_compile)
