"""How often the loop's periodic test finds a pattern along the bin in residuals that have none.

The diagnosis (soilcal.loop.diagnose) scans a sine of the position over its wavelength and
takes the largest share of the residual variance it explains; its p is the share of 4999
seeded permutations of the residuals whose largest share is as large.  Residuals without any
structure are exchangeable, so that p is exact: at alpha 0.05 about 5 % of such tables should
be flagged, whatever the layout of the positions and however many wavelengths the scan tries.
This checks it on tables of unit-normal residuals at ``m`` distinct positions, evenly spaced
(the layout at which the shortest period the positions resolve, two spacings, is scanned
exactly) or drawn at random along the bin, ``--tables`` tables per case from one seeded
generator.  One row per case in ``benchmarks/results/periodic_false_alarm.csv`` (the share
flagged at 0.05 and at 0.01 with their exact binomial 95 % intervals), tabulated in
``periodic_false_alarm.md``.

    python benchmarks/periodic_false_alarm.py
    python benchmarks/periodic_false_alarm.py --positions 8,16 --tables 1000
"""

from __future__ import annotations

import argparse
import platform
import sys
from pathlib import Path

import numpy as np
from _report import commit, write_page, write_rows

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "src"))

FIELDS = ["utc", "commit", "seed", "layout", "positions", "tables", "flagged_05", "share_05", "ci95_05",
          "flagged_01", "share_01", "ci95_01"]


def case(m: int, layout: str, tables: int, rng, span: float = 14.0):
    """(count p < 0.05, count p < 0.01) over ``tables`` unit-normal residual tables at ``m``
    positions along ``span`` metres."""
    from soilcal.loop.diagnose import _periodic

    n05 = n01 = 0
    for _ in range(tables):
        x = np.linspace(0.0, span, m) if layout == "even" else np.sort(rng.uniform(0.0, span, m))
        r = rng.standard_normal(m)
        rc = r - r.mean()
        p = _periodic("position_m", "position", x, r, m, float(rc @ rc))["p"]
        n05 += p < 0.05
        n01 += p < 0.01
    return n05, n01


def main(argv=None):
    from scipy import stats

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--positions", default="8,12,16,24")
    ap.add_argument("--layouts", default="even,random")
    ap.add_argument("--tables", type=int, default=400)
    ap.add_argument("--seed", type=int, default=2026)
    ap.add_argument("--out", default=str(HERE / "results"))
    a = ap.parse_args(argv)
    import datetime

    utc = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M")
    rng = np.random.default_rng(a.seed)
    rows = []
    for layout in a.layouts.split(","):
        for m in (int(s) for s in a.positions.split(",")):
            n05, n01 = case(m, layout, a.tables, rng)
            ci = {k: stats.binomtest(int(c), a.tables).proportion_ci(0.95) for k, c in (("05", n05), ("01", n01))}
            rows.append(dict(utc=utc, commit=commit(), seed=a.seed, layout=layout, positions=m, tables=a.tables,
                             flagged_05=int(n05), share_05=round(n05 / a.tables, 4),
                             ci95_05=f"{ci['05'].low:.3f}-{ci['05'].high:.3f}",
                             flagged_01=int(n01), share_01=round(n01 / a.tables, 4),
                             ci95_01=f"{ci['01'].low:.3f}-{ci['01'].high:.3f}"))
            print(rows[-1], flush=True)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    write_rows(out / "periodic_false_alarm.csv", rows, FIELDS)
    head = ["layout", "positions", "tables", "share_05", "ci95_05", "share_01", "ci95_01"]
    table = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    table += ["| " + " | ".join(str(r[k]) for k in head) + " |" for r in rows]
    write_page(out / "periodic_false_alarm.md",
               ["# False alarms of the periodic test on residuals without structure", "",
                f"Machine: {platform.machine()}, Python {platform.python_version()}.  Last command: "
                f"`{' '.join(['python benchmarks/periodic_false_alarm.py'] + sys.argv[1:])}`.  Rows: "
                f"`periodic_false_alarm.csv` ({rows[0]['utc']} UTC, commit {rows[0]['commit']}, generator seed "
                f"{a.seed}).  share_05, share_01: the share of tables flagged at p < 0.05 and p < 0.01 (an exact "
                "test flags 0.05 and 0.01 of them), with exact binomial 95 % intervals.", "", *table])


if __name__ == "__main__":
    main()
