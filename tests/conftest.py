"""Tests run on two workers (pytest-xdist, ``-n 2 --dist loadfile`` in pyproject.toml): a test
file goes to one worker whole, so its module-scoped fixtures are built once.  The session
fixture ``tiny_dem_run`` (the tiny DEM calibration, minutes) would be built once per worker that
runs a test using it: all its users live in one file.  The workflow tests (whole Snakemake
runs, minutes per file) are collected first, and ``--no-loadscope-reorder`` (pyproject.toml)
has the workers take the files in that order (without it pytest-xdist queues the files by their
number of tests, most first, and these few-test files came late), so that the workers start them
first and the short tests fill in beside them instead of one long file running alone at the end."""

from __future__ import annotations

import os

import pytest


FIRST = ("tests/workflow/",)


def pytest_collection_modifyitems(config, items):
    items.sort(key=lambda it: not it.nodeid.startswith(FIRST))  # stable: the order within each part stays
    files = sorted({it.nodeid.split("::")[0] for it in items
                    if "tiny_dem_run" in getattr(it, "fixturenames", ())})
    if len(files) > 1 and os.environ.get("PYTEST_XDIST_WORKER"):
        raise pytest.UsageError(f"tiny_dem_run is used in {', '.join(files)}: on several workers it is "
                                "built once per worker; keep its users in one file (or run with -n 0)")
