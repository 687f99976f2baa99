"""Snakemake adapter: compile the DEM kernels into Numba's cache once (rule dem_kernels)."""

from soilcal.dem.scenarios.compile import compile_and_record
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    compile_and_record(snakemake.output[0])  # noqa: F821
