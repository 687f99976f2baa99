"""Snakemake adapter: regression and ANOVA of one stage (rule regression)."""

import gc

from soilcal.chain.files import read_stage, write_regression
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    write_regression(read_stage(snakemake.input.stage), snakemake.input.responses,  # noqa: F821
                     dict(snakemake.output.items()))  # noqa: F821

# the job's work is done and its files written: move every object to the collector's permanent
# generation, so that the interpreter's exit does not traverse the heap once more (as the DEM
# jobs do, dem_point.py)
gc.freeze()
