"""The one-parameter surrogate (soilcal.loop.select.Surrogate, smooth_fits): a least-squares
quadratic through the design's seed means where it follows them within the seed scatter, an
interpolant where it does not.

Expected values by construction: design means that are a line in the parameter plus a
pattern orthogonal to 1, theta and theta^2 over the design points are fitted by the
quadratic exactly as the line, so measured values on that line give back its parameter to
rounding; the lack-of-fit F and its p follow from the sums of squares the values were built
with (Montgomery, Design and Analysis of Experiments: lack of fit against pure error, here the
point x seed interaction of a two-way layout without replication)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from soilcal.loop import select as sl
from soilcal.loop.effects import EFFECTS

EFF = EFFECTS["rate_friction"]
BOUNDS = {"beta": (-0.3, 0.6)}
DESIGN = sl.theta_design(EFF, BOUNDS, 5)  # -0.3, -0.075, 0, 0.15, 0.375, 0.6
T = np.array([d["beta"] for d in DESIGN])
N, SEEDS = 12, 3
A = np.linspace(-1.0, 1.0, N)


def _orthogonal() -> np.ndarray:
    """A unit pattern over the design points orthogonal to 1, theta and theta^2."""
    B = np.column_stack([np.ones_like(T), T, T ** 2])
    r = np.array([1.0, -2.0, 0.5, 3.0, -1.0, 0.25])
    r = r - B @ np.linalg.lstsq(B, r, rcond=None)[0]
    return r / np.linalg.norm(r)


def _seed_pattern() -> np.ndarray:
    """Deviations over points x seeds with zero mean over the seeds and over the points, unit sum of squares."""
    rng = np.random.default_rng(0)
    e = rng.standard_normal((len(T), SEEDS))
    e = e - e.mean(axis=1, keepdims=True) - e.mean(axis=0, keepdims=True) + e.mean()
    return e / np.linalg.norm(e)


def _values(lof: float, scatter: float, seed_level: float = 0.0) -> np.ndarray:
    """points x rows x seeds: 100 (1 + a_i theta) + lof * pattern (sign by row) + scatter * the
    seed pattern + each seed's own level (shared by every point: common random numbers)."""
    r, e = _orthogonal(), _seed_pattern()
    V = np.empty((len(T), N, SEEDS))
    for i in range(N):
        V[:, i, :] = (100.0 * (1 + A[i] * T))[:, None] + lof * (-1) ** i * r[:, None] + scatter * e \
            + seed_level * np.array([-1.0, 0.5, 2.0])[None, :] * (i + 1)
    return V


def _runs(V: np.ndarray) -> pd.DataFrame:
    return pd.DataFrame([{"measurement": "m", "row": i + 1, "measure": "F_N", "seed": s, "value": V[d, i, s],
                          "status": "ok", "t:beta": T[d]}
                         for d in range(len(T)) for i in range(N) for s in range(SEEDS)])


def _obs(beta: float) -> pd.DataFrame:
    return pd.DataFrame({"measurement": "m", "row": np.arange(1, N + 1), "measure": "F_N",
                         "measured": 100.0 * (1 + A * beta)})


def test_lack_of_fit_p_from_the_sums_of_squares():
    lof, scatter = 0.4, 2.0
    smooth, p = sl.smooth_fits(T[:, None], _values(lof, scatter))
    # per row, on its own: lack-of-fit SS = SEEDS * lof^2 (unit pattern orthogonal to the
    # quadratic), error SS = scatter^2 (unit interaction pattern)
    f = (SEEDS * lof ** 2 / (len(T) - 3)) / (scatter ** 2 / ((len(T) - 1) * (SEEDS - 1)))
    assert p == pytest.approx(np.full(N, stats.f.sf(f, len(T) - 3, (len(T) - 1) * (SEEDS - 1))), rel=1e-9)
    assert (smooth == (p >= sl.LACK_OF_FIT_ALPHA)).all()


def test_the_seeds_own_levels_do_not_count_as_scatter():
    # common random numbers: a seed's level shared by every design point cancels in the changes
    assert sl.smooth_fits(T[:, None], _values(0.4, 2.0, seed_level=50.0))[1] == pytest.approx(
        sl.smooth_fits(T[:, None], _values(0.4, 2.0))[1], rel=1e-9)


def test_within_the_scatter_the_quadratic_gives_back_the_parameter():
    # the orthogonal pattern (5 % of the force) within a seed scatter that holds it: the
    # quadratic takes the line, and measured values on the line give its beta to rounding;
    # an interpolant through the means follows the pattern and misses it
    V = _values(5.0, 40.0)
    ed = sl.build_effect_data(_obs(0.3), _runs(V), EFF, BOUNDS)
    assert ed.surrogate.quadratic.all() and (ed.lack_of_fit_p >= sl.LACK_OF_FIT_ALPHA).all()
    y0 = ed.means[list(T).index(0.0)]
    x, _ = sl.Model([ed], y0, _obs(0.3)["measured"].to_numpy(float)).fit()
    assert x[0] == pytest.approx(0.3, abs=1e-7)


def test_beyond_the_scatter_the_surrogate_interpolates():
    # the same pattern with little seed scatter: the quadratic does not follow the means, so the
    # surrogate goes through them (a response that saturates keeps its shape)
    V = _values(5.0, 0.5)
    ed = sl.build_effect_data(_obs(0.3), _runs(V), EFF, BOUNDS)
    assert not ed.surrogate.quadratic.any() and (ed.lack_of_fit_p < sl.LACK_OF_FIT_ALPHA).all()
    for d, t in enumerate(T):
        assert ed.surrogate([t]) == pytest.approx(V[d].mean(axis=1), rel=1e-12)


def test_no_smoothing_without_scatter_or_with_too_few_points():
    smooth, p = sl.smooth_fits(T[:, None], _values(0.0, 0.0))
    # no scatter (rounding only): nothing to test against, nothing to smooth away
    assert not smooth.any() and np.isnan(p).all()
    assert not sl.smooth_fits(T[:3, None], _values(0.4, 2.0)[:3])[0].any()
    assert not sl.smooth_fits(T[:, None], _values(0.4, 2.0)[:, :, :1])[0].any()
    assert not sl.smooth_fits(T[:, None], None)[0].any()


def _saturating(t, a):
    """A monotone, concave response that saturates: 100 (1 + a (1 - exp(-6 (t + 0.3))))."""
    return 100.0 * (1 + a * (1 - np.exp(-6.0 * (t + 0.3))))


@pytest.mark.parametrize("beta", [0.45, 0.6])
def test_a_quadratic_that_turns_over_where_the_means_do_not_is_not_used(beta):
    # twelve rows of a saturating response, exact seed means (the seed pattern has zero mean
    # over the seeds) and a seed scatter of 40 that the lack-of-fit test lets the quadratic
    # through: its vertex lies inside the bounds, so it would fall past its peak where every
    # row's means rise.  The monotone cubic through the means rises in every row, and the
    # measured values at beta lie between the rows' values at the design points either side
    # of it (0.375 and 0.6), so the fit lands between them; at a design point (0.6) the cubic
    # goes through the exact means and gives beta back to rounding
    a = np.linspace(0.2, 1.0, N)
    V = np.stack([_saturating(T, ai)[:, None] + 40.0 * _seed_pattern() for ai in a], axis=1)
    obs = pd.DataFrame({"measurement": "m", "row": np.arange(1, N + 1), "measure": "F_N",
                        "measured": _saturating(beta, a)})
    ed = sl.build_effect_data(obs, _runs(V), EFF, BOUNDS)
    assert ed.surrogate.smooth.any()  # the test alone would take the quadratic
    assert not ed.surrogate.quadratic.any() and ed.surrogate.kind() == "monotone cubic"
    y0 = ed.means[list(T).index(0.0)]
    x, _ = sl.Model([ed], y0, obs["measured"].to_numpy(float)).fit()
    if beta in T:
        assert x[0] == pytest.approx(beta, abs=1e-6)
    else:
        assert 0.375 <= x[0] <= 0.6


def test_each_row_is_tested_against_its_own_scatter():
    # eleven force rows (about 1000 N, linear in beta, 2 % seed scatter) and one row of order
    # 1 clamped at zero below beta 0 (exact means, scatter 0.001): pooled, the force rows'
    # scatter would hide the small row's lack of fit.  On its own the small row's lack of fit
    # is far beyond its scatter, so it keeps the monotone cubic, which stays at its means' 0
    # over the clamped part, where a quadratic undershoots
    rng = np.random.default_rng(1)
    V = np.empty((len(T), N, SEEDS))
    for i in range(N - 1):
        V[:, i, :] = (1000.0 * (1 + 0.5 * T))[:, None] + 20.0 * rng.standard_normal((len(T), SEEDS))
    V[:, N - 1, :] = np.maximum(0.0, T)[:, None] + 0.001 * _seed_pattern()
    smooth, p = sl.smooth_fits(T[:, None], V)
    assert not smooth[N - 1] and p[N - 1] < 1e-6
    s = sl.Surrogate(EFF, BOUNDS, T[:, None], V.mean(axis=2), smooth)
    for t in np.linspace(-0.3, 0.0, 7):
        assert s([t])[N - 1] == pytest.approx(0.0, abs=1e-12)
    assert s.kind().endswith("monotone cubic in 1")


def test_rows_of_either_kind_interleaved_keep_their_own_values():
    # four rows, alternately quadratic (smooth: 100 + 30 beta + 10 beta^2, its vertex at
    # -1.5, outside the bounds) and monotone cubic (not smooth: a line, 50 - 20 beta, and a
    # saturating row, 5 min(beta, 0)): the quadratic gives its parabola, the cubic (PCHIP)
    # a line exactly and the saturating row's constant 0 beyond its kink, between and beyond
    # the design points; each row its own, none another's
    means = np.column_stack([100 + 30 * T + 10 * T ** 2, 50 - 20 * T, 200 + 30 * T + 10 * T ** 2,
                             5 * np.minimum(T, 0.0)])
    s = sl.Surrogate(EFF, BOUNDS, T[:, None], means, [True, False, True, False])
    assert s.quadratic.tolist() == [True, False, True, False]
    for t in np.linspace(-0.3, 0.6, 13):
        got = s([t])
        want = [100 + 30 * t + 10 * t ** 2, 50 - 20 * t, 200 + 30 * t + 10 * t ** 2, 5 * min(t, 0.0)]
        assert got == pytest.approx(want, rel=1e-12, abs=1e-12), t


def _friction_bin(scatter, saturating=False):
    """A soil-bin stand-in (soilcal.loop.standin's blade force at the base friction) whose
    horizontal force is exactly quadratic in the friction factor r = mu / mu_cal, so in
    rate_friction's beta (r = 1 + beta ln(v / v0), between 0.25 and 1.33 over the bounds):
    F_h(r) = F_h (1 + 0.8 (r - 1) + 0.3 (r - 1)^2), rising over the bounds (vertex at r = -1/3);
    ``saturating``: F_h (1 + 0.4 tanh(4 (r - 1))) instead.  Seed scatter: a relative ``scatter``
    cos(40 r) times -1, 0, +1 for seeds 0, 1, 2 (mod 3), zero in the mean over three
    consecutive seeds at every design point (the loop's seeds 0-2 and the measured repeats'
    100-102) but not a seed level shared by the points."""
    import math

    from soilcal.loop import standin as S

    mu0 = S.BASE["soil_soil_static_friction"]

    def simulate(cond, params, seed):
        r = params["soil_soil_static_friction"] / mu0
        fh, _ = S.forces({**params, "soil_soil_static_friction": mu0}, cond.quantities)
        q = fh * (1 + 0.4 * math.tanh(4 * (r - 1)) if saturating else 1 + 0.8 * (r - 1) + 0.3 * (r - 1) ** 2)
        return {"horizontal_force_N": q * (1 + scatter * (seed % 3 - 1) * math.cos(40 * r))}

    return simulate


@pytest.mark.parametrize("scatter, saturating, kind, lof_p", [(0.01, False, "quadratic", 1.0),
                                                             (0.0, False, "monotone cubic", None),
                                                             (1e-5, True, "monotone cubic", 0.0)])
def test_the_selection_files_say_which_surrogate_each_fit_used(tmp_path, scatter, saturating, kind, lof_p):
    # the loop on four soil-bin rows (a hidden rate effect, beta 0.3, 1 % measured noise)
    # whose force is exactly quadratic in beta, so every row's seed means lie on a quadratic,
    # or saturates:
    # - with seed scatter about them, every row's lack-of-fit SS is 0 (rounding) against a
    #   point x seed error SS > 0: F = 0, p = 1 in every row, the quadratic (rising over the
    #   bounds, so not turning over) in every row: "quadratic", smallest p 1;
    # - without seed scatter no row has an error to test against (p NaN, smooth_fits): the
    #   monotone cubic in every row, smallest p NaN;
    # - saturating (tanh) with a seed scatter of 1e-5: over the design the rows' ln(v / v0) are
    #   0.25 to 0.48 in size, and the best quadratic in beta misses 1 + 0.4 tanh(4 beta ln(v / v0))
    #   by 0.2 % to 1 % RMS, against a point x seed error SS of at most 12 (1.4e-5)^2 (relative):
    #   F > 1e5 on (3, 10) df, p < 1e-20 in every row, the monotone cubic in every row, and the
    #   smallest p written (to 6 decimals) 0.
    # Every selection.csv row that fitted rate_friction, and loop_summary.csv where it is
    # chosen, must say so (the row-by-row surrogates, loop.surrogate: rows; the shared shape is
    # tested in test_pooled_surrogate.py).
    import json

    from soilcal.chain.files import write_csv
    from soilcal.loop import core
    from soilcal.loop import standin as S
    from soilcal.loop import synthesize as sy

    simulate = _friction_bin(scatter, saturating)
    ref = {"tool_speed": 1.75, "working_depth": 0.1, "moisture_content": 16.0}
    conds = S.conditions(S.grid(27, 4, moisture=True, days=4), measures=("horizontal_force_N",))
    table = sy.synthesize(conds, S.base_params, simulate, {"rate_friction": {"beta": 0.3}}, ref, {}, noise=0.01,
                          seed=37)
    out = core.run_inprocess("bin", sy.with_measured(conds, table), S.base_params, simulate,
                             core.Settings(reference=ref, bootstrap=0, surrogate="rows"))
    assert out.chosen == ["rate_friction"], out.verdict
    write_csv(out.selection, tmp_path / "selection.csv")
    write_csv(out.summary, tmp_path / "loop_summary.csv")
    sel = pd.read_csv(tmp_path / "selection.csv")
    rows = sel[sel["effects"].str.split("+").apply(lambda e: "rate_friction" in e) & (sel["parameters"] != "{}")]
    summary = pd.read_csv(tmp_path / "loop_summary.csv").iloc[0]
    assert len(rows)
    for kind_text, p_text in list(zip(rows["surrogate"], rows["lack_of_fit_p"])) + [
            (summary["surrogate"], summary["lack_of_fit_p"])]:
        written, lof = json.loads(kind_text), json.loads(p_text)
        assert written["rate_friction"] == kind
        if lof_p is None:
            assert np.isnan(lof["rate_friction"])
        else:
            assert lof["rate_friction"] == pytest.approx(lof_p, abs=1e-6)


def test_the_cubic_rows_are_scipys_pchip_bit_for_bit():
    # the cubic rows are evaluated from the PCHIP's pieces (Surrogate._cubic) rather than by
    # calling it: at the knots, between them, at the bounds and beyond both ends (where it
    # extrapolates), on irregular rows of either sign and several scales, the values must be
    # the interpolant's own, to the last bit
    rng = np.random.default_rng(7)
    for trial in range(40):
        means = rng.standard_normal((len(T), 5)) * rng.choice([1e-3, 1.0, 1e4]) + rng.choice([0.0, 50.0])
        s = sl.Surrogate(EFF, BOUNDS, T[:, None], means, rng.random(5) < 0.4)
        if s.pchip is None:
            continue
        for t in np.concatenate([T, rng.uniform(-0.5, 0.8, 30), [-0.3 - 1e-17, 0.6 + 1e-12, -0.0]]):
            want = np.asarray(s.pchip(float(t)))
            assert s._cubic(float(t)).tobytes() == want.tobytes(), (trial, t)
            got = s([t])
            assert got[s.cubic_rows].tobytes() == want.tobytes(), (trial, t)
