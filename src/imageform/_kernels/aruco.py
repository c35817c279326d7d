r"""numba kernels of the ArUco marker detector (``imageform.geometry.aruco``).

- :func:`box_integral`: the integral image of the grey image, padded with its edges
  reflected (SciPy's ``uniform_filter(mode="reflect")``), from which every threshold
  window's local means are read with four look-ups a pixel.
- :func:`dark_components`: the local-mean adaptive threshold (a pixel is dark when it is
  below its ``win x win`` mean by more than ``offset``) and the dark pixels' connected
  components (4-connectivity), labelled run by run with union-find and numbered in raster
  order of their first pixel as ``scipy.ndimage.label`` numbers them; no label image is
  written, each component keeps its list of runs, its area and its bounding box.
- :func:`component_quads`: for each candidate component, whether its rows' spans fill
  70 % of their convex hull (:func:`_span_hull`; textured clutter does not, and is left
  there), its holes (the background of its
  box not 4-connected to the box's edge, found from the runs' gaps), whether a quad of the
  hull's vertices could pass (:func:`_quad_possible`: a blob that is no quadrilateral is
  left before its boundary is traced), its outer boundary pixels, the quadrilateral
  through four extreme boundary points (accepted when it has the filled component's area)
  and the sides fitted to the boundary pixels (total least squares), corners where they
  meet.
- :func:`cell_means`: the mean grey of each marker cell, sampled bilinearly at ``3 x 3``
  points through the homography of the unit square onto the quad; :func:`decode_cells`:
  Otsu's split of a quad's cells, its border and the nearest code.
- :func:`box_integral_u8` and :func:`dark_components_u8`: the same threshold of a uint8
  image in integers (the same dark pixels, a quarter of the memory traffic);
  :func:`box_integral_roi`: the table of a region of the image, for the full-resolution
  look at a candidate found on the image reduced by :func:`block_means`; :func:`unit_grey`:
  uint8 to [0, 1]; :func:`luma_u8` and :func:`luma_u8_into`: an RGB uint8 frame to its grey
  uint8 (the detector's Rec. 601 weights, rounded), the grey every colour frame is read on.
- :func:`sample_quadrants`: the ChArUco corners' squares sampled through their local
  homographies (``imageform.geometry.charuco``'s seen-whole check).

Work per window is proportional to the image (the threshold) plus the runs and boundary
pixels of the candidates, not their bounding boxes: a large textured blob of a photograph
costs its runs, not the area it spans. All are serial (a call is a few milliseconds on a
720p frame; parallelism belongs across frames), compiled for few signatures (float64 or
uint8 image, whole or a region's view), cached, with NumPy's division semantics
(``error_model="numpy"``: a division by zero gives inf or NaN, as the NumPy steps they
replace did, never an exception). The
Python pipeline around them is :func:`imageform.geometry.detect_aruco_markers`, whose
NumPy/SciPy twin (the component by component implementation they replace, run under
``IMAGEFORM_DISABLE_NUMBA``) gives the same markers to 1e-9 px
(``tests/geometry/test_aruco_kernels.py``).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from imageform._kernels.jit import njit

__all__ = [
    "block_means",
    "block_means_u8",
    "box_integral",
    "box_integral_roi",
    "box_integral_u8",
    "cell_means",
    "component_quads",
    "dark_components",
    "dark_components_u8",
    "decode_cells",
    "luma_u8",
    "luma_u8_into",
    "sample_quadrants",
    "unit_grey",
]


@njit(nogil=True, error_model="numpy")
def _reflect(k: int, n: int) -> int:  # pragma: no cover - compiled
    # SciPy's "reflect" (d c b a | a b c d | d c b a), any distance out
    period = 2 * n
    k = k % period
    if k < 0:
        k += period
    if k >= n:
        k = period - 1 - k
    return k


@njit(nogil=True, error_model="numpy")
def _find(parent: NDArray[np.int64], x: int) -> int:  # pragma: no cover - compiled
    root = x
    while parent[root] != root:
        root = parent[root]
    while parent[x] != root:
        nxt = parent[x]
        parent[x] = root
        x = nxt
    return root


@njit(nogil=True, error_model="numpy")
def box_integral(g: NDArray[np.float64], pad: int) -> NDArray[np.float64]:  # pragma: no cover
    """Return the integral image of ``g`` padded by ``pad`` pixels, edges reflected.

    ``out[i, j]`` is the sum of the padded image's rows ``< i`` and columns ``< j``, so any
    window of the padded image sums with four look-ups; shape ``(H + 2 pad + 1,
    W + 2 pad + 1)``. :func:`box_integral_roi` of the whole image.
    """
    hgt, wid = g.shape
    out = np.empty((hgt + 2 * pad + 1, wid + 2 * pad + 1))
    return box_integral_roi(g, pad, 0, hgt, 0, wid, out)


@njit(nogil=True, error_model="numpy")
def box_integral_roi(
    g: NDArray[np.float64],
    pad: int,
    r0: int,
    r1: int,
    c0: int,
    c1: int,
    out: NDArray[np.float64],
) -> NDArray[np.float64]:  # pragma: no cover - compiled
    """Return the integral image of a region of ``g`` and ``pad`` pixels around it.

    Rows ``r0 - pad .. r1 + pad - 1`` and columns ``c0 - pad .. c1 + pad - 1`` of ``g``, its
    edges reflected (SciPy's ``mode="reflect"``). Every window up to ``2 pad + 1`` wide
    around a pixel of ``g[r0:r1, c0:c1]`` sums from it as from :func:`box_integral` of the
    whole image, to rounding (a few units in the last place of the table's entries, far
    below the step between two 8-bit codes that decides a threshold), so
    :func:`dark_components` of the region gives the whole image's dark pixels there. Written
    into ``out``, of shape ``(r1 - r0 + 2 pad + 1, c1 - c0 + 2 pad + 1)`` (a buffer the
    caller may reuse), and returned.
    """
    hgt, wid = g.shape
    width = c1 - c0 + 2 * pad
    rows = r1 - r0 + 2 * pad
    cols = np.empty(width, dtype=np.int64)
    for k in range(width):
        cols[k] = _reflect(c0 + k - pad, wid)
    out[0, :] = 0.0
    out[:, 0] = 0.0
    # each row's running sum added to the row above as it goes (one pass); two rows at a
    # time: two independent chains of additions keep the processor busy
    for i0 in range(0, rows, 2):
        two = i0 + 1 < rows
        ra = g[_reflect(r0 + i0 - pad, hgt)]
        rb = g[_reflect(r0 + min(i0 + 1, rows - 1) - pad, hgt)]
        above = out[i0]
        oa = out[i0 + 1]
        ob = out[min(i0 + 2, rows)]
        sa = 0.0
        sb = 0.0
        for j in range(width):
            c = cols[j]
            sa += ra[c]
            sb += rb[c]
            va = sa + above[j + 1]
            oa[j + 1] = va
            if two:
                ob[j + 1] = sb + va
    return out


@njit(nogil=True, error_model="numpy")
def box_integral_u8(
    g8: NDArray[np.uint8], pad: int, out: NDArray[np.int32]
) -> NDArray[np.int32]:  # pragma: no cover - compiled
    """Return :func:`box_integral` of a uint8 image in integers (exact), written into ``out``.

    ``out`` has the shape ``(H + 2 pad + 1, W + 2 pad + 1)``; its sums must fit 31 bits:
    ``255 (H + 2 pad) (W + 2 pad) < 2³¹``.
    """
    hgt, wid = g8.shape
    width = wid + 2 * pad
    rows = hgt + 2 * pad
    cols = np.empty(width, dtype=np.int64)
    for k in range(width):
        cols[k] = _reflect(k - pad, wid)
    out[0, :] = 0
    out[:, 0] = 0
    for i in range(rows):
        row = g8[_reflect(i - pad, hgt)]
        above = out[i]
        here = out[i + 1]
        acc = np.int32(0)
        for j in range(width):
            acc += np.int32(row[cols[j]])
            here[j + 1] = acc + above[j + 1]
    return out


@njit(nogil=True, error_model="numpy")
def block_means(g: NDArray[np.float64], f: int) -> NDArray[np.float64]:  # pragma: no cover
    """Return ``g`` reduced ``f`` times: the mean of each ``f x f`` block.

    A last partial row or column of blocks is dropped; OpenCV's ``resize(INTER_AREA)`` at an
    integer factor.
    """
    hgt, wid = g.shape
    h2, w2 = hgt // f, wid // f
    out = np.zeros((h2, w2))
    inv = 1.0 / (f * f)
    for i in range(h2):
        o = out[i]
        for di in range(f):
            row = g[i * f + di]
            for j in range(w2):
                acc = 0.0
                for dj in range(f):
                    acc += row[j * f + dj]
                o[j] += acc
        for j in range(w2):
            o[j] *= inv
    return out


@njit(nogil=True, error_model="numpy")
def block_means_u8(g8: NDArray[np.uint8], f: int) -> NDArray[np.uint8]:  # pragma: no cover
    """Return the uint8 image ``g8`` reduced ``f`` times: each ``f x f`` block's mean, rounded.

    A last partial row or column of blocks is dropped; :func:`block_means` in integers, the
    mean rounded half up (OpenCV's ``resize(INTER_AREA)`` at an integer factor, to a code).
    """
    hgt, wid = g8.shape
    h2, w2 = hgt // f, wid // f
    out = np.empty((h2, w2), dtype=np.uint8)
    if f == 2:  # a 4K frame's case, unrolled
        for i in range(h2):
            ra = g8[2 * i]
            rb = g8[2 * i + 1]
            o = out[i]
            for j in range(w2):
                s = np.int32(ra[2 * j]) + ra[2 * j + 1] + rb[2 * j] + rb[2 * j + 1]
                o[j] = (s + 2) >> 2
        return out
    acc = np.zeros(w2, dtype=np.int64)
    n = f * f
    half = n // 2
    for i in range(h2):
        acc[:] = 0
        for di in range(f):
            row = g8[i * f + di]
            for j in range(w2):
                s = 0
                for dj in range(f):
                    s += row[j * f + dj]
                acc[j] += s
        o = out[i]
        for j in range(w2):
            o[j] = (acc[j] + half) // n
    return out


@njit(nogil=True, error_model="numpy")
def luma_u8(rgb: NDArray[np.uint8]) -> NDArray[np.uint8]:  # pragma: no cover
    """Return the grey uint8 of the RGB uint8 image ``rgb`` (H, W, 3): :func:`luma_u8_into`."""
    out = np.empty((rgb.shape[0], rgb.shape[1]), dtype=np.uint8)
    luma_u8_into(rgb, out)
    return out


@njit(nogil=True, error_model="numpy")
def luma_u8_into(rgb: NDArray[np.uint8], out: NDArray[np.uint8]) -> None:  # pragma: no cover
    """Write the grey uint8 of the RGB uint8 image ``rgb`` (H, W, 3) into ``out`` (H, W).

    :math:`Y = 0.299 R + 0.587 G + 0.114 B` (the detector's Rec. 601 weights,
    ``aruco._gray01``), rounded half up, in integers: ``(299 R + 587 G + 114 B + 500) // 1000``
    (exact; :func:`imageform.geometry.aruco._luma_u8_numpy` is its NumPy twin). ``rgb`` is
    C-contiguous.
    """
    hgt, wid = rgb.shape[0], rgb.shape[1]
    flat = rgb.reshape(hgt, 3 * wid)
    for i in range(hgt):
        row = flat[i]
        o = out[i]
        for j in range(wid):
            s = (
                np.int64(row[3 * j]) * 299
                + np.int64(row[3 * j + 1]) * 587
                + np.int64(row[3 * j + 2]) * 114
                + 500
            )
            # s // 1000 for s <= 255500, exactly, without a division (tested)
            o[j] = (s * 67109) >> 26


@njit(nogil=True, error_model="numpy")
def dark_components(
    g: NDArray[np.float64],
    integral: NDArray[np.float64],
    pad: int,
    win: int,
    offset: float,
    cap: int,
    cap_labels: int,
) -> tuple[
    NDArray[np.int64], NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]
]:  # pragma: no cover - compiled
    """Threshold ``g`` against its ``win x win`` local mean and label the dark components.

    See :func:`_labelled`: ``integral`` is :func:`box_integral` of ``g``.
    """
    return _labelled(g, integral, _EMPTY_U8, _EMPTY_I32, False, pad, win, offset, cap, cap_labels)


@njit(nogil=True, error_model="numpy")
def dark_components_u8(
    g8: NDArray[np.uint8],
    integral: NDArray[np.int32],
    pad: int,
    win: int,
    cap: int,
    cap_labels: int,
) -> tuple[
    NDArray[np.int64], NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]
]:  # pragma: no cover - compiled
    """:func:`dark_components` of ``g8 / 255`` with the offset 0.02, in integers.

    ``integral`` is :func:`box_integral_u8` of ``g8``. A pixel is dark when ``g8 / 255 <
    S / (255 w²) - 0.02`` (``S`` its window's sum of ``g8``, ``w`` the window), that is
    ``10 g8 w² < 10 S - 51 w²``, which never holds with equality for an odd ``w`` (``51
    w²`` is odd): the floating-point test of :func:`dark_components`, whose rounding is far
    below the one code step, ``1 / (2550 w²)``, the two sides then differ by, gives the same
    pixels (tested), at a quarter of the memory traffic; ``10 S`` must fit 31 bits
    (``w <= 917``).
    """
    return _labelled(_EMPTY_F64, _EMPTY_F64, g8, integral, True, pad, win, 0.02, cap, cap_labels)


_EMPTY_F64 = np.zeros((0, 0))
_EMPTY_U8 = np.zeros((0, 0), dtype=np.uint8)
_EMPTY_I32 = np.zeros((0, 0), dtype=np.int32)


@njit(nogil=True, error_model="numpy")
def _labelled(
    g: NDArray[np.float64],
    integral: NDArray[np.float64],
    g8: NDArray[np.uint8],
    integral32: NDArray[np.int32],
    exact: bool,
    pad: int,
    win: int,
    offset: float,
    cap: int,
    cap_labels: int,
) -> tuple[
    NDArray[np.int64], NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]
]:  # pragma: no cover - compiled
    """Threshold ``g`` against its ``win x win`` local mean and label the dark components.

    ``integral`` is :func:`box_integral` of ``g`` with ``pad >= win // 2``; ``cap`` and
    ``cap_labels`` the most runs and provisional labels expected (``H * ((W + 1) // 2)`` at
    worst): with more, every output is empty (``stats`` with no rows) and the caller asks
    again with more room. The dark pixels
    are labelled run by run: a row's run joins the labels of the runs above it that it
    touches (4-connectivity, union-find). Components are numbered ``1 .. n`` in raster
    order of their first pixel, as ``scipy.ndimage.label`` numbers them.

    Returns ``runs`` (r, 3): row, first and last column of every dark run, in raster order;
    ``comp_runs`` (r,) and ``comp_ptr`` (n + 2,): the runs of component ``k`` are
    ``runs[comp_runs[comp_ptr[k]:comp_ptr[k + 1]]]``, in raster order; ``stats`` (n + 1, 5):
    area, first row, last row, first column, last column (inclusive) of each component
    (row 0 unused).
    """
    hgt, wid = g8.shape if exact else g.shape
    r = win // 2
    lo = pad - r
    hi = pad + r + 1
    inv = 1.0 / (win * win)
    k10 = np.int32(10 * win * win)
    k51 = np.int32(51 * win * win)
    ten = np.int32(10)
    # one new label a run at most: sized once (growing inside the loop would make numba
    # count references on every access); filled as they are made
    runs = np.empty((cap, 3), dtype=np.int64)
    run_lab = np.empty(cap, dtype=np.int64)
    parent = np.empty(cap_labels + 2, dtype=np.int64)
    pstats = np.empty((cap_labels + 2, 5), dtype=np.int64)
    n_prov = 0
    nr = 0
    prev_lo = 0  # the previous row's runs: prev_lo .. prev_hi - 1
    prev_hi = 0
    # dark[1 + j]: pixel j dark (0 or 1), with a light pixel either side; flip[j]: whether
    # the row changes between pixels j - 1 and j (a run starts at j or ended at j - 1), read
    # eight at a time: rows are mostly without transitions
    n_words = (wid + 8) // 8
    dark = np.zeros(8 * n_words + 1, dtype=np.uint8)
    flip = np.zeros(8 * n_words, dtype=np.uint8)
    words = flip.view(np.uint64)
    trans = np.empty(8 * n_words + 8, dtype=np.int64)
    for i in range(hgt):
        # the four corners of every window of the row as slices: the compiler vectorises
        dk = dark[1 : wid + 1]
        if exact:
            a32 = integral32[i + hi, hi : hi + wid]
            b32 = integral32[i + lo, hi : hi + wid]
            c32 = integral32[i + hi, lo : lo + wid]
            d32 = integral32[i + lo, lo : lo + wid]
            g8i = g8[i]
            for j in range(wid):
                # in 32 bits (twice the lanes of numba's 64-bit promotion): every step is
                # exact there, the table's entries and so their differences below 2³¹
                # and 10 S below 2³¹ (w <= 917)
                box = np.int32(np.int32(a32[j] - b32[j]) - np.int32(c32[j] - d32[j]))
                lhs = np.int32(np.int32(g8i[j]) * k10)
                dk[j] = np.uint8(lhs < np.int32(np.int32(ten * box) - k51))
        else:
            a = integral[i + hi, hi : hi + wid]
            b = integral[i + lo, hi : hi + wid]
            c = integral[i + hi, lo : lo + wid]
            d = integral[i + lo, lo : lo + wid]
            gi = g[i]
            for j in range(wid):
                dk[j] = np.uint8(gi[j] < (a[j] - b[j] - c[j] + d[j]) * inv - offset)
        for j in range(wid + 1):
            flip[j] = dark[j] ^ dark[j + 1]
        n_trans = 0
        for w in range(n_words):
            if words[w] != 0:
                # without a branch a pixel (which of the eight flip is unpredictable): each
                # written, kept when it flips (overwritten by the next otherwise)
                for j in range(8 * w, 8 * w + 8):
                    trans[n_trans] = j
                    n_trans += flip[j]
        if nr + n_trans // 2 > cap or n_prov + n_trans // 2 > cap_labels:
            empty = np.zeros(0, dtype=np.int64)
            return np.zeros((0, 3), dtype=np.int64), empty, empty, np.zeros((0, 5), np.int64)
        row_lo = nr
        q = prev_lo
        for t in range(0, n_trans, 2):
            start = trans[t]
            end = trans[t + 1] - 1
            lab = 0
            # runs of the row above that overlap [start, end]
            while q < prev_hi and runs[q, 2] < start:
                q += 1
            above = q
            while above < prev_hi and runs[above, 1] <= end:
                b = _find(parent, run_lab[above])
                if lab == 0:
                    lab = b
                elif b < lab:
                    parent[lab] = b
                    lab = b
                elif lab < b:
                    parent[b] = lab
                above += 1
            if lab == 0:
                n_prov += 1
                parent[n_prov] = n_prov
                lab = n_prov
                pstats[lab, 0] = 0
                pstats[lab, 1] = i
                pstats[lab, 3] = start
                pstats[lab, 4] = end
            runs[nr, 0] = i
            runs[nr, 1] = start
            runs[nr, 2] = end
            run_lab[nr] = lab
            nr += 1
            pstats[lab, 0] += end - start + 1
            pstats[lab, 2] = i
            if start < pstats[lab, 3]:
                pstats[lab, 3] = start
            if end > pstats[lab, 4]:
                pstats[lab, 4] = end
        prev_lo = row_lo
        prev_hi = nr
    # components in raster order of first pixel: each set's root is its smallest
    # provisional label (unions keep the smaller), made at the set's first run
    final = np.zeros(n_prov + 1, dtype=np.int64)
    n = 0
    for p in range(1, n_prov + 1):
        root = _find(parent, p)
        if root == p:
            n += 1
            final[p] = n
        else:
            final[p] = final[root]  # root < p: set already
    stats = np.zeros((n + 1, 5), dtype=np.int64)
    stats[:, 1] = hgt
    stats[:, 3] = wid
    for p in range(1, n_prov + 1):
        f = final[p]
        stats[f, 0] += pstats[p, 0]
        stats[f, 1] = min(stats[f, 1], pstats[p, 1])
        stats[f, 2] = max(stats[f, 2], pstats[p, 2])
        stats[f, 3] = min(stats[f, 3], pstats[p, 3])
        stats[f, 4] = max(stats[f, 4], pstats[p, 4])
    # the runs grouped by component (a stable counting sort)
    comp_ptr = np.zeros(n + 2, dtype=np.int64)
    for t in range(nr):
        comp_ptr[final[run_lab[t]] + 1] += 1
    for k in range(1, n + 2):
        comp_ptr[k] += comp_ptr[k - 1]
    fill = comp_ptr[:-1].copy()
    comp_runs = np.empty(nr, dtype=np.int64)
    for t in range(nr):
        f = final[run_lab[t]]
        comp_runs[fill[f]] = t
        fill[f] += 1
    return runs[:nr].copy(), comp_runs, comp_ptr, stats


@njit(nogil=True, error_model="numpy")
def _quad(
    pts: NDArray[np.float64], area: float, quad: NDArray[np.float64]
) -> bool:  # pragma: no cover - compiled
    """Put four extreme boundary points into ``quad``, clockwise on screen.

    False when the quad through them does not have the component's area (an L, a disc).
    """
    n = pts.shape[0]
    cx = 0.0
    cy = 0.0
    for k in range(n):
        cx += pts[k, 0]
        cy += pts[k, 1]
    cx /= n
    cy /= n
    i0 = 0
    best = -1.0
    for k in range(n):
        d = (pts[k, 0] - cx) ** 2 + (pts[k, 1] - cy) ** 2
        if d > best:
            best = d
            i0 = k
    i2 = 0
    best = -1.0
    for k in range(n):
        d = (pts[k, 0] - pts[i0, 0]) ** 2 + (pts[k, 1] - pts[i0, 1]) ** 2
        if d > best:
            best = d
            i2 = k
    dx = pts[i2, 0] - pts[i0, 0]
    dy = pts[i2, 1] - pts[i0, 1]
    i1 = 0
    i3 = 0
    hi = -math.inf
    lo = math.inf
    for k in range(n):
        side = dx * (pts[k, 1] - pts[i0, 1]) - dy * (pts[k, 0] - pts[i0, 0])
        if side > hi:
            hi = side
            i1 = k
        if side < lo:
            lo = side
            i3 = k
    if hi <= 0 or lo >= 0:
        return False
    idx = (i0, i1, i2, i3)
    for k in range(4):
        quad[k, 0] = pts[idx[k], 0]
        quad[k, 1] = pts[idx[k], 1]
    signed = 0.0
    perimeter = 0.0
    for k in range(4):
        x, y = quad[k, 0], quad[k, 1]
        xn, yn = quad[(k + 1) % 4, 0], quad[(k + 1) % 4, 1]
        signed += x * yn - y * xn
        perimeter += math.hypot(xn - x, yn - y)
    signed *= 0.5
    # the quad runs through boundary pixel centres: about half a pixel inside the blob
    expected = area - 0.5 * perimeter
    if abs(abs(signed) - expected) > 0.12 * area:
        return False
    if signed < 0:  # clockwise on screen (v down) is a positive signed area in (u, v)
        for c in range(2):
            a0, a1 = quad[0, c], quad[1, c]
            quad[0, c] = quad[3, c]
            quad[1, c] = quad[2, c]
            quad[2, c] = a1
            quad[3, c] = a0
    return True


@njit(nogil=True, error_model="numpy")
def _corner_tolerance(shortest_side: float) -> float:  # pragma: no cover - compiled
    """Largest move (px) of a quad's corner from its extreme boundary pixel to the fitted sides.

    3 px, or 12 % of the shortest side when larger: the 3 % of the perimeter OpenCV's contour
    approximation allows a marker (``polygonalApproxAccuracyRate``), 12 % of a square's
    side. A corner's extreme pixel lies inside the sides' meeting point by a few times the
    edge's blur (the threshold rounds the corner; more at an acute corner), and the blur in
    pixels grows with the frame: a 720p webcam's markers of 30-40 px moved their corners up
    to 2.2 px (6-8 % of the side), the same frames enlarged 3.6 times (markers of 100-150 px)
    3-6.5 px, oblique ones of 50 px 4-5 px. A 12-megapixel photograph's corners rounded by
    the lens and the print and sides bent with the paper move several pixels too. It was
    3 % of the side: caliscope's webcam frames enlarged 3.6 times read 384 of the 528 markers
    OpenCV read (555 now, 5 missed), 4096 x 3072 photographs 184 of 205 (209 now, 1 missed;
    ``benchmarks/results/track-upscaled-2026-12-01e.md``).
    """
    return max(3.0, 0.12 * shortest_side)


@njit(nogil=True, error_model="numpy")
def _refine_sides(
    quad: NDArray[np.float64], pts: NDArray[np.float64], out: NDArray[np.float64]
) -> bool:  # pragma: no cover - compiled
    """Put the corners where the four fitted sides meet into ``out``.

    False when a side has too few pixels, two sides are parallel or a corner moves more
    than ``_corner_tolerance`` of the shortest side (3 px, or 12 % of the side on large
    markers).

    Each side is the total-least-squares line through the boundary pixels along it, moved
    half a pixel outwards (boundary pixel centres lie half a pixel inside the dark edge).
    """
    n = pts.shape[0]
    ccx = 0.25 * (quad[0, 0] + quad[1, 0] + quad[2, 0] + quad[3, 0])
    ccy = 0.25 * (quad[0, 1] + quad[1, 1] + quad[2, 1] + quad[3, 1])
    lines = np.empty((4, 3))
    for k in range(4):
        ax, ay = quad[k, 0], quad[k, 1]
        dx = quad[(k + 1) % 4, 0] - ax
        dy = quad[(k + 1) % 4, 1] - ay
        length = math.hypot(dx, dy)
        if length < 1e-9:
            return False
        nx, ny = -dy / length, dx / length
        tol = max(1.5, 0.06 * length)
        cnt = 0
        sx = 0.0
        sy = 0.0
        for q in range(n):
            px, py = pts[q, 0] - ax, pts[q, 1] - ay
            t = (px * dx + py * dy) / length**2
            if t > 0.12 and t < 0.88 and abs(px * nx + py * ny) < tol:
                cnt += 1
                sx += pts[q, 0]
                sy += pts[q, 1]
        if cnt < 4:
            return False
        mx, my = sx / cnt, sy / cnt
        sxx = 0.0
        syy = 0.0
        sxy = 0.0
        for q in range(n):
            px, py = pts[q, 0] - ax, pts[q, 1] - ay
            t = (px * dx + py * dy) / length**2
            if t > 0.12 and t < 0.88 and abs(px * nx + py * ny) < tol:
                ux, uy = pts[q, 0] - mx, pts[q, 1] - my
                sxx += ux * ux
                syy += uy * uy
                sxy += ux * uy
        theta = 0.5 * math.atan2(2.0 * sxy, sxx - syy)  # direction of the line
        lx, ly = -math.sin(theta), math.cos(theta)
        if lx * (mx - ccx) + ly * (my - ccy) < 0:
            lx, ly = -lx, -ly  # pointing out of the quad
        lines[k, 0] = lx
        lines[k, 1] = ly
        lines[k, 2] = -(lx * mx + ly * my) - 0.5
    worst = 0.0
    shortest = math.inf
    for k in range(4):
        shortest = min(
            shortest,
            math.hypot(quad[(k + 1) % 4, 0] - quad[k, 0], quad[(k + 1) % 4, 1] - quad[k, 1]),
        )
    for k in range(4):
        a1, b1, c1 = lines[(k + 3) % 4, 0], lines[(k + 3) % 4, 1], lines[(k + 3) % 4, 2]
        a2, b2, c2 = lines[k, 0], lines[k, 1], lines[k, 2]
        det = a1 * b2 - a2 * b1
        if abs(det) < 1e-12:
            return False
        out[k, 0] = (b1 * c2 - b2 * c1) / det
        out[k, 1] = (c1 * a2 - c2 * a1) / det
        worst = max(worst, math.hypot(out[k, 0] - quad[k, 0], out[k, 1] - quad[k, 1]))
    return worst <= _corner_tolerance(shortest)


@njit(nogil=True, error_model="numpy")
def _outside_segments(
    i: int,
    rs: NDArray[np.int64],
    re: NDArray[np.int64],
    row_ptr: NDArray[np.int64],
    out_gap: NDArray[np.bool_],
    c0: int,
    c1: int,
    seg: NDArray[np.int64],
) -> int:  # pragma: no cover - compiled
    """Write row ``i``'s outside background segments (start, end) into ``seg``; their count.

    Left of the first run, right of the last, and the gaps between runs reached from the
    box's edge; in column order.
    """
    n = 0
    p0, p1 = row_ptr[i], row_ptr[i + 1]
    if rs[p0] > c0:
        seg[n, 0] = c0
        seg[n, 1] = rs[p0] - 1
        n += 1
    for q in range(p0, p1 - 1):
        if out_gap[q]:
            seg[n, 0] = re[q] + 1
            seg[n, 1] = rs[q + 1] - 1
            n += 1
    if re[p1 - 1] < c1:
        seg[n, 0] = re[p1 - 1] + 1
        seg[n, 1] = c1
        n += 1
    return n


#: A holed component whose rows' spans (first to last pixel of each row) fill less than
#: ``SPAN_NUM / SPAN_DEN`` of their convex hull is no quadrilateral (textured clutter):
#: left before its holes and boundary are traced. A marker's dark square fills its hull:
#: at least 95 % on the webcam videos' decoded markers (``component_quads``' docstring).
SPAN_NUM, SPAN_DEN = 7, 10


@njit(nogil=True, error_model="numpy")
def _span_hull(
    first: NDArray[np.int64], last: NDArray[np.int64], hull: NDArray[np.int64]
) -> tuple[int, int, int]:  # pragma: no cover - compiled
    """Return the rows' spans' pixel count, twice their convex hull's area and its vertices.

    In integers; the hull's ``top`` vertices are left in ``hull`` (``x, y`` pairs, box
    coordinates, in the chain's order; collinear points left out).

    Row ``i``'s span runs from column ``first[i]`` to ``last[i]``; the hull is that of the
    spans' end pixels' centres (Andrew's monotone chain over the points in row order, each
    row's ``first`` before its ``last``). ``hull``: a work buffer of ``4 n + 2`` entries.
    """
    n = first.shape[0]
    area = 0
    for i in range(n):
        area += last[i] - first[i] + 1
    # lower chain then upper chain, the points (x, y) sorted by (y, x): row i's first, last
    m = 2 * n
    top = 0
    for pass_ in range(2):
        start = top
        for q in range(m):
            t = q if pass_ == 0 else m - 1 - q
            i = t // 2
            x = first[i] if t % 2 == 0 else last[i]
            while top - start >= 2:
                ax, ay = hull[2 * (top - 2)], hull[2 * (top - 2) + 1]
                bx, by = hull[2 * (top - 1)], hull[2 * (top - 1) + 1]
                if (bx - ax) * (i - ay) - (by - ay) * (x - ax) <= 0:
                    top -= 1
                else:
                    break
            hull[2 * top] = x
            hull[2 * top + 1] = i
            top += 1
        top -= 1  # the chain's last point starts the other chain
    twice = 0
    for q in range(top):
        r = (q + 1) % top
        twice += hull[2 * q] * hull[2 * r + 1] - hull[2 * r] * hull[2 * q + 1]
    return area, abs(twice), top


#: ``component_quads`` tries :func:`_quad_possible` (``top²`` steps for a hull of ``top``
#: vertices) before tracing a component's boundary (steps in proportion to its runs) when
#: ``top² <= QUICK`` times its runs: the test costs less than the tracing it may spare.
QUICK = 16


@njit(nogil=True, error_model="numpy")
def _quad_possible(
    hull: NDArray[np.int64],
    top: int,
    c0: int,
    r0: int,
    area: float,
    min_side: float,
    vx: NDArray[np.float64],
    vy: NDArray[np.float64],
) -> bool:  # pragma: no cover - compiled
    """Whether :func:`_quad` and the sides' test could accept the component (False: never).

    ``hull``: :func:`_span_hull`'s ``top`` vertices (box coordinates; the box's corner at
    column ``c0``, row ``r0``); ``area``: the filled component's pixels; ``vx``, ``vy``: work
    buffers of ``top`` entries. :func:`_quad`'s four points are boundary pixels, all of them
    in the spans' hull, whose vertices are boundary pixels (rows' first and last): its
    farthest points (from the centroid, then from the first: strictly convex distances) are
    hull vertices, and so is the first in raster order of the points farthest either side of
    the diagonal (a linear function, largest on a vertex or an edge, whose first point in
    raster order is one of its ends). So with the hull's vertices in raster order, each
    tried as the first point, :func:`_quad`'s own steps give every quad it can find, one of
    them its own (its first point depends on the boundary's centroid): when none has the
    component's area and sides long and even enough (``component_quads``' statuses 3 and 4)
    the boundary need not be traced. The same arithmetic on the same points: the verdict
    for the true first point is :func:`_quad`'s.
    """
    if top < 3:
        return True  # a line: left to the full test
    for q in range(top):
        vx[q] = hull[2 * q] + c0
        vy[q] = hull[2 * q + 1] + r0
    for q in range(1, top):  # raster order: row, then column (insertion: a few vertices)
        x, y = vx[q], vy[q]
        t = q - 1
        while t >= 0 and (vy[t] > y or (vy[t] == y and vx[t] > x)):
            vx[t + 1] = vx[t]
            vy[t + 1] = vy[t]
            t -= 1
        vx[t + 1] = x
        vy[t + 1] = y
    for i0 in range(top):
        i2 = 0
        best = -1.0
        for k in range(top):
            d = (vx[k] - vx[i0]) ** 2 + (vy[k] - vy[i0]) ** 2
            if d > best:
                best = d
                i2 = k
        dx = vx[i2] - vx[i0]
        dy = vy[i2] - vy[i0]
        i1 = 0
        i3 = 0
        hi = -math.inf
        lo = math.inf
        for k in range(top):
            side = dx * (vy[k] - vy[i0]) - dy * (vx[k] - vx[i0])
            if side > hi:
                hi = side
                i1 = k
            if side < lo:
                lo = side
                i3 = k
        if hi <= 0 or lo >= 0:
            continue
        idx = (i0, i1, i2, i3)
        signed = 0.0
        perimeter = 0.0
        s_lo = math.inf
        s_hi = 0.0
        for k in range(4):
            x, y = vx[idx[k]], vy[idx[k]]
            xn, yn = vx[idx[(k + 1) % 4]], vy[idx[(k + 1) % 4]]
            signed += x * yn - y * xn
            s = math.hypot(xn - x, yn - y)
            perimeter += s
            s_lo = min(s_lo, s)
            s_hi = max(s_hi, s)
        signed *= 0.5
        expected = area - 0.5 * perimeter
        if abs(abs(signed) - expected) > 0.12 * area:
            continue
        if s_lo < min_side or s_lo < 0.25 * s_hi:
            continue
        return True
    return False


@njit(nogil=True, error_model="numpy")
def component_quads(
    runs: NDArray[np.int64],
    comp_runs: NDArray[np.int64],
    comp_ptr: NDArray[np.int64],
    cand: NDArray[np.int64],
    stats: NDArray[np.int64],
    min_side: float,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:  # pragma: no cover - compiled
    """Find the refined quadrilateral of each candidate component ``cand[m]`` (see the module).

    ``runs``, ``comp_runs``, ``comp_ptr`` and ``stats`` are :func:`dark_components`'. The
    holes are found run by run: the component's runs in each row, the background gaps between
    them joined (union-find) to the gaps they touch in the rows above and below, a gap
    outside when joined to the box's edge (the first and last rows, the parts left and
    right of each row's runs); the outer boundary pixels, in raster order, are the filled
    pixels with a 4-neighbour outside. Returns ``quads`` (m, 4, 2) (clockwise on screen,
    sub-pixel corners) and ``status`` (m,): 0 a quad, 1 no holes (a solid blob), 2 too few
    boundary pixels, 3 not a quadrilateral, 4 sides too short or too unequal, 5 the sides
    did not fit, 6 its rows' spans fill less than 70 % of their convex hull
    (:func:`_span_hull`: not a quadrilateral, told before the holes and the boundary are
    traced; on the 720p webcam videos of ``benchmarks/results/track-speed-2026-11-30j.md``
    the test leaves 46 % of the holed candidates' runs, every quad found kept: the
    quads' spans filled at least 74 % of their hull, the decoded markers' 95 %).
    Statuses 3 and 4 are told before the boundary is traced too when the spans' hull has
    few vertices (``top² <= QUICK`` runs): :func:`_quad_possible` tries each of its vertices
    as :func:`_quad`'s first point, and when no quad has the area and the sides the boundary
    is not traced (status 3 then; the same quads found: ``track-speed-2026-11-30k.md``).
    """
    m = cand.shape[0]
    quads = np.zeros((m, 4, 2))
    status = np.zeros(m, dtype=np.int64)
    quad = np.empty((4, 2))
    # work buffers sized once for the largest candidate (no allocation per candidate)
    max_nr = 1
    max_hh = 1
    max_ww = 1
    max_box = 1
    for c in range(m):
        k = cand[c]
        hh = stats[k, 2] - stats[k, 1] + 1
        ww = stats[k, 4] - stats[k, 3] + 1
        max_nr = max(max_nr, comp_ptr[k + 1] - comp_ptr[k])
        max_hh = max(max_hh, hh)
        max_ww = max(max_ww, ww)
        max_box = max(max_box, hh * ww)
    rs_buf = np.empty(max_nr, dtype=np.int64)
    re_buf = np.empty(max_nr, dtype=np.int64)
    row_ptr = np.empty(max_hh + 1, dtype=np.int64)
    gp = np.empty(max_nr + 1, dtype=np.int64)
    out_gap = np.empty(max_nr, dtype=np.bool_)
    pts = np.empty((max_box, 2))  # the boundary pixels (at most the filled box)
    seg_u = np.empty((max_ww + 2, 2), dtype=np.int64)
    seg_d = np.empty((max_ww + 2, 2), dtype=np.int64)
    first = np.empty(max_hh, dtype=np.int64)
    last = np.empty(max_hh, dtype=np.int64)
    hull = np.empty(4 * max_hh + 2, dtype=np.int64)
    vx = np.empty(4 * max_hh + 2)
    vy = np.empty(4 * max_hh + 2)
    for c in range(m):
        k = cand[c]
        r0, r1, c0, c1 = stats[k, 1], stats[k, 2], stats[k, 3], stats[k, 4]
        hh, ww = r1 - r0 + 1, c1 - c0 + 1
        # the component's runs, row by row (in raster order, every row of its box has one)
        p0, p1 = comp_ptr[k], comp_ptr[k + 1]
        nr = p1 - p0
        if nr == hh:
            status[c] = 1  # one run a row: no hole, a solid blob
            continue
        rs = rs_buf[:nr]
        re = re_buf[:nr]
        for t in range(nr):
            rr = runs[comp_runs[p0 + t]]
            rs[t] = rr[1]
            re[t] = rr[2]
        t = 0
        for i in range(hh):
            row_ptr[i] = t
            while t < nr and runs[comp_runs[p0 + t], 0] == r0 + i:
                t += 1
        row_ptr[hh] = nr
        for i in range(hh):
            first[i] = rs[row_ptr[i]] - c0
            last[i] = re[row_ptr[i + 1] - 1] - c0
        spans, twice, top = _span_hull(first[:hh], last[:hh], hull)
        if 2 * SPAN_DEN * spans < SPAN_NUM * twice:
            status[c] = 6  # its rows' spans fill too little of their hull: no quadrilateral
            continue
        # gaps (the gap after run q, when q is not its row's last) joined across rows
        for t in range(nr + 1):  # union-find of the gaps; node nr is the outside
            gp[t] = t
        for i in range(hh):
            for q in range(row_ptr[i], row_ptr[i + 1] - 1):
                if i == 0 or i == hh - 1:
                    gp[q] = nr
        for i in range(hh - 1):
            # merge-walk the background segments of rows i and i + 1
            pa, ea = row_ptr[i], row_ptr[i + 1]
            pb, eb = row_ptr[i + 1], row_ptr[i + 2]
            ta, tb = 0, 0  # segment t: 0 left part, 1 .. runs-1 gaps, runs right part
            na, nb = ea - pa, eb - pb
            while ta <= na and tb <= nb:
                if ta == 0:
                    sa, fa, node_a = c0, rs[pa] - 1, nr
                elif ta == na:
                    sa, fa, node_a = re[ea - 1] + 1, c1, nr
                else:
                    sa, fa, node_a = re[pa + ta - 1] + 1, rs[pa + ta] - 1, pa + ta - 1
                if tb == 0:
                    sb, fb, node_b = c0, rs[pb] - 1, nr
                elif tb == nb:
                    sb, fb, node_b = re[eb - 1] + 1, c1, nr
                else:
                    sb, fb, node_b = re[pb + tb - 1] + 1, rs[pb + tb] - 1, pb + tb - 1
                if sa > fa:
                    ta += 1
                    continue
                if sb > fb:
                    tb += 1
                    continue
                if max(sa, sb) <= min(fa, fb) and node_a != node_b:
                    x = node_a
                    while gp[x] != x:
                        gp[x] = gp[gp[x]]  # path halving
                        x = gp[x]
                    y = node_b
                    while gp[y] != y:
                        gp[y] = gp[gp[y]]
                        y = gp[y]
                    if x < y:
                        gp[x] = y  # the larger wins: the outside (nr) stays a root
                    elif y < x:
                        gp[y] = x
                if fa < fb:
                    ta += 1
                else:
                    tb += 1
        out_gap[:nr] = False
        outside = 0
        for i in range(hh):
            p0, p1 = row_ptr[i], row_ptr[i + 1]
            outside += rs[p0] - c0 + c1 - re[p1 - 1]
            for q in range(p0, p1 - 1):
                x = q
                while gp[x] != x:
                    gp[x] = gp[gp[x]]
                    x = gp[x]
                if x == nr:
                    out_gap[q] = True
                    outside += rs[q + 1] - re[q] - 1
        filled = hh * ww - outside
        if filled == stats[k, 0]:
            status[c] = 1  # no holes: a solid blob, not a marker (its code has white cells)
            continue
        if top * top <= QUICK * nr and not _quad_possible(
            hull, top, c0, r0, float(filled), min_side, vx, vy
        ):
            status[c] = 3  # no quad of its hull's vertices passes: its boundary not traced
            continue
        # outer boundary: filled pixels with a 4-neighbour outside (or beyond the box)
        n = 0
        for i in range(hh):
            p0, p1 = row_ptr[i], row_ptr[i + 1]
            nu = 0
            nd = 0
            if 0 < i < hh - 1:
                nu = _outside_segments(i - 1, rs, re, row_ptr, out_gap, c0, c1, seg_u)
                nd = _outside_segments(i + 1, rs, re, row_ptr, out_gap, c0, c1, seg_d)
            su = 0
            sd = 0
            q = p0
            while q < p1:
                a = rs[q]
                while q < p1 - 1 and not out_gap[q]:
                    q += 1
                b = re[q]
                q += 1
                if i == 0 or i == hh - 1:
                    for x in range(a, b + 1):
                        pts[n, 0] = x
                        pts[n, 1] = r0 + i
                        n += 1
                    continue
                # a, b and the span's parts under an outside segment above or below, merged
                # in column order (each list is sorted and disjoint)
                pts[n, 0] = a
                pts[n, 1] = r0 + i
                n += 1
                cur = a
                while su < nu and seg_u[su, 1] < a:
                    su += 1  # segments ending before this span end before the next ones
                while sd < nd and seg_d[sd, 1] < a:
                    sd += 1
                tu = su
                td = sd
                while True:
                    have_u = tu < nu and seg_u[tu, 0] <= b
                    have_d = td < nd and seg_d[td, 0] <= b
                    if not (have_u or have_d):
                        break
                    if have_u and (not have_d or seg_u[tu, 0] <= seg_d[td, 0]):
                        lo_, hi_ = seg_u[tu, 0], seg_u[tu, 1]
                        tu += 1
                    else:
                        lo_, hi_ = seg_d[td, 0], seg_d[td, 1]
                        td += 1
                    for x in range(max(lo_, cur + 1), min(hi_, b) + 1):
                        pts[n, 0] = x
                        pts[n, 1] = r0 + i
                        n += 1
                    cur = max(cur, min(hi_, b))
                if cur < b:
                    pts[n, 0] = b
                    pts[n, 1] = r0 + i
                    n += 1
        if n < 12:
            status[c] = 2
            continue
        bnd = pts[:n]
        if not _quad(bnd, float(filled), quad):
            status[c] = 3
            continue
        lo = math.inf
        hi = 0.0
        for q in range(4):
            s = math.hypot(quad[(q + 1) % 4, 0] - quad[q, 0], quad[(q + 1) % 4, 1] - quad[q, 1])
            lo = min(lo, s)
            hi = max(hi, s)
        if lo < min_side or lo < 0.25 * hi:
            status[c] = 4
            continue
        if not _refine_sides(quad, bnd, quads[c]):
            status[c] = 5
    return quads, status


@njit(nogil=True, error_model="numpy")
def cell_means(
    g: NDArray[np.float64], quads: NDArray[np.float64], cells: int
) -> NDArray[np.float64]:  # pragma: no cover - compiled
    """Average each of the ``cells x cells`` cells of each quad: (m, cells²), row by row.

    Each cell is sampled bilinearly (edges clamped) at the 3 x 3 points ``0.3, 0.5, 0.7`` of
    its side, mapped through the homography of the square ``[0, cells]²`` onto the quad
    (its corners in the quad's order: top-left, top-right, bottom-right, bottom-left).
    """
    hgt, wid = g.shape
    m = quads.shape[0]
    out = np.zeros((m, cells * cells))
    sub = (0.3, 0.5, 0.7)
    for c in range(m):
        x0, y0 = quads[c, 0, 0], quads[c, 0, 1]
        x1, y1 = quads[c, 1, 0], quads[c, 1, 1]
        x2, y2 = quads[c, 2, 0], quads[c, 2, 1]
        x3, y3 = quads[c, 3, 0], quads[c, 3, 1]
        # the unit square onto the quad (Heckbert's closed form)
        sx = x0 - x1 + x2 - x3
        sy = y0 - y1 + y2 - y3
        dx1, dx2 = x1 - x2, x3 - x2
        dy1, dy2 = y1 - y2, y3 - y2
        den = dx1 * dy2 - dx2 * dy1
        if den == 0.0:
            continue
        hg = (sx * dy2 - dx2 * sy) / den
        hh = (dx1 * sy - sx * dy1) / den
        a = x1 - x0 + hg * x1
        b = x3 - x0 + hh * x3
        d = y1 - y0 + hg * y1
        e = y3 - y0 + hh * y3
        for ci in range(cells):
            for cj in range(cells):
                acc = 0.0
                for si in range(3):
                    for sj in range(3):
                        s = (cj + sub[sj]) / cells
                        t = (ci + sub[si]) / cells
                        w = hg * s + hh * t + 1.0
                        u = (a * s + b * t + x0) / w
                        v = (d * s + e * t + y0) / w
                        u = min(max(u, 0.0), wid - 1.0)
                        v = min(max(v, 0.0), hgt - 1.0)
                        u0 = min(math.floor(u), wid - 2)
                        v0 = min(math.floor(v), hgt - 2)
                        fu, fv = u - u0, v - v0
                        acc += (1 - fv) * ((1 - fu) * g[v0, u0] + fu * g[v0, u0 + 1]) + fv * (
                            (1 - fu) * g[v0 + 1, u0] + fu * g[v0 + 1, u0 + 1]
                        )
                out[c, ci * cells + cj] = acc / 9.0
    return out


@njit(nogil=True, error_model="numpy")
def sample_quadrants(
    g: NDArray[np.float64],
    homs: NDArray[np.float64],
    corner: NDArray[np.float64],
    dirs: NDArray[np.float64],
    grid: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:  # pragma: no cover - compiled
    """Sample ``g`` at board points around ChArUco corners (``imageform.geometry.charuco``).

    Corner ``i``'s points are ``corner[i] + dirs[i, k] * grid[t]`` (board units; two
    quadrant directions ``k``, the ``P`` points of ``grid`` in each), mapped to pixels by
    ``homs[i]``; returns the values ``(m, 2 P)`` (bilinear, edges clamped, as
    ``geometry.aruco._bilinear``) and whether each point fell in the image (a point outside
    is sampled at pixel (0, 0)).
    """
    hgt, wid = g.shape
    m = homs.shape[0]
    p = grid.shape[0]
    vals = np.empty((m, 2 * p))
    ok = np.empty((m, 2 * p), dtype=np.bool_)
    for i in range(m):
        h = homs[i]
        for k in range(2):
            for t in range(p):
                bx = corner[i, 0] + dirs[i, k, 0] * grid[t, 0]
                by = corner[i, 1] + dirs[i, k, 1] * grid[t, 1]
                w = bx * h[2, 0] + by * h[2, 1] + h[2, 2]
                u = (bx * h[0, 0] + by * h[0, 1] + h[0, 2]) / w
                v = (bx * h[1, 0] + by * h[1, 1] + h[1, 2]) / w
                inside = (
                    math.isfinite(u)
                    and math.isfinite(v)
                    and 0.0 <= u <= wid - 1.0
                    and 0.0 <= v <= hgt - 1.0
                )
                if not inside:
                    u = 0.0
                    v = 0.0
                u0 = min(math.floor(u), wid - 2)
                v0 = min(math.floor(v), hgt - 2)
                fu, fv = u - u0, v - v0
                vals[i, k * p + t] = (1 - fv) * ((1 - fu) * g[v0, u0] + fu * g[v0, u0 + 1]) + fv * (
                    (1 - fu) * g[v0 + 1, u0] + fu * g[v0 + 1, u0 + 1]
                )
                ok[i, k * p + t] = inside
    return vals, ok


@njit(nogil=True, error_model="numpy")
def _sort_small(v: NDArray[np.float64]) -> None:  # pragma: no cover - compiled
    # insertion sort in place, NaN last (NumPy's order): the same values as ``v.sort()`` for
    # a quad's 36-81 cell means, without numba's quicksort (1.4 s of a first run's compiling)
    for i in range(1, v.size):
        x = v[i]
        j = i - 1
        while j >= 0 and (v[j] > x or (v[j] != v[j] and x == x)):
            v[j + 1] = v[j]
            j -= 1
        v[j + 1] = x


@njit(nogil=True, error_model="numpy")
def decode_cells(
    means: NDArray[np.float64],
    rotated: NDArray[np.uint8],
    cells: int,
    max_bits: int,
    border_rate: float,
    min_contrast: float,
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]:
    """Read the cells of each quad (``means`` (m, cells²), row by row) against the codes.

    ``geometry.aruco._decode`` in one pass: Otsu's split of the quad's cell means (white
    above), its border cells (at most ``border_rate`` of them white), the nearest code of
    ``rotated`` (n, 4, inner bits) over the four rotations (first of the smallest distance).
    Returns the code (-1 when refused: contrast under ``min_contrast``, border, or more than
    ``max_bits`` apart), rotation, distance and contrast (max - min of the means) of each.
    """
    m, n = means.shape
    n_codes = rotated.shape[0]
    n_bits = rotated.shape[2]
    code = np.full(m, -1, dtype=np.int64)
    rot = np.zeros(m, dtype=np.int64)
    dist = np.zeros(m, dtype=np.int64)
    contrast = np.zeros(m)
    v = np.empty(n)
    csum = np.empty(n)
    inner = np.empty(n_bits, dtype=np.uint8)
    n_border = cells * cells - (cells - 2) * (cells - 2)
    for q in range(m):
        row = means[q]
        lo = row[0]
        hi = row[0]
        for t in range(n):
            v[t] = row[t]
            lo = min(lo, row[t])
            hi = max(hi, row[t])
        contrast[q] = hi - lo
        _sort_small(v)
        acc = 0.0
        for t in range(n):
            acc += v[t]
            csum[t] = acc
        best = -1.0
        k = 0
        for i in range(1, n):
            m0 = csum[i - 1] / i
            m1 = (csum[n - 1] - csum[i - 1]) / (n - i)
            between = (i / n) * (1 - i / n) * (m0 - m1) ** 2
            if between > best or i == 1:
                best = between
                k = i - 1
        thr = 0.5 * (v[k] + v[k + 1])
        white_border = 0
        b = 0
        for r in range(cells):
            for c in range(cells):
                white = row[r * cells + c] > thr
                if r == 0 or c == 0 or r == cells - 1 or c == cells - 1:
                    white_border += white
                else:
                    inner[b] = white
                    b += 1
        if hi - lo < min_contrast or white_border > border_rate * n_border:
            continue
        dmin = n_bits + 1
        arg = 0
        for k_code in range(n_codes):
            for k_rot in range(4):
                d = 0
                ref = rotated[k_code, k_rot]
                for t in range(n_bits):
                    d += ref[t] != inner[t]
                if d < dmin:
                    dmin = d
                    arg = k_code * 4 + k_rot
        if dmin > max_bits:
            continue
        code[q] = arg // 4
        rot[q] = arg % 4
        dist[q] = dmin
    return code, rot, dist, contrast


@njit(nogil=True, error_model="numpy")
def unit_grey(g8: NDArray[np.uint8], out: NDArray[np.float64]) -> None:  # pragma: no cover
    """Write ``g8 / 255`` into ``out`` (the same values as NumPy's ``true_divide``)."""
    hgt, wid = g8.shape
    for i in range(hgt):
        src = g8[i]
        dst = out[i]
        for j in range(wid):
            dst[j] = src[j] / 255.0
