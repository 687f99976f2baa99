"""Measured conditions beside the calibrated simulation: the residual table.

One row per measured quantity of every condition of a soil's ``measurements`` block
(:func:`soilcal.config.measurements.conditions`), with every covariate of the row
(``cov:<column>``) and every declared quantity (``q:<quantity>``, in its SI unit), the
measured value with its standard deviation and repeat count, and the simulated mean,
standard deviation and seed count at the calibrated parameters.

Conventions:

* residual = measured - simulated (positive: the model under-predicts);
* relative residual = residual / scale, the dimensionless residual the diagnosis and the
  effect fits use, so that one table may hold forces and heights; the scale (column
  ``scale``) is the row's |measured|, except for a measured quantity of a table whose values
  change sign or come near zero (one of them below :data:`NEAR_ZERO` times their RMS: a
  vertical force about zero; an exact 0 counts), where every row of it takes the RMS of its measured values
  (said in the row's note): a ratio to a value near zero would let one row swamp the rest;
  a row whose scale is 0 has no relative residual (noted);
* residual standard error = sqrt(sd_m^2 / n_m + sd_s^2 / n_s) with the measured standard
  deviation over its repeats (``n_m`` 1 where the table gives no count: the SD is then the
  value's own uncertainty) and the seed scatter of the simulated mean; the standardised
  residual is the residual over it, empty (with a note) where neither uncertainty is known;
* residual degrees of freedom (Welch 1947; Satterthwaite 1946): both variances are
  estimated, from n_m repeats and n_s seeds, so the standardised residual follows Student's
  t rather than the unit normal, with
  nu = se^4 / ((sd_m^2/n_m)^2 / (n_m - 1) + (sd_s^2/n_s)^2 / (n_s - 1)); a term is left out
  where its SD is taken as known (a measured SD without a repeat count) or absent, and nu is
  infinite where both are.  With three repeats and three seeds nu is 2 to 4: a standardised
  residual of 3 is then as common as one of 1.6 to 2.2 under the normal law.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

# key of a simulator's answer (``simulate(cond, params, seed)``) and column of a run table
# holding why a run failed (the DEM's error), written into the residual table's note
from soilcal.loop import ERROR_KEY  # noqa: F401 (re-exported)

KEY = ["measurement", "row", "measure"]
RESIDUAL_COLUMNS = ["measurement", "row", "measure", "unit", "label", "simulation", "measured", "measured_sd",
                    "measured_n",
                    "simulated_mean", "simulated_sd", "simulated_n", "failed_runs", "residual", "scale",
                    "relative_residual", "residual_se", "residual_dof", "standardised_residual", "note"]

#: a relative residual at most this large is zero: the measured value equals the simulated mean
#: to the round-off of the arithmetic (a table of the model's own values), and the tests would
#: otherwise find "structure" in the last bits of the doubles
EXACT = 1e-9

#: a measured quantity with a value below this share of its RMS (or of both signs) is scaled by its
#: RMS: a force 50 times smaller than the rest is about zero for a DEM whose scatter is a few
#: percent of the force, while a soil-bin campaign from shallow and slow to deep and fast spans
#: a factor of 10-20 (its smallest value 0.05-0.1 of the RMS), which each row's own value scales
NEAR_ZERO = 0.02


def scales(df: pd.DataFrame) -> tuple[np.ndarray, list]:
    """Per row the scale of the relative residual (module docstring) and the measured
    quantities (measurement, measure) scaled by their RMS."""
    m = df["measured"].astype(float).to_numpy()
    scale = np.abs(m)
    by_rms = []
    for key, idx in df.groupby(["measurement", "measure"], sort=False).indices.items():
        v = m[idx]
        v = v[np.isfinite(v)]
        if not len(v):
            continue
        rms = float(np.sqrt(np.mean(v ** 2)))
        if rms > 0 and ((v < 0).any() and (v > 0).any() or np.abs(v).min() < NEAR_ZERO * rms):
            scale[idx] = rms
            by_rms.append(key)
    return np.where(scale > 0, scale, np.nan), by_rms


def simulation_key(c) -> str:
    """What a condition simulates (scenario, setup, parameters, calibrated stage and case,
    preset, the numeric quantities an effect may act through and the tool), as a short digest: two rows that
    share it are the same test measured twice, held out together by the selection's folds."""
    import hashlib
    import json

    from soilcal.config.quantities import QUANTITIES

    # every quantity but a test day's or group's label: a tool id is a different test
    physical = {q: v for q, v in (c.quantities or {}).items() if QUANTITIES.get(q) is not None or q == "tool"}
    what = [c.scenario, c.setup, c.params, c.stage, c.case, c.preset, physical]
    return hashlib.sha1(json.dumps(what, sort_keys=True, default=str).encode()).hexdigest()[:12]


def _short(reason: str, width: int = 240) -> str:
    text = " ".join(str(reason).split())
    return text if len(text) <= width else text[: width - 3] + "..."


def observations(conditions) -> pd.DataFrame:
    """The measured side: one row per condition and measured quantity with a measured value."""
    rows = []
    for c in conditions:
        sim = simulation_key(c)
        for r in c.responses:
            row = {"measurement": c.measurement, "row": int(c.row), "measure": r["measure"], "unit": r["unit"],
                   "label": c.label, "simulation": sim,
                   "measured": np.nan if r["measured"] is None else float(r["measured"]),
                   "measured_sd": np.nan if r.get("measured_sd") is None else float(r["measured_sd"]),
                   "measured_n": np.nan if r.get("n") is None else float(r["n"])}
            for col, v in (c.covariates or {}).items():
                row[f"cov:{col}"] = v
            for q, v in (c.quantities or {}).items():
                row[f"q:{q}"] = v
            rows.append(row)
    df = pd.DataFrame(rows)
    if len(df) == 0:
        return pd.DataFrame(columns=KEY + ["unit", "label", "simulation", "measured", "measured_sd", "measured_n"])
    return df


def simulated_stats(runs: pd.DataFrame) -> pd.DataFrame:
    """Mean, SD (ddof 1) and count of the ``ok`` runs' values per measured quantity, and the
    count of the other runs (``failed_runs``: failed or without a value) (``runs``:
    measurement, row, measure, value[, status])."""
    good = np.isfinite(pd.to_numeric(runs["value"], errors="coerce").to_numpy(float))
    if "status" in runs.columns:
        good &= (runs["status"].astype(str) == "ok").to_numpy()
    g = runs[good].groupby(KEY)["value"]
    out = pd.DataFrame({"simulated_mean": g.mean(), "simulated_sd": g.std(ddof=1), "simulated_n": g.count()})
    failed = runs[~good].groupby(KEY).size().rename("failed_runs")
    out = out.join(failed, how="outer")
    out["failed_runs"] = out["failed_runs"].fillna(0).astype(int)
    if ERROR_KEY in runs.columns:  # the first reason given for each quantity's failed runs
        why = runs[~good & runs[ERROR_KEY].fillna("").astype(str).str.strip().ne("").to_numpy()]
        out = out.join(why.groupby(KEY)[ERROR_KEY].first().rename("failed_reason"), how="left")
    return out.reset_index()


def residual_frame(obs: pd.DataFrame, runs: pd.DataFrame) -> pd.DataFrame:
    """The residual table (module docstring) from :func:`observations` and the runs at the
    calibrated parameters."""
    if len(runs):
        sim = simulated_stats(runs)
    else:
        sim = pd.DataFrame({"measurement": pd.Series(dtype=object), "row": pd.Series(dtype=int),
                            "measure": pd.Series(dtype=object), "simulated_mean": pd.Series(dtype=float),
                            "simulated_sd": pd.Series(dtype=float), "simulated_n": pd.Series(dtype=float),
                            "failed_runs": pd.Series(dtype=int)})
    df = obs.merge(sim, on=KEY, how="left")
    if "simulation" not in df:  # a measured side built without conditions: each row its own test
        df["simulation"] = df["measurement"].astype(str) + "/" + df["row"].astype(str)
    for c in ("simulated_mean", "simulated_sd"):
        df[c] = df[c].astype(float)
    df["simulated_n"] = df["simulated_n"].fillna(0).astype(int)
    df["failed_runs"] = df["failed_runs"].fillna(0).astype(int)
    m, s = df["measured"].astype(float), df["simulated_mean"].astype(float)
    df["residual"] = m - s
    scale, by_rms = scales(df)
    df["scale"] = scale
    df["relative_residual"] = (m - s) / df["scale"]
    nm = df["measured_n"].fillna(1.0).clip(lower=1.0)
    var_m = (df["measured_sd"] ** 2 / nm).fillna(0.0)
    var_s = (df["simulated_sd"] ** 2 / df["simulated_n"].clip(lower=1)).fillna(0.0)
    se = np.sqrt(var_m + var_s)
    df["residual_se"] = np.where(se > 0, se, np.nan)
    n_m, n_s = df["measured_n"].astype(float).to_numpy(), df["simulated_n"].astype(float).to_numpy()
    ref_m, ref_s = reference_variances(df)
    df["residual_dof"] = satterthwaite(ref_m, n_m - 1.0, ref_s, n_s - 1.0)
    df["standardised_residual"] = df["residual"] / df["residual_se"]
    notes = []
    rms_scaled = set(by_rms)
    for r in df.itertuples():
        n = []
        if not np.isfinite(r.measured):
            n.append("no measured value")
        elif not np.isfinite(r.scale):
            n.append("measured value 0: no relative residual")
        elif (r.measurement, r.measure) in rms_scaled:
            n.append(f"relative to the RMS {r.scale:.4g} of {r.measure} (values near zero or of both signs)")
        if r.failed_runs:
            why = getattr(r, "failed_reason", None)
            n.append(f"{r.failed_runs} run{'s' if r.failed_runs > 1 else ''} failed"
                     + (f" ({_short(why)})" if isinstance(why, str) and why else ""))
        if r.simulated_n == 0:
            n.append("no simulated value")
        if not np.isfinite(r.residual_se):
            n.append("no uncertainty known (no measured SD, one seed)")
        elif not np.isfinite(r.measured_sd):
            n.append("seed scatter only (no measured SD)")
        notes.append("; ".join(n))
    df["note"] = notes
    df = df.drop(columns=["failed_reason"], errors="ignore")
    extra = [c for c in df.columns if c.startswith(("cov:", "q:"))]
    return df[RESIDUAL_COLUMNS[:5] + extra + RESIDUAL_COLUMNS[5:]]


def satterthwaite(var_a, dof_a, var_b, dof_b) -> np.ndarray:
    """Welch-Satterthwaite degrees of freedom of a sum of two variances on ``dof_a`` and
    ``dof_b`` degrees of freedom, (a + b)^2 / (a^2 / dof_a + b^2 / dof_b); a part with no
    degrees of freedom of its own (dof <= 0 or infinite: known, or absent with variance 0)
    adds nothing below the line; infinite where neither part is estimated."""
    a, b = np.asarray(var_a, float), np.asarray(var_b, float)
    da, db = np.asarray(dof_a, float), np.asarray(dof_b, float)
    a, b = np.where(np.isfinite(a), a, 0.0), np.where(np.isfinite(b), b, 0.0)
    ta = np.where(np.isfinite(da) & (da > 0), a ** 2 / np.where(da > 0, da, 1.0), 0.0)
    tb = np.where(np.isfinite(db) & (db > 0), b ** 2 / np.where(db > 0, db, 1.0), 0.0)
    den = ta + tb
    return np.where(den > 0, (a + b) ** 2 / np.where(den > 0, den, 1.0), np.inf)


def welch_anova_p(m, sd, n) -> float:
    """Welch's heteroscedastic one-way ANOVA of group means ``m`` with sample SDs ``sd`` from
    ``n`` > 1 values each (Welch 1951, Biometrika 38: 330): weights w = n / sd^2, the weighted
    mean's scatter sum(w (m - mean)^2) / (k - 1) over 1 + 2 (k - 2) / (k^2 - 1) h, with
    h = sum((1 - w / sum(w))^2 / (n - 1)), read as F on k - 1 and (k^2 - 1) / (3 h) degrees of
    freedom; its upper tail.  It holds its level where the groups' true SDs differ (a noisier
    day with fewer repeats), which a pooled SD does not; for k = 2 it is Welch's t-test."""
    from scipy import stats

    m, sd, n = (np.asarray(x, float) for x in (m, sd, n))
    k = len(m)
    w = n / sd ** 2
    big = float(np.sum(w))
    mean = float(np.sum(w * m)) / big
    h = float(np.sum((1.0 - w / big) ** 2 / (n - 1.0)))
    a = float(np.sum(w * (m - mean) ** 2)) / (k - 1)
    b = 1.0 + 2.0 * (k - 2) / (k * k - 1.0) * h
    return float(stats.f.sf(a / b, k - 1, (k * k - 1.0) / (3.0 * h)))


def replicate_scatter_chi(m, ref_m, pooled_dof, sd=None, n=None) -> float:
    """The chi-square of replicate rows' values ``m`` about their weighted mean, each weighted by
    1 / its reference variance ``ref_m``; where that variance is a measured SD pooled over the
    quantity's rows on ``pooled_dof`` degrees of freedom (finite, > 0), the scatter is read as
    F on them and given as the chi-square of the same tail on len(m) - 1 degrees of freedom:
    against each row's own SD of a few repeats it is a sum of t^2, not chi-square.  Where the
    quantity's SDs are not pooled (``pooled_dof`` 0: not proportional to the value) and every
    row gives its SD ``sd`` from ``n`` > 1 repeats, the rows are compared by Welch's
    heteroscedastic ANOVA (:func:`welch_anova_p`, each row its own true SD: a replicate day may
    be noisier than another) and its tail given as the chi-square of the same tail.  Null
    conditions of 3 rows of 10 repeats, the third of 3 repeats at 3 times the SD: an SD pooled
    over the condition's rows put 25 % at p < 0.05, Welch 7.6-7.9 % (4.5 % at equal SDs).
    Welch's F approximation is not exact for so few repeats: rows of 10, 10 and 2 repeats, SDs
    1, 1 and 3, 12.6-12.9 %; six equal-SD rows of 3 repeats 7.0-7.8 % (a pooled SD is exact
    there), of 5, 6.0 %; two or three rows of 2 or 3 repeats at equal SDs 2.6-3.7 %."""
    from scipy import stats

    m, wr = np.asarray(m, float), 1.0 / np.asarray(ref_m, float)
    if not (np.isfinite(pooled_dof) and pooled_dof > 0) and sd is not None and n is not None and len(m) > 1:
        sd, n = np.asarray(sd, float), np.asarray(n, float)
        if np.all(np.isfinite(sd) & (sd > 0) & np.isfinite(n) & (n > 1)) and np.all(np.isfinite(m)):
            tail = welch_anova_p(m, sd, n)
            return float(stats.chi2.isf(max(tail, 1e-300), len(m) - 1))
    chi = float(np.sum(wr * (m - np.sum(wr * m) / np.sum(wr)) ** 2))
    if len(m) > 1 and np.isfinite(pooled_dof) and pooled_dof > 0:
        tail = stats.f.sf(chi / (len(m) - 1), len(m) - 1, pooled_dof)
        chi = float(stats.chi2.isf(max(tail, 1e-300), len(m) - 1))
    return chi


#: the separator of a quantity's key (measurement, measure): a control character no name holds,
#: and not NUL, at which pandas' grouping and factorize stop reading a string key (pandas 3.0.6:
#: "m\x00F_h" and "m\x00F_v" fall into one group)
KEY_SEP = "\x1f"
HOMOGENEITY_ALPHA = 0.05  # Bartlett's test of a quantity's relative variances: below it, not pooled


def bartlett_p(var, dof) -> float:
    """Bartlett's test of equal variances from the estimates ``var`` on ``dof`` degrees of
    freedom each (the summary-statistic form of :func:`scipy.stats.bartlett`): its p value; 1
    for fewer than two estimates."""
    from scipy import stats

    v, d = np.asarray(var, float), np.asarray(dof, float)
    if len(v) < 2:
        return 1.0
    if np.any(v <= 0):
        return 0.0 if np.any(v > 0) else 1.0
    big = float(np.sum(d))
    sp = float(np.sum(d * v)) / big
    m = big * np.log(sp) - float(np.sum(d * np.log(v)))
    c = 1.0 + (float(np.sum(1.0 / d)) - 1.0 / big) / (3.0 * (len(v) - 1))
    return float(stats.chi2.sf(m / c, len(v) - 1))


def pooled_relative_variance(sd, n, scale, group, homogeneity: bool = True, dof: bool = False):
    """Per row, the squared SD over ``scale`` pooled over the rows of its ``group`` (a measured
    quantity) that estimate it (n > 1 values behind it, the SD finite): sum((n - 1) (sd /
    scale)^2) / sum(n - 1); NaN where its group has none, or where Bartlett's test
    (:func:`bartlett_p`) rejects that the group's relative variances are one at
    :data:`HOMOGENEITY_ALPHA`: an SD that is not proportional to the value (an absolute noise
    floor, one row far noisier than the others, a quantity scaled by its RMS) is not pooled and
    each row keeps its own.  ``homogeneity=False`` skips that test: the pooled value is then
    the group's typical relative variance whatever its rows' spread (the weights of
    :func:`relative_variances`).  Rows repeating one estimate (the replicate rows of one
    simulation) are to be passed once.  With ``dof``, also per row the pooled value's degrees
    of freedom, sum(n - 1) over the rows it pools (0 where it is NaN)."""
    sd, n, scale = (np.asarray(x, float) for x in (sd, n, scale))
    rel = (sd / scale) ** 2
    ok = np.isfinite(rel) & np.isfinite(n) & (n > 1)
    num, den = np.where(ok, (n - 1) * rel, 0.0), np.where(ok, n - 1, 0.0)
    names = np.asarray(group).astype(str)
    if len(set(names.tolist())) == len(names):  # every row its own group: nothing to pool or test
        out = np.where(den > 0, num / np.where(den > 0, den, 1.0), np.nan)
    else:
        g = pd.Series(names)
        num = pd.Series(num).groupby(g).transform("sum").to_numpy(float)
        den = pd.Series(den).groupby(g).transform("sum").to_numpy(float)
        out = np.where(den > 0, num / np.where(den > 0, den, 1.0), np.nan)
        if homogeneity:
            for _, at in pd.Series(np.arange(len(g))).groupby(g):
                at = at.to_numpy()
                at = at[ok[at]]
                if len(at) > 1 and bartlett_p(rel[at], n[at] - 1.0) < HOMOGENEITY_ALPHA:
                    out[names == g.iloc[at[0]]] = np.nan
    if dof:
        return out, np.where(np.isfinite(out), den, 0.0)
    return out


def pooled_measured_dof(df: pd.DataFrame, known: np.ndarray) -> np.ndarray:
    """Per row, the degrees of freedom of its quantity's measured SD pooled over the ``known``
    rows (:func:`pooled_relative_variance`: the n - 1 of the rows it pools, a row entered twice
    once, :func:`first_entries`), 0 where the quantity's measured SDs are not pooled."""
    if "measured_sd" not in df or not len(df):
        return np.zeros(len(df))
    c = _columns(df)
    enter = np.asarray(known, bool) & first_entries(df)
    return pooled_relative_variance(np.where(enter, c["sd_m"], np.nan), c["nm"], c["scale"], c["meas"], dof=True)[1]


#: the estimates a part of a row's variance can take (:func:`variance_sources`)
OWN, REPLICATE, POOLED, POOLED_REPLICATE = "own", "replicate", "pooled", "pooled replicate"
#: the rules of :func:`variance_sources`: which estimates a part takes, the first a row has
PREFER = {"own": (OWN, REPLICATE, POOLED, POOLED_REPLICATE),  # the noise floor (:func:`noise_floor`)
          "pooled": (POOLED, OWN),  # the weights (:func:`relative_variances`)
          "pooled estimates": (POOLED, OWN)}  # the residual's degrees of freedom (:func:`reference_variances`)


def _columns(df: pd.DataFrame) -> dict:
    """The columns the rows' variances come from, as arrays over the rows of ``df``: a column
    the table lacks is unknown (NaN); a missing repeat count is one repeat (``nm``, the count as
    given in ``n_given``), a missing seed count no seed; the quantity's key ``meas`` and the
    simulation ``sims`` (each row its own where the table has no ``simulation`` column)."""
    n = len(df)

    def col(name):
        return df[name].astype(float).to_numpy() if name in df else np.full(n, np.nan)

    n_given, ns = col("measured_n"), col("simulated_n")
    return dict(measured=col("measured"), sd_m=col("measured_sd"), n_given=n_given,
                nm=np.clip(np.where(np.isnan(n_given), 1.0, n_given), 1.0, None), sd_s=col("simulated_sd"),
                ns=np.where(np.isnan(ns), 0.0, ns), scale=np.asarray(scale_of(df), float),
                meas=(df["measurement"].astype(str) + KEY_SEP + df["measure"].astype(str)).to_numpy(),
                sims=df["simulation"].astype(str).to_numpy() if "simulation" in df else np.arange(n).astype(str))


def first_entries(df: pd.DataFrame, across_tables: bool = False) -> np.ndarray:
    """Per row, False where it repeats an earlier row of ``df`` (a table row entered twice): the
    same table, simulation, quantity, covariate values, measured value, SD and repeat count;
    with ``across_tables`` in any table (a row copied into a second table).  A copy of a row
    with a measured SD tells nothing new: it counts once in every pooled SD
    (:func:`variance_sources`: the residual's degrees of freedom, the weights and the noise
    floor alike; the SDs are pooled per table, so a copy in another table is that table's own
    entry) and, in any table, in the test of a uniform bias
    (:func:`soilcal.loop.core.scatter_about_scale`).  Rows without an SD are single repeats,
    and two repeats may read alike: the replicate scatter counts each.  Every row is its own
    entry where the table has no ``simulation`` column (each row its own simulation)."""
    return entry_of(df, across_tables) == np.arange(len(df))


def entry_of(df: pd.DataFrame, across_tables: bool = False) -> np.ndarray:
    """Per row of ``df``, the position of its first entry (:func:`first_entries`): its own
    position, or that of the earlier row it repeats."""
    if "simulation" not in df or not len(df):
        return np.arange(len(df))
    cols = [c for c in ("simulation", "measurement", "measure", "measured", "measured_sd", "measured_n",
                        *sorted(c for c in df.columns if str(c).startswith("cov:")))
            if c in df and not (across_tables and c == "measurement")]
    keys = pd.Series(list(map(tuple, df[cols].astype(str).to_numpy())))
    return keys.map({k: i for i, k in reversed(list(enumerate(keys)))}).to_numpy(int)


def variance_sources(df: pd.DataFrame, prefer: str, homogeneity: bool = True, replicates: bool = False) -> dict:
    """Which estimate each row's measured part (sd_m^2 / n_m) and seed part (sd_s^2 / n_s) of
    its variance takes: the one rule set of :func:`reference_variances`,
    :func:`relative_variances` and the noise floor (:func:`noise_floor`), each a choice of the
    arguments.  The estimates, each a variance per repeat (or seed) relative to the row's scale
    squared:

    * own: the row's own SD (a measured SD without a repeat count is the value's own
      uncertainty, taken as known, n_m 1; a seed SD needs two seeds); an *estimate* where
      n > 1;
    * replicate (measured part, with ``replicates``): where a condition's repeats are rows of
      their own without an SD, the scatter of their values, each the mean of its n_m repeats
      (one where no count is given), which estimates sigma^2 mean(1 / n_m) of the per-repeat
      variance sigma^2: var(values) / mean(1 / n_m) on rows - 1 degrees of freedom;
    * pooled: (sd / scale)^2 pooled over the rows of the measured quantity
      (:func:`pooled_relative_variance`, with Bartlett's homogeneity test where
      ``homogeneity``): the seed SDs once per simulation (its replicate rows repeat one
      estimate), the measured SDs once per table row, a row entered twice once
      (:func:`first_entries`);
    * pooled replicate (with ``replicates``): the replicate scatters pooled over the
      quantity's conditions, each over its mean scale.

    ``prefer`` (:data:`PREFER`): ``"own"`` takes the first of own, replicate, pooled and pooled
    replicate a row has; ``"pooled"`` the pooled value where there is one, else own;
    ``"pooled estimates"`` the pooled value only where the row's own part is an estimate, else
    own.

    Returns the columns read (:func:`_columns`) and per part (suffix ``_m``, ``_s``): ``take``
    (per row the estimate's name, "" where it has none), ``estimate``, ``pooled`` with its
    ``pooled_dof`` (0 where NaN) and, with ``replicates``, ``replicate`` (per row the
    per-repeat variance in the values' unit), ``replicate_key``, ``replicate_dof``,
    ``pooled_replicate`` and ``pooled_replicate_dof`` (measured part)."""
    c = _columns(df)
    n = len(df)
    m, sd_m, nm, sd_s, ns, scale, meas, sims = (c[k] for k in ("measured", "sd_m", "nm", "sd_s", "ns", "scale",
                                                                "meas", "sims"))
    own_m, own_s = np.isfinite(sd_m), np.isfinite(sd_s) & (ns >= 2)
    entry = first_entries(df)
    enter_m = own_m & entry
    first = ~pd.DataFrame({"s": sims, "m": meas}).duplicated().to_numpy()
    pool_m, pool_dof_m = pooled_relative_variance(np.where(enter_m, sd_m, np.nan), nm, scale, meas, homogeneity,
                                                  dof=True)
    pool_s, pool_dof_s = pooled_relative_variance(np.where(first & own_s, sd_s, np.nan), ns, scale, meas, homogeneity,
                                                  dof=True)
    out = dict(c, estimate_m=own_m & (nm > 1), estimate_s=own_s, pooled_m=pool_m, pooled_dof_m=pool_dof_m,
               pooled_s=pool_s, pooled_dof_s=pool_dof_s)
    has_m = {OWN: own_m, POOLED: np.isfinite(pool_m)}
    has_s = {OWN: own_s, POOLED: np.isfinite(pool_s)}
    if prefer == "pooled estimates":
        has_m[POOLED] = has_m[POOLED] & out["estimate_m"]
        has_s[POOLED] = has_s[POOLED] & out["estimate_s"]
    if replicates:
        out.update(_replicate_scatter(m, ~np.isfinite(sd_m), nm, scale, meas, sims, homogeneity))
        has_m[REPLICATE] = np.isfinite(out["replicate"])
        has_m[POOLED_REPLICATE] = np.isfinite(out["pooled_replicate"])
    take_m, take_s = np.full(n, "", dtype=object), np.full(n, "", dtype=object)
    for name in PREFER[prefer]:
        if name in has_m:
            take_m[(take_m == "") & has_m[name]] = name
        if name in has_s:
            take_s[(take_s == "") & has_s[name]] = name
    out.update(take_m=take_m, take_s=take_s)
    return out


def _replicate_scatter(m, loose, nm, scale, meas, sims, homogeneity: bool) -> dict:
    """The replicate estimates of :func:`variance_sources`: per row among the ``loose`` rows (no
    measured SD, a measured value) of a condition (simulation and quantity) with two such rows
    at least whose values differ (repeats rounded alike state no scatter), the per-repeat
    variance var(values) / mean(1 / n_m) in the values' unit, its key and degrees of freedom;
    and per row, those variances relative to their condition's mean scale squared pooled over
    the quantity's conditions, with their degrees of freedom."""
    n = len(m)
    rep, rep_dof = np.full(n, np.nan), np.zeros(n)
    rep_key = np.array([""] * n, dtype=object)
    rep_sd, rep_n, rep_scale, rep_q = [], [], [], []
    loose = loose & np.isfinite(m)
    if loose.any():
        key = pd.Series(sims + KEY_SEP + meas)[loose]
        for k, at in key.groupby(key.to_numpy(), sort=False):
            at = at.index.to_numpy()
            if len(at) < 2 or not np.ptp(m[at]) > 0:  # one value, or repeats rounded alike: no scatter
                continue
            per_repeat = float(np.var(m[at], ddof=1)) / float(np.mean(1.0 / nm[at]))
            rep[at], rep_key[at], rep_dof[at] = per_repeat, k, len(at) - 1.0
            rep_sd.append(np.sqrt(per_repeat)), rep_n.append(len(at)), rep_q.append(meas[at[0]])
            rep_scale.append(float(np.mean(scale[at])))
    pooled, pooled_dof = np.full(n, np.nan), np.zeros(n)
    if rep_sd:
        v, d = pooled_relative_variance(np.asarray(rep_sd), np.asarray(rep_n, float), np.asarray(rep_scale),
                                        np.asarray(rep_q), homogeneity, dof=True)
        by_q = {q: (vq, dq) for q, vq, dq in zip(rep_q, v, d) if np.isfinite(vq)}
        for i, q in enumerate(meas):
            if q in by_q:
                pooled[i], pooled_dof[i] = by_q[q]
    return dict(replicate=rep, replicate_key=rep_key, replicate_dof=rep_dof, pooled_replicate=pooled,
                pooled_replicate_dof=pooled_dof)


def reference_variances(df: pd.DataFrame, flags: bool = False) -> tuple[np.ndarray, ...]:
    """The measured and seed variances of the rows' means that their residual degrees of
    freedom are computed from: where a part is estimated (n > 1 repeats or seeds), its squared
    SD relative to the row's scale pooled over the measured quantity's rows, with Bartlett's
    test (:func:`variance_sources`, ``"pooled estimates"``), times the row's scale squared over
    n (a measured quantity of a measurement table: one rig, one simulated scenario); else the
    row's own variance (a measured SD without a repeat count is taken as known), 0 where it has
    none.  Welch-Satterthwaite's degrees of freedom computed from the row's own estimated
    variances grow where those few repeats or seeds happen to scatter little, exactly where
    the standardised residual is large (1 % measured noise over 10 repeats, 5 % seed scatter
    over 3 seeds: 7.9 % of the rows beyond the 5 % two-sided point, mean square 1.23).  With
    ``flags``, also per row whether each estimated part is pooled (else the row's own)."""
    t = variance_sources(df, "pooled estimates")
    nm, ns, sd_m, sd_s, scale = t["nm"], t["ns"], t["sd_m"], t["sd_s"], t["scale"]
    # the pooled relative variance back in the row's unit, where the row's scale gives it one
    pooled_m = (t["take_m"] == POOLED) & np.isfinite(t["pooled_m"] * scale)
    pooled_s = (t["take_s"] == POOLED) & np.isfinite(t["pooled_s"] * scale)
    own_m = np.where(np.isfinite(sd_m), sd_m ** 2 / nm, 0.0)
    own_s = np.where(np.isfinite(sd_s) & (ns >= 1), sd_s ** 2 / np.clip(ns, 1.0, None), 0.0)
    ref_m = np.where(pooled_m, t["pooled_m"] * scale ** 2 / nm, own_m)
    ref_s = np.where(pooled_s, t["pooled_s"] * scale ** 2 / np.clip(ns, 1.0, None), own_s)
    if flags:
        return ref_m, ref_s, ~t["estimate_m"] | pooled_m, ~t["estimate_s"] | pooled_s
    return ref_m, ref_s


def relative_variances(df: pd.DataFrame, parts: bool = False):
    """Per row, the variance of its relative residual from the measured and the seed scatter,
    (sd_m^2 / n_m + sd_s^2 / n_s) / scale^2 (module docstring): the weights of the quantities
    of one measured test (:func:`soilcal.loop.diagnose.per_test`), which are to be one per
    quantity, not the noise of each row's SD.  Each part's relative variance (sd / scale)^2 is
    the one pooled over the rows of its measured quantity wherever there is one, else the
    row's own (:func:`variance_sources`, ``"pooled"``: without Bartlett's test, a row entered
    twice counted once), divided by the row's own repeat count n_m or seed count n_s.  From
    three repeats or three seeds an SD squared is a variance on 2 degrees of freedom, a third
    of such estimates off by a factor of 3 or more either way (chi-square on 2: e^-3 + 1 -
    e^(-1/3) = 0.33); pooled over the 18 rows of a quantity, on 36.  The pooled value stands
    where the row's own SD is missing too (one seed behind the simulated mean).  A part with
    neither is left out, as the residual's standard error leaves it out (no measured SD: the
    seed scatter alone).  NaN where neither part is known (no measured SD and one seed) or the
    variance is 0, and for a table without the columns.  With ``parts`` also, per row, which
    parts the variance holds (1 the measured, 2 the seed, 3 both, 0 none): variances of
    different parts are not to be weighed against each other (the seed scatter alone
    understates a row's variance).

    Without Bartlett's test the pool is the mean of (sd / scale)^2 over the quantity's rows
    whatever their spread: for a quantity scaled by its RMS, or with an absolute noise floor,
    its rows near zero have the largest (sd / scale)^2 and dominate it, so the quantity's
    weight is too small; that costs the combined value precision, not its expectation (the
    weights do not depend on the residuals).  The weights use each row's n, so where repeat or
    seed counts (or failed runs) follow a covariate, the weights differ between tests and the
    quantities' different offsets can look like structure in it; constant n per quantity (the
    usual table) gives constant weights."""
    n = len(df)
    if not n or not {"measurement", "measure"} <= set(df.columns) or not {"scale", "measured"} & set(df.columns):
        return (np.full(n, np.nan), np.zeros(n, int)) if parts else np.full(n, np.nan)
    t = variance_sources(df, "pooled", homogeneity=False)
    nm, ns, sd_m, sd_s, scale = t["nm"], t["ns"], t["sd_m"], t["sd_s"], t["scale"]
    # the pooled value, else the row's own (NaN where it has no SD); no seed part without a seed
    part_m = np.where(t["take_m"] == POOLED, t["pooled_m"], (sd_m / scale) ** 2) / nm
    part_s = np.where(ns >= 1, np.where(t["take_s"] == POOLED, t["pooled_s"], (sd_s / scale) ** 2)
                      / np.clip(ns, 1.0, None), np.nan)
    known = np.isfinite(part_m) | np.isfinite(part_s)
    var = np.where(np.isfinite(part_m), part_m, 0.0) + np.where(np.isfinite(part_s), part_s, 0.0)
    var = np.where(known & (var > 0), var, np.nan)
    if parts:
        return var, np.isfinite(part_m).astype(int) + 2 * np.isfinite(part_s).astype(int)
    return var


def scale_of(df: pd.DataFrame) -> np.ndarray:
    """The relative residual's denominators of the rows (:func:`scales`, the ``scale`` column;
    |measured| for a table written before the column existed)."""
    return df["scale"].to_numpy(float) if "scale" in df else np.abs(df["measured"].to_numpy(float))


def usable(res: pd.DataFrame) -> pd.DataFrame:
    """Rows with a measured and a simulated value (those the loop can learn from)."""
    return res[np.isfinite(res["relative_residual"].astype(float))].reset_index(drop=True)


def _floor_terms(df: pd.DataFrame) -> dict:
    """Per row of ``df`` the measured and seed variances of the noise floor (:func:`noise_floor`;
    :func:`variance_sources`, ``"own"`` with the replicate scatter) relative to the row's scale
    squared (NaN where unknown), whether each is the row's own, and which estimate each comes
    from with its degrees of freedom (rows whose parts share one estimate, a pooled SD or one
    simulation's seeds, share its sampling error)."""
    t = variance_sources(df, "own", replicates=True)
    nm, ns, sd_m, sd_s, scale = t["nm"], t["ns"], t["sd_m"], t["sd_s"], t["scale"]
    meas, sims, n_given, take_m, take_s = t["meas"], t["sims"], t["n_given"], t["take_m"], t["take_s"]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        rel_m = np.select([take_m == OWN, take_m == REPLICATE, take_m == POOLED, take_m == POOLED_REPLICATE],
                          [sd_m ** 2 / nm / scale ** 2, t["replicate"] / nm / scale ** 2, t["pooled_m"] / nm,
                           t["pooled_replicate"] / nm], np.nan)
        rel_s = np.select([take_s == OWN, take_s == POOLED],
                          [sd_s ** 2 / np.clip(ns, 1.0, None) / scale ** 2, t["pooled_s"] / np.clip(ns, 1.0, None)],
                          np.nan)
    n_rows = len(df)
    src_m, src_s = np.array([""] * n_rows, dtype=object), np.array([""] * n_rows, dtype=object)
    dof = {}
    # a row entered twice, or copied into a second table, repeats one estimate: its copies
    # share its sampling error; a simulation's seeds are one estimate per measured quantity in
    # whichever table reads them (the runs are shared, one per simulation and seed)
    entry = entry_of(df, across_tables=True)
    measure = df["measure"].astype(str).to_numpy() if "measure" in df else np.full(n_rows, "")
    for i in range(n_rows):
        # an SD without a repeat count is the value's own uncertainty, taken as known
        src, d = {OWN: (f"m{entry[i]}", n_given[i] - 1.0 if np.isfinite(n_given[i]) and n_given[i] > 1 else np.inf),
                  REPLICATE: (f"r{t['replicate_key'][i]}", t["replicate_dof"][i]),
                  POOLED: (f"pm{meas[i]}", t["pooled_dof_m"][i]),
                  POOLED_REPLICATE: (f"pr{meas[i]}", t["pooled_replicate_dof"][i])}.get(take_m[i], ("", None))
        if src:
            src_m[i], dof[src] = src, d
        src, d = {OWN: (f"s{sims[i]}{KEY_SEP}{measure[i]}", ns[i] - 1.0),
                  POOLED: (f"ps{meas[i]}", t["pooled_dof_s"][i])}.get(take_s[i], ("", None))
        if src:
            src_s[i], dof[src] = src, d
    return dict(rel_m=rel_m, rel_s=rel_s, own_m=np.isfinite(sd_m), own_s=np.isfinite(sd_s) & (ns >= 2), src_m=src_m,
                src_s=src_s, dof=dof)


def floor_variances(df: pd.DataFrame) -> np.ndarray:
    """Per row of ``df`` its share of the noise floor's square (:func:`noise_floor`): (sd_m^2 /
    n_m + sd_s^2 / n_s) / scale^2 with the same variances the floor takes (NaN where a part is
    unknown); the floor is sqrt of their mean."""
    t = _floor_terms(df)
    return t["rel_m"] + t["rel_s"]


def _picked(df: pd.DataFrame, rows) -> np.ndarray:
    return np.ones(len(df), bool) if rows is None else np.asarray(rows, bool)


def noise_floor(df: pd.DataFrame, rows=None) -> tuple[float, str]:
    """The RMS relative error a model without any misfit would show on the rows ``rows`` (a
    boolean mask over the usable rows ``df``; all of them by default): sqrt(mean over those rows
    of (sd_m^2 / n_m + sd_s^2 / n_s) / scale^2), the expected square of each row's relative
    residual where the measured value and the simulated mean differ by their own errors alone,
    with the row's relative scale (:func:`scales`, the ``scale`` column) and its measured SD over
    its repeats (``n_m`` 1 where the table gives no count, as in the residual's standard error)
    and its seed SD over its seeds.  Where a row's own SD is missing, its variance comes from
    the rows that estimate one (:func:`variance_sources`, ``"own"``): for the measured part, the
    scatter of the replicate rows of its condition where the table gives its repeats as rows
    without an SD, else the measured SD pooled over its quantity's rows (none where Bartlett's
    test rejects that they share one), else the replicate scatter pooled over the quantity's
    conditions; for the seed part (one seed), the seed SD pooled over the quantity's
    simulations.  Every one of these is a variance per repeat, divided by the row's own ``n_m``:
    a row that gives a count of 4 without an SD is the mean of 4 repeats whichever rows its
    variance comes from.  The pooling runs over every row of ``df``; the mean over ``rows``.
    Returns (the floor as a fraction, a note): NaN (not 0) with the reason where some row's
    uncertainty is unknown, or no row is given; else the note says how many rows took a pooled
    or replicate variance ("" where every row had its own)."""
    pick = _picked(df, rows)
    if len(df) == 0 or not pick.any():
        return float("nan"), "no row with a measured and a simulated value"
    return _floor(_floor_terms(df), pick)


def _floor(t: dict, pick) -> tuple[float, str]:
    """:func:`noise_floor` from the rows' terms ``t`` (:func:`_floor_terms`) and the mask ``pick``."""
    pm, ps = pick & ~np.isfinite(t["rel_m"]), pick & ~np.isfinite(t["rel_s"])
    total = int(pick.sum())
    if pm.any() or ps.any():
        why = []
        if pm.any():
            why.append(f"{int(pm.sum())} of the {total} rows have no measured SD and their measured quantity none to "
                       "take one from (an `sd` column with `n`, or each condition's repeats as rows of their own)")
        if ps.any():
            why.append(f"{int(ps.sum())} of the {total} rows have one seed and their measured quantity no seed SD to "
                       "take one from (two seeds per condition at least)")
        return float("nan"), "; ".join(why)
    floor = float(np.sqrt(np.mean((t["rel_m"] + t["rel_s"])[pick])))
    took_m, took_s = int((pick & ~t["own_m"]).sum()), int((pick & ~t["own_s"]).sum())
    note = []
    if took_m:
        note.append(f"{took_m} of the {total} rows without a measured SD of their own took their condition's "
                    "replicate scatter or their quantity's pooled SD")
    if took_s:
        note.append(f"{took_s} of the {total} rows with one seed took their quantity's pooled seed SD")
    return floor, "; ".join(note)


def floor_interval(df: pd.DataFrame, rows=None, level: float = 0.95) -> tuple[float, float, float]:
    """The ``level`` interval of the noise floor (:func:`noise_floor`), which is itself estimated
    from the rows' SDs, and its degrees of freedom: floor^2 is a sum of variance estimates, each
    a scaled chi-square on its own degrees of freedom (a measured SD on n_m - 1, a condition's
    seeds on n_s - 1, shared by the rows of one simulation, a pooled SD on the sum of its rows';
    an SD given without a repeat count is taken as known), read after Satterthwaite (1946) as
    floor^2 chi-square(nu) / nu with nu = (sum sigma^2)^2 / sum(sigma^4 / d) over the estimates'
    true shares sigma^2 of floor^2 and their degrees of freedom d.  The shares are known only as
    their estimates T, and T^2 overstates sigma^4 by (d + 2) / d (twice for d = 2, which halved nu
    and covered the true floor in 99 % of tables): sigma^4 / d is estimated by T^2 / (d + 2) and
    (sum sigma^2)^2 by (sum T)^2 - 2 sum T^2 / (d + 2).  Where floor^2 is one estimate on d
    degrees of freedom this gives nu = d exactly, the exact chi-square interval (the
    uncorrected (sum T)^2 gives d + 2: at d = 2 it covers 82.4 %).  On 4000 seeded tables of
    6-40 rows with SDs from 2-5 repeats and 3 seeds the 95 % interval covered the true floor in
    93.5-94.9 %.  (lo, hi, nu); NaN where the floor is unknown; a floor of known SDs alone (nu
    infinite) is its own interval.  NaN too where an SD the floor takes as estimated is exactly
    0 (seeds or repeats that gave one value, or values rounded alike): a chi-square estimate of
    0 would give its share, and with no other estimate the floor, an interval of zero width, as
    if it were known, while the true variance behind it may be anything below the resolution of
    the values; its width is unknown, and the report says so.  A pooled estimate and the rows'
    own SDs it pools are counted as independent, which overstates nu a little where some rows
    take it.  A row entered twice or copied into a second table (:func:`first_entries`) repeats
    its SDs: its copies share one estimate, as the rows of one simulation share its seeds'.
    With three repeats and three seeds per row each SD has 2 degrees of freedom: on 18 rows of
    equal shares nu is about 72, and the interval runs from 0.86 to 1.19 times the floor."""
    return noise_floor_and_interval(df, rows, level)[2]


def noise_floor_and_interval(df: pd.DataFrame, rows=None, level: float = 0.95) -> tuple:
    """(floor, note, (lo, hi, nu)): :func:`noise_floor` and :func:`floor_interval` from one pass
    over the rows' terms."""
    pick = _picked(df, rows)
    if len(df) == 0 or not pick.any():
        return float("nan"), "no row with a measured and a simulated value", (float("nan"),) * 3
    t = _floor_terms(df)
    floor, note = _floor(t, pick)
    return floor, note, _interval(t, pick, floor, level)


def _interval(t: dict, pick, floor: float, level: float) -> tuple[float, float, float]:
    """:func:`floor_interval` from the rows' terms ``t``, the mask ``pick`` and the floor."""
    from scipy import stats

    if not np.isfinite(floor):
        return float("nan"), float("nan"), float("nan")
    share = {}
    for rel, src in ((t["rel_m"], t["src_m"]), (t["rel_s"], t["src_s"])):
        for v, s in zip(rel[pick], src[pick]):
            share[s] = share.get(s, 0.0) + float(v) / int(pick.sum())
    estimated = {s: v for s, v in share.items() if np.isfinite(t["dof"][s]) and t["dof"][s] > 0}
    if any(v == 0 for v in estimated.values()):  # an SD estimated as 0: its own scatter is unknown
        return float("nan"), float("nan"), float("nan")
    total = sum(share.values())
    den = sum(v ** 2 / (t["dof"][s] + 2.0) for s, v in estimated.items())
    if not den > 0 or not total > 0:
        return floor, floor, float("inf")
    nu = (total ** 2 - 2.0 * den) / den  # > 0: (sum T)^2 >= sum T^2 > 2 sum T^2 / (d + 2) for d > 0
    a = (1.0 - level) / 2.0
    lo = floor * float(np.sqrt(nu / stats.chi2.ppf(1.0 - a, nu)))
    hi = floor * float(np.sqrt(nu / stats.chi2.ppf(a, nu)))
    return lo, hi, float(nu)
