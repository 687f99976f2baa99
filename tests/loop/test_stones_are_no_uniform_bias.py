"""A uniform bias (a load cell's calibration) shifts every measured row alike: about it the rows
lie within their measured and seed uncertainty.  Stones in the bin raise a few rows far off and
the mean of all with them; about that mean those rows still scatter far beyond the uncertainty,
and the verdict must not call the mean "a uniform bias throughout"."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from soilcal.loop import core


def _residuals(measured, se=2.0):
    # one measured force per condition against a simulated mean of 100 (no seed scatter), the
    # residual's standard error ``se`` (the measured SD over sqrt(n), n so large that the SD is
    # known: its t is a normal deviate)
    m = np.asarray(measured, float)
    k = len(m)
    return pd.DataFrame({"measurement": "bin", "row": np.arange(1, k + 1), "measure": "F", "simulation": [
        f"s{i}" for i in range(k)], "measured": m, "simulated_mean": 100.0, "scale": 100.0, "residual": m - 100.0,
        "relative_residual": (m - 100.0) / 100.0, "residual_se": se, "standardised_residual": (m - 100.0) / se,
        "measured_sd": se * 1e6, "measured_n": 1e12, "residual_dof": np.inf})


def test_rows_shifted_alike_lie_within_their_uncertainty_about_the_fitted_scale():
    # 12 rows at 108: about s = 0.08 every residual is 0
    chi, dof, p = core.scatter_about_scale(_residuals([108.0] * 12), 0.08)
    assert chi == pytest.approx(0.0, abs=1e-9) and dof == 11 and p == pytest.approx(1.0)
    # 108 -+ 2 (one standard error) alternating: standardised -+1 about 108, chi-square 12 on 11
    chi, dof, p = core.scatter_about_scale(_residuals([106.0, 110.0] * 6), 0.08)
    assert chi == pytest.approx(12.0) and p == pytest.approx(stats.chi2.sf(12.0, 11))


def test_a_few_rows_far_off_scatter_about_their_mean_beyond_the_uncertainty():
    # 9 rows at 100 and 3 stones at 130: mean offset s = 0.075, about 107.5 the residuals are
    # -7.5 (9 rows) and +22.5 (3), standardised by 2: chi-square 9 x 3.75^2 + 3 x 11.25^2 = 506.25
    chi, dof, p = core.scatter_about_scale(_residuals([100.0] * 9 + [130.0] * 3), 0.075)
    assert chi == pytest.approx(506.25) and dof == 11 and p < 1e-90


def test_a_table_without_a_measured_uncertainty_has_no_scatter_to_judge():
    res = _residuals([100.0] * 9 + [130.0] * 3).assign(measured_sd=np.nan)
    chi, dof, p = core.scatter_about_scale(res, 0.075)
    assert np.isnan(p)


def _campaign(disturbances):
    # 18 soil-bin tests on the stand-in blade (moisture measured), the table from the model with
    # ``disturbances`` and 2 % instrument noise, three repeats each
    from soilcal.loop import standin as S
    from soilcal.loop import synthesize as sy

    ref = {"tool_speed": 1.75, "working_depth": 0.1, "moisture_content": 16.0}
    conds = S.conditions(S.grid(23, 18, moisture=True, days=6))
    table = sy.synthesize(conds, S.base_params, S.simulate, {}, ref, disturbances, noise=0.02, seed=33)
    return core.run_inprocess("bin", sy.with_measured(conds, table), S.base_params, S.simulate,
                              core.Settings(reference=ref, bootstrap=0))


def test_stones_in_the_bin_are_not_called_a_uniform_bias_throughout():
    # 30 % of the tests raised by 10-30 % (stones met by the tool): their mean is 5.7 % above
    # the model, which a moisture cohesion fits as well as a uniform scale does; but about that
    # level the rows scatter beyond their uncertainty, which no calibration offset does
    out = _campaign({"stones": {}})
    assert out.chosen == [] and out.verdict.startswith("unexplained: the measured values are"), out.verdict
    assert "throughout, a uniform bias" not in out.verdict, out.verdict
    assert "% above the model on average, but they scatter about that level beyond the measured and seed" \
        in out.verdict, out.verdict
    assert "no uniform bias" in out.summary.iloc[0]["nuisance_method"]


def test_a_uniform_offset_on_the_same_tests_is_still_called_one():
    out = _campaign({"stones": {"fraction": 1.0, "low": 0.08, "high": 0.08}})
    assert out.chosen == [] and "% above the model throughout, a uniform bias" in out.verdict, out.verdict


def test_the_quantities_of_one_test_count_once():
    # the same 12 tests measuring two forces that move together (a stone raises both): the
    # stones' chi-square is that of 12 tests, 506.25 on 11 degrees of freedom, not twice it on 23
    one = _residuals([100.0] * 9 + [130.0] * 3)
    two = pd.concat([one, one.assign(measure="V")], ignore_index=True)
    chi, dof, p = core.scatter_about_scale(two, 0.075)
    assert chi == pytest.approx(506.25) and dof == 11


def test_a_residual_that_follows_a_bias_from_stones_says_the_rows_scatter_about_it():
    # 12 tests of one force, 40 % of them raised by 20-30 % (stones): the residual follows a
    # bias no candidate explains, given as the scale fitted alone; the rows scatter about it
    # far beyond their uncertainty, which the verdict and loop_summary.csv say
    from soilcal.loop import standin as S
    from soilcal.loop import synthesize as sy

    ref = {"tool_speed": 1.75, "working_depth": 0.1}
    conds = S.conditions(S.grid(2, 12), measures=("horizontal_force_N",))
    table = sy.synthesize(conds, S.base_params, S.simulate, {}, ref,
                          {"stones": {"fraction": 0.4, "low": 0.2, "high": 0.3}}, noise=0.02, seed=12)
    out = core.run_inprocess("bin", sy.with_measured(conds, table), S.base_params, S.simulate,
                             core.Settings(reference=ref, bootstrap=0))
    assert out.chosen == [] and out.verdict.startswith("unexplained: the residual follows bias"), out.verdict
    assert ("% above the model on average, but they scatter about that level beyond the measured and seed "
            "uncertainty") in out.verdict, out.verdict
    assert "some rows lie far off for a reason no covariate carries" in out.verdict
    assert "no uniform bias" in out.summary.iloc[0]["nuisance_method"]


def _offset_table(seed, k, reps, off):
    # ``k`` conditions of the stand-in blade, each measured in ``reps`` table rows (days) that
    # share its simulation, every measured value the model x (1 + off) with 1 % noise (its SD
    # stated, 10 repeats); the DEM's seed scatter 5 % over 3 seeds, which dominates
    from dataclasses import replace

    from soilcal.loop import residuals as rs
    from soilcal.loop import standin as S

    rng = np.random.default_rng(seed)
    grid = [dict(g, day=f"r{j}") for g in S.grid(seed, k, moisture=True, days=min(6, k)) for j in range(reps)]
    conds = S.conditions(grid)

    def truth(c):
        fh, fv = S.forces(S.BASE, c.quantities)
        return {"horizontal_force_N": fh, "vertical_force_N": fv}

    conds = [replace(c, responses=tuple(
        dict(r, measured=truth(c)[r["measure"]] * (1 + off) * (1 + 0.01 * rng.standard_normal() / np.sqrt(10)),
             measured_sd=0.01 * truth(c)[r["measure"]] * (1 + off), n=10) for r in c.responses)) for c in conds]
    sims, rows = {}, []
    for c in conds:
        for sd in range(3):
            key = (rs.simulation_key(c), sd)
            if key not in sims:
                sims[key] = {m: v * (1 + 0.05 * rng.standard_normal()) for m, v in truth(c).items()}
            rows += [{"measurement": c.measurement, "row": c.row, "measure": r["measure"], "seed": sd,
                      "value": sims[key][r["measure"]], "status": "ok"} for r in c.responses]
    return rs.residual_frame(rs.observations(conds), pd.DataFrame(rows))


@pytest.mark.parametrize("k, reps", [(12, 1), (6, 3)])
def test_a_pure_offset_under_seed_scatter_is_within_its_uncertainty(k, reps):
    # every value 25 % above the model; about a prediction 1.25 x the simulated mean its seed
    # error is 1.25 x as large, and replicate rows share their simulation's: a uniform bias,
    # which at alpha 0.05 may read as scatter in about 1 of 20 tables.  Before, the seed part
    # was left unscaled and replicates counted as independent: p < 0.05 in 35 % of tables
    # (12 x 1) and, with no offset, 24 % (6 x 3)
    from soilcal.loop import residuals as rs

    ps = []
    for seed in range(24):
        res = _offset_table(seed, k, reps, 0.25)
        u = rs.usable(res)
        s = float(np.mean(u["measured"] / u["simulated_mean"]) - 1.0)
        ps.append(core.scatter_about_scale(res, s)[2])
    assert np.sum(np.array(ps) < 0.05) <= 3, ps  # 1.2 expected at alpha; binomial P(> 3) 0.03
