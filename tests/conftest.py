"""Tests run on two workers (pytest-xdist, ``-n 2 --dist loadfile`` in pyproject.toml): a test
file goes to one worker whole, so its module-scoped fixtures are built once.  The session
fixture ``tiny_dem_run`` (the tiny DEM calibration, minutes) would be built once per worker that
runs a test using it: all its users live in one file.  The workflow tests (whole Snakemake
runs, minutes per file) are collected early, and ``--no-loadscope-reorder`` (pyproject.toml)
has the workers take the files in that order (without it pytest-xdist queues the files by their
number of tests, most first, and these few-test files came late), so that the workers start them
early and the short tests fill in beside them instead of one long file running alone at the end.

Ahead of them come the longest files that call no DEM kernel (``NO_DEM``: photo measurement, at
least three minutes of test time in CI's ``--durations`` list): CI (``.ci/run``) starts the
tests while ``soilcal scenario compile`` still compiles the engine (about two minutes on one
core), and a test or workflow job that reaches the engine's time loop meanwhile waits for it
(:mod:`soilcal.dem._kernel_cache`), so the workers measure photos while the kernels compile."""

from __future__ import annotations

import os

import pytest

# Each worker runs on one of the machine's cores, so its BLAS (numpy's OpenBLAS: statsmodels,
# scipy's and scikit-learn's fits) runs on one thread: two BLAS threads per worker made the two
# workers' small least-squares and Gaussian-process fits wait on each other's threads (CPU of
# the loop and chain tests ~10 % higher, wall time up to half again as long).  Set before numpy
# loads in this process (conftest is imported before the test modules), inherited by the
# workers and the processes the tests start (Snakemake sets it per job from its threads).
# A value given in the environment is kept.
for _var in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
# numpy asks the kernel for transparent huge pages (madvise) for each array of 4 MB or more, and
# the photo tests make many full-frame float arrays that live for milliseconds: on the 2-core
# test machine faulting them in as huge pages cost several times the system time of small pages
# (test_furrow_stress 18.0 -> 4.9 s system CPU, 60.6 -> 50.8 s in all, with them off).  Set
# before numpy loads, as above, and kept when given in the environment.
os.environ.setdefault("NUMPY_MADVISE_HUGEPAGE", "0")


#: files that run no DEM (no soilcal.dem.scenarios, engine or workflow), the longest first
NO_DEM = ("tests/imaging/test_pile_stress.py", "tests/imaging/test_imaging.py",
          "tests/imaging/test_furrow_stress.py")
FIRST = ("tests/workflow/",)


def _rank(item):
    path = item.nodeid.split("::")[0]
    if path in NO_DEM:
        return NO_DEM.index(path)
    return len(NO_DEM) + (0 if path.startswith(FIRST) else 1)


def pytest_collection_modifyitems(config, items):
    items.sort(key=_rank)  # stable: the order within each part stays
    files = sorted({it.nodeid.split("::")[0] for it in items
                    if "tiny_dem_run" in getattr(it, "fixturenames", ())})
    if len(files) > 1 and os.environ.get("PYTEST_XDIST_WORKER"):
        raise pytest.UsageError(f"tiny_dem_run is used in {', '.join(files)}: on several workers it is "
                                "built once per worker; keep its users in one file (or run with -n 0)")
