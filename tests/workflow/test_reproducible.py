"""Same inputs, same tables: a second run from an empty results/, with the DEM jobs on two
Numba threads instead of one, gives the tiny run's screening stage file for file."""

from __future__ import annotations

import pytest

from soilcal.chain.compare import IDENTICAL, VOLATILE_ONLY, compare_trees
from wfutil import TINY_SOILS, copy_workflow, make_tiny, run

STAGE = "results/cinnamon-soil/dem/pb"


@pytest.fixture(scope="module")
def second(tmp_path_factory):
    tmp = make_tiny(copy_workflow(tmp_path_factory.mktemp("again"), TINY_SOILS), threads=2)
    run(tmp, "--cores", "2", f"{STAGE}/anova.csv", f"{STAGE}/effects.csv", f"{STAGE}/fit.csv")
    return tmp


def test_a_second_run_on_two_threads_gives_the_same_tables(tiny_dem_run, second):
    comps = [c for c in compare_trees(tiny_dem_run / STAGE, second / STAGE)
             if not c.path.startswith("figures/")]
    outcome = {c.path: c.outcome for c in comps}
    # every table of the stage was written by both runs
    assert {"design.csv", "responses.csv", "anova.csv", "coefficients.csv", "effects.csv", "fit.csv",
            "stage.json"} <= set(outcome)
    assert sum(p.startswith("runs/") for p in outcome) == 12
    bad = {c.path: c.detail for c in comps if c.outcome not in (IDENTICAL, VOLATILE_ONLY)}
    assert not bad, bad
    # the DEM run rows differ in their wall-clock seconds and the thread count they record, nothing else
    for c in comps:
        if c.path.startswith("runs/"):
            assert c.outcome == VOLATILE_ONLY and c.detail == "wall_s, threads", (c.path, c.detail)
        elif c.path != "responses.csv":
            assert c.outcome == IDENTICAL, c.path
