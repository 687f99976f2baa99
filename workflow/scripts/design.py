"""Snakemake adapter: the stage a source runs and its design (checkpoint design)."""

from soilcal.chain.files import write_stage_design
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    info = write_stage_design(
        snakemake.wildcards.source, snakemake.params.stage, snakemake.params.soil,  # noqa: F821
        dict(snakemake.input.items()), dict(snakemake.output.items()))  # noqa: F821
    print("design equals the printed one as a set of rows:", info["equal"])
    if info.get("generator_columns"):
        print("factor -> generator column, as printed:", info["generator_columns"])
    print("stage:", info.get("derivation", ""))
    for line in info.get("fixed", []):
        print("fixed:", line)
    for line in info.get("fixed_warnings", []) + info.get("fixed_not_used", []):
        print("warning:", line)
