"""Snakemake adapter: one measured tool/process condition at the calibrated set (tool_point), or with an effect of the measured-data loop switched on (loop_point)."""

import numba

from soilcal.chain.files import restart_dir
from soilcal.chain.verify import run_tool_point
from soilcal.dem._kernel_cache import kernel_line
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    numba.set_num_threads(snakemake.threads)  # noqa: F821
    job = snakemake.params.job  # noqa: F821
    print(job.get("not_run") or f"{', '.join(job['measures'])}: {len(job['specs'])} seeds")
    df = run_tool_point(job, snakemake.output[0], threads=snakemake.threads,  # noqa: F821
                        restart_dir=restart_dir(snakemake.output[0]))  # noqa: F821
    print(df[["measure", "seed", "value", "status", "error"]].to_string(index=False))
    print(kernel_line())
