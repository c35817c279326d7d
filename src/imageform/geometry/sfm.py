r"""Structure from motion: camera poses and 3-D points from an ordered set of frames.

The course's second application: with the intrinsics known (a calibrated endoscope), the
frames of a video give, by correspondences, the camera's motion and the scene's shape. The
pipeline, each step a public function:

1. :func:`detect_features`: SIFT keypoints (scale- and rotation-invariant, sub-pixel,
   OpenCV's implementation, the ``reconstruct`` extra) and their 128-number descriptors;
2. :func:`match_features`: nearest neighbours by descriptor distance with Lowe's ratio test
   (the nearest clearly nearer than the second) and a mutual check (each the other's
   nearest);
3. geometric verification of each pair (sequential neighbours in a video) by the essential
   matrix (:func:`~imageform.geometry.find_essential_matrix`, 5-point LO-RANSAC) on the
   undistorted keypoints;
4. tracks: the verified matches joined across frames (union-find), one 3-D point each;
5. the initial pair: the early pair with the most inliers among those with enough parallax
   (median triangulation angle of 2 degrees or more), its relative pose
   (:func:`~imageform.geometry.recover_pose`) and its triangulated points;
6. incremental registration: each next frame's pose from its 2-D/3-D correspondences
   (:func:`~imageform.geometry.solve_pnp_ransac`), then every track seen by two registered
   frames triangulated (:func:`~imageform.geometry.triangulate_points`) when its rays meet
   at 1.5 degrees or more and it reprojects within 4 pixels in front of every camera;
7. bundle adjustment (:func:`bundle_adjust`): every pose (the first fixed) and every point
   refined together by minimising the reprojection error, scipy's ``least_squares`` with a
   sparse Jacobian and a Huber loss; observations beyond 4 pixels are then dropped and the
   adjustment run again.

The reconstruction is up to a similarity (a rotation, a translation and a scale): the first
camera is the world frame and the initial pair's baseline has length 1.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imageform._validate import as_int, as_real, as_real_array, describe
from imageform.errors import DegenerateConfigurationError, InvalidInputError

__all__ = [
    "Features",
    "Reconstruction",
    "bundle_adjust",
    "detect_features",
    "match_features",
    "reconstruct_sequence",
]

F64 = NDArray[np.float64]


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


def detect_features(image: object, *, max_features: int = 4000) -> Features:
    """Detect SIFT keypoints and descriptors (OpenCV's SIFT, the ``reconstruct`` extra).

    Parameters
    ----------
    image : array_like (H, W) or (H, W, 3)
        uint8 (or floats in [0, 1]) grey or RGB.
    max_features : int
        Keep the strongest this many.

    Returns
    -------
    Features
    """
    from imageform._optional import require

    cv2 = require("cv2", what="imageform reconstruct's keypoints (SIFT)")
    n = as_int(max_features, "max_features", minimum=8, maximum=1_000_000)
    a = np.asarray(image)
    if a.ndim == 3 and a.shape[-1] == 3:
        a = a @ np.array([0.299, 0.587, 0.114])
    elif a.ndim == 3 and a.shape[-1] == 1:
        a = a[..., 0]
    if a.ndim != 2 or a.size == 0:
        raise InvalidInputError(f"expected image as (H, W) or (H, W, 3), got {describe(image)}")
    if a.dtype != np.uint8:
        a = np.clip(a * (255.0 if a.dtype.kind == "f" and a.max() <= 1.0 else 1.0), 0, 255)
        a = np.round(a).astype(np.uint8)
    sift = cv2.SIFT_create(nfeatures=n)
    kps, desc = sift.detectAndCompute(a, None)
    if desc is None or not kps:
        return Features(np.zeros((0, 2)), np.zeros((0, 128), np.float32), np.zeros(0), np.zeros(0))
    xy = np.array([k.pt for k in kps], np.float64)
    return Features(
        xy,
        np.asarray(desc, np.float32),
        np.array([k.size for k in kps], np.float64),
        np.array([k.angle for k in kps], np.float64),
    )


def match_features(
    a: NDArray[np.float32], b: NDArray[np.float32], *, ratio: float = 0.8, mutual: bool = True
) -> NDArray[np.int64]:
    r"""Match descriptors by nearest neighbour, Lowe's ratio test and a mutual check.

    A pair ``(i, j)`` is kept when ``b[j]`` is ``a[i]``'s nearest neighbour with
    :math:`d_1 < \rho\, d_2` (the second nearest clearly farther; Lowe 2004, IJCV 60(2),
    sec. 7.1) and, with ``mutual``, ``a[i]`` is ``b[j]``'s nearest as well.

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
    # squared distances |a|^2 + |b|^2 - 2 a.b, in one matrix product
    d2 = (a * a).sum(1)[:, None] + (b * b).sum(1)[None, :] - 2.0 * (a @ b.T)
    np.maximum(d2, 0.0, out=d2)
    rows = np.arange(a.shape[0])
    back = np.argmin(d2, axis=0) if mutual else None
    best = np.argmin(d2, axis=1)
    d1 = d2[rows, best].copy()
    d2[rows, best] = np.inf  # the second nearest is the nearest of the rest
    d2nd = d2.min(axis=1)
    keep = d1 < (r * r) * d2nd
    if back is not None:
        keep &= back[best] == rows
    idx = np.flatnonzero(keep)
    return np.column_stack([idx, best[idx]]).astype(np.int64)


@dataclass
class Reconstruction:
    """The result of :func:`reconstruct_sequence`.

    Attributes
    ----------
    R : ndarray (n, 3, 3), t : ndarray (n, 3)
        World to camera poses (NaN for frames not registered); the first registered frame
        of the initial pair is the world frame.
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
        What failed and why (frames that could not be registered, ...).
    residuals_px : ndarray (M,)
        The reprojection error of every observation the final bundle adjustment kept
        (pixels; the distance between the observed keypoint and its point's projection).
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


class _Tracks:
    """Union-find over (frame, keypoint) observations."""

    def __init__(self, sizes: list[int]) -> None:
        self.offset = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        self.parent = np.arange(int(self.offset[-1]), dtype=np.int64)

    def find(self, x: int) -> int:
        p = self.parent
        root = x
        while p[root] != root:
            root = int(p[root])
        while p[x] != root:
            p[x], x = root, int(p[x])
        return root

    def union(self, a: int, b: int) -> None:
        ra, rb = self.find(a), self.find(b)
        if ra != rb:
            self.parent[max(ra, rb)] = min(ra, rb)

    def node(self, frame: int, k: int) -> int:
        return int(self.offset[frame]) + k


def _angle_deg(C1: F64, C2: F64, X: F64) -> F64:
    a, b = X - C1, X - C2
    c = np.sum(a * b, axis=1) / (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1) + 1e-300)
    return np.degrees(np.arccos(np.clip(c, -1.0, 1.0)))


def _skew_batch(v: F64) -> F64:
    """Return the cross-product matrices ``[v]x`` of ``(M, 3)`` vectors as ``(M, 3, 3)``."""
    S = np.zeros((v.shape[0], 3, 3))
    S[:, 0, 1], S[:, 0, 2] = -v[:, 2], v[:, 1]
    S[:, 1, 0], S[:, 1, 2] = v[:, 2], -v[:, 0]
    S[:, 2, 0], S[:, 2, 1] = -v[:, 1], v[:, 0]
    return S


def _project(K: F64, R: F64, t: F64, X: F64) -> tuple[F64, F64]:
    Xc = X @ R.T + t
    z = Xc[:, 2]
    uv = (Xc @ K.T)[:, :2] / np.where(np.abs(z) > 1e-12, z, np.nan)[:, None]
    return uv, z


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
              \pi\left(K (R_i X_j + t_i)\right) \right\|^2\right)

    with :math:`\rho` the Huber loss at ``loss_px`` pixels (Triggs et al. 2000, "Bundle
    adjustment: a modern synthesis"). The poses are Rodrigues vectors and translations; the
    camera ``fixed`` stays where it is, and so does the scale, which the first pose does not
    fix: the other cameras' distance to it is kept by the points. Solved by scipy's
    trust-region reflective method with the Jacobian's sparsity pattern (each residual
    depends on one camera and one point).

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
        Most function evaluations.

    Returns
    -------
    R, t, points
        Refined.
    """
    from scipy.optimize import least_squares

    from imageform.geometry.rotations import matrix_to_rvec, rvec_to_matrix

    n, m = R.shape[0], points.shape[0]
    free = np.array([i for i in range(n) if i != fixed], np.int64)
    slot = -np.ones(n, np.int64)
    slot[free] = np.arange(free.size)
    r0 = np.array([np.asarray(matrix_to_rvec(R[i]), np.float64) for i in free]).reshape(-1, 3)
    x0 = np.concatenate([np.hstack([r0, t[free]]).ravel(), points.ravel()])
    Rf, tf = R[fixed], t[fixed]
    fx, fy, cx, cy, sk = K[0, 0], K[1, 1], K[0, 2], K[1, 2], K[0, 1]

    def unpack(x: F64) -> tuple[F64, F64, F64, F64]:
        cams = x[: 6 * free.size].reshape(-1, 6)
        X = x[6 * free.size :].reshape(m, 3)
        Rs = np.empty((n, 3, 3))
        ts = np.empty((n, 3))
        Rs[fixed], ts[fixed] = Rf, tf
        if free.size:
            Rs[free] = np.asarray(rvec_to_matrix(cams[:, :3]), np.float64)
            ts[free] = cams[:, 3:]
        return cams, X, Rs, ts

    def residuals(x: F64) -> F64:
        _, X, Rs, ts = unpack(x)
        Xc = np.einsum("mij,mj->mi", Rs[cam_idx], X[pt_idx]) + ts[cam_idx]
        z = np.where(np.abs(Xc[:, 2]) > 1e-9, Xc[:, 2], 1e-9)
        u = fx * Xc[:, 0] / z + sk * Xc[:, 1] / z + cx
        v = fy * Xc[:, 1] / z + cy
        return np.column_stack([u - uv[:, 0], v - uv[:, 1]]).ravel()

    M = cam_idx.shape[0]
    obs = np.arange(M)
    has = slot[cam_idx] >= 0
    # the Jacobian's pattern: rows 2k, 2k+1; the camera's 6 columns (if free), the point's 3
    cam_cols = 6 * np.maximum(slot[cam_idx], 0)[:, None] + np.arange(6)
    pt_cols = 6 * free.size + 3 * pt_idx[:, None] + np.arange(3)

    def jacobian(x: F64) -> Any:
        r"""Return the Jacobian: :math:`\partial(R v)/\partial r = -R [v]_\times J_r`.

        The derivative of a rotation by its Rodrigues vector (Gallego & Yezzi 2015).
        """
        from scipy.sparse import csr_matrix

        cams, X, Rs, ts = unpack(x)
        Rm = Rs[cam_idx]
        Xw = X[pt_idx]
        Xc = np.einsum("mij,mj->mi", Rm, Xw) + ts[cam_idx]
        z = np.where(np.abs(Xc[:, 2]) > 1e-9, Xc[:, 2], 1e-9)
        # d(u, v) / d Xc
        Jp = np.zeros((M, 2, 3))
        Jp[:, 0, 0] = fx / z
        Jp[:, 0, 1] = sk / z
        Jp[:, 0, 2] = -(fx * Xc[:, 0] + sk * Xc[:, 1]) / z**2
        Jp[:, 1, 1] = fy / z
        Jp[:, 1, 2] = -fy * Xc[:, 1] / z**2
        J_pt = Jp @ Rm  # d/dX
        if free.size:
            r = np.zeros((n, 3))
            r[free] = cams[:, :3]
            rv = r[cam_idx]
            th2 = np.sum(rv * rv, axis=1)
            skew_r = _skew_batch(rv)
            Jr = np.where(
                (th2 > 1e-16)[:, None, None],
                (rv[:, :, None] * rv[:, None, :] + (np.swapaxes(Rm, 1, 2) - np.eye(3)) @ skew_r)
                / np.maximum(th2, 1e-300)[:, None, None],
                np.eye(3),
            )
            dR = -Rm @ _skew_batch(Xw) @ Jr  # d(R X)/dr
            J_cam = np.concatenate([Jp @ dR, Jp], axis=2)  # (M, 2, 6): r then t
            rows_c = np.repeat(2 * obs[has], 6).reshape(-1, 6)
            data = [J_cam[has, 0].ravel(), J_cam[has, 1].ravel()]
            rr = [rows_c.ravel(), (rows_c + 1).ravel()]
            cc = [cam_cols[has].ravel(), cam_cols[has].ravel()]
        else:
            data, rr, cc = [], [], []
        rows_p = np.repeat(2 * obs, 3).reshape(-1, 3)
        data += [J_pt[:, 0].ravel(), J_pt[:, 1].ravel()]
        rr += [rows_p.ravel(), (rows_p + 1).ravel()]
        cc += [pt_cols.ravel(), pt_cols.ravel()]
        return csr_matrix(
            (np.concatenate(data), (np.concatenate(rr), np.concatenate(cc))),
            shape=(2 * M, x0.size),
        )

    sol = least_squares(
        residuals,
        x0,
        jac=jacobian,
        loss="huber" if loss_px > 0 else "linear",
        f_scale=float(loss_px) if loss_px > 0 else 1.0,
        x_scale=1.0,  # "jac" stopped on xtol far from the minimum (a 4-camera test: 1.45 px)
        max_nfev=max_nfev,
        method="trf",
        tr_solver="lsmr",
    )
    x = sol.x
    cams = x[: 6 * free.size].reshape(-1, 6)
    Rn, tn = R.copy(), t.copy()
    if free.size:
        Rn[free] = np.asarray(rvec_to_matrix(cams[:, :3]), np.float64)
        tn[free] = cams[:, 3:]
    return Rn, tn, x[6 * free.size :].reshape(m, 3)


def reconstruct_sequence(
    images: list[Any],
    K: object,
    distortion: object = None,
    *,
    window: int = 3,
    max_features: int = 4000,
    ratio: float = 0.8,
    threshold_px: float = 1.0,
    rng: int = 0,
) -> Reconstruction:
    """Reconstruct the cameras and a sparse point cloud from an ordered image sequence.

    Parameters
    ----------
    images : list of array_like
        The frames, in order (a video's), all of one size.
    K : array_like (3, 3)
        The camera's intrinsics.
    distortion : distortion model, optional
        Its lens distortion: keypoints are undistorted before any geometry.
    window : int
        Each frame is matched with the next ``window`` frames.
    max_features : int
        SIFT keypoints per frame.
    ratio : float
        Lowe's ratio.
    threshold_px : float
        The essential matrix's inlier threshold (Sampson distance, pixels).
    rng : int
        Seed of the RANSAC samplers.

    Returns
    -------
    Reconstruction

    Raises
    ------
    InvalidInputError
        Fewer than two frames, frames of different sizes.
    DegenerateConfigurationError
        No pair of frames with enough matches and parallax to start from.
    """
    from imageform.geometry.pnp_ransac import solve_pnp_ransac
    from imageform.geometry.relative_pose import recover_pose
    from imageform.geometry.triangulation import triangulate_points
    from imageform.geometry.twoview import find_essential_matrix

    if len(images) < 2:
        raise InvalidInputError(f"expected at least 2 frames, got {len(images)}")
    shapes = {np.asarray(im).shape[:2] for im in images}
    if len(shapes) != 1:
        raise InvalidInputError(f"expected frames of one size, got {sorted(shapes)}")
    k = np.asarray(K, np.float64)
    win = as_int(window, "window", minimum=1, maximum=100)
    n = len(images)
    feats = [detect_features(im, max_features=max_features) for im in images]
    # undistorted (ideal pinhole) pixels of every keypoint
    ideal: list[F64] = []
    for feat in feats:
        if distortion is not None and len(feat):
            xy = (feat.xy - k[:2, 2]) / np.diag(k)[:2]
            und, ok = distortion.undistort(xy)  # type: ignore[attr-defined]
            und = np.asarray(und, np.float64)
            und[~np.asarray(ok, bool)] = np.nan
            ideal.append(und * np.diag(k)[:2] + k[:2, 2])
        else:
            ideal.append(feat.xy.copy())
    notes: list[str] = []
    textured = [len(feat) for feat in feats]
    if max(textured) < 50:
        raise InvalidInputError(
            f"no texture: at most {max(textured)} keypoints a frame (50 needed to match)"
        )
    tracks = _Tracks(textured)
    pair_info: dict[tuple[int, int], tuple[int, float, F64]] = {}
    for i in range(n):
        for j in range(i + 1, min(n, i + 1 + win)):
            m = match_features(feats[i].descriptors, feats[j].descriptors, ratio=ratio)
            if m.shape[0] < 30:
                continue
            p1, p2 = ideal[i][m[:, 0]], ideal[j][m[:, 1]]
            good = np.all(np.isfinite(p1), 1) & np.all(np.isfinite(p2), 1)
            m, p1, p2 = m[good], p1[good], p2[good]
            if m.shape[0] < 30:
                continue
            try:
                er = find_essential_matrix(p1, p2, k, threshold=threshold_px, rng=rng)
            except (DegenerateConfigurationError, InvalidInputError):
                continue
            inl = np.asarray(er.inliers, bool)
            if inl.sum() < 30:
                continue
            for a, b in m[inl]:
                tracks.union(tracks.node(i, int(a)), tracks.node(j, int(b)))
            # parallax of the pair: the median angle between the rays of its inliers
            rp = recover_pose(er.E, p1, p2, k, inliers=inl)
            C2 = -np.asarray(rp.R).T @ np.asarray(rp.t).ravel()
            X = np.asarray(rp.points, np.float64)
            fin = np.all(np.isfinite(X), axis=1)
            ang = float(np.median(_angle_deg(np.zeros(3), C2, X[fin]))) if fin.any() else 0.0
            pair_info[(i, j)] = (int(inl.sum()), ang, m[inl])
    if not pair_info:
        raise DegenerateConfigurationError(
            "no pair of frames has 30 verified matches: too little overlap or texture"
        )
    # the tracks: every observation's root, and the observations of each multi-view track
    total = int(tracks.offset[-1])
    roots = np.array([tracks.find(x) for x in range(total)], np.int64)
    frame_of = np.searchsorted(tracks.offset, np.arange(total), side="right") - 1
    order = np.argsort(roots, kind="stable")
    bounds = np.flatnonzero(np.diff(roots[order])) + 1
    # a track with two keypoints in one frame joined two different points: dropped
    groups = [
        g for g in np.split(order, bounds) if g.size >= 2 and np.unique(frame_of[g]).size == g.size
    ]
    track_obs = [
        (frame_of[g].astype(np.int64), (g - tracks.offset[frame_of[g]]).astype(np.int64))
        for g in groups
    ]
    n_tracks = len(track_obs)
    # the initial pair: most inliers among pairs with 2 degrees of parallax or more
    cands = [(v[0], key) for key, v in pair_info.items() if v[1] >= 2.0]
    if not cands:
        cands = [(v[0], key) for key, v in pair_info.items()]
        notes.append("no pair with 2 degrees of parallax: started from the best matched one")
    _, (i0, j0) = max(cands)
    _, _, m0 = pair_info[(i0, j0)]
    p1, p2 = ideal[i0][m0[:, 0]], ideal[j0][m0[:, 1]]
    er = find_essential_matrix(p1, p2, k, threshold=threshold_px, rng=rng)
    rp = recover_pose(er.E, p1, p2, k, inliers=np.asarray(er.inliers, bool))
    Rs = np.full((n, 3, 3), np.nan)
    ts = np.full((n, 3), np.nan)
    Rs[i0], ts[i0] = np.eye(3), np.zeros(3)
    Rs[j0], ts[j0] = np.asarray(rp.R, np.float64), np.asarray(rp.t, np.float64).ravel()
    registered = np.zeros(n, bool)
    registered[[i0, j0]] = True
    point_of = -np.ones(n_tracks, np.int64)  # track -> point index
    pts: list[F64] = []
    # per frame: keypoint -> track (or -1)
    kp_track = [-np.ones(textured[f], np.int64) for f in range(n)]
    for tid, (fr, kp) in enumerate(track_obs):
        for f, q in zip(fr, kp, strict=True):
            kp_track[int(f)][int(q)] = tid

    def triangulate_new() -> None:
        """Triangulate every track seen by two registered frames and not yet a point."""
        todo = [
            tid
            for tid in range(n_tracks)
            if point_of[tid] < 0 and int(np.sum(registered[track_obs[tid][0]])) >= 2
        ]
        if not todo:
            return
        reg = np.flatnonzero(registered)
        slot = -np.ones(n, np.int64)
        slot[reg] = np.arange(reg.size)
        uv = np.full((reg.size, len(todo), 2), np.nan)
        for c, tid in enumerate(todo):
            fr, kp = track_obs[tid]
            for f, q in zip(fr, kp, strict=True):
                if registered[f]:
                    uv[slot[f], c] = ideal[int(f)][int(q)]
        P = np.stack([k @ np.hstack([Rs[g], ts[g][:, None]]) for g in reg])
        tri = triangulate_points(P, uv)
        X = np.asarray(tri.points, np.float64)
        valid = np.asarray(tri.valid, bool) & np.all(np.isfinite(X), axis=1)
        centres = np.stack([-Rs[g].T @ ts[g] for g in reg])
        for c, tid in enumerate(todo):
            if not valid[c]:
                continue
            seen = np.flatnonzero(np.all(np.isfinite(uv[:, c]), axis=1))
            Cs = centres[seen]
            x = X[c]
            rays = x - Cs
            rays /= np.linalg.norm(rays, axis=1, keepdims=True)
            cosines = rays @ rays.T
            if math.degrees(math.acos(float(np.clip(cosines.min(), -1, 1)))) < 1.5:
                continue
            ok = True
            for s in seen:
                proj, z = _project(k, Rs[reg[s]], ts[reg[s]], x[None])
                if z[0] <= 0 or np.linalg.norm(proj[0] - uv[s, c]) > 4.0:
                    ok = False
                    break
            if ok:
                point_of[tid] = len(pts)
                pts.append(x)

    triangulate_new()
    # register the others: the frame that sees the most points first
    pending = [fi for fi in range(n) if not registered[fi]]
    while pending:
        counts = []
        for fi in pending:
            tr = kp_track[fi]
            has = (tr >= 0) & np.isin(np.arange(tr.size), np.flatnonzero(tr >= 0))
            pid = np.where(has, point_of[np.maximum(tr, 0)], -1)
            counts.append(int(np.sum(pid >= 0)))
        fi = pending.pop(int(np.argmax(counts)))
        tr = kp_track[fi]
        pid = np.where(tr >= 0, point_of[np.maximum(tr, 0)], -1)
        kps = np.flatnonzero((pid >= 0) & np.all(np.isfinite(ideal[fi]), axis=1))
        if kps.size < 12:
            notes.append(f"frame {fi}: {kps.size} 2-D/3-D correspondences (12 needed)")
            continue
        X = np.array([pts[p] for p in pid[kps]])
        uv = ideal[fi][kps]
        try:
            res = solve_pnp_ransac(X, uv, k, threshold=3.0, rng=rng)
        except (DegenerateConfigurationError, InvalidInputError):
            notes.append(f"frame {fi}: PnP failed")
            continue
        if not bool(res.valid) or int(np.sum(res.inliers)) < 12:
            notes.append(f"frame {fi}: PnP found {int(np.sum(res.inliers))} inliers (12 needed)")
            continue
        Rs[fi], ts[fi] = np.asarray(res.R, np.float64), np.asarray(res.tvec, np.float64)
        registered[fi] = True
        triangulate_new()
    # bundle adjustment over everything, twice (the second without the outliers)
    P = np.array(pts, np.float64).reshape(-1, 3)
    reg = np.flatnonzero(registered)
    cam_slot = -np.ones(n, np.int64)
    cam_slot[reg] = np.arange(reg.size)
    obs_c, obs_p, obs_uv = [], [], []
    for tid in np.flatnonzero(point_of >= 0).tolist():
        fr, kp = track_obs[tid]
        for gi, q in zip(fr.tolist(), kp.tolist(), strict=True):
            if registered[gi] and np.all(np.isfinite(ideal[int(gi)][int(q)])):
                obs_c.append(cam_slot[gi])
                obs_p.append(point_of[tid])
                obs_uv.append(ideal[int(gi)][int(q)])
    ci, pi, uvo = np.array(obs_c, np.int64), np.array(obs_p, np.int64), np.array(obs_uv)
    Rr, t_reg = Rs[reg], ts[reg]
    fixed = int(cam_slot[i0])
    if P.shape[0]:
        for loss in (2.0, 0.0):  # robust first, then plain least squares without outliers
            Rr, t_reg, P = bundle_adjust(k, Rr, t_reg, P, ci, pi, uvo, fixed=fixed, loss_px=loss)
            Xc = np.einsum("mij,mj->mi", Rr[ci], P[pi]) + t_reg[ci]
            proj = (Xc @ k.T)[:, :2] / Xc[:, 2:3]
            err = np.where(Xc[:, 2] > 0, np.linalg.norm(proj - uvo, axis=1), np.inf)
            keep = np.isfinite(err) & (err < 4.0)
            ci, pi, uvo = ci[keep], pi[keep], uvo[keep]
    Rs[reg], ts[reg] = Rr, t_reg
    rms = np.full(n, np.nan)
    for slot_i, gi in enumerate(reg.tolist()):
        sel = ci == slot_i
        if sel.any():
            proj, _ = _project(k, Rr[slot_i], t_reg[slot_i], P[pi[sel]])
            rms[gi] = float(np.sqrt(np.mean(np.sum((proj - uvo[sel]) ** 2, axis=1))))
    length = np.bincount(pi, minlength=P.shape[0]).astype(np.int64)
    colors = np.zeros((P.shape[0], 3), np.uint8)
    for tid in np.flatnonzero(point_of >= 0).tolist():
        fr, kp = track_obs[tid]
        g0, q = int(fr[0]), int(kp[0])
        im = np.asarray(images[g0])
        x, y = np.round(feats[g0].xy[q]).astype(int)
        v = im[min(max(y, 0), im.shape[0] - 1), min(max(x, 0), im.shape[1] - 1)]
        colors[point_of[tid]] = v[:3] if np.ndim(v) else v
    residuals = np.zeros(0)
    if ci.size:  # every kept observation's reprojection error, after the final adjustment
        Xc = np.einsum("mij,mj->mi", Rr[ci], P[pi]) + t_reg[ci]
        residuals = np.linalg.norm((Xc @ k.T)[:, :2] / Xc[:, 2:3] - uvo, axis=1)
    return Reconstruction(Rs, ts, registered, P, colors, length, rms, notes, residuals)
