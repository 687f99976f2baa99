import numpy as np
import pytest

from soilcal.dem.materials import Material, MaterialTable
from soilcal.dem.scenarios import SCENARIOS


def table(e=0.5, mu=0.5, mur=0.0, gamma=0.0, E=1e7, nu=0.3, rho=2600.0, plasticity=0.0):
    mats = MaterialTable()
    mats.add(Material("soil", rho, nu, youngs=E))
    mats.set_pair("soil", "soil", e, mu, mur, gamma, plasticity)
    return mats


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
