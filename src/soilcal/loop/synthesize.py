"""Measurement tables with an effect nobody declared: the generator behind ``soilcal loop synthesize``.

The measured value of each condition is the simulation at the soil's calibrated parameters
with hidden effects switched on (library effects, :mod:`soilcal.loop.effects`, with their
parameters, relative to the reference values: given, else the mean over the measured rows as
the loop itself takes them, :func:`default_reference`; written in the ``reference:<quantity>``
columns of the truth), mean over ``seeds``, times disturbances from outside the library, times
measurement noise:

* ``periodic``: 1 + a sin(2 pi x / wavelength + phase), x the row's ``position`` quantity
  (m along the soil bin; the row number where the table has none; the wavelength has no
  default, in the unit of x): a periodic
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
returned table's ``truth`` columns, the hidden effects' parameters in its ``hidden:<effect>.<parameter>``
columns and the disturbances' in its ``disturbance:<name>.<parameter>`` columns (``soilcal loop
synthesize`` writes them to ``<out>.truth.csv`` with the parameters each condition ran at).  A
hidden effect's parameter is a finite number (within its physical range where the library
states one, :attr:`soilcal.loop.effects.Effect.ranges`) at which the effect follows its
formula at every row (:func:`check_acts`: no parameter driven to a physical limit).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from soilcal.errors import InputError
from soilcal.loop.effects import EFFECTS, apply_all

#: disturbance -> its parameters and their defaults (None: required)
DISTURBANCES = {"periodic": {"amplitude": 0.1, "wavelength": None, "phase": 0.0},
                "stones": {"fraction": 0.3, "low": 0.1, "high": 0.3},
                "day_offset": {"sd": 0.1}}


#: (disturbance, parameter) -> (test of the value given the disturbance's values, what is expected)
_RANGES = {
    ("periodic", "amplitude"): (lambda v, d: 0 <= v < 1, "a relative amplitude in [0, 1) (the factor 1 + a sin "
                                                          "stays positive)"),
    ("periodic", "wavelength"): (lambda v, d: v > 0, "a wavelength > 0 in {where}"),
    ("periodic", "phase"): (lambda v, d: True, "a phase in radians"),
    ("stones", "fraction"): (lambda v, d: 0 <= v <= 1, "a share of the rows in [0, 1]"),
    ("stones", "low"): (lambda v, d: v > -1, "a relative rise > -1 (the factor 1 + low stays positive)"),
    ("stones", "high"): (lambda v, d: v >= d["low"], "a relative rise >= low (the rise is drawn in [low, high])"),
    ("day_offset", "sd"): (lambda v, d: v >= 0, "a relative SD >= 0 of the offset of a test day"),
}


def check_hidden(hidden: dict, source="<synthesize>") -> None:
    for name, theta in hidden.items():
        if name not in EFFECTS:
            raise InputError(source, "effect", "one of " + ", ".join(EFFECTS), name)
        if not theta:
            raise InputError(source, f"effect.{name}", "a value of its parameters, e.g. " + name + ":"
                             + ",".join(f"{k}=..." for k in EFFECTS[name].params), "none")
        for k in theta:
            if k not in EFFECTS[name].params:
                raise InputError(source, f"effect.{name}", "a parameter of the effect (" + ", ".join(EFFECTS[name].params)
                                 + ")", k)
        for k, v in theta.items():
            unit = EFFECTS[name].params[k][0]
            lo, hi = EFFECTS[name].ranges.get(k, (-math.inf, math.inf))
            try:
                x = float(v)
            except (TypeError, ValueError):
                x = math.nan
            if not (math.isfinite(x) and lo <= x <= hi):
                rng = "" if (lo, hi) == (-math.inf, math.inf) else f" from {lo:g} to {hi:g}, its physical range"
                raise InputError(source, f"effect.{name}.{k}", f"a finite number{rng} ({unit})", v)


def check_disturbances(disturbances: dict, conditions, source="<synthesize>") -> dict:
    """The disturbances with their defaults filled in; unknown names and parameters refused,
    and a periodic disturbance needs its wavelength (in the position's unit, m, or in rows
    where the table has no ``position`` quantity)."""
    out = {}
    for name, given in disturbances.items():
        if name not in DISTURBANCES:
            raise InputError(source, "disturbance", "one of " + ", ".join(DISTURBANCES), name)
        known = DISTURBANCES[name]
        for k in given:
            if k not in known:
                raise InputError(source, f"disturbance.{name}", "a parameter of the disturbance ("
                                 + ", ".join(known) + ")", k)
        full = {k: float(given.get(k, v)) if given.get(k, v) is not None else None for k, v in known.items()}
        missing = [k for k, v in full.items() if v is None]
        where = ("m along the soil bin (the position quantity)"
                 if any("position" in (c.quantities or {}) for c in conditions) else
                 "rows (the table declares no position quantity, so the row number is the position)")
        if missing:
            raise InputError(source, f"disturbance.{name}.{missing[0]}", f"a value in {where}", "none")
        for k, v in full.items():
            ok, want = _RANGES[(name, k)]
            if not (math.isfinite(v) and ok(v, full)):
                raise InputError(source, f"disturbance.{name}.{k}", want.format(where=where), v)
        out[name] = full
    return out


def check_acts(hidden: dict, disturbances: dict, conditions, base_params, reference: dict,
               source="<synthesize>", disturbance_source=None) -> None:
    """Every hidden effect and disturbance changes some row of the table, else the table
    would carry none of what the truth file records: an effect that acts through a quantity
    no row declares (moisture cohesion on a table without moisture), only in another
    scenario (plastic contacts in a compression test), or whose rows all sit at the
    reference where it is off; a day offset without two test days (one day's offset is a
    bias of the whole table).  InputError naming the effect and what the rows carry."""
    from soilcal.config.quantities import QUANTITIES

    conditions = list(conditions)
    carried = sorted({q for c in conditions for q in (c.quantities or {})})
    tables = ", ".join(sorted({c.measurement for c in conditions}))
    for name, given in hidden.items():
        eff = EFFECTS[name]
        theta = {k: float(given.get(k, eff.null[k])) for k in eff.params}
        if eff.is_null(theta):
            continue  # switched off on purpose
        scenarios = sorted({c.scenario for c in conditions})
        if not any(eff.acts_in(c.scenario) for c in conditions):
            raise InputError(source, f"effect.{name}", f"an effect that acts on the rows of {tables}: {name} acts "
                             "only in the " + ", ".join(x for x in eff.scenarios if not x.startswith("standin"))
                             + f" scenario, not in {', '.join(scenarios)}",
                             "no row changed")
        if not any(eff.applies_to(c.quantities or {}, c.scenario) for c in conditions):
            raise InputError(source, f"effect.{name}", f"an effect that acts on the rows of {tables}: {name} acts "
                             f"through {' or '.join(eff.needs)}, a quantity no covariate of the table declares "
                             f"(its quantities: {', '.join(carried) or 'none'})", "no row changed")
        changed = False
        for c in conditions:
            p = base_params(c)
            on = eff.apply(p, c.quantities or {}, theta, reference, c.scenario)
            changed = changed or on != p
            # a parameter the effect drives to a physical limit (a friction of 0, a surface
            # energy below 0) stops following its formula there: it does not move with the
            # effect's parameter, so the table would carry another mechanism than the truth says
            for k, v in theta.items():
                if v == 0.0:
                    continue
                near = eff.apply(p, c.quantities or {}, {**theta, k: v * (1.0 - 1e-3)}, reference, c.scenario)
                pinned = [key for key in eff.changes if on.get(key) != p.get(key) and on.get(key) == near.get(key)]
                if pinned:
                    lo, hi = eff.bounds()[k]
                    raise InputError(source, f"effect.{name}.{k}",
                                     f"a value at which {name} follows its formula ({eff.formula}) at every row: at "
                                     f"{c.measurement} row {c.row} it drives {', '.join(pinned)} to a physical limit "
                                     f"({', '.join(f'{key} {on[key]:.4g}' for key in pinned)}), where it stops "
                                     f"(the loop fits {k} from {lo:g} to {hi:g})", v)
        if not changed and not eff.needs:
            # acting on every row and changing none: its parameters sit at a physical limit
            p = base_params(conditions[0])
            raise InputError(source, f"effect.{name}", f"an effect that changes some row of {tables}: at "
                             + ", ".join(f"{k} {v:g}" for k, v in theta.items()) + f" {name} ({eff.formula}) "
                             "leaves every row as calibrated, " + ", ".join(f"{key} {p.get(key, 0.0):.4g}"
                                                                            for key in eff.changes)
                             + " held at its physical limit", "no row changed")
        if not changed:
            at = ", ".join(f"{q} = {reference[q]:.6g} {QUANTITIES[q][0]}" for q in eff.needs if q in reference)
            raise InputError(source, f"effect.{name}", f"an effect that changes some row of {tables}: every row "
                             f"is at the reference ({at}), where {name} is off (--reference sets another)",
                             "no row changed")
    if "day_offset" in disturbances:
        days = set(test_days(conditions))
        if len(days) < 2:
            raise InputError(disturbance_source or source, "disturbance.day_offset", f"a table with two test days at least (a covariate "
                             f"with quantity: day, or named day, session, ...); {tables} has " + (f"one day ({days.pop()})" if days - {""} else
                                                                     "no day column"),
                             "one offset for every row")


def test_days(conditions) -> list[str]:
    """The test day of every condition (its ``day`` quantity; "" for a row without one, a day
    of its own): the groups a day offset shifts together.  Where no condition declares one,
    the column the loop groups its held-out folds by (:func:`soilcal.loop.core.fold_grouping`:
    a ``group`` quantity, or a column named ``day``, ``session``, ...), so that a day offset
    falls on the days the loop reads."""
    conditions = list(conditions)
    if any("day" in (c.quantities or {}) for c in conditions):
        return [str((c.quantities or {}).get("day", "")) for c in conditions]
    from soilcal.loop import core
    from soilcal.loop.residuals import observations

    qcols = core.quantity_of(conditions)
    col, _ = core.fold_grouping(core.Settings(), qcols, observations(conditions))
    if col is None:  # one value on every row: that one day
        col = next((k for c in conditions for k in (c.covariates or {})
                    if core.grouping_reason(k, qcols.get(k)) is not None), None)
    if col is None:
        return ["" for _ in conditions]
    return [("" if (c.covariates or {}).get(col) is None else str((c.covariates or {}).get(col)))
            for c in conditions]


def default_reference(conditions, declared: dict | None = None, source="<synthesize>", strict: bool = False,
                      over=None) -> dict:
    """Numeric quantity of the conditions -> the value where the calibrated parameters hold
    (where an effect is switched off): ``declared`` (checked as a soil's ``loop.reference``;
    with ``strict``, a quantity no condition carries is refused, as a typo on the command
    line, else it is left out, as the loop leaves it), else the mean over the measured rows,
    by the loop's own rule (:func:`soilcal.loop.core.mean_reference`): over the conditions
    ``over`` where given (every measured table of the soil, as the workflow's loop runs them,
    where ``conditions`` are one table's), else over ``conditions``."""
    from soilcal.config.quantities import QUANTITIES
    from soilcal.loop.residuals import observations
    from soilcal.loop.settings import settings_from

    declared = settings_from({"loop": {"reference": dict(declared or {})}}, source).reference
    obs = observations(conditions)
    carried = [c[2:] for c in obs.columns if c.startswith("q:") and QUANTITIES.get(c[2:]) is not None]
    for q in declared:
        if strict and q not in carried:
            raise InputError(source, f"reference.{q}", "a numeric quantity of the measured conditions ("
                             + (", ".join(carried) or "none declared") + ")", q)
    from soilcal.loop.core import mean_reference

    ref = mean_reference(observations(list(over)) if over is not None else obs, declared)
    return {q: ref[q] for q in carried if q in ref}


def synthesize(conditions, base_params, simulate, hidden: dict | None = None, reference: dict | None = None,
               disturbances: dict | None = None, noise: float = 0.02, seed: int = 0,
               seeds=(100, 101, 102), table_of=None) -> pd.DataFrame:
    """One row per condition and measured quantity: measurement, row, measure, value, sd, n,
    and the truth (simulated mean with the hidden effects, the disturbance factor).  A seed
    whose run failed is a repeat not made (``n`` counts the others); a condition whose runs
    all failed is refused (InputError naming its table, ``table_of(measurement)``, its row and
    the simulator's reason), not written as an empty measured value."""
    hidden = hidden or {}
    check_hidden(hidden)
    conditions = list(conditions)
    if not len(seeds):
        raise InputError("<synthesize>", "repeats", "at least one measured repeat (one DEM seed each)", 0)
    disturbances = check_disturbances(disturbances or {}, conditions)
    reference = default_reference(conditions, reference)
    rng = np.random.default_rng(seed)
    factor = np.ones(len(conditions))
    if "periodic" in disturbances:
        d = disturbances["periodic"]
        for i, c in enumerate(conditions):
            x = (c.quantities or {}).get("position", float(c.row))
            factor[i] *= 1 + d["amplitude"] * math.sin(2 * math.pi * float(x) / d["wavelength"] + d["phase"])
    if "stones" in disturbances:
        d = disturbances["stones"]
        hit = rng.random(len(conditions)) < d["fraction"]
        lift = rng.uniform(d["low"], d["high"], len(conditions))
        factor *= np.where(hit, 1 + lift, 1.0)
    if "day_offset" in disturbances:
        d = disturbances["day_offset"]
        per_row = test_days(conditions)
        days = sorted(set(per_row))
        off = dict(zip(days, rng.normal(0.0, d["sd"], len(days))))
        for i, day in enumerate(per_row):
            factor[i] *= 1 + off[day]
    rows = []
    for i, c in enumerate(conditions):
        p = apply_all(hidden, base_params(c), c.quantities or {}, reference, c.scenario)
        vals = [simulate(c, p, s) for s in seeds]
        for r in c.responses:
            sims = np.array([v.get(r["measure"], math.nan) for v in vals], float)
            draws = noise * rng.standard_normal(len(sims))  # one per seed: a failed one leaves the others' draws
            ok = np.isfinite(sims)
            if not ok.any():
                from soilcal.loop.residuals import ERROR_KEY

                why = next((str(v[ERROR_KEY]) for v in vals if v.get(ERROR_KEY)), "no value (NaN)")
                raise InputError(table_of(c.measurement) if table_of else f"measurement {c.measurement}",
                                 f"row {c.row}", f"a condition the simulation runs (every one of the {len(sims)} "
                                 f"runs of {r['measure']} failed; its measured value would be empty)", why)
            sims = sims[ok]
            reps = sims * factor[i] * (1 + draws[ok])
            rows.append({"measurement": c.measurement, "row": c.row, "measure": r["measure"],
                         "value": float(np.mean(reps)), "sd": float(np.std(reps, ddof=1)) if len(reps) > 1 else math.nan,
                         "n": len(reps), "truth_simulated": float(np.mean(sims)), "truth_disturbance": factor[i],
                         **{f"reference:{q}": v for q, v in reference.items()},
                         **{f"hidden:{nm}.{k}": float(v) for nm, th in hidden.items() for k, v in th.items()},
                         **{f"disturbance:{nm}.{k}": float(v) for nm, d in disturbances.items() for k, v in d.items()}})
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
