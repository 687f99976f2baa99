"""Guangxi cohesive soil (Wei et al., PLOS ONE, doi 10.1371/journal.pone.0340462): encoded data
against the numbers quoted in the paper's text (its Tables 1-13 were lost in extraction).

Checks use the identities of a least-squares ANOVA: adj R^2 = 1 - (1 - R^2)(n - 1)/(n - p - 1);
for an orthogonal two-level screening design with 1 df per factor, SS_model = sum SS_i, hence
F_model = mean of the factor F values; p = P(F(df1, df2) > F) (scipy.stats.f).
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
from soilcal.config import design_runs, load_soil

ROOT = Path(__file__).resolve().parents[2]
CFG = ROOT / "config" / "soils" / "guangxi-cohesive.yaml"
PUB = ROOT / "resources" / "published" / "guangxi-cohesive"
MEAS = ROOT / "resources" / "measurements" / "guangxi-cohesive"
SCHEMA = ROOT / "src" / "soilcal" / "config" / "soil.schema.yaml"

MOISTURE = [0, 5, 10, 15, 20]


@pytest.fixture(scope="module")
def cfg():
    return yaml.safe_load(CFG.read_text())


@pytest.fixture(scope="module")
def bbd(cfg):
    return next(s for s in cfg["stages"] if s["id"] == "bbd")


def _missing(cfg, word):
    return [m for m in cfg["missing"] if word in m["where"]]


def test_config_validates_against_schema(cfg):
    jsonschema.Draft202012Validator(yaml.safe_load(SCHEMA.read_text())).validate(cfg)


def test_config_loads():
    assert load_soil(CFG, ROOT / "resources").name == "guangxi-cohesive"


# ----------------------------------------------------------------------------- BBD (Sec. 3.3)


def test_bbd_levels_are_climbing_steps_2_to_4(bbd):
    f = bbd["factors"]
    assert list(f) == ["A", "B", "G"]
    assert (f["A"]["low"], f["A"]["centre"], f["A"]["high"]) == (0.27, 0.33, 0.39)
    assert (f["B"]["low"], f["B"]["centre"], f["B"]["high"]) == (0.392, 0.488, 0.584)
    assert (f["G"]["low"], f["G"]["centre"], f["G"]["high"]) == (0.04, 0.06, 0.08)
    for x in f.values():  # equal climbing steps: the centre is the midpoint
        assert math.isclose(x["centre"], (x["low"] + x["high"]) / 2)


def test_bbd_is_17_runs_with_table_lost(bbd, cfg):
    assert bbd["runs"] == 17 == design_runs(bbd) == len(doe.box_behnken(3, bbd["center_points"]))
    assert bbd["center_points"] == 5
    assert bbd["table"] is None
    assert _missing(cfg, "Table 8")


def test_bbd_adj_r2_follows_from_r2_for_full_quadratic(bbd):
    fit = bbd["printed"]["angle_of_repose"]["fit_full"]
    n, p = 17, 9
    assert round(1 - (1 - fit["R2"]) * (n - 1) / (n - p - 1), 4) == fit["adj_R2"]


def test_bbd_printed_anova_cells(bbd):
    a = pd.read_csv(PUB / bbd["printed"]["angle_of_repose"]["anova_full"], dtype=str).set_index("source")
    assert list(a.columns) == ["sum_sq", "df", "mean_sq", "F", "p", "significance"]
    assert a.loc["Model", "p"] == "<0.0001"
    assert a.loc["Lack of Fit", "p"] == "0.2104"
    assert a.loc["G^2", "p"] == "0.0005"
    assert a.loc["Pure Error", "sum_sq"] == "0.7595"
    assert a["df"].isna().all()  # Table 9 lost: no df printed


def test_pso_settings_and_contradiction(bbd, cfg):
    opt = bbd["optimise"]
    assert opt["method"] == "pso"
    assert opt["pso"] == {"particles": 50, "iterations": 200}
    text = bbd["note"] + cfg["notes"]
    assert "100 particles" in text and "1000 iterations" in text  # the other printed setting
    assert "0.00042287" in cfg["notes"] and 0.00042287 > 1e-5  # 'stable error ... < 1e-5' is false
    # PSO bounds (Sec. 3.5) = BBD ranges
    for sym, lo, hi in (("A", 0.27, 0.39), ("B", 0.392, 0.584), ("G", 0.04, 0.08)):
        assert (bbd["factors"][sym]["low"], bbd["factors"][sym]["high"]) == (lo, hi)


# ----------------------------------------------------------------------------- targets


def test_one_case_per_moisture_content(bbd, cfg):
    cases = bbd["optimise"]["cases"]
    assert [c["id"] for c in cases] == [f"mc{m:02d}" for m in MOISTURE]
    for c, m in zip(cases, MOISTURE):
        tid = c["goals"]["angle_of_repose"]["target"]
        assert c["goals"]["angle_of_repose"]["goal"] == "target"
        assert cfg["targets"][tid]["moisture_content"] == m


def test_target_angles_as_printed(cfg):
    v = {m: cfg["targets"][f"angle_mc{m:02d}"]["value"] for m in MOISTURE}
    assert v == {0: 30.83, 5: None, 10: 31.97, 15: None, 20: 37.13}
    printed = [x for x in v.values() if x is not None]
    assert printed == sorted(printed)  # 'angle of repose increases with moisture content'
    assert _missing(cfg, "Table 1")


def test_measured_angle_csv_matches_targets(cfg):
    t = pd.read_csv(MEAS / "angle_of_repose_vs_moisture.csv")
    assert list(t["moisture_content"]) == MOISTURE
    for m, a in zip(t["moisture_content"], t["angle_deg"]):
        tv = cfg["targets"][f"angle_mc{m:02d}"]["value"]
        assert (tv is None and np.isnan(a)) or a == tv


def test_dry_density_csv_matches_properties(cfg):
    t = pd.read_csv(MEAS / "dry_density_vs_moisture.csv")
    assert list(t["moisture_content"]) == cfg["properties"]["moisture_content"]["values"] == MOISTURE
    assert list(t["dry_density_kg_m3"]) == cfg["properties"]["dry_density"]["values"] == [2384, 1980, 1802, 1653, 1527]


def test_model_gradation_sums_to_100(cfg):
    bins = cfg["properties"]["particle_size_distribution"]["bins"]
    assert [b["percent"] for b in bins] == [14, 14, 22, 50]
    assert sum(b["percent"] for b in bins) == 100


# ----------------------------------------------------------------------------- PB (Sec. 3.1)


@pytest.fixture(scope="module")
def pb():
    return pd.read_csv(PUB / "pb_effects.csv", dtype=str).set_index("source")


def test_pb_model_p_from_f(pb):
    # 12 runs, 7 factors with 1 df each -> residual df 4
    p = stats.f.sf(float(pb.loc["Model", "F"]), 7, 12 - 1 - 7)
    assert round(p, 4) == float(pb.loc["Model", "p"]) == 0.0132


@pytest.mark.parametrize("src", ["A", "B", "C", "D", "G"])
def test_pb_factor_significance_from_f(pb, src):
    p = stats.f.sf(float(pb.loc[src, "F"]), 1, 4)
    bound = pb.loc[src, "p"]
    assert (p < float(bound[1:])) if bound.startswith("<") else (p > float(bound[1:]))


def test_pb_t_limit_is_2_77():
    assert math.floor(stats.t.isf(0.025, 4) * 100) / 100 == 2.77  # 'values above 2.77'


def test_pb_unprinted_factors_leave_room_consistent_with_model_f(pb):
    """F_model = mean of the 7 factor F values; E and F must fill the rest, each insignificant."""
    f = {s: float(pb.loc[s, "F"]) for s in "ABCDG"}
    rest = 7 * float(pb.loc["Model", "F"]) - sum(f.values())
    assert round(rest, 2) == 7.40
    fcrit = stats.f.isf(0.05, 1, 4)
    assert 0 <= rest <= 2 * fcrit  # two insignificant F values (< 7.71 each) can sum to 7.40


def test_pb_a_contradiction_recorded(pb, cfg):
    assert pb.loc["A", "F"] == "8.31"  # Sec. 3.1
    assert "8.31" in cfg["notes"] and "8.44" in cfg["notes"]  # Sec. 3.8 prints 8.44


# ----------------------------------------------------------------------------- optimisation errors


def test_quoted_optimisation_errors():
    t = pd.read_csv(PUB / "optimisation_errors.csv")
    e = {(r.moisture_content, r.method): r.error_percent for r in t.itertuples()}
    assert e[(0, "pso")] < e[(0, "desirability")]  # 0.62 < 1.45
    assert e[(15, "pso")] < e[(15, "desirability")]  # 2.16 < 2.37
    assert max(v for (m, k), v in e.items() if k == "pso") <= 2.2  # abstract: PSO within 2.2 %
    assert e[(10, "desirability")] == 0.12


def test_bbd_10_percent_error_contradiction_recorded(cfg):
    assert "0.12 %" in cfg["notes"] and "0.10 %" in cfg["notes"]


def test_particle_mass_error_figures(cfg):
    # Sec. 3.6: 2.8 % and 2.14 % use different denominators; recorded in notes
    assert round(100 * (32.2 - 31.3) / 32.2, 1) == 2.8
    assert round(100 * (32.2 - 31.3) / 31.3, 1) != 2.8
    assert round(100 * (31.97 - 31.3) / 31.3, 2) == 2.14
    assert "2.14" in cfg["notes"] and "2.8" in cfg["notes"]


def test_every_lost_table_is_listed_missing(cfg):
    wheres = " ".join(m["where"] for m in cfg["missing"])
    for t in range(1, 14):
        assert f"Table {t}" in wheres, t
