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


__all__ = ["dem_field_name"]
