"""Snakemake adapter: verify_seeds.csv of one stage (the seeds of its second verification stage)."""

from soilcal.chain.verify import write_seeds
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    i = snakemake.input  # noqa: F821
    df = write_seeds(snakemake.params.soil, i.stage, i.optimum, i.targets, i.runs,  # noqa: F821
                     snakemake.params.preset, snakemake.output[0])  # noqa: F821
    print(df.to_string(index=False))
