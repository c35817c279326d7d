"""Numba kernels: the 4-connected components of ``g < t`` as runs, their boxes and masks.

The plain twin is scipy's ``ndimage.label(g < t)`` followed by ``ndimage.find_objects``
(:func:`imageform.analysis.sfr._components_at` runs either; the tests check that both give
the same components, boxes and masks, in the same order). ``find_slanted_edges`` labels
the image at 16 levels; on a 12.8-megapixel photograph scipy's label image, its second pass
for the boxes and the boolean image made for each level took about 60 % of its time. Here
each level is one scan of the image that thresholds as it goes and records the runs of dark
pixels of each row; a run touching one of the previous row's runs (4-connectivity: they
share a column) is joined to it with a union-find (run-based two-pass labelling: L. He, Y.
Chao, K. Suzuki, "A run-based two-scan labeling algorithm", IEEE Trans. Image Processing 17,
2008). No label image is written; a component's mask is painted from its runs only when it
is kept.
"""

from __future__ import annotations

import numpy as np

from imageform._kernels.jit import njit

__all__ = ["level_runs", "outline", "paint_runs"]


@njit
def _root(parent, i):  # type: ignore[no-untyped-def]  # pragma: no cover - numba
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@njit
def _join(runs, parent, k, i, s, e, p, prev_hi):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Record run ``k`` (row ``i``, columns ``s:e``) and join it to the runs above it.

    The previous row's runs that share a column with it are searched from index ``p`` on,
    below ``prev_hi``; returns the new ``p``.
    """
    runs[k, 0] = i
    runs[k, 1] = s
    runs[k, 2] = e
    parent[k] = k
    while p < prev_hi and runs[p, 2] <= s:
        p += 1
    q = p
    while q < prev_hi and runs[q, 1] < e:
        a = _root(parent, q)
        b = _root(parent, k)
        if a < b:
            parent[b] = a
        elif b < a:
            parent[a] = b
        q += 1
    return p


@njit
def _resolve(runs, parent, m, h, w):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Return ``(runs, comp, boxes)`` of the first ``m`` runs, components in raster order."""
    runs = runs[:m]
    # a component's root is its first run (the smallest index): numbering the roots in
    # order numbers the components in the raster order of their first pixels
    comp = np.empty(m, dtype=np.int64)
    n = 0
    for r in range(m):
        a = _root(parent, r)
        if a == r:
            comp[r] = n
            n += 1
        else:
            comp[r] = comp[a]
    boxes = np.empty((n, 4), dtype=np.int64)
    boxes[:, 0] = h
    boxes[:, 1] = 0
    boxes[:, 2] = w
    boxes[:, 3] = 0
    for r in range(m):
        c = comp[r]
        boxes[c, 0] = min(boxes[c, 0], runs[r, 0])
        boxes[c, 1] = max(boxes[c, 1], runs[r, 0] + 1)
        boxes[c, 2] = min(boxes[c, 2], runs[r, 1])
        boxes[c, 3] = max(boxes[c, 3], runs[r, 2])
    return runs, comp, boxes


@njit
def level_runs(g, t):  # type: ignore[no-untyped-def]  # pragma: no cover - numba
    """Return the runs and 4-connected components of ``g < t`` and of ``g > t``, in one scan.

    Returns ``(dark, light)``, each ``(runs, comp, boxes)``: ``runs`` (m, 3) each run's
    row, first and last + 1 column, in raster order; ``comp`` (m,) its component, numbered
    0, 1, ... in the raster order of the components' first pixels (scipy's ``label``
    numbers them so, from 1); ``boxes`` (n, 4) each component's ``r0, r1, c0, c1`` (rows
    ``r0:r1``, columns ``c0:c1``).
    """
    h, w = g.shape
    # room for the most runs the rows can hold (int32: 16 bytes a run, 6.4 million runs
    # reserved per polarity for 12.8 megapixels); np.empty leaves the pages untouched until
    # used, and a run is written only where the image has one
    cap = h * ((w + 1) // 2)
    d_runs = np.empty((cap, 3), dtype=np.int32)
    d_parent = np.empty(cap, dtype=np.int32)
    l_runs = np.empty((cap, 3), dtype=np.int32)
    l_parent = np.empty(cap, dtype=np.int32)
    dk = 0
    lk = 0
    d_lo = d_hi = l_lo = l_hi = 0
    for i in range(h):
        row = g[i]
        d_row, l_row = dk, lk
        dp, lp = d_lo, l_lo
        j = 0
        while j < w:
            v = row[j]
            s = j
            j += 1
            if v < t:
                while j < w and row[j] < t:
                    j += 1
                dp = _join(d_runs, d_parent, dk, i, s, j, dp, d_hi)
                dk += 1
            elif v > t:
                while j < w and row[j] > t:
                    j += 1
                lp = _join(l_runs, l_parent, lk, i, s, j, lp, l_hi)
                lk += 1
        d_lo, d_hi = d_row, dk
        l_lo, l_hi = l_row, lk
    return _resolve(d_runs, d_parent, dk, h, w), _resolve(l_runs, l_parent, lk, h, w)


@njit
def paint_runs(runs, comp, keep, boxes):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Return the masks (over their boxes) of the components ``keep`` (sorted), as a list."""
    masks = []
    slot = np.full(boxes.shape[0], -1, dtype=np.int64)
    for i in range(keep.size):
        c = keep[i]
        slot[c] = i
        masks.append(np.zeros((boxes[c, 1] - boxes[c, 0], boxes[c, 3] - boxes[c, 2]), np.bool_))
    for r in range(runs.shape[0]):
        i = slot[comp[r]]
        if i < 0:
            continue
        c = comp[r]
        mk = masks[i]
        row = runs[r, 0] - boxes[c, 0]
        for j in range(runs[r, 1] - boxes[c, 2], runs[r, 2] - boxes[c, 2]):
            mk[row, j] = True
    return masks


@njit
def outline(m):  # type: ignore[no-untyped-def]  # pragma: no cover - numba
    """Return the first dark pixel of each row and column of mask ``m``, from each side.

    Returns ``(left, right, top, bottom)``: per row the first dark column seen from the
    left and from the right, per column the first dark row seen from the top and from the
    bottom; -1 where the row (column) has no dark pixel. The twin:
    ``imageform.analysis.sfr._outline`` (``argmax`` over the mask's lines).
    """
    h, w = m.shape
    left = np.full(h, -1, dtype=np.int64)
    right = np.full(h, -1, dtype=np.int64)
    top = np.full(w, -1, dtype=np.int64)
    bottom = np.full(w, -1, dtype=np.int64)
    for i in range(h):
        for j in range(w):
            if m[i, j]:
                if left[i] < 0:
                    left[i] = j
                right[i] = j
                if top[j] < 0:
                    top[j] = i
                bottom[j] = i
    return left, right, top, bottom
