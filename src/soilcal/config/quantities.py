"""The physical quantities a measured table's covariate may declare (``quantity``, ``unit``):
their SI unit and accepted units.  Plain data, imported by the measurement loader and by the
measured-data loop."""

import math

#: quantity -> (SI unit, {accepted unit: factor to SI}); ``None`` for a label quantity
#: (a tool id, a test day, a group) whose cells are names, not numbers
QUANTITIES = {
    "tool_speed": ("m/s", {"m/s": 1.0, "km/h": 1 / 3.6, "mm/s": 1e-3, "cm/s": 1e-2}),
    "working_depth": ("m", {"m": 1.0, "cm": 1e-2, "mm": 1e-3}),
    "rotor_speed": ("r/min", {"r/min": 1.0, "rpm": 1.0, "rad/s": 60 / (2 * math.pi)}),
    "moisture_content": ("%", {"%": 1.0, "-": 100.0, "fraction": 100.0, "g/g": 100.0, "kg/kg": 100.0}),  # a mass fraction: 0.15 = 15 %
    "layer_depth": ("m", {"m": 1.0, "cm": 1e-2, "mm": 1e-3}),
    "bulk_density": ("kg/m^3", {"kg/m^3": 1.0, "g/cm^3": 1e3, "t/m^3": 1e3}),
    "position": ("m", {"m": 1.0, "cm": 1e-2, "mm": 1e-3}),
    "tool": None,
    "day": None,
    "group": None,
}


def moisture_factor(unit) -> float | None:
    """Factor to % of a moisture content's declared unit: ``%`` (also written ``percent``,
    ``wt%``, ``% w/w``, ``g/100g``, ``% dry basis``, ``% of dry mass``) or a mass fraction
    (``-``, ``fraction``, ``g/g``, ``kg/kg``) times 100; case, spaces, dots and brackets
    ignored.  A moisture content is gravimetric, of the dry mass: None for any other unit,
    a volumetric one (``vol %``, ``% v/v``, ``m3 m-3``) or one of the wet mass
    (``% wet basis``) too."""
    import re

    key = re.sub(r"[\s.()]+", "", str(unit).lower())
    return {**QUANTITIES["moisture_content"][1], "percent": 1.0, "wt%": 1.0, "%w/w": 1.0, "g/100g": 1.0,
            "%drybasis": 1.0, "%ofdrymass": 1.0}.get(key)


def quantity_factor(quantity: str, unit) -> float | None:
    """Factor to the SI unit of :data:`QUANTITIES` of a numeric quantity's ``unit`` as a
    measured table's covariate declares it: one of the quantity's units, and for a moisture
    content every unit :func:`moisture_factor` knows (the units the soil's own
    ``properties.moisture_content`` takes, ``percent`` or ``wt%`` too); also one of these
    written otherwise where the WHOLE text is that unit
    (:func:`soilcal.config.measurements.whole_unit`: ``m s-1``, ``km h-1``, ``g cm-3``,
    ``Mg m-3``, ``min-1``, ``g g-1``).  None for another unit, for a text that holds a unit
    among other words or numbers (``10 cm``, ``0.1 m s-1``, ``vol %``, ``% wet basis``), or a
    label quantity."""
    if QUANTITIES.get(quantity) is None:
        return None
    f = moisture_factor(unit) if quantity == "moisture_content" else QUANTITIES[quantity][1].get(unit)
    if f is None and isinstance(unit, str):
        from soilcal.config.measurements import whole_unit

        u = whole_unit(unit)
        if u is not None and u != unit:
            return moisture_factor(u) if quantity == "moisture_content" else QUANTITIES[quantity][1].get(u)
    return f


#: the units of a moisture content :func:`moisture_factor` knows, as the messages name them
MOISTURE_UNITS = ("% (also percent, wt%, % w/w, g/100g, % dry basis) or a mass fraction (-, fraction, g/g, "
                  "kg/kg) of the dry mass: a gravimetric moisture content (a volumetric one, theta_v, is "
                  "theta_v * rho_water / rho_dry_bulk; one of the wet mass, w_wet, is w_wet / (1 - w_wet))")


def soil_moisture(path, data: dict) -> dict | None:
    """The moisture contents a soil declares (``properties.moisture_content``): ``points`` (its
    ``values`` and ``value``) and ``ranges`` (its ``low`` .. ``high``), in the unit the soil
    gives them; ``unit``; ``factor`` to % (:func:`moisture_factor`); ``text``, how the soil
    file writes them.  None where it declares none.  The one reader of that property: a unit
    :func:`moisture_factor` does not know raises InputError naming ``path`` and
    ``properties.moisture_content.unit`` with the units it knows (its values cannot be
    compared with any moisture)."""
    from soilcal.errors import InputError

    prop = (data.get("properties") or {}).get("moisture_content")
    if not isinstance(prop, dict):
        return None

    def num(v):
        return isinstance(v, (int, float)) and not isinstance(v, bool)

    points = [float(v) for v in list(prop.get("values") or []) + [prop.get("value")] if num(v)]
    ranges = [(float(prop["low"]), float(prop["high"]))] if num(prop.get("low")) and num(prop.get("high")) else []
    if not points and not ranges:
        return None
    unit = prop.get("unit", "%")
    factor = quantity_factor("moisture_content", unit)
    if factor is None:
        raise InputError(path, "properties.moisture_content.unit",
                         f"a moisture content unit soilcal knows, {MOISTURE_UNITS} ({unit!r} is not one of them: "
                         "give the values in % or as a fraction)", unit)
    text = ", ".join([f"{v:g}" for v in points] + [f"{lo:g}-{hi:g}" for lo, hi in ranges]) + f" {unit}"
    return {"points": points, "ranges": ranges, "unit": unit, "factor": factor, "text": text}


#: how near two moisture contents, both in %, must lie to be the same moisture (relative, and
#: absolute in %): the same number written twice or in the other form (0.07 as a fraction is
#: 7.000000000000001 %), not a neighbouring moisture (16.31 against 17.2 %)
MOISTURE_RTOL = 1e-9


def same_number(a: float, b: float) -> bool:
    """Whether two numbers of one quantity, in one unit, are the same value written twice (a
    map key and a table's cell, two moistures): equal within :data:`MOISTURE_RTOL`, relative
    and absolute."""
    return math.isclose(a, b, rel_tol=MOISTURE_RTOL, abs_tol=MOISTURE_RTOL)


def declares_moisture(declared: dict, pct: float) -> bool:
    """Whether the moisture contents a soil declares (:func:`soil_moisture`) hold ``pct``, a
    moisture content in %: one of its values, or inside its ``low`` .. ``high`` (its ends
    included), compared in % by :func:`same_number`, so that a moisture written in % and
    declared as a fraction, or the other way round, is the same moisture at every value and
    at a range's ends."""
    f = declared["factor"]
    return (any(same_number(pct, v * f) for v in declared["points"])
            or any(lo * f <= pct <= hi * f or same_number(pct, lo * f) or same_number(pct, hi * f)
                   for lo, hi in declared["ranges"]))


#: quantities that must be above zero (an effect takes their logarithm or a ratio to them)
POSITIVE_QUANTITIES = ("tool_speed", "working_depth", "rotor_speed", "layer_depth", "bulk_density")
