"""Snakemake adapter: measure every photo group of one soil's manifest (rule image_measure)."""

import json
import logging
from pathlib import Path

from soilcal.imaging.manifest import measure_manifest, set_aside_lines
from soilcal.logs import empty_folder, redirect

with redirect(snakemake.log[0]):  # noqa: F821
    out = Path(snakemake.output.json)  # noqa: F821
    figdir = Path(snakemake.output.figures)  # noqa: F821
    figdir.mkdir(parents=True, exist_ok=True)
    # the refusals folder holds this run's diagnostic images and a refused group's figures only:
    # those of an earlier run (a photo since replaced, a group since measured) would be read as
    # this run's (a symlink to a folder kept elsewhere: its contents; no link inside is followed)
    empty_folder(snakemake.params.refusals, "refusals folder")  # noqa: F821
    logging.info("measuring %s", snakemake.params.manifest)  # noqa: F821
    result = measure_manifest(snakemake.params.manifest, figdir, snakemake.params.threshold,  # noqa: F821
                              refusals=snakemake.params.refusals)  # noqa: F821
    for group, r in result.items():
        logging.info("%s: %s", group, {k: r[k] for k in ("angle_deg", "spread_deg", "area_mm2") if k in r})
        # as soilcal image warns on stderr: each photo or frame set aside, and each frame flagged
        # low that the user accepted (accept_low), averaged into the group's angle all the same
        for line in set_aside_lines(r, group):
            logging.warning("%s", line)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=2) + "\n")
