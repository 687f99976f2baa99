"""The loop's analytic compression stand-in (soilcal.loop.standin, scenario
``standin_compression``) against its closed forms, computed by hand here: the loading stress
sigma = C E* eps^1.5 of an affine Hertz packing (C = phi Z / (3 pi) with phi = 0.6, Z = 6) and
the strain recovered on unloading with the plastic Hertz law, eps_max (1 - lambda_p^(2/3))."""

from __future__ import annotations

import math

import numpy as np
import pytest

from soilcal.errors import InputError
from soilcal.loop import standin as S

# G = 1e6 Pa, nu = 0.3 (the stand-in's calibrated set): E = 2 G (1 + nu) = 2.6e6 Pa,
# E* = E / (2 (1 - nu^2)) = 2.6e6 / 1.82 = 1.428571e6 Pa; C = 0.6 * 6 / (3 pi) = 0.3819719;
# sigma(0.1) = 0.3819719 * 1.428571e6 * 0.1^1.5 (= 0.0316228) = 17255.7 Pa
STRESS_10_KPA = 17.2557


@pytest.mark.parametrize("lp, recovered", [
    (0.0, 0.2),      # elastic Hertz: the whole contact strain comes back
    (0.125, 0.15),   # 0.125^(2/3) = 0.5^2 = 0.25: 0.2 * 0.75
    (0.512, 0.072),  # 0.512^(2/3) = 0.8^2 = 0.64: 0.2 * 0.36
])
def test_recovered_strain_closed_form(lp, recovered):
    params = dict(S.BASE, soil_soil_plasticity=lp)
    out = S.compression(params, {"max_strain": 0.2})
    assert out["recovered_strain"] == pytest.approx(recovered, rel=1e-12)
    # loading is Hertz's whatever lambda_p: the stress at 10 % strain does not move
    assert out["stress_10_kpa"] == pytest.approx(STRESS_10_KPA, rel=1e-5)


def test_a_parameter_set_without_plasticity_is_elastic():
    assert "soil_soil_plasticity" not in S.BASE
    out = S.compression(S.BASE, {"max_strain": 0.25})
    assert out["recovered_strain"] == pytest.approx(0.25, rel=1e-12)
    assert out["stress_10_kpa"] == pytest.approx(STRESS_10_KPA, rel=1e-5)


def test_stress_scales_with_the_contact_modulus():
    # G doubled: E* doubled, so the stress at 10 % strain doubles; nu = 0: E* = 2 G / 2 = G
    out = S.compression(dict(S.BASE, soil_shear_modulus=2e6), {"max_strain": 0.2})
    assert out["stress_10_kpa"] == pytest.approx(2 * STRESS_10_KPA, rel=1e-5)
    out = S.compression(dict(S.BASE, soil_poisson=0.0), {"max_strain": 0.2})
    # 1.2 / pi * 1e6 * 0.1^1.5 = 0.3819719 * 1e6 * 0.0316228 = 12079.0 Pa
    assert out["stress_10_kpa"] == pytest.approx(12.0790, rel=1e-5)


def test_stopped_before_ten_percent_has_no_stress_at_ten_percent():
    out = S.compression(S.BASE, {"max_strain": 0.08})
    assert math.isnan(out["stress_10_kpa"])
    assert out["recovered_strain"] == pytest.approx(0.08, rel=1e-12)


def test_simulate_dispatches_on_the_scenario_with_common_random_numbers():
    cond = S.compression_conditions([{"max_strain": 0.2}])[0]
    assert cond.scenario == "standin_compression"
    a = S.simulate(cond, dict(S.BASE, soil_soil_plasticity=0.125), 7)
    b = S.simulate(cond, dict(S.BASE, soil_soil_plasticity=0.512), 7)
    # same seed and row, same scatter: the ratio is the closed form's, 0.36 / 0.75 = 0.48
    assert b["recovered_strain"] / a["recovered_strain"] == pytest.approx(0.48, rel=1e-12)
    assert b["stress_10_kpa"] == a["stress_10_kpa"]
    blade = S.conditions([{"working_depth": 0.1}])[0]
    assert set(S.simulate(blade, S.BASE, 7)) == {"horizontal_force_N", "vertical_force_N"}


def test_seed_scatter_is_one_percent():
    cond = S.compression_conditions([{"max_strain": 0.2}])[0]
    rec = np.array([S.simulate(cond, S.BASE, s)["recovered_strain"] for s in range(400)]) / 0.2
    # relative normal scatter, SD 1 % (standard error of the SD over 400 draws: about 0.04 %)
    assert abs(rec.mean() - 1.0) < 0.002
    assert 0.008 < rec.std(ddof=1) < 0.012


def test_refuses_an_unknown_scenario_and_a_bad_max_strain():
    from dataclasses import replace

    cond = S.compression_conditions([{"max_strain": 0.2}])[0]
    with pytest.raises(InputError, match="scenario"):
        S.simulate(replace(cond, scenario="compression"), S.BASE, 0)
    for bad in (0.0, 0.95, None):
        with pytest.raises(InputError, match="max_strain"):
            S.compression(S.BASE, {"max_strain": bad})
