from soilcal.logs import redirect
from soilcal.replay.run import write_figures

with redirect(snakemake.log[0]):
    paths = write_figures(snakemake.wildcards.kind, snakemake.params.stage, snakemake.input.table,
                          snakemake.params.targets, snakemake.output[0],
                          snakemake.params.parameters)
    print("\n".join(map(str, paths)))
