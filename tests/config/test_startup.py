"""Start-up checks of a soil beyond its schema: each bad setting stops the config check (and the
workflow's start-up, which loads the soils the same way) with one line naming the soil file and
the field, before any job runs."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from soilcal.config import load_soil
from soilcal.doe.adaptive import DEFAULTS
from soilcal.errors import InputError
from wfutil import copy_soil

ROOT = Path(__file__).resolve().parents[2]


def edit(path: Path, fn) -> Path:
    data = yaml.safe_load(path.read_text())
    fn(data)
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def refused(path: Path, tmp: Path) -> InputError:
    with pytest.raises(InputError) as exc:
        load_soil(path, tmp / "resources")
    return exc.value


# ------------------------------------------------------------------ densities


@pytest.mark.parametrize("rho", [175.7567, 1394.0, 7850.0, 19300.0])
def test_densities_of_soils_and_tool_materials_pass(rho):
    from soilcal.dem.scenarios.base import DemParams

    assert DemParams.from_mapping({"steel_density": rho}).steel_density == rho
    if rho <= 4000.0:  # a soil's: peat to iron-rich mineral soil (base.SOIL_RANGES)
        assert DemParams.from_mapping({"soil_density": rho}).soil_density == rho
    else:  # a steel or tungsten density is no soil's
        with pytest.raises(InputError, match=r"params\.soil_density: expected a soil particle density in \[100, 4000\]"):
            DemParams.from_mapping({"soil_density": rho})


def test_a_density_typed_in_g_per_cm3_is_refused(tmp_path):
    p = edit(copy_soil(tmp_path), lambda d: d["simulation"].update(params={"soil_density": 1.394}))
    e = refused(p, tmp_path)
    assert e.path == str(p) and e.field == "simulation.params.soil_density" and e.got == 1.394
    assert "[100, 25000] kg/m^3" in e.expected


# ------------------------------------------------------------------ loop.fold_by


def test_fold_by_names_a_covariate_column_of_the_measured_tables(tmp_path):
    p = copy_soil(tmp_path)
    columns = sorted(yaml.safe_load(p.read_text())["measurements"]["cutting_resistance"]["covariates"])
    edit(p, lambda d: d.update(loop={"fold_by": columns[0]}))
    load_soil(p, tmp_path / "resources")
    edit(p, lambda d: d.update(loop={"fold_by": "test_day"}))
    e = refused(p, tmp_path)
    assert e.path == str(p) and e.field == "loop.fold_by" and e.got == "test_day"
    assert e.expected == f"a covariate column of the soil's measured tables ({', '.join(columns)})"


# ------------------------------------------------------------------ simulation.screening


def _pb_factor_count(p: Path) -> int:
    d = yaml.safe_load(p.read_text())
    return len(next(s for s in d["stages"] if s["kind"] == "plackett_burman")["factors"])


def test_screening_min_factors_above_max_factors_is_refused(tmp_path):
    p = edit(copy_soil(tmp_path), lambda d: d["simulation"].update(screening={"min_factors": 4, "max_factors": 3}))
    e = refused(p, tmp_path)
    assert e.path == str(p) and e.field == "simulation.screening.min_factors" and e.got == 4
    assert "max_factors (3)" in e.expected
    # max_factors below the default min_factors names max_factors, the key the file gives
    edit(p, lambda d: d["simulation"].update(screening={"max_factors": 2}))
    e = refused(p, tmp_path)
    assert e.field == "simulation.screening.max_factors" and e.got == 2


def test_screening_min_factors_above_the_screenings_factor_count_is_refused(tmp_path):
    p = copy_soil(tmp_path)
    k = _pb_factor_count(p)
    edit(p, lambda d: d["simulation"].update(screening={"min_factors": k}))
    load_soil(p, tmp_path / "resources")  # every screened factor on the path: allowed
    edit(p, lambda d: d["simulation"].update(screening={"min_factors": k + 1}))
    e = refused(p, tmp_path)
    assert e.path == str(p) and e.field == "simulation.screening.min_factors" and e.got == k + 1
    assert e.expected.startswith(f"an integer <= {k}, the factor count of screening stage 'pb'")
    # a path run on the printed levels selects nothing: the count does not matter
    edit(p, lambda d: d["simulation"].update(design="printed"))
    load_soil(p, tmp_path / "resources")


# ------------------------------------------------------------------ simulation.adaptive


CENTRE, VERIFY = (DEFAULTS[k] for k in ("centre_replicates", "verify_seeds"))


def _adaptive(tmp: Path, settings: dict, design: str | None = "adaptive") -> Path:
    def fn(d):
        if design:
            d["simulation"]["design"] = design
        d["simulation"]["adaptive"] = settings
    return edit(copy_soil(tmp), fn)


def _bbd(p: Path) -> dict:
    return next(s for s in yaml.safe_load(p.read_text())["stages"] if s["id"] == "bbd")


@pytest.mark.parametrize("settings, field, expected", [
    ({"separation": 2}, "simulation.adaptive.separation", "a number < 2"),
    ({"tolerances": {"angle": {"pct": 2}}}, "simulation.adaptive.tolerances.angle",
     "a response of a stage the adaptive design runs (stacking_angle)"),
    ({"tolerances": {"stacking_angle": {}}}, "simulation.adaptive.tolerances.stacking_angle", "exactly one of"),
    ({"tolerances": {"stacking_angle": {"pct": 2, "abs": 0.5}}}, "simulation.adaptive.tolerances.stacking_angle",
     "exactly one of"),
    # n_start, verify_seeds or batch larger than the budget (the cinnamon Box-Behnken stage has 3 factors)
    ({"n_start": 40, "budget": 30}, "simulation.adaptive.budget",
     f"at least {CENTRE + 40 - 1 + VERIFY} runs"),
    ({"verify_seeds": 40, "budget": 30}, "simulation.adaptive.budget",
     f"at least {CENTRE + 2 * 3 + 40} runs: the start of stage 'bbd'"),
    ({"batch": 40, "budget": 30}, "simulation.adaptive.batch",
     f"at most {30 - (CENTRE + 2 * 3)}, the runs of the budget (30) left after the start of stage 'bbd'"),
    ({"p_verify": 1.5}, "simulation.adaptive.p_verify", "a number < 1"),
])
def test_bad_adaptive_settings_are_refused_at_start_up(tmp_path, settings, field, expected):
    p = _adaptive(tmp_path, settings)
    e = refused(p, tmp_path)
    assert e.path == str(p) and e.field == field and expected in e.expected, str(e)


def test_the_budget_holds_the_start_and_one_verification(tmp_path):
    p = _adaptive(tmp_path, {})
    d = len(_bbd(p)["factors"])
    centre, verify = 3, 5
    need = centre + (2 * d + 1) - 1 + verify  # centre seeds, 2 d Halton points, one verification
    edit(p, lambda x: x["simulation"].update(adaptive={"centre_replicates": centre, "verify_seeds": verify,
                                                       "budget": need}))
    load_soil(p, tmp_path / "resources")
    edit(p, lambda x: x["simulation"]["adaptive"].update(budget=need - 1))
    e = refused(p, tmp_path)
    assert e.field == "simulation.adaptive.budget" and e.got == need - 1
    assert e.expected.startswith(f"at least {need} runs: the start of stage 'bbd'")


def test_adaptive_settings_are_checked_for_the_workflows_design_override(tmp_path):
    from soilcal.config import load_workflow_config

    p = _adaptive(tmp_path, {"tolerances": {"angle": {"pct": 2}}}, design=None)
    cfg = {"soils": ["cinnamon-soil"], "soil_dir": str(tmp_path / "config/soils"),
           "resources": str(tmp_path / "resources")}
    soils = load_workflow_config(cfg)  # the soil's own design (recipe) does not read the block
    assert (soils["cinnamon-soil"].data["simulation"].get("design") or "recipe") == "recipe"
    with pytest.raises(InputError) as exc:
        load_workflow_config(dict(cfg, design="adaptive"))  # snakemake --config design=adaptive
    assert exc.value.path == str(p) and exc.value.field == "simulation.adaptive.tolerances.angle"
    soils = load_workflow_config(dict(cfg, design="printed"))
    assert soils["cinnamon-soil"].data["simulation"]["design"] == "printed"



def test_measurement_checks_follow_the_workflows_source_override(tmp_path):
    """A soil replayed from its printed tables whose measured table is calibrated on a stage
    its simulation block does not simulate loads as published; --config source=dem runs it on
    the DEM, so start-up refuses it there, as it would the soil's own source: dem."""
    from soilcal.config import load_workflow_config

    def published_pb_only(d):
        d["source"] = "published"
        d["simulation"]["stages"] = ["pb", "steepest"]  # the measured table is calibrated on bbd

    p = edit(copy_soil(tmp_path), published_pb_only)
    cfg = {"soils": ["cinnamon-soil"], "soil_dir": str(tmp_path / "config/soils"),
           "resources": str(tmp_path / "resources")}
    assert load_workflow_config(cfg)["cinnamon-soil"].data["source"] == "published"
    for source in ("dem", "both"):
        with pytest.raises(InputError) as exc:
            load_workflow_config(dict(cfg, source=source))
        assert exc.value.path == str(p) and exc.value.field == "measurements.cutting_resistance.calibrated.stage"
        assert exc.value.got == "bbd"


# ------------------------------------------------------------------ photo measurements, targets


def test_the_measures_each_kind_gives_are_those_its_measurement_builds():
    """``MEASURES`` lists the numbers of each kind's measurement entry (what image_measure may
    name): the numeric values of the dicts the pile, drum and furrow measurements build."""
    from types import SimpleNamespace

    import numpy as np

    from soilcal.imaging.drum import DrumResult, drum_summary
    from soilcal.imaging.manifest import MEASURES
    from soilcal.imaging.measure import FurrowResult, pile_summary

    pile = [SimpleNamespace(left_deg=30.0 + i, right_deg=31.0, as_dict=dict) for i in range(2)]
    drum = [DrumResult("f.jpg", 40.0, 41.0, 39.0, 2.0, 1.0, 0.0, "plate", "rim", [1, 2], 3.0, 0.8, 50)]
    furrow = FurrowResult("u.jpg", np.zeros(20), np.zeros(20), [1.0, 0.0], 1, 300.0, 2.0, 0.0)
    built = {"pile": pile_summary(pile), "drum": drum_summary(drum), "furrow": furrow.as_dict()}
    for kind, entry in built.items():
        numbers = {k for k, v in entry.items() if isinstance(v, (int, float)) and not isinstance(v, bool)}
        assert numbers == set(MEASURES[kind]), kind


def test_an_image_measure_the_groups_kind_does_not_give_is_refused(tmp_path):
    from soilcal.imaging.manifest import MEASURES

    p = copy_soil(tmp_path)
    group = yaml.safe_load(p.read_text())["targets"]["stacking_angle"]["image"]
    kind = next(ph["kind"] for ph in yaml.safe_load((tmp_path / "resources/images/cinnamon-soil/manifest.yaml")
                                                    .read_text())["photos"] if ph.get("group", ph["kind"]) == group)
    edit(p, lambda d: d["targets"]["stacking_angle"].update(image_measure="angle"))
    e = refused(p, tmp_path)
    assert e.path == str(p) and e.field == "targets.stacking_angle.image_measure" and e.got == "angle"
    assert e.expected == f"a value the measurement of the {kind} group {group!r} gives ({', '.join(MEASURES[kind])})"
    edit(p, lambda d: d["targets"]["stacking_angle"].update(image_measure=MEASURES[kind][1]))
    load_soil(p, tmp_path / "resources")
    # without a photo group there is nothing to measure
    edit(p, lambda d: d["targets"]["stacking_angle"].pop("image"))
    assert refused(p, tmp_path).field == "targets.stacking_angle.image_measure"


def test_a_target_table_that_is_not_under_the_soils_measurements_is_refused(tmp_path):
    p = edit(copy_soil(tmp_path), lambda d: d["targets"]["stacking_angle"].update(table="stacking.csv"))
    e = refused(p, tmp_path)
    assert e.path == str(p) and e.field == "targets.stacking_angle.table" and e.got == "stacking.csv"
    assert str(tmp_path / "resources/measurements/cinnamon-soil") in e.expected
    (tmp_path / "resources/measurements/cinnamon-soil/stacking.csv").write_text("angle\n27.69\n")
    load_soil(p, tmp_path / "resources")


def test_a_target_in_another_unit_than_its_response_is_refused(tmp_path):
    p = copy_soil(tmp_path)
    unit = _bbd(p)["responses"][0]["unit"]
    edit(p, lambda d: d["targets"]["stacking_angle"].update(unit="rad"))
    e = refused(p, tmp_path)
    assert e.path == str(p) and e.field == "targets.stacking_angle.unit" and e.got == "rad"
    assert e.expected.startswith(f"{unit}, the unit of response 'stacking_angle'")


# ------------------------------------------------------------------ YAML booleans as table values


@pytest.mark.parametrize("word, boolean", [("no", "false"), ("On", "true")])
def test_a_table_value_yaml_reads_as_a_boolean_key_says_to_quote_it(tmp_path, word, boolean):
    p = copy_soil(tmp_path)
    table = tmp_path / "resources/measurements/cinnamon-soil/cutting_resistance.csv"
    text = p.read_text()
    old = "directrix: {setup: {arc: plate-arc,"
    assert old in text
    p.write_text(text.replace(old, f"directrix: {{setup: {{{word}: plate-arc,"))
    table.write_text(table.read_text().replace(",arc,", f",{word},"))
    e = refused(p, tmp_path)
    assert e.path == str(p) and e.field == "measurements.cutting_resistance.covariates.directrix.setup"
    assert f"the key quoted, \"{word}\": the table value '{word}'" in e.expected
    assert f"is read by YAML as the boolean {boolean}" in e.expected
    p.write_text(text.replace(old, f"directrix: {{setup: {{\"{word}\": plate-arc,"))
    load_soil(p, tmp_path / "resources")


def test_a_photo_folder_copied_from_another_soil_is_refused(tmp_path):
    """A second soil whose photo folder is a copy of another soil's: the manifest still names
    that soil, and its photos would be taken for this soil's measurement."""
    p = copy_soil(tmp_path)
    manifest = tmp_path / "resources/images/cinnamon-soil/manifest.yaml"
    other = yaml.safe_load(manifest.read_text())
    other["soil"] = "black-soil"
    manifest.write_text(yaml.safe_dump(other, sort_keys=False))
    e = refused(p, tmp_path)
    assert (e.path, e.field, e.got) == (str(manifest), "soil", "black-soil")
    assert e.expected.startswith("'cinnamon-soil', the soil whose photo folder this is")


@pytest.mark.parametrize("source", ["dem", "both"])
def test_a_dem_soil_without_a_simulation_block_is_refused_by_the_check_of_its_file(tmp_path, source):
    """`soilcal config check FILE` gives the workflow's start-up check: a soil whose own source
    runs the DEM needs the block that says how each response is simulated."""
    def no_block(d):
        d["source"] = source
        d.pop("simulation")

    p = edit(copy_soil(tmp_path), no_block)
    e = refused(p, tmp_path)
    assert (e.path, e.field, e.got) == (str(p), "simulation", None)
    assert e.expected.startswith("a simulation block naming the scenario of each response")


@pytest.mark.parametrize("source", ["dem", "both"])
def test_a_published_soil_without_a_simulation_block_run_on_the_dem_by_the_workflow_is_told_so(tmp_path, source):
    """A soil whose own source is published, without a simulation block, loads; the workflow's
    --config source=dem (both) runs it on the DEM: start-up refuses it naming the workflow's
    source, not the soil file's source key (which says published)."""
    from soilcal.chain.plan import soil_sources
    from soilcal.config import load_workflow_config

    def published(d):
        d["source"] = "published"
        d.pop("simulation")

    p = edit(copy_soil(tmp_path), published)
    cfg = {"soils": ["cinnamon-soil"], "soil_dir": str(tmp_path / "config/soils"),
           "resources": str(tmp_path / "resources")}
    soil = load_workflow_config(cfg)["cinnamon-soil"]
    assert soil_sources(soil) == ["published"]
    with pytest.raises(InputError) as exc:
        load_workflow_config(dict(cfg, source=source))
    e = exc.value
    assert (e.path, e.field, e.got) == (str(p), "simulation", None)
    assert f"the workflow's source {source} (--config source={source})" in e.expected
    assert "source: published" not in e.expected
