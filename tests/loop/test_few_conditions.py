"""Few measured conditions: the AICc of n observations and K estimated parameters (the residual
variance among them) is undefined where n <= K + 1 (its small-sample term 2K(K+1)/(n-K-1) has
no finite value).  A table of four conditions, one measured quantity each, cannot give an
effect beside a free uniform scale (K = 3) an AICc: such a candidate is not scored, and
``selection.csv`` and the verdict say so and how many observations it needs, where an infinite
AICc used to reject it as if it fitted infinitely badly."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from soilcal.loop import select as sl

from test_replicates import _trend_effect


def test_aicc_is_undefined_where_the_observations_do_not_exceed_the_parameters_by_two():
    # n ln(SSE/n) + 2K + 2K(K+1)/(n-K-1): n = 5, K = 3 -> 5 ln(1) + 6 + 24 / 1 = 30
    assert sl.aicc(5.0, 5, 3) == pytest.approx(30.0)
    assert math.isnan(sl.aicc(4.0, 4, 3)) and math.isnan(sl.aicc(1.0, 3, 3))
    assert sl.aicc_needs(3) == 5


def _campaign(n):
    # n conditions, one measured value each, from a model 8 % low (a load cell's calibration)
    # with a trend 0.3 x in the covariate x: the measured values 100 (1 - 0.08)(1 + 0.3 x),
    # times (1 + 0.2 % noise)
    x = np.linspace(-0.5, 0.5, n)
    rng = np.random.default_rng(3)
    measured = 100.0 * (1 - 0.08) * (1 + 0.3 * x) * (1 + rng.normal(0.0, 0.002, n))
    obs = pd.DataFrame({"simulation": [f"s{i}" for i in range(n)], "measure": "F", "measured": measured})
    return obs, sl.forward(obs, np.full(n, 100.0), {"trend": _trend_effect(x)})


def _beside_scale(sel):
    return [s for step, names, s in sel.steps if step == 1 and names == ["trend", "uniform_scale"]][0]


def test_an_effect_beside_a_uniform_scale_on_four_conditions_is_not_scored_and_the_verdict_says_why():
    from soilcal.loop import core

    obs, sel = _campaign(4)
    scaled = _beside_scale(sel)
    assert math.isnan(scaled.aicc) and math.isfinite(scaled.ref_aicc)
    assert ("AICc of the model undefined: 4 observations for 3 estimated parameters (the residual variance among "
            "them), which need 5 at least, so it cannot be scored") in scaled.reason
    assert not scaled.accepted and sel.chosen == []
    clause = core._unscored(sel, obs)
    assert "trend+uniform_scale (held-out RMS" in clause and ") could not be scored: on 4 observations" in clause
    assert "it needs 5, 1 more" in clause


def test_the_same_campaign_on_five_conditions_is_scored():
    # one more condition defines the AICc (K = 3, n = 5): the trend and the offset are found
    obs, sel = _campaign(5)
    scaled = _beside_scale(sel)
    assert math.isfinite(scaled.aicc) and scaled.accepted
    assert sel.chosen == ["trend"] and sel.with_scale
    assert scaled.theta["trend.t"] == pytest.approx(0.3, abs=0.02)
    assert scaled.theta["uniform_scale.s"] == pytest.approx(-0.08, abs=0.01)
    assert core_clause(obs, sel) == ""


def core_clause(obs, sel):
    from soilcal.loop import core

    return core._unscored(sel, obs)


def test_a_model_the_held_out_test_refused_is_not_said_to_need_more_observations():
    # four conditions 8 % low with no trend in them (100 (1 - 0.08) times 0.2 % noise): the
    # trend beside the scale cannot lower the held-out error of the scale alone by 10 % (there
    # is no trend to find), so its undefined AICc is not what kept it out, and one more
    # condition would not name it
    rng = np.random.default_rng(3)
    x = np.linspace(-0.5, 0.5, 4)
    measured = 100.0 * (1 - 0.08) * (1 + rng.normal(0.0, 0.002, 4))
    obs = pd.DataFrame({"simulation": [f"s{i}" for i in range(4)], "measure": "F", "measured": measured})
    sel = sl.forward(obs, np.full(4, 100.0), {"trend": _trend_effect(x)})
    scaled = _beside_scale(sel)
    assert math.isnan(scaled.aicc) and not scaled.accepted and sel.chosen == []
    assert scaled.rmse() > (1 - sl.MIN_IMPROVEMENT) * scaled.rmse(True)  # the held-out test refused it too
    assert core_clause(obs, sel) == ""


def test_a_model_the_paired_test_cannot_decide_on_four_conditions_is_still_said_to_need_more():
    # the trend 0.3 x is in the rows (8 % low, 2 % noise): beside the scale it lowers the
    # held-out error by far more than 10 %, but a paired test over 4 folds (3 degrees of
    # freedom) need not reach alpha; the verdict must still name it, or nothing says it
    x = np.linspace(-0.5, 0.5, 4)
    for seed in range(40):
        rng = np.random.default_rng(seed)
        measured = 100.0 * (1 - 0.08) * (1 + 0.3 * x) * (1 + rng.normal(0.0, 0.02, 4))
        obs = pd.DataFrame({"simulation": [f"s{i}" for i in range(4)], "measure": "F", "measured": measured})
        sel = sl.forward(obs, np.full(4, 100.0), {"trend": _trend_effect(x)})
        scaled = _beside_scale(sel)
        if scaled.rmse() <= (1 - sl.MIN_IMPROVEMENT) * scaled.rmse(True) and not scaled.p < 0.05:
            break
    else:
        pytest.fail("no table of 40 had the trend 10 % lower on held-out error with paired p >= 0.05")
    assert math.isnan(scaled.aicc) and not scaled.accepted
    # it is named with what the held-out test showed, the paired p that did not decide among it,
    # so that the clause does not read as if the undefined AICc alone had kept it out
    clause = core_clause(obs, sel)
    assert "trend+uniform_scale (held-out RMS" in clause and ") could not be scored" in clause, clause
    assert f"paired p {scaled.p:.2g} >= 0.05, which does not decide either" in clause, clause


def _named_effect(x, name):
    eff = _trend_effect(x)
    eff.effect.name = name
    return eff


@pytest.mark.parametrize("n", [4, 5])
def test_a_true_trend_on_few_conditions_is_not_called_a_uniform_bias(n):
    # n conditions, a trend 0.3 x over x in [-0.5, 0.5] and no offset (2 % noise): the data are
    # the trend's, a constant cannot fit them.  Beside a free uniform scale the trend cannot be
    # scored on 4 observations (AICc of 3 parameters undefined) and on 5 pays a small-sample
    # penalty of 24 against 6 for the scale alone, so that comparison cannot show it; alone it
    # beats the scale alone, and it must not be called a constant (it was, in every such table)
    x = np.linspace(-0.5, 0.5, n)
    chosen = 0
    for seed in range(10):
        rng = np.random.default_rng(100 + seed)
        measured = 100.0 * (1 + 0.3 * x) * (1 + rng.normal(0.0, 0.02, n))
        obs = pd.DataFrame({"simulation": [f"s{i}" for i in range(n)], "measure": "F", "measured": measured})
        sel = sl.forward(obs, np.full(n, 100.0), {"trend": _trend_effect(x)})
        if sel.chosen == ["trend"]:
            chosen += 1
            assert sel.uniform.accepted, sel.uniform.reason
            assert not sl.like_a_constant(sel), (seed, sel.beside_uniform.reason)
    assert chosen >= 5


def test_a_uniform_offset_on_four_conditions_is_still_told_from_an_effect_that_adds_to_every_row():
    # 4 conditions 8 % low and nothing else (2 % noise); an all-positive covariate (an
    # adhesion's share of the force, 0.6-1.0) fits the offset about as well as a scale.  It is
    # named only where it beats the scale alone in the selection's gate (paired p < 0.05), at
    # most alpha of such tables: 2 or more of 10 has a chance below 9 % at 5 %, 3 or more 1 %
    n = 4
    said = named = 0
    for seed in range(10):
        rng = np.random.default_rng(200 + seed)
        share = 0.6 + 0.4 * rng.uniform(0.0, 1.0, n)
        measured = 100.0 * (1 - 0.08) * (1 + rng.normal(0.0, 0.02, n))
        obs = pd.DataFrame({"simulation": [f"s{i}" for i in range(n)], "measure": "F", "measured": measured})
        sel = sl.forward(obs, np.full(n, 100.0), {"share": _named_effect(share, "share")})
        if sel.judged and sl.like_a_constant(sel):
            said += 1
        elif sel.chosen:
            named += 1
    assert said >= 5 and named <= 2, (said, named)


def test_a_paired_test_that_cannot_be_run_is_said_so_not_printed_as_a_p_of_nan():
    # six conditions, 8 % low with a trend 0.3 x (1 % noise), held out by test day: five on one
    # day, one on the other.  Fitted on the lone condition, an effect beside the scale has one
    # row for two parameters, so that fold cannot be predicted and the paired test has one fold:
    # it cannot be run.  The verdict must say why, not give "paired p nan"
    from soilcal.loop import core

    x = np.linspace(-0.5, 0.5, 6)
    rng = np.random.default_rng(7)
    measured = 100.0 * (1 - 0.08) * (1 + 0.3 * x) * (1 + rng.normal(0.0, 0.01, 6))
    obs = pd.DataFrame({"simulation": [f"s{i}" for i in range(6)], "measure": "F", "measured": measured,
                        "cov:day": [0, 0, 0, 0, 0, 1]})
    sel = sl.forward(obs, np.full(6, 100.0), {"trend": _trend_effect(x)}, "day")
    gate = [s for step, _, s in sel.steps if step == "gate"][-1]
    assert math.isnan(gate.p) and not gate.accepted
    clause = core._not_separated(sel, 0.05)
    assert "trend was not separated" in clause and "nan" not in clause, clause
    assert "no paired test (fewer than two folds to compare (of 2 held-out groups, 1 could" in clause, clause


def _offset_and_share(n, off, seed, t_share=0.0):
    # n conditions with two candidates: a centred trend (x over [-0.5, 0.5], shuffled) and an
    # all-positive share (0.6-1.0, an adhesion's share of the force); the measured values are
    # 100 (1 + t_share share)(1 + off) times (1 + 2 % noise)
    rng = np.random.default_rng(seed)
    trend = np.linspace(-0.5, 0.5, n)
    rng.shuffle(trend)
    share = 0.6 + 0.4 * rng.uniform(0.0, 1.0, n)
    measured = 100.0 * (1 + t_share * share) * (1 + off) * (1 + rng.normal(0.0, 0.02, n))
    obs = pd.DataFrame({"simulation": [f"s{i}" for i in range(n)], "measure": "F", "measured": measured})
    return obs, sl.forward(obs, np.full(n, 100.0), {"A": _named_effect(trend, "A"), "P": _named_effect(share, "P")})


def test_beating_the_scale_alone_does_not_name_an_effect_where_the_comparison_beside_it_is_scored():
    # six conditions 6 % high and nothing else: the all-positive share fits the offset, and
    # alone beats the scale alone, but beside the scale (AICc defined with a spare observation)
    # it does not lower the held-out error significantly: the rows show a uniform bias, and
    # the share must not be named for it
    from soilcal.loop import core

    obs, sel = _offset_and_share(6, 0.06, 920010)
    b = sel.beside_uniform
    assert sel.chosen == ["P"] and sel.uniform.accepted
    assert math.isfinite(b.aicc) and b.aicc_spare > 0 and not b.p < 0.05
    assert not sl.rule_of_one(sel) and sl.like_a_constant(sel)
    assert core._beside_clause(sel, 0.05).startswith("adds nothing beside a free uniform scale")
    assert core._judged_alone(sel, 0.05) == ""


def test_an_offset_whose_effect_the_gates_dropped_is_still_a_uniform_bias():
    # four conditions 10 % high and nothing else: where the share beats the scale alone and the
    # gates beside the scale then drop it (chosen empty, the forward step's choice judged),
    # nothing was chosen to name, so the rows' offset is the verdict, not silence
    from soilcal.loop import core

    obs, beat = _offset_and_share(4, 0.10, 913001)
    assert beat.chosen == [] and beat.judged and beat.uniform.accepted and math.isnan(beat.beside_uniform.aicc)
    assert not sl.rule_of_one(beat) and sl.like_a_constant(beat)
    clause = core._beside_clause(beat, 0.05)
    assert clause.startswith("cannot be scored beside a free uniform scale") and "alone it beats" in clause, clause
    assert "does not lower the held-out error" in clause or "gates did not keep it" in clause, clause


@pytest.mark.parametrize("n,seed,said", [(4, 940004, "could not be scored"), (5, 940003, "decided by its small-sample term")])
def test_an_effect_kept_for_beating_the_scale_alone_is_said_to_maybe_hold_an_offset(n, seed, said):
    # a share effect 0.3 and an 8 % offset on n conditions: where the comparison beside the
    # scale does not decide (AICc undefined on 4, defined on its fewest observations on 5),
    # the share is kept for beating the scale alone, and its parameter may then hold the
    # offset (fitted 0.19 for a true 0.3): the verdict must say so
    from soilcal.loop import core

    obs, sel = _offset_and_share(n, -0.08, seed, t_share=0.3)
    assert sel.chosen == ["P"] and not sel.with_scale and sl.rule_of_one(sel) and not sl.like_a_constant(sel)
    assert sel.final.theta["P.t"] < 0.25  # the offset sits in the share's parameter
    clause = core._judged_alone(sel, 0.05)
    assert said in clause and "judged against that scale alone" in clause, clause
    assert "whether a uniform bias lies beside it these rows cannot tell: its parameter may hold it" in clause, clause


def test_the_backward_gate_gives_a_finite_p_as_before():
    # eight conditions with a weak share effect (0.04, 2 % noise): the forward step takes the
    # share and the backward gate drops it with a paired test that could be run; its reason
    # keeps the form "(p 0.933)" that selection.csv has always had
    import re

    obs, sel = _offset_and_share(8, 0.0, 0, t_share=0.04)
    gate = [s for step, names, s in sel.steps if step == "gate" and names == ["P"]][-1]
    assert re.match(r"without P, as is and with a free uniform scale on both \(p 0\.\d+\): ", gate.reason), gate.reason


def test_the_warning_for_an_effect_judged_against_the_scale_alone_reaches_the_report_and_summary(tmp_path):
    # four soil-bin tests of one force each on the stand-in blade, a hidden rate effect (beta 0.3)
    # and 1 % noise: beside a free uniform scale the rate effect has no AICc (3 parameters on 4
    # observations), so it is judged against the scale alone, and the verdict written to
    # report.md and loop_summary.csv says that a uniform bias beside it would sit in its parameter
    from soilcal.chain.files import write_csv
    from soilcal.loop import core, files
    from soilcal.loop import standin as S
    from soilcal.loop import synthesize as sy

    ref = {"tool_speed": 1.75, "working_depth": 0.1, "moisture_content": 16.0}
    conds = S.conditions(S.grid(27, 4, moisture=True, days=4), measures=("horizontal_force_N",))
    table = sy.synthesize(conds, S.base_params, S.simulate, {"rate_friction": {"beta": 0.3}}, ref, {}, noise=0.01,
                          seed=37)
    settings = core.Settings(reference=ref, bootstrap=0)
    out = core.run_inprocess("bin", sy.with_measured(conds, table), S.base_params, S.simulate, settings)
    assert out.chosen == ["rate_friction"], out.verdict
    plan = files._plan("bin", out.candidates, ref, settings, core.quantity_of(conds), out.skipped, out.residuals)
    report = files.report("bin", out, [plan])
    write_csv(out.summary, tmp_path / "loop_summary.csv")
    summary = pd.read_csv(tmp_path / "loop_summary.csv")["verdict"].iloc[0]
    for text in (report, summary):
        beta = out.theta["rate_friction.beta"]
        assert (f"explained by rate_friction (rate_friction.beta {beta:.3g}, 95 %: " in text
                and "); beside a free uniform scale it could not be scored (" in text)
        assert "so it was judged against that scale alone, which it beats (held-out RMS" in text
        assert "whether a uniform bias lies beside it these rows cannot tell: its parameter may hold it" in text
