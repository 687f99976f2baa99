"""Snakemake adapter: the stopped adaptive design of one case (rule adaptive_case)."""

from soilcal.chain.adaptive import case_files
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    w, i, o = snakemake.wildcards, snakemake.input, snakemake.output  # noqa: F821
    res = case_files(snakemake.params.soil, w.stage, w.case, i.targets, i.steps, i.runs,  # noqa: F821
                     [o.runs, o.surrogates, o.region, o.result, o.verification_runs],
                     upstream_csv=i.upstream if hasattr(i, "upstream") else None)
    print(res["status"] + ":", res["message"], f"({res['runs']} runs)")
