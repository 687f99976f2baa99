"""Errata machinery: printed precision, internal consistency of printed ANOVA tables."""

from __future__ import annotations

import math

import pandas as pd
import pytest
from scipy import stats

from soilcal.chain.errata import Errata, anova_self_consistency, duplicated_sequences, parse_printed, plausibility


@pytest.mark.parametrize(
    "text, lo, hi",
    [("24.15", 24.145, 24.155), ("0.0002", 0.00015, 0.00025), ("2.10", 2.095, 2.105), ("-0.88", -0.885, -0.875),
     ("17", 16.5, 17.5), ("7.9e10", 7.85e10, 7.95e10)],
)
def test_printed_interval(text, lo, hi):
    p = parse_printed(text)
    assert p.lo == pytest.approx(lo) and p.hi == pytest.approx(hi)


def test_less_than_p_value():
    p = parse_printed("<0.0001")
    assert p.contains(3e-7) and not p.contains(0.0002)
    assert parse_printed("") is None and parse_printed(float("nan")) is None


def _table(rows):
    return pd.DataFrame(rows, columns=["source", "sum_sq", "df", "mean_sq", "F", "p"]).astype(str)


def _consistent_rows():
    # A table built from exact arithmetic: MS = SS/df, F = MS/MS_res, p = F survival function.
    ms_res = 0.5
    rows = [["A", "10.00", "1", "10.00", f"{10 / ms_res:.2f}", f"{stats.f.sf(20, 1, 6):.4f}"],
            ["B", "4.00", "1", "4.00", f"{4 / ms_res:.2f}", f"{stats.f.sf(8, 1, 6):.4f}"],
            ["Residual", "3.00", "6", "0.50", "", ""]]
    model = ["Model", "14.00", "2", "7.00", f"{7 / ms_res:.2f}", f"{stats.f.sf(14, 2, 6):.4f}"]
    return [model] + rows + [["Cor Total", "17.00", "8", "", "", ""]]


def test_consistent_table_has_no_errata():
    err = Errata()
    anova_self_consistency(err, "t", _table(_consistent_rows()), orthogonal=True)
    assert err.frame().empty


def test_each_kind_of_inconsistency_is_reported():
    rows = _consistent_rows()
    rows[1][3] = "11.00"  # A: MS != SS/df
    rows[2][4] = "9.50"  # B: F != MS/MS_res (true 8.00)
    rows[0][1] = "15.00"  # Model SS != A + B and Cor Total != Model + Residual
    err = Errata()
    anova_self_consistency(err, "t", _table(rows), orthogonal=True)
    f = err.frame()
    wheres = set(f["where"])
    assert "t / A / mean_sq" in wheres
    assert "t / B / F" in wheres
    assert "t / Model / sum_sq" in wheres
    assert "t / Cor Total / sum_sq" in wheres


def test_wrong_p_value_is_reported():
    rows = _consistent_rows()
    rows[1][5] = "0.0500"  # true p of F(1,6)=20 is 0.0042
    err = Errata()
    anova_self_consistency(err, "t", _table(rows))
    (row,) = err.frame().itertuples()
    assert row.where == "t / A / p" and math.isclose(float(row.recomputed), stats.f.sf(20, 1, 6), rel_tol=1e-5)


def test_implausible_modulus_and_copied_column():
    soil = {"properties": {"poisson_ratio": {"value": 0.311, "unit": "-", "source": "x"}},
            "materials": {"steel": {"shear_modulus": {"value": 7.9e10, "unit": "MPa", "source": "Sec. 3.1"}}},
            "parameters": {}, "stages": []}
    err = Errata()
    plausibility(err, soil)
    (row,) = err.frame().itertuples()
    assert row.where.startswith("materials.steel.shear_modulus") and "implausible" in row.note
    a = pd.DataFrame({"y": [1.0, 2.0, 3.0, 4.0, 5.0]})
    b = pd.DataFrame({"y": [9.0, 2.0, 3.0, 4.0, 5.0, 7.0]})
    err = Errata()
    duplicated_sequences(err, {"s1": ("T1", a, ["y"]), "s2": ("T2", b, ["y"])})
    assert len(err.frame()) == 1


def test_a_moisture_content_is_judged_in_its_declared_unit():
    """0.9 as a mass fraction (unit -) is 90 %, plausible; 15 with unit - (15 % meant, typed as
    a fraction) is 1500 %, beyond the 0-500 % a gravimetric moisture content of a real soil
    takes (a peat holds a few times its dry mass); 15 % is plausible."""
    def rows(q):
        err = Errata()
        plausibility(err, {"properties": {"moisture_content": q}, "parameters": {}, "stages": []})
        return list(err.frame().itertuples())

    assert rows({"value": 0.9, "unit": "-"}) == []
    assert rows({"value": 15, "unit": "%"}) == []
    (row,) = rows({"values": [0.12, 15], "unit": "-"})
    assert row.where.startswith("properties.moisture_content") and row.recomputed == "1500 %"
    assert "implausible moisture content" in row.note
    # the units the measurement tables take for a percentage are judged as percent too
    for unit in ("wt%", "percent", "% w/w"):
        (row,) = rows({"value": 650, "unit": unit})
        assert row.recomputed == "650 %", unit


def test_every_declared_moisture_is_judged_a_lone_range_end_too():
    """A moisture above 500 % of dry mass is implausible for any soil whichever field
    declares it: a range's low or high given alone (refused by the loader, but the errata read
    the file as printed) and a range end beside a plausible value."""
    def rows(q):
        err = Errata()
        plausibility(err, {"properties": {"moisture_content": q}, "parameters": {}, "stages": []})
        return [r.recomputed for r in err.frame().itertuples()]

    assert rows({"low": 650, "unit": "%"}) == ["650 %"]
    assert rows({"high": 650, "unit": "%"}) == ["650 %"]
    assert rows({"low": 25, "unit": "fraction"}) == ["2500 %"]
    assert rows({"value": 17.2, "low": 650, "unit": "%"}) == ["650 %"]
    assert rows({"values": [0.172, 0.215], "low": 0.1, "high": 6.5, "unit": "fraction"}) == ["650 %"]
