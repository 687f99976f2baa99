"""Furrow-opener scenario: Eq. (3)-(4) area difference, profile slices, validation, a run."""

import math

import numpy as np
import pytest
from numpy.polynomial import Polynomial

from soilcal.dem.scenarios import furrow
from soilcal.errors import InputError


def test_area_difference_known_integrals():
    f = Polynomial([0.0, 0.0, 1.0])          # x^2
    # shifted by 1 over [-1, 1]: enclosed = signed = 2
    assert furrow.area_difference(f + 1.0, f, -1.0, 1.0) == pytest.approx((2.0, 2.0))
    # odd difference x: enclosed int |x| = 1, signed 0
    e, s = furrow.area_difference(f + Polynomial([0, 1.0]), f, -1.0, 1.0)
    assert e == pytest.approx(1.0) and s == pytest.approx(0.0, abs=1e-15)
    # x^3 - x on [-2, 2]: |.| integral = 2 * (1/4 + (4 - 2) - (1/4 - 1/2)) = 5
    e, s = furrow.area_difference(Polynomial([0, -1.0, 0, 1.0]), Polynomial([0.0]), -2, 2)
    assert e == pytest.approx(5.0) and s == pytest.approx(0.0, abs=1e-12)


def test_area_difference_of_eq3_against_itself_shifted():
    # Phi = F - 5 mm over [-200, 200] mm: enclosed 5 x 400 = 2000 mm^2 = 0.2 dm^2
    F = furrow.measured_profile()
    assert furrow.area_difference(F - 5.0, F, -200.0, 200.0) == pytest.approx(
        (2000.0, -2000.0), rel=1e-9)


def test_furrow_area_of_known_profiles():
    # flat bottom 30 mm below the surface over [-200, 200]: 30 x 400 mm^2 exactly (the
    # end points carry half weight)
    assert furrow.furrow_area(Polynomial([170.0]), 200.0, -200.0, 200.0) == pytest.approx(
        12000.0, rel=1e-12)
    # parabolic furrow Phi = 100 + x^2 / 400 under a surface at 200 mm: the profile stays
    # below it on [-200, 200], area = int (100 - x^2/400) dx = 40000 - 2 x 200^3 / 1200
    phi = Polynomial([100.0, 0.0, 1.0 / 400.0])
    exact = 40000.0 - 2 * 200.0**3 / 1200.0
    assert furrow.furrow_area(phi, 200.0, -200.0, 200.0) == pytest.approx(exact, rel=1e-5)


def test_named_default_values_set_by_the_user_are_kept():
    base = furrow.setups()["yangtze-opener"]
    assert furrow._settings(dict(base), "quick")["tank_length"] == 2.0
    # the user asks for the paper's 3.0 m tank under the quick preset
    s = furrow._settings(dict(base, overrides=["tank_length"]), "quick")
    assert s["tank_length"] == 3.0 and s["particle_radius"] == 0.022
    # a value other than the default is a user value even without the list
    assert furrow._settings(dict(base, tank_length=2.0), "quick")["tank_length"] == 2.0


def test_measured_profile_is_eq3():
    F = furrow.measured_profile()
    assert F.degree() == 9
    # the ten coefficients as printed in Eq. (3), constant term first
    printed = [7.28, -0.27, 4.41e-3, 2.97e-5, -9.65e-8, -2.05e-9, 2.12e-12, 5.65e-14,
               -1.96e-17, -5.04e-19]
    assert F.coef == pytest.approx(printed, rel=1e-12)
    # the polynomial turns over near +223.8 mm only: on the left it keeps rising
    d = F.deriv()
    r = np.real(d.roots()[np.abs(np.imag(d.roots())) < 1e-9])
    assert np.min(np.abs(r[r > 100] - 223.8)) < 1.0
    assert not np.any(r < 0)
    assert F(-300.0) == pytest.approx(1706.336, abs=1e-3)


def test_slice_profile_envelope_of_a_row_of_spheres():
    r = 0.01
    y = np.arange(0.0, 0.4001, 2 * r)
    x = np.column_stack([np.full_like(y, 0.5), y, np.full_like(y, 0.1)])
    rad = np.full(len(y), r)
    ym, zm = furrow.slice_profile(x, rad, 0.475, 0.525, 0.2, 0.0, 0.002, (0.0, 0.4))
    # envelope: 0.1 + sqrt(r^2 - (y - y_i)^2) of the nearest sphere, in mm
    yy = 0.2 + ym / 1e3
    dy = yy - np.round(yy / (2 * r)) * 2 * r
    assert zm == pytest.approx(1e3 * (0.1 + np.sqrt(r * r - dy * dy)), abs=1e-6)
    # a sphere outside the slice (and beyond its radius) does not count
    x2 = np.vstack([x, [0.6, 0.2, 0.5]])
    ym2, zm2 = furrow.slice_profile(x2, np.append(rad, r), 0.475, 0.525, 0.2, 0.0, 0.002,
                                    (0.0, 0.4))
    assert zm2.max() == pytest.approx(zm.max())


def test_fit_profile_recovers_polynomial():
    p = Polynomial([10.0, 0.0, 2e-3])
    y = np.linspace(-250, 250, 60)
    fit = furrow.fit_profile(y, p(y), 2, 200.0)
    assert fit.coef == pytest.approx(p.coef, abs=1e-9)


def _setup(**kw):
    s = dict(furrow.setups()["yangtze-opener"])
    s.update(kw)
    return s


@pytest.mark.parametrize("field,value,match", [
    ("depth", 0.3, "setup.depth"),          # deeper than the (quick) tank's soil
    ("speed", 0.0, "setup.speed"),
    ("speed", -0.72, "setup.speed"),
    ("x_limit", 0.3, "setup.x_limit"),
    ("n_slices", 20, "setup.n_slices"),
    ("depth", 0.04, "setup.depth"),         # shallower than 2 r_max = 48.4 mm (quick)
    # 0.05 + 0.45 + 0.7 + 0.9 = 2.1 m of tank needed, the quick tank is 2.0 m
    ("front_clearance", 0.9, "setup.tank_length"),
    ("front_clearance", 0.0, "setup.front_clearance"),
    ("front_clearance", 0.6, "setup.front_clearance"),  # less than four depths (0.8 m)
    ("max_overlap", 1.0, "setup.max_overlap"),
])
def test_impossible_settings_fail_before_the_run(field, value, match):
    with pytest.raises(InputError, match=match):
        furrow.validate(_setup(**{field: value}), "quick", "test")
    with pytest.raises(InputError, match=match):
        furrow.run(_setup(**{field: value}), furrow.paper_params(), "quick", use_cache=False)


def test_paper_tank_deeper_than_soil_fails():
    with pytest.raises(InputError, match="setup.depth"):
        furrow.validate(_setup(depth=0.35), "paper", "test")


@pytest.mark.slow
def test_quick_run_finite_and_opposing(tmp_path, monkeypatch):
    monkeypatch.setenv("SOILCAL_SCENARIO_CACHE", str(tmp_path))
    res = furrow.run(_setup(), furrow.paper_params(), "quick", seed=1, threads=1)
    r = res.responses
    for k in ("area_difference_dm2", "traction_N", "traction_sd_N", "furrow_area_dm2"):
        assert math.isfinite(r[k]), k
    assert r["traction_N"] > 0          # the soil resists the opener's advance
    assert res.n_particles > 500 and res.seed == 1
    row = res.row()
    assert row["r:traction_N"] == r["traction_N"] and row["p:soil_density"] == 2570.0
    assert list(tmp_path.glob("bin-*.npz"))  # settled bin kept for reuse


@pytest.mark.parametrize("preset", ["quick", "paper"])
def test_every_named_tool_setup_validates(preset):
    from soilcal.dem.scenarios import bulldozing, rotary

    for mod in (furrow, bulldozing, rotary):
        for name, s in mod.setups().items():
            mod.validate(dict(s, name=name), preset, f"{mod.NAME}:{name}")
