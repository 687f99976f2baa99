"""Particle-swarm minimisation (pymoo's PSO) of an objective over a box of actual factor levels.

Velocity and position update (Kennedy & Eberhart 1995; Shi & Eberhart 1998 inertia weight), as
implemented in pymoo.algorithms.soo.nonconvex.pso:

    v <- w v + c1 r1 (p_best - x) + c2 r2 (g_best - x),   |v| <= 0.2 (x_u - x_l),   x <- x + v

with r1, r2 ~ U(0, 1) per particle and dimension. Inertia schedules:

- ``"linear"`` (default): w decreases linearly from w_max to w_min over the iterations, with
  c1 = c2 = 1.8, w from 0.9 to 0.2 as in Wei et al. (PLOS ONE, cohesive soil, Sec. 3.5);
- ``"adaptive"``: pymoo's fuzzy adaptation of w, c1, c2 (Zhan et al. 2009);
- a number: constant w.

The calibration objective of the cohesive-soil paper (Sec. 3.5, with its Eq. 9 relative error)
is the relative deviation of the regression prediction from the measured target,

    f(x) = |Y(x) - Y_target| / Y_target,

see :func:`target_error_objective`. The global best f after the initial swarm and after every
iteration is recorded (convergence history); ``converged_at`` is the first iteration after
which the global best improves by less than ``tol`` in total.

Determinism: each repeat r runs with its own integer seed drawn from
numpy.random.SeedSequence(seed); the seeds are recorded in the result.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
from pymoo.algorithms.soo.nonconvex.pso import PSO
from pymoo.core.problem import Problem

from soilcal.errors import InputError


class _BoxProblem(Problem):
    def __init__(self, fun: Callable, xl: np.ndarray, xu: np.ndarray):
        super().__init__(n_var=len(xl), n_obj=1, xl=xl, xu=xu)
        self._fun = fun
        self.n_calls = 0

    def _evaluate(self, X, out, *args, **kwargs):
        self.n_calls += X.shape[0]
        out["F"] = self._fun(X).reshape(-1, 1)


def _vectorise(objective: Callable) -> Callable[[np.ndarray], np.ndarray]:
    """Call ``objective`` on the (n, k) swarm; fall back to one row at a time if it returns
    something other than n values."""

    def fun(X: np.ndarray) -> np.ndarray:
        try:
            f = np.asarray(objective(X), dtype=float).reshape(-1)
        except Exception:
            f = None
        if f is None or f.size != X.shape[0]:
            f = np.array([float(np.asarray(objective(x), dtype=float).reshape(-1)[0]) for x in X])
        if not np.all(np.isfinite(f)):
            raise InputError(None, "objective", "finite values over the whole box", "NaN/inf")
        return f

    return fun


@dataclass
class PSOResult:
    """Best point, its objective, and the convergence history of the best repeat."""

    x: np.ndarray
    f: float
    history: np.ndarray
    seed: int
    seeds: list[int]
    n_evals: int
    converged_at: int
    repeats: list[dict] = field(default_factory=list)
    settings: dict = field(default_factory=dict)

    def __getitem__(self, key: str) -> Any:
        return getattr(self, key)

    def keys(self) -> list[str]:
        return ["x", "f", "history", "seed", "seeds", "n_evals", "converged_at", "repeats", "settings"]


def convergence_iteration(history: np.ndarray, tol: float = 1e-6) -> int:
    """First iteration after which the global best improves by less than ``tol`` in total."""
    h = np.asarray(history, dtype=float)
    if h.size == 0:
        return 0
    remaining = h - h[-1]
    idx = np.nonzero(remaining >= tol)[0]
    return int(idx[-1] + 1) if idx.size else 0


def _run(fun, xl, xu, particles, iterations, seed, inertia, w_max, w_min, c1, c2, tol):
    adaptive = inertia == "adaptive"
    w0 = w_max if inertia == "linear" else (0.9 if adaptive else float(inertia))
    problem = _BoxProblem(fun, xl, xu)
    algo = PSO(pop_size=particles, w=w0, c1=c1, c2=c2, adaptive=adaptive)
    algo.setup(problem, termination=("n_gen", iterations + 1), seed=int(seed), verbose=False)
    history = []
    t = 0
    while algo.has_next():
        if inertia == "linear" and t >= 1:
            frac = (t - 1) / max(iterations - 1, 1)
            algo.w = w_max - (w_max - w_min) * frac
        algo.next()
        history.append(float(algo.opt[0].F[0]))
        t += 1
    best = algo.opt[0]
    h = np.array(history)
    return {"x": np.asarray(best.X, dtype=float).copy(), "f": float(best.F[0]), "history": h,
            "seed": int(seed), "n_evals": problem.n_calls, "converged_at": convergence_iteration(h, tol)}


def pso_optimise(
    objective: Callable,
    bounds_actual,
    particles: int = 50,
    iterations: int = 200,
    seed: int = 0,
    repeats: int = 1,
    inertia: str | float = "linear",
    w_max: float = 0.9,
    w_min: float = 0.2,
    c1: float = 1.8,
    c2: float = 1.8,
    tol: float = 1e-6,
) -> PSOResult:
    """Minimise ``objective`` over the box ``bounds_actual`` ((k, 2) rows [low, high]).

    ``objective`` receives the swarm as an (n, k) array and returns n values (or, if it does
    not, is called on one (k,) row at a time). ``iterations`` velocity updates follow the initial
    (Latin hypercube) swarm, so the history has iterations + 1 entries. With ``repeats`` > 1 the
    best repeat is returned and every repeat's x, f and seed is listed in ``repeats``.
    The result supports ``res.x`` and ``res["x"]``.
    """
    if not callable(objective):
        raise InputError(None, "objective", "a callable f(X) -> values", type(objective).__name__)
    b = np.asarray(bounds_actual, dtype=float)
    if b.ndim != 2 or b.shape[1] != 2 or b.shape[0] < 1 or not np.all(np.isfinite(b)) or np.any(b[:, 1] <= b[:, 0]):
        raise InputError(None, "bounds_actual", "(k, 2) rows [low, high] with low < high", np.asarray(bounds_actual).tolist())
    for name, v, lo in (("particles", particles, 2), ("iterations", iterations, 1), ("repeats", repeats, 1)):
        if int(v) != v or v < lo:
            raise InputError(None, name, f"an integer >= {lo}", v)
    if not (inertia in ("linear", "adaptive") or isinstance(inertia, (int, float))):
        raise InputError(None, "inertia", "'linear', 'adaptive' or a number", inertia)
    if inertia == "linear" and not (0 < w_min <= w_max):
        raise InputError(None, "w_min/w_max", "0 < w_min <= w_max", (w_min, w_max))
    seeds = [int(s) for s in np.random.SeedSequence(int(seed)).generate_state(int(repeats))] if repeats > 1 else [int(seed)]
    fun = _vectorise(objective)
    runs = [_run(fun, b[:, 0], b[:, 1], int(particles), int(iterations), s, inertia, w_max, w_min, c1, c2, tol)
            for s in seeds]
    best = min(runs, key=lambda r: r["f"])
    return PSOResult(
        x=best["x"], f=best["f"], history=best["history"], seed=best["seed"], seeds=seeds,
        n_evals=sum(r["n_evals"] for r in runs), converged_at=best["converged_at"],
        repeats=[{"seed": r["seed"], "x": r["x"], "f": r["f"]} for r in runs],
        settings={"particles": int(particles), "iterations": int(iterations), "inertia": inertia,
                  "w_max": w_max, "w_min": w_min, "c1": c1, "c2": c2, "seed": int(seed), "repeats": int(repeats)},
    )


def target_error_objective(model, target: float) -> Callable[[np.ndarray], np.ndarray]:
    """f(X) = |Y(X) - target| / |target| with Y = ``model.predict_actual`` (actual levels)."""
    if not np.isfinite(target) or target == 0:
        raise InputError(None, "target", "a finite non-zero target value", target)

    def f(X: np.ndarray) -> np.ndarray:
        return np.abs(np.asarray(model.predict_actual(np.atleast_2d(X)), dtype=float) - target) / abs(target)

    return f


__all__ = ["PSOResult", "convergence_iteration", "pso_optimise", "target_error_objective"]
