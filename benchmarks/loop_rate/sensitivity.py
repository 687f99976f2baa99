"""Which plate measure carries rate_friction above the seed scatter?  One condition of the DEM
campaign of ``benchmarks/loop.py`` (cinnamon soil, quick preset, line plate, 0.4 m/s, 30 mm),
built by its ``_campaign`` with all three plate measures and run by the loop's own DEM
simulator (``soilcal.loop.cli.dem_simulator``), with the effect switched on through
``soilcal.loop.effects`` so that both sliding frictions are scaled by f = 1 + beta ln(v / v0).
The plate stays at 0.4 m/s (so inertia does not change with f): f is set by the reference
speed, v0 = v exp(-(f - 1) / beta) at beta 0.4 (the campaign's hidden value, which maps its
speeds 0.1-1.0 m/s onto f 0.45-1.37).  Seeds FIRST-LAST (0-2: the loop's design seeds), common
to every f.  One JSON line per run: f, seed, the frictions, the horizontal and vertical force
and the resultant angle (the simulator's progress lines go to the same output; readers take
the lines that start with ``{``).

    nice python benchmarks/loop_rate/sensitivity.py FIRST-LAST F... >> OUT.jsonl

The rows of ``benchmarks/results/loop_rate/sensitivity.jsonl`` (24 DEM runs), summarised by
``sensitivity_summary.py``:

    nice python benchmarks/loop_rate/sensitivity.py 0-2 1.0 0.7 1.3 0.5 > sensitivity.jsonl
    nice python benchmarks/loop_rate/sensitivity.py 3-5 1.0 0.7 1.3 0.5 >> sensitivity.jsonl
"""
import json
import math
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # benchmarks/loop.py
import loop as B
from soilcal.loop import effects
from soilcal.loop.cli import condition_params, dem_simulator

BETA, SPEED, DEPTH = 0.4, 0.4, 0.03
first, last = (int(x) for x in sys.argv[1].split("-"))
factors = [float(x) for x in sys.argv[2:]]
with tempfile.TemporaryDirectory() as tmp:
    c0 = B._campaign(Path(tmp), 18, 0, responses=tuple(B.CAMPAIGN_RESPONSES))[0]  # the line plate
assert c0.setup["name"] == "plate-line"
c = replace(c0, setup={**c0.setup, "speed": SPEED, "depth": DEPTH},
            quantities={**c0.quantities, "tool_speed": SPEED, "working_depth": DEPTH})
sim = dem_simulator(1)
base = condition_params({})(c)
for f in factors:
    v0 = SPEED * math.exp(-(f - 1.0) / BETA)
    p = effects.apply_all({"rate_friction": {"beta": BETA}}, dict(base), c.quantities,
                          {**B.DEM_REFERENCE, "tool_speed": v0}, c.scenario)
    for s in range(first, last + 1):
        r = sim(c, p, s)
        print(json.dumps(dict(f=f, seed=s, v0=round(v0, 4), mu_ss=round(p["soil_soil_static_friction"], 4),
                              mu_st=round(p["soil_steel_static_friction"], 4),
                              **{m: round(float(r[m]), 3) for m in B.CAMPAIGN_RESPONSES})), flush=True)
