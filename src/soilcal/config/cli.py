"""``soilcal config check FILE...``: validate soil entries and their published tables;
``soilcal config check --workflow config/config.yaml``: the workflow config and every soil it
lists, as the workflow does before any job."""

from __future__ import annotations

import json
import sys


def _check(args) -> int:
    from soilcal.config import design_runs, load_soil, load_workflow_config, read_yaml
    from soilcal.errors import InputError

    if not args.files and not args.workflow:
        raise InputError("<command line>", "files", "a soil YAML file or --workflow CONFIG", None)
    soils = []
    if args.workflow:
        cfg = read_yaml(args.workflow)
        if not isinstance(cfg, dict):
            raise InputError(args.workflow, "<root>", "a mapping of workflow settings", type(cfg).__name__)
        soils += [(f"{s.path}", s) for s in load_workflow_config(cfg, args.workflow).values()]
    soils += [(str(path), load_soil(path, args.resources)) for path in args.files]
    for path, soil in soils:
        stages = [{"id": s["id"], "kind": s["kind"], "runs": design_runs(s), "table": s.get("table")} for s in soil.stages]
        print(json.dumps({"file": path, "soil": soil.name, "valid": True, "stages": stages,
                          "defaults": list(soil.defaulted), "load_notes": soil.load_notes}))
        for note in soil.load_notes:
            print(f"soilcal: note: {path}: {note}", file=sys.stderr)
    return 0


def register(sub) -> None:
    p = sub.add_parser("config", help="soil configuration")
    g = p.add_subparsers(dest="command", required=True)
    c = g.add_parser("check", help="validate soil YAML files against the schema and their tables")
    c.add_argument("files", nargs="*", help="soil YAML files")
    c.add_argument("--resources", default="resources", help="resources root (default: resources)")
    c.add_argument("--workflow", metavar="CONFIG",
                   help="a workflow config (config/config.yaml): check it and every soil it lists "
                        "(its soil_dir and resources)")
    c.set_defaults(func=_check)
