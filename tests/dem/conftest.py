import numpy as np
import pytest

from soilcal.dem.materials import Material, MaterialTable


def table(e=0.5, mu=0.5, mur=0.0, gamma=0.0, E=1e7, nu=0.3, rho=2600.0):
    mats = MaterialTable()
    mats.add(Material("soil", rho, nu, youngs=E))
    mats.set_pair("soil", "soil", e, mu, mur, gamma)
    return mats


@pytest.fixture
def rng():
    return np.random.default_rng(12345)
