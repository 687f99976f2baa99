"""Snakemake adapter: verification bars and per-case progress of a soil's adaptive designs."""

import gc

from soilcal.chain.adaptive import figure_files
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    paths = figure_files(snakemake.wildcards.soil, snakemake.input.verification,  # noqa: F821
                         snakemake.params.cases, snakemake.output[0])  # noqa: F821
    print("\n".join(map(str, paths)))

# the job's work is done and its files written: move every object to the collector's permanent
# generation, so that the interpreter's exit does not traverse the heap once more (as the DEM
# jobs do, dem_point.py)
gc.freeze()
