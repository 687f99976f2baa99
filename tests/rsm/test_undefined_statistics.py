"""Statistics the data leave undefined are written empty with the reason, never as inf.

A Box-Behnken design of three factors and three centre points whose run 2 (A = -1, B = +1,
C = 0) gave no response: the full quadratic's A*B term then rests on one point alone, which
the model passes through whatever its response (leverage 1), so that point has no
leave-one-out prediction and PRESS and pred R2 are undefined.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from soilcal import doe, rsm
from soilcal.chain.stage import regression_frames

SCATTER = np.array([0.1, -0.2, 0.15, -0.05, 0.3, -0.1, 0.2, 0.05, -0.15, 0.1, 0.02, -0.3, 0.12, -0.08, 0.04])


def _table(missing=(2,)) -> pd.DataFrame:
    x = doe.box_behnken(3, 3)
    df = pd.DataFrame(x.astype(int), columns=list("ABC"))
    df.insert(0, "run", np.arange(1, len(df) + 1))
    a, b, c = x.T
    y = 30 + a + 2 * b - c + 0.5 * a * b + a * a + SCATTER
    df["angle"] = y
    df.loc[df["run"].isin(missing), "angle"] = np.nan
    return df


STAGE = {"id": "bbd", "kind": "box_behnken", "center_points": 3, "table_coding": "coded",
         "factors": {s: {"parameter": s.lower(), "low": -1.0, "high": 1.0} for s in "ABC"},
         "responses": [{"id": "angle"}]}


def _fit(table: pd.DataFrame):
    d = table.dropna(subset=["angle"])
    return rsm.fit_response_surface(d, list("ABC"), "angle", [-1] * 3, [1] * 3, data_coding="coded")


def test_a_point_of_leverage_one_is_the_one_the_model_passes_through_whatever_its_response():
    t = _table()
    fit = _fit(t)
    pos = list(fit.leverage_one)
    assert len(pos) >= 1
    # leverage 1 <=> the point's residual is zero whatever its response: move each response by
    # 10 and refit
    d = t.dropna(subset=["angle"]).reset_index(drop=True)
    through = []
    for i in range(len(d)):
        moved = d.copy()
        moved.loc[i, "angle"] += 10.0
        if abs(_fit(moved).residuals[i]) < 1e-8:
            through.append(i)
    assert pos == through
    stats = fit.fit_statistics()
    assert np.isnan(stats["PRESS"]) and np.isnan(stats["pred_R2"])
    runs = [int(d["run"][i]) for i in pos]
    note = fit.statistics_note(list(d["run"]))
    assert note.startswith(f"point {runs[0]} has leverage 1") and "PRESS and pred R2 undefined" in note
    # the full design: no such point, PRESS the leave-one-out sum, no note
    full = _fit(_table(missing=()))
    assert not full.leverage_one.size and np.isfinite(full.press) and full.statistics_note() == ""


def test_fit_csv_has_no_infinity_and_says_why_a_statistic_is_empty():
    t = _table()
    fit = regression_frames(STAGE, t)["fit"]
    numeric = fit.select_dtypes("number").to_numpy(float)
    assert not np.isinf(numeric).any()
    full = fit[fit["model"] == "full"].iloc[0]
    run = int(t.dropna(subset=["angle"])["run"].iloc[int(_fit(t).leverage_one[0])])
    assert np.isnan(full["PRESS"]) and np.isnan(full["pred_R2"])
    assert f"point {run} has leverage 1" in full["note"]
    # a Box-Cox interval reaching past the searched lambda range: the open end empty, the note says so
    for _, r in fit.iterrows():
        for key in ("boxcox_ci_low", "boxcox_ci_high"):
            if pd.isna(r[key]):
                assert "Box-Cox: the 95 % interval of lambda" in r["note"]
    bc = rsm.boxcox(_fit(t))
    if np.isinf(bc["ci_low"]) or np.isinf(bc["ci_high"]):
        assert pd.isna(full["boxcox_ci_low"]) or pd.isna(full["boxcox_ci_high"])
        assert bc["ci_note"] and f"Box-Cox: {bc['ci_note']}" in full["note"]
    # every point present: nothing undefined for the model
    whole = regression_frames(STAGE, _table(missing=()))["fit"]
    assert np.isfinite(whole["PRESS"]).all()
    assert not whole["note"].str.contains("leverage").any()


@pytest.mark.parametrize("lams, expected", [
    (np.linspace(0.9, 1.1, 21), "covers the whole searched range 0.9 to 1.1"),
])
def test_box_cox_interval_beyond_the_searched_range_is_named(lams, expected):
    """On a narrow lambda grid around 1 the 95 % interval of a well-fitted positive response
    reaches past both ends."""
    fit = _fit(_table(missing=()))
    bc = rsm.boxcox(fit, lambdas=lams)
    assert np.isinf(bc["ci_low"]) and np.isinf(bc["ci_high"])
    assert expected in bc["ci_note"]
