"""``soilcal replay SOIL_YAML``: replay one soil's stages on its printed responses."""

from __future__ import annotations

from pathlib import Path


def _replay(args) -> int:
    from soilcal.config import load_soil
    from soilcal.replay.run import write_design, write_errata, write_optimum, write_regression

    soil = load_soil(args.soil, args.resources)
    base = Path(args.out) / soil.name / "published"
    dirs = {}
    for st in soil.stages:
        d = base / st["id"]
        dirs[st["id"]] = str(d)
        table = soil.table_path(st["id"])
        write_design(st, table, d / "design.csv", d / "design_check.csv")
        if table is None:
            continue
        if st["kind"] in ("plackett_burman", "box_behnken"):
            write_regression(st, table, {k: d / f"{k}.csv" for k in ("anova", "fit", "coefficients", "effects")})
        if st["kind"] == "steepest_ascent" or st.get("optimise"):
            write_optimum(st, table, soil.data["targets"], soil.data["seed"], d / "optimum.csv")
    df = write_errata(soil.data, soil.published_dir(), dirs, base / "errata.csv")
    print(f"{soil.name}: {len(df)} errata -> {base / 'errata.csv'}")
    return 0


def register(sub) -> None:
    p = sub.add_parser("replay", help="replay a soil's calibration on its printed responses (no figures)")
    p.add_argument("soil", help="soil YAML file")
    p.add_argument("--resources", default="resources")
    p.add_argument("--out", default="results")
    p.set_defaults(func=_replay)
