"""The physical quantities a measured table's covariate may declare (``quantity``, ``unit``):
their SI unit and accepted units.  Plain data, imported by the measurement loader and by the
measured-data loop."""

import math
import re

#: the one table of unit symbols soilcal reads a unit written with symbols by
#: (:func:`unit_powers`: a property's unit by :func:`si_factor`, a compound unit in a table's
#: column name or ``unit:`` by :func:`soilcal.config.measurements.whole_unit`): symbol ->
#: (factor to SI, dimension as powers of mass, length, time).  Case matters: ``mPa`` is a
#: millipascal, ``MPa`` a megapascal, ``mN`` a millinewton, ``MN`` a meganewton.  An angle or a
#: revolution is dimensionless here (``r``, ``rev`` a revolution, 2 pi rad).  The imperial units
#: are exact by definition (the inch 0.0254 m, the foot 0.3048 m, the pound 0.45359237 kg, the
#: pound-force a pound times the standard gravity 9.80665 m/s^2, the psi a pound-force per
#: square inch); :data:`QUANTITIES` and the measured responses' units take them from here.
_INCH, _FOOT, _POUND, _G_N = 0.0254, 0.3048, 0.45359237, 9.80665
UNIT_SYMBOLS = {
    "g": (1e-3, (1, 0, 0)), "kg": (1.0, (1, 0, 0)), "Mg": (1e3, (1, 0, 0)), "t": (1e3, (1, 0, 0)),
    "lb": (_POUND, (1, 0, 0)),
    "mm": (1e-3, (0, 1, 0)), "cm": (1e-2, (0, 1, 0)), "dm": (0.1, (0, 1, 0)), "m": (1.0, (0, 1, 0)),
    "km": (1e3, (0, 1, 0)), "in": (_INCH, (0, 1, 0)), "ft": (_FOOT, (0, 1, 0)),
    "L": (1e-3, (0, 3, 0)), "l": (1e-3, (0, 3, 0)), "mL": (1e-6, (0, 3, 0)),
    "ml": (1e-6, (0, 3, 0)), "cc": (1e-6, (0, 3, 0)),
    "s": (1.0, (0, 0, 1)), "min": (60.0, (0, 0, 1)), "h": (3600.0, (0, 0, 1)),
    "N": (1.0, (1, 1, -2)), "kN": (1e3, (1, 1, -2)), "MN": (1e6, (1, 1, -2)), "mN": (1e-3, (1, 1, -2)),
    "lbf": (_POUND * _G_N, (1, 1, -2)),
    "Pa": (1.0, (1, -1, -2)), "kPa": (1e3, (1, -1, -2)), "MPa": (1e6, (1, -1, -2)), "GPa": (1e9, (1, -1, -2)),
    "mPa": (1e-3, (1, -1, -2)), "psi": (_POUND * _G_N / _INCH ** 2, (1, -1, -2)),
    "J": (1.0, (1, 2, -2)), "mJ": (1e-3, (1, 2, -2)),
    "W": (1.0, (1, 2, -3)), "kW": (1e3, (1, 2, -3)),
    "rad": (1.0, (0, 0, 0)), "r": (2 * math.pi, (0, 0, 0)), "rev": (2 * math.pi, (0, 0, 0)),
}
#: the units of a length or depth a table or a response may be given in, factor to m
LENGTH_FACTORS = {u: UNIT_SYMBOLS[u][0] for u in ("m", "cm", "mm", "in", "ft")}


#: quantity -> (SI unit, {accepted unit: factor to SI}); ``None`` for a label quantity
#: (a tool id, a test day, a group) whose cells are names, not numbers (imperial units as
#: :data:`UNIT_SYMBOLS` defines them; the mile 1609.344 m: a mile per hour 0.44704 m/s)
QUANTITIES = {
    "tool_speed": ("m/s", {"m/s": 1.0, "km/h": 1 / 3.6, "m/min": 1 / 60, "mm/s": 1e-3, "cm/s": 1e-2,
                           "mph": 0.44704, "ft/s": _FOOT, "ft/min": _FOOT / 60}),
    "working_depth": ("m", dict(LENGTH_FACTORS)),
    "rotor_speed": ("r/min", {"r/min": 1.0, "rpm": 1.0, "r/s": 60.0, "rad/s": 60 / (2 * math.pi)}),
    "moisture_content": ("%", {"%": 1.0, "-": 100.0, "fraction": 100.0, "g/g": 100.0, "kg/kg": 100.0}),  # a mass fraction: 0.15 = 15 %
    "layer_depth": ("m", dict(LENGTH_FACTORS)),
    "bulk_density": ("kg/m^3", {"kg/m^3": 1.0, "g/cm^3": 1e3, "t/m^3": 1e3, "lb/ft^3": _POUND / _FOOT ** 3}),
    "position": ("m", dict(LENGTH_FACTORS)),
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
    from soilcal.config.measurements import whole_unit

    units = [unit] + ([whole_unit(unit)] if isinstance(unit, str) else [])
    lookup = moisture_factor if quantity == "moisture_content" else QUANTITIES[quantity][1].get
    return next((f for f in map(lookup, units) if f is not None), None)


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

#: quantities that cannot be below zero but may be zero (an oven-dry soil's moisture content)
NONNEGATIVE_QUANTITIES = ("moisture_content",)


# ------------------------------------------------------------------ physical ranges

#: kind -> (low, high, SI unit): the physical range of a measured property or material of a
#: real soil or tool, in SI, by which a soil of one's own is checked at load
#: (:func:`soilcal.config.load._check_own_properties`) and a published soil's printed values
#: are judged (:func:`soilcal.chain.errata.plausibility`).  Bounds of real materials, not of the
#: shipped soils: a bulk density from surface peat (~50 kg/m^3) to a compacted gravel
#: (~2.4e3); a particle density from organic matter (~1.3e3, bounded at 500) to iron oxides
#: (~5.2e3); any mass density (a tool's, a plain ``density``) from peat to tungsten (1.93e4);
#: a gravimetric moisture content to 500 % (peat holds 300-1000 % at saturation, andisols
#: over 100 %); moduli from a loose soil's kPa to a carbide's 5e11 Pa.
PLAUSIBLE = {
    "shear_modulus": (1e3, 3e11, "Pa"),
    "youngs_modulus": (1e3, 5e11, "Pa"),
    "poisson_ratio": (0.0, 0.5, "-"),
    "density": (50.0, 2.0e4, "kg/m^3"),
    "bulk_density": (50.0, 3.0e3, "kg/m^3"),
    "particle_density": (500.0, 5.0e3, "kg/m^3"),
    "restitution": (1e-9, 1.0, "-"),
    "static_friction": (0.0, 3.0, "-"),
    "rolling_friction": (0.0, 1.0, "-"),
    "surface_energy": (0.0, 100.0, "J/m^2"),
    "moisture_content": (0.0, 500.0, "%"),
}
#: the keys a soil's mass density of its bulk is given under (judged as a bulk density), and
#: of its solids (as a particle density); any other key with "density" in it is some other
#: quantity (relative_density in %, root_length_density in cm/cm^3, dry_density_ratio) and not
#: judged as a mass density
BULK_DENSITY_KEYS = ("bulk_density", "dry_density", "dry_bulk_density", "wet_density", "wet_bulk_density",
                     "maximum_dry_density", "max_dry_density")
PARTICLE_DENSITY_KEYS = ("particle_density", "solid_density", "grain_density")


def plausible_kind(name: str, material: bool = False) -> str | None:
    """The kind of :data:`PLAUSIBLE` a property keyed ``name`` (under ``materials`` when
    ``material``) is judged as, or None for a property no range is known of: a material's
    mass density under ``density`` or a bulk or particle density key is a ``density``."""
    if name in BULK_DENSITY_KEYS + PARTICLE_DENSITY_KEYS:
        return "density" if material else ("bulk_density" if name in BULK_DENSITY_KEYS else "particle_density")
    return name if name in PLAUSIBLE else None


#: symbols whose letters name two units, one of them not in :data:`UNIT_SYMBOLS`: ``mg`` (a
#: Mg or a milligram), ``mj`` (a mJ or a megajoule); matched with their case only
_CASE_SENSITIVE = ("mg", "mj")
#: the ``mpa`` of a printed table (``mpa``, ``MPA``, ``Mpa``) is a megapascal: no soil's stress
#: or modulus is in millipascals, and a ``mPa`` written so, exactly, is refused as a stress
#: (:data:`MILLIPASCAL`)
_CASE_CHOICES = {"mpa": "MPa"}


def _unit_cases() -> dict:
    """lower-case spelling -> symbol of :data:`UNIT_SYMBOLS`, for the symbols whose letters name
    one unit in any case (``kg`` for ``Kg``, ``KG``; ``kn`` for ``KN``; ``psi`` for ``PSI``):
    not those of two units (``mn``: mN or MN; ``mg``, ``mj``: :data:`_CASE_SENSITIVE`), but
    :data:`_CASE_CHOICES`."""
    by_lower = {}
    for sym, spec in UNIT_SYMBOLS.items():
        by_lower.setdefault(sym.lower(), {})[sym] = spec
    cases = {low: min(syms) for low, syms in by_lower.items()
             if len(set(syms.values())) == 1 and low not in _CASE_SENSITIVE}
    return {**cases, **_CASE_CHOICES}


#: THE rule of a unit symbol's case, for a property's unit (:func:`si_factor`), a response's or
#: covariate's ``unit:`` and a column's name (:func:`soilcal.config.measurements.whole_unit`,
#: ``name_units``): a symbol written in another case is read where its letters name one unit of
#: :data:`UNIT_SYMBOLS` in any case (:func:`_unit_cases`); a name's one-letter word is matched
#: with its case only (``M`` is no ``m``, ``n`` no ``N``)
UNIT_CASES = _unit_cases()
#: a millipascal, a unit of a viscosity (``mPa s``), never of a soil's stress or modulus: as a
#: stress it is refused, asking whether MPa was meant
MILLIPASCAL = "mPa"
_SUPERSCRIPTS = str.maketrans("⁻¹²³⁴−", "-1234-")
_POWER = re.compile(r"(?P<sym>[A-Za-z]+)(?:\^?(?P<exp>-?\d))?")


def unit_powers(text, any_case: dict | None = None) -> list[tuple[str, str | None, bool]] | None:
    """The symbols of a unit written with symbols of :data:`UNIT_SYMBOLS`, SI style: exponents
    (``m s-1``, ``g cm-3``, ``m^2``, ``m·s⁻¹``), at most one ``/`` or ``per`` (``kg/m3``,
    ``N per m``), symbols apart by spaces, dots, ``*`` or ``·``; a ``1`` before the ``/`` is no
    symbol (``1/min``).  As ``(symbol, exponent as written or None, below the /)`` in the
    order written; a symbol matched with its case, or by its lower case in ``any_case``
    (lower case -> symbol).  None for a text that is not such a unit (a word or number of no
    symbol, two ``/``, a ``/`` with nothing after it, an empty text).  The one parser of units
    written with symbols."""
    t = ("" if text is None else str(text)).translate(_SUPERSCRIPTS).strip()
    t = re.sub(r"\s+per\s+|\s*/\s*", " / ", t, flags=re.IGNORECASE)
    words = [w for w in re.split(r"[\s.·⋅*]+", t) if w]
    if words[:2] == ["1", "/"]:
        words = words[1:]
    out, below = [], False
    for w in words:
        if w == "/":
            if below:
                return None
            below = True
            continue
        m = _POWER.fullmatch(w)
        sym = None if m is None else m["sym"] if m["sym"] in UNIT_SYMBOLS else (any_case or {}).get(m["sym"].lower())
        if sym is None:
            return None
        out.append((sym, m["exp"], below))
    if not out or words[-1] == "/":
        return None
    return out


#: the SI units of :data:`PLAUSIBLE` as dimensions
_SI_DIMENSIONS = {"kg/m^3": (1, -3, 0), "Pa": (1, -1, -2), "J/m^2": (1, 0, -2), "-": (0, 0, 0)}
#: a dimensionless value's unit: factor
_DIMENSIONLESS = {"": 1.0, "-": 1.0, "1": 1.0, "dimensionless": 1.0, "%": 1e-2}
#: the units :func:`si_factor` takes, by SI unit, as the messages name them
SI_UNITS_TAKEN = {
    "kg/m^3": "kg/m^3, g/cm^3, t/m^3, Mg/m^3, kg/dm^3, g/mL, lb/ft^3 (also written g cm-3, kg m-3; Kg/m3, G/CM3)",
    "Pa": "Pa, kPa, MPa, GPa, N/m^2, kN/m^2, MN/m^2, psi (also written N m-2)",
    "J/m^2": "J/m^2, mJ/m^2, N/m, mN/m (also written J m-2, mN m-1)",
    "-": "- (also 1, dimensionless) or %",
}


def si_factor(unit, si_unit: str) -> float | None:
    """Factor to ``si_unit`` (a unit of :data:`PLAUSIBLE`) of a property's declared ``unit``,
    where the whole text is a unit of that dimension (:func:`unit_powers`): symbols of
    :data:`UNIT_SYMBOLS` with exponents, a ``/`` or ``per`` between them (``g/cm^3``, ``g cm-3``, ``kg.m-3``,
    ``Mg m^-3``, ``kg/dm3``, ``g/mL``, ``lb/ft3``, ``N/m^2``, ``MN m-2``, ``psi``, ``J/m2``), a
    unit in another case by :data:`UNIT_CASES` (``mpa``, ``KPA``, ``PSI``: MPa, kPa, psi, as
    printed tables write them; ``mPa``, a millipascal, is no soil's stress: None), or a
    dimensionless one
    (``-``, ``1``, ``dimensionless``, ``%``).  None for a text that is no unit of that
    dimension (``kN/m^3`` is a unit weight, no density; ``x1000 kg/m3`` is no unit)."""
    u = "" if unit is None else str(unit).strip()
    if si_unit == "-":
        return _DIMENSIONLESS.get(u.lower())
    powers = unit_powers(u, UNIT_CASES)
    if powers is None or (si_unit == "Pa" and any(sym == MILLIPASCAL for sym, _, _ in powers)):
        return None
    factor, dims = 1.0, [0, 0, 0]
    for sym, exp, below in powers:
        f, d = UNIT_SYMBOLS[sym]
        e = int(exp or 1) * (-1 if below else 1)
        factor *= f ** e
        dims = [x + y * e for x, y in zip(dims, d)]
    if tuple(dims) != _SI_DIMENSIONS[si_unit]:
        return None
    return float(f"{factor:.12g}")  # g/cm^3 is 1000, not 999.9999999999999
