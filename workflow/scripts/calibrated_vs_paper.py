"""Snakemake adapter: calibrated_vs_paper.csv of one soil."""

from soilcal.chain.verify import write_calibrated_vs_paper
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    soil = snakemake.wildcards.soil  # noqa: F821
    dirs = {s: f"results/{soil}/dem/{s}" for s in snakemake.params.stages}  # noqa: F821
    df = write_calibrated_vs_paper(snakemake.params.soil, snakemake.params.stages, dirs,  # noqa: F821
                                   snakemake.output[0], set_file=snakemake.params.set_file)  # noqa: F821
    print(df.to_string(index=False))
