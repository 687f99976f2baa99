"""Same inputs, same tables: DEM jobs of a second run from an empty results/ give the tiny
run's rows again, apart from the seconds they took.  (Whole runs, local against a SLURM
cluster: ``benchmarks/slurm.py``; one and two Numba threads give identical states:
``tests/dem/test_motion.py``.)"""

from __future__ import annotations

import pytest

from soilcal.chain.compare import VOLATILE_ONLY, compare_trees
from wfutil import TINY_SOILS, copy_workflow, make_tiny, run

STAGE = "results/cinnamon-soil/dem/pb"
RUNS = [1, 2, 3, 4]


@pytest.fixture(scope="module")
def second(tmp_path_factory):
    tmp = make_tiny(copy_workflow(tmp_path_factory.mktemp("again"), TINY_SOILS))
    run(tmp, "--cores", "2", *(f"{STAGE}/runs/{r}.csv" for r in RUNS))
    return tmp


def test_a_second_run_gives_the_same_rows(tiny_dem_run, second):
    comps = compare_trees(tiny_dem_run / STAGE, second / STAGE)
    got = {c.path: c for c in comps if c.path.startswith("runs/")}
    assert set(got) == {f"runs/{r}.csv" for r in range(1, 13)}
    for r in RUNS:
        c = got[f"runs/{r}.csv"]
        # the DEM rows differ in the seconds the job took, nothing else
        assert c.outcome == VOLATILE_ONLY and c.detail == "wall_s", (c.path, c.outcome, c.detail)
    # the design the points were read from is the same file
    assert {c.path: c.outcome for c in comps}["design.csv"] == "identical"
