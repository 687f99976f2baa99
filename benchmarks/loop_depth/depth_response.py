"""How much does the quick line plate's horizontal force follow the depth_compaction effect,
seed by seed?  The loop benchmark's campaign line plate at 0.4 m/s (its reference speed),
depths 20 and 40 mm (d/d0 - 1 = -1/3, +1/3 about the reference 30 mm), g in {0, 0.25, 0.6,
1.0} (0.25 and 1.0: the benchmark's non-null design levels; 0.6: the hidden value), seeds
0-2 (the loop's design seeds) and 1000-1002 (the measured side's).  One JSON line per run,
appended to OUT (runs already in OUT are skipped).
    python benchmarks/loop_depth/depth_response.py benchmarks/results/loop_depth/depth_response.jsonl
"""
import json, sys, tempfile, time
from dataclasses import replace
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # benchmarks/loop.py
import loop as B
from soilcal.loop import effects
from soilcal.loop.cli import condition_params, dem_simulator

out = Path(sys.argv[1])
done = {(r["depth"], r["g"], r["seed"]) for r in map(json.loads, out.read_text().splitlines())} if out.exists() else set()
with tempfile.TemporaryDirectory() as tmp:
    c0 = B._campaign(Path(tmp), 18, 0)[0]  # line plate
sim, base = dem_simulator(1), condition_params({})
for seed in (0, 1000, 1, 1001, 2, 1002):
    for g in (0.0, 0.6, 0.25, 1.0):
        for d in (0.02, 0.04):
            if (d, g, seed) in done:
                continue
            c = replace(c0, setup={**c0.setup, "speed": 0.4, "depth": d},
                        quantities={**c0.quantities, "tool_speed": 0.4, "working_depth": d})
            p = effects.apply_all({"depth_compaction": {"g": g}} if g else {}, base(c), c.quantities,
                                  B.DEM_REFERENCE, c.scenario)
            t0 = time.process_time()
            F = sim(c, p, seed)["horizontal_force_N"]
            with out.open("a") as fh:
                fh.write(json.dumps(dict(depth=d, g=g, seed=seed, F=F, rho=p["soil_density"],
                                         G=p["soil_shear_modulus"], cpu_s=round(time.process_time() - t0, 1))) + "\n")
