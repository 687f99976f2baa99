"""Snakemake adapter: optimum, near-optimal sets and identifiability of one stage."""

from soilcal.chain.files import read_stage, read_targets, write_optimum
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    write_optimum(read_stage(snakemake.input.stage), snakemake.input.responses,  # noqa: F821
                  read_targets(snakemake.input.targets), snakemake.params.seed,  # noqa: F821
                  snakemake.output.optimum, snakemake.output.identifiability)  # noqa: F821
