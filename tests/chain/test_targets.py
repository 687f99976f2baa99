"""The targets table of a soil (soilcal.chain.targets.targets_frame): printed value or photo
measurement, and what is said when neither exists."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from soilcal.chain.targets import COLUMNS, targets_frame, write_targets
from soilcal.config.load import load_soil
from soilcal.errors import InputError

ROOT = Path(__file__).resolve().parents[2]

SOIL = {
    "citation": {"title": "the papers the targets below come from"},
    "targets": {
        # a photo group and a printed value (cinnamon soil, Sec. 2.4: 27.69 deg)
        "stacking_angle": {"value": 27.69, "unit": "deg", "image": "stacking", "source": "Sec. 2.4"},
        # a printed measurement without photos (black soil, stage 1: 35.2 deg)
        "accumulation_angle": {"value": 35.2, "unit": "deg", "source": "Sec. 3.1.2"},
        # lost in extraction (guangxi, angle at 5 % moisture)
        "angle_mc05": {"value": None, "unit": "deg", "moisture_content": 5, "note": "Table 1 lost"},
        # a photo group with another measure and no printed value
        "slope": {"unit": "deg", "image": "side", "image_measure": "slope_deg", "layer": "upper"},
    }
}
MEAS = {"stacking": {"angle_deg": 28.4, "spread_deg": 0.7, "n_photos": 10},
        "side": {"slope_deg": 31.5, "angle_deg": 99.0, "n_frames": 4}}


def _by_id(df: pd.DataFrame) -> dict[str, dict]:
    return {r["target_id"]: r for r in df.to_dict("records")}


def test_published_source_uses_the_printed_values():
    df = targets_frame(SOIL, "published")
    assert list(df.columns) == COLUMNS
    r = _by_id(df)
    assert r["stacking_angle"]["value"] == 27.69 and r["stacking_angle"]["source"] == "printed"
    assert r["stacking_angle"]["printed_value"] == 27.69 and r["stacking_angle"]["image_group"] == "stacking"
    assert np.isnan(r["stacking_angle"]["image_value"])  # photos are not read for the published source
    assert r["stacking_angle"]["note"] == "Sec. 2.4"
    assert r["accumulation_angle"]["value"] == 35.2 and r["accumulation_angle"]["source"] == "printed"
    assert np.isnan(r["angle_mc05"]["value"]) and r["angle_mc05"]["source"] == "not available"
    assert r["angle_mc05"]["moisture_content"] == 5
    assert r["slope"]["source"] == "not available"


def test_dem_source_photo_replaces_the_printed_value():
    r = _by_id(targets_frame(SOIL, "dem", MEAS))
    s = r["stacking_angle"]
    assert s["value"] == 28.4 and s["source"] == "image" and s["image_value"] == 28.4
    assert s["printed_value"] == 27.69  # kept beside it
    assert s["image_spread"] == 0.7 and s["image_n"] == 10
    assert "stacking" in s["note"] and "printed 27.69" in s["note"]
    # image_measure chooses the key; n_frames when there is no n_photos
    sl = r["slope"]
    assert sl["value"] == 31.5 and sl["source"] == "image" and sl["image_n"] == 4
    assert np.isnan(sl["printed_value"]) and np.isnan(sl["image_spread"]) and sl["layer"] == "upper"
    assert "printed" not in sl["note"]
    # no photo group, a printed value: the paper's measurement
    a = r["accumulation_angle"]
    assert a["value"] == 35.2 and a["source"] == "measurement" and np.isnan(a["image_value"])
    # neither: NaN, not available, and why
    m = r["angle_mc05"]
    assert np.isnan(m["value"]) and m["source"] == "not available"
    assert "no photo group and no printed value" in m["note"] and "Table 1 lost" in m["note"]


def test_dem_source_missing_photo_group_is_named():
    with pytest.raises(InputError, match="stacking") as exc:
        targets_frame(SOIL, "dem", {"side": MEAS["side"]}, measurements_path="results/x/images/measurements.json")
    assert exc.value.field == "stacking.angle_deg"
    assert exc.value.path == "results/x/images/measurements.json"
    assert exc.value.got == ["side"]
    with pytest.raises(InputError, match="stacking"):
        targets_frame(SOIL, "dem", None)
    # the group is there but not the measure the target reads
    with pytest.raises(InputError) as exc:
        targets_frame(SOIL, "dem", {"stacking": MEAS["stacking"], "side": {"angle_deg": 30.0}})
    assert exc.value.field == "side.slope_deg" and exc.value.got == ["angle_deg"]


def test_shipped_soils_published_targets():
    cin = load_soil(ROOT / "config" / "soils" / "cinnamon-soil.yaml", ROOT / "resources").data
    r = _by_id(targets_frame(cin, "published"))
    assert r["stacking_angle"]["value"] == 27.69 and r["stacking_angle"]["source"] == "printed"
    gx = load_soil(ROOT / "config" / "soils" / "guangxi-cohesive.yaml", ROOT / "resources").data
    r = _by_id(targets_frame(gx, "published"))
    assert r["angle_mc00"]["value"] == 30.83 and r["angle_mc20"]["value"] == 37.13
    assert r["angle_mc05"]["source"] == "not available" and r["angle_mc15"]["source"] == "not available"


def test_write_targets_reads_the_measurements_json(tmp_path):
    mj = tmp_path / "measurements.json"
    mj.write_text(json.dumps(MEAS))
    out = tmp_path / "t" / "targets.csv"
    write_targets(SOIL, "dem", out, mj)
    df = pd.read_csv(out)
    assert list(df.columns) == COLUMNS
    assert df.set_index("target_id").loc["stacking_angle", "value"] == 28.4


def test_a_soil_without_a_citation_has_no_printed_values():
    # a soil of one's own: its 33.5 deg is its own measurement, and no column calls it printed
    own = {"targets": {"angle": {"value": 33.5, "unit": "deg"},
                       "pile": {"value": 30.0, "unit": "deg", "image": "stacking"}}}
    for source in ("published", "dem"):
        r = _by_id(targets_frame(own, source, MEAS))
        assert np.isnan(r["angle"]["printed_value"]) and np.isnan(r["pile"]["printed_value"])
        assert (r["angle"]["value"], r["angle"]["source"]) == (33.5, "measurement")
    r = _by_id(targets_frame(own, "dem", MEAS))
    assert (r["pile"]["value"], r["pile"]["source"]) == (28.4, "image")
    assert r["pile"]["note"] == "photo group stacking (angle_deg); the soil's own value 30"


def test_a_measured_target_s_sd_is_written_beside_its_value():
    # the soil's own drum angle, measured as 38.4 +/- 0.9 deg; a photo target's scatter is the
    # photos' own (image_spread), not the sd the soil gives beside another value
    own = {"targets": {"drum": {"value": 38.4, "sd": 0.9, "unit": "deg", "moisture_content": 0.12},
                       "bare": {"value": 40.0, "unit": "deg"},
                       "pile": {"value": 30.0, "sd": 2.0, "unit": "deg", "image": "stacking"}}}
    r = _by_id(targets_frame(own, "dem", MEAS))
    assert r["drum"]["sd"] == 0.9 and r["drum"]["value"] == 38.4
    assert np.isnan(r["bare"]["sd"])
    assert np.isnan(r["pile"]["sd"]) and r["pile"]["image_spread"] == 0.7


def test_a_target_s_moisture_is_written_with_its_unit():
    # a soil that gives its moistures as fractions: the target at 0.172 is 17.2 %, and the
    # file says which; a soil that gives no unit is in %, a target without a moisture has none
    frac = {"properties": {"moisture_content": {"values": [0.172, 0.215], "unit": "fraction"}},
            "targets": {"dry": {"value": 28.0, "unit": "deg", "moisture_content": 0.172},
                        "any": {"value": 30.0, "unit": "deg"}}}
    r = _by_id(targets_frame(frac, "dem"))
    assert (r["dry"]["moisture_content"], r["dry"]["moisture_unit"]) == (0.172, "fraction")
    assert r["any"]["moisture_unit"] == ""
    pct = {"properties": {"moisture_content": {"values": [17.2]}},
           "targets": {"dry": {"value": 28.0, "unit": "deg", "moisture_content": 17.2}}}
    assert _by_id(targets_frame(pct, "dem"))["dry"]["moisture_unit"] == "%"


def test_a_photo_target_names_the_heap_photos_its_group_set_aside():
    # 3 heap photos, one flagged low and set aside (measurements.json's set_aside): the value
    # and image_n are the 2 others', and the row says which photo was left out and where why
    meas = {**MEAS, "stacking": {"angle_deg": 28.4, "spread_deg": 0.7, "n_photos": 2,
                                 "set_aside": [{"path": "resources/images/x/heap_card.jpg",
                                                "reason": "two plate lines"}]}}
    s = _by_id(targets_frame(SOIL, "dem", meas, "results/x/images/measurements.json"))["stacking_angle"]
    assert s["value"] == 28.4 and s["image_n"] == 2
    assert "heap_card.jpg" in s["note"] and "set aside" in s["note"] and "measurements.json" in s["note"], s["note"]
    assert "printed 27.69" in s["note"]
    # a group with nothing set aside says nothing of it
    assert "set aside" not in _by_id(targets_frame(SOIL, "dem", MEAS))["stacking_angle"]["note"]


def test_a_photo_target_names_the_frames_the_user_accepted_though_flagged_low():
    # a drum frame flagged low that the user checked and accepted (accept_low) is in the value:
    # the row says so and where why it was flagged, beside the frames set aside
    meas = {**MEAS, "stacking": {"angle_deg": 28.4, "spread_deg": 0.7, "n_frames": 2,
                                 "set_aside": [{"path": "f/a.png", "reason": "jagged"}],
                                 "accepted_low": [{"path": "f/b.png", "reason": "short of the drum circle"}]}}
    s = _by_id(targets_frame(SOIL, "dem", meas, "results/x/images/measurements.json"))["stacking_angle"]
    assert "set aside as low, not in the value: a.png" in s["note"]
    assert "accepted by the user, in the value: b.png" in s["note"] and "accepted_low" in s["note"], s["note"]
    assert "accepted" not in _by_id(targets_frame(SOIL, "dem", MEAS))["stacking_angle"]["note"]
