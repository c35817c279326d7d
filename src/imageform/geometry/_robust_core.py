"""The RANSAC engine, a small Levenberg-Marquardt solver and input checks.

They are shared by the robust two-view estimators (:mod:`imageform.geometry.robust`,
:mod:`.twoview`).

Internal to :mod:`imageform.geometry`.
"""

from __future__ import annotations

import functools
import math
import numbers
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from imageform._backend import to_numpy
from imageform._random import as_rng
from imageform._validate import MAX_MAGNITUDE, check_positive, describe
from imageform._validate import as_points_bounded as as_points
from imageform.errors import InvalidInputError

__all__ = [
    "F_REFINE_FACTOR",
    "H_SUPPORT_WIDTH",
    "MAGSAC_REACH",
    "REFINE_FACTOR",
    "TERMINATION_FACTOR",
    "check_confidence",
    "check_pairs",
    "hartley",
    "kernel_seed",
    "levenberg_marquardt",
    "magsac",
    "ransac",
    "refine_support",
    "result_dtype",
    "rotation",
    "trials_needed",
]

F64 = NDArray[np.float64]

#: Minimal samples drawn and solved together (one batched solve).
BATCH = 32

#: Upper bound of the final least-squares support, as a multiple of the inlier threshold
#: (see :func:`refine_support`).
REFINE_FACTOR = 2.0

#: Upper bound of the fundamental matrix's refinement support, as a multiple of the
#: threshold (:data:`REFINE_FACTOR` for the others). The Sampson distance's support is
#: ``3σ̂``; with the threshold near the noise (``τ = σ``, as the 1 px default and
#: benchmarks/bench_twoview.py's first setting), a bound of ``2τ`` cut it at ``2σ``, leaving
#: out 4.6 % of the true inliers, and the model that chose the support kept them out: issue
#: 28, median error of the true points over 100 of its scenes 0.276 px with ``2τ``, 0.247 px
#: with ``3τ`` (OpenCV's USAC_MAGSAC 0.288 px).
F_REFINE_FACTOR = 3.0

#: Width of the homography's refinement support in units of the noise ``σ̂`` (see
#: :func:`refine_support`; 3 for the 1-D epipolar residuals): the 99.99 % quantile of the
#: norm of a 2-D Gaussian residual, ``sqrt(-2 ln 1e-4) = 4.29``. The support is chosen by the
#: model that is then fitted to it, so the true inliers left out (the tail beyond ``3σ̂``,
#: 1.1 % of a 2-D residual) pull the fit towards that model: issue 28, 56 of the 4200 true
#: inliers of benchmarks/bench_twoview.py's 30 planar scenes beyond ``3σ̂`` cost 5 % of the
#: median accuracy (0.361 against 0.343 px with all of them).
H_SUPPORT_WIDTH = math.sqrt(-2.0 * math.log(1e-4))

#: Reach of MAGSAC++'s marginalised loss (Barath et al. 2020) as a multiple of the inlier
#: threshold: ``k σ_max = MAGSAC_REACH τ``, residuals beyond it count as outliers (loss 1,
#: weight 0). See ``imageform._kernels.ransac._magsac`` and docs/two-view.md.
MAGSAC_REACH = 3.0

#: Upper bound of the support whose inlier ratio sets the adaptive sample count of the
#: compiled estimators (``imageform._kernels.ransac``), as a multiple of the threshold: the
#: correspondences within ``3σ̂`` (``σ̂`` the noise estimated from the inliers, as
#: :func:`refine_support`), clipped to ``[τ, TERMINATION_FACTOR τ]``. With ``τ`` near the
#: noise, the inliers within ``τ`` are about two thirds of the true ones and a count from
#: them draws several times the samples needed (issue 28: 1263 against 259 samples, the
#: median fundamental 7-point scene of benchmarks/bench_twoview.py).
TERMINATION_FACTOR = 1.5


def check_pairs(a: object, b: object, name_a: str, name_b: str, n_min: int) -> tuple[F64, F64]:
    """Two point sets ``(N, 2)`` of the same length ``N >= n_min``, finite, as float64."""
    plain = _plain_pairs(a, b, n_min)
    if plain is not None:
        return plain
    pa = np.asarray(to_numpy(as_points(a, name_a, 2)), dtype=np.float64)
    pb = np.asarray(to_numpy(as_points(b, name_b, 2)), dtype=np.float64)
    if pa.ndim != 2:
        raise InvalidInputError(f"expected {name_a} of shape (N, 2), got {pa.shape}")
    if pb.ndim != 2:
        raise InvalidInputError(f"expected {name_b} of shape (N, 2), got {pb.shape}")
    if pa.shape[0] != pb.shape[0]:
        raise InvalidInputError(
            f"expected {name_a} and {name_b} of the same length, "
            f"got {pa.shape[0]} and {pb.shape[0]}"
        )
    if pa.shape[0] < n_min:
        raise InvalidInputError(
            f"expected at least {n_min} correspondences in {name_a}, {name_b}, got {pa.shape[0]}"
        )
    return pa, pb


def _plain_pairs(a: object, b: object, n_min: int) -> tuple[F64, F64] | None:
    """Check the common case of :func:`check_pairs` in a few microseconds, else None.

    Two float32 / float64 NumPy arrays (N, 2), ``N >= n_min``, every value finite and within
    ``MAX_MAGNITUDE``: what the full checks accept from such arrays (a tenth of a
    millisecond, as much as a robust homography's whole estimate). Anything else (None)
    goes through the full checks, which say what is wrong.
    """
    if type(a) is not np.ndarray or type(b) is not np.ndarray:
        return None
    if a.dtype not in _FLOATS or b.dtype not in _FLOATS or a.ndim != 2 or b.ndim != 2:
        return None
    if a.shape[1] != 2 or b.shape[1] != 2 or a.shape[0] != b.shape[0] or a.shape[0] < n_min:
        return None
    pa = np.asarray(a, dtype=np.float64)
    pb = np.asarray(b, dtype=np.float64)
    lo = min(float(pa.min()), float(pb.min()))
    hi = max(float(pa.max()), float(pb.max()))
    if not (math.isfinite(lo) and math.isfinite(hi) and max(-lo, hi) <= MAX_MAGNITUDE):
        return None
    return pa, pb


_FLOATS = (np.dtype(np.float64), np.dtype(np.float32))


def kernel_seed(rng: object) -> np.uint64:
    """Return a compiled sampler's seed: one draw ``as_rng(rng).integers(0, 2**63 - 1)``.

    For an int seed the draw is cached: building a Generator costs tens of microseconds, a
    tenth of a robust homography's estimate.
    """
    if isinstance(rng, numbers.Integral) and not isinstance(rng, bool) and int(rng) >= 0:
        return _int_seed(int(rng))
    return np.uint64(as_rng(rng).integers(0, 2**63 - 1))


@functools.lru_cache(maxsize=1024)
def _int_seed(seed: int) -> np.uint64:
    return np.uint64(np.random.default_rng(seed).integers(0, 2**63 - 1))


def result_dtype(*inputs: object) -> type[np.floating]:
    """Return float32 when every input is a float32 array, else float64.

    Conventions: float32 in, float32 out; the computation is float64 either way.
    """
    if all(getattr(x, "dtype", None) == np.float32 for x in inputs):
        return np.float32
    return np.float64


def check_confidence(confidence: object) -> float:
    p = check_positive(confidence, "confidence")
    if p >= 1.0:
        raise InvalidInputError(f"expected confidence in (0, 1), got {describe(confidence)}")
    return p


def hartley(p: F64) -> tuple[F64, F64]:
    """Points ``(..., N, 2)`` centred with mean distance sqrt(2), and ``T`` (..., 3, 3).

    Hartley & Zisserman (2nd ed.) sec. 4.4.4; coincident points keep scale 1.
    """
    c = p.mean(axis=-2, keepdims=True)
    d = np.sqrt(np.sum((p - c) ** 2, axis=-1)).mean(axis=-1)
    s = np.where(d > 0, math.sqrt(2.0) / np.where(d > 0, d, 1.0), 1.0)
    T = np.zeros((*p.shape[:-2], 3, 3))
    T[..., 0, 0] = T[..., 1, 1] = s
    T[..., :2, 2] = -c[..., 0, :] * s[..., None]
    T[..., 2, 2] = 1.0
    return (p - c) * s[..., None, None], T


def trials_needed(n_inliers: int, n: int, s: int, confidence: float) -> float:
    r"""Count the samples for probability ``confidence`` of one outlier-free sample of size ``s``.

    .. math:: k = \frac{\log(1 - p)}{\log(1 - \varepsilon^s)}

    (Fischler & Bolles 1981; Hartley & Zisserman 2nd ed., Algorithm 4.5.)
    """
    eps = n_inliers / n
    if eps >= 1.0:
        return 0.0
    if eps <= 0.0:
        return math.inf
    denom = math.log1p(-(eps**s))
    if denom == 0.0:
        return math.inf
    return math.log1p(-confidence) / denom


def _samples(rng: np.random.Generator, b: int, n: int, s: int) -> NDArray[np.intp]:
    """``b`` samples of ``s`` distinct indices in ``[0, n)`` (rows with repeats redrawn)."""
    out = np.empty((0, s), dtype=np.intp)
    while out.shape[0] < b:
        idx = rng.integers(0, n, (2 * b, s))
        srt = np.sort(idx, axis=1)
        out = np.concatenate([out, idx[np.all(srt[:, 1:] != srt[:, :-1], axis=1)]])
    return out[:b]


def ransac(
    n: int,
    s: int,
    solve: Callable[[NDArray[np.intp]], F64],
    sq_errors: Callable[[F64], F64],
    threshold: float,
    confidence: float,
    max_trials: int,
    rng: np.random.Generator,
    local_opt: Callable[[F64, NDArray[np.bool_]], F64] | None = None,
    pool: int = 0,
    loss: Callable[[F64], F64] | None = None,
) -> tuple[F64 | None, NDArray[np.bool_], int]:
    """MSAC with adaptive trial count and LO-RANSAC local optimisation.

    ``solve(idx (B, s))`` returns models ``(M, ...)`` (any number per sample, NaN-free);
    ``sq_errors(models)`` their squared residuals ``(M, n)``. Each model is scored by the
    truncated quadratic ``Σ min(e², τ²)`` (MSAC, Torr & Zisserman 2000); every new best model
    is handed to ``local_opt(model, inliers)`` (LO-RANSAC, Chum, Matas & Kittler 2003), whose
    result replaces it when it scores better. The number of samples adapts to the inlier
    ratio of the best (locally optimised) model so far.

    With ``pool > 0`` the ``pool`` best-scoring raw hypotheses that were not locally
    optimised are kept too, and before sampling stops (the adaptive count or
    ``max_trials`` reached) each is locally optimised: with noisy data a minimal sample of
    inliers can score worse than a model already optimised into a wrong basin, and never
    be optimised itself. When that improves the best model, the adaptive count is
    recomputed from its inlier ratio and sampling goes on if it asks for more. Returns
    ``(best model or None, inliers, trials)``.

    With ``loss`` (squared residuals to per-correspondence losses, e.g. :func:`magsac`'s),
    a model's score is the sum of its losses instead of the truncated quadratic.
    """
    thr2 = threshold * threshold
    best_model: F64 | None = None
    best_score = math.inf
    best_inl = np.zeros(n, dtype=bool)
    needed = float(max_trials)
    drawn = 0
    runners: list[tuple[float, F64]] = []

    def score(models: F64) -> tuple[F64, NDArray[np.bool_]]:
        e = sq_errors(models)
        e = np.where(np.isfinite(e), e, np.inf if loss is not None else thr2)
        if loss is not None:
            return loss(e).sum(axis=-1), e < thr2
        return np.minimum(e, thr2).sum(axis=-1), e < thr2

    def optimise(model: F64, inl: NDArray[np.bool_], sc: float) -> None:
        nonlocal best_model, best_score, best_inl
        if sc < best_score:
            best_model, best_score, best_inl = model, sc, inl
        if local_opt is None or inl.sum() <= s:
            return
        with np.errstate(all="ignore"):
            lo = local_opt(model, inl)
        if lo is not None and np.all(np.isfinite(lo)):
            sc2, inl2 = score(lo[None])
            if sc2[0] < best_score:
                best_model, best_score, best_inl = lo, float(sc2[0]), inl2[0]

    while True:
        while drawn < min(needed, max_trials):
            b = int(min(BATCH, max(1, max_trials - drawn)))
            idx = _samples(rng, b, n, s)
            drawn += b
            with np.errstate(all="ignore"):
                models = solve(idx)
            if models.shape[0] == 0:
                continue
            sc, inl = score(models)
            order = np.argsort(sc, kind="stable")
            k = int(order[0])
            if pool > 0:
                rest = order[1 : pool + 1] if sc[k] < best_score else order[:pool]
                runners.extend((float(sc[j]), models[j]) for j in rest)
                runners.sort(key=lambda r: r[0])
                del runners[pool:]
            if sc[k] >= best_score:
                continue
            optimise(models[k], inl[k], float(sc[k]))
            needed = trials_needed(int(best_inl.sum()), n, s, confidence)
        if not runners:
            break
        before = best_score
        for sc_r, model in runners:
            e = sq_errors(model[None])[0]
            optimise(model, np.isfinite(e) & (e < thr2), sc_r)
        runners = []
        needed = trials_needed(int(best_inl.sum()), n, s, confidence)
        if best_score >= before or drawn >= min(needed, max_trials):
            break
    return best_model, best_inl, drawn


#: MAGSAC++'s constants (as ``imageform._kernels.ransac``): ``k`` (the 0.99 quantile of
#: the χ distribution with 4 degrees of freedom), ``k²/2``, ``Γ(3/2, k²/2)``, and the scales
#: that make the weight 1 at 0 and the loss 1 at ``k σ_max``.
_MS_K = 3.64
_MS_XK = _MS_K * _MS_K / 2.0
_MS_GK = 0.5 * math.sqrt(math.pi) * math.erfc(math.sqrt(_MS_XK)) + math.sqrt(_MS_XK) * math.exp(
    -_MS_XK
)
_MS_G0 = 0.5 * math.sqrt(math.pi) - _MS_GK
_MS_LK = 0.75 * math.sqrt(math.pi) - 1.5 * _MS_GK - _MS_XK**1.5 * math.exp(-_MS_XK)


def magsac(sq_err: F64, threshold: float, reach: float = MAGSAC_REACH) -> tuple[F64, F64]:
    r"""MAGSAC++'s loss and IRLS weight of squared residuals, each scaled to 1.

    The noise ``σ`` of an inlier is taken uniform on ``[0, σ_max]`` and the residual's
    likelihood marginalised over it (Barath, Noskova, Ivashechkin & Matas 2020, "MAGSAC++,
    a fast, reliable and accurate robust estimator", CVPR, eqs. 11-12, ``ρ = 4`` degrees
    of freedom); with ``k σ_max = reach τ``, ``k = 3.64`` and ``x = e² / (2 σ_max²)``:

    .. math:: \text{loss} \propto \gamma(5/2, x) + x\,(\Gamma(3/2, x) - \Gamma(3/2, k^2/2)),
              \qquad w \propto \Gamma(3/2, x) - \Gamma(3/2, k^2/2)

    for ``x < k²/2``; beyond, loss 1 and weight 0. The loss is 1 at ``k σ_max`` (an
    outlier's, as a truncated quadratic's at its threshold), the weight 1 at 0.
    """
    from scipy.special import erfc

    sigma_max = reach * threshold / _MS_K
    x = np.asarray(sq_err, dtype=np.float64) / (2.0 * sigma_max * sigma_max)
    inside = x < _MS_XK
    xs = np.where(inside, x, 0.0)
    sx = np.sqrt(xs)
    ex = np.exp(-xs)
    g = 0.5 * math.sqrt(math.pi) * erfc(sx) + sx * ex
    low = 0.75 * math.sqrt(math.pi) - 1.5 * g - xs * sx * ex
    loss = np.where(inside, (low + xs * (g - _MS_GK)) / _MS_LK, 1.0)
    weight = np.where(inside, np.maximum(g - _MS_GK, 0.0) / _MS_G0, 0.0)
    return loss, weight


def levenberg_marquardt(
    residual: Callable[[F64], F64],
    p0: F64,
    *,
    max_iter: int = 50,
    tol: float = 1e-12,
    jacobian: Callable[[F64], F64] | None = None,
) -> tuple[F64, float]:
    """Minimise ``‖r(p)‖²`` by Levenberg-Marquardt (Marquardt 1963, scaled damping).

    The Jacobian is ``jacobian(p)`` when given, else central differences. Returns the
    parameters and the final cost ``‖r‖²``.
    """
    p = np.asarray(p0, dtype=np.float64).copy()
    r = residual(p)
    cost = float(r @ r)
    lam = 1e-3
    gain = 0.0

    def num_jac(q: F64) -> F64:
        cols = []
        for i in range(q.size):
            h = 1e-6 * max(1.0, abs(q[i]))
            e = np.zeros_like(q)
            e[i] = h
            cols.append((residual(q + e) - residual(q - e)) / (2 * h))
        return np.stack(cols, axis=-1)

    jac = jacobian if jacobian is not None else num_jac
    for _ in range(max_iter):
        J = jac(p)
        A = J.T @ J
        g = J.T @ r
        D = np.diag(A).copy()
        D[D <= 0] = 1.0
        improved = False
        while lam < 1e10:
            try:
                step = -np.linalg.solve(A + lam * np.diag(D), g)
            except np.linalg.LinAlgError:
                lam *= 10.0
                continue
            pn = p + step
            rn = residual(pn)
            cn = float(rn @ rn)
            if np.isfinite(cn) and cn <= cost:
                gain = cost - cn
                p, r, cost = pn, rn, cn
                lam = max(lam / 10.0, 1e-12)
                improved = True
                break
            lam *= 10.0
        if not improved or gain <= tol * max(cost, 1e-300):
            break
    return p, cost


def _chi2_cdf(c: float, k: int) -> float:
    """``P(χ²_k < c)`` for k in {1, 2, 3, 4} (closed forms)."""
    if k == 1:
        return math.erf(math.sqrt(c / 2.0))
    if k == 2:
        return -math.expm1(-c / 2.0)
    if k == 3:
        return math.erf(math.sqrt(c / 2.0)) - math.sqrt(2.0 * c / math.pi) * math.exp(-c / 2.0)
    return 1.0 - math.exp(-c / 2.0) * (1.0 + c / 2.0)


def refine_support(
    sq_err: F64, threshold: float, dof: int, width: float = 3.0, factor: float = REFINE_FACTOR
) -> float:
    """Residual bound of the correspondences used by the final least-squares refinement.

    The consensus threshold ``τ`` clips the tail of the inlier distribution (at ``τ = σ``
    a third of the inliers of a 1-D residual lie beyond it), which costs accuracy. The
    noise ``σ̂`` is estimated from the inliers' mean squared residual ``m`` corrected for
    the truncation, ``m = σ² k P(χ²_{k+2} < τ²/σ²) / P(χ²_k < τ²/σ²)`` for a residual
    with ``k = dof`` Gaussian components, and the support is ``width σ̂`` (default ``3 σ̂``)
    clipped to ``[τ, factor τ]`` (a wider least-squares support than the consensus threshold,
    as the threshold multiplier of Lebeda, Matas & Chum (2012), "Fixing the locally
    optimized RANSAC", BMVC). Exact data (``σ̂ = 0``) keep ``τ``.
    """
    m = float(np.mean(sq_err)) if sq_err.size else 0.0
    t2 = threshold * threshold
    if not np.isfinite(m) or m <= 0.0:
        return threshold
    if m >= t2 * dof / (dof + 2.0) * (1.0 - 1e-9):
        return threshold * factor

    def mean_sq(sig: float) -> float:
        c = t2 / (sig * sig)
        lo = _chi2_cdf(c, dof)
        return sig * sig * dof * _chi2_cdf(c, dof + 2) / lo if lo > 0 else t2 * dof / (dof + 2.0)

    a, b = 1e-12 * threshold, 1e6 * threshold
    for _ in range(100):
        mid = math.sqrt(a * b)
        if mean_sq(mid) < m:
            a = mid
        else:
            b = mid
    sigma = math.sqrt(a * b)
    return float(min(max(width * sigma, threshold), factor * threshold))


def refit_on_support(
    model: F64,
    sq_error: Callable[[F64], F64],
    refit: Callable[[F64, NDArray[np.bool_]], F64],
    threshold: float,
    dof: int,
    min_points: int,
    rounds: int = 3,
    width: float = 3.0,
    factor: float = REFINE_FACTOR,
) -> F64:
    """Refit ``model`` by least squares on the correspondences within its support.

    The support is what :func:`refine_support` sets (``width``, ``factor``); refits go on
    until the support stops changing (or falls under ``min_points``), at most ``rounds``
    times; ``refit(model, selected)`` fits once.
    """
    e0 = sq_error(model)
    wide = refine_support(e0[e0 < threshold * threshold], threshold, dof, width, factor)
    sel = e0 < wide * wide
    for _ in range(rounds):
        model = refit(model, sel)
        new = sq_error(model) < wide * wide
        if new.sum() < min_points or np.array_equal(new, sel):
            break
        sel = new
    return model


def rotation(w: F64) -> F64:
    """``R = exp([w]ₓ)`` of one rotation vector (3,) (Rodrigues' formula, series near 0)."""
    th2 = float(w @ w)
    if th2 < 1e-12:
        a, b = 1.0 - th2 / 6.0, 0.5 - th2 / 24.0
    else:
        th = math.sqrt(th2)
        a, b = math.sin(th) / th, (1.0 - math.cos(th)) / th2
    Kx = np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])
    return np.eye(3) + a * Kx + b * (Kx @ Kx)
