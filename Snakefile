# soilcal: DEM soil calibration.  `snakemake --cores 2` calibrates every soil of
# config/config.yaml on its response source: the DEM (one job per design point) or the printed
# tables (`--config source=published`); one chain of rules serves both.
configfile: "config/config.yaml"
report: "workflow/report/workflow.rst"


include: "workflow/rules/common.smk"
include: "workflow/rules/imaging.smk"
include: "workflow/rules/doe.smk"
include: "workflow/rules/sources.smk"
include: "workflow/rules/rsm.smk"
include: "workflow/rules/optimise.smk"
include: "workflow/rules/verify.smk"
include: "workflow/rules/adaptive.smk"
include: "workflow/rules/loop.smk"
include: "workflow/rules/plots.smk"
include: "workflow/rules/errata.smk"


rule all:
    input:
        all_targets(),
    default_target: True
