"""The residuals' degrees of freedom do not grow with the luck of a few repeats or seeds.

Known truth: every measured condition's true value is the model's, the measured value the mean
of n normal repeats with their sample SD, the simulated value the mean of 3 normal seeds with
theirs.  A standardised residual mapped to the unit normal on its degrees of freedom
(:func:`soilcal.loop.diagnose.normal_equivalent`) is then unit normal: its square has mean 1
and 5 % of them lie beyond 1.96.  Welch-Satterthwaite's degrees of freedom computed from each
row's own estimated variances grow where its three seeds happen to scatter little, exactly
where the residual over them is large: 1 % measured noise over 10 repeats and 5 % seed scatter
over 3 seeds gave a mean square 1.13 and 6.1 % beyond 1.96 (12 rows per table: the scatter
test at p < 0.05 in 17.5 % of 200 tables).
"""

from __future__ import annotations

import numpy as np
import pytest
import pandas as pd

from soilcal.loop.diagnose import normal_equivalent, replicate_residuals
from soilcal.loop.residuals import residual_frame

N = 12000


def _table(rng, n_cond, cv_m, n_m, cv_s, n_s, reps=1, sd=True):
    truth = rng.uniform(50.0, 500.0, n_cond)
    obs, runs = [], []
    for i, t in enumerate(truth):
        for j in range(reps):
            rep = t * (1.0 + cv_m * rng.standard_normal(n_m))
            obs.append(dict(measurement="bin", row=i * reps + j + 1, measure="F_N", unit="N", label="", simulation=f"c{i}",
                            measured=float(rep.mean()), measured_sd=float(rep.std(ddof=1)) if sd else np.nan,
                            measured_n=float(n_m) if sd else np.nan))
        seeds = t * (1.0 + cv_s * rng.standard_normal(n_s))
        runs += [dict(measurement="bin", row=i * reps + j + 1, measure="F_N", seed=k, value=float(v), status="ok")
                 for j in range(reps) for k, v in enumerate(seeds)]
    return residual_frame(pd.DataFrame(obs), pd.DataFrame(runs))


def _unit_normal(z):
    z = np.asarray(z, float)
    return float(np.mean(z ** 2)), float(np.mean(np.abs(z) > 1.959964))


def _honest(ms, tail):
    """Not liberal, nor far conservative: Welch-Satterthwaite's t law on 2-4 degrees of freedom
    is an approximation, which errs a little towards the conservative (the share beyond 1.96
    4.2-4.3 % in these tables); over 12000 rows the binomial SD of the share is 0.002, of the
    mean square 0.013."""
    return 0.9 < ms < 1.04 and 0.036 < tail < 0.056


def test_seed_dominated_rows_are_unit_normal_on_their_degrees_of_freedom():
    res = _table(np.random.default_rng(3), N, 0.01, 10, 0.05, 3)
    ms, tail = _unit_normal(normal_equivalent(res["standardised_residual"], res["residual_dof"]))
    assert _honest(ms, tail), (ms, tail)


def test_measurement_dominated_rows_are_unit_normal_on_their_degrees_of_freedom():
    res = _table(np.random.default_rng(4), N, 0.05, 4, 0.01, 3)
    ms, tail = _unit_normal(normal_equivalent(res["standardised_residual"], res["residual_dof"]))
    assert _honest(ms, tail), (ms, tail)


def test_replicate_rows_without_an_sd_are_unit_normal_on_their_degrees_of_freedom():
    # three replicate rows (days) of one simulation, 2 % scatter, no SD stated; 3 % seed scatter
    res = _table(np.random.default_rng(5), N // 3, 0.02, 1, 0.03, 3, reps=3, sd=False)
    z, dof = replicate_residuals(res)
    assert len(z) == N // 3
    ms, tail = _unit_normal(normal_equivalent(z, dof))
    assert _honest(ms, tail), (ms, tail)


@pytest.mark.parametrize("cv_m, n_m, cv_s, reps", [(0.02, 5, 0.03, 3),  # replicate rows, SDs of 5 repeats
                                                   (0.05, 10, 0.01, 1),  # the measurement dominates
                                                   (0.01, 10, 0.05, 1)])  # the seeds dominate
def test_the_scatter_about_the_scale_is_chi_square_on_its_degrees_of_freedom(cv_m, n_m, cv_s, reps):
    """No offset, 150 conditions: the statistic's mean is its degrees of freedom, its SD
    sqrt(2 dof) (per degree of freedom 0.07-0.12 here).  Before, the replicates' scatter was
    taken against each row's own SD of 5 repeats (a sum of t^2: chi-square per degree of
    freedom 1.31), and the residual of a condition's mean on the fewer of the measured and seed
    degrees of freedom, 2 for 3 seeds however small their share (0.62 where the measurement
    dominates)."""
    from soilcal.loop.core import scatter_about_scale

    res = _table(np.random.default_rng(9), 150, cv_m, n_m, cv_s, 3, reps=reps)
    chi, dof, p = scatter_about_scale(res, 0.0)
    assert dof == 149 + 150 * (reps - 1)
    assert abs(chi / dof - 1.0) < 2.5 * np.sqrt(2.0 / dof), (chi / dof, p)


def test_replicate_rows_sharing_a_simulation_hold_the_scatter_tests_level():
    """6 conditions x 3 days, each row's SD from 5 repeats (2 %), the days' rows sharing their
    condition's 3 seeds (3 %), no offset: the scatter test's chi-square on 18 degrees of freedom
    rejects at p < 0.05 in 5 % of tables (4 of 80, binomial SD 1.9).  Counted as 18
    independent rows, which share 6 seed errors, it rejected in 16 % of 200."""
    from soilcal.loop.diagnose import diagnose

    rng = np.random.default_rng(21)
    p = []
    for _ in range(80):
        d = diagnose(_table(rng, 6, 0.02, 5, 0.03, 3, reps=3))
        p.append(float(d.loc[d["test"] == "scatter", "p"].iloc[0]))
    assert np.sum(np.array(p) < 0.05) <= 8, np.sum(np.array(p) < 0.05)


def _mixed(rng, spec, tables):
    """``tables`` tables of rows (truth, absolute measured SD, repeats, seed CV, seeds), no
    offset; per row its truth and its residual mapped to the unit normal."""
    out = []
    for _ in range(tables):
        obs, runs = [], []
        for i, (t, sd, n_m, cv_s, n_s) in enumerate(spec):
            rep = t + sd * rng.standard_normal(n_m)
            obs.append(dict(measurement="bin", row=i + 1, measure="F_N", unit="N", label="", simulation=f"c{i}",
                            measured=float(rep.mean()), measured_sd=float(rep.std(ddof=1)), measured_n=float(n_m)))
            runs += [dict(measurement="bin", row=i + 1, measure="F_N", seed=k, value=float(v), status="ok")
                     for k, v in enumerate(t * (1.0 + cv_s * rng.standard_normal(n_s)))]
        res = residual_frame(pd.DataFrame(obs), pd.DataFrame(runs))
        out += zip([s[0] for s in spec], normal_equivalent(res["standardised_residual"], res["residual_dof"]))
    return np.array(out)


@pytest.mark.parametrize("spec", [
    # an absolute noise floor: 6 rows of 20 N +- 2 N next to 6 of 500 N +- 5 N
    [(20.0, 2.0, 10, 0.05, 3)] * 6 + [(500.0, 5.0, 10, 0.05, 3)] * 6,
    # one row far noisier than the rest: 11 rows 100-200 N at 1 %, one of 45 N +- 20 N
    [(t, 0.01 * t, 10, 0.05, 3) for t in np.linspace(100.0, 200.0, 11)] + [(45.0, 20.0, 10, 0.05, 3)]])
def test_sds_not_proportional_to_the_value_are_not_pooled(spec):
    """Where a quantity's measured SDs are not one share of its values, a relative SD pooled
    over its rows is no row's SD: the large rows' residuals were read on the degrees of freedom
    of the small rows' huge relative SD (12.3 % and 13.4 % of them beyond 1.96; a right model
    looks wrong).  Bartlett's test rejects the common relative variance and each row keeps its
    own degrees of freedom: each group of rows 5 % beyond 1.96 within Welch-Satterthwaite's
    approximation (binomial SD 0.5-1.4 % over these rows)."""
    z = _mixed(np.random.default_rng(11), spec, 150)
    for small in (True, False):
        zz = z[(z[:, 0] < 50.0) == small, 1]
        tail = float(np.mean(np.abs(zz) > 1.959964))
        assert 0.02 < tail < 0.08, (small, tail, len(zz))


def test_bartlett_from_summary_statistics_is_scipys():
    from scipy import stats

    from soilcal.loop.residuals import bartlett_p

    rng = np.random.default_rng(2)
    groups = [rng.normal(0.0, s, n) for s, n in ((1.0, 5), (1.5, 8), (0.7, 4), (3.0, 10))]
    p = bartlett_p([np.var(g, ddof=1) for g in groups], [len(g) - 1 for g in groups])
    assert abs(p - stats.bartlett(*groups).pvalue) < 1e-12


def _floor_replicates(rng, n_cond, reps):
    """``n_cond`` conditions, half of 20 N +- 2 N and half of 500 N +- 5 N (an absolute noise
    floor: Bartlett's test refuses one relative SD), each measured as ``reps`` replicate rows
    with the mean and sample SD of 10 normal repeats, its 3 seeds at 5 %; no offset."""
    obs, runs = [], []
    for i in range(n_cond):
        t, sd = (20.0, 2.0) if i % 2 else (500.0, 5.0)
        seeds = t * (1.0 + 0.05 * rng.standard_normal(3))
        for j in range(reps):
            rep = t + sd * rng.standard_normal(10)
            row = i * reps + j + 1
            obs.append(dict(measurement="bin", row=row, measure="F_N", unit="N", label="", simulation=f"c{i}",
                            measured=float(rep.mean()), measured_sd=float(rep.std(ddof=1)), measured_n=10.0))
            runs += [dict(measurement="bin", row=row, measure="F_N", seed=k, value=float(v), status="ok")
                     for k, v in enumerate(seeds)]
    return residual_frame(pd.DataFrame(obs), pd.DataFrame(runs))


def test_replicates_of_sds_not_pooled_scatter_as_chi_square():
    """Where a quantity's SDs are not pooled (an absolute noise floor), the replicate rows of a
    condition scatter about their mean against the SD pooled over those rows, read as F on
    their repeats' degrees of freedom: 300 conditions x 3 replicate rows of 10 repeats, no
    offset, so the scatter about the scale and the diagnosis's scatter test are chi-square on
    their degrees of freedom (per degree of freedom 1 +- 0.05 here).  Against each row's own SD
    the replicates' part was a sum of t^2 (mean 9/7 per degree of freedom on 9): here 1.08 and
    1.12 per degree of freedom (0.93 and 0.97 now), and of 200 tables of 12 conditions 11.5 %
    and 14 % at p < 0.05 (3.5 % and 5 % now)."""
    from soilcal.loop.core import scatter_about_scale
    from soilcal.loop.diagnose import diagnose

    res = _floor_replicates(np.random.default_rng(17), 300, 3)
    chi, dof, p = scatter_about_scale(res, 0.0)
    assert dof == 299 + 300 * 2
    assert abs(chi / dof - 1.0) < 2.5 * np.sqrt(2.0 / dof), (chi / dof, p)
    d = diagnose(res)
    sc = d[d["test"] == "scatter"].iloc[0]
    assert sc["n"] == 900
    assert abs(sc["statistic"] / sc["n"] - 1.0) < 2.5 * np.sqrt(2.0 / sc["n"]), sc["statistic"] / sc["n"]


def test_the_scatter_about_the_scale_holds_its_level_where_sds_are_not_pooled():
    """5 N +- 2 N beside 500 N +- 10 N (10 repeats each, 6 rows of each, 3 seeds at 5 %; the
    quantity scaled by its RMS, so neither the measured nor the seed SDs are one share of it and
    Bartlett's test refuses their pooling), no offset: at alpha 0.05 a test of the right level
    rejects 5 % of tables, so of 40 at most 6 (the binomial's upper 0.34 % tail begins at 7).
    Where a part keeps the row's own SD, the mean's residual is read on the fewer of its
    measured and seed degrees of freedom; Welch-Satterthwaite's from the own SDs grows where 3
    seeds happen to scatter little (8.5 % of 200 tables at p < 0.05).  The fewer degrees of
    freedom are conservative here (chi-square per degree of freedom 0.7, no table rejected):
    the conservative side is accepted, the bound guards the level only."""
    from soilcal.loop.core import scatter_about_scale

    spec = [(5.0, 2.0)] * 6 + [(500.0, 10.0)] * 6
    rng = np.random.default_rng(13)
    p = []
    for _ in range(40):
        obs, runs = [], []
        for i, (t, sd) in enumerate(spec):
            rep = t + sd * rng.standard_normal(10)
            obs.append(dict(measurement="bin", row=i + 1, measure="F_N", unit="N", label="", simulation=f"c{i}",
                            measured=float(rep.mean()), measured_sd=float(rep.std(ddof=1)), measured_n=10.0))
            runs += [dict(measurement="bin", row=i + 1, measure="F_N", seed=k, value=float(v), status="ok")
                     for k, v in enumerate(t * (1.0 + 0.05 * rng.standard_normal(3)))]
        p.append(scatter_about_scale(residual_frame(pd.DataFrame(obs), pd.DataFrame(runs)), 0.0)[2])
    assert np.sum(np.array(p) < 0.05) <= 6, np.sum(np.array(p) < 0.05)


def test_a_row_entered_twice_or_copied_into_a_second_table_tells_nothing_new():
    """A copy of a row with its SD is no new observation: with it, the residual's degrees of
    freedom of every row and the scatter test (chi-square, degrees of freedom, p) are those of
    the table without it, whether the copy stands in the same table or in a second one (a
    second table's SDs are pooled on their own, so the copy is that table's only entry)."""
    from soilcal.loop.core import scatter_about_scale
    from soilcal.loop.residuals import reference_variances

    res = _table(np.random.default_rng(11), 12, 0.02, 5, 0.03, 3)
    twice = pd.concat([res, res.iloc[[3]]], ignore_index=True)
    copied = pd.concat([res, res.iloc[[3]].assign(measurement="again")], ignore_index=True)
    ref_m, ref_s = reference_variances(res)
    base = scatter_about_scale(res, 0.05)
    assert np.isfinite(base[0]) and base[1] == 11
    for t in (twice, copied):
        m, s = reference_variances(t)
        np.testing.assert_allclose(m[:12], ref_m, rtol=1e-12)
        np.testing.assert_allclose(s[:12], ref_s, rtol=1e-12)
        np.testing.assert_allclose(scatter_about_scale(t, 0.05), base, rtol=1e-12)
