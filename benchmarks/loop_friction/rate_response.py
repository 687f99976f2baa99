"""Does the quick bulldozing plate's horizontal force respond to the rate_friction effect?
Line plate (the loop benchmark's campaign setup), 30 mm deep, speeds 0.1 and 1.0 m/s, beta 0
and 0.4 (reference 0.4 m/s, ``benchmarks/loop.py``'s ``DEM_REFERENCE``), seeds 1000 on
(common to every cell).  Prints per cell the effect's soil-soil and soil-steel friction, the
forces, their geometric mean and the SD of their logarithm.

    python benchmarks/loop_friction/rate_response.py [NSEEDS]    (default 6)

``loop.md``'s item on rate_friction quotes ``rate_response.py 4`` (16 DEM runs; its output in
``benchmarks/results/loop_friction/rate_response_4.txt``).
"""
import math
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # benchmarks/loop.py
import loop as B
from soilcal.loop import effects
from soilcal.loop.cli import condition_params, dem_simulator

seeds = range(1000, 1000 + int(sys.argv[1] if len(sys.argv) > 1 else 6))
with tempfile.TemporaryDirectory() as tmp:
    c0 = B._campaign(Path(tmp), 18, 0)[0]  # the line plate
sim = dem_simulator(1)
base = condition_params({})
for v in (0.1, 1.0):
    for beta in (0.0, 0.4):
        c = replace(c0, setup={**c0.setup, "speed": v, "depth": 0.03},
                    quantities={**c0.quantities, "tool_speed": v, "working_depth": 0.03})
        p = effects.apply_all({"rate_friction": {"beta": beta}} if beta else {}, base(c), c.quantities,
                              B.DEM_REFERENCE, c.scenario)
        f = [sim(c, p, s)["horizontal_force_N"] for s in seeds]
        print(f"v={v} beta={beta} mu_ss={p['soil_soil_static_friction']:.3f} mu_st={p['soil_steel_static_friction']:.3f} "
              f"F={np.round(f, 1).tolist()} gmean={math.exp(np.mean(np.log(f))):.2f} "
              f"sdlog={np.std(np.log(f), ddof=1):.3f}", flush=True)
