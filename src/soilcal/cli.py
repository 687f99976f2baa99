"""Command-line interface: ``soilcal <group> <command> ...``.

Each sub-package that offers commands has a module ``soilcal.<pkg>.cli`` with a
``register(subparsers)`` function adding one command group; they are discovered here so that
the groups stay independent of each other.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import sys

_GROUP_MODULES = (
    "soilcal.config.cli",
    "soilcal.imaging.cli",
    "soilcal.doe.cli",
    "soilcal.rsm.cli",
    "soilcal.optimise.cli",
    "soilcal.dem.cli",
    "soilcal.chain.cli",
    "soilcal.loop.cli",
    "soilcal.plots.cli",
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="soilcal", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="group", required=True)
    for name in _GROUP_MODULES:
        if importlib.util.find_spec(name) is None:
            continue
        importlib.import_module(name).register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    from soilcal.errors import SoilcalError

    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except SoilcalError as exc:
        print(f"soilcal: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
