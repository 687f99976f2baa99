"""Bad parameters fail before the run with a clear message; blow-ups name step and particle."""

import re

import pytest

from conftest import table
from soilcal.dem.engine import Simulation
from soilcal.dem.materials import Material, MaterialTable
from soilcal.errors import InputError, SimulationError


@pytest.mark.parametrize("e", [0.0, -0.2, 1.5])
def test_restitution_out_of_range(e):
    with pytest.raises(InputError, match=r"restitution: expected a coefficient of restitution in \(0, 1\]"):
        table(e=e)


def test_negative_friction():
    with pytest.raises(InputError, match=r"\.friction: expected sliding friction >= 0"):
        table(mu=-0.1)
    with pytest.raises(InputError, match=r"rolling_friction: expected rolling friction >= 0"):
        table(mur=-0.01)


@pytest.mark.parametrize("kw", [dict(shear=0.0), dict(shear=-1e6), dict(youngs=0.0)])
def test_non_positive_modulus(kw):
    with pytest.raises(InputError, match=r"materials\.soil\.(shear|youngs): expected (G|E) > 0 Pa"):
        Material("soil", 2600, 0.3, **kw)


def test_time_step_above_rayleigh_bound():
    sim = Simulation(table(E=1e8), dt=1e-3)
    sim.add_particles([[0, 0, 0.01]], 2e-3, "soil")
    with pytest.raises(InputError, match=r"dt: expected a time step <= the Rayleigh time"):
        sim.run(10)
    assert sim.step == 0


def test_unknown_contact_model_name():
    with pytest.raises(InputError, match=r"contact_model\.rolling: expected one of"):
        Simulation(table(), contact_model=dict(rolling="type_b"))


def test_missing_pair_parameters():
    mats = MaterialTable()
    mats.add(Material("soil", 2600, 0.3, youngs=1e8))
    mats.add(Material("steel", 7800, 0.3, youngs=2e11))
    mats.set_pair("soil", "soil", 0.5, 0.5)
    sim = Simulation(mats)
    sim.add_particles([[0, 0, 0.01]], 2e-3, "soil")
    sim.add_plane((0, 0, 0), (0, 0, 1), "steel")
    with pytest.raises(InputError, match=r"interactions\.soil-steel: expected contact parameters"):
        sim.run(1)


def test_blow_up_names_step_and_particle():
    # a fast sphere hitting a soft floor: Hertz overlap ~ 40 % of the radius
    sim = Simulation(table(E=1e6), dt_fraction=0.2, gravity=(0, 0, 0))
    sim.add_particles([[0, 0, 0.05], [0.0, 0.0, 2.1e-3]], 2e-3, "soil",
                      v=[[0, 0, 0], [0, 0, -5.0]])
    sim.add_plane((0, 0, 0), (0, 0, 1), "soil")
    with pytest.raises(SimulationError, match=r"step \d+: particle 1: overlap above 5 % of its radius") as err:
        sim.run(10000)
    assert 0 < sim.step < 10000
    # the simulated time of the blow-up: its step times the time step, as the message gives both
    m = re.search(r"step (\d+):.*dt ([0-9.e+-]+) s, t ([0-9.e+-]+) s\)", str(err.value))
    assert m and float(m.group(3)) == pytest.approx(int(m.group(1)) * float(m.group(2)), rel=1e-3)
