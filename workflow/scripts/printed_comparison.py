"""Snakemake adapter: DEM responses against the paper's at the printed design points."""

import pandas as pd

from soilcal.chain.files import read_stage, write_csv
from soilcal.chain.sources import printed_comparison
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    out = printed_comparison(read_stage(snakemake.input.stage), snakemake.params.printed_stage,  # noqa: F821
                             pd.read_csv(snakemake.input.responses), pd.read_csv(snakemake.input.table))  # noqa: F821
    points = out["points"].assign(kind="point")
    summary = out["summary"].assign(kind="summary")
    write_csv(pd.concat([summary, points], ignore_index=True), snakemake.output[0])  # noqa: F821
    print(out["summary"].to_string(index=False))
