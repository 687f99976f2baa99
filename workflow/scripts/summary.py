"""Snakemake adapter: results/summary.csv and its figure (every DEM-calibrated soil)."""

from soilcal.chain.verify import write_summary
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    df = write_summary(snakemake.params.soils, snakemake.input.verification, snakemake.input.responses,  # noqa: F821
                       snakemake.output.table, snakemake.output.figures)  # noqa: F821
    print(df.to_string(index=False))
