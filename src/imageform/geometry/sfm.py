r"""Structure from motion: camera poses and 3-D points from an ordered set of frames.

The course's second application: with the intrinsics known (a calibrated endoscope), the
frames of a video give, by correspondences, the camera's motion and the scene's shape. The
pipeline, each step a public function:

1. :func:`detect_features`: SIFT keypoints (scale- and rotation-invariant, sub-pixel,
   OpenCV's implementation, the ``reconstruct`` extra) and their 128-number descriptors;
2. :func:`match_features`: nearest neighbours by descriptor distance with Lowe's ratio test
   (the nearest clearly nearer than the second) and a mutual check (each the other's
   nearest);
3. geometric verification of each pair by the essential matrix
   (:func:`~imageform.geometry.find_essential_matrix`, 5-point LO-RANSAC) on the
   undistorted keypoints, then the cheirality check of its pose
   (:func:`~imageform.geometry.recover_pose`): the inliers whose point lies behind a
   camera fit the twisted pair (a symmetric or repeated texture) and go, and a pair whose
   twisted pair explains half as many matches as its pose is ambiguous and not used; a
   pair whose essential matrix fits the mirrored copies alone (more of them than true
   matches, its pose half a turn off, nothing behind a camera) is found by the loops of
   three verified frames: the pair whose relative rotation breaks more loops (by 30
   degrees) than it closes goes, greedily (Zach, Klopschitz & Pollefeys 2010); the
   pairs are the sequential neighbours of a video and, for loop closures, the frames
   farther away whose visual words vote alike (a small vocabulary, k-means of the
   descriptors, tf-idf histograms compared by cosine; Sivic & Zisserman 2003);
4. tracks: the verified matches joined across frames (connected components; one keypoint
   a frame, a component that joins two keypoints of one frame rebuilt greedily);
5. the initial pair: the pair with the most inliers among those with enough parallax
   (median triangulation angle of 2 degrees or more), its relative pose
   (:func:`~imageform.geometry.recover_pose`) and its triangulated points, 30 at least
   (else the next pair, five tried);
6. incremental registration: each next frame's pose from its 2-D/3-D correspondences
   (:func:`~imageform.geometry.solve_pnp_ransac`; the ones it rejects are no views of
   those points), then every track of that frame seen by two registered frames
   triangulated (linear, then Gauss-Newton) when its rays meet at 1.5 degrees or more
   and it reprojects within 4 pixels in front of every camera. A frame with fewer than 12
   PnP inliers waits and is tried again once more frames are registered (as COLMAP
   does); when every frame left has failed since the last registration, the fallbacks
   (a frame whose tracks are short: its pairs below the 30 inliers a verified pair needs,
   a track cut by a frame between): its keypoints in no track matched to the points its
   2 x ``window`` nearest registered frames see (Lowe's ratio, mutual; PnP on both sets,
   12 inliers), else the pose of a verified pair with a registered frame (its rotation
   and translation direction) with the scale that most points reproject from (6 at
   least, a one-point RANSAC) among those that keep the camera within 3 steps of the
   path a frame from the registered frames nearest it in the sequence;
7. bundle adjustment (:func:`bundle_adjust`: Levenberg-Marquardt on the reprojection
   error, the points eliminated by the Schur complement) over everything each time the
   registered frames grew by 40 %, observations beyond 4 pixels dropped, the tracks
   completed (a point's projection lands on a keypoint with a like descriptor: a new
   view; on another point's view: the two tracks merged when the points are one) and
   re-triangulated;
8. at the end: a robust adjustment (Huber), outliers dropped, completion, merging and
   re-triangulation, then adjustments without the observations beyond 2 pixels, the last
   one plain least squares;
9. a model that holds fewer than half the frames (its start in a part of the sequence a
   weak link cuts off): steps 5-8 again from a pair among the frames it left out (the
   keypoints and verified pairs kept), twice at most, and the model with the most frames
   returned, as COLMAP keeps the largest of its models.

Through a lens (``distortion``), every error is measured in the image, where the
keypoints' noise is, through the lens's local linear map at each keypoint: the RANSACs of
steps 3, 5 and 6 run on undistorted pixels with one threshold for a pair or a frame (the
threshold times the median stretch of its keypoints), and each match or correspondence
they refused is judged again on its own (the Sampson distance in image pixels,
``_sampson_image``; the reprojection error in the image, 3 px); the tracks are triangulated
on the errors in the image, and a track one view of which fails the checks loses that view
(its worst), not all (a fisheye's rim is stretched ten to thirty times past the median).

The reconstruction is up to a similarity (a rotation, a translation and a scale): the
first registered frame's camera (frame 0's, when it is registered) is the world frame and
the initial pair's baseline has length 1.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from imageform._colormath import luma_601_matmul
from imageform._typing import ArrayLike
from imageform._validate import as_bool, as_int, as_real, as_real_array, describe
from imageform.errors import DegenerateConfigurationError, InvalidInputError

if TYPE_CHECKING:
    from imageform.geometry.distortion import DistortionModel

__all__ = [
    "Features",
    "Reconstruction",
    "bundle_adjust",
    "detect_features",
    "match_features",
    "reconstruct_sequence",
]

F64 = NDArray[np.float64]

#: A diagnostic's window into :func:`reconstruct_sequence` (benchmarks/check_track_breaks.py):
#: when a dict, each call fills it with its keypoints, the pairs matched and verified, the
#: tracks built and the observations kept and set aside (by what), and each pose the pair-pose
#: fallback weighed (benchmarks/check_pair_pose.py). None: nothing is kept.
_TRACE: dict[str, Any] | None = None

#: The most degrees a verified pair's rotation may differ from the rotation its points give
#: (refined in six degrees of freedom) for the pair's pose to register a frame
#: (``pose_from_pair`` in :func:`reconstruct_sequence`).
_PAIR_POSE_TOL_DEG = 5.0
#: Whether the estimators' inliers are judged again one by one in image pixels through the
#: lens (``_sampson_image``, the pose's reprojection error through ``_image_jacobian``),
#: their RANSAC run with one threshold stretched for the whole set (False: as before
#: 2026-11-30k, for the benchmark's comparison).
_PER_VIEW_INLIERS = True


@dataclass(frozen=True)
class Features:
    """Keypoints and descriptors of one image.

    Attributes
    ----------
    xy : ndarray (N, 2)
        Sub-pixel positions (centre of the top-left pixel at (0, 0)).
    descriptors : ndarray (N, 128) float32
        SIFT descriptors.
    scale, angle : ndarray (N,)
        Keypoint size in pixels and orientation in degrees.
    """

    xy: F64
    descriptors: NDArray[np.float32]
    scale: F64
    angle: F64

    def __len__(self) -> int:
        """How many keypoints."""
        return int(self.xy.shape[0])


def _as_mask(mask: object, shape: tuple[int, ...], name: str) -> NDArray[np.uint8]:
    """Return a detection mask as OpenCV wants it: uint8, 255 where keypoints may be."""
    m = np.asarray(mask)
    if m.ndim == 3 and m.shape[-1] in (1, 3, 4):
        m = m[..., 0]
    if m.shape != tuple(shape[:2]):
        raise InvalidInputError(
            f"expected {name} of the image's size {shape[1]} x {shape[0]} px, got {describe(mask)}"
        )
    if m.dtype.kind not in "biuf":
        raise InvalidInputError(f"expected {name} as booleans or numbers, got {describe(mask)}")
    return np.where(m > 0, 255, 0).astype(np.uint8)


def _as_uint8(values: ArrayLike, dtype: np.dtype, image: ArrayLike) -> NDArray[np.uint8]:
    """Return ``values`` of an image of type ``dtype`` as uint8.

    Integers other than uint8 (a 16-bit PNG or TIFF) span their type's range; floats are in
    [0, 1] when ``image`` has none beyond 1, else in [0, 255].
    """
    v = np.asarray(values, np.float64)
    if dtype == np.uint8:
        gain = 1.0
    elif dtype.kind in "ui":
        gain = 255.0 / float(np.iinfo(dtype).max)
    else:
        gain = 255.0 if dtype.kind == "f" and np.max(image) <= 1.0 else 1.0
    return np.round(np.clip(v * gain, 0, 255)).astype(np.uint8)


def detect_features(
    image: ArrayLike,
    *,
    max_features: int = 4000,
    mask: ArrayLike | None = None,
    max_size: int | None = 3200,
    contrast_threshold: float = 0.04,
    equalize: bool = False,
) -> Features:
    r"""Detect SIFT keypoints and descriptors (OpenCV's SIFT, the ``reconstruct`` extra).

    An image whose longer side exceeds ``max_size`` is first reduced by area averaging to
    that size, by the factor :math:`s = \text{max\_size} / \max(H, W)`, and the keypoints
    are mapped back to the full image, pixel centres to pixel centres:
    :math:`x = (x_s + \tfrac12)/s - \tfrac12`, sizes divided by :math:`s`. SIFT doubles
    its input before the first octave (Lowe 2004, IJCV 60(2), sec. 3.3), so a 24 Mpx
    photograph costs it about 5 GB and a minute, while the keypoints that survive the
    ``max_features`` cut are the coarse, stable ones a reduced image keeps as well; COLMAP
    caps its SIFT input the same way (``SiftExtraction.max_image_size``, 3200;
    Schönberger & Frahm 2016) and OpenSfM too (``feature_process_size``).

    Parameters
    ----------
    image : array_like (H, W), (H, W, 3) or (H, W, 4)
        Grey, RGB or RGBA (the alpha ignored): uint8, other integers over their type's
        range (uint16: 0 to 65535, as a 16-bit PNG or TIFF), or floats in [0, 1] (floats
        beyond 1: in [0, 255]).
    max_features : int
        Keep the strongest this many.
    mask : array_like (H, W), optional
        Where keypoints may be (nonzero or True): the scene that moves with the camera's
        world, without e.g. an endoscope's dark vignetted corners or a static background
        behind a moving object. None: everywhere.
    max_size : int or None
        Longest side, pixels, SIFT sees (at least 64); None: the full image always.
    contrast_threshold : float
        SIFT's contrast threshold (OpenCV's ``contrastThreshold``, Lowe 2004 sec. 4: an
        extremum of the difference of Gaussians weaker than
        :math:`\tfrac12\,\text{contrast\_threshold} / 3` of the grey range is dropped), in
        (0, 1). 0.04, OpenCV's default, suits photographs; the smooth, low-contrast tissue of
        an endoscope's frames keeps a few tens of keypoints with it, and 0.01 ten times as
        many (``benchmarks/check_endo_real.py``).
    equalize : bool
        Equalize the grey levels before SIFT by contrast-limited adaptive histogram
        equalization (CLAHE: Zuiderveld 1994, "Contrast limited adaptive histogram
        equalization", Graphics Gems IV; OpenCV's, tiles of about 64 px: ``round(W / 64)``
        x ``round(H / 64)`` of them, at least one, OpenCV's 8 x 8 on a 512 px image; each
        tile's histogram clipped at twice its mean count and the excess spread over every
        level, the mapping interpolated bilinearly between tiles). The tiles are sized in
        pixels, not as a fraction of the frame: 8 x 8 tiles of a 192 px frame are 24 px,
        and a grey mapping that changes every 24 px, fixed to the image while the tissue
        moves under it, is at the scale of SIFT's own blobs and descriptors (such a
        colonoscope clip made no model with them; it does with 64 px tiles,
        ``benchmarks/results/sfm-pycolmap16-2026-12-01d.md``). An endoscope's light falls off
        from the centre and its tissue is smooth: the dim parts of a frame keep few
        keypoints at one threshold for the whole frame, and each tile's own contrast
        stretched gives them as many as the lit parts (the C3VD frames of tests/data/endo:
        266 -> 936 keypoints, median, at contrast 0.01). False: the grey levels as they
        are.

    Returns
    -------
    Features
        Positions and sizes in the full image's pixels. The first octave is the image
        doubled with pixel ``x`` at ``2x`` exactly (OpenCV's ``enable_precise_upscale``;
        its default puts every keypoint a quarter pixel down and right).
    """
    from imageform._optional import require

    cv2 = require("cv2", what="imageform reconstruct's keypoints (SIFT)")
    n = as_int(max_features, "max_features", minimum=8, maximum=1_000_000)
    cap = None if max_size is None else as_int(max_size, "max_size", minimum=64)
    ct = as_real(contrast_threshold, "contrast_threshold", positive=True, maximum=1.0)
    equalize = as_bool(equalize, "equalize")
    a = np.asarray(image)
    dtype = a.dtype
    if dtype.kind in "uif" and a.ndim == 3 and a.shape[-1] in (3, 4):
        a = luma_601_matmul(np, a[..., :3])  # Rec. 601 luma, float64
    elif a.ndim == 3 and a.shape[-1] == 1:
        a = a[..., 0]
    if a.ndim != 2 or a.size == 0 or dtype.kind not in "uif":
        raise InvalidInputError(
            f"expected image as (H, W), (H, W, 3) or (H, W, 4) numbers, got {describe(image)}"
        )
    if a.dtype != np.uint8:
        a = _as_uint8(a, dtype, a)
    m = None if mask is None else _as_mask(mask, a.shape, "mask")
    h, w = a.shape
    sx = sy = 1.0
    if cap is not None and max(h, w) > cap:
        ws, hs = max(round(w * cap / max(h, w)), 1), max(round(h * cap / max(h, w)), 1)
        a = cv2.resize(a, (ws, hs), interpolation=cv2.INTER_AREA)
        if m is not None:
            m = cv2.resize(m, (ws, hs), interpolation=cv2.INTER_NEAREST)
        sx, sy = w / ws, h / hs
    if equalize:
        # tiles of about 64 px whatever the frame's size (OpenCV's 8 x 8 grid on a 512 px
        # image): 8 x 8 tiles of a 192 px frame are 24 px, and a grey mapping that changes
        # every 24 px, fixed to the image while the tissue moves, is at SIFT's own scale
        tiles = (max(1, round(a.shape[1] / 64)), max(1, round(a.shape[0] / 64)))
        a = cv2.createCLAHE(clipLimit=2.0, tileGridSize=tiles).apply(a)
    # the doubled first octave must map pixel x to 2x: OpenCV's default resize maps it to
    # 2x + 1/2 and every keypoint lands a quarter pixel off, down and right
    sift = cv2.SIFT_create(nfeatures=n, contrastThreshold=ct, enable_precise_upscale=True)
    kps, desc = sift.detectAndCompute(a, m)
    if desc is None or not kps:
        return Features(np.zeros((0, 2)), np.zeros((0, 128), np.float32), np.zeros(0), np.zeros(0))
    xy = np.array([k.pt for k in kps], np.float64)
    if sx != 1.0 or sy != 1.0:
        xy = (xy + 0.5) * np.array([sx, sy]) - 0.5
    return Features(
        xy,
        np.asarray(desc, np.float32),
        np.array([k.size for k in kps], np.float64) * (0.5 * (sx + sy)),
        np.array([k.angle for k in kps], np.float64),
    )


def match_features(
    a: NDArray[np.float32], b: NDArray[np.float32], *, ratio: float = 0.8, mutual: bool = True
) -> NDArray[np.int64]:
    r"""Match descriptors by nearest neighbour, Lowe's ratio test and a mutual check.

    A pair ``(i, j)`` is kept when ``b[j]`` is ``a[i]``'s nearest neighbour with
    :math:`d_1 < \rho\, d_2` (the second nearest clearly farther; Lowe 2004, IJCV 60(2),
    sec. 7.1) and, with ``mutual``, ``a[i]`` is ``b[j]``'s nearest as well. One matrix
    product gives all three (float32): SIFT's descriptors are integers of norm about 512,
    so every squared distance is an exact integer whatever the order of the additions.

    Returns
    -------
    ndarray (M, 2) int64
        Index pairs into ``a`` and ``b``.
    """
    r = as_real(ratio, "ratio", positive=True, maximum=1.0)
    a = as_real_array(a, "a", ndim=2).astype(np.float32)
    b = as_real_array(b, "b", ndim=2).astype(np.float32)
    if a.shape[1] != b.shape[1]:
        raise InvalidInputError(
            f"expected b with the descriptor length of a ({a.shape[1]}), got {b.shape[1]}"
        )
    if a.shape[0] < 2 or b.shape[0] < 2:
        return np.zeros((0, 2), np.int64)
    # squared distances |a|^2 + |b|^2 - 2 a.b from one matrix product: the nearest of each
    # row, its second nearest (the nearest of the rest), and the mutual check's nearest of
    # each column. SIFT's descriptors are integers of norm 512 at most: every sum is an
    # integer below 2^24, exact in float32 whatever the order of the additions
    na, nb = (a * a).sum(1), (b * b).sum(1)
    d2 = a @ b.T
    d2 *= -2.0
    d2 += na[:, None]
    d2 += nb[None, :]
    rows = np.arange(a.shape[0])
    best = np.argmin(d2, axis=1)
    back = np.argmin(d2, axis=0) if mutual else None
    d1 = np.maximum(d2[rows, best], 0.0)
    d2[rows, best] = np.inf
    d2nd = np.maximum(d2.min(axis=1), 0.0)
    keep = d1 < (r * r) * d2nd
    if back is not None:
        keep &= back[best] == rows
    idx = np.flatnonzero(keep)
    return np.column_stack([idx, best[idx]]).astype(np.int64)


@dataclass(frozen=True)
class Reconstruction:
    r"""The result of :func:`reconstruct_sequence`.

    Attributes
    ----------
    R : ndarray (n, 3, 3), t : ndarray (n, 3)
        World to camera poses (NaN for frames not registered); the first registered
        frame's camera (frame 0's when it is registered) is the world frame.
    registered : ndarray (n,) bool
    points : ndarray (P, 3)
        The 3-D points.
    colors : ndarray (P, 3) uint8
        Their colour, from the first frame that saw them.
    track_length : ndarray (P,) int
        How many registered frames see each point.
    rms_px : ndarray (n,)
        Each frame's reprojection RMS (NaN when not registered).
    notes : list of str
        What failed and why (frames that could not be registered, ...), and the frames
        the fallbacks registered and how.
    residuals_px : ndarray (M,)
        The reprojection error of every observation the final bundle adjustment kept
        (pixels; the distance between the observed keypoint and its point's projection).
    K : ndarray (3, 3) or None
        The camera matrix of the final bundle adjustment: the one given, or with its focal
        length refined (``refine_focal``).
    focal_fit_px : float or None
        With ``K`` held: the focal length one more bundle adjustment finds when it refines
        it from the final poses and points (a check of the given ``K``: a note when it
        differs by more than 10 %); None when ``refine_focal`` or fewer than 3 frames.
    distortion : distortion model or None
        The lens of the final bundle adjustment: the one given, or with
        ``refine_distortion`` its radial term refined (``BrownConrady(k1)``, COLMAP's
        ``SIMPLE_RADIAL``, or ``KannalaBrandt(k1)``, the equidistant fisheye with one term,
        where that was tried and kept). With ``K``, the camera to reproject the points into
        the frames.
    focal_sd_px : float or None
        With ``refine_focal``: how well the frames fix the focal length found, its standard
        deviation (pixels; inf where the cost does not rise away from it): the profile of
        the final bundle adjustment's cost in f (f held 10 % either side, every pose, point
        and kept lens term adjusted again; :math:`\sigma_f = f \sqrt{\hat\sigma^2 / a}`,
        :math:`a` the curvature in :math:`\ln f`, :math:`\hat\sigma^2` the residual
        variance), widened by what a reconstruction started again from the camera found
        moved it and, where two lens models both fix f, by half their difference. Over
        10 % of f: a note says the frames do not fix it (inf with fewer than 3 frames
        registered). None when f is held.
    """

    R: F64
    t: F64
    registered: NDArray[np.bool_]
    points: F64
    colors: NDArray[np.uint8]
    track_length: NDArray[np.int64]
    rms_px: F64
    notes: list[str] = field(default_factory=list)
    residuals_px: F64 = field(default_factory=lambda: np.zeros(0))
    K: F64 | None = None
    focal_fit_px: float | None = None
    distortion: DistortionModel | None = None
    focal_sd_px: float | None = None

    @property
    def focal_fixed(self) -> bool | None:
        """Whether the frames fix the focal length found: ``focal_sd_px`` at most 10 % of it.

        None when f is held (``focal_sd_px`` None); the one verdict the notes, ``imageform
        reconstruct``'s summary, report and ``metrics.json`` (``intrinsics.focal_fixed``)
        state.
        """
        if self.focal_sd_px is None:
            return None
        return self.K is not None and bool(self.focal_sd_px <= _FOCAL_FIXED * float(self.K[0, 0]))


#: The focal length's profile (:func:`_reconstruct`'s ``focal_spread``) holds it this share
#: either side of the one found
_FOCAL_PROFILE = 0.1

#: A given focal length is flagged when a bundle adjustment that refines it moves it by more
#: than this share (:func:`reconstruct_sequence`'s note). The check moves only part of the
#: way from the structure built with the given one (the figurine's 523.8 px -> 656.3 px for
#: pycolmap's 1087.4 px, benchmarks/results/sfm-autok-2026-11-30e.md); the true K moves by
#: 2 % at most on the rendered room and Middlebury's temple and dino.
_FOCAL_CHECK = 0.1


def _angle_deg(C1: F64, C2: F64, X: F64) -> F64:
    a, b = X - C1, X - C2
    c = np.sum(a * b, axis=1) / (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1) + 1e-300)
    return np.degrees(np.arccos(np.clip(c, -1.0, 1.0)))


def _behind(K: F64, R: F64, t: F64, p1: F64, p2: F64, min_parallax: float) -> NDArray[np.bool_]:
    r"""Which correspondences of a relative pose lie behind one of the two cameras.

    The depths :math:`\lambda_1, \lambda_2` of the two rays' closest points, from
    :math:`\lambda_2 \tilde x_2 \approx \lambda_1 R \tilde x_1 + t` by least squares
    (normalised coordinates; as :func:`~imageform.geometry.recover_pose`'s cheirality
    test, Hartley & Zisserman 2004, sec. 9.6.3); a correspondence is behind when a depth
    is not positive and its rays are ``min_parallax`` radians apart or more (nearly
    parallel rays, a point near infinity, have a depth of either sign within the noise).
    """
    Ki = np.linalg.inv(K)
    h1 = np.column_stack([p1, np.ones(len(p1))]) @ Ki.T
    h2 = np.column_stack([p2, np.ones(len(p2))]) @ Ki.T
    a = h1 @ R.T
    aa, ab, bb = np.sum(a * a, 1), np.sum(a * h2, 1), np.sum(h2 * h2, 1)
    at, bt = a @ t, h2 @ t
    det = aa * bb - ab * ab
    with np.errstate(divide="ignore", invalid="ignore"):
        z1 = (ab * bt - bb * at) / det
        z2 = (aa * bt - ab * at) / det
        parallax = np.arccos(np.clip(ab / np.sqrt(aa * bb), -1.0, 1.0))
    return ~((z1 > 0) & (z2 > 0)) & (parallax >= min_parallax)


def _pair_pose_disagreement(R: F64, t: F64, X: F64, uv: F64, K: F64) -> float:
    """Return the angle (degrees) between a pose's rotation and the one its points give.

    The fallback pose of :func:`reconstruct_sequence` (``pose_from_pair``) takes its
    rotation from a verified pair's essential matrix and one number, the scale, from the
    points; refined on its inliers ``X`` (3-D, n x 3) / ``uv`` (ideal pixels, n x 2) in all
    six degrees of freedom (Levenberg-Marquardt from ``R``, ``t``: :func:`refine_pose`), the
    points say where the frame faces by themselves. A pair's essential matrix fitted to a
    repeated texture can be turned a few degrees and still, with the scale free, reproject
    a handful of points within the threshold (OpenCV's chessboard views: the pair of frames
    7 and 10, 34 matches, 12.4 degrees off; 11 correspondences, 7 distinct points in two
    bands of the image, within 3.1 px; refined, 13.35 degrees from the pair's rotation
    and 1.18 from the truth: ``benchmarks/check_pair_pose.py``). ``R``, ``t`` are not changed.
    """
    from imageform.geometry.pnp import refine_pose

    Rr, _, _ = refine_pose(  # it refines its input arrays in place: copies
        np.array(R, np.float64)[None],
        np.array(t, np.float64)[None],
        np.ascontiguousarray(X, np.float64)[None],
        np.ascontiguousarray(uv, np.float64)[None],
        np.asarray(K, np.float64),
        np.ones((1, X.shape[0])),
        30,
    )
    c = (np.trace(Rr[0] @ np.asarray(R).T) - 1.0) / 2.0
    return float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))))


def _inconsistent_pairs(
    rot: dict[tuple[int, int], F64],
    tol_deg: float = 30.0,
    support: dict[tuple[int, int], int] | None = None,
) -> list[tuple[int, int]]:
    r"""Find the verified pairs whose relative rotations the loops of three frames contradict.

    For frames :math:`i < j < l` whose three pairs are verified, the rotations close the
    loop, :math:`R_{jl} R_{ij} \approx R_{il}` (``rot[(i, j)]`` maps frame i's camera frame
    to frame j's); a pair whose essential matrix fits the matches of a mirrored texture's
    copies alone (more of them than true matches; in front of its cameras, so no
    cheirality test within the pair can tell) is half a turn off and breaks the loops it
    is in. Greedily, the pair in the most loops off by ``tol_deg`` or more, when those
    are more than the loops it closes, goes; then the loops are counted again (Zach,
    Klopschitz & Pollefeys 2010, loop constraints on relative rotations).

    With ``support`` (each pair's verified matches) a loop counts as much as its weakest
    pair's support, not 1: the copies of a repeated texture can form more loops among
    themselves than the true pairs that bridge them (frames 2-6 and 9-11 of a walk that
    see one photograph on two walls: 10 copy pairs of 67-184 matches against 5 true
    bridges of 267-796), and counted alike the true bridges went and the walk came out in
    two pieces half a turn apart. Weighted, the loops through the well-matched neighbours
    decide (Enqvist, Kahl & Olsson 2011 weight a cycle by its matches likewise).
    """
    keys = set(rot)
    dropped: list[tuple[int, int]] = []
    cos_tol = np.cos(np.radians(tol_deg))
    while True:
        bad: dict[tuple[int, int], float] = dict.fromkeys(keys, 0.0)
        good: dict[tuple[int, int], float] = dict.fromkeys(keys, 0.0)
        frames = sorted({f for key in keys for f in key})
        for i, j in keys:
            for l_ in frames:
                if l_ <= j or (i, l_) not in keys or (j, l_) not in keys:
                    continue
                d = rot[(j, l_)] @ rot[(i, j)] @ rot[(i, l_)].T
                closed = (np.trace(d) - 1.0) / 2.0 > cos_tol
                loop = ((i, j), (j, l_), (i, l_))
                w = 1.0 if support is None else float(min(support.get(q, 0) for q in loop))
                for key in loop:
                    if closed:
                        good[key] += w
                    else:
                        bad[key] += w
        worst = max(keys, key=lambda q: (bad[q] - good[q], q), default=None)
        if worst is None or bad[worst] <= good[worst]:
            return dropped
        keys.discard(worst)
        dropped.append(worst)


def _skew_batch(v: F64) -> F64:
    """Return the cross-product matrices ``[v]x`` of ``(M, 3)`` vectors as ``(M, 3, 3)``."""
    S = np.zeros((v.shape[0], 3, 3))
    S[:, 0, 1], S[:, 0, 2] = -v[:, 2], v[:, 1]
    S[:, 1, 0], S[:, 1, 2] = v[:, 2], -v[:, 0]
    S[:, 2, 0], S[:, 2, 1] = -v[:, 1], v[:, 0]
    return S


def _project_obs(K: F64, R: F64, t: F64, X: F64) -> tuple[F64, F64]:
    r"""Pixels and depths of points ``X`` (M, 3) seen by cameras ``R`` (M, 3, 3), ``t`` (M, 3).

    The module's one projection, :math:`u = \pi(K (R X + t))` with :math:`\pi` the division
    by the third coordinate (NaN where the depth is 0).
    """
    Xc = np.einsum("mij,mj->mi", R, X) + t
    z = Xc[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        uv = (Xc @ K[:2].T) / np.where(z != 0, z, np.nan)[:, None]
    return uv, z


def _project_one(K: F64, R: F64, t: F64, X: F64) -> tuple[F64, F64]:
    """Pixels and depths of points ``X`` (M, 3) seen by one camera ``R`` (3, 3), ``t`` (3,)."""
    Xc = X @ R.T + t
    z = Xc[:, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        uv = (Xc @ K[:2].T) / np.where(z != 0, z, np.nan)[:, None]
    return uv, z


def _radial(K: F64, k1: float, proj: F64) -> tuple[F64, F64, F64, F64]:
    r"""COLMAP's ``SIMPLE_RADIAL`` lens on pinhole pixels ``proj`` (M, 2).

    .. math:: x = K_2^{-1} (p - c), \quad u = c + K_2\, (1 + k_1 \|x\|^2)\, x

    (:math:`K_2` the upper left 2 x 2 of ``K``, :math:`c` its principal point; Schönberger
    & Frahm 2016, COLMAP's ``SimpleRadialCameraModel``). Returns the image pixels ``u``,
    the lens's local linear map :math:`A = K_2 J_d K_2^{-1}` (M, 2, 2) from pinhole to image
    pixels, :math:`J_d = (1 + k_1 r^2) I + 2 k_1 x x^T`, by which the pinhole Jacobians of
    a pose and a point become the image's, and the derivatives of ``u`` by :math:`f_x`
    (``fy`` and the skew scaled alike), :math:`(u - c) / f_x`, and by :math:`k_1`,
    :math:`K_2 x r^2` (each (M, 2)).
    """
    k2 = K[:2, :2]
    c = K[:2, 2]
    x = (proj - c) @ np.linalg.inv(k2).T
    r2 = np.sum(x * x, axis=1)
    d = 1.0 + k1 * r2
    u = c + (x * d[:, None]) @ k2.T
    jd = d[:, None, None] * np.eye(2) + 2.0 * k1 * x[:, :, None] * x[:, None, :]
    A = k2 @ jd @ np.linalg.inv(k2)
    du_df = (u - c) / K[0, 0]
    du_dk = (x * r2[:, None]) @ k2.T
    return u, A, du_df, du_dk


def _equidistant(K: F64, k1: float, proj: F64) -> tuple[F64, F64, F64, F64]:
    r"""Apply the equidistant fisheye with one Kannala-Brandt term to pinhole pixels ``proj``.

    .. math:: x = K_2^{-1} (p - c), \quad \theta = \arctan \|x\|, \quad
              \theta_d = \theta (1 + k_1 \theta^2), \quad
              u = c + K_2\, \frac{\theta_d}{\|x\|}\, x

    (Kannala & Brandt 2006, IEEE TPAMI 28(8), eq. (6), its ``k2 ... k4`` zero; ``k1 = 0``:
    the equidistant lens :math:`r_d = f \theta`; ``KannalaBrandt(k1)``). Returns what
    :func:`_radial` does: the image pixels, the local map :math:`A = K_2 J_d K_2^{-1}`,
    :math:`J_d = s I + (\theta_d' / (1 + r^2) - s)\, x x^T / r^2` (:math:`s = \theta_d / r`,
    :math:`\theta_d' = 1 + 3 k_1 \theta^2`), and the derivatives of ``u`` by :math:`f_x`
    and by :math:`k_1`, :math:`K_2 (\theta^3 / r)\, x`.
    """
    k2 = K[:2, :2]
    c = K[:2, 2]
    x = (proj - c) @ np.linalg.inv(k2).T
    r = np.sqrt(np.sum(x * x, axis=1))
    small = ~(r > 1e-9)
    rs = np.where(small, 1.0, r)
    th = np.arctan(r)
    td = th * (1.0 + k1 * th * th)
    s = np.where(small, 1.0, td / rs)
    u = c + (x * s[:, None]) @ k2.T
    coef = np.where(small, 0.0, ((1.0 + 3.0 * k1 * th * th) / (1.0 + r * r) - s) / rs**2)
    jd = s[:, None, None] * np.eye(2) + coef[:, None, None] * x[:, :, None] * x[:, None, :]
    A = k2 @ jd @ np.linalg.inv(k2)
    du_df = (u - c) / K[0, 0]
    du_dk = (x * np.where(small, 0.0, th**3 / rs)[:, None]) @ k2.T
    return u, A, du_df, du_dk


#: The largest radial term :func:`_schur_lm` takes, as its displacement at the farthest
#: view, :math:`|k_1| r_{max}^2`: beyond 1/3 a barrel term folds the image back on itself
#: (:math:`d(r (1 + k_1 r^2)) / dr = 1 + 3 k_1 r^2`), and well before it the term trades
#: against the focal length and the depths.
_RADIAL_MAX = 0.3


def _sum_blocks(idx: NDArray[np.int64], blocks: F64, n: int) -> F64:
    """Sum of the ``blocks`` (M, ...) that share an index, as (n, ...)."""
    shape = blocks.shape[1:]
    size = int(np.prod(shape))
    flat = (idx[:, None] * size + np.arange(size)).ravel()
    out = np.bincount(flat, weights=blocks.reshape(-1), minlength=n * size)
    # (bincount of nothing is int64 zeros even with weights: float, as blocks are)
    return out.astype(np.float64, copy=False).reshape((n, *shape))


def _huber(r2: F64, delta: float) -> tuple[float, F64]:
    """Huber's cost of residual norms ``sqrt(r2)`` and its IRLS weights (0: least squares)."""
    if delta <= 0:
        return float(0.5 * r2.sum()), np.ones_like(r2)
    r = np.sqrt(r2)
    inside = r <= delta
    cost = float(np.sum(np.where(inside, 0.5 * r2, delta * (r - 0.5 * delta))))
    return cost, np.where(inside, 1.0, delta / np.maximum(r, 1e-300))


def _camera_pairs(
    cam: NDArray[np.int64],
    pt: NDArray[np.int64],
    nc: int,
    npt: int,
    chunk: int = 65536,
    kernel: bool | None = None,
) -> Callable[[F64, F64], F64]:
    r"""Return a function of the views' blocks ``Y``, ``W`` (M, 6, 3) giving :math:`\sum Y W^T`.

    The reduced camera system's :math:`W V^{-1} W^T` (6 ``nc``, 6 ``nc``), with
    :math:`Y_o = W_o V_p^{-1}` for view ``o`` of point ``p``: its block of cameras
    :math:`(c, d)` is :math:`\sum Y_a W_b^T` over the views ``a`` in ``c`` and ``b`` in ``d``
    of one point. The pairs of views are listed once, here for every call (the structure
    does not change between Levenberg-Marquardt's steps): a point's views in camera order,
    :math:`k (k + 1) / 2` pairs for a point of ``k`` views, one half of the symmetric
    matrix, the other half the transposes. ``cam`` and ``pt`` (M,): each view's camera and
    point. The numba kernel (``imageform._kernels.bundle``) sums them where numba runs
    (``kernel`` None: :func:`imageform._backend.use_numba`), else array products, ``chunk``
    pairs at a time.
    """
    from imageform._backend import use_numba

    M = cam.size
    order = np.lexsort((cam, pt))  # by point, then camera
    cnt = np.bincount(pt, minlength=npt)
    st = np.concatenate([[0], np.cumsum(cnt)]).astype(np.int64)
    if use_numba(cam) if kernel is None else kernel:
        from imageform._kernels.bundle import reduce_cameras

        views, cam64 = order.astype(np.int64), np.ascontiguousarray(cam, np.int64)

        def compiled(Y: F64, W: F64) -> F64:
            S = np.zeros((6 * nc, 6 * nc))
            reduce_cameras(
                np.ascontiguousarray(Y, np.float64),
                np.ascontiguousarray(W, np.float64),
                st,
                views,
                cam64,
                nc,
                S,
            )
            return S

        return compiled
    ps = pt[order]
    rank = np.arange(M) - st[ps]
    # the view at rank r of a point of k views pairs with the ranks r .. k - 1 of its point
    reps = cnt[ps] - rank
    total = int(reps.sum())
    a_pos = np.repeat(np.arange(M), reps)
    b_pos = a_pos + np.arange(total) - np.repeat(np.cumsum(reps) - reps, reps)
    pa, pb = order[a_pos], order[b_pos]
    key = cam[pa] * nc + cam[pb]
    by = np.argsort(key, kind="stable")
    pa, pb, key = pa[by], pb[by], key[by]
    # two views of one point in one camera (a track that holds a frame twice): the pair's
    # block and its transpose both fall on the diagonal block
    twin = (pa != pb) & (cam[pa] == cam[pb])
    bounds = [*range(0, total, chunk), total]
    lower = np.tril(np.ones((nc, nc), bool), -1)

    def reduced(Y: F64, W: F64) -> F64:
        S = np.zeros((nc * nc, 6, 6))
        for lo, hi in itertools.pairwise(bounds):
            blocks = np.matmul(Y[pa[lo:hi]], W[pb[lo:hi]].transpose(0, 2, 1))
            tw = twin[lo:hi]
            if tw.any():
                blocks[tw] += blocks[tw].transpose(0, 2, 1)
            k = key[lo:hi]
            first = np.flatnonzero(np.concatenate([[True], k[1:] != k[:-1]]))
            S[k[first]] += np.add.reduceat(blocks, first, axis=0)
        S4 = S.reshape(nc, nc, 6, 6)
        S4[lower] = S4.transpose(1, 0, 3, 2)[lower]
        return np.ascontiguousarray(S4.transpose(0, 2, 1, 3)).reshape(6 * nc, 6 * nc)

    return reduced


def _schur_lm(
    K: F64,
    R: F64,
    t: F64,
    X: F64,
    ci: NDArray[np.int64],
    pi: NDArray[np.int64],
    uv: F64,
    fixed: NDArray[np.bool_],
    delta: float,
    max_iter: int,
    ftol: float = 1e-10,
    A: F64 | None = None,
    kernel: bool | None = None,
    focal: bool = False,
    radial: float | None = None,
    refine_radial: bool = True,
    fisheye: bool = False,
) -> tuple[F64, F64, F64, F64, float]:
    r"""Levenberg-Marquardt on the reprojection error, the points eliminated (Schur complement).

    Each camera moves by a rotation :math:`\exp([\omega]_\times) R` and a translation
    :math:`t + \delta t`, each point by :math:`X + \delta X`. The damped normal equations

    .. math:: \begin{pmatrix} U & W \\ W^T & V \end{pmatrix}
              \begin{pmatrix} \delta c \\ \delta p \end{pmatrix} =
              \begin{pmatrix} g_c \\ g_p \end{pmatrix}

    (``V`` block diagonal, one 3 x 3 block a point) are solved by the reduced camera system
    :math:`(U - W V^{-1} W^T)\, \delta c = g_c - W V^{-1} g_p`, dense and small, then
    :math:`\delta p = V^{-1} (g_p - W^T \delta c)` (Triggs et al. 2000, "Bundle adjustment:
    a modern synthesis", sec. 6.1). Huber's loss by iterative reweighting; Marquardt's
    damping (the diagonal scaled by ``1 + lambda``). Cameras with ``fixed`` set stay.
    ``A`` (M, 2, 2), optional: each observation's residual and Jacobian are mapped by it
    (the lens's local linear map from undistorted to image pixels: the error is measured in
    the image, where the keypoint's noise is, not where a fisheye stretches it).

    The normal equations and the reduced camera system are summed view by view by numba
    kernels (``imageform._kernels.bundle``) where numba runs (``kernel`` None:
    :func:`imageform._backend.use_numba`), else by array operations: the same sums in
    another order.

    ``focal``: the focal length is refined too, one for every camera (COLMAP's default
    for a camera whose focal length was guessed): ``fx``, ``fy`` and the skew scale
    together (their ratios stay), the principal point stays. Its derivative is
    :math:`\partial u / \partial f_x = (u - c) / f_x`.

    ``radial`` (a float, the starting :math:`k_1`): the views ``uv`` are image pixels of
    COLMAP's ``SIMPLE_RADIAL`` lens, :math:`u = c + K_2 (1 + k_1 r^2) x` (:func:`_radial`),
    and its one radial term is refined, one for every camera (``A`` must be None: the lens
    is the model's, its local map recomputed at each step); bounded by
    :math:`|k_1| r_{max}^2 \le 0.3`, :math:`r_{max}` the farthest view's normalised radius
    (``refine_radial`` False: the lens held at ``radial``). ``fisheye``: the lens is the
    equidistant fisheye with one Kannala-Brandt term instead (:func:`_equidistant`), the
    same bound on :math:`|k_1| \theta_{max}^2`.
    Each refined intrinsic adds one row and column to the reduced camera system (its
    coupling with each camera's 6 parameters and with each point's 3, summed in NumPy
    beside the kernels). Returns ``R``, ``t``, ``X``, ``K`` (the refined camera matrix;
    ``K`` itself without ``focal``) and :math:`k_1` (0 without ``radial``).
    """
    from scipy.linalg import cho_factor, cho_solve

    from imageform._backend import use_numba
    from imageform.geometry.rotations import rvec_to_matrix

    if radial is not None and A is not None:
        raise ValueError("radial and A are exclusive")  # pragma: no cover
    n, m, M = R.shape[0], X.shape[0], ci.size
    slot = -np.ones(n, np.int64)
    free = np.flatnonzero(~np.asarray(fixed, bool))
    slot[free] = np.arange(free.size)
    nf = free.size
    cs = slot[ci]
    has = cs >= 0
    csh, pih = cs[has], pi[has]
    eye3, eye6 = np.eye(3), np.eye(6)
    refine_k1 = radial is not None and refine_radial
    ni = int(focal) + int(refine_k1)  # the intrinsics refined
    # W V^-1 W^T, the blocks summed over the points two free cameras share: laid out once
    if kernel is None:
        kernel = use_numba(X)
    reduced = _camera_pairs(csh, pih, nf, m, kernel=kernel)
    Mh = csh.size
    if kernel:
        from imageform._kernels.bundle import normal_equations

        K = np.ascontiguousarray(K, np.float64)
        ci, pi = np.ascontiguousarray(ci, np.int64), np.ascontiguousarray(pi, np.int64)
        cs = np.ascontiguousarray(cs, np.int64)
        hpos = np.where(has, np.cumsum(has) - 1, -1).astype(np.int64)
        A_k = np.zeros((0, 2, 2)) if A is None else np.ascontiguousarray(A, np.float64)
    if radial is not None:  # the farthest view's normalised radius, squared: the bound
        xo = (uv - K[:2, 2]) @ np.linalg.inv(K[:2, :2]).T
        r2max = float(np.max(np.sum(xo * xo, axis=1), initial=0.0))
        k1_max = _RADIAL_MAX / max(r2max, 1e-12)

    def gram(A: F64, B: F64) -> F64:
        """Return the blocks :math:`A_m^T B_m` of two (M, 2, k) stacks."""
        return np.matmul(A.transpose(0, 2, 1), B)

    def evaluate(
        R: F64, t: F64, X: F64, K: F64, k1: float
    ) -> tuple[F64, F64, float, F64, F64 | None, F64]:
        """Residuals, their squares, the cost, the weights, the lens's map and d/d(f, k1)."""
        proj, z = _project_obs(K, R[ci], t[ci], X[pi])
        lensmap = A
        Ji = np.zeros((M, 2, ni))
        if radial is not None:
            proj, lensmap, du_df, du_dk = (_equidistant if fisheye else _radial)(K, k1, proj)
            if focal:
                Ji[:, :, 0] = du_df
            if refine_k1:
                Ji[:, :, -1] = du_dk
        elif focal:
            # d(u, v) / d fx with fy and the skew scaled alike: (u - c) / fx
            Ji[:, :, 0] = (proj - K[:2, 2]) / K[0, 0]
            if A is not None:
                Ji[:, :, 0] = np.einsum("mij,mj->mi", A, Ji[:, :, 0])
        r = proj - uv
        if A is not None:
            r = np.einsum("mij,mj->mi", A, r)
        r2 = np.sum(r * r, axis=1)
        bad = ~((z > 0) & np.isfinite(r2))
        r = np.where(bad[:, None], 0.0, r)
        r2 = np.where(bad, 0.0, r2)
        Ji[bad] = 0.0
        cost, w = _huber(r2, delta)
        w[bad] = 0.0
        if lensmap is not None and radial is not None:
            lensmap = np.where(np.isfinite(lensmap), lensmap, 0.0)
        return r, r2, cost + 1e6 * float(bad.sum()), w, lensmap, Ji

    def jacobians(R: F64, t: F64, X: F64, K: F64, lensmap: F64 | None) -> tuple[F64, F64]:
        """Return each view's d/dX (M, 2, 3) and d/d(omega, t) of the free (Mh, 2, 6)."""
        fx, fy, sk = K[0, 0], K[1, 1], K[0, 1]
        RX = np.einsum("mij,mj->mi", R[ci], X[pi])
        Xc = RX + t[ci]
        z = np.where(np.abs(Xc[:, 2]) > 1e-9, Xc[:, 2], 1e-9)
        Jp = np.zeros((M, 2, 3))  # d(u, v) / d Xc
        Jp[:, 0, 0] = fx / z
        Jp[:, 0, 1] = sk / z
        Jp[:, 0, 2] = -(fx * Xc[:, 0] + sk * Xc[:, 1]) / z**2
        Jp[:, 1, 1] = fy / z
        Jp[:, 1, 2] = -fy * Xc[:, 1] / z**2
        if lensmap is not None:
            Jp = lensmap @ Jp
        Jx = Jp @ R[ci]  # d/dX
        Jc = np.concatenate([-Jp @ _skew_batch(RX), Jp], axis=2)[has]  # d/d(omega, t)
        return Jx, Jc

    R, t, X, K = R.copy(), t.copy(), X.copy(), np.array(K, np.float64)
    k1 = 0.0 if radial is None else float(radial)
    res, _, cost, w, lensmap, Ji = evaluate(R, t, X, K, k1)
    lam = 1e-3
    gain = 0.0
    for _ in range(max_iter):
        if kernel:
            U, V = np.zeros((nf, 6, 6)), np.zeros((m, 3, 3))
            gc, gp, Wo = np.zeros((nf, 6)), np.zeros((m, 3)), np.empty((Mh, 6, 3))
            Ak = A_k if radial is None else np.ascontiguousarray(lensmap, np.float64)
            normal_equations(K, R, t, X, ci, pi, cs, hpos, res, w, Ak, U, V, gc, gp, Wo)
            if ni:
                Jx, Jc = jacobians(R, t, X, K, lensmap)
        else:
            Jx, Jc = jacobians(R, t, X, K, lensmap)
            wJx = Jx * w[:, None, None]
            V = _sum_blocks(pi, gram(wJx, Jx), m)
            gp = _sum_blocks(pi, -(wJx[:, 0] * res[:, :1] + wJx[:, 1] * res[:, 1:]), m)
            wJc = Jc * w[has, None, None]
            U = _sum_blocks(csh, gram(wJc, Jc), nf)
            rh = res[has]
            gc = _sum_blocks(csh, -(wJc[:, 0] * rh[:, :1] + wJc[:, 1] * rh[:, 1:]), nf)
            Wo = gram(wJc, Jx[has])  # (Mh, 6, 3)
        if ni:  # the intrinsics' rows: with themselves, each free camera, each point
            wJi = Ji * w[:, None, None]
            Uii = np.einsum("mki,mkj->ij", wJi, Ji)
            gi = -np.einsum("mki,mk->i", wJi, res)
            Uci = _sum_blocks(csh, gram(Jc, wJi[has]), nf)  # (nf, 6, ni)
            Wi = _sum_blocks(pi, gram(Jx, wJi), m)  # (m, 3, ni)
        dV = np.diagonal(V, axis1=1, axis2=2)
        dU = np.diagonal(U, axis1=1, axis2=2)
        improved = False
        while lam < 1e10:
            Vinv = np.linalg.inv(V + (lam * dV + 1e-12)[:, :, None] * eye3)
            Y = Wo @ Vinv[pih]  # (Mh, 6, 3)
            S = -reduced(Y, Wo)
            S4 = S.reshape(nf, 6, nf, 6)
            ar = np.arange(nf)
            S4[ar, :, ar, :] += U + (lam * dU + 1e-12)[:, :, None] * eye6
            b = gc - _sum_blocks(csh, np.einsum("mij,mj->mi", Y, gp[pih]), nf)
            if ni:
                VWi = Vinv @ Wi  # V^-1 Wi, a point at a time (m, 3, ni)
                col = (Uci - _sum_blocks(csh, Y @ Wi[pih], nf)).reshape(6 * nf, ni)
                corner = Uii + np.diag(lam * np.diag(Uii) + 1e-12)
                corner -= np.einsum("mji,mjk->ik", Wi, VWi)
                S = np.block([[S, col], [col.T, corner]])
                b = np.append(b.ravel(), gi - np.einsum("mji,mj->i", VWi, gp))
            try:
                dc = cho_solve(cho_factor(S, check_finite=False), b.ravel(), check_finite=False)
            except np.linalg.LinAlgError:
                lam *= 10.0
                continue
            K1, k11 = K, k1
            gpf = gp
            if ni:
                di, dc = dc[-ni:], dc[:-ni]
                if focal:
                    if not K[0, 0] + di[0] > 0:
                        lam *= 8.0
                        continue
                    K1 = K.copy()
                    K1[:2, :2] *= (K[0, 0] + di[0]) / K[0, 0]
                if refine_k1:
                    k11 = k1 + float(di[-1])
                    if not abs(k11) <= k1_max:
                        lam *= 8.0
                        continue
                gpf = gp - Wi @ di
            dc6 = dc.reshape(nf, 6)
            wtdc = _sum_blocks(pih, np.einsum("mji,mj->mi", Wo, dc6[csh]), m)
            dp = np.einsum("mij,mj->mi", Vinv, gpf - wtdc)
            R1, t1 = R.copy(), t.copy()
            if nf:
                R1[free] = np.asarray(rvec_to_matrix(dc6[:, :3]), np.float64) @ R[free]
                t1[free] = t[free] + dc6[:, 3:]
            X1 = X + dp
            res1, _, cost1, w1, map1, Ji1 = evaluate(R1, t1, X1, K1, k11)
            if cost1 < cost:
                gain = (cost - cost1) / max(cost, 1e-300)
                R, t, X, K, k1, res, cost, w = R1, t1, X1, K1, k11, res1, cost1, w1
                lensmap, Ji = map1, Ji1
                lam = max(lam / 5.0, 1e-9)
                improved = True
                break
            lam *= 8.0
        if not improved or gain < ftol:
            break
    return R, t, X, K, k1


def bundle_adjust(
    K: F64,
    R: F64,
    t: F64,
    points: F64,
    cam_idx: NDArray[np.int64],
    pt_idx: NDArray[np.int64],
    uv: F64,
    *,
    fixed: int = 0,
    loss_px: float = 2.0,
    max_nfev: int = 50,
) -> tuple[F64, F64, F64]:
    r"""Refine poses and points together by minimising the reprojection error.

    .. math:: \min_{R_i, t_i, X_j} \sum_{(i, j)} \rho\left(\left\| u_{ij} -
              \pi\left(K (R_i X_j + t_i)\right) \right\|\right)

    with :math:`\rho` Huber's loss at ``loss_px`` pixels (Triggs et al. 2000, "Bundle
    adjustment: a modern synthesis"). Levenberg-Marquardt with the points eliminated: each
    step solves the small dense reduced camera system (the Schur complement of the points'
    3 x 3 blocks), then the points one by one (Triggs et al. sec. 6.1); the rotations are
    updated multiplicatively, :math:`R \leftarrow \exp([\omega]_\times) R`. The camera
    ``fixed`` stays where it is, and so does the scale, which the first pose does not fix:
    the damping keeps the other cameras' distance to it where the points put it.

    Parameters
    ----------
    K : ndarray (3, 3)
    R : ndarray (n, 3, 3), t : ndarray (n, 3)
        Initial poses (world to camera) of the cameras observed.
    points : ndarray (P, 3)
    cam_idx, pt_idx : ndarray (M,)
        Which camera and which point each observation is.
    uv : ndarray (M, 2)
        The observed (undistorted) pixels.
    fixed : int
        The camera held fixed (the gauge).
    loss_px : float
        Huber's threshold, pixels; 0 for plain least squares (once outliers are gone).
    max_nfev : int
        Most Levenberg-Marquardt iterations.

    Returns
    -------
    R, t, points
        Refined.
    """
    k = as_real_array(K, "K", ndim=2)
    R = as_real_array(R, "R", ndim=3).astype(np.float64)
    t = as_real_array(t, "t", ndim=2).astype(np.float64)
    points = as_real_array(points, "points", ndim=2).astype(np.float64)
    obs = as_real_array(uv, "uv", ndim=2)
    n, m = R.shape[0], points.shape[0]
    if k.shape != (3, 3) or R.shape[1:] != (3, 3) or t.shape != (n, 3) or points.shape[1] != 3:
        raise InvalidInputError(
            f"expected K (3, 3), R (n, 3, 3), t (n, 3), points (P, 3), got K {k.shape}, "
            f"R {R.shape}, t {t.shape}, points {points.shape}"
        )
    ci, pi = np.asarray(cam_idx), np.asarray(pt_idx)
    if obs.shape[1:] != (2,) or ci.shape != obs.shape[:1] or pi.shape != obs.shape[:1]:
        raise InvalidInputError(
            f"expected cam_idx (M,), pt_idx (M,) and uv (M, 2), got {describe(cam_idx)}, "
            f"{describe(pt_idx)} and {describe(uv)}"
        )
    for name, idx, size in (("cam_idx", ci, n), ("pt_idx", pi, m)):
        if idx.size and (idx.dtype.kind not in "iu" or idx.min() < 0 or idx.max() >= size):
            raise InvalidInputError(
                f"expected {name} as integers in [0, {size}), got {describe(idx)}"
            )
    f = as_int(fixed, "fixed", minimum=0, maximum=max(n - 1, 0))
    keep = np.zeros(n, bool)
    keep[f] = True
    Rb, tb, Xb, *_ = _schur_lm(
        k,
        R,
        t,
        points,
        ci.astype(np.int64),
        pi.astype(np.int64),
        obs,
        keep,
        float(loss_px),
        as_int(max_nfev, "max_nfev", minimum=1, maximum=100_000),
    )
    return Rb, tb, Xb


def _triangulate_tracks(
    K: F64,
    R: F64,
    t: F64,
    frame: NDArray[np.int64],
    col: NDArray[np.int64],
    uv: F64,
    m: int,
    lens: F64 | None = None,
) -> F64:
    r"""Points ``m`` from observations (frame, which point, pixel): DLT, then Gauss-Newton.

    Each observation gives two rows :math:`x P^3 - P^1`, :math:`y P^3 - P^2` of the linear
    system of its point (normalised coordinates :math:`K^{-1} u`, each row of unit norm);
    the point is the eigenvector of :math:`A^T A`'s smallest eigenvalue (Hartley &
    Zisserman 2004, sec. 12.2), then three Gauss-Newton steps on the reprojection error.
    ``lens`` (M, 2, 2): each observation's map from undistorted to image pixels
    (:func:`_image_jacobian`); the errors are then measured in the image, where the
    keypoints' noise is (the maximum-likelihood point): each Gauss-Newton residual and
    its Jacobian multiplied by it, each observation's DLT rows divided by its stretch
    (:func:`_magnification`). Without it the undistorted pixels weigh alike, and a
    fisheye's rim view, its noise stretched ten to thirty times, pulls the point off the
    other views.
    """
    Ki = np.linalg.inv(K)
    xn = uv @ Ki[:2, :2].T + Ki[:2, 2]
    Pm = np.concatenate([R[frame], t[frame][:, :, None]], axis=2)  # (M, 3, 4)
    rows = np.stack(
        [xn[:, :1] * Pm[:, 2] - Pm[:, 0], xn[:, 1:2] * Pm[:, 2] - Pm[:, 1]], axis=1
    )  # (M, 2, 4)
    rows /= np.maximum(np.linalg.norm(rows, axis=2, keepdims=True), 1e-300)
    if lens is not None:
        mag = _magnification(lens)
        rows /= np.where(np.isfinite(mag) & (mag > 0), mag, 1.0)[:, None, None]
    A = _sum_blocks(col, np.einsum("mki,mkj->mij", rows, rows), m)
    A += 1e-300 * np.eye(4)
    _, vec = np.linalg.eigh(A)
    Xh = vec[:, :, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        X = Xh[:, :3] / Xh[:, 3:4]
    X[~np.isfinite(X).all(axis=1)] = np.nan
    fx, fy, sk = K[0, 0], K[1, 1], K[0, 1]
    for _ in range(3):
        Rm = R[frame]
        Xc = np.einsum("mij,mj->mi", Rm, X[col]) + t[frame]
        z = np.where(np.abs(Xc[:, 2]) > 1e-9, Xc[:, 2], 1e-9)
        r = (
            np.column_stack(
                [fx * Xc[:, 0] / z + sk * Xc[:, 1] / z + K[0, 2], fy * Xc[:, 1] / z + K[1, 2]]
            )
            - uv
        )
        Jp = np.zeros((col.size, 2, 3))
        Jp[:, 0, 0] = fx / z
        Jp[:, 0, 1] = sk / z
        Jp[:, 0, 2] = -(fx * Xc[:, 0] + sk * Xc[:, 1]) / z**2
        Jp[:, 1, 1] = fy / z
        Jp[:, 1, 2] = -fy * Xc[:, 1] / z**2
        J = Jp @ Rm
        if lens is not None:
            r = np.einsum("mij,mj->mi", lens, r)
            J = lens @ J
        H = _sum_blocks(col, np.einsum("mki,mkj->mij", J, J), m) + 1e-12 * np.eye(3)
        g = _sum_blocks(col, np.einsum("mki,mk->mi", J, r), m)
        ok = np.isfinite(H).all(axis=(1, 2)) & np.isfinite(g).all(axis=1)
        step = np.zeros((m, 3))
        try:
            step[ok] = np.linalg.solve(H[ok], -g[ok][:, :, None])[:, :, 0]
        except np.linalg.LinAlgError:
            break
        X = X + step
    return X


def _similar_pairs(
    descriptors: list[NDArray[np.float32]], window: int, per_frame: int, seed: int
) -> list[tuple[int, int]]:
    r"""Loop-closure candidates: frame pairs beyond ``window`` whose visual words vote alike.

    A small vocabulary (k-means of a sample of the descriptors, 256 words) makes each frame
    a histogram of words weighted by tf-idf, normalised; the similarity of two frames is
    the cosine of their histograms (Sivic & Zisserman 2003, "Video Google", ICCV). Each
    frame proposes its ``per_frame`` most similar frames farther than ``window`` away.
    """
    n = len(descriptors)
    if per_frame <= 0 or n <= window + 1:
        return []
    gen = np.random.default_rng(seed)
    pool = np.concatenate([d for d in descriptors if d.shape[0]]).astype(np.float32)
    sample = pool[gen.choice(pool.shape[0], min(pool.shape[0], 10_000), replace=False)]
    words = min(256, max(8, sample.shape[0] // 20))
    # Lloyd's k-means, the distances by one matrix product an iteration
    c = sample[gen.choice(sample.shape[0], words, replace=False)].copy()
    for _ in range(8):
        label = np.argmin((c * c).sum(1)[None, :] - 2.0 * (sample @ c.T), axis=1)
        cnt = np.bincount(label, minlength=words)
        sums = np.zeros_like(c)
        np.add.at(sums, label, sample)
        moved = cnt > 0
        c[moved] = sums[moved] / cnt[moved, None]
    cc = (c * c).sum(1)
    hist = np.zeros((n, words))
    for f, d in enumerate(descriptors):
        if d.shape[0]:
            label = np.argmin(cc[None, :] - 2.0 * (d @ c.T), axis=1)
            hist[f] = np.bincount(label, minlength=words)
    idf = np.log(n / np.maximum((hist > 0).sum(0), 1))
    h = hist / np.maximum(hist.sum(1, keepdims=True), 1) * idf
    h /= np.maximum(np.linalg.norm(h, axis=1, keepdims=True), 1e-300)
    sim = h @ h.T
    out: set[tuple[int, int]] = set()
    for i in range(n):
        far = np.abs(np.arange(n) - i) > window
        cand = np.flatnonzero(far)
        for j in cand[np.argsort(-sim[i, cand])[:per_frame]]:
            out.add((min(i, int(j)), max(i, int(j))))
    return sorted(out)


def _build_tracks(
    offset: NDArray[np.int64], edges: NDArray[np.int64]
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Join matched keypoints (global ids) into tracks with one keypoint a frame at most.

    Connected components of the match graph; a component with two keypoints of one frame
    (two points joined by a wrong match) is rebuilt greedily, a union refused when the two
    parts share a frame. Returns each node's track (-1: none) and the number of tracks.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    total = int(offset[-1])
    if edges.shape[0] == 0:
        return -np.ones(total, np.int64), np.zeros(0, np.int64)
    g = coo_matrix((np.ones(edges.shape[0]), (edges[:, 0], edges[:, 1])), shape=(total, total))
    _, label = connected_components(g, directed=False)
    frame_of = np.searchsorted(offset, np.arange(total), side="right") - 1
    size = np.bincount(label)
    # components with a frame twice
    key = label.astype(np.int64) * (frame_of.max() + 1) + frame_of
    uk, cnt = np.unique(key, return_counts=True)
    bad = np.zeros(size.size, bool)
    bad[uk[cnt > 1] // (frame_of.max() + 1)] = True
    label = label.astype(np.int64)
    if bad.any():
        parent: dict[int, int] = {}
        frames: dict[int, set[int]] = {}

        def find(x: int) -> int:
            while parent[x] != x:
                parent[x] = parent[parent[x]]
                x = parent[x]
            return x

        next_label = int(size.size)
        for a, b in edges[bad[label[edges[:, 0]]]].tolist():
            for x in (a, b):
                if x not in parent:
                    parent[x] = x
                    frames[x] = {int(frame_of[x])}
            ra, rb = find(a), find(b)
            if ra == rb or frames[ra] & frames[rb]:
                continue
            parent[rb] = ra
            frames[ra] |= frames.pop(rb)
        roots: dict[int, int] = {}
        for x in parent:
            r = find(x)
            if r not in roots:
                roots[r] = next_label
                next_label += 1
            label[x] = roots[r]
    keep = np.bincount(label)[label] >= 2
    label = np.where(keep, label, -1)
    _, track = np.unique(label[keep], return_inverse=True)
    out = -np.ones(total, np.int64)
    out[keep] = track
    return out, np.bincount(track)


def _image_jacobian(k: F64, distortion: DistortionModel | None, uv: F64) -> F64:
    r"""Return the lens's local linear map from undistorted to image pixels, (N, 2, 2).

    :math:`A = K_2\, J_d(\hat x)\, K_2^{-1}`, :math:`J_d` the Jacobian of the distortion at
    the undistorted normalised point :math:`\hat x` (central differences, step
    :math:`10^{-6}`), :math:`K_2` the upper left 2 x 2 of ``K``: an error :math:`\delta` in
    undistorted pixels is :math:`A \delta` in the image. The identity without distortion
    and where the point is not finite.
    """
    n = uv.shape[0]
    out = np.broadcast_to(np.eye(2), (n, 2, 2)).copy()
    if distortion is None or n == 0:
        return out
    k2 = k[:2, :2]
    k2i = np.linalg.inv(k2)
    xn = (uv - k[:2, 2]) @ k2i.T
    fin = np.all(np.isfinite(xn), axis=1)
    h = 1e-6
    cols = []
    for e in (np.array([h, 0.0]), np.array([0.0, h])):
        plus = np.asarray(distortion.distort(xn[fin] + e), np.float64)
        minus = np.asarray(distortion.distort(xn[fin] - e), np.float64)
        cols.append((plus - minus) / (2 * h))
    jd = np.stack(cols, axis=2)  # (m, 2, 2): d distorted / d undistorted
    a = k2 @ jd @ k2i
    good = np.all(np.isfinite(a), axis=(1, 2))
    out[np.flatnonzero(fin)[good]] = a[good]
    return out


def _magnification(A: F64) -> F64:
    """How much the undistortion stretches a pixel (area), ``1 / sqrt(|det A|)``."""
    det = np.abs(A[:, 0, 0] * A[:, 1, 1] - A[:, 0, 1] * A[:, 1, 0])
    with np.errstate(divide="ignore"):
        return np.asarray(1.0 / np.sqrt(det), np.float64)


def _sampson_image(E: F64, K: F64, p1: F64, p2: F64, A1: F64, A2: F64) -> F64:
    r"""Return the Sampson distances of correspondences in image pixels, (N,).

    ``p1``, ``p2``: undistorted pixels; ``A1``, ``A2`` (N, 2, 2): the lens's local map from
    undistorted to image pixels at each (:func:`_image_jacobian`). With
    :math:`F = K^{-T} E K^{-1}` and the gradients :math:`g_1 = (F^T x_2)_{1:2}`,
    :math:`g_2 = (F x_1)_{1:2}` of the epipolar residual :math:`x_2^T F x_1` in undistorted
    pixels, an isotropic unit noise in the image moves that residual by the variance
    :math:`\|A_1^{-T} g_1\|^2 + \|A_2^{-T} g_2\|^2`: the first-order distance
    :math:`|x_2^T F x_1| / \sqrt{\cdot}` is the image pixels' Sampson distance (Hartley &
    Zisserman 2004, sec. 4.2.6, with each point's covariance :math:`A^{-1} A^{-T}`). The
    pinhole's (``A`` the identity) is the usual one.
    """
    Ki = np.linalg.inv(K)
    F = Ki.T @ E @ Ki
    Fx1 = p1 @ F[:, :2].T + F[:, 2]
    Ftx2 = p2 @ F[:2, :] + F[2, :]
    num = np.sum(p2 * Fx1[:, :2], -1) + Fx1[:, 2]
    with np.errstate(all="ignore"):
        g1 = np.linalg.solve(np.swapaxes(A1, 1, 2), Ftx2[:, :2, None])[:, :, 0]
        g2 = np.linalg.solve(np.swapaxes(A2, 1, 2), Fx1[:, :2, None])[:, :, 0]
        d = np.abs(num) / np.sqrt(np.sum(g1 * g1, 1) + np.sum(g2 * g2, 1))
    return np.asarray(np.where(np.isfinite(d), d, np.inf), np.float64)


def _homography_hint(
    pair_info: dict[tuple[int, int], tuple[int, float, NDArray[np.int64]]],
    ideal: list[F64],
    pair: tuple[int, int],
    threshold_px: float,
    rng: int,
) -> str:
    """Say whether the best pair's matches fit one homography: a pan, or one plane.

    Two views related by a homography (a camera turned about its centre, or a plane) are
    the planar or panoramic case of COLMAP's two-view geometry: 80 % of the essential
    matrix's inliers within the same error of one homography (Schönberger & Frahm 2016).
    """
    from imageform.geometry.robust import find_homography

    a, b = pair
    m = pair_info[pair][2]
    try:
        res = find_homography(
            ideal[a][m[:, 0]], ideal[b][m[:, 1]], threshold=2.0 * threshold_px, rng=rng
        )
        share = float(np.mean(res.inliers))
    except (DegenerateConfigurationError, InvalidInputError):
        share = 0.0
    if share < 0.8:
        return ""
    return (
        f"{share:.0%} of the matches of frames {a} and {b} fit one homography: the camera "
        "turned about its centre without moving (a pan) or moved too little, or the scene is "
        "one plane; "
    )


def _undistorted(xy: F64, k: F64, distortion: DistortionModel | None) -> F64:
    """Return the ideal pinhole pixels of image pixels ``xy`` (NaN where none), (N, 2)."""
    if distortion is None or len(xy) == 0:
        return np.array(xy, np.float64)
    xn = (xy - k[:2, 2]) / np.diag(k)[:2]
    und, ok = distortion.undistort(xn)
    und = np.asarray(und, np.float64)
    und[~np.asarray(ok, bool)] = np.nan
    return np.asarray(und * np.diag(k)[:2] + k[:2, 2], np.float64)


def _simple_radial(k1: float, fisheye: bool = False) -> DistortionModel:
    """COLMAP's ``SIMPLE_RADIAL`` lens as imageform's: ``BrownConrady(k1)``.

    ``fisheye``: the equidistant fisheye with one term, ``KannalaBrandt(k1)``.
    """
    from imageform.geometry.distortion import BrownConrady, KannalaBrandt

    return KannalaBrandt(k1=float(k1)) if fisheye else BrownConrady(k1=float(k1))


def _is_fisheye(distortion: DistortionModel | None) -> bool:
    """Whether the lens is a Kannala-Brandt fisheye."""
    from imageform.geometry.distortion import KannalaBrandt

    return isinstance(distortion, KannalaBrandt)


def _radial_start(distortion: DistortionModel | None) -> float:
    """Return the radial term ``refine_distortion`` starts from: the lens's k1, 0 for none.

    ``BrownConrady`` with k1 alone (COLMAP's ``SIMPLE_RADIAL``), or ``KannalaBrandt`` with
    k1 alone (the equidistant fisheye and one term: :func:`_fisheye_tried`).
    """
    from imageform.geometry.distortion import BrownConrady, KannalaBrandt

    if distortion is None:
        return 0.0
    if isinstance(distortion, BrownConrady | KannalaBrandt) and not any(distortion.coeffs[1:]):
        return float(distortion.k1)
    raise InvalidInputError(
        "refine_distortion refines one radial term k1 (COLMAP's SIMPLE_RADIAL, or the "
        "equidistant fisheye's): expected no distortion, or BrownConrady or KannalaBrandt "
        f"with k1 alone, got {distortion!r}"
    )


#: ``refine_distortion``: the radial term is refined once this many frames are registered
#: and this many points triangulated (two views leave it free to trade against the depths)
_RADIAL_MIN_FRAMES = 4
_RADIAL_MIN_POINTS = 100

#: ``refine_distortion``: a radial term whose displacement at the image's corner,
#: :math:`|\Delta k_1| r_c^2`, moves by more than this share of the corner's radius starts
#: the reconstruction again from the lens found (as ``_FOCAL_RESTART`` for f)
_RADIAL_RESTART = 0.01

#: ``refine_distortion``: the radial term found is kept when it lowers the final sum of
#: squared reprojection errors by this share at least, against the one given (0 for none)
#: held (``choose_lens`` in :func:`_reconstruct`)
_RADIAL_GAIN = 0.02


def reconstruct_sequence(
    images: Sequence[ArrayLike],
    K: ArrayLike,
    distortion: DistortionModel | None = None,
    *,
    window: int = 3,
    max_features: int = 4000,
    ratio: float = 0.8,
    threshold_px: float = 1.0,
    rng: int = 0,
    masks: ArrayLike | Sequence[ArrayLike | None] | None = None,
    contrast_threshold: float = 0.04,
    refine_focal: bool = False,
    refine_distortion: bool = False,
    equalize: bool = False,
    overlays: bool = True,
) -> Reconstruction:
    r"""Reconstruct the cameras and a sparse point cloud from an ordered image sequence.

    Parameters
    ----------
    images : list of array_like
        The frames, in order (a video's), all of one size.
    K : array_like (3, 3)
        The camera's intrinsics.
    distortion : distortion model, optional
        Its lens distortion: keypoints are undistorted before any geometry.
    window : int
        Each frame is matched with the next ``window`` frames (and with the frames farther
        away that its visual words make look alike, each verified geometrically).
    max_features : int
        SIFT keypoints per frame.
    ratio : float
        Lowe's ratio.
    threshold_px : float
        The essential matrix's inlier threshold (Sampson distance, pixels).
    rng : int
        Seed of the RANSAC samplers.
    masks : array_like (H, W) or sequence of them, optional
        Where keypoints may be (nonzero): one mask for every frame (an endoscope's
        vignetting) or one a frame (an object that moves in front of a static background;
        only what moves rigidly with the scene may be kept). None: everywhere.
    contrast_threshold : float
        SIFT's contrast threshold (:func:`detect_features`): 0.01 for endoscopic tissue.
    refine_focal : bool
        Refine the focal length in the bundle adjustments of every registered frame once
        three are registered, and in the final one (one focal length for every frame, the
        principal point and the aspect ratio kept: COLMAP's default for a focal length it
        guessed); when it moves by more than 5 %, the reconstruction starts again from
        the one found (twice at most: the first frames were registered with a wrong one).
        Else ``K`` is held, and checked: one more bundle adjustment that
        refines the focal length from the final poses and points, a note when it moves
        by more than 10 % (the result's ``focal_fit_px``). The result's ``K`` is the one
        found, its standard deviation the result's ``focal_sd_px``; where that is over
        10 % of f, a note says the frames do not fix it (a camera that moves without
        turning: scaling f and the sideways parts of the points and translations together
        changes no image), and the f found is no measurement.
    refine_distortion : bool
        Refine one radial distortion term shared by every frame, COLMAP's
        ``SIMPLE_RADIAL`` lens (its default for a camera it does not know, with
        ``refine_focal``):

        .. math:: u = c + f\,(1 + k_1 r^2)\, x, \quad r^2 = \|x\|^2

        (:math:`x` the normalised pinhole coordinates; ``BrownConrady(k1)``), from the
        ``distortion`` given (None: :math:`k_1 = 0`; any other lens than ``BrownConrady``
        with k1 alone is refused), in the bundle adjustments once 4 frames and 100 points
        are registered, and in the final one; bounded by :math:`|k_1| r_{max}^2 \le 0.3`
        (:math:`r_{max}` the farthest keypoint's radius). Each time it moves, every keypoint
        is undistorted again with the lens found (the pairs, PnP and the triangulation use
        it); when its displacement at the image's corner moves by more than 1 % of the
        corner's radius, the reconstruction starts again from it (as for ``refine_focal``).
        The result's ``distortion`` is the one found. Then it is checked by one more
        reconstruction with k1 held at the one given (f refined alone, with
        ``refine_focal``): when the camera ran off (k1 at 90 % of its bound or f moved by a
        factor 3: a fisheye) that one is returned, or, when its f ran off too, one with f
        and k1 held; when the term was kept and frames are left out, the one with k1 held
        is returned if it registers more frames. A note says so.

        Without a lens given (``distortion`` None) and with ``refine_focal``, where the
        camera ran off, or its term is barrel and at half its bound or more on the
        keypoints, the equidistant fisheye is tried too, one more reconstruction from
        ``KannalaBrandt()`` (:math:`r_d = f \theta`, :math:`\theta` the ray's angle to the
        axis; Kannala & Brandt 2006, eq. (6)), f refined from the one whose field across
        the image's larger side is 140 degrees (or the one given, when shorter) and one
        Kannala-Brandt term :math:`\theta_d = \theta (1 + k_1 \theta^2)` refined and kept
        by the same 2 % test; it is returned (``distortion`` a ``KannalaBrandt`` with k1
        alone) when it registers as many frames or more, its camera did not run off, and
        the tracks of both models cost it no more: each track triangulated with each
        model's cameras held, every view's squared reprojection error in the image capped
        at 2 px (a view it cannot explain at the cap), plus GRIC's :math:`\ln(2n)` per
        lens parameter (Torr 1998; Torr & Zisserman 2000); but where the frames fix one
        lens's f and not the other's (``focal_sd_px`` over 10 % of f), the one that fixes
        it is returned when it registers as many frames: on 8 to 13 frames the two costs
        swing with the keypoints and the seed (C3VD: ``SIMPLE_RADIAL``'s f from 292 to 913
        px, the fisheye's 187 to 221; ``benchmarks/results/sfm-model-choice-2026-12-01e.md``).
        A note says what was tried, the two costs, each f and its standard deviation and
        what was chosen. The fisheye is also tried where ``SIMPLE_RADIAL``'s f is not fixed.
        ``distortion`` given as ``KannalaBrandt`` with k1 alone: that lens's term is the
        one refined.
    equalize : bool
        Each frame's grey levels equalized by CLAHE before SIFT (:func:`detect_features`):
        for an endoscope, whose light falls off from the centre: more points on the C3VD
        clip and the colonoscope clips (``benchmarks/results/sfm-pycolmap16-2026-12-01d.md``),
        but poses that move against a run without it (no truth says which is nearer) and,
        without a camera, a focal length the frames do not fix: with a camera given,
        checked against a run without it.
    overlays : bool
        Leave out the keypoints on what stands still in the image while the camera moves
        (:func:`imageform.geometry.still_mask`: burned-in text, an icon, an aperture's
        rim, grown by 8 px) when no ``masks`` are given (given, they say where keypoints
        may be; :func:`field_of_view_mask` takes the overlays out of an endoscope's
        aperture). A keypoint there matches the same place in every frame, and a frame
        of another scene that carries the same overlay matches the sequence there only
        (its letters match along the text's lines: a translation an essential matrix
        fits). A note says how much of the frame was left out. Nothing is left out where
        nothing stands still, from fewer than 8 frames, or where the camera did not move.

    Returns
    -------
    Reconstruction
        One model. When the first holds fewer than half the frames, another is started
        among the frames it left out (twice at most) and the one with the most frames is
        returned; its notes say so.

    Raises
    ------
    InvalidInputError
        Fewer than two frames, frames of different sizes.
    DegenerateConfigurationError
        No pair of frames with enough matches and parallax to start from, or none whose
        pose triangulates 30 points (five pairs tried).
    """
    refine_focal = as_bool(refine_focal, "refine_focal")
    refine_distortion = as_bool(refine_distortion, "refine_distortion")
    cache: dict[str, Any] = {}
    kw: dict[str, Any] = {
        "window": window,
        "max_features": max_features,
        "ratio": ratio,
        "threshold_px": threshold_px,
        "rng": rng,
        "masks": masks,
        "contrast_threshold": contrast_threshold,
        "equalize": as_bool(equalize, "equalize"),
        "overlays": as_bool(overlays, "overlays"),
        "refine_focal": refine_focal,
        "refine_distortion": refine_distortion,
        # refused before the keypoints: a lens it cannot refine
        "radial_given": _radial_start(distortion) if refine_distortion else None,
        "cache": cache,
    }
    if not (refine_focal or refine_distortion):
        return _one_model(images, K, distortion, kw)
    best = _self_calibrated(images, K, distortion, kw)
    if not refine_distortion:
        return _focal_said(best, K)
    f_given = float(np.asarray(K, np.float64)[0, 0])
    feats = cache.get("feats")
    why = _ran_off(best, f_given, feats)
    checked = _radial_checked(images, K, distortion, kw, best)
    if distortion is not None or not refine_focal:
        return _focal_said(checked, K)
    if why is None:  # a strong barrel term, at half its bound or more: a fisheye's sign
        k1 = _radial_start(best.distortion)
        share = 0.0 if feats is None else _radial_share(best, feats)
        if checked.focal_sd_px is not None and not checked.focal_fixed:
            # another lens may fix f where this one does not
            why = f"SIMPLE_RADIAL's {_sd_said(checked)}: not fixed by the frames"
        elif not (k1 < 0 and share >= _FISHEYE_HINT) or checked is not best:
            return _focal_said(checked, K)
        else:
            why = f"k1 = {k1:.3f}, {100 * share:.0f} % of its bound on the keypoints"
    else:
        why = f"SIMPLE_RADIAL ran off: {why}"
    return _focal_said(_fisheye_tried(images, K, kw, checked, why), K)


def _focal_said(rec: Reconstruction, K: ArrayLike) -> Reconstruction:
    """``rec`` with one verdict on its focal length: fixed by the frames or not.

    The verdict is ``focal_sd_px`` against ``_FOCAL_FIXED`` alone (``metrics.json``'s
    ``intrinsics.focal_fixed``). Where the last restart still moved f by ``_FOCAL_RESTART``
    or more (:func:`_self_calibrated`'s ``_STILL_MOVED`` note), that move, already one of
    the standard deviation's terms (:func:`_with_spread`), is said within the verdict, not
    as a verdict of its own: the note is folded into it, whichever way it goes.
    """
    if rec.K is None or rec.focal_sd_px is None:
        return rec
    moved = next((n for n in rec.notes if n.startswith(_STILL_MOVED)), None)
    notes = [n for n in rec.notes if n is not moved]
    if rec.focal_fixed:
        if moved is None:
            return rec
        note = (
            f"the focal length is fixed by the frames: {_sd_said(rec)}, at most "
            f"{100 * _FOCAL_FIXED:.0f} %, though {moved}: that move is counted in its "
            "standard deviation"
        )
        return replace(rec, notes=[*notes, note])
    f0 = float(np.asarray(K, np.float64)[0, 0])
    note = (
        f"the focal length is not fixed by the frames: {_sd_said(rec)} (more than "
        f"{100 * _FOCAL_FIXED:.0f} %; started from {f0:.1f} px"
        + ("" if moved is None else f"; {moved}")
        + "): the scale of the points across the view is not known; calibrate the camera "
        "and give it, or more frames that turn"
    )
    return replace(rec, notes=[*notes, note])


def _self_calibrated(
    images: Sequence[ArrayLike],
    K: ArrayLike,
    distortion: DistortionModel | None,
    kw: dict[str, Any],
) -> Reconstruction:
    """One model whose focal length (and lens) are refined, restarted from the camera found.

    The focal length (or the lens) moved far from where it started: the first frames were
    registered with a wrong one (and some not at all); again from the one found, twice at
    most (:func:`reconstruct_sequence`'s ``refine_focal`` and ``refine_distortion``).
    """
    refine_distortion = bool(kw["refine_distortion"])
    cache = kw["cache"]
    cache.pop("pairs", None)  # verified with another camera, perhaps; the keypoints stay
    best = _one_model(images, K, distortion, kw)
    if not (kw["refine_focal"] or refine_distortion):
        return best
    K_start = np.array(K, np.float64)
    lens_start = distortion
    h, w = np.asarray(images[0]).shape[:2]
    said: list[str] = []

    def moved(rec: Reconstruction) -> tuple[float, float, float, float, bool, bool]:
        """(f and k1 started from, f and k1 found, whether each moved past its threshold)."""
        assert rec.K is not None
        start, found = float(K_start[0, 0]), float(rec.K[0, 0])
        k1_start = _radial_start(lens_start) if refine_distortion else 0.0
        k1_found = _radial_start(rec.distortion) if refine_distortion else 0.0
        # the corner's normalised radius, squared: where the radial term moves most
        c = rec.K[:2, 2]
        rc2 = max((x - c[0]) ** 2 + (y - c[1]) ** 2 for x in (0, w - 1) for y in (0, h - 1))
        lens_moved = abs(k1_found - k1_start) * rc2 / found**2
        f_far = abs(found / start - 1) >= _FOCAL_RESTART
        return start, found, k1_start, k1_found, f_far, lens_moved >= _RADIAL_RESTART

    restarted: float | None = None  # the last restart's f: started from, found
    for _ in range(2):
        start, found, k1_start, k1_found, f_far, lens_far = moved(best)
        if not (f_far or lens_far):
            break
        K1 = K_start.copy()
        K1[:2, :2] *= found / start
        lens1 = best.distortion if refine_distortion else distortion
        cache.pop("pairs", None)  # verified with the other K; the keypoints stay
        try:
            again = _one_model(images, K1, lens1, kw)
        except DegenerateConfigurationError:
            break
        f_again = float(again.K[0, 0]) if again.K is not None else found
        restarted = found - f_again  # two reconstructions, from two cameras
        if refine_distortion:
            k1_again = _radial_start(again.distortion)
            note = (
                f"the camera moved from f = {start:.1f} px, k1 = {k1_start:.3f} to "
                f"f = {found:.1f} px, k1 = {k1_found:.3f}: reconstructed again from them, "
                f"found f = {f_again:.1f} px, k1 = {k1_again:.3f}"
            )
        else:
            note = (
                f"the focal length moved from {start:.1f} px to {found:.1f} px: "
                f"reconstructed again from {found:.1f} px, found {f_again:.1f} px"
            )
        if int(again.registered.sum()) < int(best.registered.sum()):
            best = replace(best, notes=[*best.notes, note + ", fewer frames: not kept"])
            break
        said.append(note)
        best = replace(again, notes=[*again.notes, *said])
        K_start, lens_start = K1, lens1
    else:  # two restarts and the camera still moves
        start, found, k1_start, k1_found, f_far, lens_far = moved(best)
        still: list[str] = []
        if f_far:  # f's part: said within its one verdict (_focal_said), sd widened by it
            still.append(
                f"{_STILL_MOVED} from {start:.1f} to {found:.1f} px "
                f"({100 * (found / start - 1):+.1f} %)"
            )
        if lens_far:  # the lens's: k1 alone, f's verdict is _focal_said's
            still.append(
                f"the lens did not settle: the last reconstruction moved k1 from "
                f"{k1_start:.3f} to {k1_found:.3f}: one radial term does not fit the frames "
                "(a lens beyond it, a fisheye?); calibrate the camera and give it"
            )
        best = replace(best, notes=[*best.notes, *still])
    return _with_spread(best, restarted)


def _with_spread(rec: Reconstruction, d: float | None, half: bool = False) -> Reconstruction:
    r"""Return ``rec`` with ``focal_sd_px`` widened by the difference ``d`` of two f found.

    The profile's :math:`\sigma_p` (``_reconstruct``'s ``focal_spread``) holds the tracks,
    the registration and the lens model fixed. A reconstruction started from another
    camera registers and triangulates anew, and where the frames do not fix f it lands
    elsewhere (C3VD's 13 frames: 466, 288, 422 px, the profile's 41 px): the last restart's
    two focal lengths (the one it started from, found by the reconstruction before, and
    the one it found, kept or not) are two draws, their sample variance :math:`d^2 / 2`
    added: :math:`\sigma_f = \sqrt{\sigma_p^2 + d^2 / 2}`. ``half``: ``d`` is the
    difference between the f of two lens models, weighed alike (a model average's
    between-model variance, :math:`(d / 2)^2`; Hoeting et al. 1999, "Bayesian model
    averaging", Statist. Sci. 14(4), eq. 2).
    """
    if rec.K is None or rec.focal_sd_px is None or d is None:
        return rec
    var = d * d / (4.0 if half else 2.0)
    return replace(rec, focal_sd_px=float(np.sqrt(rec.focal_sd_px**2 + var)))


#: ``refine_distortion``: the camera ran off when the radial term reached this share of its
#: bound (:math:`|k_1| r_{max}^2 \ge 0.9 \cdot 0.3`, :math:`r_{max}` the farthest keypoint's
#: normalised radius) or the focal length moved by this factor or more from the one given
_RUNOFF_BOUND = 0.9
_RUNOFF_FACTOR = 3.0


def _radial_share(rec: Reconstruction, feats: Sequence[Features]) -> float:
    """Return the radial term's share of its bound, :math:`|k_1| r_{max}^2 / 0.3`.

    ``r_max``: the farthest keypoint's normalised radius in the registered frames (0
    without a term).
    """
    if rec.K is None or rec.distortion is None:
        return 0.0
    f = float(rec.K[0, 0])
    k1 = _radial_start(rec.distortion)
    reg = np.flatnonzero(rec.registered).tolist()
    xy = np.concatenate([feats[i].xy for i in reg]) if reg else np.zeros((0, 2))
    r2 = float(np.max(np.sum(((xy - rec.K[:2, 2]) / f) ** 2, axis=1), initial=0.0))
    return abs(k1) * r2 / _RADIAL_MAX


def _ran_off(rec: Reconstruction, f_given: float, feats: Sequence[Features] | None) -> str | None:
    """Why the camera of ``rec`` ran off (k1 at its bound, f moved a factor 3), or None.

    A lens that one radial term does not fit (a fisheye) lets f and k1 slide along their
    valley (the C3VD colonoscope from 537.6 px: f 2487 px, k1 -17.8, its working camera's f
    199 px), f far from any camera the frames were taken with. ``feats``: the keypoints
    (the bound is on their farthest radius, :func:`_schur_lm`); None: f alone is checked. A
    camera that did not settle but stayed within the factor is no run-off: its last move
    is said with f's verdict (:func:`_focal_said`), the lens's in a note of its own
    (:func:`_self_calibrated`).
    """
    if rec.K is None:
        return None
    f = float(rec.K[0, 0])
    k1 = _radial_start(rec.distortion) if rec.distortion is not None else 0.0
    why: list[str] = []
    if feats is not None and k1 != 0.0:
        share = _radial_share(rec, feats)
        if share >= _RUNOFF_BOUND:
            why.append(
                f"k1 = {k1:.3f} at its bound (|k1| r_max^2 = {share * _RADIAL_MAX:.3f}, "
                f"{_RADIAL_MAX:g} allowed)"
            )
    if max(f / f_given, f_given / f) >= _RUNOFF_FACTOR:
        why.append(f"f = {f:.1f} px, {f / f_given:.2f} times the {f_given:.1f} px given")
    return "; ".join(why) or None


def _radial_checked(
    images: Sequence[ArrayLike],
    K: ArrayLike,
    distortion: DistortionModel | None,
    kw: dict[str, Any],
    best: Reconstruction,
) -> Reconstruction:
    """Check the radial term ``refine_distortion`` found against holding it.

    Two failures are caught by a reconstruction with k1 held at the one given (f refined
    alone, with ``refine_focal``):

    - the camera ran off (:func:`_ran_off`): the one with k1 held is kept when it does not
      run off itself, else f and k1 are both held at the ones given;
    - the term kept cost frames: fitted from a model of a few frames it moves the points
      and the keypoints (a phone's JPEGs, corrected already: k1 +0.039, 8.4 % lower error)
      and a frame whose PnP held 12 inliers of 14 holds 4; when the model with k1 held
      registers more frames, it is kept.

    Each is said in a note of the model returned.
    """
    k1_given = _radial_start(distortion)
    k1_found = _radial_start(best.distortion) if best.distortion is not None else 0.0
    f_given = float(np.asarray(K, np.float64)[0, 0])
    feats = kw["cache"].get("feats")
    why = _ran_off(best, f_given, feats)
    costs = k1_found != k1_given and not bool(best.registered.all())
    if why is None and not costs:
        return best
    assert best.K is not None
    n, nreg = len(images), int(best.registered.sum())
    found = f"f = {float(best.K[0, 0]):.1f} px, k1 = {k1_found:.4f}, {nreg} of {n} frames"
    held_kw = {**kw, "refine_distortion": False, "radial_given": None}
    try:
        held: Reconstruction | None = _self_calibrated(images, K, distortion, held_kw)
    except DegenerateConfigurationError:
        held = None
    if why is None:  # the term kept: does it cost frames?
        if held is None or int(held.registered.sum()) <= nreg:
            return best
        assert held.K is not None
        note = (
            f"the radial term cost frames: with it {found}; held at k1 = {k1_given:.4f} "
            f"(f refined alone: {float(held.K[0, 0]):.1f} px) {int(held.registered.sum())} "
            "frames: held"
        )
        return replace(held, notes=[*held.notes, note])
    said = f"the camera ran off ({found}: {why})"
    held_why = None if held is None else _ran_off(held, f_given, None)
    if held is not None and held_why is None:
        assert held.K is not None
        note = (
            f"{said}: k1 held at {k1_given:.4f}, f refined alone: "
            f"{float(held.K[0, 0]):.1f} px, {int(held.registered.sum())} of {n} frames"
        )
        return replace(held, notes=[*held.notes, note])
    fixed_kw = {**held_kw, "refine_focal": False}
    kw["cache"].pop("pairs", None)
    try:
        fixed = _one_model(images, K, distortion, fixed_kw)
    except DegenerateConfigurationError:
        return replace(best, notes=[*best.notes, said + ": kept (nothing else registers)"])
    note = (
        f"{said}; f refined alone ran off too"
        + ("" if held is None or held.K is None else f" (f = {float(held.K[0, 0]):.1f} px)")
        + f": f and k1 held at the ones given ({f_given:.1f} px, {k1_given:.4f}), "
        f"{int(fixed.registered.sum())} of {n} frames; calibrate the camera and give it"
    )
    return replace(fixed, notes=[*fixed.notes, note])


#: The fisheye tried when ``SIMPLE_RADIAL`` ran off starts from the focal length whose
#: equidistant field across the image's larger side is this many degrees (an endoscope's
#: 140 to 170), or from the one given when that is shorter (:func:`_fisheye_tried`)
_FISHEYE_FIELD_DEG = 140.0

#: The fisheye is tried where ``SIMPLE_RADIAL``'s barrel term reached this share of its
#: bound on the keypoints (:math:`|k_1| r_{max}^2 \ge 0.5 \cdot 0.3`)
_FISHEYE_HINT = 0.5

#: The model choice's robust cost caps a view's squared reprojection error at this many
#: pixels, squared: the final adjustment's outlier limit (:func:`_track_cost`)
_TRACK_CAP_PX = 2.0


def _tracks_of(cache: dict[str, Any], rec: Reconstruction) -> tuple[NDArray[np.int64], ...] | None:
    """Return the views ``rec`` kept, (frame, keypoint, point) each, as ``_reconstruct`` did."""
    for res, fr, kp, pid in cache.get("tracks", []):
        if res is rec.residuals_px:
            return fr, kp, pid
    return None


def _track_cost(
    rec: Reconstruction,
    feats: Sequence[Features],
    tracks: Sequence[tuple[NDArray[np.int64], ...]],
) -> tuple[float, int]:
    r"""Return the robust cost of ``tracks`` seen through ``rec``'s cameras, and its views.

    Each track (the keypoints, frame by frame, one model took for one point) is
    triangulated from its views in the frames ``rec`` registered, with ``rec``'s poses,
    focal length and lens held (:func:`_triangulate_tracks` on the keypoints undistorted
    by that lens), and every view costs its squared reprojection error in the image,
    capped at :math:`T^2` (``_TRACK_CAP_PX``, the final filter's 2 px):

    .. math:: C = \sum_{\text{views}} \min(e^2, T^2)

    a view in a frame ``rec`` did not register, or of a track with fewer than two views
    there, costs :math:`T^2`. The truncated quadratic of MSAC and MLESAC (Torr & Zisserman
    2000, "MLESAC", CVIU 78(1)) and of the robust term of GRIC (Torr 1998, "Geometric
    motion segmentation and model selection", Phil. Trans. R. Soc. A 356): on one set of
    data for every model compared, an outlier counted at its cap, not left out as a
    median of the views each model kept leaves it.
    """
    assert rec.K is not None
    K = np.asarray(rec.K, np.float64)
    lens = rec.distortion
    cap = _TRACK_CAP_PX**2
    fr = np.concatenate([t[0] for t in tracks]).astype(np.int64)
    kp = np.concatenate([t[1] for t in tracks]).astype(np.int64)
    shift = np.cumsum([0] + [int(t[2].max(initial=-1)) + 1 for t in tracks])
    col = np.concatenate([t[2] + shift[j] for j, t in enumerate(tracks)]).astype(np.int64)
    m, total = int(shift[-1]), fr.size
    if total == 0:
        return 0.0, 0
    xy = np.zeros((total, 2))
    for f in np.unique(fr).tolist():
        at = fr == f
        xy[at] = feats[f].xy[kp[at]]
    uv = _undistorted(xy, K, lens)
    use = rec.registered[fr] & np.all(np.isfinite(uv), axis=1)
    views = np.bincount(col[use], minlength=m)
    use &= views[col] >= 2
    sel = np.flatnonzero(use)
    fs, cs = fr[sel], col[sel]
    X = _triangulate_tracks(K, rec.R, rec.t, fs, cs, uv[sel], m)
    # then Gauss-Newton on the errors in the image (the lens's local map A at each view),
    # as the bundle adjustment weighs them: a fisheye's rim is not the pinhole's
    A = _image_jacobian(K, lens, uv[sel])
    Rm = rec.R[fs]
    for _ in range(3):
        Xc = np.einsum("mij,mj->mi", Rm, X[cs]) + rec.t[fs]
        z = np.where(np.abs(Xc[:, 2]) > 1e-9, Xc[:, 2], 1e-9)
        r = np.einsum("mij,mj->mi", A, (Xc / z[:, None]) @ K[:2].T - uv[sel])
        Jp = np.zeros((cs.size, 2, 3))
        Jp[:, 0, 0], Jp[:, 0, 1] = K[0, 0] / z, K[0, 1] / z
        Jp[:, 0, 2] = -(K[0, 0] * Xc[:, 0] + K[0, 1] * Xc[:, 1]) / z**2
        Jp[:, 1, 1], Jp[:, 1, 2] = K[1, 1] / z, -K[1, 1] * Xc[:, 1] / z**2
        J = A @ Jp @ Rm
        H = _sum_blocks(cs, np.einsum("mki,mkj->mij", J, J), m) + 1e-12 * np.eye(3)
        g = _sum_blocks(cs, np.einsum("mki,mk->mi", J, r), m)
        ok = np.isfinite(H).all(axis=(1, 2)) & np.isfinite(g).all(axis=1)
        step = np.zeros((m, 3))
        step[ok] = np.linalg.solve(H[ok], -g[ok][:, :, None])[:, :, 0]
        X = X + step
    proj, z = _project_obs(K, rec.R[fs], rec.t[fs], X[cs])
    if lens is not None:  # the lens on the normalised coordinates, as _undistorted
        k2 = np.diag(K)[:2]
        proj = np.asarray(lens.distort((proj - K[:2, 2]) / k2), np.float64) * k2 + K[:2, 2]
    d = proj - xy[sel]
    e2 = np.sum(d * d, axis=1)
    e2[~((z > 0) & np.isfinite(e2))] = cap
    return float(np.sum(np.minimum(e2, cap)) + cap * (total - sel.size)), total


def _fisheye_tried(
    images: Sequence[ArrayLike],
    K: ArrayLike,
    kw: dict[str, Any],
    checked: Reconstruction,
    why: str,
) -> Reconstruction:
    r"""Try the equidistant fisheye where COLMAP's ``SIMPLE_RADIAL`` ran off (no lens given).

    An endoscope's lens (140 to 170 degrees) is no pinhole with one radial term: f and k1
    slide along their valley (:func:`_ran_off`). One more reconstruction with the
    equidistant fisheye, :math:`r_d = f \theta` (``KannalaBrandt()``), f refined, and one
    Kannala-Brandt term :math:`k_1` refined and kept only where it lowers the squared
    reprojection error by 2 % (``choose_lens``); kept when it registers as many frames as
    ``checked`` (the model :func:`_radial_checked` returned) or more, its own camera did not
    run off (f a factor 3 from where it started, k1 at 90 % of its bound), and on one set
    of data, the tracks either model kept, its robust cost is no higher:

    .. math:: C_m = \sum_{\text{views}} \min(e_m^2, T^2) + k_m \ln(2n) \sigma^2

    (:func:`_track_cost`: each track triangulated with model :math:`m`'s cameras held,
    :math:`e_m` its views' errors in the image, :math:`T` = 2 px, :math:`n` the views,
    :math:`k_m` the lens parameters refined, f and the term where kept, :math:`\sigma` =
    1 px): the robust term of Torr's GRIC ("Geometric motion segmentation and model
    selection", Phil. Trans. R. Soc. A 356, 1998) and MSAC's truncated quadratic (Torr &
    Zisserman, "MLESAC", CVIU 78(1), 2000), with its penalty for parameters. The median
    error of the views each model kept is no such measure: a model's own filter leaves
    out what it cannot explain (the 2 px filter left both at 0.54 px on C3VD). Each model
    is fitted to its own tracks and judged on the other's too, as on held-out data. Also
    tried where ``SIMPLE_RADIAL`` did not run off but its term is barrel and at half its
    bound or more on the keypoints (``_FISHEYE_HINT``). ``why``: what made it tried, for
    the note.
    """
    from imageform.geometry.distortion import KannalaBrandt

    k_fish = np.array(K, np.float64)
    h, w = np.asarray(images[0]).shape[:2]
    f_field = max(w, h) / np.radians(_FISHEYE_FIELD_DEG)  # r_d = f theta at half the field
    k_fish[:2, :2] *= min(1.0, f_field / float(k_fish[0, 0]))
    f_start = float(k_fish[0, 0])
    fish_kw = {**kw, "radial_given": 0.0}
    try:
        fish = _self_calibrated(images, k_fish, KannalaBrandt(), fish_kw)
    except DegenerateConfigurationError:
        return replace(checked, notes=[*checked.notes, "the fisheye tried: no model: not kept"])
    n = len(images)
    n_chk, n_fish = int(checked.registered.sum()), int(fish.registered.sum())
    e_chk = float(np.median(checked.residuals_px)) if checked.residuals_px.size else np.inf
    e_fish = float(np.median(fish.residuals_px)) if fish.residuals_px.size else np.inf
    assert fish.K is not None and checked.K is not None
    k1 = _radial_start(fish.distortion)
    # one set of data for both: the tracks either model kept, each through both cameras
    cache, feats = kw["cache"], kw["cache"].get("feats")
    tracks = [t for t in (_tracks_of(cache, checked), _tracks_of(cache, fish)) if t is not None]
    c_chk, n_views = _track_cost(checked, feats, tracks) if len(tracks) == 2 else (np.nan, 0)
    c_fish, _ = _track_cost(fish, feats, tracks) if len(tracks) == 2 else (np.nan, 0)
    # GRIC's penalty for the lens's parameters, ln(r n) sigma^2 each (r = 2 coordinates a
    # view, n the views, sigma = 1 px the keypoints' noise): f, and the term where kept
    pen = float(np.log(2.0 * max(n_views, 1)))
    c_chk += pen * (1 + (_radial_start(checked.distortion) != 0.0))
    c_fish += pen * (1 + (k1 != 0.0))
    said = (
        f"the fisheye tried ({why}; equidistant, Kannala-Brandt k1 = {k1:.4f}, f from "
        f"{f_start:.1f} px): f = {float(fish.K[0, 0]):.1f} px, {n_fish} of {n} frames, "
        f"median reprojection error {e_fish:.2f} px, the tracks of both models cost "
        f"{c_fish:.0f} px^2; against f = {float(checked.K[0, 0]):.1f} px, {n_chk} of {n} "
        f"frames, {e_chk:.2f} px, {c_chk:.0f} px^2 ({n_views} views, each error capped at "
        f"{_TRACK_CAP_PX:g} px)"
    )
    # each lens's own f and standard deviation, before any widening by the other's f: the
    # verdict on the f returned is _focal_said's alone
    said += (
        f"; each lens alone, the fisheye's {_sd_said(fish)}, SIMPLE_RADIAL's {_sd_said(checked)}"
    )
    off = _ran_off(fish, f_start, feats)
    if off is not None:
        return replace(checked, notes=[*checked.notes, f"{said}: it ran off ({off}): not kept"])
    # a model whose f the frames fix beats one whose f they do not, unless it registers
    # fewer frames; else the cost (NaN, no tracks to compare: not kept)
    fixed_fish, fixed_chk = bool(fish.focal_fixed), bool(checked.focal_fixed)
    fixes = (fixed_fish and not fixed_chk) or (fixed_chk and not fixed_fish and n_chk >= n_fish)
    by_cost = not fixes and c_fish <= c_chk
    # where both lenses fix f, what the choice between them leaves open: their two f,
    # weighed alike (a lens that does not fix f says nothing of it)
    d = float(fish.K[0, 0]) - float(checked.K[0, 0]) if fixed_fish and fixed_chk else None
    if n_fish >= n_chk and ((fixed_fish and not fixed_chk) or by_cost):
        # the pinhole's run-off stays said (metrics.json's intrinsics.fallback)
        ran = [m for m in checked.notes if m.startswith("the camera ran off")]
        how = "" if by_cost else ", its f fixed by the frames"
        kept = replace(fish, notes=[*fish.notes, *ran, f"{said}: kept (the fisheye{how})"])
        return _with_spread(kept, d, half=True)
    return _with_spread(replace(checked, notes=[*checked.notes, f"{said}: not kept"]), d, True)


#: The start of :func:`_self_calibrated`'s note where the last restart still moved f by
#: ``_FOCAL_RESTART`` or more; :func:`_focal_said` folds it into its verdict
_STILL_MOVED = "the last restart still moved f"

#: A focal length is fixed by the frames when its standard deviation
#: (``Reconstruction.focal_sd_px``) is at most this share of it
_FOCAL_FIXED = 0.1


def _sd_said(rec: Reconstruction) -> str:
    """``rec``'s focal length and its standard deviation, in words."""
    assert rec.K is not None
    f, sd = float(rec.K[0, 0]), rec.focal_sd_px
    return f"f = {f:.1f} px" + ("" if sd is None else f" +- {sd:.1f} px ({100 * sd / f:.0f} %)")


#: With ``refine_focal``: a focal length that moves by more than this share starts the
#: reconstruction again from the one found (:func:`reconstruct_sequence`).
_FOCAL_RESTART = 0.05


def _one_model(
    images: Sequence[ArrayLike],
    K: ArrayLike,
    distortion: DistortionModel | None,
    kw: dict[str, Any],
) -> Reconstruction:
    """Reconstruct the largest model of up to three starts (:func:`reconstruct_sequence`)."""
    best = _reconstruct(images, K, distortion, **kw, starts=None)
    n = len(images)
    # one model holds fewer than half the frames: the sequence may have a larger part its
    # start could not reach (a weak link between two parts); COLMAP makes several models
    # and keeps the largest: a start among the frames left out, twice at most
    for _ in range(2):
        nreg = int(best.registered.sum())
        if 2 * nreg >= n:
            break
        left = frozenset(np.flatnonzero(~best.registered).tolist())
        try:
            other = _reconstruct(images, K, distortion, **kw, starts=left)
        except DegenerateConfigurationError:  # no pair among them to start from
            break
        if int(other.registered.sum()) <= nreg:
            break
        note = (
            f"another start among the {len(left)} frames a model of {nreg} frames left out "
            f"registered {int(other.registered.sum())}: kept (the larger model)"
        )
        best = replace(other, notes=[*other.notes, note])
    return best


def _reconstruct(
    images: Sequence[ArrayLike],
    K: ArrayLike,
    distortion: DistortionModel | None,
    *,
    window: int,
    max_features: int,
    ratio: float,
    threshold_px: float,
    rng: int,
    masks: ArrayLike | Sequence[ArrayLike | None] | None,
    contrast_threshold: float,
    cache: dict[str, Any],
    equalize: bool = False,
    overlays: bool = False,
    starts: frozenset[int] | None,
    refine_focal: bool = False,
    refine_distortion: bool = False,
    radial_given: float | None = None,
) -> Reconstruction:
    """Reconstruct one model (:func:`reconstruct_sequence`), started from a pair in ``starts``.

    ``starts``: the frames an initial pair may have both of (None: any). ``cache`` keeps
    the keypoints and the verified pairs between the calls of one sequence.
    """
    from imageform.geometry.pnp_ransac import solve_pnp_ransac
    from imageform.geometry.relative_pose import recover_pose
    from imageform.geometry.twoview import find_essential_matrix

    if len(images) < 2:
        raise InvalidInputError(f"expected at least 2 frames, got {len(images)}")
    shapes = {np.asarray(im).shape[:2] for im in images}
    if len(shapes) != 1:
        raise InvalidInputError(f"expected frames of one size, got {sorted(shapes)}")
    k = np.array(K, np.float64)  # a copy: refine_focal changes it
    win = as_int(window, "window", minimum=1, maximum=100)
    ct = as_real(contrast_threshold, "contrast_threshold", positive=True, maximum=1.0)
    n = len(images)
    (shape,) = shapes
    if masks is None:
        per_frame: list[object] = [None] * n
    elif isinstance(masks, (list, tuple)) or (
        isinstance(masks, np.ndarray) and masks.ndim == 3 and masks.shape[1:] == shape
    ):
        if len(masks) != n:
            raise InvalidInputError(f"expected {n} masks (one a frame), got {len(masks)}")
        per_frame = [_as_mask(m, shape, f"masks[{i}]") for i, m in enumerate(masks)]
    else:
        one = _as_mask(masks, shape, "masks")
        per_frame = [one] * n
    if overlays and masks is None and "overlay" not in cache:
        from imageform.geometry.frame_masks import still_mask

        cache["overlay"] = still_mask(images)
    still = cache.get("overlay") if overlays and masks is None else None
    if still is not None and still.any():  # no masks given: one for every frame
        per_frame = [np.where(still, 0, 255).astype(np.uint8)] * n
    if "feats" not in cache:
        cache["feats"] = [
            detect_features(
                im, max_features=max_features, mask=m, contrast_threshold=ct, equalize=equalize
            )
            for im, m in zip(images, per_frame, strict=True)
        ]
    feats = cache["feats"]
    # refine_distortion: COLMAP's SIMPLE_RADIAL lens, its k1 from the one given (0: none)
    radial_k1: float | None = None
    fisheye = _is_fisheye(distortion)
    if refine_distortion:
        radial_k1 = _radial_start(distortion)
        distortion = _simple_radial(radial_k1, fisheye)
    raw = np.concatenate([feat.xy for feat in feats]) if feats else np.zeros((0, 2))
    # undistorted (ideal pinhole) pixels of every keypoint
    ideal: list[F64] = [_undistorted(feat.xy, k, distortion) for feat in feats]
    # the lens's local linear map from undistorted to image pixels at every keypoint: a
    # fisheye's undistortion stretches the rim twenty times, and so the keypoints' noise
    lin = [_image_jacobian(k, distortion, u) for u in ideal]
    all_A = np.concatenate(lin)
    all_mag = _magnification(all_A)
    notes: list[str] = []
    if still is not None and still.any():
        notes.append(
            f"{100 * float(np.mean(still)):.1f} % of the frame stands still while the camera "
            "moves (an overlay, an aperture's rim: still_mask): no keypoints there"
        )
    textured = [len(feat) for feat in feats]
    if max(textured) < 50:
        raise InvalidInputError(
            f"no texture: at most {max(textured)} keypoints a frame (50 needed to match)"
        )
    offset = np.concatenate([[0], np.cumsum(textured)]).astype(np.int64)
    pair_info: dict[tuple[int, int], tuple[int, float, NDArray[np.int64]]] = {}
    pair_rot: dict[tuple[int, int], F64] = {}  # each verified pair's relative rotation
    pair_dir: dict[tuple[int, int], F64] = {}  # and its translation's direction
    # rays closer than this (radians) meet on either side of the cameras within the noise
    min_parallax = float(np.arctan(3.0 * threshold_px / min(abs(k[0, 0]), abs(k[1, 1]))))

    # the best pair's counts and its essential matrix's inliers (pair, matches), for the
    # error message when no pair is verified
    seen: dict[str, Any] = {"matches": 0, "inliers": 0, "best": None}

    def stretch(*frames_kps: Any) -> float:
        """Return the undistortion's median stretch of keypoints (frame, indices, ...), >= 1.

        The estimators' thresholds are in undistorted pixels, one for all: scaled by it, a
        fisheye's rim keeps its matches (a scale for the whole set, a compromise; the
        bundle adjustment and its filters measure each observation in the image).
        """
        if distortion is None:
            return 1.0
        it = iter(frames_kps)
        mags = [all_mag[offset[f] + np.asarray(kp)] for f, kp in zip(it, it, strict=True)]
        v = np.concatenate(mags)
        v = v[np.isfinite(v)]
        return max(1.0, float(np.median(v))) if v.size else 1.0

    def epipolar_inliers(
        E: F64, i: int, kp1: NDArray[np.int64], j: int, kp2: NDArray[np.int64], found: Any
    ) -> NDArray[np.bool_]:
        """Return the RANSAC's inliers ``found`` and the matches within ``threshold_px``.

        The RANSAC's threshold is one for the pair (``stretch``: the median); each match
        it refused is judged again by its own Sampson distance in image pixels
        (:func:`_sampson_image`): a fisheye's rim match, stretched past the pair's median
        by the undistortion, is kept when it fits within ``threshold_px`` in the image, as
        a pinhole's match would. Without a lens (or ``_PER_VIEW_INLIERS`` off): the
        RANSAC's inliers.
        """
        inl = np.asarray(found, bool)
        if distortion is None or not _PER_VIEW_INLIERS:
            return inl
        a1, a2 = all_A[offset[i] + kp1], all_A[offset[j] + kp2]
        d = _sampson_image(np.asarray(E, np.float64), k, ideal[i][kp1], ideal[j][kp2], a1, a2)
        return np.asarray(inl | (d < threshold_px), bool)

    def verify(i: int, j: int) -> None:
        """Match frames i and j, keep the essential matrix's inliers and the parallax."""
        m = match_features(feats[i].descriptors, feats[j].descriptors, ratio=ratio)
        seen["matches"] = max(seen["matches"], int(m.shape[0]))
        if _TRACE is not None:
            _TRACE.setdefault("putative", {})[(i, j)] = m.copy()
        if m.shape[0] < 30:
            return
        p1, p2 = ideal[i][m[:, 0]], ideal[j][m[:, 1]]
        good = np.all(np.isfinite(p1), 1) & np.all(np.isfinite(p2), 1)
        m, p1, p2 = m[good], p1[good], p2[good]
        if m.shape[0] < 30:
            return
        try:
            thr = threshold_px * stretch(i, m[:, 0], j, m[:, 1])
            er = find_essential_matrix(p1, p2, k, threshold=thr, rng=rng)
        except (DegenerateConfigurationError, InvalidInputError):
            return
        inl = epipolar_inliers(er.E, i, m[:, 0], j, m[:, 1], er.inliers)
        if int(inl.sum()) > seen["inliers"]:
            seen["inliers"], seen["best"] = int(inl.sum()), ((i, j), m[inl])
        if inl.sum() < 30:
            return
        try:
            rp = recover_pose(er.E, p1, p2, k, inliers=inl)
        except DegenerateConfigurationError:  # no factorisation with points in front
            return
        # cheirality: an inlier of E whose point lies behind a camera of the chosen pose
        # fits the twisted pair (the same E, the second camera turned half a turn about
        # the baseline), e.g. a patch matched to its copy in a symmetric texture: no view
        # of one point. When the twisted pair explains half as many matches as the pose
        # chosen (two rigid scenes in the matches), which one is the scene is a coin's
        # toss: the pair is not used (its views come back by completion once both frames
        # are registered)
        behind = inl & _behind(k, np.asarray(rp.R), np.asarray(rp.t).ravel(), p1, p2, min_parallax)
        inl &= ~behind
        if inl.sum() < 30 or behind.sum() >= 0.5 * inl.sum():
            return
        pair_rot[(i, j)] = np.asarray(rp.R, np.float64)
        tu = np.asarray(rp.t, np.float64).ravel()
        pair_dir[(i, j)] = tu / max(float(np.linalg.norm(tu)), 1e-300)
        if j - i > win:  # a loop closure: never the initial pair, its parallax unused
            pair_info[(i, j)] = (int(inl.sum()), 0.0, m[inl])
            return
        # parallax of the pair: the median angle between the rays of its inliers
        C2 = -np.asarray(rp.R).T @ np.asarray(rp.t).ravel()
        X = np.asarray(rp.points, np.float64)
        fin = np.all(np.isfinite(X), axis=1) & inl
        ang = float(np.median(_angle_deg(np.zeros(3), C2, X[fin]))) if fin.any() else 0.0
        pair_info[(i, j)] = (int(inl.sum()), ang, m[inl])

    if "pairs" in cache:  # a second start: the pairs verified for the first
        pair_info, pair_rot, pair_dir, seen = cache["pairs"]
    else:
        for i in range(n):
            for j in range(i + 1, min(n, i + 1 + win)):
                verify(i, j)
        for i, j in _similar_pairs([f.descriptors for f in feats], win, 2, rng):
            verify(i, j)
        # a pair whose whole support is a mirrored texture's copies (its pose half a turn
        # off, no match behind a camera) breaks the loops of three frames it is in: it goes
        support = {q: v[0] for q, v in pair_info.items()}
        for key in _inconsistent_pairs(pair_rot, support=support):
            del pair_info[key]
        cache["pairs"] = (pair_info, pair_rot, pair_dir, seen)
    if not pair_info:
        hint = ""
        if seen["best"] is not None and seen["inliers"] >= 30:
            # the essential matrices fitted but no pair was kept (points behind the cameras,
            # a rotation the loops refuse): a pan's matches fit any translation's
            pair, m_best = seen["best"]
            best_info = {pair: (int(m_best.shape[0]), 0.0, m_best)}
            hint = _homography_hint(best_info, ideal, pair, threshold_px, rng)
        why = "no pair of frames gives a pose"
        if not hint:
            why = "no pair of frames has 30 verified matches: too little overlap or texture"
        raise DegenerateConfigurationError(
            f"{hint}{why} (keypoints a frame: median {int(np.median(textured))}; the best "
            f"pair: {seen['matches']} matches, {seen['inliers']} fit one essential matrix)"
        )
    edges = np.concatenate(
        [
            np.column_stack([offset[i] + m[:, 0], offset[j] + m[:, 1]])
            for (i, j), (_, _, m) in pair_info.items()
        ]
    )
    node_track, track_size = _build_tracks(offset, edges)
    n_tracks = track_size.size
    if _TRACE is not None:
        _TRACE["xy"] = [f.xy.copy() for f in feats]
        _TRACE["verified"] = {key: v[2].copy() for key, v in pair_info.items()}
        _TRACE["offset"], _TRACE["node_track"] = offset.copy(), node_track.copy()
        _TRACE["dropped"] = []  # (frame, keypoint, why) of each observation set aside
    # the observations (frame, keypoint, track, undistorted pixel, usable), in no order:
    # completion and merging append to them and move them between tracks
    nodes = np.flatnonzero(node_track >= 0)
    o_frame = (np.searchsorted(offset, nodes, side="right") - 1).astype(np.int64)
    o_kp = (nodes - offset[o_frame]).astype(np.int64)
    o_track = node_track[nodes].astype(np.int64)
    all_uv = np.concatenate(ideal)
    o_uv = all_uv[nodes]
    o_A = all_A[nodes]
    o_ok = np.all(np.isfinite(o_uv), axis=1)
    kp_track = [node_track[offset[f] : offset[f + 1]].copy() for f in range(n)]
    desc = [f.descriptors for f in feats]
    # the initial pair: most inliers among pairs with 2 degrees of parallax or more
    cands = [(v[0], key) for key, v in pair_info.items() if v[1] >= 2.0]
    if not cands:
        cands = [(v[0], key) for key, v in pair_info.items() if key[1] - key[0] <= win]
        notes.append("no pair with 2 degrees of parallax: started from the best matched one")
    if starts is not None:
        cands = [c for c in cands if c[1][0] in starts and c[1][1] in starts]
        if not cands:
            raise DegenerateConfigurationError("no pair among the frames left out to start from")
    Rs = np.full((n, 3, 3), np.nan)
    ts = np.full((n, 3), np.nan)
    registered = np.zeros(n, bool)
    P = np.full((n_tracks, 3), np.nan)  # each track's point (NaN: none yet)
    i0 = j0 = -1  # the initial pair, once chosen
    h, w = np.asarray(images[0]).shape[:2]
    max_err = 4.0

    def has_point() -> NDArray[np.bool_]:
        return np.all(np.isfinite(P), axis=1)

    def image_error(ids: NDArray[np.int64], proj: F64) -> F64:
        """Reprojection errors of observations ``ids`` in image pixels (through ``o_A``)."""
        d = proj - o_uv[ids]
        if distortion is not None:
            d = np.einsum("mij,mj->mi", o_A[ids], d)
        return np.asarray(np.linalg.norm(d, axis=1), np.float64)

    def triangulate(tids: NDArray[np.int64], retries: int = 2) -> None:
        """Triangulate the tracks ``tids`` (no point yet) from their registered views.

        With a lens (and ``_PER_VIEW_INLIERS``), a track of three views or more one view
        of which fails the checks loses that view (its worst: behind the camera, else the
        largest error in the image) and is triangulated again, ``retries`` times at most:
        each view is judged, as COLMAP's track triangulation keeps a track's consistent
        views (Schönberger & Frahm 2016), not the track by its worst view (a fisheye's
        rim view, a keypoint matched off its point).
        """
        tids = np.unique(tids)
        tids = tids[~has_point()[tids]]
        if tids.size == 0:
            return
        want = np.zeros(n_tracks, bool)
        want[tids] = True
        sel = np.flatnonzero(want[o_track] & registered[o_frame] & o_ok)
        col = np.searchsorted(tids, o_track[sel])
        cnt = np.bincount(col, minlength=tids.size)
        fr = o_frame[sel]
        X = _triangulate_tracks(
            k, Rs, ts, fr, col, o_uv[sel], tids.size,
            o_A[sel] if distortion is not None and _PER_VIEW_INLIERS else None,
        )  # fmt: skip
        X[cnt < 2] = np.nan
        fin = np.all(np.isfinite(X), axis=1)
        X[~fin] = 0.0
        # checks: in front of every view, within max_err pixels, rays 1.5 degrees apart
        proj, z = _project_obs(k, Rs[fr], ts[fr], X[col])
        err = image_error(sel, proj)
        fine = (z > 0) & (err < max_err)
        bad = np.bincount(col, weights=~fine, minlength=tids.size) > 0
        C = -np.einsum("mji,mj->mi", Rs[fr], ts[fr])
        ray = X[col] - C
        ray /= np.maximum(np.linalg.norm(ray, axis=1, keepdims=True), 1e-300)
        # the largest angle of a view's ray with the track's mean ray, twice: about the
        # largest angle between two rays
        mean = _sum_blocks(col, ray, tids.size)
        mean /= np.maximum(np.linalg.norm(mean, axis=1, keepdims=True), 1e-300)
        cosm = np.clip(np.sum(ray * mean[col], axis=1), -1.0, 1.0)
        spread = np.zeros(tids.size)
        np.maximum.at(spread, col, np.degrees(np.arccos(cosm)))
        good = fin & ~bad & (2.0 * spread >= 1.5)
        P[tids[good]] = X[good]
        if retries > 0 and distortion is not None and _PER_VIEW_INLIERS:
            again = fin & bad & (cnt >= 3)
            if again.any():
                worst = np.where(z > 0, err, np.inf)
                worst[~again[col]] = -1.0
                top = np.full(tids.size, -1.0)
                np.maximum.at(top, col, worst)
                # the view (one a track) whose error is its track's largest
                drop = np.flatnonzero(again[col] & (worst == top[col]))
                _, once = np.unique(col[drop], return_index=True)
                drop = sel[drop[once]]
                o_ok[drop] = False
                if _TRACE is not None:
                    _TRACE["dropped"] += [
                        (f, q, "triangulation")
                        for f, q in zip(o_frame[drop].tolist(), o_kp[drop].tolist(), strict=True)
                    ]
                triangulate(tids[again], retries - 1)

    def relens(k1: float) -> None:
        """Undistort every keypoint again with ``k`` and the radial term ``k1`` (its lens)."""
        nonlocal distortion, radial_k1, all_A, all_mag, all_uv, o_uv, o_A
        radial_k1 = k1
        distortion = _simple_radial(k1, fisheye)
        ideal[:] = [_undistorted(feat.xy, k, distortion) for feat in feats]
        all_A = np.concatenate([_image_jacobian(k, distortion, u) for u in ideal])
        all_mag = _magnification(all_A)
        all_uv = np.concatenate(ideal)
        at = offset[o_frame] + o_kp
        o_uv, o_A = all_uv[at], all_A[at]
        o_ok[~np.all(np.isfinite(o_uv), axis=1)] = False

    def adjust(delta: float, iters: int, focal: bool = False, lens: bool = False) -> None:
        """Bundle adjustment over every registered frame and point (``focal``: and ``k``'s f).

        ``lens`` (with ``refine_distortion``): the radial term too, on the keypoints as
        the image has them, once ``_RADIAL_MIN_FRAMES`` frames and ``_RADIAL_MIN_POINTS``
        points hold it; the keypoints are then undistorted again with the lens found.
        """
        ids = np.flatnonzero(o_ok & registered[o_frame] & has_point()[o_track])
        if ids.size == 0:
            return
        fixed = ~registered
        fixed[i0] = True
        R0 = np.where(registered[:, None, None], Rs, np.eye(3))
        t0 = np.where(registered[:, None], ts, 0.0)
        pts, pslot = np.unique(o_track[ids], return_inverse=True)
        radial = (
            radial_k1 is not None
            and lens
            and int(registered.sum()) >= _RADIAL_MIN_FRAMES
            and pts.size >= _RADIAL_MIN_POINTS
        )
        Rn, tn, Xn, Kn, k1n = _schur_lm(
            k,
            R0,
            t0,
            P[pts],
            o_frame[ids],
            pslot,
            raw[offset[o_frame[ids]] + o_kp[ids]] if radial else o_uv[ids],
            fixed,
            delta,
            iters,
            A=None if distortion is None or radial else o_A[ids],
            focal=focal,
            radial=radial_k1 if radial else None,
            fisheye=fisheye,
        )
        Rs[registered], ts[registered] = Rn[registered], tn[registered]
        P[pts] = Xn
        # without refine_distortion the keypoints' undistortion stays the given K's (a
        # small change); with it, the keypoints are undistorted again by the lens found
        moved = bool(np.any(Kn != k))
        k[:] = Kn
        if radial_k1 is not None and (radial or moved):
            relens(k1n if radial else radial_k1)

    def choose_lens(k1_given: float) -> None:
        """Keep the radial term found only where it lowers the reprojection error.

        One more adjustment holds it at ``k1_given`` (0: no distortion), from the final
        poses, points and focal length; when the term found lowers the sum of squared
        errors of the same observations by less than ``_RADIAL_GAIN``, the data do not
        tell it (forward motion or a narrow view let it trade against f and the depths)
        and the held one is kept (a penalty for one more parameter, as a model selection
        by an information criterion: Torr 1998, "Geometric motion segmentation and model
        selection", Phil. Trans. R. Soc. A 356).
        """
        assert radial_k1 is not None
        ids = np.flatnonzero(o_ok & registered[o_frame] & has_point()[o_track])
        if ids.size == 0 or radial_k1 == k1_given:
            return
        fixed = ~registered
        fixed[i0] = True
        R0 = np.where(registered[:, None, None], Rs, np.eye(3))
        t0 = np.where(registered[:, None], ts, 0.0)
        pts, pslot = np.unique(o_track[ids], return_inverse=True)
        fr = o_frame[ids]
        uv = raw[offset[fr] + o_kp[ids]]

        def sse(K_: F64, k1: float, R_: F64, t_: F64, X_: F64) -> float:
            proj, _ = _project_obs(K_, R_[fr], t_[fr], X_[pslot])
            d = (_equidistant if fisheye else _radial)(K_, k1, proj)[0] - uv
            return float(np.nansum(d * d))

        found = sse(k, radial_k1, R0, t0, P[pts])
        Rn, tn, Xn, Kn, _ = _schur_lm(
            k, R0, t0, P[pts], fr, pslot, uv, fixed, 0.0, 50,
            focal=refine_focal, radial=k1_given, refine_radial=False, fisheye=fisheye,
        )  # fmt: skip
        held = sse(Kn, k1_given, Rn, tn, Xn)
        gain = 1.0 - found / max(held, 1e-300)
        said = (
            f"the radial term k1 = {radial_k1:.4f} lowers the reprojection error (its sum of "
            f"squares) by {100 * gain:.1f} % against k1 = {k1_given:.4f}"
        )
        if gain >= _RADIAL_GAIN:
            notes.append(said + ": kept")
            return
        notes.append(
            said + f" (less than {100 * _RADIAL_GAIN:.0f} %): held at {k1_given:.4f}, f refined"
            " alone"
        )
        Rs[registered], ts[registered] = Rn[registered], tn[registered]
        P[pts] = Xn
        k[:] = Kn
        relens(k1_given)

    def check_focal() -> float | None:
        """Return the focal length a final adjustment that refines it finds (K itself held)."""
        ids = np.flatnonzero(o_ok & registered[o_frame] & has_point()[o_track])
        if ids.size == 0 or int(registered.sum()) < 3:
            return None
        fixed = ~registered
        fixed[i0] = True
        pts, pslot = np.unique(o_track[ids], return_inverse=True)
        _, _, _, Kc, _ = _schur_lm(
            k,
            np.where(registered[:, None, None], Rs, np.eye(3)),
            np.where(registered[:, None], ts, 0.0),
            P[pts],
            o_frame[ids],
            pslot,
            o_uv[ids],
            fixed,
            0.0,
            30,
            A=None if distortion is None else o_A[ids],
            focal=True,
        )
        return float(Kc[0, 0])

    def focal_spread() -> float | None:
        r"""Return the standard deviation of the focal length the final adjustment found.

        The profile of its cost (Venzon & Moolgavkar 1988, "A method for computing
        profile-likelihood-based confidence intervals", Appl. Statist. 37(1); Triggs et
        al. 2000, sec. 10):
        f held at :math:`f e^{\pm h}` (:math:`h = \ln(1 + \delta)`, ``_FOCAL_PROFILE``),
        every pose and point (and the lens's term where it was kept) adjusted again, the
        sums of squared image errors :math:`S_-, S_0, S_+` give the parabola
        :math:`S(u) \approx S_0 + a u^2` in :math:`u = \ln f`,
        :math:`a = (S_+ + S_- - 2 S_0) / (2 h^2)`, and

        .. math:: \sigma_f = f \sqrt{\hat\sigma^2 / a}, \quad
                  \hat\sigma^2 = S_0 / (2 M - 6 n - 3 m - p)

        (:math:`M` views, :math:`n` frames, :math:`m` points, :math:`p` intrinsics). The
        other parameters follow f along its valley, so a lens term or depths that trade
        against it (few frames, forward motion) make it wide. Inf where the cost does not
        rise (f not fixed at all), and with fewer than 3 frames (two views leave f free
        along the baseline: it trades against the depths).
        """
        ids = np.flatnonzero(o_ok & registered[o_frame] & has_point()[o_track])
        nreg = int(registered.sum())
        if ids.size == 0 or nreg < 3:
            return float("inf")
        fixed = ~registered
        fixed[i0] = True
        R0 = np.where(registered[:, None, None], Rs, np.eye(3))
        t0 = np.where(registered[:, None], ts, 0.0)
        pts, pslot = np.unique(o_track[ids], return_inverse=True)
        fr = o_frame[ids]
        radial = radial_k1 is not None
        uv = raw[offset[fr] + o_kp[ids]] if radial else o_uv[ids]
        lens_free = radial and radial_given is not None and radial_k1 != radial_given
        k1_0 = 0.0 if radial_k1 is None else radial_k1

        def sse(K_: F64, k1: float, R_: F64, t_: F64, X_: F64) -> float:
            proj, _ = _project_obs(K_, R_[fr], t_[fr], X_[pslot])
            if radial:
                d = (_equidistant if fisheye else _radial)(K_, k1, proj)[0] - uv
            else:
                d = proj - uv
                if distortion is not None:
                    d = np.einsum("mij,mj->mi", o_A[ids], d)
            return float(np.nansum(d * d))

        s0 = sse(k, k1_0, R0, t0, P[pts])
        side = []
        h = float(np.log1p(_FOCAL_PROFILE))
        for u in (-h, h):
            Kq = k.copy()
            Kq[:2, :2] *= np.exp(u)
            Rn, tn, Xn, _, k1n = _schur_lm(
                Kq, R0, t0, P[pts], fr, pslot, uv, fixed, 0.0, 30,
                A=None if distortion is None or radial else o_A[ids],
                radial=radial_k1, refine_radial=lens_free, fisheye=fisheye,
            )  # fmt: skip
            side.append(sse(Kq, k1n if lens_free else k1_0, Rn, tn, Xn))
        a = (side[0] + side[1] - 2.0 * s0) / (2.0 * h * h)
        dof = 2 * ids.size - 6 * (nreg - 1) - 3 * pts.size - 1 - int(lens_free)
        if not a > 0 or dof <= 0:
            return float("inf")
        return float(k[0, 0] * np.sqrt(s0 / dof / a))

    def filter_obs(limit: float, min_angle: float = 0.0) -> None:
        """Drop observations beyond ``limit`` pixels; points left with one view go."""
        ids = np.flatnonzero(registered[o_frame] & has_point()[o_track] & o_ok)
        fr = o_frame[ids]
        proj, z = _project_obs(k, Rs[fr], ts[fr], P[o_track[ids]])
        err = image_error(ids, proj)
        out = ids[~((z > 0) & (err < limit))]
        o_ok[out] = False
        if _TRACE is not None:
            _TRACE["dropped"] += [
                (f, q, f"filter {limit:g} px")
                for f, q in zip(o_frame[out].tolist(), o_kp[out].tolist(), strict=True)
            ]
        use = registered[o_frame] & o_ok
        views = np.bincount(o_track[use], minlength=n_tracks)
        P[views < 2] = np.nan

    def complete(radius: float) -> int:
        """Add the views a track's matching missed; merge tracks that are one point.

        Every point is projected into each registered frame that has no view of it and
        sees some of what one of its views sees (2 of a sample of 32 of that view's
        points land in the frame: the work grows with what each frame sees, not with
        the number of points times the number of frames); the keypoint nearest the
        projection (within ``radius`` pixels, its descriptor near the track's) becomes a
        view of it, or, when it is another point's view and the two points are one (each
        reprojects within ``radius`` in all of the other's views, no frame in common), the
        two tracks are merged. Returns how many views were added.
        """
        nonlocal o_frame, o_kp, o_track, o_uv, o_ok, o_A
        from scipy.spatial import cKDTree

        hp = has_point()
        ok_obs = o_ok & registered[o_frame]
        # each track's reference descriptor: its first usable view's
        ref = -np.ones(n_tracks, np.int64)
        ids = np.flatnonzero(ok_obs & hp[o_track])
        ref[o_track[ids[::-1]]] = ids[::-1]
        ref_desc = np.zeros((n_tracks, 128), np.float32)
        rt = np.flatnonzero(ref >= 0)
        for f in np.unique(o_frame[ref[rt]]).tolist():
            s = rt[o_frame[ref[rt]] == f]
            ref_desc[s] = desc[f][o_kp[ref[s]]]
        new_f, new_k, new_t = [], [], []
        merges: list[tuple[int, int]] = []
        by_frame = np.argsort(o_frame, kind="stable")
        fstart = np.searchsorted(o_frame[by_frame], np.arange(n + 1))
        reg = np.flatnonzero(registered)
        # which frames see what frame f sees: a sample of each frame's points (at most
        # 32) projected into every frame; frame g's points are candidates for f when 2 of
        # its sample land in f. The candidates then grow with what f sees, not with the
        # whole reconstruction (every point into every frame: quadratic in a long video)
        pts_of: dict[int, NDArray[np.int64]] = {}
        samples, sample_of = [], []
        for g in reg.tolist():
            obs = by_frame[fstart[g] : fstart[g + 1]]
            pts = o_track[obs[ok_obs[obs] & hp[o_track[obs]]]]
            pts_of[g] = pts
            if pts.size:
                pick = pts[np.linspace(0, pts.size - 1, min(32, pts.size)).astype(np.int64)]
                samples.append(pick)
                sample_of.append(np.full(pick.size, g, np.int64))
        sample = np.concatenate(samples) if samples else np.zeros(0, np.int64)
        sampled_in = np.concatenate(sample_of) if sample_of else np.zeros(0, np.int64)
        stamp = np.zeros(n_tracks, np.int64)
        seen_in = -np.ones(n_tracks, np.int64)
        for f in reg.tolist():
            pr, zs = _project_one(k, Rs[f], ts[f], P[sample])
            lands = (zs > 0) & np.all((pr > -0.5) & (pr < [w - 0.5, h - 0.5]), axis=1)
            overlap = np.flatnonzero(np.bincount(sampled_in[lands], minlength=n) >= 2)
            overlap = overlap[overlap != f]
            if overlap.size == 0:
                continue
            # their points, each once (the last write of a track's slot wins), without
            # the ones f sees already: work in proportion to the candidates
            every = np.concatenate([pts_of[g] for g in overlap.tolist()])
            slot = np.arange(every.size)
            stamp[every] = slot
            cand = every[stamp[every] == slot]
            seen_in[o_track[by_frame[fstart[f] : fstart[f + 1]]]] = f
            cand = np.sort(cand[(seen_in[cand] != f) & (ref[cand] >= 0)])
            if cand.size == 0:
                continue
            proj, z = _project_one(k, Rs[f], ts[f], P[cand])
            inside = (z > 0) & np.all((proj > -0.5) & (proj < [w - 0.5, h - 0.5]), axis=1)
            cand, proj = cand[inside], proj[inside]
            fin = np.all(np.isfinite(ideal[f]), axis=1)
            kp_ids = np.flatnonzero(fin)
            if cand.size == 0 or kp_ids.size == 0:
                continue
            dist, q = cKDTree(ideal[f][kp_ids]).query(proj, distance_upper_bound=radius)
            near = np.isfinite(dist)
            cand, q = cand[near], kp_ids[q[near]]
            dd = np.linalg.norm(desc[f][q] - ref_desc[cand], axis=1)
            alike = dd < 250.0
            cand, q, dd = cand[alike], q[alike], dd[alike]
            # one track a keypoint: the nearest descriptor
            order_ = np.lexsort((dd, q))
            first = np.ones(order_.size, bool)
            first[1:] = q[order_][1:] != q[order_][:-1]
            cand, q = cand[order_][first], q[order_][first]
            owner = kp_track[f][q]
            free = owner < 0
            new_f.append(np.full(int(free.sum()), f, np.int64))
            new_k.append(q[free])
            new_t.append(cand[free])
            kp_track[f][q[free]] = cand[free]
            other = ~free & (owner != cand)
            merges += list(zip(cand[other].tolist(), owner[other].tolist(), strict=True))
        added = 0
        if new_f:
            nf_ = np.concatenate(new_f)
            nk_ = np.concatenate(new_k)
            o_frame = np.concatenate([o_frame, nf_])
            o_kp = np.concatenate([o_kp, nk_])
            o_track = np.concatenate([o_track, np.concatenate(new_t)])
            o_uv = np.concatenate([o_uv, all_uv[offset[nf_] + nk_]])
            o_A = np.concatenate([o_A, all_A[offset[nf_] + nk_]])
            o_ok = np.concatenate([o_ok, np.ones(nf_.size, bool)])
            added = int(nf_.size)
        # merges: the second track's views join the first, if the two points are one (a
        # track merged once waits for the next completion to merge again)
        gone = np.zeros(n_tracks, bool)
        touched = np.zeros(n_tracks, bool)
        by_track = np.argsort(o_track, kind="stable")
        start = np.searchsorted(o_track[by_track], np.arange(n_tracks + 1))
        hp = has_point()
        for ta, tb in merges:
            if touched[ta] or touched[tb] or ta == tb or not hp[tb]:
                continue
            va = by_track[start[ta] : start[ta + 1]]
            vb = by_track[start[tb] : start[tb + 1]]
            if np.intersect1d(o_frame[va], o_frame[vb]).size:
                continue
            both = np.concatenate([va, vb])
            both = both[o_ok[both] & registered[o_frame[both]]]
            fine = True
            for X in (P[ta], P[tb]):
                proj, z = _project_obs(
                    k, Rs[o_frame[both]], ts[o_frame[both]], np.broadcast_to(X, (both.size, 3))
                )
                err = image_error(both, proj)
                fine &= bool(np.all((z > 0) & (err < radius)))
            if not fine:
                continue
            o_track[vb] = ta
            for fb, kb in zip(o_frame[vb].tolist(), o_kp[vb].tolist(), strict=True):
                kp_track[fb][kb] = ta
            P[tb] = np.nan
            gone[tb] = touched[ta] = touched[tb] = True
        return added + int(gone.sum())

    # the start: the candidates in order of inliers, the first whose two views triangulate
    # 30 points that pass the checks (a pair of repetitive texture, e.g. a chessboard, can
    # pass RANSAC with a wrong pose that leaves a handful)
    for _, (a, b) in sorted(cands, reverse=True)[:5]:
        Rs[:], ts[:], P[:], registered[:] = np.nan, np.nan, np.nan, False
        m0 = pair_info[(a, b)][2]
        p1, p2 = ideal[a][m0[:, 0]], ideal[b][m0[:, 1]]
        try:
            thr = threshold_px * stretch(a, m0[:, 0], b, m0[:, 1])
            er = find_essential_matrix(p1, p2, k, threshold=thr, rng=rng)
            inl0 = epipolar_inliers(er.E, a, m0[:, 0], b, m0[:, 1], er.inliers)
            rp = recover_pose(er.E, p1, p2, k, inliers=inl0)
        except (DegenerateConfigurationError, InvalidInputError) as exc:
            notes.append(f"frames {a} and {b}: no pose to start from ({exc})")
            continue
        i0, j0 = a, b
        Rs[i0], ts[i0] = np.eye(3), np.zeros(3)
        Rs[j0], ts[j0] = np.asarray(rp.R, np.float64), np.asarray(rp.t, np.float64).ravel()
        registered[[i0, j0]] = True
        triangulate(o_track[o_frame == i0])
        adjust(2.0, 10)
        made = int(has_point().sum())
        if made >= 30:
            break
        notes.append(f"frames {a} and {b}: {made} points triangulated (30 needed to start)")
        i0 = j0 = -1
    if i0 < 0:
        why = "; ".join(notes[-3:])
        if cands:
            why = _homography_hint(pair_info, ideal, max(cands)[1], threshold_px, rng) + why
        raise DegenerateConfigurationError(
            "no pair of frames triangulates 30 points to start from: " + why
        )
    last_ba = 2
    # register the others: the frame that sees the most points first. A frame that fails
    # waits until more frames are registered (their points may be the ones it sees) and is
    # tried again then, as COLMAP does; it is given up when nothing changed since its try
    pending = [fi for fi in range(n) if not registered[fi]]
    reg_order = [i0, j0]
    failed_at: dict[int, int] = {}  # frame -> frames registered when it last failed
    why_not: dict[int, str] = {}

    def add_views(fi: int, kp: NDArray[np.int64], tracks: NDArray[np.int64]) -> None:
        """Make keypoints ``kp`` of frame ``fi`` (in no track yet) views of ``tracks``."""
        nonlocal o_frame, o_kp, o_track, o_uv, o_ok, o_A
        if kp.size == 0:
            return
        o_frame = np.concatenate([o_frame, np.full(kp.size, fi, np.int64)])
        o_kp = np.concatenate([o_kp, kp])
        o_track = np.concatenate([o_track, tracks])
        o_uv = np.concatenate([o_uv, all_uv[offset[fi] + kp]])
        o_A = np.concatenate([o_A, all_A[offset[fi] + kp]])
        o_ok = np.concatenate([o_ok, np.ones(kp.size, bool)])
        kp_track[fi][kp] = tracks

    def match_points(fi: int, known: NDArray[np.int64]) -> tuple[NDArray[np.int64], ...]:
        """Match frame ``fi``'s untracked keypoints to the points its neighbours see.

        The points seen by the registered frames nearest ``fi`` in the sequence (2 x
        ``window`` of them at most), each by its view in the frame nearest ``fi``, against
        ``fi``'s keypoints that are no view of a point yet (Lowe's ratio, mutual): the
        correspondences a pair's matching missed (a pair below its inlier minimum, a track
        cut by a frame between). Returns the keypoints and their tracks.
        """
        reg = np.flatnonzero(registered)
        near = reg[np.argsort(np.abs(reg - fi), kind="stable")[: 2 * win]]
        hp_ = has_point()
        sel = np.flatnonzero(np.isin(o_frame, near) & o_ok & hp_[o_track])
        sel = sel[~np.isin(o_track[sel], known)]
        empty = np.zeros(0, np.int64)
        if sel.size < 2:
            return empty, empty
        # one view a track: the nearest frame's (a track's own views would fail the ratio)
        order_ = np.lexsort((np.abs(o_frame[sel] - fi), o_track[sel]))
        sel = sel[order_]
        first = np.ones(sel.size, bool)
        first[1:] = o_track[sel][1:] != o_track[sel][:-1]
        sel = sel[first]
        pool = np.stack([desc[f][q] for f, q in zip(o_frame[sel], o_kp[sel], strict=True)])
        free = np.flatnonzero((kp_track[fi] < 0) & np.all(np.isfinite(ideal[fi]), axis=1))
        if free.size < 2:
            return empty, empty
        mm = match_features(desc[fi][free], pool, ratio=ratio)
        return free[mm[:, 0]], o_track[sel[mm[:, 1]]]

    @dataclass
    class _Pose:
        R: F64
        tvec: F64
        inliers: NDArray[np.bool_]
        valid: bool = True

    refused: list[str] = []  # pairs pose_from_pair's last call refused, and why

    def image_inliers(
        fi: int, kp: NDArray[np.int64], X3: F64, R: F64, t: F64, limit: float
    ) -> NDArray[np.bool_]:
        """Which points ``X3`` reproject within ``limit`` image pixels of ``fi``'s ``kp``.

        Each error through the lens's local map at its keypoint (``all_A``), as the
        filters measure it: the PnP's RANSAC threshold is one for the frame (``stretch``:
        the median), and a correspondence it refused is kept when it is within ``limit``
        in the image.
        """
        proj, z = _project_one(k, R, t, X3)
        d = np.einsum("mij,mj->mi", all_A[offset[fi] + kp], proj - ideal[fi][kp])
        with np.errstate(invalid="ignore"):
            return np.asarray((z > 0) & (np.linalg.norm(d, axis=1) < limit), bool)

    def pose_from_pair(
        fi: int, kp: NDArray[np.int64], tracks: NDArray[np.int64]
    ) -> tuple[_Pose, int, float] | None:
        r"""Pose of frame ``fi`` from a verified pair with a registered frame, scaled by points.

        The pair's essential matrix (30 inliers or more, its rotation in the loops of three
        frames) gives the rotation and the translation's direction :math:`u` relative to
        the registered frame ``g``: :math:`R = R_{g\to f} R_g`,
        :math:`t = R_{g\to f} t_g + s u`; the scale :math:`s > 0` is one number, each
        2-D/3-D correspondence a hypothesis (the point's depth along its ray), the one most
        points reproject within PnP's threshold from wins (a one-point RANSAC, exhaustive),
        6 points at least and half of those the tracks give. Only a scale that puts the
        camera near the registered frames nearest ``fi`` in the sequence counts: within
        3 of their steps (the median distance between registered frames, a frame apart) a
        frame of the gap between them and it (a frame that does not belong may match a
        repeated texture and scale to a pose far off the path). And only a pair whose
        rotation the inliers confirm: refined on them in six degrees of freedom, the pose
        turns less than ``_PAIR_POSE_TOL_DEG`` (5) degrees from the pair's
        (:func:`_pair_pose_disagreement`; a pair turned by a repeated texture otherwise
        registers the frame that far off). Returns the pose, the pair's registered frame and
        that angle; None when no pair gives that.
        """
        if kp.size == 0:
            return None
        reg_ = np.flatnonzero(registered)
        cen = -np.einsum("nji,nj->ni", Rs[reg_], ts[reg_])
        steps = np.linalg.norm(np.diff(cen, axis=0), axis=1) / np.diff(reg_)
        step = float(np.median(steps)) if steps.size else np.inf
        near_ = reg_[np.argsort(np.abs(reg_ - fi), kind="stable")[:2]]
        near_c = cen[np.searchsorted(reg_, near_)]
        reach = 3.0 * step * np.abs(near_ - fi)
        per_view = distortion is not None and _PER_VIEW_INLIERS
        thr = 3.0 * stretch(fi, kp)
        A_kp = all_A[offset[fi] + kp]
        X = P[tracks]
        xh = np.column_stack([ideal[fi][kp], np.ones(kp.size)]) @ np.linalg.inv(k).T
        best: _Pose | None = None
        best_g, score, best_off = -1, 0, 0.0
        refused.clear()
        for g in reg_.tolist():
            key = (min(g, fi), max(g, fi))
            if key not in pair_info or key not in pair_dir:
                continue
            Rp, up = pair_rot[key], pair_dir[key]
            Rr, u = (Rp, up) if g < fi else (Rp.T, -(Rp.T @ up))
            A = (X @ Rs[g].T + ts[g]) @ Rr.T
            du = np.cross(xh, u)
            da = np.cross(xh, A)
            with np.errstate(divide="ignore", invalid="ignore"):
                sc = -np.sum(du * da, axis=1) / np.sum(du * du, axis=1)
            sc = sc[np.isfinite(sc) & (sc > 0)]
            # the camera's center for scale s: C_g - s R_g^T R_r^T u
            cg, dirc = -Rs[g].T @ ts[g], Rs[g].T @ (Rr.T @ u)
            cand: _Pose | None = None
            got = score
            for s_ in np.unique(sc):
                cf = cg - s_ * dirc
                if not np.any(np.linalg.norm(near_c - cf, axis=1) <= reach):
                    continue
                Xc = A + s_ * u
                with np.errstate(divide="ignore", invalid="ignore"):
                    uv = (Xc @ k[:2].T) / Xc[:, 2:3]
                    d = uv - ideal[fi][kp]
                    near = np.linalg.norm(d, axis=1) < thr
                    if per_view:  # or within 3 px in the image
                        d = np.einsum("mij,mj->mi", A_kp, d)
                        near |= np.linalg.norm(d, axis=1) < 3.0
                    inl = (Xc[:, 2] > 0) & near
                if int(inl.sum()) > got:
                    cand = _Pose(Rr @ Rs[g], Rr @ ts[g] + s_ * u, inl)
                    got = int(inl.sum())
            if cand is None:
                continue
            sel = cand.inliers
            off = _pair_pose_disagreement(cand.R, cand.tvec, X[sel], ideal[fi][kp][sel], k)
            if _TRACE is not None:
                _TRACE.setdefault("pair_pose", []).append(
                    {"frame": fi, "pair": g, "R": cand.R.copy(), "t": cand.tvec.copy()}
                    | {"R_other": Rs[g].copy(), "X": X[sel].copy(), "uv": ideal[fi][kp][sel]}
                    | {"angle": off}
                )
            if off >= _PAIR_POSE_TOL_DEG:
                refused.append(
                    f"its pair with frame {g}, whose {got} points turn the pair's rotation "
                    f"{off:.1f} degrees"
                )
                continue
            best, best_g, score, best_off = cand, g, got, off
        if best is None or score < max(6, 0.5 * min(kp.size, 12)):
            return None
        return best, best_g, best_off

    def register(fi: int, fallback: bool) -> bool:
        """Register frame ``fi`` by PnP on its tracks' points; ``fallback``: by the others.

        The fallbacks, when the tracks give fewer than 12 PnP inliers: the points matched
        directly (:func:`match_points`) join the tracks' in PnP, then the pose from a
        verified pair scaled by the points (:func:`pose_from_pair`).
        """
        nonlocal last_ba

        def pnp(X3: F64, kp: NDArray[np.int64]) -> tuple[Any, int]:
            """PnP RANSAC of ``fi``'s keypoints ``kp`` on points ``X3``: (result, inliers).

            No inliers when the pose turns against the verified pair with a registered
            frame that has the most matches (see :func:`turned`).
            """
            try:
                thr = 3.0 * stretch(fi, kp)
                r: Any = solve_pnp_ransac(X3, ideal[fi][kp], k, threshold=thr, rng=rng)
            except (DegenerateConfigurationError, InvalidInputError):
                return None, 0
            if not bool(r.valid):
                return r, 0
            if distortion is not None and _PER_VIEW_INLIERS:
                R_, t_ = np.asarray(r.R, np.float64), np.asarray(r.tvec, np.float64).ravel()
                inl_ = np.asarray(r.inliers, bool) | image_inliers(fi, kp, X3, R_, t_, 3.0)
                r = _Pose(R_, t_, inl_)
            if turned(np.asarray(r.R, np.float64)):
                flipped.append(int(np.sum(r.inliers)))
                return r, 0
            return r, int(np.sum(r.inliers))

        def turned(R: F64) -> bool:
            """Whether ``R`` is 30 degrees or more from the best verified pair's rotation.

            Tracks through a repeated texture's copies can hand PnP the copy's points: a pose
            that reprojects them well, half a turn off (a walk of 8 frames, frame 4 next to
            the initial pair 6-7, 135 inliers). The pair of ``fi`` with a registered frame
            that has the most verified matches, usually its neighbour in the sequence,
            says which way the frame faces.
            """
            best = None
            for g in np.flatnonzero(registered).tolist():
                key = (min(fi, g), max(fi, g))
                if key in pair_info and (best is None or pair_info[key][0] > best[0]):
                    best = (pair_info[key][0], key, g)
            if best is None:
                return False
            _, (a, b), g = best
            rel = Rs[g] @ R.T if a == fi else R @ Rs[g].T  # frame a's camera to frame b's
            c = (np.trace(rel @ pair_rot[(a, b)].T) - 1.0) / 2.0
            return bool(c < np.cos(np.radians(30.0)))

        flipped: list[int] = []  # inliers of the PnP poses turned() refused
        hp = has_point()
        tr = kp_track[fi]
        kps = np.flatnonzero(tr >= 0)
        kps = kps[hp[tr[kps]] & np.all(np.isfinite(ideal[fi][kps]), axis=1)]
        res: Any = None
        found = 0
        if kps.size >= 12:
            res, found = pnp(P[tr[kps]], kps)
        extra_kp = extra_tr = np.zeros(0, np.int64)
        how = ""
        if found < 12:
            if not fallback:
                why_not[fi] = (
                    f"frame {fi}: {kps.size} 2-D/3-D correspondences, PnP found {found} "
                    "inliers (12 needed)"
                    + (
                        f" (a pose with {flipped[0]} turned 30 degrees or more from its best "
                        "verified pair: points of a repeated texture's copy?)"
                        if flipped
                        else ""
                    )
                )
                return False
            # too few views of points through the tracks: the points matched directly
            extra_kp, extra_tr = match_points(fi, tr[kps])
            allk = np.concatenate([kps, extra_kp])
            if allk.size >= 12 and extra_kp.size:
                res, found = pnp(np.concatenate([P[tr[kps]], P[extra_tr]]), allk)
            how = f"{extra_kp.size} of its points matched directly, PnP {found} inliers"
            if found < 12:
                pose = pose_from_pair(fi, allk, np.concatenate([tr[kps], extra_tr]))
                if pose is None:
                    why_not[fi] = (
                        f"frame {fi}: {kps.size} 2-D/3-D correspondences by the tracks and "
                        f"{extra_kp.size} by matching the points, PnP found {found} inliers "
                        "(12 needed), no verified pair's pose that 6 of them scale near its "
                        "neighbours"
                        + (
                            f" (refused: {'; '.join(refused)}, {_PAIR_POSE_TOL_DEG:g} allowed)"
                            if refused
                            else ""
                        )
                    )
                    return False
                res, g, off = pose
                how = (
                    f"the pose of its pair with frame {g}, scaled by "
                    f"{int(np.sum(res.inliers))} points (refined on them, it turns "
                    f"{off:.1f} degrees)"
                )
            notes.append(f"frame {fi}: registered by {how}")
        Rs[fi], ts[fi] = np.asarray(res.R, np.float64), np.asarray(res.tvec, np.float64)
        registered[fi] = True
        reg_order.append(fi)
        inl = np.asarray(res.inliers, bool)
        # the correspondences PnP rejected are not this frame's views of those points; the
        # points matched directly that fit become views
        rejected = np.zeros(tr.size, bool)
        rejected[kps[~inl[: kps.size]]] = True
        mine = np.flatnonzero(o_frame == fi)
        o_ok[mine[rejected[o_kp[mine]]]] = False
        if _TRACE is not None:
            _TRACE["dropped"] += [
                (fi, q, "PnP outlier") for q in o_kp[mine[rejected[o_kp[mine]]]].tolist()
            ]
        if extra_kp.size:
            keep = inl[kps.size :]
            ek, et = extra_kp[keep], extra_tr[keep]
            _, once = np.unique(et, return_index=True)
            add_views(fi, ek[once], et[once])
        triangulate(tr[tr >= 0])
        nreg = int(registered.sum())
        if nreg >= 1.4 * last_ba:
            # the focal length too once three frames hold it (two leave it free along the
            # baseline): a guess 70 % off converges here, not in the final adjustment
            adjust(2.0, 10, refine_focal and nreg >= 3, lens=True)
            filter_obs(max_err)
            complete(2.0)
            triangulate(np.arange(n_tracks))
            last_ba = nreg
        return True

    def sees(f: int, hp: NDArray[np.bool_]) -> int:
        """How many triangulated points frame ``f``'s tracks hold (``hp``: has_point())."""
        return int(np.sum(hp[kp_track[f][kp_track[f] >= 0]]))

    while pending:
        nreg = int(registered.sum())
        ready = [fi for fi in pending if failed_at.get(fi, -1) < nreg]
        if ready:
            hp = has_point()
            fi = ready[int(np.argmax([sees(f, hp) for f in ready]))]
            if register(fi, fallback=False):
                pending.remove(fi)
            else:
                failed_at[fi] = nreg
            continue
        # every frame left failed since the last registration: the fallbacks, the frame
        # that sees the most points first
        hp = has_point()
        order = sorted(pending, key=lambda f: -sees(f, hp))
        done = next((f for f in order if register(f, fallback=True)), None)
        if done is None:
            break
        pending.remove(done)
    notes += [why_not[fi] for fi in sorted(pending)]
    # the final adjustment: robust, outliers out, the tracks completed, merged and
    # re-triangulated, robust again, then plain least squares on what is left
    adjust(2.0, 30, refine_focal, lens=True)
    filter_obs(max_err)
    complete(2.0)
    triangulate(np.arange(n_tracks))
    adjust(1.0, 30, refine_focal, lens=True)
    filter_obs(2.0)
    adjust(0.0, 50, refine_focal, lens=True)
    filter_obs(2.0)
    if radial_k1 is not None and radial_given is not None:
        choose_lens(radial_given)
    focal_fit = None if refine_focal else check_focal()
    focal_sd = focal_spread() if refine_focal else None
    # the output in the first registered frame's camera frame (frame 0 when registered):
    # X' = R_f X + t_f, R_i' = R_i R_f^T, t_i' = t_i - R_i' t_f (a rigid motion: the
    # reprojections and the initial pair's baseline stay)
    hp = has_point()
    f0 = int(np.flatnonzero(registered)[0])
    Rf, tf = Rs[f0].copy(), ts[f0].copy()
    Rs[registered] = Rs[registered] @ Rf.T
    ts[registered] = ts[registered] - Rs[registered] @ tf
    P[hp] = P[hp] @ Rf.T + tf
    Rs[f0], ts[f0] = np.eye(3), np.zeros(3)
    # the output: the tracks with a point, renumbered
    pid = -np.ones(n_tracks, np.int64)
    pid[hp] = np.arange(int(hp.sum()))
    ids = np.flatnonzero(registered[o_frame] & o_ok & hp[o_track])
    Pout = P[hp]
    length = np.bincount(pid[o_track[ids]], minlength=Pout.shape[0]).astype(np.int64)
    fr = o_frame[ids]
    proj, _ = _project_obs(k, Rs[fr], ts[fr], P[o_track[ids]])
    e2 = image_error(ids, proj) ** 2
    residuals = np.sqrt(e2)  # every kept observation's reprojection error, after the final BA
    # the tracks kept (frame, keypoint, point), for a model choice on common data
    # (_track_cost); keyed by the residuals' array, which replace() keeps
    kept = (residuals, fr.copy(), o_kp[ids].copy(), pid[o_track[ids]])
    cache.setdefault("tracks", []).append(kept)
    if _TRACE is not None:
        _TRACE.update({"o_frame": o_frame.copy(), "o_kp": o_kp.copy(), "o_track": o_track.copy()})
        _TRACE.update(
            {"o_ok": o_ok.copy(), "has_point": hp.copy(), "registered": registered.copy()}
        )
        _TRACE["order"] = list(reg_order)
    cnt = np.bincount(fr, minlength=n)
    with np.errstate(invalid="ignore", divide="ignore"):
        rms = np.sqrt(np.bincount(fr, weights=e2, minlength=n) / cnt)
    rms[~registered | (cnt == 0)] = np.nan
    Rs[~registered], ts[~registered] = np.nan, np.nan
    # colours from each point's first view
    first = -np.ones(n_tracks, np.int64)
    first[o_track[ids[::-1]]] = ids[::-1]
    first = first[hp]
    colors = np.zeros((Pout.shape[0], 3), np.uint8)
    for f in np.unique(o_frame[first]).tolist():
        sel = o_frame[first] == f
        im = np.asarray(images[f])
        xy = np.round(feats[f].xy[o_kp[first[sel]]]).astype(np.int64)
        x = np.clip(xy[:, 0], 0, im.shape[1] - 1)
        y = np.clip(xy[:, 1], 0, im.shape[0] - 1)
        v = _as_uint8(im[y, x], im.dtype, im)
        colors[sel] = v[:, :3] if v.ndim == 2 else v[:, None]
    if focal_fit is not None and abs(focal_fit / k[0, 0] - 1) > _FOCAL_CHECK:
        notes.append(
            f"the focal length fits the frames poorly: a bundle adjustment that refines it "
            f"finds f = {focal_fit:.1f} px, the camera's is {k[0, 0]:.1f} px "
            f"({100 * (focal_fit / k[0, 0] - 1):+.0f} %); check the camera (its image size, "
            "a zoom) or refine it (refine_focal; imageform reconstruct --refine-focal)"
        )
    return Reconstruction(
        Rs, ts, registered, Pout, colors, length, rms, notes, residuals, k, focal_fit, distortion,
        focal_sd,
    )  # fmt: skip
