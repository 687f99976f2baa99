"""Snakemake adapter: a DEM stage's runs gathered into its response table."""

import pandas as pd

from soilcal.chain.files import read_stage, write_csv
from soilcal.chain.sources import gather_runs, read_runs
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    stage = read_stage(snakemake.input.stage)  # noqa: F821
    df = gather_runs(stage, pd.read_csv(snakemake.input.design), read_runs(snakemake.input.runs))  # noqa: F821
    write_csv(df, snakemake.output[0])  # noqa: F821
    failed = df[df["status"] != "ok"]
    print(f"{len(df)} points, {len(failed)} failed")
    for _, r in failed.iterrows():
        print(" ", r.iloc[0], r["error"])
