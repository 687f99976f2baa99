"""A soil's own sphere sizes in the bulldozing and rotary soil bins.

The named setups of these tool tests are a shipped soil's apparatus; the bin's spheres are the
preset's unless the soil's ``set:`` gives its own, as the furrow's ``particle_radius`` and the
bench-top tests' ``radius`` allow.  The expected radii are the ones written here, and the
surface-energy factor is the ratio of Sauter radii r32 = <r^3>/<r^2> worked out by hand: for
radii uniform by number on [a, b], r32 = 3 (b^4 - a^4) / (4 (b^3 - a^3)); for discrete sizes of
mass fractions f_k, r32 = 1 / sum f_k / r_k."""

from __future__ import annotations

import textwrap

import pytest
import yaml

from own_soil import bbd_soil, write_soil
from soilcal.config import load_soil
from soilcal.dem.scenarios import bulldozing, rotary
from soilcal.dem.scenarios.base import merge_setup
from soilcal.errors import InputError


def r32_uniform(a, b):
    return 0.75 * (b**4 - a**4) / (b**3 - a**3)


# bulldozing, paper preset's bin: diameters 3, 2, 1 mm, mass 8.85, 8.2, 82.95 %
R32_PLATE_PAPER = 1.0 / (0.0885 / 0.0015 + 0.082 / 0.001 + 0.8295 / 0.0005)
# rotary, paper preset's bin: radius 1.5 mm +- 1/3, i.e. uniform on [1, 2] mm
R32_ROTOR_PAPER = r32_uniform(0.001, 0.002)


@pytest.mark.parametrize("preset", ["quick", "paper"])
@pytest.mark.parametrize("mod,name,ref", [(bulldozing, "plate-line", R32_PLATE_PAPER),
                                          (rotary, "rpm-250", R32_ROTOR_PAPER)])
def test_own_uniform_radii_are_the_bins_spheres(mod, name, ref, preset):
    setup = merge_setup(mod.setups(), name, {"particle_radius": 0.004, "radius_spread": 0.05}, "own.yaml")
    s = mod.validate(setup, preset, "own.yaml")
    spec = mod._bin(s) if mod is rotary else mod._bin(s, "own.yaml")
    assert spec.r_min == pytest.approx(0.0038) and spec.r_max == pytest.approx(0.0042)
    assert spec.psd is None
    assert s["cohesion_scale"] == pytest.approx(r32_uniform(0.0038, 0.0042) / ref, rel=1e-9)


def test_own_size_distribution_of_the_plate_bin():
    # diameters 8 and 6 mm, 40 and 60 % by mass: the bin holds them, the quick preset's
    # uniform 7 mm radii do not take their place
    setup = merge_setup(bulldozing.setups(), "plate-line",
                        {"psd_sizes": [0.008, 0.006], "psd_mass_percent": [40, 60]}, "own.yaml")
    s = bulldozing.validate(setup, "quick", "own.yaml")
    spec = bulldozing._bin(s, "own.yaml")
    assert spec.r_min == pytest.approx(0.003) and spec.r_max == pytest.approx(0.004)
    assert s["cohesion_scale"] == pytest.approx(1.0 / (0.4 / 0.004 + 0.6 / 0.003) / R32_PLATE_PAPER)


@pytest.mark.parametrize("given,preset,field", [
    ({"particle_radius": 0.004, "psd_sizes": [0.006], "psd_mass_percent": [100]}, "quick", "setup.particle_radius"),
    ({"particle_radius": 0.004}, "paper", "setup.particle_radius"),   # the paper preset's are a distribution
    ({"particle_radius": 0.004}, "quick", "setup.particle_radius"),   # not at the quick preset's spread
    ({"psd_sizes": [0.006, 0.004]}, "quick", "setup.psd_sizes"),      # the quick preset's are uniform
    # half a distribution under the paper preset: the soil's sizes would run at the paper's
    # mass fractions (or the paper's sizes at the soil's)
    ({"psd_sizes": [0.006, 0.004, 0.002]}, "paper", "setup.psd_sizes"),
    ({"psd_mass_percent": [50, 30, 20]}, "paper", "setup.psd_mass_percent"),
])
def test_incomplete_or_mixed_sizes_are_refused_naming_the_field(given, preset, field):
    setup = merge_setup(bulldozing.setups(), "plate-line", given, "own.yaml")
    with pytest.raises(InputError) as exc:
        bulldozing.validate(setup, preset, "own.yaml")
    assert exc.value.field == field and "own.yaml" in str(exc.value)


def test_own_distribution_leaves_no_preset_radius_in_the_settings():
    # the quick preset's uniform 7 mm +- 10 % are not the run's spheres: the settings a run
    # and simulation.csv record must not list them
    setup = merge_setup(bulldozing.setups(), "plate-line",
                        {"psd_sizes": [0.008, 0.004], "psd_mass_percent": [50, 50]}, "own.yaml")
    s = bulldozing.validate(setup, "quick", "own.yaml")
    assert s["particle_radius"] is None and s["radius_spread"] is None
    assert s["psd_sizes"] == [0.008, 0.004]


@pytest.mark.parametrize("given", [{"particle_radius": 0.004}, {"radius_spread": 0.1}])
def test_rotary_half_of_the_own_radii_is_refused(given):
    setup = merge_setup(rotary.setups(), "rpm-250", given, "own.yaml")
    with pytest.raises(InputError) as exc:
        rotary.validate(setup, "paper", "own.yaml")
    assert exc.value.field == f"setup.{next(iter(given))}"


def test_rotary_particle_radius_error_names_the_particle_radius():
    setup = merge_setup(rotary.setups(), "rpm-250", {"particle_radius": -0.002, "radius_spread": 0.1}, "own.yaml")
    with pytest.raises(InputError) as exc:
        rotary.validate(setup, "quick", "own.yaml")
    assert exc.value.field == "setup.particle_radius"


#: the soil's measured tool tests beside its one Box-Behnken stage (own_soil.bbd_soil), each
#: with its own bin spheres
MEASUREMENTS = textwrap.dedent("""\
    plate:
      table: plate.csv
      scenario: bulldozing
      setup: plate-line
      set: {particle_radius: 0.004, radius_spread: 0.05, paper_psd: [[0.0008, 100]]}
      responses:
        - {measure: horizontal_force_N, value: horizontal_N, unit: N}
      calibrated: {stage: bbd, case: angle}
    tiller:
      table: tiller.csv
      scenario: rotary
      setup: rpm-250
      set: {particle_radius: 0.006, radius_spread: 0.1}
      responses:
        - {measure: flatness_mm, value: flatness_mm, unit: mm}
      calibrated: {stage: bbd, case: angle}
    """)


def _write(tmp_path, edit=None):
    d = bbd_soil("own-bin", {"rolling": (0.1, 0.3), "energy": (0.2, 0.6), "steel": (0.4, 0.8)}, target_angle=35.0,
                 measurements=yaml.safe_load(MEASUREMENTS))
    if edit:
        edit(d)
    return write_soil(tmp_path, d, {"plate.csv": "horizontal_N\n120.5\n", "tiller.csv": "flatness_mm\n14.0\n"})


def test_a_soil_sets_its_own_bin_spheres_in_its_measurements_block(tmp_path):
    soil = load_soil(_write(tmp_path), tmp_path)
    assert soil.data["measurements"]["plate"]["set"]["particle_radius"] == 0.004


def test_half_a_distribution_in_the_soil_file_names_the_soils_key(tmp_path):
    path = _write(tmp_path, lambda d: d["measurements"]["plate"].update(
        preset="paper", set={"psd_sizes": [0.006, 0.004, 0.002]}))
    with pytest.raises(InputError) as exc:
        load_soil(path, tmp_path)
    assert exc.value.field == "measurements.plate.set.psd_sizes" and str(path) in str(exc.value)
