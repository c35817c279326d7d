r"""Find a ColorChecker Classic (4 × 6 patches) in an uncropped photograph.

:func:`detect_colorchecker` returns the chart's homography, its 24 patch centres and sampling
quadrilaterals in image coordinates, a score and the chart's in-plane rotation;
:func:`measure_chart_patches` averages the patches through it (a :class:`ChartPatches`, the
input of :func:`~imageform.analysis.fit_color_correction`), the uncropped sibling of
:func:`~imageform.analysis.chart_patches`.

The method (written for imageform; the steps follow the usual chart detectors, e.g. the
segmentation detector of colour-checker-detection and OpenCV's ``mcc`` module):

1. **Flat regions.** The photograph is block-averaged to at most ``max_size`` pixels on its
   long side; the colour gradient magnitude of the Gaussian-smoothed image is thresholded at
   several levels, and the 4-connected regions below each threshold are candidate patches.
   When no chart is found there, a photograph larger than ``max_size`` is searched once
   more at twice that resolution (a small chart in a large photograph), one at or under it
   on a 2x bilinear upsample.
2. **Square-ish candidates**, by moments: an affine image of a square (any rotation, tilt
   or shear) of area :math:`A` and covariance :math:`\Sigma` has
   :math:`A / (12 \sqrt{\det \Sigma}) = 1` (a uniform square of side *s* has variance
   :math:`s^2/12` along each side); regions with this ratio in [0.85, 1.12] and an
   elongation of at most 3 are kept, duplicates across thresholds removed. A patch with a
   mark inside it (a dot, a number, a label: chart software draws them on the chart it
   found) is a flat ring, whose ratio is :math:`(1 - q) / (1 + q)` for a hole of share
   *q*: ring-like regions (ratio over 0.3, elongation under 2) have their holes filled, and
   the filled region is a candidate when it passes the same test, its holes take at most
   half of it (not the chart's frame around its patches) and it holds at most one other
   flat region (its mark; not the background around a small chart).
3. **Lattice hypotheses.** A candidate and two of its neighbours give a lattice origin and
   basis :math:`B = [d_1\ d_2]`; it is kept when the candidate's own shape agrees, i.e.
   :math:`12\, B^{-1} \Sigma B^{-T} \approx (s/p)^2 I` (the patch sides run along the
   basis, side over pitch between 0.55 and 0.97), which rules out diagonal bases. Every
   hypothesis counts the candidates on its lattice (RANSAC-style, all hypotheses at once).
4. **Growth.** The best lattices are refitted as homographies (normalised DLT) from integer
   lattice coordinates to the candidates' centroids, re-collecting candidates, three times.
   The windows of at most eight lattices are scored (step 5). A lattice with more than
   twice a chart's 24 cells on it (tiles, the cells of a grid of lines, a facade: a
   periodic texture) is taken whole, none of its cells starting another, and is not
   counted among the eight (twelve lattices grown at most): a scene with many such
   textures ranked above a chart no longer uses up the search before the chart is reached.
   Such a lattice has the affine fit of step 5 only, without its least-median retry and
   without the costlier fits of steps 6 and 7.
5. **Chart, orientation and validity by colour.** Every 4 × 6 window of the lattice in
   either of its two chart orientations (the two quarter turns the window's shape allows;
   the chart as printed: the basis is right-handed like the image) whose homography can be a
   camera's view of a flat chart (the whole chart on one side of the vanishing line, no
   patch over 40 times the image area of another) and whose neutral row is brighter where
   the reference's is (the ranks' correlation positive: a camera maps lightness
   monotonically, an affine fit can also fit it inverted) is sampled, and the reference
   colours are regressed on the measured ones with an affine map in linear light
   (a 3 × 3 matrix and an offset per channel). A patch is an outlier (an occluder, a
   reflection) when the fit of the *other* patches predicts its colour more than
   max(4 × median, 10) ΔE*ab from its reference (leave-one-out, in CIELAB: dark patches
   count, and a channel clipped at the gamut's edge, the cyan's red, barely does). The score
   is that fit's :math:`R^2` without the outliers. Several spoiled patches at once (glare
   over a corner of the chart) mask one another in the leave-one-out tests, so when that
   :math:`R^2` is under 0.95 a least-median-of-squares fit (Rousseeuw 1984; affine fits to
   400 random 6-patch subsets, the least median ΔE*ab wins) judges the outliers as well and
   the better score is kept. Every window that overlaps the lattice is tried (a chart cut by
   the frame beside a stray square). The best window and orientation above ``min_score``
   wins.
6. **Uneven light.** When no window passes, a shadow across the chart or light falling off
   along it may be why: each patch's colour is then scaled by its own light, which no affine
   map absorbs. The lattices are scored again by the colour homography
   :math:`r_k \approx s_k A m_k` (a 3 × 3 :math:`A`, a light :math:`s_k` per patch;
   Finlayson, Gong and Fisher, "Color Homography: Theory and Applications", IEEE TPAMI
   41(1), 2019, by their alternating least squares), by its adjusted :math:`R^2` (one
   parameter per patch more: a lattice of unrelated colours does not pass) and only in
   windows where at least 12 of the 24 patches were segmented (the weaker colour test needs
   more geometry: a lattice of window frames in a street scene scored 0.82 so with 6), and a
   chart found so comes with a :class:`~imageform.analysis.ChartWarning` naming the range of
   the lights.
7. **Marks on the patches.** When the affine fit fails, a label or a number printed or drawn on
   every patch may be why (each patch's mean is the patch's colour mixed with the mark's):
   the lattices are scored once more on each patch's dominant colour (7 x 7 samples per
   cell, those more than 4 robust sigmas from their median left out, as
   :func:`measure_chart_patches` does), and a chart found so must reach an :math:`R^2` of at
   least 0.9 (trimmed samples let more lattices of unrelated colours fit: the best of the
   photographs without a chart in benchmarks/results/chart-real-2026-11-29h.md scores 0.70
   so, 0.66 plain). Steps 6 and 7 are both tried and the higher score that passes wins (a
   chart with a mark on every patch has no plain fit at all: the colour homography of a
   lattice of clutter beside it must not win by default).
8. **By its shape.** When no window passes by colour, one that is plainly a chart by its
   shape may still be: 22 or more of its 24 cells segmented as flat squares, at most one
   flat square centred on a cell of its lattice in the two cells around it (the lattice is
   the chart, not a window of a grid of tiles or boxes; one is a stray), and its plain
   colour fit at most 0.15 under ``min_score`` and at least 0.15 over the same cells read
   half a turn round or mirrored (the orientation is still in the colours). A Classic
   under an orange lamp, one channel on the camera's shoulder, fits 0.71-0.80 so
   (benchmarks/results/chart-shape-2026-12-03a.md); it is found with a
   :class:`~imageform.analysis.ChartWarning`.
9. **A mirrored chart.** When steps 5-8 find no chart at either resolution, they are run
   once more on the same candidates for a chart with its columns reversed (a webcam's
   mirrored preview, a photograph flipped left to right: 26 of 58 tuning photographs in
   benchmarks/results/chart-fresh-2026-12-01e.md, whose colours no rotation of the printed
   chart matches, R² 0.24-0.63), with the same tests; a chart found so has ``mirrored``
   True. Otherwise the detection comes back with ``found`` False and the reason (a
   photograph without a chart is an answer, not an error).

Coordinates are imageform's pixel convention (docs/conventions.md): ``(u, v)`` = (column,
row), integer values at pixel centres. Chart coordinates are ``(column, row)`` of the
upright chart, in patch pitches, patch ``k`` (row by row, the order of
:data:`~imageform.analysis.synthetic.COLORCHECKER_SRGB8`) centred at
``(k % 6, k // 6)``: the upright chart has the brown "dark skin" patch top left and the
grey row at the bottom.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from imageform import _deprecate
from imageform._colormath import srgb_decode, srgb_encode
from imageform._random import RNGLike
from imageform._typing import ArrayLike
from imageform._validate import (
    as_bool,
    as_int,
    as_real,
    check_memory,
    describe,
    format_shape,
    real_array,
)
from imageform.analysis._arrays import image_in, is_dask
from imageform.analysis.chart_grid import ChartPatches, ChartWarning, _clean_pixels
from imageform.errors import InvalidInputError

__all__ = [
    "ChartDetection",
    "ChartNotFoundError",
    "ChartPhoto",
    "detect_colorchecker",
    "measure_chart_patches",
    "synthetic_chart_photo",
]

_ROWS, _COLS = 4, 6
#: Gradient thresholds (encoded sRGB per pixel) of the flat-region segmentation.
_LEVELS = (0.012, 0.025, 0.05, 0.1)


class ChartNotFoundError(InvalidInputError):
    """A function that needs a colour chart got an image without one.

    Raised by the functions that measure a chart (:func:`measure_chart_patches` of a
    detection with ``found`` False, :func:`~imageform.analysis.sample_chart`, a colour
    correction fitted to a photograph); the detector itself, :func:`detect_colorchecker`,
    returns its :class:`ChartDetection` with ``found`` False instead (docs/conventions.md,
    "Not found").
    """


@_deprecate.renamed_fields({"centres": "centers"})
@dataclass(frozen=True)
class ChartDetection:
    """The outcome of :func:`detect_colorchecker`: a ColorChecker found in a photograph, or not.

    All positions are image pixels ``(u, v)`` (column, row; pixel centres at integers). When
    no chart was found (``found`` False, ``reason`` says why), the arrays keep their shapes
    and hold NaN (``segmented`` and ``outliers`` False), ``score`` and ``rotation`` are NaN.
    """

    #: (3, 3) homography from chart ``(column, row)`` (patch pitches, patch k at
    #: ``(k % 6, k // 6)``) to image ``(u, v)``.
    homography: np.ndarray
    #: (4, 2) outer corners of the patch lattice, ``(-0.5, -0.5)``, ``(5.5, -0.5)``,
    #: ``(5.5, 3.5)``, ``(-0.5, 3.5)`` in chart coordinates: the upright chart's top left, top
    #: right, bottom right and bottom left.
    corners: np.ndarray
    #: (24, 2) patch centres, row by row.
    centers: np.ndarray
    #: (24, 4, 2) sampling quadrilaterals (the inner part of each patch), corners in the
    #: same order as ``corners``.
    quads: np.ndarray
    #: (24,) bool: the patch was segmented in the photograph (others are placed by the
    #: homography: occluded, merged with the surround, or too blurred). This field was
    #: named ``found`` in imageform 0.1, before the chart-level ``found`` below.
    segmented: np.ndarray
    #: (24,) bool: patches whose colour disagrees with the fit of the other patches
    #: (leave-one-out; left out of the score; likely occluded or covered by a reflection).
    outliers: np.ndarray
    #: :math:`R^2` of the affine linear-light fit of the reference colours on the measured
    #: ones (1 is perfect).
    score: float
    #: In-plane rotation of the chart in degrees, (-180, 180]: the image direction of the
    #: chart's rows (left to right; from patch 1 to patch 6 on a mirrored chart), clockwise
    #: from the image's +u axis as seen on screen.
    rotation: float
    #: True when a chart was found; False when the image shows none (the other fields are
    #: then NaN / False).
    found: bool = True
    #: Why no chart was found, in one line ("" when found).
    reason: str = ""
    #: True when the chart was found mirrored (its columns reversed, as a webcam's mirrored
    #: preview shows it); the homography then has a negative determinant and ``corners``
    #: are still the corners of the chart's patches 1, 6, 24 and 19 (outer corners).
    mirrored: bool = False

    def __post_init__(self) -> None:
        """Arrays to float64/bool of the documented shapes (finite when found)."""
        object.__setattr__(self, "found", as_bool(self.found, "found"))
        object.__setattr__(self, "mirrored", as_bool(self.mirrored, "mirrored"))
        if not isinstance(self.reason, str):
            raise InvalidInputError(f"expected reason as a str, got {describe(self.reason)}")
        shapes = {"homography": (3, 3), "corners": (4, 2), "centers": (24, 2), "quads": (24, 4, 2)}
        for name, shape in shapes.items():
            arr = real_array(getattr(self, name), name, shape, finite=self.found)
            object.__setattr__(self, name, arr)
        for name in ("segmented", "outliers"):
            arr = np.asarray(getattr(self, name))
            if arr.dtype != np.bool_ or arr.shape != (24,):
                raise InvalidInputError(
                    f"expected {name} as booleans of shape (24,), got {describe(arr)}"
                )
            object.__setattr__(self, name, arr)
        for name in ("score", "rotation"):
            value = getattr(self, name)
            if self.found or not (isinstance(value, float | np.floating) and np.isnan(value)):
                value = as_real(value, name)  # NaN only when not found
            object.__setattr__(self, name, float(value))

    def to_dict(self) -> dict[str, Any]:
        """Return the detection as JSON-ready values (positions None when not found)."""
        if not self.found:
            return {
                "found": False,
                "reason": self.reason,
                **dict.fromkeys(("homography", "corners", "centers", "quads")),
                "segmented": self.segmented.tolist(),
                "outliers": self.outliers.tolist(),
                "score": None,
                "rotation_degrees": None,
                "mirrored": False,
            }
        return {
            "found": True,
            "reason": "",
            "homography": self.homography.tolist(),
            "corners": self.corners.tolist(),
            "centers": self.centers.tolist(),
            "quads": self.quads.tolist(),
            "segmented": self.segmented.tolist(),
            "outliers": self.outliers.tolist(),
            "score": self.score,
            "rotation_degrees": self.rotation,
            "mirrored": self.mirrored,
        }


def _not_found(reason: str) -> ChartDetection:
    """Return the detection of a photograph without a chart: NaN positions, ``found`` False."""
    no = np.zeros(_ROWS * _COLS, dtype=bool)
    return ChartDetection(
        homography=np.full((3, 3), np.nan),
        corners=np.full((4, 2), np.nan),
        centers=np.full((_ROWS * _COLS, 2), np.nan),
        quads=np.full((_ROWS * _COLS, 4, 2), np.nan),
        segmented=no,
        outliers=no.copy(),
        score=float("nan"),
        rotation=float("nan"),
        found=False,
        reason=reason,
    )


# ---------------------------------------------------------------- geometry helpers


def _apply_h(h: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Points (..., 2) through the homography ``h``; inf or NaN on its vanishing line."""
    p = np.asarray(pts, dtype=np.float64)
    q = p @ h[:, :2].T + h[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):  # a degenerate lattice's refit
        return q[..., :2] / q[..., 2:3]


def _normalizer(p: np.ndarray) -> np.ndarray:
    c = p.mean(axis=0)
    s = np.sqrt(2.0) / max(float(np.mean(np.linalg.norm(p - c, axis=1))), 1e-12)
    return np.array([[s, 0.0, -s * c[0]], [0.0, s, -s * c[1]], [0.0, 0.0, 1.0]])


def _fit_h(src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """Fit the homography src -> dst by the normalised DLT (Hartley & Zisserman, alg. 4.2).

    An affine map is returned when the points cannot determine more (fewer than 6 or nearly
    collinear rows).
    """
    ts, td = _normalizer(src), _normalizer(dst)
    s = _apply_h(ts, src)
    d = _apply_h(td, dst)
    n = len(s)
    if n < 6:
        a = np.c_[s, np.ones(n)]
        sol, *_ = np.linalg.lstsq(a, d, rcond=None)
        hn = np.eye(3)
        hn[:2, :] = sol.T
    else:
        zero = np.zeros((n, 3))
        one = np.c_[s, np.ones(n)]
        rows = np.concatenate(
            [
                np.c_[zero, -one, d[:, 1:2] * one],
                np.c_[one, zero, -d[:, 0:1] * one],
            ]
        )
        _, _, vt = np.linalg.svd(rows)
        hn = vt[-1].reshape(3, 3)
    h = np.linalg.solve(td, hn @ ts)
    return np.asarray(h / h[2, 2])


# ---------------------------------------------------------------- candidates


def _gaussian_taps(sigma: float) -> np.ndarray:
    """Normalised Gaussian taps, radius ``int(3 sigma + 0.5)`` (scipy's default truncation)."""
    radius = int(3.0 * sigma + 0.5)
    x = np.arange(-radius, radius + 1, dtype=np.float64)
    w = np.exp(-0.5 * (x / sigma) ** 2)
    return np.asarray(w / w.sum())


def _work_image(rgb: np.ndarray, max_size: int, scale: float) -> tuple[np.ndarray, int]:
    """Block-mean the image by an integer factor so that its long side is at most ``max_size``.

    The result is float32 in [0, 1] (``scale``: 255 for uint8).
    """
    from imageform._kernels.chart import block_mean_numba

    hgt, wid = rgb.shape[:2]
    f = max(1, int(np.ceil(max(hgt, wid) / max_size)))
    if f == 1:
        return np.asarray(rgb, dtype=np.float32) / np.float32(scale), 1
    return block_mean_numba(np.ascontiguousarray(rgb), f, float(scale)), f


def _rgb_in(image: object) -> tuple[np.ndarray, float]:
    """Return the photograph as an (H, W, 3) array and its full scale.

    uint8 and uint16 arrays are kept as they are (no float copy of a large photograph), the rest
    goes through the usual checks (``image_in``: floats in [0, 1]); Dask is computed.
    """
    if isinstance(image, np.ndarray) and image.dtype in (np.uint8, np.uint16):
        if image.ndim != 3 or image.shape[-1] != 3:
            raise InvalidInputError(
                f"expected image of shape (H, W, 3), got {format_shape(tuple(image.shape))}"
            )
        return image, 255.0 if image.dtype == np.uint8 else 65535.0
    rgb = image_in(image)
    if is_dask(rgb):
        rgb = np.asarray(rgb.compute())
    if rgb.ndim != 3:
        raise InvalidInputError(
            f"expected image of shape (H, W, 3), got {format_shape(tuple(rgb.shape))}"
        )
    return rgb, 1.0


def _candidates(work: np.ndarray) -> dict[str, np.ndarray]:
    """Square-ish flat regions of the work image: centroid, area, covariance."""
    from scipy import ndimage, spatial

    from imageform._kernels.chart import flat_gradient_numba, region_moments_numba

    taps = _gaussian_taps(0.8).astype(np.float32)
    grad = flat_gradient_numba(np.ascontiguousarray(work, dtype=np.float32), taps)
    hgt, wid = grad.shape
    max_area = hgt * wid / 12.0
    out: list[np.ndarray] = []
    rings: list[np.ndarray] = []
    for level in _LEVELS:
        lab, n = ndimage.label(grad < level)
        if n == 0:
            continue
        mom = region_moments_numba(lab, n)
        m0, mx, my, mxx, myy, mxy = mom.T
        keep = (m0 >= 16) & (m0 <= max_area)
        if not keep.any():
            continue
        a = m0[keep]
        cx, cy = mx[keep] / a, my[keep] / a
        sxx = mxx[keep] / a - cx * cx + 1 / 12
        syy = myy[keep] / a - cy * cy + 1 / 12
        sxy = mxy[keep] / a - cx * cy
        det = np.maximum(sxx * syy - sxy * sxy, 1e-12)
        fill = a / (12.0 * np.sqrt(det))
        tr = sxx + syy
        disc = np.sqrt(np.maximum(tr * tr / 4 - det, 0.0))
        elong = np.sqrt((tr / 2 + disc) / np.maximum(tr / 2 - disc, 1e-12))
        ok = (fill > 0.85) & (fill < 1.12) & (elong < 3.0)
        out.append(np.c_[cx, cy, a, sxx, syy, sxy, fill][ok])
        # a patch with a mark inside it (a dot, a number, a label) is a flat ring: fill
        # ring-like regions' holes and keep those that are square then
        ring = (fill > _RING_FILL) & (fill <= 0.85) & (elong < 2.0) & (m0[keep] >= 24)
        if ring.any():
            boxes = np.c_[cx, cy, sxx, syy, a][ring]
            rings.append(_filled_holes(lab, np.flatnonzero(keep)[ring] + 1, boxes, max_area))
    if rings:
        # a marked patch holds its mark (at most one square-ish flat region, a dot); a
        # region around a whole group of them (the background around a small chart) is
        # no patch
        out.append(_hold_at_most_one(np.concatenate(rings), np.concatenate(out)))
    if not out:
        return {"c": np.zeros((0, 2)), "area": np.zeros(0), "cov": np.zeros((0, 2, 2))}
    cand = np.concatenate(out)
    # Duplicates across levels: keep the largest region (closest to the whole patch).
    order = np.argsort(-cand[:, 2])
    cand = cand[order]
    tree = spatial.cKDTree(cand[:, :2])
    alive = np.ones(len(cand), dtype=bool)
    for i in range(len(cand)):
        if not alive[i]:
            continue
        near = tree.query_ball_point(cand[i, :2], 0.35 * np.sqrt(cand[i, 2]))
        for j in near:
            if j > i:
                alive[j] = False
    cand = cand[alive]
    cov = np.stack([np.c_[cand[:, 3], cand[:, 5]], np.c_[cand[:, 5], cand[:, 4]]], axis=1)
    return {"c": cand[:, :2].copy(), "area": cand[:, 2].copy(), "cov": cov}


#: The least fill ratio of a region whose holes :func:`_filled_holes` fills: a square ring
#: of inner area share q has :math:`(1 - q) / (1 + q)`, 0.33 at q = 1/2.
_RING_FILL = 0.3
#: The largest share of a filled region its holes may take: a mark inside a patch, not the
#: patches inside the chart's frame (their share is about 2/3 of the frame's outline).
_MAX_HOLE_SHARE = 0.5


def _hold_at_most_one(filled: np.ndarray, plain: np.ndarray) -> np.ndarray:
    r"""Rows of ``filled`` whose square (by moments) holds at most one region of ``plain``.

    A square of side *s* has variance :math:`s^2 / 12` along its sides, so its points are
    within Mahalanobis distance :math:`\sqrt{3}` per side of its centroid: a smaller row of
    ``plain`` is inside when its centroid's squared Mahalanobis distance is under 3. The
    rows inside count as one region when their centroids are within a quarter of the filled
    square's side of one another (the same mark found at several thresholds).
    """
    if not len(filled) or not len(plain):
        return filled
    cov = np.stack([np.c_[filled[:, 3], filled[:, 5]], np.c_[filled[:, 5], filled[:, 4]]], 1)
    inv = np.linalg.inv(cov)
    d = plain[None, :, :2] - filled[:, None, :2]
    m2 = np.einsum("fni,fij,fnj->fn", d, inv, d)
    inside = (m2 < 3.0) & (plain[None, :, 2] < filled[:, None, 2])
    keep = np.ones(len(filled), dtype=bool)
    for i in np.flatnonzero(inside.sum(axis=1) > 1):
        pts = plain[inside[i], :2]
        gap = np.linalg.norm(pts[:, None] - pts[None], axis=-1).max()
        keep[i] = gap <= 0.25 * np.sqrt(filled[i, 2])
    return filled[keep]


def _filled_holes(
    lab: np.ndarray, labels: np.ndarray, moments: np.ndarray, max_area: float
) -> np.ndarray:
    r"""Moments rows (as in :func:`_candidates`) of ``labels``' regions with holes filled.

    ``moments``: each region's centroid, variances and area (cx, cy, sxx, syy, count). A
    region is looked for within two standard deviations and two pixels of its centroid (a
    square ring's extent is :math:`\sqrt{3}` of them) and skipped when not all its pixels
    are there. It is kept when it has holes, they take at most ``_MAX_HOLE_SHARE`` of the
    filled region, and the filled region is square-ish (fill ratio in [0.85, 1.12],
    elongation under 3).
    """
    from scipy import ndimage

    rows = []
    hgt, wid = lab.shape
    for k, (cx, cy, sxx, syy, count) in zip(labels, moments, strict=True):
        ru, rv = 2.0 * np.sqrt(sxx) + 2.0, 2.0 * np.sqrt(syy) + 2.0
        box = (
            slice(max(int(cy - rv), 0), min(int(cy + rv) + 2, hgt)),
            slice(max(int(cx - ru), 0), min(int(cx + ru) + 2, wid)),
        )
        own = lab[box] == k
        if own.sum() != count:
            continue
        full = ndimage.binary_fill_holes(own)
        a = float(full.sum())
        holes = a - float(own.sum())
        if holes <= 0 or holes > _MAX_HOLE_SHARE * a or a > max_area:
            continue
        yy, xx = np.nonzero(full)
        fu = xx + float(box[1].start)
        fv = yy + float(box[0].start)
        mu, mv = float(fu.mean()), float(fv.mean())
        suu = float(((fu - mu) ** 2).mean()) + 1 / 12
        svv = float(((fv - mv) ** 2).mean()) + 1 / 12
        suv = float(((fu - mu) * (fv - mv)).mean())
        det = max(suu * svv - suv * suv, 1e-12)
        fill = a / (12.0 * np.sqrt(det))
        tr = suu + svv
        disc = np.sqrt(max(tr * tr / 4 - det, 0.0))
        elong = np.sqrt((tr / 2 + disc) / max(tr / 2 - disc, 1e-12))
        if 0.85 < fill < 1.12 and elong < 3.0:
            rows.append([mu, mv, a, suu, svv, suv, fill])
    return np.asarray(rows, dtype=np.float64).reshape(-1, 7)


# ---------------------------------------------------------------- lattice hypotheses


def _hypotheses(cand: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(origin index, basis (2, 2) columns d1 d2, score) of every plausible lattice."""
    from scipy import spatial

    c, area, cov = cand["c"], cand["area"], cand["cov"]
    n = len(c)
    k = min(9, n)
    tree = spatial.cKDTree(c)
    _, nb = tree.query(c, k=k)
    nb = nb[:, 1:]
    i_idx = np.repeat(np.arange(n), nb.shape[1] ** 2)
    j_idx = np.repeat(nb, nb.shape[1], axis=1).ravel()
    k_idx = np.tile(nb, (1, nb.shape[1])).ravel()
    d1 = c[j_idx] - c[i_idx]
    d2 = c[k_idx] - c[i_idx]
    cross = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    ok = cross > 0.3 * np.linalg.norm(d1, axis=1) * np.linalg.norm(d2, axis=1)
    ratio_a = area[j_idx] / area[i_idx]
    ratio_b = area[k_idx] / area[i_idx]
    ok &= (ratio_a > 0.5) & (ratio_a < 2.0) & (ratio_b > 0.5) & (ratio_b < 2.0)
    i_idx, d1, d2, cross = i_idx[ok], d1[ok], d2[ok], cross[ok]
    if not len(i_idx):
        return np.zeros(0, int), np.zeros((0, 2, 2)), np.zeros(0)
    basis = np.stack([d1, d2], axis=2)  # columns
    inv = np.empty_like(basis)
    inv[:, 0, 0], inv[:, 1, 1] = basis[:, 1, 1] / cross, basis[:, 0, 0] / cross
    inv[:, 0, 1], inv[:, 1, 0] = -basis[:, 0, 1] / cross, -basis[:, 1, 0] / cross
    s = 12.0 * np.einsum("nij,njk,nlk->nil", inv, cov[i_idx], inv)
    s11, s22, s12 = s[:, 0, 0], s[:, 1, 1], s[:, 0, 1]
    good = (s11 > 0.15) & (s11 < 0.95) & (s22 > 0.15) & (s22 < 0.95)
    good &= (s11 / s22 > 0.6) & (s11 / s22 < 1.65) & (np.abs(s12) < 0.25 * np.sqrt(s11 * s22))
    i_idx, basis, inv = i_idx[good], basis[good], inv[good]
    score = np.zeros(len(i_idx))
    for lo in range(0, len(i_idx), 1024):
        sl = slice(lo, lo + 1024)
        rel = c[None, :, :] - c[i_idx[sl]][:, None, :]
        uv = np.einsum("hij,hnj->hni", inv[sl], rel)
        ruv = np.round(uv)
        res = np.abs(uv - ruv).max(axis=2)
        ar = area[None, :] / area[i_idx[sl]][:, None]
        inl = (res < 0.22) & (np.abs(ruv).max(axis=2) <= 5) & (ar > 0.4) & (ar < 2.5)
        score[sl] = inl.sum(axis=1)
    return i_idx, basis, score


def _collect(
    cand: dict[str, np.ndarray], h: np.ndarray, area_scale: float, tol: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Collect the candidates on the lattice of ``h`` (lattice -> image), one per cell.

    Returns indices, integer coords and residuals; one candidate per cell (the closest).
    """
    hinv = np.linalg.inv(h)
    # a candidate on the lattice's vanishing line (a steep fit to a few candidates) maps to
    # infinity: NaN, never on the lattice
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        uv = _apply_h(hinv, cand["c"])
        ruv = np.round(uv)
        res = np.abs(uv - ruv).max(axis=1)
        # local area of one lattice cell, from the Jacobian of h at the candidate
        eps = 0.5
        px = _apply_h(h, ruv + [eps, 0]) - _apply_h(h, ruv - [eps, 0])
        py = _apply_h(h, ruv + [0, eps]) - _apply_h(h, ruv - [0, eps])
        cell = np.abs(px[:, 0] * py[:, 1] - px[:, 1] * py[:, 0])
        ar = cand["area"] / np.maximum(cell * area_scale, 1e-9)
        ok = (res < tol) & (ar > 0.45) & (ar < 2.2) & (np.abs(ruv).max(axis=1) <= 12)
    idx = np.flatnonzero(ok)
    if not len(idx):
        return idx, np.zeros((0, 2)), np.zeros(0)
    keys = ruv[idx]
    order = np.lexsort((res[idx], keys[:, 1], keys[:, 0]))
    idx, keys = idx[order], keys[order]
    first = np.r_[True, np.any(np.diff(keys, axis=0) != 0, axis=1)]
    return idx[first], keys[first], res[idx[first]]


def _in_square_window(
    idx: np.ndarray, keys: np.ndarray, size: int
) -> tuple[np.ndarray, np.ndarray]:
    """Return the members of the ``size × size`` window of lattice cells that holds the most.

    A chart fits in one whatever its orientation: growth never strays onto clutter that happens to
    continue the lattice far away.
    """
    if not len(keys):
        return idx, keys
    lo, hi = keys.min(axis=0).astype(int), keys.max(axis=0).astype(int)
    best, best_n = None, -1
    for u0 in range(lo[0] - size + 1, hi[0] + 1):
        in_u = (keys[:, 0] >= u0) & (keys[:, 0] < u0 + size)
        if in_u.sum() <= best_n:
            continue
        for v0 in range(lo[1] - size + 1, hi[1] + 1):
            m = in_u & (keys[:, 1] >= v0) & (keys[:, 1] < v0 + size)
            n = int(m.sum())
            if n > best_n:
                best, best_n = m, n
    assert best is not None
    return idx[best], keys[best]


def _grow(
    cand: dict[str, np.ndarray], origin: int, basis: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Refit the lattice as a homography from its inliers, three rounds."""
    h = np.eye(3)
    h[:2, :2] = basis
    h[:2, 2] = cand["c"][origin]
    det = abs(float(np.linalg.det(basis)))
    area_scale = float(cand["area"][origin]) / max(det, 1e-9)
    idx = np.zeros(0, int)
    keys = np.zeros((0, 2))
    for tol in (0.22, 0.25, 0.28, 0.28):
        idx, keys, _ = _collect(cand, h, area_scale, tol)
        idx, keys = _in_square_window(idx, keys, max(_ROWS, _COLS))
        if len(idx) < 4:
            return None
        span = keys.max(axis=0) - keys.min(axis=0)
        if min(span) < 1:
            return None
        h = _fit_h(keys, cand["c"][idx])
        if not np.all(np.isfinite(h)):
            return None
        dets = _cell_area(h, keys)
        area_scale = float(np.median(cand["area"][idx] / np.maximum(dets, 1e-9)))
    return h, idx, keys


def _cell_area(h: np.ndarray, keys: np.ndarray) -> np.ndarray:
    """Image area of the lattice cells ``keys`` under ``h`` (NaN on its vanishing line)."""
    with np.errstate(invalid="ignore"):
        px = _apply_h(h, keys + [0.5, 0]) - _apply_h(h, keys - [0.5, 0])
        py = _apply_h(h, keys + [0, 0.5]) - _apply_h(h, keys - [0, 0.5])
        return np.abs(px[:, 0] * py[:, 1] - px[:, 1] * py[:, 0])


# ---------------------------------------------------------------- colour check


#: Chart (column, row) -> lattice (u, v) for the four quarter turns, as 3x3 affine maps
#: applied after the window offset: rotation 0 and 180 need a 6-wide window, 90 and 270 a
#: 4-wide one. All have determinant +1 (the chart as printed); a mirrored chart's maps are
#: these after :data:`_MIRROR` (determinant -1).
def _turn(quarter: int, u0: float, v0: float) -> np.ndarray:
    m = {
        0: [[1, 0, 0], [0, 1, 0]],
        2: [[-1, 0, _COLS - 1], [0, -1, _ROWS - 1]],
        1: [[0, -1, _ROWS - 1], [1, 0, 0]],
        3: [[0, 1, 0], [-1, 0, _COLS - 1]],
    }[quarter]
    a = np.vstack([np.asarray(m, dtype=np.float64), [0.0, 0.0, 1.0]])
    a[0, 2] += u0
    a[1, 2] += v0
    return a


#: Chart (column, row) -> (column, row) of the chart seen in a mirror: its columns reversed
#: (a webcam's mirrored preview, a photograph flipped left to right).
_MIRROR = np.array([[-1.0, 0.0, _COLS - 1], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])

_GRID = np.stack(np.meshgrid(np.arange(_COLS), np.arange(_ROWS)), axis=-1).reshape(-1, 2)
_OFFS = np.stack(np.meshgrid(np.linspace(-0.2, 0.2, 5), np.linspace(-0.2, 0.2, 5)), -1).reshape(
    -1, 2
)


_OFFS_FINE = np.stack(
    np.meshgrid(np.linspace(-0.25, 0.25, 7), np.linspace(-0.25, 0.25, 7)), -1
).reshape(-1, 2)


def _sample(work: np.ndarray, h: np.ndarray, trim: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Mean and spread of the work image over the inner part of every cell of chart->work h.

    With ``trim``, 7 x 7 samples per cell trimmed to the cell's dominant colour as
    :func:`measure_chart_patches` trims pixels (a label over part of a patch is left out); a
    cell with under half its samples kept gets an infinite spread (unusable).
    """
    return _sample_cells(work, h, _GRID.astype(np.float64), trim)


def _sample_cells(
    work: np.ndarray, h: np.ndarray, cells: np.ndarray, trim: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_sample` of the cells ``cells`` (n, 2) (lattice coordinates) of the map ``h``.

    The samples of a cell are a square grid about its centre, the same points whichever
    quarter turn or mirror image of the chart the cell is read in: a lattice's windows
    share the samples of their cells (:func:`_best_window` samples each cell once).
    """
    from scipy import ndimage

    offs = _OFFS_FINE if trim else _OFFS
    pts = _apply_h(h, (cells[:, None, :] + offs[None, :, :]).reshape(-1, 2))
    vals = np.stack(
        [
            ndimage.map_coordinates(work[..., ch], [pts[:, 1], pts[:, 0]], order=1, mode="nearest")
            for ch in range(3)
        ],
        axis=-1,
    ).reshape(len(cells), len(offs), 3)
    if not trim:
        return vals.mean(axis=1), vals.std(axis=1).max(axis=1)
    keep = _clean_pixels(vals)
    kept = np.where(keep[..., None], vals, np.nan)
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a cell with no sample kept
        mean = np.nanmean(kept, axis=1)
        spread = np.nanstd(kept, axis=1).max(axis=1)
    few = 2 * keep.sum(axis=1) < keep.shape[1]
    return np.where(few[:, None], vals.mean(axis=1), mean), np.where(few, np.inf, spread)


#: A patch is a colour outlier when the colour the fit of the other patches predicts for it
#: is more than ``max(_OUTLIER_FACTOR * median, _OUTLIER_DELTA_E)`` CIELAB ΔE*ab (CIE 1976)
#: from its reference, the median taken over the other patches' residuals of that fit.
_OUTLIER_FACTOR, _OUTLIER_DELTA_E = 4.0, 10.0


_XYZ_WHITE: list[np.ndarray] = []


def _xyz_white() -> np.ndarray:
    """Linear sRGB -> XYZ over the white's XYZ, as a right-hand factor (3, 3)."""
    if not _XYZ_WHITE:
        from imageform.color.rgb_spaces import rgb_to_xyz_matrix

        m = rgb_to_xyz_matrix("srgb")
        _XYZ_WHITE.append((m / m.sum(axis=1)[:, None]).T.copy())
    return _XYZ_WHITE[0]


def _lab_from_linear(lin: np.ndarray) -> np.ndarray:
    """CIELAB (D65, the sRGB white) of linear sRGB rows (..., 3), clipped to [0, 1] first."""
    xyz = np.clip(lin, 0.0, 1.0) @ _xyz_white()
    f = np.where(xyz > (6 / 29) ** 3, np.cbrt(xyz), xyz / (3 * (6 / 29) ** 2) + 4 / 29)
    return np.stack(
        [116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]), 200 * (f[..., 1] - f[..., 2])],
        axis=-1,
    )


def _drop_one_fits(
    x: np.ndarray, ref_lin: np.ndarray, lab_ref: np.ndarray, use: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """ΔE*ab of every patch under the fit of ``use`` without each used patch in turn.

    Returns the used patches' indices (m,) and ΔE (m, n): row i is the fit without patch
    ``idx[i]`` (Sherman-Morrison downdates of one least-squares fit, no refit), column j
    the distance of patch j's prediction from its reference.
    """
    idx = np.flatnonzero(use)
    xu = x[idx]
    g = np.linalg.pinv(xu.T @ xu)
    b = xu.T @ ref_lin[idx]
    gx = xu @ g  # (m, 4): g x_k
    lev = np.einsum("ij,ij->i", gx, xu)
    gk = g[None] + np.einsum("ki,kj->kij", gx, gx) / np.maximum(1.0 - lev, 1e-9)[:, None, None]
    bk = b[None] - np.einsum("ki,kj->kij", xu, ref_lin[idx])
    wk = np.einsum("kij,kjc->kic", gk, bk)  # (m, 4, 3)
    pred = np.einsum("nj,kjc->knc", x, wk)  # (m, n, 3)
    d = _lab_from_linear(pred) - lab_ref[None]
    return idx, np.sqrt((d * d).sum(axis=-1))


def _held_out(
    x: np.ndarray, ref_lin: np.ndarray, lab_ref: np.ndarray, use: np.ndarray
) -> np.ndarray:
    """ΔE*ab of each used patch's leave-one-out prediction (hat-matrix identity, no refit).

    Values for patches not in ``use`` are meaningless.
    """
    xu = x[use]
    g = np.linalg.pinv(xu.T @ xu)
    w = g @ (xu.T @ ref_lin[use])
    lev = np.einsum("ij,jk,ik->i", x, g, x)
    held = ref_lin - (ref_lin - x @ w) / np.maximum(1.0 - lev, 1e-9)[:, None]
    d = _lab_from_linear(held) - lab_ref
    return np.asarray(np.sqrt((d * d).sum(axis=1)))


def _bound(others: np.ndarray) -> float:
    return max(_OUTLIER_FACTOR * float(np.median(others)), _OUTLIER_DELTA_E)


def _colour_fit(
    meas: np.ndarray, ref_lin: np.ndarray, usable: np.ndarray, robust: bool = True
) -> tuple[float, np.ndarray]:
    """Return R² of the affine linear-light fit ref ~ [meas, 1] W and the colour outliers.

    Outliers (an occluder, a reflection) are judged against a robust fit, leaving each
    patch out in turn: the patch whose removal best fits the others (mean CIELAB distance)
    is the suspect, and it is an outlier when the colour that fit predicts for it is more
    than ``max(4 × median, 10)`` ΔE*ab from its reference (median of the others'). It is
    dropped and the search repeated, at most six times; a dropped patch that the final fit
    predicts within the bound is taken back. In CIELAB dark patches count as much as light
    ones, and a channel clipped at the edge of the gamut (the ColorChecker's cyan has no
    red in sRGB) moves the colour little: no patch is rejected for its gamut. With
    ``robust``, an R² under ``_ROBUST_BELOW`` is tried again by :func:`_lmeds_fit`.
    """
    x = np.c_[srgb_decode(np, np.clip(meas, 0.0, 1.0)), np.ones(len(meas))]
    lab_ref = _lab_from_linear(ref_lin)
    use = usable.copy()
    out = np.zeros(len(meas), dtype=bool)
    for _ in range(6):
        if use.sum() < 14:
            return -1.0, out
        loo = _held_out(x, ref_lin, lab_ref, use)[use]
        if loo.max() <= _bound(loo):  # no patch stands out: the usual case, one cheap pass
            break
        idx, d = _drop_one_fits(x, ref_lin, lab_ref, use)
        own = d[np.arange(len(idx)), idx]
        others = np.where(use[None], d, np.nan)
        others[np.arange(len(idx)), idx] = np.nan
        i = int(np.argmin(np.nanmean(others, axis=1)))
        if own[i] <= _bound(others[i][np.isfinite(others[i])]):
            break
        out[idx[i]] = True
        use[idx[i]] = False
    if out.any() and use.sum() >= 14:
        w, *_ = np.linalg.lstsq(x[use], ref_lin[use], rcond=None)
        d = _lab_from_linear(x @ w) - lab_ref
        err = np.sqrt((d * d).sum(axis=1))
        back = out & (err <= _bound(err[use]))
        use |= back
        out &= ~back
    r2 = _r2(x, ref_lin, use)
    if robust and r2 < _ROBUST_BELOW:
        # several patches off at once (glare over a corner of the chart) mask one another
        # in the leave-one-out tests: a least-median-of-squares fit does not see them
        r2_lms, out_lms = _lmeds_fit(x, ref_lin, lab_ref, usable)
        if r2_lms > r2:
            return r2_lms, out_lms
    return r2, out


def _r2(x: np.ndarray, ref_lin: np.ndarray, use: np.ndarray) -> float:
    """R² of the least-squares fit ref ~ x W over the patches ``use`` (-1: too few)."""
    if use.sum() < 14:
        return -1.0
    w, *_ = np.linalg.lstsq(x[use], ref_lin[use], rcond=None)
    res = ref_lin[use] - x[use] @ w
    tot = ref_lin[use] - ref_lin[use].mean(axis=0)
    ss_tot = float(np.sum(tot * tot))
    if ss_tot < 1e-9:  # a reference without distinct colours identifies nothing
        return -1.0
    return 1.0 - float(np.sum(res * res)) / ss_tot


#: The least R² of a chart found only on trimmed samples (marks over part of the patches);
#: above ``min_score``, as such samples let more false lattices fit (the best of the
#: negatives of chart-real-2026-11-29h: 0.70 trimmed, 0.66 plain).
_TRIMMED_MIN_SCORE = 0.9
#: Below this R² of the plain fit, :func:`_colour_fit` also tries the least-median fit.
_ROBUST_BELOW = 0.95
#: Random 6-patch subsets the least-median fit tries (a fixed seed: the same answer each run).
_LMEDS_TRIALS = 400


_SUBSETS: dict[int, np.ndarray] = {}


def _lmeds_subsets(m: int) -> np.ndarray:
    """Return the least-median fit's random 6-patch subsets of ``m`` patches (T, 6)."""
    if m not in _SUBSETS:
        gen = np.random.default_rng(0)
        _SUBSETS[m] = np.ascontiguousarray(
            np.argsort(gen.random((_LMEDS_TRIALS, m)), axis=1)[:, :6]
        )
    return _SUBSETS[m]


def _lmeds_fit(
    x: np.ndarray, ref_lin: np.ndarray, lab_ref: np.ndarray, usable: np.ndarray
) -> tuple[float, np.ndarray]:
    """R² and outliers of a least-median-of-squares affine fit (Rousseeuw 1984).

    Affine fits to random 6-patch subsets of the usable patches; the one whose median
    CIELAB ΔE*ab over all usable patches is least is the robust fit. Patches it predicts
    more than ``max(4 × median, 10)`` ΔE*ab from their references are outliers (at most six,
    as in :func:`_colour_fit`: more and the window is not a chart with a few spoiled
    patches); R² is that of the least-squares fit of the others.
    """
    idx = np.flatnonzero(usable)
    none = np.zeros(len(x), dtype=bool)
    if len(idx) < 14:
        return -1.0, none
    from imageform._kernels.chart import lmeds_best_numba

    sub = _lmeds_subsets(len(idx))
    xu = np.ascontiguousarray(x[idx])
    t = lmeds_best_numba(
        xu,
        np.ascontiguousarray(ref_lin[idx]),
        np.ascontiguousarray(lab_ref[idx]),
        sub,
        _xyz_white(),
    )
    xs, rs = xu[sub[t]], ref_lin[idx[sub[t]]]  # the best subset's fit, as the kernel's
    w = np.linalg.solve(xs.T @ xs + 1e-9 * np.eye(4), xs.T @ rs)
    d = _lab_from_linear(xu @ w) - lab_ref[idx]
    best = np.sqrt((d * d).sum(axis=-1))
    bad = best > _bound(best)
    if bad.sum() > 6:
        return -1.0, none
    out = none.copy()
    out[idx[bad]] = True
    return _r2(x, ref_lin, usable & ~out), out


def _shading_fit(
    meas: np.ndarray, ref_lin: np.ndarray, usable: np.ndarray
) -> tuple[float, np.ndarray, np.ndarray]:
    r"""R², outliers and per-patch light of a colour homography fit (unevenly lit charts).

    A shadow across the chart, or light falling off along it, scales each patch's linear
    colour by its own factor: :math:`r_k \approx s_k A m_k` with :math:`A` a 3 × 3 matrix
    and :math:`s_k` the light on patch *k* (the colour homography of Finlayson, Gong and
    Fisher, "Color Homography: Theory and Applications", IEEE TPAMI 41(1), 2019), solved by
    their alternating least squares. The affine fit of :func:`_colour_fit` cannot absorb
    such light; this one can (the colours still have to match, up to brightness). Outliers
    as in :func:`_colour_fit` (at most six, dropped worst first). Returns the adjusted
    :math:`R^2 = 1 - (1 - R^2)(n - 1)/(n - p - 1)` of :math:`s_k A m_k` against the
    references (*n* = 3 values per patch, *p* = 9 + one light per patch: the lights would
    otherwise let an arbitrary lattice of colours score as high as a chart), the outliers, and
    the factors over their median (NaN for patches left out).
    """
    m = srgb_decode(np, np.clip(meas, 0.0, 1.0))
    lab_ref = _lab_from_linear(ref_lin)
    use = usable.copy()
    out = np.zeros(len(meas), dtype=bool)
    gains = np.full(len(meas), np.nan)

    def fit(sel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        s = np.ones(int(sel.sum()))
        ms, rs = m[sel], ref_lin[sel]
        a = np.eye(3)
        for _ in range(30):
            a, *_ = np.linalg.lstsq(ms * s[:, None], rs, rcond=None)
            p = ms @ a
            s = np.clip((rs * p).sum(axis=1) / np.maximum((p * p).sum(axis=1), 1e-12), 0.02, 50.0)
        p_all = m @ a
        r_all = ref_lin
        s_all = np.clip(
            (r_all * p_all).sum(axis=1) / np.maximum((p_all * p_all).sum(axis=1), 1e-12), 0.02, 50.0
        )
        return p_all * s_all[:, None], s_all

    for _ in range(7):
        if use.sum() < 14:
            return -1.0, out, gains
        pred, s_all = fit(use)
        d = _lab_from_linear(pred) - lab_ref
        err = np.sqrt((d * d).sum(axis=1))
        worst = int(np.argmax(np.where(use, err, -1.0)))
        if err[worst] <= _bound(err[use]) or out.sum() >= 6:
            break
        out[worst] = True
        use[worst] = False
    res = ref_lin[use] - pred[use]
    tot = ref_lin[use] - ref_lin[use].mean(axis=0)
    ss_tot = float(np.sum(tot * tot))
    if ss_tot < 1e-9:
        return -1.0, out, gains
    gains[use] = s_all[use] / np.median(s_all[use])
    # adjusted R² (Ezekiel 1930): 3 values per patch, 9 + one light per patch parameters; a
    # free light per patch would otherwise let an arbitrary lattice of colours fit as well
    n_obs, n_par = 3 * int(use.sum()), 9 + int(use.sum())
    r2 = 1.0 - float(np.sum(res * res)) / ss_tot
    return 1.0 - (1.0 - r2) * (n_obs - 1) / (n_obs - n_par - 1), out, gains


def _window_fit(
    mean: np.ndarray, ref_lin: np.ndarray, usable: np.ndarray, shading: bool, robust: bool = True
) -> tuple[float, np.ndarray]:
    """R² and outliers of the affine fit, or of the colour homography with ``shading``."""
    if shading:
        r2, out, _ = _shading_fit(mean, ref_lin, usable)
        return r2, out
    return _colour_fit(mean, ref_lin, usable, robust)


#: The largest ratio of two patches' image areas on one chart: a chart tilted by 60 degrees
#: across a wide field of view; a real one in chart-real-2026-11-29 is at most 3.2, a
#: homography fitted to a stray lattice can be anything.
_MAX_AREA_RATIO = 40.0


#: The least number of segmented patches of a window scored by the colour homography (a
#: light per patch makes the colour test weaker: half the chart's patches must be seen as
#: flat squares on the lattice). A real chart found so in chart-real-2026-11-29 shows 24; a
#: lattice of window frames in a street scene, 6.
_SHADING_MIN_SEGMENTED = 12


def _plausible_view(hc: np.ndarray) -> bool:
    """Whether chart -> work ``hc`` can be a camera's view of a flat chart.

    The whole chart (its outline, half a pitch around the patch centres) must be on one side
    of the image's vanishing line (the homography's third coordinate keeps its sign: a
    plane's points behind the camera have none), and no patch may image over
    ``_MAX_AREA_RATIO`` times larger than another.
    """
    g = np.array(
        [[-0.5, -0.5], [_COLS - 0.5, -0.5], [_COLS - 0.5, _ROWS - 0.5], [-0.5, _ROWS - 0.5]]
    )
    w = np.c_[g, np.ones(4)] @ hc[2]
    if not (np.all(w > 0) or np.all(w < 0)):
        return False
    area = _cell_area(hc, _GRID.astype(np.float64))
    return bool(area.min() > 0 and area.max() <= _MAX_AREA_RATIO * area.min())


def _usable(mean: np.ndarray, spread: np.ndarray) -> np.ndarray:
    """Which sampled cells a colour fit may use: flat (spread under 0.08), not clipped."""
    return np.asarray((spread < 0.08) & (mean.max(axis=1) < 0.98))


def _greys_descend(mean: np.ndarray, ref_lin: np.ndarray, least: float = 0.0) -> bool:
    """Whether the window's neutral row is brighter where the reference's is (rank order).

    A camera maps lightness monotonically, but the affine colour fit (a 3 x 3 matrix and an
    offset) can also fit an inverted one: a chart of another layout whose grey row runs the
    other way (a ColorChecker Passport read as a mirrored Classic: its white patch taken for
    the black, its other rows fitted but one, R² 0.99 on a tuning photograph of
    benchmarks/results/chart-fresh-2026-12-01e.md). The Spearman correlation of the six
    neutral patches' measured brightness with the reference's must be over ``least``: 0
    (one patch out of place, a hand over it or glare on it, keeps it positive), -0.5 for
    the colour homography with its light per patch (a shadow over part of the grey row
    scrambles its order, an inverted row is -1).
    """
    got = mean[_ROWS * _COLS - _COLS :].sum(axis=1)
    want = ref_lin[_ROWS * _COLS - _COLS :].sum(axis=1)
    d = np.argsort(np.argsort(got, kind="stable"), kind="stable") - np.argsort(
        np.argsort(want, kind="stable"), kind="stable"
    )
    # Spearman's rho of two rankings without ties: 1 - 6 sum d^2 / (n (n^2 - 1))
    return bool(1.0 - 6.0 * float(d @ d) / (_COLS * (_COLS * _COLS - 1)) > least)


def _best_window(
    work: np.ndarray,
    h: np.ndarray,
    keys: np.ndarray,
    ref_lin: np.ndarray,
    shading: bool = False,
    trim: bool = False,
    robust: bool = True,
    mirror: bool = False,
) -> tuple[float, np.ndarray, np.ndarray] | None:
    """Best (score, chart->lattice map, outliers) over windows and quarter turns.

    ``robust`` False: the affine fit without the least-median retry (a periodic texture's
    lattice). ``mirror``: the windows of a mirrored chart instead (columns reversed).
    """
    umin, vmin = keys.min(axis=0).astype(int)
    umax, vmax = keys.max(axis=0).astype(int)
    best: tuple[float, np.ndarray, np.ndarray] | None = None
    ku, kv = np.unique(keys.astype(int), axis=0).T
    windows: list[np.ndarray] = []  # the chart -> lattice maps of the windows to score
    for quarter in range(4):
        wu, wv = (_COLS, _ROWS) if quarter % 2 == 0 else (_ROWS, _COLS)
        # every window that overlaps the lattice: one whose patches run past the lattice (a
        # chart cut by the frame) can hold as many found patches as one shifted onto a
        # stray candidate beside the chart; the counts below choose
        placements = [
            (u0, v0)
            for u0 in range(umin - wu + 1, umax + 1)
            for v0 in range(vmin - wv + 1, vmax + 1)
        ]
        if not placements:
            continue
        pu, pv = np.asarray(placements).T[:, :, None]
        counts = ((ku >= pu) & (ku < pu + wu) & (kv >= pv) & (kv < pv + wv)).sum(axis=1).tolist()
        top = max(counts)
        for (u0, v0), cnt in zip(placements, counts, strict=True):
            if cnt < max(top - 2, 6) or (shading and cnt < _SHADING_MIN_SEGMENTED):
                continue
            a = _turn(quarter, u0, v0) @ _MIRROR if mirror else _turn(quarter, u0, v0)
            if _plausible_view(h @ a):
                windows.append(a)
    if not windows:
        return None
    # each window's cells on the lattice (a is an integer map): every cell sampled once
    cells = np.stack([_GRID @ a[:2, :2].T + a[:2, 2] for a in windows])
    uniq, inv = np.unique(np.rint(cells).reshape(-1, 2), axis=0, return_inverse=True)
    cell_mean, cell_spread = _sample_cells(work, h, uniq.astype(np.float64), trim)
    inv = inv.reshape(len(windows), len(_GRID))
    for a, at in zip(windows, inv, strict=True):
        mean, spread = cell_mean[at], cell_spread[at]
        if not _greys_descend(mean, ref_lin, -0.5 if shading else 0.0):
            continue
        usable = _usable(mean, spread)
        r2, out = _window_fit(mean, ref_lin, usable, shading, robust)
        if best is None or r2 > best[0]:
            best = (r2, a, out)
    return best


#: Lattices of a chart's size whose windows :func:`_search` scores, at most (lattices of a
#: periodic texture, over ``_TEXTURE_CELLS`` candidates, not counted), and all lattices
#: grown, at most (so at most four textures' lattices are grown without counting).
_ATTEMPTS, _GROWN = 8, 12
#: A lattice with more candidates on it than this (anywhere within 12 cells of its origin)
#: is a periodic texture, not a chart (24 patches): twice a chart's count.
_TEXTURE_CELLS = 48


def _on_lattice(
    cand: dict[str, np.ndarray], h: np.ndarray, idx: np.ndarray, keys: np.ndarray
) -> np.ndarray:
    """Return every candidate on the grown lattice ``h`` (indices), whatever its extent.

    A degenerate ``h`` (the last refit of a lattice grown from a few collinear candidates)
    collects nothing more than the lattice's own ``idx``.
    """
    area_scale = float(np.median(cand["area"][idx] / np.maximum(_cell_area(h, keys), 1e-9)))
    try:
        every, _, _ = _collect(cand, h, area_scale, 0.28)
    except np.linalg.LinAlgError:
        return idx
    return every


#: A window that is the whole chart by its shape (:func:`_by_shape`) is accepted with a
#: colour fit this much under ``min_score``: a strong cast on a camera's tone curve (one
#: channel near its shoulder) leaves an affine fit R² 0.71-0.80 on a Classic under an
#: orange lamp (the risk_input1 photographs of chart-fresh-2026-12-01e.md), while the
#: best window of the photographs without a Classic in the tuning and held-out sets
#: (another 4 x 6 chart, a SpyderCHECKR 24, included) scores 0.64 at most.
_SHAPE_RELIEF = 0.15
#: ... when at least this many of its 24 cells are segmented flat squares on the lattice ...
_SHAPE_SEGMENTED = 22
#: ... (fewer than this many flat squares centred on cells of its lattice in the two cells
#: around it: a grid of tiles or boxes puts a row of them there, one is a stray) ...
_SHAPE_BESIDE = 2
#: ... and its colours read it better than the same cells read turned half a turn or
#: mirrored, by this much R² (the orientation is in the colours).
_SHAPE_MARGIN = 0.15

#: The chart's symmetries that keep its 4 x 6 outline: a half turn and the two mirrors.
_SYMMETRIES = (
    np.array([[-1.0, 0.0, _COLS - 1], [0.0, -1.0, _ROWS - 1], [0.0, 0.0, 1.0]]),
    np.array([[-1.0, 0.0, _COLS - 1], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
    np.array([[1.0, 0.0, 0.0], [0.0, -1.0, _ROWS - 1], [0.0, 0.0, 1.0]]),
)


def _by_shape(
    work: np.ndarray,
    cand: dict[str, np.ndarray],
    ref_lin: np.ndarray,
    plain: list[
        tuple[tuple[float, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray]
    ],
    least: float,
) -> tuple[float, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
    """Return the best window that is a whole chart by its shape, its fit ``least`` or more.

    Of the lattices' best plain windows (as :func:`_search` found them, best first): at
    least ``_SHAPE_SEGMENTED`` of its cells segmented, fewer than ``_SHAPE_BESIDE``
    candidates centred (within 0.15 pitch) on cells of its lattice in the two cells around
    it (an isolated 4 x 6 block of flat squares: not a tiled wall, not a window of a larger
    grid; candidates farther off or between cells, and a single stray, are clutter), and
    its colour fit at least ``_SHAPE_MARGIN`` over the same cells read in the chart's
    other orientations of that outline (half a turn, either mirror image). None when no
    window is such.
    """
    for win, every in sorted(plain, key=lambda item: -item[0][0]):
        r2, h, a, _, keys, _ = win
        if r2 < least:
            break
        chart = np.round(_apply_h(np.linalg.inv(a), keys))
        inside = np.all((chart >= 0) & (chart <= [_COLS - 1, _ROWS - 1]), axis=1)
        if len({(int(u), int(v)) for u, v in chart[inside]}) < _SHAPE_SEGMENTED:
            continue
        hc = h @ a
        on = _apply_h(np.linalg.inv(hc), cand["c"][every])
        beside = np.all((on > -2.5) & (on < [_COLS + 1.5, _ROWS + 1.5]), axis=1)
        beside &= np.all(np.abs(on - np.round(on)) < 0.15, axis=1)  # on a cell, not clutter
        out = ~np.all((on[beside] > -0.5) & (on[beside] < [_COLS - 0.5, _ROWS - 0.5]), axis=1)
        if int(out.sum()) >= _SHAPE_BESIDE:
            continue  # the lattice goes on beside the window: a grid, not a chart
        others = [-1.0]
        for sym in _SYMMETRIES:
            mean, spread = _sample(work, hc @ sym)
            if _greys_descend(mean, ref_lin):
                usable = _usable(mean, spread)
                others.append(_colour_fit(mean, ref_lin, usable)[0])
        if r2 - max(others) >= _SHAPE_MARGIN:
            return win
    return None


def _search(
    work: np.ndarray,
    ref_lin: np.ndarray,
    min_score: float,
    mirror: bool = False,
    cand: dict[str, np.ndarray] | None = None,
) -> tuple[float, np.ndarray, np.ndarray, np.ndarray, np.ndarray | None] | str:
    """Search the work image for the chart (``mirror``: for a mirrored chart).

    Returns (score, chart -> work homography, outliers, chart coordinates of the segmented
    patches, the light on each patch over its median when the chart was accepted only by the
    colour homography of :func:`_shading_fit`, else None), or why none was found. ``cand``:
    the work image's candidates when they are known (the mirrored search of the same image).
    """
    if cand is None:
        cand = _candidates(work)
    n_cand = len(cand["area"])
    if n_cand < 6:
        return f"{n_cand} flat square region(s) in the image, a ColorChecker shows 24"
    origin, basis, score = _hypotheses(cand)
    order = np.argsort(-score, kind="stable")
    tried: set[int] = set()
    best: tuple[float, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None
    lattices: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    # each lattice's best plain window and every candidate on the lattice (the shape rule)
    plain: list[
        tuple[tuple[float, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray]
    ] = []
    attempts = grown_n = 0
    for hyp in order:
        if score[hyp] < 6 or attempts >= _ATTEMPTS or grown_n >= _GROWN:
            break
        if int(origin[hyp]) in tried:
            continue
        grown = _grow(cand, int(origin[hyp]), basis[hyp])
        grown_n += 1
        tried.add(int(origin[hyp]))
        if grown is None:
            attempts += 1
            continue
        h, idx, keys = grown
        tried.update(int(i) for i in idx)
        # every candidate on the lattice, past the chart-sized window it grew in, is tried
        # with it (no more origins on it); a periodic texture (tiles, a grid of lines, a
        # facade) continues far past a chart's 24 cells and does not use up the attempts
        # left for lattices of a chart's size
        every = _on_lattice(cand, h, idx, keys)
        tried.update(int(i) for i in every)
        texture = len(every) > _TEXTURE_CELLS
        if not texture:
            attempts += 1
            lattices.append(grown)
        win = _best_window(work, h, keys, ref_lin, robust=not texture, mirror=mirror)
        if win is None:
            continue
        r2, a, out = win
        if best is None or r2 > best[0]:
            best = (r2, h, a, idx, keys, out)
        if not texture:
            plain.append(((r2, h, a, idx, keys, out), every))
        if r2 > 0.97:
            break
    if best is None:
        return "no 4x6 lattice of flat patches"
    shading = trim = False
    if best[0] < min_score:
        # a shadow across the chart or light falling off along it: the lattices again, each
        # patch under its own light (the colours have to match up to brightness); and marks
        # over part of every patch (printed labels, drawn numbers, dots): the lattices again
        # on each patch's dominant colour, accepted only at the stricter _TRIMMED_MIN_SCORE
        # (trimmed samples make more false lattices usable). Both are tried and the better
        # wins: a chart whose every patch carries a mark has no plain fit at all, and the
        # colour homography of a lattice of clutter beside it must not win by default. The
        # lattices of periodic textures (over _TEXTURE_CELLS candidates) had the plain
        # least-squares fit only: the costlier fits are for lattices of a chart's size
        shaded = trimmed = None
        for h, idx, keys in lattices:
            win = _best_window(work, h, keys, ref_lin, shading=True, mirror=mirror)
            if win is not None and (shaded is None or win[0] > shaded[0]):
                shaded = (win[0], h, win[1], idx, keys, win[2])
            win = _best_window(work, h, keys, ref_lin, trim=True, mirror=mirror)
            if win is not None and (trimmed is None or win[0] > trimmed[0]):
                trimmed = (win[0], h, win[1], idx, keys, win[2])
        need = max(min_score, _TRIMMED_MIN_SCORE)
        s_shaded = shaded[0] if shaded is not None and shaded[0] >= min_score else -np.inf
        s_trimmed = trimmed[0] if trimmed is not None and trimmed[0] >= need else -np.inf
        if trimmed is not None and s_trimmed > s_shaded:
            best, trim = trimmed, True
        elif shaded is not None and s_shaded > -np.inf:
            best, shading = shaded, True
        else:
            shaped = _by_shape(work, cand, ref_lin, plain, min_score - _SHAPE_RELIEF)
            if shaped is None:
                why = f"best candidate's colour fit R2 = {best[0]:.2f} < min_score = {min_score:g}"
                if trimmed is not None:
                    why += f" (on the patches' dominant colours {trimmed[0]:.2f} < {need:g})"
                return why
            best = shaped
    r2, h, a, idx, keys, out = best
    # chart coordinates of the matched candidates, refit chart -> work directly
    chart_xy = _apply_h(np.linalg.inv(a), keys)
    inside = np.all((chart_xy > -0.5) & (chart_xy < [_COLS - 0.5, _ROWS - 0.5]), axis=1)
    chart_xy, pts = np.round(chart_xy[inside]), cand["c"][idx[inside]]
    hc = _fit_h(chart_xy, pts) if len(pts) >= 4 else h @ a
    if not np.all(np.isfinite(hc)) or not _plausible_view(hc):
        hc = h @ a
    # the score and the outliers again, sampled through the refitted homography
    mean, spread = _sample(work, hc, trim)
    usable = _usable(mean, spread)
    r2_final, out_final = _window_fit(mean, ref_lin, usable, shading)
    if r2_final >= r2 or r2_final >= min_score:
        r2, out = r2_final, out_final
    light = _shading_fit(mean, ref_lin, usable & ~out)[2] if shading else None
    return r2, hc, out, chart_xy, light


# ---------------------------------------------------------------- public API


def detect_colorchecker(
    image: ArrayLike,
    *,
    reference: ArrayLike | None = None,
    max_size: int = 1024,
    min_score: float = 0.8,
    sample: float = 0.5,
    mirrored: bool | None = None,
) -> ChartDetection:
    """Find a ColorChecker Classic (4 × 6) anywhere in a photograph.

    Any position, scale (down to about 10 pixels per patch at the working resolution, i.e.
    about 5 f pixels in a photograph block-averaged by f to ``max_size``), in-plane
    rotation (upside down included: the patch colours fix it), perspective tilt to about
    45 degrees, clutter, blur, noise, uneven light and another illuminant. The method is in
    the module docstring (:mod:`imageform.analysis.chart_detect`).

    Parameters
    ----------
    image : array_like, shape (H, W, 3)
        Encoded sRGB (uint8, uint16 or floats in [0, 1]); a Dask array is computed.
    reference : array_like, shape (24, 3), optional, keyword-only
        Encoded sRGB of the chart's patches, row by row, to recognise it by; default the
        ColorChecker (:data:`~imageform.analysis.synthetic.COLORCHECKER_SRGB8` / 255).
    max_size : int, keyword-only
        The long side of the working image (block-averaged by an integer factor): the
        speed / smallest-chart trade-off (a photograph without a chart is searched again at
        twice this size).
    min_score : float, keyword-only
        The least :math:`R^2` of the affine colour fit that accepts a chart (0 to 1); a
        window that is a whole chart by its shape (22 or more of its cells segmented, at
        most one flat square on its lattice around it, its colours reading it 0.15 better than
        half a turn or mirrored) is accepted down to ``min_score - 0.15``, with a
        :class:`~imageform.analysis.ChartWarning`.
    sample : float, keyword-only
        Side of the sampling square in patch pitches (the patches are about 0.85 pitch
        wide): the quads :func:`measure_chart_patches` averages.
    mirrored : bool or None, keyword-only
        Whether the chart may be seen mirrored (its columns reversed: a webcam's mirrored
        preview, a photograph flipped left to right, a mirror). None (default): the chart
        as printed is searched first and, only when none is found, a mirrored one (on the
        same segmentation); False: as printed only (imageform 0.1's search); True: mirrored
        only. The detection says which it found (``ChartDetection.mirrored``); its patch
        ``k`` is the chart's patch ``k`` either way.

    Returns
    -------
    ChartDetection
        The chart's homography, corners, patch centres and quads, score and rotation with
        ``found`` True; or, when the image holds no 4 × 6 lattice of flat patches whose
        colours match the reference (or is under 16 pixels on a side), ``found`` False, the
        ``reason`` in one line and NaN positions. A photograph without a chart is not an
        error; :func:`measure_chart_patches` of a detection that found nothing raises
        :class:`ChartNotFoundError`.

    Raises
    ------
    InvalidInputError
        ``image`` is not an RGB image, or ``reference``, ``max_size``, ``min_score`` or
        ``sample`` is out of range.

    Warns
    -----
    ChartWarning
        The chart was found only with a light per patch (a shadow across it, or light
        falling off along it): a colour correction fitted to it is biased by the light.
        Or it was found by its shape with a colour fit under ``min_score``.

    Examples
    --------
    >>> from imageform.analysis import synthetic_chart_photo
    >>> photo = synthetic_chart_photo(rng=3)
    >>> det = detect_colorchecker(photo.image)
    >>> err = np.linalg.norm(det.centers - photo.centers, axis=1).max()
    >>> det.found, bool(err < 1.0), bool(det.segmented.all())
    (True, True, True)
    >>> empty = detect_colorchecker(np.full((120, 160, 3), 0.5))
    >>> empty.found, empty.reason
    (False, '0 flat square region(s) in the image, a ColorChecker shows 24')
    """
    from imageform.analysis.synthetic import COLORCHECKER_SRGB8

    rgb, full = _rgb_in(image)
    max_size = as_int(max_size, "max_size", minimum=64, maximum=100_000)
    min_score = as_real(min_score, "min_score", minimum=-1.0, maximum=1.0)
    sample = as_real(sample, "sample", positive=True, maximum=1.0)
    if mirrored is not None:
        mirrored = as_bool(mirrored, "mirrored")
    ref = (
        np.asarray(COLORCHECKER_SRGB8, dtype=np.float64) / 255.0
        if reference is None
        else real_array(reference, "reference", (24, 3))
    )
    if np.any(ref < 0) or np.any(ref > 1):
        raise InvalidInputError(f"expected reference in [0, 1], got {describe(ref)}")
    ref_lin = srgb_decode(np, ref)
    if min(rgb.shape[:2]) < 16:
        return _not_found(
            f"image of {rgb.shape[0]}x{rgb.shape[1]} pixels is too small to hold a colour chart"
        )
    # upright first; a mirrored chart only where no upright one is found (on the same
    # candidates: segmentation and lattices do not depend on the chart's handedness)
    mirrors = {None: (False, True), False: (False,), True: (True,)}[mirrored]
    stages: dict[str, tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]] = {}
    reasons: list[str] = []
    for mirror in mirrors:
        res, scale = _find(rgb, full, ref_lin, max_size, min_score, mirror, stages)
        if isinstance(res, tuple):
            break
        reasons.append(res if not reasons else f"mirrored: {res.split(' (')[0]}")
        if res.startswith(_NO_LATTICE_REASONS):
            break  # no lattice for a chart of either handedness
    else:
        return _not_found(reasons[0] + "".join(f" ({r})" for r in reasons[1:]))
    if not isinstance(res, tuple):
        return _not_found(reasons[0])
    r2, hc, out, chart_xy, light = res
    if light is not None:
        import warnings

        lo, hi = np.nanmin(light), np.nanmax(light)
        warnings.warn(
            "detect_colorchecker: the light on the chart is uneven (a shadow or a light "
            f"fall-off: patches at x{lo:.2f} to x{hi:.2f} of the median brightness); found by "
            f"colour up to brightness (R2 = {r2:.2f}), a colour correction fitted to it is "
            "biased by the light",
            ChartWarning,
            stacklevel=2,
        )
    if light is None and r2 < min_score:
        import warnings

        warnings.warn(
            f"detect_colorchecker: found by its shape (a whole, isolated 4 x 6 lattice) with a "
            f"colour fit R2 = {r2:.3f} under min_score = {min_score:g}: a strong cast on the "
            "camera's tone curve, or a chart printed off its reference; check the patch "
            "colours before fitting a correction to them",
            ChartWarning,
            stacklevel=2,
        )
    segmented = np.zeros(_ROWS * _COLS, dtype=bool)
    segmented[(chart_xy[:, 1] * _COLS + chart_xy[:, 0]).astype(int)] = True
    hf = scale @ hc
    hf = hf / hf[2, 2]
    unit = np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]])
    corners = _apply_h(hf, unit * [_COLS, _ROWS] + [(_COLS - 1) / 2, (_ROWS - 1) / 2])
    centres = _apply_h(hf, _GRID.astype(np.float64))
    quads = _apply_h(hf, (_GRID[:, None, :] + sample * unit[None]).reshape(-1, 2)).reshape(-1, 4, 2)
    row_dir = _apply_h(hf, np.array([[_COLS - 1, 1.5]])) - _apply_h(hf, np.array([[0.0, 1.5]]))
    rot = float(np.degrees(np.arctan2(row_dir[0, 1], row_dir[0, 0])))
    if rot <= -180.0:
        rot += 360.0
    return ChartDetection(
        hf, corners, centres, quads, segmented, out, float(r2), rot, mirrored=bool(mirror)
    )


#: Reasons of a search that found no lattice at all: the mirrored search, on the same
#: candidates, would find none either.
_NO_LATTICE_REASONS = ("no 4x6 lattice", "0 flat", "1 flat", "2 flat", "3 flat", "4 flat", "5 flat")


def _find(
    rgb: np.ndarray,
    full: float,
    ref_lin: np.ndarray,
    max_size: int,
    min_score: float,
    mirror: bool,
    stages: dict[str, tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]],
) -> tuple[tuple[float, np.ndarray, np.ndarray, np.ndarray, np.ndarray | None] | str, np.ndarray]:
    """Search at the resolutions of :func:`detect_colorchecker`: (result, work -> image).

    ``stages`` keeps each resolution's work image, its map to the image and its candidates
    for the next call (the mirrored search of the same photograph).
    """

    def stage(name: str) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        if name not in stages:
            if name == "up":
                # small charts (patch pitch under about 12 pixels) separate better on a 2x
                # bilinear upsample (o -> o / 2 - 0.25 in image pixels)
                from imageform._kernels.chart import upsample2_numba

                work = upsample2_numba(np.ascontiguousarray(stage("work")[0]))
                scale = np.array([[0.5, 0.0, -0.25], [0.0, 0.5, -0.25], [0.0, 0.0, 1.0]])
            else:
                work, f = _work_image(rgb, max_size if name == "work" else 2 * max_size, full)
                # work pixel -> image pixel (pixel centres): block means of f x f pixels
                scale = np.array(
                    [[f, 0.0, (f - 1) / 2.0], [0.0, f, (f - 1) / 2.0], [0.0, 0.0, 1.0]]
                )
            stages[name] = (work, scale, _candidates(work))
        return stages[name]

    work, scale, cand = stage("work")
    res = _search(work, ref_lin, min_score, mirror, cand)
    if isinstance(res, tuple):
        return res, scale
    # not found on the block means: a chart of under about 10 * f pixels per patch in a
    # large photograph merged into its surround, once more at twice the resolution; not
    # found at full resolution, once more on the 2x upsample
    fine, fscale, fcand = stage("fine" if scale[0, 0] > 1 else "up")
    res_fine = _search(fine, ref_lin, min_score, mirror, fcand)
    if isinstance(res_fine, tuple):
        return res_fine, fscale
    return res, scale


def _quad_mask_bounds(quad: np.ndarray, hgt: int, wid: int) -> tuple[slice, slice, np.ndarray]:
    """Pixels (centres) inside a convex quadrilateral: the bounding slices and the mask."""
    u0 = max(int(np.ceil(quad[:, 0].min())), 0)
    u1 = min(int(np.floor(quad[:, 0].max())), wid - 1)
    v0 = max(int(np.ceil(quad[:, 1].min())), 0)
    v1 = min(int(np.floor(quad[:, 1].max())), hgt - 1)
    if u1 < u0 or v1 < v0:
        return slice(0, 0), slice(0, 0), np.zeros((0, 0), dtype=bool)
    vv, uu = np.mgrid[v0 : v1 + 1, u0 : u1 + 1]
    inside = np.ones(uu.shape, dtype=bool)
    area2 = 0.0
    for k in range(4):
        a, b = quad[k], quad[(k + 1) % 4]
        area2 += a[0] * b[1] - a[1] * b[0]
    sign = 1.0 if area2 >= 0 else -1.0
    for k in range(4):
        a, b = quad[k], quad[(k + 1) % 4]
        cross = (b[0] - a[0]) * (vv - a[1]) - (b[1] - a[1]) * (uu - a[0])
        inside &= sign * cross >= 0
    return slice(v0, v1 + 1), slice(u0, u1 + 1), inside


#: A patch whose left-out pixels hold a flat colour of more than this fraction of its kept
#: pixels' count is missing: a mark over about half the sampled square could be the patch.
_AMBIGUOUS = 0.8


def measure_chart_patches(
    image: ArrayLike,
    chart: ChartDetection,
    *,
    max_std: float = 0.04,
    saturation: float = 1.0,
    max_saturated_fraction: float = 0.01,
    min_clean: float = 0.6,
) -> ChartPatches:
    """Mean encoded sRGB of each patch of a chart found by :func:`detect_colorchecker`.

    The pixels whose centres lie in each of ``chart.quads`` (the inner part of the patch) are
    averaged in the full-resolution image, **leaving out the pixels of marks** over part of
    a patch (a printed number or label, a pen stroke, a sticker, a reflection, a finger or a
    cable): the patch's dominant colour is the per-channel median of its pixels, pixels more
    than 4 robust sigmas (1.4826 x the median absolute deviation, at least 0.02) from it in
    some channel are left out, and the median and spread are taken again over the rest. The
    share of the pixels kept is ``used`` in the result. A patch is **missing** when fewer
    than ``min_clean`` of its pixels are kept (too little of it is left clean, or it is not
    one flat colour: the sample runs over an edge), when the kept pixels are not flat (any
    channel's standard deviation above ``max_std``), when it holds no pixel (outside the
    image), or when the detection flagged it as a colour outlier (``chart.outliers``);
    **saturated** when more than ``max_saturated_fraction`` of its kept pixels reach
    ``saturation`` in some channel. Both raise a :class:`ChartWarning`;
    :func:`~imageform.analysis.fit_color_correction` leaves them out. A patch is missing,
    too, when the pixels left out hold a flat colour of their own of more than 0.8 times
    the kept pixels' count (a mark over about half the square: which colour is the patch's
    is unknown). A flat mark over clearly more than half of the sampled square is taken for
    the patch (the median is then the mark's colour) unless the detection flags the patch
    as an outlier.

    Parameters
    ----------
    image : array_like, shape (H, W, 3)
        The photograph the chart was detected in (encoded sRGB).
    chart : ChartDetection
        The chart found in ``image`` by :func:`detect_colorchecker`.
    max_std : float, keyword-only
        Largest per-channel standard deviation (encoded, [0, 1] scale) of a flat patch.
    saturation : float, keyword-only
        The clipping level (encoded, [0, 1] scale).
    max_saturated_fraction : float, keyword-only
        Fraction of a patch's pixels at ``saturation`` above which it is saturated.
    min_clean : float, keyword-only
        Least share of a patch's sampled pixels, in (0, 1], that must agree with its dominant
        colour (1: any mark makes the patch missing).

    Returns
    -------
    ChartPatches
        Row by row in the reference chart's order (upright), whatever the photo's rotation;
        ``used`` is the share of each patch's pixels averaged (0 where none was sampled).

    Raises
    ------
    ChartNotFoundError
        ``chart.found`` is False: the detection found no chart to measure.
    InvalidInputError
        No patch of the chart is usable, or an argument is out of range.

    Examples
    --------
    >>> from imageform.analysis import synthetic_chart_photo
    >>> photo = synthetic_chart_photo(rng=3, cast=(1.0, 1.0, 1.0), noise=0.0)
    >>> p = measure_chart_patches(photo.image, detect_colorchecker(photo.image))
    >>> bool(p.valid.all()), bool(np.abs(p.means - photo.patches).max() < 0.01)
    (True, True)
    """
    if not isinstance(chart, ChartDetection):
        raise TypeError(f"expected chart as a ChartDetection, got {describe(chart)}")
    if not chart.found:
        raise ChartNotFoundError(f"no ColorChecker found in the image: {chart.reason}")
    rgb, full = _rgb_in(image)
    max_std = as_real(max_std, "max_std", nonnegative=True)
    saturation = as_real(saturation, "saturation", positive=True)
    max_saturated_fraction = as_real(
        max_saturated_fraction, "max_saturated_fraction", minimum=0.0, maximum=1.0
    )
    min_clean = as_real(min_clean, "min_clean", minimum=0.0, maximum=1.0)
    if min_clean <= 0.0:
        raise InvalidInputError(f"expected min_clean in (0, 1], got {min_clean!r}")
    hgt, wid = rgb.shape[:2]
    n = len(chart.quads)
    means = np.full((n, 3), np.nan)
    stds = np.full((n, 3), np.nan)
    sat = np.zeros(n)
    used = np.full(n, np.nan)
    ambiguous = np.zeros(n, dtype=bool)
    for k in range(n):
        sv, su, mask = _quad_mask_bounds(chart.quads[k], hgt, wid)
        if not mask.any():
            continue
        px = rgb[sv, su][mask].astype(np.float64) / full
        keep = _clean_pixels(px)
        used[k] = keep.mean()
        rest = px[~keep]
        if len(rest) and _clean_pixels(rest).sum() > _AMBIGUOUS * keep.sum():
            # the pixels left out hold a second flat colour nearly as large as the kept one
            # (a mark over about half the square): which of the two is the patch is unknown
            ambiguous[k] = True
        px = px[keep] if keep.any() else px
        means[k] = px.mean(axis=0)
        stds[k] = px.std(axis=0)
        sat[k] = (px >= saturation).any(axis=1).mean()
    empty = ~np.isfinite(means).all(axis=1)
    saturated = (sat > max_saturated_fraction) & ~empty
    missing = (
        empty
        | np.asarray(chart.outliers)
        | (np.nan_to_num(stds, nan=0.0) > max_std).any(axis=1)
        | (np.nan_to_num(used, nan=0.0) < min_clean)
        | ambiguous
    )
    if not (~saturated & ~missing).any():
        raise InvalidInputError(
            f"no usable chart patch (max_std={max_std:g}, saturation={saturation:g}, "
            f"min_clean={min_clean:g}): saturated {np.flatnonzero(saturated).tolist()}, "
            f"missing {np.flatnonzero(missing).tolist()}"
        )
    for what, idx in (
        ("saturated", np.flatnonzero(saturated)),
        ("missing", np.flatnonzero(missing)),
    ):
        if idx.size:
            import warnings

            warnings.warn(
                f"measure_chart_patches: {idx.size} {what} patch(es) {idx.tolist()} (0-based, "
                "row by row) will be left out of a fit",
                ChartWarning,
                stacklevel=2,
            )
    return ChartPatches(
        means, np.nan_to_num(stds, nan=0.0), saturated, missing, np.nan_to_num(used, nan=0.0)
    )


# ---------------------------------------------------------------- synthetic chart photographs


@_deprecate.renamed_fields({"centres": "centers"})
class ChartPhoto(NamedTuple):
    """A synthetic photograph of a ColorChecker and its truth (:func:`synthetic_chart_photo`)."""

    #: Encoded sRGB in [0, 1], shape (H, W, 3), float64.
    image: np.ndarray
    #: (3, 3) homography from chart ``(column, row)`` to image ``(u, v)`` (as
    #: :attr:`ChartDetection.homography`).
    homography: np.ndarray
    #: (24, 2) true patch centres in the image, row by row.
    centers: np.ndarray
    #: (24, 3) encoded sRGB of each patch at its centre, as lit (cast and shading), before
    #: blur and noise.
    patches: np.ndarray


#: Patch side and card margins of the rendered chart, in patch pitches (close to the
#: ColorChecker Classic's proportions).
_PATCH, _MARGIN_U, _MARGIN_V = 0.85, 0.3, 0.45


def _chart_homography(
    rng: np.random.Generator, hgt: int, wid: int, width: float, tilt: float, rotation: float
) -> np.ndarray:
    """Return a random chart (column, row) -> image homography.

    The chart plane is tilted by ``tilt`` degrees about a random in-plane axis, rotated by
    ``rotation``, seen by a pinhole (focal = image width), scaled so that its lattice is ``width``
    of the image width, placed at random inside.
    """
    t, phi, r = np.radians(tilt), rng.uniform(0, np.pi), np.radians(rotation)
    axis = np.array([np.cos(phi), np.sin(phi), 0.0])
    kx = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    r_tilt = np.eye(3) + np.sin(t) * kx + (1 - np.cos(t)) * kx @ kx
    rz = np.array([[np.cos(r), -np.sin(r), 0], [np.sin(r), np.cos(r), 0], [0, 0, 1.0]])
    rot = rz @ r_tilt
    focal = float(wid)
    # chart units: pitch 1, centred; distance so that the lattice spans `width` of the frame
    dist = focal * (_COLS + 2 * _MARGIN_U) / (width * wid)
    centre = np.array([(_COLS - 1) / 2, (_ROWS - 1) / 2])
    m = np.c_[rot[:, 0], rot[:, 1], [0.0, 0.0, dist] - rot[:, :2] @ centre]
    k = np.array([[focal, 0, 0], [0, focal, 0], [0, 0, 1.0]])
    h = k @ m
    card = np.array(
        [
            [-0.5 - _MARGIN_U, -0.5 - _MARGIN_V],
            [_COLS - 0.5 + _MARGIN_U, -0.5 - _MARGIN_V],
            [_COLS - 0.5 + _MARGIN_U, _ROWS - 0.5 + _MARGIN_V],
            [-0.5 - _MARGIN_U, _ROWS - 0.5 + _MARGIN_V],
        ]
    )
    pts = _apply_h(h, card)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    span = hi - lo
    room = np.array([wid - 1.0, hgt - 1.0]) - span
    shift = np.where(room > 0, rng.uniform(0, 1, 2) * np.maximum(room, 0), room / 2) - lo
    h = np.array([[1, 0, shift[0]], [0, 1, shift[1]], [0, 0, 1.0]]) @ h
    return h / h[2, 2]


def synthetic_chart_photo(
    background: ArrayLike | None = None,
    *,
    shape: tuple[int, int] = (512, 768),
    width: float | None = None,
    tilt: float | None = None,
    rotation: float | None = None,
    cast: ArrayLike | None = None,
    shading: float = 0.3,
    blur: float = 0.7,
    noise: float = 0.01,
    rng: RNGLike = 0,
) -> ChartPhoto:
    """Render a ColorChecker photographed in a scene: the test input of :func:`detect_colorchecker`.

    The 24 patches (:data:`~imageform.analysis.synthetic.COLORCHECKER_SRGB8`) on a dark card
    are rendered through a random perspective homography (3 × 3 supersampling) over
    ``background``, in linear light; the whole frame is then multiplied by the illuminant
    ``cast`` (per channel) and a smooth ``shading`` field (vignetting and a light ramp),
    blurred by a Gaussian of ``blur`` pixels, encoded to sRGB, and Gaussian ``noise`` is added.

    Parameters
    ----------
    background : array_like, shape (H, W, 3), optional
        Encoded sRGB scene (e.g. a real photograph); default random clutter of ``shape``.
    shape : (int, int), keyword-only
        (H, W) when no background is given.
    width : float, keyword-only
        The chart's width over the image width (default uniform in [0.15, 0.6]).
    tilt : float, keyword-only
        Out-of-plane tilt of the chart in degrees (default uniform in [0, 40]).
    rotation : float, keyword-only
        In-plane rotation in degrees (default uniform in [-180, 180)).
    cast : array_like, shape (3,), keyword-only
        Linear-light gains of the illuminant (default random, each in [0.6, 1.1]).
    shading : float, keyword-only
        Depth of the vignetting and light ramp (0: uniform light).
    blur, noise : float, keyword-only
        Gaussian blur sigma in pixels, and noise sigma in encoded units.
    rng : int or numpy.random.Generator, keyword-only
        The random source of the placement, the cast, the shading and the noise.

    Returns
    -------
    ChartPhoto

    Examples
    --------
    >>> p = synthetic_chart_photo(rng=1)
    >>> p.image.shape, p.centers.shape
    ((512, 768, 3), (24, 2))
    """
    from scipy import ndimage

    from imageform._random import as_rng
    from imageform._validate import as_float, as_size
    from imageform.analysis.synthetic import COLORCHECKER_SRGB8, _smooth_noise

    gen = as_rng(rng)
    if background is None:
        hgt, wid = as_size(shape, "shape")
        check_memory(hgt * wid * 3 * 8 * 8.0, "shape", "the chart photograph")
        if hgt < 32 or wid < 32:
            raise InvalidInputError(f"expected shape of at least 32x32, got {hgt}x{wid}")
        base = 0.2 + 0.5 * gen.uniform(size=3) * (
            0.5 + 0.5 * _smooth_noise(gen, (hgt, wid), 30)[..., None]
        )
        for _ in range(40):
            ry, rx = int(gen.integers(0, hgt)), int(gen.integers(0, wid))
            dy, dx = gen.integers(4, max(5, hgt // 6)), gen.integers(4, max(5, wid // 6))
            base[ry : ry + dy, rx : rx + dx] = gen.uniform(0.05, 0.95, 3)
        bg = np.clip(base, 0.0, 1.0)
    else:
        bg = np.asarray(image_in(background, "background"), dtype=np.float64)
        if bg.ndim != 3 or min(bg.shape[:2]) < 32:
            raise InvalidInputError(
                f"expected background of shape (H, W, 3), at least 32x32, got {describe(bg)}"
            )
        hgt, wid = bg.shape[:2]
        check_memory(hgt * wid * 3 * 8 * 8.0, "background", "the chart photograph")
    width = (
        gen.uniform(0.15, 0.6)
        if width is None
        else as_real(width, "width", minimum=0.02, maximum=1.0)
    )
    tilt = (
        gen.uniform(0.0, 40.0) if tilt is None else as_real(tilt, "tilt", minimum=0.0, maximum=80.0)
    )
    rotation = gen.uniform(-180.0, 180.0) if rotation is None else as_real(rotation, "rotation")
    gains = (
        gen.uniform(0.6, 1.1, 3)
        if cast is None
        else np.asarray(as_float(cast, "cast"), dtype=np.float64).reshape(-1)
    )
    if gains.shape != (3,) or np.any(gains <= 0):
        raise InvalidInputError(f"expected cast as 3 positive gains, got {describe(cast)}")
    shading = as_real(shading, "shading", minimum=0.0, maximum=0.9)
    blur = as_real(blur, "blur", nonnegative=True, maximum=100.0)
    noise = as_real(noise, "noise", nonnegative=True)
    h = _chart_homography(gen, hgt, wid, width, tilt, rotation)
    lin = srgb_decode(np, bg.copy())
    # render the card: pixels of its bounding box, 3x3 supersampled, mapped back to the chart
    card = np.array(
        [[-0.5 - _MARGIN_U, -0.5 - _MARGIN_V], [_COLS - 0.5 + _MARGIN_U, _ROWS - 0.5 + _MARGIN_V]]
    )
    corners = _apply_h(
        h, np.array([card[0], [card[1, 0], card[0, 1]], card[1], [card[0, 0], card[1, 1]]])
    )
    u0, v0 = np.maximum(np.floor(corners.min(axis=0)).astype(int), 0)
    u1, v1 = np.minimum(np.ceil(corners.max(axis=0)).astype(int), [wid - 1, hgt - 1])
    ref_lin = srgb_decode(np, np.asarray(COLORCHECKER_SRGB8, dtype=np.float64) / 255.0)
    card_lin = float(srgb_decode(np, np.array(gen.uniform(0.05, 0.12))))
    if u1 >= u0 and v1 >= v0:
        sub = (np.arange(3) - 1) / 3.0
        grid = np.mgrid[v0 : v1 + 1, u0 : u1 + 1].astype(np.float64)
        vv, uu = grid[0], grid[1]
        acc = np.zeros(uu.shape + (3,))
        cover = np.zeros(uu.shape)
        hinv = np.linalg.inv(h)
        for dv in sub:
            for du in sub:
                xy = _apply_h(hinv, np.stack([uu + du, vv + dv], axis=-1))
                x, y = xy[..., 0], xy[..., 1]
                on_card = (
                    (x >= card[0, 0]) & (x <= card[1, 0]) & (y >= card[0, 1]) & (y <= card[1, 1])
                )
                col, row = np.round(x), np.round(y)
                in_patch = (
                    on_card
                    & (np.abs(x - col) <= _PATCH / 2)
                    & (np.abs(y - row) <= _PATCH / 2)
                    & (col >= 0)
                    & (col < _COLS)
                    & (row >= 0)
                    & (row < _ROWS)
                )
                idx = (np.clip(row, 0, _ROWS - 1) * _COLS + np.clip(col, 0, _COLS - 1)).astype(int)
                val = np.where(in_patch[..., None], ref_lin[idx], card_lin)
                acc += np.where(on_card[..., None], val, 0.0)
                cover += on_card
        cover /= 9.0
        box = lin[v0 : v1 + 1, u0 : u1 + 1]
        lin[v0 : v1 + 1, u0 : u1 + 1] = box * (1 - cover[..., None]) + acc / 9.0
    # light: illuminant gains, vignetting and a ramp in a random direction
    yy, xx = np.mgrid[0:hgt, 0:wid].astype(np.float64)
    rr = ((xx - wid / 2) ** 2 + (yy - hgt / 2) ** 2) / ((wid / 2) ** 2 + (hgt / 2) ** 2)
    ang = gen.uniform(0, 2 * np.pi)
    ramp = (xx / wid - 0.5) * np.cos(ang) + (yy / hgt - 0.5) * np.sin(ang)
    light = (1.0 - shading * 0.6 * rr) * (1.0 + shading * ramp)
    lin = lin * light[..., None] * gains
    if blur > 0:
        lin = ndimage.gaussian_filter(lin, sigma=(blur, blur, 0.0), mode="nearest")
    img = srgb_encode(np, np.clip(lin, 0.0, 1.0))
    if noise > 0:
        img = img + gen.normal(0.0, noise, img.shape)
    centres = _apply_h(h, _GRID.astype(np.float64))
    ci = np.clip(np.round(centres).astype(int), 0, [wid - 1, hgt - 1])
    patches = srgb_encode(np, np.clip(ref_lin * gains * light[ci[:, 1], ci[:, 0], None], 0.0, 1.0))
    return ChartPhoto(np.clip(img, 0.0, 1.0), h, centres, patches)
