"""A soil of one's own (not a shipped one) for the tests: one Box-Behnken stage on three DEM
parameters, built as the parsed YAML and written, with its measured tables, to a temporary
directory."""

from __future__ import annotations

from pathlib import Path

import yaml

#: DEM parameters a soil of one's own declares, by the id its factors name
PARAMETERS = {
    "rolling": {"name": "Soil-soil rolling friction", "unit": "-", "pair": "soil-soil", "kind": "rolling_friction"},
    "energy": {"name": "JKR surface energy", "unit": "J/m^2", "pair": "soil-soil", "kind": "surface_energy"},
    "sfric": {"name": "Soil-soil static friction", "unit": "-", "pair": "soil-soil", "kind": "static_friction"},
    "steel": {"name": "Soil-steel static friction", "unit": "-", "pair": "soil-steel", "kind": "static_friction"},
}


def bbd_soil(name: str, levels: dict[str, tuple[float, float]], target_angle: float | None = None,
             parameters: dict | None = None, **blocks) -> dict:
    """The parsed YAML of soil ``name``: one Box-Behnken stage ``bbd`` (3 centre points, no
    printed table) whose factors A, B, C vary the parameters ``levels`` names, in its order,
    each over its ``(low, high)``; the parameters are declared as :data:`PARAMETERS`, or as
    ``parameters`` gives them.  Its one response is ``angle`` (deg); with ``target_angle`` the
    target ``angle`` holds that value (deg) and the stage's case ``angle`` aims at it
    (desirability).  ``blocks``: the soil's other top-level blocks (``properties``,
    ``simulation``, ``measurements``) as given."""
    declared = {**PARAMETERS, **(parameters or {})}
    stage = {"id": "bbd", "kind": "box_behnken",
             "factors": {sym: {"parameter": p, "low": lo, "high": hi}
                         for sym, (p, (lo, hi)) in zip("ABC", levels.items(), strict=True)},
             "center_points": 3,
             "responses": [{"id": "angle", "name": "Repose angle", "unit": "deg"}]}
    soil = {"name": name, "parameters": {p: declared[p] for p in levels}, "stages": [stage]}
    if target_angle is not None:
        stage["optimise"] = {"method": "desirability",
                             "cases": [{"id": "angle", "goals": {"angle": {"goal": "target", "target": "angle"}}}]}
        soil["targets"] = {"angle": {"value": target_angle, "unit": "deg"}}
    return soil | blocks


def write_soil(folder: Path, soil: dict, tables: dict[str, str] | None = None) -> Path:
    """``<folder>/<name>.yaml`` holding ``soil``, and each of ``tables`` (file name: its text) as
    ``<folder>/measurements/<name>/<file>``, where a soil loaded with ``folder`` as its
    resources finds its measured tables; returns the YAML's path."""
    name = soil["name"]
    for file, text in (tables or {}).items():
        (folder / "measurements" / name).mkdir(parents=True, exist_ok=True)
        (folder / "measurements" / name / file).write_text(text)
    path = folder / f"{name}.yaml"
    path.write_text(yaml.safe_dump(soil, sort_keys=False))
    return path
