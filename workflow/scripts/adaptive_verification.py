"""Snakemake adapter: verification.csv and summary.csv of a soil's adaptive designs."""

import gc

from soilcal.chain.adaptive import verification_files
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    w, i, o = snakemake.wildcards, snakemake.input, snakemake.output  # noqa: F821
    df = verification_files(w.soil, snakemake.params.soil, snakemake.params.stage_dirs, i.targets,  # noqa: F821
                            i.results, i.verification_runs, o.verification, o.summary)
    print(df.to_string(index=False))

# the job's work is done and its files written: move every object to the collector's permanent
# generation, so that the interpreter's exit does not traverse the heap once more (as the DEM
# jobs do, dem_point.py)
gc.freeze()
