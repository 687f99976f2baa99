"""The stage a response source actually runs: its factors, levels and fixed values.

A soil's config describes each stage as the paper ran it.  The published source replays
exactly that stage.  The DEM source runs the papers' *recipe* on its own results
(``simulation.design: recipe``, the default), so a stage that follows another one is derived
from the DEM results of the earlier stage, as the papers derived it from theirs:

* **steepest ascent after a screening** (``from_stage`` is a Plackett-Burman stage): the
  factors whose screening effect is significant (p < ``simulation.screening.alpha``, 0.05 as
  the papers: vineyard soil "the factors with P-values less than 0.05 in Tables 4 and 5 were
  selected"; at least ``min_factors`` = 3, what a Box-Behnken design needs, at most
  ``max_factors``, by default as many as the config's path stage lists) go on the path;
  its direction descends the summed squared relative error of the first-order models to the
  targets (:func:`soilcal.doe.steepest.path_direction`); the path walks each factor's
  screening range (``simulation.path.rule: range``, the papers' practice) or steps in the
  ratio of the effects (``proportional``, Montgomery 11.2), or, aimed at several targets
  together (``target``), steps Montgomery's way along the line from the centre through the
  point where the first-order models meet all of them
  (:func:`soilcal.doe.steepest.path_target`): the papers' rule uses only the signs of the
  summed pull, which walks every factor the same way even where one targeted response needs
  to rise and another to stay (vineyard soil: static and dynamic angles).  The default
  (``auto``) is ``range`` for one targeted response and ``target`` for several; the other
  screened factors are
  held at their intermediate levels (the centre of their screening range: "the parameters
  with insignificant influence were taken as intermediate level values", cinnamon soil
  Sec. 3.3.2), or at the value the path stage's own ``fixed`` gives them (the vineyard soil's
  paper held its shear modulus at 10 MPa, the low end of its screening range); a fixed value
  of a factor the DEM screening selects is not used and is listed in
  ``derivation.fixed_not_used`` (:func:`apply_own_fixed`).  Every fixed value a derived stage
  runs is recorded with its origin in ``derivation.fixed``.
* **Box-Behnken after a steepest ascent**: the path step whose DEM responses are closest to
  the targets is the centre, its neighbours the low and high levels ("the levels of no. 2,
  no. 3 and no. 4 were selected as low, medium and high", cinnamon soil;
  :func:`soilcal.doe.steepest.bbd_levels`), shifted inside the parameters' physical ranges.
  "Closest" is judged on the trend fitted through all the path's runs
  (``simulation.path.choose: fitted``, the default; :func:`soilcal.doe.steepest.path_trend`):
  one DEM run per step carries its seed's scatter, and the papers' rule (``closest``: each
  step's own run) lets one lucky seed pick the centre (README, "Choosing the Box-Behnken
  centre on a noisy path").  The path stage records
  the rule (``path_choice``); a path the DEM source runs on printed levels keeps the papers'
  rule, so its files stay those of the published replay.
* **parameters fixed at an earlier stage's optimum** (``fixed_from``, black soil stage 2):
  the DEM source fixes them at ITS calibrated set of that stage (the ``calibrated`` row of
  ``optimum.csv``, or of ``final.csv``, the better verified round, where the soil runs the
  second verification round, :func:`soilcal.chain.refine.final_frame`), not at the paper's.

``simulation.design: printed`` runs every stage on the paper's own printed levels instead
(the same for a stage that follows one the DEM source does not run, ``simulation.stages``).
The derivation is recorded in the stage's ``derivation`` entry (``stage.json``).

Targets of a path: a response's own target (a target id equal to the response id) or, when
the soil's targets are per layer or moisture content, the mean of the targets its
optimisation cases aim that response at (``path_targets``).
"""

from __future__ import annotations

import copy
from functools import partial

import numpy as np
import pandas as pd

from soilcal.doe.designs import BBD_MIN_FACTORS
from soilcal.errors import InputError

#: a Box-Behnken level is kept this fraction of the physical range inside an open end of it
#: (a restitution above 0), where a level may not lie (:func:`_bounds_in_config_units`)
OPEN_END_MARGIN = 1e-9
DEFAULT_STEPS = 6
#: the screening's defaults: alpha as the papers, min_factors what a Box-Behnken design needs
SCREENING_DEFAULTS = {"alpha": 0.05, "min_factors": BBD_MIN_FACTORS}
#: (earlier stage's kind, this stage's kind) of the stages the DEM source derives (module docstring)
DERIVED_KINDS = {("plackett_burman", "steepest_ascent"), ("steepest_ascent", "box_behnken")}
DERIVED_EXPECTED = ("a steepest ascent after a Plackett-Burman screening, or a Box-Behnken design after a "
                    "steepest ascent")


def sim_block(soil_data: dict) -> dict:
    return soil_data.get("simulation") or {}


def dem_stage_ids(soil_data: dict) -> list[str]:
    """Stage ids the DEM source runs (``simulation.stages``, default every stage)."""
    ids = [s["id"] for s in soil_data["stages"]]
    chosen = sim_block(soil_data).get("stages")
    return ids if not chosen else [s for s in ids if s in chosen]


def design_mode(soil_data: dict) -> str:
    return sim_block(soil_data).get("design", "recipe")


def simulated_stage_ids(soil_data: dict) -> list[str]:
    """Stage ids whose runs the DEM source makes, the ones the start-up checks cover:
    :func:`dem_stage_ids`, or with ``design: adaptive`` the stages the adaptive design runs
    (:func:`soilcal.chain.adaptive.adaptive_stage_ids`; the recipe's screening and path are
    then not run, and need no levels or parameters of their own)."""
    if design_mode(soil_data) == "adaptive":
        from soilcal.chain.adaptive import adaptive_stage_ids

        return adaptive_stage_ids(soil_data)
    return dem_stage_ids(soil_data)


def runs_own_levels(soil_data: dict, stage_id: str) -> bool:
    """Whether the DEM source runs the levels the soil config gives the stage (a
    Plackett-Burman or Box-Behnken design generated from ``low`` / ``high``, a path's
    ``levels``): a stage it runs under ``design: recipe`` or ``printed`` (:func:`dem_stage_ids`)
    that is not derived from an earlier DEM stage (:func:`dependencies`) and not, with
    ``design: printed``, run on its printed table's rows.  ``design: adaptive`` runs no design
    of the config's levels (its optimised stages range over ``low`` .. ``high``)."""
    if design_mode(soil_data) == "adaptive" or stage_id not in dem_stage_ids(soil_data):
        return False
    if "from" in dependencies(soil_data, stage_id):
        return False
    return not (design_mode(soil_data) == "printed" and _stage(soil_data, stage_id).get("table"))


def decodes_low_high(soil_data: dict, stage_id: str) -> bool:
    """Whether the DEM runs of a two- or three-level stage are decoded from its ``low`` and
    ``high`` (coded 0 at their midpoint): its generated design (:func:`runs_own_levels`), or
    with ``design: printed`` a table printed in coded levels.  A table printed in actual
    units is run as printed."""
    if runs_own_levels(soil_data, stage_id):
        return True
    st = _stage(soil_data, stage_id)
    return (design_mode(soil_data) == "printed" and stage_id in dem_stage_ids(soil_data)
            and "from" not in dependencies(soil_data, stage_id) and bool(st.get("table"))
            and st.get("table_coding", "coded") == "coded")


def _stage(soil_data: dict, stage_id: str) -> dict:
    for s in soil_data["stages"]:
        if s["id"] == stage_id:
            return s
    raise InputError(soil_data.get("name", "<soil>"), "stages", f"a stage with id {stage_id!r}", stage_id)


def dependencies(soil_data: dict, stage_id: str) -> dict[str, str]:
    """Earlier DEM stages a DEM stage is derived from: ``{"from": id, "fixed_from": id}``
    (only the keys that apply)."""
    st = _stage(soil_data, stage_id)
    run = dem_stage_ids(soil_data)
    out = {}
    if design_mode(soil_data) == "recipe" and st.get("from_stage") in run:
        out["from"] = st["from_stage"]
    ff = (st.get("fixed_from") or {}).get("stage")
    if ff in run:
        out["fixed_from"] = ff
    return out


def optimised_dem_stage_ids(soil_data: dict) -> list[str]:
    """The optimised stages the DEM source runs: those of :func:`dem_stage_ids` with an
    ``optimise`` block, the stages the workflow verifies and the second calibration round
    refines."""
    return [sid for sid in dem_stage_ids(soil_data) if _stage(soil_data, sid).get("optimise")]


def factor_stage(soil_data: dict, stage_id: str) -> str:
    """The stage whose config factors are those the DEM runs of stage ``stage_id`` may vary:
    the stage itself, or, for a stage derived from an earlier DEM stage (:func:`dependencies`,
    ``design: recipe``), that of the stage it is derived from, followed back: a Box-Behnken
    design derived from the DEM path varies the path's factors (:func:`bbd_from_path`), which
    are the path's own where the path runs its own levels, and the screening's factors it selects
    where the path is derived from the DEM screening (:func:`path_from_screening`)."""
    sid = stage_id
    while "from" in (deps := dependencies(soil_data, sid)):
        sid = deps["from"]  # an earlier stage (soilcal.config.load): the chain ends
    return sid


def published_stage(soil_data: dict, stage_id: str) -> dict:
    """The stage as the paper ran it (the published source)."""
    st = copy.deepcopy(_stage(soil_data, stage_id))
    st["source"] = "published"
    st["derivation"] = {"kind": "config", "text": "as printed in the soil config"}
    return st


def apply_own_fixed(st: dict, config_stage: dict, fixed: dict, origin: dict, varied: set,
                    soil_data: dict) -> None:
    """Set ``st["fixed"]`` to ``fixed`` with the stage's own ``fixed`` values over it, and record
    where each value comes from (``st["derivation"]["fixed"]``: ``{parameter: {"value",
    "origin"}}``, ``origin`` filled in beforehand for the values ``fixed`` brings in).

    A value the soil config fixes for the stage holds in its runs, over the one an earlier stage
    fixes and over the intermediate level at which the recipe would hold a screened factor the
    screening did not select (the value it replaces is named in its origin): the config says so
    explicitly, as the papers fixed such factors (vineyard soil: the shear modulus at 10 MPa,
    the low end of its 10-100 MPa screening range).  Only a parameter the stage's derived design
    varies (``varied``: a path factor the DEM screening selected, a Box-Behnken factor) cannot
    hold a fixed value; its config value is listed in ``derivation.fixed_not_used`` with why,
    never dropped without a word.

    Parameters are told apart by the DEM parameter they set
    (:func:`soilcal.config.parameters.dem_key`, as the loader tells them apart): a stage's own
    value of ``soil_G_pa`` (Pa) replaces an earlier ``soil_shear_modulus`` (MPa) and is not used
    where the design varies ``soil_shear_modulus``, so each DEM parameter is set once and the
    record names the value the runs take.  An own value of a factor of the screening the stage
    descends from (:func:`soilcal.chain.adaptive.screening_of`) that lies outside that factor's
    ``low`` .. ``high`` runs as given; its origin says so (the screening did not judge the factor
    there) and ``derivation.fixed[<parameter>].warning`` repeats it for the design job's log."""
    from soilcal.config.parameters import dem_key

    params = soil_data.get("parameters") or {}
    fixed, origin = dict(fixed), dict(origin)
    varied_by = {dem_key(params, p): p for p in varied}
    screened = _screened_factors(soil_data, config_stage["id"])
    not_used, warnings = {}, {}
    where = f"stages.{config_stage['id']}.fixed"
    for k, v in (config_stage.get("fixed") or {}).items():
        key = dem_key(params, k)
        if key in varied_by:
            vp = varied_by[key]
            sets = f" (both set the DEM parameter {key[1]})" if vp != k else ""
            not_used[k] = {"value": v, "why": (f"{where}.{k} is not used: the derived design of stage "
                                               f"{config_stage['id']} varies {vp}{sets} (a factor the DEM results chose)")}
            continue
        notes = []
        for p in [p for p in fixed if dem_key(params, p) == key]:
            prev, prev_origin = fixed.pop(p), origin.pop(p, "an earlier value")
            if p != k:
                notes.append(f"over {p} = {float(prev):g} {params.get(p, {}).get('unit', '')}, "
                             f"{prev_origin}; both set the DEM parameter {key[1]}")
            elif abs(float(v) - float(prev)) > 1e-12 * max(1.0, abs(float(prev))):
                notes.append(f"over {float(prev):g}, {prev_origin}")
        fixed[k] = v
        origin[k] = f"{where}.{k} (soil config)" + "".join(f" ({n})" for n in notes)
        if key in screened:
            warn = _outside_screening(soil_data, k, v, *screened[key])
            if warn:
                warnings[k] = f"{where}.{k} = {float(v):g} {warn}"
                origin[k] += f"; {warn}"
    st["fixed"] = fixed
    st.setdefault("derivation", {})
    rec = {}
    for k in fixed:
        rec[k] = {"value": fixed[k], "origin": origin.get(k, f"{where}.{k} (soil config)")}
        if k in warnings:
            rec[k]["warning"] = warnings[k]
    st["derivation"]["fixed"] = rec
    if not_used:
        st["derivation"]["fixed_not_used"] = not_used


def _screened_factors(soil_data: dict, stage_id: str) -> dict:
    """``{dem_key: (screening id, symbol, factor)}``, the first factor setting each DEM parameter
    in the Plackett-Burman screening a stage
    descends from through its ``from_stage`` links (:func:`soilcal.chain.adaptive.screening_of`,
    the same in every design mode), keyed by the DEM parameter each factor sets
    (:func:`soilcal.config.parameters.dem_key`)."""
    from soilcal.chain.adaptive import screening_of
    from soilcal.config.parameters import dem_key

    scr = screening_of(soil_data, stage_id)
    if scr is None:
        return {}
    params = soil_data.get("parameters") or {}
    found = {}
    for sym, f in scr["factors"].items():
        if f.get("low") is not None and f.get("high") is not None:
            # the first factor of a parameter, as :func:`soilcal.chain.adaptive.screening_range`
            # takes it
            found.setdefault(dem_key(params, f["parameter"]), (scr["id"], sym, f))
    return found


#: how far (relative to the screening range) a fixed value may lie past a range end and still
#: count as inside it: a number written twice, or converted between units
SCREENING_RANGE_RTOL = 1e-9


def _outside_screening(soil_data: dict, pname: str, value, scr_id: str, sym: str, f: dict) -> str:
    """Why ``value`` of ``pname`` lies outside the range ``low`` .. ``high`` of screening factor
    ``sym`` (stage ``scr_id``) on the DEM parameter both set, in ``pname``'s unit; empty where
    it lies inside."""
    from soilcal.dem.scenarios.base import unit_scale

    params = soil_data.get("parameters") or {}
    src = soil_data.get("name", "<soil>")
    own = unit_scale(src, params.get(pname) or {}, f"parameters.{pname}")
    theirs = unit_scale(src, params.get(f["parameter"]) or {}, f"parameters.{f['parameter']}")
    lo, hi = float(f["low"]) * theirs / own, float(f["high"]) * theirs / own
    tol = SCREENING_RANGE_RTOL * (hi - lo)
    if lo - tol <= float(value) <= hi + tol:
        return ""
    unit = (params.get(pname) or {}).get("unit", "")
    factor = f"factor {sym}" + (f" ({f['parameter']})" if f["parameter"] != pname else "")
    return (f"lies outside the screening range {lo:g}..{hi:g} {unit} of {factor} of stage {scr_id}: "
            "the screening did not judge the parameter there (its finding that the factor is not "
            "significant holds over that range only); the value runs as given")


def _dem_base(stage: dict) -> dict:
    """A config stage as the DEM source writes it: responses by id, no printed analysis."""
    st = copy.deepcopy(stage)
    st.pop("printed", None)
    st["source"] = "dem"
    st["table"] = "responses.csv"
    st["table_coding"] = "actual"
    st["responses"] = [{k: v for k, v in r.items() if k != "column"} for r in st["responses"]]
    return st


def response_targets(soil_data: dict, response_ids, targets: dict) -> dict[str, dict]:
    """Target of each response for a path: its own target id, else the mean of the targets
    the soil's optimisation cases give it (``{rid: {"value", "from"}}``; responses without
    one are left out)."""
    out = {}
    for rid in response_ids:
        t = targets.get(rid, {})
        if t.get("value") is not None and np.isfinite(float(t["value"])):
            out[rid] = {"value": float(t["value"]), "from": [rid]}
            continue
        ids, vals = [], []
        for st in soil_data["stages"]:
            for case in (st.get("optimise") or {}).get("cases", []):
                g = case["goals"].get(rid)
                if not g or g.get("goal") != "target":
                    continue
                if "target" in g:
                    v = targets.get(g["target"], {}).get("value")
                    name = g["target"]
                else:
                    v, name = g.get("value"), f"{case['id']} (value)"
                if v is not None and np.isfinite(float(v)) and name not in ids:
                    ids.append(name)
                    vals.append(float(v))
        if vals:
            out[rid] = {"value": float(np.mean(vals)), "from": ids}
    return out


def _g12(v) -> float:
    """A level to 12 significant digits (0.08, not 0.08000000000000002 from a path step)."""
    return float(f"{float(v):.12g}")


def _bounds_in_config_units(soil_data: dict, pname: str) -> tuple[float, float]:
    """The range of the DEM parameter a config parameter sets (the range its values are
    checked against, :class:`soilcal.dem.scenarios.base.DemParams`: its physical range and, for
    a soil's material parameter, its plausibility bound, in SI: a soil-soil surface energy in
    [0, 100] J/m^2) in the unit its levels are written in
    (``parameters.<pname>.unit``, e.g. mJ/m^2: up to 1e5 mJ/m^2), an open end moved inside by
    :data:`OPEN_END_MARGIN` of the range.  A parameter that sets no DEM parameter, or a unit
    without a factor to SI, raises InputError naming ``parameters.<pname>``
    (:func:`soilcal.dem.scenarios.base.dem_field`)."""
    from soilcal.dem.scenarios.base import _RANGES, SOIL_RANGES, _kind, dem_field

    name, scale = dem_field(soil_data.get("name", "<soil>"), soil_data, pname, f"parameters.{pname}")
    ends = []
    for rng in (_RANGES[_kind(name)], SOIL_RANGES.get(name)):
        if rng is not None:
            lo, hi, lo_in, hi_in, _ = rng
            margin = OPEN_END_MARGIN * (hi - lo)
            ends.append(((lo if lo_in else lo + margin), (hi if hi_in else hi - margin)))
    return max(e[0] for e in ends) / scale, min(e[1] for e in ends) / scale


def _centre(f: dict) -> float:
    if f.get("centre") is not None:
        return float(f["centre"])
    return (float(f["low"]) + float(f["high"])) / 2.0


def _symbol_for(pname: str, pb_sym: str, config_stage: dict, taken: set) -> str:
    """The config path stage's symbol of a parameter (the paper's symbol) when it has one,
    else the screening symbol; never one already used for another parameter."""
    for sym, f in config_stage["factors"].items():
        if f["parameter"] == pname and sym not in taken:
            return sym
    cand = pb_sym
    k = 2
    while cand in taken or cand in config_stage["factors"]:
        cand = f"{pb_sym}{k}"
        k += 1
    return cand


def _keep_printed_optimum(st: dict, config_stage: dict) -> None:
    """Keep a case's printed optimum only where it is expressed on the same parameters."""
    opt = st.get("optimise")
    if not opt:
        return
    par_of = {s: f["parameter"] for s, f in config_stage["factors"].items()}
    ours = {f["parameter"]: s for s, f in st["factors"].items()}
    for case in opt.get("cases", []):
        po = case.get("printed_optimum")
        if not po:
            continue
        mapped = {ours[par_of[s]]: v for s, v in po.items() if s in par_of and par_of[s] in ours}
        if set(mapped) == set(st["factors"]):
            case["printed_optimum"] = mapped
        else:
            case.pop("printed_optimum")


def path_from_screening(soil_data: dict, stage_id: str, screening_stage: dict, effects: pd.DataFrame,
                        responses: pd.DataFrame, targets: dict) -> dict:
    """A steepest-ascent stage laid out from the DEM screening (module docstring)."""
    from soilcal.doe.steepest import derive_path, path_direction, path_target, select_factors

    config_stage = _stage(soil_data, stage_id)
    sim = sim_block(soil_data)
    scr = {**SCREENING_DEFAULTS, **(sim.get("screening") or {})}
    if scr.get("max_factors") is None:
        scr["max_factors"] = max(len(config_stage["factors"]), scr["min_factors"])
    path_cfg = sim.get("path") or {}
    n_levels = {len(f.get("levels") or []) for f in config_stage["factors"].values()} - {0}
    n_steps = int(path_cfg.get("steps") or (n_levels.pop() if len(n_levels) == 1 else DEFAULT_STEPS))
    rule = path_cfg.get("rule", "auto")

    rids = [r["id"] for r in config_stage["responses"]]
    ptargets = response_targets(soil_data, rids, targets)
    if not ptargets:
        raise InputError(soil_data.get("name"), f"stages.{stage_id}.responses",
                         "a target for at least one response of the path (a target id equal to "
                         "the response id, or optimisation cases aiming at it)", rids)
    eff = effects[effects["response"].isin(list(ptargets))]
    sel = select_factors(eff, alpha=scr["alpha"], min_factors=scr["min_factors"],
                         max_factors=scr["max_factors"])
    chosen = [t for t in sel.loc[sel["selected"], "term"]]
    coefs = {r: {t: float(b) for t, b in zip(g["term"], g["coefficient"]) if t in chosen}
             for r, g in eff.groupby("response", sort=False)}
    sf = screening_stage["factors"]
    # where the path starts: the screening's centre runs where it has them (the two-level runs'
    # mean misses the centre where the response curves), else that mean; plus the first-order
    # effect of every screened factor off the path held away from its centre (the path stage's
    # own fixed value, e.g. the vineyard soil's shear modulus at the low end of its range)
    from soilcal.chain.stage import screening_centre

    centre = screening_centre(screening_stage, responses)
    held = _held_coded(config_stage, sf, chosen)
    intercepts, start = {}, {}
    for r in coefs:
        c = centre.get(r)
        b0 = c["mean"] if c else float(responses[r].mean())  # no centre value: the two-level runs
        shift = sum(float(b) * held[t] for t, b in zip(eff.loc[eff["response"] == r, "term"],
                                                        eff.loc[eff["response"] == r, "coefficient"]) if t in held)
        intercepts[r] = b0 + shift
        start[r] = {"from": "centre runs" if c else "two-level runs' mean", "value": _g12(b0),
                    "held_factors_shift": _g12(shift), "intercept": _g12(b0 + shift)}
    tvals = {r: ptargets[r]["value"] for r in coefs}
    direction = path_direction(coefs, intercepts, tvals)
    if rule == "auto":  # one target: the papers' rule; several: aimed at all of them together
        rule = "target" if len(tvals) > 1 else "range"
    low = {t: float(sf[t]["low"]) for t in chosen}
    high = {t: float(sf[t]["high"]) for t in chosen}
    if rule == "target":
        path = derive_path(path_target(coefs, intercepts, tvals), low, high, n_steps, rule=rule)
    else:
        path = derive_path(direction, low, high, n_steps, rule=rule)

    st = _dem_base(config_stage)
    st.pop("chosen_step", None)  # the paper's choice on the paper's path
    st["path_choice"] = path_cfg.get("choose", "fitted")
    taken: set = set()
    factors = {}
    for t in chosen:
        pname = sf[t]["parameter"]
        sym = _symbol_for(pname, t, config_stage, taken)
        taken.add(sym)
        factors[sym] = {"parameter": pname, "levels": [_g12(v) for v in path[t]], "screening_symbol": t}
    st["factors"] = factors
    # the screening's fixed values carry on, the screened factors off the path at the centre of
    # their range; the stage's own fixed values hold over both (apply_own_fixed)
    fixed = dict(screening_stage.get("fixed") or {})
    origin = {k: _upstream_origin(screening_stage, k, "the screening's fixed value") for k in fixed}
    for t, f in sf.items():
        if t not in chosen:
            fixed[f["parameter"]] = _g12(_centre(f))
            origin[f["parameter"]] = (f"centre of the range {f['low']:g}-{f['high']:g} of screening factor {t} "
                                      f"(stage {screening_stage['id']}: not significant, held at its intermediate level)")
    st["path_targets"] = ptargets
    st["derivation"] = {
        "kind": "screening",
        "from_stage": screening_stage["id"],
        "text": (f"path over {', '.join(chosen)} of the DEM screening {screening_stage['id']} "
                 f"({rule} rule, {n_steps} steps); other screened factors at the centre of their range "
                 "unless the stage fixes them (derivation.fixed: each fixed value and where it comes from)"),
        "selection": sel.to_dict("records"),
        "direction": {t: float(v) for t, v in direction.items()},
        "start": start,
        "held_coded": {t: _g12(v) for t, v in held.items()},
        "curvature": centre,
        "rule": rule,
        **({"target": {"coded": {t: _g12(v) for t, v in path.attrs["target_coded"].items()},
                       "base": path.attrs["base"]},
            "box_half_width": {_sym_of(factors, t): _g12(v) for t, v in path.attrs["box_half_width"].items()}}
           if rule == "target" else {}),
        "screening": scr,
        "paper_factors": {s: f["parameter"] for s, f in config_stage["factors"].items()},
    }
    apply_own_fixed(st, config_stage, fixed, origin, {f["parameter"] for f in factors.values()}, soil_data)
    return st


def _held_coded(config_stage: dict, sf: dict, chosen: list[str]) -> dict[str, float]:
    """Coded level of each screened factor off the path that the path stage's own ``fixed``
    holds away from the centre of its screening range (the others sit at 0)."""
    own = config_stage.get("fixed") or {}
    out = {}
    for t, f in sf.items():
        if t in chosen or f["parameter"] not in own:
            continue
        v = own[f["parameter"]]
        v = v.get("value") if isinstance(v, dict) else v
        try:
            x = (float(v) - _centre(f)) / ((float(f["high"]) - float(f["low"])) / 2.0)
        except (TypeError, ValueError):
            continue
        if np.isfinite(x) and abs(x) > 1e-9:  # not the centre written with round-off
            out[t] = x
    return out


def _sym_of(factors: dict, screening_symbol: str) -> str:
    """The path stage's symbol of the factor a screening symbol names."""
    return next(s for s, f in factors.items() if f["screening_symbol"] == screening_symbol)


def _upstream_origin(stage: dict, pname: str, what: str) -> str:
    """Where an earlier stage's fixed value came from: its own record (``derivation.fixed``),
    else its config's ``fixed`` entry."""
    rec = ((stage.get("derivation") or {}).get("fixed") or {}).get(pname)
    if rec and rec.get("origin"):
        return f"{rec['origin']}, carried on from stage {stage['id']}"
    return f"stages.{stage['id']}.fixed.{pname} ({what})"


def bbd_from_path(soil_data: dict, stage_id: str, path_stage: dict, path_responses: pd.DataFrame) -> dict:
    """A Box-Behnken stage centred on the DEM path step closest to the targets."""
    from soilcal.doe.steepest import bbd_levels, chosen_step, trend_caution

    config_stage = _stage(soil_data, stage_id)
    syms = list(path_stage["factors"])
    path = pd.DataFrame({"step": np.arange(1, len(path_stage["factors"][syms[0]]["levels"]) + 1)})
    for s in syms:
        path[s] = path_stage["factors"][s]["levels"]
    targets = {r: t["value"] for r, t in (path_stage.get("path_targets") or {}).items()}
    resp = path_responses.sort_values("step")
    ys = {r: resp[r].to_numpy(float) for r in targets if r in resp.columns}
    choice = path_stage.get("path_choice", "closest")
    step, table = chosen_step(path, ys, targets, rule=choice)
    trends = {r: {k: (None if isinstance(v, float) and not np.isfinite(v) else v) for k, v in t.items()}
              for r, t in table.attrs.get("trend", {}).items()}  # stage.json: no NaN
    cautions = {r: c for r, t in table.attrs.get("trend", {}).items() if (c := trend_caution(t))}
    bounds = {s: _bounds_in_config_units(soil_data, path_stage["factors"][s]["parameter"]) for s in syms}
    # a path aimed at several targets gives each factor the box half width of the "range"
    # rule's neighbours (soilcal.doe.steepest.derive_path, rule "target")
    half_width = (path_stage.get("derivation") or {}).get("box_half_width")
    levels = bbd_levels(path, step, syms, bounds, half_width=half_width)
    st = _dem_base(config_stage)
    st["factors"] = {s: {"parameter": path_stage["factors"][s]["parameter"],
                         "low": _g12(levels[s]["low"]), "centre": _g12(levels[s]["centre"]),
                         "high": _g12(levels[s]["high"])} for s in syms}
    # the path's fixed values carry on; the stage's own hold for every parameter it does not vary
    path_fixed = dict(path_stage.get("fixed") or {})
    origin = {k: _upstream_origin(path_stage, k, "the path's fixed value") for k in path_fixed}
    k = len(syms)
    st["runs"] = 2 * k * (k - 1) + int(st.get("center_points", 0))
    _keep_printed_optimum(st, config_stage)
    st["derivation"] = {
        "kind": "path",
        "from_stage": path_stage["id"],
        "text": (f"Box-Behnken centred on step {step} of the DEM path {path_stage['id']}"
                 + (" (the step closest to the target on the trend fitted through the path's runs)"
                    if choice == "fitted" else " (the step whose own run is closest to the target)")
                 + "".join(f"; {r}: {c}" for r, c in cautions.items())),
        "cautions": cautions,
        "chosen_step": int(step),
        "choice": choice,
        "trend": trends,
        "steps": table.to_dict("records"),
        "levels": {s: levels[s].get("note", "") for s in syms},
    }
    apply_own_fixed(st, config_stage, path_fixed, origin, {f["parameter"] for f in st["factors"].values()},
                    soil_data)
    return st


def fix_from_optimum(st: dict, upstream_stage: dict, optimum: pd.DataFrame, case: str | None,
                     params: dict | None = None) -> dict:
    """``st`` with the parameters of ``upstream_stage``'s factors fixed at its calibrated set;
    a fixed value of the stage that sets the same DEM parameter under another id (``params``:
    the soil's ``parameters``, :func:`soilcal.config.parameters.dem_key`) is replaced, and
    named in the origin, so the DEM parameter is set once."""
    from soilcal.chain.stage import calibrated_levels

    from soilcal.config.parameters import dem_key

    levels = calibrated_levels(upstream_stage, optimum, case)
    fixed = dict(st.get("fixed") or {})
    params = params or {}
    st.setdefault("derivation", {})
    rec = st["derivation"].setdefault("fixed", {})
    paper, replaced = {}, {}
    for sym, v in levels.items():
        pname = upstream_stage["factors"][sym]["parameter"]
        paper[pname] = fixed.get(pname)
        # a value the stage gives under another id that sets the same DEM parameter goes too
        for p in [p for p in fixed if p != pname and dem_key(params, p) == dem_key(params, pname)]:
            replaced[pname] = (p, fixed.pop(p))
            rec.pop(p, None)
        fixed[pname] = float(v)
    st["fixed"] = fixed
    for pname in paper:
        over = ""
        if paper[pname] is not None:
            over = f", over the stage's own {paper[pname]:g}"
        elif pname in replaced:
            over = f", over the stage's own {replaced[pname][0]} = {float(replaced[pname][1]):g}"
        rec[pname] = {"value": fixed[pname],
                      "origin": (f"calibrated set of stage {upstream_stage['id']}"
                                 + (f" (case {case})" if case else "") + " (fixed_from)" + over)}
    st["derivation"]["fixed_from"] = {"stage": upstream_stage["id"], "case": case,
                                      "values": {k: fixed[k] for k in paper}, "paper": paper}
    return st


def dem_stage(soil_data: dict, stage_id: str, targets: dict, upstream: dict | None = None) -> dict:
    """The stage the DEM source runs (module docstring).

    ``upstream`` holds the DEM results of the stages of :func:`dependencies`:
    ``{"from": {"stage", "responses", "effects"}, "fixed_from": {"stage", "optimum"}}``.
    """
    upstream = upstream or {}
    config_stage = _stage(soil_data, stage_id)
    deps = dependencies(soil_data, stage_id)
    if "from" in deps:
        up = upstream["from"]
        if up["stage"]["kind"] == "plackett_burman" and config_stage["kind"] == "steepest_ascent":
            st = path_from_screening(soil_data, stage_id, up["stage"], up["effects"], up["responses"], targets)
        elif up["stage"]["kind"] == "steepest_ascent" and config_stage["kind"] == "box_behnken":
            st = bbd_from_path(soil_data, stage_id, up["stage"], up["responses"])
        else:
            raise InputError(soil_data.get("name"), f"stages.{stage_id}.from_stage", DERIVED_EXPECTED,
                             f"{config_stage['kind']} after {up['stage']['kind']}")
    else:
        st = _dem_base(config_stage)
        why = ("the paper's printed levels (simulation.design: printed)" if design_mode(soil_data) == "printed"
               else "the levels in the soil config")
        if config_stage.get("from_stage") and config_stage["from_stage"] not in dem_stage_ids(soil_data):
            why += f" (stage {config_stage['from_stage']} is not simulated: simulation.stages)"
        st["derivation"] = {"kind": "config", "text": why}
        n_centre = int((sim_block(soil_data).get("screening") or {}).get("center_points") or 0)
        if st["kind"] == "plackett_burman" and n_centre and design_mode(soil_data) == "recipe":
            st["center_points"] = n_centre
            st["derivation"]["text"] += (f", plus {n_centre} centre run(s) (simulation.screening.center_points: "
                                         "they measure the response where the path starts and its curvature; "
                                         "the effects come from the two-level runs)")
        apply_own_fixed(st, config_stage, {}, {}, set(), soil_data)
        if st["kind"] == "steepest_ascent":
            st["path_targets"] = response_targets(soil_data, [r["id"] for r in st["responses"]], targets)
    if "fixed_from" in deps:
        up = upstream["fixed_from"]
        st = fix_from_optimum(st, up["stage"], up["optimum"], (config_stage.get("fixed_from") or {}).get("case"),
                              soil_data.get("parameters"))
    return st


#: how far a simulated Box-Behnken factor's ``centre`` may lie from the midpoint of its low and
#: high levels, as a fraction of the range (the black soil's printed 0.28 for 0.275 over
#: 0.05-0.50: 1.1 %)
BBD_CENTRE_RTOL = 0.02


def dem_value_in_range(soil_path, name: str, value, scale: float, where: str) -> None:
    """A config value (``value`` in the config's unit, ``scale`` to SI) of DEM parameter
    ``name`` lies in that parameter's physical range and, for a soil's material parameter, its
    plausibility bound (:class:`soilcal.dem.scenarios.base.DemParams`, the check every DEM run
    makes), else InputError naming ``soil_path`` and ``where``."""
    from soilcal.dem.scenarios.base import DemParams

    try:
        DemParams.from_mapping({name: float(value) * scale}, str(soil_path))
    except InputError as exc:
        raise InputError(soil_path, where, f"{exc.expected} (DEM parameter {name})", value) from None


def check_own_factors(soil_path, soil_data: dict, stage_id: str) -> None:
    """A simulated stage that leaves its factors to the recipe
    (:func:`soilcal.config.load.left_to_recipe`) must be derived by it (:func:`dependencies`),
    else InputError naming ``stages.<id>.factors``: ``design: printed`` and ``adaptive`` run a
    stage's own factors, as does the recipe when the stage it follows is not simulated."""
    st = _stage(soil_data, stage_id)
    if st["factors"] or "from" in dependencies(soil_data, stage_id):
        return
    how = {"printed": "simulation.design: printed runs the stage's own levels",
           "adaptive": "simulation.design: adaptive ranges the stage's own factors over their screening's"}
    why = how.get(design_mode(soil_data), f"stage {st.get('from_stage')} is not simulated (simulation.stages), "
                                          "so the stage runs its own levels")
    raise InputError(soil_path, f"stages.{stage_id}.factors", f"the stage's factors ({why})", "nothing",
                     note="only the DEM recipe (simulation.design: recipe, the default) derives a stage's factors "
                          "from the DEM results of the stage it follows")


def check_dem_stages(soil_path, soil_data: dict) -> None:
    """Start-up check of the stages the DEM source runs (:func:`simulated_stage_ids`), so that a
    config the chain cannot run fails before any DEM job, naming the soil file and field:

    * a stage derived from an earlier DEM stage (``from_stage``, :func:`dependencies`) is a
      steepest ascent after a Plackett-Burman screening or a Box-Behnken design after a
      steepest ascent (:func:`dem_stage` knows no other derivation);
    * every factor's parameter and every fixed parameter maps to a DEM parameter
      (:func:`soilcal.dem.scenarios.base.dem_field`, the mapping the DEM jobs use), and the
      fixed values and the levels of a stage that runs its config's levels lie in that
      parameter's physical range, and a Box-Behnken factor's ``centre`` is the midpoint of
      its ``low`` and ``high`` where the runs are decoded from them (:func:`decodes_low_high`);
      with ``design: adaptive`` a factor's levels are the range it
      takes from its screening where it takes one
      (:func:`soilcal.chain.adaptive.adaptive_range`), named as the screening's
      ``stages.<screening>.factors.<symbol>.low`` / ``.high`` (a range declared under
      ``simulation.search_ranges``, which the adaptive design does not use, is checked against
      the same ranges as the soil loads, in every mode:
      :func:`soilcal.config.load.check_search_ranges`).

    (A Plackett-Burman stage's ``runs`` is checked for every soil as it loads.)
    """
    from soilcal.chain import adaptive
    from soilcal.dem.scenarios.base import dem_field

    in_range = partial(dem_value_in_range, soil_path)

    def mapped(pname, where):
        try:
            return dem_field(soil_path, soil_data, pname, where)
        except InputError as exc:
            if exc.field == where:
                raise
            raise InputError(soil_path, exc.field, exc.expected, exc.got, note=f"used by {where}") from None

    for sid in simulated_stage_ids(soil_data):
        st = _stage(soil_data, sid)
        deps = dependencies(soil_data, sid)
        if "from" in deps:
            up = _stage(soil_data, deps["from"])
            if (up["kind"], st["kind"]) not in DERIVED_KINDS:
                raise InputError(soil_path, f"stages.{sid}.from_stage", DERIVED_EXPECTED,
                                 f"{st['kind']} after {up['kind']}",
                                 note=f"stage {up['id']!r}; the DEM source derives a stage from the DEM results "
                                      "of the one it follows: give the stage in between, or run the config's "
                                      "levels with simulation.design: printed")
        for sym, f in st["factors"].items():
            where = f"stages.{sid}.factors.{sym}"
            name, scale = mapped(f["parameter"], f"{where}.parameter")
            if "from" in deps:
                continue  # levels derived from the earlier stage's DEM results
            screened = (adaptive.adaptive_range(soil_data, sid, f["parameter"])
                        if design_mode(soil_data) == "adaptive" else None)
            if screened is not None:
                # the adaptive design ranges the factor over its screening's levels (ranges:
                # screening), which it runs in place of the stage's own
                for key in ("low", "high"):
                    in_range(name, getattr(screened, key), scale, f"{screened.field}.{key}")
                continue
            if st["kind"] == "box_behnken" and decodes_low_high(soil_data, sid) \
                    and None not in (f.get("low"), f.get("centre"), f.get("high")):
                mid = (f["low"] + f["high"]) / 2
                if abs(f["centre"] - mid) > BBD_CENTRE_RTOL * (f["high"] - f["low"]):
                    # the runs' coded 0 lies midway: another centre would be dropped without a word
                    raise InputError(soil_path, f"{where}.centre",
                                     f"the midpoint of low and high ({mid:g}), where the simulated Box-Behnken "
                                     f"design's coded level 0 lies (within {BBD_CENTRE_RTOL:.0%} of the range, a "
                                     "printed rounding; or leave centre out)", f["centre"])
            for key in ("low", "centre", "high"):
                if f.get(key) is not None:
                    in_range(name, f[key], scale, f"{where}.{key}")
            for i, v in enumerate(f.get("levels") or []):
                in_range(name, v, scale, f"{where}.levels[{i}]")
        for pname, v in (st.get("fixed") or {}).items():
            where = f"stages.{sid}.fixed.{pname}"
            name, scale = mapped(pname, where)
            in_range(name, v, scale, where)


__all__ = ["bbd_from_path", "check_dem_stages", "check_own_factors", "dem_value_in_range", "dem_stage", "dem_stage_ids", "simulated_stage_ids", "dependencies", "design_mode",
           "path_from_screening", "published_stage", "response_targets", "decodes_low_high", "runs_own_levels"]
