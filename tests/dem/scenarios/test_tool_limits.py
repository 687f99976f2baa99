"""Tool passes the run could not finish are refused before the bin is settled: a pass of
more steps than MAX_PASS_STEPS."""

import math

import pytest

from soilcal.dem.scenarios import bulldozing, furrow, rotary, soilbin
from soilcal.dem.scenarios.base import DemParams, merge_setup
from soilcal.errors import InputError


def _params():
    return DemParams()


def test_tool_speed_in_the_wrong_unit_is_refused_with_its_step_count(monkeypatch):
    p = _params()
    setup = merge_setup(bulldozing.setups(), "plate-line", {"speed": 0.001 / 3.6}, "<t>")
    monkeypatch.setattr(bulldozing, "settled_bin", lambda *a, **k: pytest.fail("settled"))
    s = bulldozing._settings(setup, "quick")
    s["cohesion_scale"] = soilbin.reference_cohesion(
        bulldozing._bin(s), bulldozing._bin(bulldozing._settings(bulldozing._setup("line"),
                                                                 "paper")), setup, "<t>")
    dt = soilbin.tool_time_step(bulldozing._bin(s), p)
    steps = math.ceil(0.2 / (0.001 / 3.6) / dt)
    with pytest.raises(InputError, match="setup.speed") as e:
        bulldozing.run(setup, p, "quick", use_cache=False)
    assert f"{steps:,} steps" in str(e.value)
    r = merge_setup(rotary.setups(), "rpm-150", {"forward_speed": 0.001 / 3.6}, "<t>")
    with pytest.raises(InputError, match="setup.forward_speed"):
        rotary.validate(r, "quick", "<t>", params=p)
    f = merge_setup(furrow.setups(), "yangtze-opener", {"speed": 0.001 / 3.6}, "<t>")
    with pytest.raises(InputError, match="setup.speed"):
        furrow.validate(f, "quick", "<t>", params=p)
