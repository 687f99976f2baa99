"""Snakemake adapter: final.csv of one stage (the set each case ends with)."""

import gc

from soilcal.chain.refine import write_final
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    i = snakemake.input  # noqa: F821
    df = write_final(snakemake.params.soil, i.stage, i.targets, i.optimum, i.refined, i.runs,  # noqa: F821
                     i.refined_runs, snakemake.output[0])  # noqa: F821
    print(df.to_string(index=False))

# the job's work is done and its files written: move every object to the collector's permanent
# generation, so that the interpreter's exit does not traverse the heap once more (as the DEM
# jobs do, dem_point.py)
gc.freeze()
