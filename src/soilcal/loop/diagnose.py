"""Structure in the residual: which covariate the misfit follows, with p-values.

Tests on the relative residual ``r`` (:mod:`soilcal.loop.residuals`) of the usable rows,
each an ordinary least-squares fit (statsmodels) against a null of no structure:

* ``bias``: the mean of ``r`` is zero (one-sample t-test); share explained: mean^2 / mean(r^2);
* ``scatter``: the standardised residuals (residual over the combined measured and seed
  standard error) follow Student's t with each row's Welch-Satterthwaite degrees of freedom
  (:mod:`soilcal.loop.residuals`: the SDs are estimated from a few repeats and seeds); each
  is mapped to the unit-normal deviate of the same two-sided tail probability, and the sum
  of their squares is chi-square on n degrees of freedom (upper tail), over the rows whose
  measured SD is known: scatter beyond what the measurement and the seeds explain (a stone,
  a disturbance the covariates do not carry); a condition measured as replicate rows without
  an SD enters with the residual of their mean over their own scatter
  (:func:`replicate_residuals`), replicate rows with an SD, which share their simulation's
  seed error, with their mean's residual and their scatter about it (:func:`_shared_simulation`).  Taken as unit normal instead, residuals
  standardised with SDs of three repeats and three seeds flag scatter where there is none:
  at alpha 0.05, in 44.5 % of 600 simulated 12-row tables (2.7 % with the t deviates; with
  ten repeats and seeds 10.3 % against 3.5 %);
* ``trend`` of a numeric covariate with at least three distinct values: ``r ~ x``, the
  slope's t-test;
* ``curvature`` with at least four distinct values: ``r ~ x + x^2``, the t-test of the
  square term;
* ``periodic`` of the ``position`` along the bin with at least :data:`PERIODIC_MIN` distinct
  values: a sine of the position, scanned over its wavelength, the largest share it explains
  against permutations of the residuals (:func:`_periodic`): a ridge pattern left by the bed preparation
  repeats along the bin, and neither a trend nor a curvature follows it;
* ``group`` of a label covariate (a tool, a test day, any column declared as one of
  :data:`LABEL_QUANTITIES`) or of a numeric one with two levels, and of the measured
  quantity where a table holds several: one-way ANOVA ``r ~ C(g)``, F-test, where some group
  has two rows.  A column that groups the rows exactly as an earlier one does is tested once,
  and one that groups them by measured condition (a run number, a label per row) not at all:
  it would only compare the rows with each other, the scatter test's question.

Where the tested rows hold tests of more than one measured quantity (two tables, one of a
heap's static angle and one of a drum's dynamic angle; a plate's two forces measured together
are one set, :func:`quantity_sets`), the trend, curvature and group tests fit each quantity its
own offset beside the covariate's terms (:func:`quantity_offsets`), and ``r2`` is the share of
the residual variance those terms add to the offsets' fit: a calibration that misses one
quantity by 13 % and the other by 2 % is the ``measure`` group test's structure, and taken as
scatter it hid the layer depth's trend common to both (the vineyard soil's three layers: the
trend's p 0.41 without the offsets, 0.0005 with them).  A covariate that changes only with the
quantity (a speed per table) has no test left beside the offsets.  The periodic test takes the
residuals as they are.

The bias and the covariates' tests take one value per measured test (a row of a measured
table): the mean relative residual of the quantities it measures (:func:`per_test`).  A
stone, a ridge or a day's level moves the horizontal and the vertical force of one test
alike, and counted as two independent observations they make a trend look twice as well
supported as it is: a periodic disturbance along the bin (amplitude 10 %, 15 tests of two
forces) gave a curvature in the working depth at Holm p 0.0007 over 30 rows, 0.07 over the
15 tests.  The mean weights each quantity by the inverse of its relative residual's variance,
v = (sd_m^2 / n_m + sd_s^2 / n_s) / scale^2, the measured and seed variances of the residual
table (:mod:`soilcal.loop.residuals`) with each quantity's relative SDs pooled over its rows
(:func:`soilcal.loop.residuals.relative_variances`), so that the weights are one per quantity
and not the noise of each row's few repeats and seeds: sum(r_i / v_i) / sum(1 / v_i), whose
variance 1 / sum(1 / v_i) is the least any weighting reaches for independent errors.  With
equal weights a noisy quantity swamps a quiet one.  On the DEM soil bin (cinnamon soil,
bulldozing plate, six seeds; ``benchmarks/results/loop_rate/sensitivity.md``) the horizontal
force's relative seed SD is 0.10 and the vertical force's 0.34, their deviations
correlated +0.76, and a friction change moves them by +0.36 and +0.70 per unit ln f: the
horizontal force alone carries 3.6 seed SDs of it, the equal-weight mean 2.5, the
inverse-variance mean 3.4 (the best linear combination, which needs the correlation the
residual table does not carry, 3.75).  In the loop benchmark (``benchmarks/results/loop.md``)
the DEM campaigns that measured both forces, diagnosed with equal weights, named no effect
where the horizontal force alone named rate_friction; their saved residual tables diagnosed
with these weights follow the speed as the horizontal force's rows alone do (campaign 1: trend
Holm p 0.043, 0.43 with equal weights, 0.034 on the horizontal rows), the horizontal force
weighted 0.94 to 0.99.  Where the variance of a quantity of a test is unknown (no measured SD
and one seed: no standard error in the residual table, and none to pool from the quantity's
other rows) that test takes the plain mean, as does every test whose quantities have one
variance (equal weights), and every test whose quantities' variances are not made of the same
parts: a quantity with no measured SD on any row but several seeds has its seed scatter alone,
which understates its variance (as the scatter test below says of such a row), and beside one
with both parts it would take most of the weight (a 10 % measured SD over three repeats and a
3 % seed SD, against a 5 % seed SD alone: weights 0.19 and 0.81).  The weights use each row's
repeat and seed counts, so where those counts (or failed runs) follow a covariate the weights
differ between tests, and the quantities' different offsets can look like structure in that
covariate; with one count per quantity, the usual table, the weights are one per quantity.
With most of the weight on the quiet quantity, an offset in the noisy quantity alone barely
reaches the bias and trend tests; the group test of the measured quantities (``measure``), on
all rows, still sees it.  The shared disturbances are why the quantities are combined into one
value; only the weights follow their noise.  Replicates of one condition (table rows of one
simulation: a speed run three times) share the simulated mean and whatever the condition
carries beyond the model, so the bias and the covariates' tests take the mean over them
(:func:`per_condition`), except for a covariate that varies among the replicates (a test day, a
replicate number), tested on the measured tests.  The scatter test and the group test of the
measured quantities take every row.

The p-values of all tests of a table are corrected together (Holm, :func:`holm_adjusted`,
statsmodels' values); a test is significant when its corrected p is below ``alpha``.  Each
test's ``r2`` is the share of the residual variance about its mean that the fit explains
(for ``bias``, of the sum of squares about zero).  :func:`ranking` orders the covariates by
the largest share any of their tests explains.

Covariates of a campaign are seldom independent: the tests of one day may happen to run at
the faster speeds.  :func:`beyond` tells whether a covariate still explains the residual once
another one's structure is fitted (a nested F-test of its terms, statsmodels
``compare_f_test``): a second covariate that adds nothing beyond the first shares the first's
structure rather than having its own.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

#: declared quantities whose cells are labels even where they are numbers (a plate number)
LABEL_QUANTITIES = ("tool", "day", "group")

DIAGNOSIS_COLUMNS = ["test", "covariate", "quantity", "n", "levels", "estimate", "statistic", "p", "p_adjusted",
                     "r2", "significant"]


def _is_numeric(s: pd.Series) -> bool:
    return bool(len(s)) and pd.to_numeric(s, errors="coerce").notna().all()


def _ols(y, X):
    from statsmodels.regression.linear_model import OLS

    return OLS(np.asarray(y, float), np.asarray(X, float)).fit()


#: covariate column names that identify a test day, session or group of replicates (compared in
#: lower case, with spaces, hyphens and dots read as underscores): tested as labels where they
#: declare no quantity, even with numbered cells, and grouping the held-out folds
#: (:func:`soilcal.loop.core.fold_grouping`)
#: (not ``group``, ``block`` or ``series``: as often the experiment's own treatment levels, a
#: moisture set per group, as sessions with a level of their own; declared ``quantity: group``
#: they group the folds)
GROUPING_NAMES = ("day", "date", "test_day", "test_date", "day_id", "day_no", "session", "test_session",
                  "session_id", "session_no", "batch", "batch_id", "test_group", "replicate_group", "rep_group")


def grouping_name(col: str) -> bool:
    """Whether a column's name is one of :data:`GROUPING_NAMES`."""
    import re

    return re.sub(r"[\s.\-]+", "_", str(col).strip().lower()) in GROUPING_NAMES


def _numeric(col: pd.Series, name: str, q: str) -> bool:
    """Whether a covariate is tested as a number (trend, curvature) rather than a label: a
    column of numbers that is not the measured quantity, not declared as a label quantity and,
    declaring none, not named as a test day or session (:data:`GROUPING_NAMES`: day 1, 2, 3 are
    days, not a scale)."""
    return (_is_numeric(col) and name != "measure" and q not in LABEL_QUANTITIES
            and not (not q and grouping_name(name)))


def _standardised(col: pd.Series) -> np.ndarray:
    x = pd.to_numeric(col, errors="coerce").to_numpy(float)
    return (x - x.mean()) / (x.std() or 1.0)


def _covariate_columns(res: pd.DataFrame) -> list[str]:
    return [c for c in res.columns if c.startswith("cov:")]


def _indicators(labels, n: int) -> np.ndarray:
    """Indicator columns of the levels of ``labels`` (n of them), the first (sorted) level
    dropped; no column where there is one level."""
    labels = np.asarray(labels).astype(str)
    return np.column_stack([(labels == lv).astype(float) for lv in sorted(set(labels))[1:]] or [np.empty((n, 0))])


def quantity_sets(frame: pd.DataFrame) -> np.ndarray | None:
    """Per row of a frame of measured tests (:func:`per_test`, :func:`per_condition`) the
    measured quantities its test holds, joined by ``+`` (a plate's two forces are one set);
    None where the frame names no quantity."""
    if "_quantities" in frame.columns:
        return frame["_quantities"].astype(str).to_numpy()
    if "measure" in frame.columns:
        return frame["measure"].astype(str).to_numpy()
    return None


def quantity_offsets(frame: pd.DataFrame, rows=None) -> np.ndarray:
    """Indicator columns (first level dropped) of the measured quantities of the tests
    (:func:`quantity_sets`) on the rows ``rows`` (a boolean mask; all by default), where those
    rows hold tests of more than one set of quantities: each its own offset in the covariates'
    tests (module docstring); no column otherwise."""
    q = quantity_sets(frame)
    n = len(frame) if rows is None else int(np.sum(rows))
    if q is None:
        return np.empty((n, 0))
    return _indicators(q if rows is None else q[np.asarray(rows, bool)], n)


def _covariate_tests(name, q, col, r, numeric, distinct, offsets: np.ndarray | None = None) -> list[dict]:
    """Trend and curvature of a numeric covariate, or the group test of a label one, on the
    rows that carry it, beside the measured quantities' own offsets where the rows hold tests
    of several (``offsets``, :func:`quantity_offsets`; module docstring).  ``r2``: the share of
    the residual variance about its mean that the covariate's terms add to the offsets' fit
    (the fit's R^2 where there are no offsets)."""
    n = len(r)
    sst = float(np.sum((r - r.mean()) ** 2)) if n else 0.0
    Z = np.empty((n, 0)) if offsets is None else np.asarray(offsets, float)
    k = Z.shape[1]
    base = np.column_stack([np.ones(n), Z])
    rows = []
    if n <= base.shape[1]:
        return rows
    f0 = _ols(r, base) if k else None  # the offsets alone
    ssr0 = float(f0.ssr) if k else sst

    def share(fit) -> float:
        return float((ssr0 - fit.ssr) / sst) if sst > 0 else 0.0

    def adds(X) -> bool:  # the covariate's terms vary beyond the quantities' offsets
        return np.linalg.matrix_rank(X) > np.linalg.matrix_rank(base)

    if numeric and distinct >= 3:
        if n < 4 + k:
            return rows
        sx = pd.to_numeric(col, errors="coerce").to_numpy(float).std() or 1.0
        xs = _standardised(col)
        X1 = np.column_stack([base, xs])
        if not adds(X1):
            return rows
        f1 = _ols(r, X1)
        rows.append(dict(test="trend", covariate=name, quantity=q, n=n, levels=distinct,
                         estimate=float(f1.params[-1] / sx), statistic=float(f1.tvalues[-1]),
                         p=float(f1.pvalues[-1]), r2=share(f1)))
        X2 = np.column_stack([base, xs, xs ** 2])
        if distinct >= 4 and n >= 5 + k and np.linalg.matrix_rank(X2) == X2.shape[1]:
            f2 = _ols(r, X2)
            rows.append(dict(test="curvature", covariate=name, quantity=q, n=n, levels=distinct,
                             estimate=float(f2.params[-1] / sx ** 2), statistic=float(f2.tvalues[-1]),
                             p=float(f2.pvalues[-1]), r2=share(f2)))
        if q == "position" and distinct >= PERIODIC_MIN:
            rows.append(_periodic(name, q, pd.to_numeric(col, errors="coerce").to_numpy(float), r, distinct, sst))
    else:
        X = np.column_stack([base, _indicators(col, n)])
        rank = np.linalg.matrix_rank(X)
        if n <= rank or not adds(X):  # no row left to estimate the within-group variance, or no group beyond the offsets
            return rows
        f = _ols(r, X)
        if k:
            stat, p, _ = f.compare_f_test(f0)
        else:
            stat, p = f.fvalue, f.f_pvalue
        rows.append(dict(test="group", covariate=name, quantity=q or ("measure" if name == "measure" else ""),
                         n=n, levels=distinct, estimate=float(np.sqrt(max(ssr0 - f.ssr, 0.0) / n)),
                         statistic=float(stat), p=float(p), r2=share(f)))
    return rows


#: distinct positions a periodic test needs (a sine and a cosine beside the mean, and a scan)
PERIODIC_MIN = 8
#: wavelengths scanned per independent frequency (oversampling of the periodogram)
PERIODIC_OVERSAMPLE = 5
#: permutations of the periodic test, and the seed of their generator
PERIODIC_PERMUTATIONS = 4999
PERIODIC_SEED = 0


def _periodic(name, q, x, r, distinct, sst) -> dict:
    """The ``periodic`` test of a position along the bin: r ~ a sin(2 pi x / L) + b cos(2 pi x / L)
    + c, scanned over the frequencies 1 / L from one period over the positions' span to (m - 1) / 2
    periods (the Nyquist frequency of m distinct positions at their mean spacing, span / (m - 1):
    the shortest period evenly spaced positions resolve, beyond which a sine aliases one
    scanned already), :data:`PERIODIC_OVERSAMPLE`
    per step; the statistic is the largest share of the residual variance a sine explains over
    the scan, and its p the share of :data:`PERIODIC_PERMUTATIONS` permutations of the residuals
    over the positions (generator seed :data:`PERIODIC_SEED`) whose largest share is as large,
    (1 + count) / (1 + permutations): a scan's maximum has no F law, and the approximate
    false-alarm rule 1 - (1 - p_min)^n (Press & Rybicki, ApJ 338 (1989) 277) flagged 6.5-8 % of
    residuals without structure at alpha 0.05.  ``estimate``: the best wavelength, in the
    covariate's unit; ``statistic``: its F."""
    n = len(r)
    m = int(distinct)  # distinct positions: repeats at one position add no frequency to tell
    span = float(np.max(x) - np.min(x))
    freqs = np.linspace(1.0 / span, ((m - 1) / 2.0) / span, PERIODIC_OVERSAMPLE * max((m - 1) // 2, 1))
    w = 2 * np.pi * freqs[:, None] * (x - x.min())[None, :]
    basis = []
    keep = []
    tiny = 1e-9 * np.sqrt(n)
    for j, (sn, cs) in enumerate(zip(np.sin(w), np.cos(w))):
        cols = [c - c.mean() for c in (sn, cs)]
        cols = [c for c in cols if np.linalg.norm(c) >= tiny]
        if not cols:  # a frequency the positions cannot tell from the mean
            continue
        qm, rr = np.linalg.qr(np.column_stack(cols))
        if len(cols) == 2 and abs(rr[1, 1]) < tiny:
            # the sine and cosine one column at these positions (at the Nyquist frequency of
            # evenly spaced ones the sine is 0 at every position, the cosine +-1): one direction
            qm, rr = qm[:, :1], rr[:1, :1]
        if qm.shape[1] == 1:
            qm = np.column_stack([qm[:, 0], np.zeros(n)])
        basis.append(qm)
        keep.append(j)
    rc = r - r.mean()
    ss = float(rc @ rc)
    if not basis or ss <= 0 or n < 4:
        return dict(test="periodic", covariate=name, quantity=q, n=n, levels=distinct, estimate=np.nan,
                    statistic=np.nan, p=np.nan, r2=0.0)
    F = len(basis)
    Q = np.ascontiguousarray(np.stack(basis).transpose(1, 0, 2).reshape(n, 2 * F))  # n x (frequency, sin/cos)

    def largest(R):  # R: (..., n) centred residuals -> the largest share over the scan, and where
        proj = (R @ Q).reshape(*R.shape[:-1], F, 2)  # one matrix product (BLAS) for every frequency
        share = np.sum(proj ** 2, axis=-1) / np.sum(R ** 2, axis=-1)[..., None]
        return share.max(axis=-1), share.argmax(axis=-1)

    r2, at = largest(rc)
    rng = np.random.default_rng(PERIODIC_SEED)
    count, done = 0, 0
    while done < PERIODIC_PERMUTATIONS:  # in blocks, so a long table's scan stays small in memory
        k = min(500, PERIODIC_PERMUTATIONS - done)
        # k permutations at once, each row's shuffle the draws rng.permutation(n) makes in turn
        null, _ = largest(rc[rng.permuted(np.tile(np.arange(n), (k, 1)), axis=1)])
        count += int(np.sum(null >= r2 - 1e-12))
        done += k
    p = (1.0 + count) / (1.0 + PERIODIC_PERMUTATIONS)
    r2 = float(r2)
    f = r2 / 2.0 / ((1.0 - r2) / (n - 3)) if r2 < 1 and n > 3 else np.inf
    return dict(test="periodic", covariate=name, quantity=q, n=n, levels=distinct,
                estimate=float(1.0 / freqs[keep[int(at)]]), statistic=float(f), p=p, r2=r2 if sst > 0 else 0.0)


def normal_equivalent(t, dof):
    """The unit-normal deviates with the same two-sided tail probabilities as the Student t
    values ``t`` on ``dof`` degrees of freedom (infinite: ``t`` itself), signs kept."""
    from scipy import stats

    t = np.asarray(t, float)
    dof = np.asarray(dof, float)
    out = t.copy()
    fin = np.isfinite(dof)
    if fin.any():
        out[fin] = np.sign(t[fin]) * stats.norm.isf(stats.t.sf(np.abs(t[fin]), dof[fin]))
    return out


def per_test(d: pd.DataFrame) -> pd.DataFrame:
    """One row per measured test of the residual rows ``d``: the relative residuals of the
    quantities one test measures (its horizontal and vertical force) averaged with weights
    1 / v, v each row's relative variance (:func:`soilcal.loop.residuals.relative_variances`:
    measured and seed variance over the scale squared, the relative SDs pooled per quantity),
    the plain mean where some row of the test has no known variance (no measured SD and one
    seed, or a table without those columns) or where its rows' variances do not hold the same
    parts (measured and seed) (module docstring), the other columns (its covariates) kept.  A
    stone, a ridge or a day's level moves every quantity of a test alike, so they are not
    independent observations of a covariate's structure: counted as such, a table of two
    quantities per test halves the p-values of its trend tests (module docstring).  A test is a
    row of a measured table; table rows entered twice (the same simulation, the same value in
    every covariate column and the same measured values, SDs and repeat counts) are one test: a
    row copied into a table tells a covariate's structure no more than once (three rows of
    twelve entered twice made the residual "follow" the moisture at Holm p 0.004).  ``d`` itself
    where each test has one row or no test is named (no ``measurement``, ``row`` columns)."""
    if "measurement" not in d.columns or "row" not in d.columns or len(d) == 0:
        return d
    key = d["measurement"].astype(str) + "/" + d["row"].astype(str)
    if "simulation" in d.columns:
        same = [c for c in ["simulation", *sorted(c for c in d.columns if c.startswith("cov:"))] if c in d.columns]
        what = [c for c in ("measure", "measured", "measured_sd", "measured_n") if c in d.columns]
        cells = ["|".join(map(str, a)) + "#" + "=".join(map(str, b))
                 for a, b in zip(d[same].itertuples(index=False), d[what].itertuples(index=False))]
        # per table row: its simulation and covariates, and every measured value it holds
        rows = {}
        for k, c in zip(key, cells):
            rows.setdefault(k, []).append(c)
        sig = {k: "&".join(sorted(v)) for k, v in rows.items()}
        key = pd.Series([sig[k] for k in key], index=d.index)
    if key.is_unique:
        return d
    from soilcal.loop.residuals import relative_variances

    r = d["relative_residual"].astype(float).to_numpy()
    v, parts = relative_variances(d, parts=True)  # v NaN where a row's variance is unknown
    w = 1.0 / v
    g = d.assign(_test=key.to_numpy()).groupby("_test", sort=False)
    out = g.first()
    has = np.isfinite(r)  # a row without a residual counts in neither mean
    # the parts each row's variance holds (1 measured, 2 seed, 3 both); a row without a
    # residual is left out of the comparison (99 / -1 never set the min / max)
    t = pd.DataFrame({"_test": key.to_numpy(), "w": np.where(has, w, 0.0), "wr": np.where(has, w * r, 0.0), "r": r,
                      "known": np.isfinite(w) | ~has, "lo": np.where(has, parts, 99), "hi": np.where(has, parts, -1)})
    s = t.groupby("_test", sort=False).agg(w=("w", "sum"), wr=("wr", "sum"), mean=("r", "mean"), known=("known", "all"),
                                           lo=("lo", "min"), hi=("hi", "max"))
    # weights only between variances of the same parts: a quantity without a measured SD has
    # its seed scatter alone, which understates its variance beside one that has both
    weighted = s["known"] & (s["w"] > 0) & (s["lo"] == s["hi"])
    out["relative_residual"] = (s["wr"] / s["w"].where(weighted)).where(weighted, s["mean"])
    if "measure" in d.columns:  # the quantities each test holds (quantity_sets)
        out["_quantities"] = g["measure"].agg(lambda m: "+".join(sorted(set(map(str, m)))))
    return out.reset_index(drop=True)



def _condition_key(dt: pd.DataFrame) -> pd.Series | None:
    """Per measured test (a row of :func:`per_test`) its measured condition: the simulation it
    shares with its replicates (:func:`soilcal.loop.residuals.simulation_key`); None where the
    table names no simulation."""
    return dt["simulation"].astype(str) if "simulation" in dt.columns else None


def per_condition(dt: pd.DataFrame) -> pd.DataFrame:
    """One row per measured condition of the measured tests ``dt`` (:func:`per_test`): the
    relative residuals of a condition's replicates (table rows of one simulation, as a soil-bin
    table repeats each speed three times) averaged, the other columns taken from its first
    test.  Replicates share the simulated mean (and its seeds' error) and whatever the
    condition carries beyond the model (the bed prepared for it), so they are not independent
    observations of a covariate's structure: counted as such, three repeats per speed of a
    residual without structure (a deviation of SD 5 % per condition, 3 % per repeat; 8
    conditions) gave a significant trend, curvature or bias in 42 % of 100 tables, six repeats
    in 85 %, one row per condition in 1 %.  ``dt`` itself where each condition has one test."""
    key = _condition_key(dt)
    if key is None or key.is_unique:
        return dt
    g = dt.groupby(key.to_numpy(), sort=False)
    out = g.first()
    out["relative_residual"] = g["relative_residual"].mean()
    return out.reset_index(drop=True)


def varies_within(dt: pd.DataFrame) -> set[str]:
    """The covariate columns (``cov:``) whose value differs among the replicates of one
    condition (:func:`per_condition`): a test day when a speed was run on several days, a
    replicate number.  Their tests compare the replicates and take the measured tests."""
    key = _condition_key(dt)
    if key is None or key.is_unique:
        return set()
    out = set()
    for c in _covariate_columns(dt):
        if (dt[c].astype(str).groupby(key.to_numpy()).nunique() > 1).any():
            out.add(c)
    return out


def replicate_residuals(d: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """Standardised residuals (and their Welch-Satterthwaite degrees of freedom, from the
    replicate and seed variances pooled over the measured quantity's conditions) of the
    conditions measured as replicate rows without an SD: per condition and measured quantity
    with two measured values at least, not all equal, the residual of their mean, over
    sqrt(s^2 / n + sd_s^2 / n_s) with s the replicates' sample SD (n of them) and sd_s the seed
    SD of the simulated mean (n_s seeds) (:mod:`soilcal.loop.residuals`): the replicates are the
    measured uncertainty a table of one row per condition states in its ``sd`` and ``n``
    columns.  Every repeat counts, equal values too: repeats rounded to whole newtons or half
    degrees often repeat a value, and counting them once shrank the test's degrees of freedom
    (250, 250, 256 N read as two repeats)."""
    return replicate_standardised(replicate_conditions(d))


def replicate_conditions(d: pd.DataFrame) -> tuple | None:
    """What :func:`replicate_residuals` standardises, gathered from the rows ``d``: per
    condition and measured quantity with two measured values at least, not all equal, (mean,
    replicate SD, n, simulated mean, seed SD, seeds, scale, quantity), each an array over them,
    and their relative variance pooled over each quantity's conditions
    (:func:`soilcal.loop.residuals.pooled_relative_variance`); None where there is none.
    Gathered once, it is standardised against the simulated means and seed SDs times any
    factor (:func:`replicate_standardised`), as the scatter about a uniform scale does at every
    scale it tries (:func:`soilcal.loop.core.scatter_about_scale`)."""
    need = {"simulation", "measure", "measured", "simulated_mean", "simulated_sd", "simulated_n"}
    if not need <= set(d.columns) or not len(d):
        return None

    from soilcal.loop.residuals import KEY_SEP, pooled_relative_variance

    rows = d if "measured_sd" not in d else d[~np.isfinite(d["measured_sd"].astype(float).to_numpy())]
    cond = []  # per condition and quantity: mean, replicate SD, n, simulated mean, seed SD, seeds, scale, quantity
    for _, g in rows.groupby([rows["simulation"].astype(str), rows["measure"].astype(str)], sort=False):
        m = g["measured"].to_numpy(float)  # every repeat: rounded forces repeat a value
        m = m[np.isfinite(m)]
        n = len(m)
        if n < 2:
            continue
        sd = float(np.std(m, ddof=1))
        if sd == 0.0:
            continue  # repeats that all read one value (rounded) state no scatter to judge against
        scale = (float(np.nanmean(g["scale"].to_numpy(float))) if "scale" in g else float(np.mean(np.abs(m))))
        cond.append((float(np.mean(m)), sd, n, float(g["simulated_mean"].iloc[0]), float(g["simulated_sd"].iloc[0]),
                     float(g["simulated_n"].iloc[0]), scale,
                     str(g["measurement"].iloc[0]) + KEY_SEP + str(g["measure"].iloc[0]) if "measurement" in g
                     else str(g["measure"].iloc[0])))
    if not cond:
        return None
    mean, sd, n, sim, sd_s, n_s, scale, q = (np.array(c) for c in zip(*cond))
    mean, sd, n, sim, sd_s, n_s, scale = (np.asarray(x, float) for x in (mean, sd, n, sim, sd_s, n_s, scale))

    return mean, sd, n, sim, sd_s, n_s, scale, q, pooled_relative_variance(sd, n, scale, q)


def replicate_standardised(cond: tuple | None, factor: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """(standardised residuals, degrees of freedom) of :func:`replicate_residuals` from the
    conditions ``cond`` (:func:`replicate_conditions`), their simulated means and seed SDs
    times ``factor`` (a uniform scale 1 + s: the means times 1 + s, the SDs times |1 + s|)."""
    from soilcal.loop.residuals import pooled_relative_variance, satterthwaite

    if cond is None:
        return np.empty(0), np.empty(0)
    mean, sd, n, sim, sd_s, n_s, scale, q, pooled_m = cond
    if factor != 1.0:
        sim, sd_s = sim * factor, sd_s * abs(factor)
    var_m = sd ** 2 / n
    var_s = np.where(np.isfinite(sd_s) & (n_s >= 1), sd_s ** 2 / np.clip(n_s, 1.0, None), 0.0)
    se = np.sqrt(var_m + var_s)
    # degrees of freedom from the variances pooled over the quantity's conditions (relative to
    # their scale), not from the condition's own: those grow where its two or three replicates
    # or seeds happen to scatter little, exactly where the residual over them is large
    # (:func:`soilcal.loop.residuals.reference_variances`)
    ref_m = pooled_m * scale ** 2 / n
    ref_s = np.where(n_s > 1, pooled_relative_variance(sd_s, n_s, scale, q) * scale ** 2 / np.clip(n_s, 1.0, None),
                     var_s)
    ref_m, ref_s = np.where(np.isfinite(ref_m), ref_m, var_m), np.where(np.isfinite(ref_s), ref_s, var_s)
    ok = np.isfinite(sim) & (se > 0)
    z = (mean - sim) / np.where(se > 0, se, 1.0)
    return z[ok], satterthwaite(ref_m, n - 1.0, ref_s, n_s - 1.0)[ok]

def replicate_spread(d: pd.DataFrame) -> dict | None:
    """Whether the replicate rows without a measured SD scatter about their condition's mean
    far more in some conditions than in others: stones met in some replicates of a condition
    and not in others widen those conditions' spread alone, while the rig's noise, however
    large, and a uniform bias (which moves every replicate alike) widen every condition's
    alike.  Per measured quantity, Bartlett's test of equal variances across its conditions
    with two replicate rows at least (:func:`scipy.stats.bartlett`), on the rows relative to
    their condition's mean (noise a share of the value) and on the rows themselves (an
    absolute noise floor): the larger of the two p values, so that neither noise model alone
    makes the spread uneven, and the smallest of those over the quantities times their number
    (Bonferroni).  For 3 rows a condition Levene's test is no use: centred on the mean it put
    18 % of right tables at p < 0.05, on the median (one deviation always 0) none of any.
    Bartlett's holds its level for normal repeats of one relative or one absolute SD (2.6 %
    and 4.1 % of 8-condition tables); for heavier tails (t on 3 dof) it rejects in 19 %.
    Returns ``replicate_percent`` (the replicates' relative SD pooled over the conditions),
    ``widest_percent`` and ``narrowest_percent`` (the largest and smallest condition's),
    ``dof`` (of the quantity with the smallest p), ``p``; None where no quantity has three
    conditions with replicate rows without an SD that differ."""
    from scipy import stats

    need = {"simulation", "measure", "measured"}
    if not need <= set(d.columns) or not len(d):
        return None
    rows = d if "measured_sd" not in d else d[~np.isfinite(d["measured_sd"].astype(float).to_numpy())]
    best, k = None, 0
    for _, q in rows.groupby(rows["measure"].astype(str), sort=False):
        rel, ab = [], []
        # its conditions in the order they first appear, each one's rows in table order
        cond, _ = pd.factorize(q["simulation"].astype(str))
        values = q["measured"].to_numpy(float)
        for c in range(int(cond.max()) + 1):
            m = values[cond == c]
            m = m[np.isfinite(m)]
            if len(m) < 2 or not np.mean(m) != 0 or not np.ptp(m) > 0:
                continue  # identical replicates (values rounded alike) carry no spread to compare
            rel.append(m / abs(float(np.mean(m))))
            ab.append(m)
        if len(rel) < 3:
            continue
        k += 1
        p = max(float(stats.bartlett(*rel).pvalue), float(stats.bartlett(*ab).pvalue))
        sds = np.array([np.std(r, ddof=1) for r in rel])
        dofs = np.array([len(r) - 1 for r in rel], float)
        if best is None or p < best["p"]:
            best = dict(p=p, dof=(len(rel) - 1, int(sum(len(r) for r in rel)) - len(rel)),
                        replicate_percent=100 * float(np.sqrt(np.sum(dofs * sds ** 2) / np.sum(dofs))),
                        widest_percent=100 * float(np.max(sds)), narrowest_percent=100 * float(np.min(sds)))
    if best is None:
        return None
    best["p"] = min(1.0, best["p"] * k)
    return best


def _shared_simulation(d: pd.DataFrame, known: np.ndarray) -> tuple[np.ndarray, float, int]:
    """The scatter test's part of the rows with a measured SD (``known``) that share one
    simulation and quantity with another such row (replicate rows of a condition, on other
    days): they share its seeds' error, so their residuals are not independent (6 conditions x 3
    days, no offset: the scatter test at p < 0.05 in 8 % of tables).  Per such group of r rows,
    the residual of their inverse-variance mean (seed variance sd_s^2 / n_s once) as the normal
    deviate on its Welch-Satterthwaite degrees of freedom (from the SDs pooled over the
    quantity's rows, :func:`soilcal.loop.residuals.reference_variances`), squared, plus their
    scatter about their mean against the pooled measured SD, read as F on its degrees of
    freedom and given as chi-square on r - 1 of the same tail: r degrees of freedom, as r
    independent rows would give.  Returns the rows so taken, their chi-square and its degrees
    of freedom."""

    from soilcal.loop import residuals as rs

    taken = np.zeros(len(d), bool)
    need = {"simulation", "measure", "measurement", "measured", "measured_sd", "simulated_mean", "simulated_sd",
            "simulated_n"}
    if not need <= set(d.columns) or not known.any():
        return taken, 0.0, 0
    known = known & (d["measured_sd"].astype(float).to_numpy() > 0)  # an SD of 0 gives no weight
    key = (d["simulation"].astype(str) + rs.KEY_SEP + d["measure"].astype(str)).to_numpy()
    size = pd.Series(known.astype(int)).groupby(key).transform("sum").to_numpy()
    multi = known & (size > 1)
    if not multi.any():
        return taken, 0.0, 0
    n_m = d["measured_n"].astype(float).fillna(1.0).clip(lower=1.0).to_numpy() if "measured_n" in d else np.ones(len(d))
    ref_m, ref_s = rs.reference_variances(d)
    pooled_dof = rs.pooled_measured_dof(d, known)  # 0 where the quantity's SDs are not pooled
    chi, n = 0.0, 0
    for _, at in pd.Series(np.arange(len(d))[multi]).groupby(key[multi]):
        at = at.to_numpy()
        m = d["measured"].to_numpy(float)[at]
        w = 1.0 / (d["measured_sd"].to_numpy(float)[at] ** 2 / n_m[at])
        sim, sd_s, n_s = (float(d["simulated_mean"].iloc[at[0]]), float(d["simulated_sd"].iloc[at[0]]),
                          float(d["simulated_n"].iloc[at[0]]))
        var_s = sd_s ** 2 / n_s if np.isfinite(sd_s) and n_s >= 1 else 0.0
        se = np.sqrt(1.0 / np.sum(w) + var_s)
        if not (np.isfinite(sim) and np.isfinite(se) and se > 0):
            continue
        dof_m = float(np.sum(n_m[at] - 1.0)) or np.inf
        dof = float(rs.satterthwaite(1.0 / np.sum(1.0 / ref_m[at]), dof_m, float(np.mean(ref_s[at])), n_s - 1.0))
        between = float(normal_equivalent([(np.sum(w * m) / np.sum(w) - sim) / se], [dof])[0]) ** 2
        within = rs.replicate_scatter_chi(m, ref_m[at], pooled_dof[at[0]], d["measured_sd"].to_numpy(float)[at],
                                            n_m[at])
        chi += between + within
        n += len(at)
        taken[at] = True
    return taken, chi, n


def holm_adjusted(p) -> np.ndarray:
    """Holm's step-down adjusted p-values (Holm 1979), in the order given: the k-th smallest of
    m times (m - k + 1), made non-decreasing in that order and capped at 1; the values of
    statsmodels' ``multipletests(p, method="holm")[1]``, whose Holm branch runs a full garbage
    collection on every call (a tenth of a second and more in a process holding many objects,
    paid by every diagnosis)."""
    p = np.asarray(p, dtype=float)
    order = np.argsort(p, kind="stable")
    adj = np.minimum(np.maximum.accumulate(p[order] * np.arange(len(p), 0, -1)), 1.0)
    out = np.empty_like(adj)
    out[order] = adj
    return out


def diagnose(res: pd.DataFrame, quantity_of: dict | None = None, alpha: float = 0.05) -> pd.DataFrame:
    """One row per test (module docstring) on the usable rows of a residual table;
    ``quantity_of``: covariate column -> its declared quantity.  The bias and the covariates'
    tests take one value per measured condition (:func:`per_test`, :func:`per_condition`), the
    scatter and the measured quantities' group test every row."""
    from scipy import stats

    quantity_of = quantity_of or {}
    from soilcal.loop.residuals import EXACT

    r_all = res["relative_residual"].astype(float)
    d = res[np.isfinite(r_all)].reset_index(drop=True)
    rel = d["relative_residual"].astype(float)
    d["relative_residual"] = rel.where(rel.abs() > EXACT, 0.0)  # round-off is no residual
    dt = per_test(d)
    dc = per_condition(dt)
    within = varies_within(dt)
    r = dc["relative_residual"].to_numpy(float)
    rows = []
    n = len(r)
    if n >= 2:
        t = stats.ttest_1samp(r, 0.0)
        rows.append(dict(test="bias", covariate="", quantity="bias", n=n, levels=1, estimate=float(r.mean()),
                         statistic=float(t.statistic), p=float(t.pvalue),
                         r2=float(r.mean() ** 2 / np.mean(r ** 2)) if np.any(r) else 0.0))
    z = (d["standardised_residual"].astype(float).to_numpy() if "standardised_residual" in d
         else np.full(len(d), np.nan))  # no standardised residual: no scatter test
    dof = (d["residual_dof"].astype(float).to_numpy() if "residual_dof" in d else np.full(len(z), np.inf))
    # only where the measured uncertainty is known: seed scatter alone understates it
    known = (np.isfinite(d["measured_sd"].astype(float).to_numpy()) if "measured_sd" in d
             else np.ones(len(d), bool)) & np.isfinite(z)
    shared, chi_shared, n_shared = _shared_simulation(d, known)
    single = known & ~shared
    z = normal_equivalent(z[single], dof[single])
    zr, dofr = replicate_residuals(d)  # replicate rows without an SD: their mean against their own scatter
    z = np.concatenate([z, normal_equivalent(zr, dofr)])
    n_all = len(z) + n_shared
    if n_all >= 3:
        chi = float(np.sum(z ** 2)) + chi_shared
        rows.append(dict(test="scatter", covariate="", quantity="scatter", n=n_all, levels=1,
                         estimate=float(np.sqrt(chi / n_all)), statistic=chi, p=float(stats.chi2.sf(chi, n_all)),
                         r2=0.0))
    # a covariate constant over each condition's replicates is tested on the condition means; one
    # that varies among them (a test day, a replicate number) on the measured tests
    groups = [(c[4:], dt[c], dt) if c in within else (c[4:], dc[c], dc) for c in _covariate_columns(dt)]
    if "measure" in d and d["measure"].nunique() > 1:
        groups.append(("measure", d["measure"], d))
    seen = []
    for name, col_all, frame in groups:
        rr = frame["relative_residual"].to_numpy(float)
        # each measured condition (a table row); a label that groups the rows exactly by it is a
        # row id (a run number, one day per row): its group test would only compare the rows
        # with each other, which is the scatter test's question, and name the id as the cause
        condition = (pd.Series(list(zip(frame["measurement"].astype(str), frame["row"].astype(str))),
                               index=frame.index) if "measurement" in frame and "row" in frame else None)
        q = quantity_of.get(name, "")
        has = col_all.notna().to_numpy()  # a covariate missing on some rows is tested on the others
        col = col_all[has]
        numeric = _numeric(col, name, q)
        distinct = int(col.astype(str).nunique())
        if distinct < 2:
            continue
        if not (numeric and distinct >= 3):
            partition = (name == "measure",) + tuple(pd.factorize(col_all.astype(str))[0]) + tuple(~has)
            if partition in seen:  # the same grouping as an earlier column (a plate number beside its name)
                continue
            seen.append(partition)
            if (name != "measure" and condition is not None
                    and tuple(pd.factorize(col.astype(str))[0]) == tuple(pd.factorize(condition[has])[0])):
                continue  # one level per condition: a row id (see above)
        offsets = None if name == "measure" else quantity_offsets(frame, has)
        rows += _covariate_tests(name, q, col, rr[has], numeric, distinct, offsets)
    df = pd.DataFrame(rows, columns=[c for c in DIAGNOSIS_COLUMNS if c not in ("p_adjusted", "significant")])
    if len(df):
        p = df["p"].fillna(1.0).to_numpy(float)
        df["p_adjusted"] = holm_adjusted(p)
        df["significant"] = df["p_adjusted"] < alpha
    else:
        df["p_adjusted"] = pd.Series(dtype=float)
        df["significant"] = pd.Series(dtype=bool)
    return df[DIAGNOSIS_COLUMNS]


def _terms(res: pd.DataFrame, name: str, quantity_of: dict) -> np.ndarray | None:
    """Columns of a covariate's structure as the tests fit it: x and x^2 of a numeric one
    (standardised; x alone with three distinct values), indicators of a label one (first
    level dropped); ``bias``: none (the intercept); None for an unknown name."""
    if name == "bias":
        return np.empty((len(res), 0))
    col = res["measure"] if name == "measure" else res.get(f"cov:{name}")
    if col is None:
        return None
    distinct = int(col.astype(str).nunique())
    if _numeric(col, name, quantity_of.get(name, "")) and distinct >= 3:
        xs = _standardised(col)
        return np.column_stack([xs, xs ** 2]) if distinct >= 4 else xs[:, None]
    return _indicators(col, len(res))  # no column for one level on these rows: no structure of its own


def beyond(res: pd.DataFrame, name: str, first: str, quantity_of: dict | None = None) -> float:
    """p of the nested F-test that covariate ``name`` explains the relative residual beyond
    covariate ``first`` (module docstring), over the usable rows that carry both; NaN where
    either is unknown or too few rows are left to tell."""
    quantity_of = quantity_of or {}
    from soilcal.loop.residuals import usable

    d = usable(res)
    if "measure" not in (name, first):  # the measured quantity varies within a test: every row
        d = per_test(d)
        if not {f"cov:{name}", f"cov:{first}"} & varies_within(d):  # condition means, as diagnose tests them
            d = per_condition(d)
    for c in (name, first):
        col = d["measure"] if c == "measure" else d.get(f"cov:{c}")
        if c != "bias" and col is not None:
            d = d[col.notna()]
    d = d.reset_index(drop=True)
    if len(d) == 0:
        return float("nan")
    a, b = _terms(d, first, quantity_of), _terms(d, name, quantity_of)
    if a is None or b is None or b.shape[1] == 0:
        return float("nan")
    one = np.ones((len(d), 1))
    small = np.column_stack([one, a])
    big = np.column_stack([small, b])
    if len(d) <= big.shape[1] or np.linalg.matrix_rank(big) <= np.linalg.matrix_rank(small):
        return float("nan")
    r = d["relative_residual"].to_numpy(float)
    return float(_ols(r, big).compare_f_test(_ols(r, small))[1])


def ranking(diag: pd.DataFrame) -> pd.DataFrame:
    """Covariates (and ``bias``) by the largest share of the residual any of their tests
    explains, with their smallest corrected p and whether any test is significant."""
    if len(diag) == 0:
        return pd.DataFrame(columns=["covariate", "quantity", "r2", "p_adjusted", "significant", "tests", "best_test",
                                     "best_estimate", "best_r2", "best_p_adjusted"])
    d = diag.assign(covariate=diag["covariate"].where(~diag["test"].isin(["bias", "scatter"]), diag["test"]))
    out = d.groupby("covariate", sort=False).agg(quantity=("quantity", "first"), r2=("r2", "max"),
                                                 p_adjusted=("p_adjusted", "min"), significant=("significant", "any"),
                                                 tests=("test", lambda s: " ".join(s)))
    # the test that carries the covariate's largest share (a significant one first): its kind,
    # estimate (a periodic test's wavelength), share and corrected p, said together
    order = d.assign(_sig=d["significant"].astype(bool), _r2=d["r2"].astype(float).fillna(-1.0))
    best = (order.sort_values(["_sig", "_r2"], ascending=[False, False], kind="stable")
            .groupby("covariate", sort=False).first())
    out = out.join(best[["test", "estimate", "r2", "p_adjusted"]].rename(
        columns={"test": "best_test", "estimate": "best_estimate", "r2": "best_r2", "p_adjusted": "best_p_adjusted"}))
    return out.sort_values(["significant", "r2"], ascending=[False, False]).reset_index()


def matched_quantities(diag: pd.DataFrame) -> set[str]:
    """The quantities (and ``bias``) whose structure is significant: what an effect's
    signature must share to become a candidate.  Where the residual scatters significantly
    beyond the measured and seed uncertainty and no covariate's test is significant, also the
    quantity of the test most sure of a structure (the smallest uncorrected p, not the largest
    share: a group of k levels, a parabola or a periodic scan of many wavelengths explains a
    larger share of pure noise than a line does): six speeds of a rate effect
    (the residual -36 % to +4 %, 54 standard errors at the slowest) follow ln v, which a
    straight line and a parabola in v each fit to r2 0.70 and 0.93 but at p 0.037 and 0.049,
    not significant after Holm; the scatter test says there is structure and the share says
    where.  A candidate so proposed is still accepted only on a significantly lower held-out
    error (:mod:`soilcal.loop.select`)."""
    flags = diag["significant"].astype(bool)
    sig = diag[flags]
    out = set()
    for r in sig.itertuples():
        if r.test == "bias":
            out.add("bias")
        elif r.quantity:
            out.add(str(r.quantity))
    scatter = flags & (diag["test"] == "scatter")
    if scatter.any() and not (flags & (diag["test"] != "scatter")).any():
        rest = diag[(diag["test"] != "scatter") & (diag["r2"].astype(float) > 0) & diag["p"].astype(float).notna()]
        if len(rest):
            top = rest.loc[rest["p"].astype(float).idxmin()]
            out.add("bias" if top["test"] == "bias" else str(top["quantity"] or ""))
    out.discard("")
    return out


DETECTABLE_COLUMNS = ["test", "covariate", "quantity", "n", "low", "high", "tests", "power", "scatter_percent",
                      "detectable_percent", "seed_se_percent", "measured_se_percent"]


def _smallest_shift(df: int, t_crit: float, power: float) -> float:
    """The noncentrality at which a two-sided t-test on ``df`` degrees of freedom with the
    critical value ``t_crit`` rejects with probability ``power`` (scipy's noncentral t)."""
    from scipy import optimize, stats

    def short(delta):  # the far tail is below 1e-300 where scipy returns NaN for it
        return float(stats.nct.sf(t_crit, df, delta) + np.nan_to_num(stats.nct.cdf(-t_crit, df, delta))) - power

    hi = t_crit + 5.0
    while short(hi) < 0:
        hi *= 2.0
    return float(optimize.brentq(short, 0.0, hi, xtol=1e-10))


def detectable(res: pd.DataFrame, diag: pd.DataFrame, quantity_of: dict | None = None, alpha: float = 0.05,
               power: float = 0.8) -> pd.DataFrame:
    """What the diagnosis of ``res`` could have found: per test of a mean bias or of a trend
    (``diag``'s rows), the smallest structure it detects with probability ``power``, given the
    residual's own scatter, at the strictest level of its Holm family, ``alpha`` over the
    number of tests in ``diag`` (Holm's first step; a conservative bound, as Holm's later
    steps are looser).

    * ``bias``: a mean relative residual of ``detectable_percent``; the scatter is the SD of
      the relative residual (one-sample t-test on n - 1 degrees of freedom);
    * ``trend``: a change of the relative residual by ``detectable_percent`` across the
      covariate's measured range, ``low`` to ``high`` (in the table's unit); the scatter is
      the residual standard error about the fitted line (the slope's t-test on n - 2 degrees
      of freedom, standard error scatter / sqrt(sum (x - mean x)^2)).

    The noncentrality comes from the noncentral t (:func:`_smallest_shift`).  Beside it,
    ``seed_se_percent`` and ``measured_se_percent``: the medians, over every row of every
    quantity of ``res`` (one per residual row, not per test, and unweighted), of the seeds'
    standard error of the simulated mean (sd_s / sqrt(n_s)) and of the measurement's
    (sd_m / sqrt(n_m)), each row's own SDs, as percent of the row's scale (the relative
    residual's, :func:`soilcal.loop.residuals.scales`).  They describe the rows' noise, not
    the standard error of a test's combined value: where a test measures several quantities of
    unequal noise, that value is their inverse-variance mean (:func:`per_test`), whose standard
    error, 1 / sqrt(sum(1 / v)) over the test's quantities, lies at or below the quietest
    quantity's and so below these medians.  Where the scatter is about their combination, more
    seeds or repeats (whichever dominates) shrink what goes unseen as the square root of their
    number; where it is well above, the rows scatter for a reason neither carries."""
    from scipy import stats

    quantity_of = quantity_of or {}
    if diag is None or len(diag) == 0:
        return pd.DataFrame(columns=DETECTABLE_COLUMNS)
    tests = len(diag)
    level = alpha / tests
    d = res[np.isfinite(res["relative_residual"].astype(float))].reset_index(drop=True)
    from soilcal.loop.residuals import scale_of

    meas = scale_of(d)
    dt = per_test(d)  # the bias and trends are tested on one value per measured condition
    dc, within = per_condition(dt), varies_within(dt)

    def median_percent(sd, n):
        v = sd / np.sqrt(np.clip(n, 1.0, None)) / meas
        v = v[np.isfinite(v)]
        return float(np.median(v) * 100) if len(v) else float("nan")

    seed_se = median_percent(d["simulated_sd"].to_numpy(float), d["simulated_n"].to_numpy(float))
    measured_se = (median_percent(d["measured_sd"].to_numpy(float), d["measured_n"].fillna(1.0).to_numpy(float))
                   if "measured_sd" in d else float("nan"))
    rows = []
    for t in diag.itertuples():
        if t.test == "bias":
            r = dc["relative_residual"].to_numpy(float)
            n = len(r)
            if n < 3:
                continue
            scatter = float(np.std(r, ddof=1))
            shift = _smallest_shift(n - 1, float(stats.t.isf(level / 2, n - 1)), power)
            rows.append(dict(test="bias", covariate="", quantity="bias", n=n, low=np.nan, high=np.nan,
                             scatter_percent=100 * scatter, detectable_percent=100 * shift * scatter / np.sqrt(n)))
        elif t.test == "trend":
            frame = dt if f"cov:{t.covariate}" in within else dc
            col = frame.get(f"cov:{t.covariate}")
            if col is None:
                continue
            has = col.notna().to_numpy()
            x = pd.to_numeric(col[has], errors="coerce").to_numpy(float)
            r = frame["relative_residual"].to_numpy(float)[has]
            n = len(r)
            Z = np.column_stack([np.ones(n), quantity_offsets(frame, has)])  # as the trend test fits it
            k = Z.shape[1] - 1
            if n < 4 + k:
                continue
            fit = _ols(r, np.column_stack([Z, x - x.mean()]))
            scatter = float(np.sqrt(fit.ssr / (n - 2 - k)))
            sxx = float(_ols(x, Z).ssr) if k else float(np.sum((x - x.mean()) ** 2))  # x beyond the offsets
            shift = _smallest_shift(n - 2 - k, float(stats.t.isf(level / 2, n - 2 - k)), power)
            lo, hi = float(x.min()), float(x.max())
            rows.append(dict(test="trend", covariate=t.covariate, quantity=quantity_of.get(t.covariate, ""), n=n,
                             low=lo, high=hi, scatter_percent=100 * scatter,
                             detectable_percent=100 * shift * scatter / np.sqrt(sxx) * (hi - lo)))
    out = pd.DataFrame(rows, columns=[c for c in DETECTABLE_COLUMNS if c not in ("tests", "power", "seed_se_percent",
                                                                                  "measured_se_percent")])
    out["tests"] = tests
    out["power"] = power
    out["seed_se_percent"] = seed_se
    out["measured_se_percent"] = measured_se
    return out[DETECTABLE_COLUMNS]
