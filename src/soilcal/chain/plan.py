"""Which response sources a soil runs, and the part of its config a DEM job depends on."""

from __future__ import annotations

import copy

from soilcal.errors import InputError

SOURCES = ("published", "dem", "both")
#: soil config keys that document the paper and never change a computed number
_DOCUMENTATION = ("title", "citation", "notes", "missing", "errata", "verification")


def soil_sources(soil, override: str | None = None) -> list[str]:
    """``["published"]``, ``["dem"]`` or both: the workflow's ``source`` (``--config
    source=...``) when given, else the soil's own ``source``."""
    s = override or soil.data.get("source", "published")
    if s not in SOURCES:
        raise InputError("config/config.yaml", "source", f"one of {', '.join(SOURCES)}", s)
    # a DEM source without a simulation block was refused as the soil loaded
    # (soilcal.config.load, with the workflow's source as the soil's)
    return ["published", "dem"] if s == "both" else [s]


def _strip_notes(obj):
    if isinstance(obj, dict):
        return {k: _strip_notes(v) for k, v in obj.items() if k not in ("note", "notes", "source")}
    if isinstance(obj, list):
        return [_strip_notes(v) for v in obj]
    return obj


def dem_context(soil_data: dict, search_ranges: bool = False, verification: bool = False) -> dict:
    """The soil config without its documentation (citation, notes, errata, printed
    verification prose): what the DEM source's results depend on.  Passed to the DEM rules
    as params, so that editing a note re-runs nothing.  ``simulation.search_ranges`` only with
    ``search_ranges`` (the second round's rules, which search within it, and the adaptive
    design's, which record it as not used, :func:`soilcal.chain.adaptive.stage_for`:
    editing a declared range re-runs those alone, :func:`without_search_ranges`);
    ``simulation.verification`` only with ``verification`` (the rules that read its seeds and
    rounds: raising the verification's seeds re-runs the verification alone, not the design
    stages before it)."""
    d = {k: copy.deepcopy(v) for k, v in soil_data.items() if k not in _DOCUMENTATION}
    d = d if search_ranges else without_search_ranges(d)
    if not verification and isinstance(d.get("simulation"), dict) and "verification" in d["simulation"]:
        d = dict(d, simulation={k: v for k, v in d["simulation"].items() if k != "verification"})
    return _strip_notes(d)


def without_search_ranges(soil_data: dict) -> dict:
    """The soil config without ``simulation.search_ranges`` (the ranges only the second
    calibration round searches within and the adaptive design records as not used), for the
    params of every other rule."""
    sim = soil_data.get("simulation")
    if not isinstance(sim, dict) or "search_ranges" not in sim:
        return soil_data
    return dict(soil_data, simulation={k: v for k, v in sim.items() if k != "search_ranges"})


__all__ = ["SOURCES", "dem_context", "soil_sources", "without_search_ranges"]
