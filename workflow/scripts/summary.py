"""Snakemake adapter: results/summary.csv and its figure (every DEM-calibrated soil)."""

import gc

from soilcal.chain.verify import write_summary
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    df = write_summary(snakemake.params.soils, snakemake.input.verification, snakemake.input.responses,  # noqa: F821
                       snakemake.output.table, snakemake.output.figures)  # noqa: F821
    print(df.to_string(index=False))

# the job's work is done and its files written: move every object to the collector's permanent
# generation, so that the interpreter's exit does not traverse the heap once more (as the DEM
# jobs do, dem_point.py)
gc.freeze()
