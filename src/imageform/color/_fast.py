"""Dispatch of :func:`imageform.color.convert` to the fused numba colour kernels.

Only NumPy arrays reach here (``_backend.use_numba``); a pair of spaces without a kernel
returns ``None`` and ``convert`` runs its array path (the twin). This module belongs to the
colour package: it turns the colour parameters (white, RGB space, Y'CbCr standard and
range) into the numbers and matrices the kernels of :mod:`imageform._kernels` take, so that
the kernels never import the domain packages.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["dispatch", "lab_tables"]

_KERNEL_PAIRS = {
    ("srgb", "lab"),
    ("lab", "srgb"),
    ("srgb", "hsv"),
    ("srgb", "ycbcr"),
    ("ycbcr", "srgb"),
}


def dispatch(
    image: np.ndarray,
    s: str,
    d: str,
    p: dict[str, Any],
    out: np.ndarray | None = None,
    enc8: str | None = None,
) -> np.ndarray | None:
    """Run the kernel for ``s -> d`` on a validated-shape NumPy array, or return None.

    ``out``: the checked result buffer (or None); ``enc8``: ``"lab8"`` / ``"hsv8"`` for
    OpenCV's 8-bit output, which only uint8 sRGB input runs here.
    """
    if enc8 is not None:
        return _dispatch8(image, s, d, p, out)
    if (s, d) not in _KERNEL_PAIRS or image.dtype not in (np.float32, np.float64, np.uint8):
        return None
    from imageform._kernels import color_lab, color_simple
    from imageform._validate import as_image_strict, check_finite
    from imageform.color import ycbcr
    from imageform.color.rgb_spaces import rgb_to_xyz_matrix, xyz_to_rgb_matrix
    from imageform.color.whitepoints import resolve_white

    if image.dtype == np.uint8 and s != "srgb":
        return None  # integer Lab / code values: the array path explains or handles them
    if image.size == 0:
        return None

    stats = None
    if (s, d) == ("srgb", "lab"):
        w = resolve_white(p["white"], observer=p.get("observer", 2))
        m = rgb_to_xyz_matrix("srgb") / w[:, None]
        if image.dtype == np.float64:
            as_image_strict(image, "srgb image")
        res, stats = color_lab.srgb_to_lab(image, m, out)
    elif (s, d) == ("lab", "srgb"):
        check_finite(image, "lab image")
        w = resolve_white(p["white"], observer=p.get("observer", 2))
        res = color_lab.lab_to_srgb(image, xyz_to_rgb_matrix("srgb") * w[None, :])
        if out is not None:
            out[...] = res
            res = out
    elif (s, d) == ("srgb", "hsv"):
        res, stats = color_simple.srgb_to_hsv(image, out)
    else:
        _, kr, kb = ycbcr._coeffs(p.get("standard", "bt601"))
        yg, yo, cg, co = ycbcr._scale(p.get("signal_range", "full"), p.get("bit_depth"))
        kg = 1.0 - kr - kb
        a = np.array(
            [
                [kr, kg, kb],
                [-kr / (2 * (1 - kb)), -kg / (2 * (1 - kb)), 0.5],
                [0.5, -kg / (2 * (1 - kr)), -kb / (2 * (1 - kr))],
            ]
        )
        gain = np.array([yg, cg, cg])
        off = np.array([yo, co, co])
        if d == "ycbcr":
            res, stats = color_simple.ycbcr_affine(image, a * gain[:, None], off, out)
        else:
            ainv = np.linalg.inv(a * gain[:, None])
            res, stats = color_simple.ycbcr_affine(image, ainv, -ainv @ off, out)
    if stats is not None and image.dtype != np.uint8:
        # the boundary checks of as_image, from the statistics the kernel gathered
        outside, finite = color_simple.summarize(stats)
        if not finite:
            check_finite(image, f"{s} image")  # confirms (a non-finite sum may be overflow)
        if s == "srgb" and outside:
            as_image_strict(image, "srgb image")  # raises for plainly 0-255 floats
    return res


def lab_tables(white: Any, observer: Any) -> np.ndarray | None:
    """Return ``RGB->XYZ / white`` of sRGB for the 8-bit Lab tables; None when t may leave them.

    (The f table of :mod:`imageform._kernels.color_u8` ends just above t = 1: a white under
    which sRGB's white has X / Xn above 1 + 4 / SCALE takes the float path.)
    """
    from imageform._kernels import color_u8
    from imageform.color.rgb_spaces import rgb_to_xyz_matrix
    from imageform.color.whitepoints import resolve_white

    w = resolve_white(white, observer=observer)
    m = rgb_to_xyz_matrix("srgb") / w[:, None]
    if m.sum(axis=1).max() > 1.0 + 4.0 / color_u8.SCALE:
        return None
    return m


def _dispatch8(
    image: np.ndarray, s: str, d: str, p: dict[str, Any], out: np.ndarray | None
) -> np.ndarray | None:
    """uint8 sRGB -> OpenCV-encoded uint8 Lab / HSV (:mod:`imageform._kernels.color_u8`)."""
    if s != "srgb" or image.dtype != np.uint8 or image.size == 0:
        return None
    from imageform._kernels import color_u8

    if d == "hsv":
        return color_u8.srgb8_to_hsv8(image, out)
    m = lab_tables(p["white"], p.get("observer", 2))
    if m is None:
        return None  # X / Xn above the f table (a white other than sRGB's): the float path
    return color_u8.srgb8_to_lab8(image, m, out)
