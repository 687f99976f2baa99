# Photo measurement per soil: pile / drum angles and the furrow profile from the photos listed
# in resources/images/<soil>/manifest.yaml (validated with every photo present at start-up).


rule image_measure:
    input:
        image_photos,
    output:
        json="results/{soil}/images/measurements.json",
        figures=report(
            directory("results/{soil}/images/figures"),
            patterns=["{name}.png"],
            caption="../report/images.rst",
            category="{soil}",
            subcategory="photos",
        ),
    params:
        manifest=lambda w: f"{RES}/images/{w.soil}/manifest.yaml",
        threshold=lambda w: IMAGE_MANIFESTS[w.soil].get("threshold", "otsu"),
        # a photo that cannot be measured gets a diagnostic image of what was tried here
        # (named in the job's error; logs are kept when a job fails)
        refusals=lambda w: f"logs/{w.soil}/images/refused",
    conda:
        "../../envs/soilcal.yaml"
    log:
        "logs/{soil}/images/image_measure.log",
    benchmark:
        "benchmarks/workflow/{soil}/images/image_measure.tsv"
    script:
        "../scripts/image_measure.py"
