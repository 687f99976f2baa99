"""The measured-data loop: residual -> the effect the model lacks -> refit -> error before and after.

* :mod:`soilcal.loop.residuals`: the measured conditions beside the calibrated simulation;
* :mod:`soilcal.loop.diagnose`: structure in the residual (bias, trend, curvature, groups,
  excess scatter) with Holm-corrected p-values;
* :mod:`soilcal.loop.effects`: the effect library, physical mechanisms as switchable
  changes of the DEM parameters of a condition;
* :mod:`soilcal.loop.select`: surrogates over each effect's design, leave-one-group-out
  held-out errors, paired test and AICc, forward selection with a backward gate;
* :mod:`soilcal.loop.core`: the steps in order, for the workflow and in one process;
* :mod:`soilcal.loop.synthesize`: measurement tables with a hidden effect;
* :mod:`soilcal.loop.files`: the workflow's file-level functions and the report.
"""

#: the key of a run's answer (and the column of a run table) holding why it failed; here, so
#: that the command line reads it without importing pandas
ERROR_KEY = "error"
