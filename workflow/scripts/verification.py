"""Snakemake adapter: verification.csv of one soil."""

from soilcal.chain.verify import write_verification
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    soil = snakemake.wildcards.soil  # noqa: F821
    dirs = {s: f"results/{soil}/dem/{s}" for s in snakemake.params.stages}  # noqa: F821
    refined = {s: f"{d}/refined.csv" for s, d in dirs.items()} if snakemake.input.refined else None  # noqa: F821
    df = write_verification(snakemake.params.soil, snakemake.params.stages, dirs,  # noqa: F821
                            snakemake.input.targets, snakemake.input.runs, snakemake.output[0],  # noqa: F821
                            refined_paths=refined, refined_run_paths=snakemake.input.refined_runs,  # noqa: F821
                            seed_paths=snakemake.input.seeds)  # noqa: F821
    print(df.to_string(index=False))
