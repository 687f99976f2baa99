"""Snakemake adapter: verification bars, or the tool-test curves and bars, of one soil."""

from pathlib import Path

import pandas as pd

from soilcal import plots
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    out = Path(snakemake.output[0])  # noqa: F821
    out.mkdir(parents=True, exist_ok=True)
    soil = snakemake.wildcards.soil  # noqa: F821
    if "verification" in snakemake.input.keys():  # noqa: F821
        df = pd.read_csv(snakemake.input.verification)  # noqa: F821
        paths = plots.verification_bars(df, out / "verification", title=f"{soil}: verification at the calibrated set")
    else:
        df = pd.read_csv(snakemake.input.tools, dtype={"covariate_value": str})  # noqa: F821
        paths = plots.tool_curves(df, out / "tool") + plots.tool_bars(df, out / "tool")
    print("\n".join(map(str, paths)))
