r"""Sequential, surrogate-guided design for the inverse problem (``design: adaptive``).

A calibration asks for the parameter sets whose simulated responses equal the measured targets
within a tolerance, not for an optimum.  This design spends its runs where that question is
still open and stops when a verified candidate answers it.

Space
-----
The free factors, coded to [-1, 1] over their ranges (:func:`soilcal.doe.designs.actual_to_coded`);
fixed factors are not part of the space and never move.

Start
-----
The centre of the box with ``centre_replicates`` seeds (the first estimate of the seed
scatter) and ``n_start - 1`` scrambled Halton points (``scipy.stats.qmc.Halton``, seeded):
``n_start = 2 d + 1`` points by default.

Surrogates (one per response)
-----------------------------
* ``gp``: a Gaussian process (``sklearn.gaussian_process``), constant x Matern 5/2 with one
  length scale per factor, plus a white-noise term.  Each point's mean of n_i seeds carries the
  known noise variance s^2 / n_i, s the pooled standard deviation of the replicated points
  (``alpha``); the white term takes what the replicate spread does not explain (fitted).
* ``quadratic``: the full second-order polynomial by ordinary least squares
  (``statsmodels``), a candidate once there are at least two more points than its terms.

Each is scored by its leave-one-out root mean square error on the point means: for the GP the
closed form of Rasmussen & Williams (2006, Eq. 5.12), r_i = [K^-1 y]_i / [K^-1]_ii; for the
quadratic the PRESS residuals r_i = e_i / (1 - h_ii).  The smaller score is used; both scores
and the choice are written to the iteration's record.

Probability of consistency
--------------------------
With mu_j(x) and s_j(x) the surrogate's prediction and predictive standard deviation of the
*mean* response j (seed noise excluded), targets t_j and tolerances tol_j::

    P(x) = prod_j [ Phi((t_j + tol_j - mu_j) / s_j) - Phi((t_j - tol_j - mu_j) / s_j) ]

(responses taken as independent).  P is large where the surrogate is sure of consistency and
moderate where it is unsure, so maximising it explores the uncertain part of the consistent
set as well as exploiting its sure part.

Proposals
---------
``batch`` points per iteration from ``n_candidates`` scrambled Halton candidates: greedily the
largest P, each at least ``separation`` (coded distance) from the points already chosen and
from every evaluated point.  Where P vanishes everywhere (all below ``p_unreachable``), the
candidates are ranked by the standardised shortfall instead,
-sum_j (max(|mu_j - t_j| - tol_j, 0) / s_j)^2 (the exponent of P's Gaussian tail), so the
proposals still head for the targets; per candidate the larger of the chosen surrogates' and
their rivals' (the surrogate not chosen, :func:`optimistic_shortfall`), so a corner where the
quadratic's trend sees the target and the Gaussian process reverts to its mean gets run.

Stopping
--------
The candidate of largest P (among the candidates and the evaluated points) is the best
candidate (while P < ``p_unreachable`` everywhere, the point whose predictions lie closest to
the targets, in tolerances, instead).  It is run with ``verify_seeds`` seeds once its
P >= ``p_verify``, or once every prediction there lies within tolerance and is either known as
well as a verification would measure it or has had 2 d + 1 proposal runs since the last
verification (:func:`ready_to_verify`), or, ready or not, when the budget left after the
iteration's proposals could no longer pay for a verification, or when there is nothing new to
propose, and the best candidate is not one already verified (a design that spends its budget or
its box ends with a measured answer); the verification runs join the data, so they also
inform the surrogate, and no point within ``separation`` of a verified one is verified again.
The best verification (smallest worst error, in tolerances) is the design's answer.  The design
stops when that verified mean is within tolerance of every target (``target met``), when the
run ``budget`` is spent (``budget spent``), when an iteration has nothing new to run (every
candidate within ``separation`` of a run and no verification due: ``box exhausted``), or when
the surrogate is sure that no point of the
box is consistent: P < ``p_unreachable`` everywhere after a batch of proposals aimed at the
target has been run, while the predicted distance to the target exceeds the tolerance plus
twice the predictive standard deviation, and either the runs alone put the target out of reach
(:func:`beyond_data`: every run lies beyond the tolerance plus a t quantile of one seed's
scatter), or the data back the surrogate (:func:`surrogate_backed`: at least 10 d points that
scatter about it as the seeds' scatter explains), the surrogate not chosen sees the target
beyond its 95 % band too (:func:`rivals_reach`), and the closest reachable point, measured
with ``verify_seeds`` seeds (a verification the design runs for it; a verified point counts with
the seeds that did not fail, two at least), reads beyond the
tolerance too (:func:`beyond_measured`) (``unreachable``), with the closest reachable value
of each response and where it lies.  A stop by target, budget, iterations or box with a
verification says, per response whose verification seeds cannot tell the band at one seed's
scatter s (the pooled replicate SD), how many seeds at one point would: (1.96 s / tol)^2, or
(1.645 s / tol)^2 for an optimised response's one-sided band (:func:`seeds_to_tell`; at fewer, a
point on the target reads outside the band more than 5 % of the time and one off it inside more
often, and the best of several verifications more often still, so a ``target met`` there is
partly the draw).

The answer is a set: the candidates with P > 1/2 form the consistent region; each factor's
range and spread over it, and the factors the data do not pin down (spread over more than half
of their range) are reported with it.

Cases that share their runs
--------------------------
The cases of one stage (the vineyard soil's three layers, the cohesive soil's moistures) aim
different targets at the same simulated responses over the same factors, so every run of one
case is evidence for the others: with ``shared`` (:func:`step`; :func:`run_shared` in one
process) a case's surrogates are fitted to its own runs and those of its sibling cases (kind
``shared``), and its proposals keep ``separation`` from them too, while its budget, its
verifications and its stopping rule count its own runs only.  Only the first case runs the
start design (the others wait for it at iteration 0); each case draws its seeds from its own
stream (:func:`case_settings`), so no two cases repeat a seed.

Goals without a target value (``minimize``, ``maximize``)
---------------------------------------------------------
A response whose goal is to be as small (large) as the box allows, such as a discrepancy
between a simulated and a measured profile, has no target value: it has an absolute
tolerance ``tol`` (how much worse than the best a user accepts; required, a percentage of a
moving best has no meaning) and, at every iteration, the level y* it is held to: the lowest
(highest) predicted mean over the candidates and the evaluated points, among those where the
target goals are plausibly met (P of the target goals >= 1/2, or their largest P where none
reaches it, or, where it underflows everywhere, the points closest to them).  Its factor in P is one-sided, Phi((y* + tol - mu) / s) (for ``maximize``
Phi((mu - y* + tol) / s)): the probability that the point lies within tolerance of the best.
Whether the box has been searched is the expected improvement beyond the tolerance,
I(x) = E[max(y* - tol - f(x), 0)] = s (phi(z) + z Phi(z)), z = (y* - tol - mu) / s (Jones,
Schonlau and Welch 1998, Eq. 15, with the incumbent lowered by the tolerance), times P of the
target goals: while its largest value over the candidates exceeds ``improvement_stop``
tolerances, or while no proposal has been run (a surrogate of the start alone can take a noisy
response for a flat one), the proposals maximise it (summed over the goals in tolerances), the best
candidate is verified only once 2 d + 1 proposals have passed since the last verification, and
no verification stops the design; once the box is searched the proposals maximise P and the
verification rule above applies.  The design then stops ``optimum verified`` when the
verified mean lies within tolerance of y* (and of every target) and the box is searched.

Everything is a pure function of the evaluated runs and the seed, so an interrupted design
resumes from its run table and proposes exactly what it would have proposed.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from soilcal.doe.designs import actual_to_coded, at_bound, coded_to_actual
from soilcal.errors import InputError

#: defaults of a soil's ``simulation.adaptive`` block (documented in the soil schema)
DEFAULTS = dict(n_start=None, centre_replicates=2, batch=2, budget=60, verify_seeds=4,
                tolerance_pct=2.0, p_verify=0.5, p_unreachable=0.01, separation=0.15,
                n_candidates=4096, max_iterations=50, improvement_stop=0.1)
#: the goals a response can have: a target value, or as small / as large as the box allows
GOALS = ("target", "minimize", "maximize")
#: the goals without a target value
OPTIMISED_GOALS = GOALS[1:]
#: factors whose spread over the consistent region exceeds this share of their range are
#: "not pinned down"
UNPINNED_SHARE = 0.5
#: a pinned factor whose consistent candidates reach this share of its range from a bound is
#: "at bound": the box, not the data, holds it there (the candidates are a Halton sample, so
#: the region's edge on a bound shows within about a fiftieth of the range; in coded units,
#: :func:`soilcal.doe.at_bound`'s tolerance is twice this)
NEAR_BOUND = 0.02


# --------------------------------------------------------------------------- problem

@dataclass(frozen=True)
class Factor:
    """A free factor and its range (actual units)."""
    name: str
    low: float
    high: float



@dataclass(frozen=True)
class Target:
    """A response's goal and its tolerance: ``tol`` absolute, or ``tol_pct`` of |value|.

    ``goal`` ``target`` (default): ``value`` is the target.  ``minimize`` / ``maximize``:
    ``value`` is the best level the design currently holds the response to (NaN in the
    problem a user states; :func:`resolve` sets it each iteration) and ``tol`` is required."""
    response: str
    value: float
    tol: float | None = None
    tol_pct: float | None = None
    goal: str = "target"

    @property
    def tolerance(self) -> float:
        if self.tol is not None:
            return float(self.tol)
        return abs(self.value) * float(self.tol_pct if self.tol_pct is not None else
                                       DEFAULTS["tolerance_pct"]) / 100.0

    @property
    def optimised(self) -> bool:
        return self.goal in OPTIMISED_GOALS

    def _level(self) -> float:
        if self.optimised and not math.isfinite(self.value):
            raise InputError(self.response, "value", f"the best level of a goal {self.goal}, set by resolve() "
                             "from the surrogates before it is used", self.value)
        return self.value

    def deviation(self, mu):
        """How far ``mu`` lies from the target (both sides), or beyond the best level of a
        minimised (maximised) response (negative where it is better)."""
        mu = np.asarray(mu, float)
        v = self._level()
        if self.goal == "minimize":
            return mu - v
        if self.goal == "maximize":
            return v - mu
        return np.abs(mu - v)

    def miss(self, mu):
        """How far ``mu`` lies outside the tolerance band (<= 0 inside it), in the response's
        unit: both sides of a target, one side of the best level of a minimised (maximised)
        response."""
        return self.deviation(mu) - self.tolerance

    def probability(self, mu, s):
        """The probability that the mean response lies within the band, given the prediction
        ``mu`` and its standard deviation ``s``."""
        self._level()
        tol = self.tolerance
        # scipy where it is used: the workflow's rules import this module to plan the jobs
        from scipy import stats

        if self.goal == "minimize":
            return stats.norm.cdf((self.value + tol - mu) / s)
        if self.goal == "maximize":
            return stats.norm.cdf((mu - self.value + tol) / s)
        return np.clip(stats.norm.cdf((self.value + tol - mu) / s) - stats.norm.cdf((self.value - tol - mu) / s),
                       0.0, 1.0)

    def improvement(self, mu, s):
        """Expected improvement beyond the tolerance over the best level (module docstring);
        0 for a target goal."""
        if not self.optimised:
            return np.zeros_like(np.asarray(mu, float))
        self._level()
        from scipy import stats

        gain = (self.value - self.tolerance - mu) if self.goal == "minimize" else (mu - self.value - self.tolerance)
        z = gain / s
        return s * (stats.norm.pdf(z) + z * stats.norm.cdf(z))

    def said(self) -> str:
        if self.optimised:
            return f"the best predicted level {self.value:g} ({self.goal}, tolerance {self.tolerance:.2g})"
        return f"the target {self.value:g} +- {self.tolerance:.2g}"


@dataclass
class Problem:
    factors: list[Factor]
    targets: list[Target]
    fixed: dict = field(default_factory=dict)
    source: str = "<adaptive>"

    def __post_init__(self):
        if not self.factors:
            raise InputError(self.source, "factors", "at least one free factor", "none")
        for f in self.factors:
            if not (math.isfinite(f.low) and math.isfinite(f.high) and f.high > f.low):
                raise InputError(self.source, f"factors.{f.name}", "a range with low < high",
                                 (f.low, f.high))
            if f.name in self.fixed:
                raise InputError(self.source, f"fixed.{f.name}", "a factor that is not also free",
                                 self.fixed[f.name])
        if not self.targets:
            raise InputError(self.source, "targets", "at least one response with a goal", "none")
        for t in self.targets:
            if t.goal not in GOALS:
                raise InputError(self.source, f"targets.{t.response}.goal", f"one of {', '.join(GOALS)}", t.goal)
            if t.optimised:
                if t.tol is None or not (math.isfinite(float(t.tol)) and float(t.tol) > 0):
                    raise InputError(self.source, f"targets.{t.response}.tol",
                                     f"an absolute tolerance > 0 for a goal {t.goal} (how much worse than the best "
                                     "is acceptable, in the response's unit)", t.tol)
                continue
            if not math.isfinite(t.value):
                raise InputError(self.source, f"targets.{t.response}", "a finite target", t.value)
            if not t.tolerance > 0:
                raise InputError(self.source, f"targets.{t.response}",
                                 "a tolerance > 0 (tol, or tol_pct of a non-zero target)", t.tolerance)

    @property
    def names(self) -> list[str]:
        return [f.name for f in self.factors]

    @property
    def responses(self) -> list[str]:
        return [t.response for t in self.targets]

    def to_actual(self, coded: np.ndarray) -> np.ndarray:
        return coded_to_actual(np.atleast_2d(coded), [f.low for f in self.factors], [f.high for f in self.factors])

    def to_coded(self, actual: np.ndarray) -> np.ndarray:
        return actual_to_coded(np.atleast_2d(actual), [f.low for f in self.factors], [f.high for f in self.factors])


@dataclass
class Settings:
    n_start: int | None = DEFAULTS["n_start"]
    centre_replicates: int = DEFAULTS["centre_replicates"]
    batch: int = DEFAULTS["batch"]
    budget: int = DEFAULTS["budget"]
    verify_seeds: int = DEFAULTS["verify_seeds"]
    p_verify: float = DEFAULTS["p_verify"]
    p_unreachable: float = DEFAULTS["p_unreachable"]
    separation: float = DEFAULTS["separation"]
    n_candidates: int = DEFAULTS["n_candidates"]
    max_iterations: int = DEFAULTS["max_iterations"]
    improvement_stop: float = DEFAULTS["improvement_stop"]
    seed: int = 0

    @classmethod
    def from_mapping(cls, d: dict | None, seed: int = 0, source: str = "<adaptive>") -> "Settings":
        d = dict(d or {})
        d.pop("tolerance_pct", None)  # a target's default, read by the targets
        unknown = sorted(set(d) - set(cls.__dataclass_fields__))
        if unknown:
            raise InputError(source, f"adaptive.{unknown[0]}",
                             f"one of {', '.join(sorted(cls.__dataclass_fields__))}", d[unknown[0]])
        s = cls(**{**d, "seed": int(d.get("seed", seed))})
        for key in ("centre_replicates", "batch", "budget", "verify_seeds", "n_candidates", "max_iterations"):
            v = getattr(s, key)
            if not (isinstance(v, (int, np.integer)) and not isinstance(v, bool) and v >= 1):
                raise InputError(source, f"adaptive.{key}", "an integer >= 1", v)
        if s.n_start is not None and not (isinstance(s.n_start, int) and s.n_start >= 2):
            raise InputError(source, "adaptive.n_start", "an integer >= 2 (or null: 2 d + 1)", s.n_start)
        for key in ("p_verify", "p_unreachable"):
            v = getattr(s, key)
            if not (isinstance(v, (int, float)) and 0 < v < 1):
                raise InputError(source, f"adaptive.{key}", "a probability in (0, 1)", v)
        if not (isinstance(s.improvement_stop, (int, float)) and not isinstance(s.improvement_stop, bool)
                and s.improvement_stop > 0):
            raise InputError(source, "adaptive.improvement_stop", "a number > 0 (tolerances)", s.improvement_stop)
        if not (isinstance(s.separation, (int, float)) and 0 <= s.separation < 2):
            raise InputError(source, "adaptive.separation", "a coded distance in [0, 2)", s.separation)
        return s


# --------------------------------------------------------------------------- runs table
#
# One row per DEM run: iteration, kind (start | proposal | verification), point (an integer
# id, shared by the seeds of one point), seed, the factors' actual levels, one column per
# response.  This table is the design's whole state.

RUN_KEYS = ("iteration", "kind", "point", "seed")


def point_table(problem: Problem, runs: pd.DataFrame) -> pd.DataFrame:
    """Mean, SD and count of every response per point (rows with a NaN response are left out
    of that response's statistics: a failed run is no evidence)."""
    if runs.empty:
        return pd.DataFrame(columns=["point", *problem.names])
    rows = []
    for pid, g in runs.groupby("point", sort=True):
        row = {"point": int(pid), **{n: float(g[n].iloc[0]) for n in problem.names},
               "kind": str(g["kind"].iloc[0]), "iteration": int(g["iteration"].min())}
        for r in problem.responses:
            v = g[r].to_numpy(float)
            v = v[np.isfinite(v)]
            row[r] = float(v.mean()) if v.size else np.nan
            row[f"{r}_sd"] = float(v.std(ddof=1)) if v.size > 1 else np.nan
            row[f"{r}_n"] = int(v.size)
        rows.append(row)
    return pd.DataFrame(rows)


def pooled_sd(points: pd.DataFrame, response: str) -> float | None:
    """Pooled replicate standard deviation over the points with at least two seeds."""
    return pooled_sd_dof(points, response)[0]


def pooled_sd_dof(points: pd.DataFrame, response: str) -> tuple[float | None, float]:
    """:func:`pooled_sd` and its degrees of freedom, sum(n_i - 1) over the points it pools
    (None, 0 without replicates)."""
    n = points[f"{response}_n"].to_numpy(int)
    sd = points[f"{response}_sd"].to_numpy(float)
    ok = (n > 1) & np.isfinite(sd)
    if not ok.any():
        return None, 0.0
    nu = float(np.sum(n[ok] - 1))
    return float(math.sqrt(np.sum((n[ok] - 1) * sd[ok] ** 2) / nu)), nu


# --------------------------------------------------------------------------- surrogates

class Surrogate:
    """Prediction and predictive SD of a response's mean at coded points; ``noise_sd``: the
    scatter of one seed about that mean as the fit sees it."""
    kind = ""
    loo_rmse = math.inf
    noise_sd = 0.0
    #: the other surrogates fitted to the same points, not chosen (:func:`fit_surrogates`): a
    #: second opinion where the chosen one's verdict decides a stop (:func:`rivals_reach`)
    rivals: tuple = ()
    #: the leverage of each point the surrogate was fitted to (the diagonal of the linear map
    #: from the points' values to its predictions there), in the order of the points; None for
    #: a surrogate not fitted to them (leverage 0: its predictions do not follow the values)
    hat: np.ndarray | None = None

    def predict(self, xc: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover
        raise NotImplementedError


class GPSurrogate(Surrogate):
    kind = "gp"

    def __init__(self, xc, y, n, noise_sd, seed):
        from sklearn.gaussian_process import GaussianProcessRegressor
        from sklearn.gaussian_process.kernels import ConstantKernel, Matern, WhiteKernel

        d = xc.shape[1]
        self.mu0, self.scale = float(np.mean(y)), float(np.std(y)) or 1.0
        yn = (y - self.mu0) / self.scale
        # the known noise of each point's mean; a floor keeps K well conditioned
        if noise_sd is not None:
            alpha = (noise_sd / self.scale) ** 2 / np.maximum(n, 1) + 1e-8
        else:
            alpha = np.full(len(y), 1e-8)
        kernel = (ConstantKernel(1.0, (1e-3, 1e3))
                  * Matern(length_scale=np.ones(d), length_scale_bounds=(0.05, 50.0), nu=2.5)
                  + WhiteKernel(1e-3, (1e-8, 1.0)))
        gp = GaussianProcessRegressor(kernel=kernel, alpha=alpha, normalize_y=False,
                                      n_restarts_optimizer=3, random_state=seed)
        # one BLAS thread: the fit's matrices are as small as the design's points, and the
        # optimiser's thousands of calls on them cost a threaded BLAS more CPU in waking its
        # threads than the work they share
        from threadpoolctl import threadpool_limits

        with warnings.catch_warnings(), threadpool_limits(limits=1, user_api="blas"):
            warnings.simplefilter("ignore")  # convergence notes of the kernel's bounds
            gp.fit(xc, yn)
        self.gp = gp
        self.white = float(gp.kernel_.k2.noise_level)
        # one seed's scatter as the fit sees it: the known replicate part and the fitted white term
        self.noise_sd = float(self.scale * np.sqrt(self.white + (noise_sd / self.scale) ** 2
                                                   if noise_sd is not None else self.white))
        self.length_scales = np.atleast_1d(gp.kernel_.k1.k2.length_scale).astype(float)
        K = gp.kernel_(xc) + np.diag(alpha)
        Kinv = np.linalg.inv(K)
        loo = (Kinv @ yn) / np.diag(Kinv)
        self.loo_rmse = float(np.sqrt(np.mean(loo ** 2)) * self.scale)
        # ordinary kriging: the mean level is estimated (generalised least squares), and its
        # uncertainty is part of every prediction's; taken as known (the sample mean), a GP
        # whose signal amplitude fits to its lower bound predicts one level everywhere with
        # almost no uncertainty although a few noisy runs leave the level itself uncertain
        self.xc = np.asarray(xc, float)
        self.Kinv = Kinv
        ones = np.ones(len(yn))
        self.kinv_one = Kinv @ ones
        self.one_kinv_one = float(ones @ self.kinv_one)
        self.level = float(self.kinv_one @ yn) / self.one_kinv_one
        self.weights = Kinv @ (yn - self.level)
        # leverages: at the points the predictor is H yn with H = 1 c' + A (I - 1 c'),
        # c = K^-1 1 / (1' K^-1 1) (the level's weights) and A = K_s K^-1 (K_s the signal kernel)
        c = self.kinv_one / self.one_kinv_one
        A = gp.kernel_.k1(self.xc) @ Kinv
        self.hat = c + np.diag(A) - (A @ ones) * c

    def predict(self, xc):
        """Mean response and its standard error (no seed scatter) at coded points: the
        ordinary-kriging predictor, var = k** - k K^-1 k + (1 - 1' K^-1 k)^2 / (1' K^-1 1)
        with the fitted signal kernel (Rasmussen & Williams 2006, Sec. 2.7, Eq. 2.42 with a
        constant basis and a vague prior on its coefficient)."""
        x = np.atleast_2d(xc)
        signal = self.gp.kernel_.k1
        k = signal(x, self.xc)
        m = self.level + k @ self.weights
        u = 1.0 - k @ self.kinv_one
        var = signal.diag(x) - np.einsum("ij,jk,ik->i", k, self.Kinv, k) + u ** 2 / self.one_kinv_one
        return self.mu0 + self.scale * m, self.scale * np.sqrt(np.maximum(var, 1e-12))


def quadratic_terms(xc: np.ndarray) -> np.ndarray:
    """Columns 1, x_i, x_i x_j (i < j), x_i^2 of the full second-order model."""
    xc = np.atleast_2d(xc)
    d = xc.shape[1]
    cols = [np.ones(len(xc))] + [xc[:, i] for i in range(d)]
    cols += [xc[:, i] * xc[:, j] for i in range(d) for j in range(i + 1, d)]
    cols += [xc[:, i] ** 2 for i in range(d)]
    return np.column_stack(cols)


class QuadraticSurrogate(Surrogate):
    kind = "quadratic"

    def __init__(self, xc, y):
        from statsmodels.regression.linear_model import OLS

        X = quadratic_terms(xc)
        self.fit = OLS(y, X).fit()
        self.noise_sd = float(np.sqrt(self.fit.mse_resid)) if self.fit.df_resid > 0 else 0.0
        h = self.fit.get_influence().hat_matrix_diag
        self.hat = np.asarray(h, float)
        press = self.fit.resid / np.maximum(1.0 - h, 1e-12)
        self.loo_rmse = float(np.sqrt(np.mean(press ** 2)))

    def predict(self, xc):
        pred = self.fit.get_prediction(quadratic_terms(xc))
        return np.asarray(pred.predicted_mean, float), np.asarray(pred.se_mean, float)


def n_quadratic_terms(d: int) -> int:
    return 1 + 2 * d + d * (d - 1) // 2


def fit_surrogates(problem: Problem, points: pd.DataFrame, seed: int) -> tuple[dict, pd.DataFrame]:
    """The surrogate used for each response and the table of the candidates' scores."""
    chosen, rows = {}, []
    d = len(problem.factors)
    for k, r in enumerate(problem.responses):
        ok = np.isfinite(points[r].to_numpy(float))
        if ok.sum() < 3:
            raise InputError(problem.source, f"responses.{r}",
                             "at least 3 points with a finite value to fit a surrogate",
                             f"{int(ok.sum())}")
        xc = problem.to_coded(points.loc[ok, problem.names].to_numpy(float))
        y = points.loc[ok, r].to_numpy(float)
        n = points.loc[ok, f"{r}_n"].to_numpy(int)
        sd = pooled_sd(points[ok], r)
        cands = [GPSurrogate(xc, y, n, sd, seed + k)]
        p = n_quadratic_terms(d)
        if ok.sum() >= p + 2:
            cands.append(QuadraticSurrogate(xc, y))
        best = min(cands, key=lambda s: s.loo_rmse)
        best.rivals = tuple(c for c in cands if c is not best)
        chosen[r] = best
        row = {"response": r, "points": int(ok.sum()), "replicate_sd": sd,
               "gp_loo_rmse": cands[0].loo_rmse,
               "quadratic_loo_rmse": cands[1].loo_rmse if len(cands) > 1 else np.nan,
               "used": best.kind,
               "note": "" if len(cands) > 1 else f"quadratic needs {p + 2} points ({p} terms + 2)"}
        rows.append(row)
    return chosen, pd.DataFrame(rows)


def consistency(problem: Problem, surrogates: dict, xc: np.ndarray) -> tuple[np.ndarray, dict]:
    """P(x) (module docstring) and each response's (mu, s) at coded points ``xc``."""
    p = np.ones(len(xc))
    pred = {}
    for t in problem.targets:
        mu, s = surrogates[t.response].predict(xc)
        s = np.maximum(s, 1e-12)
        p *= t.probability(mu, s)
        pred[t.response] = (mu, s)
    return p, pred


def resolve(problem: Problem, surrogates: dict, xc: np.ndarray) -> Problem:
    """The problem with every minimised (maximised) response's best level set (module
    docstring: the lowest (highest) predicted mean over the coded points ``xc`` where the
    target goals are plausibly met, or, where their P vanishes everywhere, closest to them); a
    problem of targets only is returned as it is."""
    if not any(t.optimised for t in problem.targets):
        return problem
    p_t = np.ones(len(xc))
    short = np.zeros(len(xc))
    for t in problem.targets:
        if not t.optimised:
            mu, s = surrogates[t.response].predict(xc)
            s = np.maximum(s, 1e-12)
            p_t *= t.probability(mu, s)
            short -= (np.maximum(t.miss(mu), 0.0) / s) ** 2
    # where P of the targets underflows everywhere, the points closest to them (in standard
    # deviations beyond their tolerances) stand in for the plausible ones
    mask = p_t >= min(0.5, float(p_t.max())) if p_t.max() > 0 else short >= short.max()
    out = []
    for t in problem.targets:
        if t.optimised:
            mu, _ = surrogates[t.response].predict(xc[mask])
            best = float(mu.min() if t.goal == "minimize" else mu.max())
            t = Target(t.response, best, tol=t.tol, goal=t.goal)
        out.append(t)
    return Problem(problem.factors, out, fixed=dict(problem.fixed), source=problem.source)


def improvement(problem: Problem, pred: dict, p_targets: np.ndarray) -> np.ndarray:
    """The expected improvement beyond tolerance of the optimised responses, in tolerances and
    summed over them, times the probability that the target goals are met (0 for a problem
    of targets only)."""
    out = np.zeros(len(p_targets))
    for t in problem.targets:
        if t.optimised:
            mu, s = pred[t.response]
            out = out + t.improvement(mu, s) / t.tolerance
    return out * p_targets


def target_probability(problem: Problem, pred: dict) -> np.ndarray:
    """P of the target goals alone (1 where there are none)."""
    p = None
    for t in problem.targets:
        if not t.optimised:
            mu, s = pred[t.response]
            q = t.probability(mu, s)
            p = q if p is None else p * q
    return p if p is not None else np.ones(len(next(iter(pred.values()))[0]))


def shortfall(problem: Problem, pred: dict) -> np.ndarray:
    """-sum_j (max(miss_j(mu_j), 0) / s_j)^2 (:meth:`Target.miss`: |mu_j - t_j| - tol_j for a
    target, mu_j - y*_j - tol_j for a minimised response): how far each point's predictions fall
    short of their bands, in predictive standard deviations (0 where all lie within)."""
    out = 0.0
    for t in problem.targets:
        mu, sd = pred[t.response]
        out = out - (np.maximum(t.miss(mu), 0.0) / np.maximum(sd, 1e-12)) ** 2
    return np.asarray(out, float)


def rivals_reach(surrogate: Surrogate, xc: np.ndarray, t: Target) -> bool:
    """Whether a rival of ``surrogate`` (another surrogate fitted to the same points, not
    chosen: :attr:`Surrogate.rivals`) sees target ``t`` within reach at some point of ``xc``:
    its 95 % band there, mu +- 1.96 s, meets the target's band t +- tol.  Surrogates differ most
    where the points are few, at the box's corners and edges: a Gaussian process reverts to its
    mean level there, a quadratic follows its trend; a stop as ``unreachable`` needs them all."""
    for rival in surrogate.rivals:
        mu, sd = rival.predict(xc)
        if bool(np.any((mu - 1.96 * sd <= t.value + t.tolerance) & (mu + 1.96 * sd >= t.value - t.tolerance))):
            return True
    return False


def optimistic_shortfall(problem: Problem, surrogates: dict, xc: np.ndarray, pred: dict) -> np.ndarray:
    """:func:`shortfall` at ``xc`` by the chosen surrogates (``pred``) or by their rivals
    (:attr:`Surrogate.rivals`), whichever sees each point closer to the targets: where no
    point is plausibly consistent, the proposals go where any surrogate sees the targets
    nearest, so a rival's trend towards a corner the chosen one reverts from gets run."""
    best = shortfall(problem, pred)
    n_rivals = max((len(surrogates[t.response].rivals) for t in problem.targets), default=0)
    for k in range(n_rivals):
        alt = dict(pred)
        for t in problem.targets:
            rivals = surrogates[t.response].rivals
            if k < len(rivals):
                mu, sd = rivals[k].predict(xc)
                alt[t.response] = (mu, np.maximum(sd, 1e-12))
        best = np.maximum(best, shortfall(problem, alt))
    return best


# --------------------------------------------------------------------------- proposals

def halton(d: int, n: int, seed: int) -> np.ndarray:
    """``n`` scrambled Halton points in the coded box [-1, 1]^d."""
    from scipy.stats import qmc

    return 2.0 * qmc.Halton(d=d, scramble=True, seed=np.random.default_rng(seed)).random(n) - 1.0


def start_points(problem: Problem, settings: Settings) -> np.ndarray:
    """Coded start design: the centre, then ``n_start - 1`` Halton points."""
    d = len(problem.factors)
    n = settings.n_start or 2 * d + 1
    return np.vstack([np.zeros((1, d)), halton(d, n - 1, settings.seed)])


def pick_batch(xc: np.ndarray, score: np.ndarray, taken: np.ndarray, batch: int,
               separation: float) -> list[int]:
    """Greedy: the largest scores, each at least ``separation`` from the picked points and from
    ``taken`` (coded distances); none for a batch of 0 (the budget left went to a
    verification)."""
    if batch <= 0:
        return []
    order = np.argsort(-score, kind="stable")
    picked: list[int] = []
    ref = np.atleast_2d(taken) if len(taken) else np.empty((0, xc.shape[1]))
    for i in order:
        pts = np.vstack([ref, xc[picked]]) if picked else ref
        if len(pts) and np.min(np.linalg.norm(pts - xc[i], axis=1)) < separation:
            continue
        picked.append(int(i))
        if len(picked) == batch:
            break
    return picked


def closest_reachable(problem: Problem, surrogates: dict, cand: np.ndarray) -> dict:
    """The point of the box whose predicted responses are closest to the targets (distance in
    tolerances) and what each response reaches there."""
    aimed = [t for t in problem.targets if not t.optimised]

    def dist(xc):
        _, pred = consistency(problem, surrogates, np.atleast_2d(xc))
        return float(sum(((pred[t.response][0][0] - t.value) / t.tolerance) ** 2 for t in aimed))

    _, pred = consistency(problem, surrogates, cand)
    d_all = sum(((pred[t.response][0] - t.value) / t.tolerance) ** 2 for t in aimed) + np.zeros(len(cand))
    x0 = cand[int(np.argmin(d_all))]
    from scipy import optimize

    res = optimize.minimize(dist, x0, method="L-BFGS-B", bounds=[(-1.0, 1.0)] * len(x0))
    xc = res.x if res.fun <= dist(x0) else x0
    _, pred = consistency(problem, surrogates, np.atleast_2d(xc))
    return {"coded": xc, "actual": problem.to_actual(xc)[0],
            "values": {t.response: float(pred[t.response][0][0]) for t in problem.targets},
            "sd": {t.response: float(pred[t.response][1][0]) for t in problem.targets}}


# --------------------------------------------------------------------------- one iteration

@dataclass
class Step:
    """What the design does after the runs it has: the next runs (coded and actual levels,
    kind, point id, seed), or a stop, with the record of the iteration."""
    iteration: int
    status: str
    message: str
    runs: pd.DataFrame
    surrogates: pd.DataFrame
    best: dict | None
    region: pd.DataFrame
    verified: dict | None = None
    models: dict = field(default_factory=dict)  # the fitted surrogates (not written out)
    problem: Problem | None = None  # the problem as decided (the optimised responses' best levels set)
    searched: float | None = None  # largest expected improvement beyond tolerance (optimised goals)
    consistent: np.ndarray | None = None  # actual levels of a sample of the consistent region (P > 1/2)


def _candidate(problem: Problem, xc: np.ndarray, p: np.ndarray, pred: dict, i: int) -> dict:
    """Point ``i`` of coded points ``xc`` with its P and predictions (:func:`consistency`)."""
    return {"coded": xc[i], "actual": problem.to_actual(xc[i])[0], "p": float(p[i]),
            "predicted": {r: float(pred[r][0][i]) for r in problem.responses},
            "predicted_sd": {r: float(pred[r][1][i]) for r in problem.responses}}


def _new_runs(problem, coded, kinds, first_point, iteration, seeds_per_point, first_seed):
    rows = []
    seed = first_seed
    for k, (xc, kind, m) in enumerate(zip(coded, kinds, seeds_per_point)):
        xa = problem.to_actual(xc)[0]
        for _ in range(m):
            rows.append({"iteration": iteration, "kind": kind, "point": first_point + k, "seed": seed,
                         **{n: float(v) for n, v in zip(problem.names, xa)}})
            seed += 1
    return pd.DataFrame(rows, columns=[*RUN_KEYS, *problem.names])


def empty_runs(problem: Problem) -> pd.DataFrame:
    return pd.DataFrame(columns=[*RUN_KEYS, *problem.names, *problem.responses])


def near_a_bound(vmin: float, vmax: float, low: float, high: float) -> str | None:
    """Which bound of a factor's range ``low`` to ``high`` ("low", "high" or None) a consistent
    region spanning ``vmin`` to ``vmax`` (actual units) reaches, to within :data:`NEAR_BOUND`
    of the range; the low one when it reaches both."""
    lo, hi = actual_to_coded(np.array([vmin, vmax]), low, high)
    if at_bound(lo, "low", tol=2.0 * NEAR_BOUND):
        return "low"
    return "high" if at_bound(hi, "high", tol=2.0 * NEAR_BOUND) else None


def consistent_region(problem: Problem, cand: np.ndarray, p: np.ndarray) -> pd.DataFrame:
    """Per factor: range, mean and SD over the candidates with P > 1/2, and whether the data pin
    it down (module docstring)."""
    inside = p > 0.5
    xa = problem.to_actual(cand[inside]) if inside.any() else np.empty((0, len(problem.factors)))
    rows = []
    for i, f in enumerate(problem.factors):
        v = xa[:, i]
        span = (f.high - f.low)
        pinned = bool(v.size and (v.max() - v.min()) <= UNPINNED_SHARE * span)
        if pinned and span > 0 and near_a_bound(v.min(), v.max(), f.low, f.high) is not None:
            pinned = "at bound"  # held by the box: the consistent set may go on beyond it
        rows.append({"factor": f.name, "low": f.low, "high": f.high, "candidates": int(inside.sum()),
                     "share_of_box": float(inside.mean()) if inside.size else 0.0,
                     "min": float(v.min()) if v.size else np.nan,
                     "max": float(v.max()) if v.size else np.nan,
                     "mean": float(v.mean()) if v.size else np.nan,
                     "sd": float(v.std(ddof=1)) if v.size > 1 else np.nan,
                     "pinned": pinned})
    return pd.DataFrame(rows)


#: most candidates of the consistent region a step keeps (:func:`consistent_sample`)
REGION_SAMPLE = 256


def consistent_sample(problem: Problem, cand: np.ndarray, p: np.ndarray, n: int = REGION_SAMPLE) -> np.ndarray:
    """Actual levels of the first ``n`` candidates with P > 1/2, in the candidates' (Halton)
    order: a space-filling sample of the consistent region, for figures."""
    return problem.to_actual(cand[p > 0.5][:n]) if (p > 0.5).any() else np.empty((0, len(problem.factors)))


#: a point on the target reads within its band in this share of verifications at the seeds
#: :func:`seeds_to_tell` names
TELL_SHARE = 0.95


def seeds_to_tell(scatter: float, tolerance: float, one_sided: bool = False) -> int:
    """Seeds whose mean at a point exactly on the target lies within +- ``tolerance`` 95 % of
    the time, one seed scattering by ``scatter``: (1.96 scatter / tolerance)^2, rounded up.
    ``one_sided``: a minimised (maximised) response's band reaches ``tolerance`` beyond its best
    level on one side only, so a point on that level reads within it 95 % of the time at
    (1.645 scatter / tolerance)^2 seeds."""
    if not (scatter > 0 and tolerance > 0):
        return 1
    from scipy import stats

    z = stats.norm.ppf(TELL_SHARE if one_sided else 0.5 + TELL_SHARE / 2)
    return max(1, math.ceil((z * scatter / tolerance) ** 2))


def _verified(problem: Problem, runs: pd.DataFrame, settings: Settings, scatter: dict | None = None) -> dict | None:
    """The best verified point (smallest worst error in tolerances): its means and whether
    every one is within tolerance; with one seed's scatter ``scatter`` (the pooled replicate
    SD, :func:`pooled_sd`), each response also carries the standard error of its verified mean
    and the seeds it would take to tell the band (:func:`seeds_to_tell`)."""
    ver = runs[runs["kind"] == "verification"]
    if ver.empty:
        return None

    def worst(g):
        e = [float(t.deviation(np.nanmean(g[t.response].to_numpy(float)))) / t.tolerance for t in problem.targets]
        return max(e) if all(np.isfinite(e)) else math.inf

    pid = min(ver["point"].unique(), key=lambda p: (worst(ver[ver["point"] == p]), p))
    g = ver[ver["point"] == pid]
    out = {"point": pid, "iteration": int(g["iteration"].max()),
           "levels": {n: float(g[n].iloc[0]) for n in problem.names}, "responses": {}, "met": True}
    for t in problem.targets:
        v = g[t.response].to_numpy(float)
        v = v[np.isfinite(v)]
        mean = float(v.mean()) if v.size else np.nan
        sd = float(v.std(ddof=1)) if v.size > 1 else np.nan
        ok = bool(v.size >= settings.verify_seeds and np.isfinite(mean) and t.miss(mean) <= 0)
        rec = {"target": t.value, "goal": t.goal, "tolerance": t.tolerance, "mean": mean, "sd": sd, "n": int(v.size),
               # against a target only: a best level is the surrogate's, not a measurement
               "error_pct": 100 * (mean - t.value) / abs(t.value) if t.value and not t.optimised else np.nan,
               "within": ok}
        if scatter and (scatter.get(t.response) or 0) > 0 and v.size:
            rec["scatter"] = float(scatter[t.response])
            rec["standard_error"] = float(scatter[t.response]) / math.sqrt(v.size)
            rec["seeds_to_tell"] = seeds_to_tell(float(scatter[t.response]), t.tolerance, t.optimised)
        out["responses"][t.response] = rec
        out["met"] &= ok
    return out


def _untellable(verified: dict | None) -> str:
    """What a verification cannot tell at the design's seed scatter ('' when its seeds can):
    per response whose verified mean's standard error exceeds the band over 1.96."""
    if not verified:
        return ""
    said = []
    for r, v in verified["responses"].items():
        need = v.get("seeds_to_tell")
        if need and need > v["n"]:
            said.append(f"{r}: one seed scatters by {v['scatter']:.3g}, so the mean of {v['n']} seeds has a standard "
                        f"error of {v['standard_error']:.2g} against a band of "
                        + (f"{v['tolerance']:.2g} beyond the best level; a point on that level"
                           if v.get("goal", "target") != "target" else
                           f"+- {v['tolerance']:.2g}; a point on the target")
                        + f" would read within the band 95 % of the time with about {need} seeds")
    return ("; the band cannot be verified at this seed scatter with the seeds given (" + "; ".join(said) + ")"
            if said else "")


#: seeds of case i of a stage start at ``settings.seed + SEED_STRIDE * i`` (:func:`case_settings`)
SEED_STRIDE = 100_000


def case_settings(settings: Settings, index: int) -> Settings:
    """The settings of the ``index``-th case of a stage whose cases share their runs: its own
    seed stream (the first case keeps the stage's)."""
    from dataclasses import replace

    return replace(settings, seed=int(settings.seed) + SEED_STRIDE * int(index))


def shared_rows(problem: Problem, shared: pd.DataFrame | None) -> pd.DataFrame:
    """The sibling cases' runs as data for this case: kind ``shared``, one negative point id per
    (case, point) so they never merge with this case's points, NaN for a response a sibling
    did not simulate."""
    cols = [*RUN_KEYS, *problem.names, *problem.responses]
    if shared is None or not len(shared):
        return pd.DataFrame(columns=cols)
    df = shared.copy()
    for r in problem.responses:
        if r not in df.columns:
            df[r] = np.nan
    key = (df["case"].astype(str) if "case" in df.columns else pd.Series("", index=df.index)) \
        + "/" + df["point"].astype(int).astype(str)
    ids = {k: -(i + 1) for i, k in enumerate(dict.fromkeys(key))}
    df["point"] = [ids[k] for k in key]
    df["kind"] = "shared"
    return df[cols].reset_index(drop=True)


def step(problem: Problem, runs: pd.DataFrame, settings: Settings, iteration: int,
         shared: pd.DataFrame | None = None, wait_for_start: bool = False) -> Step:
    """The design's decision after ``runs`` (all runs with their responses; empty before the
    start): the runs of iteration ``iteration`` or a stop (module docstring).  ``shared``: the
    runs of the stage's sibling cases (a ``case`` column names each one's case), evidence for
    the surrogates only; ``wait_for_start``: a case that is not its stage's first runs no start
    of its own but waits, at iteration 0, for the first case's."""
    d = len(problem.factors)
    runs = runs if len(runs) else empty_runs(problem)
    missing = [r for r in problem.responses if r not in runs.columns]
    if missing:
        raise InputError(problem.source, f"runs.{missing[0]}", "a column for every response", "missing")
    shared = shared_rows(problem, shared)
    next_point = int(runs["point"].max()) + 1 if len(runs) else 0
    next_seed = int(runs["seed"].max()) + 1 if len(runs) else settings.seed
    empty_region = consistent_region(problem, np.empty((0, d)), np.empty(0))
    if runs.empty and shared.empty and wait_for_start:
        return Step(iteration, "continue", "start: the stage's first case runs it; no runs of its own",
                    empty_runs(problem)[[*RUN_KEYS, *problem.names]], pd.DataFrame(), None, empty_region)
    if runs.empty and shared.empty:
        xc = start_points(problem, settings)
        kinds = ["start"] * len(xc)
        reps = [settings.centre_replicates] + [1] * (len(xc) - 1)
        new = _new_runs(problem, xc, kinds, 0, iteration, reps, settings.seed)
        return Step(iteration, "continue", f"start: {len(xc)} points, {len(new)} runs", new,
                    pd.DataFrame(), None, empty_region)
    spent = len(runs)
    data = pd.concat([runs, shared], ignore_index=True) if len(shared) else runs
    points = point_table(problem, data)
    surrogates, scores = fit_surrogates(problem, points, settings.seed + iteration)
    cand = halton(d, settings.n_candidates, settings.seed + 7919 * iteration)
    xe = problem.to_coded(points[problem.names].to_numpy(float))
    problem = resolve(problem, surrogates, np.vstack([cand, xe]))
    scatter = seed_sd(problem, points, surrogates)
    # one seed's scatter, as a verification's mean at one point meets it: the replicates'
    # pooled SD (seed_sd's larger value may hold the surrogate's lack of fit too)
    verified = _verified(problem, runs, settings, {r: pooled_sd(points, r) for r in problem.responses})
    p_c, pred_c = consistency(problem, surrogates, cand)
    p_e, pred_e = consistency(problem, surrogates, xe)
    gain = improvement(problem, pred_c, target_probability(problem, pred_c))
    searched = float(gain.max()) if any(t.optimised for t in problem.targets) else None
    # the box counts as searched once the expected improvement is small, and not before one
    # batch of proposals has gone where it pointed: a surrogate of the start alone can see a
    # noisy response as flat and call a box searched that nothing has searched
    proposed = bool((runs["kind"] == "proposal").any())
    unsearched = searched is not None and (searched > settings.improvement_stop or not proposed)
    best = _candidate(problem, cand, p_c, pred_c, int(np.argmax(p_c)))
    if p_e.max() > best["p"]:  # an evaluated point is the surest
        best = _candidate(problem, xe, p_e, pred_e, int(np.argmax(p_e)))
    near = None
    if best["p"] < settings.p_unreachable:
        # no candidate is plausibly consistent: the best guess is the point whose predictions
        # lie closest to the targets (in tolerances), not the argmax of a vanishing P
        near = closest_reachable(problem, surrogates, cand)
        p_n, _ = consistency(problem, surrogates, near["coded"][None, :])
        best = {"coded": near["coded"], "actual": near["actual"], "p": float(p_n[0]),
                "predicted": near["values"], "predicted_sd": near["sd"], "closest": True}
    region = consistent_region(problem, cand, p_c)
    sample = consistent_sample(problem, cand, p_c)
    no_runs = empty_runs(problem)[[*RUN_KEYS, *problem.names]]

    def decided(status: str, message: str, new_runs: pd.DataFrame = no_runs) -> Step:
        # the iteration's record: everything but its status, message and runs is this fit's
        return Step(iteration, status, message, new_runs, scores, best, region, verified, surrogates, problem,
                    searched, consistent=sample)

    if verified and verified["met"] and not unsearched:
        optimised = any(t.optimised for t in problem.targets)
        return decided("optimum verified" if optimised else "target met",
                       f"the verified mean of point {verified['point']} is within tolerance of every target"
                       + (" and of the best predicted level of every optimised response; the largest expected "
                          f"improvement beyond the tolerance on that level is {searched:.2g} tolerances "
                          f"(<= {settings.improvement_stop:g})" if optimised else "")
                       + _untellable(verified))
    # unreachable: no point of the box is plausibly consistent, and the closest reachable
    # prediction lies further from a target than its uncertainty explains; the data put the
    # target out of reach, or back the surrogate and have measured the closest point
    measure_near = False
    if near is not None and (runs["kind"] == "proposal").any():  # after proposals aimed at the target
        aimed = [t for t in problem.targets if not t.optimised
                 and abs(near["values"][t.response] - t.value) > t.tolerance + 2.0 * near["sd"][t.response]]
        far = [t for t in aimed if beyond_data(data, points, t, scatter[t.response])]
        backed = [t for t in aimed if t not in far
                  and surrogate_backed(problem, points, surrogates[t.response], t, near["values"][t.response])
                  and not rivals_reach(surrogates[t.response], np.vstack([cand, xe]), t)]
        measured = measured_at(problem, points, surrogates, near, backed, settings) if backed else None
        by_model = [t for t in backed
                    if measured is not None and beyond_measured(points, measured, t, near["values"][t.response])]
        measure_near = bool(backed) and measured is None
        if far or by_model:
            at = _where(problem, near["actual"])
            msg = "; ".join(f"{t.response}: target {t.value:g} is outside what the factor ranges reach: "
                            f"the closest reachable value is {near['values'][t.response]:.4g} "
                            f"(+- {near['sd'][t.response]:.2g})"
                            + (f", measured {measured[t.response]:.4g} "
                               f"(+- {_se(_margin_sd(points, t.response)[0], measured, t):.2g}, "
                               f"{int(measured[t.response + '_n'])} seeds) where "
                               + _where(problem, measured[problem.names].to_numpy(float))
                               if t in by_model else "")
                            for t in far + by_model)
            return decided("unreachable", f"{msg}, at {at}")
    if spent >= settings.budget:
        return decided("budget spent",
                       f"{spent} runs spent of a budget of {settings.budget}; {_best_said(problem, best)}"
                       + _untellable(verified))
    if iteration > settings.max_iterations:
        return decided("iterations spent",
                       f"{settings.max_iterations} iterations without a verified set; {_best_said(problem, best)}"
                       + _untellable(verified))
    coded, kinds, reps = [], [], []
    left = settings.budget - spent
    ver_pts = problem.to_coded(runs.loc[runs["kind"] == "verification", problem.names].to_numpy(float)) \
        if (runs["kind"] == "verification").any() else np.empty((0, d))
    # no point within `separation` of a verified one is verified again: the candidate to verify
    # is the best one away from them
    cand_v = best
    if len(ver_pts):
        far = np.min(np.linalg.norm(cand[:, None, :] - ver_pts[None, :, :], axis=2), axis=1) >= settings.separation
        near_best = np.min(np.linalg.norm(ver_pts - best["coded"], axis=1)) < max(settings.separation, 1e-9)
        if near_best:
            cand_v = None
            if far.any():
                cand_v = _candidate(problem, cand, p_c, pred_c, int(np.flatnonzero(far)[np.argmax(p_c[far])]))
    last_v = int(runs.loc[runs["kind"] == "verification", "point"].max()) if len(ver_pts) else -1
    stalled = int(((runs["kind"] == "proposal") & (runs["point"] > last_v)).sum()) >= 2 * d + 1
    # the last chance: after this iteration's proposals the budget could not pay for a
    # verification, so a best candidate nobody verified is verified now, ready or not (a design
    # that spends its budget leaves a measured answer, not only a predicted one)
    last_chance = cand_v is best and left < settings.verify_seeds + settings.batch
    # measure_near: the data back the surrogate's verdict that a target is out of reach, and
    # the closest reachable point (the best candidate) is measured before the design says so
    if cand_v is not None and left >= settings.verify_seeds and (
            last_chance or (measure_near and cand_v is best)
            or ((stalled or not unsearched) and ready_to_verify(problem, cand_v, scatter, settings, stalled))):
        best = cand_v
        coded.append(best["coded"])
        kinds.append("verification")
        reps.append(settings.verify_seeds)
        left -= settings.verify_seeds
    n_new = max(0, min(settings.batch, left))
    taken = np.vstack([xe, np.atleast_2d(coded)]) if coded else xe
    score = gain if unsearched else (p_c if p_c.max() >= settings.p_unreachable
                                     else optimistic_shortfall(problem, surrogates, cand, pred_c))
    for i in pick_batch(cand, score, taken, n_new, settings.separation):
        coded.append(cand[i])
        kinds.append("proposal")
        reps.append(1)
    last = runs[runs["iteration"] == runs["iteration"].max()] if len(runs) else runs
    after_verification = len(last) > 0 and bool((last["kind"] == "verification").all())
    if not coded and cand_v is best and left >= settings.verify_seeds and not after_verification:
        # nothing new to propose: the box is exhausted, but its best candidate was never
        # verified; verify it before stopping, once (the refitted surrogate may move its best
        # candidate again: the iteration after this verification stops whatever it prefers)
        coded.append(best["coded"])
        kinds.append("verification")
        reps.append(settings.verify_seeds)
    if not coded:
        # the same runs would give the next iteration the same surrogates: stop rather than
        # iterate without running anything
        return decided("box exhausted",
                       f"every candidate lies within {settings.separation:g} (coded) of a run already made and no "
                       f"verification is due; {_best_said(problem, best)}" + _untellable(verified))
    new = _new_runs(problem, coded, kinds, next_point, iteration, reps, next_seed)
    msg = (f"iteration {iteration}: best P = {best['p']:.3f}; {len(new)} runs"
           + (" (with a verification of the best candidate)" if "verification" in kinds else "")
           + ((f"; searching: largest expected improvement {searched:.2g} tolerances"
               + ("" if proposed else ", no proposal run yet")) if unsearched else ""))
    return decided("continue", msg, new)


#: the level of the tests of :func:`beyond_data`, :func:`surrogate_backed` (the family's, for
#: the test at every point) and :func:`beyond_measured`
UNREACHABLE_ALPHA = 0.05


def _margin_sd(points: pd.DataFrame, response: str) -> tuple[float, float]:
    """:func:`pooled_sd_dof` with 0 for no SD: (0, 0) without replicates (no scatter known),
    (0, nu) where every point's seeds read alike (a response its seeds do not move: the
    margins are then the tolerance and whatever scatter the surrogate's fit sees)."""
    s, nu = pooled_sd_dof(points, response)
    return (s or 0.0, nu)


def beyond_data(runs: pd.DataFrame, points: pd.DataFrame, t: Target, scatter: float = 0.0) -> bool:
    """The runs alone put target ``t`` out of reach: every run's value lies on one side of the
    target, further than its tolerance plus t_{1 - alpha/2, nu} s, s the larger of the pooled
    replicate SD (nu its degrees of freedom) and ``scatter`` (one seed's scatter as the
    surrogate's fit sees it, :func:`seed_sd`): two seeds at the centre can read alike by
    chance, and an SD of one degree of freedom near 0 would make any run's distance count."""
    from scipy import stats

    v = runs[t.response].to_numpy(float)
    v = v[np.isfinite(v)]
    s, nu = _margin_sd(points, t.response)
    if not v.size or nu < 1:
        return False
    margin = t.tolerance + float(stats.t.ppf(1.0 - UNREACHABLE_ALPHA / 2.0, nu)) * max(s, scatter)
    return bool(v.max() < t.value - margin or v.min() > t.value + margin)


def surrogate_backed(problem: Problem, points: pd.DataFrame, surrogate: Surrogate, t: Target,
                     reached: float) -> bool:
    """Whether the data back the surrogate's verdict that target ``t`` lies beyond the value
    ``reached`` at best (a surrogate that takes the whole signal for noise is flat and would
    claim it too).  The single runs alone cannot carry a target a few seed SDs beyond the
    reach: among many runs the largest single seed lies a few SDs above its mean, so some run
    always reads near such a target; the surrogate pools the runs, and these tests keep it
    honest.  With the point means ybar_i of n_i seeds, the surrogate's mu_i there, the pooled
    replicate SD s with nu degrees of freedom, z_i = (ybar_i - mu_i) sqrt(n_i) / s and h_i the
    surrogate's leverage at point i (:attr:`Surrogate.hat`; its fit spends sum h_i of the m
    points' degrees of freedom, the number of terms of the quadratic, the trace of the
    Gaussian process's smoother):

    - at least 10 d points (d factors; the rule of thumb for a Gaussian-process emulator's
      design size, Loeppky, Sacks and Welch 2009, Technometrics 51, 366-376);
    - overall: sum z_i^2 / (m - sum h_i) below the (1 - alpha) quantile of F(m - sum h_i, nu)
      (the lack-of-fit test against pure error: residuals of a fit to the same points are
      smaller than the points' scatter about the true surface, by the degrees of freedom the
      fit spends; Montgomery, Design and Analysis of Experiments, Sec. 10.3.5);
    - at every point, on the target's side: sign(t - reached) z_i / sqrt(1 - h_i) below the
      (1 - alpha / m) quantile of Student's t with nu degrees of freedom (Bonferroni over the
      m points; the residual studentised by its leverage): no point reads closer to the
      target than the surrogate by more than its seeds explain.

    Where the seeds of every point read alike (s = 0) the residuals have no scatter to be
    judged by, and the verdict is left to :func:`beyond_data`.

    A verdict backed so still needs the closest point measured (:func:`beyond_measured`): the
    tests have little power against a feature the points have not sampled, such as a corner
    the surrogate's smoothness flattens."""
    from scipy import stats

    r = t.response
    s, nu = _margin_sd(points, r)
    ok = np.isfinite(points[r].to_numpy(float))
    m = int(ok.sum())
    if nu < 1 or not s > 0 or m < 10 * len(problem.factors):
        return False
    h = np.zeros(m) if surrogate.hat is None else np.asarray(surrogate.hat, float)
    if h.shape != (m,):
        raise ValueError(f"surrogate_backed: the surrogate was fitted to {h.size} points, not to the {m} given")
    dof = m - float(np.sum(h))
    if dof < 1.0:
        return False  # a fit that spends every point's degree of freedom leaves no lack of fit to test
    n = points.loc[ok, f"{r}_n"].to_numpy(float)
    mu, _ = surrogate.predict(problem.to_coded(points.loc[ok, problem.names].to_numpy(float)))
    z = (points.loc[ok, r].to_numpy(float) - mu) * np.sqrt(n) / s
    side = 1.0 if t.value > reached else -1.0
    fits = float(np.sum(z ** 2)) / dof <= float(stats.f.ppf(1.0 - UNREACHABLE_ALPHA, dof, nu))
    zs = z / np.sqrt(np.maximum(1.0 - h, 1e-12))
    return fits and float(np.max(side * zs)) <= float(stats.t.ppf(1.0 - UNREACHABLE_ALPHA / m, nu))


def measured_at(problem: Problem, points: pd.DataFrame, surrogates: dict, near: dict, targets: list[Target],
                settings: Settings):
    """The evaluated point of at least ``verify_seeds`` seeds of each of ``targets``' responses
    (a point the design verified: at least two, as a failed seed leaves fewer and the design
    does not verify again near a verified point) that measures the closest reachable point
    ``near`` (:func:`closest_reachable`), or None: one within ``separation`` of it, or one the
    surrogates predict as close to each of ``targets`` as ``near`` within their uncertainty
    (|mu_k - mu_near| <= 2 sqrt(s_k^2 + s_near^2)) -- where the response is flat near its best,
    the closest point moves with every refit, and a measurement anywhere on that plateau
    measures the reach; of several, the one predicted closest to the targets (in tolerances)."""
    n = points[[f"{t.response}_n" for t in targets]].to_numpy(float).min(axis=1)
    verified = points["kind"].astype(str).to_numpy() == "verification"
    enough = (n >= settings.verify_seeds) | (verified & (n >= 2))
    if not enough.any():
        return None
    xe = problem.to_coded(points[problem.names].to_numpy(float))
    ok = enough & (np.linalg.norm(xe - np.asarray(near["coded"], float), axis=1) < max(settings.separation, 1e-9))
    plateau = enough.copy()
    dist = np.zeros(len(xe))
    for t in targets:
        mu, sd = surrogates[t.response].predict(xe)
        plateau &= np.abs(mu - near["values"][t.response]) <= 2.0 * np.sqrt(sd ** 2 + near["sd"][t.response] ** 2)
        dist += ((mu - t.value) / t.tolerance) ** 2
    ok |= plateau
    if not ok.any():
        return None
    return points.iloc[int(np.flatnonzero(ok)[np.argmin(dist[ok])])]


def _se(s: float, row, t: Target) -> float:
    """The standard error s / sqrt(n) of the mean at ``row`` (n its seeds)."""
    return s / math.sqrt(max(float(row[f"{t.response}_n"]), 1.0))


def beyond_measured(points: pd.DataFrame, row, t: Target, reached: float) -> bool:
    """The measured mean at the closest point (``row``) lies on the surrogate's side of target
    ``t``, further than its tolerance plus t_{1 - alpha, nu} s / sqrt(n) (s the pooled
    replicate SD, nu its degrees of freedom, n the point's seeds): a one-sided test, its side
    set before the measurement by the surrogate's reach (``reached`` below or above the
    target), where :func:`beyond_data` takes the side its runs fall on and so tests both."""
    from scipy import stats

    s, nu = _margin_sd(points, t.response)
    mean = float(row[t.response])
    if nu < 1 or not math.isfinite(mean):
        return False
    margin = t.tolerance + float(stats.t.ppf(1.0 - UNREACHABLE_ALPHA, nu)) * _se(s, row, t)
    return bool(mean < t.value - margin) if t.value > reached else bool(mean > t.value + margin)


def seed_sd(problem: Problem, points: pd.DataFrame, surrogates: dict) -> dict:
    """One seed's scatter per response: the larger of the pooled replicate SD and the scatter the
    surrogate's fit leaves (two seeds at the centre can badly understate it)."""
    return {r: max(pooled_sd(points, r) or 0.0, surrogates[r].noise_sd) for r in problem.responses}


def ready_to_verify(problem: Problem, best: dict, scatter: dict, settings: Settings,
                    stalled: bool = False) -> str:
    """Why the best candidate is verified now ('' when it is not): P >= ``p_verify``; or every
    response's prediction lies within tolerance and either is known at least as well as a
    verification measures it (predictive SD <= seed scatter / sqrt(verify_seeds), ``scatter``
    from :func:`seed_sd`) or the proposals have ``stalled`` (2 d + 1 proposal runs since the last
    verification).  Where the seed scatter is wide against the tolerance, P cannot reach
    ``p_verify`` however many runs are added, and only a verification can tell."""
    if best["p"] >= settings.p_verify:
        return f"P = {best['p']:.2f} >= {settings.p_verify:g}"
    sure = True
    for t in problem.targets:
        sd = scatter.get(t.response) or 0.0
        mu, s = best["predicted"][t.response], best["predicted_sd"][t.response]
        if t.miss(mu) > 0:
            return ""
        sure &= sd > 0 and s <= sd / math.sqrt(settings.verify_seeds)
    if sure:
        return "every prediction within tolerance and known as well as a verification measures it"
    return "every prediction within tolerance, and 2 d + 1 proposals since the last verification" if stalled else ""


def _where(problem: Problem, actual) -> str:
    """The levels of a point, each factor on a bound of its range marked as such."""
    return ", ".join(f"{n} = {v:.4g}" + _bound(f, v) for n, v, f in zip(problem.names, actual, problem.factors))


def _best_said(problem: Problem, best: dict) -> str:
    """Where a design that stopped without meeting its targets left its best candidate: its
    probability of consistency, each response's prediction against its target, and its levels
    (a factor on a bound: the target may lie beyond the range)."""
    pred = "; ".join(f"{t.response} {best['predicted'][t.response]:.4g} (+- {best['predicted_sd'][t.response]:.2g}) "
                     f"against {t.said()}" for t in problem.targets)
    return f"the best candidate (P = {best['p']:.2g}) predicts {pred}, at {_where(problem, best['actual'])}"


def _bound(f: Factor, v: float) -> str:
    span = f.high - f.low
    if abs(v - f.low) <= 1e-3 * span:
        return " (its low bound)"
    if abs(v - f.high) <= 1e-3 * span:
        return " (its high bound)"
    return ""


# --------------------------------------------------------------------------- in-process driver

def run(problem: Problem, evaluate, settings: Settings, runs: pd.DataFrame | None = None,
        on_iteration=None) -> tuple[pd.DataFrame, Step]:
    """Drive the design in one process: ``evaluate(levels: dict, seed: int) -> {response:
    value}`` runs one simulation (fixed factors are added to ``levels``).  ``runs``: the runs
    of an interrupted design (it resumes where they end).  Returns all runs and the final
    step.  ``on_iteration(step, runs)`` is called after each iteration's runs."""
    runs = empty_runs(problem) if runs is None else runs.copy()
    iteration = int(runs["iteration"].max()) + 1 if len(runs) else 0
    while True:
        st = step(problem, runs, settings, iteration)
        if st.status != "continue":
            return runs, st
        new = _evaluated(problem, st.runs, evaluate)
        runs = pd.concat([runs, new], ignore_index=True) if len(runs) else new
        if on_iteration is not None:
            on_iteration(st, runs)
        iteration += 1


def _evaluated(problem: Problem, new: pd.DataFrame, evaluate) -> pd.DataFrame:
    """The runs ``new`` with their responses from ``evaluate`` (:func:`run`)."""
    new = new.copy()
    for r in problem.responses:
        new[r] = np.nan
    for i, row in new.iterrows():
        levels = {n: float(row[n]) for n in problem.names} | dict(problem.fixed)
        out = evaluate(levels, int(row["seed"]))
        for r in problem.responses:
            new.at[i, r] = float(out.get(r, np.nan))
    return new


def run_shared(problems: dict[str, Problem], evaluate, settings: Settings) -> dict[str, tuple[pd.DataFrame, Step]]:
    """Drive the cases of one stage in one process, sharing their runs (module docstring), in
    lockstep as the workflow runs them: every case decides iteration k from all runs of the
    iterations before k.  ``problems``: case id -> problem, in the stage's order; returns case
    id -> (its own runs, its final step)."""
    names = list(problems)
    first = problems[names[0]]
    for c in names[1:]:
        if problems[c].names != first.names or problems[c].fixed != first.fixed:
            raise InputError(problems[c].source, "factors", "the same factors and fixed values as the stage's "
                             f"other cases ({', '.join(first.names)})", problems[c].names)
    own = {c: empty_runs(problems[c]) for c in names}
    final: dict[str, Step] = {}
    iteration = 0
    while len(final) < len(names):
        decided = {}
        for i, c in enumerate(names):
            if c in final:
                continue
            others = [own[o].assign(case=o) for o in names if o != c and len(own[o])]
            shared = pd.concat(others, ignore_index=True) if others else None
            st = step(problems[c], own[c], case_settings(settings, i), iteration, shared=shared,
                      wait_for_start=i > 0)
            decided[c] = st
        for c, st in decided.items():
            if st.status != "continue":
                final[c] = st
            elif len(st.runs):
                new = _evaluated(problems[c], st.runs, evaluate)
                own[c] = pd.concat([own[c], new], ignore_index=True) if len(own[c]) else new
        iteration += 1
    return {c: (own[c], final[c]) for c in names}


__all__ = ["DEFAULTS", "GOALS", "Factor", "Problem", "Settings", "Step", "Target", "consistency",
           "SEED_STRIDE", "case_settings", "consistent_region", "empty_runs", "fit_surrogates", "improvement",
           "point_table", "resolve", "run", "run_shared", "shared_rows", "start_points", "step"]
