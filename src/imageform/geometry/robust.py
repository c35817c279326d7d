"""Robust homography: RANSAC (MSAC scoring, LO-RANSAC, adaptive trials) and LM refinement.

:func:`find_homography` is imageform's counterpart of OpenCV's ``findHomography(...,
RANSAC)``: minimal 4-point DLT hypotheses scored by the truncated forward transfer error,
each new best model locally optimised by iterated least squares on its inliers, then the
final model refined by Levenberg-Marquardt on the reprojection error of its inliers.
"""

from __future__ import annotations

from typing import Literal, NamedTuple

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from imageform._backend import use_numba
from imageform._random import RNGLike, as_rng
from imageform._validate import as_int, check_option, check_positive
from imageform.errors import DegenerateConfigurationError
from imageform.geometry import _robust_core
from imageform.geometry._minimal import null_space
from imageform.geometry._robust_core import (
    check_confidence,
    check_pairs,
    hartley,
    levenberg_marquardt,
    ransac,
    result_dtype,
)

__all__ = ["HomographyResult", "find_homography"]

F64 = NDArray[np.float64]

_REFINE = ("symmetric", "forward", "none")
_REFINE_CODE = {"forward": 0, "symmetric": 1, "none": -1}
#: Sample and iteration counts beyond this are the same as unbounded (an int64 for numba).
_INT_CAP = 2**62


class HomographyResult(NamedTuple):
    """A robustly estimated homography ``dst ~ H src``.

    ``H (3, 3)`` scaled to ``H[2, 2] = 1``; ``inliers (N,)`` the correspondences whose
    forward transfer error is below the threshold; ``rms`` the forward transfer RMS of the
    inliers in pixels; ``trials`` the number of minimal samples drawn.
    """

    H: F64
    inliers: NDArray[np.bool_]
    rms: float
    trials: int


def _dlt(s: F64, d: F64, w: F64 | None = None) -> F64:
    """Homographies (B, 3, 3) from (B, n, 2) correspondences by the (weighted) DLT."""
    x, y = s[..., 0], s[..., 1]
    u, v = d[..., 0], d[..., 1]
    one, zero = np.ones_like(x), np.zeros_like(x)
    r1 = np.stack((zero, zero, zero, -x, -y, -one, v * x, v * y, v), axis=-1)
    r2 = np.stack((x, y, one, zero, zero, zero, -u * x, -u * y, -u), axis=-1)
    if w is not None:
        r1, r2 = r1 * w[..., None], r2 * w[..., None]
    A = np.concatenate((r1, r2), axis=-2)
    if A.shape[-2] < 9:
        h = null_space(A)[..., 0]
    else:
        h = np.linalg.eigh(np.swapaxes(A, -1, -2) @ A)[1][..., 0]
    return h.reshape(*h.shape[:-1], 3, 3)


def _transfer(H: F64, p: F64) -> F64:
    """``H`` (..., 3, 3) applied to points (N, 2): (..., N, 2), NaN at infinity."""
    q = p @ np.swapaxes(H[..., :, :2], -1, -2) + H[..., None, :, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        return q[..., :2] / q[..., 2:3]


def _transfer_jac(M: F64, p: F64) -> F64:
    """Jacobian (2N, 9) of the flattened ``π(M x̃)`` (N, 2) with respect to ``M`` (row-major)."""
    n = p.shape[0]
    xh = np.c_[p, np.ones(n)]
    q = xh @ M.T
    iw = 1.0 / q[:, 2]
    u, v = q[:, 0] * iw, q[:, 1] * iw
    J = np.zeros((n, 2, 9))
    J[:, 0, 0:3] = xh * iw[:, None]
    J[:, 0, 6:9] = -xh * (u * iw)[:, None]
    J[:, 1, 3:6] = xh * iw[:, None]
    J[:, 1, 6:9] = -xh * (v * iw)[:, None]
    return J.reshape(2 * n, 9)


def _sq_forward(H: F64, src: F64, dst: F64) -> F64:
    r = _transfer(H, src) - dst
    return np.sum(r * r, axis=-1)


def _refine(H: F64, src: F64, dst: F64, mode: str, max_iter: int) -> F64:
    """Refine ``H`` by LM on the forward (``dst``) or symmetric transfer error.

    The parameters ``H`` are in Hartley-normalised coordinates (gauge: the scale, left to the
    damping).
    """
    sn, Ts = hartley(src)
    dn, Td = hartley(dst)
    Tdi = np.linalg.inv(Td)
    Hn = Td @ H @ np.linalg.inv(Ts)
    Hn = Hn / np.linalg.norm(Hn)
    sd = 1.0 / Td[0, 0]  # normalised -> pixel scale of dst
    ss = 1.0 / Ts[0, 0]

    def residual(h: F64) -> F64:
        M = h.reshape(3, 3)
        r = (_transfer(M, sn) - dn).ravel() * sd
        if mode == "symmetric":
            Mi = np.asarray(np.linalg.inv(M), dtype=np.float64)
            r = np.concatenate([r, (_transfer(Mi, dn) - sn).ravel() * ss])
        return r

    def jacobian(h: F64) -> F64:
        M = h.reshape(3, 3)
        J = _transfer_jac(M, sn) * sd
        if mode == "symmetric":
            Mi = np.asarray(np.linalg.inv(M), dtype=np.float64)
            # d(M⁻¹)/dM_kl = -M⁻¹ E_kl M⁻¹
            G = -np.einsum("ik,lj->ijkl", Mi, Mi).reshape(9, 9)
            J = np.concatenate([J, (_transfer_jac(Mi, dn) @ G) * ss])
        return J

    with np.errstate(all="ignore"):
        h, _ = levenberg_marquardt(residual, Hn.ravel(), max_iter=max_iter, jacobian=jacobian)
    out = Tdi @ h.reshape(3, 3) @ Ts
    return out


def _normalise_scale(H: F64) -> F64:
    return H / H[2, 2] if abs(H[2, 2]) > 1e-12 * np.linalg.norm(H) else H / np.linalg.norm(H)


def _finish(
    H: F64, s: F64, d: F64, thr: float, drawn: int, src: object, dst: object
) -> HomographyResult:
    H = _normalise_scale(H)
    e = _sq_forward(H, s, d)
    inl = e < thr * thr
    rms = float(np.sqrt(np.mean(e[inl]))) if inl.any() else float("nan")
    return HomographyResult(H.astype(result_dtype(src, dst)), inl, rms, drawn)


def _find_homography_numba(
    s: F64,
    d: F64,
    thr: float,
    p: float,
    trials: int,
    mode: str,
    n_iter: int,
    rng: RNGLike,
    src: object,
    dst: object,
) -> HomographyResult:
    """:func:`find_homography` by the compiled kernel (same steps, see ``_kernels.ransac``)."""
    from imageform._kernels.ransac_h import homography_estimate

    H = np.empty((3, 3))
    inl = np.empty(s.shape[0], dtype=bool)
    rms = np.empty(1)
    drawn = homography_estimate(
        np.ascontiguousarray(s),
        np.ascontiguousarray(d),
        thr,
        p,
        min(trials, _INT_CAP),
        _robust_core.kernel_seed(rng),
        _REFINE_CODE[mode],
        min(n_iter, _INT_CAP),
        _robust_core.REFINE_FACTOR,
        _robust_core.TERMINATION_FACTOR,
        _robust_core.H_SUPPORT_WIDTH,
        H,
        inl,
        rms,
    )
    if drawn < 0:
        raise DegenerateConfigurationError(
            f"no homography from src to dst with at least 4 inliers within {thr:g} px after "
            f"{-drawn} samples"
        )
    # the kernel scaled H as _normalise_scale and wrote its inliers and their RMS
    return HomographyResult(H.astype(result_dtype(src, dst)), inl, float(rms[0]), int(drawn))


def find_homography(
    src: npt.ArrayLike,
    dst: npt.ArrayLike,
    *,
    threshold: float = 3.0,
    confidence: float = 0.999,
    max_trials: int = 2000,
    refine: Literal["symmetric", "forward", "none"] = "symmetric",
    max_iter: int = 50,
    rng: RNGLike = 0,
) -> HomographyResult:
    r"""Homography ``dst ~ H src`` from correspondences with outliers (RANSAC + LM).

    Minimal samples of 4 correspondences give hypotheses by the normalised DLT, scored by
    the truncated forward transfer error (MSAC)

    .. math:: C(H) = \sum_i \min\left(\| \mathbf{x}'_i - \pi(H \tilde{\mathbf{x}}_i)
              \|^2, \tau^2\right),

    the number of samples adapting to the inlier ratio (``k = log(1-p) / log(1-ε⁴)``); each
    new best hypothesis is re-fitted by least squares on its inliers (LO-RANSAC). The final
    ``H`` minimises, by Levenberg-Marquardt, the symmetric transfer error
    ``Σ ‖x' - π(H x)‖² + ‖x - π(H⁻¹ x')‖²`` (``refine="symmetric"``, noise in both images)
    or the forward one (``"forward"``, as OpenCV) of the correspondences within the
    refinement support (``4.29σ̂``, the 99.99 % quantile of a 2-D residual, with ``σ̂`` the
    noise estimated from the inliers, between ``τ`` and ``2τ``); the inliers are those
    within ``τ`` of the final ``H``.

    Parameters
    ----------
    src, dst : array_like (N, 2)
        Corresponding pixels, N >= 4.
    threshold : float
        Inlier threshold ``τ`` on the forward transfer error, pixels.
    confidence : float
        Probability ``p`` in (0, 1) of drawing an outlier-free sample.
    max_trials : int
        Upper bound on the number of minimal samples.
    refine : {"symmetric", "forward", "none"}
        Error minimised by the final LM.
    max_iter : int
        LM iterations.
    rng : int, numpy.random.Generator or None
        The sampler's random source (SPEC 7); ``rng=0`` (default) is reproducible.

    Returns
    -------
    HomographyResult
        ``H``, ``inliers``, ``rms`` (pixels), ``trials``.

    Raises
    ------
    InvalidInputError
        Shapes other than (N, 2), different lengths, N < 4, NaN or inf, a bad option.
    DegenerateConfigurationError
        No hypothesis with 4 inliers was found.

    References
    ----------
    Hartley & Zisserman, *Multiple View Geometry* 2nd ed., Algorithms 4.2, 4.6; Torr &
    Zisserman (2000), "MLESAC", CVIU 78; Chum, Matas & Kittler (2003), "Locally optimized
    RANSAC", DAGM.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> src = rng.uniform(0, 640, (50, 2))
    >>> H = np.array([[1.1, 0.05, 12.0], [-0.03, 0.95, -7.0], [1e-4, 2e-4, 1.0]])
    >>> q = np.c_[src, np.ones(50)] @ H.T
    >>> dst = q[:, :2] / q[:, 2:]
    >>> dst[:10] += 40.0   # 10 outliers
    >>> res = find_homography(src, dst)
    >>> int(res.inliers.sum()), bool(np.allclose(res.H, H, atol=1e-9))
    (40, True)
    """
    s, d = check_pairs(src, dst, "src", "dst", 4)
    thr = check_positive(threshold, "threshold")
    p = check_confidence(confidence)
    trials = as_int(max_trials, "max_trials", minimum=1)
    mode = check_option(refine, _REFINE, "refine")
    n_iter = as_int(max_iter, "max_iter", minimum=0)
    if use_numba(s):
        return _find_homography_numba(s, d, thr, p, trials, mode, n_iter, rng, src, dst)
    gen = as_rng(rng)
    n = s.shape[0]
    sn, Ts = hartley(s)
    dn, Td = hartley(d)
    Tdi = np.linalg.inv(Td)

    def denorm(Hn: F64) -> F64:
        return Tdi @ Hn @ Ts

    def solve(idx: NDArray[np.intp]) -> F64:
        Hs = denorm(_dlt(sn[idx], dn[idx]))
        ok = np.all(np.isfinite(Hs), axis=(-2, -1))
        return Hs[ok]

    def sq(models: F64) -> F64:
        return _sq_forward(models, s, d)

    def local_opt(H: F64, inl: NDArray[np.bool_]) -> F64:
        for m in (2.0, 1.5, 1.0):
            e = _sq_forward(H, s, d)
            sel = e < (m * thr) ** 2
            if sel.sum() < 5:
                break
            H = denorm(_dlt(sn[sel][None], dn[sel][None])[0])
        return H

    H, inl, drawn = ransac(n, 4, solve, sq, thr, p, trials, gen, local_opt)
    if H is None or inl.sum() < 4:
        raise DegenerateConfigurationError(
            f"no homography from src to dst with at least 4 inliers within {thr:g} px after "
            f"{drawn} samples"
        )
    if mode != "none" and inl.sum() > 4:
        H = _robust_core.refit_on_support(
            H,
            lambda m: _sq_forward(m, s, d),
            lambda m, sel: _refine(m, s[sel], d[sel], mode, n_iter),
            thr,
            2,
            4,
            width=_robust_core.H_SUPPORT_WIDTH,
        )
    return _finish(H, s, d, thr, drawn, src, dst)
