"""Snakemake adapter: fit, score and choose the effects; summary, report and figures."""

import gc
from pathlib import Path

from soilcal.logs import redirect
from soilcal.loop.files import select_files

with redirect(snakemake.log[0]):  # noqa: F821
    out = select_files(snakemake.params.soil_path, snakemake.params.resources_root,  # noqa: F821
                       Path(snakemake.output.summary).parent, snakemake.params.effect_files)  # noqa: F821
    print(out.verdict)
    print(out.summary.to_string(index=False))

# the job's work is done and its files written: move every object to the collector's permanent
# generation, so that the interpreter's exit does not traverse the heap once more (as the DEM
# jobs do, dem_point.py)
gc.freeze()
