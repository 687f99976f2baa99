"""Snakemake adapter: verification bars and per-case progress of a soil's adaptive designs."""

from soilcal.chain.adaptive import figure_files
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    paths = figure_files(snakemake.wildcards.soil, snakemake.input.verification,  # noqa: F821
                         snakemake.params.cases, snakemake.output[0])  # noqa: F821
    print("\n".join(map(str, paths)))
