"""Two-level screening analysis (Plackett-Burman) as Design-Expert reports it.

Main-effects model on the real factors only, coded +/-1 (Montgomery ch. 8; Plackett &
Burman 1946). For an orthogonal two-level design with N runs:

    coefficient b_j = sum(x_ij y_i) / N,   effect = 2 b_j = mean(y|+) - mean(y|-),
    SS_j = N b_j^2,   contribution % = 100 SS_j / SS_total (corrected),
    F_j = SS_j / MS_res,  p_j = 1 - F_cdf(F_j; 1, N - 1 - k).

Dummy columns are not model terms, so their variation stays in the residual (this is what
Design-Expert does when the dummy variables are left out of the model). For a non-orthogonal
(e.g. mis-printed) design, SS_j is the partial (Type III) sum of squares and b_j the OLS
coefficient, effect = 2 b_j.
"""

from __future__ import annotations

from typing import Sequence

import pandas as pd

from soilcal.errors import InputError
from soilcal.rsm.model import fit_response_surface


def screening_effects(
    data: pd.DataFrame,
    factors: Sequence[str],
    response: str,
    dummies: Sequence[str] | None = None,
    low=None,
    high=None,
    data_coding: str = "coded",
) -> pd.DataFrame:
    """Effects table [term, effect, coefficient, sum_sq, contribution_percent, F, p, rank].

    ``dummies`` are ignored columns (listed only to check they are not also factors);
    rank 1 = largest sum of squares. ``df.attrs`` carries the model ANOVA row ("Model"
    sum_sq, df, F, p), the residual SS/df and the fit.
    """
    factors = list(factors)
    dummies = list(dummies or [])
    both = set(factors) & set(dummies)
    if both:
        raise InputError(None, "dummies", "columns that are not also factors", sorted(both))
    if data_coding == "coded":
        low = [-1.0] * len(factors) if low is None else low
        high = [1.0] * len(factors) if high is None else high
    elif low is None or high is None:
        raise InputError(None, "low/high", "factor bounds when data_coding='actual'", None)
    fit = fit_response_surface(
        data, factors, response, low, high, terms=factors, data_coding=data_coding
    )
    tab = fit.anova().set_index("source")
    sst = float(tab.loc["Cor Total", "sum_sq"])
    rows = []
    for t, b in zip(fit.terms, fit.params[1:]):
        ss = float(tab.loc[t, "sum_sq"])
        rows.append((t, 2.0 * float(b), float(b), ss, 100.0 * ss / sst, float(tab.loc[t, "F"]), float(tab.loc[t, "p"])))
    out = pd.DataFrame(rows, columns=["term", "effect", "coefficient", "sum_sq", "contribution_percent", "F", "p"])
    out["rank"] = out["sum_sq"].rank(ascending=False, method="min").astype(int)
    out.attrs["model"] = {k: float(tab.loc["Model", k]) for k in ("sum_sq", "df", "mean_sq", "F", "p")}
    out.attrs["residual"] = {k: float(tab.loc["Residual", k]) for k in ("sum_sq", "df", "mean_sq")}
    out.attrs["cor_total"] = sst
    out.attrs["fit"] = fit
    return out


__all__ = ["screening_effects"]
