from soilcal.logs import redirect
from soilcal.replay.run import write_optimum

with redirect(snakemake.log[0]):
    write_optimum(snakemake.params.stage, snakemake.input.table, snakemake.params.targets,
                  snakemake.params.seed, snakemake.output[0])
