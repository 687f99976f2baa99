"""Snakemake adapter: tool_verification.csv of one soil."""

from soilcal.chain.verify import write_tool_verification
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    df = write_tool_verification(snakemake.params.soil_path, snakemake.params.resources_root,  # noqa: F821
                                 list(snakemake.input.runs), snakemake.params.runs, snakemake.output[0])  # noqa: F821
    print(df.to_string(index=False))
