"""A user's own soil with only what the calibration needs: one Box-Behnken table, its three
factors, one response and one target; no citation, no properties, no missing-items list.

It loads with the package's loader (the documented defaults filled in), and the published
replay runs for it through Snakemake in a copy of the workflow; the fitted full quadratic
equals an independent least-squares fit of the table written here."""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from bbd_stand_in import box_behnken_3
from soilcal.config import load_soil
from soilcal.config.load import schema_defaults
from wfutil import copy_workflow, run

SOIL_YAML = textwrap.dedent("""\
    name: my-soil
    parameters:
      rolling: {name: Soil-soil rolling friction, unit: "-"}
      energy: {name: JKR surface energy, unit: J/m^2}
      steel: {name: Soil-steel static friction, unit: "-"}
    stages:
      - id: bbd
        kind: box_behnken
        factors:
          A: {parameter: rolling, low: 0.1, high: 0.3}
          B: {parameter: energy, low: 2, high: 6}
          C: {parameter: steel, low: 0.4, high: 0.8}
        center_points: 3
        table: bbd.csv
        responses:
          - {id: angle, name: Repose angle, unit: deg}
        optimise:
          method: desirability
          cases:
            - id: angle
              goals: {angle: {goal: target, target: angle}}
    targets:
      angle: {value: 31.0, unit: deg}
    """)

LOW = np.array([0.1, 2.0, 0.4])
HIGH = np.array([0.3, 6.0, 0.8])


def _table() -> pd.DataFrame:
    """The 15-run Box-Behnken design (three factors, three centre points), coded, with a
    response from a known quadratic plus fixed scatter."""
    df, x = box_behnken_3()
    a, b, c = x.T
    scatter = np.array([0.21, -0.13, 0.05, -0.27, 0.16, 0.02, -0.09, 0.24, -0.18, 0.11, -0.04, 0.07, 0.12, -0.06, -0.08])
    y = 30 + 1.5 * a + 0.8 * b - 1.1 * c + 0.6 * a * b - 0.4 * b * c + 0.9 * a * a - 0.5 * c * c + scatter
    df["angle"] = np.round(y, 3)
    return df


def _write(root: Path) -> Path:
    (root / "config/soils").mkdir(parents=True, exist_ok=True)
    (root / "resources/published/my-soil").mkdir(parents=True, exist_ok=True)
    _table().to_csv(root / "resources/published/my-soil/bbd.csv", index=False)
    p = root / "config/soils/my-soil.yaml"
    p.write_text(SOIL_YAML)
    return p


TERMS = ["Intercept", "A", "B", "C", "A*B", "A*C", "B*C", "A^2", "B^2", "C^2"]


def _quadratic(x: np.ndarray) -> np.ndarray:
    a, b, c = x.T
    return np.column_stack([np.ones(len(x)), a, b, c, a * b, a * c, b * c, a * a, b * b, c * c])


def test_minimal_soil_loads_with_documented_defaults(tmp_path):
    soil = load_soil(_write(tmp_path), tmp_path / "resources")
    assert soil.name == "my-soil" and [s["id"] for s in soil.stages] == ["bbd"]
    assert set(soil.defaulted) == {"source", "seed", "properties"}
    defaults = schema_defaults()
    assert soil.data["seed"] == defaults["seed"] == 0
    assert soil.data["source"] == defaults["source"] == "published"
    assert soil.data["properties"] == {} and soil.data["targets"]["angle"]["value"] == 31.0
    assert "citation" not in soil.data and "missing" not in soil.data
    assert len(soil.tables["bbd"]) == 15


@pytest.fixture(scope="module")
def replayed(tmp_path_factory):
    tmp = copy_workflow(tmp_path_factory.mktemp("minimal"), ["my-soil"], source="published")
    _write(tmp)
    d = "results/my-soil/published"
    run(tmp, "--cores", "2", f"{d}/errata.csv")
    return tmp / d


def test_replay_writes_the_regression_outputs(replayed):
    for name in ("stage.json", "design.csv", "responses.csv", "anova.csv", "fit.csv", "coefficients.csv",
                 "effects.csv", "optimum.csv", "identifiability.csv"):
        assert (replayed / "bbd" / name).is_file(), name
    assert (replayed / "errata.csv").is_file() and (replayed / "targets.csv").is_file()
    anova = pd.read_csv(replayed / "bbd/anova.csv")
    assert {"Model", "Residual", "Lack of Fit", "Pure Error", "Cor Total"} <= set(anova["source"])


def test_fitted_coefficients_equal_an_independent_least_squares_fit(replayed):
    table = _table()
    coded = table[["A", "B", "C"]].to_numpy(float)
    y = table["angle"].to_numpy(float)
    beta_coded = np.linalg.lstsq(_quadratic(coded), y, rcond=None)[0]
    actual = (LOW + HIGH) / 2 + coded * (HIGH - LOW) / 2
    beta_actual = np.linalg.lstsq(_quadratic(actual), y, rcond=None)[0]
    coef = pd.read_csv(replayed / "bbd/coefficients.csv")
    full = coef[(coef["response"] == "angle") & (coef["model"] == "full")].set_index("term")
    assert list(full.index) == TERMS
    np.testing.assert_allclose(full.loc[TERMS, "coded"].to_numpy(float), beta_coded, rtol=0, atol=1e-8)
    np.testing.assert_allclose(full.loc[TERMS, "actual"].to_numpy(float), beta_actual, rtol=0, atol=1e-8)


def test_default_seed_is_written_where_it_is_used(replayed):
    opt = pd.read_csv(replayed / "bbd/optimum.csv")
    searched = opt[opt["method"].isin(["desirability", "near_optimal"])]
    assert len(searched) and (searched["seed"] == 0).all()
    assert searched["angle"].sub(31.0).abs().min() < 0.05


def test_a_target_moisture_in_a_fraction_is_written_as_a_fraction(tmp_path):
    # the soil declares its moisture as a fraction (0.172, not 17.2 %): the targets rule
    # writes the target's moisture in that unit, as the soil's own reader gives it
    tmp = copy_workflow(tmp_path, ["my-soil"], source="published")
    p = _write(tmp)
    p.write_text(SOIL_YAML.replace("  angle: {value: 31.0, unit: deg}\n",
                                   "  angle: {value: 31.0, unit: deg, moisture_content: 0.172}\n")
                 + "properties:\n  moisture_content: {value: 0.172, unit: fraction}\n")
    run(tmp, "--cores", "1", "results/my-soil/published/targets.csv")
    t = pd.read_csv(tmp / "results/my-soil/published/targets.csv").set_index("target_id")
    assert t.loc["angle", "moisture_content"] == pytest.approx(0.172)
    assert t.loc["angle", "moisture_unit"] == "fraction"


def test_a_replay_of_a_soil_without_printed_tables_says_why_it_writes_only_designs(tmp_path):
    tmp = copy_workflow(tmp_path, ["my-soil"], source="published")
    p = _write(tmp)
    p.write_text(SOIL_YAML.replace("    table: bbd.csv\n", ""))
    out = run(tmp, "-n", "--cores", "1")
    assert "no stage of this soil has one: only its designs are written" in out.stderr, out.stderr[-2000:]
    # with its table the note is not given
    p.write_text(SOIL_YAML)
    assert "only its designs are written" not in run(tmp, "-n", "--cores", "1").stderr
