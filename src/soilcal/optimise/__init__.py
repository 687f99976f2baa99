"""soilcal.optimise: Derringer-Suich desirability optimisation of fitted response surfaces
(:mod:`soilcal.optimise.desirability`) and particle-swarm minimisation with pymoo
(:mod:`soilcal.optimise.pso`)."""

from soilcal.optimise.desirability import (
    GOALS,
    Goal,
    ResponseModel,
    d_in_range,
    d_maximize,
    d_minimize,
    d_target,
    desirability_optimise,
    make_goal,
    overall_desirability,
)
from soilcal.optimise.pso import PSOResult, convergence_iteration, pso_optimise, target_error_objective

__all__ = [
    "GOALS",
    "Goal",
    "PSOResult",
    "ResponseModel",
    "convergence_iteration",
    "d_in_range",
    "d_maximize",
    "d_minimize",
    "d_target",
    "desirability_optimise",
    "make_goal",
    "overall_desirability",
    "pso_optimise",
    "target_error_objective",
]
