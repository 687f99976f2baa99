"""How a soil's parameter entries (``parameters.<id>``) name the DEM parameters they set.

Plain names, no engine: read by the config loader (a stage sets each DEM parameter once) and
by the DEM's mapping of a config parameter to its field
(:func:`soilcal.dem.scenarios.base.dem_field`)."""

from __future__ import annotations


def dem_field_name(entry: dict | None) -> str | None:
    """The DEM parameter name a config parameter entry gives, ``<pair>_<kind>``
    (``soil-steel`` + ``static_friction`` -> ``soil_steel_static_friction``), whether or not
    the engine has it; None without pair and kind."""
    if not entry or "pair" not in entry or "kind" not in entry:
        return None
    return f"{entry['pair'].replace('-', '_')}_{entry['kind']}"


def dem_key(params: dict, pid: str) -> tuple[str, str]:
    """What a parameter id sets, for telling whether two ids set the same thing:
    ``("dem", <DEM parameter name>)`` (:func:`dem_field_name`) where its entry in ``params``
    (a soil's ``parameters``) gives one, else ``("id", pid)``.  Two ids with one key (the
    shear modulus once in MPa, once in Pa) set one DEM parameter."""
    name = dem_field_name((params or {}).get(pid))
    return ("dem", name) if name is not None else ("id", pid)


__all__ = ["dem_field_name", "dem_key"]
