"""A corpus of broken inputs, each built into a temporary folder from a shipped soil.

Every case is one broken input a user may hand to soilcal: a soil YAML, a printed design table,
a measured table, a photo or its manifest, scenario settings, command-line arguments or the
workflow config.  ``Case.build(tmp)`` writes the inputs under ``tmp`` (paths relative to it)
and returns the ``soilcal`` arguments that read them; run from ``tmp``, the command must stop
with exactly one line

    soilcal: error: <file>: <field>: expected <expected>, got <got>

naming ``Case.file``, ``Case.field`` and ``Case.expected``, exit with status 2, print no
traceback, and leave the output folder ``Case.out`` as it was.

Used by ``tests/corpus/test_corpus.py`` and ``benchmarks/broken_inputs.py``.
"""

from __future__ import annotations

import shutil
import struct
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import yaml
from wfutil import copy_soil

ROOT = Path(__file__).resolve().parents[2]
CMD = "<command line>"

#: input kinds, in report order
KINDS = ("soil_yaml", "printed_table", "measurement_table", "photo", "scenario", "cli", "workflow_config")


@dataclass(frozen=True)
class Case:
    id: str
    kind: str
    build: Callable[[Path], list[str]]
    file: str
    field: str
    expected: str
    out: str = "out"
    #: also run as a subprocess of ``python -m soilcal.cli`` (exit status, no traceback)
    subprocess: bool = False
    #: also run ``snakemake -n`` on a copy of the workflow with this input
    snakemake: bool = False


CASES: list[Case] = []


def case(id, kind, file, field, expected, out="out", subprocess=False, snakemake=False):
    assert kind in KINDS, kind

    def deco(fn):
        assert all(c.id != id for c in CASES), id
        CASES.append(Case(id, kind, fn, file, field, expected, out, subprocess, snakemake))
        return fn

    return deco


# ------------------------------------------------------------------ helpers


def edit_yaml(path: Path, fn) -> None:
    data = yaml.safe_load(path.read_text())
    fn(data)
    path.write_text(yaml.safe_dump(data, sort_keys=False))


def edit_text(path: Path, old: str, new: str) -> None:
    text = path.read_text()
    assert old in text, (path, old)
    path.write_text(text.replace(old, new, 1))


def replay(soil: str = "cinnamon-soil") -> list[str]:
    return ["replay", f"config/soils/{soil}.yaml", "--resources", "resources", "--out", "out"]


def soil_case(id, file, field, expected, soil="cinnamon-soil", kind="soil_yaml", **kw):
    """A case that edits a copy of ``soil`` (the decorated function gets tmp and the YAML path)
    and replays it into out/."""

    def deco(fn):
        def build(tmp: Path) -> list[str]:
            fn(tmp, copy_soil(tmp, soil))
            return replay(soil)

        build.__doc__ = fn.__doc__
        case(id, kind, file, field, expected, **kw)(build)
        return fn

    return deco


def stage(d, sid):
    return next(s for s in d["stages"] if s["id"] == sid)


MINIMAL_TABLE = """run,A,B,C,angle
1,-1,-1,0,29.81
2,-1,1,0,28.83
3,1,-1,0,31.13
4,1,1,0,33.63
5,-1,0,-1,29.86
6,-1,0,1,27.74
7,1,0,-1,32.39
8,1,0,1,30.73
9,0,-1,-1,29.14
10,0,-1,1,29.00
11,0,1,-1,31.87
12,0,1,1,28.69
13,0,0,0,29.92
14,0,0,0,29.80
15,0,0,0,29.68
"""

MINIMAL_SOIL = {
    "name": "my-soil",
    "parameters": {
        "rolling": {"name": "Soil-soil rolling friction", "unit": "-"},
        "energy": {"name": "JKR surface energy", "unit": "J/m^2"},
        "steel": {"name": "Soil-steel static friction", "unit": "-"},
    },
    "stages": [{
        "id": "bbd", "kind": "box_behnken",
        "factors": {"A": {"parameter": "rolling", "low": 0.1, "high": 0.3},
                    "B": {"parameter": "energy", "low": 2.0, "high": 6.0},
                    "C": {"parameter": "steel", "low": 0.4, "high": 0.8}},
        "center_points": 3, "table": "bbd.csv",
        "responses": [{"id": "angle", "name": "Repose angle", "unit": "deg"}],
        "optimise": {"method": "desirability",
                     "cases": [{"id": "angle", "goals": {"angle": {"goal": "target", "target": "angle"}}}]},
    }],
    "targets": {"angle": {"value": 33.5, "unit": "deg"}},
}


def minimal_soil(tmp: Path, edit=None) -> Path:
    """The minimal soil of the README (one Box-Behnken table, three factors, one target)."""
    import copy

    data = copy.deepcopy(MINIMAL_SOIL)
    if edit:
        edit(data)
    (tmp / "config/soils").mkdir(parents=True, exist_ok=True)
    (tmp / "resources/published/my-soil").mkdir(parents=True, exist_ok=True)
    (tmp / "resources/published/my-soil/bbd.csv").write_text(MINIMAL_TABLE)
    p = tmp / "config/soils/my-soil.yaml"
    p.write_text(yaml.safe_dump(data, sort_keys=False))
    return p


def _png_chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def png_header(width: int, height: int) -> bytes:
    """A PNG that declares ``width`` x ``height`` pixels (grey, 8 bit) and holds almost none."""
    return (b"\x89PNG\r\n\x1a\n" + _png_chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0))
            + _png_chunk(b"IDAT", zlib.compress(b"\x00" * 64)) + _png_chunk(b"IEND", b""))


PILE = ROOT / "resources/images/cinnamon-soil/stacking_1.jpg"
DRUM = ROOT / "resources/images/xinjiang-vineyard/drum_upper_f01.jpg"
FURROW = ROOT / "resources/images/yangtze-clay-loam/furrow.jpg"


def small_pile(dst: Path) -> Path:
    """The cinnamon heap photo at half size (measured in a second instead of four)."""
    from PIL import Image

    with Image.open(PILE) as im:
        im.resize((im.width // 2, im.height // 2), Image.LANCZOS).save(dst, quality=92)
    return dst


def photo_dir(tmp: Path) -> Path:
    d = tmp / "photos"
    d.mkdir(exist_ok=True)
    return d


def pile_args(name: str) -> list[str]:
    return ["image", "pile", f"photos/{name}", "--figures", "out"]


def image(tmp: Path, name: str, mode: str, size=(400, 300), colour=0) -> Path:
    from PIL import Image

    p = photo_dir(tmp) / name
    Image.new(mode, size, colour).save(p)
    return p


MANIFEST = "resources/images/cinnamon-soil/manifest.yaml"


def manifest_case(id, field, expected, file=MANIFEST, **kw):
    """A case that edits a copy of the cinnamon soil's photo manifest (the function gets tmp and
    the manifest's data, edited in place) and measures it into out/."""

    def deco(fn):
        def build(tmp: Path) -> list[str]:
            copy_soil(tmp)
            m = tmp / "resources/images/cinnamon-soil/manifest.yaml"
            data = yaml.safe_load(m.read_text())
            fn(tmp, data)
            if data is not None:
                m.write_text(yaml.safe_dump(data, sort_keys=False))
            return ["image", "soil", MANIFEST, "--figures", "out"]

        case(id, "photo", file, field, expected, **kw)(build)
        return fn

    return deco


def scenario(*args) -> Callable[[Path], list[str]]:
    def build(tmp: Path) -> list[str]:
        return ["scenario", "run", *args, "--out", "out/row.csv"]

    return build


def workflow_config(tmp: Path, edit) -> list[str]:
    copy_soil(tmp)
    cfg = {"soils": ["cinnamon-soil"], "soil_dir": "config/soils", "resources": "resources"}
    edit(cfg)
    (tmp / "config/config.yaml").write_text(yaml.safe_dump(cfg, sort_keys=False))
    return ["config", "check", "--workflow", "config/config.yaml"]


SOIL = "config/soils/cinnamon-soil.yaml"
BBD = "resources/published/cinnamon-soil/bbd.csv"
MEAS = "resources/measurements/cinnamon-soil/cutting_resistance.csv"


# ================================================================== soil YAML


@soil_case("unknown-top-level-key", SOIL, "stage", "one of the known fields", subprocess=True)
def _(tmp, p):
    edit_yaml(p, lambda d: d.update(stage=[]))


@soil_case("misspelt-stage-field", SOIL, "stages[2].centre_points", "one of the known fields")
def _(tmp, p):
    edit_text(p, "center_points: 5", "centre_points: 5")


@soil_case("seed-not-an-integer", SOIL, "seed", "a value of type integer")
def _(tmp, p):
    edit_text(p, "seed: 1082", "seed: abc")


@soil_case("seed-negative", SOIL, "seed", "a number >= 0")
def _(tmp, p):
    edit_text(p, "seed: 1082", "seed: -1")


@soil_case("name-not-the-file-name", SOIL, "name", "the file name without .yaml")
def _(tmp, p):
    edit_text(p, "name: cinnamon-soil", "name: cinnamon")


@soil_case("name-with-spaces", SOIL, "name", "text matching")
def _(tmp, p):
    edit_text(p, "name: cinnamon-soil", "name: Cinnamon Soil")


@soil_case("factor-low-above-high", SOIL, "stages[2].factors.B.low", "a number below high (0.52)")
def _(tmp, p):
    edit_yaml(p, lambda d: stage(d, "bbd")["factors"]["B"].update(low=0.6))


@soil_case("factor-low-equals-high", SOIL, "stages[2].factors.A.low", "a number below high (0.14)")
def _(tmp, p):
    edit_yaml(p, lambda d: stage(d, "bbd")["factors"]["A"].update(low=0.14))


@soil_case("factor-centre-outside-range", SOIL, "stages[2].factors.C.centre", "a number between low (0.42) and high (0.66)")
def _(tmp, p):
    edit_yaml(p, lambda d: stage(d, "bbd")["factors"]["C"].update(centre=0.9))


@soil_case("factor-level-not-a-number", SOIL, "stages[2].factors.C.high", "a value of type number")
def _(tmp, p):
    edit_yaml(p, lambda d: stage(d, "bbd")["factors"]["C"].update(high="0.66 (steel)"))


@soil_case("factor-unknown-parameter", SOIL, "stages[2].factors.A.parameter", "an id listed under parameters")
def _(tmp, p):
    edit_yaml(p, lambda d: stage(d, "bbd")["factors"]["A"].update(parameter="soil_soil_rolling"))


@soil_case("factor-without-parameter", SOIL, "stages[2].factors.A.parameter", "a required field")
def _(tmp, p):
    edit_yaml(p, lambda d: stage(d, "bbd")["factors"]["A"].pop("parameter"))


@soil_case("fixed-unknown-parameter", SOIL, "stages[2].fixed.soil_restitution", "an id listed under parameters")
def _(tmp, p):
    edit_yaml(p, lambda d: stage(d, "bbd")["fixed"].update(soil_restitution=0.4))


@soil_case("missing-table-file", SOIL, "stages[2].table", "an existing file")
def _(tmp, p):
    (tmp / BBD).unlink()


@soil_case("table-name-not-csv", SOIL, "stages[2].table", "text matching")
def _(tmp, p):
    edit_yaml(p, lambda d: stage(d, "bbd").update(table="bbd.xlsx"))


@soil_case("unknown-stage-kind", SOIL, "stages[2].kind", "one of plackett_burman, steepest_ascent, box_behnken")
def _(tmp, p):
    edit_yaml(p, lambda d: stage(d, "bbd").update(kind="central_composite"))


@soil_case("duplicate-stage-id", SOIL, "stages[2].id", "a stage id used once")
def _(tmp, p):
    edit_yaml(p, lambda d: stage(d, "bbd").update(id="pb"))


@soil_case("from-stage-unknown", SOIL, "stages[2].from_stage", "the id of an earlier stage")
def _(tmp, p):
    edit_yaml(p, lambda d: stage(d, "bbd").update(from_stage="climbing"))


@soil_case("stages-missing", SOIL, "stages", "a required field")
def _(tmp, p):
    edit_yaml(p, lambda d: d.pop("stages"))


@soil_case("stages-empty", SOIL, "stages", "a list of at least 1 item")
def _(tmp, p):
    edit_yaml(p, lambda d: d.update(stages=[]))


@soil_case("response-id-with-spaces", SOIL, "stages[2].responses[0].id", "text matching")
def _(tmp, p):
    edit_yaml(p, lambda d: stage(d, "bbd")["responses"][0].update(id="Stacking angle"))


@soil_case("transform-unknown", SOIL, "stages[2].transform.stacking_angle", "one of none, sqrt, log, inverse")
def _(tmp, p):
    edit_yaml(p, lambda d: stage(d, "bbd").update(transform={"stacking_angle": "cube"}))


@soil_case("goal-unknown-target", SOIL, "stages[2].optimise.cases[0].goals.stacking_angle.target",
           "an id listed under targets")
def _(tmp, p):
    edit_yaml(p, lambda d: stage(d, "bbd")["optimise"]["cases"][0]["goals"]["stacking_angle"].update(target="angle"))


@soil_case("goal-unknown-response", SOIL, "stages[2].optimise.cases[0].goals.angle", "a response id of this stage")
def _(tmp, p):
    def edit(d):
        goals = stage(d, "bbd")["optimise"]["cases"][0]["goals"]
        goals["angle"] = goals.pop("stacking_angle")
    edit_yaml(p, edit)


@soil_case("chosen-step-off-the-path", SOIL, "stages[1].chosen_step", "a step number of the path")
def _(tmp, p):
    edit_yaml(p, lambda d: stage(d, "steepest").update(chosen_step=9))


@soil_case("path-levels-of-unequal-length", SOIL, "stages[1].factors", "the same number of levels for every factor")
def _(tmp, p):
    edit_yaml(p, lambda d: stage(d, "steepest")["factors"]["A"]["levels"].pop())


@soil_case("target-value-text", SOIL, "targets.stacking_angle.value", "a value of type number or null")
def _(tmp, p):
    edit_yaml(p, lambda d: d["targets"]["stacking_angle"].update(value="27.69 deg"))


@soil_case("target-unknown-photo-group", SOIL, "targets.stacking_angle.image", "a photo group of")
def _(tmp, p):
    edit_yaml(p, lambda d: d["targets"]["stacking_angle"].update(image="heap"))


@soil_case("printed-anova-file-missing", SOIL, "stages[2].printed.stacking_angle.anova_full", "an existing file")
def _(tmp, p):
    (tmp / "resources/published/cinnamon-soil/bbd_anova_full.csv").unlink()


@soil_case("yaml-syntax-error", SOIL, "line 17", "valid YAML", subprocess=True)
def _(tmp, p):
    edit_text(p, "seed: 1082", "seed: [1082")


@soil_case("yaml-key-given-twice", SOIL, "line 17", "each key once per mapping ('seed' is first given on line 16)")
def _(tmp, p):
    edit_text(p, "seed: 1082\n", "seed: 1082\nseed: 7\n")


@soil_case("yaml-not-utf8", SOIL, "<file>", "a UTF-8 text file")
def _(tmp, p):
    p.write_bytes(p.read_bytes().replace(b"Luoyang", "Lu\xf6yang".encode("latin-1"), 1))


@soil_case("yaml-empty-file", SOIL, "<root>", "a mapping of soil fields")
def _(tmp, p):
    p.write_text("")


@soil_case("yaml-a-list", SOIL, "<root>", "a mapping of soil fields")
def _(tmp, p):
    p.write_text("- name: cinnamon-soil\n- seed: 1\n")


@case("soil-file-missing", "soil_yaml", "config/soils/my-soil.yaml", "<file>", "an existing YAML file", subprocess=True)
def _(tmp):
    return replay("my-soil")


@case("minimal-soil-goal-without-targets", "soil_yaml", "config/soils/my-soil.yaml",
      "stages[0].optimise.cases[0].goals.angle.target", "an id listed under targets")
def _(tmp):
    minimal_soil(tmp, lambda d: d.pop("targets"))
    return replay("my-soil")


@case("minimal-soil-citation-unknown-field", "soil_yaml", "config/soils/my-soil.yaml", "citation.authour",
      "one of the known fields")
def _(tmp):
    minimal_soil(tmp, lambda d: d.update(citation={"authour": "A. User"}))
    return replay("my-soil")


@case("minimal-soil-no-parameters", "soil_yaml", "config/soils/my-soil.yaml", "parameters", "a required field")
def _(tmp):
    minimal_soil(tmp, lambda d: d.pop("parameters"))
    return replay("my-soil")


# ================================================================== printed tables


def table_case(id, field, expected, file=BBD, **kw):
    def deco(fn):
        def build(tmp):
            copy_soil(tmp)
            path = tmp / file
            fn(path)
            return replay()

        case(id, "printed_table", file, field, expected, **kw)(build)
        return fn

    return deco


def _rows(path: Path) -> list[str]:
    return path.read_text().splitlines()


def _set_cell(path: Path, row: int, column: str, value: str) -> None:
    lines = _rows(path)
    head = lines[0].split(",")
    cells = lines[row].split(",")
    cells[head.index(column)] = value
    lines[row] = ",".join(cells)
    path.write_text("\n".join(lines) + "\n")


def _drop_column(path: Path, column: str) -> None:
    lines = [ln.split(",") for ln in _rows(path)]
    j = lines[0].index(column)
    path.write_text("\n".join(",".join(c for k, c in enumerate(ln) if k != j) for ln in lines) + "\n")


@table_case("table-missing-response-column", "columns", "columns A, B, C, stacking_angle")
def _(path):
    _drop_column(path, "stacking_angle")


@table_case("table-missing-factor-column", "columns", "columns A, B, C, stacking_angle")
def _(path):
    _drop_column(path, "B")


@table_case("table-text-in-a-response-cell", "row 3, column stacking_angle", "a number")
def _(path):
    _set_cell(path, 3, "stacking_angle", "27.5a")


@table_case("table-text-in-a-factor-cell", "row 4, column C", "a number")
def _(path):
    _set_cell(path, 4, "C", "zero")


@table_case("table-empty-factor-cell", "row 2, column A", "a number")
def _(path):
    _set_cell(path, 2, "A", "")


@table_case("table-infinite-response", "row 6, column stacking_angle", "a finite number")
def _(path):
    _set_cell(path, 6, "stacking_angle", "inf")


@table_case("table-row-missing", "rows", "17 rows for the box_behnken design of stage 'bbd'", subprocess=True)
def _(path):
    path.write_text("\n".join(_rows(path)[:-1]) + "\n")


@table_case("table-row-extra", "rows", "17 rows for the box_behnken design of stage 'bbd'")
def _(path):
    lines = _rows(path)
    path.write_text("\n".join(lines + ["18,0,0,0,26.9"]) + "\n")


@table_case("table-empty-file", "<file>", "a readable CSV table")
def _(path):
    path.write_text("")


@table_case("table-header-only", "rows", "17 rows")
def _(path):
    path.write_text(_rows(path)[0] + "\n")


@table_case("table-duplicated-run-id", "row 5, column run", "a run number used once", subprocess=True, snakemake=True)
def _(path):
    _set_cell(path, 5, "run", "4")


@table_case("table-coded-level-out-of-range", "column A", "coded levels -1/0/1")
def _(path):
    _set_cell(path, 1, "A", "2")


@table_case("table-ragged-row", "line 4", "5 fields")
def _(path):
    lines = _rows(path)
    lines[3] += ",1"
    path.write_text("\n".join(lines) + "\n")


@table_case("table-binary-file", "<file>", "a readable CSV table")
def _(path):
    path.write_bytes(bytes(range(256)) * 4)


@table_case("path-table-without-step-column", "columns", "columns step, A, B, C, stacking_angle",
            file="resources/published/cinnamon-soil/steepest.csv")
def _(path):
    _drop_column(path, "step")


@table_case("screening-table-centre-level", "column X3", "coded levels -1/1",
            file="resources/published/cinnamon-soil/pb.csv")
def _(path):
    _set_cell(path, 2, "X3", "0")


# ================================================================== measured tables


def meas_case(id, file, field, expected, soil="cinnamon-soil", **kw):
    def deco(fn):
        def build(tmp):
            p = copy_soil(tmp, soil)
            fn(tmp, p)
            return replay(soil)

        case(id, "measurement_table", file, field, expected, **kw)(build)
        return fn

    return deco


CUT = "measurements.cutting_resistance"


@meas_case("measured-table-missing-column", SOIL, f"{CUT}.covariates.directrix", "a column of cutting_resistance.csv",
           subprocess=True)
def _(tmp, p):
    _drop_column(tmp / MEAS, "directrix")


@meas_case("measured-table-undeclared-column", MEAS, "column speed_m_s", "a column declared in cinnamon-soil.yaml")
def _(tmp, p):
    lines = _rows(tmp / MEAS)
    lines = [lines[0] + ",speed_m_s"] + [ln + ",0.16" for ln in lines[1:]]
    (tmp / MEAS).write_text("\n".join(lines) + "\n")


@meas_case("measured-value-not-a-number", MEAS, "row 2, column horizontal_measured_N", "a number")
def _(tmp, p):
    _set_cell(tmp / MEAS, 2, "horizontal_measured_N", "252.1 N")


@meas_case("measured-value-empty", MEAS, "row 3, column vertical_measured_N", "the measured vertical_force_N")
def _(tmp, p):
    _set_cell(tmp / MEAS, 3, "vertical_measured_N", "")


@meas_case("measured-setup-value-not-mapped", MEAS, "row 1, column directrix", "a value mapped under")
def _(tmp, p):
    _set_cell(tmp / MEAS, 1, "directrix", "zigzag")


@meas_case("measured-response-unit-wrong", SOIL, f"{CUT}.responses[0].unit", "N (the unit of horizontal_force_N")
def _(tmp, p):
    # a length for a force (kN would be converted to N)
    edit_yaml(p, lambda d: d["measurements"]["cutting_resistance"]["responses"][0].update(unit="mm"))


@meas_case("measured-set-column-named-in-km-h", SOIL, f"{CUT}.covariates.speed_kmh",
           "the unit of the cells, which the column's name says are in km/h")
def _(tmp, p):
    """A speed column in km/h set as the plate's speed (m/s) with no unit and no scale."""
    lines = _rows(tmp / MEAS)
    lines = [lines[0] + ",speed_kmh"] + [ln + ",0.576" for ln in lines[1:]]
    (tmp / MEAS).write_text("\n".join(lines) + "\n")
    edit_yaml(p, lambda d: d["measurements"]["cutting_resistance"]["covariates"].update(speed_kmh={"set": "speed"}))


@meas_case("measured-quantity-unit-unknown", "config/soils/black-soil.yaml",
           "measurements.surface_flatness.covariates.rotor_speed_rpm.unit", "a unit of rotor_speed", soil="black-soil")
def _(tmp, p):
    edit_yaml(p, lambda d: d["measurements"]["surface_flatness"]["covariates"]["rotor_speed_rpm"].update(unit="rpm/s"))


@meas_case("measured-quantity-unit-on-a-label", SOIL, f"{CUT}.covariates.directrix.unit", "no unit: tool is a label")
def _(tmp, p):
    edit_yaml(p, lambda d: d["measurements"]["cutting_resistance"]["covariates"]["directrix"].update(unit="mm"))


@meas_case("measured-table-missing-file", SOIL, f"{CUT}.table", "an existing file")
def _(tmp, p):
    (tmp / MEAS).unlink()


@meas_case("measured-table-empty-file", MEAS, "<file>", "a readable CSV table")
def _(tmp, p):
    (tmp / MEAS).write_text("")


@meas_case("measured-table-header-only", MEAS, "rows", "at least one row")
def _(tmp, p):
    (tmp / MEAS).write_text(_rows(tmp / MEAS)[0] + "\n")


@meas_case("measured-table-decimal-commas", MEAS, "line 2", "5 fields, as many as the header")
def _(tmp, p):
    """Every measured force typed with an unquoted decimal comma: one field more per row."""
    for row, value in enumerate(("321,10", "252,10", "154,50", "304,80"), start=1):
        _set_cell(tmp / MEAS, row, "horizontal_measured_N", value)


@meas_case("measured-table-semicolons", MEAS, "<file>", "a comma-separated table with decimal points")
def _(tmp, p):
    """The table exported by a spreadsheet set to a decimal comma: ';' between the fields."""
    import csv

    rows = list(csv.reader(_rows(tmp / MEAS)))
    (tmp / MEAS).write_text("\n".join(";".join(c.replace(".", ",") for c in r) for r in rows) + "\n")


@meas_case("measured-table-column-twice", MEAS, "column directrix", "a column named once in the header")
def _(tmp, p):
    lines = _rows(tmp / MEAS)
    (tmp / MEAS).write_text("\n".join([lines[0].replace("plate,", "directrix ,", 1)] + lines[1:]) + "\n")


@meas_case("measured-covariate-two-forms", SOIL, f"{CUT}.covariates.plate", "exactly one of setup, set, param, case, ignore")
def _(tmp, p):
    edit_yaml(p, lambda d: d["measurements"]["cutting_resistance"]["covariates"]["plate"].update(param="soil_density"))


@meas_case("measured-calibrated-case-unknown", SOIL, f"{CUT}.calibrated.case", "a case id of stage 'bbd'")
def _(tmp, p):
    edit_yaml(p, lambda d: d["measurements"]["cutting_resistance"]["calibrated"].update(case="angle"))


@meas_case("measured-sd-negative", MEAS, "row 2, column horizontal_sd_N", "a standard deviation > 0")
def _(tmp, p):
    """An SD column beside the horizontal force, with a minus sign in row 2."""
    lines = _rows(tmp / MEAS)
    sds = ["horizontal_sd_N", "12.5", "-8.1", "6.0", "9.4"]
    (tmp / MEAS).write_text("\n".join(f"{ln},{sd}" for ln, sd in zip(lines, sds)) + "\n")
    edit_yaml(p, lambda d: d["measurements"]["cutting_resistance"]["responses"][0].update(sd="horizontal_sd_N"))


@meas_case("measured-sd-is-the-value-column", SOIL, f"{CUT}.responses[0].sd",
           "a column with one role (horizontal_measured_N is already the value column")
def _(tmp, p):
    edit_yaml(p, lambda d: d["measurements"]["cutting_resistance"]["responses"][0].update(sd="horizontal_measured_N"))


@meas_case("measured-table-outside-its-folder", SOIL, f"{CUT}.table", "a table inside resources/measurements/cinnamon-soil/")
def _(tmp, p):
    """The table named by a path that climbs out of the soil's measurements folder."""
    (tmp / "resources/outside.csv").write_text((tmp / MEAS).read_text())
    edit_yaml(p, lambda d: d["measurements"]["cutting_resistance"].update(table="../../outside.csv"))


@meas_case("measured-stage-not-simulated", SOIL, f"{CUT}.calibrated.stage",
           "a stage the DEM simulates (simulation.stages: pb, steepest)")
def _(tmp, p):
    edit_yaml(p, lambda d: d["simulation"].update(stages=["pb", "steepest"]))


@meas_case("measured-speed-kmh-without-scale", SOIL, f"{CUT}.covariates.speed_kmh.scale",
           "0.2778 (km/h to m/s, the unit of setup key speed)")
def _(tmp, p):
    """A plate-speed column in km/h whose covariate declares the unit but converts nothing."""
    lines = _rows(tmp / MEAS)
    speeds = ["speed_kmh", "0.576", "0.576", "1.8", "3.6"]
    (tmp / MEAS).write_text("\n".join(f"{ln},{v}" for ln, v in zip(lines, speeds)) + "\n")
    edit_yaml(p, lambda d: d["measurements"]["cutting_resistance"]["covariates"].update(
        speed_kmh={"set": "speed", "quantity": "tool_speed", "unit": "km/h"}))


@meas_case("measured-rotor-speed-not-a-number", "resources/measurements/black-soil/surface_flatness.csv",
           "row 2, column rotor_speed_rpm", "a value mapped under", soil="black-soil")
def _(tmp, p):
    _set_cell(tmp / "resources/measurements/black-soil/surface_flatness.csv", 2, "rotor_speed_rpm", "fast")


# ================================================================== photos


@case("photo-empty-file", "photo", "photos/empty.jpg", "file", "a complete, readable image", subprocess=True)
def _(tmp):
    (photo_dir(tmp) / "empty.jpg").write_bytes(b"")
    return pile_args("empty.jpg")


@case("photo-truncated-png", "photo", "photos/cut.png", "file", "a complete, readable image")
def _(tmp):
    from PIL import Image

    p = photo_dir(tmp) / "cut.png"
    Image.open(PILE).save(p)
    p.write_bytes(p.read_bytes()[: p.stat().st_size // 2])
    return pile_args("cut.png")


@case("photo-truncated-jpeg", "photo", "photos/cut.jpg", "file", "a complete, readable image")
def _(tmp):
    data = PILE.read_bytes()
    (photo_dir(tmp) / "cut.jpg").write_bytes(data[: len(data) // 2])
    return pile_args("cut.jpg")


@case("photo-text-file-named-png", "photo", "photos/notes.png", "file", "a complete, readable image")
def _(tmp):
    (photo_dir(tmp) / "notes.png").write_text("heap 1: 27.5 deg\n")
    return pile_args("notes.png")


@case("photo-pdf-named-jpg", "photo", "photos/scan.jpg", "file", "a complete, readable image (JPEG/PNG/TIFF/HEIC)")
def _(tmp):
    (photo_dir(tmp) / "scan.jpg").write_bytes(b"%PDF-1.4\n1 0 obj<<>>endobj\ntrailer<<>>\n%%EOF\n")
    return pile_args("scan.jpg")


@case("photo-huge-dimensions", "photo", "photos/huge.png", "file", "an image of at most 64 megapixels",
      subprocess=True)
def _(tmp):
    (photo_dir(tmp) / "huge.png").write_bytes(png_header(100_000, 100_000))
    return pile_args("huge.png")


@case("photo-above-the-pixel-limit", "photo", "photos/big.png", "file", "an image of at most 64 megapixels")
def _(tmp):
    (photo_dir(tmp) / "big.png").write_bytes(png_header(12_000, 9_000))
    return pile_args("big.png")


@case("photo-too-small", "photo", "photos/thumb.png", "file", "an image of at least 64 x 64 pixels")
def _(tmp):
    image(tmp, "thumb.png", "RGB", (48, 36), (120, 90, 60))
    return pile_args("thumb.png")


@case("photo-all-black", "photo", "photos/black.jpg", "image", "a photo with contrast", subprocess=True)
def _(tmp):
    image(tmp, "black.jpg", "RGB")
    return pile_args("black.jpg")


@case("photo-cmyk-blank", "photo", "photos/cmyk.jpg", "image", "a photo with contrast")
def _(tmp):
    image(tmp, "cmyk.jpg", "CMYK", colour=(0, 0, 0, 255))
    return pile_args("cmyk.jpg")


@case("photo-palette-blank", "photo", "photos/palette.png", "image", "a photo with contrast")
def _(tmp):
    image(tmp, "palette.png", "P", colour=3)
    return pile_args("palette.png")


@case("photo-alpha-blank", "photo", "photos/alpha.png", "image", "a photo with contrast")
def _(tmp):
    image(tmp, "alpha.png", "RGBA", colour=(200, 180, 150, 0))
    return pile_args("alpha.png")


@case("photo-uniform-colour", "photo", "photos/wall.png", "image", "a photo with contrast")
def _(tmp):
    image(tmp, "wall.png", "RGB", colour=(200, 180, 150))
    return pile_args("wall.png")


@case("photo-16-bit-blank", "photo", "photos/grey16.png", "image", "a photo with contrast")
def _(tmp):
    image(tmp, "grey16.png", "I;16", colour=40000)
    return pile_args("grey16.png")


@case("photo-missing", "photo", "photos/stacking_3.jpg", "file", "an existing image file")
def _(tmp):
    photo_dir(tmp)
    return pile_args("stacking_3.jpg")


@case("photo-second-of-two-broken", "photo", "photos/b.jpg", "file", "a complete, readable image")
def _(tmp):
    small_pile(photo_dir(tmp) / "a.jpg")
    (photo_dir(tmp) / "b.jpg").write_bytes(PILE.read_bytes()[:2000])
    return ["image", "pile", "photos/a.jpg", "photos/b.jpg", "--figures", "out"]


@case("drum-frame-text-file", "photo", "photos/frame.bmp", "file", "a complete, readable image (BMP/PNG/TIFF/JPEG/HEIC)")
def _(tmp):
    (photo_dir(tmp) / "frame.bmp").write_text("frame 1\n")
    return ["image", "drum", "photos/frame.bmp", "--figures", "out"]


@case("drum-frame-16-bit-blank", "photo", "photos/frame16.png", "image", "a frame with contrast")
def _(tmp):
    image(tmp, "frame16.png", "I;16", (256, 256), 65535)
    return ["image", "drum", "photos/frame16.png", "--figures", "out"]


@case("furrow-without-scale", "photo", "photos/furrow.jpg", "scale_length_mm", "--scale-length-mm or a manifest.yaml")
def _(tmp):
    shutil.copy(FURROW, photo_dir(tmp) / "furrow.jpg")
    return ["image", "furrow", "photos/furrow.jpg", "--figures", "out"]


@manifest_case("manifest-misspelt-field", "photos[0].scale_lenght_mm", "one of the known fields")
def _(tmp, m):
    m["photos"][0]["scale_lenght_mm"] = m["photos"][0].pop("scale_length_mm")


@manifest_case("manifest-unknown-kind", "photos[1].kind", "one of ('pile', 'drum', 'furrow')")
def _(tmp, m):
    m["photos"][1]["kind"] = "heap"


@manifest_case("manifest-photo-missing", "photos[1].file", "an existing image file")
def _(tmp, m):
    (tmp / "resources/images/cinnamon-soil/stacking_2.jpg").unlink()


@manifest_case("manifest-scale-negative", "photos[0].scale_length_mm", "a positive length")
def _(tmp, m):
    m["photos"][0]["scale_length_mm"] = -100.0


@manifest_case("manifest-scale-text", "photos[1].scale_length_mm", "a positive length")
def _(tmp, m):
    m["photos"][1]["scale_length_mm"] = "100 mm"


@manifest_case("manifest-group-mixes-kinds", "photos[1].kind", "pile, the kind of the other photos of group 'stacking'")
def _(tmp, m):
    m["photos"][1]["kind"] = "drum"


@manifest_case("manifest-bad-threshold", "threshold", "one of otsu, adaptive")
def _(tmp, m):
    m["threshold"] = "triangle"


@manifest_case("manifest-drum-option-out-of-range", "photos[0].chord_fraction", "a fraction of the chord in [0.1, 1]")
def _(tmp, m):
    m["photos"] = [{"file": "stacking_1.jpg", "kind": "drum", "group": "dynamic", "chord_fraction": 1.5}]


@manifest_case("manifest-second-group-broken", "file", "a complete, readable image",
               file="resources/images/cinnamon-soil/stacking_2.jpg")
def _(tmp, m):
    # the first group measures; the second's photo is broken: no figure of the first may stay
    small_pile(tmp / "resources/images/cinnamon-soil/stacking_1.jpg")
    (tmp / "resources/images/cinnamon-soil/stacking_2.jpg").write_bytes(b"")
    m["photos"][1]["group"] = "second"


# ================================================================== scenario settings


case("scenario-unknown", "scenario", CMD, "scenario", "one of bulldozing, compression, drum", subprocess=True)(
    scenario("heap"))
case("scenario-unknown-setup", "scenario", CMD, "setup", "one of black-soil-stage1")(
    scenario("repose", "--setup", "loam-100mm"))
case("scenario-negative-particle-count", "scenario", CMD, "setup.n_particles", "an integer >= 20", subprocess=True)(
    scenario("repose", "--set", "n_particles=-10"))
case("scenario-particle-count-text", "scenario", CMD, "setup.n_particles", "an integer >= 20")(
    scenario("repose", "--set", "n_particles=many"))
case("scenario-unknown-setup-key", "scenario", CMD, "setup.tube_diametre", "one of contact_conventions, dt_fraction")(
    scenario("repose", "--set", "tube_diametre=0.06"))
case("scenario-set-without-value", "scenario", CMD, "--set", "key=value")(
    scenario("repose", "--set", "tube_diameter"))
case("scenario-negative-tube", "scenario", CMD, "setup.tube_diameter", "a finite number > 0")(
    scenario("repose", "--set", "tube_diameter=-0.06"))
case("scenario-unknown-method", "scenario", CMD, "setup.method", "'cylinder' or 'funnel'")(
    scenario("repose", "--set", "method=hopper"))
case("scenario-drum-overfilled", "scenario", CMD, "setup.fill_fraction", "a fill fraction in (0, 1]")(
    scenario("drum", "--set", "fill_fraction=2"))
case("scenario-unknown-parameter", "scenario", CMD, "params.soil_friction", "one of soil_soil_restitution")(
    scenario("repose", "--param", "soil_friction=0.5"))
case("scenario-parameter-text", "scenario", CMD, "params.soil_density", "a number")(
    scenario("repose", "--param", "soil_density=heavy"))
case("scenario-negative-density", "scenario", CMD, "params.soil_density", "a density in [100, 25000] kg/m^3")(
    scenario("repose", "--param", "soil_density=-1500"))
case("scenario-unknown-preset", "scenario", CMD, "--preset", "one of ('quick', 'paper')")(
    scenario("repose", "--preset", "fast"))
case("scenario-no-replicates", "scenario", CMD, "--replicates", "an integer >= 1")(
    scenario("repose", "--replicates", "0"))
case("scenario-negative-seed", "scenario", CMD, "--seed", "an integer >= 0")(
    scenario("repose", "--seed", "-3"))


@case("scenario-setups-of-unknown", "scenario", CMD, "scenario", "one of bulldozing")
def _(tmp):
    return ["scenario", "setups", "pile"]


@soil_case("simulation-unknown-scenario", SOIL, "simulation.responses.stacking_angle.scenario", "one of bulldozing",
           kind="scenario")
def _(tmp, p):
    edit_yaml(p, lambda d: d["simulation"]["responses"]["stacking_angle"].update(scenario="heap"))


@soil_case("simulation-unknown-setup", SOIL, "simulation.responses.stacking_angle.setup", "a setup of repose",
           kind="scenario")
def _(tmp, p):
    edit_yaml(p, lambda d: d["simulation"]["responses"]["stacking_angle"].update(setup="cinnamon"))


@soil_case("simulation-unknown-measure", SOIL, "simulation.responses.stacking_angle.measure", "angle_deg",
           kind="scenario")
def _(tmp, p):
    edit_yaml(p, lambda d: d["simulation"]["responses"]["stacking_angle"].update(measure="angle"))


@soil_case("simulation-negative-particle-count", SOIL, "simulation.responses.stacking_angle.set.n_particles",
           "an integer >= 20", kind="scenario")
def _(tmp, p):
    edit_yaml(p, lambda d: d["simulation"]["responses"]["stacking_angle"].update(set={"n_particles": -500}))


@soil_case("simulation-unknown-parameter", SOIL, "simulation.params.soil_densty", "one of soil_soil_restitution",
           kind="scenario")
def _(tmp, p):
    edit_yaml(p, lambda d: d["simulation"].update(params={"soil_densty": 1394}))


@soil_case("simulation-density-in-g-per-cm3", SOIL, "simulation.params.soil_density",
           "a density in [100, 25000] kg/m^3 (a value in g/cm^3 times 1000)", kind="scenario")
def _(tmp, p):
    edit_yaml(p, lambda d: d["simulation"].update(params={"soil_density": 1.394}))


@soil_case("simulation-paper-psd-in-millimetres", SOIL, "simulation.responses.stacking_angle.set.paper_psd",
           "particle radii in metres", kind="scenario")
def _(tmp, p):
    edit_yaml(p, lambda d: d["simulation"]["responses"]["stacking_angle"].update(
        set={"paper_psd": [[1.5, 8.85], [1.0, 8.2], [0.5, 82.95]]}))


@soil_case("property-poisson-ratio-in-percent", SOIL, "properties.poisson_ratio.unit", "one of -, Pa, kPa")
def _(tmp, p):
    edit_yaml(p, lambda d: d["properties"]["poisson_ratio"].update(value=31.1, unit="%"))


@soil_case("loop-bounds-as-a-list", SOIL, "loop.bounds.rate_friction", "a mapping parameter -> [low, high]")
def _(tmp, p):
    edit_yaml(p, lambda d: d.update(loop={"bounds": {"rate_friction": [0, 0.2]}}))


@soil_case("loop-fold-by-not-a-covariate", SOIL, "loop.fold_by",
           "a covariate column of the soil's measured tables (directrix, plate)")
def _(tmp, p):
    edit_yaml(p, lambda d: d.update(loop={"fold_by": "day"}))


@soil_case("simulation-screening-more-factors-than-screened", SOIL, "simulation.screening.min_factors",
           "an integer <= 7, the factor count of screening stage 'pb'", kind="scenario")
def _(tmp, p):
    edit_yaml(p, lambda d: d["simulation"].update(screening={"min_factors": 8}))


@soil_case("simulation-bad-preset", SOIL, "simulation.preset", "one of quick, paper", kind="scenario")
def _(tmp, p):
    edit_yaml(p, lambda d: d["simulation"].update(preset="fast"))


@soil_case("simulation-no-replicates", SOIL, "simulation.replicates", "a number >= 1", kind="scenario")
def _(tmp, p):
    edit_yaml(p, lambda d: d["simulation"].update(replicates=0))


@soil_case("simulation-unknown-path-choice", SOIL, "simulation.path.choose", "one of fitted, closest")
def _(tmp, p):
    edit_yaml(p, lambda d: d["simulation"].update(path={"choose": "nearest"}))


# ================================================================== command-line arguments


@case("cli-unknown-command", "cli", CMD, "command", "one of 'config', 'image'", subprocess=True)
def _(tmp):
    return ["replya", "config/soils/cinnamon-soil.yaml"]


@case("cli-unknown-option", "cli", CMD, "--output", "an option or argument of soilcal replay", subprocess=True)
def _(tmp):
    copy_soil(tmp)
    return ["replay", "config/soils/cinnamon-soil.yaml", "--output", "out"]


@case("cli-missing-argument", "cli", CMD, "soil", "a value for each required argument of soilcal replay")
def _(tmp):
    return ["replay", "--out", "out"]


@case("cli-not-an-integer", "cli", CMD, "--replicates", "an integer", subprocess=True)
def _(tmp):
    return ["scenario", "run", "repose", "--replicates", "two", "--out", "out/row.csv"]


@case("cli-not-a-choice", "cli", CMD, "--threshold", "one of 'otsu', 'adaptive'")
def _(tmp):
    shutil.copy(PILE, photo_dir(tmp) / "a.jpg")
    return ["image", "pile", "photos/a.jpg", "--threshold", "triangle", "--figures", "out"]


@case("cli-option-without-value", "cli", CMD, "--threshold", "one argument")
def _(tmp):
    shutil.copy(PILE, photo_dir(tmp) / "a.jpg")
    return ["image", "pile", "photos/a.jpg", "--figures", "out", "--threshold"]


@case("cli-group-without-command", "cli", CMD, "command", "a value for each required argument of soilcal scenario")
def _(tmp):
    return ["scenario"]


@case("cli-config-check-nothing", "cli", CMD, "files", "a soil YAML file or --workflow CONFIG")
def _(tmp):
    return ["config", "check"]


@case("cli-manifest-missing", "cli", "photos/manifest.yaml", "manifest", "a readable YAML file")
def _(tmp):
    photo_dir(tmp)
    return ["image", "soil", "photos/manifest.yaml", "--figures", "out"]


@case("cli-furrow-degree-zero", "cli", CMD, "--degree", "an integer polynomial degree from 1 to 15")
def _(tmp):
    shutil.copy(FURROW, photo_dir(tmp) / "furrow.jpg")
    return ["image", "furrow", "photos/furrow.jpg", "--scale-length-mm", "440", "--degree", "0", "--figures", "out"]


@case("cli-furrow-negative-scale", "cli", CMD, "--scale-length-mm", "a positive length of the beam in mm")
def _(tmp):
    shutil.copy(FURROW, photo_dir(tmp) / "furrow.jpg")
    return ["image", "furrow", "photos/furrow.jpg", "--scale-length-mm", "-440", "--figures", "out"]


@case("cli-drum-chord-out-of-range", "cli", CMD, "--chord-fraction", "a fraction of the chord in [0.1, 1]")
def _(tmp):
    shutil.copy(DRUM, photo_dir(tmp) / "f.jpg")
    return ["image", "drum", "photos/f.jpg", "--chord-fraction", "1.5", "--figures", "out"]


@case("cli-out-is-a-file", "cli", "out/cinnamon-soil", "<file>", "a path that can be read or written", out="out",
      subprocess=True)
def _(tmp):
    copy_soil(tmp)
    (tmp / "out").mkdir()
    (tmp / "out/cinnamon-soil").write_text("not a folder\n")
    return ["replay", "config/soils/cinnamon-soil.yaml", "--resources", "resources", "--out", "out"]


@case("cli-loop-unknown-measurement", "cli", SOIL, "measurements", "the id of a measured table (cutting_resistance)")
def _(tmp):
    copy_soil(tmp)
    return ["loop", "run", SOIL, "--measurement", "cutting_force", "--out", "out"]


@case("cli-loop-parameter-without-value", "cli", CMD, "--param", "NAME=NUMBER, a DEM parameter and its SI value")
def _(tmp):
    copy_soil(tmp)
    return ["loop", "run", SOIL, "--param", "soil_density", "--out", "out"]



@case("cli-bench-negative-count", "cli", CMD, "--n", "a number of spheres >= 1", subprocess=True)
def _(tmp):
    return ["bench", "settle", "--n", "-5"]


@case("cli-bench-zero-skin", "cli", CMD, "--skin", "a neighbour skin > 0 m")
def _(tmp):
    return ["bench", "settle", "--n", "200", "--skin", "0"]


@case("cli-scenario-zero-threads", "cli", CMD, "--threads", "an integer in [1, ")
def _(tmp):
    return ["scenario", "run", "repose", "--threads", "0", "--out", "out/row.csv"]


# ================================================================== workflow config


@case("workflow-unknown-soil", "workflow_config", "config/config.yaml", "soils[0]",
      "a soil file config/soils/cinnamon.yaml", subprocess=True, snakemake=True)
def _(tmp):
    return workflow_config(tmp, lambda c: c.update(soils=["cinnamon"]))


@case("workflow-unknown-source", "workflow_config", "config/config.yaml", "source", "one of published, dem, both")
def _(tmp):
    return workflow_config(tmp, lambda c: c.update(source="edem"))


@case("workflow-unknown-key", "workflow_config", "config/config.yaml", "soil_folder", "one of the known fields")
def _(tmp):
    return workflow_config(tmp, lambda c: c.update(soil_folder="soils"))


@case("workflow-no-soils", "workflow_config", "config/config.yaml", "soils", "a list of at least 1 item")
def _(tmp):
    return workflow_config(tmp, lambda c: c.update(soils=[]))


@case("workflow-soil-name-with-spaces", "workflow_config", "config/config.yaml", "soils[0]", "text matching")
def _(tmp):
    return workflow_config(tmp, lambda c: c.update(soils=["Cinnamon soil"]))


@case("workflow-soil-name-with-capitals-and-underscores", "workflow_config", "config/config.yaml", "soils[0]",
      "an id of lower-case letters, digits and hyphens", snakemake=True)
def _(tmp):
    return workflow_config(tmp, lambda c: c.update(soils=["Cinnamon_Soil"]))


@case("soil-name-with-capitals-and-underscores", "soil_yaml", "config/soils/My_Soil.yaml", "name",
      "an id of lower-case letters, digits and hyphens")
def _(tmp):
    p = minimal_soil(tmp, lambda d: d.update(name="My_Soil"))
    p.rename(tmp / "config/soils/My_Soil.yaml")
    return ["config", "check", "config/soils/My_Soil.yaml"]


@case("soil-name-not-the-file-name", "workflow_config", "config/soils/cinnamon-soil.yaml", "name",
      "the file name without .yaml ('cinnamon-soil')", snakemake=True)
def _(tmp):
    argv = workflow_config(tmp, lambda c: None)
    edit_yaml(tmp / SOIL, lambda d: d.update(name="cinnamon"))
    return argv


@case("workflow-design-adaptive-tolerance-of-no-response", "workflow_config", SOIL,
      "simulation.adaptive.tolerances.angle", "a response of a stage the adaptive design runs (stacking_angle)")
def _(tmp):
    # the soil's own design (recipe) does not read the block; the config's design: adaptive does
    argv = workflow_config(tmp, lambda c: c.update(design="adaptive"))
    edit_yaml(tmp / SOIL, lambda d: d["simulation"].update(adaptive={"tolerances": {"angle": {"pct": 2}}}))
    return argv


@case("workflow-photo-of-the-manifest-missing", "workflow_config", MANIFEST, "photos[1].file", "an existing image file")
def _(tmp):
    # the workflow's start-up reads every soil's photo manifest; so does the config check
    argv = workflow_config(tmp, lambda c: None)
    (tmp / "resources/images/cinnamon-soil/stacking_2.jpg").unlink()
    return argv


@case("workflow-config-missing", "workflow_config", "config/config.yaml", "<file>", "an existing YAML file")
def _(tmp):
    return ["config", "check", "--workflow", "config/config.yaml"]


def by_id(case_id: str) -> Case:
    return next(c for c in CASES if c.id == case_id)
