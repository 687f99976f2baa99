"""Row-by-row surrogates against one response shape pooled over the conditions, on a stand-in
of the DEM loop's depth campaign (the loop's selection step alone, by a proxy).

A depth gradient of density (depth_compaction, f = 1 + g (d / d0 - 1), d0 = 30 mm) acts on a
plate force in proportion to the density: F = (40 + 1500 d) f N over 18 conditions at depths
drawn in 20-40 mm.  The measured values are three repeats at the hidden g; the effect's design
(g = -0.5, 0, 0.25, 1.0, :func:`soilcal.loop.select.theta_design` with three levels) has three
runs per point and condition, each scattered anew (a bed settled anew at each density, as the
DEM's are): lognormal, SD 0.14 (``uniform``) or 0.10 at 20 mm rising to 0.28 at 40 mm
(``depth``: the DEM plate's SD of log force per run, ``benchmarks/results/loop.md``, notes on
depth_compaction).  Per campaign, g is fitted by least squares of the relative errors, and each
condition is predicted with g fitted without it (leave one condition out); the paired one-sided
t-test over the conditions of the squared errors against the reference model's is the proxy of
the loop's paired held-out test.  Methods:

* ``rows``: the loop's surrogates now (:class:`soilcal.loop.select.Surrogate`, quadratic or
  monotone cubic per row by :func:`soilcal.loop.select.smooth_fits`); reference: the
  switched-off design mean (the calibrated runs), as the loop's;
* ``rows, level``: the same surrogates; reference: their value at g = 0 (the calibrated model as the
  row's smoothed design estimates it);
* ``pooled, base``: ln y = ln y0_i + a x + b x^2 with x = ln f the density factor's logarithm, a
  and b shared by the rows (least squares on the rows' log design means with a level per row),
  anchored at each row's switched-off mean; reference: that mean;
* ``pooled, level``: the same shape with each row's level fitted over all its design points;
  reference: that level at g = 0 (the calibrated model estimated from every run of the row);
* ``loop's shape``: the loop's :class:`soilcal.loop.select.PooledSurrogate` ("pooled, level" where
  its lack-of-fit test passes, else the rows' surrogates), reference: its value at g = 0, as the
  loop's (:func:`soilcal.loop.select.baseline`);
* ``pooled, level vs base``: that model against the switched-off mean (unfair: more runs behind
  the model than behind its reference).

    python benchmarks/loop_surrogate/pooled_mc.py [CAMPAIGNS]    # default 200 per case

Writes ``benchmarks/results/loop_surrogate/pooled_mc.{csv,md}``.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats
from scipy.optimize import minimize_scalar

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from _report import run_header, write_rows_page  # noqa: E402

OUT = HERE.parent / "results" / "loop_surrogate"
N, SEEDS, D0 = 18, 3, 0.03
BOUNDS = (-0.5, 1.0)


def _force(d, g):
    return (40.0 + 1500.0 * d) * np.maximum(1 + g * (d / D0 - 1), 0.1)


def _dose(g, z):
    from soilcal.loop.effects import dose

    return dose("depth_compaction", g, z)


class Pooled:
    """exp(level_i + a x + b x^2), a and b the loop's fit (:func:`soilcal.loop.select._pooled_fit`):
    level_i the row's switched-off mean's log (``anchor`` "base") or fitted over its design
    points ("level", the loop's own)."""

    def __init__(self, T, Y, z, anchor):
        from soilcal.loop.select import _pooled_fit

        L = np.log(Y)
        self.a, self.b, level = _pooled_fit(L, np.stack([_dose(g, z) for g in T]))
        self.z = z
        self.level = L[list(T).index(0.0)] if anchor == "base" else level

    def __call__(self, th):
        x = _dose(float(th[0]), self.z)
        return np.exp(self.level + self.a * x + self.b * x * x)


def _fit(f, measured, keep):
    return minimize_scalar(lambda g: np.sum((((measured - f([g])) / measured)[keep]) ** 2), bounds=BOUNDS,
                           method="bounded").x


def campaign(rng, truth, scatter, T):
    from soilcal.loop import select as sl
    from soilcal.loop.effects import EFFECTS

    d = rng.uniform(0.020, 0.040, N)
    s = np.full(N, 0.14) if scatter == "uniform" else 0.10 + 0.18 * (d - 0.020) / 0.020
    measured = _force(d, truth) * np.exp(s * rng.standard_normal((SEEDS, N))).mean(axis=0)
    V = np.stack([_force(d, g) for g in T])[:, :, None] * np.exp(s[None, :, None]
                                                                 * rng.standard_normal((len(T), N, SEEDS)))
    Y = V.mean(axis=2)
    z = d / D0 - 1
    base = Y[list(T).index(0.0)]
    rows = sl.Surrogate(EFFECTS["depth_compaction"], {"g": BOUNDS}, T[:, None], Y, sl.smooth_fits(T[:, None], V)[0])
    pb, pl = Pooled(T, Y, z, "base"), Pooled(T, Y, z, "level")
    pk = sl.PooledSurrogate(EFFECTS["depth_compaction"], {"g": BOUNDS}, T[:, None], Y, z, ["plate|F"] * N, V,
                            sl.smooth_fits(T[:, None], V)[0])
    out = []
    for method, f, ref in (("rows", rows, base), ("rows, level", rows, rows([0.0])), ("pooled, base", pb, base),
                           ("pooled, level", pl, pl([0.0])), ("loop's shape", pk, pk([0.0])),
                           ("pooled, level vs base", pl, base)):
        e = np.empty(N)
        for i in range(N):
            keep = np.arange(N) != i
            e[i] = (measured[i] - f([_fit(f, measured, keep)])[i]) / measured[i]
        e0 = (measured - ref) / measured
        out.append({"method": method, "g_fitted": _fit(f, measured, np.ones(N, bool)),
                    "heldout_rms": float(np.sqrt(np.mean(e ** 2))), "reference_rms": float(np.sqrt(np.mean(e0 ** 2))),
                    "paired_p": float(stats.ttest_rel(e0 ** 2, e ** 2, alternative="greater").pvalue)})
    return out


def main(argv=None) -> None:
    from soilcal.loop import select as sl
    from soilcal.loop.effects import EFFECTS

    args = sys.argv[1:] if argv is None else argv
    n = int(args[0]) if args else 200
    T = np.array([t["g"] for t in sl.theta_design(EFFECTS["depth_compaction"], {"g": BOUNDS}, 3)])
    rows = []
    t0 = time.perf_counter()
    for scatter in ("uniform", "depth"):
        for truth in (0.0, 0.6):
            rng = np.random.default_rng([11, int(10 * truth), scatter == "depth"])
            for k in range(n):
                for r in campaign(rng, truth, scatter, T):
                    rows.append({"scatter": scatter, "hidden_g": truth, "campaign": k, **r})
    df = pd.DataFrame(rows)
    OUT.mkdir(parents=True, exist_ok=True)
    df.to_csv(OUT / "pooled_mc.csv", index=False)
    lines = ["# Row-by-row surrogates against a response shape pooled over the conditions", "",
             run_header("loop_surrogate/pooled_mc.py", [n], f"{time.perf_counter() - t0:.0f} s") + "; "
             "the stand-in, methods and proxy test are in the script's docstring.  Significant: the paired one-sided "
             "t-test of the conditions' held-out squared errors against the reference's at p < 0.05 (with no hidden "
             "effect a false gain, which the loop's other gates then face).", "",
             "| scatter | hidden g | method | campaigns | significant gain | held-out RMS, % (median) | reference RMS, % "
             "(median) | RMS error of g |", "|---|---:|---|---:|---:|---:|---:|---:|"]
    for (scatter, truth, method), g in df.groupby(["scatter", "hidden_g", "method"], sort=False):
        lines.append(f"| {scatter} | {truth:g} | {method} | {len(g)} | {np.mean(g['paired_p'] < 0.05):.3f} | "
                     f"{100 * g['heldout_rms'].median():.2f} | {100 * g['reference_rms'].median():.2f} | "
                     f"{np.sqrt(np.mean((g['g_fitted'] - truth) ** 2)):.3f} |")
    write_rows_page(OUT / "pooled_mc.md", lines, "pooled_mc.csv")


if __name__ == "__main__":
    main()
