"""The tiny DEM calibration through a real SLURM cluster gives the local run's tables.

Runs only with ``SOILCAL_SLURM=1``, a SLURM cluster answering ``sinfo`` (``sudo
benchmarks/slurm/single_node.sh`` starts a one-node cluster on this machine) and
``snakemake-executor-plugin-slurm`` installed; it takes several minutes
(``benchmarks/slurm.py`` is the same comparison, with a kill and a resume, as a benchmark).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess

import pytest

from soilcal.chain.compare import DIFFERS, ONLY_A, ONLY_B, compare_trees
from wfutil import TINY_SOILS, copy_workflow, make_tiny, run


def _why_not() -> str:
    if os.environ.get("SOILCAL_SLURM") != "1":
        return "set SOILCAL_SLURM=1 to run the workflow through a SLURM cluster"
    if shutil.which("sinfo") is None:
        return "no SLURM client (sinfo) on this machine"
    p = subprocess.run(["sinfo", "-h", "-o", "%T"], capture_output=True, text=True)
    if p.returncode != 0 or not p.stdout.strip():
        return "no SLURM cluster answers sinfo (sudo benchmarks/slurm/single_node.sh starts one)"
    try:
        import snakemake_executor_plugin_slurm  # noqa: F401
    except ImportError:
        return "snakemake-executor-plugin-slurm is not installed"
    return ""


pytestmark = pytest.mark.skipif(bool(_why_not()), reason=_why_not() or "-")


def test_the_cluster_run_gives_the_local_tables(tmp_path):
    # the local run made here, not the session's tiny_dem_run: the users of that fixture share
    # one test file (tests/conftest.py), and this opt-in test stays apart
    for d in ("local", "cluster"):
        (tmp_path / d).mkdir()
    local = make_tiny(copy_workflow(tmp_path / "local", TINY_SOILS))
    run(local, "--cores", "2")
    cluster = make_tiny(copy_workflow(tmp_path / "cluster", TINY_SOILS))
    out = run(cluster, "--profile", "profiles/slurm")
    text = out.stdout + out.stderr
    # every DEM job went through SLURM, the light rules ran here
    assert len(re.findall(r"has been submitted with SLURM jobid \d+", text)) > 30
    assert not re.search(r"rule_(design|regression|figures)/", text)
    comps = compare_trees(local / "results", cluster / "results")
    assert sum(c.path.startswith("cinnamon-soil/dem/") and "/runs/" in c.path for c in comps) > 30
    bad = [(c.path, c.outcome, c.detail) for c in comps if c.outcome in (DIFFERS, ONLY_A, ONLY_B)]
    assert not bad, bad
    assert "Nothing to be done" in run(cluster, "-n", "--profile", "profiles/slurm").stdout
