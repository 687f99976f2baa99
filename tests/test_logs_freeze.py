"""A workflow job's log block (soilcal.logs.redirect) ends the job: leaving it without an error
moves every object to the garbage collector's permanent generation; an input error does not
get that far (status 2, one line)."""

from __future__ import annotations

import gc

import pytest

from soilcal.errors import InputError
from soilcal.logs import redirect


@pytest.fixture(autouse=True)
def _thaw():
    gc.unfreeze()
    yield
    gc.unfreeze()


@pytest.mark.parametrize("to_log", [True, False])
def test_a_block_that_ends_freezes_the_heap(tmp_path, to_log):
    with redirect(tmp_path / "job.log" if to_log else None):
        assert gc.get_freeze_count() == 0
    assert gc.get_freeze_count() > 0


def test_a_block_that_fails_does_not(tmp_path):
    with pytest.raises(SystemExit), redirect(tmp_path / "job.log"):
        raise InputError("soil.yaml", "seed", "an integer", "x")
    assert gc.get_freeze_count() == 0
