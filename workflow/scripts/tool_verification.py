"""Snakemake adapter: tool_verification.csv of one soil."""

import gc

from soilcal.chain.verify import write_tool_verification
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    df = write_tool_verification(snakemake.params.soil_path, snakemake.params.resources_root,  # noqa: F821
                                 list(snakemake.input), snakemake.params.runs, snakemake.output[0])  # noqa: F821
    print(df.to_string(index=False))

# the job's work is done and its files written: move every object to the collector's permanent
# generation, so that the interpreter's exit does not traverse the heap once more (as the DEM
# jobs do, dem_point.py)
gc.freeze()
