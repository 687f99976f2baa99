"""A photo measurement (the `soilcal image` commands, measure_manifest of the workflow's photo
jobs) runs numpy without transparent huge pages, unless the environment says otherwise; loading
a soil (which imports soilcal.imaging, as the Snakemake process does) changes neither numpy's
setting nor the environment the jobs inherit."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PROBE = f"""
import os, numpy._core.multiarray as m
from soilcal.config.load import load_soil
load_soil({str(ROOT / "config/soils/cinnamon-soil.yaml")!r}, {str(ROOT / "resources")!r})
print(m._get_madvise_hugepage(), os.environ.get("NUMPY_MADVISE_HUGEPAGE"))
from soilcal.imaging import huge_pages_off
huge_pages_off()
print(m._get_madvise_hugepage(), os.environ.get("NUMPY_MADVISE_HUGEPAGE"))
"""


def _probe(value: str | None) -> list[str]:
    env = {k: v for k, v in os.environ.items() if k != "NUMPY_MADVISE_HUGEPAGE"}
    env["PYTHONPATH"] = str(ROOT / "src")
    if value is not None:
        env["NUMPY_MADVISE_HUGEPAGE"] = value
    return subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True, text=True,
                          check=True).stdout.split("\n")[:2]


@pytest.mark.parametrize("given, loaded, measuring", [
    (None, "True None", "False None"),  # numpy's default until a measurement, then off here only
    ("1", "True 1", "True 1"),          # the user's choice kept
    ("0", "False 0", "False 0"),
])
def test_huge_pages_off_for_a_measurement_unless_the_environment_says(given, loaded, measuring):
    assert _probe(given) == [loaded, measuring]


def test_the_image_commands_and_the_workflow_s_photo_jobs_turn_them_off():
    from soilcal.imaging import cli, manifest

    src = Path(cli.__file__).read_text()
    for handler in ("_pile", "_drum", "_furrow", "_soil"):
        body = src.split(f"def {handler}(args):\n", 1)[1]
        assert body.lstrip().startswith("huge_pages_off()"), handler
    assert "huge_pages_off()" in Path(manifest.__file__).read_text().split("def measure_manifest", 1)[1][:1500]
