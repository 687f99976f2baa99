"""How far the engine's time step moves the restitution a contact delivers from the one it is
given.

The viscoelastic dashpot (contact.py) is evaluated, as LIGGGHTS evaluates it, with the
half-step velocity of the velocity-Verlet kick while the spring sees the full-step position,
so the coefficient of restitution a collision delivers converges to the configured one to
first order in the step: the fewer steps a contact lasts, the lower the delivered
restitution, the more so the lower the configured one.  A calibrated restitution is
therefore the engine's at the step it was calibrated with, as it is in any engine that
integrates the dashpot so.

Case: two equal spheres (radius ``--radius``, density 2600 kg/m^3, Poisson 0.3, Young's
modulus ``--youngs``: the quick preset's soft soil by default) meet head-on at relative speed
v0 without gravity or tangential force; the delivered restitution is the relative speed after
the contact over v0 (overlaps up to 30 % of the radius accepted, as the presets do).  The step is ``dt_fraction`` x the Rayleigh time (the quick preset
asks for 0.3, the paper preset 0.2), capped as every run is by the damped-contact bound
(materials.py), which the row records as ``dt_fraction_used``; ``contact_steps`` is how
many steps the contact lasted.  One row per case in
``benchmarks/results/restitution_step.csv``, tabulated in ``restitution_step.md``.

    python benchmarks/restitution_step.py
    python benchmarks/restitution_step.py --restitutions 0.1,0.3 --fractions 0.3,0.01
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

FIELDS = ["utc", "commit", "youngs_Pa", "radius_m", "v0_m_s", "restitution", "dt_fraction",
          "dt_fraction_used", "dt_s", "contact_steps", "delivered", "rel_error_pct"]


def impact(e, v0, frac, radius, youngs):
    """(delivered restitution, steps in contact, step, step / Rayleigh time)."""
    from soilcal.dem.engine import Simulation
    from soilcal.dem.materials import Material, MaterialTable

    mats = MaterialTable()
    mats.add(Material("soil", 2600.0, 0.3, youngs=youngs))
    mats.set_pair("soil", "soil", e, 0.0)
    sim = Simulation(mats, dt_fraction=frac, gravity=(0, 0, 0), max_overlap=0.3,
                     contact_model=dict(tangential="none"))
    gap = 1e-4 * radius
    sim.add_particles([[0, 0, 0], [2 * radius + gap, 0, 0]], radius, "soil",
                      v=[[v0 / 2, 0, 0], [-v0 / 2, 0, 0]])
    touched, steps = False, 0
    while True:
        sim.run(1)
        a, b = sim.index([0, 1])
        if sim.x[b, 0] - sim.x[a, 0] < 2 * radius:
            touched = True
            steps += 1
        elif touched:
            break
    a, b = sim.index([0, 1])
    return (sim.v[b, 0] - sim.v[a, 0]) / v0, steps, sim.dt, sim.dt / sim.rayleigh


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--restitutions", default="0.05,0.1,0.3,0.5,0.7")
    ap.add_argument("--fractions", default="0.3,0.2,0.1,0.02")
    ap.add_argument("--speeds", default="0.1,1.0", help="impact speeds v0 [m/s]")
    ap.add_argument("--radius", type=float, default=2e-3)
    ap.add_argument("--youngs", type=float, default=1.3e6)
    ap.add_argument("--out", default=str(HERE / "results"))
    a = ap.parse_args(argv)
    import datetime

    utc = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M")
    rows = []
    for v0 in (float(s) for s in a.speeds.split(",")):
        for e in (float(s) for s in a.restitutions.split(",")):
            for f in (float(s) for s in a.fractions.split(",")):
                got, steps, dt, used = impact(e, v0, f, a.radius, a.youngs)
                rows.append(dict(utc=utc, commit=commit(), youngs_Pa=a.youngs, radius_m=a.radius,
                                 v0_m_s=v0, restitution=e, dt_fraction=f,
                                 dt_fraction_used=round(used, 4), dt_s=f"{dt:.4g}",
                                 contact_steps=steps, delivered=round(float(got), 5),
                                 rel_error_pct=round(float(100 * (got - e) / e), 2)))
                print(rows[-1], flush=True)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    write_rows(out / "restitution_step.csv", rows, FIELDS)
    head = ["v0_m_s", "restitution", "dt_fraction", "dt_fraction_used", "contact_steps",
            "delivered", "rel_error_pct"]
    table = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    table += ["| " + " | ".join(str(r[k]) for k in head) + " |" for r in rows]
    write_page(out / "restitution_step.md",
               ["# Restitution delivered against the time step", "", f"Machine: {platform.machine()}, Python {platform.python_version()}.  Last "
                f"command: `{' '.join(['python benchmarks/restitution_step.py'] + sys.argv[1:])}`."
                f"  Rows: `restitution_step.csv` ({rows[0]['utc']} UTC, commit "
                f"{rows[0]['commit']}); Young's modulus {a.youngs:g} Pa, radius {a.radius:g} m.",
                "", *table])


if __name__ == "__main__":
    main()
