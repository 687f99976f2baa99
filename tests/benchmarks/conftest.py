"""Loading a benchmark script (``benchmarks/*.py``) as a module, with ``benchmarks/`` on the
path for its own imports (``_report``) while the test module runs."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[2] / "benchmarks"


@pytest.fixture(scope="module")
def load_benchmark():
    """A function ``(script, name) -> module`` loading ``benchmarks/<script>`` under ``name``."""
    def load(script: str, name: str):
        spec = importlib.util.spec_from_file_location(name, BENCH / script)
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        return mod

    sys.path.insert(0, str(BENCH))
    try:
        yield load
    finally:
        sys.path.remove(str(BENCH))
