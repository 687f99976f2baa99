"""Confined compression: monotonic loading of a settled bed; validation."""


import numpy as np
import pytest

from soilcal.dem.scenarios import compression
from soilcal.dem.scenarios.base import DemParams
from soilcal.errors import InputError


def test_compression_stress_rises_with_strain():
    # 600 spheres: a 300-sphere bed is too coarse for the stress to rise between 5 and 10 %
    # (seed 1: 0.051 then 0.040 kPa); the 600-sphere bed jams at 14 % strain, so 12 %
    s = dict(compression.setups()["guangxi-cohesive"], n_particles=600, max_strain=0.12,
             quick_height=0.03)
    res = compression.run(s, DemParams(soil_soil_surface_energy=0.0), "quick", seed=1, threads=1)
    se = res.series
    assert se["strain"].max() >= 0.12
    # the rod moves down at constant speed: strain grows linearly in time from first contact
    assert np.all(np.diff(se["strain"]) > 0)
    # loading: the stress at 10 % strain exceeds the stress at 5 %, and the curve rises
    # overall (a granular bed under a rod moving down at constant speed)
    r = res.responses
    assert r["stress_10_kpa"] > r["stress_5_kpa"] > 0
    loaded = se["strain"] > 0.02
    assert np.corrcoef(se["strain"][loaded], se["stress_pa"][loaded])[0, 1] > 0.8


def test_compression_stops_at_jamming_instead_of_blowing_up():
    # a loose bed cannot be pressed much beyond random close packing (solid fraction 0.64):
    # asked for 60 % strain, the run stops when the largest overlap reaches jam_overlap,
    # with the bed denser than poured and below the packing limit
    s = dict(compression.setups()["guangxi-cohesive"], n_particles=300, max_strain=0.6,
             quick_height=0.03, jam_overlap=0.15)
    res = compression.run(s, DemParams(soil_soil_surface_energy=0.0), "quick", seed=1, threads=1)
    r = res.responses
    assert r["stop_reason"] == "overlap" and r["strain_end"] < 0.6
    phi_end = r["solid_fraction_0"] / (1.0 - r["strain_end"])
    assert r["solid_fraction_0"] < 0.5 and r["solid_fraction_0"] < phi_end < 0.72
    assert np.isnan(compression.measure.value_at(res.series["strain"], res.series["stress_pa"], 0.59))


def test_compression_validation():
    s = dict(compression.setups()["guangxi-cohesive"])
    with pytest.raises(InputError, match="setup.rod_diameter"):
        compression.validate(dict(s, rod_diameter=0.12), "quick", "t")
    with pytest.raises(InputError, match="setup.rod_speed"):
        compression.validate(dict(s, rod_speed=-0.008), "quick", "t")
    with pytest.raises(InputError, match="setup.max_strain"):
        compression.validate(dict(s, max_strain=1.5), "quick", "t")
    with pytest.raises(InputError, match="setup.jam_overlap"):
        compression.validate(dict(s, jam_overlap=0.3), "quick", "t")


def test_paper_sample_too_large_for_memory_fails_before_the_run(monkeypatch):
    # 3 kg of the printed particle sizes (004 Sec. 3.7 and 2.6, half the spheres 0.315 mm
    # across) are tens of millions of spheres; with 8 GB available the run must stop at the
    # insertion with the count and the memory it would need, before any allocation
    from soilcal.dem import state

    monkeypatch.setattr(state, "available_memory", lambda: 8_000_000_000)
    s = dict(compression.setups()["guangxi-cohesive"])
    n = compression.sizing(s, "paper")["n"]
    assert n > 8e9 / state.BYTES_PER_PARTICLE
    with pytest.raises(InputError, match=r"particles\.n: expected a particle count whose engine "
                       r"state fits in the memory available here \(8 GB") as err:
        compression.run(s, DemParams(), "paper", seed=0, threads=1)
    assert f"{n:,} spheres" in str(err.value)


def test_unloaded_strain_is_the_zero_crossing_of_the_unloading_path():
    m = compression.measure
    # a straight unloading line from (0.10, 40 Pa) through (0.09, 20 Pa) crosses zero at 0.08
    assert m.unloaded_strain(0.10, 40.0, [0.095, 0.09, 0.085, 0.075], [30.0, 20.0, 10.0, -10.0]) \
        == pytest.approx(0.08, abs=1e-12)
    # the first sample already free: between the loading's end and it
    assert m.unloaded_strain(0.10, 30.0, [0.09], [-10.0]) == pytest.approx(0.0925, abs=1e-12)
    assert np.isnan(m.unloaded_strain(0.10, 30.0, [0.09, 0.08], [20.0, 5.0]))


def test_plastic_contacts_give_back_less_strain_on_unloading():
    """Loaded to 8 % and unloaded: an elastic (Hertz) bed recovers part of its strain, the
    contacts' own compression; with the plastic law each contact gives back only the part
    above its plastic overlap (an affine packing would keep 1 - lambda_p^(2/3) = 0.29 of the
    rebound at lambda_p = 0.6), so the same bed recovers less."""
    s = dict(compression.setups()["guangxi-cohesive"], n_particles=600, max_strain=0.08,
             quick_height=0.03, unload=True)
    rec = {}
    for lam in (0.0, 0.6):
        p = DemParams(soil_soil_surface_energy=0.0, soil_soil_plasticity=lam)
        res = compression.run(s, p, "quick", seed=1, threads=1)
        r, se = res.responses, res.series
        assert r["strain_end"] >= 0.08
        # the rod went back up until the bed let go of it
        assert np.all(np.diff(se["strain_unload"]) < 0) and se["stress_unload_pa"][-1] <= 0.0
        assert 0.0 < r["recovered_strain"] < r["strain_end"]
        rec[lam] = r["recovered_strain"]
    assert rec[0.6] < 0.8 * rec[0.0]


def test_unload_must_be_a_boolean():
    s = dict(compression.setups()["guangxi-cohesive"], unload="yes")
    with pytest.raises(InputError, match="setup.unload"):
        compression.validate(s, "quick", "t")
