"""Where the DEM parameters of a soil's simulated stages come from, checked at start-up.

A DEM run needs every field of :class:`soilcal.dem.scenarios.base.DemParams`.  A soil sets
them through its printed properties (``properties.poisson_ratio``, ``particle_density``,
``shear_modulus``), ``simulation.params``, a stage's ``fixed`` values and factors, and, for a
stage the DEM derives from an earlier simulated one (``from_stage``: the earlier factors
held at their intermediate levels; ``fixed_from``: the earlier optimum), that stage's.

The engine's own defaults (:class:`DemParams`) are the values of one soil study, so a soil
that leaves a soil parameter out would run with another soil's value.  So every *soil*
parameter of a simulated stage must come from the soil itself; only :data:`GENERIC` ones may
be left to the defaults, which hold for any soil (steel's material constants; no soil-steel
adhesion; elastic soil-soil contacts), and the stage files record every value a run used
(``p:<name>`` columns of ``runs/*.csv``).
"""

from __future__ import annotations

from soilcal.errors import InputError

#: DemParams fields with a default that holds for any soil (value and meaning)
GENERIC = {
    "steel_density": "7850 kg/m^3, carbon steel",
    "steel_poisson": "0.3, carbon steel",
    "steel_shear_modulus": "7.9e10 Pa, carbon steel",
    "soil_steel_surface_energy": "0 J/m^2, no soil-steel adhesion",
    "soil_soil_plasticity": "0, elastic (Hertz) soil-soil contacts",
}

#: a printed Young's modulus, which no run takes (the runs take the shear modulus), is checked
#: all the same where the soil is simulated: its plausible range in Pa follows from the shear
#: modulus's and the Poisson ratio's, E = 2 (1 + nu) G (soilcal.dem.scenarios.base.SOIL_RANGES)
YOUNGS_RANGE = (2.0e4, 1.5e11)


def soil_parameters() -> list[str]:
    """The DemParams fields a soil must set (every one but :data:`GENERIC`)."""
    from soilcal.dem.scenarios.base import DemParams

    return [n for n in DemParams.names() if n not in GENERIC]


def given(data: dict, stage_id: str, _seen=None, soil_path=None) -> set[str]:
    """DemParams fields that the soil sets for the runs of a simulated stage (module
    docstring).  A stage's factor or fixed parameter maps to its field as the DEM jobs map it
    (:func:`soilcal.dem.scenarios.base.dem_field`; one that maps to none is an InputError
    naming ``soil_path`` and the entry)."""
    from soilcal.chain.derive import _stage, dependencies
    from soilcal.dem.scenarios.base import PROPERTY_FIELDS, dem_field

    seen = set() if _seen is None else _seen
    if stage_id in seen:
        return set()
    seen.add(stage_id)
    out = set()
    out |= {name for prop, name in PROPERTY_FIELDS.items()
            if ((data.get("properties") or {}).get(prop) or {}).get("value") is not None}
    out |= set(((data.get("simulation") or {}).get("params") or {}))
    st = _stage(data, stage_id)
    for pname in st.get("fixed") or {}:
        out.add(dem_field(soil_path, data, pname, f"stages.{stage_id}.fixed.{pname}")[0])
    for sym, f in (st.get("factors") or {}).items():
        out.add(dem_field(soil_path, data, f.get("parameter"), f"stages.{stage_id}.factors.{sym}.parameter")[0])
    for earlier in dependencies(data, stage_id).values():
        out |= given(data, earlier, seen, soil_path)
    return out


def check_properties(soil_path, data: dict) -> None:
    """The printed properties the runs take (:data:`soilcal.dem.scenarios.base.PROPERTY_FIELDS`):
    a unit with a factor to SI and a value physical and plausible for a soil
    (:data:`soilcal.dem.scenarios.base.SOIL_RANGES`); a printed ``youngs_modulus`` within
    :data:`YOUNGS_RANGE`.  Otherwise one error naming the property."""
    from soilcal.dem.scenarios.base import _UNIT_SCALE, DemParams, property_values, unit_scale

    props = data.get("properties") or {}
    replaced = set(((data.get("simulation") or {}).get("params") or {}))
    for name, (x, prop) in property_values(soil_path, data).items():
        try:
            # a printed value that simulation.params replaces is no run's (a misprint kept as
            # printed, as the vineyard soil's density): only its physical range is asked of it
            DemParams.from_mapping({name: x}, str(soil_path), plausible=name not in replaced)
        except InputError as exc:
            raise InputError(soil_path, f"properties.{prop}.value",
                             f"{exc.expected} (DEM parameter {name}, from the value in {props[prop].get('unit', '-')})",
                             props[prop]["value"]) from None
    entry = props.get("youngs_modulus")
    if isinstance(entry, dict) and entry.get("unit", "-") in _UNIT_SCALE:
        # no run takes it: a unit without a factor here (N/mm^2) is left to the errata's note
        scale = unit_scale(soil_path, entry, "properties.youngs_modulus")
        lo, hi = YOUNGS_RANGE
        for key in ("value", "low", "high", "values"):
            for i, v in enumerate((entry.get(key) or []) if key == "values" else [entry.get(key)]):
                if v is not None and not lo <= float(v) * scale <= hi:
                    raise InputError(soil_path, f"properties.youngs_modulus.{key}" + (f"[{i}]" if key == "values" else ""),
                                     f"a soil Young's modulus in [{lo:g}, {hi:g}] Pa (2 (1 + nu) G over the plausible "
                                     f"shear moduli; in {entry.get('unit', '-')}: [{lo / scale:g}, {hi / scale:g}])", v)


def property_base(soil_path, data: dict):
    """:class:`~soilcal.dem.scenarios.base.DemParams` with the soil's printed properties the runs
    take over the engine's defaults (checked, :func:`check_properties`): the base on which the
    start-up checks of a setup lay ``simulation.params`` and a measured row's values, as the runs
    lay them (:func:`soilcal.dem.scenarios.base.stage_params`)."""
    from soilcal.dem.scenarios.base import DemParams, property_values

    check_properties(soil_path, data)
    replaced = set(((data.get("simulation") or {}).get("params") or {}))
    return DemParams.from_mapping({n: x for n, (x, _) in property_values(soil_path, data).items() if n not in replaced},
                                  str(soil_path))


def check_parameters(soil_path, data: dict) -> None:
    """Every soil parameter of every stage the DEM source simulates is set by the soil
    (module docstring): otherwise one error naming the stage and the missing parameters."""
    from soilcal.chain.derive import simulated_stage_ids
    from soilcal.dem.scenarios.base import PROPERTY_FIELDS

    if not data.get("simulation"):
        return
    check_properties(soil_path, data)
    need = soil_parameters()
    for sid in simulated_stage_ids(data):
        missing = [n for n in need if n not in given(data, sid, soil_path=soil_path)]
        if missing:
            prop_of = {name: prop for prop, name in PROPERTY_FIELDS.items()}
            named = [n + (f" (or properties.{prop_of[n]} with its unit)" if n in prop_of else "") for n in missing]
            raise InputError(soil_path, "simulation.params",
                             f"a value of every soil parameter the runs of stage {sid!r} use (SI units, in "
                             f"simulation.params or the stage's fixed values); missing: {', '.join(named)}",
                             "none")


# --------------------------------------------------------------------------- simulation.csv

#: columns of ``results/<soil>/dem/simulation.csv`` (:func:`simulation_setup`)
SETUP_COLUMNS = ["item", "value", "origin", "note"]

#: the simulation block's options with a default, as the chain applies them (the soil schema
#: documents each): key -> (default, what the default is)
BLOCK_DEFAULTS = {
    "preset": ("quick", "scenario preset (default quick)"),
    "replicates": (1, "seeds per design point (default 1)"),
    "design": ("recipe", "the design the DEM runs (default recipe: the papers' recipe on the DEM's own results)"),
    "threads": (1, "Numba threads per DEM job (default 1)"),
}


def _text(v) -> str:
    """A value as the file writes it: text as it is, numbers and lists as JSON."""
    import json

    if isinstance(v, str):
        return v
    return json.dumps(v, default=str)


def base_params(data: dict, path):
    """DemParams from a soil's printed properties and ``simulation.params`` alone (the base
    every run starts from before its stage's fixed values and factor levels); ``data`` is the
    soil file's content, ``path`` its name in errors."""
    from soilcal.dem.scenarios.base import DemParams, property_values

    values = {name: x for name, (x, _) in property_values(path, data).items()}
    values.update({k: float(v) for k, v in ((data.get("simulation") or {}).get("params") or {}).items()})
    return DemParams.from_mapping(values, str(path))


def _sizing(scenario: str, setup: dict, preset: str, params, source: str) -> dict:
    """A bench-top scenario's ``sizing`` of a run (the drum's takes the source, the others the
    parameters)."""
    from soilcal.dem.scenarios import get

    mod = get(scenario, source)
    return mod.sizing(setup, preset, source) if scenario == "drum" else mod.sizing(setup, preset, params)


def cohesion_factor(scenario: str, setup: dict, preset: str, params, source: str = "<setup>") -> tuple[float, str]:
    """The surface-energy factor a run of ``scenario`` with ``setup`` and ``preset`` applies
    (``cohesion_scale``, :mod:`soilcal.dem.scenarios.base`), and what it is taken against:
    the run's particles against the setup's ``paper_psd``, or a soil bin whose setup leaves
    it at None against the paper preset's bin of the scenario's named setup."""
    from soilcal.dem import cost
    from soilcal.dem.scenarios.base import paper_cohesion

    if scenario == "incline":
        return 1.0, "no particle-size scaling (one block or ball)"
    if scenario in cost.SOIL_BIN:
        factor = float(cost.soil_bin(scenario, setup, preset, source)[0]["cohesion_scale"])
        dist = None
    else:
        dist = _sizing(scenario, setup, preset, params, source)["dist"]
    if not setup.get("scale_cohesion", True):
        return 1.0, "scale_cohesion: false (the soil's surface energies as given)"
    if dist is not None:
        if not setup.get("paper_psd"):
            return 1.0, "no paper_psd to scale against"
        factor = paper_cohesion(setup, dist, source)
    if setup.get("paper_psd"):
        return float(factor), "Sauter radius of the run's particles over that of the setup's paper_psd"
    return float(factor), ("Sauter radius of the run's bin over that of the paper preset's bin of the scenario's "
                           "named setup (the setup's paper_psd is None)")


def _preset_value(scenario: str, key: str, setup: dict, preset: str, params, soil_path):
    """What a bench-top run takes for a setup value the named setup leaves to the preset
    (None), and how (:func:`soilcal.dem.scenarios.base.make_simulation`, the scenario's
    ``sizing``); (None, "") where this does not say."""
    from soilcal.dem import cost
    from soilcal.dem.scenarios.base import DEFAULT_ROLLING, PRESET_DEFAULTS, stiffness_scale_for

    if scenario not in cost.BENCHTOP:
        return None, ""
    d = PRESET_DEFAULTS[preset]
    if key == "rolling_model":
        return DEFAULT_ROLLING, "the engine's default rolling model"
    if key == "contact_conventions":
        return "edem", "EDEM's (JKR pull-off 1.5 pi gamma R*, rolling torque on the particle's own lever)"
    if key == "dt_fraction":
        return d["dt_fraction"], "fraction of the Rayleigh time step"
    if key == "stiffness_scale":
        g = params.soil_shear_modulus
        return round(stiffness_scale_for(params, preset), 6), (
            f"the preset's cap {d['g_max']:g} Pa over the soil's shear modulus {g:g} Pa (at most 1; a stage that "
            "varies the modulus changes it)" if d["g_max"] is not None else "the soil's own modulus")
    if key in ("n_particles", "radius") and scenario != "incline":
        try:
            sz = _sizing(scenario, setup, preset, params, str(soil_path))
        except Exception:  # noqa: BLE001 - documentation only
            return None, ""
        if key == "n_particles":
            return int(sz["n"]), "spheres of the run"
        dist = sz["dist"]
        return [round(float(dist.r_min), 9), round(float(dist.r_max), 9)], "smallest and largest sphere radius, m"
    return None, ""


def _setup_rows(add, where: str, scenario: str, setup_name: str, overrides: dict, preset: str,
                params, soil_path, taken: dict | None = None) -> None:
    """Rows of one simulated setup: every value the run takes, from the soil's ``set`` or the
    named setup; a soil bin's preset values; the cohesion factor.  ``taken``: override key ->
    the soil field it comes from, for a value the entry takes from elsewhere in the soil."""
    from soilcal.dem import cost
    from soilcal.dem.scenarios import get
    from soilcal.dem.scenarios.base import merge_setup

    mod = get(scenario, str(soil_path))
    named = mod.setups()[setup_name]
    setup = merge_setup(mod.setups(), setup_name, overrides, str(soil_path))
    effective = setup
    if scenario in cost.SOIL_BIN:
        try:
            effective = cost.soil_bin(scenario, setup, preset, str(soil_path))[0]
        except InputError:  # a setup this preset cannot run: its rows say the setup's values
            pass
    for key in sorted(k for k in set(setup) | set(effective) if k not in ("name", "overrides", "cohesion_scale")):
        if key not in setup:
            add(f"{where}.setup.{key}", effective[key], "preset",
                f"the {preset} preset's value (not a value of the named setup {setup_name!r})")
        elif key in (taken or {}):
            add(f"{where}.setup.{key}", overrides[key], "soil", f"{taken[key]} (the soil's own; {where} leaves "
                f"set.{key} out), in place of the named setup's {_text(named.get(key))}")
        elif key in overrides:
            add(f"{where}.setup.{key}", overrides[key], "soil", f"{where}.set.{key}, in place of the named "
                f"setup's {_text(named.get(key))}")
        elif effective.get(key) != setup[key]:
            add(f"{where}.setup.{key}", effective[key], "preset",
                f"the {preset} preset's value (the named setup {setup_name!r} has {_text(setup[key])})")
        elif key == "paper_psd" and setup[key] is None and scenario in cost.SOIL_BIN:
            add(f"{where}.setup.{key}", None, "named setup",
                f"None in {setup_name!r}: the surface energy is for the particles of the paper preset's bin of "
                f"{setup_name!r} (a shipped soil's; set.paper_psd gives the soil's own)")
        elif setup[key] is None:
            value, what = _preset_value(scenario, key, setup, preset, params, soil_path)
            add(f"{where}.setup.{key}", value, "preset",
                f"left to the {preset} preset by the named setup {setup_name!r}" + (f": {what}" if what else ""))
        else:
            add(f"{where}.setup.{key}", setup[key], "named setup", f"{setup_name!r} (a shipped soil's apparatus)")
    try:
        factor, how = cohesion_factor(scenario, setup, preset, params, str(soil_path))
        add(f"{where}.cohesion_scale[{preset}]", round(factor, 6), "computed",
            f"surface energies times this factor: {how}")
    except Exception as exc:  # noqa: BLE001 - the file documents the runs, it never stops them
        add(f"{where}.cohesion_scale[{preset}]", None, "computed", f"not computed here ({exc}); see the run's log")


def simulation_setup(soil, design_override: str | None = None) -> "pd.DataFrame":
    """Everything a soil's DEM runs are set up with, and where each value comes from:
    ``results/<soil>/dem/simulation.csv`` (:data:`SETUP_COLUMNS`).

    ``origin``: ``soil`` (the soil file gives it; ``note`` names the field), ``default`` (the
    soil leaves it out and the documented default holds: the schema's for the block's options,
    :data:`GENERIC` for the DEM parameters), ``named setup`` (a value of the named scenario
    setup, the apparatus of a shipped soil, that the soil's ``set`` does not replace),
    ``preset`` (the preset's discretisation), ``workflow config`` (``--config design=...``), ``workflow`` (what the workflow does not run)
    or ``computed`` (the surface-energy factor of the particle-size rule).  Every other DEM
    parameter value of a run is in the ``p:<name>`` columns of its ``runs/*.csv``.
    ``soil``: a loaded :class:`soilcal.config.load.Soil` (its ``defaulted`` fields count as
    defaults); ``design_override``: the workflow config's ``design``, where given."""
    import pandas as pd

    from soilcal.chain.adaptive import adaptive_stage_ids
    from soilcal.chain.derive import SCREENING_DEFAULTS, dem_stage_ids, design_mode, simulated_stage_ids
    from soilcal.chain.verify import VERIFY_DEFAULTS
    from soilcal.config.measurements import DEFAULT_PRESET, DEFAULT_REPLICATES, entry_set_of
    from soilcal.dem.scenarios.base import DemParams
    from soilcal.doe.adaptive import DEFAULTS as ADAPTIVE_DEFAULTS

    data = soil.data
    sim = data.get("simulation") or {}
    rows = []

    def add(item, value, origin, note=""):
        rows.append({"item": item, "value": "" if value is None else _text(value), "origin": origin, "note": note})

    defaulted = set(getattr(soil, "defaulted", ()) or ())
    add("seed", data.get("seed", 0), "default" if "seed" in defaulted or "seed" not in data else "soil",
        "master seed of every random choice (default 0)" if "seed" in defaulted or "seed" not in data else "seed")
    for key, (default, what) in BLOCK_DEFAULTS.items():
        if key == "design" and design_override is not None:
            add(f"simulation.{key}", design_override, "workflow config", f"--config design={design_override}, "
                "for every soil")
        elif key in sim:
            add(f"simulation.{key}", sim[key], "soil", f"simulation.{key} ({what})")
        else:
            add(f"simulation.{key}", default, "default", what)
    design = design_mode(data)
    if "stages" in sim:
        add("simulation.stages", dem_stage_ids(data), "soil", "simulation.stages")
    else:
        add("simulation.stages", dem_stage_ids(data), "default", "every stage")
    if design == "adaptive":
        add("simulation.adaptive.stages", adaptive_stage_ids(data), "computed", "the optimised stages the design runs")
    # the screening and path options act where the recipe lays a steepest-ascent path
    path_run = design != "adaptive" and any(s["kind"] == "steepest_ascent" for s in data["stages"]
                                            if s["id"] in dem_stage_ids(data))
    scr = sim.get("screening") or {} if path_run else {}
    for key, default in SCREENING_DEFAULTS.items() if path_run else ():
        add(f"simulation.screening.{key}", scr.get(key, default), "soil" if key in scr else "default",
            f"simulation.screening.{key}" if key in scr else "screening of the path's factors")
    if path_run:
        add("simulation.screening.max_factors", scr.get("max_factors", "the stage's factor count"),
            "soil" if "max_factors" in scr else "default", "simulation.screening.max_factors"
            if "max_factors" in scr else "as many as the path stage's factors")
    path = sim.get("path") or {}
    for key, default in (("rule", "range"), ("steps", "the path stage's printed levels, else 6"),
                         ("choose", "fitted")) if path_run else ():
        add(f"simulation.path.{key}", path.get(key, default), "soil" if key in path else "default",
            f"simulation.path.{key}" if key in path else "steepest-ascent path")
    ver = sim.get("verification") or {}
    for key, default in list(VERIFY_DEFAULTS.items()) + [("refine", True)] if design != "adaptive" else ():
        add(f"simulation.verification.{key}", ver.get(key, default), "soil" if key in ver else "default",
            f"simulation.verification.{key}" if key in ver else "verification at the calibrated set")
    if design == "adaptive":
        ad = sim.get("adaptive") or {}
        for key, default in list(ADAPTIVE_DEFAULTS.items()) + [("share_runs", True), ("ranges", "screening")]:
            if key == "n_start" and key not in ad:
                default = "2 d + 1 for d free factors"
            add(f"simulation.adaptive.{key}", ad.get(key, default), "soil" if key in ad else "default",
                f"simulation.adaptive.{key}" if key in ad else "adaptive design")
        if "tolerances" in ad:
            add("simulation.adaptive.tolerances", ad["tolerances"], "soil", "simulation.adaptive.tolerances")
    res = sim.get("resources") or {}
    for key in ("mem_mb", "runtime"):
        add(f"simulation.resources.{key}", res.get(key, "from each job's size (soilcal.dem.cost)"),
            "soil" if key in res else "default", f"simulation.resources.{key}" if key in res
            else "declared to the scheduler per DEM job")

    # DEM parameters: the soil's own, and the generic defaults the runs of a stage take
    from soilcal.dem.scenarios.base import dem_field, property_values

    stages = simulated_stage_ids(data) if sim else []

    def own_fields(sid):
        st = next(s for s in data["stages"] if s["id"] == sid)
        used = [(p, f"stages.{sid}.fixed.{p}") for p in st.get("fixed") or {}]
        used += [(f.get("parameter"), f"stages.{sid}.factors.{k}") for k, f in (st.get("factors") or {}).items()]
        return {dem_field(soil.path, data, p, w)[0] for p, w in used}

    stage_set = {sid: own_fields(sid) for sid in stages}

    def over(name):
        hit = [sid for sid in stages if name in stage_set[sid]]
        return f"; replaced by the fixed value or factor of stage(s) {', '.join(hit)}" if hit else ""

    for name, (x, prop) in property_values(soil.path, data).items():
        later = name in (sim.get("params") or {})
        add(f"dem.{name}", x, "soil", f"properties.{prop}, in SI"
            + (f"; replaced by simulation.params.{name}" if later else "") + over(name))
    for name, v in (sim.get("params") or {}).items():
        add(f"dem.{name}", v, "soil", f"simulation.params.{name} (SI)" + over(name))
    defaults = DemParams()
    for name, meaning in GENERIC.items():
        left = [sid for sid in stages if name not in given(data, sid, soil_path=soil.path)]
        if left:
            add(f"dem.{name}", getattr(defaults, name), "default",
                f"generic: {meaning}; in the runs of stage(s) {', '.join(left)}")
    params = base_params(soil.data, soil.path)

    # the scenario setup of every simulated response, at the soil's preset and the paper
    # preset where the verification also runs it
    preset = sim.get("preset", "quick")
    paper = set(ver.get("paper") or [])
    for rid, entry in (sim.get("responses") or {}).items():
        where = f"simulation.responses.{rid}"
        add(f"{where}.scenario", entry["scenario"], "soil", f"{where}.scenario")
        add(f"{where}.setup", entry["setup"], "soil", f"{where}.setup (named setup)")
        add(f"{where}.measure", entry["measure"], "soil", f"{where}.measure")
        if "replicates" in entry:
            add(f"{where}.replicates", entry["replicates"], "soil", f"{where}.replicates (seeds per design point "
                "of this response, in place of simulation.replicates)")
        for pr in [preset] + (["paper"] if rid in paper and preset != "paper" else []):
            _setup_rows(add, where if pr == preset else f"{where}[{pr}]", entry["scenario"], entry["setup"],
                        dict(entry.get("set") or {}), pr, params, soil.path)

    # the measured tool tests (the recipe's and the printed design's; the adaptive design runs none)
    if design == "adaptive" and data.get("measurements"):
        add("measurements", "not run", "workflow", "design: adaptive runs no tool tests and no measured-data "
            "loop (soilcal loop run runs them from a parameter set)")
    for mid, entry in (data.get("measurements") or {}).items() if design != "adaptive" else ():
        where = f"measurements.{mid}"
        add(f"{where}.scenario", entry["scenario"], "soil", f"{where}.scenario")
        add(f"{where}.setup", entry["setup"], "soil", f"{where}.setup (named setup; a setup covariate may choose "
            "another per row)")
        mpreset = entry.get("preset", DEFAULT_PRESET)
        varied = sorted(c for c, cv in (entry.get("covariates") or {}).items()
                        if "setup" in cv or "set" in cv)
        if varied:
            add(f"{where}.covariates", varied, "soil", "table columns that choose the setup or set a setup "
                "value per row, over the values below")
        mset, taken = entry_set_of(soil.path, data, mid, entry)
        _setup_rows(add, where, entry["scenario"], entry["setup"], mset, mpreset, params, soil.path, taken)
        add(f"{where}.replicates", entry.get("replicates", DEFAULT_REPLICATES),
            "soil" if "replicates" in entry else "default", f"{where}.replicates" if "replicates" in entry
            else "seeds per measured condition")
        add(f"{where}.preset", entry.get("preset", DEFAULT_PRESET), "soil" if "preset" in entry else "default",
            f"{where}.preset" if "preset" in entry else "scenario preset of the tool tests")
    return pd.DataFrame(rows, columns=SETUP_COLUMNS)


#: text fields that document a soil and change no value of simulation.csv
_DOC_KEYS = ("note", "notes", "source", "title")


def setup_inputs(data: dict) -> dict:
    """The part of a soil file's content that :func:`simulation_setup` reads: ``name``,
    ``seed``, ``simulation``, ``stages``, ``parameters``, ``measurements``, the printed
    properties the runs take (:data:`soilcal.dem.scenarios.base.PROPERTY_FIELDS`) and, for
    ``design: adaptive`` (whose stages are those with a case to aim at), whether each target has
    a value or a photo group; the text that documents them (``note``, ``source``, ``title``) and
    ``simulation.search_ranges`` (which simulation.csv does not read) are left out.  The workflow's rule passes this as its params, so an edit elsewhere in the soil
    file (its citation, notes, errata, a target's value) does not rerun it."""
    from soilcal.chain.derive import design_mode
    from soilcal.chain.plan import without_search_ranges
    from soilcal.dem.scenarios.base import PROPERTY_FIELDS

    def bare(v):
        if isinstance(v, dict):
            return {k: bare(x) for k, x in v.items() if not (k in _DOC_KEYS and isinstance(x, str))}
        if isinstance(v, list):
            return [bare(x) for x in v]
        return v

    # the declared search ranges: read by the second round and the adaptive design only
    runs_read = without_search_ranges(data)
    out = {k: bare(runs_read[k]) for k in ("name", "seed", "simulation", "stages", "parameters", "measurements")
           if k in runs_read}
    props = data.get("properties") or {}
    out["properties"] = {p: bare(props[p]) for p in PROPERTY_FIELDS if p in props}
    if data.get("simulation") and design_mode(data) == "adaptive":
        out["targets"] = {tid: {k: t[k] for k in ("value", "image") if k in t}
                          for tid, t in (data.get("targets") or {}).items() if isinstance(t, dict)}
    return out


def write_simulation_setup(soil, out, design_override: str | None = None) -> "pd.DataFrame":
    """:func:`simulation_setup` written to ``out`` (``results/<soil>/dem/simulation.csv``)."""
    from soilcal.chain.files import write_csv

    df = simulation_setup(soil, design_override)
    write_csv(df, out)
    return df
