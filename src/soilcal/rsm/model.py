"""Response-surface regression with Design-Expert semantics (statsmodels OLS underneath).

Model (coded units, Montgomery ch. 11; Myers, Montgomery & Anderson-Cook, RSM 4th ed.):

    y' = b0 + sum_i b_i x_i + sum_{i<j} b_ij x_i x_j + sum_i b_ii x_i^2 + e,
    y' = f(y) the (optional) response transform, x = (X - centre)/half_range.

ANOVA as printed by Design-Expert for response surfaces:
- Model SS = Cor Total SS - Residual SS, df = p - 1.
- Each term: partial (Type III) SS = SSE(model without the term) - SSE(model). For the
  cinnamon-soil Box-Behnken data (Qiu et al. 2022, Table 7) this reproduces the printed
  squares A^2 2.09, B^2 24.15, C^2 9.10 (sequential SS would not: the squares of a BBD are
  correlated with each other).
- F = MS_term / MS_residual, p = 1 - F_cdf(F; df_term, df_res).
- Pure error: within-group SS of replicated design points (identical factor settings),
  df = sum(n_g - 1); Lack of fit = Residual - Pure error.

Fit statistics (Design-Expert "Fit Statistics" panel, on the transformed scale):
- Std. Dev. = sqrt(MS_res), C.V.% = 100 Std.Dev / mean(y').
- PRESS = sum (e_i / (1 - h_ii))^2, Pred R^2 = 1 - PRESS / SS_total.  A point of leverage 1
  (h_ii >= 1 - 1e-8: the model passes through it whatever its value, e.g. the one point left
  of a Box-Behnken square whose partner failed) has no leave-one-out prediction: PRESS and
  Pred R^2 are then undefined, NaN, and :meth:`RSMFit.statistics_note` says why (the formula
  would give 0/0 or e/(tiny), a NaN or an infinite PRESS).
- Adeq Precision = (max yhat - min yhat) / sqrt(mean V(yhat)), with
  mean V(yhat) = p sigma^2 / n (the average of x_i^T (X^T X)^-1 x_i sigma^2 over the design
  points equals p sigma^2 / n).

Diagnostics: leverage h_ii, internally studentized r_i = e_i / (s sqrt(1 - h_ii)),
externally studentized residuals, Cook's D = r_i^2 h_ii / (p (1 - h_ii)).

Actual-unit equation: each coded monomial prod (x_f)^k with x_f = (X_f - c_f)/h_f is
expanded into monomials of the actual factors and collected.
"""

from __future__ import annotations

import re
from collections import defaultdict
from dataclasses import dataclass, field
from itertools import combinations
from typing import Mapping, Sequence

import numpy as np
import pandas as pd
from statsmodels.regression.linear_model import OLS  # not statsmodels.api: it imports every sub-package (0.4 s per job)
from scipy import stats

from soilcal.errors import InputError

# --------------------------------------------------------------------------- terms

#: leverage at or above 1 - LEVERAGE_ONE_TOL counts as 1 (module docstring, PRESS)
LEVERAGE_ONE_TOL = 1e-8

_TERM_PIECE = re.compile(r"^\s*([^\^\s]+)\s*(?:\^\s*(\d+))?\s*$")


def parse_term(term: str, factors: Sequence[str]) -> tuple[int, ...]:
    """Exponent vector of a term name ("A", "A*B", "A^2", "A*B^2") over ``factors``."""
    exps = [0] * len(factors)
    for piece in term.split("*"):
        m = _TERM_PIECE.match(piece)
        if not m or m.group(1) not in factors:
            raise InputError(None, "terms", f"products of factors {list(factors)} like 'A', 'A*B', 'A^2'", term)
        exps[list(factors).index(m.group(1))] += int(m.group(2) or 1)
    if sum(exps) == 0:
        raise InputError(None, "terms", "a non-constant term", term)
    return tuple(exps)


def term_name(exps: Sequence[int], factors: Sequence[str]) -> str:
    """Canonical name of an exponent vector: factors in list order, 'A*B', 'A^2'."""
    parts = []
    for f, k in zip(factors, exps):
        if k == 1:
            parts.append(f)
        elif k > 1:
            parts.append(f"{f}^{k}")
    return "*".join(parts) if parts else "Intercept"


def full_quadratic_terms(factors: Sequence[str]) -> list[str]:
    """Design-Expert order: main effects, two-factor interactions, squares."""
    f = list(factors)
    return f + [f"{a}*{b}" for a, b in combinations(f, 2)] + [f"{a}^2" for a in f]


def _contains(big: tuple[int, ...], small: tuple[int, ...]) -> bool:
    return big != small and all(b >= s for b, s in zip(big, small))


# --------------------------------------------------------------------------- transforms

_TRANSFORM_NAMES = {"none", "sqrt", "ln", "log", "log10", "inverse", "inverse_sqrt"}


def _normalise_transform(transform) -> tuple[str, float | None]:
    if isinstance(transform, (tuple, list)):
        if len(transform) != 2 or transform[0] != "power":
            raise InputError(None, "transform", "('power', lambda)", transform)
        return "power", float(transform[1])
    if transform not in _TRANSFORM_NAMES:
        raise InputError(None, "transform", f"one of {sorted(_TRANSFORM_NAMES)} or ('power', lambda)", transform)
    name = {"log": "ln"}.get(transform, transform)
    return name, None


def apply_transform(y, transform="none", constant: float = 0.0) -> np.ndarray:
    """y' = f(y + k). 'ln' (alias 'log') natural log, 'log10', 'inverse' 1/y, 'inverse_sqrt'."""
    name, lam = _normalise_transform(transform)
    z = np.asarray(y, dtype=float) + constant
    if name == "none":
        return z
    if name in ("sqrt", "ln", "log10", "inverse_sqrt") or (name == "power" and lam is not None and lam <= 0):
        if np.any(z <= 0):
            raise InputError(None, "transform", f"positive response values for transform {transform!r}", float(z.min()))
    if name == "sqrt":
        return np.sqrt(z)
    if name == "ln":
        return np.log(z)
    if name == "log10":
        return np.log10(z)
    if name == "inverse":
        if np.any(z == 0):
            raise InputError(None, "transform", "non-zero response values for 'inverse'", 0.0)
        return 1.0 / z
    if name == "inverse_sqrt":
        return 1.0 / np.sqrt(z)
    return np.log(z) if lam == 0 else z**lam


def inverse_transform(yt, transform="none", constant: float = 0.0) -> np.ndarray:
    """Back-transform predictions to original units."""
    name, lam = _normalise_transform(transform)
    z = np.asarray(yt, dtype=float)
    if name == "none":
        out = z
    elif name == "sqrt":
        out = z**2
    elif name == "ln":
        out = np.exp(z)
    elif name == "log10":
        out = 10.0**z
    elif name == "inverse":
        out = 1.0 / z
    elif name == "inverse_sqrt":
        out = 1.0 / z**2
    else:
        out = np.exp(z) if lam == 0 else np.sign(z) * np.abs(z) ** (1.0 / lam)
    return out - constant


# --------------------------------------------------------------------------- fit


def _bounds(values, factors: Sequence[str], name: str) -> np.ndarray:
    if isinstance(values, Mapping):
        missing = [f for f in factors if f not in values]
        if missing:
            raise InputError(None, name, f"a value for each factor {list(factors)}", f"missing {missing}")
        return np.array([float(values[f]) for f in factors])
    arr = np.asarray(values, dtype=float).reshape(-1)
    if arr.size != len(factors):
        raise InputError(None, name, f"{len(factors)} values, one per factor {list(factors)}", arr.size)
    return arr


def _term_exponents(exps: Sequence[tuple[int, ...]], k: int) -> np.ndarray:
    """The terms' exponents as a (terms, k) float array, the form :func:`_model_matrix` takes."""
    return np.asarray(exps, dtype=float).reshape(-1, k)


def _model_matrix(xc: np.ndarray, e: np.ndarray) -> np.ndarray:
    """[1, prod(x ** e) for each term e], e from :func:`_term_exponents`: with two or more
    factors all terms in one array operation (the optimisers call this for one point at a
    time, a hundred thousand times per stage; the values are those of the term-by-term loop,
    bit for bit).  With one factor the term-by-term loop: numpy squares an array against a
    one-element exponent array exactly, and the broadcast power may differ from that in the
    last bit."""
    if xc.shape[1] < 2:
        cols = [np.ones(xc.shape[0])]
        for row in e:
            cols.append(np.prod(xc ** row, axis=1))
        return np.column_stack(cols)
    out = np.empty((xc.shape[0], e.shape[0] + 1))
    out[:, 0] = 1.0
    out[:, 1:] = np.multiply.reduce(xc[:, None, :] ** e, axis=2)  # np.prod without its wrapper
    return out


@dataclass
class RSMFit:
    """A fitted response surface; see the module docstring for the statistics."""

    factors: list[str]
    low: np.ndarray
    high: np.ndarray
    response: str
    transform: object
    terms: list[str]
    X_coded: np.ndarray
    observed: np.ndarray
    transform_constant: float = 0.0
    _res: object = field(default=None, repr=False)

    def __post_init__(self) -> None:
        self._exps = [parse_term(t, self.factors) for t in self.terms]
        self.terms = [term_name(e, self.factors) for e in self._exps]
        if len(set(self.terms)) != len(self.terms):
            raise InputError(None, "terms", "each term at most once", self.terms)
        self.y_t = apply_transform(self.observed, self.transform, self.transform_constant)
        self._exp_array = _term_exponents(self._exps, len(self.factors))
        self.model_matrix = _model_matrix(self.X_coded, self._exp_array)
        self.n, self.p = self.model_matrix.shape
        if self.n <= self.p:
            raise InputError(None, "data", f"more runs than model parameters ({self.p})", self.n)
        if np.linalg.matrix_rank(self.model_matrix) < self.p:
            raise InputError(None, "terms", "terms estimable from the design (full-rank model matrix)", self.terms)
        self._res = OLS(self.y_t, self.model_matrix).fit()
        # the coefficients as a plain read-only array: statsmodels' params wrapper costs more
        # than a one-point prediction itself, and the optimisers make tens of thousands of them
        self._params = np.array(self._res.params, dtype=float)
        self._params.setflags(write=False)

    # -- basic quantities
    @property
    def params(self) -> np.ndarray:
        """Coded coefficients [Intercept, terms...] on the transformed scale."""
        return self._params

    @property
    def fitted_transformed(self) -> np.ndarray:
        return np.asarray(self._res.fittedvalues)

    @property
    def fitted(self) -> np.ndarray:
        """Fitted values in original units."""
        return inverse_transform(self.fitted_transformed, self.transform, self.transform_constant)

    @property
    def residuals(self) -> np.ndarray:
        """Residuals on the transformed scale."""
        return np.asarray(self._res.resid)

    @property
    def centre(self) -> np.ndarray:
        return (self.low + self.high) / 2.0

    @property
    def half_range(self) -> np.ndarray:
        return (self.high - self.low) / 2.0

    @property
    def df_resid(self) -> int:
        return self.n - self.p

    @property
    def sse(self) -> float:
        return float(self.residuals @ self.residuals)

    @property
    def mse(self) -> float:
        return self.sse / self.df_resid

    @property
    def ols(self):
        """The underlying statsmodels RegressionResults."""
        return self._res

    # -- prediction
    def _coded_input(self, X) -> np.ndarray:
        if isinstance(X, pd.DataFrame):
            X = X[self.factors].to_numpy(dtype=float)
        X = np.atleast_2d(np.asarray(X, dtype=float))
        if X.shape[1] != len(self.factors):
            raise InputError(None, "X", f"{len(self.factors)} columns {self.factors}", X.shape[1])
        return X

    def predict_transformed(self, X_coded) -> np.ndarray:
        return _model_matrix(self._coded_input(X_coded), self._exp_array) @ self.params

    def predict(self, X_coded) -> np.ndarray:
        """Prediction in original units from coded factor levels."""
        return inverse_transform(self.predict_transformed(X_coded), self.transform, self.transform_constant)

    def _coded_from_actual(self, X_actual) -> np.ndarray:
        return (self._coded_input(X_actual) - self.centre) / self.half_range

    def predict_actual(self, X_actual) -> np.ndarray:
        """Prediction in original units from actual factor levels."""
        return self.predict(self._coded_from_actual(X_actual))

    def confidence_actual(self, X_actual, alpha: float = 0.05) -> tuple[np.ndarray, np.ndarray]:
        """(low, high): the 1 - alpha confidence interval of the fitted mean at actual factor
        levels, x0' b -+ t(1 - alpha/2, n - p) sqrt(MSE x0' (X'X)^-1 x0) on the transformed
        scale (statsmodels ``get_prediction``), back-transformed to original units (bounds
        sorted: a decreasing transform swaps them)."""
        mm = _model_matrix(self._coded_from_actual(X_actual), self._exp_array)
        ci = np.asarray(self._res.get_prediction(mm).conf_int(alpha=alpha))
        b = inverse_transform(ci, self.transform, self.transform_constant)
        return np.minimum(b[:, 0], b[:, 1]), np.maximum(b[:, 0], b[:, 1])

    def extremes(self, lower, upper) -> tuple[float, float] | None:
        """(lowest, highest) prediction over the coded box ``lower`` .. ``upper`` (per factor),
        for a surface whose terms are of degree 2 at most and whose transform is none, ln or
        log10 (increasing back-transforms); None for any other model (other increasing
        back-transforms, such as a power with a positive exponent, included).  A quadratic's
        extremes over a box lie at a vertex or at the stationary point of its restriction to a
        face (each factor at its lower bound, its upper bound or free: 3^k faces), so the
        candidates are the vertices and those stationary points that lie inside their face; the
        extremes are the model's own predictions there.  A face whose restricted Hessian is singular holds no isolated
        extreme that its boundary does not match, and is passed over."""
        name, _ = _normalise_transform(self.transform)
        if name not in ("none", "ln", "log10") or any(sum(e) > 2 for e in self._exps):
            return None
        k = len(self.factors)
        lo = np.asarray(lower, float).reshape(-1)
        hi = np.asarray(upper, float).reshape(-1)
        if lo.size != k or hi.size != k:
            raise InputError(None, "lower/upper", f"{k} coded bounds each, one per factor {list(self.factors)}",
                             (lo.size, hi.size))
        g, H = np.zeros(k), np.zeros((k, k))  # transformed prediction = b0 + g x + x' H x / 2
        for b, e in zip(self.params[1:], self._exps):
            idx = [i for i, p in enumerate(e) for _ in range(p)]
            if len(idx) == 1:
                g[idx[0]] += b
            elif idx[0] == idx[1]:
                H[idx[0], idx[0]] += 2.0 * b
            else:
                H[idx[0], idx[1]] += b
                H[idx[1], idx[0]] += b
        points = []
        for pattern in np.ndindex(*(3,) * k):  # 0: at lower, 1: at upper, 2: free
            x = np.where(np.array(pattern) == 1, hi, lo)
            free = [i for i, p in enumerate(pattern) if p == 2]
            if free:
                fixed = [i for i, p in enumerate(pattern) if p != 2]
                A = H[np.ix_(free, free)]
                if np.linalg.matrix_rank(A) < len(free):
                    continue
                x[free] = np.linalg.solve(A, -(g[free] + H[np.ix_(free, fixed)] @ x[fixed]))
                if np.any(x[free] < lo[free]) or np.any(x[free] > hi[free]):
                    continue
            points.append(x)
        y = self.predict(np.array(points))
        return float(np.min(y)), float(np.max(y))

    def _gradients(self, X_coded) -> np.ndarray:
        """Per set (rows, coded levels) the gradient of the prediction in the coefficients,
        g'(eta) f(x): f the model row, eta the prediction on the transformed scale, g the
        inverse transform (central differences; f(x) itself without a transform)."""
        mm = _model_matrix(self._coded_input(np.atleast_2d(np.asarray(X_coded, float))), self._exp_array)
        eta = mm @ self.params
        h = 1e-6 * np.maximum(1.0, np.abs(eta))
        up = inverse_transform(eta + h, self.transform, self.transform_constant)
        down = inverse_transform(eta - h, self.transform, self.transform_constant)
        return ((np.asarray(up, float) - np.asarray(down, float)) / (2 * h))[:, None] * mm

    def _delta_se(self, a: np.ndarray) -> float:
        """sqrt(a' C a), C the coefficients' covariance (the delta method)."""
        return float(np.sqrt(max(float(a @ np.asarray(self._res.cov_params()) @ a), 0.0)))

    def predict_se(self, x_coded) -> float:
        """The standard error of the surface's mean prediction at one set (coded levels),
        sqrt(a' C a) with a = g'(eta) f(x) (:meth:`_gradients`; exact without a transform,
        where it is statsmodels' ``se_mean``)."""
        return self._delta_se(self._gradients(x_coded)[0])

    def change_se(self, x_from_coded, x_to_coded) -> float:
        """The standard error of the surface's change between two sets (coded levels),
        predict(x_to) - predict(x_from): sqrt(a' C a) with a = g'(eta_to) f(x_to) -
        g'(eta_from) f(x_from) (:meth:`_gradients`; exact without a transform)."""
        a = self._gradients(np.vstack([x_from_coded, x_to_coded]))
        return self._delta_se(a[1] - a[0])

    # -- ANOVA
    def _pure_error(self) -> tuple[float, int]:
        groups: dict[tuple, list[float]] = defaultdict(list)
        for row, y in zip(np.round(self.X_coded, 9), self.y_t):
            groups[tuple(row)].append(y)
        ss, df = 0.0, 0
        for vals in groups.values():
            if len(vals) > 1:
                v = np.asarray(vals)
                ss += float(((v - v.mean()) ** 2).sum())
                df += len(v) - 1
        return ss, df

    #: a pure error this small beside the total sum of squares is rounding of identical
    #: responses (six centre points printed 35.2 leave ~1e-28, not 0), not replicate scatter
    PURE_ERROR_RTOL = 1e-12

    def pure_error_negligible(self) -> bool:
        """Whether the replicated points (the centre points) carry no pure error: every group of
        identical design rows has identical responses, or the pure error's sum of squares is at
        most :data:`PURE_ERROR_RTOL` of the total (what a mean of equal floats leaves).  Then
        the lack of fit has nothing to be tested against: :meth:`anova` leaves its F and p
        empty and :meth:`statistics_note` says why."""
        groups: dict[tuple, list[float]] = defaultdict(list)
        for row, y in zip(np.round(self.X_coded, 9), self.y_t):
            groups[tuple(row)].append(y)
        reps = [np.asarray(v) for v in groups.values() if len(v) > 1]
        if not reps:
            return False
        if all(np.ptp(v) == 0 for v in reps):
            return True
        sspe, _ = self._pure_error()
        sst = float(((self.y_t - self.y_t.mean()) ** 2).sum())
        return sspe <= self.PURE_ERROR_RTOL * sst

    def term_sum_sq(self) -> dict[str, float]:
        """Partial (Type III) sum of squares of each term."""
        out = {}
        for j, t in enumerate(self.terms):
            keep = [i for i in range(self.p) if i != j + 1]
            red = OLS(self.y_t, self.model_matrix[:, keep]).fit()
            out[t] = float(red.ssr) - self.sse
        return out

    def anova(self) -> pd.DataFrame:
        """Design-Expert ANOVA table: Model, terms, Residual, Lack of Fit, Pure Error, Cor Total."""
        mse, dfr = self.mse, self.df_resid
        sst = float(((self.y_t - self.y_t.mean()) ** 2).sum())
        ssm = sst - self.sse
        rows = []

        def frow(src, ss, df):
            ms = ss / df
            f = ms / mse
            rows.append((src, ss, df, ms, f, float(stats.f.sf(f, df, dfr))))

        frow("Model", ssm, self.p - 1)
        for t, ss in self.term_sum_sq().items():
            frow(t, ss, 1)
        rows.append(("Residual", self.sse, dfr, mse, np.nan, np.nan))
        sspe, dfpe = self._pure_error()
        if dfpe > 0:
            sslof, dflof = self.sse - sspe, dfr - dfpe
            if dflof > 0:
                mslof, mspe = sslof / dflof, sspe / dfpe
                if not self.pure_error_negligible():
                    flof = mslof / mspe
                    rows.append(("Lack of Fit", sslof, dflof, mslof, flof, float(stats.f.sf(flof, dflof, dfpe))))
                else:
                    # replicates that agree (centre points printed alike, to rounding): no pure
                    # error to test the lack of fit against, so no F and no p
                    rows.append(("Lack of Fit", sslof, dflof, mslof, np.nan, np.nan))
            rows.append(("Pure Error", sspe, dfpe, sspe / dfpe, np.nan, np.nan))
        rows.append(("Cor Total", sst, self.n - 1, np.nan, np.nan, np.nan))
        return pd.DataFrame(rows, columns=["source", "sum_sq", "df", "mean_sq", "F", "p"])

    # -- fit statistics
    @property
    def leverage(self) -> np.ndarray:
        X = self.model_matrix
        return np.einsum("ij,ji->i", X, np.linalg.solve(X.T @ X, X.T))

    @property
    def leverage_one(self) -> np.ndarray:
        """Positions (0-based, in the fit's row order) of the points with leverage 1 (module
        docstring): their residual is zero whatever their value."""
        return np.flatnonzero(self.leverage >= 1.0 - LEVERAGE_ONE_TOL)

    @property
    def press(self) -> float:
        """PRESS, NaN where a point has leverage 1 (module docstring)."""
        h = self.leverage  # one solve for both the test and the sum
        if np.any(h >= 1.0 - LEVERAGE_ONE_TOL):
            return float("nan")
        return float(((self.residuals / (1.0 - h)) ** 2).sum())

    def statistics_note(self, labels: Sequence | None = None) -> str:
        """Why :meth:`fit_statistics` leaves PRESS and Pred R^2 undefined (empty when it does
        not); ``labels`` name the fit's points in order (run numbers), default 1, 2, ..."""
        notes = []
        idx = self.leverage_one
        if idx.size:
            names = [str(labels[i]) if labels is not None else str(i + 1) for i in idx]
            which = (f"point {names[0]} has" if len(names) == 1 else f"points {', '.join(names)} have")
            notes.append(f"{which} leverage 1 (a model term rests on {'it' if len(names) == 1 else 'them'} alone, "
                         "so the model passes through it whatever the response): PRESS and pred R2 undefined")
        _, dfpe = self._pure_error()
        if dfpe > 0 and self.df_resid - dfpe > 0 and self.pure_error_negligible():
            notes.append("the replicated points (centre points) have identical responses: no pure error, so the "
                         "lack of fit has no F and no p")
        return "; ".join(notes)

    def fit_statistics(self) -> dict[str, float]:
        """Std. Dev., Mean, C.V.%, R2, adj R2, pred R2, PRESS, Adeq Precision (PRESS and pred R2
        NaN where a point has leverage 1: :meth:`statistics_note`)."""
        sst = float(((self.y_t - self.y_t.mean()) ** 2).sum())
        sd = float(np.sqrt(self.mse))
        mean = float(self.y_t.mean())
        yhat = self.fitted_transformed
        v_mean = self.p * self.mse / self.n
        press = self.press
        return {
            "std_dev": sd,
            "mean": mean,
            "CV_percent": 100.0 * sd / mean,
            "R2": 1.0 - self.sse / sst,
            "adj_R2": 1.0 - (self.sse / self.df_resid) / (sst / (self.n - 1)),
            "pred_R2": 1.0 - press / sst,
            "PRESS": press,
            "adeq_precision": float((yhat.max() - yhat.min()) / np.sqrt(v_mean)),
        }

    # -- diagnostics
    @property
    def studentized_residuals(self) -> np.ndarray:
        """Internally studentized residuals e_i / (s sqrt(1 - h_ii))."""
        return self.residuals / np.sqrt(self.mse * (1.0 - self.leverage))

    @property
    def externally_studentized_residuals(self) -> np.ndarray:
        r = self.studentized_residuals
        d = self.df_resid
        return r * np.sqrt((d - 1) / np.maximum(d - r**2, 1e-300))

    @property
    def cooks_distance(self) -> np.ndarray:
        h = self.leverage
        return self.studentized_residuals**2 * h / (self.p * (1.0 - h))

    def diagnostics(self) -> pd.DataFrame:
        return pd.DataFrame(
            {
                "run": np.arange(1, self.n + 1),
                "observed": self.observed,
                "fitted": self.fitted,
                "residual": self.residuals,
                "leverage": self.leverage,
                "studentized": self.studentized_residuals,
                "ext_studentized": self.externally_studentized_residuals,
                "cooks_distance": self.cooks_distance,
            }
        )

    # -- equations
    def actual_coefficients(self) -> dict[tuple[int, ...], float]:
        """Monomial exponents (actual units) -> coefficient, from expanding the coded model."""
        k = len(self.factors)
        poly: dict[tuple[int, ...], float] = defaultdict(float)
        poly[(0,) * k] += float(self.params[0])
        c, h = self.centre, self.half_range
        for b, e in zip(self.params[1:], self._exps):
            # prod_f ((X_f - c_f)/h_f)^e_f, expanded by the binomial theorem per factor
            term = {(0,) * k: float(b)}
            for f, ef in enumerate(e):
                if ef == 0:
                    continue
                new: dict[tuple[int, ...], float] = defaultdict(float)
                from math import comb

                for mono, coef in term.items():
                    for j in range(ef + 1):
                        m = list(mono)
                        m[f] += j
                        new[tuple(m)] += coef * comb(ef, j) * (-c[f]) ** (ef - j) / h[f] ** ef
                term = new
            for mono, coef in term.items():
                poly[mono] += coef
        return dict(poly)

    def coefficients(self) -> pd.DataFrame:
        """[term, coded, actual]: Intercept first, then the model terms; monomials that
        appear only in the actual-unit expansion (non-hierarchical models) are appended
        with coded coefficient 0."""
        k = len(self.factors)
        act = self.actual_coefficients()
        rows = [("Intercept", float(self.params[0]), act.get((0,) * k, 0.0))]
        for t, e, b in zip(self.terms, self._exps, self.params[1:]):
            rows.append((t, float(b), act.get(e, 0.0)))
        known = {(0,) * k, *self._exps}
        for mono in sorted(act, key=lambda m: (sum(m), [-x for x in m])):
            if mono not in known and abs(act[mono]) > 0:
                rows.append((term_name(mono, self.factors), 0.0, act[mono]))
        return pd.DataFrame(rows, columns=["term", "coded", "actual"])

    def equation(self, units: str = "coded", digits: int = 4) -> str:
        col = "coded" if units == "coded" else "actual"
        df = self.coefficients()
        s = f"{self.response} = {df[col].iloc[0]:.{digits}g}"
        for t, v in zip(df["term"].iloc[1:], df[col].iloc[1:]):
            s += f" {'-' if v < 0 else '+'} {abs(v):.{digits}g}*{t}"
        return s


def fit_response_surface(
    data: pd.DataFrame,
    factors: list[str],
    response: str,
    low,
    high,
    terms: list[str] | None = None,
    transform="none",
    data_coding: str = "coded",
    transform_constant: float = 0.0,
) -> RSMFit:
    """Fit a response surface by OLS with Design-Expert ANOVA semantics.

    data: one row per run, columns ``factors`` (coded or actual per ``data_coding``) and
    ``response``. low/high: actual factor bounds (mapping or sequence), used for coding and
    for the actual-unit equation. terms: None = full quadratic.
    """
    if not isinstance(data, pd.DataFrame):
        raise InputError(None, "data", "a pandas DataFrame", type(data).__name__)
    missing = [c for c in [*factors, response] if c not in data.columns]
    if missing:
        raise InputError(None, "data", f"columns {list(factors) + [response]}", f"missing {missing}")
    if data_coding not in ("coded", "actual"):
        raise InputError(None, "data_coding", "'coded' or 'actual'", data_coding)
    lo = _bounds(low, factors, "low")
    hi = _bounds(high, factors, "high")
    if np.any(hi == lo):
        raise InputError(None, "low/high", "high != low for every factor", list(zip(lo, hi)))
    X = data[list(factors)].to_numpy(dtype=float)
    if data_coding == "actual":
        X = (X - (lo + hi) / 2.0) / ((hi - lo) / 2.0)
    y = data[response].to_numpy(dtype=float)
    if not np.all(np.isfinite(y)) or not np.all(np.isfinite(X)):
        raise InputError(None, "data", "finite factor levels and responses", "NaN/inf")
    return RSMFit(
        factors=list(factors),
        low=lo,
        high=hi,
        response=response,
        transform=transform,
        terms=list(terms) if terms is not None else full_quadratic_terms(factors),
        X_coded=X,
        observed=y,
        transform_constant=float(transform_constant),
    )


def _refit(fit: RSMFit, terms: list[str]) -> RSMFit:
    return RSMFit(
        factors=fit.factors,
        low=fit.low,
        high=fit.high,
        response=fit.response,
        transform=fit.transform,
        terms=terms,
        X_coded=fit.X_coded,
        observed=fit.observed,
        transform_constant=fit.transform_constant,
    )


def drop_terms(fit: RSMFit, terms: Sequence[str]) -> RSMFit:
    """Refit without the named terms."""
    drop = {term_name(parse_term(t, fit.factors), fit.factors) for t in terms}
    unknown = drop - set(fit.terms)
    if unknown:
        raise InputError(None, "terms", f"terms of the model {fit.terms}", sorted(unknown))
    return _refit(fit, [t for t in fit.terms if t not in drop])


def backward_eliminate(fit: RSMFit, alpha_out: float = 0.1, hierarchical: bool = True) -> RSMFit:
    """Design-Expert backward elimination: repeatedly remove the term with the largest
    partial-F p-value above ``alpha_out``; with ``hierarchical`` a term is not a candidate
    while a higher-order term containing it (e.g. A inside A*B or A^2) is in the model."""
    current = fit
    while current.terms:
        tab = current.anova().set_index("source")
        exps = dict(zip(current.terms, current._exps))
        cands = []
        for t in current.terms:
            if hierarchical and any(_contains(exps[u], exps[t]) for u in current.terms if u != t):
                continue
            cands.append((float(tab.loc[t, "p"]), t))
        cands = [c for c in cands if c[0] > alpha_out]
        if not cands:
            break
        worst = max(cands)[1]
        if len(current.terms) == 1:
            break
        current = _refit(current, [t for t in current.terms if t != worst])
    return current


__all__ = [
    "RSMFit",
    "fit_response_surface",
    "drop_terms",
    "backward_eliminate",
    "full_quadratic_terms",
    "parse_term",
    "term_name",
    "apply_transform",
    "inverse_transform",
]
