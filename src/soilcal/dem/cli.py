"""``soilcal bench ...`` commands of the DEM engine."""

from __future__ import annotations

import json


def _settle(args) -> int:
    from soilcal.dem.bench import run_settle

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
