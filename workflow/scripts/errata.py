from soilcal.logs import redirect
from soilcal.chain.files import write_errata

with redirect(snakemake.log[0]):
    df = write_errata(snakemake.params.soil, snakemake.params.published, snakemake.params.stage_dirs,
                      snakemake.output[0])
    print(f"{len(df)} errata")
