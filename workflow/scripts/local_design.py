"""Snakemake adapter: local.csv of one stage (the local design at the first set of every case
the second round would move because of a bias)."""

from soilcal.chain.refine import write_local
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    i = snakemake.input  # noqa: F821
    df = write_local(i.stage, i.responses, i.targets, i.optimum, i.runs, snakemake.output[0],  # noqa: F821
                     soil_data=snakemake.params.soil, half_width=snakemake.params.half_width)  # noqa: F821
    print(df.to_string(index=False) if len(df) else "no case needs a local design")
