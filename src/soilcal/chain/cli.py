"""``soilcal replay SOIL_YAML``: replay one soil's stages on its printed responses."""

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


def register(sub) -> None:
    p = sub.add_parser("replay", help="replay a soil's calibration on its printed responses (no figures)")
    p.add_argument("soil", help="soil YAML file")
    p.add_argument("--resources", default="resources")
    p.add_argument("--out", default="results")
    p.set_defaults(func=_replay)
