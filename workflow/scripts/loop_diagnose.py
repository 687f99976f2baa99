"""Snakemake adapter: residuals, diagnosis and the plan of candidate effects of one soil."""

from pathlib import Path

from soilcal.logs import redirect
from soilcal.loop.files import diagnose_files

with redirect(snakemake.log[0]):  # noqa: F821
    plan = diagnose_files(snakemake.params.soil_path, snakemake.params.resources_root,  # noqa: F821
                          snakemake.params.files, Path(snakemake.output.plan).parent)  # noqa: F821
    print("candidates:", ", ".join(plan["candidates"]) or "none")
