"""Snakemake adapter: final.csv of one stage (the set each case ends with)."""

from soilcal.chain.refine import write_final
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    i = snakemake.input  # noqa: F821
    df = write_final(snakemake.params.soil, i.stage, i.targets, i.optimum, i.refined, i.runs,  # noqa: F821
                     i.refined_runs, snakemake.output[0])  # noqa: F821
    print(df.to_string(index=False))
