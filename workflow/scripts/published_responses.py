"""Snakemake adapter: the printed table as the published source's responses."""

from soilcal.chain.sources import published_responses
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    print(published_responses(snakemake.input.table, snakemake.output[0]))  # noqa: F821
