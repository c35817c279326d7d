r"""Dense depth from a rectified stereo pair: semi-global matching, disparity to depth.

:func:`stereo_disparity` matches a rectified pair (:func:`~imageform.geometry.stereo_rectify`,
:func:`~imageform.geometry.rectification_map`) by semi-global matching (Hirschmüller 2008)
on census costs; :func:`disparity_to_depth` and :func:`disparity_to_points` turn its
disparities into depth and 3-D points with the rectification's ``Q`` matrix
(``cv2.reprojectImageTo3D``'s definition).

References
----------
H. Hirschmüller, "Stereo processing by semiglobal matching and mutual information", IEEE
Trans. PAMI 30(2), 328-341, 2008.
H. Hirschmüller, D. Scharstein, "Evaluation of stereo matching costs on images with
radiometric differences", IEEE Trans. PAMI 31(9), 1582-1599, 2009.
R. Zabih, J. Woodfill, "Non-parametric local transforms for computing visual
correspondence", ECCV 1994.
"""

from __future__ import annotations

import math
from typing import Any, Literal

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from imageform._backend import to_numpy, use_numba
from imageform._colormath import luma_601
from imageform._validate import (
    as_int,
    as_real,
    as_real_array,
    check_memory,
    check_option,
    describe,
)
from imageform.errors import InvalidInputError
from imageform.geometry.stereo import StereoRectification

__all__ = ["disparity_to_depth", "disparity_to_points", "stereo_disparity"]

#: the largest P2 whose 8 path costs still sum within 16 bits (each at most 48 + P2)
MAX_P2 = 8000
#: block sizes of the census window (its code holds block_size² - 1 <= 48 bits)
BLOCK_SIZES = (3, 5, 7)
#: the default ``census_step`` of :func:`stereo_disparity` (grey levels, 0-255): chosen on the
#: tuning pairs of ``benchmarks/check_stereo_noise.py`` (its table: steps 2, 4 and 8)
CENSUS_STEP = 4.0
#: sides of the block over which :func:`stereo_disparity` sums the census costs
COST_WINDOWS = (1, 3, 5, 7)
#: the default ``cost_window`` of :func:`stereo_disparity`: chosen on the board pairs and the
#: Middlebury pairs of ``benchmarks/check_stereo_webcam.py`` (its table: windows 1, 3, 5)
COST_WINDOW = 3
#: the largest block sum after its division (``uint8`` costs; 8 paths of ``cost + P2`` within
#: 16 bits for every ``P2 <= MAX_P2``)
MAX_COST = 191
#: the sub-pixel fits of :func:`stereo_disparity`
SUBPIXEL_FITS = ("equiangular", "parabola")
#: ``plane_fill``: a flat region's pixels have a 5 x 5 standard deviation under this (grey levels)
PLANE_FLAT_SD = 3.0
#: ``plane_fill``: the rim, the textured pixels within this many pixels of a flat region
PLANE_RIM = 3
#: ``plane_fill``: the least area of a flat region (pixels) and the largest (share of the image)
PLANE_AREA = (30, 0.02)
#: ``plane_fill``: a rim's disparity within this many pixels of the plane is an inlier; the
#: plane is taken where at least this share of the rim's valid pixels are inliers (and at
#: least half of the rim's pixels are valid)
PLANE_INLIER = (1.0, 0.8)
#: ``plane_fill``: passes of the plane's refit on the rim's and the region's own disparities
#: within ``PLANE_INLIER[0]`` px of it (0: the rim's plane as it is)
PLANE_REFIT = 2
#: ``plane_fill``: a region keeps its matched disparities where the plane's mean absolute
#: difference of the left image and the right one warped by it (its mean taken out) exceeds
#: the matched disparities' by more than this factor (chosen on the tuning sets of
#: ``benchmarks/check_stereo_planes.py``: 1.25, 1.3, 1.4, 1.6 tried)
PLANE_PHOTO = 1.4
#: ``plane_fill``: a region keeps its matched disparities where more than this share of its
#: pixels would, on the plane, hide a textured pixel matched to the same right pixel (a plane
#: nearer than what the right view sees there)
PLANE_HIDE = 0.2
#: ``plane_fill``: a region keeps its matched disparities where its rim fits the plane worse
#: than this many times the median rim of the image (mean absolute residual, each capped at
#: 3 px: a rim that spans an occluding edge) and the share of its own valid disparities more
#: than ``PLANE_RECESS[2]`` px behind the plane exceeds the share as far in front of it by more
#: than ``PLANE_RECESS[1]`` (a recess seen past nearer surfaces; chosen on the tuning sets of
#: ``benchmarks/check_stereo_recess.py``: 2 to 4 and 0.1 to 0.25 tried)
PLANE_RECESS = (3.0, 0.15, 0.25)
#: ``slant_prior``: the side of the square in which each pixel's plane is fitted (pixels),
#: the largest root mean square residual of a fit taken (px), the largest slant taken and
#: the least (px of disparity a pixel; the larger of the two axes'); chosen on the tuning
#: sets of ``benchmarks/check_stereo_sgmp.py`` (fits 0.25, 0.35 and 0.5 px, least slants 0,
#: 0.05, 0.1 and 0.15 tried: under 0.15 the da Vinci boards lose, 1.07 % more than 1 px off
#: at 0.1 against 0.99 % without the prior; their fits of 0.1 to 0.2 are the first map's
#: staircase on a board of slant 0.004)
SLANT_WINDOW = 9
SLANT_FIT = 0.25
SLANT_MAX = 1.0
SLANT_MIN = 0.15


def _grey(image: Any, name: str) -> NDArray[np.float32]:
    """``image`` (H, W) or (H, W, C) as a float32 grey image on a 0-255 scale."""
    dtype = getattr(image, "dtype", None)
    a = as_real_array(image, name, ndim=(2, 3))
    if a.ndim == 3:
        if a.shape[2] == 1:
            a = a[..., 0]
        elif a.shape[2] in (3, 4):
            a = luma_601(np, a)  # Rec. 601 luma, channel by channel
        else:
            raise InvalidInputError(
                f"expected {name} as a grey (H, W) or colour (H, W, 3) image, got shape {a.shape}"
            )
    kind = np.dtype(dtype).kind if dtype is not None else "f"
    if dtype is not None and np.dtype(dtype) == np.uint16:
        a = a * (255.0 / 65535.0)
    elif kind == "f":
        a = a * 255.0
    return np.ascontiguousarray(a, dtype=np.float32)


def stereo_disparity(
    left: npt.ArrayLike,
    right: npt.ArrayLike,
    *,
    min_disparity: int = 0,
    num_disparities: int = 64,
    block_size: int = 5,
    p1: int | None = None,
    p2: int | None = None,
    adaptive_p2: bool = False,
    uniqueness: float = 0.1,
    lr_check: float | None = 1.0,
    speckle_size: int = 0,
    speckle_range: float = 1.0,
    vertical: bool = False,
    subpixel: Literal["equiangular", "parabola"] = "equiangular",
    median_filter: bool = False,
    census_threshold: float = 0.0,
    census_step: float | None = CENSUS_STEP,
    cost_window: int = COST_WINDOW,
    plane_fill: bool = True,
    slant_prior: bool = False,
) -> NDArray[np.float32]:
    r"""Disparity of a rectified stereo pair by semi-global matching on census costs.

    For every left pixel ``(x, y)`` the disparity ``d = x_left - x_right`` (OpenCV's
    definition and sign: the right image sees the point at ``x - d``) among
    ``min_disparity ... min_disparity + num_disparities - 1``, in pixels, sub-pixel:

    1. **Cost**: the Hamming distance of the census codes (R. Zabih & J. Woodfill 1994) of
       the ``block_size`` x ``block_size`` windows about ``(x, y)`` and ``(x - d, y)``:
       one bit per neighbour, set where it is darker than the centre, and (the graded
       census, ``census_step``) a second bit set where it is darker by more than
       ``census_step`` grey levels: a neighbour a grey level or two darker in one view and
       not in the other costs 1, one clearly darker in one and not in the other 2. Census, not
       OpenCV's Birchfield-Tomasi: it depends only on the order of intensities, so a gain
       or offset between the two cameras (an endoscope's two sensors, auto-exposure)
       changes nothing, and it was the most robust cost of Hirschmüller & Scharstein's
       evaluation (PAMI 31(9), 2009) under radiometric differences. With ``cost_window``
       ``w > 1`` (default 3) the cost is the sum of those Hamming distances over the
       ``w`` x ``w`` left pixels about ``(x, y)`` (each at its own ``x' - d``; the border
       replicated), divided by the least whole ``q`` that keeps it within 191 and rounded,
       ``C = round(Σ H / q)`` (``q = 3`` for the graded 5 x 5 census and ``w = 3``): OpenCV's
       ``StereoSGBM`` sums its pixel costs over a ``blockSize`` block the same way. A census
       compares every neighbour with one centre pixel, so that pixel's noise flips many bits
       at once, and in a flat region (a board's squares) each pixel's best disparity
       scatters; the sum averages that noise over the block.
    2. **Aggregation** along 8 paths (both ways horizontally, vertically and along both
       diagonals; OpenCV's ``MODE_HH``, not its 5-path default) by Hirschmüller's
       recursion (PAMI 30(2), 2008, eq. 13):

       .. math::

           L_r(p, d) = C(p, d) + \min\bigl(L_r(p-r, d),\ L_r(p-r, d \pm 1) + P_1,\
           \min_k L_r(p-r, k) + P_2\bigr) - \min_k L_r(p-r, k)

       summed, ``S(p, d) = Σ_r L_r(p, d)``. With ``slant_prior``, the paths run a second
       time on the same costs and follow the slant of the first map (steps 2 to 4 and 6):
       each pixel takes the least-squares plane ``d = a x + b y + c`` of the valid
       disparities in the 9 x 9 window about it where that plane fits them within 0.25 px
       (root mean square), ``|a|, |b| <= 1`` and ``max(|a|, |b|) >= 0.15`` (flatter fits are
       mostly the staircase of a fronto-parallel bias), and the second pass compares
       ``L_r(p, d)`` with ``L_r(p - r, d - g_r)``, ``g_r`` the plane's change of ``d`` along
       the step ``r`` (a fraction interpolated linearly between the two whole shifts): a
       surface slanted by ``g`` pixels of disparity a pixel costs no ``P1`` step every
       ``1 / g`` pixels (SGM-P, D. Scharstein, T. Taniai, S. Sinha, 3DV 2017, its priors here
       the first pass's own).
    3. **Winner-take-all** ``d = argmin S(p, ·)``, refined by the vertex of the
       equiangular V through ``S`` at ``d - 1, d, d + 1`` (two lines of opposite slopes;
       M. Shimizu & M. Okutomi 2001's fit for absolute-difference costs, which census
       bits count), ``d + (S_- - S_+) / (2 (max(S_-, S_+) - S))``; with
       ``subpixel="parabola"``, of the parabola through them (OpenCV's),
       ``d + (S_- - S_+) / (2 (S_- + S_+ - 2 S))``. Both pull ``d`` toward whole pixels
       (SGM's sums are flatter at the winner than either model), the V less: on
       ``benchmarks/check_stereo_depth.py``'s rendered pair the mean error of true
       disparities a quarter pixel past a whole one is -0.09 px with the V, -0.15 px with
       the parabola.
    4. **Checks**, each making the pixel invalid (NaN): some disparity of the range takes
       ``x - d`` out of the right image (OpenCV's rule: the first ``min_disparity +
       num_disparities - 1`` columns, and the last ``-min_disparity`` ones, are invalid);
       another disparity more than 1 away costs less than ``S_min / (1 - uniqueness)``;
       the left-right check, OpenCV's ``StereoSGBM`` rule (``disp12MaxDiff``): along each
       row from its right end, every unique winner claims its right pixel ``x - d`` unless
       a pixel before it claimed that one at a lower or equal ``S``; a pixel fails when
       both ``floor(d)`` and ``ceil(d)`` of its sub-pixel ``d`` land on right pixels claimed
       by disparities more than ``lr_check`` away (occlusions, mismatches: a pixel a
       closer surface hides loses its right pixel to it; an unclaimed one passes); with
       ``speckle_size``, the pixel lies in a 4-connected region of at most that many pixels
       whose neighbours differ by at most ``speckle_range`` (OpenCV's ``filterSpeckles``).
    5. With ``median_filter``, before the speckle filter: every disparity replaced by the
       median of its 3 x 3 neighbourhood, invalid pixels counted below every valid one (a
       pixel is invalid where five or more of the nine are), the border replicated: what
       OpenCV's ``StereoSGBM::compute`` does to every map it returns (``medianBlur(disp,
       disp, 3)``, which its parameters cannot turn off). It fills isolated invalid pixels
       and removes isolated outliers: on the Middlebury pairs of
       ``benchmarks/check_stereo_depth.py`` it is the difference between OpenCV's density
       and this function's at equal uniqueness (Adirondack 92.6 % valid, 96.8 % with it,
       OpenCV 95.6 %).
    6. With ``plane_fill`` (default), last: every flat region of the left image (its 5 x 5
       standard deviation under 3 grey levels, 4-connected, 30 pixels to 2 % of the image)
       takes the least-squares plane ``d = a x + b y + c`` of the valid disparities on its
       textured rim (the pixels within 3 px outside it), refitted twice on the rim's
       disparities within 1 px of it, where at least 80 % of the rim's valid disparities are
       such inliers and half of the rim is valid (a rim on two surfaces fails; invalid pixels
       of the region are filled too, never those of the invalid band). The plane is then
       refitted twice on the rim's and the region's own valid disparities within 1 px of it
       (matched faint texture pulls it toward a curved surface), and the region keeps its
       matched disparities where the plane explains its pixels worse:
       ``E(plane) > 1.4 E(matched)``, ``E(d)`` the mean absolute deviation from its mean of
       ``L(x, y) - R(x - d, y)`` over the region's valid pixels (the right row interpolated
       linearly), or where more than 20 % of its pixels on the plane would land on right
       pixels claimed by textured pixels of a disparity more than 1 px lower (the plane would
       hide what the right view sees), or where its rim fits the plane more than 3 times
       worse than the image's median rim and its own matched disparities lie behind the plane
       more often than in front of it (the shares more than 0.25 px off apart by more than
       0.15: a recess seen past nearer surfaces, whose rim is the occluders'). In a region
       without texture every disparity costs alike and each path carries in the disparity
       of the edge it came from, a step costing ``P1``: the sum takes one of those edges' values
       where a slanted surface's disparity changes (SGM's fronto-parallel bias; the plane
       fits of segments, Hirschmüller 2008 for untextured areas, Klaus et al. ICPR 2006). On
       ``benchmarks/check_stereo_recess.py``'s board pairs (truth the board's plane) the
       share more than 1 px off falls from 8.08 % to 4.87 % on webcam-1 (OpenCV
       ``MODE_HH`` 6.51 %), from 11.66 % to 8.89 % on the XIMEA pairs (OpenCV 10.04 %), from
       10.82 % to 8.43 % on webcam-2 (OpenCV 8.17 %), from 2.39 % to 0.99 % on the da Vinci
       endoscope's (OpenCV 13.64 %); Middlebury Adirondack's from 5.80 % to 4.67 %, teddy
       5.41 % to 5.37 % (5.78 % with the rim's plane alone, 2026-11-30h), the mean of six
       Middlebury 2005 / 2006 scenes 4.00 % to 3.99 % (4.08 %), the two ETH3D pairs' mean
       4.68 % to 4.64 % (4.88 % without the recess test;
       ``benchmarks/results/stereo-recess-2026-11-30k.md``). The cap of 2 % keeps large flat
       regions (Venus's background, whose long rim spans several surfaces) as matched.

    Parameters
    ----------
    left, right : array_like (H, W) or (H, W, C)
        The rectified images (rows are epipolar lines), the same shape; colour is matched
        as its Rec. 601 luma. Floats are read on a 0-1 scale, ``uint16`` on 0-65535, other
        integers on 0-255 (the scale matters only to ``adaptive_p2``). NaN and inf are
        refused.
    min_disparity : int
        The smallest disparity searched (negative when the principal points are apart).
    num_disparities : int
        How many disparities are searched (any positive number; OpenCV needs a multiple of
        16, which this accepts as well).
    block_size : {3, 5, 7}
        Side of the census window (8, 24 or 48 bits a pixel).
    p1, p2 : int, optional
        Penalties of a disparity step of 1 and of a larger one along a path, in bits of
        Hamming distance on the scale of step 1's costs (``0 < p1 < p2 <= 8000``). Defaults
        ``p1`` a third of the code's bits (``(block_size² - 1) / 3``, twice that for the
        graded census) times ``cost_window² / q`` (the scale of the block's sums) and
        ``p2 = 4 p1`` (48 and 192 for the graded 5 x 5 census and ``cost_window=3``; with
        ``cost_window=1``, 16 and 64, and 8 and 32 for the plain census: of 26 pairs tried
        on Middlebury's cones, one
        of the five at its best density with its share of errors over 3 px kept, taken for
        its figures on the other pairs of ``benchmarks/check_stereo_depth.py`` and its
        plain rule); with ``adaptive_p2``, ``p2 = 32 p1`` (the ``P2'`` that the intensity
        step divides: 256 for 5 x 5, where the gross errors of those pairs stop falling).
    adaptive_p2 : bool
        Divide ``p2`` by the intensity step along the path, ``p2 / |I_p - I_{p-r}|`` on a
        0-255 scale (Hirschmüller's eq. 12), never below ``p1``: disparity steps come cheaper
        at edges.
    uniqueness : float
        In ``[0, 1)``: the margin by which the winner must beat every disparity more than 1
        away (OpenCV's ``uniquenessRatio`` / 100; 0 turns the test off).
    lr_check : float or None
        Largest difference of a disparity and the claims on its right pixels (OpenCV's
        ``disp12MaxDiff`` and rule, step 4); None turns the check off.
    speckle_size : int
        Invalidate regions of at most this many pixels (0, the default, keeps all; OpenCV's
        ``speckleWindowSize``).
    speckle_range : float
        Largest difference of neighbours within one region (OpenCV's ``speckleRange``, here in
        pixels, not in 16ths).
    vertical : bool
        Match along columns: the rectified pair of a vertical rig (cameras stacked,
        :class:`~imageform.geometry.StereoRectification`'s ``vertical``), whose epipolar lines
        are columns. The disparity is then ``d = y_left - y_right`` (the first image's row
        minus the second's, the ``d`` of the rectification's ``Q``, as OpenCV's), "rows" and
        "columns" trade places in the steps above (the invalid band is the first ``min_disparity
        + num_disparities - 1`` rows), and the result is exactly that of the transposed pair,
        transposed: the census window and the 8 paths are symmetric.
    subpixel : {"equiangular", "parabola"}
        The sub-pixel fit of step 3.
    median_filter : bool
        Apply OpenCV's 3 x 3 median to the map (step 5).
    census_threshold : float
        Grey levels (on a 0-255 scale, ``>= 0``) by which a neighbour must be darker than
        the centre to set its census bit (0, the default: any darker neighbour); with the
        graded census its second bit needs ``census_threshold + census_step``. With the plain
        census (``census_step=None``) in flat regions (the squares of a board, a dim
        endoscope's tissue, Middlebury tsukuba's walls) the bits are set by differences of a
        grey level or two that the two cameras do not share, and their costs scatter the
        disparity; a threshold makes such regions cost the same at every disparity, and the
        paths carry the disparity of their edges in, as OpenCV's Birchfield-Tomasi costs do,
        but it drops fine texture of low contrast too: on
        ``benchmarks/check_stereo_noise.py``'s pairs, plain census, threshold 4, the share of
        disparities more than 1 px off falls from 33.6 % to 3.9 % on the da Vinci endoscope's
        board pairs and rises from 9.9 % to 16.1 % on Middlebury's Adirondack. The census
        then depends on the images' contrast: a gain between the cameras changes the bits
        near the threshold.
    census_step : float or None
        Grey levels (0-255 scale, ``>= 0``) of the graded census's second bit (default 4):
        each neighbour costs 0, 1 or 2 by how far the two views disagree on it (darker, or
        darker by more than the step), so faint shading and noise weigh half as much as
        texture while texture of low contrast still counts. On
        ``benchmarks/check_stereo_noise.py``'s tuning pairs (steps 2, 4, 8 tried) it
        lowers the share of disparities more than 1 px off on every real pair against the plain
        census: da Vinci endoscope board pairs 33.6 % to 8.9 % (OpenCV 13.6 %),
        Adirondack 9.9 % to 7.3 %, tsukuba 6.5 % to 5.1 %, as dense on street pairs
        (69.7 % valid against 69.6 %); the share more than 3 px off rises by up to 0.14
        point on Middlebury's Adirondack pairs, cones and teddy. None: the plain census of
        one bit per neighbour (the default before; step 0 gives its map too, every cost and
        default penalty doubled). A 7 x 7 window's 48 bits fill the 64-bit code:
        ``block_size=7`` always takes the plain census.
    cost_window : {1, 3, 5, 7}
        Side of the block of left pixels whose census costs are summed (step 1; OpenCV's
        ``blockSize`` sum). Default 3: on ``benchmarks/check_stereo_webcam.py``'s board pairs
        (truth the board's plane) the share of disparities more than 1 px off falls from
        11.84 % to 8.08 % on webcam-1 (OpenCV ``MODE_HH`` 6.51 %), from 19.52 % to 11.66 %
        on the XIMEA pairs (OpenCV 10.04 %), from 8.93 % to 2.39 % on the da Vinci endoscope's
        (OpenCV 13.64 %), and on every Middlebury pair but cones (2.80 % to 2.82 %) too
        (Adirondack 7.25 % to 5.80 %, tsukuba 5.07 % to 4.60 %). 5 lowers the boards' further
        (webcam-1 6.98 %, XIMEA 8.33 %) but raises Middlebury teddy's and cones' (finer
        shapes, fattened edges). 1: each pixel's cost alone, the default before 2026-11-30.
    plane_fill : bool
        Give flat regions the plane of their textured rim (step 6; default on). False: the
        map of before 2026-11-30h.
    slant_prior : bool
        Aggregate a second time along the slants of the first map (step 2; default off): 1.6
        to 2.9 times the CPU time. On the tuning sets of ``benchmarks/check_stereo_sgmp.py``
        (``benchmarks/results/stereo-sgmp-2026-12-01a.md``) the share of pixels more than 1 px
        off falls on every set's mean or stays (webcam-1 boards 4.87 % to 4.23 %, webcam-2
        8.43 % to 8.05 %, XIMEA 8.89 % to 8.77 %, Middlebury 2005 / 2006 3.99 % to 3.91 %,
        ETH3D 4.64 % to 4.56 %, Middlebury 2003 / 2014 3.70 % to 3.68 %, MPI-Sintel 1.30 %
        to 1.29 %, da Vinci 0.99 % to 1.00 %; teddy 5.37 % to 5.42 %); on the pairs held out
        (``stereo-sgmp-2026-12-01c.md``) it did not: Middlebury 2005 Art and Laundry at 640 px
        16.96 % to 17.00 %, KITTI 2012 pair 70 9.53 % to 9.70 % (denser, 86.3 % to 88.7 %
        valid, fewer errors over 3 px; OpenCV 18.70 % and 11.35 %).

    Returns
    -------
    ndarray (H, W) float32
        The disparity in pixels; NaN where invalid (``np.isnan`` is the invalid mask).

    Raises
    ------
    InvalidInputError
        Images of other shapes, NaN or inf in them, a parameter out of its range.

    Notes
    -----
    The work is ``O(H W D)`` with ``D = num_disparities`` (about 3 ns a pixel and disparity
    on one core with numba, the block sums of ``cost_window`` some 0.3 ns more, sliding;
    ``plane_fill`` some 80 ns a pixel, whatever ``D``, in NumPy and SciPy, its refit and
    tests 1 % to 8 % more of the whole;
    ``benchmarks/check_stereo_planes.py`` times it against OpenCV's ``MODE_HH``); memory 3
    bytes a pixel and disparity. The numba kernels
    (:mod:`imageform._kernels.sgm`) and their NumPy twins give the same numbers.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> right = rng.uniform(0, 1, (40, 80))
    >>> left = np.roll(right, 7, axis=1)  # everything 7 px to the right in the left image
    >>> d = stereo_disparity(left, right, num_disparities=16)
    >>> float(np.nanmedian(d)), bool(np.isnan(d[:, :7]).all())
    (7.0, True)
    >>> top = np.roll(right.T, 7, axis=0)  # a vertical pair: the first image's rows 7 lower
    >>> dv = stereo_disparity(top, right.T, num_disparities=16, vertical=True)
    >>> bool(np.array_equal(dv, d.T, equal_nan=True))
    True
    """
    gl = _grey(left, "left")
    gr = _grey(right, "right")
    if gl.shape != gr.shape:
        raise InvalidInputError(
            f"expected left and right images of one size, got {gl.shape[1]} x {gl.shape[0]} "
            f"and {gr.shape[1]} x {gr.shape[0]} px"
        )
    h, w = gl.shape
    min_d = as_int(min_disparity, "min_disparity", minimum=-(2**20), maximum=2**20)
    n_d = as_int(num_disparities, "num_disparities", minimum=1, maximum=4096)
    bs = as_int(block_size, "block_size")
    if bs not in BLOCK_SIZES:
        raise InvalidInputError(f"expected block_size 3, 5 or 7 (the census window), got {bs}")
    thr = as_real(census_threshold, "census_threshold", minimum=0.0, maximum=255.0)
    step = -1.0
    if census_step is not None:
        step = as_real(census_step, "census_step", minimum=0.0, maximum=255.0)
        step = step if bs < 7 else -1.0  # a 7 x 7 window's 48 bits fill the code alone
    nbits = (bs * bs - 1) * (2 if step >= 0 else 1)
    cw = as_int(cost_window, "cost_window")
    if cw not in COST_WINDOWS:
        raise InvalidInputError(
            f"expected cost_window 1, 3, 5 or 7 (the block of summed costs), got {cw}"
        )
    div = _divisor(nbits, cw)
    if p1 is None:  # a third of the code's bits, on the scale of the block's sums
        P1 = max(1, (nbits // 3) * cw * cw // div)
    else:
        P1 = as_int(p1, "p1", minimum=1, maximum=MAX_P2 - 1)
    if not isinstance(adaptive_p2, bool | np.bool_):
        raise TypeError(f"expected adaptive_p2 as a bool, got {describe(adaptive_p2)}")
    if p2 is None:
        P2 = (32 if adaptive_p2 else 4) * P1
    else:
        P2 = as_int(p2, "p2", minimum=1, maximum=MAX_P2)
    P2 = min(P2, MAX_P2)
    if not P2 > P1:
        raise InvalidInputError(
            f"expected p2 > p1 (a larger jump costs more), got p1 {P1}, p2 {P2}"
        )
    u = as_real(uniqueness, "uniqueness", minimum=0.0)
    if not u < 1.0:
        raise InvalidInputError(f"expected uniqueness in [0, 1), got {u}")
    lr = -1.0 if lr_check is None else as_real(lr_check, "lr_check", minimum=0.0)
    sp = as_int(speckle_size, "speckle_size", minimum=0, maximum=2**40)
    sr = as_real(speckle_range, "speckle_range", minimum=0.0)
    if not isinstance(vertical, bool | np.bool_):
        raise TypeError(f"expected vertical as a bool, got {describe(vertical)}")
    equiangular = check_option(subpixel, SUBPIXEL_FITS, "subpixel") == "equiangular"
    if not isinstance(median_filter, bool | np.bool_):
        raise TypeError(f"expected median_filter as a bool, got {describe(median_filter)}")
    if not isinstance(plane_fill, bool | np.bool_):
        raise TypeError(f"expected plane_fill as a bool, got {describe(plane_fill)}")
    if not isinstance(slant_prior, bool | np.bool_):
        raise TypeError(f"expected slant_prior as a bool, got {describe(slant_prior)}")
    check_memory(3.0 * h * w * n_d, "num_disparities", f"the costs of {h} x {w} px x {n_d}")
    if use_numba(gl):
        from imageform._kernels import sgm as kern
    else:
        from imageform.geometry import _sgm_numpy as kern  # type: ignore[no-redef]
    if vertical:  # columns as rows: the kernels walk rows
        gl, gr = np.ascontiguousarray(gl.T), np.ascontiguousarray(gr.T)
    d = _match(
        kern, gl, gr, min_d, n_d, bs, P1, P2, bool(adaptive_p2), u, lr, sp, sr, equiangular,
        bool(median_filter), thr, step, cw, bool(slant_prior), bool(plane_fill),
    )  # fmt: skip
    if plane_fill:
        d = _plane_fill(d, gl, min_d, n_d, gr)
    return np.ascontiguousarray(d.T) if vertical else d


def _match(
    kern: Any,
    gl: NDArray[np.float32],
    gr: NDArray[np.float32],
    min_d: int,
    n_d: int,
    bs: int,
    p1: int,
    p2: int,
    adaptive: bool,
    uniqueness: float,
    lr: float,
    speckle_size: int,
    speckle_range: float,
    equiangular: bool = True,
    median: bool = False,
    census_threshold: float = 0.0,
    census_step: float = -1.0,
    cost_window: int = 1,
    slant: bool = False,
    fill: bool = False,
) -> NDArray[np.float32]:
    """Run the pipeline on checked grey images with the kernels (or twins) of module ``kern``.

    With ``slant``, a second aggregation whose paths follow the slants (:func:`_slants`) of
    the first one's map (given the plane fill first with ``fill``), on the same costs.
    """
    r = bs // 2
    thr, step = np.float32(census_threshold), np.float32(census_step)
    cl = kern.census(gl, r, thr, step)
    cr = kern.census(gr, r, thr, step)
    nbits = (bs * bs - 1) * (2 if census_step >= 0 else 1)
    # the volumes allocated by NumPy, not in the kernels: NumPy asks Linux for huge pages
    # (madvise), numba does not, and 4 kB pages cost a fifth of the matching's time in faults
    h, w = gl.shape
    vol = np.empty((h, w, n_d), np.uint8)
    if cost_window > 1:
        div = _divisor(nbits, cost_window)
        cost = kern.window_costs(cl, cr, min_d, n_d, nbits, cost_window // 2, div, vol)
    else:
        cost = kern.cost_volume(cl, cr, min_d, n_d, nbits, vol)
    total = np.empty((h, w, n_d), dtype=np.uint16)
    none = np.zeros((0, 1, 1), dtype=np.int32)  # no slant: one compiled signature for both
    disp = kern.match(
        cost, gl, p1, p2, adaptive, min_d, float(uniqueness), float(lr), total, equiangular, none
    )
    if slant:
        first = _plane_fill(disp, gl, min_d, n_d, gr) if fill else disp
        disp = kern.match(
            cost, gl, p1, p2, adaptive, min_d, float(uniqueness), float(lr), total, equiangular,
            _slants(first),
        )  # fmt: skip
    del cost, total
    if median:
        disp = kern.median3(disp)
    if speckle_size > 0:
        kern.speckles(disp, speckle_size, float(speckle_range))
    return np.asarray(disp, dtype=np.float32)


def _slants(disp: NDArray[np.float32]) -> NDArray[np.int32]:
    """Return the prior of :func:`stereo_disparity`'s second pass: each local plane's slant.

    The least-squares plane ``d = a x + b y + c`` of the valid disparities in the
    ``SLANT_WINDOW`` square about each pixel (box sums of the moments); where its root mean
    square residual is under ``SLANT_FIT`` px, at least a third of the window is valid,
    ``|a|, |b| <= SLANT_MAX`` and ``max(|a|, |b|) >= SLANT_MIN``, the changes of ``d`` along
    the steps ``(1, 0), (1, 1), (0, 1), (-1, 1)``, ``a, a + b, b, b - a``, in 1/256 px
    (``int32 (4, H, W)``); 0 elsewhere (a window across an occluding edge fits no plane).
    """
    from scipy import ndimage

    h, w = disp.shape
    win = SLANT_WINDOW
    v = np.isfinite(disp)
    z = np.where(v, disp, 0.0).astype(np.float64)
    vf = v.astype(np.float64)
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
    xx -= 0.5 * w
    yy -= 0.5 * h

    def box(a: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.asarray(ndimage.uniform_filter(a, win, mode="constant"), dtype=np.float64)

    s1, sx, sy = box(vf), box(vf * xx), box(vf * yy)
    sxx, sxy, syy = box(vf * xx * xx), box(vf * xx * yy), box(vf * yy * yy)
    sz, sxz, syz, szz = box(z), box(z * xx), box(z * yy), box(z * z)
    # the normal equations' symmetric 3 x 3 matrix solved by its cofactors
    c00, c01, c02 = syy * s1 - sy * sy, sx * sy - sxy * s1, sxy * sy - syy * sx
    c11, c12, c22 = sxx * s1 - sx * sx, sxy * sx - sxx * sy, sxx * syy - sxy * sxy
    det = sxx * c00 + sxy * c01 + sx * c02
    ok = (s1 >= 1.0 / 3.0) & (det > 0.1 * s1**3)  # a full window's det is ~45 s1^3
    det = np.where(ok, det, 1.0)
    a = (c00 * sxz + c01 * syz + c02 * sz) / det
    bb = (c01 * sxz + c11 * syz + c12 * sz) / det
    c = (c02 * sxz + c12 * syz + c22 * sz) / det
    quad = a * a * sxx + bb * bb * syy + c * c * s1 + 2 * (a * bb * sxy + a * c * sx + bb * c * sy)
    ms = (szz - 2 * (a * sxz + bb * syz + c * sz) + quad) / np.maximum(s1, 1e-9)
    ok &= ms < SLANT_FIT**2
    ok &= (np.abs(a) <= SLANT_MAX) & (np.abs(bb) <= SLANT_MAX)
    ok &= np.maximum(np.abs(a), np.abs(bb)) >= SLANT_MIN
    a = np.where(ok, a, 0.0)
    bb = np.where(ok, bb, 0.0)
    steps = np.stack([a, a + bb, bb, bb - a])
    return np.ascontiguousarray(np.floor(steps * 256.0 + 0.5).astype(np.int32))


def _plane_fill(
    disp: NDArray[np.float32],
    grey: NDArray[np.float32],
    min_d: int,
    n_d: int,
    right: NDArray[np.float32] | None = None,
) -> NDArray[np.float32]:
    """Give the flat regions of ``grey`` the plane of the disparities on their textured rim.

    :func:`stereo_disparity`'s step 6: the regions (4-connected) whose 5 x 5 standard deviation
    is under ``PLANE_FLAT_SD``, of ``PLANE_AREA`` pixels; their rims (the other pixels within
    ``PLANE_RIM`` px, each to its nearest region); per region the least-squares plane
    ``d = a x + b y + c`` of its rim's valid disparities, refitted twice on the rim pixels
    within ``PLANE_INLIER[0]`` px of it; taken where those are at least ``PLANE_INLIER[1]`` of
    the rim's valid pixels and half of the rim is valid, then refitted ``PLANE_REFIT`` times on
    the rim's and the region's own valid disparities within ``PLANE_INLIER[0]`` px of it, and
    given to every pixel of the region inside the valid band (invalid ones too) unless the
    plane explains the region's pixels worse than its matched disparities (``PLANE_PHOTO``,
    with the ``right`` image; None skips that test), hides textured pixels (``PLANE_HIDE``)
    or stands in front of a recess (``PLANE_RECESS``).
    """
    from scipy import ndimage

    h, w = grey.shape
    g = grey.astype(np.float64)
    mean = ndimage.uniform_filter(g, 5, mode="nearest")
    var = ndimage.uniform_filter(g * g, 5, mode="nearest") - mean * mean
    lab, n = ndimage.label(var < PLANE_FLAT_SD**2)
    if n == 0:
        return disp
    area = np.bincount(lab.ravel(), minlength=n + 1)
    keep = (area >= PLANE_AREA[0]) & (area <= PLANE_AREA[1] * h * w)
    keep[0] = False
    lab = np.where(keep[lab], lab, 0)
    if not lab.any():
        return disp
    rim = _rim_labels(lab, _rim_d2(PLANE_RIM))
    at = np.flatnonzero(rim)  # the rim's pixels in raster order, their region and disparity
    near = rim.ravel()[at]
    d_rim = disp.ravel()[at]
    valid = np.isfinite(disp)
    ok_rim = np.isfinite(d_rim)
    seg = near[ok_rim]
    ys, xs = np.divmod(at[ok_rim], w)
    d_src = d_rim[ok_rim]
    m = n + 1
    coef, fitted, weight = _fit_planes(seg, xs, ys, d_src, m, None, 3)
    inliers = np.bincount(seg, weights=weight, minlength=m)
    used = np.bincount(seg, minlength=m)
    rim_px = np.bincount(near, minlength=m)
    take = fitted & (inliers >= PLANE_INLIER[1] * used) & (2 * used >= rim_px)
    take[0] = False
    if not take.any():
        return disp
    # the refit on the rim and the region's own disparities near the plane: a curved surface's
    # faint texture, matched, pulls the plane toward it; a flat square's path-carried values
    # lie about the plane's middle and move it little
    inner = (lab > 0) & valid & take[lab]
    yi, xi = np.nonzero(inner)
    both = (
        np.concatenate([seg, lab[inner]]),
        np.concatenate([xs, xi]),
        np.concatenate([ys, yi]),
        np.concatenate([d_src, disp[inner]]),
    )
    if PLANE_REFIT > 0:
        refit, ok, _ = _fit_planes(*both, m, coef, PLANE_REFIT)
        ok &= take
        coef[ok] = refit[ok]
    k = lab[inner]
    plane = coef[k, 0] * xi + coef[k, 1] * yi + coef[k, 2]
    if right is not None:
        take &= ~(_photo_ratio(grey, right, yi, xi, disp[inner], plane, k, m) > PLANE_PHOTO)
    take &= ~(_hidden_share(disp, lab, take, coef, m) > PLANE_HIDE)
    take &= ~_recessed(d_src, seg, xs, ys, coef, take, disp[inner] - plane, k, m)
    x0 = min(max(min_d + n_d - 1, 0), w)
    x1 = max(min(w, w + min_d), x0)
    if use_numba(disp) and disp.dtype == np.float32:  # the same numbers in one pass
        from imageform._kernels import sgm

        return np.asarray(
            sgm.plane_write(
                np.ascontiguousarray(disp), np.ascontiguousarray(lab),
                np.ascontiguousarray(take), np.ascontiguousarray(coef, dtype=np.float64),
                x0, x1,
            )
        )  # fmt: skip
    sel = take[lab]
    sel[:, :x0] = False
    sel[:, x1:] = False
    yy, xx = np.nonzero(sel)
    k = lab[yy, xx]
    out = disp.copy()
    out[yy, xx] = (coef[k, 0] * xx + coef[k, 1] * yy + coef[k, 2]).astype(np.float32)
    return out


def _rim_labels(lab: NDArray[np.integer[Any]], r2: int) -> NDArray[np.intp]:
    """Return the label of each pixel's nearest region pixel within ``sqrt(r2)`` px, 0 if none.

    For the pixels outside the regions (``lab == 0``): the label ``lab > 0`` of the nearest
    region pixel, as SciPy's feature transform (``distance_transform_edt``) picks it, where its
    squared distance is at most ``r2``; 0 elsewhere (``intp (H, W)``). With numba the kernel
    ``rim_labels`` gives the same labels from each region's edge pixels' discs, without the
    transform over the whole image (ties to the least column, then the least row: SciPy's).
    """
    if use_numba(lab):
        from imageform._kernels import sgm

        return np.asarray(sgm.rim_labels(np.ascontiguousarray(lab), int(r2)), dtype=np.intp)
    from scipy import ndimage

    h, w = lab.shape
    # each pixel's nearest region pixel; the rim from the squared distances of the indices
    # (SciPy's distances are their square roots: the same pixels)
    iy, ix = ndimage.distance_transform_edt(lab == 0, return_distances=False, return_indices=True)
    if max(h, w) >= 2**15:  # h² + w² past int32
        iy, ix = iy.astype(np.int64), ix.astype(np.int64)
    d2 = (iy - np.arange(h, dtype=iy.dtype)[:, None]) ** 2
    d2 += (ix - np.arange(w, dtype=ix.dtype)) ** 2
    rim = (lab == 0) & (d2 <= r2)
    out = np.zeros((h, w), dtype=np.intp)
    out[rim] = lab[iy[rim], ix[rim]]
    return out


def _rim_d2(radius: float) -> int:
    """Return the largest squared whole-pixel distance whose square root is within ``radius``."""
    r2 = int(radius * radius) + 2
    while r2 >= 0 and not math.sqrt(r2) <= radius:
        r2 -= 1
    return r2


def _fit_planes(
    seg: NDArray[np.intp],
    xs: NDArray[np.intp],
    ys: NDArray[np.intp],
    disp: NDArray[np.float32],
    m: int,
    coef: NDArray[np.float64] | None,
    passes: int,
) -> tuple[NDArray[np.float64], NDArray[np.bool_], NDArray[np.float64]]:
    """Least-squares planes ``d = a x + b y + c`` of the points of each segment ``0 .. m - 1``.

    The first pass on every point (``coef`` None) or on those within ``PLANE_INLIER[0]`` px of
    the planes ``coef``, each next one on the points within that of the last fit. Returns the
    planes (zero where none fits), where one fits (10 points, not all on a line), and the
    weights (1 inlier, 0 not) against the last fit.
    """
    x, y, z = xs.astype(np.float64), ys.astype(np.float64), disp.astype(np.float64)
    kern: Any = None
    if use_numba(z):  # the sums in one pass over the points, the same to the last bit
        from imageform._kernels import sgm

        kern = sgm

        seg = np.ascontiguousarray(seg, dtype=np.int64)

    def inliers(c: NDArray[np.float64]) -> NDArray[np.float64]:
        if kern is not None:
            wt = np.empty_like(z)
            kern.plane_weights(seg, x, y, z, c, float(PLANE_INLIER[0]), wt)
            return wt
        r = z - (c[seg, 0] * x + c[seg, 1] * y + c[seg, 2])
        return (np.abs(r) <= PLANE_INLIER[0]).astype(np.float64)

    def moments(wt: NDArray[np.float64]) -> list[NDArray[np.float64]]:
        if kern is not None:
            sums = np.zeros((m, 9))
            kern.plane_sums(seg, x, y, z, wt, sums)
            return list(sums.T)
        terms = (x * x, x * y, y * y, x, y, np.ones_like(x), x * z, y * z, z)
        return [
            np.asarray(np.bincount(seg, weights=wt * v, minlength=m), dtype=np.float64)
            for v in terms
        ]

    weight = np.ones_like(z) if coef is None else inliers(coef)
    out = np.zeros((m, 3))
    fitted = np.zeros(m, dtype=bool)
    for _ in range(passes):
        t = moments(weight)
        sxx, sxy, syy, sx, sy, s1 = t[:6]
        A = np.stack(
            [
                np.stack([sxx, sxy, sx], -1),
                np.stack([sxy, syy, sy], -1),
                np.stack([sx, sy, s1], -1),
            ],
            -2,
        )
        b = np.stack(t[6:], -1)
        fitted = s1 >= 10
        fitted &= np.abs(np.linalg.det(A)) > 1e-9 * np.maximum(s1, 1.0) ** 3
        out[:] = 0.0
        if fitted.any():
            out[fitted] = np.linalg.solve(A[fitted], b[fitted][..., None])[..., 0]
        weight = inliers(out)
    return out, fitted, weight


def _photo_ratio(
    grey: NDArray[np.float32],
    right: NDArray[np.float32],
    ys: NDArray[np.intp],
    xs: NDArray[np.intp],
    matched: NDArray[np.float32],
    plane: NDArray[np.float64],
    seg: NDArray[np.intp],
    m: int,
) -> NDArray[np.float64]:
    """Per segment, how much worse the plane explains the left pixels than the matched values.

    ``E(d) = mean |D - mean D|`` over the segment's pixels, ``D = L(x, y) - R(x - d, y)``
    (the right row interpolated linearly, the border replicated; the mean taken out so that an
    offset between the cameras counts for nothing); returns ``E(plane) / E(matched)``.
    """
    w = grey.shape[1]
    left = grey[ys, xs].astype(np.float64)
    if use_numba(left) and right.dtype == np.float32:
        from imageform._kernels import sgm as kern

        args = (np.ascontiguousarray(right), ys, xs)
        sk = np.ascontiguousarray(seg, dtype=np.int64)
        matched64 = matched.astype(np.float64)
        return kern.photo_spread(left, *args, plane, sk, m) / np.maximum(
            kern.photo_spread(left, *args, matched64, sk, m), 1e-6
        )
    cnt = np.maximum(np.bincount(seg, minlength=m), 1)

    def spread(d: NDArray[np.floating[Any]]) -> NDArray[np.float64]:
        xr = np.clip(xs - d.astype(np.float64), 0.0, w - 1.0)
        i = np.floor(xr).astype(np.intp)
        f = xr - i
        j = np.minimum(i + 1, w - 1)
        diff = left - (right[ys, i] * (1.0 - f) + right[ys, j] * f)
        mu = np.bincount(seg, weights=diff, minlength=m) / cnt
        return np.bincount(seg, weights=np.abs(diff - mu[seg]), minlength=m) / cnt

    return spread(plane) / np.maximum(spread(matched), 1e-6)


def _hidden_share(
    disp: NDArray[np.float32],
    lab: NDArray[np.intp],
    take: NDArray[np.bool_],
    coef: NDArray[np.float64],
    m: int,
) -> NDArray[np.float64]:
    """Per segment, the share of its pixels whose plane would hide a matched textured pixel.

    The valid pixels outside the segments claim the right pixels ``floor(x - d)`` and
    ``ceil(x - d)``; a segment's pixel on its plane ``p`` landing on a right pixel claimed by a
    disparity below ``p - 1`` would stand in front of that pixel, which the right view sees.
    """
    h, w = disp.shape
    if use_numba(disp) and disp.dtype == np.float32:
        from imageform._kernels import sgm as kern

        return np.asarray(
            kern.hidden_share(
                np.ascontiguousarray(disp), np.ascontiguousarray(lab, dtype=np.int64),
                np.ascontiguousarray(take), np.ascontiguousarray(coef, dtype=np.float64),
                float(PLANE_INLIER[0]),
            )
        )  # fmt: skip
    src = (lab == 0) & np.isfinite(disp)
    ys, xs = np.nonzero(src)
    d = disp[src].astype(np.float64)
    low = np.full(h * w, np.inf)
    for xr in (np.floor(xs - d), np.ceil(xs - d)):
        inside = (xr >= 0) & (xr < w)
        np.minimum.at(low, ys[inside] * w + xr[inside].astype(np.intp), d[inside])
    sel = (lab > 0) & take[lab]
    ys, xs = np.nonzero(sel)
    k = lab[sel]
    p = coef[k, 0] * xs + coef[k, 1] * ys + coef[k, 2]
    xr = np.round(xs - p)
    inside = (xr >= 0) & (xr < w)
    hides = np.zeros(k.size)
    at = ys[inside] * w + xr[inside].astype(np.intp)
    hides[inside] = p[inside] > low[at] + PLANE_INLIER[0]
    return np.bincount(k, weights=hides, minlength=m) / np.maximum(np.bincount(k, minlength=m), 1)


def _recessed(
    rim: NDArray[np.float32],
    seg: NDArray[np.intp],
    xs: NDArray[np.intp],
    ys: NDArray[np.intp],
    coef: NDArray[np.float64],
    take: NDArray[np.bool_],
    off: NDArray[np.floating[Any]],
    k: NDArray[np.intp],
    m: int,
) -> NDArray[np.bool_]:
    """Per segment, whether its plane stands in front of a recess seen past nearer surfaces.

    A flat region under a bench or behind a chair has the occluders on its rim: the rim's
    disparities (``rim`` at ``xs, ys`` of segment ``seg``) fit one plane badly, their mean
    absolute residual (each capped at 3 px) over ``PLANE_RECESS[0]`` times the median of the
    segments still taken (0.01 px at least), and the region's own matched disparities
    (``off``, their offsets from the plane, of segment ``k``) lie behind the plane (by more
    than ``PLANE_RECESS[2]`` px) more often than in front of it, the shares apart by more than
    ``PLANE_RECESS[1]``.
    """
    out = np.zeros(m, dtype=bool)
    if not take.any():
        return out
    plane = coef[seg, 0] * xs + coef[seg, 1] * ys + coef[seg, 2]
    resid = np.minimum(np.abs(rim - plane), 3.0)
    used = np.maximum(np.bincount(seg, minlength=m), 1)
    fit = np.bincount(seg, weights=resid, minlength=m) / used
    side = (off < -PLANE_RECESS[2]).astype(np.float64) - (off > PLANE_RECESS[2])
    lean = np.bincount(k, weights=side, minlength=m) / np.maximum(np.bincount(k, minlength=m), 1)
    typical = max(float(np.median(fit[take])), 0.01)  # 0.01: rims fitted exactly (synthetic)
    out[:] = take & (fit > PLANE_RECESS[0] * typical) & (lean > PLANE_RECESS[1])
    return out


def _divisor(nbits: int, window: int) -> int:
    """Return the block sums' divisor: the least keeping the largest sum within ``MAX_COST``."""
    return max(1, -(-nbits * window * window // MAX_COST))


def _q_matrix(rectification: StereoRectification | npt.ArrayLike) -> NDArray[np.float64]:
    Q = getattr(rectification, "Q", rectification)
    Q = to_numpy(Q) if not isinstance(Q, list | tuple) else Q
    Qm = as_real_array(Q, "rectification", check=False)
    if Qm.shape != (4, 4):
        raise InvalidInputError(
            f"expected rectification as a StereoRectification or its Q matrix (4, 4), got shape "
            f"{Qm.shape}"
        )
    if not np.isfinite(Qm).all():
        raise InvalidInputError("expected rectification's Q of finite numbers")
    if not np.any(Qm[3]):
        raise InvalidInputError(
            "expected rectification's Q with a non-zero last row (it maps no disparity to a depth)"
        )
    return Qm


def _disparity(disparity: Any) -> NDArray[np.floating[Any]]:
    d = np.asarray(to_numpy(disparity))
    if d.dtype.kind not in "fiu" or d.ndim != 2:
        raise InvalidInputError(
            f"expected disparity as real numbers (H, W) (NaN where invalid), got {describe(d)}"
        )
    if np.isinf(d).any():
        raise InvalidInputError("expected disparity finite or NaN (invalid), got inf")
    return d if d.dtype == np.float32 else d.astype(np.float64)


def disparity_to_points(
    disparity: npt.ArrayLike, rectification: StereoRectification | npt.ArrayLike
) -> NDArray[np.floating[Any]]:
    r"""3-D points of a disparity map in the rectified left camera's frame (``reprojectImageTo3D``).

    ``(X, Y, Z, W)ᵀ = Q (u, v, d, 1)ᵀ`` and the point ``(X, Y, Z) / W`` for every pixel
    ``(u, v)`` with disparity ``d`` (``d = x_left - x_right``, :func:`stereo_disparity`'s;
    ``y_left - y_right`` for a vertical rig, ``stereo_disparity(..., vertical=True)``);
    for a horizontal rig ``Z = f B / (d - (c_{x,1} - c_{x,2}))`` with the baseline ``B``.
    Units: those of the calibration's ``T`` (millimetres from ``imageform stereo-calibrate``).

    Parameters
    ----------
    disparity : array_like (H, W)
        Disparities in pixels, NaN where invalid.
    rectification : StereoRectification or array_like (4, 4)
        :func:`~imageform.geometry.stereo_rectify`'s result, or its ``Q`` matrix.

    Returns
    -------
    ndarray (H, W, 3)
        ``(X, Y, Z)``, float32 for float32 disparities, else float64; NaN where the
        disparity is NaN or puts the point at or beyond infinity (``W <= 0``: zero or
        negative disparity on a zero-disparity rectification).

    Examples
    --------
    >>> Q = np.array([[1.0, 0, 0, -320], [0, 1, 0, -240], [0, 0, 0, 800], [0, 0, 0.01, 0]])
    >>> disparity_to_points(np.full((1, 1), 16.0), Q)[0, 0].tolist()  # B = 100, f = 800
    [-2000.0, -1500.0, 5000.0]
    """
    d = _disparity(disparity)
    Q = _q_matrix(rectification)
    h, w = d.shape
    check_memory(8.0 * h * w * 6, "disparity", f"the points of {h} x {w} px")
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    dd = d.astype(np.float64)
    uvd1 = np.stack([u, v, dd, np.ones_like(u)], axis=-1)
    X = uvd1 @ Q.T
    W = X[..., 3]
    with np.errstate(divide="ignore", invalid="ignore"):
        pts = X[..., :3] / W[..., None]
    bad = ~(W > 0) | ~np.isfinite(pts).all(axis=-1)
    pts[bad] = np.nan
    return pts.astype(d.dtype if d.dtype == np.float32 else np.float64)


def disparity_to_depth(
    disparity: npt.ArrayLike, rectification: StereoRectification | npt.ArrayLike
) -> NDArray[np.floating[Any]]:
    r"""Depth ``Z`` of every pixel of a disparity map: ``Z = f B / (d - Δc)``.

    The third coordinate of :func:`disparity_to_points` (``Q[2, 3] / (Q[3, 2] d + Q[3, 3])``):
    ``f`` the rectified focal length, ``B`` the baseline, ``Δc = c_{x,1} - c_{x,2}`` (0 on a
    zero-disparity rectification; ``c_{y,1} - c_{y,2}`` and ``d = y_left - y_right`` for a
    vertical rig). Distance along the rectified left camera's optical axis,
    in the units of the calibration's ``T``.

    Parameters
    ----------
    disparity : array_like (H, W)
        Disparities in pixels (:func:`stereo_disparity`), NaN where invalid.
    rectification : StereoRectification or array_like (4, 4)
        :func:`~imageform.geometry.stereo_rectify`'s result, or its ``Q`` matrix.

    Returns
    -------
    ndarray (H, W)
        Depth; float32 for float32 disparities, else float64; NaN where the disparity is
        NaN or gives no point in front of the camera.

    Examples
    --------
    >>> Q = np.array([[1.0, 0, 0, -320], [0, 1, 0, -240], [0, 0, 0, 800], [0, 0, 0.01, 0]])
    >>> disparity_to_depth(np.array([[16.0, 0.0, np.nan]]), Q).tolist()  # f B = 80 000
    [[5000.0, nan, nan]]
    """
    d = _disparity(disparity)
    Q = _q_matrix(rectification)
    h, w = d.shape
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    dd = d.astype(np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        W = Q[3, 0] * u + Q[3, 1] * v + Q[3, 2] * dd + Q[3, 3]
        z = (Q[2, 0] * u + Q[2, 1] * v + Q[2, 2] * dd + Q[2, 3]) / W
    z[~(W > 0) | ~np.isfinite(z)] = np.nan
    return z.astype(d.dtype if d.dtype == np.float32 else np.float64)
