"""Colour spaces that image files declare: ICC profiles, PNG's sRGB, gAMA and cHRM, EXIF.

A phone writes its photographs in Display P3, a camera set to Adobe RGB writes Adobe RGB,
a raw converter often ProPhoto; the pixel values mean different colours in each. The file
says which in an embedded ICC profile (ICC.1:2010, the matrix/TRC form every RGB working
space uses), in PNG's ``sRGB`` chunk, or in EXIF's ``ColorSpace`` tag (1: sRGB;
uncalibrated with the DCF interoperability index ``R03``: Adobe RGB). Reading those values
as sRGB is wrong by several CIEDE2000 on saturated colours.

:func:`~imageform.io.image_color_space` reads what a file declares and names the matching space of
:data:`imageform.color.RGB_SPACES` (or its ``linear_`` twin): a profile's primaries and
white, brought back from the profile connection space (D50) through its ``chad`` tag (or
Bradford from its ``wtpt`` for version 2 profiles), within 0.003 in xy, and its tone curves
within 0.004 of the space's decoding at six levels. :func:`icc_profile` gives the profile
imageform embeds when it writes an image in one of those spaces (small public-domain
profiles, ``io/data/icc/README.md``).
"""

from __future__ import annotations

import struct
from functools import cache
from importlib import resources
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from imageform.errors import InvalidInputError

__all__ = [
    "RGB_PROFILED",
    "DeclaredColorSpace",
    "IccProfile",
    "icc_profile",
    "identify_icc",
    "parse_icc",
]

#: The profile connection space's white, ICC.1:2010 sec. 7.2.16 (D50, s15Fixed16 values).
_D50 = np.array([0.9642, 1.0, 0.8249])
#: Profiles imageform embeds, per space (io/data/icc/README.md: source and licence).
_SHIPPED = {
    "srgb": "sRGB-v2-magic.icc",
    "display_p3": "DisplayP3-v2-magic.icc",
    "adobe_rgb": "AdobeCompat-v2.icc",
    "prophoto": "ProPhoto-v2-magic.icc",
    "rec2020": "Rec2020-v2-magic.icc",
    "rec709": "Rec709-v2-magic.icc",
    "linear_srgb": "scRGB-v2.icc",
}
#: Spaces with a shipped ICC profile (embedded by ``write_image(..., color_space=...)``).
RGB_PROFILED = tuple(_SHIPPED)
_XY_TOL = 0.003
_TRC_TOL = 0.004
_LEVELS = np.array([0.02, 0.1, 0.25, 0.5, 0.75, 0.95])


class IccProfile(NamedTuple):
    """What imageform reads of an ICC profile.

    ``version`` (major, minor), ``color_space`` (the data colour space signature: ``RGB``,
    ``GRAY``, ``CMYK`` ...), ``description``; for matrix/TRC RGB profiles ``matrix`` (3, 3)
    (columns: the red, green and blue colorants in the PCS, D50), ``white`` (native white
    XYZ: ``chad``⁻¹ D50, or ``wtpt``), ``primaries_xy`` (3, 2) and ``white_xy`` at the
    native white, ``curves`` (three callables from encoded to linear); otherwise None.
    """

    version: tuple[int, int]
    color_space: str
    description: str
    matrix: NDArray[np.float64] | None
    white: NDArray[np.float64] | None
    primaries_xy: NDArray[np.float64] | None
    white_xy: NDArray[np.float64] | None
    curves: tuple[object, object, object] | None


class DeclaredColorSpace(NamedTuple):
    """The colour space an image file declares (:func:`image_color_space`).

    ``name``: a space of :data:`imageform.color.SPACES` (``srgb``, ``display_p3``,
    ``adobe_rgb``, ``prophoto``, ``rec2020``, ``rec709`` or a ``linear_`` twin), or None
    when the file declares nothing or a profile imageform does not recognise; a TIFF that
    :func:`~imageform.io.write_image` wrote in a space without a profile names that space
    (``lab``, ``xyz`` ...). ``source``: ``icc``, ``png-srgb``, ``png-gama`` / ``png-chrm`` (a
    PNG's ``gAMA`` and ``cHRM`` chunks), ``png-cicp`` (a PNG's ``cICP`` chunk), ``nclx``
    (HEIF's H.273 code points), ``exif``,
    ``tiff-description`` (``imageform_color_space`` in a TIFF's ImageDescription JSON),
    ``radiance`` (a Radiance HDR file: linear RGB, its ``PRIMARIES``) or ``none``.
    ``description``: the profile's own description (``""`` without one).
    """

    name: str | None
    source: str
    description: str


def _s15(b: bytes) -> float:
    return struct.unpack(">i", b)[0] / 65536.0


def _curve(data: bytes, off: int, size: int) -> object:
    """One tone curve (``curv`` or ``para``, ICC.1:2010 sec. 10.5, 10.16) as a function."""
    sig = data[off : off + 4]
    if sig == b"curv":
        (n,) = struct.unpack(">I", data[off + 8 : off + 12])
        if n == 0:
            return lambda x: np.asarray(x, dtype=np.float64)
        if n == 1:
            g = struct.unpack(">H", data[off + 12 : off + 14])[0] / 256.0
            return lambda x: np.power(np.clip(x, 0.0, 1.0), g)
        if off + 12 + 2 * n > len(data):
            raise InvalidInputError("ICC profile: a curve runs past the end of the profile")
        table = np.frombuffer(data, ">u2", n, off + 12).astype(np.float64) / 65535.0
        grid = np.linspace(0.0, 1.0, n)
        return lambda x: np.interp(np.clip(x, 0.0, 1.0), grid, table)
    if sig == b"para":
        (kind,) = struct.unpack(">H", data[off + 8 : off + 10])
        count = {0: 1, 1: 3, 2: 4, 3: 5, 4: 7}.get(kind)
        if count is None:
            raise InvalidInputError(f"ICC profile: unknown parametric curve type {kind}")
        p = [_s15(data[off + 12 + 4 * i : off + 16 + 4 * i]) for i in range(count)]
        # every type as Y = (aX + b)^g + e for X >= d, else cX + f (ICC.1:2010 table 68)
        g, a, b, c, d, e, f = 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0
        if kind == 0:
            g = p[0]
        elif kind in (1, 2):
            g, a, b = p[:3]
            d = -b / a if a else 0.0
            if kind == 2:
                e = f = p[3]
        else:
            g, a, b, c, d = p[:5]
            if kind == 4:
                e, f = p[5], p[6]

        def para(x: object) -> NDArray[np.float64]:
            x = np.clip(np.asarray(x, dtype=np.float64), 0.0, 1.0)
            hi = np.power(np.maximum(a * x + b, 0.0), g) + e
            return np.where(x >= d, hi, c * x + f)

        return para
    raise InvalidInputError(f"ICC profile: unknown tone curve type {sig!r}")


def _text(data: bytes, off: int, size: int) -> str:
    """Read a ``desc`` (v2), ``mluc`` (v4) or ``text`` tag as a string ("" if unreadable)."""
    sig = data[off : off + 4]
    try:
        if sig == b"desc":
            (n,) = struct.unpack(">I", data[off + 8 : off + 12])
            return data[off + 12 : off + 12 + n].split(b"\0")[0].decode("latin-1").strip()
        if sig == b"mluc":
            (count,) = struct.unpack(">I", data[off + 8 : off + 12])
            if count == 0:
                return ""
            length, start = struct.unpack(">II", data[off + 20 : off + 28])
            raw = data[off + start : off + start + length]
            return raw.decode("utf-16-be", errors="replace").rstrip("\0").strip()
        if sig == b"text":
            return data[off + 8 : off + size].split(b"\0")[0].decode("latin-1").strip()
    except (struct.error, UnicodeDecodeError):
        return ""
    return ""


def _xy(xyz: NDArray[np.float64]) -> NDArray[np.float64]:
    s = xyz.sum(axis=0)
    return np.stack([xyz[0] / s, xyz[1] / s], axis=-1)


def parse_icc(data: bytes) -> IccProfile:
    r"""Read an ICC profile's header, description and matrix/TRC tags.

    ICC.1:2010 (profile version 4.3) and ICC.1:2001-04 (version 2): the 128-byte header,
    the tag table, ``desc``/``mluc``, ``wtpt``, ``chad``, ``rXYZ``/``gXYZ``/``bXYZ`` and
    ``rTRC``/``gTRC``/``bTRC`` (``curv`` tables and gammas, ``para`` curves of types 0-4).
    The colorants are in the PCS (D50); the native white and primaries are

    .. math:: \mathbf{w} = C^{-1}\,\mathbf{w}_{D50},\qquad \mathbf{p}_i = C^{-1}\,\mathbf{c}_i

    with ``C`` the ``chad`` matrix, or Bradford from ``wtpt`` to D50 for a version 2
    profile without ``chad`` (ICC.1:2010 annex E).

    Parameters
    ----------
    data : bytes
        The whole profile.

    Returns
    -------
    IccProfile

    Raises
    ------
    InvalidInputError
        Not an ICC profile (no ``acsp`` signature), truncated, or a tag that points outside
        it.

    Examples
    --------
    >>> from imageform.io import icc_profile, parse_icc
    >>> p = parse_icc(icc_profile("display_p3"))
    >>> p.color_space, p.primaries_xy.round(3).tolist()
    ('RGB', [[0.68, 0.32], [0.265, 0.69], [0.15, 0.06]])
    """
    if not isinstance(data, (bytes, bytearray, memoryview)):
        raise InvalidInputError(
            f"expected data, an ICC profile, as bytes; got {type(data).__name__}"
        )
    data = bytes(data)
    if len(data) < 132 or data[36:40] != b"acsp":
        raise InvalidInputError("not an ICC profile (no 'acsp' signature in its header)")
    version = (data[8], data[9] >> 4)
    space = data[16:20].decode("latin-1").strip()
    (count,) = struct.unpack(">I", data[128:132])
    if 132 + 12 * count > len(data):
        raise InvalidInputError("ICC profile: its tag table runs past the end of the profile")
    tags: dict[bytes, tuple[int, int]] = {}
    for i in range(count):
        sig, off, size = struct.unpack(">4sII", data[132 + 12 * i : 144 + 12 * i])
        if off + size > len(data) or size < 8:
            raise InvalidInputError(f"ICC profile: tag {sig!r} points outside the profile")
        tags[sig] = (off, size)

    def xyz(sig: bytes) -> NDArray[np.float64]:
        off, _ = tags[sig]
        return np.array([_s15(data[off + 8 + 4 * k : off + 12 + 4 * k]) for k in range(3)])

    description = ""
    if b"desc" in tags:
        description = _text(data, *tags[b"desc"])
    rgb = (b"rXYZ", b"gXYZ", b"bXYZ", b"rTRC", b"gTRC", b"bTRC")
    if space != "RGB" or not all(t in tags for t in rgb):
        return IccProfile(version, space, description, None, None, None, None, None)
    M = np.stack([xyz(b"rXYZ"), xyz(b"gXYZ"), xyz(b"bXYZ")], axis=1)
    if b"chad" in tags:
        off, _ = tags[b"chad"]
        chad = np.array([_s15(data[off + 8 + 4 * k : off + 12 + 4 * k]) for k in range(9)])
        back = np.linalg.inv(chad.reshape(3, 3))
    elif b"wtpt" in tags and version[0] < 4:
        from imageform.color import chromatic_adaptation_matrix

        # version 2: wtpt is the native white, the colorants adapted to D50 by Bradford
        back = np.asarray(chromatic_adaptation_matrix(_D50, xyz(b"wtpt"), "bradford"))
    else:
        back = np.eye(3)
    native = back @ M
    white = back @ _D50
    curves = tuple(_curve(data, *tags[t]) for t in (b"rTRC", b"gTRC", b"bTRC"))
    return IccProfile(
        version, space, description, M, white, _xy(native), _xy(white[:, None])[0],
        curves,  # type: ignore[arg-type]
    )  # fmt: skip


@cache
def _references() -> tuple[tuple[str, NDArray[np.float64], NDArray[np.float64], NDArray], ...]:
    """(name, primaries xy, white xy, decoded levels) of every encoded RGB space."""
    from imageform.color import RGB_SPACES, convert, rgb_space

    out = []
    for name in RGB_SPACES:
        s = rgb_space(name)
        ramp = np.repeat(_LEVELS[:, None], 3, axis=1)[None]  # (1, 6, 3) greys
        linear = np.asarray(convert(ramp, name, f"linear_{name}"))[0, :, 0]
        arrays = (np.array(s.primaries_xy), np.array(s.white_xy), linear)
        for a in arrays:
            a.setflags(write=False)  # computed once (functools.cache): read, never written
        out.append((name, *arrays))
    return tuple(out)


def identify_icc(profile: IccProfile) -> str | None:
    """Name the space of :data:`imageform.color.SPACES` an RGB profile describes, or None.

    The native primaries and white (see :func:`parse_icc`) within 0.003 in xy of the
    space's, and each tone curve within 0.004 of the space's decoding (its ``linear_``
    twin for straight curves) at the levels 0.02, 0.1, 0.25, 0.5, 0.75 and 0.95.

    Examples
    --------
    >>> from imageform.io import icc_profile, identify_icc, parse_icc
    >>> identify_icc(parse_icc(icc_profile("adobe_rgb")))
    'adobe_rgb'
    """
    if not isinstance(profile, IccProfile):
        raise InvalidInputError(
            f"expected profile, an IccProfile (parse_icc), got {type(profile).__name__}"
        )
    if profile.primaries_xy is None or profile.curves is None or profile.white_xy is None:
        return None
    levels = np.stack([np.asarray(c(_LEVELS)) for c in profile.curves])  # type: ignore[operator]
    return _identify(profile.primaries_xy, profile.white_xy, (levels,))


def _identify(
    primaries_xy: NDArray[np.float64],
    white_xy: NDArray[np.float64],
    decodings: tuple[NDArray[np.float64], ...],
) -> str | None:
    """Name the space of these primaries and white whose decoding one of ``decodings`` is.

    ``decodings``: the linear values of :data:`_LEVELS` through each candidate tone curve.
    """
    for name, prim, white, decoded in _references():
        if np.max(np.abs(primaries_xy - prim)) > _XY_TOL:
            continue
        if np.max(np.abs(white_xy - white)) > _XY_TOL:
            continue
        for levels in decodings:
            if np.max(np.abs(levels - decoded)) <= _TRC_TOL:
                return name
        for levels in decodings:
            if np.max(np.abs(levels - _LEVELS)) <= _TRC_TOL:
                return f"linear_{name}"
    return None


#: libpng's ``PNG_GAMMA_THRESHOLD`` (0.05): a file gamma within 5 % of sRGB's 1/2.2 (the
#: product of the two within 0.05 of 1) needs no correction; such a ``gAMA`` reads as sRGB's.
_PNG_GAMMA_THRESHOLD = 0.05
#: sRGB's chromaticities, as PNG writers store them in ``cHRM`` (PNG 3rd ed. sec. 11.3.3.2).
_SRGB_CHRM = (0.3127, 0.329, 0.64, 0.33, 0.3, 0.6, 0.15, 0.06)


def declared_by_png_chunks(
    gamma: float | None, chromaticity: tuple[float, ...] | None
) -> DeclaredColorSpace | None:
    """Name what a PNG's ``gAMA`` and ``cHRM`` chunks declare (no ``iCCP``, no ``sRGB``).

    PNG 3rd ed. sec. 12.2 and 13.13: ``gAMA`` holds the file gamma ``g`` (value / 100000) with
    which the samples were encoded, so that the light they mean is ``V**(1 / g)`` (``V`` the
    sample over its largest value); ``cHRM`` holds the white and the red, green and blue
    chromaticities. The pair names a space of :data:`imageform.color.RGB_SPACES` as an ICC
    profile does (:func:`identify_icc`: primaries and white within 0.003, the curve within
    0.004 of the space's decoding, or straight for the ``linear_`` twin). As colour-managed
    readers do: without ``cHRM`` the primaries are sRGB's (Skia's ``SkPngCodec``); without
    ``gAMA`` the curve is sRGB's; a file gamma within 5 % of 1/2.2 is sRGB's curve (libpng's
    ``PNG_GAMMA_THRESHOLD``: the gAMA 45455 that PNG writers add beside ``sRGB``). A gAMA
    of 0 or less, or a cHRM with a zero ``y``, is ignored, as libpng ignores it.

    Returns
    -------
    DeclaredColorSpace or None
        Source ``png-gama`` (``png-chrm`` with ``cHRM`` alone); ``name`` None when no space
        matches, the chunks in ``description``. None when neither chunk is usable.
    """
    if gamma is not None and not (np.isfinite(gamma) and gamma > 0):
        gamma = None
    chrm = None
    if chromaticity is not None and len(chromaticity) == 8:
        c = np.asarray(chromaticity, dtype=np.float64)
        if np.all(np.isfinite(c)) and np.all(c[1::2] > 0) and np.all(c >= 0):
            chrm = c
    if gamma is None and chrm is None:
        return None
    c = chrm if chrm is not None else np.asarray(_SRGB_CHRM)
    white, primaries = c[:2], c[2:].reshape(3, 2)
    srgb_curve = _references()[0][3]  # RGB_SPACES starts with srgb
    if gamma is None:
        decodings: tuple[NDArray[np.float64], ...] = (srgb_curve,)
    else:
        power = np.power(_LEVELS, 1.0 / gamma)
        srgb_like = abs(gamma * 2.2 - 1.0) <= _PNG_GAMMA_THRESHOLD
        decodings = (power, srgb_curve) if srgb_like else (power,)
    name = _identify(primaries, white, tuple(np.repeat(d[None], 3, axis=0) for d in decodings))
    parts = [] if gamma is None else [f"gAMA {gamma:.5g}"]
    if chrm is not None:
        xy = [f"({x:.4f}, {y:.4f})" for x, y in c.reshape(4, 2)]
        parts.append(f"cHRM white {xy[0]}, red {xy[1]}, green {xy[2]}, blue {xy[3]}")
    else:
        parts.append("no cHRM (sRGB primaries)")
    source = "png-gama" if gamma is not None else "png-chrm"
    return DeclaredColorSpace(name, source, ", ".join(parts))


def icc_profile(space: str) -> bytes:
    """Return the ICC profile imageform embeds for an RGB ``space`` (bytes).

    ``srgb``, ``display_p3``, ``adobe_rgb``, ``prophoto``, ``rec2020``, ``rec709`` and
    ``linear_srgb`` (scRGB): Clinton Ingram's Compact ICC Profiles (CC0), version 2, listed
    with their source in ``imageform/io/data/icc/README.md``.

    Raises
    ------
    InvalidInputError
        A space without a shipped profile.
    """
    from imageform.color import space_name

    name = space_name(space, "space")
    if name not in _SHIPPED:
        raise InvalidInputError(
            f"no ICC profile is shipped for {name}; spaces with one: {', '.join(_SHIPPED)}"
        )
    return _read_shipped(_SHIPPED[name])


@cache
def _read_shipped(file: str) -> bytes:
    return (resources.files("imageform.io") / "data" / "icc" / file).read_bytes()


def declared_by_profile(data: bytes) -> DeclaredColorSpace:
    """Name what an embedded ICC profile ``data`` declares: its space and description."""
    prof = parse_icc(data)
    return DeclaredColorSpace(identify_icc(prof), "icc", prof.description)


def encoded_space(space: str, transfer: str) -> str | None:
    """Name the space of RGB ``space`` encoded with ``transfer``, when a profile holds it.

    The space's own curve gives the space; ``linear`` its ``linear_`` twin; sRGB's (or
    BT.709's) primaries with BT.709's curve are ``rec709`` (LibRaw's default output). None
    when no shipped profile describes the pair (the file is then written untagged).
    """
    from imageform.color import rgb_space

    own = rgb_space(space).transfer
    if transfer == own:
        name = space
    elif transfer == "linear":
        name = f"linear_{space}"
    elif space in ("srgb", "rec709") and transfer == "rec709":
        name = "rec709"
    else:
        return None
    return name if name in _SHIPPED else None


def embedded_profile(space: str) -> bytes | None:
    """Return the profile :func:`~imageform.io.write_image` embeds for ``space`` (sRGB: None)."""
    from imageform.color import space_name

    name = space_name(space, "color_space")
    return None if name == "srgb" else icc_profile(name)
