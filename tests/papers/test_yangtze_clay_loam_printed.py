"""Yangtze clay loam (Zeng et al., Agriculture 2023, 13, 648): the encoded data against the paper.

Every expected number is a printed value of the paper (table/equation cited beside it) or follows
from printed values by the textbook identities of a least-squares ANOVA:
MS = SS/df, F = MS/MS_residual, SS_model + SS_residual = SS_total, R^2 = SS_model/SS_total,
adj R^2 = 1 - (1 - R^2)(n - 1)/(n - p - 1) (Montgomery, Design and Analysis of Experiments, ch. 10).
Printed responses are rounded to 0.01 dm^2; every coefficient of a least-squares fit is linear in
the responses, b = (X'X)^-1 X' sqrt(y), so the range of b over the rounding box
y_i +/- 0.005 is exact: each sqrt(y_i) sits at the end of its interval that the weight's sign
favours. The paper is consistent with Table 4 wherever a printed value lies in that range.
"""

from __future__ import annotations

import math
from pathlib import Path

import jsonschema
import numpy as np
import pandas as pd
import pytest
import yaml
from scipy import stats

from soilcal import doe
from soilcal.config import load_soil

ROOT = Path(__file__).resolve().parents[2]
CFG = ROOT / "config" / "soils" / "yangtze-clay-loam.yaml"
PUB = ROOT / "resources" / "published" / "yangtze-clay-loam"
MEAS = ROOT / "resources" / "measurements" / "yangtze-clay-loam"
SCHEMA = ROOT / "src" / "soilcal" / "config" / "soil.schema.yaml"

SYMS = ["A", "B", "C", "D"]
REDUCED_TERMS = ["A", "B", "C", "D", "A*B", "B*C", "B*D", "A^2", "B^2"]  # Eq. (5)
PRINTED_COEF = {"Intercept": "0.90", "A": "-0.27", "B": "0.13", "C": "0.13", "D": "-0.097",
                "A*B": "0.048", "B*C": "-0.072", "B*D": "-0.14", "A^2": "0.28", "B^2": "-0.032"}


def _half_unit(s: str) -> float:
    """Half of the last printed digit of a decimal string ('0.097' -> 0.0005)."""
    s = s.strip().lstrip("-<>")
    if "e" in s.lower():
        mant, exp = s.lower().split("e")
        return _half_unit(mant) * 10 ** int(exp)
    dec = len(s.split(".")[1]) if "." in s else 0
    return 0.5 * 10 ** (-dec)


@pytest.fixture(scope="module")
def cfg():
    return yaml.safe_load(CFG.read_text())


@pytest.fixture(scope="module")
def stage(cfg):
    return cfg["stages"][0]


@pytest.fixture(scope="module")
def table():
    return pd.read_csv(PUB / "bbd.csv")


@pytest.fixture(scope="module")
def anova():
    return pd.read_csv(PUB / "bbd_anova_reduced.csv", dtype=str).set_index("source")


@pytest.fixture(scope="module")
def coded(stage, table):
    """Table 4 in coded units; the printed 0.17 (Table 3: 0.175) maps to 0 after rounding."""
    out = {}
    for s in SYMS:
        f = stage["factors"][s]
        x = doe.actual_to_coded(table[s].to_numpy(float), f["low"], f["high"])
        out[s] = np.round(x)
    return pd.DataFrame(out)


def _model_matrix(coded: pd.DataFrame, terms: list[str]) -> np.ndarray:
    cols = [np.ones(len(coded))]
    for t in terms:
        if "*" in t:
            a, b = t.split("*")
            cols.append(coded[a] * coded[b])
        elif t.endswith("^2"):
            cols.append(coded[t[0]] ** 2)
        else:
            cols.append(coded[t])
    return np.column_stack(cols)


# ----------------------------------------------------------------------------- config


def test_config_validates_against_schema(cfg):
    schema = yaml.safe_load(SCHEMA.read_text())
    jsonschema.Draft202012Validator(schema).validate(cfg)


def test_config_loads_with_table_checks():
    soil = load_soil(CFG, ROOT / "resources")
    assert soil.name == "yangtze-clay-loam"
    assert len(soil.tables["bbd"]) == 29


def test_levels_are_table_3(stage):
    lv = {s: (f["low"], f["centre"], f["high"]) for s, f in stage["factors"].items()}
    assert lv == {"A": (0.3, 0.45, 0.6), "B": (0.2, 0.4, 0.6), "C": (0.05, 0.175, 0.3), "D": (5, 7, 9)}
    for lo, c, hi in lv.values():
        assert math.isclose(c, (lo + hi) / 2)


def test_fixed_soil_steel_values_are_tables_1_2(stage, cfg):
    assert stage["fixed"] == {"soil_steel_restitution": 0.3, "soil_steel_static_friction": 0.71,
                              "soil_steel_rolling_friction": 0.097}
    assert stage["transform"] == {"area_difference": "sqrt"}
    case = stage["optimise"]["cases"][0]
    assert case["goals"]["area_difference"] == {"goal": "minimize"}
    assert case["printed_optimum"] == {"A": 0.5, "B": 0.2, "C": 0.05, "D": 5}


# ----------------------------------------------------------------------------- Table 4


def test_table_4_shape_and_levels(table, stage):
    assert list(table.columns) == ["run"] + SYMS + ["area_difference"]
    assert len(table) == 29 and list(table["run"]) == list(range(1, 30))
    assert stage["table_coding"] == "actual"
    assert sorted(set(table["A"])) == [0.3, 0.45, 0.6]
    assert sorted(set(table["B"])) == [0.2, 0.4, 0.6]
    assert sorted(set(table["D"])) == [5.0, 7.0, 9.0]
    # Table 4 prints the rolling-friction centre as 0.17, Table 3 as 0.175.
    assert sorted(set(table["C"])) == [0.05, 0.17, 0.3]
    assert (table["C"] == 0.17).sum() == 17


def test_c_centre_rounding_is_recorded(cfg):
    assert "0.17" in cfg["notes"] and "0.175" in cfg["notes"]
    assert any("0.17" in m["note"] and "Table 4" in m["where"] for m in cfg["missing"])


def test_coded_design_is_the_box_behnken_design(coded, stage):
    assert set(np.unique(coded.to_numpy())) <= {-1.0, 0.0, 1.0}
    assert len(coded) == 4 * math.comb(4, 2) + stage["center_points"]
    cmp = doe.same_rows(coded.to_numpy(), doe.box_behnken(4, stage["center_points"]))
    assert bool(cmp)


def test_max_min_ratio_contradiction_is_recorded(table, cfg):
    y = table["area_difference"]
    ratio = y.max() / y.min()
    assert math.isclose(ratio, 12.2)  # 2.44 / 0.20 from Table 4
    assert round(ratio, 1) != 11.9  # Sec. 3.2.1 prints 11.9
    assert ratio > 10  # the decision to take the square root is unaffected
    assert round(math.sqrt(ratio), 2) == 3.49  # printed 3.4
    assert "11.9" in cfg["notes"] and "12.2" in cfg["notes"]


# ----------------------------------------------------------------------------- Table 5


def _f(a, src, col):
    return float(a.loc[src, col])


def test_anova_rows_add_up(anova):
    ss = lambda s: _f(anova, s, "sum_sq")  # noqa: E731
    df = lambda s: int(anova.loc[s, "df"])  # noqa: E731
    assert df("Model") + df("Residual") == df("Cor Total") == 28
    assert df("Lack of Fit") + df("Pure Error") == df("Residual") == 19
    assert df("Pure Error") == 5 - 1  # five centre runs (25-29)
    tol = 0.005 + 0.005 + 0.005
    assert abs(ss("Model") + ss("Residual") - ss("Cor Total")) <= tol
    assert abs(ss("Lack of Fit") + ss("Pure Error") - ss("Residual")) <= 0.005 + 0.0005 + 0.005


@pytest.mark.parametrize("src", ["Model", "A", "B", "C", "D", "B*D", "A^2", "Residual", "Lack of Fit", "Pure Error"])
def test_anova_mean_square_is_ss_over_df(anova, src):
    ss_s, ms_s = anova.loc[src, "sum_sq"], anova.loc[src, "mean_sq"]
    df = int(anova.loc[src, "df"])
    ss_lo, ss_hi = float(ss_s) - _half_unit(ss_s), float(ss_s) + _half_unit(ss_s)
    ms = float(ms_s)
    assert ss_lo / df - _half_unit(ms_s) <= ms <= ss_hi / df + _half_unit(ms_s)


@pytest.mark.parametrize("src", ["Model", "A", "B", "C", "D", "B*D", "A^2"])
def test_anova_f_is_ms_over_residual_ms(anova, src):
    ms_s, res_s = anova.loc[src, "mean_sq"], anova.loc["Residual", "sum_sq"]
    # extreme values of MS_term / MS_residual inside the printed rounding
    ms_lo, ms_hi = float(ms_s) - _half_unit(ms_s), float(ms_s) + _half_unit(ms_s)
    res_lo = (float(res_s) - _half_unit(res_s)) / 19
    res_hi = (float(res_s) + _half_unit(res_s)) / 19
    assert ms_lo / res_hi <= _f(anova, src, "F") <= ms_hi / res_lo


def test_anova_lack_of_fit_f(anova):
    f = _f(anova, "Lack of Fit", "mean_sq") / _f(anova, "Pure Error", "mean_sq")
    assert abs(f - _f(anova, "Lack of Fit", "F")) <= 0.03  # 0.013 / 6.23e-3 = 2.09; printed 2.11


@pytest.mark.parametrize("src", ["Model", "A", "B", "C", "D", "B*D", "A^2", "Lack of Fit"])
def test_anova_p_follows_from_f_and_df(anova, src):
    df1 = int(anova.loc[src, "df"])
    df2 = 4 if src == "Lack of Fit" else 19
    f_s = anova.loc[src, "F"]
    # p at the ends of the printed F's rounding interval brackets the printed p
    p_hi = stats.f.sf(float(f_s) - _half_unit(f_s), df1, df2)
    p_lo = stats.f.sf(float(f_s) + _half_unit(f_s), df1, df2)
    printed = anova.loc[src, "p"]
    if printed.startswith("<"):
        assert p_hi < float(printed[1:])
    else:
        assert p_lo - _half_unit(printed) <= float(printed) <= p_hi + _half_unit(printed)


def test_fit_statistics_follow_from_anova(anova, stage):
    fit = stage["printed"]["area_difference"]["fit_reduced"]
    r2 = _f(anova, "Model", "sum_sq") / _f(anova, "Cor Total", "sum_sq")
    assert abs(r2 - fit["R2"]) < 0.005  # 2.10/2.32 = 0.905 vs 0.9044
    adj = 1 - (1 - fit["R2"]) * 28 / 19
    assert round(adj, 4) == fit["adj_R2"]


def test_pure_error_from_centre_runs(table, anova):
    c = np.sqrt(table.loc[table["run"] >= 25, "area_difference"].to_numpy())
    ss = float(((c - c.mean()) ** 2).sum())
    assert abs(ss - _f(anova, "Pure Error", "sum_sq")) <= 0.0005 + 0.001  # 0.0254 vs printed 0.025
    assert round(c.mean(), 2) == 0.90  # Eq. (5) intercept 0.90 ~ centre mean


# ----------------------------------------------------------------------------- Eq. (5)


def test_coefficient_table_is_eq_5(stage):
    c = pd.read_csv(PUB / "bbd_coefficients.csv", dtype=str)
    assert list(c.columns) == ["model", "term", "coded", "actual"]
    assert set(c["model"]) == {"reduced"}
    assert dict(zip(c["term"], c["coded"])) == PRINTED_COEF
    assert c["actual"].isna().all()
    drops = stage["printed"]["area_difference"]["reduced_drops"]
    full = SYMS + [f"{a}*{b}" for i, a in enumerate(SYMS) for b in SYMS[i + 1:]] + [f"{s}^2" for s in SYMS]
    assert sorted(set(full) - set(drops)) == sorted(REDUCED_TERMS)


def test_printed_coefficients_inside_rounding_range_of_table_4(table, coded):
    """Each printed Eq. (5) coefficient is reachable from Table 4 within its 0.01 rounding."""
    m = _model_matrix(coded, REDUCED_TERMS)
    w = np.linalg.pinv(m)
    y = table["area_difference"].to_numpy(float)
    lo, hi = np.sqrt(y - 0.005), np.sqrt(y + 0.005)
    for i, term in enumerate(["Intercept"] + REDUCED_TERMS):
        bmin = float(np.where(w[i] > 0, w[i] * lo, w[i] * hi).sum())
        bmax = float(np.where(w[i] > 0, w[i] * hi, w[i] * lo).sum())
        p = PRINTED_COEF[term]
        assert bmin - _half_unit(p) <= float(p) <= bmax + _half_unit(p), (term, bmin, bmax, p)


def test_ab_and_bc_differ_from_table_4_at_printed_precision(table, coded, cfg):
    """AB and BC of Eq. (5) do not round from the printed Table 4 (input rounding): recorded."""
    m = _model_matrix(coded, REDUCED_TERMS)
    b = np.linalg.lstsq(m, np.sqrt(table["area_difference"].to_numpy(float)), rcond=None)[0]
    est = dict(zip(["Intercept"] + REDUCED_TERMS, b))
    assert round(est["A*B"], 3) != 0.048 and round(est["B*C"], 3) != -0.072
    for t in ("Intercept", "A", "B", "C", "D", "B*D", "A^2", "B^2"):
        p = PRINTED_COEF[t]
        assert abs(est[t] - float(p)) <= _half_unit(p), t
    assert "AB = 0.048" in cfg["notes"] and "BC = -0.072" in cfg["notes"]


def test_printed_anova_is_the_nine_term_model(table, coded, stage):
    """Fit statistics of Table 5 belong to Eq. (5), not to the full 14-term quadratic."""
    y = np.sqrt(table["area_difference"].to_numpy(float))
    sst = float(((y - y.mean()) ** 2).sum())
    fit = stage["printed"]["area_difference"]["fit_reduced"]
    res = {}
    for name, terms in (("reduced", REDUCED_TERMS),
                        ("full", SYMS + [f"{a}*{b}" for i, a in enumerate(SYMS) for b in SYMS[i + 1:]]
                         + [f"{s}^2" for s in SYMS])):
        m = _model_matrix(coded, terms)
        r = y - m @ np.linalg.lstsq(m, y, rcond=None)[0]
        sse = float(r @ r)
        dfe = len(y) - m.shape[1]
        res[name] = (1 - sse / sst, 1 - (sse / dfe) / (sst / 28), 100 * math.sqrt(sse / dfe) / y.mean())
    r2, adj, cv = res["reduced"]
    assert abs(r2 - fit["R2"]) < 0.001 and abs(adj - fit["adj_R2"]) < 0.001
    assert round(cv, 2) == fit["CV_percent"]
    assert abs(res["full"][0] - fit["R2"]) > 0.005 and abs(res["full"][1] - fit["adj_R2"]) > 0.02


# ----------------------------------------------------------------------------- soilcal.rsm


def _coef_map(df: pd.DataFrame) -> dict:
    d = df.reset_index() if "term" not in df.columns else df
    col = next(c for c in ("coded", "coef", "estimate") if c in d.columns)
    return dict(zip(d["term"], d[col].astype(float)))


def test_rsm_recomputes_the_printed_reduced_model(table, coded, stage):
    from soilcal import rsm

    data = coded.copy()
    data["area_difference"] = table["area_difference"]
    low = np.array([-1.0] * 4)
    high = np.array([1.0] * 4)
    full = rsm.fit_response_surface(data, SYMS, "area_difference", low, high, transform="sqrt",
                                    data_coding="coded")
    red = rsm.drop_terms(full, stage["printed"]["area_difference"]["reduced_drops"])
    st = dict(red.fit_statistics())
    fit = stage["printed"]["area_difference"]["fit_reduced"]
    assert abs(st["R2"] - fit["R2"]) < 0.001
    assert abs(st["adj_R2"] - fit["adj_R2"]) < 0.001
    assert round(st["CV_percent"], 2) == fit["CV_percent"]
    est = _coef_map(red.coefficients())
    for t in ("Intercept", "A", "B", "C", "D", "B*D", "A^2", "B^2"):
        p = PRINTED_COEF[t]
        assert abs(est[t] - float(p)) <= _half_unit(p), t
    # Table 5 F values: within 3 % (Table 4 rounding propagates to about 1-3 % in F)
    a = red.anova()
    a = a.set_index("source") if "source" in a.columns else a
    printed = pd.read_csv(PUB / "bbd_anova_reduced.csv", dtype=str).set_index("source")
    for src in ("A", "B", "C", "D", "B*D", "A^2"):
        assert abs(float(a.loc[src, "F"]) / float(printed.loc[src, "F"]) - 1) < 0.03, src


# ----------------------------------------------------------------------------- measurements


@pytest.mark.parametrize("fname,col", [("static_friction_inclined_plane.csv", "static_friction"),
                                       ("rolling_friction_inclined_plane.csv", "rolling_friction")])
def test_inclined_plane_tables_1_2(fname, col):
    t = pd.read_csv(MEAS / fname, dtype=str)
    digits = len(t[col][0].split(".")[1])
    for ang, mu in zip(t["inclination_deg"], t[col]):
        assert round(math.tan(math.radians(float(ang))), digits) == float(mu)  # mu = tan(alpha)
    assert round(t[col].astype(float).mean(), digits) == float(t["mean"][0])


def test_eq_1_sin_cos_swap_is_recorded(cfg):
    assert "Eq. (1)" in cfg["notes"] and "cot" in cfg["notes"]


def test_traction_resistance_error():
    t = pd.read_csv(MEAS / "traction_resistance.csv")
    r = t.iloc[0]
    assert (r["measured_N"], r["simulated_N"]) == (1303.07, 1167.30)
    assert round(100 * (r["measured_N"] - r["simulated_N"]) / r["measured_N"], 1) == r["relative_error_percent"]


def test_area_difference_verification_repeats():
    y = pd.read_csv(MEAS / "area_difference_verification.csv")["area_difference"]
    assert list(y) == [0.29, 0.29, 0.32]
    assert round(y.mean(), 2) == 0.30 and round(y.std(ddof=1), 2) == 0.02  # Sec. 3.2.3


def test_furrow_polynomial_eq_3(cfg):
    poly = cfg["targets"]["furrow_profile"]["polynomial"]
    c = poly["coefficients"]
    assert len(c) == 10  # 9th degree
    assert c[0] == 7.28 and c[1] == -0.27 and c[9] == -5.04e-19
    t = pd.read_csv(MEAS / "furrow_profile_polynomial.csv")
    assert list(t["power"]) == list(range(10)) and list(t["coefficient"]) == c
    assert any("units" in m["item"] for m in cfg["missing"])


def test_particle_size_distribution_sums_to_100(cfg):
    bins = cfg["properties"]["particle_size_distribution"]["bins"]
    assert math.isclose(sum(b["percent"] for b in bins), 100.0)
