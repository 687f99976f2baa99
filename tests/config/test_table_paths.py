"""A soil's tables stay in its own folders: a stage's printed table under
``resources/published/<soil>/`` and a target's table under ``resources/measurements/<soil>/``.
A path that climbs out (``..``) or is absolute is refused at load, naming the field, even
where a real table sits at the place it points to."""

from __future__ import annotations

import shutil

import pytest
import yaml

from soilcal.config.load import load_soil
from soilcal.errors import InputError
from wfutil import copy_soil


def _soil(tmp_path, edit):
    p = copy_soil(tmp_path, "cinnamon-soil")
    d = yaml.safe_load(p.read_text())
    edit(d)
    p.write_text(yaml.safe_dump(d, sort_keys=False))
    return p


def _stage(d, sid):
    return next(s for s in d["stages"] if s["id"] == sid)


@pytest.mark.parametrize("escape", ["../other-soil/bbd.csv", "sub/../../other-soil/bbd.csv", "ABSOLUTE"])
def test_a_printed_table_outside_the_soils_published_folder_is_refused(tmp_path, escape):
    pub = tmp_path / "resources/published"
    (pub / "other-soil").mkdir(parents=True)
    elsewhere = pub / "other-soil/bbd.csv"
    # a real copy of the stage's own table, so only its path can be what is refused
    p = _soil(tmp_path, lambda d: None)
    shutil.copy(pub / "cinnamon-soil/bbd.csv", elsewhere)
    table = str(elsewhere) if escape == "ABSOLUTE" else escape
    d = yaml.safe_load(p.read_text())
    _stage(d, "bbd")["table"] = table
    p.write_text(yaml.safe_dump(d, sort_keys=False))
    with pytest.raises(InputError) as e:
        load_soil(p, tmp_path / "resources")
    i = [s["id"] for s in d["stages"]].index("bbd")
    assert e.value.field == f"stages[{i}].table" and e.value.got == table
    assert f"a table inside {pub / 'cinnamon-soil'}/" in e.value.expected


def test_a_target_table_outside_the_soils_measurements_folder_is_refused(tmp_path):
    meas = tmp_path / "resources/measurements"
    p = _soil(tmp_path, lambda d: None)
    (meas / "other-soil").mkdir(parents=True)
    shutil.copy(meas / "cinnamon-soil/cutting_resistance.csv", meas / "other-soil/angles.csv")
    d = yaml.safe_load(p.read_text())
    tid = next(iter(d["targets"]))
    d["targets"][tid]["table"] = "../other-soil/angles.csv"
    p.write_text(yaml.safe_dump(d, sort_keys=False))
    with pytest.raises(InputError) as e:
        load_soil(p, tmp_path / "resources")
    assert e.value.field == f"targets.{tid}.table" and e.value.got == "../other-soil/angles.csv"
    assert f"a table inside {meas / 'cinnamon-soil'}/" in e.value.expected


def test_tables_in_a_subfolder_of_the_soils_own_folders_load(tmp_path):
    p = _soil(tmp_path, lambda d: None)
    pub = tmp_path / "resources/published/cinnamon-soil"
    (pub / "2021").mkdir()
    shutil.move(pub / "bbd.csv", pub / "2021/bbd.csv")
    d = yaml.safe_load(p.read_text())
    _stage(d, "bbd")["table"] = "2021/./bbd.csv"
    p.write_text(yaml.safe_dump(d, sort_keys=False))
    soil = load_soil(p, tmp_path / "resources")
    assert soil.table_path("bbd") == pub / "2021/./bbd.csv"
