"""Snakemake adapter: the figures of one kind for one stage (rule figures)."""

from soilcal.chain.files import read_stage, read_targets, write_figures
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    ref = snakemake.input.reference[0] if snakemake.input.reference else None  # noqa: F821
    paths = write_figures(snakemake.wildcards.kind, read_stage(snakemake.input.stage),  # noqa: F821
                          snakemake.input.responses, read_targets(snakemake.input.targets),  # noqa: F821
                          snakemake.output[0], snakemake.params.parameters,  # noqa: F821
                          reference_stage=snakemake.params.reference_stage, reference_table=ref)  # noqa: F821
    print("\n".join(map(str, paths)))
