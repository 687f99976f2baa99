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

_PROPERTIES = {"poisson_ratio": "soil_poisson", "particle_density": "soil_density", "shear_modulus": "soil_shear_modulus"}


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
    from soilcal.dem.scenarios.base import dem_field

    seen = set() if _seen is None else _seen
    if stage_id in seen:
        return set()
    seen.add(stage_id)
    out = set()
    for prop, name in _PROPERTIES.items():
        if ((data.get("properties") or {}).get(prop) or {}).get("value") is not None:
            out.add(name)
    out |= set(((data.get("simulation") or {}).get("params") or {}))
    st = _stage(data, stage_id)
    for pname in st.get("fixed") or {}:
        out.add(dem_field(soil_path, data, pname, f"stages.{stage_id}.fixed.{pname}")[0])
    for sym, f in (st.get("factors") or {}).items():
        out.add(dem_field(soil_path, data, f.get("parameter"), f"stages.{stage_id}.factors.{sym}.parameter")[0])
    for earlier in dependencies(data, stage_id).values():
        out |= given(data, earlier, seen, soil_path)
    return out


def check_parameters(soil_path, data: dict) -> None:
    """Every soil parameter of every stage the DEM source simulates is set by the soil
    (module docstring): otherwise one error naming the stage and the missing parameters."""
    from soilcal.chain.derive import simulated_stage_ids

    if not data.get("simulation"):
        return
    need = soil_parameters()
    for sid in simulated_stage_ids(data):
        missing = [n for n in need if n not in given(data, sid, soil_path=soil_path)]
        if missing:
            props = {name: prop for prop, name in _PROPERTIES.items()}
            named = [n + (f" (or properties.{props[n]} with its unit)" if n in props else "") for n in missing]
            raise InputError(soil_path, "simulation.params",
                             f"a value of every soil parameter the runs of stage {sid!r} use (SI units, in "
                             f"simulation.params or the stage's fixed values); missing: {', '.join(named)}",
                             "none")
