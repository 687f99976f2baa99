from soilcal.logs import redirect
from soilcal.replay.run import write_regression

with redirect(snakemake.log[0]):
    write_regression(snakemake.params.stage, snakemake.input.table, dict(snakemake.output.items()))
