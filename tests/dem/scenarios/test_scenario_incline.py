"""Inclined plane: a block slides once tan(theta) exceeds mu_s, a ball rolls once tan(theta)
exceeds mu_r (constant-torque model: rolling resistance mu_r F_n R against the gravity torque
m g sin(theta) R about the contact point), both analytic."""

import math

import pytest

from soilcal.dem.scenarios import incline
from soilcal.dem.scenarios.base import DemParams
from soilcal.errors import InputError


def onset(setup_name, **params):
    s = dict(incline.setups()[setup_name])
    s["start_deg"] = 0.0
    p = DemParams.from_mapping(dict(params, soil_soil_surface_energy=0.0), "test")
    return incline.run(s, p, "quick", seed=0, threads=1)


@pytest.mark.parametrize("mu", [0.4, 0.71])
def test_block_slides_at_the_friction_angle(mu):
    res = onset("yangtze-static", soil_steel_static_friction=mu)
    crit = math.degrees(math.atan(mu))
    r = res.responses
    assert r["moved"] == 1
    # the last stuck step may lie up to one 0.25 deg step above the friction angle (the
    # staircase samples the onset); the first moving step is above it
    assert r["last_stuck_deg"] < crit + 0.3
    assert r["first_moving_deg"] > crit
    assert r["coefficient"] == pytest.approx(mu, abs=0.012)


@pytest.mark.parametrize("mur", [0.097, 0.2])
def test_ball_rolls_at_the_rolling_friction_angle(mur):
    res = onset("yangtze-rolling", soil_steel_rolling_friction=mur, soil_steel_static_friction=0.71)
    crit = math.degrees(math.atan(mur))
    r = res.responses
    # within one 0.1 deg step below (the constant-torque model creeps near the threshold)
    # and two steps above the analytic onset
    assert crit - 0.1 < r["first_moving_deg"] < crit + 0.25
    assert r["coefficient"] == pytest.approx(mur, abs=0.004)
    assert res.n_particles == 1


def test_bad_incline_settings_fail_before_the_run():
    s = dict(incline.setups()["yangtze-static"])
    with pytest.raises(InputError, match="setup.max_deg"):
        incline.validate(dict(s, max_deg=95.0), "quick", "t")
    with pytest.raises(InputError, match="setup.block_diameter"):
        incline.validate(dict(s, block_diameter=0.005), "quick", "t")
    with pytest.raises(InputError, match="setup.kind"):
        incline.validate(dict(s, kind="tumbling"), "quick", "t")
    with pytest.raises(InputError, match="preset"):
        incline.validate(s, "slow", "t")
