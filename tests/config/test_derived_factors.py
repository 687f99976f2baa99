"""A soil of one's own calibrated by the DEM recipe declares its screening's factor ranges
only: the steepest-ascent and Box-Behnken stages that follow it may leave out ``factors``, and
the recipe derives them from the DEM results (soilcal.chain.derive).

The soil is the cinnamon soil with its path and Box-Behnken stages stripped of what the paper
printed for them (factors, tables, printed results).  No DEM run: the screening effects and the
path's responses are frames built by hand, and every expected level is reasoned out beside its
assertion from the screening ranges of Table 2 (Qiu et al. 2022, quoted in the soil config)."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from soilcal.chain.derive import bbd_from_path, dem_stage_ids, path_from_screening
from soilcal.config import design_runs, load_soil
from soilcal.errors import InputError

ROOT = Path(__file__).resolve().parents[2]
SOIL = "cinnamon-soil"
TARGET = 27.69  # Sec. 2.4, the measured stacking angle (targets.stacking_angle)


def _own(data: dict) -> dict:
    """The soil with nothing of the paper's path and Box-Behnken stages but their ids, kinds,
    links, responses and optimisation goals."""
    d = copy.deepcopy(data)
    for st in d["stages"]:
        if st["kind"] == "plackett_burman":
            continue
        for key in ("factors", "table", "table_coding", "printed", "chosen_step", "fixed", "title", "source"):
            st.pop(key, None)
        for case in (st.get("optimise") or {}).get("cases", []):
            for key in ("printed_optimum", "printed_verification"):
                case.pop(key, None)
    return d


@pytest.fixture(scope="module")
def raw() -> dict:
    return yaml.safe_load((ROOT / "config" / "soils" / f"{SOIL}.yaml").read_text())


def _load(tmp_path: Path, data: dict):
    p = tmp_path / f"{SOIL}.yaml"
    p.write_text(yaml.safe_dump(data, sort_keys=False))
    return load_soil(p, ROOT / "resources")


def _effects(p: dict[str, float], b: dict[str, float]) -> pd.DataFrame:
    rows = [{"response": "stacking_angle", "term": t, "effect": 2 * b[t], "coefficient": b[t], "p": p[t]} for t in p]
    return pd.DataFrame(rows)


def test_the_derived_stages_load_without_factors(tmp_path, raw):
    soil = _load(tmp_path, _own(raw))
    path, bbd = soil.stage("steepest"), soil.stage("bbd")
    assert path["factors"] == {} and bbd["factors"] == {}
    # their runs are known once the recipe has derived them
    assert design_runs(path) is None and design_runs(bbd) is None
    assert design_runs(soil.stage("pb")) == 12
    assert dem_stage_ids(soil.data) == ["pb", "steepest", "bbd"]


def test_the_path_and_the_design_follow_the_screening_alone(tmp_path, raw):
    data = _load(tmp_path, _own(raw)).data
    pb = next(s for s in data["stages"] if s["id"] == "pb")
    # four factors significant; with no path factors declared the path takes the three that a
    # Box-Behnken design needs (simulation.screening.min_factors, 3), by rank of p: X3, X7, X1
    p = {"X1": 0.004, "X2": 0.34, "X3": 0.001, "X4": 0.22, "X5": 0.03, "X6": 0.88, "X7": 0.002}
    b = {"X1": 1.0, "X2": -0.7, "X3": 4.0, "X4": 0.9, "X5": 1.5, "X6": 0.1, "X7": 2.0}
    resp = pd.DataFrame({"stacking_angle": [24.0, 26.0, 24.5, 25.5]})  # mean 25 < 27.69: climb
    targets = {"stacking_angle": {"value": TARGET, "source": "printed"}}
    st = path_from_screening(data, "steepest", pb, _effects(p, b), resp, targets)
    # no paper symbols to keep: each factor keeps its screening symbol
    assert list(st["factors"]) == ["X3", "X7", "X1"]
    # six steps (no printed path to count them from) over each screening range (Table 2),
    # low to high as every effect is positive and the mean lies below the target
    assert st["factors"]["X3"]["levels"] == [0.05, 0.08, 0.11, 0.14, 0.17, 0.2]
    assert st["factors"]["X7"]["levels"] == [0.1, 0.24, 0.38, 0.52, 0.66, 0.8]
    assert st["factors"]["X1"]["levels"] == [0.15, 0.27, 0.39, 0.51, 0.63, 0.75]
    # X5, significant but fourth, and the others at the centres of their ranges
    assert st["fixed"]["soil_steel_static_friction"] == pytest.approx((0.3 + 0.9) / 2, abs=1e-12)
    assert st["fixed"]["soil_soil_static_friction"] == pytest.approx((0.2 + 0.92) / 2, abs=1e-12)
    assert st["derivation"]["paper_factors"] == {}
    # the Box-Behnken design centred on the step closest to the target, 27.5 at step 3
    st["id"] = "steepest"
    path_resp = pd.DataFrame({"step": np.arange(1, 7), "stacking_angle": [22.0, 24.5, 27.5, 29.0, 31.0, 33.0]})
    bbd = bbd_from_path(data, "bbd", st, path_resp)
    expected = {"X3": (0.08, 0.11, 0.14), "X7": (0.24, 0.38, 0.52), "X1": (0.27, 0.39, 0.51)}
    assert list(bbd["factors"]) == list(expected)
    for s, levels in expected.items():
        f = bbd["factors"][s]
        assert (f["low"], f["centre"], f["high"]) == pytest.approx(levels, abs=1e-12)
    assert bbd["runs"] == 2 * 3 * 2 + 5  # the stage's 5 centre points
    assert "printed_optimum" not in bbd["optimise"]["cases"][0]


@pytest.mark.parametrize("change, field", [
    # a screening has no earlier DEM results to derive its factors from
    (lambda d: d["stages"][0].pop("factors"), "stages[0].factors"),
    # a Box-Behnken stage is derived from a path, not from a screening
    (lambda d: d["stages"][2].update(from_stage="pb"), "stages[2].factors"),
    # a stage with a printed table is replayed on its own factors
    (lambda d: d["stages"][2].update(table="bbd.csv"), "stages[2].factors"),
])
def test_a_stage_the_recipe_cannot_derive_needs_its_factors(tmp_path, raw, change, field):
    data = _own(raw)
    change(data)
    with pytest.raises(InputError) as e:
        _load(tmp_path, data)
    assert e.value.field == field and "DEM recipe" in e.value.expected


@pytest.mark.parametrize("sim, field", [
    ({"design": "printed"}, "stages.steepest.factors"),
    ({"design": "adaptive"}, "stages.bbd.factors"),
    # the path is not simulated: the Box-Behnken stage would run its own levels
    ({"stages": ["pb", "bbd"]}, "stages.bbd.factors"),
])
def test_a_design_that_runs_the_stages_own_levels_needs_its_factors(tmp_path, raw, sim, field):
    data = _own(raw)
    data["simulation"].update(sim)
    with pytest.raises(InputError) as e:
        _load(tmp_path, data)
    assert e.value.field == field and str(tmp_path / f"{SOIL}.yaml") in str(e.value)


def test_the_workflow_plans_the_screening_of_both_sources_and_no_published_derived_stage(tmp_path, raw):
    """A dry run of the workflow (``source: both``): the screening is designed for both sources;
    the stages left to the recipe have no published design (nothing to replay) and wait for
    the DEM screening (checkpoints), and no job reads a printed table of theirs."""
    from wfutil import copy_workflow, planned_jobs

    tmp = copy_workflow(tmp_path, [SOIL])
    data = _own(raw)
    data["source"] = "both"
    (tmp / "config/soils" / f"{SOIL}.yaml").write_text(yaml.safe_dump(data, sort_keys=False))
    jobs = [f for out in planned_jobs(tmp) for f in out.split(", ")]
    d = f"results/{SOIL}"
    assert f"{d}/published/pb/design.csv" in jobs and f"{d}/dem/pb/design.csv" in jobs
    assert not [j for j in jobs if j.startswith((f"{d}/published/steepest", f"{d}/published/bbd"))]
