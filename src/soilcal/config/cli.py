"""``soilcal config check FILE...``: validate soil entries and their published tables."""

from __future__ import annotations

import json


def _check(args) -> int:
    from soilcal.config import design_runs, load_soil

    for path in args.files:
        soil = load_soil(path, args.resources)
        stages = [{"id": s["id"], "kind": s["kind"], "runs": design_runs(s), "table": s.get("table")} for s in soil.stages]
        print(json.dumps({"file": str(path), "soil": soil.name, "valid": True, "stages": stages}))
    return 0


def register(sub) -> None:
    p = sub.add_parser("config", help="soil configuration")
    g = p.add_subparsers(dest="command", required=True)
    c = g.add_parser("check", help="validate soil YAML files against the schema and their tables")
    c.add_argument("files", nargs="+")
    c.add_argument("--resources", default="resources", help="resources root (default: resources)")
    c.set_defaults(func=_check)
