"""The tiny DEM calibration run shared by the workflow tests (one run per test session)."""

from __future__ import annotations

from pathlib import Path

import pytest

from wfutil import REPLAY_SOIL, TINY_SOILS, copy_workflow, make_tiny, replay_only, run


@pytest.fixture(scope="session")
def tiny_dem_run(tmp_path_factory) -> Path:
    """A workflow copy after ``snakemake --cores 2`` of the tiny run, from an empty results/:
    the cinnamon soil calibrated on the DEM and replayed (``wfutil.make_tiny``), and a second
    soil replayed from its printed tables beside it (``wfutil.replay_only``)."""
    tmp = copy_workflow(tmp_path_factory.mktemp("dem"), TINY_SOILS + [REPLAY_SOIL])
    tmp = replay_only(make_tiny(tmp))
    run(tmp, "--cores", "2")
    return tmp
