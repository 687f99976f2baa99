"""Snakemake adapter: compile the DEM kernels into Numba's cache once (rule dem_kernels)."""

import gc

from soilcal.dem.scenarios.compile import compile_and_record
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    compile_and_record(snakemake.output[0])  # noqa: F821

# the job's work is done and its files written: move every object to the collector's permanent
# generation, so that the interpreter's exit does not traverse the heap once more (as the DEM
# jobs do, dem_point.py)
gc.freeze()
