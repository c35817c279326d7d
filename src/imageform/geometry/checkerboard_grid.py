"""Checkerboard structure recovery: neighbour graph, lattice labels, rectangle growing, checks.

Private helpers of :mod:`imageform.geometry.checkerboard`.

The inner corners of a checkerboard lie on two families of straight lines (the square edges;
nearly straight under lens distortion), and each corner's two edge directions point at its
four grid neighbours. So:

1. **Neighbour graph.** For each candidate and each of its two edge directions ``d`` and
   signs ``±``, the neighbour is the nearest candidate within a small angle of ``±d`` that
   itself has an edge direction along the joining vector (the edge is shared).
2. **Lattice labels.** A breadth-first walk from a seed gives each reached candidate integer
   coordinates ``(i, j)``, carrying an oriented basis from node to node (Geiger et al. 2012,
   sec. III-B grow a grid the same way, by energy; here only complete rows are accepted).
3. **Rectangle growing.** From the seed, the rectangle of labels grows one full row or
   column at a time while the new row or column is complete; partial rows (spurious
   corners at the board's border) never enter.
4. **Checks.** The final grid must be a consistent lattice: every row and column nearly
   straight and evenly spaced locally (second differences small against the spacing), every
   cell a convex quadrilateral of the same orientation, and the cells' brightness must
   alternate like a checkerboard's.
"""

from __future__ import annotations

from collections import deque

import numpy as np
from numpy.typing import NDArray

from imageform import _deprecate
from imageform._backend import use_numba
from imageform.geometry.checkerboard_candidates import Candidates

__all__ = [
    "cell_parity_ok",
    "grow_rectangle",
    "label_lattice",
    "lattice_problem",
    "lattice_problem_numpy",
    "lattice_rectangle",
    "neighbors",
]

#: Largest angle (radians) between an edge direction and the vector to a neighbour.
ANGLE_TOL = 0.3


def neighbors(cand: Candidates, min_dist: float, k_nearest: int = 16) -> NDArray[np.int64]:
    """Neighbour table ``(N, 2, 2)``: ``[n, k, s]`` the neighbour along ``(+d_k, -d_k)[s]``, or -1.

    Only the ``k_nearest`` nearest candidates of each are considered (a grid neighbour is
    among the 8 nearest on a board); links are kept only when mutual.
    """
    from imageform._kernels.checkerboard import neighbors_numba, neighbors_numpy

    xy = np.ascontiguousarray(cand.xy, dtype=np.float64)
    dirs = np.ascontiguousarray(cand.dirs, dtype=np.float64)
    kernel = neighbors_numba if use_numba(xy) else neighbors_numpy
    return kernel(xy, dirs, float(min_dist), int(k_nearest), float(np.cos(ANGLE_TOL)))


neighbours = _deprecate.renamed(
    neighbors,
    "imageform.geometry.checkerboard_grid.neighbours",
    instead="use imageform.geometry.checkerboard_grid.neighbors instead",
)


def label_lattice(
    seed: int, cand: Candidates, nbr: NDArray[np.int64], max_hops: int = 10**9
) -> dict[tuple[int, int], int]:
    """Breadth-first lattice coordinates of the component of ``seed``; conflicts are dropped.

    Each reached node carries an oriented basis ``(e_i, e_j)`` (its own edge directions,
    matched in order and sense to its parent's) that maps its links to lattice steps.
    The walk stops ``max_hops`` links from the seed.
    """
    dirs = cand.dirs.tolist()
    links = nbr.tolist()
    coord_of: dict[int, tuple[int, int]] = {seed: (0, 0)}
    node_at: dict[tuple[int, int], int] = {(0, 0): seed}
    d0 = dirs[seed]
    basis: dict[int, tuple[float, float, float, float]] = {
        seed: (d0[0][0], d0[0][1], d0[1][0], d0[1][1])
    }
    queue = deque([seed])
    while queue:
        a = queue.popleft()
        eix, eiy, ejx, ejy = basis[a]
        ia, ja = coord_of[a]
        if abs(ia) + abs(ja) >= max_hops:
            continue
        for k in range(2):
            vx, vy = dirs[a][k]
            for s, sign in enumerate((1.0, -1.0)):
                b = links[a][k][s]
                if b < 0 or b in coord_of:
                    continue
                di = sign * (vx * eix + vy * eiy)
                dj = sign * (vx * ejx + vy * ejy)
                if abs(di) >= abs(dj):
                    c = (ia + (1 if di > 0 else -1), ja)
                else:
                    c = (ia, ja + (1 if dj > 0 else -1))
                if c in node_at:
                    continue
                # the neighbour's basis: its edge directions matched to ours, same sense
                (p0x, p0y), (p1x, p1y) = dirs[b]
                c0 = p0x * eix + p0y * eiy
                c1 = p1x * eix + p1y * eiy
                if abs(c0) >= abs(c1):
                    (bix, biy), (bjx, bjy), ci = (p0x, p0y), (p1x, p1y), c0
                else:
                    (bix, biy), (bjx, bjy), ci = (p1x, p1y), (p0x, p0y), c1
                si = 1.0 if ci >= 0 else -1.0
                sj = 1.0 if bjx * ejx + bjy * ejy >= 0 else -1.0
                coord_of[b] = c
                node_at[c] = b
                basis[b] = (si * bix, si * biy, sj * bjx, sj * bjy)
                queue.append(b)
    return node_at


def grow_rectangle(
    node_at: dict[tuple[int, int], int], xy: NDArray[np.float64], max_error: float = 0.35
) -> NDArray[np.int64]:
    """Grow the largest complete rectangle from the 3 x 3 block around ``(0, 0)``.

    A new row (or column) is accepted when all its labels exist and every new point lies
    within ``max_error`` grid steps of its linear prediction ``2 p_k - p_{k-1}``. Returns
    node indices ``(n_i, n_j)`` (first axis ``i``); empty when the 3 x 3 block is incomplete.
    """
    if not all((i, j) in node_at for i in (-1, 0, 1) for j in (-1, 0, 1)):
        return np.zeros((0, 0), dtype=np.int64)

    pts = xy.tolist()  # plain floats: rows of <= a few dozen points, no array overhead
    limit2 = max_error * max_error

    def fits(
        new: list[tuple[int, int]], last: list[tuple[int, int]], prev: list[tuple[int, int]]
    ) -> bool:
        if not all(c in node_at for c in new):
            return False
        for cn, cl, cp in zip(new, last, prev, strict=True):
            (xn, yn), (xl, yl), (xp, yp) = pts[node_at[cn]], pts[node_at[cl]], pts[node_at[cp]]
            step2 = (xl - xp) ** 2 + (yl - yp) ** 2
            err2 = (xn - 2.0 * xl + xp) ** 2 + (yn - 2.0 * yl + yp) ** 2
            if not err2 < limit2 * step2:
                return False
        return True

    i0, i1, j0, j1 = -1, 1, -1, 1
    grew = True
    while grew:
        grew = False
        js = range(j0, j1 + 1)
        if fits([(i1 + 1, j) for j in js], [(i1, j) for j in js], [(i1 - 1, j) for j in js]):
            i1, grew = i1 + 1, True
        if fits([(i0 - 1, j) for j in js], [(i0, j) for j in js], [(i0 + 1, j) for j in js]):
            i0, grew = i0 - 1, True
        is_ = range(i0, i1 + 1)
        if fits([(i, j1 + 1) for i in is_], [(i, j1) for i in is_], [(i, j1 - 1) for i in is_]):
            j1, grew = j1 + 1, True
        if fits([(i, j0 - 1) for i in is_], [(i, j0) for i in is_], [(i, j0 + 1) for i in is_]):
            j0, grew = j0 - 1, True
    return np.array(
        [[node_at[(i, j)] for j in range(j0, j1 + 1)] for i in range(i0, i1 + 1)], dtype=np.int64
    )


def lattice_rectangle(
    seed: int, cand: Candidates, nbr: NDArray[np.int64], max_hops: int = 10**6
) -> NDArray[np.int64]:
    """Run :func:`grow_rectangle` of :func:`label_lattice` from ``seed``.

    Returns node indices ``(n_i, n_j)``, empty when the 3 x 3 block around the seed is incomplete
    (one numba kernel, ``lattice_rectangle_numba``, where numba runs; the two functions otherwise).
    """
    xy = np.ascontiguousarray(cand.xy, dtype=np.float64)
    if use_numba(xy) and max_hops <= 100_000:
        from imageform._kernels.checkerboard import lattice_rectangle_numba

        return lattice_rectangle_numba(
            int(seed),
            np.ascontiguousarray(cand.dirs, dtype=np.float64),
            np.ascontiguousarray(nbr, dtype=np.int64),
            xy,
            int(max_hops),
            0.35,
        )
    return grow_rectangle(label_lattice(seed, cand, nbr, max_hops=max_hops), xy)


#: Largest second difference along a row or column of a board's corners, as a share of the
#: local spacing (:func:`lattice_problem`). A wide-angle lens bends a board's rows near the
#: image's edge and perspective shortens its squares: a GoPro's views (Udacity's
#: calibration_wide set) reach 0.30-0.33, a fisheye webcam's 0.41; one corner off by ``d``
#: gives ``2 d / spacing``, so 0.45 still refuses a corner a quarter of a square off (which
#: the sub-pixel step would not pull back).
MAX_BEND = 0.45


def lattice_problem(grid: NDArray[np.float64], max_bend: float = MAX_BEND) -> str | None:
    """Why ``grid`` (R, C, 2) is not a consistent lattice, or None when it is.

    Second differences along rows and columns must stay below ``max_bend`` times the local
    spacing (:data:`MAX_BEND`); all cells must be convex with one orientation. (One numba kernel,
    ``lattice_problem_numba``, where numba runs; :func:`lattice_problem_numpy` otherwise.)
    """
    g = np.ascontiguousarray(grid, dtype=np.float64)
    if not use_numba(g) or g.ndim != 3 or g.shape[-1] != 2:
        return lattice_problem_numpy(grid, max_bend)
    from imageform._kernels.checkerboard import lattice_problem_numba

    code, a, b = lattice_problem_numba(g, float(max_bend))
    if code == 0:
        return None
    name = "row" if code <= 2 else "column"
    if code in (1, 3):
        return f"a {name} of the grid bends or jumps (second difference {a:.2f} x spacing)"
    if code in (2, 4):
        return f"spacing along a {name} changes abruptly (ratio {a:.2f}-{b:.2f})"
    return "the grid's cells are not convex quadrilaterals of one orientation"


def lattice_problem_numpy(grid: NDArray[np.float64], max_bend: float = MAX_BEND) -> str | None:
    """Plain NumPy twin of :func:`lattice_problem`."""
    for axis, name in ((1, "row"), (0, "column")):
        g = np.moveaxis(grid, axis, 0)
        if g.shape[0] < 3:
            continue
        second = np.linalg.norm(g[2:] - 2.0 * g[1:-1] + g[:-2], axis=-1)
        spacing = 0.5 * np.linalg.norm(g[2:] - g[:-2], axis=-1)
        ratio = second / spacing
        if not np.all(ratio < max_bend):
            return (
                f"a {name} of the grid bends or jumps "
                f"(second difference {ratio.max():.2f} x spacing)"
            )
        steps = np.linalg.norm(g[1:] - g[:-1], axis=-1)
        jump = steps[1:] / steps[:-1]
        if not np.all((jump > 0.5) & (jump < 2.0)):
            return (
                f"spacing along a {name} changes abruptly (ratio {jump.min():.2f}-{jump.max():.2f})"
            )
    p00, p01, p10, p11 = grid[:-1, :-1], grid[:-1, 1:], grid[1:, :-1], grid[1:, 1:]

    def cross(a: NDArray, b: NDArray) -> NDArray:
        return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]

    turns = np.stack(
        [
            cross(p01 - p00, p11 - p01),
            cross(p11 - p01, p10 - p11),
            cross(p10 - p11, p00 - p10),
            cross(p00 - p10, p01 - p00),
        ]
    )
    if not (np.all(turns > 0) or np.all(turns < 0)):
        return "the grid's cells are not convex quadrilaterals of one orientation"
    return None


def _sample(gray: NDArray[np.floating], pts: NDArray[np.float64]) -> NDArray[np.floating]:
    """Bilinear samples of ``gray`` at the (u, v) points ``pts`` (..., 2), edges repeated."""
    from scipy import ndimage

    vals = ndimage.map_coordinates(
        gray, [pts[..., 1].ravel(), pts[..., 0].ravel()], order=1, mode="nearest"
    )
    return np.asarray(vals).reshape(pts.shape[:-1])


def cell_means(gray: NDArray[np.floating], grid: NDArray[np.float64]) -> NDArray[np.float64]:
    """Mean brightness of each cell ``(R-1, C-1)`` sampled around the cell centre."""
    centre = 0.25 * (grid[:-1, :-1] + grid[:-1, 1:] + grid[1:, :-1] + grid[1:, 1:])
    # samples a third of the way from the centre to each corner
    pts = [centre]
    for corner in (grid[:-1, :-1], grid[:-1, 1:], grid[1:, :-1], grid[1:, 1:]):
        pts.append(centre + (corner - centre) / 3.0)
    p = np.stack(pts)  # (5, R-1, C-1, 2)
    return _sample(gray, p).mean(axis=0)


def cell_parity_ok(means: NDArray[np.float64]) -> bool:
    """Whether adjacent cells alternate dark/bright like a checkerboard's.

    With cell parity ``P = (i + j) mod 2``, the difference (parity-1 cell minus parity-0
    cell) over every pair of adjacent cells must have one sign.
    """
    flip = 1 - 2 * (np.add.outer(np.arange(means.shape[0]), np.arange(means.shape[1])) % 2)
    dx = np.diff(means, axis=1) * flip[:, :-1]
    dy = np.diff(means, axis=0) * flip[:-1, :]
    diffs = np.concatenate([dx.ravel(), dy.ravel()])
    if diffs.size == 0:
        return True
    return bool(np.all(diffs > 0) or np.all(diffs < 0))


def board_continues(
    gray: NDArray[np.floating],
    grid: NDArray[np.float64],
    own: NDArray[np.float64] | None = None,
    *,
    saddles: bool = True,
) -> str | None:
    """Which side of ``grid`` (R, C, 2) the checkerboard visibly continues past, or None.

    A complete ``cols x rows`` grid can still be the wrong one: a sub-grid of a larger
    board whose extra rows are cut by the image border. Past each side the next row of
    inner corners ``k + 1`` is extrapolated (quadratically) and the image is read a quarter
    to a half cell beyond it, in the middle of each cell. Past a real board's last inner
    row lie its outer squares and then the margin or background, which do not alternate;
    if instead three or more neighbouring cells there (inside the image) alternate with the
    board's own parity by at least a sixth of its contrast, and two or more of the
    extrapolated points of row ``k + 1`` beside them are X-corners (:func:`_saddles`:
    clutter past a board's edge can alternate by chance, the edge has no X-corners), the
    board goes on.
    A board cut within a quarter cell of row ``k + 1`` cannot be told from a smaller one.
    ``own``: the grid's :func:`cell_means`, when the caller has them. ``saddles=False``
    drops the X-corner condition and asks for two alternating cells instead of three (a
    board of unknown size: near the image's border the corners of row ``k + 1`` can escape
    the saddle test, a grid of three rows has two cells a side, and a clutter that
    alternates only costs a refusal there).
    """
    h, w = gray.shape
    if own is None:
        own = cell_means(gray, grid)
    flip = 1 - 2 * (np.add.outer(np.arange(own.shape[0]), np.arange(own.shape[1])) % 2)
    sense = 1.0 if float(np.mean(own * flip)) > 0 else -1.0  # +1: flip=+1 cells bright
    mid = float(np.mean(own))
    contrast = float(np.mean(np.abs(np.diff(own, axis=1))))  # bright - dark
    # each side: the grid seen from it (its last row is the side) and the parity of the
    # board's cell row along that side (cells two rows further out have the same parity)
    sides = {
        "after the last row": (grid, flip[-1]),
        "before the first row": (grid[::-1], flip[0]),
        "after the last column": (grid.transpose(1, 0, 2), flip[:, -1]),
        "before the first column": (grid.transpose(1, 0, 2)[::-1], flip[:, 0]),
    }
    fractions = np.array([0.25, 0.35, 0.45])
    for name, (g, parity) in sides.items():
        if g.shape[0] < 3 or g.shape[1] < 3:
            continue
        p1 = 3.0 * g[-1] - 3.0 * g[-2] + g[-3]  # inner-corner row k + 1
        base = 0.5 * (p1[:-1] + p1[1:])  # (C - 1, 2) middle of each cell's near side
        step = 0.5 * ((p1 - g[-1])[:-1] + (p1 - g[-1])[1:])
        pts = base[None] + fractions[:, None, None] * step[None]  # (3, C - 1, 2)
        inside = np.all((pts >= 0) & (pts <= [w - 1, h - 1]), axis=(0, 2))
        least = 3 if saddles else 2  # cells in a run
        if inside.sum() < least:
            continue
        m = _sample(gray, pts).mean(axis=0)
        agree = ((m - mid) * parity * sense > contrast / 3.0) & inside
        runs = _runs(agree, least)  # cells start..stop-1, their corners start..stop
        if not runs:
            continue
        if not saddles:
            return name
        saddle = _saddles(gray, p1, p1 - g[-1], contrast)
        for start, stop in runs:
            if np.count_nonzero(saddle[start : stop + 1]) >= 2:
                return name
    return None


def _runs(flags: NDArray[np.bool_], least: int) -> list[tuple[int, int]]:
    """``(start, stop)`` of every run of at least ``least`` consecutive True flags."""
    out, start = [], None
    for i, f in enumerate([*flags.tolist(), False]):
        if f and start is None:
            start = i
        elif not f and start is not None:
            if i - start >= least:
                out.append((start, i))
            start = None
    return out


def _saddles(
    gray: NDArray[np.floating],
    points: NDArray[np.float64],
    outward: NDArray[np.float64],
    contrast: float,
) -> NDArray[np.bool_]:
    """Whether each of ``points`` (N, 2), a row of would-be inner corners, is an X-corner.

    The four quadrants around a point, along the row and ``outward`` (N, 2), are read a
    quarter to two fifths of a cell away: at an inner corner of a board the diagonal
    quadrants are equal and the adjacent ones differ by the board's ``contrast``; on a
    board's outer edge (an L-shaped corner of an outer square and the margin) or on
    background, two adjacent quadrants are equal or a diagonal pair is not. A point whose
    quadrants are not all inside the image is not one.
    """
    h, w = gray.shape
    along = np.gradient(points, axis=0)  # (N, 2) one cell along the row
    q = []
    for su, sv in ((1, 1), (-1, -1), (1, -1), (-1, 1)):
        d = su * along + sv * outward
        q.append(points[None] + np.array([0.25, 0.4])[:, None, None] * d[None])  # (2, N, 2)
    pts = np.stack(q)  # (4, 2, N, 2)
    inside = np.all((pts >= 0) & (pts <= [w - 1, h - 1]), axis=(0, 1, 3))
    pp, mm, pm, mp = _sample(gray, pts).mean(axis=1)  # (N,) each
    across = np.min(np.abs(np.stack([pp - pm, pp - mp, mm - pm, mm - mp])), axis=0)
    diagonal = np.maximum(np.abs(pp - mm), np.abs(pm - mp))
    return (across - diagonal > contrast / 4.0) & inside


def _outer_x_share(
    gray: NDArray[np.floating], grid: NDArray[np.float64], own: NDArray[np.float64]
) -> list[float | None]:
    """Share of each outer row and column of ``grid`` (R, C, 2) that are X-corners.

    In the order first row, last row, first column, last column: the share of that side's
    corners that :func:`_saddles` reads as X-corners (quadrants toward the next row inward
    and the next one out), among those whose quadrants lie inside the image; None where
    fewer than two do. Every inner corner of a board is an X-corner, its outer ones too
    (their outer quadrants are the board's outer squares); a corner of an outer square
    with the margin, or a thin margin against a darker background, that a lattice took
    for another row has two equal adjacent quadrants. ``own``: the grid's
    :func:`cell_means` (the board's contrast).
    """
    contrast = float(np.mean(np.abs(np.diff(own, axis=1))))
    h, w = gray.shape
    out: list[float | None] = []
    for g in (grid[::-1], grid, grid.transpose(1, 0, 2)[::-1], grid.transpose(1, 0, 2)):
        row, outward = g[-1], g[-1] - g[-2]
        ok = _saddles(gray, row, outward, contrast)
        reach = np.abs(np.gradient(row, axis=0)) * 0.4 + np.abs(outward) * 0.4
        inside = np.all((row - reach >= 0) & (row + reach <= [w - 1, h - 1]), axis=1)
        n = int(np.count_nonzero(inside))
        out.append(None if n < 2 else float(np.count_nonzero(ok & inside)) / n)
    return out
