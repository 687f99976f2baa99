"""soilcal.dem: Numba discrete-element engine for soil calibration.

Spheres with Hertz-Mindlin contacts (EDEM/LIGGGHTS damping), rolling resistance (constant
torque or EPSD), JKR cohesion, plane and mesh walls, periodic x/y boundaries.  See
:mod:`soilcal.dem.contact` for the contact formulas and :class:`soilcal.dem.engine.Simulation`
for the Python interface.
"""

import os

# The engine launches a few short parallel loops per time step.  With the OpenMP threading
# layer's default active waiting, a launch costs milliseconds as soon as another process
# shares the cores; passive waiting keeps it at microseconds.  Users may override it.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
