r"""CUDA kernels of the camera geometry: projection, distortion, undistortion, remapping.

One kernel launch per call, one thread per point or output pixel, every stage fused:

- :func:`project`: world points through ``[R | t]``, Brown-Conrady and ``K`` to pixels (or
  the pinhole alone), with the validity mask, in one pass (``R``, ``t`` and ``K`` read on the
  device: nothing is copied to the host);
- :func:`distort` and :func:`undistort`: Brown-Conrady and its Newton inverse, at most
  ``max_iter`` steps per point (a fixed bound);
- :func:`remap`: bilinear sampling of a ``(B, H, W, C)`` image at a ``(H', W', 2)`` map;
- :func:`undistort_image`: the undistortion map computed where it is sampled (no map array).

The per-point maths is written once. Brown-Conrady and its Newton inverse are the Python
functions of the CPU kernels' scalar helpers,
:func:`imageform._kernels.distortion.bc_distort_xy` and
:func:`~imageform._kernels.distortion.bc_undistort_xy` (``.py_func``), compiled a second time
here as CUDA device functions, so both targets run the same statements. The projection follows
:mod:`imageform._kernels.project` and :mod:`imageform._kernels.project_distort` (the same
tests, the same arithmetic), and the bilinear sample is the four-product formula of the
NumPy twin :func:`imageform.geometry.undistort._remap_bilinear_numpy` (NaN propagates from
any neighbour, as there).

Numbers: float64 inputs give the NumPy path's numbers to rounding (the CUDA compiler may fuse
multiply-adds); float32 inputs are computed partly in float64 (the distortion model's
constants are float64) and stored as float32. Tests run every kernel under numba's CUDA
simulator (``NUMBA_ENABLE_CUDASIM=1``) against the NumPy path and compile each one for
``sm_90`` where NVVM is installed (``tests/backends/test_cuda_kernels.py``).

Arrays and launches go through :mod:`imageform._cuda._launch` (no copy, no host
synchronisation, the producer's stream); :func:`on_cuda` is the dispatch test of the public
functions. Importing this module imports nothing heavy: ``numba.cuda`` is imported when a
kernel is first needed.
"""

from __future__ import annotations

import functools
import math
import struct
import sys
from typing import Any

import numpy as np

from imageform._cuda import _launch
from imageform._cuda._launch import dtype_name as _dt
from imageform._cuda._launch import empty_like, guarded

__all__ = [
    "distort",
    "import_cuda",
    "on_cuda",
    "project",
    "remap",
    "require_cuda",
    "row_grid",
    "undistort",
    "undistort_image",
]

# --- dispatch ------------------------------------------------------------------------------


def on_cuda(*arrays: object, floats: bool = True) -> bool:
    """Whether a call on ``arrays`` runs the CUDA kernels.

    Every one a CUDA array (:func:`imageform._cuda._launch.is_cuda_array`), none recording
    gradients, not inside ``torch.compile``'s tracing, the kernels usable
    (:func:`~imageform._cuda._launch.use_cuda`), and (``floats``) the first one float32 or
    float64. Importing this module imports no GPU library: this check is cheap on NumPy.
    """
    if not arrays:
        return False
    for a in arrays:
        # autograd and torch.compile keep the Array-API path (differentiable, traceable)
        if not _launch.is_cuda_array(a) or getattr(a, "requires_grad", False):
            return False
    torch = sys.modules.get("torch")
    if torch is not None and torch.compiler.is_compiling():
        return False
    if floats and _dt(arrays[0]) not in ("float32", "float64"):
        return False
    return _launch.use_cuda()


def require_cuda(what: str) -> None:
    """Raise :class:`~imageform.errors.InvalidInputError` (one line) unless the kernels can run.

    ``what`` names the request in the caller's words (``"--device cuda"``).
    """
    if not _launch.use_cuda():
        from imageform.errors import InvalidInputError

        raise InvalidInputError(
            f"{what}: no CUDA device is usable here (numba finds none); use the CPU"
        )


#: ``numba.cuda``, set by :func:`import_cuda`. A module global, not a local of the kernel
#: factories: numba's simulator swaps the global named ``cuda`` of a kernel's module.
cuda: Any = None


def import_cuda() -> Any:
    """Import ``numba.cuda`` into this module's global ``cuda`` (once) and return it."""
    global cuda
    if cuda is None:
        cuda = _launch.cuda()
    return cuda


@functools.cache
def row_grid() -> Any:
    """Return the prologue of the kernels on a 2-D grid, a device function (compiled once).

    On :func:`~imageform._cuda._launch.launch_rows`'s grid, ``x, y, step = row_grid_d()`` in a
    kernel (``row_grid_d = row_grid()``) gives the thread's column ``x``, its first row ``y``
    and the row stride ``step`` (the grid's height is capped at CUDA's limit). The kernel
    returns when ``x`` is past the last column, then loops ``while y < rows: ...; y += step``
    (no division: ``range()`` counts its trips).
    """
    import_cuda()

    def grid_rows():  # type: ignore[no-untyped-def]
        x, y = cuda.grid(2)
        return x, y, cuda.gridsize(2)[1]

    return cuda.jit(device=True)(grid_rows)


# --- kernels -------------------------------------------------------------------------------


@functools.cache
def _kernels() -> Any:
    """Compile-on-first-use CUDA kernels (a namespace of numba CUDA dispatchers)."""
    import types

    import_cuda()
    from imageform._kernels.distortion import bc_distort_xy, bc_undistort_xy

    distort_xy = cuda.jit(device=True)(bc_distort_xy.py_func)
    undistort_xy = cuda.jit(device=True)(bc_undistort_xy.py_func)
    k = types.SimpleNamespace()
    k.distort_xy = distort_xy
    k.undistort_xy = undistort_xy

    def project_kernel(pts, K, R, t, k1, k2, p1, p2, k3, k4, k5, k6, distorted, uv, valid):  # type: ignore[no-untyped-def]
        # pinhole (distorted False): as imageform._kernels.project (K divided by K[2, 2],
        # valid = 0 < z < inf and a finite result); distorted: as
        # imageform._kernels.project_distort (valid = z > 0)
        i = cuda.grid(1)
        if i >= pts.shape[0]:
            return
        X = pts[i, 0]
        Y = pts[i, 1]
        Z = pts[i, 2]
        xc = R[0, 0] * X + R[0, 1] * Y + R[0, 2] * Z + t[0]
        yc = R[1, 0] * X + R[1, 1] * Y + R[1, 2] * Z + t[1]
        zc = R[2, 0] * X + R[2, 1] * Y + R[2, 2] * Z + t[2]
        if distorted:
            if zc > 0.0:
                inv = 1.0 / zc
                xd, yd = distort_xy(xc * inv, yc * inv, k1, k2, p1, p2, k3, k4, k5, k6)
                uv[i, 0] = K[0, 0] * xd + K[0, 1] * yd + K[0, 2]
                uv[i, 1] = K[1, 1] * yd + K[1, 2]
                valid[i] = True
            else:
                uv[i, 0] = math.nan
                uv[i, 1] = math.nan
                valid[i] = False
            return
        n = K[2, 2]
        u = math.nan
        v = math.nan
        if 0.0 < zc < math.inf:
            x = xc / zc
            y = yc / zc
            u = (K[0, 0] / n) * x + (K[0, 1] / n) * y + K[0, 2] / n
            v = (K[1, 1] / n) * y + K[1, 2] / n
        ok = math.isfinite(u) and math.isfinite(v)
        uv[i, 0] = u if ok else math.nan
        uv[i, 1] = v if ok else math.nan
        valid[i] = ok

    def distort_kernel(xy, k1, k2, p1, p2, k3, k4, k5, k6, out):  # type: ignore[no-untyped-def]
        i = cuda.grid(1)
        if i >= xy.shape[0]:
            return
        xd, yd = distort_xy(xy[i, 0], xy[i, 1], k1, k2, p1, p2, k3, k4, k5, k6)
        out[i, 0] = xd
        out[i, 1] = yd

    def undistort_kernel(xy, k1, k2, p1, p2, k3, k4, k5, k6, max_iter, tol, out, ok):  # type: ignore[no-untyped-def]
        i = cuda.grid(1)
        if i >= xy.shape[0]:
            return
        x, y, good = undistort_xy(xy[i, 0], xy[i, 1], k1, k2, p1, p2, k3, k4, k5, k6, max_iter, tol)
        out[i, 0] = x
        out[i, 1] = y
        ok[i] = good

    def sample(img, b, i, j, u, v, fill, out):  # type: ignore[no-untyped-def]
        # bilinear at (u, v) into out[b, i, j, :]: the NumPy twin's arithmetic
        h = img.shape[1]
        w = img.shape[2]
        nc = img.shape[3]
        if not (u >= 0.0 and u <= w - 1 and v >= 0.0 and v <= h - 1):  # NaN: outside
            for c in range(nc):
                out[b, i, j, c] = fill
            return
        x0 = int(u)  # u >= 0 inside: truncation is the floor (and x0 <= w - 1)
        y0 = int(v)
        x1 = x0 + 1 if x0 + 1 < w else w - 1
        y1 = y0 + 1 if y0 + 1 < h else h - 1
        ax = u - x0
        ay = v - y0
        w00 = (1.0 - ax) * (1.0 - ay)
        w01 = ax * (1.0 - ay)
        w10 = (1.0 - ax) * ay
        w11 = ax * ay
        for c in range(nc):
            out[b, i, j, c] = (
                w00 * img[b, y0, x0, c]
                + w01 * img[b, y0, x1, c]
                + w10 * img[b, y1, x0, c]
                + w11 * img[b, y1, x1, c]
            )

    sample_d = cuda.jit(device=True)(sample)
    row_grid_d = row_grid()

    def remap_kernel(img, mp, fill, out):  # type: ignore[no-untyped-def]
        # a 2-D launch (launch_rows): thread (row i, column j); the position is read once
        # and every image of the batch sampled there
        j, i, step = row_grid_d()
        if j >= out.shape[2]:
            return
        while i < out.shape[1]:
            u = float(mp[i, j, 0])  # float64 weights from a float32 map (exact positions)
            v = float(mp[i, j, 1])
            for b in range(out.shape[0]):
                sample_d(img, b, i, j, u, v, fill, out)
            i += step

    def undistort_image_kernel(img, Kn, Km, k1, k2, p1, p2, k3, k4, k5, k6, fill, out):  # type: ignore[no-untyped-def]
        # the source position as imageform.geometry._remap_xp.map_grid computes it, once per
        # output pixel for the whole batch
        j, i, step = row_grid_d()
        if j >= out.shape[2]:
            return
        while i < out.shape[1]:
            y = (float(i) - Kn[1, 2]) / Kn[1, 1]
            x = (float(j) - Kn[0, 2] - Kn[0, 1] * y) / Kn[0, 0]
            xd, yd = distort_xy(x, y, k1, k2, p1, p2, k3, k4, k5, k6)
            us = Km[0, 0] * xd + Km[0, 1] * yd + Km[0, 2]
            vs = Km[1, 1] * yd + Km[1, 2]
            for b in range(out.shape[0]):
                sample_d(img, b, i, j, us, vs, fill, out)
            i += step

    k.py = {
        "project": project_kernel,
        "distort": distort_kernel,
        "undistort": undistort_kernel,
        "remap": remap_kernel,
        "undistort_image": undistort_image_kernel,
    }
    for name, fn in k.py.items():
        setattr(k, name, cuda.jit(fn))
    return k


#: the coefficients' float64 bytes -> their kernel arguments (:func:`_coeffs`)
_COEFFS: dict[Any, _launch.Constants] = {}


def _coeffs(coeffs: Any) -> _launch.Constants:
    """Return the eight Brown-Conrady coefficients as kernel arguments (zeros for ``None``).

    Python floats, packed once per set of coefficients for the fast launch (a model's
    coefficients are the same from call to call); looked up by their float64 bytes (a
    zero's sign included, so the kernel gets the very numbers).
    """
    c = (0.0,) * 8 if coeffs is None else tuple(coeffs)
    try:
        key: Any = struct.pack(f"{len(c)}d", *c)
    except struct.error:  # not numbers: float() says why
        key = None
    got = None if key is None else _COEFFS.get(key)
    if got is None:
        vals = tuple(float(v) for v in c)
        vals += (0.0,) * (8 - len(vals))
        got = _launch.Constants(vals)
        if key is not None:
            if len(_COEFFS) > 256:
                _COEFFS.clear()
            _COEFFS[key] = got
    return got


def project(pts: Any, K: Any, R: Any, t: Any, coeffs: Any = None) -> tuple[Any, Any] | None:
    """Project ``(N, 3)`` device points; ``coeffs`` Brown-Conrady's eight, or ``None`` (pinhole).

    ``K``, ``R``, ``t`` device arrays of the points' dtype. Returns ``(uv (N, 2), valid (N,))``
    of the points' library and device; one kernel launch. ``None`` (every wrapper here) when
    the kernels turned out unusable (:func:`~imageform._cuda._launch.guarded`): the
    caller's Array-API path runs.
    """
    n = int(pts.shape[0])
    uv = empty_like(pts, (n, 2))
    valid = empty_like(pts, (n,), np.bool_)
    args = (pts, K, R, t, _coeffs(coeffs), coeffs is not None, uv, valid)
    if not guarded(("project", _dt(pts)), _kernels().project, n, *args):
        return None
    return uv, valid


def distort(xy: Any, coeffs: Any) -> Any:
    """Brown-Conrady on ``(N, 2)`` device points; one launch."""
    out = empty_like(xy)
    args = (xy, _coeffs(coeffs), out)
    if not guarded(("distort", _dt(xy)), _kernels().distort, int(xy.shape[0]), *args):
        return None
    return out


def undistort(xy: Any, coeffs: Any, max_iter: int, tol: float) -> tuple[Any, Any] | None:
    """Newton's inverse of Brown-Conrady on ``(N, 2)`` device points: ``(xy, ok)``; one launch."""
    n = int(xy.shape[0])
    out = empty_like(xy, (n, 2))
    ok = empty_like(xy, (n,), np.bool_)
    args = (xy, _coeffs(coeffs), int(max_iter), float(tol), out, ok)
    if not guarded(("undistort", _dt(xy)), _kernels().undistort, n, *args):
        return None
    return out, ok


def remap(img: Any, map_uv: Any, fill: float) -> Any:
    """Bilinear remap of a ``(B, H, W, C)`` float device image at ``(H', W', 2)``; one launch."""
    b, _, _, c = (int(s) for s in img.shape)
    ho, wo = int(map_uv.shape[0]), int(map_uv.shape[1])
    out = empty_like(img, (b, ho, wo, c))
    args = (img, map_uv, float(fill), out)
    if not guarded(("remap", _dt(img), _dt(map_uv)), _kernels().remap, (ho, wo), *args):
        return None
    return out


def undistort_image(
    img: Any, Kn: Any, Km: Any, coeffs: Any, out_hw: tuple[int, int], fill: float
) -> Any:
    """Undistort a ``(B, H, W, C)`` float device image (Brown-Conrady); one launch.

    ``Kn``: the output's intrinsics, ``Km``: the source's, float64 device arrays ``(3, 3)``.
    """
    b, c = int(img.shape[0]), int(img.shape[3])
    ho, wo = out_hw
    out = empty_like(img, (b, ho, wo, c))
    args = (img, Kn, Km, _coeffs(coeffs), float(fill), out)
    key = ("undistort_image", _dt(img))
    if not guarded(key, _kernels().undistort_image, (ho, wo), *args):
        return None
    return out
