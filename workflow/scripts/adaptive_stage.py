"""Snakemake adapter: optimum.csv and identifiability.csv of a stage's adaptive designs."""

from soilcal.chain.adaptive import stage_files, stage_log_lines
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    w, i, o = snakemake.wildcards, snakemake.input, snakemake.output  # noqa: F821
    opt = stage_files(snakemake.params.soil, w.stage, i.results, i.regions,  # noqa: F821
                      [o.stage, o.optimum, o.identifiability],
                      upstream_csv=i.upstream if hasattr(i, "upstream") else None)
    print(opt.to_string(index=False))
    for line in stage_log_lines(o.stage):
        print(line)
