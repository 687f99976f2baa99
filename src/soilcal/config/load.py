"""Load and validate soil entries and the workflow configuration."""

from __future__ import annotations

import copy
import functools
import math
import re
from dataclasses import dataclass, field
from functools import cached_property
from importlib import resources
from pathlib import Path
from typing import Any

import jsonschema
import numpy as np
import pandas as pd
import yaml

from soilcal.config.tables import read_table  # noqa: F401 (re-exported)
from soilcal.errors import EMPTY_CELL, InputError

SOIL_SCHEMA = Path(str(resources.files("soilcal.config") / "soil.schema.yaml"))
#: the workflow config's schema (config/config.yaml and --config; workflow/schemas links to it)
WORKFLOW_SCHEMA = Path(str(resources.files("soilcal.config") / "workflow.schema.yaml"))


class _Keys:
    """The loaders' mapping rule: a key given twice in one mapping is refused (plain PyYAML
    keeps the last silently).  Keys are compared as the values they read as, so ``5`` and
    ``5.0`` (one Python key, the later entry would win) are the same key; a quoted ``"5"`` is
    text, another key."""

    def construct_mapping(self, node, deep=False):
        if isinstance(node, yaml.MappingNode):
            seen = {}
            for key_node, _ in node.value:
                if not isinstance(key_node, yaml.ScalarNode) or key_node.tag == "tag:yaml.org,2002:merge":
                    continue
                key = self.construct_object(key_node)
                if key in seen:
                    line, text = seen[key]
                    raise _DuplicateKey(key_node.value, key_node.start_mark.line + 1,
                                        line if text == key_node.value else f"{line}, as {text!r}")
                seen[key] = (key_node.start_mark.line + 1, key_node.value)
        return super().construct_mapping(node, deep=deep)


class _DuplicateKey(Exception):
    def __init__(self, key, line, first):
        super().__init__(key)
        self.key, self.line, self.first = key, line, first


class _Loader(_Keys, yaml.SafeLoader):
    """SafeLoader that also reads ``7.9e10`` (no sign, no dot) as a float, as YAML 1.2 does,
    and refuses a key given twice in one mapping (:class:`_Keys`).  Pure Python: its parse
    errors are the messages :func:`read_yaml` gives."""


#: libyaml's parser, where PyYAML was built with it (the wheels on PyPI are); a PyYAML without it
#: reads every file with the pure-Python :class:`_Loader`: the same values, more slowly
_CBase = getattr(yaml, "CSafeLoader", None)


class _CLoader(_Keys, _CBase or yaml.SafeLoader):
    """:class:`_Loader` on libyaml's parser (PyYAML's ``CSafeLoader``): the same resolver and
    constructor, so the same values, read several times faster; :func:`read_yaml` reads each
    file with it first."""


for _cls in (_Loader, _CLoader):
    _cls.add_implicit_resolver(
        "tag:yaml.org,2002:float",
        re.compile(
            r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
            |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
            |\.[0-9_]+(?:[eE][-+]?[0-9]+)?
            |[-+]?\.(?:inf|Inf|INF)
            |\.(?:nan|NaN|NAN))$""",
            re.X,
        ),
        list("-+0123456789."),
    )


def read_yaml(path: str | Path) -> Any:
    """Read a YAML file; a missing or unparsable file raises InputError naming it.  The file is
    parsed with libyaml (:class:`_CLoader`); where that fails in any way it is read again with
    the pure-Python parser (:class:`_Loader`), whose error the message gives (libyaml words
    its errors differently)."""
    path = Path(path)
    if not path.is_file():
        raise InputError(path, "<file>", "an existing YAML file", "no such file")
    try:
        with open(path, encoding="utf-8") as fh:
            return yaml.load(fh, Loader=_CLoader)  # noqa: S506 - CSafeLoader subclass
    except Exception:  # noqa: BLE001 - the pure-Python read below raises the error the message names
        pass
    try:
        with open(path, encoding="utf-8") as fh:
            return yaml.load(fh, Loader=_Loader)  # noqa: S506 - SafeLoader subclass
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}" if mark is not None else "<document>"
        got = str(getattr(exc, "problem", None) or exc).replace("\n", " ")
        ctx, cmark = getattr(exc, "context", None), getattr(exc, "context_mark", None)
        if ctx and cmark is not None and (mark is None or cmark.line != mark.line):
            got += f" ({ctx} on line {cmark.line + 1})"
        raise InputError(path, where, "valid YAML", got) from None
    except _DuplicateKey as exc:
        raise InputError(path, f"line {exc.line}", f"each key once per mapping ({exc.key!r} is first given on line {exc.first})",
                         f"{exc.key!r} again") from None
    except UnicodeDecodeError as exc:
        raise InputError(path, "<file>", "a UTF-8 text file", f"a byte that is not UTF-8 at offset {exc.start}") from None
    except OSError as exc:
        raise InputError(path, "<file>", "a readable YAML file", exc.strerror or type(exc).__name__) from None


def _field_path(parts) -> str:
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out or "<root>"


#: the schemas' patterns in words, for the message of a value that does not match one
_PATTERN_WORDS = {
    "^[a-z0-9][a-z0-9-]*$": "an id of lower-case letters, digits and hyphens, starting with a letter or digit",
    "^[a-z][a-z0-9_]*$": "an id of lower-case letters, digits and underscores, starting with a letter",
}


def _schema_error(path: Path, schema: dict, data: Any) -> None:
    validator = jsonschema.Draft202012Validator(schema)
    errors = list(validator.iter_errors(data))
    if not errors:
        return
    err = jsonschema.exceptions.best_match(errors)
    where = _field_path(err.absolute_path)
    if err.validator == "additionalProperties":
        allowed = sorted(err.schema.get("properties", {}))
        extra = sorted(set(err.instance) - set(allowed)) if isinstance(err.instance, dict) else []
        name = extra[0] if extra else "?"
        fld = f"{where}.{name}" if where != "<root>" else name
        raise InputError(path, fld, "one of the known fields " + ", ".join(allowed), f"unknown field {name!r}")
    if err.validator == "required":
        missing = err.message.split("'")[1] if "'" in err.message else err.message
        fld = f"{where}.{missing}" if where != "<root>" else missing
        raise InputError(path, fld, "a required field", "nothing")
    if err.validator == "dependentRequired":
        # e.g. a range's low given without its high: which key is there and which one it needs
        given = next((k for k, need in err.validator_value.items()
                      if k in err.instance and any(n not in err.instance for n in need)), None)
        need = [n for n in err.validator_value.get(given, []) if n not in err.instance]
        fld = f"{where}.{need[0]}" if where != "<root>" else need[0]
        hint = ""
        if given in ("low", "high"):
            hint = ("; a one-sided bound, such as a soil sieved below 2 mm, is no range: write it in the "
                    "entry's note, and its value if one was measured")
        raise InputError(path, fld, f"{' and '.join(need)} with {given} (a range has both ends{hint})",
                         f"{given} {err.instance[given]!r} alone")
    if err.validator == "type":
        types = err.validator_value if isinstance(err.validator_value, list) else [err.validator_value]
        raise InputError(path, where, "a value of type " + " or ".join(map(str, types)), err.instance)
    bounds = {"minimum": ">=", "maximum": "<=", "exclusiveMinimum": ">", "exclusiveMaximum": "<"}
    if err.validator in bounds:
        raise InputError(path, where, f"a number {bounds[err.validator]} {err.validator_value}", err.instance)
    if err.validator in ("minItems", "maxItems"):
        n = err.validator_value
        most = "at least" if err.validator == "minItems" else "at most"
        raise InputError(path, where, f"a list of {most} {n} item{'s' if n != 1 else ''}",
                         f"{len(err.instance)} item{'s' if len(err.instance) != 1 else ''}")
    if err.validator in ("minProperties", "maxProperties"):
        n = err.validator_value
        most = "at least" if err.validator == "minProperties" else "at most"
        raise InputError(path, where, f"a mapping of {most} {n} entr{'ies' if n != 1 else 'y'}",
                         f"{len(err.instance)} entries")
    if err.validator == "enum":
        raise InputError(path, where, "one of " + ", ".join(map(str, err.validator_value)), err.instance)
    if err.validator == "pattern":
        what = _PATTERN_WORDS.get(err.validator_value)
        expected = f"{what} (text matching {err.validator_value})" if what else f"text matching {err.validator_value}"
        raise InputError(path, where, expected, err.instance)
    raise InputError(path, where, err.message)


#: what a stage without ``factors`` is expected to be
DERIVED_FACTORS_EXPECTED = ("the stage's factors (only a steepest_ascent stage after a plackett_burman one, or a "
                            "box_behnken stage after a steepest_ascent one, with from_stage and no table, may leave "
                            "them to the DEM recipe, which derives them from the earlier stage's DEM results)")
def derived_by_recipe(stage: dict, stages: list[dict] | None = None) -> bool:
    """Whether ``stage`` may leave its ``factors`` to the DEM recipe: a steepest ascent or a
    Box-Behnken stage with ``from_stage`` and no printed table (``stages``: the soil's, to
    check that the earlier stage is of the kind the recipe derives it from)."""
    from soilcal.chain.derive import DERIVED_KINDS

    if (stage.get("kind") not in {k for _, k in DERIVED_KINDS} or not stage.get("from_stage")
            or stage.get("table") is not None):
        return False
    if stages is None:
        return True
    up = next((s for s in stages if s.get("id") == stage["from_stage"]), None)
    return up is not None and (up.get("kind"), stage["kind"]) in DERIVED_KINDS


def left_to_recipe(stage: dict) -> bool:
    """Whether a loaded stage declares no factors of its own (:func:`derived_by_recipe`): the
    DEM recipe derives them, and nothing runs the stage on its config's levels."""
    return not stage.get("factors") and derived_by_recipe(stage)


def design_runs(stage: dict) -> int | None:
    """Number of runs of a stage's design, from its kind and factor count; None for a stage
    whose factors the DEM recipe derives (:func:`left_to_recipe`)."""
    if left_to_recipe(stage):
        return None
    kind = stage["kind"]
    k = len(stage["factors"])
    if kind == "plackett_burman":
        cols = k + len(stage.get("dummies", []))
        return int(stage.get("runs") or 4 * (cols // 4 + 1))
    if kind == "box_behnken":
        # pyDOE3.bbdesign: a 2^2 factorial on every pair of factors, the others at 0.
        return 4 * math.comb(k, 2) + int(stage.get("center_points", 0))
    if kind == "steepest_ascent":
        lengths = {len(f.get("levels", [])) for f in stage["factors"].values()}
        return max(lengths) if lengths else 0
    raise ValueError(kind)


@dataclass
class Soil:
    """A validated soil entry."""

    path: Path
    data: dict
    resources_root: Path = field(default=Path("resources"))
    #: top-level fields the file left out and the loader filled with the schema's default
    defaulted: tuple[str, ...] = ()
    #: the soil's photo manifest as read and checked at load (None: the soil has none)
    manifest: dict | None = None
    #: the conditions of its measured tables as read and checked at load
    #: (:func:`soilcal.config.measurements.conditions`; None: read on use)
    measured: tuple | None = None

    @property
    def name(self) -> str:
        return self.data["name"]

    @property
    def load_notes(self) -> list[str]:
        """What the user should know of how the soil is simulated though nothing is wrong:
        measured rows that differ only in ignored covariates and share one simulation
        (:attr:`soilcal.config.measurements.Condition.note`), each once; a file in the soil's
        measurement folder that the soil file names nowhere, and so is not read
        (:func:`soilcal.config.measurements.unread_files`)."""
        from soilcal.config.measurements import unread_files

        return (list(dict.fromkeys(c.note for c in (self.measured or ()) if c.note))
                + unread_files(self.data, self.resources_root))

    @property
    def stages(self) -> list[dict]:
        return self.data["stages"]

    def stage(self, stage_id: str) -> dict:
        for s in self.stages:
            if s["id"] == stage_id:
                return s
        raise InputError(self.path, "stages", f"a stage with id {stage_id!r}", [s["id"] for s in self.stages])

    def published_dir(self) -> Path:
        return self.resources_root / "published" / self.name

    def table_path(self, stage_id: str) -> Path | None:
        t = self.stage(stage_id).get("table")
        return None if t is None else self.published_dir() / t

    def printed_path(self, name: str) -> Path:
        return self.published_dir() / name

    @cached_property
    def tables(self) -> dict[str, pd.DataFrame]:
        return {s["id"]: read_table(self.table_path(s["id"])) for s in self.stages if s.get("table")}


def _check_levels(path: Path, where: str, d: dict) -> None:
    lo, hi, c = d.get("low"), d.get("high"), d.get("centre")
    if lo is not None and hi is not None and not lo < hi:
        held = (lo == hi and where.startswith("stages") and ".factors." in where)
        raise InputError(path, f"{where}.low", f"a number below high ({hi})"
                         + (" (a parameter held at one value goes under the stage's fixed values)" if held else ""), lo)
    if c is not None and lo is not None and hi is not None and not lo <= c <= hi:
        raise InputError(path, f"{where}.centre", f"a number between low ({lo}) and high ({hi})", c)


def _second_round_factor_stages(d: dict) -> dict[str, str]:
    """``{stage: factor stage}`` of the stages whose factors the second calibration round moves,
    the optimised stages the DEM source runs (:func:`soilcal.chain.derive.optimised_dem_stage_ids`,
    ``simulation.stages``): each with the stage whose config factors its DEM runs may vary
    (:func:`soilcal.chain.derive.factor_stage`: itself, or under ``design: recipe`` for a
    Box-Behnken design derived from the DEM path, the path, or the screening the path is
    derived from)."""
    from soilcal.chain.derive import factor_stage, optimised_dem_stage_ids

    return {sid: factor_stage(d, sid) for sid in optimised_dem_stage_ids(d)}


def _why_not_moved(d: dict, stage_id: str, moved: dict[str, str]) -> str:
    """Why the second round does not move the factors of stage ``stage_id``, one that is no
    factor stage of :func:`_second_round_factor_stages` (``moved``)."""
    st = next(st for st in d["stages"] if st["id"] == stage_id)
    chosen = (d.get("simulation") or {}).get("stages")
    if chosen and stage_id not in chosen:
        return f"a stage the DEM source does not run (simulation.stages: {', '.join(chosen)})"
    if stage_id in moved:
        return f"a stage whose DEM runs vary the factors of stage {moved[stage_id]} instead (design: recipe)"
    return f"a {st['kind'].replace('_', '-')} stage without an optimise block"


def check_search_ranges(path: Path, d: dict) -> None:
    """``simulation.search_ranges``: each entry names a parameter under ``parameters`` that a
    factor the second calibration round may move sets (:func:`_second_round_factor_stages`: a
    factor of an optimised stage that the DEM source runs, ``simulation.stages``, or, where
    ``design: recipe`` derives that stage from the DEM path, a factor of the path or of the
    screening the path is derived from, as the stage's DEM runs vary those; the round searches
    past the stage's levels, :func:`soilcal.chain.refine.search_region`).  A range for a
    parameter varied only by a stage no such run varies (a screening or a path the optimised
    stage is not derived from, a stage the DEM source does not run, one whose printed levels
    are lost), only fixed, or set nowhere would never be used, and is refused naming the stage
    factors that set it and why each does not count; so is every range of a soil that turns
    the second round off (``simulation.verification.refine: false``).  (A parameter the
    screening may select counts; the second round's ``refined.csv`` names the ranges of the
    stage's factors it uses.)  Each range has low <
    high, lies in the physical range of the DEM parameter it sets (the check every DEM run
    makes: :func:`soilcal.chain.derive.dem_value_in_range`, in the parameter's unit) and
    contains the ``low`` .. ``high`` of every stage factor setting that parameter (a search
    range narrower than a box it is to widen is a typing slip or another unit).  Checked in
    every design mode (``design: printed`` and ``adaptive`` record a declared range as not
    used)."""
    from soilcal.chain.derive import dem_value_in_range
    from soilcal.chain.refine import refine_settings
    from soilcal.dem.scenarios.base import dem_field

    ranges = (d.get("simulation") or {}).get("search_ranges") or {}
    params = d.get("parameters") or {}
    if ranges and not refine_settings(d):
        raise InputError(path, "simulation.search_ranges", "no entry while simulation.verification.refine is "
                         "false: the second calibration round, the only reader of a declared range, does not run",
                         ", ".join(ranges), note="delete the entries, or turn the second round on")
    moved = _second_round_factor_stages(d) if ranges else {}
    sources = set(moved.values())
    runs = "; ".join(sid if src == sid else f"{sid}, whose DEM runs vary the factors of stage {src} (design: recipe)"
                     for sid, src in moved.items()) or "none"
    for pid, r in ranges.items():
        where = f"simulation.search_ranges.{pid}"
        if pid not in params:
            raise InputError(path, where, "a parameter id listed under parameters (" + ", ".join(params) + ")", pid)
        varying = [(st["id"], sym, f) for st in d.get("stages") or []
                   for sym, f in (st.get("factors") or {}).items() if f.get("parameter") == pid]
        if not any(sid in sources for sid, _, _ in varying):
            why = "; ".join(f"stages.{sid}.factors.{sym} is in {_why_not_moved(d, sid, moved)}"
                            for sid, sym, _ in varying) or "no stage varies it"
            raise InputError(path, where, "a parameter set by a factor of a stage the second calibration round "
                             f"moves (an optimised stage the DEM source runs: {runs})", pid,
                             note=f"{why}; the range would never be used: delete the entry")
        lo, hi = float(r["low"]), float(r["high"])
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise InputError(path, f"{where}.low", f"a finite number below high ({r['high']})", r["low"])
        name, scale = dem_field(path, d, pid, f"parameters.{pid}")
        for key in ("low", "high"):
            dem_value_in_range(path, name, r[key], scale, f"{where}.{key}")
        for sid, sym, f in varying:
            if f.get("low") is None or f.get("high") is None:
                continue
            box = f"stages.{sid}.factors.{sym}"
            if lo > float(f["low"]):
                raise InputError(path, f"{where}.low", f"at most {f['low']:g}, the low level of {box}: a "
                                 f"search range contains every stage's range of {pid}", r["low"])
            if hi < float(f["high"]):
                raise InputError(path, f"{where}.high", f"at least {f['high']:g}, the high level of {box}: a "
                                 f"search range contains every stage's range of {pid}", r["high"])


def _check_verification_seeds(path: Path, d: dict) -> None:
    """``simulation.verification.max_replicates`` is at least its ``replicates`` (default 4):
    the second verification stage adds seeds to the first stage's, it cannot take fewer."""
    from soilcal.chain.verify import VERIFY_DEFAULTS

    ver = (d.get("simulation") or {}).get("verification") or {}
    if "max_replicates" in ver:
        reps = ver.get("replicates", VERIFY_DEFAULTS["replicates"])
        if ver["max_replicates"] < reps:
            raise InputError(path, "simulation.verification.max_replicates",
                             f"at least simulation.verification.replicates ({reps})", ver["max_replicates"])


def _check_stage_sets_each_parameter_once(path: Path, where: str, st: dict, params: dict) -> None:
    """A stage varies or fixes each parameter once: two factors on one parameter, or a factor
    and a fixed value of it, would leave one of the two without any effect on the runs (the
    last one set wins), and a dummy column must not bear a factor's symbol.  Two parameter
    ids that set the same DEM parameter (:func:`soilcal.config.parameters.dem_field_name`, the
    name :func:`soilcal.dem.scenarios.base.dem_field` maps them to) count as one."""

    from soilcal.config.parameters import dem_field_name, dem_key

    def key(pid):
        return dem_key(params, pid)

    def named(pid):
        name = dem_field_name(params.get(pid))
        return repr(pid) if name is None else f"{pid!r} (DEM parameter {name})"

    setters: dict = {}
    for sym, f in st["factors"].items():
        k = key(f["parameter"])
        if k in setters:
            raise InputError(path, f"{where}.factors.{sym}.parameter",
                             f"a parameter no other factor of the stage varies ({setters[k]})", f["parameter"])
        setters[k] = f"factor {sym} varies {named(f['parameter'])}"
    for p in st.get("fixed", {}):
        k = key(p)
        if k in setters:
            raise InputError(path, f"{where}.fixed.{p}",
                             f"a parameter the stage does not vary ({setters[k]}; give it as a factor "
                             "or as a fixed value, not both)", p)
        setters[k] = f"fixed.{p} sets {named(p)}"
    dummies = list(st.get("dummies") or [])
    for name in dummies:
        if name in st["factors"] or dummies.count(name) > 1:
            raise InputError(path, f"{where}.dummies",
                             "dummy column names used once and by no factor (" + ", ".join(st["factors"]) + ")", name)


def _check_own_properties(path: Path, d: dict) -> None:
    """A soil of one's own (no ``citation``: no printed value to keep as printed) gives its
    measured properties and materials in their units; a value outside the physical range of
    :data:`soilcal.config.quantities.PLAUSIBLE` once converted (a bulk density 1.52 declared in
    kg/m^3, a moisture content 15 declared as a fraction) would run the DEM or judge a moisture
    a thousand or a hundred times off without a word.  Refused naming the field, the range and,
    where the other unit of the quantity takes the value into it, that unit; a unit of no
    factor to the range's (:func:`~soilcal.config.quantities.si_factor`,
    :func:`~soilcal.config.quantities.quantity_factor`, the moisture units the tables take) is refused naming the units taken.
    A key no range is known of (relative_density, root_length_density) is not judged."""
    from soilcal.config.quantities import MOISTURE_UNITS, PLAUSIBLE, SI_UNITS_TAKEN, plausible_kind, quantity_factor, si_factor

    entries = [(f"properties.{k}", k, q, False) for k, q in (d.get("properties") or {}).items()]
    entries += [(f"materials.{m}.{k}", k, q, True) for m, props in (d.get("materials") or {}).items()
                for k, q in (props or {}).items()]
    for where, name, q, material in entries:
        kind = plausible_kind(name, material)
        if kind is None or not isinstance(q, dict) or "bins" in q:
            continue
        lo, hi, si = PLAUSIBLE[kind]
        what = name.replace("_", " ").replace("poisson", "Poisson").replace("youngs", "Young's")
        values = [(key, q[key]) for key in ("value", "low", "high")
                  if isinstance(q.get(key), (int, float)) and not isinstance(q.get(key), bool)]
        values += [(f"values[{i}]", v) for i, v in enumerate(q.get("values") or [])
                   if isinstance(v, (int, float)) and not isinstance(v, bool)]
        if not values:
            continue
        unit = q.get("unit")
        factor = quantity_factor("moisture_content", unit) if kind == "moisture_content" else si_factor(unit, si)
        if factor is None:
            taken = MOISTURE_UNITS if kind == "moisture_content" else SI_UNITS_TAKEN[si]
            raise InputError(path, f"{where}.unit", f"a unit of {what}: {taken}", unit)
        for key, v in values:
            x = float(v) * factor
            if lo <= x <= hi:
                continue
            said = [] if str(unit).strip() == si else [f"{v:g} {unit} is {x:.4g} {si}"]
            if si == "kg/m^3":
                other = next((u for u, f in (("g/cm^3", 1e3), ("kg/m^3", 1.0)) if lo <= float(v) * f <= hi), None)
                said += [f"in {other}? declare unit: {other}"] if other else []
            elif kind == "moisture_content" and factor != 1.0 and lo <= float(v) <= hi:
                said += ["in %? declare unit: %"]
            said = f" ({': '.join(said)})" if said else ""
            range_text = f"{lo:g} to {hi:g}" + ("" if si == "-" else f" {si}")
            raise InputError(path, f"{where}.{key}", f"a {what} of {range_text}{said}", v)


def _semantic_checks(path: Path, d: dict, resources_root: Path,
                     source_override: bool = False) -> tuple[dict | None, tuple]:
    """The checks a schema cannot state; returns the soil's photo manifest (None without one)
    and the conditions of its measured tables (empty without any).  ``source_override``: the
    soil's ``source`` is the workflow's (``--config source=...``), not the file's."""
    from soilcal.doe.designs import BBD_MIN_FACTORS

    if d["name"] != path.stem:
        raise InputError(path, "name", f"the file name without .yaml ({path.stem!r})", d["name"])
    for k, q in d.get("properties", {}).items():
        if isinstance(q, dict) and "bins" not in q:
            _check_levels(path, f"properties.{k}", q)
    if d.get("citation") is None:
        _check_own_properties(path, d)
    params = d["parameters"]
    targets = d.get("targets", {})
    seen: dict[str, dict] = {}
    for i, st in enumerate(d["stages"]):
        where = f"stages[{i}]"
        sid = st["id"]
        if sid in seen:
            raise InputError(path, f"{where}.id", "a stage id used once", sid)
        if "factors" not in st:
            if st.get("from_stage") and st["from_stage"] not in seen:
                # a misspelt from_stage, not the missing factors (checked below for every stage)
                raise InputError(path, f"{where}.from_stage", "the id of an earlier stage", st["from_stage"])
            if not derived_by_recipe(st, list(seen.values())):
                raise InputError(path, f"{where}.factors", DERIVED_FACTORS_EXPECTED, "nothing")
            # the DEM recipe derives them from the earlier stage's DEM results
            # (soilcal.chain.derive); a source or design that needs them says so at start-up
            st["factors"] = {}
        for sym, f in st["factors"].items():
            fw = f"{where}.factors.{sym}"
            if f["parameter"] not in params:
                raise InputError(path, f"{fw}.parameter", "an id listed under parameters", f["parameter"])
            _check_levels(path, fw, f)
            if st.get("table") is None:
                continue  # a stage whose table the paper does not print: levels may be missing too
            if st["kind"] in ("plackett_burman", "box_behnken") and ("low" not in f or "high" not in f):
                raise InputError(path, fw, "low and high levels for a two/three-level design", f)
            if st["kind"] == "steepest_ascent" and not f.get("levels"):
                raise InputError(path, f"{fw}.levels", "the actual value of every step", None)
        if st["kind"] == "plackett_burman" and st.get("runs") is not None:
            from soilcal.chain.stage import pb_columns

            try:
                pb_columns(st)  # a design's run count: a multiple of 4 above the factors and dummies
            except InputError as exc:
                raise InputError(path, f"{where}.runs", exc.expected, exc.got) from None
        if st["kind"] == "steepest_ascent" and st.get("table") is not None:
            # the printed path's steps (a path the DEM runs on its own levels: check_block)
            from soilcal.dem.scenarios.design import path_steps

            n_steps = path_steps(path, where, st)
            if "chosen_step" in st and not 1 <= st["chosen_step"] <= n_steps:
                raise InputError(path, f"{where}.chosen_step", "a step number of the path", st["chosen_step"])
        for p in st.get("fixed", {}):
            if p not in params:
                raise InputError(path, f"{where}.fixed.{p}", "an id listed under parameters", p)
        _check_stage_sets_each_parameter_once(path, where, st, params)
        if st["kind"] == "box_behnken" and len(st["factors"]) < BBD_MIN_FACTORS and not left_to_recipe(st):
            # the design exists for three factors and more (its design job would stop)
            raise InputError(path, f"{where}.factors", f"at least {BBD_MIN_FACTORS} factors for a Box-Behnken design "
                             "(fix the others in fixed)", f"{len(st['factors'])} ({', '.join(st['factors'])})")
        for key in ("from_stage",):
            if key in st and st[key] not in seen:
                raise InputError(path, f"{where}.{key}", "the id of an earlier stage", st[key])
        if "fixed_from" in st and st["fixed_from"]["stage"] not in seen:
            raise InputError(path, f"{where}.fixed_from.stage", "the id of an earlier stage", st["fixed_from"]["stage"])
        rids = [r["id"] for r in st["responses"]]
        if len(set(rids)) != len(rids):
            raise InputError(path, f"{where}.responses", "distinct response ids", rids)
        for r in st.get("printed", {}):
            if r not in rids:
                raise InputError(path, f"{where}.printed.{r}", "a response id of this stage (" + ", ".join(rids) + ")", r)
        for r in st.get("transform", {}):
            if r not in rids:
                raise InputError(path, f"{where}.transform.{r}", "a response id of this stage", r)
        opt = st.get("optimise")
        if opt:
            for j, case in enumerate(opt["cases"]):
                for r, g in case["goals"].items():
                    gw = f"{where}.optimise.cases[{j}].goals.{r}"
                    if r not in rids:
                        raise InputError(path, gw, "a response id of this stage (" + ", ".join(rids) + ")", r)
                    if g["goal"] == "target" and "value" not in g and "target" not in g:
                        raise InputError(path, gw, "a target value or a target id", g)
                    if "value" in g and "target" in g:
                        raise InputError(path, gw, "a target value or a target id, not both (which would it aim at?)",
                                         g)
                    if "target" in g and g["target"] not in targets:
                        raise InputError(path, f"{gw}.target", "an id listed under targets", g["target"])
                    if g["goal"] == "in_range" and not ("low" in g and "high" in g and g["low"] < g["high"]):
                        raise InputError(path, gw, "low < high for an in_range goal", g)
                cw = f"{where}.optimise.cases[{j}]"
                syms = list(st.get("factors") or {})
                for key in case.get("printed_optimum") or {}:
                    if syms and key not in syms and key not in rids:
                        raise InputError(path, f"{cw}.printed_optimum.{key}", "a factor symbol of this stage ("
                                         + ", ".join(syms) + ") or a response id (" + ", ".join(rids) + ")", key)
                for key in case.get("printed_verification") or {}:
                    if key not in rids:
                        raise InputError(path, f"{cw}.printed_verification.{key}",
                                         "a response id of this stage (" + ", ".join(rids) + ")", key)
        _check_table(path, st, where, resources_root / "published" / d["name"])
        for r, pr in st.get("printed", {}).items():
            for key in ("anova_full", "anova_reduced", "effects", "coefficients"):
                if key in pr and not (resources_root / "published" / d["name"] / pr[key]).is_file():
                    raise InputError(path, f"{where}.printed.{r}.{key}", "an existing file under resources/published/" + d["name"], pr[key])
        seen[sid] = st
    manifest = _check_images(path, d, resources_root)
    _check_layers(path, d)
    _check_targets(path, d, resources_root)
    if d.get("source") in ("dem", "both") and not d.get("simulation"):
        # the DEM source needs to know how each response is simulated; the source is the soil's
        # own, or the workflow's (--config source=...) for every soil
        how = (f"the workflow's source {d['source']} (--config source={d['source']}) runs the DEM for every soil; "
               "or run the workflow with source=published" if source_override
               else f"source {d['source']} runs the DEM; or source: published")
        raise InputError(path, "simulation", f"a simulation block naming the scenario of each response ({how})", None)
    check_search_ranges(path, d)
    _check_verification_seeds(path, d)
    if d.get("simulation"):
        from soilcal.dem.scenarios.design import check_block

        check_block(path, d)
        if d["simulation"].get("design") == "adaptive":
            from soilcal.chain.adaptive import check_settings

            check_settings(path, d)
    _check_paper_psd(path, d)
    measured = ()
    if d.get("measurements"):
        from soilcal.config.measurements import check_measurements

        _check_boolean_keys(path, d)

        measured = tuple(check_measurements(path, d, resources_root))
    if d.get("loop"):
        from soilcal.loop.settings import settings_from

        settings = settings_from(d, path)
        _check_fold_by(path, d, settings.fold_by)
        if measured:
            from soilcal.loop.core import check_reference

            check_reference(measured, settings.reference, path)
    return manifest, measured


#: unquoted words YAML 1.1 (PyYAML) reads as booleans besides true and false
_YAML_BOOLEAN_WORDS = ("yes", "no", "on", "off")


def _check_boolean_keys(path: Path, d: dict) -> None:
    """A table value written unquoted as a key of a covariate's ``setup`` or ``case`` map
    (``no: plate-arc``) that YAML reads as a boolean (yes, no, on, off) is refused, saying so
    and how to quote it; the table's cell stays the text ``no`` and would match no key."""
    bad = [(mid, col, form) for mid, e in (d.get("measurements") or {}).items() if isinstance(e, dict)
           for col, cv in (e.get("covariates") or {}).items() if isinstance(cv, dict)
           for form in ("setup", "case") if isinstance(cv.get(form), dict)
           and any(isinstance(k, bool) for k in cv[form])]
    if not bad:
        return
    with open(path, encoding="utf-8") as fh:
        root = yaml.compose(fh, Loader=_Loader)

    def child(node, key):
        if isinstance(node, yaml.MappingNode):
            for k, v in node.value:
                if isinstance(k, yaml.ScalarNode) and k.value == key:
                    return v
        return None

    for mid, col, form in bad:
        node = root
        for key in ("measurements", mid, "covariates", col, form):
            node = child(node, key)
        for k, _ in node.value if isinstance(node, yaml.MappingNode) else []:
            if k.tag == "tag:yaml.org,2002:bool" and k.style is None and k.value.lower() in _YAML_BOOLEAN_WORDS:
                boolean = "true" if k.value.lower() in ("yes", "on") else "false"
                raise InputError(path, f"measurements.{mid}.covariates.{col}.{form}",
                                 f'the key quoted, "{k.value}": the table value \'{k.value}\' written unquoted (line '
                                 f"{k.start_mark.line + 1}) is read by YAML as the boolean {boolean}", k.value)


def _check_fold_by(path: Path, d: dict, fold_by) -> None:
    """``loop.fold_by`` names a covariate column of the soil's measured tables (a column under
    ``measurements.<id>.covariates``), which the held-out folds of the loop are grouped by."""
    if fold_by is None:
        return
    columns = sorted({c for entry in (d.get("measurements") or {}).values()
                      for c in (entry.get("covariates") or {})})
    if not isinstance(fold_by, str) or fold_by not in columns:
        raise InputError(path, "loop.fold_by", "a covariate column of the soil's measured tables ("
                         + (", ".join(columns) if columns else "none: no measurements.<id>.covariates") + ")",
                         fold_by)


def manifest_path(resources_root: Path, name: str) -> Path:
    """The soil's photo manifest, ``<resources>/images/<soil>/manifest.yaml``."""
    return Path(resources_root) / "images" / name / "manifest.yaml"


def _check_images(path: Path, d: dict, resources_root: Path) -> dict | None:
    """The soil's photo manifest, where it has one, checked as the workflow reads it
    (:func:`soilcal.imaging.manifest.read_manifest`: its fields, every photo present); a
    target measured on photos names a photo group of it.  Returns the manifest (None without
    one)."""
    from soilcal.imaging.manifest import MEASURES, read_manifest

    manifest = manifest_path(resources_root, d["name"])
    m = read_manifest(manifest) if manifest.is_file() else None
    if m is not None and m.get("soil") is not None and m["soil"] != d["name"]:
        # a folder copied (or linked) from another soil: its photos would calibrate this one
        raise InputError(manifest, "soil", f"{d['name']!r}, the soil whose photo folder this is (a manifest "
                         "copied from another soil's folder names that soil; the field may be left out)", m["soil"])
    targets = d.get("targets", {})
    for tid, t in targets.items():
        if "image_measure" in t and not t.get("image"):
            raise InputError(path, f"targets.{tid}.image_measure",
                             f"a photo group to measure it on (targets.{tid}.image)", t["image_measure"])
    named = {tid: t["image"] for tid, t in targets.items() if t.get("image")}
    if not named:
        return m
    tid = next(iter(named))
    if m is None:
        raise InputError(path, f"targets.{tid}.image", f"a photo group of {manifest}", "no such file")
    kinds = {ph["group"]: ph["kind"] for ph in m["photos"]}
    groups = sorted(kinds)
    for tid, g in named.items():
        if g not in groups:
            raise InputError(path, f"targets.{tid}.image", f"a photo group of {manifest} ({', '.join(groups)})", g)
        key = targets[tid].get("image_measure", "angle_deg")
        if key not in MEASURES[kinds[g]]:
            raise InputError(path, f"targets.{tid}.image_measure",
                             f"a value the measurement of the {kinds[g]} group {g!r} gives ({', '.join(MEASURES[kinds[g]])})"
                             + ("" if "image_measure" in targets[tid] else "; left out, it is angle_deg"), key)
    _check_image_states(path, targets, named)
    return m


def _check_image_states(path: Path, targets: dict, named: dict) -> None:
    """One photo group's measurement is of one soil state (a group has one kind, and every
    measure of it, ``angle_deg``, ``left_deg`` or ``spread_deg``, comes from the same photos):
    two targets on the same group (``image``) that both give a moisture content or a layer
    (``moisture_content``, ``layer``), different ones, would calibrate both states to the same
    photos (a target line copied for the next moisture with its ``image`` left as it was):
    refused naming the second target's ``image``, both states and, for each, the target that
    gave it (the first on the group to give that state, not always the group's first
    target)."""
    from soilcal.config.quantities import same_number

    given = {}  # photo group -> state key -> (its value, the first target that gave it)
    for tid, g in named.items():
        t = targets[tid]
        state = {k: t[k] for k in ("moisture_content", "layer") if t.get(k) is not None}
        seen = given.setdefault(g, {})

        def same(k, v):
            if k == "layer":
                return str(state[k]).strip() == str(v).strip()
            return same_number(float(state[k]), float(v))

        differ = [(k, *seen[k]) for k in ("moisture_content", "layer") if k in state and k in seen
                  and not same(k, seen[k][0])]
        if differ:
            says = "; ".join(f"targets.{other} ({k} {v} there, {state[k]} here)" for k, v, other in differ)
            raise InputError(path, f"targets.{tid}.image",
                             f"a photo group of this target's own soil state: {g!r} is already the "
                             f"photo group of {says}; one group's photos, every measure "
                             "of them, are of one moisture and layer", g)
        for k, v in state.items():  # a later target may give what the first left out
            seen.setdefault(k, (v, tid))


def _check_layers(path: Path, d: dict) -> None:
    """``layers``: a mapping of each layer's name to what it is, as text with its unit
    (``upper: "0-20 cm"``) or nothing, or a list of the names (``[upper, middle, lower]``);
    each refusal names the field and shows the forms taken.  A name is text in either form, as
    a target's ``layer`` gives it: a bare number (``20``, a mapping's key as a list's item) is
    refused asking for it quoted; what a layer is, given as a number alone (``20`` or
    ``"20"``, ``"0-20"``), is refused: it has no unit; blank text (``""``) is nothing."""
    if "layers" not in d:
        return
    layers = d["layers"]
    forms = ('a mapping of each layer to what it is, layers: {upper: "0-20 cm", middle: "20-40 cm"} '
             "(or nothing: {upper: null}), or a list of the names, layers: [upper, middle]")
    if isinstance(layers, list):
        if not layers:
            raise InputError(path, "layers", forms, "an empty list")
        names = [(f"layers[{i}]", name) for i, name in enumerate(layers)]
    elif isinstance(layers, dict) and layers:
        names = [(f"layers.{name}", name) for name in layers]
    else:
        raise InputError(path, "layers", forms, layers)
    for i, (field, name) in enumerate(names):
        if not isinstance(name, str) or not name.strip():
            said = f' (quote it, "{name}", if the layer is so named)' if isinstance(name, (int, float)) else ""
            raise InputError(path, field, "a layer's name, as text, the text a target's layer gives" + said, name)
        if name in [n for _f, n in names[:i]]:
            raise InputError(path, field, "a layer named once", name)
    if isinstance(layers, dict):
        for name, what in layers.items():
            if isinstance(what, str) and not what.strip():
                continue  # upper: "" says nothing of the layer, as upper: (null) does
            if what is not None and (not isinstance(what, str) or re.fullmatch(r"[\d\s.,;:+\-\u2013\u2014/~]*", what)):
                raise InputError(path, f"layers.{name}", 'what the layer is, as text with its unit ("0-20 cm", '
                                 '"20 cm deep"), or nothing: a bare number has no unit', what)


def _check_targets(path: Path, d: dict, resources_root: Path) -> None:
    """A target's ``layer`` is one of the soil's declared ``layers`` (a misspelt one would make a
    layer of its own), its ``table`` a file under ``<resources>/measurements/<soil>/``, and a target
    has the unit of every response it is the target of: the response whose id it bears (the
    steepest-ascent path aims that response at it) and every response an optimisation goal
    aims at it (``target: <id>``)."""
    targets = d.get("targets", {})
    mdir = resources_root / "measurements" / d["name"]
    from soilcal.config.measurements import table_inside

    layers = d.get("layers")
    for tid, t in targets.items():
        if t.get("layer") is not None and str(t["layer"]) not in {str(k) for k in (layers or {})}:
            if layers:
                want = "one of the soil's layers (" + ", ".join(map(str, layers)) + ")"
            else:
                want = ('a layer the soil declares: it declares none (add layers: {' + f"{t['layer']}: ..." +
                        '} naming each layer once, e.g. its depth "0-20 cm")')
            raise InputError(path, f"targets.{tid}.layer", want, t["layer"])
        if t.get("table") is not None and not table_inside(path, f"targets.{tid}.table", mdir, t["table"]).is_file():
            raise InputError(path, f"targets.{tid}.table", f"an existing file under {mdir}", t["table"])
        if t.get("moisture_content") is not None:
            _check_target_moisture(path, d, tid, t["moisture_content"])
    for st in d["stages"]:
        units = {r["id"]: r["unit"] for r in st["responses"]}
        links = [(rid, rid, "whose id it bears") for rid in units if rid in targets]
        for case in (st.get("optimise") or {}).get("cases", []):
            links += [(rid, g["target"], f"of optimisation case {case['id']!r}")
                      for rid, g in case["goals"].items() if "target" in g and rid in units]
        for rid, tid, how in links:
            got = str(targets[tid]["unit"]).strip()
            if got != str(units[rid]).strip():
                raise InputError(path, f"targets.{tid}.unit",
                                 f"{units[rid]}, the unit of response {rid!r} of stage {st['id']!r} ({how})", got)


def _check_target_moisture(path: Path, d: dict, tid: str, mc) -> None:
    """A target recorded at a moisture content (``targets.<id>.moisture_content``, in the unit
    of ``properties.moisture_content``) is a target of this soil only at a moisture the soil
    declares: one of its ``properties.moisture_content`` values, or inside its ``low`` ..
    ``high``.  A measurement or photo at another moisture is of another soil state: the DEM
    parameters calibrated to it would be filed under the soil's own moisture without a word."""
    from soilcal.config.quantities import declares_moisture, soil_moisture

    where = f"targets.{tid}.moisture_content"
    declared = soil_moisture(path, d)
    if declared is None:
        raise InputError(path, where, "a moisture content the soil declares (properties.moisture_content: "
                                      "value, values or low/high, none given)", mc)
    if declares_moisture(declared, float(mc) * declared["factor"]):
        return
    raise InputError(path, where, f"a moisture content the soil declares in properties.moisture_content "
                                  f"({declared['text']}; the target's moisture is in that unit, the same number): "
                                  "add it to properties.moisture_content.values if the soil was measured at it", mc)


def _check_table(path: Path, st: dict, where: str, pub: Path) -> None:
    if st.get("table") is None:
        return
    from soilcal.config.measurements import table_inside

    tpath = table_inside(path, f"{where}.table", pub, st["table"])
    if not tpath.is_file():
        raise InputError(path, f"{where}.table", f"an existing file {tpath}", "no such file")
    df = read_table(tpath)
    rcols = [r.get("column", r["id"]) for r in st["responses"]]
    key = "step" if st["kind"] == "steepest_ascent" else None
    need = ([key] if key else []) + list(st["factors"]) + rcols
    absent = [c for c in need if c not in df.columns]
    if absent:
        raise InputError(tpath, "columns", "columns " + ", ".join(need), f"missing {', '.join(absent)}")
    n = design_runs(st)
    if len(df) != n:
        raise InputError(tpath, "rows", f"{n} rows for the {st['kind']} design of stage {st['id']!r} (from {path.name})", len(df))
    ids = [c for c in (key, "run") if c in df.columns]
    for c in ids + list(st["factors"]) + rcols:
        if c in rcols and df[c].isna().all():
            continue  # a response the paper does not print
        # a response the paper prints has a number in every run: a blank or "n/a" cell would
        # leave that run out of the fit without a word
        _check_cells(tpath, df, c, required=True)
    for c in ids:
        dup = df[c][df[c].duplicated()]
        if len(dup):
            i = int(dup.index[0])
            raise InputError(tpath, f"row {i + 1}, column {c}", f"a {c} number used once", _cell(dup.iloc[0]))
    coding = st.get("table_coding", "coded" if st["kind"] != "steepest_ascent" else "actual")
    if coding == "coded":
        allowed = {-1, 1} if st["kind"] == "plackett_burman" else {-1, 0, 1}
        for c in list(st["factors"]) + [x for x in st.get("dummies", []) if x in df.columns]:
            bad = sorted(set(df[c].dropna()) - allowed)
            if bad:
                raise InputError(tpath, f"column {c}", "coded levels " + "/".join(map(str, sorted(allowed))), bad)
    elif st["kind"] != "steepest_ascent":
        for c, f in st["factors"].items():
            lo, hi = f["low"], f["high"]
            bad = df[c][(df[c] < lo - 1e-9 * abs(hi)) | (df[c] > hi + 1e-9 * abs(hi))]
            if len(bad):
                raise InputError(tpath, f"column {c}", f"values within [{lo}, {hi}]", bad.tolist())


@functools.lru_cache(maxsize=4)
def _schema_once(path: Path) -> Any:
    return read_yaml(path)


def soil_schema() -> dict:
    """The soil schema (:data:`SOIL_SCHEMA`), parsed once per process (a file of the package);
    each call returns its own copy."""
    return copy.deepcopy(_schema_once(Path(SOIL_SCHEMA)))


def schema_defaults(schema: dict | None = None) -> dict[str, Any]:
    """The top-level fields the soil schema gives a ``default`` (documented in its description)."""
    schema = soil_schema() if schema is None else schema
    return {k: v["default"] for k, v in schema["properties"].items() if isinstance(v, dict) and "default" in v}


def _cell(v):
    """A table cell as a plain Python value for a message."""
    if isinstance(v, float) and v.is_integer():
        return int(v)
    return v.item() if hasattr(v, "item") else v


def _check_cells(tpath: Path, df: pd.DataFrame, column: str, required: bool) -> None:
    """Every cell of ``column`` a finite number (empty allowed unless ``required``); the first
    bad cell raises InputError naming its row (1 = first data row) and column."""
    col = df[column]
    for i, v in enumerate(col.tolist()):
        if v is None or (isinstance(v, float) and math.isnan(v)) or (isinstance(v, str) and not v.strip()):
            if required:
                raise InputError(tpath, f"row {i + 1}, column {column}", "a number", EMPTY_CELL)
            continue
        try:
            x = float(v)
        except (TypeError, ValueError):
            raise InputError(tpath, f"row {i + 1}, column {column}", "a number", v) from None
        if not math.isfinite(x):
            raise InputError(tpath, f"row {i + 1}, column {column}", "a finite number", v)


def _check_paper_psd(path: Path, d: dict) -> None:
    """A soil's own particle sizes (``set: {paper_psd: ...}`` of a simulated response or a
    measured test) are the paper preset's particles, and the quick preset scales the surface
    energy by their Sauter radius: so the setup must hold them under the paper preset too, or
    a slip (millimetres for metres) would scale the cohesion of every quick run without a word.
    The setup is validated under the paper preset with the soil's own density and moduli and
    without its ``radius`` and ``n_particles`` (either would take the place of ``paper_psd``
    there, while the quick runs still scale by it); the error names the entry's
    ``set.paper_psd`` only when the same setup holds the named setup's own sizes."""
    from soilcal.chain.provenance import base_params
    from soilcal.config.measurements import entry_set_of
    from soilcal.dem.scenarios import SCENARIOS
    from soilcal.dem.scenarios.base import merge_setup

    preset_of = (d.get("simulation") or {}).get("preset", "quick")
    entries = [(f"simulation.responses.{rid}", e, preset_of, e.get("set") or {}, {})
               for rid, e in ((d.get("simulation") or {}).get("responses") or {}).items()]
    for mid, e in (d.get("measurements") or {}).items():
        entries.append((f"measurements.{mid}", e, e.get("preset", "quick"), *entry_set_of(path, d, mid, e)))
    params = None
    for where, entry, preset, given, taken in entries:
        if "paper_psd" not in given or preset == "paper" or entry.get("scenario") not in SCENARIOS:
            continue
        mod = SCENARIOS[entry["scenario"]]
        if entry.get("setup") not in mod.setups():  # a setup name the entry's own check names
            continue
        params = params or base_params(d, path)
        sizes = {k: None for k in ("radius", "n_particles") if k in mod.setups()[entry["setup"]]}
        try:
            # the named setup's own sizes first: a setup the paper preset cannot hold at all
            # is not the particle sizes' fault (the quick runs' own checks report it)
            own = {k: v for k, v in given.items() if k != "paper_psd"}
            mod.validate(dict(merge_setup(mod.setups(), entry["setup"], own, str(path)), **sizes), "paper",
                         str(path), params)
        except InputError:
            continue
        try:
            mod.validate(dict(merge_setup(mod.setups(), entry["setup"], given, str(path)), **sizes), "paper",
                         str(path), params)
        except InputError as exc:
            raise InputError(path, f"{where}.set.paper_psd",
                             "particle radii in metres that the setup holds as the paper preset's particles "
                             f"({exc.field}: {exc.expected}, got {exc.got})"
                             + (f"; this test takes {taken['paper_psd']}, the soil's own: give the test its own "
                                "paper_psd" if "paper_psd" in taken else ""), given["paper_psd"]) from None


def load_soil(path: str | Path, resources_root: str | Path = "resources", design: str | None = None,
              source: str | None = None) -> Soil:
    """Read, schema-validate and check one soil file; return a :class:`Soil`.

    A top-level field the file leaves out that the schema gives a default (``source``,
    ``seed``, ``properties``, ``targets``) is filled in with that default; the names of the
    filled fields are in :attr:`Soil.defaulted`.  ``design`` (the workflow config's
    ``design``, ``--config design=...``) replaces ``simulation.design`` of a soil with a
    simulation block before the checks, and ``source`` (``--config source=...``) its
    ``source``, so the soil is checked as the workflow runs it.
    """

    path = Path(path)
    data = read_yaml(path)
    if not isinstance(data, dict):
        raise InputError(path, "<root>", "a mapping of soil fields", "an empty file" if data is None else type(data).__name__)
    schema = soil_schema()
    _schema_error(path, schema, data)
    defaulted = []
    for key, value in schema_defaults(schema).items():
        if key not in data:
            data[key] = copy.deepcopy(value)
            defaulted.append(key)
    if design is not None and data.get("simulation"):
        data["simulation"]["design"] = design
    if source is not None:
        data["source"] = source
    manifest, measured = _semantic_checks(path, data, Path(resources_root), source_override=source is not None)
    return Soil(path=path, data=data, resources_root=Path(resources_root), defaulted=tuple(defaulted),
                manifest=manifest, measured=measured)


def load_workflow_config(cfg: dict, origin: str | Path = "config/config.yaml",
                         origins: dict[str, str] | None = None) -> dict[str, Soil]:
    """Validate the workflow config and every soil it lists; return soils by name (the
    config's ``design`` and ``source``, where given, as every soil's ``simulation.design`` and
    ``source``).

    An error names ``origin``, the config file, or for a top-level key given elsewhere (a
    ``--configfile``, ``--config`` on the command line) where ``origins`` says it was given.
    A soil listed without its file names the list entry (``soils[i]``) and the file looked for.
    """
    origins = origins or {}

    def where(key: str) -> str | Path:
        return origins.get(key, origin)

    try:
        _schema_error(Path(origin), read_yaml(WORKFLOW_SCHEMA), cfg)
    except InputError as exc:
        top = re.split(r"[.\[]", exc.field, maxsplit=1)[0]
        if top in origins:
            raise InputError(origins[top], exc.field, exc.expected, exc.got) from None
        raise
    soil_dir = Path(cfg.get("soil_dir", "config/soils"))
    res = Path(cfg.get("resources", "resources"))
    for i, name in enumerate(cfg["soils"]):
        if name in cfg["soils"][:i]:
            raise InputError(where("soils"), f"soils[{i}]",
                             f"each soil listed once (soils[{cfg['soils'].index(name)}] lists it)", name)
    out = {}
    for i, name in enumerate(cfg["soils"]):
        p = soil_dir / f"{name}.yaml"
        if not p.is_file():
            raise InputError(where("soils"), f"soils[{i}]", f"a soil file {p} (the soil's YAML, named after the soil)",
                             "no such file")
        out[name] = load_soil(p, res, design=cfg.get("design"), source=cfg.get("source"))
    return out
