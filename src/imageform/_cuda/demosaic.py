r"""CUDA kernels of demosaicing and raw development: one launch per call.

- :func:`demosaic`: bilinear and Malvar-He-Cutler on a float ``(B, H, W)`` Bayer mosaic into
  ``(B, H, W, 3)``, the optional clipping to [0, 1] fused, one thread per 2x2 CFA quad
  (:mod:`imageform._cuda.demosaic_quads`). The mosaic is read in place with the
  phase-preserving mirror about the edge pixel (index ``-k`` reads ``k``), which is what
  :func:`imageform.sensor.demosaic` builds with ``numpy.pad(mode="reflect")``: no padded copy
  is made. The filters are those of :mod:`imageform._kernels.demosaic_bilinear` and
  :mod:`imageform._kernels.demosaic_malvar` (the same sums in the same order); float32
  mosaics are computed in float32 (the constants typed), as the CPU kernels do.
- :func:`develop_bayer`: :func:`imageform._kernels.raw_develop.develop_rows` per pixel, one
  thread a pixel (the digital numbers linearised, white-balanced and clipped per photosite of
  the 3x3 or 5x5 window, bilinear or Malvar demosaicing, the 3x3 matrix, clipping, the
  transfer table, float32 or uint16 rounded half up): the whole raw pipeline of ``imageform
  develop`` in one kernel, float32 throughout as on the CPU.

Tests run the kernels under numba's CUDA simulator against the NumPy twins and compile them
for ``sm_90`` where NVVM is installed (``tests/backends/test_cuda_geometry_kernels.py``).
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from imageform._cuda import _launch
from imageform._cuda._launch import empty_like, guarded
from imageform._cuda.geometry import import_cuda, row_grid

__all__ = [
    "MODE_CAMERA",
    "MODE_FLOAT",
    "MODE_UINT16",
    "demosaic",
    "develop_bayer",
    "develop_on_device",
    "develop_parameters",
]

#: :func:`develop_bayer` outputs, as :mod:`imageform._kernels.raw_develop`'s.
MODE_CAMERA, MODE_FLOAT, MODE_UINT16 = 0, 1, 2

#: Demosaicing methods of the kernels (``method`` argument).
_METHODS = {"bilinear": 0, "malvar": 1}


#: ``numba.cuda`` (a module global: numba's simulator swaps the global named ``cuda``).
cuda: Any = None


@functools.cache
def _kernels() -> Any:
    import math
    import types

    global cuda
    cuda = import_cuda()

    def mirror(i, n):  # type: ignore[no-untyped-def]
        # index i in [-2, n + 1] mirrored about the edge samples (-1 reads 1, n reads n - 2)
        if i < 0:
            return -i
        if i >= n:
            return 2 * n - 2 - i
        return i

    mirror_d = cuda.jit(device=True)(mirror)

    def clip01(v, zero, one):  # type: ignore[no-untyped-def]
        # min(max(v, 0), 1) by comparisons (NaN stays NaN, as numpy.clip)
        return zero if v < zero else (one if v > one else v)

    clip_d = cuda.jit(device=True)(clip01)
    row_grid_d = row_grid()

    def make_rgb_at(get: Any, T: Any) -> Any:
        """Return a device function: ``(R, G, B)`` at pixel ``(y, x)``, samples read by ``get``.

        ``get(a, b, yy, xx)`` reads one (mirrored) sample as type ``T``; the constants are of
        type ``T`` (float32 arithmetic for float32 data, as the CPU kernels).
        """

        def rgb_at(a, b, y, x, h, w, ry, rx, method):  # type: ignore[no-untyped-def]
            ym = mirror_d(y - 1, h)
            yp = mirror_d(y + 1, h)
            xm = mirror_d(x - 1, w)
            xp = mirror_d(x + 1, w)
            c = get(a, b, y, x)
            s1h = get(a, b, y, xm) + get(a, b, y, xp)
            s1v = get(a, b, ym, x) + get(a, b, yp, x)
            dg = get(a, b, ym, xm) + get(a, b, ym, xp) + get(a, b, yp, xm) + get(a, b, yp, xp)
            red_row = (y & 1) == ry
            is_rb = (x & 1) == (rx if red_row else 1 - rx)
            if method == 0:  # bilinear: demosaic_bilinear.bilinear_numba
                q = T(0.25)
                half = T(0.5)
                g = q * (s1h + s1v) if is_rb else c
                own = c if is_rb else half * s1h
                oth = q * dg if is_rb else half * s1v
            else:  # Malvar-He-Cutler: demosaic_malvar.malvar_numba
                s2h = get(a, b, y, mirror_d(x - 2, w)) + get(a, b, y, mirror_d(x + 2, w))
                s2v = get(a, b, mirror_d(y - 2, h), x) + get(a, b, mirror_d(y + 2, h), x)
                eighth = T(0.125)
                if is_rb:
                    g = (T(4.0) * c + T(2.0) * (s1h + s1v) - (s2h + s2v)) * eighth
                    own = c
                    oth = (T(6.0) * c + T(2.0) * dg - T(1.5) * (s2h + s2v)) * eighth
                else:
                    base = T(5.0) * c - dg
                    g = c
                    own = (base + T(4.0) * s1h - s2h + T(0.5) * s2v) * eighth
                    oth = (base + T(4.0) * s1v - s2v + T(0.5) * s2h) * eighth
            if red_row:
                return own, g, oth
            return oth, g, own

        return cuda.jit(device=True)(rgb_at)

    def balanced(mosaic, prm, y, x):  # type: ignore[no-untyped-def]
        # clip((DN - B_s) k_s, 0, 1) of the photosite (y, x): raw_develop._balance_row
        p = y & 1
        q = x & 1
        v = (np.float32(mosaic[y, x]) - prm[p, q]) * prm[2 + p, q]
        return clip_d(v, np.float32(0.0), np.float32(1.0))

    rgb_balanced_d = make_rgb_at(cuda.jit(device=True)(balanced), np.float32)

    def develop_pixel(mosaic, prm, y, x, ry, rx, method, m, lut, encode, mode, out_f, out_u):  # type: ignore[no-untyped-def]
        h, w = mosaic.shape
        f = np.float32
        r, g, b = rgb_balanced_d(mosaic, prm, y, x, h, w, ry, rx, method)
        if mode == 0:
            out_f[y, x, 0] = r
            out_f[y, x, 1] = g
            out_f[y, x, 2] = b
            return
        zero = f(0.0)
        one = f(1.0)
        v0 = clip_d(m[0, 0] * r + m[0, 1] * g + m[0, 2] * b, zero, one)
        v1 = clip_d(m[1, 0] * r + m[1, 1] * g + m[1, 2] * b, zero, one)
        v2 = clip_d(m[2, 0] * r + m[2, 1] * g + m[2, 2] * b, zero, one)
        if encode:
            nm1 = lut.shape[0] - 2
            fn = f(lut.shape[0] - 1)
            s = math.sqrt(v0) * fn
            e = int(s)
            e = e if e < nm1 else nm1
            v0 = lut[e] + (s - f(e)) * (lut[e + 1] - lut[e])
            s = math.sqrt(v1) * fn
            e = int(s)
            e = e if e < nm1 else nm1
            v1 = lut[e] + (s - f(e)) * (lut[e + 1] - lut[e])
            s = math.sqrt(v2) * fn
            e = int(s)
            e = e if e < nm1 else nm1
            v2 = lut[e] + (s - f(e)) * (lut[e + 1] - lut[e])
        if mode == 1:
            out_f[y, x, 0] = v0
            out_f[y, x, 1] = v1
            out_f[y, x, 2] = v2
        else:
            top = f(65535.0)
            half = f(0.5)
            out_u[y, x, 0] = int(v0 * top + half)
            out_u[y, x, 1] = int(v1 * top + half)
            out_u[y, x, 2] = int(v2 * top + half)

    develop_pixel_d = cuda.jit(device=True)(develop_pixel)

    def develop_kernel(mosaic, prm, ry, rx, method, m, lut, encode, mode, out_f, out_u):  # type: ignore[no-untyped-def]
        # prm (4, 2) float32: rows 0-1 the black level, rows 2-3 the scale of the 2x2 tile;
        # a 2-D launch (launch_rows): thread (row y, column x)
        x, y, step = row_grid_d()
        if x >= mosaic.shape[1]:
            return
        while y < mosaic.shape[0]:
            develop_pixel_d(mosaic, prm, y, x, ry, rx, method, m, lut, encode, mode, out_f, out_u)
            y += step

    k = types.SimpleNamespace()
    k.py = {
        "develop": develop_kernel,
    }
    for name, fn in k.py.items():
        setattr(k, name, cuda.jit(fn))
    return k


def demosaic(raw: Any, ry: int, rx: int, method: str, clip: bool) -> Any | None:
    """Demosaic a float device mosaic ``(B, H, W)`` (red at ``(ry, rx)``) into ``(B, H, W, 3)``.

    ``method``: ``"bilinear"`` or ``"malvar"``; ``clip``: clip to [0, 1] in the same pass.
    One kernel launch (:mod:`imageform._cuda.demosaic_quads`, a thread per 2x2 quad);
    ``None`` when the kernels turned out unusable or the mosaic is smaller than 4 x 4 (the
    kernels' mirror reads up to 3 pixels past an edge): the caller's Array-API path runs.
    """
    from imageform._cuda.demosaic_quads import kernels

    nb, h, w = (int(s) for s in raw.shape)
    if min(h, w) < 4:
        return None
    out = empty_like(raw, (nb, h, w, 3))
    bits = 32 if str(raw.dtype).endswith("float32") else 64
    # one thread per 2x2 quad; the output viewed as (B, H, 3 W) value rows
    args = (raw, int(ry), int(rx), bool(clip), out.reshape((nb, h, 3 * w)))
    size = ((h + 1) // 2, (w + 1) // 2)
    if not guarded(("demosaic", method, bits), getattr(kernels(), f"{method}{bits}"), size, *args):
        return None
    return out


def develop_bayer(
    mosaic: np.ndarray,
    black: np.ndarray,
    scale: np.ndarray,
    ry: int,
    rx: int,
    method: str,
    m: np.ndarray,
    lut: np.ndarray | None,
    mode: int,
) -> np.ndarray:
    """Develop a uint16 Bayer mosaic on the GPU; the NumPy result of ``mode``.

    The arguments of :func:`imageform._kernels.raw_develop.develop_rows` (``black`` and
    ``scale`` per photosite of the 2x2 tile, ``m`` camera RGB to the output's linear RGB,
    ``lut`` the transfer table or ``None`` for linear output), plus the demosaicing
    ``method`` (bilinear or malvar). The mosaic is copied to the device, developed in one
    launch (:func:`develop_on_device`), and the result copied back.
    """
    cuda = import_cuda()
    h, w = mosaic.shape
    prm = develop_parameters(black, scale)
    table = np.zeros(2, np.float32) if lut is None else np.asarray(lut, np.float32)
    out = cuda.device_array((h, w, 3), np.uint16 if mode == MODE_UINT16 else np.float32)
    develop_on_device(
        cuda.to_device(np.ascontiguousarray(mosaic, dtype=np.uint16)),
        cuda.to_device(prm),
        ry,
        rx,
        method,
        cuda.to_device(np.ascontiguousarray(m, dtype=np.float32)),
        cuda.to_device(table),
        lut is not None,
        mode,
        out,
    )
    return np.asarray(out.copy_to_host())


def develop_parameters(black: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """Return the ``(4, 2)`` float32 parameters of the kernel: black levels above the scales."""
    return np.ascontiguousarray(
        np.concatenate([np.asarray(black, np.float32), np.asarray(scale, np.float32)])
    )


def develop_on_device(
    mosaic: Any,
    prm: Any,
    ry: int,
    rx: int,
    method: str,
    m: Any,
    lut: Any,
    encode: bool,
    mode: int,
    out: Any,
) -> Any:
    """Launch the development kernel on arrays already on the device (one launch, no copy).

    ``mosaic`` ``(H, W)`` uint16, ``prm`` from :func:`develop_parameters`, ``m`` ``(3, 3)``
    and ``lut`` float32, all device arrays of any library; ``out`` ``(H, W, 3)``: float32
    (camera RGB or the float output) or uint16 (``MODE_UINT16``). Returns ``out``.
    """
    cuda = import_cuda()
    h, w = (int(s) for s in mosaic.shape)
    none_f = cuda.device_array((0, 0, 3), np.float32)
    none_u = cuda.device_array((0, 0, 3), np.uint16)
    out_f, out_u = (none_f, out) if mode == MODE_UINT16 else (out, none_u)
    args = (mosaic, prm, int(ry), int(rx), _METHODS[method], m, lut, bool(encode), int(mode))
    if not guarded(("develop", mode), _kernels().develop, (h, w), *args, out_f, out_u):
        from imageform.errors import InvalidInputError

        raise InvalidInputError(
            "device='cuda': numba's CUDA target cannot compile the kernel here "
            f"({_launch.status()}); use the CPU"
        )
    return out
