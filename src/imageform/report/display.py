"""Turning a simulation stage into something to look at (8-bit sRGB) or to keep (16-bit raw).

One function, :func:`stage_display_image`, decides how every stage kind is displayed, so
that the report, the stage files and the figures agree. The kinds are documented in
:mod:`imageform.simulate.result`.
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from imageform._validate import as_real, check_name, describe, format_shape
from imageform.errors import InvalidInputError

__all__ = ["DISPLAY_PERCENTILE", "raw_to_uint16", "stage_display_image"]

#: The percentile of a linear stage that is shown as white (display only).
DISPLAY_PERCENTILE = 99.0


def _host(image: object) -> object:
    """Return a PyTorch tensor as a NumPy array (on the host); anything else as it is."""
    if type(image).__module__.startswith("torch"):
        return image.detach().cpu().numpy()  # type: ignore[attr-defined]
    return image


def _as_rgb(a: np.ndarray, name: str) -> np.ndarray:
    """(H, W), (H, W, 1) or (H, W, 3) -> (H, W, 3)."""
    if a.ndim == 3 and a.shape[-1] == 1:
        a = a[..., 0]
    if a.ndim == 2:
        return np.repeat(a[..., None], 3, axis=-1)
    if a.ndim == 3 and a.shape[-1] == 3:
        return a
    raise InvalidInputError(
        f"expected {name} of shape (H, W), (H, W, 1) or (H, W, 3), got {a.shape}"
    )


def stage_display_image(
    image: np.ndarray,
    kind: Literal["linear", "raw", "srgb"],
    *,
    white_level: float | None = None,
    percentile: float = DISPLAY_PERCENTILE,
) -> np.ndarray:
    r"""Return the 8-bit sRGB picture ``(H, W, 3)`` uint8 of one stage of the chain.

    - ``"linear"`` (linear light, any scale): divide by the ``percentile``-th percentile
      ``p`` of all values, then sRGB-encode:

      .. math:: V = \mathrm{sRGB}\big(\min(\max(L / p, 0), 1)\big)

      (an all-zero image stays black).
    - ``"raw"`` (digital numbers, ``(H, W)``): grey ``V = DN / white_level``.
    - ``"srgb"``: shown as it is.

    Then ``round(255 V)``. This is a picture only: values outside [0, 1] after the scaling
    (highlights above the percentile, negative noise, out-of-gamut colours) are clipped for
    display, never in the data (the stage files and metrics keep the arrays as they are).

    Parameters
    ----------
    image : ndarray, shape (H, W), (H, W, 1) or (H, W, 3)
        Finite values.
    kind : {"linear", "raw", "srgb"}
        Linear light (scaled to a percentile and encoded), raw codes (scaled by
        ``white_level``), or already encoded sRGB.
    white_level : float, optional
        Largest code of a raw stage (required for ``"raw"``).
    percentile : float
        For ``"linear"``: which percentile becomes white (99 by default).

    Notes
    -----
    Source: IEC 61966-2-1:1999, clause 5.3 (the sRGB encoding).

    Examples
    --------
    >>> stage_display_image(np.array([[0.0, 0.18, 1.0]]), "linear", percentile=100)[0, 1]
    array([118, 118, 118], dtype=uint8)
    >>> stage_display_image(np.array([[0, 2048, 4095]]), "raw", white_level=4095)[0, :, 0]
    array([  0, 128, 255], dtype=uint8)
    """
    from imageform._colormath import srgb_encode

    k = check_name(kind, ("linear", "raw", "srgb"), "stage kind", "kind")
    if image is None or isinstance(image, str | bytes):
        raise InvalidInputError(f"expected image as a numeric array, got {describe(image)}")
    a = np.asarray(_host(image))
    if a.dtype.kind not in "biuf":
        raise InvalidInputError(f"expected image as a numeric array, got {describe(image)}")
    if a.ndim not in (2, 3) or (a.ndim == 3 and a.shape[-1] not in (1, 3)):
        raise InvalidInputError(
            f"expected image of shape (H, W), (H, W, 1) or (H, W, 3), got {format_shape(a.shape)}"
        )
    if a.size == 0:
        raise InvalidInputError(f"expected a non-empty image, got shape {format_shape(a.shape)}")
    # checked whatever the kind (unused but for "raw"): a complex value is never cut
    wl = None if white_level is None else as_real(white_level, "white_level", positive=True)
    if k == "raw":
        if a.ndim != 2:
            raise InvalidInputError(
                f"expected image as a raw stage of shape (H, W), got {format_shape(a.shape)}"
            )
        if wl is None:
            raise InvalidInputError("a raw stage needs white_level > 0, got None")
    elif k == "linear":
        percentile = as_real(percentile, "percentile")
        if not 0 < percentile <= 100:
            raise InvalidInputError(f"expected percentile in (0, 100], got {percentile:g}")
    a = a.astype(np.float32)  # a picture: float32 is plenty
    if not np.all(np.isfinite(a)):
        raise InvalidInputError(
            "image contains NaN or inf (or values beyond float32); cannot display it"
        )
    if k == "raw":
        v = a / np.float32(wl)
    elif k == "linear":
        flat = a.ravel()
        if flat.size > 1_000_000:  # a regular subsample gives the same percentile to display
            flat = flat[:: flat.size // 500_000]
        p = float(np.percentile(flat, percentile))
        if p <= 0:
            p = float(a.max())
        v = a / np.float32(p) if p > 0 else np.zeros_like(a)
        np.clip(v, 0.0, 1.0, out=v)
        # linear_to_srgb's formula without its checks (the values are finite, in [0, 1])
        v = np.asarray(srgb_encode(np, v))
    else:
        v = a
    # every array here is this function's own (a is a float32 copy): scaled in place
    rgb = _as_rgb(np.asarray(v), f"a {k} stage")
    np.clip(rgb, 0.0, 1.0, out=rgb)
    rgb *= 255.0
    return np.round(rgb, out=rgb).astype(np.uint8)


def raw_to_uint16(image: np.ndarray) -> np.ndarray | None:
    """Return the raw digital numbers as uint16 if they are whole numbers in [0, 65535], else None.

    The caller then keeps them as a float TIFF: nothing is rounded or clipped.

    Examples
    --------
    >>> raw_to_uint16(np.array([[0.0, 4095.0]])).dtype
    dtype('uint16')
    >>> raw_to_uint16(np.array([[0.5]])) is None
    True
    """
    a = np.asarray(image)
    if a.dtype == np.uint16:
        return a
    if a.dtype.kind in "biu":
        ok = a.size == 0 or (int(a.min()) >= 0 and int(a.max()) <= 65535)
        return a.astype(np.uint16) if ok else None
    if (
        a.dtype.kind == "f"
        and np.all(np.isfinite(a))
        and float(a.min()) >= 0
        and float(a.max()) <= 65535
        and np.all(a == np.round(a))
    ):
        return a.astype(np.uint16)
    return None
