"""``soilcal replay SOIL_YAML``: replay one soil's stages on its printed responses;
``soilcal compare A B``: compare two results trees table by table."""

from __future__ import annotations

from pathlib import Path


def _replay(args) -> int:
    from soilcal.config import load_soil
    from soilcal.chain.files import replay_soil

    soil = load_soil(args.soil, args.resources)
    base = Path(args.out) / soil.name / "published"
    _, errata = replay_soil(soil, base)
    print(f"{soil.name}: {len(errata)} errata -> {base / 'errata.csv'}")
    return 0


def _compare(args) -> int:
    from soilcal.chain.compare import IDENTICAL, compare_trees, same_results, summary
    from soilcal.errors import InputError

    for name, root in (("A", args.a), ("B", args.b)):
        if not Path(root).is_dir():
            raise InputError(root, name, "a results folder", "no such folder")
    comps = compare_trees(args.a, args.b)
    for c in comps:
        if c.outcome != IDENTICAL or args.verbose:
            print(f"{c.outcome}: {c.path}" + (f" ({c.detail})" if c.detail else ""))
    counts = ", ".join(f"{n} {k}" for k, n in summary(comps).items())
    ok = same_results(comps)
    print(f"{len(comps)} files: {counts or 'none'}: " + ("same results" if ok else "the results differ"))
    return 0 if ok and comps else 1


def register(sub) -> None:
    p = sub.add_parser("replay", help="replay a soil's calibration on its printed responses (no figures)")
    p.add_argument("soil", help="soil YAML file")
    p.add_argument("--resources", default="resources")
    p.add_argument("--out", default="results")
    p.set_defaults(func=_replay)
    c = sub.add_parser("compare", help="compare two results trees table by table (exit 0: same results)")
    c.add_argument("a", help="first results folder")
    c.add_argument("b", help="second results folder")
    c.add_argument("-v", "--verbose", action="store_true", help="list identical files too")
    c.set_defaults(func=_compare)
