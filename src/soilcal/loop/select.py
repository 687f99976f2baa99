"""Fit, score and choose the effects that explain a residual.

For each candidate effect the simulation has been run at a small design of its parameters
(:func:`theta_design`, the switched-off value among them) at every measured condition, with
the same seeds at every design point (common random numbers).  Per measured quantity ``i`` a
surrogate ``s_i(theta)`` is fitted to the seed means over the design: one response shape shared
by a table's rows through the effect's dose where the effect has one and the shape passes its
lack-of-fit test (:class:`PooledSurrogate`, ``loop.surrogate: pooled``, the default), else row
by row (:class:`Surrogate`).  The prediction of a model with several effects adds their changes
from their switched-off values to a baseline ``b_i`` (first-order superposition:
``b_i + sum_E (s_i^E(theta_E) - s_i^E(null))``), ``b_i`` the effects' surrogates at their
switched-off values (:func:`baseline`: the calibrated model as the designs, smoothed, estimate
it), and a model's reference takes the same baseline, so that the smoothing alone gains nothing
in the comparison; effects that change
different DEM parameters act nearly independently over small changes, but not exactly (a
friction and a density both scale the passive pressure): where runs with the chosen effects
switched on together exist, their difference from that sum enters as a mixed term
(:class:`Joint`, :func:`soilcal.loop.core.run_inprocess`), as runs of a single effect at its
fitted value correct its surrogate there.

Scoring a model against a reference model (the calibrated one, or the model with the
effects already chosen), on the relative errors ``e_i = (measured_i - prediction_i) / |measured_i|``
(weighted, below):

* **held-out error**: leave-one-group-out folds (a group is a measured condition, or the
  value of the ``fold_by`` covariate); in each fold the parameters are fitted on the other
  groups (bounded least squares, scipy ``least_squares``, started from the two design
  points, or combinations of points for several effects, with the smallest error) and the
  error of the fold's rows predicted;
* **paired test** over the folds: one-sided paired t-test (scipy ``ttest_rel``) that the
  reference's fold RMS error exceeds the model's; where a fold holds several conditions (a
  test day), over the conditions' held-out gains, the mean's variance from the larger of the
  one-way ANOVA mean squares between and within folds (:func:`paired_p`);
* **information criterion**: AICc = n ln(SSE/n) + 2K + 2K(K+1)/(n-K-1) of the fit, K the
  number of effect parameters plus one (the residual variance), n the measured observations:
  replicate rows of one condition and measured quantity (one simulation, so one prediction:
  :func:`replicate_groups`) are one observation, their mean relative error, as the diagnosis
  takes them (counted as rows, three repeats tripled the log-likelihood's gain against the
  same penalty: a parameter without effect lowered the AICc in 46 % of tables of 8
  conditions x 3 repeats, 11 % on their condition means, the rate an extra parameter has);
* **confidence intervals**: from the Jacobian of the full fit, cov = s^2 (J^T J)^-1,
  s^2 = SSE/(n-k), two-sided 95 % with Student's t on n-k degrees of freedom, or, where it is
  wider, clustered by held-out group (G of them, more than k + 1): cov = G/(G-1) A B A with
  A = (J^T J)^-1 and B the sum over the groups of (J_g^T e_g)(J_g^T e_g)^T, Student's t on G-1
  (replicate rows of one condition share its deviation: taken as independent rows, 8
  conditions x 3 repeats gave half the width of their condition means' t-interval) (every
  model tried, ``selection.csv``).  They treat the surrogates as exact, but each design point is
  the mean of a few seeds: with three seeds of a quick plate (about 14 % scatter per run) the
  effect's sensitivity itself is uncertain by a fifth, and an interval of the fit alone can
  miss the parameter by far.  The chosen model's interval (``loop_summary.csv``) therefore
  also takes a bootstrap (:func:`bootstrap_ci`): the seeds of each condition resampled (one
  draw per condition for every design point of every effect and every measured quantity, so
  common random numbers are kept; the deviations from the seed mean scaled by
  sqrt(n/(n-1)), so that the resampled mean has the variance s^2/n of the sample's), the
  measured values redrawn within their standard error, the model refitted; the 2.5 and 97.5
  percentiles of :data:`BOOTSTRAP` refits, the generator seeded with :data:`BOOTSTRAP_SEED`
  (:func:`soilcal.loop.core._interval` reports the wider of the two).

**Weights** (:func:`row_weights`): each row's relative error weighs ``w_i = 1 / v_i``, ``v_i``
the variance of its relative residual, (sd_m^2 / n_m + sd_s^2 / n_s) / scale^2 with the
relative SDs pooled per measured quantity (:func:`soilcal.loop.residuals.relative_variances`,
the diagnosis's weights), the weights divided by their mean.  The quantities one test
measures (a plate's horizontal and vertical force) differ in their scatter, and taken alike
the noisy one drives the fitted parameter and the held-out comparison (on the DEM plate the
vertical force's relative seed SD is about three times the horizontal's; in the saved
two-force campaigns its rows weigh 1/15 to 1/80 of the horizontal force's, its measured
noise relative to its smaller scale adding to its seed scatter).  Where some row's variance is unknown, the rows' variances do not hold the
same parts (measured and seed), or they are all equal, every row weighs alike (the plain
least squares, number for number).  The weights run through every part above: the fit
minimises sum w_i e_i^2 (generalised least squares with a diagonal covariance known up to
one factor, sigma^2 / w_i); a fold's held-out error is the weighted RMS sqrt(sum w_i e_i^2 /
sum w_i) over its rows, and so are the conditions' gains of the paired test and the 10 % of
the acceptance (:func:`lowers_heldout`); the AICc's SSE is sum w_i e_i^2 (a replicate group's
observation its rows' weighted mean error with their mean weight; the log-likelihood's own
term of the weights, sum ln w_i / 2, is the same for a model and its reference); the
intervals' J, e and s^2 are those of the weighted residuals sqrt(w_i) e_i; the bootstrap
refits each draw with the same weights (they come from the rows' pooled variances, not from
a draw).  The RMS and largest errors of ``selection.csv`` and ``loop_summary.csv``
(``heldout_rmse_percent``, ``reference_heldout_rmse_percent``, ``rmse_before_percent``,
``rmse_after_percent``) stay those of the plain relative errors (:meth:`Score.rmse`); the
weighted held-out RMS the selection compares is :meth:`Score.weighted_rmse`
(``selection.csv``'s ``weighted_heldout_rmse_percent`` and
``reference_weighted_heldout_rmse_percent``, ``loop_summary.csv``'s
``weighted_rmse_before_percent`` and ``weighted_rmse_after_percent``, empty where every row
weighs alike), and the verdict quotes it, as "weighted held-out RMS", where it decided.

A model is accepted against its reference when the paired test's p is below ``alpha``, its
pooled (weighted) held-out RMS error is at least :data:`MIN_IMPROVEMENT` (10 %) below the reference's
(an effect whose gain is within the measurements' precision is not worth its parameter) and
its AICc is lower; :func:`forward` chooses the effects.  Where the rows' noise floor is known
(:func:`heldout_floor`: the RMS error the measured and seed scatter alone give, and its 95 %
interval) and the reference's held-out error lies above that interval, the 10 % is counted on
the part of the errors above the floor's low end, sqrt(rmse^2 - low^2) (:func:`lowers_heldout`):
no model removes the scatter.  On the DEM soil bin (``benchmarks/loop.py``, depth_compaction,
campaign 0, uniform speeds: 18 conditions, noise floor 13.90 %, its interval 11.64-17.25 %) the
density gradient took the held-out RMS error from 18.24 % to 16.84 % at paired p 0.0496: 0.923
of it in all, short of the 10 %, and 0.867 of the part above 11.64 % (14.04 % to 12.17 %).
"""

from __future__ import annotations

import bisect
import itertools
import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np
import pandas as pd

from soilcal.loop.residuals import KEY_SEP

T_PREFIX = "t:"


def theta_design(effect, bounds: dict, points: int = 5) -> list[dict]:
    """Design points of an effect's parameters: ``points`` levels evenly over each
    parameter's bounds plus its switched-off value (a full grid in two parameters)."""
    axes = []
    for k in effect.theta_names():
        lo, hi = bounds[k]
        lv = set(np.round(np.linspace(lo, hi, int(points)), 12).tolist())
        null = float(effect.null[k])
        if lo <= null <= hi:
            lv.add(null)
        axes.append(sorted(lv))
    return [dict(zip(effect.theta_names(), combo)) for combo in itertools.product(*axes)]


#: level of the lack-of-fit test (:func:`smooth_fits`) below which a one-parameter surrogate
#: interpolates its design means instead of fitting a quadratic through them
LACK_OF_FIT_ALPHA = 0.05


def _point_seed_ss(V: np.ndarray) -> float:
    """The point x seed interaction sum of squares of one row's runs ``V`` (design point x
    seed): the error of a two-way layout without replication, the seeds' own levels taken
    out (:func:`smooth_fits`, :func:`_pooled_lack_of_fit`)."""
    means = V.mean(axis=1)
    return float(np.sum((V - means[:, None] - V.mean(axis=0)[None, :] + means.mean()) ** 2))


def smooth_fits(thetas: np.ndarray, values: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """Per row, whether a least-squares quadratic in one parameter follows the design's seed
    means within that row's own seed scatter, and the row's lack-of-fit p: (smooth, p), each
    one entry a row (an empty pair where there are no values).

    ``values``: design point x row x seed (NaN where a run failed), the same seeds at every
    point (common random numbers).  Each complete row (every design point and seed run) is its
    own two-way layout, point x seed: the seeds' own levels, shared by every point, cancel in
    the changes the surrogate carries, so the error is the row's point x seed interaction
    (mean square on (D - 1)(S - 1) degrees of freedom, D points, S seeds), and the lack of fit
    the row's seed means' deviations from its quadratic, times S, on D - 3 (Montgomery, Design
    and Analysis of Experiments, lack-of-fit test; two-factor layout without replication);
    F = MS_lof / MS_error, p its upper tail.  Rows are tested one by one, never pooled: rows of
    different units or scale do not hide each other's lack of fit, and rows that one
    simulation gives (several depths of one test) are not counted as independent degrees of
    freedom.  Smooth where p >= :data:`LACK_OF_FIT_ALPHA`; not (p NaN) where there are fewer
    than four points (a quadratic through three interpolates them), fewer than two seeds, for
    an incomplete row, or for a row without scatter."""
    from scipy import stats

    from soilcal.rsm.model import RSMFit

    t = np.asarray(thetas, float).ravel()
    if values is None or values.ndim != 3:
        return np.zeros(0, bool), np.zeros(0)
    R = values.shape[1]
    p = np.full(R, math.nan)
    if len(t) < 4 or values.shape[2] < 2:
        return np.zeros(R, bool), p
    D, S = values.shape[0], values.shape[2]
    B = np.column_stack([np.ones(D), t, t ** 2])
    for i in np.flatnonzero(np.isfinite(values).all(axis=(0, 2))):  # complete rows only
        V = values[:, i, :]
        means = V.mean(axis=1)
        coef, *_ = np.linalg.lstsq(B, means, rcond=None)
        ss_lof = S * float(np.sum((means - B @ coef) ** 2))
        ss_err = _point_seed_ss(V)
        # a row whose point x seed error is rounding only (at most RSMFit.PURE_ERROR_RTOL of its
        # total, what means of equal floats leave) has no scatter to test against
        if ss_err > RSMFit.PURE_ERROR_RTOL * float(np.sum((V - V.mean()) ** 2)):
            df_lof, df_err = D - 3, (D - 1) * (S - 1)
            p[i] = float(stats.f.sf((ss_lof / df_lof) / (ss_err / df_err), df_lof, df_err))
    return np.isfinite(p) & (p >= LACK_OF_FIT_ALPHA), p


class Surrogate:
    """Per-row surrogate of one effect's parameters over its design (module docstring).  In
    one parameter, row by row: a least-squares quadratic through the design means where it
    follows them within the row's seed scatter (``smooth``, one flag a row,
    :func:`smooth_fits`: a response measured with a few seeds per point is not taken for its
    noise, which an interpolant would follow from point to point) and does not turn over
    inside the bounds where the row's means are monotone (a saturating response that a
    weak test lets through would otherwise be fitted by a quadratic falling beyond its peak);
    else a monotone cubic through the means (scipy ``PchipInterpolator``, no overshoot where
    an effect saturates, e.g. a surface energy clamped at zero).  ``quadratic``: per row,
    whether the quadratic is used.  A least-squares quadratic in two parameters."""

    def __init__(self, effect, bounds: dict, thetas: np.ndarray, means: np.ndarray, smooth=False):
        from scipy.interpolate import PchipInterpolator

        self.effect = effect
        self.names = effect.theta_names()
        self.thetas = np.asarray(thetas, float)
        self.lo = np.array([bounds[k][0] for k in self.names], float)
        self.hi = np.array([bounds[k][1] for k in self.names], float)
        self.span = self.hi - self.lo
        self.k = len(self.names)
        means = np.asarray(means, float)
        R = means.shape[1]
        self.smooth = np.broadcast_to(np.asarray(smooth, bool), (R,)).copy()
        self.pchip = None
        self.quadratic = np.ones(R, bool)
        t = None  # the one parameter's design values, where a cubic may be used
        if self.k == 1 and len(thetas) >= 3:
            self.quadratic = self.smooth & (len(thetas) >= 4)
            t = np.asarray(thetas, float)[:, 0]
            order = np.argsort(t)
        if t is None or self.quadratic.any():
            B = self._basis(self._u(thetas))
            if B.shape[0] < B.shape[1]:
                B = B[:, : 1 + self.k]  # too few points for the square terms: linear
            self.nb = B.shape[1]
            self.coef, *_ = np.linalg.lstsq(B, means, rcond=None)  # means: (design, rows) -> (basis, rows)
            if self.k == 1 and self.nb == 3:
                # a quadratic whose vertex lies inside the bounds where the row's means are
                # monotone turns over where the response does not: that row keeps the cubic
                c1, c2 = self.coef[1], self.coef[2]
                with np.errstate(divide="ignore", invalid="ignore"):
                    vertex = np.where(c2 != 0, -c1 / (2 * c2), np.inf)  # in u, the bounds are -1..1
                d = np.diff(means[order], axis=0)
                monotone = (d >= 0).all(axis=0) | (d <= 0).all(axis=0)
                self.quadratic &= ~(monotone & (np.abs(vertex) < 1))
        if t is not None and not self.quadratic.all():
            # the cubic through the rows that use it only (each row's cubic is its own)
            self.cubic_rows = np.flatnonzero(~self.quadratic)
            self.pchip = PchipInterpolator(t[order], means[order][:, self.cubic_rows], axis=0, extrapolate=True)
            # its pieces as :meth:`_cubic` evaluates them: the knots, and per interval the
            # coefficients of s^0..s^3 (one array of the rows each)
            self._knots = self.pchip.x.tolist()
            self._pieces = [tuple(self.pchip.c[3 - p, i] for p in range(4)) for i in range(len(self._knots) - 1)]
        self._any_quadratic = bool(self.quadratic.any())

    def refit(self, means: np.ndarray) -> "Surrogate":
        """The same kind of surrogate through other design means (a bootstrap draw's): each row
        keeps its ``smooth`` flag."""
        return Surrogate(self.effect, {k: (self.lo[j], self.hi[j]) for j, k in enumerate(self.names)}, self.thetas,
                         means, self.smooth)

    def kind(self) -> str:
        """Which surrogate the rows use, for the selection's files: "quadratic", "monotone
        cubic", or, where the rows differ, how many use each."""
        if self.k != 1:
            return "quadratic"
        q, n = int(self.quadratic.sum()), len(self.quadratic)
        if q == n:
            return "quadratic"
        if q == 0:
            return "monotone cubic"
        return f"quadratic in {q} of {n} rows, monotone cubic in {n - q}"

    def _u(self, thetas):
        return 2.0 * (np.atleast_2d(thetas) - self.lo) / self.span - 1.0

    @staticmethod
    def _terms(u: list, one):
        """The quadratic's terms [1, u_j, u_j^2, u_a u_b (a < b)] of the coded parameters ``u``:
        columns over the design (arrays, ``one`` a column of ones) or one point's numbers
        (``one`` 1.0, as :meth:`__call__` evaluates them)."""
        return [one] + list(u) + [v * v for v in u] + [u[a] * u[b] for a, b in itertools.combinations(range(len(u)), 2)]

    def _basis(self, U):
        return np.column_stack(self._terms([U[:, j] for j in range(self.k)], np.ones(len(U))))

    def _cubic(self, v: float) -> np.ndarray:
        """The monotone cubic's rows at ``v``, as ``self.pchip(v)`` gives them, bit for bit
        (scipy's ``PPoly`` evaluation: the interval whose left knot is the last at or below
        ``v``, the first or the last one beyond the knots; the powers of the distance s from
        that knot summed from the constant term up, s^2 as s s and s^3 as s^2 s), without the
        per-call cost of ``PPoly.__call__`` (the optimisers call this thousands of times)."""
        x = self._knots
        i = min(max(bisect.bisect_right(x, v) - 1, 0), len(x) - 2)
        c0, c1, c2, c3 = self._pieces[i]
        s = v - x[i]
        s2 = s * s
        return (((0.0 + c0) + c1 * s) + c2 * s2) + c3 * (s2 * s)

    def __call__(self, theta) -> np.ndarray:
        """The rows' values at one parameter vector ``theta`` (the quadratic's terms of plain
        numbers, :meth:`_terms`: the optimisers call this thousands of times)."""
        theta = np.asarray(theta, float).ravel()
        if self.pchip is not None:
            cubic = self._cubic(float(theta[0]))
            if not self._any_quadratic:
                return cubic
        cols = self._terms((2.0 * (theta - self.lo) / self.span - 1.0).tolist(), 1.0)
        quad = (np.array([cols[: self.nb]]) @ self.coef)[0]
        if self.pchip is not None:
            quad[self.cubic_rows] = cubic
        return quad


class PooledSurrogate:
    """One response shape shared by the rows of a measured quantity, through the effect's
    dose (:data:`soilcal.loop.effects.DOSES`), for an effect of one parameter that acts on
    every condition at a strength its covariate sets (a density factor that grows with the
    depth, a friction factor with the log of the speed).  Per group of rows (one table's one
    measured quantity), with x_i(t) the dose of row i at the parameter t:

        ln s_i(t) = l_i + a x_i(t) + b x_i(t)^2

    (s_i itself where some design mean or run of the group is not positive), a and b shared by
    the group's rows, each row's level l_i fitted over all the design points (least squares on
    the design means' logs, each row centred on its own mean).  Two coefficients per group
    instead of three per row, and every row's level from all of its design runs, not from one
    point: on a stand-in of the DEM plate's depth campaign (18 conditions, three seeds per
    point, 14 % scatter per run) the effect was found in 0.725 of campaigns against 0.55 with
    the rows' own surrogates, and its g recovered with an RMS error of 0.134 against 0.181;
    with the scatter rising from 10 % to 28 % over the depths, 0.46 against 0.27
    (``benchmarks/results/loop_surrogate/pooled_mc.md``, a proxy of the paired test).

    A group keeps it where it follows the rows' seed means within their seed scatter: the
    lack-of-fit F-test of :func:`smooth_fits`, pooled over the group's rows, on the runs' logs
    (each row's point x seed layout: the error the interaction, n (D - 1)(S - 1) degrees of
    freedom; the lack of fit the seed means of the logs about the shape refitted to them, times
    S, on n D - n - 2).  A group that fails it, or cannot be tested (fewer than two seeds or four
    points, a failed run), keeps the row-by-row :class:`Surrogate` (``rows``): the shared
    shape assumes the rows respond to the dose alike, which a test whose resistance changes
    its make-up with the covariate (friction's share of a force that inertia takes over at
    speed) need not do."""

    def __init__(self, effect, bounds: dict, thetas: np.ndarray, means: np.ndarray, z: np.ndarray, groups,
                 values: np.ndarray | None = None, smooth=False, pooled: np.ndarray | None = None):
        from soilcal.loop.effects import dose

        self.effect = effect
        self.names = effect.theta_names()
        self.k = 1
        self.thetas = np.asarray(thetas, float)
        self.bounds = dict(bounds)
        self.lo = np.array([bounds[k][0] for k in self.names], float)
        self.hi = np.array([bounds[k][1] for k in self.names], float)
        self.z = np.asarray(z, float)
        self.groups = pd.factorize(pd.Series(list(groups)).astype(str))[0]
        self._dose = dose
        means = np.asarray(means, float)
        self.rows = Surrogate(effect, bounds, self.thetas, means, smooth)
        self.smooth = self.rows.smooth
        R = means.shape[1]
        t = self.thetas[:, 0]
        X = np.stack([dose(effect.name, float(v), self.z) for v in t])  # design x row
        self.level, self.a, self.b = means[0].copy(), np.zeros(R), np.zeros(R)
        self.log = np.zeros(R, bool)
        self.lack_of_fit_p = np.full(R, math.nan)
        test = pooled is None
        self.pooled = np.zeros(R, bool) if test else np.asarray(pooled, bool).copy()
        for g in np.unique(self.groups):
            idx = np.flatnonzero(self.groups == g)
            Vg = None if values is None else values[:, idx, :]
            log = bool((means[:, idx] > 0).all() and (Vg is None or (np.nan_to_num(Vg, nan=1.0) > 0).all()))
            L = np.log(means[:, idx]) if log else means[:, idx]
            a, b, lvl = _pooled_fit(L, X[:, idx])
            self.level[idx], self.a[idx], self.b[idx], self.log[idx] = lvl, a, b, log
            if test:
                p = _pooled_lack_of_fit(Vg, X[:, idx], log, len(t))
                self.lack_of_fit_p[idx] = p
                self.pooled[idx] = np.isfinite(p) and p >= LACK_OF_FIT_ALPHA
        self._all = bool(self.pooled.all())

    def refit(self, means: np.ndarray) -> "PooledSurrogate":
        """The same surrogate through other design means (a bootstrap draw's): the groups keep
        the form their lack-of-fit test gave them."""
        return PooledSurrogate(self.effect, self.bounds, self.thetas, means, self.z, self.groups, None, self.smooth,
                               self.pooled)

    def kind(self) -> str:
        n, q = len(self.pooled), int(self.pooled.sum())
        if q == n:
            return "pooled through the dose"
        if q == 0:
            return self.rows.kind()
        return f"pooled through the dose in {q} of {n} rows, the rest {self.rows.kind()}"

    def __call__(self, theta) -> np.ndarray:
        x = self._dose(self.effect.name, float(np.asarray(theta, float).ravel()[0]), self.z)
        v = self.level + self.a * x + self.b * x * x
        v = np.where(self.log, np.exp(v), v)
        if self._all:
            return v
        out = self.rows(theta)
        out[self.pooled] = v[self.pooled]
        return out


def _pooled_fit(L: np.ndarray, X: np.ndarray) -> tuple[float, float, np.ndarray]:
    """(a, b, levels) of L[d, i] = l_i + a X[d, i] + b X[d, i]^2 by least squares (every row
    centred on its mean; a and b 0 where the doses do not vary, a row's level then its mean)."""
    Xc, X2c = X - X.mean(axis=0), X * X - (X * X).mean(axis=0)
    A = np.column_stack([Xc.ravel(), X2c.ravel()])
    a = b = 0.0
    if np.any(A != 0):
        (a, b), *_ = np.linalg.lstsq(A, (L - L.mean(axis=0)).ravel(), rcond=None)
    return float(a), float(b), (L - a * X - b * X * X).mean(axis=0)


def _pooled_lack_of_fit(V: np.ndarray | None, X: np.ndarray, log: bool, D: int) -> float:
    """The pooled shape's lack-of-fit p over a group's runs ``V`` (design x row x seed):
    :class:`PooledSurrogate`; NaN where it cannot be tested."""
    from scipy import stats

    if V is None or V.ndim != 3 or D < 4 or V.shape[2] < 2 or not np.isfinite(V).all():
        return math.nan
    W = np.log(V) if log else V
    n, S = W.shape[1], W.shape[2]
    M = W.mean(axis=2)
    a, b, lvl = _pooled_fit(M, X)
    ss_lof = S * float(np.sum((M - (lvl + a * X + b * X * X)) ** 2))
    ss_err = sum(_point_seed_ss(W[:, i, :]) for i in range(n))
    df_lof = n * D - n - (2 if np.ptp(X) > 0 else 0)
    df_err = n * (D - 1) * (S - 1)
    if df_lof <= 0 or not ss_err > 1e-12 * float(np.sum((W - W.mean()) ** 2)):
        return math.nan
    return float(stats.f.sf((ss_lof / df_lof) / (ss_err / df_err), df_lof, df_err))


@dataclass
class EffectData:
    """One candidate's simulated design: the surrogate over all usable rows, and each
    run's value (``values``: design point x row x seed position, NaN where a run failed or
    a row has fewer seeds) for the bootstrap."""

    effect: object
    bounds: dict
    surrogate: Surrogate  # or a PooledSurrogate (build_effect_data)
    design: list = field(default_factory=list)
    missing: list = field(default_factory=list)  # rows with a failed run at some design point
    values: np.ndarray | None = None
    seeds: list | None = None  # per row, the seeds behind values' last axis (ascending)
    means: np.ndarray | None = None  # design x row: the means the surrogate went through (or was fitted to)
    lack_of_fit_p: np.ndarray | None = None  # per row, the one-parameter surrogate's lack-of-fit p (:func:`smooth_fits`)

    def thetas(self) -> np.ndarray:
        return np.array([[d[k] for k in self.effect.theta_names()] for d in self.design], float)

    @property
    def at_null(self) -> np.ndarray | None:
        """The surrogate's rows at the switched-off parameters: the calibrated model's means as
        this effect's design estimates them (None for the uniform scale, :func:`scale_data`)."""
        if isinstance(self.surrogate, _ScaleSurrogate):
            return None
        if "_at_null" not in self.__dict__:
            null = np.array([float(self.effect.null[k]) for k in self.effect.theta_names()])
            self.__dict__["_at_null"] = np.asarray(self.surrogate(null), float)
        return self.__dict__["_at_null"]


def baseline(effects: list, y0: np.ndarray) -> np.ndarray:
    """The calibrated model's means that a model of ``effects`` (:class:`EffectData`) adds their
    changes to: per row the mean of the effects' surrogates at their switched-off parameters
    (:attr:`EffectData.at_null`); ``y0`` (the calibrated runs' means) where none has a
    surrogate (the calibrated model itself, the uniform scale alone).

    A surrogate smooths over all its design points, so at the switched-off value it is a
    closer estimate of the calibrated model than the calibrated runs' mean alone.  A model and
    the reference it is scored against take the same baseline (:class:`Model`'s ``base``):
    taken against the calibrated runs' means, the smoothing alone "gained" significantly in
    12-17 % of stand-in campaigns with no effect, 0-1 % against the surrogate's own value
    there (``benchmarks/results/loop_surrogate/pooled_mc.md``)."""
    at = [e.at_null for e in effects if e.at_null is not None]
    return np.asarray(y0, float) if not at else np.mean(at, axis=0)


@dataclass(frozen=True)
class Narrowing:
    """Where a one-parameter effect's runs stop measuring: every run at the levels past the
    working range failed (a tail of its design, :func:`narrowing`).  ``low``..``high``: the
    levels contiguous with the switched-off value at which every row measured (the range the
    effect is fitted over); ``failed_below`` / ``failed_above``: the nearest failing level on
    each side (None where that side works to the design's end); ``where``: the first row that
    failed there and its error; ``gaps``: the levels a second round runs between the working
    range and the failures, to learn how far the scenario goes."""

    effect: str
    param: str
    low: float
    high: float
    failed_below: float | None
    failed_above: float | None
    where: str
    gaps: tuple

    def failed(self) -> str:
        """Where its runs stopped measuring, and the first failing row's error."""
        sides = [f"{'at or above' if s == 'above' else 'at or below'} {v:g}"
                 for s, v in (("below", self.failed_below), ("above", self.failed_above)) if v is not None]
        return f"{self.effect}.{self.param}: no run measured {' or '.join(sides)} ({self.where})"

    def text(self) -> str:
        if self.low == self.high:
            return self.failed() + f"; every row measured at its switched-off value {self.low:g} alone"
        return self.failed() + f"; fitted over {self.low:g} to {self.high:g}, the levels at which every row measured"


def _row_key(rec) -> str:
    return f"{rec[0]} row {rec[1]} {rec[2]}"


def narrowing(runs: pd.DataFrame, effect, points: int = 5) -> Narrowing | None:
    """The :class:`Narrowing` of a one-parameter effect whose runs (``measurement``, ``row``,
    ``measure``, ``value``, ``status``, ``t:<name>``) fail at every level past some level on
    one side of its switched-off value, for some row: a scenario that the effect, strong
    enough, leaves with nothing to measure (soil held by an adhesive tube leaves no heap),
    which says the measured value rules those levels out rather than that the response stays
    at its last value (the interpolation of :func:`_fill_failed` for isolated failures).  None
    where the effect has two parameters, its switched-off level failed or is not in the
    design, or no side fails to its end.  ``gaps``: ``max(2, points - working levels)`` levels
    evenly inside each failing gap."""
    names = effect.theta_names()
    if len(names) != 1 or runs is None or not len(runs):
        return None
    k = names[0]
    col = T_PREFIX + k
    if col not in runs.columns:
        return None
    level = pd.to_numeric(runs[col], errors="coerce").to_numpy(float)
    value = pd.to_numeric(runs["value"], errors="coerce").to_numpy(float)
    ok = np.isfinite(value)
    if "status" in runs.columns:
        ok &= runs["status"].astype(str).to_numpy() == "ok"
    keys = list(zip(runs["measurement"].astype(str), runs["row"], runs["measure"].astype(str)))
    levels = sorted({float(x) for x in level[np.isfinite(level)]})
    null = float(effect.null[k])
    if null not in levels:
        return None
    works, first = [], {}
    for lv in levels:
        at = level == lv
        rows = {kk for kk, a in zip(keys, at) if a}
        good = {kk for kk, a, o in zip(keys, at, ok) if a and o}
        works.append(rows <= good)
        bad = sorted(rows - good, key=str)
        if bad:
            i = next(j for j, (kk, a) in enumerate(zip(keys, at)) if a and kk == bad[0])
            err = str(runs["error"].iloc[i]) if "error" in runs.columns and pd.notna(runs["error"].iloc[i]) else ""
            # the error's first clause (the run file holds all of it)
            first[lv] = _row_key(bad[0]) + (f": {err.split('; ')[0]}" if err else ": no value")
    i0 = levels.index(null)
    if not works[i0]:
        return None
    lo_i = hi_i = i0
    while hi_i + 1 < len(levels) and works[hi_i + 1]:
        hi_i += 1
    while lo_i > 0 and works[lo_i - 1]:
        lo_i -= 1
    above = hi_i + 1 < len(levels) and not any(works[hi_i + 1:])
    below = lo_i > 0 and not any(works[:lo_i])
    if not (above or below):
        return None
    n_gap = max(2, int(points) - (hi_i - lo_i + 1))
    gaps = []
    if above:
        gaps += np.linspace(levels[hi_i], levels[hi_i + 1], n_gap + 2)[1:-1].tolist()
    if below:
        gaps += np.linspace(levels[lo_i - 1], levels[lo_i], n_gap + 2)[1:-1].tolist()
    near = levels[hi_i + 1] if above else levels[lo_i - 1]
    return Narrowing(effect.name, k, levels[lo_i] if below else levels[0], levels[hi_i] if above else levels[-1],
                     levels[lo_i - 1] if below else None, levels[hi_i + 1] if above else None,
                     first[near], tuple(sorted(round(float(g), 12) for g in gaps)))


def within(runs: pd.DataFrame, nar: Narrowing) -> pd.DataFrame:
    """The runs at the levels of a :class:`Narrowing`'s working range."""
    lv = pd.to_numeric(runs[T_PREFIX + nar.param], errors="coerce")
    return runs[(lv >= nar.low) & (lv <= nar.high)]


def _fill_failed(Y: np.ndarray, design: list, effect, obs: pd.DataFrame | None) -> list[str]:
    """Fill, in place, the NaN cells of the design-point means ``Y`` (design x rows): a run
    that failed at a design point; the row's value there is interpolated over its other
    points (one parameter) or taken from the switched-off point (two); a row with fewer than
    two points is refused.  Returns the rows filled."""
    names = effect.theta_names()
    index = {t: j for j, t in enumerate(design)}
    null = tuple(float(effect.null[k]) for k in names)
    missing = []
    for i in np.flatnonzero(np.isnan(Y).any(axis=0)):
        ok = ~np.isnan(Y[:, i])
        where = (f"{obs['measurement'].iloc[i]} row {obs['row'].iloc[i]} {obs['measure'].iloc[i]}"
                 if obs is not None else f"row {i + 1}")
        if ok.sum() < 2:
            raise ValueError(f"effect {effect.name}: fewer than two design points simulated for {where}")
        missing.append(where)
        if len(names) == 1:
            xs = np.array([t[0] for t in design])
            Y[~ok, i] = np.interp(xs[~ok], xs[ok], Y[ok, i])
        elif null in index and ok[index[null]]:
            Y[~ok, i] = Y[index[null], i]
        else:
            raise ValueError(f"effect {effect.name}: no simulated value of {where} at the switched-off point")
    return missing


def build_effect_data(obs: pd.DataFrame, runs: pd.DataFrame, effect, bounds: dict,
                      reference: dict | None = None) -> EffectData:
    """Surrogate of ``effect`` from its runs (measurement, row, measure, value, ``t:<name>``,
    and ``seed`` for the bootstrap) for the rows of ``obs`` (a failed run at a design point:
    :func:`_fill_failed`): a :class:`PooledSurrogate` where ``reference`` (quantity -> the
    value where the calibrated parameters hold) is given and the effect has a dose
    (:data:`soilcal.loop.effects.DOSES`; the rows' quantities from ``obs``' ``q:`` columns),
    else a :class:`Surrogate`."""
    from soilcal.loop.effects import DOSES, dose_z

    names = effect.theta_names()
    tcols = [T_PREFIX + k for k in names]
    design = sorted({tuple(float(x) for x in t) for t in runs[tcols].itertuples(index=False)})  # every point run
    r = runs[np.isfinite(pd.to_numeric(runs["value"], errors="coerce"))]
    if "status" in r.columns:
        r = r[r["status"].astype(str) == "ok"]
    means = r.groupby(["measurement", "row", "measure"] + tcols)["value"].mean().reset_index()
    Y = np.full((len(design), len(obs)), np.nan)
    index = {t: j for j, t in enumerate(design)}
    keys = {(m, int(rw), ms): i for i, (m, rw, ms) in enumerate(zip(obs["measurement"], obs["row"], obs["measure"]))}
    for rec in means.itertuples(index=False):
        i = keys.get((rec[0], int(rec[1]), rec[2]))
        if i is not None:
            Y[index[tuple(float(x) for x in rec[3:3 + len(tcols)])], i] = rec[-1]
    values, seeds = _seed_values(r, obs, design, index, keys, tcols)
    missing = _fill_failed(Y, design, effect, obs.reset_index(drop=True))
    smooth, p_lof = smooth_fits(np.array(design), values) if len(names) == 1 else (False, None)
    if len(names) == 1 and len(smooth) == 0:
        smooth, p_lof = False, np.full(len(obs), math.nan)
    if reference is not None and effect.name in DOSES and len(names) == 1:
        qcols = [c for c in obs.columns if str(c).startswith("q:")]
        z = np.array([dose_z(effect.name, {c[2:]: v for c, v in zip(qcols, rec) if pd.notna(v)}, reference)
                      for rec in obs[qcols].itertuples(index=False)], float)
        groups = (obs["measurement"].astype(str) + KEY_SEP + obs["measure"].astype(str)).to_numpy()
        sg = PooledSurrogate(effect, bounds, np.array(design), Y, z, groups, values, smooth)
        p_lof = np.where(sg.pooled, sg.lack_of_fit_p, p_lof)
    else:
        sg = Surrogate(effect, bounds, np.array(design), Y, smooth)
    return EffectData(effect, bounds, sg, [dict(zip(names, t)) for t in design], missing, values, seeds, Y.copy(),
                      p_lof)


def _seed_values(r: pd.DataFrame, obs, design, index, keys, tcols):
    """(design x row x seed position array of each run's value, per row its seeds in
    ascending order): NaN where a run failed or a row has fewer seeds; (None, None) without
    a seed column.  Runs without a seed number are left out (they cannot be paired)."""
    if "seed" not in r.columns:
        return None, None
    sd = pd.to_numeric(r["seed"], errors="coerce")
    r = r[np.isfinite(sd) & (sd == np.round(sd))]  # a seed is a whole number
    if r.empty:
        return None, None
    seeds = [[] for _ in range(len(obs))]
    for (m, rw, ms), sd in r.groupby(["measurement", "row", "measure"])["seed"]:
        i = keys.get((m, int(rw), ms))
        if i is not None:
            seeds[i] = sorted({int(x) for x in sd})
    ns = max((len(v) for v in seeds), default=0)
    if ns == 0:
        return None, None
    out = np.full((len(design), len(obs), ns), np.nan)
    pos = [{sd: j for j, sd in enumerate(v)} for v in seeds]
    for rec in r[["measurement", "row", "measure", "seed", "value"] + tcols].itertuples(index=False):
        i = keys.get((rec[0], int(rec[1]), rec[2]))
        if i is None:
            continue
        d = index[tuple(float(x) for x in rec[5:5 + len(tcols)])]
        out[d, i, pos[i][int(rec[3])]] = float(rec[4])
    return out, seeds


@dataclass(frozen=True, eq=False)
class Folds:
    """The folds of a cross-validation: ``held_out``, the index arrays of the rows held out
    together (one array a fold), and ``units``, the index arrays of the simulated conditions,
    each within one fold (:func:`paired_p` tests over them), or None where the folds are not
    grouped by a covariate (each fold is then one condition).  Compared by identity: arrays
    have no single truth value."""

    held_out: list[np.ndarray]
    units: list[np.ndarray] | None = None


def _folds(obs: pd.DataFrame, fold_by: str | None) -> Folds:
    """The :class:`Folds` of ``obs``: as ``held_out``, the groups of the values of
    ``fold_by`` (a covariate column), else the simulated conditions (rows of one test measured
    twice, as two rows of a table or in two tables, are held out together:
    :func:`soilcal.loop.residuals.simulation_key`); with ``fold_by``, the conditions within each
    group as ``units`` (else None)."""
    cond = (obs["simulation"].astype(str) if "simulation" in obs
            else obs["measurement"].astype(str) + "/" + obs["row"].astype(str))
    if fold_by:
        raw = obs[f"cov:{fold_by}"]
        col = ("g:" + raw.astype(str)).where(raw.notna(), "c:" + cond)  # a row without the group: its condition
    else:
        col = cond
    held_out = [np.flatnonzero(col.to_numpy() == g) for g in dict.fromkeys(col)]
    if not fold_by:
        return Folds(held_out)
    # a condition's rows lie in one group (a table's row carries one value of fold_by)
    key = (col + KEY_SEP + cond).to_numpy()
    return Folds(held_out, [np.flatnonzero(key == g) for g in dict.fromkeys(key)])


@dataclass
class Joint:
    """The interaction of a model's effects, from runs with all of them switched on together at
    ``centre`` (one value per parameter, in the model's order; every effect of one parameter):
    per row ``gap`` = the joint runs' mean - the first-order sum of the effects' separate changes
    there (:func:`joint_gap`).  :meth:`Model.predict` adds ``gap`` times the product over the
    effects of (theta - null) / (centre - null): the mixed term of a second-order expansion
    about the switched-off point, zero where any effect is off and exact at ``centre`` (for a
    single effect, the surrogate's error at ``centre``, brought in linearly from the
    switched-off value, where the surrogate is exact)."""

    gap: np.ndarray
    centre: np.ndarray
    null: np.ndarray

    def weight(self, x) -> float:
        return float(np.prod((np.asarray(x, float) - self.null) / (self.centre - self.null)))


def joint_gap(effects: list, y0: np.ndarray, centre: np.ndarray, joint_means: np.ndarray) -> np.ndarray:
    """Per row the joint runs' mean at ``centre`` less the first-order prediction there (the
    calibrated mean plus each effect's change from its own surrogate); 0 where a row has no
    joint run."""
    first = Model(effects, y0, np.ones_like(y0)).predict(np.asarray(centre, float))
    return np.where(np.isfinite(joint_means), joint_means - first, 0.0)


#: the relative step of scipy's forward differences (``approx_derivative`` with its default
#: '2-point' method: the square root of the float64 machine epsilon)
_FD_STEP = np.finfo(np.float64).eps ** 0.5


def forward_difference(fun, lo: np.ndarray, hi: np.ndarray):
    """(residuals, Jacobian) to hand scipy's ``least_squares`` for the residual function ``fun``
    within the bounds ``lo``-``hi``: the Jacobian is the forward-difference one that
    ``least_squares`` computes itself with its default ``jac='2-point'``
    (``scipy.optimize._numdiff.approx_derivative``), number for number: the step
    sqrt(eps) max(1, |x|) with the sign of x, reversed where it would cross a bound and fits
    on the other side, else cut to the farther bound; the same differences, divisions and array
    layout.  It takes the residuals at x from the point the optimiser evaluated last (every
    Jacobian of the trust-region method is at such a point) and leaves out the generality of
    scipy's routine, whose overhead was larger than the residuals' cost on the loop's small
    problems.  ``tests/loop/test_forward_difference.py`` compares the fits with scipy's own."""
    last = []

    def residuals(x):
        out = fun(x)
        last[:] = [np.array(x, float), out]
        return out

    def jac(x):
        x0 = np.asarray(x, float)
        f0 = last[1] if last and np.array_equal(last[0], x0) else np.atleast_1d(fun(x0))
        h = _FD_STEP * ((x0 >= 0).astype(float) * 2 - 1) * np.maximum(1.0, np.abs(x0))
        below, above = x0 - lo, hi - x0
        step = x0 + h
        fitting = np.abs(h) <= np.maximum(below, above)
        h[((step < lo) | (step > hi)) & fitting] *= -1
        forward = (above >= below) & ~fitting
        h[forward] = above[forward]
        backward = (above < below) & ~fitting
        h[backward] = -below[backward]
        jt = np.empty((x0.size, f0.size))
        for i in range(x0.size):
            x1 = x0.copy()
            x1[i] = x0[i] + h[i]
            jt[i] = (np.atleast_1d(fun(x1)) - f0) / ((x0[i] + h[i]) - x0[i])
        return (np.ravel(jt) if f0.size == 1 else jt).T

    return residuals, jac


@dataclass
class Model:
    """Effects with fitted parameters and the calibrated means they modify: the prediction is
    the baseline of ``base`` (:func:`baseline`; default the model's own effects) plus each
    effect's change from its switched-off value, s_i(theta) - s_i(null).  A reference scored
    against a model with more effects takes that model's effects as its ``base`` (the same
    calibrated means under both)."""

    effects: list            # EffectData
    y0: np.ndarray           # calibrated simulated means of the rows; the baseline of ``base`` replaces it
    measured: np.ndarray
    scale: np.ndarray | None = None  # the relative errors' denominators (residuals.scales); default |measured|
    joint: Joint | None = None  # the effects' interaction from runs with all of them on (:class:`Joint`)
    # per row the weight of its squared relative error, mean 1 (:func:`row_weights`); None: every row alike
    weights: np.ndarray | None = None
    base: list | None = None  # the EffectData whose switched-off values give the baseline (None: ``effects``)
    # the noise floor's interval (low, high) in the held-out RMS error's weighting (:func:`heldout_floor`):
    # a reference's carries into its scores (:func:`lowers_heldout`); None: not known
    floor: tuple | None = None
    # what its fits share (:meth:`_at_starts`, :func:`full_fit`, :func:`cross_validate`): the
    # fields are not changed once the model has been fitted
    _cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def __post_init__(self):
        self.y0 = baseline(self.effects if self.base is None else self.base, self.y0)
        if self.scale is None:
            self.scale = np.abs(np.asarray(self.measured, float))
        if self.weights is not None:
            self.weights = np.asarray(self.weights, float)
        self._root_w = None if self.weights is None else np.sqrt(self.weights)

    @property
    def k(self) -> int:
        return sum(e.surrogate.k for e in self.effects)

    def predict(self, x: np.ndarray, values: list | None = None) -> np.ndarray:
        """The baseline plus each effect's change from its switched-off value; a uniform scale
        (:func:`scale_data`) multiplies the sum, as a bias of the whole model does.  ``values``: per effect, its
        surrogate's value at its part of ``x`` where that is known already."""
        out = self.y0
        factor = 1.0
        j = 0
        for i, e in enumerate(self.effects):
            if isinstance(e.surrogate, _ScaleSurrogate):
                factor = 1.0 + float(x[j])
            else:
                out = out + ((e.surrogate(x[j:j + e.surrogate.k]) if values is None else values[i]) - e.at_null)
            j += e.surrogate.k
        if self.joint is not None:
            out = out + self.joint.gap * self.joint.weight(np.asarray(x, float)[:len(self.joint.centre)])
        return out * factor

    def errors(self, x, idx=None) -> np.ndarray:
        return self._relative(self.predict(x), np.arange(len(self.y0)) if idx is None else idx)

    def _relative(self, predicted, rows) -> np.ndarray:
        """The relative errors of rows ``rows`` of a prediction."""
        return (self.measured[rows] - predicted[rows]) / self.scale[rows]

    def weighted(self, e, rows=None) -> np.ndarray:
        """The relative errors ``e`` of rows ``rows`` (all by default) times the square root of
        their weights: the residuals whose sum of squares the fit minimises; ``e`` itself where
        every row weighs alike."""
        if self._root_w is None:
            return e
        return e * (self._root_w if rows is None else self._root_w[rows])

    def rms(self, e, rows) -> float:
        """The RMS of the relative errors ``e`` of rows ``rows``, weighted by the rows' weights,
        sqrt(sum w e^2 / sum w) (the plain RMS where every row weighs alike)."""
        if self.weights is None:
            return float(np.sqrt(np.mean(e ** 2)))
        w = self.weights[rows]
        return float(np.sqrt(np.sum(w * e ** 2) / np.sum(w)))

    def bounds(self):
        lo = np.concatenate([e.surrogate.lo for e in self.effects]) if self.effects else np.zeros(0)
        hi = np.concatenate([e.surrogate.hi for e in self.effects]) if self.effects else np.zeros(0)
        return lo, hi

    def _at_starts(self):
        """(every combination of the effects' design points, within the bounds: the starts, and
        the prediction at each): every fit of the model (one a held-out fold,
        :func:`cross_validate`) ranks the same starts, so they are predicted once (the model's
        effects, means and joint term are not changed after its first fit), each effect's
        surrogate once at each of its own design points."""
        if "starts" not in self._cache:
            points, values = [], []
            for e in self.effects:
                sg = e.surrogate
                pts = [np.clip(np.array([d[k] for k in e.effect.theta_names()], float), sg.lo, sg.hi) for d in e.design]
                points.append(pts)
                values.append([None if isinstance(sg, _ScaleSurrogate) else sg(p) for p in pts])
            starts, predicted = [], []
            for c in itertools.product(*(range(len(p)) for p in points)):
                x = np.concatenate([points[i][j] for i, j in enumerate(c)])
                starts.append(x)
                predicted.append(self.predict(x, [values[i][j] for i, j in enumerate(c)]))
            self._cache["starts"] = (starts, predicted)
        return self._cache["starts"]

    def fit(self, idx=None, x0=None):
        """Least-squares parameters on rows ``idx`` (all by default); (x, result or None): the
        sum over the rows of w e^2, e the relative error and w the row's weight (``weights``,
        :func:`row_weights`; 1 where every row weighs alike), so the residuals handed to the
        optimiser are sqrt(w) e and its Jacobian theirs.  The search starts from the two best
        design points and, where given, from ``x0`` as well (a refit near an earlier answer: a
        second minimum is still found); the lowest cost wins."""
        from scipy.optimize import least_squares

        if not self.effects:
            return np.zeros(0), None
        lo, hi = self.bounds()
        rows = np.arange(len(self.y0)) if idx is None else idx

        # the rows' measured values and scales taken once: the same relative errors as
        # self.errors(x, rows), for the many evaluations of one fit
        measured, scale = self.measured[rows], self.scale[rows]
        if self._root_w is not None:
            root_w = self._root_w[rows]
            if idx is None:
                errors, jac = forward_difference(lambda x: (measured - self.predict(x)) / scale * root_w, lo, hi)
            else:
                errors, jac = forward_difference(lambda x: (measured - self.predict(x)[rows]) / scale * root_w, lo, hi)
        elif idx is None:
            errors, jac = forward_difference(lambda x: (measured - self.predict(x)) / scale, lo, hi)
        else:
            errors, jac = forward_difference(lambda x: (measured - self.predict(x)[rows]) / scale, lo, hi)
        best = None
        if x0 is not None:
            best = least_squares(errors, np.clip(np.asarray(x0, float), lo, hi), jac=jac, bounds=(lo, hi),
                                 method="trf")
        starts, predicted = self._at_starts()
        cost = [float(np.sum(self.weighted(self._relative(p, rows), rows) ** 2)) for p in predicted]
        null = np.concatenate([[e.effect.null[k] for k in e.effect.theta_names()] for e in self.effects])
        span = np.where(hi > lo, hi - lo, 1.0)
        dist = [float(np.sum(((s - null) / span) ** 2)) for s in starts]
        # the two best design points start the search; a tie (data that do not move the
        # result) goes to the switched-off value
        for j in sorted(range(len(starts)), key=lambda j: (round(cost[j], 12), dist[j]))[:2]:
            res = least_squares(errors, starts[j], jac=jac, bounds=(lo, hi), method="trf")
            if best is None or res.cost < best.cost - 1e-15:
                best = res
        return best.x, best


@dataclass
class Score:
    names: list
    theta: dict
    ci: dict
    fold_rms: np.ndarray
    ref_fold_rms: np.ndarray
    heldout_errors: np.ndarray
    ref_heldout_errors: np.ndarray
    fitted_errors: np.ndarray
    aicc: float
    ref_aicc: float
    p: float
    accepted: bool
    reason: str
    no_test: str = ""  # where p is NaN, why the paired test could not be run
    own_reason: str = ""  # the score's own reason where ``reason`` puts the backward gate's words before it
    aicc_spare: int = 0  # observations beyond the fewest for which the model's AICc is defined (:func:`aicc_needs`)
    test: "PairedTest | None" = None  # which paired test gave ``p`` (:func:`paired_p`); None where none could be run
    heldout_weights: np.ndarray | None = None  # the weights of the held-out rows (:func:`row_weights`); None: alike
    floor: tuple = (math.nan, math.nan)  # the noise floor's interval (:func:`heldout_floor`), from the reference

    @property
    def weighted(self) -> bool:
        """Whether the held-out rows weigh differently (:func:`row_weights`)."""
        return self.heldout_weights is not None

    def p_text(self, digits: int = 2) -> str:
        """The paired test's p for a sentence, or, where it could not be run, why."""
        if np.isfinite(self.p):
            return f"paired p {self.p:.{digits}g}"
        return "no paired test (" + (self.no_test or "it could not be computed") + ")"

    def rmse(self, ref=False) -> float:
        """The plain RMS of the held-out relative errors (the model's, or with ``ref`` its
        reference's)."""
        e = self.ref_heldout_errors if ref else self.heldout_errors
        return float(np.sqrt(np.mean(e ** 2))) if len(e) else math.nan

    def weighted_rmse(self, ref=False) -> float:
        """The held-out RMS error the selection compares (:func:`lowers_heldout`, :func:`forward`):
        sqrt(sum w e^2 / sum w) with the rows' weights (:func:`row_weights`), the plain
        :meth:`rmse` where every row weighs alike."""
        if self.heldout_weights is None:
            return self.rmse(ref)
        e = self.ref_heldout_errors if ref else self.heldout_errors
        w = self.heldout_weights
        return float(np.sqrt(np.sum(w * e ** 2) / np.sum(w))) if len(e) else math.nan

    def max_error(self, ref=False) -> float:
        e = self.ref_heldout_errors if ref else self.heldout_errors
        return float(np.max(np.abs(e))) if len(e) else math.nan


#: relative spread of the rows' variances within which they count as equal (:func:`row_weights`):
#: a quantity's pooled variance is one number for all its rows, but two quantities of equal
#: relative variance computed from different data may differ in their last bits
ALIKE_RTOL = 1e-12


def row_weights(obs: pd.DataFrame) -> np.ndarray | None:
    """Per row of ``obs`` the weight of its squared relative error in the selection's fits,
    held-out errors and AICc (module docstring): w = 1 / v, v the row's relative variance
    (:func:`soilcal.loop.residuals.relative_variances`: (sd_m^2 / n_m + sd_s^2 / n_s) / scale^2,
    the relative SDs pooled per measured quantity), divided by their mean, so that the weights'
    mean is 1.  None (every row alike: the unweighted least squares) where some row's variance
    is unknown (no measured SD and one seed, a table without those columns), where the rows'
    variances do not hold the same parts (a quantity without any measured SD, whose seed
    scatter alone understates its variance, beside one with it), the same rules as the
    diagnosis's weights (:func:`soilcal.loop.diagnose.per_test`), or where the variances are
    equal within :data:`ALIKE_RTOL`."""
    from soilcal.loop.residuals import relative_variances

    if len(obs) == 0:
        return None
    v, parts = relative_variances(obs, parts=True)
    if not np.all(np.isfinite(v)) or len(set(np.asarray(parts).tolist())) != 1:
        return None
    if float(np.max(v) - np.min(v)) <= ALIKE_RTOL * float(np.max(v)):
        return None
    w = 1.0 / v
    return w / np.mean(w)


def replicate_groups(obs: pd.DataFrame) -> np.ndarray | None:
    """Per row the label of its observation for the information criterion: rows of one
    simulation (:func:`soilcal.loop.residuals.simulation_key`: replicate rows of a condition, a
    test entered in two tables) and one measured quantity share one prediction and are one
    observation; None (every row its own) without a ``simulation`` column."""
    if "simulation" not in obs.columns or "measure" not in obs.columns:
        return None
    return (obs["simulation"].astype(str) + "|" + obs["measure"].astype(str)).to_numpy()


def sse_of(e: np.ndarray, groups: np.ndarray | None, weights: np.ndarray | None = None) -> tuple[float, int]:
    """(sum of squares, observations) of the relative errors ``e``: over the rows, or over the
    mean error of each replicate group (:func:`replicate_groups`).  With ``weights`` (per row,
    :func:`row_weights`) the weighted sum of squares sum w e^2, a replicate group's error its
    rows' weighted mean with their mean weight: replicate rows of one quantity share its weight
    but for their repeat counts."""
    e = np.asarray(e, float)
    if weights is None:
        if groups is None:
            return float(np.sum(e ** 2)), len(e)
        means = pd.Series(e).groupby(np.asarray(groups), sort=False).mean().to_numpy(float)
        return float(np.sum(means ** 2)), len(means)
    w = np.asarray(weights, float)
    if groups is None:
        return float(np.sum(w * e ** 2)), len(e)
    code = pd.factorize(np.asarray(groups))[0]  # (numpy sums: a pandas aggregation per score cost more than its fits)
    sw, swe, cnt = (np.bincount(code, weights=x) for x in (w, w * e, np.ones(len(e))))
    return float(np.sum(sw / cnt * (swe / sw) ** 2)), len(sw)


def aicc(sse: float, n: int, k: int) -> float:
    """AICc of ``n`` observations with ``k`` estimated parameters (the residual variance
    among them); NaN where it is undefined, ``n <= k + 1`` (the small-sample term
    2k(k+1)/(n-k-1) has no finite value: a criterion that cannot score the model, not one
    that scores it infinitely badly, :func:`aicc_needs`); -inf for an exact fit."""
    if n - k - 1 <= 0:
        return math.nan
    if sse <= 0:
        return -math.inf
    return n * math.log(sse / n) + 2 * k + 2 * k * (k + 1) / (n - k - 1)


def aicc_needs(k: int) -> int:
    """The fewest observations for which the AICc of ``k`` estimated parameters is defined."""
    return int(k) + 2


def aicc_lower(s) -> bool:
    """Whether a :class:`Score`'s model lowers the AICc of its reference; False where either's
    AICc is undefined (too few observations, :func:`aicc`): the model cannot be scored."""
    if math.isnan(s.aicc) or math.isnan(s.ref_aicc):
        return False
    return s.aicc < s.ref_aicc


def full_fit(model: Model):
    """``model.fit()`` on all rows, done once per model (a model is scored against several
    references, and serves as the reference of several)."""
    if "fit" not in model._cache:
        model._cache["fit"] = model.fit()
    return model._cache["fit"]


def cross_validate(model: Model, folds: Folds) -> tuple[np.ndarray, np.ndarray]:
    """(fold RMS errors, held-out relative error of every row) of a model; done once per
    model and folds (copies returned).  A fold's RMS error is weighted by its rows' weights
    where the model has them (:meth:`Model.rms`); the held-out errors are the plain relative
    errors."""
    if folds not in model._cache:
        model._cache[folds] = _cross_validate(model, folds)
    rms, held = model._cache[folds]
    return rms.copy(), held.copy()


def _cross_validate(model: Model, folds: Folds) -> tuple[np.ndarray, np.ndarray]:
    n = len(model.y0)
    held = np.full(n, np.nan)
    rms = []
    for f in folds.held_out:
        train = np.setdiff1d(np.arange(n), f)
        if len(train) < model.k + 1:
            rms.append(np.nan)
            continue
        x, _ = model.fit(train)
        e = model.errors(x, f)
        held[f] = e
        rms.append(model.rms(e, f))
    return np.array(rms), held


#: smallest relative fall of the held-out RMS error for which an effect is worth its parameter
MIN_IMPROVEMENT = 0.1


def heldout_floor(obs: pd.DataFrame, weights: np.ndarray | None = None, level: float = 0.95) -> tuple:
    """The noise floor's ``level`` interval (low, high), as fractions, in the weighting of the
    held-out RMS error the selection compares (:meth:`Score.weighted_rmse`): the interval of
    :func:`soilcal.loop.residuals.noise_floor_and_interval` over the rows ``obs``, times
    sqrt(sum w v / sum w) / sqrt(mean v) with the rows' ``weights`` (:func:`row_weights`) and
    their floor variances v (:func:`soilcal.loop.residuals.floor_variances`) where the rows
    weigh differently.  (NaN, NaN) where the floor or its interval is not known (a table
    without the residual table's columns among them)."""
    from soilcal.loop.residuals import floor_variances, noise_floor_and_interval

    if (len(obs) == 0 or not {"measurement", "measure"} <= set(obs.columns)
            or not {"scale", "measured"} & set(obs.columns)):
        return (math.nan, math.nan)
    floor, _, (lo, hi, _) = noise_floor_and_interval(obs, level=level)
    if not (np.isfinite(floor) and floor > 0 and np.isfinite(lo) and np.isfinite(hi)):
        return (math.nan, math.nan)
    if weights is not None:
        v = floor_variances(obs)
        w = np.asarray(weights, float)
        k = math.sqrt(float(np.sum(w * v) / np.sum(w))) / floor
        if not np.isfinite(k):
            return (math.nan, math.nan)
        lo, hi = lo * k, hi * k
    return (float(lo), float(hi))


def above_floor(rmse: float, low: float) -> float:
    """The part of a held-out RMS error above the noise floor's low bound ``low``,
    sqrt(max(rmse^2 - low^2, 0))."""
    return math.sqrt(max(rmse * rmse - low * low, 0.0))


def floor_counts(s) -> bool:
    """Whether :func:`lowers_heldout` judges a :class:`Score` on the part of its errors above the
    noise floor: the floor's interval is known and the reference's held-out RMS error lies
    above its high end."""
    lo, hi = s.floor
    return bool(np.isfinite(lo) and np.isfinite(hi) and s.weighted_rmse(True) > hi)


def lowers_heldout(s, min_improvement: float = MIN_IMPROVEMENT) -> bool:
    """Whether a :class:`Score`'s model lowers its reference's held-out RMS error (weighted where
    the rows weigh differently: :meth:`Score.weighted_rmse`) by at least ``min_improvement``
    (:data:`MIN_IMPROVEMENT`), counted on the part of the error above the noise floor where
    the floor is known (:func:`floor_counts`): no model removes the measured and seed scatter,
    so the floor would otherwise dilute the gain.  That part is sqrt(rmse^2 - low^2), with the
    low end of the floor's 95 % interval (:func:`heldout_floor`; the floor is itself estimated
    from a few repeats and seeds, and its low end leaves the larger part to explain); where the
    reference's error is within the floor's interval, or the floor is unknown, the whole
    error (the low end 0), as before."""
    rmse, ref = s.weighted_rmse(), s.weighted_rmse(True)
    lo = s.floor[0] if floor_counts(s) else 0.0
    return above_floor(rmse, lo) <= (1 - min_improvement) * above_floor(ref, lo)


def short_of_p(s, alpha: float) -> bool:
    """Whether a :class:`Score`'s model lowers its reference's held-out RMS error by at least
    :data:`MIN_IMPROVEMENT` and its AICc, and fails only on the paired test (p >= ``alpha``)."""
    return (lowers_heldout(s) and aicc_lower(s)
            and not (np.isfinite(s.p) and s.p < alpha))


#: fewest folds holding conditions for which :func:`paired_p` tests over the conditions (over
#: 2 test days the conditions' test rejected up to 7.6 % of null draws at level 0.05)
MIN_POOLED_FOLDS = 4


class PairedTest(NamedTuple):
    """The paired test's one-sided p and which test gave it: ``test`` is ``"folds"`` (a paired
    t-test of the folds' RMS errors) or ``"conditions"`` (the conditions' held-out gains,
    :func:`paired_p`), ``df`` its degrees of freedom; over the conditions, ``ms_between`` and
    ``ms_within`` the one-way ANOVA mean squares of the gains by fold and ``variance`` which of
    them the mean's variance took (``"between"`` or ``"within"``)."""

    p: float
    test: str
    df: int
    ms_between: float = math.nan
    ms_within: float = math.nan
    variance: str = ""

    def text(self) -> str:
        """The test for a sentence."""
        if self.test == "folds":
            return f"paired t-test over the folds, {self.df} df"
        return (f"paired t-test over the conditions, the mean gain's variance from the {self.variance}-fold mean "
                f"square ({self.ms_between:.3g} between, {self.ms_within:.3g} within), {self.df} df")


def paired_p(ref_rms, fold_rms, ref_held, held, folds: Folds, weights: np.ndarray | None = None) -> PairedTest:
    """One-sided p that the reference's held-out error exceeds the model's (:class:`PairedTest`).

    The differences of the folds' RMS errors (``ref_rms - fold_rms``) go to a paired t-test
    over the folds.  Where a fold holds several conditions (``folds.units``, a test day held
    out whole) the folds are few (four test days: three degrees of freedom) and that test is
    weak however clear the gain within them.  The conditions' own gains (``d``: the RMS over
    each condition's rows of its held-out errors, predicted by the fit without its fold, the
    reference's minus the model's; N of them over a folds) are then tested instead, their mean
    against the larger of the one-way ANOVA mean squares by fold: t = mean(d) / sqrt(max(MSB,
    MSW) / N), on a - 1 degrees of freedom where MSB (between folds) is taken, N - a where MSW
    (within folds) is.  The conditions of one day share its fitted parameters and its level, so
    their gains are correlated: the mean's variance is then E[MSB] / N (equal folds), which MSW
    alone underestimates; where the days do not differ, MSW is the sharper estimate of it.
    The larger of the two is taken, with no preliminary test of whether the days differ
    (pooling where an F pretest found the days alike, p >= 0.25, let too many null cases
    through on 2 days).  Size at level 0.05 on normal null gains (day effect + condition noise, SD(day)/SD(condition) 0, 0.5, 1,
    2; 4000 draws per setup): 0.018-0.056 on 4 days x 2, 3 or 5 and 6 days x 3 or 5
    conditions; on 2 days x 3 or 9 it was 0.021-0.076, so with fewer than
    :data:`MIN_POOLED_FOLDS` folds holding conditions (or no fold with two conditions) the test
    stays over the folds (0.037-0.051 there).  With unequal folds E[MSB] / N falls short of the
    mean's variance where the days differ (not measured).  ``weights`` (per row,
    :func:`row_weights`): each condition's RMS errors weighted as the folds' are
    (:meth:`Model.rms`).  The weights act only within each fold's or condition's RMS error: the
    test over the folds counts every fold alike (and the one over the conditions every
    condition), however much weight its rows carry."""
    from scipy import stats

    ok = np.isfinite(fold_rms) & np.isfinite(ref_rms)
    over_folds = PairedTest(float(stats.ttest_rel(ref_rms[ok], fold_rms[ok], alternative="greater").pvalue),
                            "folds", int(ok.sum()) - 1)
    if not folds.units:
        return over_folds
    fold_of = np.full(len(held), -1)
    for j, f in enumerate(folds.held_out):
        fold_of[f] = j
    d, g = [], []
    for u in folds.units:
        e, er = held[u], ref_held[u]
        if len(u) and np.all(np.isfinite(e)) and np.all(np.isfinite(er)):
            if weights is None:
                d.append(math.sqrt(float(np.mean(er ** 2))) - math.sqrt(float(np.mean(e ** 2))))
            else:
                w = weights[u]
                d.append(math.sqrt(float(np.sum(w * er ** 2) / np.sum(w)))
                         - math.sqrt(float(np.sum(w * e ** 2) / np.sum(w))))
            g.append(int(fold_of[u[0]]))
    d, g = np.asarray(d), np.asarray(g)
    groups = [d[g == j] for j in dict.fromkeys(g.tolist())]
    a, n = len(groups), len(d)
    if a < MIN_POOLED_FOLDS or n <= a:
        return over_folds
    m = float(d.mean())
    msb = sum(len(x) * (float(x.mean()) - m) ** 2 for x in groups) / (a - 1)
    msw = sum(float(np.sum((x - x.mean()) ** 2)) for x in groups) / (n - a)
    var, df, which = (msb, a - 1, "between") if msb >= msw else (msw, n - a, "within")
    if not var > 0:
        return over_folds
    return PairedTest(float(stats.t.sf(m / math.sqrt(var / n), df)), "conditions", df, msb, msw, which)


def score(model: Model, ref: Model, folds: Folds, alpha: float = 0.05, min_improvement: float = MIN_IMPROVEMENT,
          groups: np.ndarray | None = None) -> Score:
    """Score ``model`` against ``ref`` (module docstring); ``groups``: each row's observation
    for the AICc (:func:`replicate_groups`; default every row its own).  Both models weigh the
    rows alike (their ``weights``, :func:`row_weights`): errors of different weights are not
    compared."""
    from scipy import stats

    if (model.weights is None) != (ref.weights is None) or (
            model.weights is not None and not np.array_equal(model.weights, ref.weights)):
        raise ValueError("score: the model and its reference weigh the rows differently (Model.weights, "
                         "select.row_weights); both are to be built with the same weights")
    n = len(model.y0)
    fold_rms, held = cross_validate(model, folds)
    ref_rms, ref_held = cross_validate(ref, folds)
    ok = np.isfinite(fold_rms) & np.isfinite(ref_rms)
    x, res = full_fit(model)
    xr, _ = full_fit(ref)
    e = model.errors(x)
    er = ref.errors(xr)
    r = model.weighted(e)  # sqrt(w) e: the residuals of the weighted fit (e itself where the rows weigh alike)
    sse = float(np.sum(r ** 2))
    k = model.k
    # + 1: the residual variance is estimated too; replicate rows are one observation
    obs_m, obs_r = sse_of(e, groups, model.weights), sse_of(er, groups, ref.weights)
    a, ar = aicc(*obs_m, k + 1), aicc(*obs_r, ref.k + 1)
    names = [f"{ed.effect.name}.{t}" for ed in model.effects for t in ed.effect.theta_names()]
    ci = {}
    if res is not None and n > k:
        from scipy import stats as st

        J = res.jac
        s2 = sse / (n - k)
        if np.linalg.matrix_rank(J) < k:  # the data do not pin a parameter down
            half = np.full(k, np.inf)
        else:
            A = np.linalg.pinv(J.T @ J)
            half = st.t.ppf(0.975, n - k) * np.sqrt(np.clip(np.diag(s2 * A), 0, None))
            groups = [f for f in folds.held_out if len(f)]
            if len(groups) > k + 1:  # the wider of it and the interval clustered by held-out group
                g = len(groups)
                meat = sum(np.outer(J[f].T @ r[f], J[f].T @ r[f]) for f in groups)
                cr = g / (g - 1) * A @ meat @ A
                half = np.maximum(half, st.t.ppf(0.975, g - 1) * np.sqrt(np.clip(np.diag(cr), 0, None)))
        # the surrogates end at the design's bounds, and so does a finite interval (an infinite
        # one says the fit does not pin the parameter down, and stays so)
        lo, hi = model.bounds()
        ci = {nm: ((float(max(x[j] - half[j], lo[j])), float(min(x[j] + half[j], hi[j]))) if np.isfinite(half[j])
                   else (-math.inf, math.inf)) for j, nm in enumerate(names)}
    d = ref_rms[ok] - fold_rms[ok]
    test = None
    if ok.sum() < 2:
        p = math.nan
        n_folds = len(folds.held_out)
        if n_folds < 2:
            reason = (f"fewer than two folds to compare ({n_folds} held-out group: the rows of one measured "
                      "condition, or of one loop.fold_by group, are held out together; more conditions decide)")
        else:
            reason = (f"fewer than two folds to compare (of {n_folds} held-out groups, {int(ok.sum())} could be "
                      "predicted from a fit without their rows)")
    elif np.allclose(d, d[0]) if len(d) else True:
        p = 0.0 if len(d) and d[0] > 0 else 1.0
        test = PairedTest(p, "folds", int(ok.sum()) - 1)
        test_text = "every fold's held-out RMS error changed alike"
        reason = ""
    else:
        test = paired_p(ref_rms, fold_rms, ref_held, held, folds, model.weights)
        p, test_text = test.p, test.text()
        reason = ""
    hm = np.isfinite(held) & np.isfinite(ref_held)
    out = Score(names=names, theta=dict(zip(names, map(float, x))), ci=ci, fold_rms=fold_rms, ref_fold_rms=ref_rms,
                heldout_errors=held[hm], ref_heldout_errors=ref_held[hm], fitted_errors=e, aicc=a, ref_aicc=ar,
                p=p, accepted=False, reason=reason, no_test=reason if not np.isfinite(p) else "",
                aicc_spare=int(obs_m[1]) - aicc_needs(k + 1), test=test,
                heldout_weights=None if model.weights is None else model.weights[hm],
                floor=tuple(ref.floor) if ref.floor is not None else (math.nan, math.nan))
    rmse, rmse_r = out.weighted_rmse(), out.weighted_rmse(True)
    if not reason:
        fails = []
        if not (p < alpha):
            fails.append(f"held-out error not significantly lower ({test_text}: p = {p:.3g} >= {alpha:g})")
        if not (rmse < rmse_r):
            fails.append(f"{'weighted ' if out.weighted else ''}held-out RMS error not lower")
        elif not lowers_heldout(out, min_improvement):
            if floor_counts(out):
                lo = out.floor[0]
                fails.append(f"{'weighted ' if out.weighted else ''}held-out RMS error above the noise floor lower "
                             f"by less than {100 * min_improvement:g} % ({100 * above_floor(rmse, lo):.2f} % vs "
                             f"{100 * above_floor(rmse_r, lo):.2f} % above the floor's low end {100 * lo:.2f} %; "
                             f"in all {100 * rmse:.2f} % vs {100 * rmse_r:.2f} %)")
            else:
                fails.append(f"{'weighted ' if out.weighted else ''}held-out RMS error lower by less than "
                             f"{100 * min_improvement:g} % ({100 * rmse:.2f} % vs {100 * rmse_r:.2f} %)")
        undefined = [(nm, kk, o[1]) for nm, kk, v, o in (("the model", k + 1, a, obs_m),
                                                            ("its reference", ref.k + 1, ar, obs_r)) if math.isnan(v)]
        if undefined:  # not scored (judged by the held-out test alone, 2 of 12 tables of 4 offset rows named an effect)
            fails.append("; ".join(
                f"AICc of {nm} undefined: {n_} observations for {k_} estimated parameters (the residual variance "
                f"among them), which need {aicc_needs(k_)} at least, so it cannot be scored" for nm, k_, n_ in undefined))
        elif not (a < ar):
            fails.append(f"AICc not lower ({a:.2f} vs {ar:.2f})")
        out = _renamed(out, "; ".join(fails))
        out.accepted = not fails
    return out


#: refits of the chosen model's bootstrap interval (module docstring), and its generator's seed
BOOTSTRAP = 200
BOOTSTRAP_SEED = 0


def bootstrap_ci(effects: list, y0: np.ndarray, measured: np.ndarray, measured_se: np.ndarray,
                 n_boot: int = BOOTSTRAP, seed: int = BOOTSTRAP_SEED, level: float = 0.95, x0=None,
                 conditions=None, scale: np.ndarray | None = None, joint: Joint | None = None,
                 weights: np.ndarray | None = None) -> dict | None:
    """Bootstrap interval of the parameters of the model with ``effects``
    (:class:`EffectData` with their runs' ``values`` and ``seeds``) over the seeds and the
    measured values (module docstring): parameter name -> (low, high).

    Each draw takes, per simulation (``conditions``: one label per row; rows with one label
    and the same seeds, such as a condition's horizontal and vertical force, or two tables'
    rows that one job simulates, share the draw; default: each row its own), as many seeds
    with replacement as it has (the union of its seeds over the effects), the same seeds
    for every design point of every effect.  A row with no run of the drawn seeds at some
    design point (or no numbered seed at all) keeps the mean the surrogate went through
    there; ``scale``: the rows' relative-error denominators (default |measured|,
    :func:`soilcal.loop.residuals.scales`); the draws' deviations from each design point's seed mean are added to the mean
    the surrogate went through (which also counts runs without a seed number).  Each refit
    searches from ``x0`` (the fitted parameters) where given, and from the draw's best design
    points (:meth:`Model.fit`), with the rows' ``weights`` (:func:`row_weights`; the fit's own:
    they come from the rows' pooled variances, not from a draw).  None where
    nothing can be resampled (no per-seed values, fewer than two seeds per row, ``n_boot``
    0) or where fewer than half the draws leave every row two design points."""
    import warnings

    if n_boot <= 0 or not effects or any(e.values is None or e.seeds is None or e.means is None for e in effects):
        return None
    n = len(y0)
    union = [sorted(set().union(*(e.seeds[i] for e in effects))) for i in range(n)]
    if max(len(u) for u in union) < 2:
        return None
    labels = np.arange(n) if conditions is None else pd.factorize(pd.Series(list(conditions)).astype(str))[0]
    keys = [(int(g), tuple(union[i])) for i, g in enumerate(labels)]  # one draw per simulation and seed set
    order = {k: j for j, k in enumerate(sorted(set(keys)))}
    gindex = np.array([order[k] for k in keys])
    gseeds = [list(k[1]) for k in order]
    width = max(len(v) for v in gseeds)
    # per effect: for each row, where each of its condition's seeds sits on the effect's seed
    # axis (the padding slot, NaN, where the effect has no run of that seed)
    prepared = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a cell without a seed: NaN, filled below
        for e in effects:
            V = e.values
            pad = V.shape[2]
            W = np.full((n, width), pad)
            for i in range(n):
                at = {sd: j for j, sd in enumerate(e.seeds[i])}
                cs = gseeds[gindex[i]]
                W[i, :len(cs)] = [at.get(sd, pad) for sd in cs]
            Vp = np.concatenate([V, np.full(V.shape[:2] + (1,), np.nan)], axis=2)
            mean = np.nanmean(V, axis=2)[..., None]
            count = np.sum(np.isfinite(V), axis=2)[..., None]
            prepared.append((Vp, W, pad, mean, np.sqrt(count / np.maximum(count - 1, 1)),
                             [tuple(t) for t in e.thetas()]))
    rng = np.random.default_rng(seed)
    se = np.where(np.isfinite(measured_se), measured_se, 0.0)
    names = [f"{e.effect.name}.{t}" for e in effects for t in e.effect.theta_names()]
    draws = []
    for _ in range(int(n_boot)):
        picks = np.full((len(gseeds), width), -1)
        for g, v in enumerate(gseeds):  # as many seeds as the condition has, with replacement
            picks[g, :len(v)] = rng.integers(0, len(v), size=len(v))
        rows = picks[gindex]  # (n, width), -1 beyond a condition's own seed count
        m = measured + se * rng.standard_normal(n)
        fitted, lost = [], False
        for e, (Vp, W, pad, mean, widen, design) in zip(effects, prepared):
            at = np.where(rows >= 0, np.take_along_axis(W, np.clip(rows, 0, None), axis=1), pad)
            take = np.take_along_axis(Vp, np.broadcast_to(at[None], (Vp.shape[0],) + at.shape), axis=2)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                Y = e.means + np.nanmean(widen * (take - mean), axis=2)
            none = ~np.isfinite(Y).any(axis=0)  # no run of the drawn seeds: the surrogate's own means
            Y[:, none] = e.means[:, none]
            try:
                _fill_failed(Y, design, e.effect, None)
            except ValueError:  # a row left without two design points in this draw
                lost = True
                break
            fitted.append(EffectData(e.effect, e.bounds, e.surrogate.refit(Y),
                                     e.design))
        if lost:
            continue
        x, _ = Model(fitted, y0, m, scale, joint, weights).fit(x0=x0)
        draws.append(x)
    if len(draws) < max(20, n_boot // 2):
        return None
    tail = 100 * (1 - level) / 2
    lo, hi = np.percentile(np.array(draws), [tail, 100 - tail], axis=0)
    return {nm: (float(lo[j]), float(hi[j])) for j, nm in enumerate(names)}


class _ScaleEffect:
    """A uniform relative change of every simulated value (the prediction, the effects'
    changes included, times 1 + s: :meth:`Model.predict`): no mechanism, the alternative
    the chosen effects are scored against (:func:`forward`)."""

    name = "uniform_scale"
    null = {"s": 0.0}
    # measured values from a millionth to a million times the model's: a table in another unit
    # (kN under a name in N) is fitted as the factor it is off by, which the verdict names
    # (:func:`soilcal.loop.core.unit_hints`), not held at a bound and then read as rows that
    # scatter about the bound
    bounds = {"s": (-1.0 + 1e-6, 1e6)}

    def theta_names(self) -> tuple[str, ...]:
        return ("s",)


class _ScaleSurrogate:
    """The scale's bounds and size; :meth:`Model.predict` applies it (it multiplies the sum)."""

    def __init__(self):
        self.lo = np.array([_ScaleEffect.bounds["s"][0]])
        self.hi = np.array([_ScaleEffect.bounds["s"][1]])
        self.k = 1


def scale_data() -> EffectData:
    """The uniform scale (:class:`_ScaleEffect`) as an effect of a :class:`Model`."""
    eff = _ScaleEffect()
    return EffectData(eff, dict(eff.bounds), _ScaleSurrogate(), design=[{"s": -0.5}, {"s": 0.0}, {"s": 0.5}])


@dataclass
class Selection:
    chosen: list                  # effect names, in the order added
    steps: list                   # (step, candidate names, Score) of every model tried
    final: Score | None
    forward_chosen: list = field(default_factory=list)  # before the backward gate
    uniform: Score | None = None  # the chosen effects against a free uniform scale alone
    uniform_s: float = math.nan   # that scale's fitted s (prediction y0 (1 + s))
    uniform_ci: tuple = (math.nan, math.nan)  # its 95 % interval (the scale alone against the calibrated model)
    beside_uniform: Score | None = None  # the chosen effects beside a free uniform scale against the scale alone
    with_scale: bool = False      # an effect was taken beside a free uniform scale (forward), so the scale stays
    judged: list = field(default_factory=list)  # the effects uniform and beside_uniform score
    held_back: list = field(default_factory=list)  # (effect, Score) a forward step tried beside the scale (forward)


def forward(obs: pd.DataFrame, y0: np.ndarray, data: dict, fold_by: str | None = None, alpha: float = 0.05,
            max_effects: int = 2, shared: dict | None = None, floor: tuple | None = None) -> Selection:
    """Selection over the candidates ``data`` (name -> :class:`EffectData`):

    1. forward: add, one at a time, the candidate whose model has the lowest held-out RMS
       error among those that lower both the held-out error and the AICc of the current
       model (up to ``max_effects``);
    2. backward gate: every chosen effect must lower the held-out error significantly
       against the model without it (paired test over the folds, p < ``alpha``), as is or
       with a free uniform scale of the simulated values on both models (:func:`scale_data`);
       the one with the largest p is dropped until all pass.

    A single effect thus faces the calibrated model; two effects that each leave the other's
    error in the folds are added together and each is tested against the other alone.

    An effect that shifts every row (a soil-tool adhesion adds to every force) also fits a
    table whose values are a uniform few per cent off the model, which no mechanism is.  So
    the chosen effects are also scored against a free uniform scale of the simulated values
    alone (:func:`scale_data`): ``uniform`` is that score, and where it is not accepted the
    held-out rows cannot tell the chosen effects from a uniform bias, which the verdict says
    (the effects stay named: a true adhesion on a few rows often cannot be told from a bias
    either, and testing it against the scale rejected half of such tables); ``beside_uniform``
    scores the effects beside that scale against the scale alone, and where they do not lower
    its AICc (:func:`like_a_constant`) the verdict leaves the offset unexplained.

    ``shared``: a dict that selections over the same rows (``obs``, ``y0``) and the same
    :class:`EffectData` of each candidate share, a later one with more candidates (the loop's
    second round): the folds and one :class:`Model` per set of effects, each fitted and
    cross-validated once over all of them; every score is the one a selection of its own
    gives.  ``floor``: the rows' noise-floor interval in the selection's weighting
    (:func:`heldout_floor` of ``obs``, computed here where not given), which every reference
    carries into its score (:func:`lowers_heldout`).
    """
    measured = obs["measured"].to_numpy(float)
    from soilcal.loop.residuals import scale_of

    shared = {} if shared is None else shared
    scale = scale_of(obs) if "measured" in obs else None
    weights = row_weights(obs)
    floor = heldout_floor(obs, weights) if floor is None else floor
    if fold_by not in shared.setdefault("folds", {}):  # (compared by identity: a model's cross-validations)
        shared["folds"][fold_by] = _folds(obs, fold_by)
    folds = shared["folds"][fold_by]
    groups = replicate_groups(obs)
    chosen: list[str] = []
    steps = []

    # one Model per set of effects: each is fitted and cross-validated once (full_fit, cross_validate)
    models = shared.setdefault("models", {})
    if "bias" not in shared:
        shared["bias"] = scale_data()
    bias = shared["bias"]

    def model(names, with_bias=False, base=None):
        """The model of the effects ``names`` (and the free uniform scale), on the baseline of
        the effects ``base`` (default ``names``: a reference takes its challenger's)."""
        effects = [data[c] for c in names] + ([bias] if with_bias else [])
        base = list(names) if base is None else list(base)
        key = (tuple(e.effect.name for e in effects), tuple(base))
        if key not in models:
            models[key] = Model(effects, y0, measured, scale, weights=weights, base=[data[c] for c in base],
                                floor=floor)
        return models[key]

    def scaled(names, base=None):
        return model(names, with_bias=True, base=base)

    def gains(s):
        return lowers_heldout(s) and aicc_lower(s)

    with_scale = False  # whether an effect was added beside the free uniform scale: the scale stays in the model
    held_back = []  # (effect, Score): beside the scale it gained, against the model held without the scale it did not
    for step in range(1, max_effects + 1):
        better = []
        for name in data:
            if name in chosen:
                continue
            ref, ref_scaled = model(chosen, base=chosen + [name]), scaled(chosen, base=chosen + [name])
            # as is, else with a free uniform scale on both models: a calibration offset beside
            # the effect, which an adhesion alone cannot take where the offset cancels the
            # adhesion's mean (the gate below admits an effect either way).  Once an effect came
            # in beside the scale, the next only so; a next effect after one taken as is is also
            # tried beside the scale (an adhesion under a load cell 8 % low beside a rate effect
            # taken as is fitted gamma_a 0.1 for 2.5 and was left out in 16 of 16 campaigns,
            # beside the scale named in 14, the other two said not separated: held_back, the
            # gate).  Where both forms gain, the scale is taken where it lowers the AICc by more
            # than CONSTANT_AICC
            forms = []
            for sc in ((True,) if with_scale else (False, True)):
                s = score((scaled if sc else model)(chosen + [name]), ref_scaled if sc else ref, folds, alpha,
                          groups=groups)
                steps.append((step, chosen + [name] + ([bias.effect.name] if sc else []), s))
                if gains(s) and sc and chosen and not with_scale:
                    # the scale is not in the model held so far: the effect and the scale together
                    # must pass the gate against that model as well (an adhesion and a scale took
                    # up a moisture cohesion beside a rate effect: 2.5 % held-out error down to
                    # 2.1 % against the rate effect with the scale, paired p 0.13 against it as is)
                    held = score(scaled(chosen + [name]), ref, folds, alpha,
                                 groups=groups)
                    steps.append((f"{step}, against " + "+".join(chosen) + " as is", chosen + [name]
                                  + [bias.effect.name], held))
                    if not held.accepted:
                        held_back.append((name, held))
                        continue
                if gains(s):
                    forms.append((name, s, sc))
            if len(forms) == 2 and not forms[1][1].aicc < forms[0][1].aicc - CONSTANT_AICC:
                forms = forms[:1]
            better += forms[-1:]
        if not better:
            break
        # the lowest held-out error; where some carry the scale, the lowest AICc (the held-out
        # error favours the scale's extra parameter: a rate effect beside it beat a true weak
        # adhesion taken as is)
        mixed = any(t[2] for t in better) and not all(t[2] for t in better)
        name, _, sc = min(better, key=lambda t: (t[1].aicc, t[1].weighted_rmse()) if mixed
                          else (t[1].weighted_rmse(), t[1].aicc))
        chosen.append(name)
        with_scale = with_scale or sc
    forward_chosen = list(chosen)
    if chosen and not with_scale:
        # an offset beside the effects taken as is (its 95 % interval leaves out 0): without the
        # scale, any effect that takes up part of it passes its gate (an adhesion run to its
        # bound under an 8 % offset let a rate effect of beta 0.01 in), so the gates take it
        lo, hi = score(scaled(chosen), scaled([], base=chosen), folds, alpha,
                       groups=groups).ci.get("uniform_scale.s", (math.nan, math.nan))
        with_scale = bool(np.isfinite(lo) and np.isfinite(hi) and (lo > 0.0 or hi < 0.0))

    def gate(names, nm):
        """The effect ``nm`` against the model without it; where that fails, both with a free
        uniform scale (the nuisance a calibration offset needs: a rate effect on six speeds
        under an offset passes only there)."""
        rest = [c for c in names if c != nm]
        s2 = score(scaled(names), scaled(rest, base=names), folds, alpha, groups=groups)
        if with_scale:  # an effect the forward step took beside the scale is tested beside it only
            return s2 if s2.accepted else _renamed(s2, f"without {nm}, with a free uniform scale on both: " + s2.reason)
        s = score(model(names), model(rest, base=names), folds, alpha, groups=groups)
        if s.accepted:
            return s
        return s2 if s2.accepted else _renamed(s, f"without {nm}, as is and with a free uniform scale on both "
                                                  + (f"(p {s2.p:.3g}): " if np.isfinite(s2.p) else f"({s2.p_text(3)}): ") + s.reason)

    while chosen:
        gates = [(nm, gate(chosen, nm)) for nm in chosen]
        for nm, s in gates:
            steps.append(("gate", [c for c in chosen], s))
        failing = [(nm, s) for nm, s in gates if not s.accepted]
        if not failing:
            break
        worst = max(failing, key=lambda t: (t[1].p if np.isfinite(t[1].p) else 2.0))[0]
        chosen.remove(worst)
    final = score(model(chosen), model([], base=chosen), folds, alpha, groups=groups) if chosen else None
    uniform, uniform_s, uniform_ci, beside = None, math.nan, (math.nan, math.nan), None
    # the effects judged against a uniform scale: those chosen, or, where the gates beside the
    # scale dropped them all, those the forward step took (they fit an offset the scale fits)
    judged = chosen or (forward_chosen if with_scale else [])
    if judged:
        alone = scaled([], base=judged)
        uniform = score(model(judged), alone, folds, alpha, groups=groups)
        own = score(alone, model([], base=judged), folds, alpha, groups=groups)  # the scale alone: its value and interval
        uniform_s = float(own.theta["uniform_scale.s"])
        uniform_ci = tuple(own.ci.get("uniform_scale.s", (math.nan, math.nan)))
        beside = score(scaled(judged), alone, folds, alpha,
                       groups=groups)
    return Selection(chosen=chosen, steps=steps, final=final, forward_chosen=forward_chosen, uniform=uniform,
                     uniform_s=uniform_s, uniform_ci=uniform_ci, beside_uniform=beside, with_scale=with_scale,
                     judged=judged, held_back=held_back)


#: AICc units by which the chosen effects beside a free uniform scale must beat the scale alone
#: where no uniform offset shows beside them: models within 2 of the best have substantial
#: support (Burnham & Anderson, Model Selection and Multimodel Inference, 2nd ed., 2002, Sec. 2.6)
CONSTANT_AICC = 2.0


def rule_of_one(sel: Selection, alpha: float = 0.05) -> bool:
    """Whether the chosen effects are kept for beating a free uniform scale alone where the nested
    comparison (the effects beside that scale against the scale alone) cannot decide: they were
    chosen, beat the scale alone (``uniform``: the selection's own gate, each model with its own
    parameters), and beside the scale their held-out error is lower by :data:`MIN_IMPROVEMENT`
    with the paired test passed (p < ``alpha``), while the AICc there is undefined (:func:`aicc`:
    one effect and the scale on four observations, two on five) or, for one effect, defined on
    the fewest observations it needs, where its small-sample term decides (one effect and the
    scale on five: 24 against 6 for the scale alone).  Otherwise the nested comparison decides
    (6 conditions, a 6 % offset, an all-positive candidate that beat the scale alone with
    p 0.036 but not beside it, p 0.12, was named; two candidates beside the scale on 6, the
    fewest for their AICc, were named in 1 of 25 such tables)."""
    b = sel.beside_uniform
    if not sel.chosen or b is None or b.accepted or sel.uniform is None or not sel.uniform.accepted:
        return False
    if not (math.isnan(b.aicc) or math.isnan(b.ref_aicc) or (b.aicc_spare == 0 and len(sel.chosen) == 1)):
        return False
    return bool(lowers_heldout(b) and np.isfinite(b.p) and b.p < alpha)


def like_a_constant(sel: Selection, alpha: float = 0.05) -> bool:
    """Whether the chosen effects' signature cannot be told from a constant on these rows.
    Beside a free uniform scale of the simulated values they count as more than a constant when
    they pass the selection's own gate against the scale alone (held-out error significantly
    lower in the paired test over the folds, by :data:`MIN_IMPROVEMENT`, and a lower AICc), or,
    where the scale fitted beside them is nil (its 95 % interval holds 0: no offset shows
    beside the effects), when they lower its AICc by more than :data:`CONSTANT_AICC`.  A uniform
    offset (a load cell's calibration) otherwise fits a soil-tool adhesion, which adds to every
    force, though no mechanism of it shows.  On the stand-in blade (18 conditions, 2-5 % noise)
    an AICc test alone named an effect for one offset table in about eight (10 %: an adhesion
    with a rate effect 6.1 lower beside a scale of 0.069; 27 %: an adhesion 0.36 lower, its
    held-out error higher); a weak hidden adhesion on twelve tests (gamma_a 1.0, 2 % noise)
    lowers it by 9.7 beside a scale of 0.005 though its paired test over few folds does not
    decide.

    Where the rows are too few to score them beside the scale (its AICc undefined,
    :func:`aicc`: one effect and the scale on four observations) or just enough (five), that
    comparison does not decide,
    and they count as more than a constant where they were chosen, beat the scale alone and
    lower the held-out error beside it (:func:`rule_of_one`): a criterion that
    cannot be computed says nothing of a constant (4 conditions with a trend of 30 % over their
    range and no offset, 2 % noise: the trend was chosen and then called a uniform bias in 16 of
    16 tables).  Where the nested comparison is scored and fails on its held-out error or paired
    test, or has more observations than the fewest it needs, beating the scale alone does not
    count."""
    b = sel.beside_uniform
    if b is None or b.accepted:
        return False
    if rule_of_one(sel, alpha):
        return False
    if math.isnan(b.aicc) or math.isnan(b.ref_aicc):
        return True
    lo, hi = b.ci.get("uniform_scale.s", (math.nan, math.nan))
    nil = bool(np.isfinite(lo) and np.isfinite(hi) and lo <= 0.0 <= hi)
    lower = bool(np.isfinite(b.aicc) and np.isfinite(b.ref_aicc) and b.aicc < b.ref_aicc - CONSTANT_AICC)
    return not (nil and lower)


def _renamed(s: Score, reason: str) -> Score:
    from dataclasses import replace

    return replace(s, reason=reason, own_reason=s.own_reason or s.reason)
