"""Snakemake adapter: simulation.csv of one soil (rule simulation_setup)."""

from pathlib import Path

from soilcal.chain.provenance import write_simulation_setup
from soilcal.config.load import Soil
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    p = snakemake.params  # noqa: F821
    soil = Soil(path=Path(p.path), data=p.soil, resources_root=Path(p.resources_root), defaulted=tuple(p.defaulted))
    df = write_simulation_setup(soil, snakemake.output[0], design_override=p.design)  # noqa: F821
    print(df[df["origin"] != "named setup"].to_string(index=False))
