"""Snakemake adapter: one DEM design point (rule dem_point), Numba threads from the job."""

import numba

from soilcal.chain.files import restart_dir
from soilcal.chain.sources import run_point
from soilcal.dem._kernel_cache import kernel_line
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    numba.set_num_threads(snakemake.threads)  # noqa: F821
    spec = snakemake.params.spec  # noqa: F821
    print(f"{spec['soil']} {spec['stage']} run {spec['run']} seed {spec['seed']}: {spec['levels']}")
    df = run_point(spec, snakemake.output[0], threads=snakemake.threads,  # noqa: F821
                   restart_dir=restart_dir(snakemake.output[0]))  # noqa: F821
    print(df[["response", "value", "sd", "n", "status", "error"]].to_string(index=False))
    print(kernel_line())
