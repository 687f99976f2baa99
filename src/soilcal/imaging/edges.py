"""The circle Hough transform of the drum's rim search: the numbers of
``skimage.transform.hough_circle`` with less work done for them.

:func:`hough_circle`: scikit-image adds each vote's increment to the accumulator pixel by
pixel; a Numba kernel counts the votes and gives each count the sum those additions come to
(see the function), in about half the time on a drum frame's rim search.  The kernel is
compiled on its first use and cached on disk (Numba's cache, as the DEM engine's kernels)."""

from __future__ import annotations

import numpy as np

_circle_kernel = None


def _circle_counts_kernel():
    """The Numba kernel of :func:`hough_circle` (compiled on first use and cached on disk),
    imported only when a drum's rim is searched."""
    global _circle_kernel
    if _circle_kernel is None:
        import numba

        @numba.njit(cache=True, nogil=True)
        def votes(h, w, e_rows, e_cols, off_rows, off_cols, starts, incrs):
            n_radii = starts.size - 1
            out = np.empty((n_radii, h, w), np.float64)
            # the counts in an array padded by the largest radius on every side, read at its
            # inside: a circle point beyond the image lands in the padding, not counted
            pad = 0
            for q in range(off_rows.size):
                pad = max(pad, abs(off_rows[q]), abs(off_cols[q]))
            wp = w + 2 * pad
            count = np.empty((h + 2 * pad) * wp, np.int32)
            at = np.empty(e_rows.size, np.int64)
            for p in range(e_rows.size):
                at[p] = (e_rows[p] + pad) * wp + e_cols[p] + pad
            for i in range(n_radii):
                count[:] = 0
                for q in range(starts[i], starts[i + 1]):
                    d = off_rows[q] * wp + off_cols[q]
                    for p in range(at.size):
                        count[at[p] + d] += 1
                top = 0
                for r in range(h):
                    for c in range(w):
                        top = max(top, count[(r + pad) * wp + c + pad])
                # k votes sum to k increments added one after the other
                sums = np.empty(top + 1, np.float64)
                s = 0.0
                sums[0] = 0.0
                for k in range(1, top + 1):
                    s += incrs[i]
                    sums[k] = s
                for r in range(h):
                    for c in range(w):
                        out[i, r, c] = sums[count[(r + pad) * wp + c + pad]]
            return out

        _circle_kernel = votes
    return _circle_kernel


def hough_circle(image, radius):
    """``skimage.transform.hough_circle(image, radius)`` (normalised, centres inside the
    image): the same float64 array (radius, row, column) of the votes of every edge pixel
    (nonzero) for the centres of the circles through it, each circle's n points
    (``skimage.draw.circle_perimeter``, a point it lists twice counted twice) voting 1 / n.

    scikit-image adds each vote's increment to its centre pixel by pixel; here a Numba kernel
    counts each centre's votes of a radius (integer counts, in any order), circle point by
    circle point, and gives a centre of k votes the sum of k increments added one after the
    other, which is what scikit-image's k additions of that one increment to the centre come
    to in whatever order its edge pixels come.  A drum frame's rim search (some 90 radii on a
    240 px copy of the frame) takes half the time."""
    from skimage.draw import circle_perimeter

    if image.ndim != 2:
        raise ValueError("The input image must be 2D.")
    offs_r, offs_c, starts, incrs = [], [], [0], []
    for rad in np.atleast_1d(np.asarray(radius)).astype(np.intp):
        rr, cc = circle_perimeter(0, 0, rad)
        order = np.lexsort((cc, rr))  # row by row: the counts are whole numbers, read in any order
        offs_r.append(rr[order])
        offs_c.append(cc[order])
        starts.append(starts[-1] + rr.size)
        incrs.append(1.0 / rr.size)  # the increment of one vote, as scikit-image divides
    e_rows, e_cols = np.nonzero(image)
    h, w = image.shape
    if not incrs:  # no radius: no circle, an empty accumulator as scikit-image gives
        return np.zeros((0, h, w), np.float64)
    return _circle_counts_kernel()(h, w, e_rows.astype(np.int64), e_cols.astype(np.int64),
                                   np.concatenate(offs_r).astype(np.int64), np.concatenate(offs_c).astype(np.int64),
                                   np.array(starts, np.int64), np.array(incrs, np.float64))
