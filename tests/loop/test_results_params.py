"""``soilcal loop synthesize|run --results DIR``: every measured condition starts from the
calibrated set the workflow's tool job for it runs at (soilcal.chain.verify.tool_point), read
from a results tree as the workflow reads it: the stage from ``<soil>/dem/<stage>/stage.json``,
the set from ``final.csv`` (``simulation.verification.refine``, on by default) or
``optimum.csv``; ``--param`` goes on top.

The results trees here are written by hand (no DEM run): every expected number below is one
of the hand-chosen levels, fixed values or ``--param`` values written in this file, or a
value the shipped soil YAML prints (cinnamon soil: Poisson ratio 0.311, shear modulus
3.814 MPa; Guangxi cohesive soil: Poisson ratio 0.38, shear modulus 1.0e6 Pa,
``simulation.params.soil_density`` 1802 kg/m^3), or a DemParams default where nothing sets
the parameter.
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from soilcal.cli import main
from soilcal.config.load import load_soil
from soilcal.config.measurements import conditions
from soilcal.dem.scenarios.base import DemParams
from soilcal.errors import InputError
from soilcal.loop import cli as lc

ROOT = Path(__file__).resolve().parents[2]
CINNAMON = ROOT / "config/soils/cinnamon-soil.yaml"
GUANGXI = ROOT / "config/soils/guangxi-cohesive.yaml"
RES = ROOT / "resources"
DEFAULTS = DemParams().as_dict()

#: the DEM stage bbd of the cinnamon soil as the workflow writes it: factors A (soil-soil
#: rolling friction), B (JKR surface energy, J/m^2), C (soil-steel static friction); fixed
#: values chosen here unlike the config's 0.45/0.56/0.45/0.125, so that only stage.json can
#: give them
CINNAMON_STAGE = {
    "id": "bbd", "kind": "box_behnken", "source": "dem",
    "factors": {"A": {"parameter": "soil_soil_rolling_friction", "low": 0.08, "centre": 0.11, "high": 0.14},
                "B": {"parameter": "jkr_surface_energy", "low": 0.24, "centre": 0.38, "high": 0.52},
                "C": {"parameter": "soil_steel_static_friction", "low": 0.42, "centre": 0.54, "high": 0.66}},
    "fixed": {"soil_soil_restitution": 0.41, "soil_soil_static_friction": 0.58, "soil_steel_restitution": 0.43,
              "soil_steel_rolling_friction": 0.12},
    "responses": [{"id": "stacking_angle", "name": "Stacking angle", "unit": "deg"}],
    "optimise": {"method": "desirability", "cases": [{"id": "stacking_angle",
                                                       "goals": {"stacking_angle": {"goal": "target"}}}]},
}

#: the final set (final.csv): a first-round row that is not the calibrated one, then the set
CINNAMON_REFINED = pd.DataFrame({
    "case": ["stacking_angle", "stacking_angle"], "A": [0.09, 0.083], "B": [0.30, 0.412], "C": [0.50, 0.615],
    "round": [1, 2], "refined": [True, True], "calibrated": [False, True], "note": ["", ""]})

#: the first-round optimum, different numbers: read only where the soil does not refine
CINNAMON_OPTIMUM = pd.DataFrame({
    "case": ["stacking_angle"], "method": ["desirability"], "A": [0.1], "B": [0.35], "C": [0.6],
    "calibrated": [True], "note": [""]})


def _tree(tmp_path: Path, soil: str, stage: dict, files: dict) -> Path:
    """results/<soil>/dem/<stage>/ with stage.json (unless ``stage`` is None) and ``files``."""
    d = tmp_path / "results" / soil / "dem" / "bbd"
    d.mkdir(parents=True, exist_ok=True)
    if stage is not None:
        (d / "stage.json").write_text(json.dumps(stage, indent=1))
    for name, df in files.items():
        df.to_csv(d / name, index=False)
    return tmp_path / "results"


def _cinnamon():
    soil = load_soil(CINNAMON, RES)
    return soil, conditions(soil)


# --------------------------------------------------------------------------- the parameters


def test_each_condition_starts_from_the_refined_set_of_its_stage_plus_param(tmp_path):
    results = _tree(tmp_path, "cinnamon-soil", CINNAMON_STAGE,
                    {"final.csv": CINNAMON_REFINED, "optimum.csv": CINNAMON_OPTIMUM})
    soil, conds = _cinnamon()
    assert len(conds) == 4
    overrides = {"soil_density": 1500.0, "soil_steel_static_friction": 0.7}
    got = lc.base_parameters(soil, conds, overrides, results)
    expected = dict(DEFAULTS,
                    # the calibrated row of final.csv, each factor to its <pair>_<kind> field (J/m^2 is SI)
                    soil_soil_rolling_friction=0.083, soil_soil_surface_energy=0.412,
                    soil_steel_static_friction=0.7,  # --param over the calibrated 0.615
                    # stage.json's fixed values
                    soil_soil_restitution=0.41, soil_soil_static_friction=0.58, soil_steel_restitution=0.43,
                    soil_steel_rolling_friction=0.12,
                    # the YAML's properties: Poisson ratio 0.311, shear modulus 3.814 MPa
                    soil_poisson=0.311, soil_shear_modulus=3.814e6,
                    soil_density=1500.0)  # --param
    assert set(got) == {("cutting_resistance", r) for r in (1, 2, 3, 4)}
    for key, p in got.items():
        assert p == pytest.approx(expected, rel=1e-12), key
    # without --param the calibrated level itself
    plain = lc.base_parameters(soil, conds, {}, results)[("cutting_resistance", 1)]
    assert plain["soil_steel_static_friction"] == pytest.approx(0.615, rel=1e-12)
    assert plain["soil_density"] == DEFAULTS["soil_density"]


def test_a_soil_without_the_second_round_reads_optimum_csv(tmp_path):
    results = _tree(tmp_path, "cinnamon-soil", CINNAMON_STAGE,
                    {"final.csv": CINNAMON_REFINED, "optimum.csv": CINNAMON_OPTIMUM})
    soil, conds = _cinnamon()
    soil.data.setdefault("simulation", {})["verification"] = {"refine": False}
    from soilcal.chain.refine import set_file

    assert set_file(soil.data) == "optimum.csv"
    p = lc.calibrated_params(soil, conds, results)[("cutting_resistance", 2)]
    assert (p["soil_soil_rolling_friction"], p["soil_soil_surface_energy"], p["soil_steel_static_friction"]) \
        == pytest.approx((0.1, 0.35, 0.6), rel=1e-12)
    assert p["soil_soil_restitution"] == pytest.approx(0.41, rel=1e-12)


def test_each_row_takes_the_set_of_its_own_case(tmp_path):
    """Guangxi cohesive soil: the moisture-content covariate maps rows 5, 10, 15 % to the cases
    mc05, mc10, mc15 of stage bbd (A soil-soil restitution, B soil-soil static friction, G JKR
    surface energy); simulation.params.soil_density 1802 is a condition parameter, over the set."""
    stage = {"id": "bbd", "kind": "box_behnken", "source": "dem",
             "factors": {"A": {"parameter": "soil_soil_restitution"}, "B": {"parameter": "soil_soil_static_friction"},
                         "G": {"parameter": "jkr_surface_energy"}},
             "responses": [{"id": "angle_of_repose"}],
             "optimise": {"cases": [{"id": c} for c in ("mc00", "mc05", "mc10", "mc15", "mc20")]}}
    sets = {"mc00": (0.20, 0.30, 0.010), "mc05": (0.28, 0.40, 0.045), "mc10": (0.31, 0.47, 0.061),
            "mc15": (0.36, 0.55, 0.077), "mc20": (0.39, 0.58, 0.079)}
    refined = pd.DataFrame([{"case": c, "A": a, "B": b, "G": g, "calibrated": True} for c, (a, b, g) in sets.items()])
    results = _tree(tmp_path, "guangxi-cohesive", stage, {"final.csv": refined})
    soil = load_soil(GUANGXI, RES)
    conds = conditions(soil)
    assert [(c.row, c.case) for c in conds] == [(1, "mc05"), (2, "mc10"), (3, "mc15")]
    got = lc.base_parameters(soil, conds, {"soil_steel_rolling_friction": 0.2}, results)
    for row, case in ((1, "mc05"), (2, "mc10"), (3, "mc15")):
        a, b, g = sets[case]
        assert got[("compression", row)] == pytest.approx(dict(
            DEFAULTS, soil_soil_restitution=a, soil_soil_static_friction=b, soil_soil_surface_energy=g,
            soil_poisson=0.38, soil_shear_modulus=1.0e6, soil_density=1802.0, soil_steel_rolling_friction=0.2),
            rel=1e-12), case
    # --param goes over the condition's own parameters too
    dense = lc.base_parameters(soil, conds, {"soil_density": 1700.0}, results)
    assert {p["soil_density"] for p in dense.values()} == {1700.0}


def test_without_results_the_parameters_are_as_before():
    soil, conds = _cinnamon()
    got = lc.base_parameters(soil, conds, {"soil_density": 1500.0})
    for c in conds:
        assert got[(c.measurement, c.row)] == lc.condition_params({"soil_density": 1500.0})(c)
        # cinnamon soil has no simulation.params: the DemParams defaults and the --param
        assert got[(c.measurement, c.row)] == dict(DEFAULTS, soil_density=1500.0)


# --------------------------------------------------------------------------- the errors


def test_a_case_without_a_calibrated_set_is_an_error_naming_the_file(tmp_path):
    none = pd.DataFrame({"case": ["stacking_angle"], "A": [float("nan")], "B": [float("nan")], "C": [float("nan")],
                         "calibrated": [False], "note": ["target value not available"]})
    results = _tree(tmp_path, "cinnamon-soil", CINNAMON_STAGE, {"final.csv": none})
    soil, conds = _cinnamon()
    with pytest.raises(InputError) as exc:
        lc.base_parameters(soil, conds, {}, results)
    assert exc.value.path == str(results / "cinnamon-soil/dem/bbd/final.csv")
    assert exc.value.field == "case stacking_angle" and "calibrated = True" in exc.value.expected
    assert exc.value.got == "target value not available"


def _cli(argv, capsys):
    code = main([str(a) for a in argv])
    err = capsys.readouterr().err
    return code, [ln for ln in err.splitlines() if ln.strip()]


@pytest.mark.parametrize("command", ["synthesize", "run"])
def test_a_stage_not_run_yet_stops_the_command_with_one_line(command, tmp_path, capsys):
    # stage.json and the first-round optimum, but not the refined set the soil ends with
    results = _tree(tmp_path, "cinnamon-soil", CINNAMON_STAGE, {"optimum.csv": CINNAMON_OPTIMUM})
    out = tmp_path / ("x.csv" if command == "synthesize" else "out")
    argv = ["loop", command, CINNAMON, "--resources", RES, "--results", results, "--out", out]
    if command == "synthesize":
        argv[3:3] = ["--measurement", "cutting_resistance"]
    code, lines = _cli(argv, capsys)
    assert code == 2 and len(lines) == 1, lines
    missing = results / "cinnamon-soil/dem/bbd/final.csv"
    assert lines[0].startswith(f"soilcal: error: {missing}: <file>: expected ")
    assert "final.csv" in lines[0] and "no such file" in lines[0]
    assert not out.exists() and not (tmp_path / "x.truth.csv").exists()


def test_a_missing_stage_file_and_a_missing_folder_are_named(tmp_path, capsys):
    results = _tree(tmp_path, "cinnamon-soil", None, {"final.csv": CINNAMON_REFINED})
    base = ["loop", "run", CINNAMON, "--resources", RES, "--out", tmp_path / "out"]
    code, lines = _cli(base + ["--results", results], capsys)
    assert code == 2 and len(lines) == 1
    assert lines[0].startswith(f"soilcal: error: {results / 'cinnamon-soil/dem/bbd/stage.json'}: <file>:")
    code, lines = _cli(base + ["--results", tmp_path / "nowhere"], capsys)
    assert code == 2 and len(lines) == 1
    assert lines[0].startswith("soilcal: error: <command line>: --results: expected a results folder")
    assert not (tmp_path / "out").exists()


def test_the_shell_sees_exit_status_2(tmp_path):
    results = _tree(tmp_path, "cinnamon-soil", CINNAMON_STAGE, {})
    p = subprocess.run([sys.executable, "-m", "soilcal.cli", "loop", "run", str(CINNAMON), "--resources", str(RES),
                        "--results", str(results), "--out", str(tmp_path / "out")],
                       capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert p.returncode == 2 and "Traceback" not in p.stderr
    assert p.stderr.strip().count("\n") == 0 and "cinnamon-soil/dem/bbd/final.csv" in p.stderr
    assert not (tmp_path / "out").exists()


# --------------------------------------------------------------------------- what is recorded


def _fake_simulator(threads=None):
    """A stand-in for the DEM: forces proportional to the soil-steel friction."""
    def run(cond, params, seed):
        mu = params["soil_steel_static_friction"]
        return {"horizontal_force_N": 500.0 * mu * (1 + 0.01 * cond.row + 0.001 * seed),
                "vertical_force_N": 50.0 * mu * (1 + 0.002 * seed)}

    return run


def test_synthesize_records_the_parameters_in_the_truth_file(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(lc, "dem_simulator", _fake_simulator)
    results = _tree(tmp_path, "cinnamon-soil", CINNAMON_STAGE, {"final.csv": CINNAMON_REFINED})
    out = tmp_path / "synthetic.csv"
    code = main(["loop", "synthesize", str(CINNAMON), "--measurement", "cutting_resistance", "--resources", str(RES),
                 "--results", str(results), "--param", "soil_density=1500", "--out", str(out)])
    assert code == 0
    assert f"parameters: --results {results} + --param soil_density=1500" in capsys.readouterr().out
    truth = pd.read_csv(tmp_path / "synthetic.truth.csv")
    assert len(truth) == 8  # 4 rows x 2 measures
    assert set(truth["params_source"]) == {f"--results {results} + --param soil_density=1500"}
    for col, v in (("base:soil_soil_rolling_friction", 0.083), ("base:soil_soil_surface_energy", 0.412),
                   ("base:soil_steel_static_friction", 0.615), ("base:soil_soil_restitution", 0.41),
                   ("base:soil_density", 1500.0)):
        assert truth[col].tolist() == pytest.approx([v] * 8, rel=1e-12), col
    # the runs were at the calibrated mu = 0.615: the truth's simulated mean is the stand-in's
    # 500 mu (1 + 0.01 row + 0.001 seed) averaged over the seeds 1000, 1001, 1002 (no hidden effect)
    h = truth[(truth["measure"] == "horizontal_force_N") & (truth["row"] == 1)].iloc[0]
    assert h["truth_simulated"] == pytest.approx(500.0 * 0.615 * (1 + 0.01 * 1 + 0.001 * 1001), rel=1e-12)
    # each row's DEM seeds, the condition's own (the four plates: four sets, none shared)
    from soilcal.config.load import load_soil
    from soilcal.config.measurements import condition_seed, conditions

    conds = {c.row: c for c in conditions(load_soil(CINNAMON, RES))}
    for r in truth.itertuples():
        assert r.dem_seeds == " ".join(str(condition_seed(conds[r.row], s)) for s in (1000, 1001, 1002))
    seeds = {r.row: r.dem_seeds for r in truth.itertuples()}
    assert len(set(seeds.values())) == 4 and not set(" ".join(seeds.values()).split()) & {"1000", "1001", "1002"}
    # without --results: the soil's own parameters, recorded as such
    main(["loop", "synthesize", str(CINNAMON), "--measurement", "cutting_resistance", "--resources", str(RES),
          "--out", str(out)])
    said = "not a calibrated set (--results reads one): the engine's defaults"
    assert f"parameters: {said}" in capsys.readouterr().out
    truth = pd.read_csv(tmp_path / "synthetic.truth.csv")
    assert len(set(truth["params_source"])) == 1 and truth["params_source"].iloc[0].startswith(said)
    assert set(truth["base:soil_steel_static_friction"]) == {DEFAULTS["soil_steel_static_friction"]}


def test_run_writes_the_parameters_of_every_condition(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(lc, "dem_simulator", _fake_simulator)
    results = _tree(tmp_path, "cinnamon-soil", CINNAMON_STAGE, {"final.csv": CINNAMON_REFINED})
    out = tmp_path / "loop"
    code = main(["loop", "run", str(CINNAMON), "--resources", str(RES), "--results", str(results),
                 "--param", "soil_steel_rolling_friction=0.2", "--sim-seeds", "1", "--out", str(out)])
    assert code == 0
    assert f"parameters: --results {results} + --param soil_steel_rolling_friction=0.2" in capsys.readouterr().out
    p = pd.read_csv(out / "parameters.csv")
    assert list(p.columns) == ["measurement", "row", *DemParams.names()]
    assert list(zip(p["measurement"], p["row"])) == [("cutting_resistance", r) for r in (1, 2, 3, 4)]
    for col, v in (("soil_soil_rolling_friction", 0.083), ("soil_soil_surface_energy", 0.412),
                   ("soil_steel_static_friction", 0.615), ("soil_soil_static_friction", 0.58),
                   ("soil_steel_rolling_friction", 0.2), ("soil_shear_modulus", 3.814e6)):
        assert p[col].tolist() == pytest.approx([v] * 4, rel=1e-12), col
    assert not math.isnan(pd.read_csv(out / "residuals.csv")["simulated_mean"].iloc[0])
    # the report and the figures, as the workflow writes them
    assert (out / "report.md").read_text().startswith("# Measured-data loop: cinnamon-soil")
    assert list((out / "figures/residuals").glob("*.png")) and (out / "ranking.csv").is_file()


def _cinnamon_with_tools(tmp_path, plates):
    """A copy of the cinnamon soil whose four plates are tools named ``plates`` (mapped, quoted,
    to the four plate setups)."""
    import shutil

    import yaml

    from soilcal.config.load import read_yaml

    (tmp_path / "config/soils").mkdir(parents=True)
    soil = tmp_path / "config/soils/cinnamon-soil.yaml"
    shutil.copy(CINNAMON, soil)
    for kind in ("published", "measurements", "images"):
        shutil.copytree(RES / kind / "cinnamon-soil", tmp_path / "resources" / kind / "cinnamon-soil")
    table = tmp_path / "resources/measurements/cinnamon-soil/cutting_resistance.csv"
    df = pd.read_csv(table)
    df["plate"] = plates
    df.to_csv(table, index=False)
    d = read_yaml(soil)
    cov = d["measurements"]["cutting_resistance"]["covariates"]
    cov["plate"] = {"setup": dict(zip(plates, ("plate-arc", "plate-parabola", "plate-bionic", "plate-line"))),
                    "quantity": "tool"}
    cov["directrix"] = {"ignore": True}
    soil.write_text(yaml.safe_dump(d, sort_keys=False))
    return soil, tmp_path / "resources", table


def test_synthesize_writes_the_user_s_table_back_as_written(tmp_path, monkeypatch):
    """Tools NA, N/A, null and None (mapped in the soil): synthesize re-read the user's table
    with pandas' missing-value words and wrote the four tools back as empty cells."""
    monkeypatch.setattr(lc, "dem_simulator", _fake_simulator)
    plates = ["NA", "N/A", "null", "None"]
    soil, res, _ = _cinnamon_with_tools(tmp_path, plates)
    assert [c.quantities["tool"] for c in conditions(load_soil(soil, res))] == plates
    out = tmp_path / "synthetic.csv"
    assert main(["loop", "synthesize", str(soil), "--measurement", "cutting_resistance", "--resources", str(res),
                 "--out", str(out)]) == 0
    assert pd.read_csv(out, dtype=str, keep_default_na=False)["plate"].tolist() == plates


def test_residuals_are_read_back_as_written(tmp_path):
    """residuals.csv's covariate and tool columns of four tools NA, N/A, null, None (and 007):
    re-read with pandas' missing-value words the four were one missing level, 007 the number 7."""
    from soilcal.chain.files import write_csv
    from soilcal.loop.files import read_written

    tools = ["NA", "N/A", "null", "None", "007"]
    res = pd.DataFrame({"measurement": ["m"] * 5, "row": range(1, 6), "cov:plate": tools, "q:tool": tools,
                        "cov:speed": [0.1, 0.2, float("nan"), 0.4, 0.5], "residual": [1.0, 2.0, 3.0, 4.0, 5.0]})
    write_csv(res, tmp_path / "residuals.csv")
    back = read_written(tmp_path / "residuals.csv")
    assert back["cov:plate"].tolist()[:4] == tools[:4] and back["q:tool"].tolist() == tools
    assert back["q:tool"].nunique() == 5
    assert back["cov:speed"].isna().tolist() == [False, False, True, False, False]
    assert back["residual"].tolist() == [1.0, 2.0, 3.0, 4.0, 5.0]
