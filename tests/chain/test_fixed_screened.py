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


def test_a_fixed_value_outside_the_screening_range_is_refused_at_start_up(vineyard, tmp_path):
    from soilcal.chain.derive import check_dem_stages
    from soilcal.errors import InputError

    d = copy.deepcopy(vineyard)
    check_dem_stages(tmp_path / "v.yaml", d)  # the paper's 10 MPa: the low end of 10-100 MPa
    # 5 MPa: the screening judged the shear modulus over 10-100 MPa only
    _stage(d, "bbd")["fixed"]["soil_shear_modulus"] = 5
    with pytest.raises(InputError) as ei:
        check_dem_stages(tmp_path / "v.yaml", d)
    assert ei.value.field == "stages.bbd.fixed.soil_shear_modulus" and ei.value.got == 5
    assert "10-100" in ei.value.expected


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
