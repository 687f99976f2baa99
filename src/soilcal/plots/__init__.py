"""soilcal.plots: calibration figures (response surfaces, Pareto chart, steepest-ascent path,
regression diagnostics, optimiser convergence; DEM verification against targets, tool
measurements and the papers' printed simulations), each written as <stem>.png (150 dpi) and
<stem>.pdf; see :mod:`soilcal.plots.figures` and
:mod:`soilcal.plots.dem`."""

from soilcal.plots.dem import summary_figure, tool_bars, tool_curves, verification_bars
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
    "summary_figure",
    "tool_bars",
    "tool_curves",
    "verification_bars",
]
