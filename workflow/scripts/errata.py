import gc

from soilcal.logs import redirect
from soilcal.chain.files import write_errata

with redirect(snakemake.log[0]):
    df = write_errata(snakemake.params.soil, snakemake.params.published, snakemake.params.stage_dirs,
                      snakemake.output[0])
    print(f"{len(df)} errata")

# the job's work is done and its files written: move every object to the collector's permanent
# generation, so that the interpreter's exit does not traverse the heap once more (as the DEM
# jobs do, dem_point.py)
gc.freeze()
