# Photo measurement per soil: pile / drum angles and the furrow profile from the photos listed
# in resources/images/<soil>/manifest.yaml.  Uses config["soils"] and soil_cfg(soil) (common.smk).
import yaml as _img_yaml


def _image_photos(wildcards):
    manifest = f"resources/images/{wildcards.soil}/manifest.yaml"
    with open(manifest) as fh:
        photos = (_img_yaml.safe_load(fh) or {}).get("photos") or []
    return [manifest] + [f"resources/images/{wildcards.soil}/{p['file']}" for p in photos if "file" in p]


def _image_threshold(wildcards):
    cfg = soil_cfg(wildcards.soil) or {}
    return (cfg.get("imaging") or {}).get("threshold", "otsu")


rule image_measure:
    input:
        _image_photos,
    output:
        json="results/{soil}/images/measurements.json",
        figures=directory("results/{soil}/images/figures"),
    params:
        manifest="resources/images/{soil}/manifest.yaml",
        threshold=_image_threshold,
    log:
        "logs/{soil}/images/image_measure.log",
    benchmark:
        "benchmarks/workflow/{soil}/images/image_measure.tsv"
    script:
        "../scripts/image_measure.py"


rule images_all:
    input:
        expand("results/{soil}/images/measurements.json", soil=config["soils"]),
