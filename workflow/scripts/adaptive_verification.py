"""Snakemake adapter: verification.csv and summary.csv of a soil's adaptive designs."""

from soilcal.chain.adaptive import verification_files
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    w, i, o = snakemake.wildcards, snakemake.input, snakemake.output  # noqa: F821
    df = verification_files(w.soil, snakemake.params.soil, snakemake.params.stage_dirs, i.targets,  # noqa: F821
                            i.results, i.verification_runs, o.verification, o.summary)
    print(df.to_string(index=False))
