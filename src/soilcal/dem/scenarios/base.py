"""Shared pieces of the DEM test scenarios: parameters, materials, results, validation.

Parameter names
---------------
:class:`DemParams` holds the fifteen inputs of a soil-calibration DEM run under the names
the soil configs use for their ``(pair, kind)`` entries: pair ``soil-soil`` with kind
``rolling_friction`` is ``soil_soil_rolling_friction`` and so on (``static_friction`` maps to
the engine's sliding friction coefficient mu_s).  SI units throughout (kg/m^3, Pa, J/m^2).

Defaults
--------
Soil intrinsic properties and contact parameters default to the cinnamon-soil study (Qiu et
al., Agriculture 2022, 12, 1082; ``config/soils/cinnamon-soil.yaml``), the values a bare
:class:`DemParams` (a scenario's own tests, ``soilcal scenario run``) takes; a soil calibrated
on the DEM must set every one of them itself (:mod:`soilcal.chain.provenance`, checked at
start-up), so these never stand in for another soil's value:

* density 1394 kg/m^3 (Sec. 2.1; the only density the paper prints, used in its EDEM model),
* Poisson ratio 0.311 (Sec. 2.2, Eq. 1), shear modulus 3.814 MPa (Sec. 2.3, Eq. 4),
* soil-soil restitution 0.45, static friction 0.56 (the "intermediate level values" the
  non-significant parameters were held at, Sec. 3.3.2), rolling friction 0.11 and JKR
  surface energy 0.38 J/m^2 (Box-Behnken centre levels, Sec. 3.3.2 / Table 6),
* soil-steel restitution 0.45 and rolling friction 0.125 (intermediate level values,
  Sec. 3.3.2), static friction 0.54 (Box-Behnken centre level, Sec. 3.3.2 / Table 6); the
  paper has no soil-steel surface energy (0),
* soil-soil contact plasticity ratio 0 (elastic Hertz, as every paper's EDEM model; a ratio
  above 0 switches the soil-soil contacts to the plastic Hertz law ``eepa`` of
  :mod:`soilcal.dem.contact`, the loop's ``plastic_contact`` effect).

Steel (65Mn/Q235 tools, plates, tubes): 7850 kg/m^3, Poisson 0.3, G = 7.9e10 Pa (cinnamon
soil Sec. 3.1, printed "7.9 x 10^10 MPa", a unit slip for 79 GPa (errata of that soil);
cohesive soil Sec. 2.6).

Stiffness scaling
-----------------
:func:`build_materials` multiplies every shear modulus by ``stiffness_scale`` (s) and
scales the JKR surface energy as printed in the vineyard-soil study (grapevine-burying paper,
``003_77672a72fffb4fcc.txt``, section on the scaled model; after Lommen et al. 2014 and Thakur
et al. 2014)::

    G_mod = s G,        gamma_mod = gamma (G_mod / G)^(2/5) = gamma s^(2/5)

The JKR pull-off force 1.5 pi gamma R* does not depend on the stiffness, so the rule weakens
the adhesion by s^(2/5) (0.12 for the black soil's printed G = 1e8 Pa under the quick
cap).  It does not keep every response: the black soil's funnel load (stage 1, quick
spheres, the full 0.5 kg) arched over the outlet in all 8 runs at the printed modulus but
discharged into heaps of 35.6 and 40.0 deg (means of four seeds at surface energies 0.4
and 0.7 J/m^2) with the rule at s = 0.005 (``benchmarks/stiffness_rule.py``; results and
notes in ``benchmarks/results/stiffness_rule.md``).

Cohesion scaling with particle size
-----------------------------------
A preset whose spheres are larger than the model particles a paper calibrated its surface
energy for (``quick``, or a setup's own ``radius``/``n_particles``) multiplies the JKR
surface energies by the ratio of Sauter radii (surface-volume mean, r32 = <r^3>/<r^2>)::

    gamma_model = gamma * r32_model / r32_reference

JKR pull-off is 1.5 pi gamma R*, so this scales the adhesive force with the square of the
particle size, the rule Thakur, Ooi & Ahmadian (Powder Technol. 293 (2016) 130-137) found to
keep the bulk response of a coarse-grained cohesive solid; equivalently the bulk cohesive
stress, pull-off force over the area per contact, ~ gamma / r, stays the same.  Without it a
heap of spheres five times the paper's size carries a fifth of the cohesion per unit area and
the response depends on the particle count.  The reference is the setup's ``paper_psd``
(the particle sizes the surface energy is for: a named setup's are its paper's, a soil of
one's own gives its own), or, for a soil bin whose setup leaves ``paper_psd`` at None, the
paper preset's bin of the named setup; ``scale_cohesion: false`` in a setup (every named
setup of a scenario that scales has it, true) turns the rule off.  The factor is recorded in
the run's setup as ``cohesion_scale``.

Rolling model
-------------
``rolling_model`` in a bench-top setup (repose, drum, incline, compression) chooses the
engine's rolling-resistance sub-model (:mod:`soilcal.dem.contact`): ``constant_torque``
(the default: EDEM's type A as LIGGGHTS ``cdt`` writes it, on each contact's relative
rotation), ``bounded`` (the type A torque on each particle's own rotation, bounded so that a
particle whose resistance suffices stays exactly at rest) or ``epsd`` (elastic-plastic
spring, type C).  With ``constant_torque`` a heap never rests exactly: the torque flips with
the sign of a vanishing rotation (a sphere below its rolling angle keeps an angular jitter
of about one step of the full torque, tests/dem/test_motion.py), and the heap keeps
creeping after the rest criterion fires.  The soil-bin scenarios use the default; the drum
refuses ``bounded``, which resists the rotation of spheres carried round by the drum.

``contact_conventions`` in the same setups chooses how the terms are written: None or
``edem`` (the default), ``liggghts``, ``lammps``, or a mapping of single choices
(:func:`conventions_of`; :mod:`soilcal.dem.contact`, "Conventions of the reference
engines"), so that a run can be set up exactly as a reference engine computes it.

Results
-------
:class:`Result` is one run: scenario, preset, seed, particle count, steps, simulated and
wall time, thread count, parameters, setup, scalar responses and time series.  ``row()``
flattens it to one CSV row with columns ``p:<param>``, ``s:<setup key>`` (scalars only) and
``r:<response>``; :func:`write_row` writes it atomically (temporary file + rename).

Replicates
----------
:func:`run_replicates` repeats a run with consecutive seeds and reports the mean of each
response with the replicates' sample standard deviation beside it (``<response>_rep_sd``),
the way the black-soil study averages three simulations per design point (its Tables 4
and 7: mean +/- SD of n = 3).  The
repose angle of a 5,000-sphere quick heap scatters by 0.5-0.9 deg from seed to seed, and the
mean of k replicates by about that over sqrt(k) (benchmarks/results/repose_seeds.md).

Stable-stage statistics
-----------------------
:func:`stable_mean` returns the mean and the sample standard deviation (ddof = 1) of the
samples y(t) with t_start <= t <= t_end, the "stable stage" mean force the tool papers report.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path

import numpy as np

from soilcal.atomic import write_text
from soilcal.config.parameters import dem_field_name
from soilcal.dem.contact import ROLLING
from soilcal.dem.materials import Material, MaterialTable
from soilcal.errors import InputError

PRESETS = ("quick", "paper")

#: the densities a soil, a particle model or a tool material can have, kg/m^3 (DemParams)
DENSITY_MIN, DENSITY_MAX = 100.0, 25000.0

# name -> (low, high, low_inclusive, high_inclusive, unit/meaning) of the accepted range
_RANGES = {
    "restitution": (0.0, 1.0, False, True, "a coefficient of restitution in (0, 1]"),
    "static_friction": (0.0, 5.0, True, True, "a sliding friction coefficient in [0, 5]"),
    "rolling_friction": (0.0, 1.0, True, True, "a rolling friction coefficient in [0, 1]"),
    "surface_energy": (0.0, 1.0e3, True, True, "a JKR surface energy in [0, 1000] J/m^2"),
    "density": (DENSITY_MIN, DENSITY_MAX, True, True,
                f"a density in [{DENSITY_MIN:g}, {DENSITY_MAX:g}] kg/m^3 (a value in g/cm^3 times 1000)"),
    "poisson": (-1.0, 0.5, False, False, "a Poisson ratio in (-1, 0.5)"),
    "shear_modulus": (0.0, 1.0e13, False, True, "a shear modulus in (0, 1e13] Pa"),
    "plasticity": (0.0, 1.0, True, False, "a contact plasticity ratio in [0, 1)"),
}


#: Plausibility bounds of a soil's own material parameters (name -> as ``_RANGES``), on top of
#: the physical range of their kind: wide enough for any soil a DEM model is calibrated for, and
#: narrow enough to stop a value typed in another unit (a modulus in MPa or GPa written with unit
#: Pa, a density in g/cm^3 written in kg/m^3, a surface energy in mJ/m^2 written in J/m^2):
#:
#: * density 100-4000 kg/m^3: a DEM model's particle density is often a bulk density (the
#:   vineyard and scaled models), and peats have bulk densities down to about 100 kg/m^3 (Boelter,
#:   Soil Sci. Soc. Am. Proc. 32 (1968) 250-254; their solids about 1300-1500), the solids of mineral soils 2600-2750 kg/m^3
#:   and iron-rich ones a little over 3000 (Blake & Hartge, "Particle density", Methods of Soil
#:   Analysis Part 1, 2nd ed., ASA/SSSA 1986); 1.6 (g/cm^3 meant) and 16000 are refused;
#: * shear modulus 1e4-5e10 Pa: the softest soils (peats, soft clays) have small-strain shear
#:   moduli of about 1e5-1e7 Pa, dense gravels up to about 1e9 Pa (Kramer, Geotechnical
#:   Earthquake Engineering, 1996, Ch. 6), and no soil grain is stiffer than quartz,
#:   G = 44 GPa (Mavko, Mukerji & Dvorkin, The Rock Physics Handbook, 2009); the DEM papers'
#:   soils use 1e6-1e8 Pa; 2 Pa (2 MPa meant) is refused;
#: * Poisson ratio 0-0.5: soils lie at 0.1-0.5 (Bowles, Foundation Analysis and Design, 5th ed.,
#:   1996, Table 2-7); a negative ratio (an auxetic solid) is no soil's;
#: * sliding friction 0-2 (soil-soil and soil-steel): a contact coefficient, not the bulk
#:   friction angle's tangent; the DEM soil calibrations calibrate it at about 0.2-1.2 (the
#:   shipped soils screen 0.2-1.1), and 2 leaves room for angular-grain models;
#: * JKR surface energy 0-100 J/m^2: the calibrated soils of the DEM papers lie at 0-40 J/m^2 (the
#:   shipped soils screen 0-10); a value in mJ/m^2 written in J/m^2 (380 for 0.38) is refused.
SOIL_RANGES = {
    "soil_density": (100.0, 4000.0, True, True,
                     "a soil particle density in [100, 4000] kg/m^3 (peat to iron-rich mineral soil; "
                     "a value in g/cm^3 times 1000)"),
    "soil_shear_modulus": (1.0e4, 5.0e10, True, True,
                           "a soil shear modulus in [1e4, 5e10] Pa (soft peat to quartz; a value in MPa "
                           "times 1e6, in GPa times 1e9)"),
    "soil_poisson": (0.0, 0.5, True, False, "a soil Poisson ratio in [0, 0.5)"),
    **{f"{pair}_static_friction": (0.0, 2.0, True, True, f"a {label} sliding friction coefficient in [0, 2]")
       for pair, label in (("soil_soil", "soil-soil"), ("soil_steel", "soil-steel"))},
    **{f"{pair}_surface_energy": (0.0, 100.0, True, True,
                                  f"a {label} JKR surface energy in [0, 100] J/m^2 (a value in mJ/m^2 times 0.001)")
       for pair, label in (("soil_soil", "soil-soil"), ("soil_steel", "soil-steel"))},
}


def _in(x: float, rng: tuple) -> bool:
    lo, hi, lo_in, hi_in = rng[:4]
    return math.isfinite(x) and (x >= lo if lo_in else x > lo) and (x <= hi if hi_in else x < hi)


def _kind(name: str) -> str:
    for k in _RANGES:
        if name.endswith(k):
            return k
    raise KeyError(name)


@dataclass
class DemParams:
    """Inputs of a soil DEM run (SI units); defaults: cinnamon soil, see module docstring.

    Every value is checked against the physical range of its kind (``_RANGES``) and a soil's
    own material parameters also against their plausibility bounds (:data:`SOIL_RANGES`).  Densities
    (``soil_density``, ``steel_density``) lie in [100, 25000] kg/m^3
    (:data:`DENSITY_MIN`, :data:`DENSITY_MAX`): the lightest soils are peats with a bulk density
    of about 100-200 kg/m^3 and mineral soils lie at 1000-2700 kg/m^3 (bulk to particle
    density); tool materials range from polymers (about 900-1400) over steel (7850) to tungsten
    carbide (about 15600) and tungsten (19300), and no element is denser than 22600 (osmium).
    A density typed in g/cm^3 or t/m^3 (1.394 for 1394 kg/m^3) falls below 100 for every
    material up to 100 g/cm^3 and is refused instead of simulating a particle a thousand times
    too light.  The lower bound still admits the vineyard soil's printed particle density
    (175.76 kg/m^3, ten times too low, kept as printed in its properties and replaced by
    ``simulation.params.soil_density`` 1757.567).
    """

    soil_soil_restitution: float = 0.45
    soil_soil_static_friction: float = 0.56
    soil_soil_rolling_friction: float = 0.11
    soil_soil_surface_energy: float = 0.38
    soil_steel_restitution: float = 0.45
    soil_steel_static_friction: float = 0.54
    soil_steel_rolling_friction: float = 0.125
    soil_steel_surface_energy: float = 0.0
    soil_density: float = 1394.0
    soil_poisson: float = 0.311
    soil_shear_modulus: float = 3.814e6
    steel_density: float = 7850.0
    steel_poisson: float = 0.3
    steel_shear_modulus: float = 7.9e10
    #: contact plasticity ratio lambda_p of the soil-soil contacts: 0 is elastic Hertz, > 0
    #: the plastic Hertz law ``eepa`` (soilcal.dem.contact); soil-steel contacts stay elastic
    soil_soil_plasticity: float = 0.0

    @classmethod
    def names(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))

    @classmethod
    def from_mapping(cls, mapping, source="<input>", base: "DemParams | None" = None,
                     plausible: bool = True) -> "DemParams":
        """Parameters from a name -> value mapping (others from ``base`` or the defaults).

        Unknown names and values outside the physical range raise :class:`InputError`, and with
        ``plausible`` (values a user typed) so do a soil's material parameters outside
        :data:`SOIL_RANGES`.  ``plausible=False`` is for values the workflow derived from checked
        ones: a design level laid out beyond a factor range, a measured condition with an
        effect of the loop switched on (a friction rising with speed past 2).
        """
        if mapping is None:
            mapping = {}
        if not hasattr(mapping, "items"):
            raise InputError(source, "params", "a mapping of parameter name -> value",
                             type(mapping).__name__)
        known = cls.names()
        values = (base or cls()).as_dict()
        for key, val in mapping.items():
            if key not in known:
                raise InputError(source, f"params.{key}", f"one of {', '.join(known)}", key)
            try:
                x = float(val)
            except (TypeError, ValueError):
                raise InputError(source, f"params.{key}", "a number", val) from None
            for rng in (_RANGES[_kind(key)], SOIL_RANGES.get(key) if plausible else None):
                if rng is not None and not _in(x, rng):
                    raise InputError(source, f"params.{key}", rng[4], val)
            values[key] = x
        return cls(**values)

    def as_dict(self) -> dict:
        return {k: float(v) for k, v in asdict(self).items()}

    def replace(self, **kw) -> "DemParams":
        return DemParams.from_mapping(kw, "<replace>", base=self)


#: printed unit -> factor to SI of the config values stage_params reads
_UNIT_SCALE = {"-": 1.0, "Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9, "J/m^2": 1.0,
               "mJ/m^2": 1e-3, "kg/m^3": 1.0, "g/cm^3": 1e3}


#: the units of each kind of DEM parameter (``_RANGES``): a unit of another quantity would
#: rescale the value without a word (a friction coefficient in mJ/m^2 taken times 1e-3)
_KIND_UNITS = {"restitution": ("-",), "static_friction": ("-",), "rolling_friction": ("-",),
               "poisson": ("-",), "plasticity": ("-",), "surface_energy": ("J/m^2", "mJ/m^2"),
               "density": ("kg/m^3", "g/cm^3"), "shear_modulus": ("Pa", "kPa", "MPa", "GPa")}


def unit_scale(path, entry: dict, where: str, field: str | None = None) -> float:
    """Factor to SI of a config entry's printed ``unit`` (``_UNIT_SCALE``); another unit raises
    InputError naming ``<where>.unit``, and so does, where ``field`` names the DEM parameter
    the entry sets, a unit of another quantity than that parameter's kind (:data:`_KIND_UNITS`)."""
    unit = entry.get("unit", "-")
    if unit not in _UNIT_SCALE:
        raise InputError(path, f"{where}.unit", f"one of {', '.join(_UNIT_SCALE)}", unit)
    if field is not None:
        try:
            fits = _KIND_UNITS[_kind(field)]
        except KeyError:
            fits = tuple(_UNIT_SCALE)
        if unit not in fits:
            raise InputError(path, f"{where}.unit", f"a unit of {field} ({', '.join(fits)})", unit)
    return _UNIT_SCALE[unit]


#: the printed soil properties every run takes (each with a single ``value``) -> DemParams field
PROPERTY_FIELDS = {"poisson_ratio": "soil_poisson", "particle_density": "soil_density",
                   "shear_modulus": "soil_shear_modulus"}


def property_values(path, soil_data: dict) -> dict:
    """DemParams field -> (SI value, property name) of the soil's printed properties that the
    runs take (:data:`PROPERTY_FIELDS`, each where it has a single ``value``), converted from
    its unit (:func:`unit_scale`: another unit raises InputError naming
    ``properties.<name>.unit``)."""
    out = {}
    for prop, name in PROPERTY_FIELDS.items():
        entry = (soil_data.get("properties") or {}).get(prop) or {}
        if entry.get("value") is not None:
            out[name] = (float(entry["value"]) * unit_scale(path, entry, f"properties.{prop}"), prop)
    return out


def dem_field(path, soil_data: dict, pname: str, where: str) -> tuple[str, float]:
    """The DEM parameter a soil config parameter sets and the factor to SI of its unit:
    ``<pair>_<kind>`` (``soil-steel`` + ``static_friction`` -> ``soil_steel_static_friction``).
    A parameter without pair and kind raises InputError naming ``where`` (the stage's factor or
    fixed entry that uses it); one that names no DEM parameter, or a unit without a factor to
    SI, names ``parameters.<pname>``."""
    entry = soil_data.get("parameters", {}).get(pname)
    name = dem_field_name(entry)
    if name is None:
        raise InputError(path, where, "a parameter with pair and kind under `parameters`", pname)
    known = DemParams.names()
    if name not in known:
        raise InputError(path, f"parameters.{pname}", f"a DEM parameter ({', '.join(known)})", name)
    return name, unit_scale(path, entry, f"parameters.{pname}", field=name)


def stage_params(soil, stage_id: str, levels: dict, base: "DemParams | None" = None,
                 coded: bool = False, params: dict | None = None,
                 params_field: str = "simulation.params") -> DemParams:
    """DEM parameters of one design point of a soil's stage, from its config.

    ``levels`` maps factor letters of the stage to values, actual values or, with
    ``coded``, coded levels -1..+1 decoded by :func:`soilcal.doe.designs.coded_to_actual`.
    The stage's ``fixed`` values and the soil's printed Poisson ratio, particle density and shear modulus (``properties.poisson_ratio``,
    ``properties.particle_density``, ``properties.shear_modulus``, each when it has a single
    ``value``) fill the rest; anything else keeps ``base`` (default :class:`DemParams`).
    ``params`` (DEM parameter name -> SI value, e.g. a soil config's ``simulation.params``,
    reported as ``params_field``) go over the printed properties and under the stage's fixed
    values and the levels.  A config parameter maps to the field
    ``<pair>_<kind>`` (``soil-steel`` + ``static_friction`` -> ``soil_steel_static_friction``),
    its value converted to SI from the unit it is printed in (``_UNIT_SCALE``; another unit
    is an error naming the entry).  A value outside the physical range is an error naming
    the stage's factor or fixed entry.
    """
    from soilcal.doe.designs import coded_to_actual

    path = soil.path
    stage = soil.stage(stage_id)
    known = DemParams.names()
    values = {}

    def put(name, value, where):
        try:
            x = float(value)
            DemParams.from_mapping({name: x}, str(path))
        except (TypeError, ValueError) as exc:
            expected = getattr(exc, "expected", "a number")
            raise InputError(path, where, f"{expected} (DEM parameter {name})", value) from None
        values[name] = x

    def field_of(pname, where):
        return dem_field(path, soil.data, pname, where)

    for name, (x, prop) in property_values(path, soil.data).items():
        if name not in (params or {}):  # a printed value params replaces is no run's (a misprint kept)
            put(name, x, f"properties.{prop}.value")
    for name, v in (params or {}).items():
        if name not in known:
            raise InputError(path, f"{params_field}.{name}", f"a DEM parameter ({', '.join(known)})", name)
        put(name, v, f"{params_field}.{name}")
    for pname, v in (stage.get("fixed") or {}).items():
        name, scale = field_of(pname, f"stages.{stage_id}.fixed.{pname}")
        put(name, float(v) * scale, f"stages.{stage_id}.fixed.{pname}")
    factors = stage["factors"]
    for letter, v in levels.items():
        if letter not in factors:
            raise InputError(path, f"stages.{stage_id}.factors",
                             f"one of the factors {', '.join(factors)}", letter)
        where = f"stages.{stage_id}.factors.{letter}"
        name, scale = field_of(factors[letter]["parameter"], where)
        if coded:
            f = factors[letter]
            if f.get("low") is None or f.get("high") is None:
                raise InputError(path, where, "low and high levels to decode a coded table", f)
            v = float(coded_to_actual([float(v)], [f["low"]], [f["high"]])[0])
        put(name, float(v) * scale, where)
    return DemParams.from_mapping(values, str(path), base=base)


def sauter_radius(dist) -> float:
    """Surface-volume mean radius r32 = <r^3>/<r^2> of a radius distribution.

    :class:`UniformRadius` (uniform by number on [a, b]): (b^4 - a^4)/4 / ((b^3 - a^3)/3).
    :class:`PSD` (mass fractions f_k; within a bin [a, b] the factory draws radii with
    number density ~ r^-3, i.e. mass uniform in r): r32 = 1 / sum_k f_k <1/r>_k with
    <1/r>_k = ln(b/a)/(b - a), or 1/a for a discrete size.
    """
    from soilcal.dem.factories import PSD, UniformRadius

    if isinstance(dist, UniformRadius):
        a, b = float(dist.r_min), float(dist.r_max)
        if b <= a * (1 + 1e-12):
            return a
        return 0.75 * (b**4 - a**4) / (b**3 - a**3)
    if isinstance(dist, PSD):
        a = np.asarray(dist.lower, np.float64)
        b = np.asarray(dist.upper, np.float64)
        f = np.asarray(dist.mass_fraction, np.float64)
        disc = b <= a * (1 + 1e-12)
        inv = np.where(disc, 1.0 / a, np.log(b / a) / np.where(disc, 1.0, b - a))
        return float(1.0 / np.sum(f * inv))
    raise TypeError(f"no Sauter radius for {type(dist).__name__}")


def cohesion_scale(model, reference, setup: dict | None = None,
                   source: str = "<input>") -> float:
    """Surface-energy factor r32(model) / r32(reference) (module docstring), or 1 when the
    setup sets ``scale_cohesion`` to false or there is no reference."""
    check_scale_cohesion(setup or {}, source)
    if not (setup or {}).get("scale_cohesion", SCALE_COHESION) or reference is None:
        return 1.0
    return sauter_radius(model) / sauter_radius(reference)


def paper_psd(setup: dict, source: str = "<input>"):
    """The setup's ``paper_psd`` rows ``[radius_m, mass_percent]`` as a discrete-size
    :class:`soilcal.dem.factories.PSD` (percentages renormalised)."""
    from soilcal.dem.factories import PSD

    rows = setup.get("paper_psd")
    check(isinstance(rows, (list, tuple)) and len(rows) >= 1, source, "setup.paper_psd",
          "a list of [radius_m, mass_percent] rows", rows)
    r = np.array([float(a) for a, _ in rows])
    p = np.array([float(b) for _, b in rows])
    check(np.all(r > 0) and np.all(p >= 0) and p.sum() > 0, source, "setup.paper_psd",
          "radii > 0 m and mass percentages >= 0", rows)
    return PSD(tuple(r), tuple(r), tuple(p / p.sum()))


def paper_cohesion(setup: dict, model, source: str = "<input>") -> float:
    """:func:`cohesion_scale` of the ``model`` radius distribution against the setup's
    ``paper_psd`` (1 when the setup has none)."""
    ref = paper_psd(setup, source) if setup.get("paper_psd") else None
    return cohesion_scale(model, ref, setup, source)


def check_discretisation(setup: dict, source: str) -> None:
    """Validate the optional discretisation keys of a bench-top setup: ``n_particles``
    (integer >= 20), ``radius`` (> 0), ``stiffness_scale`` (in (0, 1000]) and
    ``dt_fraction`` (in (0, 1]); None means the preset's value; ``rolling_model``
    (:data:`ROLLING_MODELS`, None for :data:`DEFAULT_ROLLING`)."""
    n = setup.get("n_particles")
    if n is not None:
        check(isinstance(n, (int, np.integer)) and not isinstance(n, bool) and n >= 20, source,
              "setup.n_particles", "an integer >= 20 (or None for the preset)", n)
    setup_number(setup, "radius", source, allow_none=True)
    s = setup_number(setup, "stiffness_scale", source, allow_none=True)
    if s is not None:
        check(s <= 1000, source, "setup.stiffness_scale", "a factor in (0, 1000]", s)
    f = setup_number(setup, "dt_fraction", source, allow_none=True)
    if f is not None:
        check(f <= 1.0, source, "setup.dt_fraction", "a fraction of the Rayleigh time in (0, 1]", f)
    check_scale_cohesion(setup, source)
    check_rolling(setup, source)


#: the named setups' value of ``scale_cohesion`` (module docstring, "Cohesion scaling")
SCALE_COHESION = True


def check_scale_cohesion(setup: dict, source: str) -> None:
    """``setup.scale_cohesion``: true (the particle-size rule, the default) or false."""
    flag = setup.get("scale_cohesion", SCALE_COHESION)
    check(isinstance(flag, (bool, np.bool_)), source, "setup.scale_cohesion", "true or false", flag)


def build_materials(params: DemParams, stiffness_scale: float = 1.0,
                    source: str = "<input>", cohesion_scale: float = 1.0) -> MaterialTable:
    """MaterialTable with materials "soil", "steel" and pairs soil-soil, soil-steel.

    Shear moduli are multiplied by ``stiffness_scale`` (s) and the surface energies become
    gamma s^(2/5) (vineyard-soil paper's rule for the scaled model, see module docstring),
    times ``cohesion_scale`` (particle-size rule, module docstring).
    """
    s = float(stiffness_scale)
    if not (math.isfinite(s) and 0.0 < s <= 1.0e3):
        raise InputError(source, "stiffness_scale", "a shear-modulus factor in (0, 1000]",
                         stiffness_scale)
    c = float(cohesion_scale)
    if not (math.isfinite(c) and c > 0.0):
        raise InputError(source, "cohesion_scale", "a surface-energy factor > 0", cohesion_scale)
    mats = MaterialTable(source=source)
    mats.add(Material("soil", density=params.soil_density, poisson=params.soil_poisson,
                      shear=params.soil_shear_modulus * s, source=source))
    mats.add(Material("steel", density=params.steel_density, poisson=params.steel_poisson,
                      shear=params.steel_shear_modulus * s, source=source))
    g = s ** 0.4 * c
    mats.set_pair("soil", "soil", restitution=params.soil_soil_restitution,
                  friction=params.soil_soil_static_friction,
                  rolling_friction=params.soil_soil_rolling_friction,
                  surface_energy=params.soil_soil_surface_energy * g,
                  plasticity=params.soil_soil_plasticity)
    mats.set_pair("soil", "steel", restitution=params.soil_steel_restitution,
                  friction=params.soil_steel_static_friction,
                  rolling_friction=params.soil_steel_rolling_friction,
                  surface_energy=params.soil_steel_surface_energy * g)
    # walls never touch each other; the engine's table still wants every pair
    mats.set_pair("steel", "steel", restitution=0.5, friction=0.3)
    return mats


#: Rolling-resistance models a setup may choose (``rolling_model``; contact.py documents each)
ROLLING_MODELS = tuple(k for k in ROLLING if k != "none")
DEFAULT_ROLLING = "constant_torque"


def contact_model(params: DemParams, rolling: str | None = None, conventions=None) -> dict:
    """Engine contact model: Hertz-Mindlin (the plastic ``eepa`` normal law when the
    soil-soil plasticity ratio is > 0), rolling resistance (``rolling``, default
    :data:`DEFAULT_ROLLING`), JKR when any energy > 0, with the ``conventions`` of a setup's
    ``contact_conventions`` (:func:`conventions_of`; EDEM's when None: the surface energy's
    pull-off 1.5 pi gamma R*, the rolling torque on the particle's own lever and the total
    normal force, as the papers use EDEM)."""
    jkr = params.soil_soil_surface_energy > 0 or params.soil_steel_surface_energy > 0
    normal = "eepa" if params.soil_soil_plasticity > 0 else "hertz"
    return dict(normal=normal, rolling=rolling or DEFAULT_ROLLING, cohesion="jkr" if jkr else "none",
                **conventions_of(conventions))


def conventions_of(value, source: str = "<input>") -> dict:
    """A setup's ``contact_conventions`` as :func:`soilcal.dem.contact.model_codes` keywords:
    None (EDEM's), the name of a set (``edem``, ``liggghts``, ``lammps``), or a mapping with an
    optional ``conventions`` set and single entries (any key of
    :data:`soilcal.dem.contact.CONVENTION_TABLES`: ``rolling_lever``, ``rolling_force``,
    ``rolling_axis``, ``tangential_damping``, ``rolling_wall``, ``jkr_convention``,
    ``jkr_break``, ``coulomb_force``, ``tangential_slip``, ``history_rotation``,
    ``contact_lever``, ``jkr_approach``, ``wall_curvature``, ``epsd_form``) that change it."""
    from soilcal.dem.contact import resolve_conventions

    named = isinstance(value, str)
    if value is None or named:
        value = {"conventions": value or "edem"}
    check(isinstance(value, dict), source, "setup.contact_conventions",
          "the name of a set of conventions or a mapping of them", value)
    value = dict(value)
    name = value.pop("conventions", "edem")
    try:
        out = resolve_conventions(name, source, **value)
    except InputError as exc:
        field = ("setup.contact_conventions" if named else
                 exc.field.replace("contact_model", "setup.contact_conventions"))
        raise InputError(source, field, exc.expected, exc.got) from None
    return dict(out, conventions=name)


def check_rolling(setup: dict, source: str) -> None:
    """``setup.rolling_model``: one of :data:`ROLLING_MODELS` or None (the default);
    ``setup.contact_conventions``: :func:`conventions_of`."""
    m = setup.get("rolling_model")
    check(m is None or m in ROLLING_MODELS, source, "setup.rolling_model",
          f"one of {', '.join(ROLLING_MODELS)} (or None for {DEFAULT_ROLLING})", m)
    conventions_of(setup.get("contact_conventions"), source)


def check(ok, source, field, expected, got=None) -> None:
    """Raise InputError(source, field, expected, got) unless ``ok`` (validation before a run)."""
    if not ok:
        raise InputError(source, field, expected, got)


def setup_number(setup, key, source, lo=0.0, inclusive=False, allow_none=False):
    """``setup[key]`` as a finite float above ``lo`` (at least ``lo`` if ``inclusive``), or
    None when missing and ``allow_none``; otherwise InputError naming ``setup.<key>``."""
    v = setup.get(key)
    if v is None and allow_none:
        return None
    try:
        x = float(v)
    except (TypeError, ValueError):
        raise InputError(source, f"setup.{key}", "a number", v) from None
    ok = math.isfinite(x) and (x >= lo if inclusive else x > lo)
    check(ok, source, f"setup.{key}", f"a finite number {'>=' if inclusive else '>'} {lo:g}", v)
    return x


def rng(seed, stream: str = "") -> np.random.Generator:
    """A numpy Generator seeded by (seed, stream) so independent choices use separate streams."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InputError("<input>", "seed", "an integer >= 0", seed)
    words = [int(seed)] + [ord(c) for c in stream]
    return np.random.default_rng(np.random.SeedSequence(words))


def stable_mean(t, y, t_start, t_end=None) -> tuple[float, float]:
    """Mean and sample SD of y over t_start <= t <= t_end (the stable stage)."""
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    if t.shape != y.shape[:1]:
        raise InputError("<input>", "stable_mean.y", f"{t.shape[0]} samples like t", y.shape)
    hi = np.inf if t_end is None else float(t_end)
    sel = (t >= float(t_start)) & (t <= hi)
    if sel.sum() < 2:
        raise InputError("<input>", "stable_mean.t_start",
                         f"a window holding at least 2 samples (t in [{t.min() if t.size else 'n/a'}, "
                         f"{t.max() if t.size else 'n/a'}])", (t_start, t_end))
    ys = y[sel]
    mean, sd = ys.mean(axis=0), ys.std(axis=0, ddof=1)
    if ys.ndim == 1:
        return float(mean), float(sd)
    return mean, sd


def merge_setup(setups: dict, name: str, overrides: dict | None, source: str) -> dict:
    """A named setup with user overrides (keys must exist in the named setup)."""
    if name not in setups:
        raise InputError(source, "setup", f"one of {', '.join(sorted(setups))}", name)
    out = dict(setups[name])
    for k, v in (overrides or {}).items():
        if k not in out:
            raise InputError(source, f"setup.{k}", f"one of {', '.join(sorted(out))}", k)
        out[k] = v
    out["name"] = out.get("name", name)
    if overrides:
        # keys the user set keep their value under every preset, even when equal to the default
        out["overrides"] = sorted(set(out.get("overrides", [])) | set(overrides))
    return out


@dataclass
class Result:
    """One scenario run: identity, cost, inputs and responses."""

    scenario: str
    preset: str
    seed: int
    n_particles: int
    steps: int
    sim_time_s: float
    wall_s: float
    threads: int
    params: dict = field(default_factory=dict)
    setup: dict = field(default_factory=dict)
    responses: dict = field(default_factory=dict)
    series: dict = field(default_factory=dict)
    per_run: list = field(default_factory=list)

    def row(self) -> dict:
        out = dict(scenario=self.scenario, preset=self.preset, seed=int(self.seed),
                   n_particles=int(self.n_particles), steps=int(self.steps),
                   sim_time_s=float(self.sim_time_s), wall_s=float(self.wall_s),
                   threads=int(self.threads))
        for k, v in self.params.items():
            out[f"p:{k}"] = v
        for k, v in self.setup.items():
            if isinstance(v, (bool, int, float, str, np.integer, np.floating)) or v is None:
                out[f"s:{k}"] = v.item() if isinstance(v, np.generic) else v
            elif k == "contact_conventions" and isinstance(v, dict):
                out[f"s:{k}"] = ";".join(f"{a}={b}" for a, b in sorted(v.items()))
        for k, v in self.responses.items():
            out[f"r:{k}"] = v.item() if isinstance(v, np.generic) else v
        return out


def write_row(path, result: Result) -> Path:
    """Write ``result.row()`` as a one-row CSV (header + values), atomically."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    row = result.row()
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(row), lineterminator="\n")
    w.writeheader()
    w.writerow(row)
    return write_text(path, buf.getvalue())


def run_replicates(module, setup: dict, params: DemParams, preset: str = "quick", seed: int = 0,
                   replicates: int = 1, threads=None, vtk_dir=None,
                   source: str = "<input>", restart_dir=None, restart_every: float = 300.0,
                   log=print) -> Result:
    """Run a scenario ``replicates`` times with the seeds seed, seed + 1, ... and average.

    One run is returned as it is.  Several runs give one :class:`Result` (see
    :func:`combine_replicates`); VTK frames of each go to ``<vtk_dir>/seed<s>``.  With
    ``restart_dir``, a scenario that supports restart files (:mod:`soilcal.dem.restart`)
    keeps one per seed there, ``<name>-seed<s>.restart``, written every ``restart_every``
    seconds of wall time and resumed from when the run is started again; a scenario that
    does not runs from its start (``log`` says so).
    """
    from soilcal.dem import restart as rst

    check(isinstance(replicates, (int, np.integer)) and not isinstance(replicates, bool)
          and replicates >= 1, source, "replicates", "an integer >= 1", replicates)
    check(isinstance(seed, (int, np.integer)) and not isinstance(seed, bool) and seed >= 0,
          source, "seed", "an integer >= 0", seed)
    use = restart_dir is not None and rst.supports(module)
    if restart_dir is not None and not use:
        log(f"restart files: the {module.NAME} scenario does not write them; it runs from its start")
    runs = []
    for s in range(int(seed), int(seed) + int(replicates)):
        vdir = vtk_dir if vtk_dir is None or replicates == 1 else Path(vtk_dir) / f"seed{s}"
        kw = {}
        if use:
            ident = dict(scenario=module.NAME, setup=setup, params=params.as_dict(),
                         preset=preset, seed=s)
            kw["restart"] = rst.Restart(Path(restart_dir) / f"{module.NAME}-seed{s}.restart",
                                        ident, restart_every, log=log)
        runs.append(module.run(setup, params, preset=preset, seed=s, threads=threads,
                               vtk_dir=vdir, **kw))
    return runs[0] if replicates == 1 else combine_replicates(runs)


def _is_number(v) -> bool:
    return isinstance(v, (bool, int, float, np.bool_, np.integer, np.floating))


MAX_OVER_RUNS = ("peak_overlap",)  # combined over replicates by their maximum


def combine_replicates(runs) -> Result:
    """One :class:`Result` from runs that differ only in their seed (same scenario, preset,
    parameters, setup keys and text setup values).

    Numeric responses become the mean over the runs (the peaks of ``MAX_OVER_RUNS``, e.g.
    ``peak_overlap``, their maximum), with the sample standard deviation (ddof = 1) of the
    runs as ``<response>_rep_sd`` (the standard error of the mean is that over
    sqrt(replicates)); 0/1 flags such as ``settled`` become the fraction of runs.  A
    response that is NaN in any run (e.g. an incline onset never reached) is NaN in the
    mean: averaging the other runs would bias it.  A text response keeps its value when all
    runs agree and lists the distinct values joined by ``|`` otherwise.  Numeric setup values
    that a run derives from its own particles (the time step from the smallest sphere drawn,
    the fill height) differ between seeds and are averaged too.  Steps, simulated and wall
    time are summed; the particle count is the mean, rounded.  The setup gains
    ``replicates`` and ``replicate_seeds`` (space separated); time series are kept per run
    as ``seed<s>:<name>``; ``per_run`` holds each run's responses.
    """
    runs = list(runs)
    check(len(runs) >= 2, "<input>", "runs", "at least two runs", len(runs))
    first = runs[0]
    for r in runs[1:]:
        same = (r.scenario == first.scenario and r.preset == first.preset
                and r.params == first.params and set(r.setup) == set(first.setup)
                and set(r.responses) == set(first.responses)
                and all(_is_number(v) or str(v) == str(r.setup[k])
                        for k, v in first.setup.items()))
        check(same, "<input>", "runs", f"runs of {first.scenario} ({first.preset}) that "
              "differ only in the seed", f"{r.scenario} ({r.preset}), seed {r.seed}")
    seeds = [int(r.seed) for r in runs]
    check(len(set(seeds)) == len(seeds), "<input>", "seeds", "distinct seeds", seeds)
    resp = {}
    for key in first.responses:
        vals = [r.responses[key] for r in runs]
        if all(_is_number(v) for v in vals):
            arr = np.asarray(vals, dtype=float)
            # a peak over runs is their largest peak, not their mean
            resp[key] = float(arr.max()) if key in MAX_OVER_RUNS else float(arr.mean())
            resp[f"{key}_rep_sd"] = float(arr.std(ddof=1))
        else:
            uniq = sorted({str(v) for v in vals})
            resp[key] = uniq[0] if len(uniq) == 1 else "|".join(uniq)
    setup_out = dict(first.setup)
    for key, v in first.setup.items():
        vals = [r.setup[key] for r in runs]
        if all(_is_number(u) for u in vals) and any(u != v for u in vals):
            setup_out[key] = float(np.mean(vals))
    setup_out.update(replicates=len(runs), replicate_seeds=" ".join(str(s) for s in seeds))
    series = {f"seed{r.seed}:{k}": v for r in runs for k, v in r.series.items()}
    return Result(scenario=first.scenario, preset=first.preset, seed=seeds[0],
                  n_particles=int(round(np.mean([r.n_particles for r in runs]))),
                  steps=int(sum(r.steps for r in runs)),
                  sim_time_s=float(sum(r.sim_time_s for r in runs)),
                  wall_s=float(sum(r.wall_s for r in runs)),
                  threads=first.threads, params=dict(first.params), setup=setup_out,
                  responses=resp, series=series,
                  per_run=[dict(seed=int(r.seed), **r.responses) for r in runs])


def threads_used(threads, source: str = "<input>", field: str = "threads") -> int:
    """Set numba's thread count (None: keep the current one); returns the count in use.
    ``source`` and ``field`` name where a bad count came from."""
    import numba

    if threads is not None:
        ok = isinstance(threads, (int, np.integer)) and not isinstance(threads, bool)
        t = int(threads) if ok else 0
        check(ok and 1 <= t <= numba.config.NUMBA_NUM_THREADS, source, field,
              f"an integer in [1, {numba.config.NUMBA_NUM_THREADS}]", threads)
        numba.set_num_threads(t)
    return int(numba.get_num_threads())


# ---------------------------------------------------------------- presets and run helpers
#: Preset defaults shared by the scenarios (each scenario adds its own sizes):
#:
#: * ``quick``: soil shear modulus reduced to at most ``g_max`` = 5e5 Pa (stiffness scaling
#:   with the surface-energy rule above), time step 30 % of the Rayleigh time (the upper end
#:   of the 10-30 % the vineyard-soil paper recommends), about ``n_particles`` spheres.
#:   The vineyard-soil paper keeps scaled moduli above 1e7 Pa (after Lommen et al.); the
#:   quick preset departs from that limit for speed, which the convergence study
#:   (benchmarks/convergence.py, stiffness factor) quantifies.  The soil-bin scenarios
#:   (furrow, bulldozing, rotary) set their own ``stiffness_scale`` in their presets
#:   (the papers' moduli in ``quick``, benchmarks/convergence_tools.py);
#: * ``paper``: unscaled moduli, time step 20 % of the Rayleigh time (003: "20 % of the
#:   Rayleigh time step"; 004 Sec. 2.6: "fixed simulation time step of 20 %"), the papers'
#:   particle sizes.
#:
#: Either step is capped at the JKR bound and at 0.7 x the damped-contact bound
#: (materials.py), as 30 % blew up heaps of heavily damped spheres: with friction on steel
#: walls the quick step is at most 0.28 T_R (0.15 T_R at e = 0.15), and the paper step is
#: below 20 % for restitution below about 0.5.
PRESET_DEFAULTS = {
    "quick": dict(g_max=5.0e5, dt_fraction=0.3, n_particles=1000, max_overlap=0.3),
    "paper": dict(g_max=None, dt_fraction=0.2, n_particles=None, max_overlap=0.3),
}


def check_preset(preset, source="<input>") -> dict:
    check(preset in PRESETS, source, "preset", f"one of {PRESETS}", preset)
    return PRESET_DEFAULTS[preset]


def stiffness_scale_for(params: DemParams, preset: str, override=None) -> float:
    """Shear-modulus factor: the override if given, else the preset's cap g_max / G_soil."""
    if override is not None:
        return float(override)
    g_max = PRESET_DEFAULTS[preset]["g_max"]
    if g_max is None:
        return 1.0
    return min(1.0, g_max / params.soil_shear_modulus)


def make_simulation(params: DemParams, setup: dict, preset: str, source: str,
                    cohesion: float = 1.0, **kw):
    """Simulation with the scenario materials, Hertz-Mindlin + the setup's rolling model
    (``rolling_model``, default constant torque), JKR when a surface energy is > 0, and the
    preset's time step; surface energies times ``cohesion`` (:func:`cohesion_scale`);
    returns (sim, scale)."""
    from soilcal.dem.engine import Simulation

    d = PRESET_DEFAULTS[preset]
    scale = stiffness_scale_for(params, preset, setup.get("stiffness_scale"))
    mats = build_materials(params, scale, source, cohesion)
    dtf = setup.get("dt_fraction") or d["dt_fraction"]
    sim = Simulation(mats, dt_fraction=float(dtf),
                     contact_model=contact_model(params, setup.get("rolling_model"),
                                                 setup.get("contact_conventions")),
                     max_overlap=d["max_overlap"], source=source, **kw)
    return sim, scale


def rest_tolerance(sim, rest_speed: float, mask=None) -> float:
    """Kinetic-energy threshold 1/2 M v_rest^2 of the (masked) particles [J]."""
    m = sim.p.m if mask is None else sim.p.m[mask]
    return 0.5 * float(np.sum(m)) * rest_speed**2


def settle(sim, rest_speed: float, max_time: float, check_every: int = 200) -> tuple[bool, float]:
    """Run until the translational kinetic energy is below 1/2 M v_rest^2 or ``max_time``
    seconds have passed; returns (settled, simulated seconds).  The rest loop of the
    scenarios (:func:`soilcal.dem.restart.settle`), without a restart file."""
    from soilcal.dem import restart

    return restart.settle(sim, rest_speed, max_time, {}, "steps", None, check_every)


def run_time(sim, seconds: float) -> int:
    """Advance ``seconds`` of simulated time (at least one step); returns steps done."""
    if sim.dt is None:
        sim.run(0)
    return sim.run(max(1, int(round(seconds / sim.dt))))


class Frames:
    """Optional VTK output: particle frames (``frame_NNNN.vtu``) and a ``frames.pvd``."""

    def __init__(self, vtk_dir, name: str):
        self.dir = Path(vtk_dir) if vtk_dir else None
        self.name = name
        self.entries = []
        if self.dir is not None:
            self.dir.mkdir(parents=True, exist_ok=True)

    def __call__(self, sim, label: str = ""):
        if self.dir is None:
            return
        from soilcal.dem.io import write_particles_vtu

        k = len(self.entries)
        path = self.dir / f"{self.name}_{k:04d}.vtu"
        write_particles_vtu(path, sim.x, sim.p.r, sim.v, sim.omega, sim.p.mat, ids=sim.p.id)
        self.entries.append((sim.step * (sim.dt or 0.0), path))

    def close(self):
        if self.dir is not None and self.entries:
            from soilcal.dem.io import write_pvd

            write_pvd(self.dir / f"{self.name}.pvd", self.entries)
