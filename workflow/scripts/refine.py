"""Snakemake adapter: refined.csv of one stage (the second calibration round)."""

from soilcal.chain.refine import write_refined
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    i = snakemake.input  # noqa: F821
    local = list(i.local)
    df = write_refined(i.stage, i.responses, i.targets, i.optimum, i.runs, snakemake.output[0],  # noqa: F821
                       soil_data=snakemake.params.soil, local_paths=list(i.local_runs),  # noqa: F821
                       half_width=snakemake.params.half_width, local_csv=local[0] if local else None)  # noqa: F821
    print(df.to_string(index=False))
