r"""Chroma subsampling of Y'CbCr (4:4:4, 4:2:2, 4:2:0) with named chroma siting, and back.

``J:a:b`` counts chroma samples in a 4-pixel-wide, 2-row block: 4:4:4 keeps every sample,
4:2:2 halves the chroma horizontally, 4:2:0 halves it in both directions. Where the kept
chroma sample sits relative to the luma grid (its *siting*) decides the filters:

=============  ==========================  ==================================================
siting         chroma sample 0 lies at      used by
=============  ==========================  ==================================================
``"left"``     x = 0, y = 0.5 (4:2:0)       MPEG-2, H.264/HEVC default (chroma_sample_loc 0);
                                            BT.601 4:2:2 (co-sited)
``"center"``   x = 0.5, y = 0.5            JPEG/JFIF, MPEG-1, H.261
``"top_left"`` x = 0, y = 0                BT.2020 / HEVC UHD (chroma_sample_loc 2)
=============  ==========================  ==================================================

(positions in luma pixels, the centre of the top-left luma pixel at (0, 0)). Downsampling
filters the chroma before decimating: a 2-tap mean where the sample is interstitial
(offset 0.5) and the 3-tap ``[1, 2, 1]/4`` where it is co-sited (offset 0). Upsampling
interpolates linearly at each luma position's chroma coordinate ``(i - offset)/2`` (or
repeats, ``method="nearest"``); edges are replicated.
"""

from __future__ import annotations

from types import MappingProxyType
from typing import Any, Literal, NamedTuple

from imageform._backend import is_dask_namespace, namespace
from imageform._typing import Array, ArrayLike
from imageform._validate import (
    as_bool,
    as_float_strict,
    as_image_strict,
    check_name,
    check_result_array,
    describe,
)
from imageform.errors import InvalidInputError, UnknownOptionError

__all__ = [
    "CHROMA_SCHEMES",
    "CHROMA_SITINGS",
    "SubsampledChroma",
    "chroma_subsample",
    "chroma_upsample",
    "subsample_round_trip",
    "subsampling_delta_e",
]

#: Subsampling factors (vertical, horizontal) of each scheme.
CHROMA_SCHEMES: MappingProxyType[str, tuple[int, int]] = MappingProxyType(
    {"4:4:4": (1, 1), "4:2:2": (1, 2), "4:2:0": (2, 2)}
)
#: Chroma siting: offsets (vertical for 4:2:0, horizontal) of chroma sample 0 in luma pixels.
CHROMA_SITINGS: MappingProxyType[str, tuple[float, float]] = MappingProxyType(
    {"left": (0.5, 0.0), "center": (0.5, 0.5), "top_left": (0.0, 0.0)}
)


def _scheme(scheme: str) -> tuple[str, tuple[int, int]]:
    if not isinstance(scheme, str) or scheme.strip() not in CHROMA_SCHEMES:
        names = ", ".join(repr(s) for s in CHROMA_SCHEMES)
        raise UnknownOptionError(
            f"unknown chroma subsampling scheme {describe(scheme, 30)}; valid: {names}"
        )
    return scheme.strip(), CHROMA_SCHEMES[scheme.strip()]


def _take(x: Any, axis: int, start: int, stop: int | None, step: int = 1) -> Any:
    idx: list[Any] = [slice(None)] * x.ndim
    idx[axis] = slice(start, stop, step)
    return x[tuple(idx)]


def _replicate(xp: Any, x: Any, axis: int, before: int, after: int) -> Any:
    n = x.shape[axis]
    parts = [_take(x, axis, 0, 1)] * before + [x] + [_take(x, axis, n - 1, n)] * after
    return xp.concat(parts, axis=axis) if (before or after) else x


def _down2(xp: Any, x: Any, axis: int, offset: float) -> Any:
    """Halve ``axis`` (odd lengths replicate the last sample)."""
    if is_dask_namespace(xp):
        return _down2_dask(x, axis, offset)
    n = x.shape[axis]
    m = (n + 1) // 2
    if offset == 0.5:
        return _down2_padded(_replicate(xp, x, axis, 0, 2 * m - n), axis, offset, m)
    return _down2_padded(_replicate(xp, x, axis, 1, 2 * m - n + 1), axis, offset, m)


def _down2_padded(p: Any, axis: int, offset: float, m: int) -> Any:
    """Filter and decimate the padded samples ``p`` to the ``m`` samples of :func:`_down2`.

    ``p`` holds the samples (``offset`` 0.5), or one sample before them then the samples
    (``p[j] = x[j - 1]``, co-sited), replicated past their end.
    """
    if offset == 0.5:
        return 0.5 * (_take(p, axis, 0, 2 * m, 2) + _take(p, axis, 1, 2 * m, 2))
    left = _take(p, axis, 0, 2 * m, 2)
    mid = _take(p, axis, 1, 2 * m + 1, 2)
    right = _take(p, axis, 2, 2 * m + 2, 2)
    return 0.25 * left + 0.5 * mid + 0.25 * right


def _even_chunks(x: Any, axis: int) -> Any:
    """``x`` with even chunks along ``axis`` (the last may be odd): a block's samples pair up."""
    ax = axis % x.ndim
    if all(ch % 2 == 0 for ch in x.chunks[ax][:-1]):
        return x
    size = max(2, max(x.chunks[ax]) + max(x.chunks[ax]) % 2)
    return x.rechunk({ax: size})


def _grown(x: Any, axis: int) -> Any:
    """``x`` with each block grown by one sample on both sides along ``axis``.

    These are the neighbours a 3-tap filter reads; the image's edge samples are replicated.
    """
    import dask.array as da

    ax = axis % x.ndim
    depth = {i: (1 if i == ax else 0) for i in range(x.ndim)}
    bnd = {i: ("nearest" if i == ax else "none") for i in range(x.ndim)}
    return da.overlap.overlap(x, depth=depth, boundary=bnd)


def _down2_dask(x: Any, axis: int, offset: float) -> Any:
    """:func:`_down2` of a Dask array, block by block (the same sums: equal values).

    Blocks of even length along ``axis`` pair up their own samples; the co-sited filter also
    reads the sample before each block (one sample of overlap, the first one replicated at
    the image's edge). Shifting whole arrays instead split the chunks at every shift (6560
    tasks for a 1024 x 1024 round trip in 256-px chunks).
    """
    ax = axis % x.ndim
    x = _even_chunks(x, axis)
    out_chunks = list(x.chunks)
    out_chunks[ax] = tuple((ch + 1) // 2 for ch in x.chunks[ax])

    if offset == 0.5:

        def block(b: Any) -> Any:
            return _down2(namespace(b), b, axis, offset)

        return x.map_blocks(block, chunks=tuple(out_chunks), dtype=x.dtype)

    def grown(b: Any) -> Any:  # b[j] = x[j - 1]; its last sample replicates past an odd end
        return _down2_padded(b, axis, offset, (b.shape[axis] - 1) // 2)

    return _grown(x, axis).map_blocks(grown, chunks=tuple(out_chunks), dtype=x.dtype)


def _interleave(xp: Any, even: Any, odd: Any, axis: int, n: int) -> Any:
    st = xp.stack([even, odd], axis=axis + 1 if axis >= 0 else axis)
    shape = list(even.shape)
    shape[axis] = 2 * even.shape[axis]
    out = xp.reshape(st, tuple(shape))
    return _take(out, axis, 0, n)


def _up2(xp: Any, c: Any, axis: int, offset: float, n: int, method: str) -> Any:
    """Double ``axis`` back to length ``n``."""
    if is_dask_namespace(xp):
        return _up2_dask(c, axis, offset, n, method)
    if method == "nearest":
        return _interleave(xp, c, c, axis, n)
    return _up2_padded(xp, _replicate(xp, c, axis, 1, 1), axis, offset, n)


def _up2_padded(xp: Any, p: Any, axis: int, offset: float, n: int) -> Any:
    """:func:`_up2` (bilinear) from the samples with one more on both sides, ``p[k + 1] = c[k]``."""
    m = p.shape[axis] - 2
    prev = _take(p, axis, 0, m)
    cur = _take(p, axis, 1, m + 1)
    nxt = _take(p, axis, 2, m + 2)
    if offset == 0.5:  # luma 2k at chroma k - 1/4, 2k+1 at k + 1/4
        even = 0.75 * cur + 0.25 * prev
        odd = 0.75 * cur + 0.25 * nxt
    else:  # luma 2k at chroma k, 2k+1 at k + 1/2
        even = cur
        odd = 0.5 * (cur + nxt)
    return _interleave(xp, even, odd, axis, n)


def _up2_dask(c: Any, axis: int, offset: float, n: int, method: str) -> Any:
    """:func:`_up2` of a Dask array, block by block (the same sums: equal values).

    Each block doubles its own samples, reading one neighbour on both sides (bilinear; the
    edge samples replicated at the image's edges); the result is cut to ``n`` at the end.
    """
    ax = axis % c.ndim
    out_chunks = list(c.chunks)
    out_chunks[ax] = tuple(2 * ch for ch in c.chunks[ax])
    if method == "nearest":

        def block(b: Any) -> Any:
            return _interleave(namespace(b), b, b, axis, 2 * b.shape[axis])

        out = c.map_blocks(block, chunks=tuple(out_chunks), dtype=c.dtype)
    else:

        def grown(b: Any) -> Any:
            return _up2_padded(namespace(b), b, axis, offset, 2 * (b.shape[axis] - 2))

        out = _grown(c, axis).map_blocks(grown, chunks=tuple(out_chunks), dtype=c.dtype)
    return out if out.shape[ax] == n else _take(out, axis, 0, n)


class _SubsampledChroma(NamedTuple):
    #: Full-resolution Y', shape (..., H, W).
    luma: Any
    #: Subsampled (Cb, Cr), shape (..., ceil(H/fv), ceil(W/fh), 2).
    chroma: Any


class SubsampledChroma(_SubsampledChroma):
    """The result of :func:`chroma_subsample`: ``(luma, chroma)``.

    ``luma``: full-resolution Y', shape (..., H, W); ``chroma``: subsampled (Cb, Cr), shape
    (..., ceil(H/fv), ceil(W/fh), 2). Built by hand, both must be real and finite.
    """

    __slots__ = ()

    def __new__(cls, luma: Any, chroma: Any) -> SubsampledChroma:
        """Build the result, refusing a non-real or non-finite ``luma`` or ``chroma``."""
        check_result_array(luma, "luma")
        check_result_array(chroma, "chroma")
        return super().__new__(cls, luma, chroma)


def chroma_subsample(
    ycbcr: ArrayLike,
    scheme: Literal["4:4:4", "4:2:2", "4:2:0"] = "4:2:0",
    *,
    siting: Literal["left", "center", "top_left"] = "left",
) -> SubsampledChroma:
    r"""Split Y'CbCr into full-resolution luma and subsampled chroma.

    .. math:: C_{sub}[k] = \tfrac12 (C[2k] + C[2k+1]) \ (\text{interstitial}),\quad
        C_{sub}[k] = \tfrac14 C[2k-1] + \tfrac12 C[2k] + \tfrac14 C[2k+1] \ (\text{co-sited})

    Parameters
    ----------
    ycbcr : array_like, shape (..., H, W, 3)
        Y', Cb, Cr (any scale; see :func:`imageform.color.srgb_to_ycbcr`).
    scheme : {"4:4:4", "4:2:2", "4:2:0"}
        The chroma subsampling scheme (``J:a:b`` notation).
    siting : {"left", "center", "top_left"}
        Chroma siting (module table); 4:2:2 uses only its horizontal part.

    Returns
    -------
    SubsampledChroma
        ``luma`` : array, shape (..., H, W); ``chroma`` : array, shape
        (..., ceil(H/fv), ceil(W/fh), 2).

    References
    ----------
    ITU-R BT.601-7 (4:2:2 co-siting); ITU-T H.264 Annex E, Fig. E-1 (chroma_sample_loc_type);
    JPEG File Interchange Format 1.02 (centred chroma).

    Examples
    --------
    >>> import numpy as np
    >>> y, c = chroma_subsample(np.zeros((4, 6, 3)), "4:2:0")
    >>> y.shape, c.shape
    ((4, 6), (2, 3, 2))
    """
    _, (fv, fh) = _scheme(scheme)
    site = check_name(siting, CHROMA_SITINGS, "chroma siting")
    img = as_image_strict(ycbcr, "ycbcr", range_check=False)
    if img.ndim < 3:
        raise InvalidInputError(f"expected ycbcr of shape (..., H, W, 3), got {tuple(img.shape)}")
    xp = namespace(img)
    luma = img[..., 0]
    chroma = img[..., 1:]
    ov, oh = CHROMA_SITINGS[site]
    if fh == 2:
        chroma = _down2(xp, chroma, -2, oh)
    if fv == 2:
        chroma = _down2(xp, chroma, -3, ov)
    return SubsampledChroma._make((luma, chroma))  # from checked input: no second pass


def chroma_upsample(
    luma: ArrayLike,
    chroma: ArrayLike,
    scheme: Literal["4:4:4", "4:2:2", "4:2:0"] = "4:2:0",
    *,
    siting: Literal["left", "center", "top_left"] = "left",
    method: Literal["bilinear", "nearest"] = "bilinear",
) -> Array:
    r"""Rebuild full-resolution Y'CbCr from luma and subsampled chroma.

    .. math:: C(i) = (1 - t)\,C_{sub}[k] + t\,C_{sub}[k + 1],\quad
        k + t = (i - o)/2

    with ``o`` the siting offset (edges replicated).

    Parameters
    ----------
    luma : array_like, shape (..., H, W)
        The full-resolution Y' plane.
    chroma : array_like, shape (..., ceil(H/fv), ceil(W/fh), 2)
        The subsampled Cb, Cr planes.
    scheme, siting :
        As given to :func:`chroma_subsample`.
    method : {"bilinear", "nearest"}
        Interpolation of the chroma samples at their sited positions.

    Returns
    -------
    array, shape (..., H, W, 3)

    Examples
    --------
    >>> import numpy as np
    >>> c = np.array([[[0.0, 0.0], [0.4, -0.4]]])
    >>> out = chroma_upsample(np.zeros((1, 4)), c, "4:2:2", siting="center")
    >>> out[0, :, 1].round(3).tolist()
    [0.0, 0.1, 0.3, 0.4]
    """
    _, (fv, fh) = _scheme(scheme)
    site = check_name(siting, CHROMA_SITINGS, "chroma siting")
    how = check_name(method, ("bilinear", "nearest"), "chroma upsampling method")
    xp = namespace(luma, chroma)
    y = as_float_strict(luma, "luma", xp=xp, integer="float32")
    c = as_float_strict(chroma, "chroma", xp=xp, dtype=y.dtype)
    if y.ndim < 2 or c.ndim != y.ndim + 1 or c.shape[-1] != 2:
        raise InvalidInputError(
            f"expected luma (..., H, W) and chroma (..., h, w, 2), got {tuple(y.shape)} and "
            f"{tuple(c.shape)}"
        )
    H, W = y.shape[-2], y.shape[-1]
    want = (-(-H // fv), -(-W // fh))
    if tuple(c.shape[-3:-1]) != want:
        raise InvalidInputError(
            f"expected chroma of shape (..., {want[0]}, {want[1]}, 2) for luma {H} x {W} "
            f"and {scheme}, got {tuple(c.shape)}"
        )
    ov, oh = CHROMA_SITINGS[site]
    if fv == 2:
        c = _up2(xp, c, -3, ov, H, how)
    if fh == 2:
        c = _up2(xp, c, -2, oh, W, how)
    return xp.concat([y[..., None], c], axis=-1)


def subsample_round_trip(
    image: ArrayLike,
    scheme: Literal["4:4:4", "4:2:2", "4:2:0"] = "4:2:0",
    *,
    siting: Literal["left", "center", "top_left"] = "left",
    method: Literal["bilinear", "nearest"] = "bilinear",
    standard: Literal["bt601", "bt709", "bt2020"] = "bt601",
    clip: bool = False,
) -> Array:
    """Round-trip sRGB -> Y'CbCr -> subsample -> upsample -> sRGB, as a codec's colour path does.

    Parameters
    ----------
    image : array_like, shape (..., H, W, 3)
        Encoded sRGB in [0, 1] or uint8/uint16.
    scheme, siting, method :
        See :func:`chroma_subsample` and :func:`chroma_upsample`.
    standard : {"bt601", "bt709", "bt2020"}
        Luma coefficients (JPEG: BT.601 full range).
    clip : bool
        Clip the rebuilt R'G'B' to [0, 1] (what a decoder writing 8-bit RGB does); only when
        asked.

    Returns
    -------
    array, shape (..., H, W, 3)

    Examples
    --------
    A flat image survives any scheme:

    >>> import numpy as np
    >>> out = subsample_round_trip(np.full((4, 4, 3), [0.8, 0.3, 0.1]))
    >>> out[1, 2].round(12).tolist()
    [0.8, 0.3, 0.1]
    """
    from imageform.color.ycbcr import srgb_to_ycbcr, ycbcr_to_srgb

    ycc = srgb_to_ycbcr(image, standard)
    y, c = chroma_subsample(ycc, scheme, siting=siting)
    rgb = ycbcr_to_srgb(chroma_upsample(y, c, scheme, siting=siting, method=method), standard)
    if as_bool(clip, "clip"):
        rgb = namespace(rgb).clip(rgb, 0.0, 1.0)
    return rgb


def subsampling_delta_e(
    image: ArrayLike,
    scheme: Literal["4:4:4", "4:2:2", "4:2:0"] = "4:2:0",
    *,
    siting: Literal["left", "center", "top_left"] = "left",
    method: Literal["bilinear", "nearest"] = "bilinear",
    standard: Literal["bt601", "bt709", "bt2020"] = "bt601",
    clip: bool = True,
) -> Array:
    r"""Per-pixel CIEDE2000 between an sRGB image and its chroma-subsampled round trip.

    .. math:: \Delta E_{00}\big(\mathrm{Lab}(I),\ \mathrm{Lab}(U(S(I)))\big)

    (sRGB -> CIELAB with the D65 white). ``clip`` (default True here: the measured decoder
    writes RGB in [0, 1]) clips the round trip before the comparison.

    Returns
    -------
    array, shape (..., H, W)

    Examples
    --------
    >>> import numpy as np
    >>> img = np.zeros((4, 4, 3)); img[:, 2:] = [0.9, 0.1, 0.1]
    >>> round(float(subsampling_delta_e(img, "4:4:4").max()), 9)
    0.0
    >>> round(float(subsampling_delta_e(img, "4:2:0", siting="center").max()), 2)
    15.28
    """
    from imageform.color.convert import convert
    from imageform.color.delta_e import delta_e_ciede2000

    img = as_image_strict(image, "image")
    rt = subsample_round_trip(
        img, scheme, siting=siting, method=method, standard=standard, clip=clip
    )
    return delta_e_ciede2000(convert(img, "srgb", "lab"), convert(rt, "srgb", "lab"))
