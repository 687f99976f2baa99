"""Measurement tables with an effect nobody declared: the generator behind ``soilcal loop synthesize``.

The measured value of each condition is the simulation at the soil's calibrated parameters
with hidden effects switched on (library effects, :mod:`soilcal.loop.effects`, with their
parameters), mean over ``seeds``, times disturbances from outside the library, times
measurement noise:

* ``periodic``: 1 + a sin(2 pi x / wavelength + phase), x the row's ``position`` quantity
  (m along the soil bin; the row number where the table has none): a periodic
  disturbance along the bin (a ridge pattern left by the bed preparation);
* ``stones``: a share ``fraction`` of the rows, drawn at random, raised by a factor drawn
  uniformly in [1 + low, 1 + high]: stones met by the tool as rigid inclusions;
* ``day_offset``: one relative offset per ``day`` label, normal with SD ``sd``: a level that
  varies at random between test days;
* repeats: one measured repeat per simulation seed in ``seeds`` (the granular scatter of a
  real test), each times relative instrument noise, normal with SD ``noise``; the table's
  value is the repeats' mean, ``sd`` their sample SD and ``n`` their count, as a lab reports
  a soil-bin test.

Every random draw comes from one generator seeded by ``seed``; the draws are listed in the
returned table's ``truth`` columns (``soilcal loop synthesize`` writes them to
``<out>.truth.csv`` with the parameters each condition ran at).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from soilcal.errors import InputError
from soilcal.loop.effects import EFFECTS, apply_all

DISTURBANCES = ("periodic", "stones", "day_offset")


def check_hidden(hidden: dict, source="<synthesize>") -> None:
    for name, theta in hidden.items():
        if name not in EFFECTS:
            raise InputError(source, "effect", "one of " + ", ".join(EFFECTS), name)
        for k in theta:
            if k not in EFFECTS[name].params:
                raise InputError(source, f"effect.{name}", "a parameter of the effect (" + ", ".join(EFFECTS[name].params)
                                 + ")", k)


def synthesize(conditions, base_params, simulate, hidden: dict | None = None, reference: dict | None = None,
               disturbances: dict | None = None, noise: float = 0.02, seed: int = 0,
               seeds=(100, 101, 102)) -> pd.DataFrame:
    """One row per condition and measured quantity: measurement, row, measure, value, sd, n,
    and the truth (simulated mean with the hidden effects, the disturbance factor)."""
    hidden = hidden or {}
    check_hidden(hidden)
    disturbances = disturbances or {}
    for name in disturbances:
        if name not in DISTURBANCES:
            raise InputError("<synthesize>", "disturbance", "one of " + ", ".join(DISTURBANCES), name)
    reference = reference or {}
    rng = np.random.default_rng(seed)
    conditions = list(conditions)
    factor = np.ones(len(conditions))
    if "periodic" in disturbances:
        d = disturbances["periodic"]
        for i, c in enumerate(conditions):
            x = (c.quantities or {}).get("position", float(c.row))
            factor[i] *= 1 + float(d.get("amplitude", 0.1)) * math.sin(2 * math.pi * float(x) / float(d.get("wavelength", 1.0))
                                                                    + float(d.get("phase", 0.0)))
    if "stones" in disturbances:
        d = disturbances["stones"]
        hit = rng.random(len(conditions)) < float(d.get("fraction", 0.3))
        lift = rng.uniform(float(d.get("low", 0.1)), float(d.get("high", 0.3)), len(conditions))
        factor *= np.where(hit, 1 + lift, 1.0)
    if "day_offset" in disturbances:
        d = disturbances["day_offset"]
        days = sorted({str((c.quantities or {}).get("day", "")) for c in conditions})
        off = dict(zip(days, rng.normal(0.0, float(d.get("sd", 0.1)), len(days))))
        for i, c in enumerate(conditions):
            factor[i] *= 1 + off[str((c.quantities or {}).get("day", ""))]
    rows = []
    for i, c in enumerate(conditions):
        p = apply_all(hidden, base_params(c), c.quantities or {}, reference, c.scenario)
        vals = [simulate(c, p, s) for s in seeds]
        for r in c.responses:
            sims = np.array([v[r["measure"]] for v in vals], float)
            reps = sims * factor[i] * (1 + noise * rng.standard_normal(len(sims)))
            rows.append({"measurement": c.measurement, "row": c.row, "measure": r["measure"],
                         "value": float(np.mean(reps)), "sd": float(np.std(reps, ddof=1)) if len(reps) > 1 else math.nan,
                         "n": len(reps), "truth_simulated": float(np.mean(sims)), "truth_disturbance": factor[i]})
    return pd.DataFrame(rows)


def with_measured(conditions, table: pd.DataFrame):
    """Copies of the conditions whose measured values (and SD, n) are the synthetic ones."""
    from dataclasses import replace

    look = {(r.measurement, int(r.row), r.measure): r for r in table.itertuples()}
    out = []
    for c in conditions:
        resp = []
        for r in c.responses:
            t = look[(c.measurement, int(c.row), r["measure"])]
            resp.append(dict(r, measured=float(t.value), measured_sd=float(t.sd), n=int(t.n)))
        out.append(replace(c, responses=tuple(resp)))
    return out
