"""A derived stage's own fixed values hold in the runs the DEM recipe lays out for it.

The recipe decides the parameters the path and the Box-Behnken design vary; every other
parameter is the soil's to fix, stage by stage, as the stage's config says (a screened factor
the stage does not fix is held at the centre of its screening range).  Before, the path took the
screening's fixed value over its own and the Box-Behnken stage dropped its own fixed block,
so its runs took the path's value, or the engine's base value (another soil's) for a
parameter only it fixed.  No DEM run here: the screening effects and path responses are
frames built by hand (tests/chain/test_derive.py)."""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from soilcal.chain.derive import bbd_from_path, path_from_screening
from soilcal.config.load import load_soil

ROOT = Path(__file__).resolve().parents[2]
# X3, X5, X7 significant (p < 0.05); the other four not (tests/chain/test_derive.py)
P_SIG = {"X1": 0.45, "X2": 0.34, "X3": 0.001, "X4": 0.22, "X5": 0.03, "X6": 0.88, "X7": 0.01}
B_SIG = {"X1": 0.5, "X2": -0.7, "X3": 4.0, "X4": 0.9, "X5": 1.5, "X6": 0.1, "X7": 2.0}


def _stage(d, sid):
    return next(s for s in d["stages"] if s["id"] == sid)


def test_a_derived_stage_keeps_its_own_fixed_values():
    d = copy.deepcopy(load_soil(ROOT / "config/soils/cinnamon-soil.yaml", ROOT / "resources").data)
    # two parameters no stage varies: a soil-steel adhesion fixed by every stage, each at its
    # own value, and a soil-soil plasticity only the Box-Behnken stage fixes
    d["parameters"]["adhesion"] = {"name": "Soil-steel surface energy", "unit": "J/m^2",
                                   "pair": "soil-steel", "kind": "surface_energy"}
    d["parameters"]["plastic"] = {"name": "Soil-soil plasticity", "unit": "-", "pair": "soil-soil",
                                  "kind": "plasticity"}
    _stage(d, "pb").setdefault("fixed", {})["adhesion"] = 0.1
    _stage(d, "steepest")["fixed"]["adhesion"] = 0.2
    _stage(d, "bbd")["fixed"].update(adhesion=0.3, plastic=0.25)
    # a screened parameter's value in the derived stages, off the screening range's centre
    # (0.45): the stage's explicit value holds, as the papers held such factors
    # (tests/chain/test_fixed_screened.py)
    _stage(d, "steepest")["fixed"]["soil_soil_restitution"] = 0.6
    _stage(d, "bbd")["fixed"]["soil_soil_restitution"] = 0.7

    effects = pd.DataFrame([{"response": "stacking_angle", "term": t, "effect": 2 * B_SIG[t],
                             "coefficient": B_SIG[t], "p": P_SIG[t]} for t in P_SIG])
    pb_runs = pd.DataFrame({"stacking_angle": [24.0, 26.0, 24.5, 25.5]})
    targets = {tid: {"value": t.get("value")} for tid, t in d["targets"].items()}
    path = path_from_screening(d, "steepest", _stage(d, "pb"), effects, pb_runs, targets)
    path["id"] = "steepest"
    assert path["fixed"]["adhesion"] == 0.2          # the path's own, not the screening's 0.1
    # a screened factor off the path at the value the stage fixes, the others at the centres
    # of their ranges (the recipe's intermediate levels)
    assert path["fixed"]["soil_soil_restitution"] == 0.6
    assert path["fixed"]["soil_soil_static_friction"] == pytest.approx((0.2 + 0.92) / 2, abs=1e-12)

    steps = pd.DataFrame({"step": np.arange(1, 7), "stacking_angle": [22.0, 24.5, 27.5, 29.0, 31.0, 33.0]})
    bbd = bbd_from_path(d, "bbd", path, steps)
    assert bbd["fixed"]["adhesion"] == 0.3           # the stage's own, not the path's 0.2
    assert bbd["fixed"]["plastic"] == 0.25           # fixed by this stage only: not dropped
    # a screened parameter off the path at the stage's own value (0.7, over the path's 0.6),
    # and the path factors are factors, not fixed values
    assert bbd["fixed"]["soil_soil_restitution"] == 0.7
    assert not set(bbd["fixed"]) & {f["parameter"] for f in bbd["factors"].values()}
