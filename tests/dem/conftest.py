import numpy as np
import pytest

from soilcal.dem.materials import Material, MaterialTable
from soilcal.dem.scenarios import SCENARIOS


def table(e=0.5, mu=0.5, mur=0.0, gamma=0.0, E=1e7, nu=0.3, rho=2600.0, plasticity=0.0):
    mats = MaterialTable()
    mats.add(Material("soil", rho, nu, youngs=E))
    mats.set_pair("soil", "soil", e, mu, mur, gamma, plasticity)
    return mats


def head_on(mats, v0, radius, dt, normal="hertz", gap=1e-7, max_steps=200000):
    """Two equal spheres of material "soil" ``gap`` apart approaching head-on at v0 without
    gravity or tangential force: (rebound speed / v0, contact time)."""
    from soilcal.dem.engine import Simulation

    sim = Simulation(mats, dt=dt, gravity=(0, 0, 0),
                     contact_model=dict(normal=normal, tangential="none"))
    sim.add_particles([[0, 0, 0], [2 * radius + gap, 0, 0]], radius, "soil",
                      v=[[v0 / 2, 0, 0], [-v0 / 2, 0, 0]])
    steps_in = 0
    touched = False
    for _ in range(max_steps):
        sim.run(1)
        gap = sim.x[1, 0] - sim.x[0, 0] - 2 * radius
        if gap < 0:
            touched = True
            steps_in += 1
        elif touched:
            break
    return (sim.v[1, 0] - sim.v[0, 0]) / v0, steps_in * dt


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture(autouse=True)
def _declared_responses(monkeypatch):
    """Every scenario run in these tests reports only responses its module declares
    (``RESPONSES``; a soil's ``simulation`` block may measure its ``MEASURES``)."""
    for mod in set(SCENARIOS.values()):
        def checked(*args, _run=mod.run, _mod=mod, **kw):
            res = _run(*args, **kw)
            extra = set(res.responses) - set(_mod.RESPONSES)
            assert not extra, f"{_mod.NAME} reports undeclared responses {sorted(extra)}"
            return res
        monkeypatch.setattr(mod, "run", checked)
