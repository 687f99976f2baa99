"""The heap's top edge read from the levelled images (measure._top_edge) is the column-by-column
definition of its docstring: the first row of the levelled mask at or above 0.5, interpolated;
refined where the gray level steps by more than 0.03 between the medians of 6 px above and
below (np.median) to its mid-level crossing; in luminance where its step exceeds
max(0.03, LUM_EDGE_SNR x its robust noise)."""

from __future__ import annotations

import numpy as np
import pytest

from soilcal.imaging import measure


def _crossing(seg, mid, sgn, start, default):
    """The first sample of ``seg`` on the far side of ``mid`` from sign ``sgn``, interpolated
    linearly from the one before; ``default`` when there is none or ``seg`` starts there."""
    for j in range(len(seg)):
        if sgn * (seg[j] - mid) <= 0:
            if j == 0:
                return default
            return start + j - 1 + (seg[j - 1] - mid) / (seg[j - 1] - seg[j])
    return default


def _by_column(lev, c0, c1, glev=None, llev=None):
    cols, rows, rows_l = [], [], []
    n = lev.shape[0]
    for c in range(int(c0), int(c1)):
        col = lev[:, c]
        idx = np.nonzero(col >= 0.5)[0]
        if idx.size == 0 or idx[0] == 0:
            continue
        i = idx[0]
        r_mask = i - 1 + (0.5 - col[i - 1]) / (col[i] - col[i - 1])
        r = rl = r_mask
        if glev is not None and 12 <= i < n - 12:
            g = glev[:, c]
            bg, fg = np.median(g[i - 12:i - 6]), np.median(g[i + 6:i + 12])
            if abs(bg - fg) > 0.03:
                r = _crossing(g[i - 6:i + 6], 0.5 * (bg + fg), np.sign(bg - fg), i - 6, r_mask)
            rl = r
            if llev is not None:
                gl = llev[:, c]
                above, below = gl[i - 12:i - 6], gl[i + 6:i + 12]
                bl, fl = np.median(above), np.median(below)
                noise = 1.4826 * np.median(np.abs(np.concatenate([above - bl, below - fl])))
                if abs(bl - fl) > max(0.03, measure.LUM_EDGE_SNR * noise):
                    rl = _crossing(gl[i - 6:i + 6], 0.5 * (bl + fl), np.sign(bl - fl), i - 6, r_mask)
        cols.append(c)
        rows.append(r)
        rows_l.append(rl)
    return np.asarray(cols, float), np.asarray(rows, float), np.asarray(rows_l, float)


def _images(seed, n=90, w=70):
    """A levelled heap mask (a ridge of random height per column, softened as a rotation's
    bilinear interpolation leaves it; columns with no heap, one reaching the top row, edges
    within 12 rows of either border), a cue image and a luminance image stepping across its
    edge by random amounts (some below the thresholds, some dark-over-light) with noise, some
    quantised to few levels (ties in the medians)."""
    rng = np.random.default_rng(seed)
    top = rng.uniform(-3, n + 3, w)
    top[rng.random(w) < 0.1] = n + 5  # no heap in the column
    top[:3] = [0.0, 5.0, n - 8.0]  # from the top row; edges near either border
    rows = np.arange(n)[:, None]
    lev = np.clip(rows - top[None, :] + 0.5, 0.0, 1.0)
    sel = rng.random(w) < 0.2
    lev[:, sel] = np.round(lev[:, sel] * 4) / 4
    out = [lev]
    for _ in range(2):
        step = rng.uniform(-0.3, 0.3, w)
        img = 0.5 + step[None, :] * np.tanh((rows - top[None, :]) / rng.uniform(0.5, 3.0)) \
            + rng.normal(0, rng.uniform(0.0, 0.05), (n, w))
        if rng.random() < 0.5:
            img = np.round(img * 16) / 16
        out.append(img)
    return out


@pytest.mark.parametrize("seed", range(40))
def test_top_edge_is_its_column_by_column_definition(seed):
    lev, glev, llev = _images(seed)
    w = lev.shape[1]
    for args in ((lev, 0, w), (lev, 2, w - 3, glev), (lev, 0, w, glev, llev), (lev, 5, 5, glev, llev)):
        got = measure._top_edge(*args)
        want = _by_column(*args)[:len(got)]
        assert len(got) == len(want)
        for g, e in zip(got, want):
            assert g.dtype == np.float64 and np.array_equal(g, e), (seed, len(args))
