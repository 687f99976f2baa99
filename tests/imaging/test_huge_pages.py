"""A process that loads numpy through soilcal.imaging (the `soilcal image` commands, the
workflow's photo jobs) runs numpy without transparent huge pages, unless the environment says
otherwise: the photo measurement's many short-lived full-frame arrays cost more system time
faulted in as huge pages than they save."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

SRC = str(Path(__file__).resolve().parents[2] / "src")
PROBE = "import soilcal.imaging, numpy._core.multiarray as m; print(m._get_madvise_hugepage())"


def _probe(value: str | None) -> str:
    env = {k: v for k, v in os.environ.items() if k != "NUMPY_MADVISE_HUGEPAGE"}
    env["PYTHONPATH"] = SRC
    if value is not None:
        env["NUMPY_MADVISE_HUGEPAGE"] = value
    return subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True, text=True,
                          check=True).stdout.strip()


@pytest.mark.parametrize("given, expected", [(None, "False"), ("1", "True"), ("0", "False")])
def test_huge_pages_off_unless_the_environment_says(given, expected):
    assert _probe(given) == expected
