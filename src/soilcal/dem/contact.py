r"""Contact laws, composed by name like LIGGGHTS/LAMMPS ``pair granular``.

A contact model is the tuple (normal, damping, tangential, rolling, cohesion) chosen with
:func:`model_codes`; the kernel :func:`contact_force` evaluates it for one particle of a pair
(the partner evaluates the same pair with n -> -n, which gives exactly the opposite force).

Notation: overlap delta = R_i + R_j - |x_i - x_j| (sphere-wall: R_i - dist), n the unit
normal from partner to particle, v_n = v_rel . n (< 0 when approaching), v_t the tangential
relative velocity at the contact point, a the contact radius.  Effective E*, G*, R*, m* and
beta are defined in :mod:`soilcal.dem.materials`.

Normal, ``hertz`` (Hertz 1882; EDEM Theory Reference Guide, Hertz-Mindlin (no slip))::

    F_n = 4/3 E* sqrt(R*) delta^(3/2),   a = sqrt(R* delta),   S_n = 2 E* a

Normal, ``eepa`` (plastic Hertz: the non-adhesive form of the Edinburgh Elasto-Plastic Adhesion
model, Thakur, Morrissey, Sun, Chen & Ooi 2014, Granul. Matter 16:383, Eqs. 1-2, with pull-off
f_0 = 0, adhesive stiffness k_adh = 0 and the Hertz exponent n = 3/2; Morrissey 2013, PhD
thesis, Univ. of Edinburgh).  With k_1 = 4/3 E* sqrt(R*) (the Hertz loading stiffness), the
contact plasticity ratio lambda_p in [0, 1) of the pair (``PairParams.plasticity``),
k_2 = k_1 / (1 - lambda_p) and delta_max the largest overlap of the contact so far::

    loading (delta >= delta_max):   F_n = k_1 delta^(3/2),  delta_max <- delta
    unloading and reloading:        F_n = max(k_2 (delta^(3/2) - delta_p^(3/2)), 0)
    delta_p^(3/2) = lambda_p delta_max^(3/2)      (the unloading branch meets the loading
                                                   branch at delta_max: k_2 (1 - lambda_p) = k_1)

delta_p is the plastic overlap: the contact carries no load below it.  The contact stays
one contact while delta > 0 (delta_max kept); it ends, and its delta_max with it, when the
surfaces part.  The dashpot (``damping``) is the Hertz contact's at the same overlap while
the contact carries load and zero where it does not (0 < delta <= delta_p: no spring, so no
viscous tension across a plastic dent).  With ``cohesion: jkr`` the law is added to the JKR
force as the change it makes to its Hertz part, F_n = F_JKR + (F_eepa - k_1 delta^(3/2)) for
delta > 0: loading and the adhesion are JKR's, unloading loses the plastic share of the
repulsion; the contact radius stays the JKR one (EEPA's growth of the adhesion with the
plastic contact area is not modelled).  lambda_p = 0 is Hertz exactly.  Without damping a
head-on impact of two spheres rebounds with the restitution (work recovered on unloading
over work of loading)::

    e^2 = (1 - 5/2 lambda_p + 3/2 lambda_p^(5/3)) / (1 - lambda_p)

independent of the impact speed.  The time step takes the unloading stiffness
S_n / (1 - lambda_p) (materials.py, "Damping bound").

Damping, ``viscoelastic`` (EDEM guide; LIGGGHTS ``model hertz`` with ``tangential history``;
Tsuji et al. 1992, Powder Technol. 71:239 for the delta^(1/4) dependence)::

    F_n^d = -2 sqrt(5/6) |beta| sqrt(S_n m*) v_n,   beta = ln e / sqrt(ln^2 e + pi^2)
    F_t^d = -2 sqrt(5/6) |beta| sqrt(S_t m*) v_t

Damping, ``viscous_radius`` (LAMMPS ``pair granular ... damping viscoelastic``, the damping
its cohesive laws accept: gran_sub_mod_damping.cpp), with a coefficient eta [1/(m s)] given as
the contact model's ``damping_eta`` instead of a restitution::

    F_n^d = -eta m* a v_n,   F_t^d = -sqrt(4 G*/E*) eta m* a v_t

(the tangential ratio damps the tangential mode at the normal mode's damping ratio, as the
``viscoelastic`` law does; the LAMMPS translation passes it as x_gamma,t).  The restitution
this gives depends on the impact speed: it is not a restitution law.

Tangential, ``mindlin`` (Mindlin 1949 no-slip; EDEM guide; LIGGGHTS ``tangential history``)::

    S_t = 8 G* a,   F_t = -S_t xi - F_t^d,   |F_t| <= mu_s |F_n,tot|

with xi the tangential displacement history: every step xi is projected onto the current
tangent plane (xi <- xi - (xi.n) n, as LIGGGHTS ``tangential history``; the length lost is
second order in the rotation per step) and incremented by v_t dt.  When the spring force exceeds the Coulomb limit, xi is shortened so that
|S_t xi| = mu_s |F_n,tot| and F_t = -S_t xi (no damping while sliding), as in LIGGGHTS.
F_n,tot = F_n + F_n^d (plus 2 F_pulloff with JKR, Thornton & Yin 1991, as LAMMPS ``jkr``).
The forces of a run's initial state (no time passes: the first evaluation after particles,
walls or the state changed) use the history as it stands and advance it by nothing (dt = 0
in the kernel), as LAMMPS and LIGGGHTS compute a run's setup without updating their shear
history; every step after that adds v_t dt with the step's half-step velocity.

Rolling, ``constant_torque`` (EDEM rolling friction "type A", Zhou et al. 1999, Physica A
269:536)::

    tau_r,i = -mu_r |F_n,tot| R_i omega_rel / |omega_rel|,   omega_rel = omega_i - omega_j

Rolling, ``epsd`` (elastic-plastic spring-dashpot, "type C", Ai, Chen, Rotter & Ooi 2011,
Powder Technol. 206:269, Eqs. 11-14; undamped, eta_r = 0)::

    k_r = 2.25 k_n mu_r^2 R_r^2 (k_n = S_n, R_r = R*),  M_r <- M_r - k_r dtheta_r,
    dtheta_r = (omega_i - omega_j)_t dt,  |M_r| <= mu_r R_r |F_n,tot|

(Ai et al. write k_n for a linear spring; with Hertz this form takes the tangent stiffness
S_n.  LIGGGHTS's ``rolling_friction epsd`` takes the secant one: ``epsd_form`` below.)

Rolling, ``bounded`` (EDEM's type A torque on each particle's own rotation, bounded so that it
cannot reverse that rotation within a step; Irazabal, Salazar & Onate 2017, "Numerical
modelling of granular materials with spherical discrete particles and the bounded rolling
friction model", Comput. Part. Mech.)::

    M_R,i  = sum over the contacts of i of  mu_r |F_n,tot| c_i     (c_i: centre to contact)
    w*_i   = omega_i + dt T_i / I_i        (rotation at the next force evaluation, T_i: all
                                            other torques on i)
    tau_r,i = -min(M_R,i, I_i |w*_i| / dt) w*_i / |w*_i|

Without the bound this is the type A torque as the EDEM guide writes it, -mu_r F_n R_i
omega_i/|omega_i| with the particle's own angular velocity, summed over its contacts.  The
bound is the torque that stops the rotation within the step: a particle whose resistance
suffices comes to rest exactly, as the continuous law (any torque in [-M_R, M_R] at
omega = 0) allows.  ``constant_torque`` instead flips sign every step at rest, so a heap at
rest keeps an angular jitter of about M_R dt / I and creeps (its angle falls with time).
A wall takes as reaction the share mu_r |F_n| c_i / M_R,i of tau_r,i of each of its contacts;
a partner sphere takes none (the torque acts on each particle's own rotation, as in the EDEM
form), so this model does not conserve angular momentum, and it resists the absolute
rotation: a particle carried round by a rotating wall without rolling on it is resisted
too (the drum scenario refuses it).

Cohesion, ``jkr`` (Johnson, Kendall & Roberts 1971, Proc. R. Soc. A 324:301), written with
the work of adhesion w (energy per unit area to separate the two surfaces)::

    delta = a^2/R* - sqrt(2 pi w a / E*)
    F_n   = 4 E* a^3/(3 R*) - sqrt(8 pi w E* a^3)
    pull-off (force-controlled minimum): F_po = -3/2 pi w R*  at a = (9 pi w R*^2/(8 E*))^(1/3)
    separation (displacement-controlled): a_c = (pi w R*^2 / (8 E*))^(1/3),
        delta_c = delta(a_c) = -3/4 (pi^2 w^2 R* / E*^2)^(1/3)

The contact is formed at delta > 0 and kept on the attractive branch beyond zero overlap
until delta < delta_c (< 0).  S_n = 2 E* a and S_t = 8 G* a use the JKR contact radius.

Conventions for the surface energy gamma given by the user (``jkr_convention``):

* ``"edem"`` (default): w = gamma, so the pull-off force is 1.5 pi gamma R*, as printed in the
  EDEM guide for its "JKR cohesion" (pull-out force -3/2 pi gamma R*).
* ``"lammps"``: gamma is the surface energy of each surface, w = 2 gamma (Dupre), so the
  pull-off force is 3 pi gamma R* as in the LAMMPS ``pair granular jkr`` documentation.
  The force law the EDEM guide prints, F = -4 sqrt(pi gamma E*) a^(3/2) + 4 E* a^3/(3 R*)
  with delta = a^2/R* - sqrt(4 pi gamma a / E*), is the same law with w = 2 gamma, i.e. this
  convention; it gives a pull-off of 3 pi gamma R*, twice the pull-off the EDEM guide prints
  next to it.  The two printed EDEM statements disagree by that factor 2 (errata); select the
  convention explicitly when matching EDEM values.

Conventions of the reference engines
------------------------------------
The engines that calibrations are compared with write some terms differently.  Each choice is
an option of :func:`model_codes` (``rolling_lever``, ``rolling_force``, ``rolling_axis``,
``tangential_damping``, ``jkr_convention``), and ``conventions`` names a whole set
(:data:`CONVENTIONS`); EDEM's is the default, as the papers calibrate in EDEM.

* ``rolling_lever`` (``constant_torque``): ``particle`` (EDEM guide, rolling friction: the
  lever is the distance c_i from the particle's centre to the contact point, each body with its
  own) or ``effective`` (LIGGGHTS ``rolling_friction cdt``, rolling_model_cdt.h: R* =
  R_i R_j/(R_i + R_j) for a particle pair, the same torque with opposite signs on both, and
  R_i against a wall: LIGGGHTS 3.8's wall torque is mu_r k_n delta R_i, checked against
  its output in tests/reference).  For equal spheres the effective lever is half the
  particle's, so the same mu_r gives half the torque.
* ``rolling_force`` (every rolling model): ``total`` (|F_n,tot|, damping included, as the
  EDEM guide's F_n) or ``elastic`` (the normal force without its damping part: k_n delta =
  4/3 E* a delta for Hertz, as LIGGGHTS cdt; |F_ne + 2 F_pulloff| with JKR, as the LAMMPS
  ``pair granular`` rolling limit F_n,crit).
* ``rolling_axis`` (``constant_torque``): ``full`` (the torque along omega_rel, as the EDEM
  guide writes it) or ``tangential`` (its component along the contact normal, a twisting
  torque, removed after it is computed, as LIGGGHTS cdt does: the magnitude is then
  mu_r F R |omega_rel,t| / |omega_rel|).
* ``tangential_damping``: ``on`` (EDEM, LIGGGHTS ``tangential_damping on``, the LIGGGHTS
  default) or ``off`` (the Mindlin spring and the Coulomb limit only).
* ``rolling_wall`` (``constant_torque`` against a wall): ``relative`` (the sphere's rotation
  relative to the wall's, so a sphere carried round by a rotating drum without rolling on it
  is not resisted) or ``absolute`` (the sphere's own omega_i, as LIGGGHTS 3.8's wall torque
  takes it: a mesh moved by ``fix move/mesh`` carries no angular velocity into it; checked
  against its output on a rotating drum in tests/reference).
* ``jkr_convention``: above.
* ``jkr_break``: where a JKR contact pulled apart breaks.  ``displacement`` (JKR's own
  instability under displacement control, delta_c above, where the force has come back to
  -5/9 of the pull-off) or ``force`` (at the force minimum, the overlap of the pull-off
  force: delta_f = a_f^2/R* - sqrt(2 pi w a_f / E*) with a_f = (9 pi w R*^2 / (8 E*))^(1/3),
  delta_f^3 = -(3/64) pi^2 w^2 R* / E*^2, a ninth of delta_c^3; LAMMPS
  ``gran_normal_jkr_pulloff_distance`` = (3 pi^2 gamma^2 R* / (16 E*^2))^(1/3) with w = 2
  gamma).  The force jumps from -F_pulloff to zero there.
* ``coulomb_force``: the normal force of the Coulomb limit.  ``total`` (mu_s |F_n,tot +
  2 F_po|, damping included) or ``jkr_elastic`` (a JKR contact's mu_s |F_ne + 2 F_po|
  without the damping, LAMMPS ``set_fncrit`` of its cohesive laws; a Hertz contact's stays
  the total, as LAMMPS's).
* ``tangential_slip``: ``spring`` (the Coulomb test on the spring force S_t xi; while
  sliding the force is the shortened spring's and carries no damping, as LIGGGHTS) or
  ``damped`` (the test on spring + dashpot; while sliding the force is that sum scaled to
  the limit and the spring keeps its elastic part, xi = -(F_t - F_t^d)/S_t; LAMMPS
  ``gran_tangential_mindlin``).
* ``history_rotation``: ``project`` (xi <- xi - (xi.n) n every evaluation) or ``rescale``
  (in a step, not at a run's setup, and when |xi.n| S_t > 1e-10 of the Coulomb limit: xi
  projected, then scaled back to its length; LAMMPS ``rotate_rescale_vec``).
* ``jkr_approach``: whether two surfaces that have not touched yet attract across a gap.
  ``touch`` (a JKR contact forms at zero overlap, the force then jumps to the JKR branch;
  JKR's hysteresis, LAMMPS, EDEM's "JKR Version 2") or ``gap`` (the same JKR force on
  approach as on separation, within the separation range of ``jkr_break``: the EDEM guide's
  Hertz-Mindlin with JKR, whose "normal force follows the same solution ... for both loading
  and unloading phases" and "provides attractive cohesion forces even if the particles are
  not in physical contact", where EDEM detects the pair: its contact radius must then
  exceed the physical one).
* ``contact_lever``: the lever of the spins in the contact point's velocity.
  ``contact_point`` (c_i = R_i - delta/2 for the velocity and the torques, as LIGGGHTS) or
  ``radius`` (R_i in the velocity, R_i - delta/2 in a pair's torques and R_i in a wall's,
  LAMMPS ``GranularModel::calculate_forces``).
* ``epsd_form``: the ``epsd`` spring.  ``tangent`` (above: k_n = S_n = 2 E* a, the limit
  on the ``rolling_force``, the stored moment turned into the current tangent plane, nothing
  added at a run's setup) or ``liggghts`` (LIGGGHTS ``rolling_friction epsd`` with
  coefficientRollingViscousDamping 0, rolling_model_epsd.h: k_n = 4/3 E* a, LIGGGHTS's
  Hertz kn (F_ne/delta for plain Hertz only), so k_r is 2/3 of the tangent form's; the
  limit mu_r R* |F_n,tot| with the damping, whatever ``rolling_force`` says; the stored
  moment not turned; against a wall the rotation scaled by (R_i - delta/2)/(R_i - delta),
  LIGGGHTS's wall wr; and a run's setup applying M_r - k_r dtheta_r of one step without
  storing it, as LIGGGHTS's setup evaluates the torque with its step but keeps the history).
* ``wall_curvature``: the effective radius of a contact with an analytic cylinder that holds
  the spheres inside (a drum).  ``flat`` (R* = R_i, as against a plane or the facets of a
  mesh, which is how EDEM and LIGGGHTS meet a drum) or ``cylinder`` (R* = R_i R_w /
  (R_i + R_w) with R_w = -2 R_cyl, LAMMPS ``fix wall/gran/region`` on a ``cylinder``
  region: region_cylinder.cpp gives the curved face the contact radius -2 R and
  ``GranularModel::check_contact`` mixes it as a pair; 2 % above R_i for a 2 mm sphere in a
  50 mm drum).  Planes and the other wall kinds keep R_i in both.

``liggghts`` = effective lever, elastic force, tangential axis, damping on, absolute wall
rotation, LIGGGHTS's epsd spring (LIGGGHTS has no JKR law: ``cohesion sjkr`` is a different model, so its JKR entries
stay EDEM's); ``lammps`` = the same rolling entries (its ``rolling sds`` is the ``epsd`` model
here, whose lever is R* in every set), the LAMMPS JKR convention, the break at the force
minimum, the elastic JKR force in the Coulomb limit, the damped slip, the rescaled rotation,
the radius as lever and the curved cylinder wall.  Two LAMMPS terms have no option: its development sources take
the normal and tangential velocities on the half-step normal (x_ij - v_ij dt/2, normalised;
granular_model.cpp; the 22 Jul 2025 release the parity cases run does not, they agree to
rounding), and its ``run`` evaluates the forces anew at every start, where the Coulomb
rescaling may shorten a sliding spring (a phase boundary of a reference case;
``soilcal.reference.deck.run_phases`` starts every phase with that evaluation, walls at
rest, as LAMMPS and LIGGGHTS do).

The contact radius a(delta) is a = x^2 with x the largest root of x^4/R* - c x - delta = 0,
c = sqrt(2 pi w / E*), found by Newton's method from the upper bound
x0 = (R* max(delta,0))^(1/4) + (R* c)^(1/3) (f is convex, so the iteration decreases
monotonically to the stable-branch root), or from the previous step's root.  In x the force
needs no root: sqrt(8 pi w E* a^3) = 2 E* c x^3, so F_n = E* x^3 (4 x^3/(3 R*) - 2 c).  The
contact history keeps x, and c is a column of the pair table.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from soilcal.dem.materials import (P_BETA, P_ESTAR, P_ETA, P_GSTAR, P_JKRC, P_JKRK, P_MUR,
                                   P_MUS, P_PLAS, P_TRATIO, P_W)
from soilcal.errors import InputError

NORMAL = {"hertz": 0, "eepa": 1}
DAMPING = {"viscoelastic": 0, "none": 1, "viscous_radius": 2}
TANGENTIAL = {"mindlin": 0, "none": 1}
ROLLING = {"none": 0, "constant_torque": 1, "epsd": 2, "bounded": 3}
COHESION = {"none": 0, "jkr": 1}
JKR_CONVENTION = {"edem": 1.0, "lammps": 2.0}  # w = factor * gamma
# conventions (module docstring, "Conventions of the reference engines"): codes[5:10]
ROLLING_LEVER = {"particle": 0, "effective": 1}
ROLLING_FORCE = {"total": 0, "elastic": 1}
ROLLING_AXIS = {"full": 0, "tangential": 1}
TANGENTIAL_DAMPING = {"on": 0, "off": 1}
ROLLING_WALL = {"relative": 0, "absolute": 1}
JKR_BREAK = {"displacement": 0, "force": 1}
COULOMB_FORCE = {"total": 0, "jkr_elastic": 1}
TANGENTIAL_SLIP = {"spring": 0, "damped": 1}
HISTORY_ROTATION = {"project": 0, "rescale": 1}
CONTACT_LEVER = {"contact_point": 0, "radius": 1}
JKR_APPROACH = {"touch": 0, "gap": 1}
WALL_CURVATURE = {"flat": 0, "cylinder": 1}
EPSD_FORM = {"tangent": 0, "liggghts": 1}
#: |xi . n| k_t above this share of the Coulomb limit rotates a ``rescale`` history (LAMMPS
#: GRAN_KERNEL_EPSILON, gran_sub_mod_kernel_defs.h)
RESCALE_EPS = 1e-10
#: named sets of conventions, each as its engine documents or implements it
CONVENTIONS = {
    "edem": dict(rolling_lever="particle", rolling_force="total", rolling_axis="full",
                 tangential_damping="on", jkr_convention="edem", rolling_wall="relative",
                 jkr_break="displacement", coulomb_force="total", tangential_slip="spring",
                 history_rotation="project", contact_lever="contact_point", jkr_approach="touch",
                 wall_curvature="flat", epsd_form="tangent"),
    "liggghts": dict(rolling_lever="effective", rolling_force="elastic",
                     rolling_axis="tangential", tangential_damping="on", jkr_convention="edem",
                     rolling_wall="absolute", jkr_break="displacement", coulomb_force="total",
                     tangential_slip="spring", history_rotation="project",
                     contact_lever="contact_point", jkr_approach="touch",
                     wall_curvature="flat", epsd_form="liggghts"),
    "lammps": dict(rolling_lever="effective", rolling_force="elastic", rolling_axis="tangential",
                   tangential_damping="on", jkr_convention="lammps", rolling_wall="relative",
                   jkr_break="force", coulomb_force="jkr_elastic", tangential_slip="damped",
                   history_rotation="rescale", contact_lever="radius", jkr_approach="touch",
                   wall_curvature="cylinder", epsd_form="tangent"),
}
CONVENTION_TABLES = {"rolling_lever": ROLLING_LEVER, "rolling_force": ROLLING_FORCE,
                     "rolling_axis": ROLLING_AXIS, "tangential_damping": TANGENTIAL_DAMPING,
                     "jkr_convention": JKR_CONVENTION, "rolling_wall": ROLLING_WALL,
                     "jkr_break": JKR_BREAK, "coulomb_force": COULOMB_FORCE,
                     "tangential_slip": TANGENTIAL_SLIP, "history_rotation": HISTORY_ROTATION,
                     "contact_lever": CONTACT_LEVER, "jkr_approach": JKR_APPROACH,
                     "wall_curvature": WALL_CURVATURE, "epsd_form": EPSD_FORM}
#: the conventions' entries of the codes array, from codes[5] on (jkr_convention is w_factor)
CODE_CONVENTIONS = ("rolling_lever", "rolling_force", "rolling_axis", "tangential_damping",
                    "rolling_wall", "jkr_break", "coulomb_force", "tangential_slip",
                    "history_rotation", "contact_lever", "jkr_approach", "wall_curvature",
                    "epsd_form")

# history slot layout (per particle and contact partner)
H_XI = 0  # 3 tangential displacement
H_A = 3  # sqrt of the last JKR contact radius (Newton warm start)
H_MR = 4  # 3 rolling spring moment (epsd); wall rows of "bounded": its resistance mu_r |F_n| c_i
H_DP = 7  # largest overlap of the contact so far (``eepa``)
H_SIZE = 9  # full row (72 bytes; walls keep their touching flag in the last slot, 8)
H_SHORT = 4  # particle pairs without the EPSD spring: tangential + JKR only (32 bytes)


def hist_width(codes) -> int:
    """History row width of particle pairs: the EPSD rolling spring and the plastic law's
    largest overlap need the full row."""
    return H_SIZE if codes[3] == ROLLING["epsd"] or codes[0] == NORMAL["eepa"] else H_SHORT

SQ56 = math.sqrt(5.0 / 6.0)


def resolve_conventions(conventions="edem", source="<input>", **overrides) -> dict:
    """The named set ``conventions`` (:data:`CONVENTIONS`) with the ``overrides`` that are not
    None; every value checked against its table (InputError naming the field otherwise)."""
    if not _is_name(conventions) or conventions not in CONVENTIONS:
        raise InputError(source, "contact_model.conventions", f"one of {sorted(CONVENTIONS)}",
                         conventions)
    out = dict(CONVENTIONS[conventions])
    for key, val in overrides.items():
        if key not in CONVENTION_TABLES:
            raise InputError(source, f"contact_model.{key}",
                             f"one of {sorted(CONVENTION_TABLES)}", key)
        if val is None:
            continue
        if not _is_name(val) or val not in CONVENTION_TABLES[key]:
            raise InputError(source, f"contact_model.{key}",
                             f"one of {sorted(CONVENTION_TABLES[key])}", val,
                             note=_yaml_note(val, CONVENTION_TABLES[key]))
        out[key] = val
    return out


#: the contact model's own entries besides the conventions (:func:`model_codes`)
MODEL_KEYS = ("normal", "damping", "tangential", "rolling", "cohesion", "conventions",
              "damping_eta")


def _is_name(value) -> bool:
    """Whether ``value`` can name an entry of a table (a string; hashable, not a bool)."""
    return isinstance(value, str)


def _yaml_note(value, table):
    """A hint for a YAML boolean given where 'on'/'off' was meant (YAML reads an unquoted
    off as false)."""
    if isinstance(value, bool) and {"on", "off"} <= set(table):
        return "YAML reads unquoted on/off as true/false: quote them, \"off\""
    return None


def model_codes(normal="hertz", damping="viscoelastic", tangential="mindlin", rolling="none",
                cohesion="none", conventions="edem", source="<input>", damping_eta=None,
                **overrides):
    """Return (codes int64[18], w_factor) for a model composed by names.

    ``conventions`` names a set of :data:`CONVENTIONS` (EDEM's by default); ``overrides``
    (any key of :data:`CONVENTION_TABLES`) change single entries of it.  ``damping_eta``
    (1/(m s)) is the coefficient of the ``viscous_radius`` damping, required by it and
    refused by the other damping models (the engine puts it in the pair table)."""
    unknown = sorted(k for k in overrides if k not in CONVENTION_TABLES)
    if unknown:
        # a misspelt model entry is not a convention: name every entry the model takes
        raise InputError(source, f"contact_model.{unknown[0]}",
                         f"an entry among {sorted(MODEL_KEYS + tuple(CONVENTION_TABLES))}",
                         unknown[0])
    if damping == "viscous_radius":
        ok = (not isinstance(damping_eta, bool) and isinstance(damping_eta, (int, float))
              and math.isfinite(damping_eta) and damping_eta >= 0)
        if not ok:
            raise InputError(source, "contact_model.damping_eta",
                             "a damping coefficient eta >= 0 in 1/(m s) for viscous_radius",
                             damping_eta)
    elif damping_eta is not None:
        raise InputError(source, "contact_model.damping_eta",
                         "no coefficient (only damping: viscous_radius takes one)", damping_eta)
    out = []
    for key, val, table in (("normal", normal, NORMAL), ("damping", damping, DAMPING),
                            ("tangential", tangential, TANGENTIAL), ("rolling", rolling, ROLLING),
                            ("cohesion", cohesion, COHESION)):
        if not _is_name(val) or val not in table:
            raise InputError(source, f"contact_model.{key}", f"one of {sorted(table)}", val)
        out.append(table[val])
    conv = resolve_conventions(conventions, source, **overrides)
    for key in CODE_CONVENTIONS:
        out.append(CONVENTION_TABLES[key][conv[key]])
    return np.array(out, dtype=np.int64), JKR_CONVENTION[conv["jkr_convention"]]


@njit(cache=True, inline="always")
def jkr_root(delta, rstar, c, x_prev):
    """x = sqrt(a) on the stable JKR branch for overlap delta (may be negative), c =
    sqrt(2 pi w / E*); Newton from the previous step's root x_prev if > 0, else from the
    upper bound x0 (module docstring); relative tolerance 1e-13 warm, 1e-15 cold.

    Newton on the convex f(x) = x^4/R* - c x - delta from any x > x_c = (c R*/4)^(1/3)
    (f' > 0 there; the stable-branch radii are a >= a_c = x_c^2, with the double root
    f = f' = 0 at separation) lands right of the root after one step and then decreases
    monotonically to it.  A step dx from x0 right of the root leaves the error
    e1 = f''(xi) e0^2 / (2 f'(x0)) <= (f''/(2 f')) (2 dx)^2 = 24 x0^2 dx^2 / (R* f'(x0))
    (f'' = 12 x^2/R* grows with x, and |e0| <= 2 |dx| while the convergence is at least
    linear with ratio 1/2), so the loop stops when that bound is below the tolerance, or
    when the step itself is at the rounding level (4e-16 x: near the double root the
    convergence is only linear).  One division per step; a warm start whose root moved by a
    relative 1e-4 stops after two steps instead of three.
    """
    x = x_prev
    tol = 1e-13
    if x <= 0.0:
        x = (rstar * max(delta, 0.0)) ** 0.25 + (rstar * c) ** (1.0 / 3.0)
        tol = 1e-15
    ir = 1.0 / rstar
    for _ in range(60):
        x2 = x * x
        x3 = x2 * x
        fp = 4.0 * x3 * ir - c
        dx = (x3 * x * ir - c * x - delta) / fp
        x -= dx
        if 24.0 * x2 * dx * dx <= tol * x * rstar * fp or abs(dx) <= 4e-16 * x:
            break
    return x


@njit(cache=True)
def jkr_force(a, rstar, estar, w):
    """JKR normal force (positive repulsive) for contact radius a."""
    a3 = a * a * a
    return 4.0 * estar * a3 / (3.0 * rstar) - math.sqrt(8.0 * math.pi * w * estar * a3)


@njit(cache=True)
def jkr_delta(a, rstar, estar, w):
    """JKR overlap for contact radius a."""
    return a * a / rstar - math.sqrt(2.0 * math.pi * w * a / estar)


@njit(cache=True)
def jkr_separation(rstar, estar, w):
    """Overlap (negative) at which a JKR contact breaks under displacement control."""
    if w <= 0.0:
        return 0.0
    ac = (math.pi * w * rstar * rstar / (8.0 * estar)) ** (1.0 / 3.0)
    return jkr_delta(ac, rstar, estar, w)


@njit(cache=True, inline="always")
def contact_force(codes, pair, ma, mb, delta, nx, ny, nz, rvx, rvy, rvz, wrx, wry, wrz,
                  ci, cj, rstar, mstar, dt, touching, hist, hk):
    """Force on particle i and torques on both bodies from one contact; updates ``hist``.

    delta: overlap; (nx,ny,nz): unit normal from partner j towards i; (rvx..): relative
    velocity of i's contact point w.r.t. j's; (wrx..): omega_i - omega_j; ci, cj: distances
    from the centres of i and j to the contact point (moment arms; cj = 0 for a wall);
    touching: the pair was in contact after the previous step (JKR keeps it on the
    attractive branch); pair[ma, mb]: pair parameters; hist[hk]: history row (the index is
    passed instead of an array view, which would touch the shared reference count in
    every parallel iteration).

    The force on j is exactly the opposite of the force on i.  With u = n x F_t, the
    tangential torques are -c_i u on i and -c_j u on j; the constant rolling torque is
    -mu_r |F_n,tot| c omega_rel/|omega_rel| on each body with its own omega_rel (so the
    partner's is -(c_j/c_i) times i's) and the EPSD moment acts as +M_r on i and -M_r on j.
    The ``bounded`` rolling model adds no torque here: it returns mu_r |F_n,tot| as
    ``mroll`` and the caller sums mu_r |F_n,tot| c over each particle's contacts.
    Returns (active, fx, fy, fz, tix, tiy, tiz, tjx, tjy, tjz, mroll).
    """
    estar = pair[ma, mb, P_ESTAR]
    w = pair[ma, mb, P_W]
    # dt < 0: a run's setup evaluation, whose step will be -dt; the histories advance by
    # nothing (only LIGGGHTS's epsd adds its step's increment to the setup torque)
    step = dt if dt > 0.0 else 0.0
    cohesive = codes[4] == 1 and w > 0.0
    if cohesive:
        if delta <= 0.0:
            # separation: delta < delta_c  <=>  delta^3 < -(27/64) pi^2 w^2 R* / E*^2; at
            # the force minimum (``jkr_break: force``) delta^3 < -(3/64) pi^2 w^2 R* / E*^2
            # a pair not yet touching: no force (``jkr_approach: touch``), or the JKR branch
            # within the same range on approach (``gap``, EDEM's JKR)
            kb = pair[ma, mb, P_JKRK] * (1.0 / 9.0 if codes[10] == 1 else 1.0)
            if (not touching and codes[15] == 0) or delta * delta * delta < -kb * rstar:
                if touching:
                    for q in range(hist.shape[1]):
                        hist[hk, q] = 0.0
                return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        x = jkr_root(delta, rstar, pair[ma, mb, P_JKRC], hist[hk, H_A])
        hist[hk, H_A] = x
        a = x * x
        x3 = a * x
        fne = estar * x3 * (4.0 * x3 / (3.0 * rstar) - 2.0 * pair[ma, mb, P_JKRC])
        fpo2 = 3.0 * math.pi * w * rstar  # 2 |F_pulloff|
    else:
        if delta <= 0.0:
            if touching:
                for q in range(hist.shape[1]):
                    hist[hk, q] = 0.0
            return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        a = math.sqrt(rstar * delta)
        fne = 4.0 / 3.0 * estar * a * delta
        fpo2 = 0.0
    # plastic Hertz (``eepa``): below the largest overlap, the stiffer unloading branch
    dashpot = True
    lam = pair[ma, mb, P_PLAS] if codes[0] == 1 else 0.0
    if lam > 0.0 and delta > 0.0:
        dm = hist[hk, H_DP]
        if delta >= dm:
            hist[hk, H_DP] = delta
        else:
            k1 = 4.0 / 3.0 * estar * math.sqrt(rstar)
            fu = k1 / (1.0 - lam) * (delta * math.sqrt(delta) - lam * dm * math.sqrt(dm))
            if fu <= 0.0:
                fu = 0.0
                dashpot = False
            fne = fne + (fu - k1 * delta * math.sqrt(delta)) if cohesive else fu
    beta = pair[ma, mb, P_BETA]
    sn = 2.0 * estar * a
    vn = rvx * nx + rvy * ny + rvz * nz
    # normal dashpot sq <= 0: F_n^d = sq v_n opposes v_n (the product stays inside the
    # branches, so that F_n = F_ne + F_n^d is rounded twice as the reference engines do,
    # not fused into one multiply-add)
    fnd = 0.0
    sq = 0.0
    if not dashpot:
        pass
    elif codes[1] == 0:
        sq = 2.0 * SQ56 * beta * math.sqrt(sn * mstar)
        fnd = sq * vn
    elif codes[1] == 2:
        sq = -pair[ma, mb, P_ETA] * mstar * a
        fnd = sq * vn
    fn = fne + fnd
    fnf = abs(fn + fpo2)
    # the normal force the rolling resistance scales with: total, or without the damping
    fnr = abs(fne + fpo2) if codes[6] == 1 else fnf
    fx = fn * nx
    fy = fn * ny
    fz = fn * nz
    tix = 0.0
    tiy = 0.0
    tiz = 0.0
    tjx = 0.0
    tjy = 0.0
    tjz = 0.0
    if codes[2] == 0:
        vtx = rvx - vn * nx
        vty = rvy - vn * ny
        vtz = rvz - vn * nz
        st = 8.0 * pair[ma, mb, P_GSTAR] * a
        # Coulomb limit: mu_s |F_n,tot + 2 F_po|, or with JKR |F_ne + 2 F_po| (jkr_elastic)
        fmax = pair[ma, mb, P_MUS] * (abs(fne + fpo2) if codes[11] == 1 and cohesive
                                      else fnf)
        # bring the history into the current tangent plane, then add v_t dt
        xx = hist[hk, H_XI]
        xy = hist[hk, H_XI + 1]
        xz = hist[hk, H_XI + 2]
        xn = xx * nx + xy * ny + xz * nz
        if codes[13] == 0:
            xx -= xn * nx
            xy -= xn * ny
            xz -= xn * nz
        elif dt > 0.0 and abs(xn) * st > RESCALE_EPS * fmax:
            # rotated, its length kept (LAMMPS rotate_rescale_vec, not at a run's setup)
            m0 = math.sqrt(xx * xx + xy * xy + xz * xz)
            xx -= xn * nx
            xy -= xn * ny
            xz -= xn * nz
            m1 = math.sqrt(xx * xx + xy * xy + xz * xz)
            s1 = m0 / m1 if m1 > 0.0 else 0.0
            xx *= s1
            xy *= s1
            xz *= s1
        xx += vtx * step
        xy += vty * step
        xz += vtz * step
        ftx = -st * xx
        fty = -st * xy
        ftz = -st * xz
        # tangential dashpot: sqrt(S_t m*) = sqrt(S_n m*) sqrt(4 G*/E*) (viscoelastic), the
        # same ratio times eta m* a (viscous_radius)
        ct = sq * pair[ma, mb, P_TRATIO] if codes[1] != 1 and codes[8] == 0 else 0.0
        if codes[12] == 1:
            # ``damped`` slip: the Coulomb test on spring + dashpot; when sliding, the
            # force is scaled to the limit and the spring keeps its elastic part
            ftx += ct * vtx
            fty += ct * vty
            ftz += ct * vtz
            fs2 = ftx * ftx + fty * fty + ftz * ftz
            if fs2 > fmax * fmax:
                if xx * xx + xy * xy + xz * xz > 0.0:
                    r = fmax / math.sqrt(fs2)
                    ftx *= r
                    fty *= r
                    ftz *= r
                    xx = -(ftx - ct * vtx) / st
                    xy = -(fty - ct * vty) / st
                    xz = -(ftz - ct * vtz) / st
                else:
                    ftx = 0.0
                    fty = 0.0
                    ftz = 0.0
        else:
            fs2 = ftx * ftx + fty * fty + ftz * ftz
            if fs2 > fmax * fmax:
                r = fmax / math.sqrt(fs2)
                xx *= r
                xy *= r
                xz *= r
                ftx *= r
                fty *= r
                ftz *= r
            else:
                ftx += ct * vtx
                fty += ct * vty
                ftz += ct * vtz
        hist[hk, H_XI] = xx
        hist[hk, H_XI + 1] = xy
        hist[hk, H_XI + 2] = xz
        fx += ftx
        fy += fty
        fz += ftz
        # moment arms from the centres to the contact point: -ci n (i), +cj n (j)
        ux = ny * ftz - nz * fty
        uy = nz * ftx - nx * ftz
        uz = nx * fty - ny * ftx
        tix = -ci * ux
        tiy = -ci * uy
        tiz = -ci * uz
        tjx = -cj * ux
        tjy = -cj * uy
        tjz = -cj * uz
    mur = pair[ma, mb, P_MUR]
    mroll = 0.0
    if codes[3] == 3:
        mroll = mur * fnr
    elif codes[3] == 1 and mur > 0.0:
        wn = math.sqrt(wrx * wrx + wry * wry + wrz * wrz)
        if wn > 0.0:
            m = mur * fnr / wn
            # direction: omega_rel, or its part in the tangent plane (torsion removed)
            ux = wrx
            uy = wry
            uz = wrz
            if codes[7] == 1:
                wd = wrx * nx + wry * ny + wrz * nz
                ux -= wd * nx
                uy -= wd * ny
                uz -= wd * nz
            # lever: each body's own c, or R* on both (a wall's R* is R_i)
            li = ci
            lj = cj
            if codes[5] == 1:
                li = rstar
                lj = rstar
            tix -= m * li * ux
            tiy -= m * li * uy
            tiz -= m * li * uz
            tjx += m * lj * ux
            tjy += m * lj * uy
            tjz += m * lj * uz
    elif codes[3] == 2 and mur > 0.0:
        # ``epsd_form``: tangent (k_n = S_n, the limit on fnr, the moment turned with the
        # tangent plane, no increment at a run's setup) or liggghts (k_n = 4/3 E* a, LIGGGHTS's
        # Hertz kn, the limit on |F_n,tot|, the moment kept as stored, and at a run's setup the
        # step's increment added to the torque but not stored: rolling_model_epsd.h)
        lig = codes[17] == 1
        wd = wrx * nx + wry * ny + wrz * nz
        dtr = abs(dt) if lig else step
        if lig and cj == 0.0:
            # against a wall LIGGGHTS turns the spring by its wr = omega_i (R_i - delta/2) /
            # (R_i - delta) (surface_model_default.h: the contact lever over the centre's
            # distance to the wall)
            rc = ci if codes[14] == 0 else ci - 0.5 * delta
            dtr *= rc / (rc - 0.5 * delta)
        dtx = (wrx - wd * nx) * dtr
        dty = (wry - wd * ny) * dtr
        dtz = (wrz - wd * nz) * dtr
        mx = hist[hk, H_MR]
        my = hist[hk, H_MR + 1]
        mz = hist[hk, H_MR + 2]
        old2 = mx * mx + my * my + mz * mz
        if old2 > 0.0 and not lig:
            mn = mx * nx + my * ny + mz * nz
            mx -= mn * nx
            my -= mn * ny
            mz -= mn * nz
            new2 = mx * mx + my * my + mz * mz
            if new2 > 0.0:
                s = math.sqrt(old2 / new2)
                mx *= s
                my *= s
                mz *= s
        kr = 2.25 * (4.0 / 3.0 * estar * a if lig else sn) * mur * mur * rstar * rstar
        mx -= kr * dtx
        my -= kr * dty
        mz -= kr * dtz
        mlim = mur * rstar * (fnf if lig else fnr)
        m2 = mx * mx + my * my + mz * mz
        if m2 > mlim * mlim:
            r = mlim / math.sqrt(m2)
            mx *= r
            my *= r
            mz *= r
        if dt >= 0.0 or not lig:
            hist[hk, H_MR] = mx
            hist[hk, H_MR + 1] = my
            hist[hk, H_MR + 2] = mz
        tix += mx
        tiy += my
        tiz += mz
        tjx -= mx
        tjy -= my
        tjz -= mz
    return True, fx, fy, fz, tix, tiy, tiz, tjx, tjy, tjz, mroll
