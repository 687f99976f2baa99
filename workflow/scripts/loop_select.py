"""Snakemake adapter: fit, score and choose the effects; summary, report and figures."""

from pathlib import Path

from soilcal.logs import redirect
from soilcal.loop.files import select_files

with redirect(snakemake.log[0]):  # noqa: F821
    out = select_files(snakemake.params.soil_path, snakemake.params.resources_root,  # noqa: F821
                       Path(snakemake.output.summary).parent, snakemake.params.effect_files)  # noqa: F821
    print(out.verdict)
    print(out.summary.to_string(index=False))
