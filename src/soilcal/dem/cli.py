"""``soilcal bench ...`` commands of the DEM engine."""

from __future__ import annotations

import json


def _settle(args) -> int:
    from soilcal.dem.bench import run_settle
    from soilcal.dem.scenarios.base import threads_used
    from soilcal.errors import InputError

    src = "<command line>"
    if args.n < 1:
        raise InputError(src, "--n", "a number of spheres >= 1", args.n)
    if args.steps < 0:
        raise InputError(src, "--steps", "a number of steps >= 0", args.steps)
    if args.skin is not None and not args.skin > 0:
        raise InputError(src, "--skin", "a neighbour skin > 0 m", args.skin)
    threads_used(args.threads, src, "--threads")
    res = run_settle(args.n, args.steps, args.threads, args.cohesion, args.seed, args.skin)
    print(json.dumps(res))
    return 0


def register(subparsers) -> None:
    from soilcal.dem.scenarios.cli import register as register_scenarios

    register_scenarios(subparsers)
    p = subparsers.add_parser("bench", help="DEM engine benchmarks")
    sub = p.add_subparsers(dest="bench_cmd", required=True)
    s = sub.add_parser("settle", help="gravity settling of a lattice of spheres on a floor")
    s.add_argument("--n", type=int, default=5000, help="number of spheres (nx*nx*50)")
    s.add_argument("--steps", type=int, default=20000)
    s.add_argument("--threads", type=int, default=1)
    s.add_argument("--cohesion", choices=["none", "jkr"], default="none")
    s.add_argument("--seed", type=int, default=2024)
    s.add_argument("--skin", type=float, default=None, help="neighbour skin [m]")
    s.set_defaults(func=_settle)
