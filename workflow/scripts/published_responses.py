"""Snakemake adapter: the printed table as the published source's responses."""

import gc

from soilcal.chain.sources import published_responses
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    print(published_responses(snakemake.input.table, snakemake.output[0]))  # noqa: F821

# the job's work is done and its files written: move every object to the collector's permanent
# generation, so that the interpreter's exit does not traverse the heap once more (as the DEM
# jobs do, dem_point.py)
gc.freeze()
