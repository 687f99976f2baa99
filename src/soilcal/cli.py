"""Command-line interface: ``soilcal <group> <command> ...``.

Each sub-package that offers commands has a module ``soilcal.<pkg>.cli`` with a
``register(subparsers)`` function adding one command group; they are discovered here so that
the groups stay independent of each other.

Every error a user can fix (a bad input file, a bad option, a path that cannot be read or
written) is printed as one line ``soilcal: error: <file>: <field>: expected ..., got ...``
(:class:`soilcal.errors.InputError`), without a traceback, and the command exits with
status 2.
"""

from __future__ import annotations

import argparse
import importlib
import re
import sys
from pathlib import Path

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

COMMAND_LINE = "<command line>"


def _name(dest: str) -> str:
    """An argument as the user knows it: the sub-command slots (``group``, ``*_cmd``) are
    'command'."""
    return "command" if dest in ("group", "command") or dest.endswith("_cmd") else dest


def _argparse_error(prog: str, message: str):
    """An argparse message as an :class:`~soilcal.errors.InputError` on the command line."""
    from soilcal.errors import InputError

    hint = f" (see {prog} --help)"
    m = re.match(r"unrecognized arguments: (.+)$", message)
    if m:
        return InputError(COMMAND_LINE, m.group(1).split()[0], f"an option or argument of {prog}{hint}", m.group(1))
    m = re.match(r"the following arguments are required: (.+)$", message)
    if m:
        names = ", ".join(_name(d) for d in m.group(1).split(", "))
        return InputError(COMMAND_LINE, names, f"a value for each required argument of {prog}{hint}", None)
    m = re.match(r"argument (\S+): invalid choice: (.+?) \(choose from (.+)\)$", message)
    if m:
        return InputError(COMMAND_LINE, _name(m.group(1)), f"one of {m.group(3)}", m.group(2).strip("'"))
    m = re.match(r"argument (\S+): invalid (\w+) value: (.+)$", message)
    if m:
        kind = {"int": "an integer", "float": "a number"}.get(m.group(2), f"a {m.group(2)} value")
        return InputError(COMMAND_LINE, m.group(1), kind, m.group(3).strip("'"))
    m = re.match(r"argument (\S+): (?:expected )?(.+)$", message)
    if m:
        return InputError(COMMAND_LINE, _name(m.group(1)), m.group(2) + hint)
    return InputError(COMMAND_LINE, prog, message + hint)


class Parser(argparse.ArgumentParser):
    """ArgumentParser whose errors are one ``soilcal: error:`` line (exit status 2)."""

    def error(self, message):  # noqa: D401 - argparse API
        print(f"soilcal: error: {_argparse_error(self.prog, message)}", file=sys.stderr)
        raise SystemExit(2)


def _group_modules():
    """The command modules present, found without importing their packages."""
    root = Path(__file__).resolve().parent
    for name in _GROUP_MODULES:
        parts = name.split(".")[1:]
        if root.joinpath(*parts[:-1], parts[-1] + ".py").is_file():
            yield name


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(prog="soilcal", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="group", required=True)
    for name in _group_modules():
        importlib.import_module(name).register(sub)
    return parser


def _os_error(exc: OSError):
    """A file that cannot be read or written, as an InputError naming it."""
    from soilcal.errors import InputError

    path = exc.filename if exc.filename is not None else COMMAND_LINE
    what = exc.strerror or type(exc).__name__
    return InputError(path, "<file>", "a path that can be read or written", what)


def _chosen_parser(parser: argparse.ArgumentParser, args) -> argparse.ArgumentParser:
    """The (sub)command parser the arguments selected, e.g. the one of ``soilcal replay``."""
    while True:
        subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        name = getattr(args, subs[0].dest, None) if subs else None
        if not subs or name not in subs[0].choices:
            return parser
        parser = subs[0].choices[name]


def main(argv: list[str] | None = None) -> int:
    from soilcal.errors import SoilcalError

    parser = build_parser()
    args, extra = parser.parse_known_args(argv)
    if extra:  # named with the command they were given to
        _chosen_parser(parser, args).error("unrecognized arguments: " + " ".join(extra))
    try:
        return int(args.func(args) or 0)
    except SoilcalError as exc:
        print(f"soilcal: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        if exc.filename is None:
            raise
        print(f"soilcal: error: {_os_error(exc)}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
