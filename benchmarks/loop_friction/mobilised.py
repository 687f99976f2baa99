"""Mobilised friction on the line plate from the forces friction_split.py printed: the plate's
face is at 78 deg to the horizontal (Table 9 skew angle, top behind the edge), so with the
horizontal resistance Fx and the vertical force Fz (+ up) on the plate, the face's normal and
tangential (up the face) loads are N = Fx sin78 - Fz cos78, T = Fx cos78 + Fz sin78, and
T/N the friction the soil mobilises on the plate (on average over the stable stage and the
whole face; the cutting edge's own load is in it too).  Per variant: mean T/N over the seeds.

    python benchmarks/loop_friction/mobilised.py benchmarks/results/loop_friction/split_v01.jsonl benchmarks/results/loop_friction/split_v1.jsonl
"""
import json
import math
import sys
a = math.radians(78.0)
for path in sys.argv[1:]:
    for line in open(path):
        if not line.startswith("{"):
            continue
        d = json.loads(line)
        r = [(fx * math.cos(a) + fz * math.sin(a)) / (fx * math.sin(a) - fz * math.cos(a)) for fx, fz in zip(d["F"], d["Fz"])]
        print(f"v {d['speed']:.2f} mu_ss {d['mu_ss']:.3f} mu_st {d['mu_st']:.3f} bed {d['bed']:3s} rolling x{d.get('fr', 1.0)}: "
              f"Fx gmean {d['gmean']:6.2f} N (sdlog {d['sdlog']:.3f}); T/N {sum(r)/len(r):.3f} (seeds {min(r):.2f}-{max(r):.2f})")
