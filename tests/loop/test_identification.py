"""The loop on measurement tables with an effect nobody declared (``soilcal.loop.synthesize``).

The stand-in for the DEM is the Rankine passive force on a blade (soilcal.loop.standin),
driven by the same DEM parameters the effects change, with 1 % seed scatter.  A soil-bin
campaign of 18 conditions (three tools, speeds, depths, moisture, positions along the bin,
six test days) is measured with 2 % noise per repeat (three repeats), with a hidden effect:

* each effect of the library: it must be named, its parameter recovered within 25 % and
  the held-out RMS error must fall by at least 70 %;
* two effects at once: both named;
* effects outside the library (a periodic disturbance along the bin, stones, an offset that
  varies between test days): never a library effect; the verdict says "unexplained";
* no effect: no effect chosen.

The truths (hidden parameters) are the generator's inputs; three campaigns (seeds) each.  The
hidden effects move the measured forces by 5-15 % (RMS), several times the measurements'
2 % noise, so that a 70 % fall of the held-out error is possible at all.

``plastic_contact`` acts on compression tests only: its campaign is 12 confined compression
tests of the stand-in (an affine Hertz packing, rod stopped at strains of 15-30 %, stress at
10 % strain and recovered strain measured, 2 % noise per repeat).  lambda_p = 0.4 leaves the
stress alone and shrinks the recovered strain by the factor 1 - 0.4^(2/3) = 0.457; it must be
named and recovered as the others, and a compression campaign without it must choose none.
"""

from __future__ import annotations

import json
import math

import pytest
from soilcal.loop import standin as S

from soilcal.loop import core
from soilcal.loop import synthesize as sy

REFERENCE = {"tool_speed": 1.75, "working_depth": 0.1, "moisture_content": 16.0}
SEEDS = (0, 1, 2)


_RUNS = {}


def _run(hidden, disturbances, seed):
    """The loop on a campaign with ``hidden`` effects and ``disturbances``; a campaign two
    tests read (the same arguments) is run once, its outcome shared."""
    key = json.dumps([hidden, disturbances, seed], sort_keys=True)
    if key not in _RUNS:
        _RUNS[key] = _run_once(hidden, disturbances, seed)
    return _RUNS[key]


def _run_once(hidden, disturbances, seed):
    conds = S.conditions(S.grid(seed, 18, moisture=True))
    table = sy.synthesize(conds, S.base_params, S.simulate, hidden, REFERENCE, disturbances, noise=0.02,
                          seed=seed + 10)
    return core.run_inprocess("standin", sy.with_measured(conds, table), S.base_params, S.simulate,
                              core.Settings(reference=REFERENCE))


LIBRARY = {
    "rate_friction": {"beta": 0.2},
    "depth_compaction": {"g": 0.4},
    "tool_adhesion": {"gamma_a": 2.5},
    "moisture_cohesion": {"c_w": 0.1},
}


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("effect", list(LIBRARY))
def test_a_library_effect_is_named_and_recovered(effect, seed):
    theta = LIBRARY[effect]
    out = _run({effect: theta}, {}, seed)
    assert out.chosen == [effect], out.verdict
    words = []
    for k, true in theta.items():
        got = out.theta[f"{effect}.{k}"]
        assert abs(got - true) <= 0.25 * abs(true), (k, got, true)
        lo, hi = core.json.loads(out.summary["ci95"].iloc[0])[f"{effect}.{k}"]
        assert lo < got < hi
        words.append(f"{effect}.{k} {got:.3g}, 95 %: {lo:.3g} to {hi:.3g}")
    # the verdict names the effect with its parameter and that parameter's 95 % interval
    assert out.verdict == f"explained by {effect} ({'; '.join(words)})"
    assert out.summary["verdict"].iloc[0] == out.verdict
    s = out.summary.iloc[0]
    assert s["rmse_after_percent"] <= 0.3 * s["rmse_before_percent"], (s["rmse_before_percent"], s["rmse_after_percent"])


@pytest.mark.parametrize("seed", SEEDS)
def test_two_effects_at_once_are_both_named(seed):
    hidden = {"rate_friction": {"beta": 0.2}, "depth_compaction": {"g": 0.4}}
    out = _run(hidden, {}, seed)
    assert sorted(out.chosen) == sorted(hidden), out.verdict
    assert abs(out.theta["rate_friction.beta"] - 0.2) <= 0.05
    assert abs(out.theta["depth_compaction.g"] - 0.4) <= 0.1
    s = out.summary.iloc[0]
    assert s["rmse_after_percent"] <= 0.3 * s["rmse_before_percent"]


OUTSIDE = {
    "periodic": {"periodic": {"amplitude": 0.15, "wavelength": 7.0}},
    "stones": {"stones": {"fraction": 0.3, "low": 0.1, "high": 0.3}},
    "day_offset": {"day_offset": {"sd": 0.15}},
}


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("case", list(OUTSIDE))
def test_an_effect_outside_the_library_is_unexplained(case, seed):
    out = _run({}, OUTSIDE[case], seed)
    assert out.chosen == [], out.verdict
    assert out.verdict.startswith("unexplained"), out.verdict
    s = out.summary.iloc[0]
    assert s["effects"] == "" and s["rmse_after_percent"] == pytest.approx(s["rmse_before_percent"])


def test_a_random_day_offset_is_named_as_what_the_residual_follows():
    out = _run({}, OUTSIDE["day_offset"], 0)
    assert "follows day" in out.verdict


@pytest.mark.parametrize("seed", SEEDS)
def test_no_hidden_effect_chooses_none(seed):
    out = _run({}, {}, seed)
    assert out.chosen == [], out.verdict
    assert not out.verdict.startswith("explained")


def test_the_calibrated_model_error_matches_the_hidden_rate_effect():
    """Before any fit, the relative residual of a condition is the hidden effect's relative
    change of the force: with beta = 0.2 at v = e * v0 the friction rises by 20 %; the
    residual of every row must follow the sign of ln(v / v0)."""
    conds = S.conditions(S.grid(0, 18))
    table = sy.synthesize(conds, S.base_params, S.simulate, {"rate_friction": {"beta": 0.2}}, REFERENCE, {},
                          noise=0.0, seed=0)
    out = core.run_inprocess("standin", sy.with_measured(conds, table), S.base_params, S.simulate,
                             core.Settings(reference=REFERENCE))
    checked = 0
    for r in out.residuals.to_dict("records"):
        lv = math.log(r["q:tool_speed"] / REFERENCE["tool_speed"])
        if abs(lv) > 0.3:
            assert math.copysign(1, r["relative_residual"]) == math.copysign(1, lv)
            checked += 1
    assert checked >= 6


# --- plastic contact, on compression tests -------------------------------------------------------


def _run_compression(hidden, seed):
    conds = S.compression_conditions(S.compression_grid(seed, 12))
    table = sy.synthesize(conds, S.base_params, S.simulate, hidden, {}, {}, noise=0.02, seed=seed + 10)
    return core.run_inprocess("standin", sy.with_measured(conds, table), S.base_params, S.simulate, core.Settings())


@pytest.mark.parametrize("seed", SEEDS)
def test_plastic_contact_is_named_and_recovered_in_a_compression_campaign(seed):
    true = 0.4
    out = _run_compression({"plastic_contact": {"lambda_p": true}}, seed)
    assert out.chosen == ["plastic_contact"], out.verdict
    got = out.theta["plastic_contact.lambda_p"]
    assert abs(got - true) <= 0.25 * true, got
    lo, hi = core.json.loads(out.summary["ci95"].iloc[0])["plastic_contact.lambda_p"]
    assert out.verdict == f"explained by plastic_contact (plastic_contact.lambda_p {got:.3g}, 95 %: {lo:.3g} to {hi:.3g})"
    assert lo < got < hi
    s = out.summary.iloc[0]
    assert s["rmse_after_percent"] <= 0.3 * s["rmse_before_percent"], (s["rmse_before_percent"], s["rmse_after_percent"])


@pytest.mark.parametrize("seed", SEEDS)
def test_a_compression_campaign_without_an_effect_chooses_none(seed):
    out = _run_compression({}, seed)
    assert out.chosen == [], out.verdict
    assert not out.verdict.startswith("explained")


def test_hidden_plastic_contact_reaches_only_the_compression_rows():
    """Blade and compression rows in one campaign, no noise: lambda_p = 0.4 leaves every
    blade force and the compression stress as they are and multiplies the recovered strain by
    1 - 0.4^(2/3) = 1 - 0.5429 = 0.4571 (the seed scatter is common to both tables)."""
    blade = S.conditions(S.grid(0, 6))
    comp = S.compression_conditions(S.compression_grid(0, 6))
    conds = blade + comp
    without = sy.synthesize(conds, S.base_params, S.simulate, {}, REFERENCE, {}, noise=0.0, seed=0)
    with_ = sy.synthesize(conds, S.base_params, S.simulate, {"plastic_contact": {"lambda_p": 0.4}}, REFERENCE, {},
                          noise=0.0, seed=0)
    ratio = with_["truth_simulated"] / without["truth_simulated"]
    rec = (with_["measure"] == "recovered_strain").to_numpy()
    assert rec.sum() == 6
    assert ratio[rec].to_numpy() == pytest.approx(0.4571, abs=1e-4)
    assert ratio[~rec].to_numpy() == pytest.approx(1.0, rel=1e-12)


def test_the_report_says_what_the_data_could_detect():
    from soilcal.loop import files

    out = _run({}, {}, 0)
    det, diag = out.detectable, out.diagnosis
    assert list(det["test"]) == [t for t in diag["test"] if t in ("bias", "trend")]
    assert list(det["covariate"]) == [c for t, c in zip(diag["test"], diag["covariate"]) if t in ("bias", "trend")]
    assert (det["tests"] == len(diag)).all() and (det["detectable_percent"] > 0).all()
    text = files.report("standin", out, [{"candidates": out.candidates, "reference": {}, "settings": {}}])
    assert "## What these data can detect" in text and "trend over tool_speed" in " ".join(text.split())


# --- verdicts at the edges: failed effect runs, too few seeds, a parameter at its bound, few rows


def test_an_effect_whose_runs_all_fail_is_listed_not_fitted_and_the_loop_goes_on():
    conds = S.conditions(S.grid(0, 18))
    table = sy.synthesize(conds, S.base_params, S.simulate, {"rate_friction": {"beta": 0.3}}, REFERENCE, {},
                          noise=0.01, seed=5)

    def failing(c, p, seed):  # every run away from the calibrated parameters fails
        out = S.simulate(c, p, seed)
        return out if p == S.base_params(c) else {k: math.nan for k in out}

    out = core.run_inprocess("standin", sy.with_measured(conds, table), S.base_params, failing,
                             core.Settings(reference=REFERENCE))
    assert out.candidates and out.chosen == []
    sel = out.selection
    for name in out.candidates:
        # every level but the switched-off one failed, in the second round's levels next to it too
        row = sel[sel["effects"] == name].iloc[0]
        assert row["reason"].startswith("not fitted: " + name + "."), row["reason"]
        assert row["reason"].endswith("every row measured at its switched-off value 0 alone"), row["reason"]
    assert out.verdict.startswith("unexplained") and "not fitted" in out.verdict


def test_with_two_seeds_a_residual_within_the_seed_scatter_is_not_called_consistent():
    conds = S.conditions(S.grid(1, 18))
    table = sy.synthesize(conds, S.base_params, S.simulate, {}, REFERENCE, {}, noise=0.02, seed=11)
    settings = core.Settings(reference=REFERENCE)
    three = core.run_inprocess("standin", sy.with_measured(conds, table), S.base_params, S.simulate, settings)
    assert three.verdict.startswith("consistent"), three.verdict
    two = core.run_inprocess("standin", sy.with_measured(conds, table), S.base_params, S.simulate, settings,
                             seeds=(0, 1))
    assert two.verdict.startswith("unexplained") and "2 seeds per condition cannot tell" in two.verdict, two.verdict


def test_a_parameter_fitted_at_the_end_of_its_design_says_so():
    # g = 2 hidden, the design spans -0.5 to 1: the fit stops at 1
    out = _run({"depth_compaction": {"g": 2.0}}, {}, 0)
    assert out.chosen == ["depth_compaction"], out.verdict
    assert out.theta["depth_compaction.g"] == pytest.approx(1.0)
    assert "depth_compaction.g at the upper bound 1 of its design" in out.verdict
    lo, hi = core.json.loads(out.summary["ci95"].iloc[0])["depth_compaction.g"]
    assert -0.5 <= lo <= hi <= 1.0


def test_three_rows_say_that_no_trend_was_tested():
    from dataclasses import replace

    conds = [replace(c, responses=c.responses[:1]) for c in S.conditions(S.grid(0, 3))]
    table = sy.synthesize(conds, S.base_params, S.simulate, {}, REFERENCE, {}, noise=0.02, seed=1)
    out = core.run_inprocess("standin", sy.with_measured(conds, table), S.base_params, S.simulate,
                             core.Settings(reference=REFERENCE))
    assert len(out.residuals) == 3 and out.verdict.endswith("with 3 rows no trend was tested (a trend test needs 4)")


@pytest.mark.parametrize("hidden", [
    {"rate_friction": {"beta": 0.2}, "depth_compaction": {"g": 0.4}},
    {"rate_friction": {"beta": 0.2}, "moisture_cohesion": {"c_w": 0.03}},
])
def test_two_interacting_effects_are_recovered_from_runs_with_both_switched_on(hidden, monkeypatch):
    # no measurement noise and the loop's own seeds: the measured values are the stand-in's with
    # both effects on, so only the model's form stands between the fit and the hidden values.
    # The rate effect scales the passive pressure (K_p), the depth and moisture effects the
    # density and cohesion it multiplies: fitted as the sum of the separate changes, beta came
    # out 0.192 and g 0.382 (4 % off), c_w 0.0289 for 0.03; with runs of both switched on
    # together at the fitted values, and the fit redone with their interaction, they are exact
    conds = S.conditions(S.grid(0, 18, moisture=True))
    table = sy.synthesize(conds, S.base_params, S.simulate, hidden, REFERENCE, {}, noise=0.0, seed=10, seeds=SEEDS)
    measured = sy.with_measured(conds, table)
    out = core.run_inprocess("standin", measured, S.base_params, S.simulate,
                             core.Settings(reference=REFERENCE, bootstrap=0), seeds=SEEDS)
    assert sorted(out.chosen) == sorted(hidden), out.verdict
    for name, theta in hidden.items():
        for k, true in theta.items():
            assert out.theta[f"{name}.{k}"] == pytest.approx(true, rel=0.01), (name, out.theta)
    assert "fitted with their interaction, from runs with" in out.verdict
    # without the joint runs (the workflow's selection) the verdict says what the fit leaves out
    monkeypatch.setattr(core, "JOINT_ROUNDS", 0)
    out = core.run_inprocess("standin", measured, S.base_params, S.simulate,
                             core.Settings(reference=REFERENCE, bootstrap=0), seeds=SEEDS)
    assert sorted(out.chosen) == sorted(hidden), out.verdict
    assert "fitted as the sum of each effect's separate change (first order), which leaves out their interaction" \
        in out.verdict


def test_a_single_effect_is_refitted_with_runs_at_its_fitted_value(monkeypatch):
    # a moisture cohesion c_w = 0.03 J/m^2 per % about 16 %: on the dry rows (8 %) the surface
    # energy 0.4 - 0.03 * 8 stays above zero, but at the design point c_w = 0.1 it is clamped at
    # zero, so the monotone cubic through the design points (0, 0.1) bends where the response
    # has a kink: noise-free, the fit came out 0.0325 (8 % off); with runs at the fitted value
    # and the model corrected there it is exact.  The round with the runs at the fitted value
    # changes the chosen effect's fit only, not the candidates or their runs: the selection
    # over the candidates is made once per set of candidates, not again in that round
    from soilcal.loop import select as sl

    selected = []
    forward = sl.forward
    monkeypatch.setattr(sl, "forward", lambda obs, y0, data, *a, **k: selected.append(tuple(data))
                        or forward(obs, y0, data, *a, **k))
    conds = S.conditions(S.grid(0, 18, moisture=True))
    hidden = {"moisture_cohesion": {"c_w": 0.03}}
    table = sy.synthesize(conds, S.base_params, S.simulate, hidden, REFERENCE, {}, noise=0.0, seed=10, seeds=SEEDS)
    out = core.run_inprocess("standin", sy.with_measured(conds, table), S.base_params, S.simulate,
                             core.Settings(reference=REFERENCE, bootstrap=0), seeds=SEEDS)
    assert selected and len(set(selected)) == len(selected), selected
    assert out.chosen == ["moisture_cohesion"], out.verdict
    assert out.theta["moisture_cohesion.c_w"] == pytest.approx(0.03, rel=0.01)
    assert out.verdict.startswith("explained by moisture_cohesion")
    assert "; the parameter refitted with runs at moisture_cohesion.c_w 0.03" in out.summary["ci95_method"].iloc[0]


def test_a_single_effect_fitted_without_runs_at_its_value_says_so(monkeypatch):
    # the workflow's selection fits the effect on the surrogate through the design points and
    # runs nothing at the fitted value: the moisture cohesion above comes out 0.0325 for 0.03,
    # and the interval's method says which refit it did not make
    conds = S.conditions(S.grid(0, 18, moisture=True))
    hidden = {"moisture_cohesion": {"c_w": 0.03}}
    table = sy.synthesize(conds, S.base_params, S.simulate, hidden, REFERENCE, {}, noise=0.0, seed=10, seeds=SEEDS)
    monkeypatch.setattr(core, "JOINT_ROUNDS", 0)
    out = core.run_inprocess("standin", sy.with_measured(conds, table), S.base_params, S.simulate,
                             core.Settings(reference=REFERENCE, bootstrap=0), seeds=SEEDS)
    assert out.chosen == ["moisture_cohesion"], out.verdict
    assert abs(out.theta["moisture_cohesion.c_w"] - 0.03) > 0.05 * 0.03  # the surrogate's error between its points
    method = out.summary["ci95_method"].iloc[0]
    assert "not refitted with runs at its fitted value" in method and "refitted with runs at" not in \
        method.replace("not refitted with runs at", "")


def test_a_refit_on_runs_whose_noise_changes_with_the_parameters_keeps_to_the_effect():
    # DEM runs draw their seeds' scatter anew at every parameter value (no common random numbers):
    # here 4 % per run, hashed from the parameters, with a weak rate effect beta = 0.06.  The
    # joint runs' difference from the surrogate is then mostly that scatter; taken as an
    # interaction and scaled towards the switched-off value, it pulled beta to 0.024; kept to the
    # rows where it exceeds two standard errors, the mean refit lies within 25 % of 0.06 (it sits
    # about 13-19 % low over campaigns: mean 0.052 over 30 equal-weight campaigns, 0.049 over
    # these eight weighted ones).  Any change of a fitted value redraws every later run of this
    # stand-in, so one campaign is one draw of the refit (its beta lies outside 25 % of 0.06 in
    # about one campaign of five): the claim is on the mean over eight campaigns, within 25 % of
    # 0.06
    import json
    import zlib

    import numpy as np

    ref = {"tool_speed": 1.75, "working_depth": 0.1}

    def chaotic(cond, params, seed):
        fh, fv = S.forces(params, cond.quantities)
        h = zlib.crc32(json.dumps(params, sort_keys=True).encode())
        e = np.random.default_rng([seed, cond.row, h]).normal(0.0, 0.04, 2)
        return {"horizontal_force_N": fh * (1 + e[0]), "vertical_force_N": fv * (1 + e[1])}

    conds = S.conditions(S.grid(2, 18))
    betas = []
    for seed in range(12, 20):
        table = sy.synthesize(conds, S.base_params, chaotic, {"rate_friction": {"beta": 0.06}}, ref, {},
                              noise=0.005, seed=seed)
        out = core.run_inprocess("standin", sy.with_measured(conds, table), S.base_params, chaotic,
                                 core.Settings(reference=ref, bootstrap=0))
        assert out.chosen == ["rate_friction"], (seed, out.verdict)
        betas.append(out.theta["rate_friction.beta"])
    assert float(np.mean(betas)) == pytest.approx(0.06, rel=0.25), betas
