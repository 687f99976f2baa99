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
