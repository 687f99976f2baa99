"""GrainLearning's benchmark refuses a case whose goal is an optimisation (minimize or
maximize) with the reason, and runs one whose every goal is a target value."""

from __future__ import annotations

import math

import pytest

from soilcal.doe import adaptive as ad


@pytest.fixture(scope="module")
def gl(load_benchmark):
    return load_benchmark("adaptive_gl.py", "adaptive_gl_bench")


def _problem(*targets):
    return ad.Problem([ad.Factor("A", 0.1, 0.5)], list(targets))


def test_a_minimised_response_is_not_an_inverse_problem(gl):
    why = gl.not_applicable(_problem(ad.Target("area_difference", math.nan, tol=0.1, goal="minimize")))
    assert why.startswith("not applicable: goal minimize has no observed value")
    mixed = _problem(ad.Target("angle", 30.0), ad.Target("force", math.nan, tol=5.0, goal="maximize"))
    assert "goal maximize" in gl.not_applicable(mixed)


def test_target_values_are_calibrated(gl):
    assert gl.not_applicable(_problem(ad.Target("angle", 30.0), ad.Target("dynamic", 42.0))) == ""
