"""The calibration targets of a soil, and where each value comes from.

``targets.csv`` (one per source, ``results/<soil>/<source>/targets.csv``) lists every target
of the soil config with the value the chain calibrates to:

* published source: the printed value (``source = printed``), as the paper calibrated;
* DEM source: the soil's own photo measurement where the target names a photo group
  (``image: <group>`` of ``resources/images/<soil>/manifest.yaml``; the group's
  ``angle_deg``, or ``image_measure``, in ``results/<soil>/images/measurements.json``,
  ``source = image``), otherwise the measured value the config holds (the paper's
  measurement, also under ``resources/measurements/<soil>/``; ``source = measurement``).

A soil without a ``citation`` (a soil of one's own, no paper) has no printed values: its
targets' values are its own measurements, ``printed_value`` is empty and a photo target's note
names the value the soil gives beside the photo measurement.  A photo target's note also names
the heap photos or drum frames its group set aside as ``low`` (``set_aside`` in
``measurements.json``), which its value and ``image_n`` leave out.

A target whose value is neither measured on a photo nor printed is kept with an empty value
and says so (``source = not available``); the optimisation cases that aim at it say why they
have no optimum.  Columns: target_id, value, sd (the standard deviation the soil gives with
the value, ``targets.<id>.sd``; empty for a photo measurement, whose scatter is image_spread),
unit, source, image_group, image_value, image_spread, image_n, printed_value, layer,
moisture_content (as the target gives it, in the unit of ``properties.moisture_content``),
moisture_unit (that unit as the soil writes it, ``%`` where it gives none; empty for a target
without a moisture), note.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd

from soilcal.errors import InputError

COLUMNS = ["target_id", "value", "sd", "unit", "source", "image_group", "image_value", "image_spread", "image_n",
           "printed_value", "layer", "moisture_content", "moisture_unit", "note"]


def target_has_value(soil_data: dict, target_id) -> bool:
    """Whether a target of the soil will have a value to aim at: a printed or measured
    ``value``, or a photo group (``image``) whose measurement gives it (module docstring)."""
    t = (soil_data.get("targets") or {}).get(target_id) or {}
    return t.get("value") is not None or bool(t.get("image"))


def goal_has_value(soil_data: dict, goal: dict) -> bool:
    """Whether an optimisation goal ``target`` has a value to aim at: its own ``value``, or a
    target (``target: <id>``) with one (:func:`target_has_value`)."""
    if goal.get("value") is not None:
        return True
    return goal.get("target") is not None and target_has_value(soil_data, goal["target"])


def targets_frame(soil_data: dict, source: str, measurements: dict | None = None,
                  measurements_path: str | Path = "measurements.json") -> pd.DataFrame:
    """The targets table of a soil for ``source`` (module docstring)."""
    rows = []
    cited = bool(soil_data.get("citation"))
    # a target's moisture is in the unit of the soil's properties.moisture_content, as its one
    # reader gives it (% by default; a target with a moisture needs the soil to declare one):
    # written beside it, 0.172 is no 0.172 %
    from soilcal.config.quantities import soil_moisture

    declared = soil_moisture(f"soil {soil_data.get('name', '')}", soil_data)
    moisture_unit = str(declared["unit"]) if declared else "%"
    for tid, t in (soil_data.get("targets") or {}).items():
        printed = t.get("value")
        printed = float(printed) if printed is not None else np.nan
        row = {"target_id": tid, "unit": t.get("unit", ""), "printed_value": printed if cited else np.nan,
               "layer": t.get("layer", ""), "moisture_content": t.get("moisture_content", np.nan),
               "moisture_unit": moisture_unit if t.get("moisture_content") is not None else "",
               "image_group": t.get("image", ""), "image_value": np.nan, "image_spread": np.nan,
               "image_n": np.nan}
        if source == "dem" and t.get("image"):
            group, key = t["image"], t.get("image_measure", "angle_deg")
            entry = (measurements or {}).get(group)
            if entry is None or key not in entry:
                raise InputError(measurements_path, f"{group}.{key}",
                                 f"the photo measurement of target {tid} (targets.{tid}.image)",
                                 sorted(measurements or {}) if entry is None else sorted(entry))
            val = float(entry[key])
            # heap photos flagged low are not in the group's value: the row says which
            aside = [Path(str(a.get("path", ""))).name for a in entry.get("set_aside") or []]
            said = f"photo group {group} ({key})"
            if aside:
                said = (f"photo group {group} ({key}; set aside as low, not in the value: {', '.join(aside)}, "
                        f"reasons in {Path(measurements_path).name} set_aside)")
            accepted = [Path(str(a.get("path", ""))).name for a in entry.get("accepted_low") or []]
            if accepted:
                said += (f"; flagged low and accepted by the user, in the value: {', '.join(accepted)} (reasons in "
                         f"{Path(measurements_path).name} accepted_low)")
            row.update(value=val, source="image", image_value=val,
                       image_spread=float(entry.get("spread_deg", np.nan)),
                       image_n=int(entry.get("n_photos", entry.get("n_frames", 1))),
                       note=f"{said}; " + (f"printed {printed:g}" if cited else f"the soil's own value {printed:g}")
                       if np.isfinite(printed) else said)
        elif np.isfinite(printed):
            row.update(value=printed, source="printed" if source == "published" and cited else "measurement",
                       sd=float(t["sd"]) if t.get("sd") is not None else np.nan, note=t.get("source", ""))
        else:
            row.update(value=np.nan, source="not available",
                       note=("no photo group and no printed value: " if cited else "no photo group and no value: ")
                       + str(t.get("note", t.get("source", ""))))
        rows.append(row)
    return pd.DataFrame(rows, columns=COLUMNS)


def write_targets(soil_data: dict, source: str, out, measurements_json=None) -> pd.DataFrame:
    from soilcal.chain.files import write_csv

    meas = None
    if measurements_json:
        meas = json.loads(Path(measurements_json).read_text())
    df = targets_frame(soil_data, source, meas, measurements_json or "measurements.json")
    write_csv(df, out)
    return df


__all__ = ["COLUMNS", "goal_has_value", "target_has_value", "targets_frame", "write_targets"]
