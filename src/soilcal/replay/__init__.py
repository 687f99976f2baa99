"""Replay of a paper's calibration chain on its printed responses.

For every stage of a soil (Plackett-Burman screening, steepest ascent, Box-Behnken) the printed
table is taken as the response data: the design is regenerated and compared with the printed
one, the regression and ANOVA are recomputed, the optimisation is redone, and every place where
a recomputed number disagrees with a printed one beyond its printed precision is listed in
``errata.csv``.
"""

from soilcal.replay.stage import (
    design_frame,
    fit_stage,
    optimum_frame,
    regression_frames,
    stage_data,
)

__all__ = ["design_frame", "fit_stage", "optimum_frame", "regression_frames", "stage_data"]
