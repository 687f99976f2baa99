"""Snakemake adapter: one verification seed of one case at its calibrated set."""

import numba

from soilcal.chain.files import restart_dir
from soilcal.chain.verify import run_verification_point
from soilcal.dem._kernel_cache import kernel_line
from soilcal.logs import redirect

with redirect(snakemake.log[0]):  # noqa: F821
    numba.set_num_threads(snakemake.threads)  # noqa: F821
    spec = snakemake.params.spec  # noqa: F821
    print(spec.get("not_run") or f"{spec['soil']} {spec['stage']} {spec['case']} seed {spec['seed']}: {spec['levels']}")
    same = list(getattr(snakemake.input, "same", None) or [])  # noqa: F821
    if same:
        print(f"case {spec['same_as']} simulates the same set, responses and seed: its rows are copied")
    df = run_verification_point({k: v for k, v in spec.items() if k != "same_as"}, snakemake.output[0],  # noqa: F821
                                threads=snakemake.threads, restart_dir=restart_dir(snakemake.output[0]),  # noqa: F821
                                copy_from=same[0] if same else None)
    print(df[["response", "preset", "value", "status", "error"]].to_string(index=False))
    print(kernel_line())
