"""A derived stage's explicit fixed value of a screened factor is the value its runs take.

The vineyard soil's paper held the soil shear modulus, a factor its screening found not
significant, at 10 MPa (the low end of its 10-100 MPa screening range) in the steepest ascent
and the Box-Behnken design, and the soil config says so (``stages.steepest.fixed`` and
``stages.bbd.fixed``).  Before, the DEM recipe replaced that value by the centre of the
screening range, 55 MPa, in both stages and nothing recorded it.  Now the stage's own value
holds, ``derivation.fixed`` of ``stage.json`` gives each fixed value with where it comes
from, and a fixed value the derived design cannot honour (the DEM screening selected the
factor for the path) is listed in ``derivation.fixed_not_used``.  No DEM run: the screening
effects and the path responses are frames built by hand."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from soilcal.chain.derive import bbd_from_path, path_from_screening
from soilcal.config.load import load_soil

ROOT = Path(__file__).resolve().parents[2]
SYMS = "ABCDEFGH"


@pytest.fixture(scope="module")
def vineyard():
    return load_soil(ROOT / "config/soils/xinjiang-vineyard.yaml", ROOT / "resources").data


def _stage(d, sid):
    return next(s for s in d["stages"] if s["id"] == sid)


def _effects(significant):
    """Screening effects of both responses: the ``significant`` symbols at p = 0.001 with a
    positive coefficient, the others at p = 0.6."""
    rows = []
    for rid in ("static_angle", "dynamic_angle"):
        for t in SYMS:
            sig = t in significant
            rows.append({"response": rid, "term": t, "coefficient": 2.0 if sig else 0.1,
                         "effect": 4.0 if sig else 0.2, "p": 0.001 if sig else 0.6})
    return pd.DataFrame(rows)


def _targets(d):
    return {tid: {"value": t.get("value")} for tid, t in d["targets"].items()}


# mean of the screening runs well below the layer targets (about 31-46 deg): the path ascends
PB_RUNS = pd.DataFrame({"static_angle": [25.0, 26.0], "dynamic_angle": [35.0, 36.0]})


def test_a_non_significant_factor_is_held_at_the_stage_s_fixed_value(vineyard):
    d = copy.deepcopy(vineyard)
    path = path_from_screening(d, "steepest", _stage(d, "pb"), _effects("BDFH"), PB_RUNS, _targets(d))
    path["id"] = "steepest"
    assert sorted(f["screening_symbol"] for f in path["factors"].values()) == list("BDFH")
    # the paper's 10 MPa (stages.steepest.fixed), not the 55 MPa centre of 10-100 MPa
    assert path["fixed"]["soil_shear_modulus"] == 10
    rec = path["derivation"]["fixed"]["soil_shear_modulus"]
    assert rec["value"] == 10
    assert "stages.steepest.fixed.soil_shear_modulus" in rec["origin"] and "55" in rec["origin"]
    # every fixed value has its origin recorded
    assert set(path["derivation"]["fixed"]) == set(path["fixed"])
    assert "fixed_not_used" not in path["derivation"]

    steps = pd.DataFrame({"step": np.arange(1, 7), "static_angle": [26.0, 29.0, 31.0, 33.0, 35.0, 37.0],
                          "dynamic_angle": [38.0, 41.0, 43.0, 45.0, 47.0, 49.0]})
    bbd = bbd_from_path(d, "bbd", path, steps)
    assert bbd["fixed"]["soil_shear_modulus"] == 10
    assert "stages.bbd.fixed.soil_shear_modulus" in bbd["derivation"]["fixed"]["soil_shear_modulus"]["origin"]
    assert set(bbd["derivation"]["fixed"]) == set(bbd["fixed"])


def test_a_screened_factor_the_stage_does_not_fix_is_held_at_its_centre(vineyard):
    d = copy.deepcopy(vineyard)
    del _stage(d, "steepest")["fixed"]["soil_shear_modulus"]
    path = path_from_screening(d, "steepest", _stage(d, "pb"), _effects("BDFH"), PB_RUNS, _targets(d))
    assert path["fixed"]["soil_shear_modulus"] == pytest.approx((10 + 100) / 2)
    assert "centre" in path["derivation"]["fixed"]["soil_shear_modulus"]["origin"]


def test_a_fixed_value_of_a_factor_the_screening_selects_is_reported_not_used(vineyard):
    d = copy.deepcopy(vineyard)
    # the DEM screening finds the shear modulus significant: the path varies it
    path = path_from_screening(d, "steepest", _stage(d, "pb"), _effects("ADFH"), PB_RUNS, _targets(d))
    varied = {f["parameter"] for f in path["factors"].values()}
    assert "soil_shear_modulus" in varied and "soil_shear_modulus" not in path["fixed"]
    nu = path["derivation"]["fixed_not_used"]["soil_shear_modulus"]
    assert nu["value"] == 10 and "stages.steepest.fixed.soil_shear_modulus" in nu["why"]


def _path(d, significant="BDFH"):
    path = path_from_screening(d, "steepest", _stage(d, "pb"), _effects(significant), PB_RUNS, _targets(d))
    path["id"] = "steepest"
    return path


@pytest.mark.parametrize("mode", ["recipe", "printed", "adaptive"])
def test_a_fixed_value_outside_the_screening_range_runs_with_a_warning_in_every_design_mode(vineyard, mode):
    """5 MPa, below the 10-100 MPa over which the screening (stage pb, factor A) judged the shear
    modulus: start-up accepts it in every mode, the stage runs it, and derivation.fixed records
    it with an origin saying it lies outside 10..100 MPa, the warning the design job logs."""
    from soilcal.chain import adaptive
    from soilcal.chain.derive import check_dem_stages, dem_stage

    d = copy.deepcopy(vineyard)
    d["simulation"]["design"] = mode
    for sid in ("steepest", "bbd"):
        _stage(d, sid)["fixed"]["soil_shear_modulus"] = 5
    check_dem_stages("v.yaml", d)  # no refusal
    if mode == "recipe":
        st = _path(d)
    elif mode == "printed":
        st = dem_stage(d, "bbd", _targets(d))
    else:
        st = adaptive.stage_for(d, "bbd")
    assert st["fixed"]["soil_shear_modulus"] == 5
    rec = st["derivation"]["fixed"]["soil_shear_modulus"]
    assert rec["value"] == 5
    for text in (rec["origin"], rec["warning"]):
        assert "outside the screening range 10..100 MPa" in text and "factor A" in text and "stage pb" in text
    assert f"stages.{st['id']}.fixed.soil_shear_modulus = 5" in rec["warning"]
    # every fixed value the stage runs has its origin recorded (the adaptive stage too)
    assert set(st["derivation"]["fixed"]) == set(st["fixed"])
    # inside the range (the paper's 10 MPa, the low end): no warning
    assert "warning" not in _path(copy.deepcopy(vineyard))["derivation"]["fixed"]["soil_shear_modulus"]


def test_a_value_the_screening_selects_gets_no_range_warning(vineyard):
    d = copy.deepcopy(vineyard)
    _stage(d, "steepest")["fixed"]["soil_shear_modulus"] = 5
    path = _path(d, "ADFH")  # the path varies the shear modulus: 5 MPa is not used
    assert "soil_shear_modulus" not in path["derivation"]["fixed"]
    assert "outside" not in path["derivation"]["fixed_not_used"]["soil_shear_modulus"]["why"]


def _alias(d, value):
    """The shear modulus given a second id in Pa, which the derived stages fix instead."""
    d["parameters"]["soil_G_pa"] = {"name": "G in Pa", "unit": "Pa", "pair": "soil", "kind": "shear_modulus"}
    for sid in ("steepest", "bbd"):
        del _stage(d, sid)["fixed"]["soil_shear_modulus"]
        _stage(d, sid)["fixed"]["soil_G_pa"] = value


def test_a_fixed_value_under_another_id_of_the_same_dem_parameter_replaces_the_centre(vineyard):
    from soilcal.chain.sources import point_spec

    soil = load_soil(ROOT / "config/soils/xinjiang-vineyard.yaml", ROOT / "resources")
    d = copy.deepcopy(soil.data)
    _alias(d, 1.0e9)  # 1000 MPa, outside the 10-100 MPa screening range
    path = _path(d)
    # one value of the DEM shear modulus: the stage's soil_G_pa, not also the 55 MPa centre
    assert "soil_shear_modulus" not in path["fixed"] and path["fixed"]["soil_G_pa"] == 1.0e9
    rec = path["derivation"]["fixed"]
    assert set(rec) == set(path["fixed"]) and rec["soil_G_pa"]["value"] == 1.0e9
    assert "over soil_shear_modulus = 55 MPa" in rec["soil_G_pa"]["origin"]
    # the range in the unit of soil_G_pa: 10-100 MPa = 1e7-1e8 Pa
    assert "outside the screening range 1e+07..1e+08 Pa" in rec["soil_G_pa"]["warning"]
    soil.data = d
    levels = {s: f["levels"][0] for s, f in path["factors"].items()}
    assert point_spec(soil, path, levels, 1, 1)["params"]["soil_shear_modulus"] == 1.0e9
    # at the range's high end, 100 MPa written in Pa: inside
    d2 = copy.deepcopy(vineyard)
    _alias(d2, 1.0e8)
    assert "warning" not in _path(d2)["derivation"]["fixed"]["soil_G_pa"]


def test_a_fixed_value_under_another_id_of_a_factor_the_path_varies_is_not_used(vineyard):
    d = copy.deepcopy(vineyard)
    _alias(d, 1.0e7)
    path = _path(d, "ADFH")  # the path walks soil_shear_modulus over 10-100 MPa
    assert "soil_G_pa" not in path["fixed"] and "soil_G_pa" not in path["derivation"]["fixed"]
    nu = path["derivation"]["fixed_not_used"]["soil_G_pa"]
    assert nu["value"] == 1.0e7 and "varies soil_shear_modulus" in nu["why"]


def test_an_earlier_optimum_replaces_a_value_under_another_id_of_the_same_dem_parameter():
    from soilcal.chain.derive import dem_stage

    d = copy.deepcopy(load_soil(ROOT / "config/soils/black-soil.yaml", ROOT / "resources").data)
    # stage 2 gives the soil-soil static friction under a second id; stage 1 varies it (x3)
    d["parameters"]["soil_soil_mu"] = {"name": "mu", "unit": "-", "pair": "soil-soil", "kind": "static_friction"}
    fixed = _stage(d, "soil-65mn")["fixed"]
    fixed["soil_soil_mu"] = fixed.pop("soil_soil_static_friction")
    upstream = dem_stage(d, "soil-soil", _targets(d))
    optimum = pd.DataFrame({"case": ["accumulation_angle"], "x1": [0.52], "x2": [0.41], "x3": [0.72],
                            "x4": [0.19], "calibrated": [True]})
    st = dem_stage(d, "soil-65mn", _targets(d), {"fixed_from": {"stage": upstream, "optimum": optimum}})
    # the DEM optimum's 0.72 is the one value of the soil-soil static friction
    assert st["fixed"]["soil_soil_static_friction"] == 0.72 and "soil_soil_mu" not in st["fixed"]
    assert "soil_soil_mu" not in st["derivation"]["fixed"]
    assert "soil_soil_mu = 0.65" in st["derivation"]["fixed"]["soil_soil_static_friction"]["origin"]


def test_a_box_behnken_value_over_the_path_s_names_the_value_it_replaces(vineyard):
    d = copy.deepcopy(vineyard)
    _stage(d, "bbd")["fixed"]["soil_shear_modulus"] = 20  # the path holds 10 MPa
    path = path_from_screening(d, "steepest", _stage(d, "pb"), _effects("BDFH"), PB_RUNS, _targets(d))
    path["id"] = "steepest"
    steps = pd.DataFrame({"step": np.arange(1, 7), "static_angle": [26.0, 29.0, 31.0, 33.0, 35.0, 37.0],
                          "dynamic_angle": [38.0, 41.0, 43.0, 45.0, 47.0, 49.0]})
    bbd = bbd_from_path(d, "bbd", path, steps)
    assert bbd["fixed"]["soil_shear_modulus"] == 20
    origin = bbd["derivation"]["fixed"]["soil_shear_modulus"]["origin"]
    assert "stages.bbd.fixed.soil_shear_modulus" in origin and "over 10" in origin


def test_the_adaptive_stage_job_logs_each_fixed_value_and_the_range_warning(vineyard, tmp_path):
    import json

    from soilcal.chain import adaptive

    d = copy.deepcopy(vineyard)
    d["simulation"]["design"] = "adaptive"
    _stage(d, "bbd")["fixed"]["soil_shear_modulus"] = 5
    path = tmp_path / "stage.json"
    path.write_text(json.dumps(adaptive.stage_for(d, "bbd")))
    lines = adaptive.stage_log_lines(path)
    assert any(ln.startswith("fixed: soil_shear_modulus = 5: stages.bbd.fixed.soil_shear_modulus") for ln in lines)
    assert [ln for ln in lines if ln.startswith("warning:")] == [
        ln for ln in lines if ln.startswith("warning: stages.bbd.fixed.soil_shear_modulus = 5 lies outside "
                                            "the screening range 10..100 MPa")]
    assert sum(ln.startswith("warning:") for ln in lines) == 1


def test_the_design_job_reports_the_range_warning(vineyard, tmp_path):
    """write_stage_design's report, which the design job's log prints line by line."""
    from soilcal.chain.files import write_stage_design

    d = copy.deepcopy(vineyard)
    d["simulation"]["design"] = "printed"
    _stage(d, "bbd")["fixed"]["soil_shear_modulus"] = 5
    tcsv = tmp_path / "targets.csv"
    pd.DataFrame([{"target_id": tid, "value": t.get("value"), "unit": t.get("unit"), "source": "printed"}
                  for tid, t in d["targets"].items()]).to_csv(tcsv, index=False)
    out = {"stage": tmp_path / "stage.json", "design": tmp_path / "design.csv", "check": tmp_path / "check.csv"}
    info = write_stage_design("dem", _stage(d, "bbd"), d, {"targets": tcsv}, out)
    assert len(info["fixed_warnings"]) == 1
    assert info["fixed_warnings"][0].startswith("stages.bbd.fixed.soil_shear_modulus = 5 lies outside the "
                                                "screening range 10..100 MPa")
