"""The effect library: physical mechanisms a calibrated soil model lacks, as switchable extensions.

A DEM calibrated on one or two bench tests (a heap, a drum) holds its contact parameters
constant; field and soil-bin measurements vary tool speed, working depth, moisture and tool,
and a mechanism the bench test did not exercise shows up as a residual that follows one of
them.  Each :class:`Effect` here is one such mechanism with one or two parameters
(``theta``), a formula that maps the calibrated DEM parameters of a measured condition onto
the parameters the mechanism implies at that condition's covariates, a *signature* (the
quantities of :data:`soilcal.config.measurements.QUANTITIES` through which it acts, plus
``bias`` for one that moves every row the same way and ``measure`` for one that moves the
measured quantities of a table differently), the value of ``theta`` at which it is switched
off (``null``), and a source.

Every effect acts on the :class:`~soilcal.dem.scenarios.base.DemParams` of a run, so that a
switched-on effect is a DEM run like any other (same scenario, setup and seeds).  A
covariate an effect needs is taken relative to a *reference*: the value at which the
calibrated parameters hold (the soil's ``loop.reference`` entry, else the mean of the
measured conditions, recorded in the loop's outputs).  An effect may act on the conditions
of some scenarios only (``scenarios``; empty: every scenario): a condition of another
scenario keeps its calibrated parameters (:meth:`Effect.applies_to`, :meth:`Effect.apply`).

The formulas (``x`` the condition's value, ``x0`` the reference; clamped to each
parameter's physical range, :data:`soilcal.dem.scenarios.base._RANGES`):

``moisture_cohesion`` (theta: ``c_w`` in J/m^2 per percentage point)
    gamma_ss(w) = gamma_ss,cal + c_w (w - w0), at least 0.
    Capillary liquid bridges hold wet grains together; for a pendular bridge between two
    equal spheres at contact the force is 2 pi R gamma_lv cos(theta) (Willett, Adams, Johnson
    & Seville, Langmuir 16 (2000) 9396, Eq. 5 at zero separation) and the share of contacts
    that carry a bridge grows with the water content.  EDEM soil models carry this as a JKR
    surface energy re-calibrated per moisture (the Guangxi cohesive soil study calibrates
    one at each of five moisture contents); the first-order term of that dependence around
    the calibrated moisture is the effect.  Signature: ``moisture_content``.

``rate_friction`` (theta: ``beta``, per e-fold of speed)
    mu(v) = mu_cal (1 + beta ln(v / v0)), at least 0, for the soil-soil and the soil-steel
    sliding friction.  The logarithmic rate term of rate-and-state friction (Dieterich,
    J. Geophys. Res. 84 (1979) 2161; Ruina, J. Geophys. Res. 88 (1983) 10359), the form in which
    soils' shear strength rises with the shearing rate (about 10 % per log10 cycle in clays:
    Graham, Crooks & Bell, Geotechnique 33 (1983) 327).  The field evidence is the speed term
    of tillage draft (ASABE D497: draft = F_i (A + B S + C S^2) W T).  ``v`` is the tool
    speed, or the rotor speed of a rotary tool (its blade-tip speed is proportional to it).
    Signature: ``tool_speed``, ``rotor_speed``.

``depth_compaction`` (theta: ``g``, relative density change per relative depth change)
    f = 1 + g (d / d0 - 1), at least 0.1; rho(d) = f rho_cal, G(d) = f^2 G_cal.
    Soil beds are denser at depth (self-weight and traffic compaction); the worked layer's
    mean bulk density is carried by the particle density (the packing is kept) and the
    stiffness rises with the square of the density, the exponent of small-strain soil
    stiffness in the void ratio function of Hardin & Black (J. Soil Mech. Found. Div. 94 (1968)
    353) over the range of agricultural soils.  ``d`` is the working depth or the layer depth.
    Signature: ``working_depth``, ``layer_depth``.

``tool_adhesion`` (theta: ``gamma_a`` in J/m^2)
    gamma_st = gamma_st,cal + gamma_a: JKR adhesion on the soil-steel contact (Johnson,
    Kendall & Roberts, Proc. R. Soc. A 324 (1971) 301; pull-off 1.5 pi gamma R*), the soil
    sticking to the tool that a heap on a plate does not exercise.  It moves the tool forces
    of every condition, more where the contact area is larger.  Signature: ``tool``,
    ``bias``, and the working (layer) depth and the tool (rotor) speed: the adhesion adds a
    force in proportion to the contact area, b d c_a on a blade, while the soil's own
    resistance grows faster with depth (its weight, ~d^2) and with speed (the soil
    accelerated, ~v^2), so its share of the force falls with both; under a calibration
    offset that cancels its mean (a load cell reading 8 % low) that fall is all of its
    structure the diagnosis sees.

``plastic_contact`` (theta: ``lambda_p``, the contact plasticity ratio; compression tests only)
    lambda_p,ss = lambda_p,cal + lambda_p, clamped to [0, 0.95] (``soil_soil_plasticity``; a
    parameter set without it is elastic, 0).  Above 0 the soil-soil contacts follow the
    plastic Hertz law ``eepa`` of :mod:`soilcal.dem.contact`: a contact loads on Hertz's
    k1 delta^1.5 and unloads and reloads on k2 (delta^1.5 - lambda_p delta_max^1.5) with
    k2 = k1 / (1 - lambda_p), the force 0 below the plastic overlap lambda_p^(2/3) delta_max
    (the Edinburgh elasto-plastic model, EEPA, in its non-adhesive form with the Hertz
    exponent n = 3/2: Thakur, Morrissey, Sun, Chen & Ooi, Granular Matter 16 (2014) 383,
    Eqs. 1-2; Morrissey, PhD thesis, University of Edinburgh, 2013): soil aggregates deform
    plastically at their contacts and give back only part of a compression: the strain a
    confined compression sample recovers when the rod is withdrawn shows it
    (``recovered_strain``; smaller by the factor 1 - lambda_p^(2/3) for an affine packing,
    :mod:`soilcal.loop.standin`), more plainly than the loading stresses, which move
    through the way the bed settles and rearranges (:mod:`soilcal.dem.scenarios.compression`).
    So the effect acts on compression tests only (scenarios ``compression`` and the
    stand-in's ``standin_compression``), where it moves the measured quantities by
    different amounts.  Signature: ``measure`` (the
    diagnosis's group test over the measured quantities of a table,
    :mod:`soilcal.loop.diagnose`), ``bias``.

:data:`EFFECTS` maps names to effects; :func:`get` refuses an unknown name with the list.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from soilcal.dem.scenarios.base import _RANGES
from soilcal.errors import InputError

#: DemParams limits the effects respect (low, high) by parameter kind: the physical range of each
#: kind (soilcal.dem.scenarios.base._RANGES), not a soil's plausibility bounds (SOIL_RANGES), which
#: judge the values a user types: an effect may take a calibrated friction of 1.9 past 2 at speed
_LIMITS = {"surface_energy": _RANGES["surface_energy"][:2], "static_friction": _RANGES["static_friction"][:2],
           "density": _RANGES["density"][:2], "shear_modulus": (1.0, _RANGES["shear_modulus"][1]),
           "plasticity": (0.0, 0.95)}


def _clamp(x: float, kind: str) -> float:
    lo, hi = _LIMITS[kind]
    return min(max(float(x), lo), hi)


@dataclass(frozen=True)
class Effect:
    """One mechanism: its parameters (name -> (unit, default bounds)), null values, signature."""

    name: str
    title: str
    params: dict          # theta name -> (unit, (low, high))
    null: dict            # theta name -> value that switches the effect off
    signature: tuple      # quantities (and "bias") through which it acts
    needs: tuple          # quantities a condition must carry for the effect to act on it
    formula: str
    source: str
    changes: tuple = field(default=())  # DemParams names it changes
    scenarios: tuple = field(default=())  # scenarios whose conditions it acts on (empty: every scenario)
    #: theta name -> (low, high): the physical range of a parameter where the library states
    #: one (a bound of ``loop.bounds`` outside it is refused); a parameter not listed has none
    ranges: dict = field(default_factory=dict)

    def theta_names(self) -> tuple[str, ...]:
        return tuple(self.params)

    def bounds(self, overrides: dict | None = None) -> dict[str, tuple[float, float]]:
        out = {k: tuple(map(float, v[1])) for k, v in self.params.items()}
        for k, v in (overrides or {}).items():
            out[k] = (float(v[0]), float(v[1]))
        return out

    def is_null(self, theta: dict) -> bool:
        """Whether ``theta`` switches the effect off."""
        return all(float(theta[k]) == float(self.null[k]) for k in self.params)

    def acts_in(self, scenario: str | None) -> bool:
        """Whether the effect acts on conditions of ``scenario`` (None: a scenario not known,
        on which an effect restricted to some scenarios does not act)."""
        return not self.scenarios or scenario in self.scenarios

    def applies_to(self, quantities: dict, scenario: str | None = None) -> bool:
        """Whether a condition of ``scenario`` carrying these quantities is changed by the
        effect at all."""
        return self.acts_in(scenario) and (not self.needs or any(q in quantities for q in self.needs))

    def apply(self, params: dict, quantities: dict, theta: dict, reference: dict,
              scenario: str | None = None) -> dict:
        """The DEM parameters (name -> SI value) of a condition of ``scenario`` with the effect
        switched on (a copy of ``params`` where the effect does not act on the scenario)."""
        if not self.acts_in(scenario):
            return dict(params)
        fn = _APPLY[self.name]
        return fn(dict(params), quantities, {k: float(theta.get(k, self.null[k])) for k in self.params}, reference)


def _ref(quantities: dict, reference: dict, names) -> tuple[float, float] | None:
    for q in names:
        if q in quantities and q in reference:
            return float(quantities[q]), float(reference[q])
    return None


def _moisture(params, quantities, theta, reference):
    xr = _ref(quantities, reference, ("moisture_content",))
    if xr is None:
        return params
    w, w0 = xr
    params["soil_soil_surface_energy"] = _clamp(params["soil_soil_surface_energy"] + theta["c_w"] * (w - w0),
                                                "surface_energy")
    return params


def _rate(params, quantities, theta, reference):
    xr = _ref(quantities, reference, ("tool_speed", "rotor_speed"))
    if xr is None:
        return params
    v, v0 = xr
    if v <= 0 or v0 <= 0:
        raise InputError("<loop>", "rate_friction", "a positive speed and reference speed", (v, v0))
    f = 1.0 + theta["beta"] * math.log(v / v0)
    for k in ("soil_soil_static_friction", "soil_steel_static_friction"):
        params[k] = _clamp(params[k] * f, "static_friction")
    return params


def _depth(params, quantities, theta, reference):
    xr = _ref(quantities, reference, ("working_depth", "layer_depth"))
    if xr is None:
        return params
    d, d0 = xr
    if d0 <= 0:
        raise InputError("<loop>", "depth_compaction", "a positive reference depth", d0)
    f = max(1.0 + theta["g"] * (d / d0 - 1.0), 0.1)
    params["soil_density"] = _clamp(params["soil_density"] * f, "density")
    params["soil_shear_modulus"] = _clamp(params["soil_shear_modulus"] * f * f, "shear_modulus")
    return params


def _adhesion(params, quantities, theta, reference):
    params["soil_steel_surface_energy"] = _clamp(params["soil_steel_surface_energy"] + theta["gamma_a"],
                                                 "surface_energy")
    return params


def _plastic(params, quantities, theta, reference):
    key = "soil_soil_plasticity"
    cal = float(params.get(key, 0.0))  # a parameter set without it: elastic Hertz
    lp = _clamp(cal + theta["lambda_p"], "plasticity")
    if key in params or lp != cal:  # left out where it stays at the elastic default
        params[key] = lp
    return params


_APPLY = {"moisture_cohesion": _moisture, "rate_friction": _rate, "depth_compaction": _depth,
          "tool_adhesion": _adhesion, "plastic_contact": _plastic}

EFFECTS: dict[str, Effect] = {
    "moisture_cohesion": Effect(
        name="moisture_cohesion", title="moisture-dependent cohesion (capillary bridges)",
        params={"c_w": ("J/m^2 per %", (-0.2, 0.2))}, null={"c_w": 0.0},
        signature=("moisture_content",), needs=("moisture_content",),
        formula="gamma_ss(w) = gamma_ss,cal + c_w (w - w0)",
        source="Willett et al., Langmuir 16 (2000) 9396, Eq. 5; surface energy per moisture as in the Guangxi cohesive soil study",
        changes=("soil_soil_surface_energy",)),
    "rate_friction": Effect(
        name="rate_friction", title="rate dependence of soil resistance (log-rate friction)",
        params={"beta": ("-", (-0.3, 0.6))}, null={"beta": 0.0},
        signature=("tool_speed", "rotor_speed"), needs=("tool_speed", "rotor_speed"),
        formula="mu(v) = mu_cal (1 + beta ln(v / v0)), soil-soil and soil-steel",
        source="Dieterich, JGR 84 (1979) 2161; Ruina, JGR 88 (1983) 10359; Graham et al., Geotechnique 33 (1983) 327; ASABE D497",
        changes=("soil_soil_static_friction", "soil_steel_static_friction")),
    "depth_compaction": Effect(
        name="depth_compaction", title="depth-dependent density and stiffness (compaction gradient)",
        params={"g": ("-", (-0.5, 1.0))}, null={"g": 0.0},
        signature=("working_depth", "layer_depth"), needs=("working_depth", "layer_depth"),
        formula="f = 1 + g (d / d0 - 1); rho = f rho_cal; G = f^2 G_cal",
        source="Hardin & Black, J. Soil Mech. Found. Div. 94 (1968) 353 (stiffness with density)",
        changes=("soil_density", "soil_shear_modulus")),
    "tool_adhesion": Effect(
        name="tool_adhesion", title="soil-tool adhesion (JKR on the soil-steel contact)",
        params={"gamma_a": ("J/m^2", (0.0, 3.0))}, null={"gamma_a": 0.0},
        signature=("tool", "bias", "working_depth", "layer_depth", "tool_speed", "rotor_speed"), needs=(),
        formula="gamma_st = gamma_st,cal + gamma_a",
        source="Johnson, Kendall & Roberts, Proc. R. Soc. A 324 (1971) 301",
        changes=("soil_steel_surface_energy",)),
    "plastic_contact": Effect(
        name="plastic_contact", title="plastic soil-soil contacts (elasto-plastic Hertz law, EEPA)",
        params={"lambda_p": ("-", (0.0, 0.9))}, null={"lambda_p": 0.0},
        signature=("measure", "bias"), needs=(),
        formula="lambda_p,ss = lambda_p,cal + lambda_p, in [0, 0.95] (plastic Hertz law eepa)",
        source="Thakur, Morrissey, Sun, Chen & Ooi, Granular Matter 16 (2014) 383, Eqs. 1-2 (non-adhesive, n = 3/2); "
               "Morrissey, PhD thesis, University of Edinburgh (2013)",
        changes=("soil_soil_plasticity",), scenarios=("compression", "standin_compression"),
        ranges={"lambda_p": _LIMITS["plasticity"]}),
}


#: The dose through which an effect of one parameter acts on a condition, where it has one: the
#: effect name -> (form, quantities, z, floor).  ``z`` is the condition's covariate relative to
#: the reference (``"ratio"``: x / x0 - 1; ``"log"``: ln(x / x0); ``"difference"``: x - x0) and
#: the dose at the parameter t is ln(max(1 + t z, floor)) for a ``"factor"`` (the log of the
#: factor the effect multiplies a DEM parameter by: the density factor f of depth_compaction,
#: the friction factor of rate_friction, their floors those of the formulas above, the
#: friction's its limit near 0) or t z for an ``"added"`` quantity (the surface energy
#: moisture_cohesion adds).  The clamps of the DEM parameters to their physical ranges are
#: left out (a surface energy held at 0, a friction at 2): where they act, the rows no longer
#: share the shape, which its lack-of-fit test is there to find.  Every condition then sees the same
#: mechanism at a different strength, which a response shape shared by the conditions can
#: carry (:class:`soilcal.loop.select.PooledSurrogate`).  tool_adhesion and plastic_contact act
#: alike on every condition (no covariate): they have no dose.
DOSES = {"depth_compaction": ("factor", ("working_depth", "layer_depth"), "ratio", 0.1),
         "rate_friction": ("factor", ("tool_speed", "rotor_speed"), "log", 0.05),
         "moisture_cohesion": ("added", ("moisture_content",), "difference", None)}


def dose_z(name: str, quantities: dict, reference: dict) -> float:
    """The covariate term ``z`` of the effect ``name``'s dose (:data:`DOSES`) at a condition
    carrying ``quantities``: 0 where the condition lacks the covariate or its reference (the
    effect leaves it unchanged, :meth:`Effect.apply`)."""
    _, names, kind, _ = DOSES[name]
    xr = _ref(quantities, reference, names)
    if xr is None:
        return 0.0
    x, x0 = xr
    if kind == "ratio":
        return x / x0 - 1.0
    if kind == "log":
        return math.log(x / x0)
    return x - x0


def dose(name: str, t: float, z):
    """The dose of the effect ``name`` at its parameter value ``t`` for the conditions' ``z``
    (:func:`dose_z`; an array): :data:`DOSES`."""
    import numpy as np

    form, _, _, floor = DOSES[name]
    if form == "factor":
        return np.log(np.maximum(1.0 + t * z, floor))
    return t * z


def get(name: str, source="<loop>") -> Effect:
    if name not in EFFECTS:
        raise InputError(source, "loop.effects", "one of " + ", ".join(EFFECTS), name)
    return EFFECTS[name]


def apply_all(effects: dict, params: dict, quantities: dict, reference: dict, scenario: str | None = None) -> dict:
    """Parameters of a condition of ``scenario`` with several effects on (``effects``: name ->
    theta), in library order."""
    out = dict(params)
    for name in EFFECTS:
        if name in effects:
            out = EFFECTS[name].apply(out, quantities, effects[name], reference, scenario)
    return out
