"""A local design at the first set, so that the second round learns the DEM's slope there.

The second calibration round (:mod:`soilcal.chain.refine`) corrects the response surface by
the bias its first verification measured at the calibrated set x0 and moves to where the
shifted surface meets the target.  A constant shift assumes that the surface's slope at x0 is
the DEM's; where the quadratic misrepresents the DEM there (a plateau that the surface bends
through: the black soil's heaps stand at about 38 deg around the Box-Behnken centre, and the
surface falls away from it), the move follows the surface's slope and the DEM does not.

So where the second round would move a case because of such a bias, the workflow first runs
a local design about x0 (checkpoint ``local_design``, ``local.csv`` of the stage, one DEM job
per point, ``results/<soil>/dem/local/<stage>/<case>/<point>.csv``): a two-level
Plackett-Burman design (pyDOE3 ``pbdesign``: 4 points for up to three factors, 8 for four to
seven) at x0 +- h in coded units (h = ``simulation.verification.local.half_width``, default
:data:`HALF_WIDTH` box half-widths), each point run with the seeds of a design point (every
response its ``simulation.replicates``, or its own ``simulation.responses.<id>.replicates``),
centred on x0 moved inward where x0 +- h would leave the second round's search region.  The
second round then fits, per targeted response, a plane to the local runs and the first round's
seeds at x0 (least squares weighted by each run's seeds, statsmodels WLS, with a centre
indicator: the factorial-plus-centre-points model, so that a bend of the response within the
design, the first set standing off the design's plane, is estimated apart and does not tilt the
level): the DEM's level a at x0 (its seeds' mean) and slope g there, with the slope's
covariance.  It corrects the surface to first order there,
s(x) + (a - s(x0)) + (g - grad s(x0)) . (x - x0), so that the corrected surface has the DEM's
value and slope at x0 and the surface's curvature
(first-order model management: Alexandrov, Dennis, Lewis and Torczon, Structural Optimization
15 (1998) 16-23), and takes the smallest move at which the corrected surfaces meet every
target, within the trust region |x - x0| <= :data:`TRUST` h in every coded factor (and the
search region), where the plane was measured; where none does, the corrected surfaces'
least-squares compromise there if it promises a worst error :data:`soilcal.chain.refine.COMPROMISE_GAIN`
points lower than at x0.  Fresh seeds verify the new set, as for every second round.

The local seeds start at ``seed + seed_offset + most_seeds + SEED_OFFSET + stride * point``
(after every verification and second-round seed; :func:`point_seed`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from soilcal.errors import InputError

#: the local design's default half-width, in coded units (box half-widths): large enough that
#: the plane's slope rises above one seed's scatter over 8 runs, small against the box
HALF_WIDTH = 0.35
#: the trust region of the corrected surface, in local half-widths about the first set
TRUST = 2.0
#: the local design's seeds start this many seeds after the verification's last
SEED_OFFSET = 1000


def point_seed(soil_data: dict, point: int) -> int:
    """The first seed of local point ``point`` past ``seed + seed_offset``: after every
    verification and second-round seed (:func:`soilcal.chain.verify.most_seeds` plus
    :data:`SEED_OFFSET`), the points' seeds as many apart as a design point's
    (:func:`soilcal.chain.sources.seed_stride`), so that no two points share a packing draw."""
    from soilcal.chain.sources import seed_stride
    from soilcal.chain.verify import most_seeds

    return most_seeds(soil_data) + SEED_OFFSET + seed_stride(soil_data) * int(point)


def half_width(soil_data: dict) -> float | None:
    """The local design's half-width (``simulation.verification.local``: ``{half_width: h}``,
    default :data:`HALF_WIDTH`; ``false``: no local design), or None where the soil runs no
    local design (or no second round)."""
    from soilcal.chain.refine import refine_settings

    v = (soil_data.get("simulation") or {}).get("verification") or {}
    local = v.get("local", True)
    if not refine_settings(soil_data) or local is False:
        return None
    h = (local if isinstance(local, dict) else {}).get("half_width", HALF_WIDTH)
    if isinstance(h, bool) or not isinstance(h, (int, float)) or not 0 < h <= 1:
        raise InputError("<soil>", "simulation.verification.local.half_width",
                         "a coded half-width in (0, 1] (box half-widths)", h)
    return float(h)


def design_points(x0, h: float, lower, upper) -> np.ndarray:
    """The local design's coded points: ``pbdesign(d)`` scaled by ``h`` about x0, moved inward
    per factor so that the points stay within ``lower`` .. ``upper`` (where the region is
    narrower than 2 h in a factor, its half-width there is the region's)."""
    from pyDOE3 import pbdesign

    x0 = np.asarray(x0, float).reshape(-1)
    lo, hi = np.asarray(lower, float).reshape(-1), np.asarray(upper, float).reshape(-1)
    hw = np.minimum(h, (hi - lo) / 2.0)
    centre = np.clip(x0, lo + hw, hi - hw)
    pb = np.asarray(pbdesign(x0.size), float)[:, :x0.size]
    return centre + pb * hw


def local_frame(stage: dict, refined: pd.DataFrame, optimum: pd.DataFrame, h: float | None,
                wider: dict | None = None) -> pd.DataFrame:
    """``local.csv`` of one stage: per case that the second round (``refined``, the frame
    :func:`soilcal.chain.refine.refine_frame` gives without local runs) moves because of a
    significant bias, the local design's points (``point``, coded and actual levels); empty
    without one or with ``h`` None."""
    from soilcal.chain.refine import search_region
    from soilcal.chain.stage import bounds, calibrated_rows
    from soilcal.chain.verify import _finite

    syms, low, high = bounds(stage)
    cols = ["case", "point", *[f"{s}_coded" for s in syms], *syms]
    if h is None or refined is None or not len(refined):
        return pd.DataFrame(columns=cols)
    centre, half = (low + high) / 2.0, (high - low) / 2.0
    lo_w, hi_w = search_region(stage, wider)
    rows = []
    for rec in refined.to_dict("records"):
        biased = [k for k, v in rec.items() if k.startswith("bias_") and _finite(v, 0.0) != 0.0]
        if str(rec.get("refined")).lower() != "true" or not biased:
            continue
        cal = calibrated_rows(optimum, rec["case"])
        if not len(cal):
            continue
        x0 = np.array([(float(cal[s].iloc[0]) - centre[j]) / half[j] for j, s in enumerate(syms)])
        for p, xc in enumerate(design_points(x0, h, lo_w, hi_w)):
            rows.append({"case": rec["case"], "point": p, **{f"{s}_coded": float(xc[j]) for j, s in enumerate(syms)},
                         **{s: float(centre[j] + xc[j] * half[j]) for j, s in enumerate(syms)}})
    return pd.DataFrame(rows, columns=cols)


def point_optimum(optimum: pd.DataFrame, local: pd.DataFrame, case: str, point: int) -> pd.DataFrame:
    """A one-row optimum frame holding the local point ``point`` of ``case`` as its calibrated
    set (the verification spec's input: :func:`soilcal.chain.verify.verification_point`)."""
    from soilcal.chain.stage import calibrated_rows

    sel = local[(local["case"].astype(str) == str(case)) & (local["point"].astype(int) == int(point))]
    if not len(sel):
        raise InputError("local.csv", f"{case}.{point}", "a point of the local design", "missing")
    row = calibrated_rows(optimum, case).iloc[[0]].copy()
    for c in local.columns:
        if c not in ("case", "point"):
            row[c] = float(sel[c].iloc[0])
    row["calibrated"] = True
    return row


class FirstOrder:
    """A surface corrected to first order at x0: s(x) + b + c . (x - x0) (module docstring)."""

    def __init__(self, model, b: float, c, x0):
        self.model, self.b = model, float(b)
        self.c, self.x0 = np.asarray(c, float), np.asarray(x0, float)
        self.factors = list(model.factors)
        self.low, self.high = getattr(model, "low", None), getattr(model, "high", None)

    def predict(self, X_coded) -> np.ndarray:
        X = np.atleast_2d(np.asarray(X_coded, float))
        return np.asarray(self.model.predict(X), float) + self.b + (X - self.x0) @ self.c


def gradient(model, x0, eps: float = 1e-4) -> np.ndarray:
    """The surface's slope at x0 per coded unit (central differences)."""
    x0 = np.asarray(x0, float)
    g = np.empty(x0.size)
    for j in range(x0.size):
        e = np.zeros(x0.size)
        e[j] = eps
        g[j] = (float(model.predict((x0 + e)[None, :])[0]) - float(model.predict((x0 - e)[None, :])[0])) / (2 * eps)
    return g


def _runs_xy(frames, response, syms, centre, half, x0):
    """(y, X, n) of the runs of ``response``: each row's value (the mean of its ``n`` seeds),
    its coded offset from x0 and its seed count (1 where a row gives none)."""
    empty = np.empty(0), np.empty((0, len(syms))), np.empty(0)
    if not frames:
        return empty
    d = pd.concat(frames, ignore_index=True)
    d = d[(d["response"].astype(str) == response) & (d["status"].astype(str) == "ok")]
    fcols = [f"f:{s}" for s in syms]
    if any(c not in d.columns for c in fcols):
        return empty
    y = pd.to_numeric(d["value"], errors="coerce").to_numpy(float)
    X = (d[fcols].apply(pd.to_numeric, errors="coerce").to_numpy(float) - centre) / half - np.asarray(x0, float)
    n = pd.to_numeric(d["n"], errors="coerce").to_numpy(float) if "n" in d.columns else np.ones(y.size)
    n = np.where(np.isfinite(n) & (n >= 1), n, 1.0)
    ok = np.isfinite(y) & np.all(np.isfinite(X), axis=1)
    return y[ok], X[ok], n[ok]


def plane(centre_frames: list[pd.DataFrame], local_frames: list[pd.DataFrame], response: str, syms, centre,
          half, x0):
    """The DEM about x0 from the first round's runs at x0 (``centre_frames``) and the local
    design's (``local_frames``; each run's ``f:<symbol>`` actual levels, ``value``, ``n``,
    ``status``): least squares of y on 1, x - x0 (coded) and a centre indicator, the
    factorial-plus-centre-points model, so that the slopes come from the design's two levels
    and a bend of the response within them (the centre standing off the design's plane) is
    estimated apart instead of tilting the level; each row weighted by its seed count ``n``
    (a mean of n seeds has 1/n of one seed's variance: statsmodels WLS), so that a local point
    of several seeds counts as much as they do.  Returns dict(level: the centre's mean
    response, slope per coded unit, cov: the slopes' covariance, curvature: the centre minus
    the plane there, curvature_se, runs: the rows, seeds: their seeds, sd: the residual SD of
    one seed), or None with too few runs of either kind or no residual degree of freedom."""
    import statsmodels.api as sm

    yc, Xc, nc = _runs_xy(centre_frames, response, syms, centre, half, x0)
    yl, Xl, nl = _runs_xy(local_frames, response, syms, centre, half, x0)
    k = len(syms)
    if yc.size < 1 or yl.size < k + 1 or yc.size + yl.size < k + 3 or np.linalg.matrix_rank(Xl) < k:
        return None
    X = np.column_stack([np.ones(yc.size + yl.size), np.vstack([Xc, Xl]),
                         np.r_[np.ones(yc.size), np.zeros(yl.size)]])
    fit = sm.WLS(np.r_[yc, yl], X, weights=np.r_[nc, nl]).fit()
    params, cov = np.asarray(fit.params, float), np.asarray(fit.cov_params(), float)
    return {"level": float(np.average(yc, weights=nc)), "slope": params[1:k + 1], "cov": cov[1:k + 1, 1:k + 1],
            "curvature": float(params[-1]), "curvature_se": float(np.sqrt(max(cov[-1, -1], 0.0))),
            "runs": int(yc.size + yl.size), "seeds": int(nc.sum() + nl.sum()), "sd": float(np.sqrt(fit.mse_resid))}
