"""Why does the quick bulldozing plate's horizontal force not follow the sliding friction above
the calibrated value?  Line plate (the loop benchmark's campaign setup), 30 mm deep, at a speed
given on the command line; the soil-soil and soil-steel sliding friction scaled by factors
(f_ss, f_st) from the calibrated 0.56 / 0.54; the bed settled either at the run's own friction
(as the loop's runs do: the settled bin's cache key holds the soil-soil parameters) or at the
calibrated friction ("bed_cal": the friction changed for the pass only).  Seeds 1000.. (common
to every variant).  Prints per variant the forces, geometric mean and SD of log force.

    python benchmarks/loop_friction/friction_split.py SPEED NSEEDS VARIANT... > OUT.jsonl
    (VARIANT: fss,fst[,cal][,rFR]; FR: factor on the soil-soil rolling friction 0.11, for the
    pass and the bed alike)

The rows of ``loop.md``'s table (``benchmarks/results/loop_friction/``, one JSON line per variant, DEM runs):

    friction_split.py 0.1 4 1,1 0.45,0.45 1.366,1.366 2,2 1,2 2,1 1.366,1.366,cal 0.45,0.45,cal 0.7,0.7
        > split_v01.jsonl
    friction_split.py 1.0 4 1,1 1.366,1.366 1.366,1.366,cal 1,1.366 1.366,1 2,2 2,2,cal 1,2 2,1
        > split_v1.jsonl   (written before the rolling factor existed: no "fr" key)
    friction_split.py 1.0 12 1,1,cal 1.366,1.366,cal 2,2,cal 0.45,0.45,cal > split_v1_paired.jsonl
"""
import json
import math
import sys
import tempfile
from pathlib import Path
import numpy as np
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # benchmarks/loop.py
import loop as B
from soilcal.dem.scenarios import bulldozing as BZ
from soilcal.dem.scenarios.base import DemParams
from soilcal.loop.cli import condition_params

speed, nseeds = float(sys.argv[1]), int(sys.argv[2])
variants = sys.argv[3:]
with tempfile.TemporaryDirectory() as tmp:
    conds = B._campaign(Path(tmp), 18, 0)
c0 = conds[0]
base = condition_params({})(c0)
setup = {**c0.setup, "speed": speed, "depth": 0.03}
orig_settled = BZ.settled_bin
cal = DemParams.from_mapping(base, "<cal>", plausible=False)
for var in variants:
    parts = var.split(",")
    fss, fst, bedcal = float(parts[0]), float(parts[1]), "cal" in parts[2:]
    fr = float(next((x[1:] for x in parts[2:] if x.startswith("r")), 1.0))  # soil-soil rolling factor
    p = dict(base, soil_soil_static_friction=base["soil_soil_static_friction"] * fss,
             soil_steel_static_friction=base["soil_steel_static_friction"] * fst,
             soil_soil_rolling_friction=base["soil_soil_rolling_friction"] * fr)
    params = DemParams.from_mapping(p, "<var>", plausible=False)
    if bedcal:
        BZ.settled_bin = lambda spec, prm, *a, **k: orig_settled(spec, cal, *a, **k)
    else:
        BZ.settled_bin = orig_settled
    f, fz = [], []
    for s in range(1000, 1000 + nseeds):
        r = BZ.run(setup, params, "quick", seed=s, threads=1)
        f.append(r.responses["horizontal_force_N"]); fz.append(r.responses["vertical_force_N"])
    lf = np.log(f)
    print(json.dumps(dict(speed=speed, fss=fss, fst=fst, bed="cal" if bedcal else "own", fr=fr,
                          mu_ss=round(p["soil_soil_static_friction"], 3), mu_st=round(p["soil_steel_static_friction"], 3),
                          F=[round(x, 1) for x in f], Fz=[round(x, 1) for x in fz],
                          gmean=round(math.exp(lf.mean()), 2), sdlog=round(float(lf.std(ddof=1)), 3))), flush=True)
