"""Analytic stand-ins for the DEM, for the loop's tests and benchmark, driven by the same DEM
parameters the effects change: the passive earth pressure on a vertical blade (scenario
``standin``) and a confined compression test with unloading (scenario
``standin_compression``); :func:`simulate` runs a condition by its scenario.

Blade (Rankine; McKyes, Soil Cutting and Tillage, 1985, Ch. 4).  Horizontal force on a blade
of width b at working depth d moving at speed v::

    F_h = b d (0.5 K_p rho_b g d + 2 c sqrt(K_p) + c_a + rho_b v^2)
    K_p = tan^2(45 deg + phi / 2),  phi = atan(mu_ss),
    c = gamma_ss / r,  c_a = gamma_st / r,  rho_b = 0.6 rho_particle

(Rankine passive pressure with cohesion, a tool adhesion term, and the momentum flux of the
soil accelerated to the tool speed), and the vertical force F_v = F_h mu_st.  The bulk
cohesion gamma / r is the JKR pull-off 1.5 pi gamma R* over the area per contact (~ r^2),
the scaling in soilcal.dem.scenarios.base.  Seed scatter: relative, normal, SD 1 %,
drawn from the seed and the row (common random numbers across parameters, as in the DEM).

Confined compression (the DEM's ``compression`` with ``unload: true``): an affine packing of
equal Hertz spheres of radius R at solid fraction phi with Z contacts per sphere in
isotropic directions, the effective-medium model of granular elasticity (Digby, J. Appl.
Mech. 48 (1981) 803; Walton, J. Mech. Phys. Solids 35 (1987) 213): every contact overlap
follows the axial strain eps.  A contact at the angle theta to the axis is compressed by
delta = 2 R eps cos^2 theta and carries Hertz's F = (4/3) E* sqrt(R*) delta^1.5 with
R* = R / 2, i.e. F = (8/3) E* R^2 eps^1.5 cos^3 theta; the axial stress of the N Z / 2 contacts
of N spheres in the volume V = N (4/3) pi R^3 / phi (Love-Weber, the branch vector 2 R n) is
sigma = (N Z / (2 V)) <F 2 R cos^2 theta>, with <|cos theta|^5> = 1/6 over isotropic
directions::

    sigma(eps) = C E* eps^1.5,   C = phi Z / (3 pi) = 0.382 (phi = 0.6, Z = 6)
    E* = E / (2 (1 - nu^2)),     E = 2 G (1 + nu)

(E* of two equal spheres from ``soil_shear_modulus`` G and ``soil_poisson`` nu, as in
soilcal.dem.materials).  The rod stops at the condition's ``max_strain`` eps_max (its setup);
up to there every contact is on its loading branch, Hertz's for the plastic law too, so the
loading stresses do not depend on lambda_p: ``stress_10_kpa`` = C E* 0.1^1.5 (NaN for
eps_max < 0.1), the peak stress sigma_max = C E* eps_max^1.5.

Withdrawing the rod unloads every contact affinely.  With the plastic Hertz law of
``soil_soil_plasticity`` = lambda_p (``eepa``, soilcal.dem.contact; Thakur et al., Granular
Matter 16 (2014) 383, Eqs. 1-2 with n = 3/2) a contact unloads along
F = k2 (delta^1.5 - lambda_p delta_max^1.5), k2 = k1 / (1 - lambda_p), and
delta / delta_max = eps / eps_max for every direction, so::

    sigma = C E* / (1 - lambda_p) (eps^1.5 - lambda_p eps_max^1.5)

which is zero at eps_0 = lambda_p^(2/3) eps_max, the strain the sample keeps; the strain it
recovers is::

    recovered_strain = eps_max - eps_0 = eps_el,max (1 - lambda_p^(2/3))

with eps_el,max = (sigma_max / (C E*))^(2/3) the elastic contact strain at the peak stress,
here eps_max itself: the affine packing has no rearrangement of grains, whose strain a real
bed keeps (the DEM's recovered strain at lambda_p = 0 is a share of its ``strain_end``, the
stand-in's all of it).  Parameter sets without ``soil_soil_plasticity`` are elastic
(lambda_p = 0).  Seed scatter: relative, normal, SD 1 % on each response, drawn from the seed
and the row (common random numbers across parameters, as the blade).
"""

from __future__ import annotations

import math

import numpy as np

from soilcal.config.measurements import Condition, unit_of
from soilcal.errors import InputError

#: scenario names of the stand-ins' conditions
BLADE = "standin"
COMPRESSION = "standin_compression"

G = 9.81
R = 0.005  # m, particle radius
WIDTH = {"A": 0.10, "B": 0.15, "C": 0.20}

BASE = dict(soil_soil_restitution=0.45, soil_soil_static_friction=0.6, soil_soil_rolling_friction=0.1,
            soil_soil_surface_energy=0.4, soil_steel_restitution=0.45, soil_steel_static_friction=0.5,
            soil_steel_rolling_friction=0.1, soil_steel_surface_energy=0.0, soil_density=2000.0,
            soil_poisson=0.3, soil_shear_modulus=1e6, steel_density=7850.0, steel_poisson=0.3,
            steel_shear_modulus=7.9e10)


def forces(params: dict, q: dict) -> tuple[float, float]:
    phi = math.atan(params["soil_soil_static_friction"])
    kp = math.tan(math.pi / 4 + phi / 2) ** 2
    rho = 0.6 * params["soil_density"]
    c = params["soil_soil_surface_energy"] / R
    ca = params["soil_steel_surface_energy"] / R
    b = WIDTH[q.get("tool", "A")]
    d = q["working_depth"]
    v = q.get("tool_speed", 1.0)
    fh = b * d * (0.5 * kp * rho * G * d + 2 * c * math.sqrt(kp) + ca + rho * v * v)
    return fh, fh * params["soil_steel_static_friction"]


#: solid fraction and contacts per sphere of the compression stand-in's packing
PHI, Z = 0.6, 6.0
#: C of sigma = C E* eps^1.5 (module docstring)
C_AFFINE = PHI * Z / (3.0 * math.pi)


def contact_modulus(params: dict) -> float:
    """E* of two equal soil spheres, E / (2 (1 - nu^2)) with E = 2 G (1 + nu) [Pa]."""
    nu = float(params["soil_poisson"])
    e = 2.0 * float(params["soil_shear_modulus"]) * (1.0 + nu)
    return e / (2.0 * (1.0 - nu * nu))


def compression(params: dict, setup: dict) -> dict:
    """``stress_10_kpa`` and ``recovered_strain`` of the compression stand-in, without
    seed scatter (module docstring)."""
    eps_max = setup.get("max_strain")
    if not isinstance(eps_max, (int, float)) or not 0.0 < eps_max < 0.9:
        raise InputError("<standin>", "setup.max_strain", "a strain in (0, 0.9)", eps_max)
    lp = float(params.get("soil_soil_plasticity", 0.0))
    if not 0.0 <= lp < 1.0:
        raise InputError("<standin>", "params.soil_soil_plasticity", "a contact plasticity ratio in [0, 1)", lp)
    ce = C_AFFINE * contact_modulus(params)
    s10 = ce * 0.1 ** 1.5 / 1e3 if eps_max >= 0.1 else math.nan
    eps_el = float(eps_max)  # (sigma_max / (C E*))^(2/3): all of the affine packing's strain is contact strain
    return {"stress_10_kpa": s10, "recovered_strain": eps_el * (1.0 - lp ** (2.0 / 3.0))}


def simulate(cond, params, seed):
    """One run of a stand-in condition (its scenario: :data:`BLADE` or :data:`COMPRESSION`):
    measure -> value."""
    if cond.scenario == COMPRESSION:
        out = compression(params, cond.setup or {})
        e = np.random.default_rng([seed, cond.row]).normal(0.0, 0.01, 2)
        return {"stress_10_kpa": out["stress_10_kpa"] * (1 + e[0]),
                "recovered_strain": out["recovered_strain"] * (1 + e[1])}
    if cond.scenario != BLADE:
        raise InputError("<standin>", "scenario", f"{BLADE} or {COMPRESSION}", cond.scenario)
    fh, fv = forces(params, cond.quantities)
    e = np.random.default_rng([seed, cond.row]).normal(0.0, 0.01, 2)
    return {"horizontal_force_N": fh * (1 + e[0]), "vertical_force_N": fv * (1 + e[1])}


def base_params(cond):
    return dict(BASE)


def conditions(rows, measures=("horizontal_force_N", "vertical_force_N")):
    """Conditions from dicts of quantities (tool, tool_speed m/s, working_depth m,
    moisture_content %, position m, day)."""
    out = []
    for i, q in enumerate(rows, start=1):
        cov = dict(q)
        qc = {k: k for k in q}
        out.append(Condition(measurement="plates", row=i, label=f"row {i}", covariate="", covariate_value="",
                             scenario=BLADE, setup={}, params={}, stage="bbd", case="c", preset="quick",
                             replicates=3, responses=tuple({"measure": m, "unit": "N", "measured": None,
                                                            "measured_sd": None, "n": None} for m in measures),
                             covariates=cov, quantities=dict(q), quantity_columns=qc))
    return out


def grid(seed=0, n=18, moisture=False, days=6):
    """A soil-bin campaign: three tools, speeds 0.5-3 m/s, depths 0.05-0.15 m, positions
    along a 40 m bin and test days, drawn with a seeded generator."""
    rng = np.random.default_rng(seed)
    rows = []
    for i in range(n):
        q = {"tool": "ABC"[i % 3], "tool_speed": float(rng.uniform(0.5, 3.0)),
             "working_depth": float(rng.uniform(0.05, 0.15)), "position": float(rng.uniform(0, 40)),
             "day": f"d{i * days // n}"}
        if moisture:
            q["moisture_content"] = float(rng.uniform(8, 24))
        rows.append(q)
    return rows


def compression_conditions(rows, measures=("stress_10_kpa", "recovered_strain")):
    """Compression conditions (scenario :data:`COMPRESSION`) from dicts holding the rod's
    ``max_strain`` (set in the setup, as a measured table's ``{set: max_strain}`` column) and
    any quantities (moisture_content %, day, ...)."""
    out = []
    for i, q in enumerate(rows, start=1):
        quant = {k: v for k, v in q.items() if k != "max_strain"}
        out.append(Condition(measurement="compression", row=i, label=f"row {i}", covariate="", covariate_value="",
                             scenario=COMPRESSION, setup={"max_strain": q["max_strain"], "unload": True}, params={},
                             stage="bbd", case="c", preset="quick", replicates=3,
                             responses=tuple({"measure": m, "unit": unit_of(m), "measured": None, "measured_sd": None,
                                              "n": None} for m in measures),
                             covariates=dict(q), quantities=quant, quantity_columns={k: k for k in quant}))
    return out


def compression_grid(seed=0, n=12):
    """A compression campaign: the rod stopped at strains drawn uniformly in [0.15, 0.30]
    (a seeded generator), loaded past the 10 % of ``stress_10_kpa``."""
    rng = np.random.default_rng(seed)
    return [{"max_strain": float(rng.uniform(0.15, 0.30))} for _ in range(n)]
