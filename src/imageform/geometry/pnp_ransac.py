"""PnP with outliers: RANSAC over minimal linear solutions, then refinement on the inliers."""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from imageform import _deprecate
from imageform._random import RNGLike, as_rng
from imageform._validate import as_int, check_positive, check_rng
from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.geometry.distortion import DistortionModel
from imageform.geometry.pnp import (
    PnPResult,
    _is_planar,
    _normalised,
    _residuals,
    _validate,
    linear_pose,
    refine_pose,
)
from imageform.geometry.rotations import matrix_to_rvec

__all__ = ["solve_pnp_ransac"]

#: Hypotheses scored together (one batched linear solve).
BATCH = 64


@_deprecate.parameters(renamed={"seed": "rng", "max_hypotheses": "max_trials"})
def solve_pnp_ransac(
    object_points: npt.ArrayLike,
    image_points: npt.ArrayLike,
    K: npt.ArrayLike,
    distortion: DistortionModel | None = None,
    *,
    threshold: float = 2.0,
    confidence: float = 0.999,
    max_trials: int = 2000,
    rng: RNGLike = 0,
    max_iter: int = 20,
) -> PnPResult:
    r"""Pose of a calibrated camera from correspondences with outliers (RANSAC + LM).

    Minimal samples (6 points, 4 for a planar set) give linear poses, scored in batches of
    64 by the number of inliers ``‖u - û‖ < threshold`` (pixels, points in front of the
    camera only); the number of hypotheses adapts to the inlier ratio ``ε``:

    .. math:: k = \frac{\log(1 - p)}{\log(1 - \varepsilon^s)}

    The best pose is refined (LM) on its inliers, and the inliers are re-selected with the
    refined pose (Fischler & Bolles 1981, "Random sample consensus", CACM 24(6); the
    adaptive count as Hartley & Zisserman 2nd ed., Algorithm 4.5).

    Parameters
    ----------
    object_points, image_points : array_like (N, 3), (N, 2)
        One problem (loop over problems for several).
    K, distortion
        As :func:`~imageform.geometry.solve_pnp`.
    threshold : float
        Inlier threshold in pixels.
    confidence : float
        Probability ``p`` of drawing at least one outlier-free sample, in (0, 1).
    max_trials : int
        Upper bound on the number of samples (``max_hypotheses`` is its deprecated name).
    rng : int, numpy.random.Generator or None
        The sampler's random source (SPEC 7): an int seeds a new Generator (reproducible
        by default, ``rng=0``), a Generator is used as is, None draws fresh entropy.
    max_iter : int
        LM iterations of the final refinement.

    Returns
    -------
    PnPResult
        Scalar batch shape; ``inliers (N,)``; ``valid`` False when fewer than the minimal
        number of inliers was found.

    Examples
    --------
    >>> K = np.array([[800.0, 0, 320], [0, 800, 240], [0, 0, 1]])
    >>> X = np.random.default_rng(1).uniform(-1, 1, (40, 3))
    >>> uv = (X + [0, 0, 6]) @ K.T
    >>> uv = uv[:, :2] / uv[:, 2:]
    >>> uv[:8] += 50.0  # 8 outliers
    >>> res = solve_pnp_ransac(X, uv, K)
    >>> int(res.inliers.sum()), (res.tvec.round(9) + 0.0).tolist()
    (32, [0.0, 0.0, 6.0])
    """
    X, uv, Km, batch, out_dtype = _validate(object_points, image_points, K, distortion)
    if batch != ():
        raise InvalidInputError(
            f"expected one problem of shape (N, 3), (N, 2), got object_points {X.shape}; "
            "call solve_pnp_ransac per problem"
        )
    max_trials = as_int(max_trials, "max_trials", minimum=1, maximum=10**8)
    max_iter = as_int(max_iter, "max_iter", minimum=1, maximum=10**6)
    thr = check_positive(threshold, "threshold")
    p = check_positive(confidence, "confidence")
    if p >= 1.0:
        raise InvalidInputError(f"expected confidence in (0, 1), got {confidence!r}")
    N = X.shape[0]
    planar = bool(_is_planar(X[None])[0])
    s = 4 if planar else 6
    if s > N:
        raise DegenerateConfigurationError(
            f"expected at least {s} points for {'planar ' if planar else ''}PnP, got {N}"
        )
    xy = _normalised(uv[None], Km, distortion)[0]
    uvi = np.stack(
        [Km[0, 0] * xy[:, 0] + Km[0, 1] * xy[:, 1] + Km[0, 2], Km[1, 1] * xy[:, 1] + Km[1, 2]], -1
    )
    gen = as_rng(check_rng(rng))
    best_count, best_R, best_t = -1, np.eye(3), np.zeros(3)
    needed, drawn = float(max_trials), 0
    while drawn < min(needed, max_trials):
        idx = np.argsort(gen.random((BATCH, N)), axis=1)[:, :s]
        with np.errstate(all="ignore"):
            R, t = linear_pose(X[idx], xy[idx])
            r, cam = _residuals(R, t, np.broadcast_to(X, (BATCH, N, 3)), uvi[None], Km)
            err = np.hypot(r[..., 0], r[..., 1])
        inl = (err < thr) & (cam[..., 2] > 0)
        counts = inl.sum(axis=1)
        k = int(np.argmax(counts))
        drawn += BATCH
        if counts[k] > best_count:
            best_count, best_R, best_t = int(counts[k]), R[k], t[k]
            eps = best_count / N
            if eps >= 1.0:
                needed = 0.0
            elif eps > 0:
                needed = math.log(1 - p) / math.log(max(1e-300, 1 - eps**s))
    r, cam = _residuals(best_R[None], best_t[None], X[None], uvi[None], Km)
    inliers = (np.hypot(r[0, :, 0], r[0, :, 1]) < thr) & (cam[0, :, 2] > 0)
    R, t = best_R[None], best_t[None]
    if inliers.sum() >= s:
        for _ in range(2):
            w = inliers[None].astype(np.float64)
            R, t, _rms = refine_pose(R, t, X[None], uvi[None], Km, w, max_iter)
            r, cam = _residuals(R, t, X[None], uvi[None], Km)
            inliers = (np.hypot(r[0, :, 0], r[0, :, 1]) < thr) & (cam[0, :, 2] > 0)
    n_in = int(inliers.sum())
    rms = np.sqrt(np.sum(r[0][inliers] ** 2) / max(n_in, 1))
    valid = n_in >= s and bool(np.all(cam[0, inliers, 2] > 0))
    return PnPResult(
        np.asarray(matrix_to_rvec(R[0]), dtype=out_dtype),
        t[0].astype(out_dtype),
        R[0].astype(out_dtype),
        np.asarray(rms, dtype=out_dtype),
        np.asarray(valid),
        inliers,
    )
