"""The verdict says what is true of a table: that it gives no measured SD (not that it has too
few rows), and that every measured value is one number."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pandas as pd

from soilcal.chain.files import write_csv
from soilcal.loop import core, files
from soilcal.loop import standin as S

REF = {"tool_speed": 1.75, "working_depth": 0.1, "moisture_content": 16.0}


def _run(tmp_path, value):
    # 12 soil-bin tests of the stand-in blade's horizontal force, no SD given
    conds = S.conditions(S.grid(1, 12, moisture=True, days=6), measures=("horizontal_force_N",))
    rng = np.random.default_rng(1)
    rows = [replace(c, responses=tuple(dict(r, measured=value(S.forces(S.BASE, c.quantities)[0], rng),
                                            measured_sd=None, n=None) for r in c.responses)) for c in conds]
    settings = core.Settings(reference=REF, bootstrap=0)
    out = core.run_inprocess("bin", rows, S.base_params, S.simulate, settings)
    plan = files._plan("bin", out.candidates, REF, settings, core.quantity_of(rows), out.skipped, out.residuals)
    write_csv(out.summary, tmp_path / "loop_summary.csv")
    return files.report("bin", out, [plan]), pd.read_csv(tmp_path / "loop_summary.csv")["verdict"].iloc[0]


def test_the_model_within_its_noise_but_no_sd_given_says_so_not_too_few_data(tmp_path):
    # the model's own values times (1 + 0.3 % noise) on 12 rows: nothing is wrong with how many
    # rows there are; what is missing is the measured uncertainty to judge 0.7 % against
    for text in _run(tmp_path, lambda f, rng: f * (1.0 + 0.003 * rng.standard_normal())):
        assert "no measured uncertainty to judge the scatter against (no measured SD given" in text, text
        assert "too few data" not in text


def test_a_table_of_one_value_throughout_is_named(tmp_path):
    # every measured force 1000 N, the simulated ones 27-206 N over the 12 conditions
    for text in _run(tmp_path, lambda f, rng: 1000.0):
        assert "every measured horizontal_force_N of plates is 1000 N over its 12 measured conditions" in text, text
        assert "is the column filled with one value?" in text


def test_a_constant_table_of_one_condition_repeated_is_not_named():
    # a condition measured twice with the same value is a repeat, not a column filled down
    u = pd.DataFrame({"measurement": "m", "measure": "F_N", "unit": "N", "simulation": ["a", "a"],
                      "measured": [5.0, 5.0], "simulated_mean": [4.0, 4.0]})
    assert core.constant_hints(u) == []


def _constant(sim, value, sd=None):
    return pd.DataFrame({"measurement": "bin", "measure": "sinkage_mm", "unit": "mm",
                         "simulation": [f"c{i}" for i in range(len(sim))], "measured": value,
                         "measured_sd": np.nan if sd is None else sd, "simulated_mean": sim})


def test_a_rounded_table_the_model_agrees_with_is_not_named():
    # sinkage read to the millimetre: 2 mm in all 12 rows, the model 1.96-2.04 mm, all of which
    # read 2 to the millimetre; a constant column is what a right model gives here
    sim = np.linspace(1.96, 2.04, 12)
    assert core.constant_hints(_constant(sim, 2.0)) == []
    # read to 0.01 mm with an SD of 0.1 mm: a spread of 0.08 mm is within +-1.96 SD of one value
    assert core.constant_hints(_constant(sim, 2.0, sd=0.1)) == []
    # the model spreading 1-3 mm cannot all read 2 to the millimetre: named
    assert core.constant_hints(_constant(np.linspace(1.0, 3.0, 12), 2.0))
    # a spread of 0.08 mm where the table is read to 0.01 mm without an SD: named
    assert core.constant_hints(_constant(sim, 2.01))


def test_a_table_of_the_other_sign_is_asked_after_its_sign_convention():
    # a draught recorded as negative: every measured value is -1 times the simulated one, a
    # relative residual of -200 % that no effect could explain
    import pandas as pd

    from soilcal.loop.core import unit_hints

    sim = [300.0, 320.0, 350.0, 390.0]
    u = pd.DataFrame({"measurement": "bin", "measure": "horizontal_force_N", "unit": "N",
                      "simulated_mean": sim, "measured": [-x for x in sim]})
    hints = unit_hints(u)
    assert len(hints) == 1 and "the other sign than the simulated in 4 of 4 rows (median ratio -1)" in hints[0]
    # the same values with the simulation's sign give no hint
    assert unit_hints(u.assign(measured=sim)) == []
