"""Params read through checkpoints wait for them (``after_checkpoints`` in
workflow/rules/common.smk): while a checkpoint they read is incomplete they are Snakemake's own
placeholder, as Snakemake makes a params value that waits for a checkpoint among the inputs,
instead of an error that stops the whole run; otherwise the value itself."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _function(name: str):
    text = (ROOT / "workflow/rules/common.smk").read_text()
    m = re.search(rf"^def {name}\(.*?(?=^\S)", text, flags=re.M | re.S)
    assert m, name
    ns: dict = {}
    exec(m.group(0), ns)  # noqa: S102 - the workflow's own source
    return ns[name]


def test_a_param_waits_for_an_incomplete_checkpoint():
    from snakemake.common.tbdstring import TBDString
    from snakemake.exceptions import IncompleteCheckpointException

    wrap = _function("after_checkpoints")

    def reads_a_checkpoint(w):
        raise IncompleteCheckpointException(None, "results/s/dem/bbd/refined.csv")

    def complete(w):
        return {"m/1": "abc"}

    waiting = wrap(reads_a_checkpoint)(None)
    assert isinstance(waiting, TBDString)
    assert wrap(complete)(None) == {"m/1": "abc"}
    assert wrap(complete).__name__ == "complete"

    def broken(w):
        raise KeyError("soil")

    with pytest.raises(KeyError):  # any other error still stops the run
        wrap(broken)(None)


@pytest.mark.parametrize("smk, param", [("verify.smk", "runs=after_checkpoints(tool_run_map)"),
                                        ("loop.smk", "files=after_checkpoints(tool_file_map)")])
def test_the_rules_whose_params_read_the_final_sets_wait(smk, param):
    assert param in (ROOT / "workflow/rules" / smk).read_text()
