"""The tiny DEM calibration run shared by the workflow tests (one run per test session)."""

from __future__ import annotations

from pathlib import Path

import pytest

from wfutil import TINY_SOILS, copy_workflow, make_tiny, run


@pytest.fixture(scope="session")
def tiny_dem_run(tmp_path_factory) -> Path:
    """A workflow copy after ``snakemake --cores 2`` of the tiny run, from an empty results/."""
    tmp = make_tiny(copy_workflow(tmp_path_factory.mktemp("dem"), TINY_SOILS))
    run(tmp, "--cores", "2")
    return tmp
