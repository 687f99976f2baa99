"""Test distribution over workers (pytest-xdist, ``--dist loadgroup`` in pyproject.toml):
each test file is one group, so a module-scoped fixture is built once, on one worker; the
files that use the tiny DEM calibration run (``tiny_dem_run``, a session fixture) form one
group, so that run is made once."""

from __future__ import annotations

import pytest

TINY = "tiny_dem_run"


def pytest_collection_modifyitems(config, items):
    path = lambda item: item.nodeid.split("::")[0]  # noqa: E731
    tiny_files = {path(it) for it in items if TINY in getattr(it, "fixturenames", ())}
    for it in items:
        if any(m.name == "xdist_group" for m in it.iter_markers()):
            continue
        it.add_marker(pytest.mark.xdist_group(TINY if path(it) in tiny_files else path(it)))
