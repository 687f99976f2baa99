"""Snakemake adapter: the targets of one soil and source (rule targets)."""

from soilcal.chain.targets import write_targets
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    images = snakemake.input.images[0] if snakemake.input.images else None  # noqa: F821
    df = write_targets(snakemake.params.soil, snakemake.wildcards.source, snakemake.output[0], images)  # noqa: F821
    print(df[["target_id", "value", "source", "printed_value"]].to_string(index=False))
