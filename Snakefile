# soilcal: DEM soil calibration. `snakemake --cores 2` replays all soils of config/config.yaml.
configfile: "config/config.yaml"


include: "workflow/rules/common.smk"
include: "workflow/rules/doe.smk"
include: "workflow/rules/rsm.smk"
include: "workflow/rules/optimise.smk"
include: "workflow/rules/plots.smk"
include: "workflow/rules/errata.smk"
include: "workflow/rules/imaging.smk"


rule all:
    input:
        all_targets(),
    default_target: True
