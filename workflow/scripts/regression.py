"""Snakemake adapter: regression and ANOVA of one stage (rule regression)."""

from soilcal.chain.files import read_stage, write_regression
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    write_regression(read_stage(snakemake.input.stage), snakemake.input.responses,  # noqa: F821
                     dict(snakemake.output.items()))  # noqa: F821
