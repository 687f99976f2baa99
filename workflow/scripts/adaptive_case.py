"""Snakemake adapter: the stopped adaptive design of one case (rule adaptive_case)."""

import gc

from soilcal.chain.adaptive import case_files
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    w, i, o = snakemake.wildcards, snakemake.input, snakemake.output  # noqa: F821
    res = case_files(snakemake.params.soil, w.stage, w.case, i.targets, i.steps, i.runs,  # noqa: F821
                     [o.runs, o.surrogates, o.region, o.result, o.verification_runs],
                     upstream_csv=i.upstream if hasattr(i, "upstream") else None)
    print(res["status"] + ":", res["message"], f"({res['runs']} runs)")

# the job's work is done and its files written: move every object to the collector's permanent
# generation, so that the interpreter's exit does not traverse the heap once more (as the DEM
# jobs do, dem_point.py)
gc.freeze()
