# Configuration, validated before any job runs: the workflow config against its schema, then
# every soil file against the soil schema and the published tables against their designs.
import os

from snakemake.utils import validate

from soilcal.config import load_workflow_config
from soilcal.imaging.manifest import read_manifest


validate(config, "../schemas/config.schema.yaml")
SOILS = load_workflow_config(config)
RES = config.get("resources", "resources")
IMAGE_MANIFESTS = {
    soil: read_manifest(f"{RES}/images/{soil}/manifest.yaml")
    for soil in SOILS
    if os.path.isfile(f"{RES}/images/{soil}/manifest.yaml")
}

wildcard_constraints:
    soil="|".join(SOILS),
    stage="[a-z0-9][a-z0-9-]*",


def soil_cfg(soil):
    return SOILS[soil].data


def stage_cfg(soil, stage):
    return SOILS[soil].stage(stage)


def stage_table(wildcards):
    st = stage_cfg(wildcards.soil, wildcards.stage)
    return [] if st.get("table") is None else f"{RES}/published/{wildcards.soil}/{st['table']}"


def stage_dir(soil, stage):
    return f"results/{soil}/published/{stage}"


def stage_targets(soil, st):
    d = stage_dir(soil, st["id"])
    out = [f"{d}/design.csv"]
    if st.get("table") is None:
        return out
    if st["kind"] in ("plackett_burman", "box_behnken"):
        out += [f"{d}/{x}.csv" for x in ("anova", "fit", "coefficients", "effects")]
        out += [f"{d}/figures/diagnostics"]
    if st["kind"] == "plackett_burman":
        out += [f"{d}/figures/pareto"]
    if st["kind"] == "box_behnken":
        out += [f"{d}/figures/surfaces"]
        if st.get("optimise"):
            out += [f"{d}/optimum.csv"]
    if st["kind"] == "steepest_ascent":
        out += [f"{d}/optimum.csv", f"{d}/figures/steepest"]
    return out


def all_targets():
    out = []
    for soil, s in SOILS.items():
        for st in s.stages:
            out += stage_targets(soil, st)
        out.append(f"results/{soil}/published/errata.csv")
        if soil in IMAGE_MANIFESTS:
            out.append(f"results/{soil}/images/measurements.json")
    return out


def image_photos(wildcards):
    m = IMAGE_MANIFESTS[wildcards.soil]
    base = f"{RES}/images/{wildcards.soil}"
    return [f"{base}/manifest.yaml"] + [f"{base}/{p['file']}" for p in m["photos"]]


def errata_inputs(wildcards):
    out = []
    for st in SOILS[wildcards.soil].stages:
        out += [f for f in stage_targets(wildcards.soil, st) if f.endswith(".csv")]
        if st.get("table") is not None:
            out.append(f"{stage_dir(wildcards.soil, st['id'])}/design_check.csv")
    return out
