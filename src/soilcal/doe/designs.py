"""Two-level screening and three-level response-surface designs, coding and row comparison.

Plackett-Burman (PB) designs
----------------------------
Plackett & Burman (1946, Biometrika 33, 305-325) give for N = 8, 12, 16, 20, 24 runs a
generator row g of length N-1; the design is the N-1 cyclic shifts of g plus one row of all
minus signs. Design-Expert prints exactly this design (in standard order the generator is
the first row, and each following row is the previous one shifted by one place), run order
randomised. The generators used here are the published ones:

    N = 8 :  + + + - + - -
    N = 12:  + + - + + + - - - + -
    N = 16:  + + + + - + - + + - - + - - -
    N = 20:  + + - - + + + + - + - + - - - - + + -
    N = 24:  + + + + + - + - + + - - + + - - + - + - - - -

pyDOE3.pbdesign builds N = 12 and N = 20 from a Paley-type Toeplitz/Hankel matrix with an
all-PLUS row, and N = 8, 16, 24 ... by Sylvester doubling; as a set of rows this is not the
classic cyclic design (for N = 12 it is a sign-flipped, column-permuted version of it). The
classic generators are therefore implemented here; pyDOE3 is used only for run counts
without a published cyclic generator (N = 4 * 2^k >= 32, 40, 48, ...), which is recorded
in the returned array's construction via :func:`plackett_burman_source`.

Both constructions are orthogonal (X^T X = N I); the choice matters only when a printed
design has to be reproduced row by row.

Box-Behnken designs come from pyDOE3.bbdesign (Box & Behnken 1960): for k = 3 it has
12 edge mid-points, for k = 4 24, plus the requested centre points.

Coding (Montgomery, Design and Analysis of Experiments, ch. 6): with centre
c = (low + high)/2 and half range h = (high - low)/2, x_coded = (x - c)/h and
x = c + x_coded * h.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from typing import Mapping

import numpy as np

from soilcal.errors import InputError

# Plackett & Burman (1946), Table of cyclic generators (first rows).
PB_GENERATORS: dict[int, str] = {
    8: "+++-+--",
    12: "++-+++---+-",
    16: "++++-+-++--+---",
    20: "++--++++-+-+----++-",
    24: "+++++-+-++--++--+-+----",
}


def _generator_array(n_runs: int) -> np.ndarray:
    return np.array([1.0 if c == "+" else -1.0 for c in PB_GENERATORS[n_runs]])


def plackett_burman_source(n_columns: int) -> str:
    """Name the construction :func:`plackett_burman` uses for ``n_columns`` columns."""
    n_runs = pb_runs(n_columns)
    if n_runs in PB_GENERATORS:
        return f"Plackett-Burman 1946 cyclic generator, N={n_runs}"
    if n_runs == 4:
        return "full 2^2 factorial with interaction column, N=4"
    return f"pyDOE3.pbdesign (Hadamard / Sylvester construction), N={n_runs}"


def pb_runs(n_columns: int) -> int:
    """Run count of a PB design: the smallest multiple of 4 strictly greater than n_columns."""
    if int(n_columns) != n_columns or n_columns < 1:
        raise InputError(None, "n_columns", "a positive integer", n_columns)
    return 4 * (int(n_columns) // 4 + 1)


def plackett_burman(n_columns: int) -> np.ndarray:
    """Plackett-Burman screening design in coded units (+1/-1), standard order.

    Rows: the N-1 cyclic shifts of the classic generator (row i is the generator shifted
    i places to the right), then the all-minus row. Columns: the first ``n_columns`` of
    the N-1 columns (Design-Expert assigns factors, then dummy variables, left to right).
    """
    n_runs = pb_runs(n_columns)
    if n_runs in PB_GENERATORS:
        g = _generator_array(n_runs)
        rows = [np.roll(g, i) for i in range(n_runs - 1)]
        rows.append(-np.ones(n_runs - 1))
        design = np.array(rows)
    elif n_runs == 4:
        design = np.array([[1, 1, -1], [-1, 1, 1], [1, -1, 1], [-1, -1, -1]], dtype=float)
    else:
        import pyDOE3  # here, not at module import: its package import loads every design module of it

        design = np.asarray(pyDOE3.pbdesign(n_runs - 1), dtype=float)
    return design[:, : int(n_columns)].astype(float)


#: the fewest factors a Box-Behnken design has (Box & Behnken 1960; pyDOE3.bbdesign)
BBD_MIN_FACTORS = 3


def box_behnken(k: int, center_points: int) -> np.ndarray:
    """Box-Behnken design in coded units via pyDOE3.bbdesign (k >= :data:`BBD_MIN_FACTORS`)."""
    if int(k) != k or k < BBD_MIN_FACTORS:
        raise InputError(None, "k", f"an integer number of factors >= {BBD_MIN_FACTORS}", k)
    if int(center_points) != center_points or center_points < 0:
        raise InputError(None, "center_points", "a non-negative integer", center_points)
    import pyDOE3  # here, not at module import: its package import loads every design module of it

    return np.asarray(pyDOE3.bbdesign(int(k), center=int(center_points)), dtype=float)


def _as_bounds(low, high, n: int) -> tuple[np.ndarray, np.ndarray]:
    lo = np.asarray(list(low.values()) if isinstance(low, Mapping) else low, dtype=float).reshape(-1)
    hi = np.asarray(list(high.values()) if isinstance(high, Mapping) else high, dtype=float).reshape(-1)
    if lo.size == 1 and n > 1:
        lo = np.full(n, lo[0])
    if hi.size == 1 and n > 1:
        hi = np.full(n, hi[0])
    if lo.size != n or hi.size != n:
        raise InputError(None, "low/high", f"{n} bounds (one per column)", (lo.size, hi.size))
    if np.any(hi == lo):
        raise InputError(None, "low/high", "high != low for every factor", list(zip(lo, hi)))
    return lo, hi


def coded_to_actual(coded, low, high) -> np.ndarray:
    """actual = centre + coded * (high - low)/2, column-wise."""
    x = np.asarray(coded, dtype=float)
    n = x.shape[-1] if x.ndim else 1
    lo, hi = _as_bounds(low, high, n)
    return (lo + hi) / 2.0 + x * (hi - lo) / 2.0


def actual_to_coded(actual, low, high) -> np.ndarray:
    """coded = (actual - centre) / ((high - low)/2), column-wise."""
    x = np.asarray(actual, dtype=float)
    n = x.shape[-1] if x.ndim else 1
    lo, hi = _as_bounds(low, high, n)
    return (x - (lo + hi) / 2.0) / ((hi - lo) / 2.0)


#: a coded level within this of -1 or +1 lies on a bound of the design region: the default
#: tolerance of :func:`at_bound`, for levels a search over the region stops at
ON_BOUND = 1e-6


def at_bound(coded, side: str, tol: float = ON_BOUND):
    """Whether coded levels lie at the ``side`` ("low" or "high") bound of the design region:
    within ``tol`` coded units (the half range is 1) of -1 or +1, or beyond it.

    The package's one definition of a level at a bound; its users differ only in ``tol``:
    :data:`ON_BOUND` for optimised sets, which stop on the bound exactly
    (:func:`soilcal.chain.stage.factors_on_bounds`,
    :func:`soilcal.optimise.near_optimal.identifiability`); ``2 * pinned_fraction`` for the
    band of the range near-optimal sets must lie in to be held by a bound (the same);
    ``2 * NEAR_BOUND`` (a fiftieth of the range) for the adaptive design's consistent region,
    a Halton sample whose edge on a bound shows only within about that
    (:func:`soilcal.doe.adaptive.consistent_region`).  A bool for a scalar, else an array.
    """
    x = np.asarray(coded, dtype=float)
    if side == "low":
        out = x <= -1.0 + tol
    elif side == "high":
        out = x >= 1.0 - tol
    else:
        raise InputError(None, "side", "'low' or 'high'", side)
    return bool(out) if out.ndim == 0 else out


@dataclass
class RowComparison:
    """Result of a multiset comparison of design rows."""

    equal: bool
    only_in_a: list = field(default_factory=list)
    only_in_b: list = field(default_factory=list)

    def __bool__(self) -> bool:
        return self.equal


def _row_keys(x: np.ndarray, atol: float) -> list[tuple]:
    q = np.round(np.asarray(x, dtype=float) / atol) if atol > 0 else np.asarray(x, dtype=float)
    return [tuple(float(v) for v in r) for r in np.atleast_2d(q)]


def same_rows(a, b, atol: float = 1e-9) -> RowComparison:
    """Compare the rows of ``a`` and ``b`` as multisets (order-free, duplicates counted).

    Values are compared after rounding to a grid of ``atol``; ``only_in_a`` / ``only_in_b``
    list the surplus rows (as lists of floats) on each side.
    """
    a = np.atleast_2d(np.asarray(a, dtype=float))
    b = np.atleast_2d(np.asarray(b, dtype=float))
    if a.shape[1] != b.shape[1]:
        raise InputError(None, "design", f"{a.shape[1]} columns in both designs", b.shape[1])
    ka, kb = Counter(_row_keys(a, atol)), Counter(_row_keys(b, atol))
    scale = atol if atol > 0 else 1.0
    only_a = [[v * scale for v in k] for k, c in (ka - kb).items() for _ in range(c)]
    only_b = [[v * scale for v in k] for k, c in (kb - ka).items() for _ in range(c)]
    return RowComparison(not only_a and not only_b, only_a, only_b)


@dataclass
class ColumnMatch:
    """How a printed design maps onto a generated one.

    ``columns[j]`` is the generated column that printed column j equals (after ``signs[j]``),
    so ``signs * generated[:, columns]`` has the same rows as ``printed``.
    """

    found: bool
    identity: bool
    columns: list[int]
    signs: list[int]
    note: str = ""


def match_columns(generated, printed, allow_sign_flip: bool = True, atol: float = 1e-9) -> ColumnMatch:
    """Find whether ``printed`` equals ``generated`` up to column order (and column signs).

    ``printed`` may have fewer columns than ``generated`` (e.g. dummy columns not printed):
    an injective map of printed columns onto generated columns is searched by backtracking,
    pruning with the multiset of rows projected on the columns assigned so far. The result
    is reported, the designs are not altered.
    """
    g = np.atleast_2d(np.asarray(generated, dtype=float))
    p = np.atleast_2d(np.asarray(printed, dtype=float))
    if g.shape[0] != p.shape[0]:
        return ColumnMatch(False, False, [], [], f"run counts differ: {g.shape[0]} vs {p.shape[0]}")
    m = p.shape[1]
    if m > g.shape[1]:
        return ColumnMatch(False, False, [], [], "printed design has more columns than generated")
    if same_rows(g[:, :m], p, atol).equal:
        return ColumnMatch(True, True, list(range(m)), [1] * m, "identical up to run order")
    signs_allowed = (1, -1) if allow_sign_flip else (1,)
    pk = np.round(p / atol)
    gk = np.round(g / atol)

    def proj_ok(cols, sgns) -> bool:
        sub_g = gk[:, cols] * np.array(sgns)
        sub_p = pk[:, : len(cols)]
        return Counter(map(tuple, sub_g)) == Counter(map(tuple, sub_p))

    best: list[tuple[list[int], list[int]]] = []

    def search(cols: list[int], sgns: list[int]) -> bool:
        j = len(cols)
        if j == m:
            best.append((list(cols), list(sgns)))
            return True
        for c in range(g.shape[1]):
            if c in cols:
                continue
            for s in signs_allowed:
                cols.append(c)
                sgns.append(s)
                if proj_ok(cols, sgns) and search(cols, sgns):
                    return True
                cols.pop()
                sgns.pop()
        return False

    if search([], []):
        cols, sgns = best[0]
        return ColumnMatch(True, False, cols, sgns, "equal after permuting/sign-flipping columns")
    return ColumnMatch(False, False, [], [], "no column permutation maps generated onto printed")


def is_orthogonal(design, atol: float = 1e-9) -> bool:
    """True when X^T X is diagonal for the coded design (balanced two-level columns)."""
    x = np.asarray(design, dtype=float)
    xtx = x.T @ x
    return bool(np.allclose(xtx - np.diag(np.diag(xtx)), 0.0, atol=atol))


__all__ = [
    "PB_GENERATORS",
    "pb_runs",
    "plackett_burman",
    "plackett_burman_source",
    "box_behnken",
    "coded_to_actual",
    "actual_to_coded",
    "RowComparison",
    "same_rows",
    "ColumnMatch",
    "match_columns",
    "is_orthogonal",
]

