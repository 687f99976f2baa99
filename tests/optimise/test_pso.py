"""Particle-swarm minimisation on functions with known minima."""

from __future__ import annotations

import numpy as np
import pytest

from soilcal.errors import InputError
from soilcal.optimise import convergence_iteration, pso_optimise, target_error_objective

CENTRE = np.array([1.0, -2.0, 0.5])


def shifted_sphere(X):
    X = np.atleast_2d(X)
    return np.sum((X - CENTRE) ** 2, axis=1)


def rosenbrock(X):
    X = np.atleast_2d(X)
    return 100 * (X[:, 1] - X[:, 0] ** 2) ** 2 + (1 - X[:, 0]) ** 2


def test_sphere_minimum_and_history():
    r = pso_optimise(shifted_sphere, [[-5, 5]] * 3, particles=30, iterations=60, seed=1)
    assert np.allclose(r.x, CENTRE, atol=1e-3)
    assert r.f < 1e-6
    assert r.history.shape == (61,)  # initial swarm + one per iteration
    assert np.all(np.diff(r.history) <= 0)  # global best never worsens
    assert r.history[-1] == r.f
    assert r.n_evals == 30 * 61
    assert 0 < r.converged_at <= 60


def test_rosenbrock_paper_swarm_settings():
    # 50 particles, 200 iterations, c1 = c2 = 1.8, w 0.9 -> 0.2 (cohesive-soil paper, Sec. 3.5)
    r = pso_optimise(rosenbrock, [[-2, 2], [-1, 3]], particles=50, iterations=200, seed=7)
    assert np.allclose(r.x, [1.0, 1.0], atol=1e-2)
    assert r.settings["c1"] == 1.8 and r.settings["w_max"] == 0.9 and r.settings["w_min"] == 0.2


def test_deterministic_and_seed_dependent():
    a = pso_optimise(shifted_sphere, [[-5, 5]] * 3, particles=20, iterations=30, seed=42)
    b = pso_optimise(shifted_sphere, [[-5, 5]] * 3, particles=20, iterations=30, seed=42)
    c = pso_optimise(shifted_sphere, [[-5, 5]] * 3, particles=20, iterations=30, seed=43)
    assert np.array_equal(a.x, b.x) and np.array_equal(a.history, b.history)
    assert not np.array_equal(a.history, c.history)


def test_repeats_keep_the_best_and_record_seeds():
    r = pso_optimise(rosenbrock, [[-2, 2], [-1, 3]], particles=10, iterations=15, seed=3, repeats=3)
    assert len(r.seeds) == 3 and len(set(r.seeds)) == 3
    assert r.f == min(p["f"] for p in r.repeats)
    assert r.seed in r.seeds
    assert r["x"] is r.x and r["f"] == r.f  # mapping access as well as attributes


def test_adaptive_and_constant_inertia():
    for inertia in ("adaptive", 0.6):
        r = pso_optimise(shifted_sphere, [[-5, 5]] * 3, particles=30, iterations=80, seed=2, inertia=inertia)
        assert np.allclose(r.x, CENTRE, atol=1e-2)


def test_scalar_objective_is_called_row_by_row():
    calls = []

    def f(x):
        calls.append(np.shape(x))
        return float(np.sum((np.asarray(x) - 0.25) ** 2))

    r = pso_optimise(f, [[0, 1], [0, 1]], particles=10, iterations=30, seed=0)
    assert np.allclose(r.x, [0.25, 0.25], atol=1e-3)
    assert (2,) in calls


def test_target_error_objective_on_a_linear_model():
    class Line:
        def predict_actual(self, X):
            X = np.atleast_2d(X)
            return 30.0 + 10.0 * X[:, 0]  # angle 35 at x = 0.5

    f = target_error_objective(Line(), 35.0)
    assert f(np.array([[0.0], [0.5]])) == pytest.approx([5 / 35, 0.0])
    r = pso_optimise(f, [[0.0, 1.0]], particles=10, iterations=40, seed=0)
    assert r.x[0] == pytest.approx(0.5, abs=1e-4)


def test_convergence_iteration():
    h = np.array([5.0, 2.0, 1.0, 1.0, 1.0])
    assert convergence_iteration(h, 1e-9) == 2
    assert convergence_iteration(np.array([1.0, 1.0])) == 0


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"bounds_actual": [[1, 0]]}, "bounds_actual"),
        ({"bounds_actual": [0, 1]}, "bounds_actual"),
        ({"particles": 1}, "particles"),
        ({"iterations": 0}, "iterations"),
        ({"inertia": "random"}, "inertia"),
    ],
)
def test_bad_input(kwargs, field):
    args = {"objective": shifted_sphere, "bounds_actual": [[-1, 1]] * 3, **kwargs}
    with pytest.raises(InputError) as e:
        pso_optimise(**args)
    assert e.value.field == field


def test_nan_objective_is_reported():
    with pytest.raises(InputError, match="objective"):
        pso_optimise(lambda X: np.full(len(X), np.nan), [[0, 1]], particles=4, iterations=2)
