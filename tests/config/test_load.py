"""Config validation: one clear error naming file and field for every kind of bad input."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
import yaml

from soilcal.config import design_runs, load_soil, load_workflow_config
from soilcal.errors import InputError

ROOT = Path(__file__).resolve().parents[2]
SOILS = sorted(p.stem for p in (ROOT / "config" / "soils").glob("*.yaml"))


@pytest.mark.parametrize("soil", SOILS)
def test_shipped_soils_validate(soil):
    s = load_soil(ROOT / "config" / "soils" / f"{soil}.yaml", ROOT / "resources")
    assert s.name == soil
    for st in s.stages:
        if st.get("table"):
            assert len(s.tables[st["id"]]) == design_runs(st)


def test_workflow_config_lists_shipped_soils():
    cfg = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    assert cfg["soils"] == ["yangtze-clay-loam", "black-soil", "cinnamon-soil", "xinjiang-vineyard", "guangxi-cohesive"]
    assert set(cfg["soils"]) == set(SOILS)


@pytest.fixture
def workspace(tmp_path):
    """A copy of the cinnamon soil entry and its published tables."""
    (tmp_path / "config" / "soils").mkdir(parents=True)
    shutil.copy(ROOT / "config/soils/cinnamon-soil.yaml", tmp_path / "config/soils/cinnamon-soil.yaml")
    shutil.copytree(ROOT / "resources/published/cinnamon-soil", tmp_path / "resources/published/cinnamon-soil")
    return tmp_path


def _edit(ws: Path, fn):
    p = ws / "config/soils/cinnamon-soil.yaml"
    d = yaml.safe_load(p.read_text())
    fn(d)
    p.write_text(yaml.safe_dump(d, sort_keys=False))
    return p


def _load(ws):
    return load_soil(ws / "config/soils/cinnamon-soil.yaml", ws / "resources")


def test_misspelt_field_names_file_and_field(workspace):
    p = _edit(workspace, lambda d: d["stages"][2]["factors"]["A"].update({"hgih": 0.2}))
    with pytest.raises(InputError) as e:
        _load(workspace)
    msg = str(e.value)
    assert str(p) in msg and "stages[2].factors.A.hgih" in msg and "unknown field" in msg


def test_wrong_type(workspace):
    _edit(workspace, lambda d: d["stages"][0]["factors"]["X1"].update({"low": "low"}))
    with pytest.raises(InputError, match=r"stages\[0\]\.factors\.X1\.low: expected a value of type number"):
        _load(workspace)


def test_low_not_below_high(workspace):
    _edit(workspace, lambda d: d["stages"][2]["factors"]["B"].update({"low": 0.6}))
    with pytest.raises(InputError, match=r"cinnamon-soil\.yaml: stages\[2\]\.factors\.B\.low: expected a number below high \(0\.52\), got 0\.6"):
        _load(workspace)


def test_a_factor_with_low_equal_to_high_points_to_the_fixed_values(workspace):
    """low == high is a factor held at one value: the error says where such a value goes."""
    _edit(workspace, lambda d: d["stages"][2]["factors"]["A"].update({"low": 0.14}))
    with pytest.raises(InputError) as e:
        _load(workspace)
    assert e.value.field == "stages[2].factors.A.low" and e.value.got == 0.14
    assert e.value.expected == ("a number below high (0.14) (a parameter held at one value goes under the "
                                "stage's fixed values)")


def test_missing_required_field(workspace):
    _edit(workspace, lambda d: d.pop("parameters"))
    with pytest.raises(InputError, match=r"parameters: expected a required field"):
        _load(workspace)


def test_left_out_optional_field_takes_its_documented_default(workspace):
    for kind in ("images", "measurements"):
        shutil.copytree(ROOT / "resources" / kind / "cinnamon-soil", workspace / "resources" / kind / "cinnamon-soil")
    _edit(workspace, lambda d: d.pop("seed"))
    soil = _load(workspace)
    assert soil.data["seed"] == 0 and soil.defaulted == ("seed",)


def test_table_row_count_must_match_design(workspace):
    t = workspace / "resources/published/cinnamon-soil/bbd.csv"
    lines = t.read_text().splitlines()
    t.write_text("\n".join(lines[:-1]) + "\n")  # drop one centre point: 16 rows for a 17-run BBD
    with pytest.raises(InputError, match=r"bbd\.csv: rows: expected 17 rows for the box_behnken design"):
        _load(workspace)


def test_coded_table_with_a_stray_level(workspace):
    t = workspace / "resources/published/cinnamon-soil/pb.csv"
    t.write_text(t.read_text().replace("\n7,-1,", "\n7,0,", 1))
    with pytest.raises(InputError, match=r"pb\.csv: column X1: expected coded levels -1/1"):
        _load(workspace)


def test_missing_table_file(workspace):
    (workspace / "resources/published/cinnamon-soil/steepest.csv").unlink()
    with pytest.raises(InputError, match=r"stages\[1\]\.table: expected an existing file .*steepest\.csv"):
        _load(workspace)


def test_unknown_parameter_reference(workspace):
    _edit(workspace, lambda d: d["stages"][2]["factors"]["A"].update({"parameter": "soil_soil_rollin"}))
    with pytest.raises(InputError, match=r"factors\.A\.parameter: expected an id listed under parameters"):
        _load(workspace)


def _second_restitution(d):
    """A second parameter id for the soil-soil restitution (same pair and kind as X1's)."""
    d["parameters"]["restitution_b"] = {"name": "Restitution again", "unit": "-", "pair": "soil-soil",
                                        "kind": "restitution"}


@pytest.mark.parametrize("edit, field, got, says", [
    # two factors on one parameter: the runs would set it twice, the first factor's levels lost
    (lambda d: d["stages"][0]["factors"]["X2"].update(parameter="soil_soil_restitution"),
     "stages[0].factors.X2.parameter", "soil_soil_restitution", "factor X1 varies 'soil_soil_restitution'"),
    # a factor and a fixed value of one parameter: one of the two would be ignored
    (lambda d: d["stages"][1]["fixed"].update(soil_soil_rolling_friction=0.1),
     "stages[1].fixed.soil_soil_rolling_friction", "soil_soil_rolling_friction", "factor A varies"),
    # two ids of one DEM parameter count as one
    (lambda d: (_second_restitution(d), d["stages"][0].setdefault("fixed", {}).update(restitution_b=0.5)),
     "stages[0].fixed.restitution_b", "restitution_b", "(DEM parameter soil_soil_restitution)"),
    # a dummy column bearing a factor's symbol
    (lambda d: d["stages"][0].update(dummies=["X8", "X9", "X10", "X1"]), "stages[0].dummies", "X1", "by no factor"),
])
def test_a_stage_sets_each_parameter_once(workspace, edit, field, got, says):
    p = _edit(workspace, edit)
    with pytest.raises(InputError) as e:
        _load(workspace)
    assert (e.value.path, e.value.field, e.value.got) == (str(p), field, got)
    assert says in e.value.expected


@pytest.mark.parametrize("runs", [10, 8])
def test_plackett_burman_runs_not_a_design_size_is_refused_at_load(workspace, runs):
    """runs of a Plackett-Burman stage: a multiple of 4 above its factors and dummies (the
    cinnamon screening has 7 factors and 4 dummies), refused when the soil loads rather than
    by the design job."""
    p = _edit(workspace, lambda d: d["stages"][0].update(runs=runs))
    with pytest.raises(InputError) as e:
        _load(workspace)
    assert e.value.path == str(p) and e.value.field == "stages[0].runs" and e.value.got == runs
    assert e.value.expected.startswith("a multiple of 4 above the 11 factors and dummies")


def test_name_must_match_file(workspace):
    _edit(workspace, lambda d: d.update({"name": "other-soil"}))
    with pytest.raises(InputError, match=r"name: expected the file name"):
        _load(workspace)


def test_unparsable_yaml(workspace):
    p = workspace / "config/soils/cinnamon-soil.yaml"
    p.write_text("name: [unclosed\n")
    with pytest.raises(InputError, match=r"cinnamon-soil\.yaml: line \d+: expected valid YAML"):
        _load(workspace)


def test_workflow_config_soil_listed_twice(workspace):
    """A soil listed twice would be calibrated once under the name of both entries: the second
    entry is named, before its file is read."""
    cfg = {"soils": ["cinnamon-soil", "other-soil", "cinnamon-soil"], "soil_dir": str(workspace / "config/soils")}
    with pytest.raises(InputError) as e:
        load_workflow_config(cfg, "config/config.yaml")
    assert (e.value.path, e.value.field, e.value.got) == ("config/config.yaml", "soils[2]", "cinnamon-soil")
    assert e.value.expected == "each soil listed once (soils[0] lists it)"


def test_workflow_config_unknown_soil(workspace):
    cfg = {"soils": ["no-such-soil"], "soil_dir": str(workspace / "config/soils")}
    with pytest.raises(InputError, match=r"^config/config\.yaml: soils\[0\]: expected a soil file .*no-such-soil\.yaml"):
        load_workflow_config(cfg, "config/config.yaml")


@pytest.mark.parametrize("name", ["My-Soil", "my_soil", "-my-soil"])
def test_workflow_config_soil_name_in_words(name):
    with pytest.raises(InputError) as e:
        load_workflow_config({"soils": [name]}, "config/config.yaml")
    assert e.value.path == "config/config.yaml" and e.value.field == "soils[0]" and e.value.got == name
    assert e.value.expected.startswith("an id of lower-case letters, digits and hyphens")


def test_workflow_config_error_names_where_the_key_was_given(workspace):
    """A key given by a --configfile or by --config on the command line (Snakemake), not by
    config/config.yaml, is named where it was given."""
    cfg = {"soils": ["no-such-soil"], "soil_dir": str(workspace / "config/soils")}
    with pytest.raises(InputError) as e:
        load_workflow_config(cfg, "config/config.yaml", origins={"soils": "mine.yaml"})
    assert e.value.path == "mine.yaml" and e.value.field == "soils[0]"
    with pytest.raises(InputError) as e:
        load_workflow_config(dict(cfg, design="adaptve"), "config/config.yaml",
                             origins={"design": "<command line: --config>"})
    assert e.value.path == "<command line: --config>" and e.value.field == "design"


def test_yaml_exponent_without_sign_is_a_number(workspace):
    from soilcal.config import read_yaml

    p = workspace / "x.yaml"
    p.write_text("g: 7.9e10\nh: 1e7\n")
    assert read_yaml(p) == {"g": 7.9e10, "h": 1e7}


def _typed(v):
    """``v`` with every scalar beside its type and every mapping as its (key, value) pairs in
    order, so that == also compares types (1 == 1.0 == True) and key order."""
    if isinstance(v, dict):
        return ("dict", [(_typed(k), _typed(x)) for k, x in v.items()])
    if isinstance(v, list):
        return ("list", [_typed(x) for x in v])
    return (type(v).__name__, repr(v))


@pytest.mark.parametrize("rel", sorted(str(p.relative_to(ROOT)) for d in ("config", "src", "resources", "workflow")
                                       for p in (ROOT / d).rglob("*.yaml")))
def test_every_yaml_file_reads_as_the_pure_python_loader_reads_it(rel):
    # read_yaml and the photo manifests parse with libyaml; PyYAML's pure-Python SafeLoader (with
    # read_yaml's rules: load._Loader) is the reference
    from soilcal.config import load

    text = (ROOT / rel).read_text(encoding="utf-8")
    assert _typed(load.read_yaml(ROOT / rel)) == _typed(yaml.load(text, Loader=load._Loader))  # noqa: S506
    # the manifests' loader (libyaml's, where PyYAML has it)
    c_loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    assert _typed(yaml.load(text, Loader=c_loader)) == _typed(yaml.safe_load(text))  # noqa: S506


@pytest.mark.skipif(not hasattr(yaml, "CSafeLoader"), reason="PyYAML built without libyaml")
def test_a_soil_is_read_by_libyaml_where_pyyaml_has_it(monkeypatch):
    """read_yaml parses with libyaml first: a pure-Python loader that cannot parse leaves the
    reading of a valid file unchanged (it is the fallback for errors only)."""
    from soilcal.config import load

    class Broken(load._Loader):
        def get_single_data(self):
            raise AssertionError("the pure-Python loader read a valid file")

    expected = load.read_yaml(ROOT / "config/soils/black-soil.yaml")
    monkeypatch.setattr(load, "_Loader", Broken)
    assert load.read_yaml(ROOT / "config/soils/black-soil.yaml") == expected


def test_the_soil_schema_is_a_fresh_copy_each_time():
    """The schema is parsed once per process; a caller's edit of its copy reaches no other."""
    from soilcal.config.load import schema_defaults, soil_schema

    first = soil_schema()
    before = schema_defaults()
    first["properties"].clear()
    assert soil_schema()["properties"] and schema_defaults() == before


def test_bbd_run_counts():
    # Box-Behnken with the papers' centre points: 29 runs for 4 factors, 17 for 3 (5 centres).
    four = {"kind": "box_behnken", "factors": dict.fromkeys("ABCD", {}), "center_points": 5}
    three = {"kind": "box_behnken", "factors": dict.fromkeys("ABC", {}), "center_points": 5}
    assert design_runs(four) == 29 and design_runs(three) == 17


def test_the_once_check_counts_two_ids_as_one_where_the_dem_maps_them_to_one_field():
    """Two parameter ids are one DEM parameter where the DEM's mapping (dem_field) gives them
    one field: a pair written soil_soil (as a soil built in code may write it) and soil-soil,
    both restitution, are soil_soil_restitution, so a factor on one and a fixed value of the
    other set it twice."""
    from soilcal.config.load import _check_stage_sets_each_parameter_once
    from soilcal.dem.scenarios.base import dem_field

    params = {"e_a": {"unit": "-", "pair": "soil-soil", "kind": "restitution"},
              "e_b": {"unit": "-", "pair": "soil_soil", "kind": "restitution"}}
    data = {"parameters": params}
    assert dem_field("s.yaml", data, "e_a", "x")[0] == dem_field("s.yaml", data, "e_b", "x")[0] \
        == "soil_soil_restitution"
    st = {"factors": {"A": {"parameter": "e_a", "low": 0.2, "high": 0.6}}, "fixed": {"e_b": 0.4}}
    with pytest.raises(InputError) as e:
        _check_stage_sets_each_parameter_once(Path("s.yaml"), "stages[0]", st, params)
    assert (e.value.field, e.value.got) == ("stages[0].fixed.e_b", "e_b")
    assert "(DEM parameter soil_soil_restitution)" in e.value.expected
