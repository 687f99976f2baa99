"""Snakemake adapter: the second round's candidate effects of one soil."""

from pathlib import Path

from soilcal.logs import redirect
from soilcal.loop.files import more_files

with redirect(snakemake.log[0]):  # noqa: F821
    plan = more_files(snakemake.params.soil_path, snakemake.params.resources_root,  # noqa: F821
                      Path(snakemake.input.plan).parent, snakemake.params.effect_files,  # noqa: F821
                      snakemake.output[0])  # noqa: F821
    print("second-round candidates:", ", ".join(plan["candidates"]) or "none")
