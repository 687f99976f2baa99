from soilcal.logs import redirect
from soilcal.replay.run import write_design

with redirect(snakemake.log[0]):
    info = write_design(snakemake.params.stage, snakemake.input.table or None,
                        snakemake.output.design, snakemake.output.check)
    print("printed design equals the generated one as a set of rows:", info["equal"])
    if info.get("generator_columns"):
        print("factor -> generator column, as printed:", info["generator_columns"])
