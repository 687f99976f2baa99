"""The plastic Hertz normal law ``eepa`` (soilcal.dem.contact) against its closed forms.

Thakur, Morrissey, Sun, Chen & Ooi 2014 (Granul. Matter 16:383), Eqs. 1-2 without adhesion and
with the Hertz exponent: loading on k1 delta^(3/2) (k1 = 4/3 E* sqrt(R*)), unloading and
reloading on k2 (delta^(3/2) - lambda_p delta_max^(3/2)), k2 = k1 / (1 - lambda_p).  The
rebound of an undamped impact follows from the work of the two branches:
e^2 = (1 - 5/2 lambda_p + 3/2 lambda_p^(5/3)) / (1 - lambda_p).
"""

import math

import numpy as np
import pytest

from conftest import head_on, table
from soilcal.dem.engine import Simulation
from soilcal.dem.materials import Material, MaterialTable, damped_critical_dt
from soilcal.errors import InputError

R = 1e-3
E, NU, RHO = 1e9, 0.3, 2600.0
ESTAR = E / (2 * (1 - NU**2))
MASS = 4 / 3 * math.pi * R**3 * RHO


def pair_sim(lam, wall=False, gamma=0.0):
    cohesion = "jkr" if gamma > 0 else "none"
    sim = Simulation(table(e=0.5, mu=0.0, gamma=gamma, E=E, plasticity=lam), dt=1e-7,
                     gravity=(0, 0, 0), contact_model=dict(normal="eepa", tangential="none",
                                                           cohesion=cohesion))
    if wall:
        sim.add_particles([[0, 0, R]], R, "soil")
        sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
    else:
        sim.add_particles([[0, 0, 0], [0, 0, 2 * R]], R, "soil")
    return sim


def force_at(sim, delta, wall):
    """Normal force on the upper sphere at overlap delta (no velocity: no dashpot)."""
    if wall:
        sim.p.x[0, 2] = R - delta
    else:
        sim.p.x[1, 2] = 2 * R - delta
    return sim.compute_forces()[0][0 if wall else 1, 2]


@pytest.mark.parametrize("wall", [False, True])
@pytest.mark.parametrize("lam", [0.3, 0.7])
def test_loading_unloading_and_reloading_branches(lam, wall):
    rstar = R if wall else R / 2
    k1 = 4 / 3 * ESTAR * math.sqrt(rstar)
    k2 = k1 / (1 - lam)
    sim = pair_sim(lam, wall)
    d1 = 0.01 * R
    dp = lam ** (2 / 3) * d1  # plastic overlap of a contact loaded to d1
    # virgin loading: Hertz
    for d in np.linspace(0.1 * d1, d1, 10):
        assert force_at(sim, d, wall) == pytest.approx(k1 * d**1.5, rel=1e-12)
    # unloading: the stiffer branch, zero at the plastic overlap and below it
    for d in np.linspace(d1, 0.2 * dp, 12):
        expected = max(k2 * (d**1.5 - lam * d1**1.5), 0.0)
        assert force_at(sim, d, wall) == pytest.approx(expected, rel=1e-9, abs=1e-12 * k1 * d1**1.5)
    assert force_at(sim, 0.999 * dp, wall) == 0.0
    # reloading retraces the unloading branch up to d1, then Hertz again (d2 the new maximum)
    for d in np.linspace(1.01 * dp, d1, 8):
        assert force_at(sim, d, wall) == pytest.approx(k2 * (d**1.5 - lam * d1**1.5), rel=1e-9)
    d2 = 1.5 * d1
    assert force_at(sim, d2, wall) == pytest.approx(k1 * d2**1.5, rel=1e-12)
    assert force_at(sim, d1, wall) == pytest.approx(max(k2 * (d1**1.5 - lam * d2**1.5), 0.0),
                                                    rel=1e-9)
    # parted surfaces end the contact: a new one loads on Hertz from zero
    assert force_at(sim, -0.01 * d1, wall) == 0.0
    assert force_at(sim, 0.5 * d1, wall) == pytest.approx(k1 * (0.5 * d1)**1.5, rel=1e-12)


def test_zero_plasticity_is_hertz():
    sim = pair_sim(0.0)
    k1 = 4 / 3 * ESTAR * math.sqrt(R / 2)
    d1 = 0.01 * R
    force_at(sim, d1, False)
    assert force_at(sim, 0.5 * d1, False) == pytest.approx(k1 * (0.5 * d1)**1.5, rel=1e-12)


def test_with_jkr_the_plastic_share_leaves_the_adhesion():
    """With JKR the law changes the Hertz part only: on loading the force is JKR's, on
    unloading it is JKR's minus (k1 delta^1.5 - F_eepa)."""
    gamma, lam = 0.3, 0.5
    sim = pair_sim(lam, gamma=gamma)
    rstar = R / 2
    k1 = 4 / 3 * ESTAR * math.sqrt(rstar)
    c = math.sqrt(2 * math.pi * gamma / ESTAR)

    def jkr(delta):
        # a from the JKR overlap delta = a^2/R* - c sqrt(a) (bisection on the stable branch)
        lo, hi = 1e-9, 1e-2
        for _ in range(200):
            a = 0.5 * (lo + hi)
            lo, hi = (a, hi) if a * a / rstar - c * math.sqrt(a) < delta else (lo, a)
        return 4 * ESTAR * a**3 / (3 * rstar) - math.sqrt(8 * math.pi * gamma * ESTAR * a**3)

    d1 = 0.01 * R
    assert force_at(sim, d1, False) == pytest.approx(jkr(d1), rel=1e-9)
    for d in (0.8 * d1, 0.5 * d1, 0.2 * d1):
        plastic = max(k1 / (1 - lam) * (d**1.5 - lam * d1**1.5), 0.0)
        assert force_at(sim, d, False) == pytest.approx(jkr(d) + plastic - k1 * d**1.5, rel=1e-8)


def impact(lam, v0, dt=2e-8):
    return head_on(table(e=1.0, mu=0.0, E=E, plasticity=lam), v0, R, dt, normal="eepa",
                   gap=1e-8, max_steps=4000000)[0]


@pytest.mark.parametrize("lam", [0.2, 0.5, 0.8])
@pytest.mark.parametrize("v0", [0.02, 0.2])
def test_undamped_impact_rebounds_with_the_work_ratio(lam, v0):
    e = math.sqrt((1 - 2.5 * lam + 1.5 * lam ** (5 / 3)) / (1 - lam))
    assert impact(lam, v0) == pytest.approx(e, rel=2e-3)


def test_the_time_step_bound_takes_the_unloading_stiffness():
    """Without friction the damped normal mode sets the bound; its spring is S_n/(1 - lam),
    so the step shrinks by sqrt(1 - lam) (the damping ratio is kept: conservative)."""
    out = {}
    for lam in (0.0, 0.75):
        mats = table(e=0.5, mu=0.0, E=E, plasticity=lam)
        tab = mats.table(1.0)
        out[lam] = mats.damping_dt({0: R}, tab, 0.3)
    rstar, mstar = R / 2, MASS / 2
    root = math.sqrt(rstar * 0.3 * R)
    le = math.log(0.5)
    z = math.sqrt(5 / 6) * abs(le / math.sqrt(le * le + math.pi**2))
    assert out[0.0] == pytest.approx(damped_critical_dt(2 * ESTAR * root, mstar, z), rel=1e-12)
    assert out[0.75] == pytest.approx(out[0.0] * math.sqrt(0.25), rel=1e-12)


@pytest.mark.parametrize("lam", [-0.1, 1.0, float("nan")])
def test_a_plasticity_ratio_outside_its_range_names_the_pair(lam):
    mats = MaterialTable(source="soil.yaml")
    mats.add(Material("soil", RHO, NU, youngs=E))
    with pytest.raises(InputError, match=r"interactions\.soil-soil\.plasticity"):
        mats.set_pair("soil", "soil", 0.5, 0.5, plasticity=lam)


def test_demparams_switch_the_soil_soil_contacts_to_the_plastic_law():
    from soilcal.dem.scenarios.base import DemParams, build_materials, contact_model
    from soilcal.dem.materials import P_PLAS

    p = DemParams().replace(soil_soil_plasticity=0.4)
    assert contact_model(p)["normal"] == "eepa"
    assert contact_model(DemParams())["normal"] == "hertz"
    tab = build_materials(p).table(1.0)
    assert tab[0, 0, P_PLAS] == 0.4 and tab[0, 1, P_PLAS] == 0.0
    with pytest.raises(InputError, match="params.soil_soil_plasticity"):
        DemParams.from_mapping({"soil_soil_plasticity": 1.0})


def test_a_stage_factor_of_kind_plasticity_sets_the_soil_soil_ratio(tmp_path):
    """A user's soil may vary the contact plasticity ratio like any contact parameter: a
    factor whose parameter has pair soil-soil and kind plasticity sets soil_soil_plasticity."""
    from own_soil import bbd_soil, write_soil
    from soilcal.config import load_soil
    from soilcal.dem.scenarios.base import stage_params

    plastic = {"name": "Contact plasticity ratio", "unit": "-", "pair": "soil-soil", "kind": "plasticity"}
    data = bbd_soil("my-soil", {"plastic": (0.2, 0.6), "energy": (2, 6), "steel": (0.4, 0.8)},
                    parameters={"plastic": plastic})
    soil = load_soil(write_soil(tmp_path, data), tmp_path / "resources")
    p = stage_params(soil, "bbd", {"A": 0.0, "B": 0.0, "C": 0.0}, coded=True)
    assert p.soil_soil_plasticity == pytest.approx(0.4, rel=1e-12)
    with pytest.raises(InputError, match="stages.bbd.factors.A"):
        stage_params(soil, "bbd", {"A": 1.0}, coded=False)
