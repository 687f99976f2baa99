"""The kernel-compile cases (soilcal.dem.scenarios.compile) are runs their scenarios accept: a case
the scenario refuses would stop rule dem_kernels before any kernel is compiled."""

import pytest

from soilcal.dem.scenarios import compile as kcompile
from soilcal.dem.scenarios import rotary
from soilcal.errors import InputError


@pytest.mark.parametrize("case", kcompile.cases(), ids=lambda c: c[0])
def test_every_compile_case_passes_its_scenarios_checks(case):
    label, mod, setup, params, _ = case
    mod.validate(setup, "quick", f"<{label}>", params=params)


def test_the_rotating_tool_case_keeps_its_short_pass_under_the_quick_preset():
    """The quick preset's 0.3 m pass, 0.85 m x 0.19 m bed and 250 ms settling would replace
    the case's own values if they were not the user's; two flatness points one particle
    diameter (2 x 13.2 mm) apart outside the trench need a pass of at least 4 r_max =
    52.8 mm (rotary module notes), which the case's 60 mm clears."""
    setup = next(c[2] for c in kcompile.cases() if c[1] is rotary)
    s = rotary.validate(setup, "quick", params=rotary.paper_params())
    assert (s["travel"], s["bin_length"], s["bin_height"], s["settle_time"]) == (0.06, 0.62, 0.09, 0.01)
    assert s["travel"] >= 4 * 0.012 * 1.1
    with pytest.raises(InputError, match="setup.travel"):
        rotary.validate(dict(setup, travel=0.05), "quick", params=rotary.paper_params())
