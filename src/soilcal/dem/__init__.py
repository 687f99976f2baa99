"""soilcal.dem: Numba discrete-element engine for soil calibration.

Spheres with Hertz-Mindlin contacts (EDEM/LIGGGHTS damping), rolling resistance (constant
torque or EPSD), JKR cohesion, plane and mesh walls, periodic x/y boundaries.  See
:mod:`soilcal.dem.contact` for the contact formulas and :class:`soilcal.dem.engine.Simulation`
for the Python interface.
"""

import os

from numba import config as _numba_config

# The engine launches three short parallel loops per time step, so the cost of a launch
# matters.  Measured on the 2-core machines of this project (empty loop over 5,000 items,
# 2 threads): OpenMP with its default spin-then-sleep waiting 7 us, OpenMP with passive
# waiting 109 us, TBB 217 us, workqueue 159 us.  Prefer OpenMP (TBB and workqueue remain the
# fallbacks where no OpenMP runtime is found) unless the user chose a layer or a priority.
if "NUMBA_THREADING_LAYER" not in os.environ and "NUMBA_THREADING_LAYER_PRIORITY" not in os.environ:
    _numba_config.THREADING_LAYER_PRIORITY = ["omp", "tbb", "workqueue"]

# Numba's cache follows each function's own file only: drop the package's cached kernels
# when any of its sources changed, before a kernel loads (soilcal.dem._kernel_cache)
from soilcal.dem._kernel_cache import refresh_package as _refresh_kernel_cache  # noqa: E402

_refresh_kernel_cache()
