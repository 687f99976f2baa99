"""The DEM campaign's conditions under --speeds uniform and log (campaign seed SEED, default 0; 18 conditions): the
speeds, and whether every other covariate is the same; share below 0.25 m/s.  No DEM runs.

    python benchmarks/loop_friction/campaign_speeds.py [SEED]
"""
import sys
import tempfile
from pathlib import Path
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # benchmarks/loop.py
import loop as B
out = {}
for sp in ("uniform", "log"):
    with tempfile.TemporaryDirectory() as tmp:
        conds = B._campaign(Path(tmp), 18, int(sys.argv[1]) if len(sys.argv) > 1 else 0, sp)
    out[sp] = [dict(c.quantities) for c in conds]
same = all({k: v for k, v in a.items() if k != "tool_speed"} == {k: v for k, v in b.items() if k != "tool_speed"}
           for a, b in zip(out["uniform"], out["log"]))
for sp, q in out.items():
    v = [c["tool_speed"] for c in q]
    print(sp, [round(x, 3) for x in v], "below 0.25:", sum(x < 0.25 for x in v), "of", len(v))
print("other covariates identical:", same)
