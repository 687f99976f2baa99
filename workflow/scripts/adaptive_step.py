"""Snakemake adapter: one iteration of the adaptive design of a case (checkpoint adaptive_step)."""

from soilcal.chain.adaptive import step_files
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    w, i = snakemake.wildcards, snakemake.input  # noqa: F821
    rec = step_files(snakemake.params.soil, w.stage, w.case, snakemake.params.iteration,  # noqa: F821
                     i.targets, i.steps, i.runs, snakemake.output[0],  # noqa: F821
                     upstream_csv=i.upstream if hasattr(i, "upstream") else None,
                     shared_step_paths=list(i.shared_steps), shared_run_paths=list(i.shared_runs))
    print(rec["status"] + ":", rec["message"])
