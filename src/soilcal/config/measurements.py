"""Measured tool and process tests of a soil, declared as data in its ``measurements`` block.

A calibrated DEM is verified against measured tests the calibration did not use (soil-bin
forces, rotary tiller power and surface flatness, confined compression).  Each test is one
CSV table under ``resources/measurements/<soil>/`` (a ``table`` path that leaves that folder is
refused) and one entry of the soil's ``measurements`` block, keyed by an id
(``^[a-z][a-z0-9_]*$``)::

    measurements:
      cutting_resistance:
        table: cutting_resistance.csv       # one row = one simulated condition
        source: "Sec. 4.3, Figure 12b"
        scenario: bulldozing                 # scenario that simulates one row
        setup: plate-line                    # its default named setup
        set: {}                              # setup overrides for every row (optional)
        params: {}                           # DEM parameter overrides, SI, every row (optional)
        covariates:                          # table column -> how it maps onto the simulation
          directrix: {setup: {arc: plate-arc, parabola: plate-parabola, line: plate-line}}
          plate: {ignore: true, note: "plate number"}
        ignore_columns: [source]             # further columns that change nothing (optional)
        responses:
          - {measure: horizontal_force_N, value: horizontal_measured_N, unit: N}
        calibrated: {stage: bbd, case: stacking_angle}
        replicates: 3                        # seeds per row (default 3)
        preset: quick                        # quick (default) or paper

Covariate forms (exactly one per column):

* ``{setup: {value: setup-name}}``: the row runs that named setup of the scenario;
* ``{set: key, scale: s}``: setup key ``key`` = cell value * ``s`` (default 1);
* ``{param: name, scale: s}``: DEM parameter ``name`` (:class:`~soilcal.dem.scenarios.base.DemParams`)
  = cell value * ``s``;
* ``{case: {value: case-id}}``: the row uses the optimum of that case of the calibrated stage;
* ``{ignore: true}``: an id or label column that does not change the simulation.

Any covariate may also say which physical quantity its column holds (``quantity``, one of
:data:`soilcal.config.quantities.QUANTITIES`, with ``unit`` for a numeric one: ``rotor_speed_rpm: {setup: {...},
quantity: rotor_speed, unit: r/min}``).  The measured-data loop (:mod:`soilcal.loop`) tests the
residual against every covariate column, and its model extensions act through these
quantities (a rate effect through ``tool_speed`` or ``rotor_speed``, moisture-dependent
cohesion through ``moisture_content``), converted to the SI unit of :data:`QUANTITIES`.
A cell of a numeric quantity must be a number, and above zero for
:data:`POSITIVE_QUANTITIES`.  A ``set`` or ``param`` covariate with a ``unit`` must have the
``scale`` that takes that unit to the unit the setup key (:data:`SETUP_KEY_UNITS`) or DEM
parameter (:func:`param_unit`) is taken in, where that unit is known and is one of the
quantity's units (``{set: speed, quantity: tool_speed, unit: km/h}`` needs ``scale: 0.2778``).

Response columns: ``value`` (the measured value; ``null`` when the paper does not print it,
then a ``note`` is required and the row is simulated and reported without a measured value),
``sd`` (the measured standard deviation, a number > 0; a blank cell where it is not known), ``n`` (the repeats behind the value, a
whole number >= 1; with ``n`` 1 or a blank ``n`` the SD is the value's own uncertainty, which
the measured-data loop takes as known), ``paper_simulated`` (the paper's own simulation),
``paper_difference`` (the printed simulated - measured difference).  The measure's unit
follows from its name's suffix (:data:`UNIT_SUFFIXES`; a name without one is dimensionless,
unit ``-``); ``unit`` is the unit of the table's columns: the measure's own, or another unit of
its quantity (:data:`RESPONSE_UNITS`: kN for a force in N, cm for a flatness in mm, % for a
dimensionless strain), whose value, SD, paper's simulated value and difference are converted
to the measure's unit as the table is read (the row's note says so); a unit of another
quantity is refused.  Every table column must be a covariate, a
response column or listed under ``ignore_columns``, so that a column nobody declared (a
second speed, a depth) cannot be silently left out of the simulation, and in one role only: a
response's ``sd`` naming its own ``value`` column, or a covariate that is also a response
column or listed under ``ignore_columns``, is refused (one ``n`` column may serve several
responses).

:func:`check_measurements` validates the block at start-up (called by the config loader);
:func:`conditions` returns one :class:`Condition` per table row.  ``Condition.params`` is the
soil's ``simulation.params``, then the entry's ``params``, then the row's ``param``
covariates (later wins); the calibrated stage's optimum is applied on top of these by the
runner (``stage``, ``case``).
"""

from __future__ import annotations

import functools
import math
import os
import re
import string
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from soilcal.config.quantities import (  # noqa: F401 (QUANTITIES re-exported)
    LENGTH_FACTORS,
    MILLIPASCAL,
    MOISTURE_UNITS,
    NONNEGATIVE_QUANTITIES,
    PLAUSIBLE,
    POSITIVE_QUANTITIES,
    QUANTITIES,
    UNIT_SYMBOLS,
    UNIT_CASES,
    quantity_factor,
    unit_powers,
)
from soilcal.errors import EMPTY_CELL, InputError

BLOCK = "measurements"
DEFAULT_REPLICATES = 3
DEFAULT_PRESET = "quick"

#: measure-name suffix -> unit the response's ``unit`` must equal (suffixes matched without
#: regard to case, so ``stress_10_kpa`` is in kPa); a measure without a suffix is
#: dimensionless (``-``)
UNIT_SUFFIXES = (
    ("_kPa", "kPa"),
    ("_Pa", "Pa"),
    ("_kW", "kW"),
    ("_Nm", "N m"),
    ("_N", "N"),
    ("_mm", "mm"),
    ("_dm2", "dm^2"),
    ("_deg", "deg"),
    ("_m", "m"),
)
DIMENSIONLESS = "-"

#: the units a measured response may be given in, per quantity, with their factor to the
#: first: a table in another unit of its measure's quantity (kN for ``horizontal_force_N``, cm
#: for ``flatness_mm``, % for a dimensionless strain) is converted to the measure's unit as it
#: is read; a unit of another quantity is refused
RESPONSE_UNITS = (
    {"N": 1.0, "kN": 1e3, "mN": 1e-3, "lbf": UNIT_SYMBOLS["lbf"][0]},
    dict(LENGTH_FACTORS),
    {"m^2": 1.0, "dm^2": 1e-2, "cm^2": 1e-4, "mm^2": 1e-6},
    {"deg": 1.0, "rad": 180.0 / math.pi},
    {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "psi": UNIT_SYMBOLS["psi"][0]},
    {"W": 1.0, "kW": 1e3},
    {"N m": 1.0, "kN m": 1e3},
    {DIMENSIONLESS: 1.0, "%": 1e-2},
)
#: other spellings of those units
UNIT_ALIASES = {"dm2": "dm^2", "m2": "m^2", "cm2": "cm^2", "mm2": "mm^2", "Nm": "N m", "N*m": "N m",
                "N.m": "N m", "N·m": "N m", "kNm": "kN m", "kN*m": "kN m", "kN.m": "kN m", "kN·m": "kN m",
                "°": "deg", "degree": "deg", "degrees": "deg"}

_FORMS = ("setup", "set", "param", "case", "ignore")
_RESPONSE_COLUMNS = ("value", "sd", "n", "paper_simulated", "paper_difference")

#: scenario -> setup key -> the unit the scenario takes the key in, for the keys a measured
#: quantity (:data:`QUANTITIES`) can set and whose unit the scenario module documents: the
#: speeds and depths of the soil-bin tools (bulldozing and furrow ``setups()``: "0.16 m/s",
#: "0.72 m/s", depths in m in ``validate``), the rotary tiller's ``rpm`` ("blade shaft speed,
#: r/min"), ``forward_speed`` ("1 km/h in m/s") and ``depth`` (m, ``validate``), the
#: compression rod's speed (module docstring, "0.008 m/s"), the repose cylinder's lift and the
#: funnel cover's speeds ("lifted at 0.05 m/s", "cover_speed (1 m/s)") and the drum's ``rpm``
#: ("7 r/min", omega = 2 pi rpm / 60).  A key not listed has no documented unit here, and the
#: ``scale`` of a covariate that sets it is not checked against its declared ``unit``.
SETUP_KEY_UNITS = {
    "bulldozing": {"speed": "m/s", "depth": "m"},
    "furrow": {"speed": "m/s", "depth": "m"},
    "rotary": {"rpm": "r/min", "forward_speed": "m/s", "depth": "m"},
    "compression": {"rod_speed": "m/s"},
    "repose": {"lift_speed": "m/s", "cover_speed": "m/s"},
    "drum": {"rpm": "r/min"},
}
#: relative tolerance of a covariate's ``scale`` against its unit's factor (0.2778 for 1/3.6)
SCALE_RTOL = 1e-3


def param_unit(name: str) -> str:
    """The unit a DEM parameter is taken in (:class:`~soilcal.dem.scenarios.base.DemParams`:
    SI throughout, densities in kg/m^3, shear moduli in Pa, surface energies in J/m^2, the
    coefficients and ratios dimensionless)."""
    for suffix, unit in (("_density", "kg/m^3"), ("_shear_modulus", "Pa"), ("_surface_energy", "J/m^2")):
        if name.endswith(suffix):
            return unit
    return DIMENSIONLESS


@dataclass(frozen=True)
class Condition:
    """One row of a measured table as a simulation: what to run and what it is compared to."""

    measurement: str
    row: int
    label: str
    covariate: str
    covariate_value: str
    scenario: str
    setup: dict
    params: dict
    stage: str
    case: str
    preset: str
    replicates: int
    responses: tuple
    #: every covariate column of the row (ignored ones too) -> its cell (numbers as float)
    covariates: dict = None
    #: declared quantity -> the row's value in the quantity's SI unit (a label for a tool/day/group)
    quantities: dict = None
    #: covariate column -> its declared quantity
    quantity_columns: dict = None
    #: where the row differs from others only in ignored covariates (a tool, a slightly
    #: different moisture): the rows simulated alike with it and the values the simulation
    #: leaves out (:func:`_shared_runs`); empty otherwise
    note: str = ""


#: the seeds of one measured condition's runs lie in a block of their own, ``SEED_BLOCK`` apart
#: per block (:func:`condition_seed`); ``SEED_BLOCKS`` blocks, chosen by a digest of what the
#: condition simulates
SEED_BLOCK = 1000
SEED_BLOCKS = 1_000_000


def condition_seed(cond: Condition, seed: int) -> int:
    """The DEM seed of run ``seed`` of a measured condition: ``seed + SEED_BLOCK * b``, with
    ``b`` in [0, SEED_BLOCKS) from a digest of what the condition simulates (its scenario,
    setup, parameters, calibrated stage and case, and preset).

    Each measured test is a sample of its own (a soil bed prepared anew, a fresh fill of the
    tube), so its simulated mean must scatter independently of the other conditions': the
    statistics of the measured-data loop (:mod:`soilcal.loop`) take every condition's seed error
    as its own.  With one seed list for every condition, the runs of one seed share its settled
    soil bin (:func:`soilcal.dem.scenarios.soilbin.settled_bin`, cached by seed) or its fill: on
    the cinnamon soil's quick line plate the logarithms of the horizontal force at (0.2 m/s, 25 mm),
    (0.8 m/s, 35 mm) and (0.4 m/s, 30 mm) correlated by 0.48, 0.26 and 0.12 over 30 seeds, so
    three seeds' common error moved every condition's mean alike, which the loop's bias test,
    taking the conditions as independent, would read as a bias.  Rows that simulate the same
    condition (a test measured twice or tabled twice) share its block, and so one simulation;
    the runs of one condition at different effect parameters share its seeds (common random
    numbers: the design points of an effect are compared on the same samples).  Two conditions
    whose digests fall in one block share seeds again, as every condition did before; among 20
    conditions that happens with probability about 2e-4."""
    import hashlib
    import json

    what = [cond.scenario, cond.setup, cond.params, cond.stage, cond.case, cond.preset]
    digest = hashlib.sha1(json.dumps(what, sort_keys=True, default=str).encode()).hexdigest()
    return int(seed) + SEED_BLOCK * (int(digest[:12], 16) % SEED_BLOCKS)


def unit_of(measure: str) -> str:
    """The unit a measure's name implies (:data:`UNIT_SUFFIXES`)."""
    low = measure.lower()
    for suffix, unit in UNIT_SUFFIXES:
        if low.endswith(suffix.lower()):
            return unit
    return DIMENSIONLESS


def response_units(measure: str) -> dict:
    """The units a measured ``measure`` may be given in, with their factor to its own unit
    (:func:`unit_of`, :data:`RESPONSE_UNITS`)."""
    want = unit_of(measure)
    for family in RESPONSE_UNITS:
        if want in family:
            return {u: f / family[want] for u, f in family.items()}
    return {want: 1.0}


def unit_factor(unit, measure: str) -> float | None:
    """Factor from ``unit`` to the unit of ``measure`` (:func:`response_units`), or None when
    ``unit`` is not a unit of its quantity.  The whole text must be one unit
    (:func:`whole_unit`: a spelling of :data:`UNIT_ALIASES`, ``KN``, ``N m``, ``m2``); a text
    that holds a unit among other words or numbers (``x1000 N``, ``0.1 kN``, ``N, mean of 3``)
    is none: what those add cannot be read."""
    return response_units(measure).get(whole_unit(unit))


def measurements_dir(resources_root, soil_name: str) -> Path:
    return Path(resources_root) / BLOCK / soil_name


def unread_files(data: dict, resources_root) -> list[str]:
    """A note per file under the soil's measurement folder (:func:`measurements_dir`) that the
    soil file names nowhere (no ``measurements.<id>.table``, no text of it mentions the file's
    path in the folder): a table put beside the others and not declared is read by nothing,
    and its rows would be left out of every comparison without a word."""
    folder = measurements_dir(resources_root, data.get("name", ""))
    if not folder.is_dir():
        return []
    texts = []

    def walk(v):
        if isinstance(v, str):
            texts.append(v)
        elif isinstance(v, dict):
            for x in v.values():
                walk(x)
        elif isinstance(v, (list, tuple)):
            for x in v:
                walk(x)

    walk(data)
    out = []
    for f in sorted(p for p in folder.rglob("*") if p.is_file() and not p.name.startswith(".")):
        rel = f.relative_to(folder).as_posix()
        named = re.compile(r"(?<![\w.-])" + re.escape(rel) + r"(?![\w-])")
        if any(named.search(t) for t in texts):
            continue
        what = ("declare it as a measurement's table (measurements.<id>.table) to compare the model with it"
                if f.suffix.lower() == ".csv" else "soilcal reads measured tables as CSV: save it as one and declare it "
                "as a measurement's table (measurements.<id>.table)")
        out.append(f"{folder / rel} is named nowhere in the soil file: it is not read ({what})")
    return out


def _text(v) -> str:
    """A cell or map key as text: 150, 150.0 and "150" all read "150"."""
    if isinstance(v, bool):
        return str(v).lower()
    if isinstance(v, (int, float)) or hasattr(v, "dtype"):
        try:
            x = float(v)
        except (TypeError, ValueError):
            return str(v).strip()
        if math.isfinite(x) and x == int(x):
            return str(int(x))
        return f"{x:g}"
    return str(v).strip()


#: a number written as text ("5.0", "17.20", "-3", ".5", "1e3"), as a map key quoted in the YAML
_NUMERIC_TEXT = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?")


def _numeric_column(cv: dict) -> bool:
    """Whether a covariate's cells are numbers of a physical quantity (``quantity`` one of the
    numeric :data:`QUANTITIES`: moisture, speed, depth, ...), not labels (a tool id, a day, a
    group, or a column that declares no quantity)."""
    return QUANTITIES.get(cv.get("quantity")) is not None


def _map_key(v, numeric: bool):
    """A ``setup`` or ``case`` map key, or the cell looked up in the map, as it is compared
    (:func:`_same_key`).  In a column of a numeric quantity (``numeric``) a number, or text
    that is a number (a key quoted in the YAML, ``"5.0"`` or ``"17.20"``), is that number, a
    float: a quoted ``"17.20"`` and a cell 17.2 are one value.  Otherwise, and in a label
    column (a tool id, a revision), whose cells are read as the table writes them
    (:func:`_label_column`), text: ``"007"`` and ``"7"`` are two tools, ``"1.10"`` and ``"1.1"``
    two revisions; an unquoted number key is the text :func:`_text` writes (``7`` is ``"7"``),
    a key with decimals in full (``1.0000004`` is not ``"1"``)."""
    if numeric:
        if isinstance(v, str):
            if _NUMERIC_TEXT.fullmatch(v.strip()):
                return float(v)
        elif (x := _number(v)) is not None:
            return x
    elif isinstance(v, float) and math.isfinite(v) and v != int(v):
        return repr(v)
    return _text(v)


def _same_key(a, b) -> bool:
    """Two map keys or a key and a cell (:func:`_map_key`) are one value: numbers equal within
    :func:`soilcal.config.quantities.same_number` (relative 1e-9, as a moisture is compared
    with the soil's), text as written."""
    from soilcal.config.quantities import same_number

    if isinstance(a, float) and isinstance(b, float):
        return same_number(a, b)
    return a == b


def _key_text(k) -> str:
    return f"{k:.15g}" if isinstance(k, float) else str(k)


def _check_map_keys(soil_path, field: str, amap: dict, numeric: bool) -> None:
    """Two keys of one ``setup`` or ``case`` map that are the same value (``5`` and ``"5.0"``
    in a numeric column, :func:`_map_key`) would send the rows at it to one of two entries:
    refused naming both."""
    seen = []
    for k in amap:
        key = _map_key(k, numeric)
        first = next((f for f, fk in seen if _same_key(key, fk)), None)
        if first is not None:
            raise InputError(soil_path, f"{field}.{k}", f"a value not already mapped ({first!r} is the same "
                             f"value, {_key_text(key)})", k)
        seen.append((k, key))


def _missing(v) -> bool:
    if v is None:
        return True
    if isinstance(v, str):
        return v.strip() == ""
    try:
        return bool(pd.isna(v))
    except (TypeError, ValueError):
        return False


def _number(v):
    """The cell as a float, or None if it is not a number."""
    if isinstance(v, bool):
        return None
    try:
        x = float(v)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None


def _plain(v):
    """A table cell as a plain Python value (numbers as float, text as str)."""
    x = _number(v)
    return x if x is not None else str(v).strip()


def _label_column(cv: dict) -> bool:
    """Whether a covariate's cells are labels read as the table writes them: a ``setup`` or
    ``case`` map column, or a column of a label quantity (tool, day, group), that declares no
    numeric quantity (:func:`_numeric_column`)."""
    if _numeric_column(cv):
        return False
    return "setup" in cv or "case" in cv or cv.get("quantity") is not None


def _read(soil_path, where: str, tpath: Path, text_columns=()) -> pd.DataFrame:
    from soilcal.config.load import read_table

    if not tpath.is_file():
        raise InputError(soil_path, f"{where}.table", f"an existing file {tpath}", "no such file")
    df = read_table(tpath, text_columns)
    if len(df) == 0:
        raise InputError(tpath, "rows", "at least one row (one measured condition)", 0)
    return df


def _stage_cases(soil_path, data: dict, where: str, entry: dict) -> tuple[dict, list[str]]:
    cal = entry["calibrated"]
    stages = {s["id"]: s for s in data["stages"]}
    sid = cal["stage"]
    if sid not in stages:
        raise InputError(soil_path, f"{where}.calibrated.stage", "the id of a stage (" + ", ".join(stages) + ")", sid)
    # the runner takes the stage's optimum from the DEM source's results: a stage that
    # simulation.stages leaves out would have its DEM jobs started again for this one entry
    if data.get("source", "published") in ("dem", "both") and (data.get("simulation") or {}).get("stages"):
        from soilcal.chain.derive import dem_stage_ids

        simulated = dem_stage_ids(data)
        if sid not in simulated:
            raise InputError(soil_path, f"{where}.calibrated.stage",
                             f"a stage the DEM simulates (simulation.stages: {', '.join(simulated)})", sid)
    opt = stages[sid].get("optimise")
    if not opt:
        with_opt = [s for s, st in stages.items() if st.get("optimise")]
        raise InputError(soil_path, f"{where}.calibrated.stage",
                         "a stage with an optimise block (" + ", ".join(with_opt) + ")", sid)
    return stages[sid], [c["id"] for c in opt["cases"]]


def _check_case_moisture(soil_path, data: dict, stage: dict, cw: str, cv: dict) -> None:
    """A moisture column that chooses the case (``case: {moisture: case id}``) maps each moisture
    to a case calibrated at that moisture: the targets its goals aim at, where they give a
    ``moisture_content`` (in the unit of ``properties.moisture_content``), were measured at it,
    and otherwise the soil declares it (``properties.moisture_content``).  Rows at one moisture
    would otherwise be simulated with the parameters calibrated at another."""
    from soilcal.config.quantities import declares_moisture, same_number, soil_moisture

    declared = soil_moisture(soil_path, data)  # an unknown unit is refused here
    soil_factor = declared["factor"] if declared else None
    soil_unit = declared["unit"] if declared else "%"
    col_factor = quantity_factor("moisture_content", cv["unit"])
    cases = {c["id"]: c for c in (stage.get("optimise") or {}).get("cases", [])}
    targets = data.get("targets") or {}
    for k, cid in cv["case"].items():
        x = _number(k)
        if x is None:
            raise InputError(soil_path, f"{cw}.case.{k}", f"a moisture content in {cv['unit']} (quantity: "
                             "moisture_content)", k)
        pct = x * col_factor
        aimed = [(tid, targets[tid]["moisture_content"]) for g in cases[cid]["goals"].values()
                 if (tid := g.get("target")) in targets and targets[tid].get("moisture_content") is not None]
        if aimed and declared is not None:
            off = [(tid, m) for tid, m in aimed if not same_number(pct, float(m) * soil_factor)]
            if off:
                raise InputError(soil_path, f"{cw}.case.{k}",
                                 f"the moisture content of the targets case {cid!r} aims at ("
                                 + ", ".join(f"targets.{tid}.moisture_content = {m:g} {soil_unit}"
                                             for tid, m in aimed)
                                 + f"), in {cv['unit']}: rows at {k} {cv['unit']} would be simulated with the "
                                   "parameters calibrated at another moisture", k)
            continue
        if declared is None:
            raise InputError(soil_path, f"{cw}.case.{k}", "a moisture content the soil declares "
                             "(properties.moisture_content: value, values or low/high, none given)", k)
        if not declares_moisture(declared, pct):
            raise InputError(soil_path, f"{cw}.case.{k}", f"a moisture content the soil declares in "
                             f"properties.moisture_content ({declared['text']}), in {cv['unit']}, the same "
                             "number: add it to properties.moisture_content.values if the soil was measured at it",
                             k)


def table_inside(soil_path, field: str, folder: Path, table: str) -> Path:
    """``folder / table``; a ``table`` that leaves its folder (the soil's measurements or
    published folder: an absolute path, or one that climbs out with ``..``) is refused.  The
    check is on the path as written: a symbolic link inside the folder is the user's own
    choice and is followed."""
    norm = Path(os.path.normpath(table))
    if Path(table).is_absolute() or norm.is_absolute() or (norm.parts and norm.parts[0] == ".."):
        raise InputError(soil_path, field, f"a table inside {folder}/ (a path relative to it)", table)
    return folder / table


def _entries(soil_path, data: dict, resources_root) -> list[tuple[str, dict, Path, pd.DataFrame, list[Condition]]]:
    """Validate every entry of the block; return (id, entry, table path, table, conditions)."""
    block = data.get(BLOCK) or {}
    out = []
    for mid, entry in block.items():
        tpath = table_inside(soil_path, f"{BLOCK}.{mid}.table", measurements_dir(resources_root, data["name"]),
                            entry["table"])
        df, conds = _entry(soil_path, data, mid, entry, tpath)
        out.append((mid, entry, tpath, df, conds))
    return out


def entry_set_of(soil_path, data: dict, mid: str, entry: dict) -> tuple[dict, dict]:
    """The setup values every row of measurement ``mid`` takes (its ``set``), and for each
    value that the entry does not give itself the field it comes from.

    The particle sizes a soil's surface energy is for are the soil's: where its simulated
    responses give their own (``simulation.responses.<id>.set.paper_psd``, all the same), a
    tool test that leaves ``paper_psd`` out takes them, so that its runs scale the calibrated
    surface energy against the particles it was calibrated for rather than against the named
    setup's (a shipped soil's).  Responses that give different ones leave the test to say
    which: it is refused naming ``measurements.<id>.set.paper_psd``."""
    from soilcal.dem.scenarios import SCENARIOS

    given = dict(entry.get("set") or {})
    mod = SCENARIOS.get(entry.get("scenario"))
    per_row = any(isinstance(cv, dict) and cv.get("set") == "paper_psd"
                  for cv in (entry.get("covariates") or {}).values())
    named = mod.setups().get(entry.get("setup")) if mod is not None else None
    if "paper_psd" in given or per_row or named is None or "paper_psd" not in named:
        return given, {}
    def key(rows):
        try:
            return tuple(tuple(float(v) for v in row) for row in rows)
        except (TypeError, ValueError):
            return repr(rows)

    own, named_of = {}, {}
    for rid, resp in ((data.get("simulation") or {}).get("responses") or {}).items():
        if not isinstance(resp, dict):
            continue
        rows = (resp.get("set") or {}).get("paper_psd")
        if rows is not None:
            own.setdefault(key(rows), []).append(rid)
            continue
        rmod = SCENARIOS.get(resp.get("scenario"))
        rnamed = rmod.setups().get(resp.get("setup")) if rmod is not None else None
        if rnamed is not None and rnamed.get("paper_psd") is not None:
            named_of[rid] = rnamed["paper_psd"]
    if not own:
        return given, {}
    # beside responses that give their own sizes, one that leaves them to its named setup is
    # calibrated for that setup's particles: the soil's responses then disagree
    for rid, rows in named_of.items():
        own.setdefault(key(rows), []).append(f"{rid} (its setup's)")
    if len(own) > 1:
        raise InputError(soil_path, f"{BLOCK}.{mid}.set.paper_psd",
                         "the particle sizes this test's surface energy is for: the soil's simulated "
                         "responses give different ones (" + "; ".join(
                             f"{', '.join(rids)}: {[list(r) for r in rows] if isinstance(rows, tuple) else rows}"
                             for rows, rids in own.items()) + ")", None)
    rid = next(iter(own.values()))[0]
    given["paper_psd"] = data["simulation"]["responses"][rid]["set"]["paper_psd"]
    return given, {"paper_psd": f"simulation.responses.{rid}.set.paper_psd"}


def _entry(soil_path, data: dict, mid: str, entry: dict, tpath: Path):
    from soilcal.dem.scenarios import SCENARIOS, measures_of
    from soilcal.dem.scenarios.base import PRESETS, DemParams, merge_setup

    where = f"{BLOCK}.{mid}"
    src = str(soil_path)

    # -- scenario and named setup
    name = entry["scenario"]
    if name not in SCENARIOS:
        raise InputError(soil_path, f"{where}.scenario", f"one of {', '.join(sorted(SCENARIOS))}", name)
    mod = SCENARIOS[name]
    setups = mod.setups()
    if entry["setup"] not in setups:
        raise InputError(soil_path, f"{where}.setup", f"a setup of {name} ({', '.join(setups)})", entry["setup"])
    preset = entry.get("preset", DEFAULT_PRESET)
    if preset not in PRESETS:  # the schema refuses this already; kept for direct callers
        raise InputError(soil_path, f"{where}.preset", f"one of {', '.join(PRESETS)}", preset)
    entry_set, taken = entry_set_of(soil_path, data, mid, entry)
    try:
        merge_setup(setups, entry["setup"], entry_set, src)
    except InputError as exc:
        raise _renamed(exc, soil_path, "setup.", f"{where}.set.") from None

    # -- parameters every row shares: the soil's simulation.params, then the entry's
    sim_params = dict((data.get("simulation") or {}).get("params") or {})
    entry_params = dict(entry.get("params") or {})
    try:
        DemParams.from_mapping(entry_params, src)
    except InputError as exc:
        raise _renamed(exc, soil_path, "params.", f"{where}.params.") from None
    base_params = {**sim_params, **{k: float(v) for k, v in entry_params.items()}}
    # under them the soil's printed properties, as the runs take them
    from soilcal.chain.provenance import property_base

    soil_base = property_base(soil_path, data)

    # -- calibrated stage and case
    stage, case_ids = _stage_cases(soil_path, data, where, entry)
    cal_case = entry["calibrated"].get("case")
    if cal_case is not None and cal_case not in case_ids:
        raise InputError(soil_path, f"{where}.calibrated.case",
                         f"a case id of stage {stage['id']!r} (" + ", ".join(case_ids) + ")", cal_case)

    # -- covariates (the form of each, before the table is read)
    covs = dict(entry.get("covariates") or {})
    known = DemParams.names()
    setup_cols, case_cols = [], []
    for col, cv in covs.items():
        cw = f"{where}.covariates.{col}"
        forms = [f for f in _FORMS if f in cv and not (f == "ignore" and cv[f] is False)]
        if len(forms) != 1:
            raise InputError(soil_path, cw, "exactly one of " + ", ".join(_FORMS), sorted(cv))
        form = forms[0]
        if form == "ignore" and cv["ignore"] is not True:
            raise InputError(soil_path, f"{cw}.ignore", "true", cv["ignore"])
        if "quantity" in cv:
            q = cv["quantity"]
            if q not in QUANTITIES:
                raise InputError(soil_path, f"{cw}.quantity", "one of " + ", ".join(QUANTITIES), q)
            if QUANTITIES[q] is None and "unit" in cv:
                raise InputError(soil_path, f"{cw}.unit", f"no unit: {q} is a label", cv["unit"])
            if QUANTITIES[q] is not None and quantity_factor(q, cv.get("unit")) is None:
                units = MOISTURE_UNITS if q == "moisture_content" else ", ".join(QUANTITIES[q][1])
                raise InputError(soil_path, f"{cw}.unit", f"a unit of {q} ({units})", cv.get("unit"))
        elif "unit" in cv:
            raise InputError(soil_path, f"{cw}.quantity", "the quantity the unit belongs to", None)
        if "scale" in cv and form not in ("set", "param"):
            raise InputError(soil_path, f"{cw}.scale", "no scale except with set or param", cv["scale"])
        if form == "setup":
            if not cv["setup"]:
                raise InputError(soil_path, f"{cw}.setup", "a map of cell value -> setup name", cv["setup"])
            _check_map_keys(soil_path, f"{cw}.setup", cv["setup"], _numeric_column(cv))
            for k, s in cv["setup"].items():
                if s not in setups:
                    raise InputError(soil_path, f"{cw}.setup.{k}", f"a setup of {name} ({', '.join(setups)})", s)
            setup_cols.append(col)
        elif form == "set":
            key = cv["set"]
            if key not in setups[entry["setup"]]:
                raise InputError(soil_path, f"{cw}.set",
                                 f"a key of the {name} setup {entry['setup']!r} ({', '.join(sorted(setups[entry['setup']]))})",
                                 key)
            if key in entry_set:
                raise InputError(soil_path, f"{cw}.set", f"a setup key not also fixed under {where}.set", key)
        elif form == "param":
            if cv["param"] not in known:
                raise InputError(soil_path, f"{cw}.param", f"a DEM parameter ({', '.join(known)})", cv["param"])
        elif form == "case":
            if not cv["case"]:
                raise InputError(soil_path, f"{cw}.case", "a map of cell value -> case id", cv["case"])
            _check_map_keys(soil_path, f"{cw}.case", cv["case"], _numeric_column(cv))
            for k, c in cv["case"].items():
                if c not in case_ids:
                    raise InputError(soil_path, f"{cw}.case.{k}",
                                     f"a case id of stage {stage['id']!r} (" + ", ".join(case_ids) + ")", c)
            if cv.get("quantity") == "moisture_content":
                _check_case_moisture(soil_path, data, stage, cw, cv)
            case_cols.append(col)
        if form in ("set", "param"):
            _check_scale(soil_path, cw, cv, name)
            _check_column_unit(soil_path, cw, col, cv, name)
        _check_declared_unit(soil_path, cw, col, cv)
    quantity_cols = {c: cv["quantity"] for c, cv in covs.items() if "quantity" in cv}
    twice = [q for q in set(quantity_cols.values()) if list(quantity_cols.values()).count(q) > 1]
    if twice:
        raise InputError(soil_path, f"{where}.covariates",
                         f"each quantity declared by one column ({twice[0]} is declared twice)", sorted(quantity_cols))
    if len(setup_cols) > 1:
        raise InputError(soil_path, f"{where}.covariates", "at most one column that chooses the setup", setup_cols)
    if len(case_cols) > 1:
        raise InputError(soil_path, f"{where}.covariates", "at most one column that chooses the case", case_cols)
    if case_cols and cal_case is not None:
        raise InputError(soil_path, f"{where}.calibrated.case",
                         f"no case: covariate {case_cols[0]!r} maps each row to its case", cal_case)
    if not case_cols and cal_case is None:
        raise InputError(soil_path, f"{where}.calibrated.case",
                         f"a case id of stage {stage['id']!r} (" + ", ".join(case_ids)
                         + ") or a covariate with a case map", None)

    # -- responses (before the table: names and units)
    resps = entry["responses"]
    seen = []
    for j, r in enumerate(resps):
        rw = f"{where}.responses[{j}]"
        if r["measure"] in seen:
            raise InputError(soil_path, f"{rw}.measure", "a measure listed once", r["measure"])
        seen.append(r["measure"])
        if r.get("value") is None and not r.get("note"):
            raise InputError(soil_path, f"{rw}.note",
                             "a note saying why the measured value is not printed (value: null)", None)

    # -- one role per column: a covariate, one kind of response column, or ignored.  Only the
    # repeat count ``n`` may serve several responses (the repeats behind every measure of a row).
    roles = {col: ("covariate", f"the covariate {where}.covariates.{col}") for col in covs}
    for j, r in enumerate(resps):
        for key in _RESPONSE_COLUMNS:
            col = r.get(key)
            if col is None:
                continue
            kind, role = roles.get(col, (None, None))
            if kind is not None and not (kind == key == "n"):
                raise InputError(soil_path, f"{where}.responses[{j}].{key}",
                                 f"a column with one role ({col} is already {role})", col)
            roles.setdefault(col, (key, f"the {key} column of {where}.responses[{j}]"))
    for k, col in enumerate(entry.get("ignore_columns") or []):
        if col in roles:
            raise InputError(soil_path, f"{where}.ignore_columns[{k}]",
                             f"a column with one role ({col} is already {roles[col][1]})", col)

    # -- the table: columns
    df = _read(soil_path, where, tpath, [c for c, cv in covs.items() if _label_column(cv)])
    cols = [str(c) for c in df.columns]
    listed = ", ".join(cols)
    for col in covs:
        if col not in cols:
            raise InputError(soil_path, f"{where}.covariates.{col}", f"a column of {tpath.name} ({listed})", col)
    ignore_cols = list(entry.get("ignore_columns") or [])
    for k, col in enumerate(ignore_cols):
        if col not in cols:
            raise InputError(soil_path, f"{where}.ignore_columns[{k}]", f"a column of {tpath.name} ({listed})", col)
    declared = set(covs) | set(ignore_cols)
    for j, r in enumerate(resps):
        for key in _RESPONSE_COLUMNS:
            col = r.get(key)
            if col is None:
                continue
            if col not in cols:
                raise InputError(soil_path, f"{where}.responses[{j}].{key}",
                                 f"a column of {tpath.name} ({listed})", col)
            declared.add(col)
    for col in cols:
        if col not in declared:
            raise InputError(tpath, f"column {col}",
                             f"a column declared in {Path(soil_path).name} under {where} (a covariate, "
                             "a response column or an entry of ignore_columns)", col)

    # -- label cells pandas reads as missing (NA, as R's write.csv writes a missing value)
    na_words = _missing_words(df, covs)

    def empty(row, col, what):
        word = na_words.get((row - 1, col))
        if word is None:
            raise InputError(tpath, f"row {row}, column {col}", what, EMPTY_CELL)
        raise InputError(tpath, f"row {row}, column {col}",
                         f"{what} ({word!r} is read as a missing value, as R's write.csv writes one; a tool, day "
                         f"or group so named is kept as a label where the column's setup or case map has it for a "
                         f"key, quoted: \"{word}\": ...)", word)

    # -- rows
    active = [c for c in covs if not covs[c].get("ignore")]
    replicates = int(entry.get("replicates", DEFAULT_REPLICATES))
    conds = []
    for i, rec in enumerate(df.to_dict("records")):
        row = i + 1
        at = lambda col: f"row {row}, column {col}"  # noqa: E731
        sname = entry["setup"]
        overrides = dict(entry_set)
        set_from = {}  # setup key -> column
        params = dict(base_params)
        param_from = {}  # parameter -> column
        case = cal_case
        for col in active:
            cv = covs[col]
            cell = rec[col]
            if _missing(cell):
                empty(row, col, f"a value of the covariate {col}")
            if "setup" in cv or "case" in cv:
                form = "setup" if "setup" in cv else "case"
                numeric = _numeric_column(cv)
                key = _map_key(cell, numeric)
                hit = [v for k, v in cv[form].items() if _same_key(_map_key(k, numeric), key)]
                if not hit and numeric:
                    raise InputError(tpath, at(col),
                                     f"a value mapped under {where}.covariates.{col}.{form} "
                                     f"({', '.join(map(str, cv[form]))})", _plain(cell))
                if not hit:
                    keys = ", ".join(repr(_map_key(k, False)) for k in cv[form])
                    raise InputError(tpath, at(col),
                                     f"a value mapped under {where}.covariates.{col}.{form} ({keys}): "
                                     f"this column declares no numeric quantity, so its cells are labels "
                                     f"compared with the keys as text, as written ({key!r} is none of them); "
                                     "write the key as the table writes the cell, or declare the column's "
                                     "numeric quantity and unit to compare them as numbers", key)
                if form == "setup":
                    sname = hit[0]
                else:
                    case = hit[0]
                continue
            scale = float(cv.get("scale", 1.0))
            x = _number(cell)
            if "param" in cv:
                if x is None:
                    raise InputError(tpath, at(col), f"a number (DEM parameter {cv['param']})", _plain(cell))
                params[cv["param"]] = x * scale
                param_from[cv["param"]] = col
                try:
                    DemParams.from_mapping({cv["param"]: x * scale}, src)
                except InputError as exc:
                    raise InputError(tpath, at(col), f"{exc.expected} (after scale {scale:g})", _plain(cell)) from None
            else:  # set
                if x is None and "scale" in cv:
                    raise InputError(tpath, at(col), f"a number (setup key {cv['set']} = value * {scale:g})",
                                     _plain(cell))
                overrides[cv["set"]] = x * scale if x is not None else str(cell).strip()
                set_from[cv["set"]] = col
        try:
            setup = merge_setup(setups, sname, overrides, src)
        except InputError as exc:  # a set covariate's key that the row's named setup lacks
            key = exc.field[len("setup."):]
            raise InputError(soil_path, f"{where}.covariates.{set_from.get(key, '?')}.set",
                             f"a key of the {name} setup {sname!r} (row {row}): {exc.expected}", key) from None
        allowed = measures_of(mod, setup)
        for j, r in enumerate(resps):
            if r["measure"] not in allowed:
                raise InputError(soil_path, f"{where}.responses[{j}].measure",
                                 f"a measured response of {name} with setup {sname!r} ({', '.join(allowed)})",
                                 r["measure"])
            if unit_factor(r["unit"], r["measure"]) is None:
                want = unit_of(r["measure"])
                raise InputError(soil_path, f"{where}.responses[{j}].unit",
                                 f"{want} (the unit of {r['measure']}, from its name) or another unit of its "
                                 f"quantity, converted to {want} as {tpath.name} is read: "
                                 + ", ".join(response_units(r["measure"])) + _millipascal_hint(r["unit"]),
                                 r["unit"])
            _check_response_column_units(soil_path, f"{where}.responses[{j}]", r, tpath)
        try:
            dem = DemParams.from_mapping(params, src, base=soil_base)
        except InputError as exc:  # a soil-wide simulation.params value: reported by its own check
            raise _renamed(exc, soil_path, "params.", "simulation.params.") from None
        try:
            mod.validate(setup, preset, src, params=dem)
        except InputError as exc:
            key = exc.field[len("setup."):] if exc.field.startswith("setup.") else exc.field
            if key in set_from:
                col = set_from[key]
                scale = float(covs[col].get("scale", 1.0))
                raise InputError(tpath, at(col), f"{exc.expected} (setup.{key} = value * {scale:g})",
                                 _plain(rec[col])) from None
            if key in taken:
                raise InputError(soil_path, f"{where}.set.{key}", f"{exc.expected} (this test takes "
                                 f"{taken[key]}, the soil's own; give the test its own {key})",
                                 exc.got) from None
            if key in entry_set:
                raise InputError(soil_path, f"{where}.set.{key}", exc.expected, exc.got) from None
            if setup_cols:
                raise InputError(tpath, at(setup_cols[0]), f"{exc.expected} ({exc.field} of setup {sname!r})",
                                 exc.got) from None
            raise InputError(soil_path, f"{where}.setup", f"{exc.expected} ({exc.field})", exc.got) from None

        responses = []
        for j, r in enumerate(resps):
            vals = {}
            for key in _RESPONSE_COLUMNS:
                col = r.get(key)
                if col is None:
                    vals[key] = None
                    continue
                cell = rec[col]
                if _missing(cell):
                    if key == "value":
                        raise InputError(tpath, at(col),
                                         f"the measured {r['measure']} (or value: null in {where}.responses[{j}])",
                                         EMPTY_CELL)
                    vals[key] = None
                    continue
                x = _number(cell)
                if x is None:
                    raise InputError(tpath, at(col), "a number", _plain(cell))
                if key == "sd" and not x > 0:
                    raise InputError(tpath, at(col), f"a standard deviation > 0 (of {r['measure']}; a blank cell "
                                     "where it is not known: an SD of 0 calls the value exact, and the measured-data "
                                     "loop would take every residual beyond the seed scatter as structure)",
                                     _plain(cell))
                if key == "n" and not (x >= 1 and x == int(x)):
                    raise InputError(tpath, at(col),
                                     f"a whole number of repeats >= 1 (behind {r['measure']})", _plain(cell))
                vals[key] = x
            n = vals["n"]
            # a table in another unit of the measure's quantity: every value in the measure's unit
            want, factor = unit_of(r["measure"]), unit_factor(r["unit"], r["measure"])
            for key in ("value", "sd", "paper_simulated", "paper_difference"):
                if vals[key] is not None:
                    vals[key] = vals[key] * factor
            note = r.get("note", "")
            if str(r["unit"]).strip() != want:
                note = (note + "; " if note else "") + f"{tpath.name} gives {r['unit']}, converted to {want} (x {factor:g})"
            responses.append(dict(measure=r["measure"], unit=want, measured=vals["value"],
                                  measured_sd=vals["sd"], n=None if n is None else int(n),
                                  paper_simulated=vals["paper_simulated"],
                                  paper_difference=vals["paper_difference"], note=note))
        quantities = {}
        for col, q in quantity_cols.items():
            cell = rec[col]
            if _missing(cell):
                empty(row, col, f"a value of the covariate {col} ({q})")
            if QUANTITIES[q] is None:
                quantities[q] = _text(cell)
                continue
            x = _number(cell)
            if x is None:
                raise InputError(tpath, at(col), f"a number ({q} in {covs[col]['unit']})", _plain(cell))
            if q in POSITIVE_QUANTITIES and not x > 0:
                raise InputError(tpath, at(col), f"a positive {q} (in {covs[col]['unit']})", _plain(cell))
            if q in NONNEGATIVE_QUANTITIES and x < 0:
                raise InputError(tpath, at(col), f"a {q} of zero or more (in {covs[col]['unit']}; an oven-dry "
                                 "soil's is 0)", _plain(cell))
            quantities[q] = x * quantity_factor(q, covs[col]["unit"])
        label_parts = [f"{c}={_text(rec[c])}" for c in active]
        conds.append(Condition(
            measurement=mid, row=row, label=", ".join(label_parts) if label_parts else f"row {row}",
            covariate=active[0] if active else "", covariate_value=_text(rec[active[0]]) if active else "",
            scenario=name, setup=setup, params=params, stage=stage["id"], case=case, preset=preset,
            replicates=replicates, responses=tuple(responses),
            covariates={c: (None if _missing(rec[c]) else _plain(rec[c])) for c in covs},
            quantities=quantities, quantity_columns=dict(quantity_cols)))
    _check_moisture(soil_path, data, tpath, df, covs, quantity_cols)
    return df, _shared_runs(tpath, covs, conds)


#: the words pandas' ``read_csv`` reads as a missing value by default (its documented
#: ``na_values`` default, pandas 2.2 to 3.0), which a numeric column of a measured table reads
#: as missing: in a label column they are made missing too (:func:`_missing_words`)
MISSING_WORDS = frozenset({"", "#N/A", "#N/A N/A", "#NA", "-1.#IND", "-1.#QNAN", "-NaN", "-nan", "1.#IND",
                           "1.#QNAN", "<NA>", "N/A", "NA", "NULL", "NaN", "None", "n/a", "nan", "null"})


def _missing_words(df: pd.DataFrame, covs: dict) -> dict:
    """Label columns (:func:`_label_column`) are read as written, so a cell ``NA``, ``N/A``,
    ``null``, ``None``, ``nan`` (pandas' missing-value words; R's ``write.csv`` writes a missing
    value ``NA``) is text there.  Such a cell is a label only where the column's ``setup`` or
    ``case`` map has it for a key (a tool called NA, mapped ``"NA": plate-arc``); elsewhere it
    is made missing in ``df``, as an empty cell is, so two days written NA are not one day
    called "NA".  The words are :data:`MISSING_WORDS`.  Returns (row position, column) -> the
    word, for the messages."""
    words = {}
    for col, cv in covs.items():
        if not _label_column(cv) or col not in df.columns:
            continue
        keys = {_map_key(k, False) for form in ("setup", "case") for k in (cv.get(form) or {})}
        j = df.columns.get_loc(col)
        for i, cell in enumerate(df[col].tolist()):
            if isinstance(cell, str) and cell.strip() and cell.strip() in MISSING_WORDS and cell.strip() not in keys:
                words[(i, col)] = cell.strip()
                df.iloc[i, j] = float("nan")
    return words


def _shared_runs(tpath: Path, covs: dict, conds: list[Condition]) -> list[Condition]:
    """Rows that run the same simulation (scenario, setup, DEM parameters, calibrated stage
    and case, preset, replicates: one job, one run per seed for all of them) yet differ in an
    ignored covariate (``{ignore: true}``: a tool, a day, a moisture varied only slightly) are
    compared with one simulated value: the simulation does not represent that difference.
    Ignoring the column is the user's choice, so the rows are not refused; each gets a note
    naming the rows simulated alike and the ignored values (the soil's ``load_notes``, printed
    by ``soilcal config check`` and the workflow, and written in ``tool_verification.csv``)."""
    import json

    ignored = [c for c, cv in covs.items() if cv.get("ignore")]
    if not ignored or len(conds) < 2:
        return conds
    groups = {}
    for c in conds:
        ident = json.dumps([c.scenario, c.setup, c.params, c.stage, c.case, c.preset, c.replicates],
                           sort_keys=True, default=str)
        groups.setdefault(ident, []).append(c)
    notes = {}
    for rows in groups.values():
        differ = [col for col in ignored if len({_text(r.covariates.get(col)) for r in rows}) > 1]
        if len(rows) < 2 or not differ:
            continue
        what = "; ".join(f"{col} = " + ", ".join(_text(r.covariates.get(col)) for r in rows) for col in differ)
        text = (f"{tpath.name} rows {', '.join(str(r.row) for r in rows)} differ only in the ignored "
                f"covariate{'s' if len(differ) > 1 else ''} {', '.join(differ)} ({what}) and are simulated "
                "alike: one simulated value for all of them, the difference is not represented")
        for r in rows:
            notes[r.row] = text
    if not notes:
        return conds
    from dataclasses import replace

    return [replace(c, note=notes[c.row]) if c.row in notes else c for c in conds]


#: a moisture table whose median is this many decades from the soil's own moisture (or, where the
#: soil gives none, in % with every value at most 1) holds fractions under a percent unit, or the reverse
MOISTURE_DECADES = (1.5, 2.5)


#: how near (decades) the other reading of a suspect moisture column (x 100 or / 100) must come to
#: the soil's own moisture for the column to be refused as in the wrong form
MOISTURE_MATCH = 0.3
#: a moisture column declared as a fraction of 1 may hold a value above 1 (more water than dry
#: mass, a peat's 1.5 g/g) only within this factor of the wettest moisture the soil's own
#: ``properties.moisture_content`` gives (in %): a soil of 12 % does not hold 150 %; its
#: "1, 2, 3, 4" are percentages declared as a fraction
MOISTURE_FRACTION_NEAR = 3.0


def _check_lone_moisture(tpath: Path, where: str, unit: str, x, pct) -> None:
    """One value of a moisture column that is 1.5 to 2.5 decades off the rest and, read the other
    way (x 100 or / 100), falls among them (within :data:`MOISTURE_LONE_SPAN` of their range: a
    0.116 among 11.6 to 12.5 %) is refused naming it: one value typed in the other unit would
    give the moisture effect a change of 99 %.  A value that read either way lies outside the
    others' range is a real spread of moisture (air-dry tests at 0.5 % beside 20 to 30 %)."""
    import numpy as np

    if len(pct) < 3:
        return
    for i, v in enumerate(pct):
        rest = np.delete(pct, i)
        lo, hi = float(rest.min()), float(rest.max())
        if v <= 0 or lo <= 0 or lo <= v <= hi:
            continue
        off = float(np.log10(lo / v)) if v < lo else float(np.log10(v / hi))
        other = v * 100.0 if v < lo else v / 100.0
        if (MOISTURE_DECADES[0] <= off <= MOISTURE_DECADES[1]
                and lo / MOISTURE_LONE_SPAN <= other <= hi * MOISTURE_LONE_SPAN):
            raise InputError(tpath, where, f"moisture contents in one unit (unit: {unit}): {x[i]:g} lies "
                             f"{10 ** round(off):g} times {'below' if v < lo else 'above'} the column's other "
                             f"values ({lo:g} to {hi:g} %) and {'x' if v < lo else '/'} 100 would fall among "
                             "them: a value typed in the other unit (or the others)?", float(x[i]))


#: how far (a factor) outside the range of a moisture column's other values one value read the
#: other way (x 100 or / 100) may fall and still be taken for a value typed in the other unit
MOISTURE_LONE_SPAN = 1.1


def _check_moisture(soil_path, data: dict, tpath: Path, df: pd.DataFrame, covs: dict, quantity_cols: dict) -> None:
    """A moisture column whose numbers are fractions under a percent unit (0.15 for 15 %), or
    percentages under a fraction unit: the moisture effect would take a change of 0.1 % for one
    of 10 %.  Refused naming the table and column, where (1) a column declared as a fraction
    (``-``, ``fraction``, ``g/g``, ``kg/kg``) holds a value above 5 (500 %, :data:`PLAUSIBLE`),
    or above 1 where the soil's ``properties.moisture_content`` is not given or its wettest is
    more than :data:`MOISTURE_FRACTION_NEAR` times drier than the column's (a soil wetter than
    its dry mass, a peat's 1.5 g/g, loads where the soil says it is that wet); (2) its median, in %, lies 1.5 to 2.5
    decades below or above the median of the soil's own ``properties.moisture_content`` (in %
    or as a fraction, as the soil file says) and, read the other way (times or over 100),
    within :data:`MOISTURE_MATCH` decades of it; (3) without that property, a column in % holds
    no value above 1 (a soil at most 1 % wet throughout; the soil's property says so where it
    is)."""
    import numpy as np

    from soilcal.config.quantities import soil_moisture

    soil = declared = wettest = ref = None
    for col, q in quantity_cols.items():
        if q != "moisture_content":
            continue
        if declared is None:  # read only where a moisture column compares with it: an unknown unit is refused here
            declared = soil_moisture(soil_path, data) or {}
            soil = (None if not declared else
                    ([v * declared["factor"] for v in declared["points"] + [x for r in declared["ranges"] for x in r]],
                     declared["text"]))
            # the soil's wettest and median moisture [%], the same for every column
            if soil is not None:
                wettest, ref = max(soil[0]), float(np.median(soil[0]))
        unit = covs[col]["unit"]
        x = np.array([v for v in (_number(c) for c in df[col]) if v is not None], float)
        if not len(x):
            continue
        factor = quantity_factor(q, unit)
        where = f"column {col}"
        top = PLAUSIBLE["moisture_content"][1]
        if factor != 1.0 and x.max() * factor > top:
            raise InputError(tpath, where, f"a moisture content as a fraction of the dry mass (unit: {unit}, as the "
                             f"soil's covariates.{col}.unit declares) of at most {top / factor:g} ({top:g} %, a "
                             f"peat's at saturation): {x.max():g} would be {x.max() * factor:g} %; if the cells are "
                             "percentages, declare unit: \"%\"", float(x.max()))
        if factor != 1.0 and x.max() > 1.0 and (wettest is None or x.max() * factor > MOISTURE_FRACTION_NEAR * wettest):
            own = ("the soil gives no properties.moisture_content (give the soil's properties.moisture_content "
                   "if it is that wet)" if wettest is None else
                   f"the soil's own properties.moisture_content is {soil[1]}, more than "
                   f"{MOISTURE_FRACTION_NEAR:g} times drier")
            raise InputError(tpath, where, f"a moisture content as a fraction of the dry mass (unit: {unit}, as the "
                             f"soil's covariates.{col}.unit declares) of at most 1 unless the soil says it is "
                             f"that wet: {x.max():g} would be {x.max() * factor:g} % of the dry mass (a peat's or "
                             f"an andisol's) and {own}; if the cells are percentages, declare unit: \"%\" under "
                             f"covariates.{col}", float(x.max()))
        pct = x * factor
        if factor == 1.0 and pct.max() > 100.0 and (wettest is None or pct.max() > MOISTURE_FRACTION_NEAR * wettest):
            own = ("the soil gives no properties.moisture_content (give it if the soil is that wet)"
                   if wettest is None else f"the soil's own properties.moisture_content is {soil[1]}, more than "
                   f"{MOISTURE_FRACTION_NEAR:g} times drier")
            raise InputError(tpath, where, f"a moisture content in % (unit: {unit}) of at most 100 % unless the "
                             f"soil says it is that wet: {pct.max():g} % is more water than dry soil (a peat's or "
                             f"an andisol's) and {own}", float(x.max()))
        _check_lone_moisture(tpath, where, unit, x, pct)
        med = float(np.median(pct))
        if soil is not None:
            if med > 0 and ref > 0:
                lg = float(np.log10(med / ref))
                # read the other way (x 100 or / 100) the column must match the soil's own moisture:
                # air-dry tests (0.5 %) of a soil held at 20 % are not fractions of 1 (50 %)
                other = abs(lg - 2.0 * np.sign(lg))
                if MOISTURE_DECADES[0] <= abs(lg) <= MOISTURE_DECADES[1] and other <= MOISTURE_MATCH:
                    times = f"{10 ** round(abs(lg)):g}"
                    if lg < 0:
                        hint = (f"fractions of 1 under unit {unit}? declare unit: fraction under the covariate to "
                                "have them read as such")
                    elif factor != 1.0:  # the column, declared a fraction, is the likelier one wrong
                        hint = (f"percentages under unit {unit}? declare unit: \"%\" under covariates.{col} to "
                                "have them read as such")
                    else:
                        hint = (f"is the soil's properties.moisture_content a fraction under unit "
                                f"{data['properties']['moisture_content'].get('unit', '%')}?")
                    raise InputError(tpath, where, f"moisture contents near the soil's own ({soil[1]}, "
                                     f"properties.moisture_content): the column's median, {med:.4g} %, is about "
                                     f"{times} times {'smaller' if lg < 0 else 'larger'} ({hint})", float(x[0]))
        elif factor == 1.0 and x.max() <= 1.0 and x.max() > 0:
            raise InputError(tpath, where, "a moisture content in % (every value is at most 1 %: fractions of 1? "
                             "declare unit: fraction under the covariate to have them read as such, or give the "
                             "soil's properties.moisture_content if it is that dry)", float(x[0]))


def _check_scale(soil_path, cw: str, cv: dict, scenario: str) -> None:
    """A ``set`` or ``param`` covariate that declares its cells' ``unit``: its ``scale`` must take
    that unit to the unit the setup key or DEM parameter is taken in, where that unit is known
    (:data:`SETUP_KEY_UNITS`, :func:`param_unit`) and is one of the quantity's units.  A key
    whose unit is another quantity's, or not documented, is left unchecked: there is no factor
    to compare with."""
    q = cv.get("quantity")
    if q is None or QUANTITIES.get(q) is None or "unit" not in cv:
        return
    if "set" in cv:
        target, what = SETUP_KEY_UNITS.get(scenario, {}).get(cv["set"]), f"setup key {cv['set']}"
    else:
        target, what = param_unit(cv["param"]), f"DEM parameter {cv['param']}"
    factors = QUANTITIES[q][1]
    if target not in factors or target == DIMENSIONLESS:  # a dimensionless DEM parameter is no moisture
        return
    unit = cv["unit"]
    factor = quantity_factor(q, unit) / quantity_factor(q, target)
    scale = cv.get("scale", 1)
    if not abs(float(scale) - factor) <= SCALE_RTOL * factor:
        raise InputError(soil_path, f"{cw}.scale",
                         f"{factor:.4g} ({unit} to {target}, the unit of {what})", scale)


#: spellings a column's name or a ``unit:`` may give a unit in besides the units of
#: :data:`RESPONSE_UNITS`, :data:`UNIT_ALIASES` and :data:`QUANTITIES` (``speed_kmh``): unit.
#: ``lb`` and ``lbs`` for a force are the pound-force, as US papers write it (a pound of mass
#: only in a density, ``lb/ft^3``, ``pcf``); a viscosity's ``mPa s`` is kept whole so that it
#: reads as no stress
NAME_UNIT_SPELLINGS = {"kmh": "km/h", "percent": "%", "pct": "%", "wt%": "%", "lb": "lbf", "lbs": "lbf",
                       "inch": "in", "inches": "in", "in.": "in", "feet": "ft", "foot": "ft", "pcf": "lb/ft^3",
                       MILLIPASCAL: MILLIPASCAL, "mPa s": "mPa s", "mPa.s": "mPa s", "mPa·s": "mPa s"}
#: words that are a unit only in a name's brackets (``w (fraction)``), not as a word of it
#: (``clay_fraction``, ``percent_sand``)
_UNIT_WORDS = ("fraction", "percent", "degree", "degrees")
#: name words after which a unit symbol that is an English word too is read as a unit at the
#: name's end: a length's (``depth_in``, ``Layer depth..in.``, ``plot_width_ft``) or a
#: pressure's (``pressure_psi``, ``cone_index_PSI``)
LENGTH_WORDS = ("depth", "height", "width", "length", "position", "distance", "sinkage", "diameter", "thickness",
                "spacing", "elevation", "rut", "flatness", "deflection", "layer", "penetration")
STRESS_WORDS = ("pressure", "stress", "cone", "index", "strength", "inflation", "load", "ci")
#: units whose symbols are words too (``depth in mm``, ``gain_in``, ``ft_id``, ``psi`` a
#: matric potential: ``psi (kPa)``, ``suction PSI``), in any spelling (``PSI``, ``inches``,
#: ``feet``): a unit only where the name gives no other unit, and then in brackets
#: (``depth (in)``; ``depth (in) [mm]`` is in mm) or as the name's last word after ``_``, a
#: space or R's ``..`` or before a statistic word, behind a word of the unit's kind
#: (``depth_in``, ``plot_width_ft``, ``pressure_psi``, ``stress_psi_mean``); no unit elsewhere (``moisture_in``, ``w_in``, ``plot_ft``, ``depth.in``,
#: ``tool_ft_2``)
_WORD_UNITS = {"in": LENGTH_WORDS, "ft": LENGTH_WORDS, "psi": STRESS_WORDS}
#: a name's bracketed part: ``speed (km/h)``, ``depth [mm]``
#: the words after which a one-letter word of a column's name inside it is read as a unit
#: (``F_N_mean``, ``draught_N_sd``): a statistic of the quantity in that unit
STATISTIC_WORDS = ("mean", "avg", "average", "sd", "std", "se", "sem", "min", "max", "median")
_BRACKETS = re.compile(r"[(\[]\s*([^()\[\]]*?)\s*[)\]]")


#: compound units, as :func:`_compound` writes them, that name a unit of the tables under
#: another symbol: a megagram is a tonne, a rotation rate per minute or per second (``min-1``,
#: ``s-1``, ISO 80000-3's rotational frequency) is in revolutions, with or without the r
_COMPOUND_SPELLINGS = {"Mg/m^3": "t/m^3", "1/min": "r/min", "rev/min": "r/min", "1/s": "r/s", "rev/s": "r/s"}


def _compound(text: str):
    """A compound unit written with exponents or a ``/``, SI style: ``m s-1``, ``m.s-1``,
    ``m·s⁻¹``, ``m s^-1``, ``km h-1``, ``g cm-3``, ``kg/m3``, ``Mg m-3``, ``min-1``, ``1/s``,
    ``g g-1``, ``N per m``, as ``(written, form)``: ``written`` whether the text is such a unit
    (:func:`~soilcal.config.quantities.unit_powers`, its symbols with their case, with an
    exponent or a ``/``), ``form`` the unit in one spelling, ``num/den`` with powers as ``^n``
    (``m/s``, ``g/cm^3``, ``1/min``).  A text that is no compound unit gives ``(False, None)``."""
    powers = unit_powers(text)
    if powers is None:
        return False, None
    num, den, marked = [], [], False
    for sym, exp, below in powers:
        e = int(exp or 1)
        if exp is not None and 0 <= e < 2:
            return False, None  # r1, s1, m1, h0 next to a unit word are ids, not powers
        marked = marked or below or exp is not None
        if e < 0 or below:
            den.append((sym, abs(e)))
        else:
            num.append((sym, e))
    if not marked:
        return False, None
    if not den and len(num) > 1:
        return False, None  # m2, cm3 are units; kN t2, depth_cm_r2 hold an id (t2, r2), no product of powers

    def power(fs):
        return " ".join(sym if e == 1 else f"{sym}^{e}" for sym, e in fs)

    return True, (power(num) or "1") + (f"/{power(den)}" if den else "")


@functools.cache
def _name_unit_table() -> tuple[dict, dict, dict]:
    """Every unit spelling :func:`name_units` knows -> its unit as the tables key it, and the
    same by lower-case spelling where that names one unit only (``RPM`` rpm, ``KMH`` km/h),
    for spellings of three characters or more, or a symbol of two letters or more in another
    case by :data:`~soilcal.config.quantities.UNIT_CASES` (``KN``, ``MPA``; ``mn`` is no mN),
    one of one letter with its case only (``M`` is no ``m``, ``n`` no ``N``); and the compound units
    among them by the form :func:`_compound` gives them (``m/s``, ``kg/m^3``, ``N m``)."""
    exact = {u: u for family in RESPONSE_UNITS for u in family}
    exact.update({u: u for spec in QUANTITIES.values() if spec for u in spec[1]})
    exact.update(UNIT_ALIASES)
    exact.update(NAME_UNIT_SPELLINGS)
    lower = {}
    for spelling, unit in exact.items():
        if len(spelling) > 2:
            lower.setdefault(spelling.lower(), set()).add(unit)
    lower = {k: next(iter(v)) for k, v in lower.items() if len(v) == 1}
    # a symbol in another case, by the one rule of quantities.UNIT_CASES (KN, MPA, PSI, FT)
    lower.update({low: exact[sym] for low, sym in UNIT_CASES.items() if len(low) > 1 and sym in exact})
    forms = dict(_COMPOUND_SPELLINGS)
    for spelling, unit in exact.items():
        for text in (spelling, spelling.replace("^", "")):
            written, form = _compound(text)
            if written:
                forms.setdefault(form, unit)
    return exact, lower, forms


def whole_unit(text) -> str | None:
    """The unit a declared ``unit:`` text is, as the tables key it, where the WHOLE text is one
    unit: one of its spellings (:func:`_name_unit_table`: ``kN``, ``N.m``, ``m2``, ``KN``,
    ``kmh``; with its case, or without it for a spelling of three characters or more that
    names one unit only), or a compound unit :func:`_compound` reads in full (``m s-1``,
    ``km h-1``, ``g cm-3``, ``Mg m-3``, ``kg/m3``, ``min-1``, ``g g-1``).  None otherwise: a
    unit is never picked out of a longer text (``x1000 N``, ``10^3 N``, ``0.1 kN``,
    ``N per 3 tines``, ``vol %``), whose other words change what the number means."""
    exact, lower, forms = _name_unit_table()
    u = str(text).strip()
    if not u:
        return None
    if u in exact:
        return exact[u]
    if len(u) > 1 and u.lower() in lower:
        return lower[u.lower()]
    written, form = _compound(u)
    return forms.get(form) if written else None


def name_units(col) -> list[str]:
    """The units a column's name gives (as :data:`RESPONSE_UNITS` and :data:`QUANTITIES` key
    them), in the order written: a unit written as a word of the name, between ``_``, spaces,
    commas or brackets, anywhere in it (``draught_kN``, ``draught kN``, ``draught, kN``,
    ``draught_kN_mean``, ``speed_km_h``, ``torque_N_m``), or after a ``/`` (``draught/kN``),
    or in brackets (``draught (kN)``, ``depth [mm]``, ``speed (km/h)``); between dots where a
    word of dots is no unit itself (R's names: ``Draught..kN.`` for ``Draught (kN)``,
    ``draught.kN``; pandas' ``draught_kN.1``).  A compound unit written SI style, with
    exponents or a ``/`` (``speed (m s-1)``, ``speed [m.s-1]``, ``density (g cm-3)``,
    ``Mg m-3``, ``kg/m3``, ``(min-1)``: :func:`_compound`), is that unit, or no unit of the
    tables (``draught (N m-1)``, a draught per width, is no N).  Matched with its
    case, else without it where that names one unit only and the spelling has three
    characters or more (``mpa`` is MPa; ``RPM`` is rpm; of two, ``kn`` and ``KN`` are kN, but
    ``mn`` is no mN: :func:`_name_unit_table`).  A one-letter word is a unit with its case in
    brackets (``depth (m)``, ``draught [N]``), as the name's last word (``horizontal_measured_N``,
    ``Sd_m``: the tables' own naming; ``Sd_m (mm)`` is in mm), or as a word after the first where the name gives no
    other unit (``draught_N_mean``, ``F_N_sd``; ``Sd_m_mm`` is in mm); the first word alone
    (``N``, ``n``, ``m``) is none.  A word of punctuation only (the ``-`` of ``Moisture - %``)
    is no unit outside brackets (``w (-)`` is dimensionless), but ``%``; the one-letter rule is for
    letters: ``%`` and ``°`` are units wherever they stand (``strain_%_total``, ``angle_°_paper``)."""
    exact, lower, forms = _name_unit_table()

    def compound(text, raw=False):
        # raw: a quotient the text writes out but no table has (N m-1, a force per width) is
        # given as written, so that it is seen as another quantity's unit; t2, r2 alone are ids
        written, form = _compound(text)
        return (True, forms.get(form, form if raw and "/" in form else None)) if written else (False, None)

    def unit(text, bracketed, one_letter=False):
        if len(text) == 1 and text.isalpha() and not (bracketed or one_letter):
            return None
        if not bracketed and text != "%" and all(c in string.punctuation for c in text):
            return None
        if text.lower() in _UNIT_WORDS and not bracketed:
            return None
        return exact.get(text) or (lower.get(text.lower()) if len(text) > 1 else None)

    # pandas' and R's suffix of a duplicate name (depth_in.1, Depth..in..1) is no part of it
    name = re.sub(r"(?<=\D)\.\d+$", "", str(col).strip())
    found, weak = [], []
    for m in _BRACKETS.finditer(name):
        inside = m.group(1)
        written, form = compound(inside, raw=True)
        if written:
            found.append(form)
            continue
        words = [w for w in re.split(r"[\s,;]+", inside) if w]
        whole = unit(inside, True)
        for u in [whole] if whole else [unit(w, True) for w in words]:
            (weak if u in _WORD_UNITS else found).append(u)  # depth (in) [mm] is in mm
    words = []
    for w in re.split(r"[\s_,;]+", _BRACKETS.sub(" ", name)):
        if "." in w and not unit(w, False) and not compound(w)[0]:
            words += w.split(".")  # R's names: Draught..kN., draught.kN
        else:
            words.append(w)
    words = [w for w in words if w]
    i = 0
    while i < len(words):
        # a compound unit over several words (m s-1, g cm-3, N per m) or two words of one
        # unit (km_h, m_s, r_min, N_m)
        span = None
        for n in (4, 3, 2):
            if i + n > len(words):
                continue
            # kg_m3 is kg/m3 as km_h is km/h
            tries = [compound(" ".join(words[i:i + n]), raw=True), compound(f"{words[i]}/{' '.join(words[i + 1:i + n])}")]
            known = next((form for written, form in tries if form), None)
            if known or tries[0][0]:
                span = (n, known)
                break
        if span is None and i + 1 < len(words):
            pair = unit(f"{words[i]}/{words[i + 1]}", False) or unit(f"{words[i]} {words[i + 1]}", False)
            span = (2, pair) if pair else None
        if span is not None:
            found.append(span[1])
            i += span[0]
            continue
        w = words[i]
        written, form = compound(w, raw=True)
        if written:
            found.append(form)
        elif len(w) == 1 and w.isalpha() and i > 0:  # %, ° are units wherever they stand
            last = i == len(words) - 1 and name.rstrip(".").endswith(w)  # Sd_m (mm): the brackets' mm
            following = words[i + 1].lower() if i + 1 < len(words) else None
            if last:
                found.append(unit(w, False, True))
            elif following is None or following in STATISTIC_WORDS:  # F_N_mean, Sd_m (mm)
                weak.append(unit(w, False, True))
            # else draught_N_2, draught_N_A, tool_m_depth: a one-letter id or abbreviation
        elif unit(w, False) in _WORD_UNITS:  # depth_in, pressure_psi; not draught_kN_in (kN), psi_kPa, gain_in
            u = unit(w, False)
            last = i == len(words) - 1 and re.search(r"(?:[_\s,;]|\.\.)" + re.escape(w) + r"\.*$", name)
            # or before a statistic word, as a one-letter unit is: depth_in_mean, stress_psi_sd
            last = last or (i + 1 < len(words) and words[i + 1].lower() in STATISTIC_WORDS)
            kind = any(p.lower().startswith(_WORD_UNITS[u]) for p in words[:i])
            weak.append(u if i > 0 and last and kind else None)
        else:
            found.append(unit(w, False) or (unit(w.split("/", 1)[1], False) if "/" in w else None))
        i += 1
    found = [u for u in found if u]
    return list(dict.fromkeys(found or [u for u in weak if u]))


def _rename_hint(col, declared: str, named: str) -> str:
    """How to rename a column whose name gives another unit (``named``) than its cells are
    declared in."""
    if len(named) == 1 and named.isalpha():
        return (f"or, if its cells are in {declared}, rename the column, e.g. {col} ({declared}): a one-letter "
                "word after the first is read as a unit at the name's end or before mean, sd, se, min, max, avg or std")
    return f"or rename the column if its cells are in {declared}"


def _check_column_unit(soil_path, cw: str, col: str, cv: dict, scenario: str) -> None:
    """A ``set`` covariate that declares no ``unit`` and no ``scale`` takes its cells in the
    unit of the setup key (:data:`SETUP_KEY_UNITS`); a column whose name gives another unit of
    that key's quantity, of another factor (:func:`name_units`: ``speed_kmh`` or ``speed (km/h)``
    for a speed in m/s, ``depth_mm`` for a depth in m; ``rpm`` is r/min), would be read
    1000 mm as 1000 m without a word, so it is refused, asking for the unit and its scale."""
    if "set" not in cv or "unit" in cv or "scale" in cv:
        return
    target = SETUP_KEY_UNITS.get(scenario, {}).get(cv["set"])
    if target is None:
        return
    for named in name_units(col):
        q = next((q for q, spec in QUANTITIES.items() if spec and target in spec[1] and named in spec[1]), None)
        if q is None:
            continue
        family = QUANTITIES[q][1]
        factor = family[named] / family[target]
        if abs(factor - 1.0) <= SCALE_RTOL:
            continue
        raise InputError(soil_path, cw, f"the unit of the cells, which the column's name says are in {named} "
                         f"(quantity: {q}, unit: {named}, scale: {factor:.4g}, {named} to "
                         f"{target}, the unit of setup key {cv['set']}; or scale: 1 if they are in {target})",
                         "no unit and no scale")


def _check_declared_unit(soil_path, cw: str, col: str, cv: dict) -> None:
    """A covariate of a numeric quantity declares its cells' ``unit``; a column whose name
    gives another unit of that quantity, of another factor (``speed (km/h)`` declared
    ``unit: m/s``), contradicts it: one of the two is wrong, and reading 0.576 km/h as
    0.576 m/s would go unnoticed, so it is refused naming the unit the name gives."""
    q = cv.get("quantity")
    if q is None or QUANTITIES.get(q) is None or "unit" not in cv:
        return
    declared = quantity_factor(q, cv["unit"])
    for named in name_units(col):
        factor = quantity_factor(q, named)
        if factor is None:
            units = MOISTURE_UNITS if q == "moisture_content" else ", ".join(QUANTITIES[q][1])
            raise InputError(soil_path, f"{cw}.unit",
                             f"the unit of the cells, which the name of column {col} says are in {named}, no unit "
                             f"of {q} soilcal converts ({units}): give the cells in one of them and name the "
                             f"column in it, e.g. {col.split('(')[0].split('[')[0].strip() or col} ({cv['unit']})",
                             cv["unit"])
        if abs(factor - declared) <= SCALE_RTOL * declared:
            continue
        raise InputError(soil_path, f"{cw}.unit",
                         f"the unit of the cells, which the column's name says are in {named} (unit: {named}; "
                         f"{_rename_hint(col, cv['unit'], named)})", cv["unit"])


#: words of a column's name that make its numbers relative to another value (a coefficient of
#: variation, a relative SD, a percentage): ``draught CV (%)``, ``horizontal_SD_percent``,
#: ``Draught.CV....``, ``draught_rsd``
RELATIVE_WORDS = ("cv", "rsd", "cov", "percent", "pct", "relative", "rel")


def _relative_word(col) -> str | None:
    """The word of a column's name that makes its numbers relative (:data:`RELATIVE_WORDS`, a
    ``%`` anywhere: ``CV%``, ``draught_sd (% of mean) N``), even where the name gives a unit
    too (``horizontal (N) CV (%)``, ``draught_cv_pct_N``); None for a name of none
    (``sd (N)``, ``draught_sd_N``).  Words are split at anything not a letter or digit and at
    pandas' or R's dots (``Draught.CV....``)."""
    name = str(col)
    if "%" in name:
        return "%"
    return next((w for w in re.split(r"[^A-Za-z0-9]+", name) if w.lower() in RELATIVE_WORDS), None)


def _millipascal_hint(text) -> str:
    """What a stress declared in mPa is told: a millipascal is no soil's stress."""
    return ("; mPa is a millipascal, 1e-9 of a MPa, no soil's stress: did you mean MPa?"
            if whole_unit(text) == MILLIPASCAL else "")


def _check_response_column_units(soil_path, rw: str, r: dict, tpath: Path) -> None:
    """A response's value, SD or paper column whose name gives a unit of its measure's
    quantity (:func:`name_units`: ``draught_kN``, ``Draught (KN)``) of another factor than the
    response's declared ``unit`` (``unit: N``) would be read 1000 times off without a word:
    refused naming the response's ``unit``, the column and the unit its name gives.  So is a
    column of a measure with units whose name gives % and no unit of the measure
    (``draught CV (%)`` as the SD of a force in N: a relative SD read as one in N)."""
    family = response_units(r["measure"])
    declared = unit_factor(r["unit"], r["measure"])
    for key in ("value", "sd", "paper_simulated", "paper_difference"):
        col = r.get(key)
        names = name_units(col) if col is not None else []
        relative = _relative_word(col) if col is not None and "%" not in family else None
        if relative is not None:
            raise InputError(soil_path, f"{rw}.value" if key == "value" else f"{rw}.{key}",
                             f"a column of {r['measure']} in a unit of its quantity ({', '.join(family)}): the "
                             f"name of column {col} says {relative}, a value relative to another (a coefficient "
                             f"of variation?), which would be read as {unit_of(r['measure'])}; give the "
                             f"{'SD' if key == 'sd' else 'values'} in {r['unit']} in a column of its own"
                             + (" (SD = CV / 100 x mean)" if key == "sd" else ""), col)
        if MILLIPASCAL in names and "Pa" in family:
            raise InputError(soil_path, f"{rw}.value" if key == "value" else f"{rw}.{key}",
                             f"a column of {r['measure']} in a unit of its quantity ({', '.join(family)}): the "
                             f"name of column {col} says mPa, a millipascal, 1e-9 of a MPa, no soil's stress (did "
                             "you mean MPa? name the column in it)", col)
        for named in names:
            if named not in family and named.split("/")[0] in family:
                raise InputError(soil_path, f"{rw}.value" if key == "value" else f"{rw}.{key}",
                                 f"a column of {r['measure']} in a unit of its quantity "
                                 f"({', '.join(family)}): the name of column {col} says {named}, "
                                 f"{named.split('/')[0]} per {named.split('/', 1)[1]}, another quantity "
                                 "(a force per width is no force; give the measured total in its own column)",
                                 col)
            if named not in family and not any(n in family for n in names):
                raise InputError(soil_path, f"{rw}.value" if key == "value" else f"{rw}.{key}",
                                 f"a column of {r['measure']} in a unit of its quantity ({', '.join(family)}): the "
                                 f"name of column {col} says {named}, a unit of another quantity (is {col} the "
                                 f"column of this response, and {r['measure']} its measure?)", col)
            if named not in family or abs(family[named] - declared) <= 1e-9 * declared:
                continue
            raise InputError(soil_path, f"{rw}.unit",
                             f"the unit of {tpath.name}'s columns, which the name of column {col} ({key}) says is "
                             f"{named} (unit: {named}, converted to {unit_of(r['measure'])} as the table is read; "
                             f"{_rename_hint(col, r['unit'], named)})", r["unit"])


def _renamed(exc: InputError, soil_path, prefix: str, field_prefix: str) -> InputError:
    fld = exc.field[len(prefix):] if exc.field.startswith(prefix) else exc.field
    return InputError(soil_path, field_prefix + fld, exc.expected, exc.got)


def check_measurements(soil_path, data: dict, resources_root) -> list[Condition]:
    """Start-up check of a soil's ``measurements`` block (called by the config loader); returns
    the conditions of its tables, as :func:`conditions` gives them."""
    out = []
    for _mid, _entry, _tpath, _df, conds in _entries(soil_path, data, resources_root) if data.get(BLOCK) else []:
        out.extend(conds)
    return out


def conditions(soil) -> list[Condition]:
    """One :class:`Condition` per row of every measured table of a loaded
    :class:`~soilcal.config.load.Soil`, in block and table order: those the loader read and
    checked (:attr:`Soil.measured`), or read now for a soil it did not load."""
    measured = getattr(soil, "measured", None)
    if measured is not None:
        return list(measured)
    out = []
    for _mid, _entry, _tpath, _df, conds in _entries(soil.path, soil.data, soil.resources_root):
        out.extend(conds)
    return out
