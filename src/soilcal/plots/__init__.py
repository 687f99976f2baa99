"""soilcal.plots: calibration figures (response surfaces, Pareto chart, steepest-ascent path,
regression diagnostics, optimiser convergence), each written as <stem>.png (150 dpi) and
<stem>.pdf; see :mod:`soilcal.plots.figures`."""

from soilcal.plots.figures import (
    convergence,
    factor_label,
    pareto_effects,
    predicted_vs_actual,
    residual_diagnostics,
    response_surface,
    save_figure,
    standardized_effects,
    steepest_ascent,
)

__all__ = [
    "convergence",
    "factor_label",
    "pareto_effects",
    "predicted_vs_actual",
    "residual_diagnostics",
    "response_surface",
    "save_figure",
    "standardized_effects",
    "steepest_ascent",
]
