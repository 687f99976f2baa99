"""The calibration chain of a soil, one stage after another, whatever the source of its
responses.

Each stage goes design -> responses -> regression/ANOVA -> optimisation -> figures, and the
calibrated parameters are then verified.  The modules:

* :mod:`~soilcal.chain.derive` - the stage a source runs: the config's stage (published), or
  the stage derived from the DEM results of the stage before it (steepest path from the
  screening, Box-Behnken centre from the path, values fixed at an earlier optimum);
* :mod:`~soilcal.chain.sources` - the two response sources: the printed table, or one DEM job
  per design point gathered into a table of the same layout;
* :mod:`~soilcal.chain.stage` - design, regression/ANOVA and optimum of one stage (plain data);
* :mod:`~soilcal.chain.files` - the file-level writers every source shares;
* :mod:`~soilcal.chain.targets` - the target values (printed, or measured on the soil's photos);
* :mod:`~soilcal.chain.verify` - verification at the calibrated set, tool tests, comparison
  with the paper's calibrated parameters;
* :mod:`~soilcal.chain.refine` - the second round: a bias-corrected set where the first
  verification missed its target;
* :mod:`~soilcal.chain.adaptive` - ``design: adaptive``: the sequential design of
  :mod:`soilcal.doe.adaptive` per optimisation case, its iteration records, DEM point specs
  and the recipe's output files;
* :mod:`~soilcal.chain.errata` - every printed number the published replay does not reproduce;
* :mod:`~soilcal.chain.plan` - which sources a soil runs.

Nothing is imported here eagerly: a DEM job imports only :mod:`~soilcal.chain.sources` and
the engine, not the statistics stack.
"""

_STAGE = ("design_frame", "fit_stage", "optimum_frame", "regression_frames", "stage_data")


def __getattr__(name):
    if name in _STAGE:
        from soilcal.chain import stage

        return getattr(stage, name)
    raise AttributeError(name)


__all__ = list(_STAGE)
