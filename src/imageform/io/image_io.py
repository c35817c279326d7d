"""The one image reader and writer: PNG, JPEG, TIFF, ``.npy``, PGM/PPM, PFM; more formats read.

HEIF, WebP, BMP, GIF, Netpbm (PBM, PAM too), TGA, QOI, ICO, Radiance HDR and DICOM are read,
not written.

One rule for every format:

- **Format**: a file is read as what its first bytes show (a PNG named ``.jpg`` as a PNG); the
  suffix must still be one of :data:`IMAGE_FORMATS` (a DICOM file, ``DICM`` at byte 128, under
  any suffix or none), and an AVIF or JPEG XL under such a suffix is refused naming what it
  holds. Writing follows the suffix.
- **Shape**: an image is ``(H, W, C)``, channels last; a grey image has ``C = 1`` (a 2-D
  TIFF or ``.npy`` comes back as ``(H, W, 1)``).
- **Values**: integers as stored (uint8 / uint16, full-range encoded values), floats as stored
  (float16 is widened to float32). A TIFF's signed integers (int8, int16, int32: a CT's or a
  microscope's numbers) and uint32 (a photon counter's) come as floats holding each stored
  number exactly, float32 (float64 for int32 and uint32), as a DICOM's signed samples do.
  Other sample types are refused, by :func:`image_info` as by :func:`read_image`: a TIFF's
  complex samples (SampleFormat 5 or 6; a complex number is no image: save its magnitude or
  real part) and 64-bit integers in one line saying so. A TIFF's
  samples are read as the values they mean: a palette through its colour map (RGB), a
  bilevel image as 0/255, WhiteIsZero inverted; a CMYK TIFF as sRGB through its embedded
  CMYK ICC profile (LittleCMS, 8 and 16 bits; without one refused), a Lab or raw-YCbCr TIFF
  refused; a palette BMP or GIF as RGB, a 1-bit BMP as 0/255; a CMYK JPEG as sRGB, through
  its embedded CMYK ICC profile (LittleCMS) where it has one, else ``(1 - C)(1 - K)``.
  Samples of fewer bits than their container (10, 12, 14 bits in uint16) come as stored, the
  sensor's numbers (DN), as tifffile and scikit-image read them: measurements (``emva``,
  ``characterize``) need them so;
  such an image looks dark until scaled by ``65535 / (2**bits - 1)``.
- **One image**: a TIFF holding a stack (pages, time points, z-planes; a plain multi-page
  TIFF whose pages differ in size or type too, thumbnails aside) and an animated GIF or
  WebP are refused in one line saying what they hold and how to pick one, rather than read as
  their first image; ``frame=N`` reads image ``N`` (:func:`image_frames` counts them). A TIFF
  of more than 4 samples per pixel (multispectral bands) is refused, by :func:`image_info` as
  by :func:`read_image`.
- **Alpha** (grey+alpha, RGBA, a palette with transparency in PNG, GIF or BMP, WebP's alpha;
  extra samples in TIFF):
  dropped when every pixel is opaque; otherwise refused unless ``alpha="drop"`` (ignore it)
  or ``alpha="keep"``. A ``.npy`` array has no alpha: its channels come back as stored (four
  channels may be CMYK).
- **Orientation**: the EXIF orientation of JPEG, PNG, TIFF and WebP files is applied, so the
  array is upright as viewers show it; :func:`image_info` gives that upright size.
- **Bounded memory**: the pixel count is read from the file's header and checked against a
  limit (:func:`max_pixels`, 100 Mpx by default, ``IMAGEFORM_MAX_PIXELS`` or ``max_pixels=``)
  before anything is decoded; a header that promises more bytes than the file holds is refused.
- **Errors**: a missing, truncated or corrupt file is an :class:`InvalidInputError` naming the
  file, in one line.
- **Writing** is atomic (a temporary sibling renamed at the end). PNG stores 8 or 16 bits,
  JPEG 8; floats are quantised ``round(v * (2^bits - 1))`` and values outside [0, 1] are an
  error unless ``out_of_range="clip"``. TIFF and ``.npy`` store the array as it is.

16-bit PNG is decoded and encoded with imagecodecs (libpng), JPEG with Pillow, TIFF with
tifffile. HEIF/HEIC (phones' photographs: ``.heic``, ``.heif``, ``.hif``) is read through
libheif (the ``heif`` extra, pillow-heif): 8 bits as uint8, 10 and 12 bits as uint16 scaled to
the full range as a 16-bit PNG; the container's rotation and mirroring are applied by libheif
(HEIF's own orientation, which the EXIF tag in such files only repeats). It is not written.
WebP (still, lossy or lossless), BMP (1 to 32 bits, palette, RLE, bottom-up or top-down) and a
single-frame GIF are read through Pillow, as uint8, and so are TGA and QOI; a BMP's embedded
ICC profile (BITMAPV5HEADER) is its declared colour space. Netpbm (``.pbm``, ``.pgm``,
``.ppm``, ``.pnm``, ``.pam``: P1-P7, plain or binary) is read by imageform's own reader
(:mod:`imageform.io._netpbm`): maxval 255 as uint8, 65535 as uint16, a bilevel image as 0/255,
any other maxval scaled to the full range of 8 bits (below 256) or 16, ``round(v / maxval *
(2**n - 1))``, as Pillow and imageio read it (the format's samples mean ``v / maxval``;
unlike a 12-bit TIFF's DN, a camera's PGM of maxval 4095 comes scaled: ``v * 4095 / 65535``
gives its stored numbers back).
A grey ``.pgm`` or RGB ``.ppm`` is written (binary, maxval 255 or 65535, no profile); the
others are not (write PNG). PFM (``.pfm``, :mod:`imageform.io._pfm`: Middlebury's disparities,
HDR renderings) is read and written by imageform's own code as float32, grey (``Pf``) or RGB
(``PF``), the scale's sign the byte order, rows stored bottom-up; the stored numbers are
returned (as Pillow does; OpenCV divides them by the scale's magnitude), ``inf`` included.
Radiance HDR (``.hdr``, RGBE, :mod:`imageform.io._hdr`) is read as float32 linear RGB,
Radiance's ``(m + 0.5) * 2**(E - 136)`` (OpenCV's reader leaves out the ``+ 0.5``), the
header's ``EXPOSURE`` not divided out; it is not written. ICO is read through Pillow as its
largest image.
DICOM (``.dcm``, ``.dicom``, or any file with ``DICM`` at byte 128) is read through pydicom
(the ``dicom`` extra; :mod:`imageform.io.dicom` states its rules): the stored values through
the Modality LUT (integers where the rescale is the identity, else float32), MONOCHROME1
inverted to MONOCHROME2's sense, YBR as RGB; a multi-frame file is refused as a TIFF stack is
(:func:`read_dicom` reads one frame, or windows it for display). It is not written.
"""

from __future__ import annotations

import contextlib
import math
import os
import re
import struct
import threading
import warnings
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from imageform import _deprecate
from imageform._files import (
    RAW_SUFFIXES,
    atomic_write,
    check_writable,
    final_name,
    git_lfs_pointer,
    not_a_regular_file,
)
from imageform._typing import ArrayLike
from imageform._validate import (
    as_path,
    check_memory,
    check_option,
    describe,
    format_shape,
    shorten,
)
from imageform.errors import InvalidInputError, UnreadableFileError
from imageform.io import _hdr, _netpbm, _pfm
from imageform.io._netpbm import is_netpbm

if TYPE_CHECKING:
    from collections.abc import Iterator

    from imageform.io.icc import DeclaredColorSpace

__all__ = [
    "DEFAULT_MAX_PIXELS",
    "IMAGE_FORMATS",
    "ImageFrames",
    "ImageInfo",
    "WrittenImage",
    "image_color_space",
    "image_files",
    "image_format",
    "image_frames",
    "image_info",
    "max_pixels",
    "pixel_size_um",
    "read_dicom",
    "read_image",
    "write_image",
]

#: File suffixes and their formats.
IMAGE_FORMATS = MappingProxyType(
    {
        ".png": "png",
        ".jpg": "jpeg",
        ".jpeg": "jpeg",
        ".tif": "tiff",
        ".tiff": "tiff",
        # slide scanners' TIFFs (read only): Aperio, Hamamatsu, Leica, Ventana, PerkinElmer
        # (Akoya) QPTIFF, BigTIFF's own suffixes
        ".svs": "tiff",
        ".ndpi": "tiff",
        ".scn": "tiff",
        ".bif": "tiff",
        ".qptiff": "tiff",
        ".btf": "tiff",
        ".tf8": "tiff",
        ".tf2": "tiff",
        ".npy": "npy",
        ".heic": "heif",
        ".heif": "heif",
        ".hif": "heif",
        ".webp": "webp",
        ".bmp": "bmp",
        ".gif": "gif",
        ".dcm": "dicom",
        ".dicom": "dicom",
        ".pbm": "netpbm",
        ".pgm": "netpbm",
        ".ppm": "netpbm",
        ".pnm": "netpbm",
        ".pam": "netpbm",
        ".tga": "tga",
        ".qoi": "qoi",
        ".pfm": "pfm",
        ".hdr": "hdr",
        ".ico": "ico",
    }
)

#: The formats :func:`write_image` writes (the others of IMAGE_FORMATS are read only).
_WRITTEN = ("png", "jpeg", "tiff", "npy", "netpbm", "pfm")
#: TIFF suffixes read, not written (a scanner's layout and metadata: imageform writes .tif).
_READ_ONLY_TIFF = (".svs", ".ndpi", ".scn", ".bif", ".qptiff", ".btf", ".tf8", ".tf2")
#: The Netpbm suffixes written: a binary PGM (grey) or PPM (RGB), 8 or 16 bits.
_NETPBM_WRITTEN = {".pgm": 1, ".ppm": 3}

#: Default limit on the pixels of an image read into memory (10000 x 10000); larger images
#: go through ``imageform chunked``, or raise the limit with ``IMAGEFORM_MAX_PIXELS``.
DEFAULT_MAX_PIXELS = 100_000_000

_ALPHA = ("reject", "drop", "keep")
#: The formats whose files may hold several images (``frame=`` picks one).
_FRAMED = ("tiff", "dicom", "gif", "webp")
#: The key of a TIFF's ImageDescription JSON (the one tifffile writes: ``{"shape": [...]}``)
#: under which :func:`write_image` records a colour space that has no ICC profile (``lab``,
#: ``xyz``, a ``linear_`` space ...) and :func:`image_color_space` reads it back.
_TIFF_COLOR_SPACE_KEY = "imageform_color_space"
_OUT_OF_RANGE = ("error", "clip")
_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
#: The bit depths each PNG colour type allows (PNG 3rd ed., table 11.1).
_PNG_DEPTHS = {0: (1, 2, 4, 8, 16), 2: (8, 16), 3: (1, 2, 4, 8), 4: (8, 16), 6: (8, 16)}
_pillow_lock = threading.RLock()


class ImageInfo(NamedTuple):
    """What a file's header says: size, channels, sample type and format.

    ``width``, ``height`` (upright, as :func:`read_image` returns it), ``channels``, sample
    ``dtype`` and ``format`` (png, jpeg, tiff, npy, heif, webp, bmp, gif, netpbm, tga, qoi,
    pfm, hdr, ico, dicom).
    """

    width: int
    height: int
    channels: int
    dtype: str
    format: str


class ImageFrames(NamedTuple):
    """How many images a file holds, and along which axes (:func:`image_frames`).

    ``total``: the images (1 for a file of one image); ``axes``: ``(words, length)`` for
    each axis of a TIFF stack, in the file's order (``(("time points", 7), ("z-planes",
    5))``), or ``(("frames", n),)`` for a multi-frame DICOM or an animated GIF or WebP; ``()``
    for one image. ``frame=`` of :func:`read_image` is the flat index over them, from 0.
    """

    total: int
    axes: tuple[tuple[str, int], ...]


class _WrittenImage(NamedTuple):
    bit_depth: int | None
    out_of_range: int


class WrittenImage(_WrittenImage):
    """What :func:`write_image` stored: bits per sample and the count of clipped values.

    ``bit_depth``: bits per sample for integer formats (None for float data); how many
    values were ``out_of_range`` (outside [0, 1], clipped). ``.bits`` is the deprecated
    name of ``bit_depth``.
    """

    __slots__ = ()

    bits = _deprecate.renamed_property("bit_depth", "imageform.io.WrittenImage.bits")


def max_pixels() -> int:
    """Return the pixel limit for reading: ``IMAGEFORM_MAX_PIXELS`` if set, else 100 Mpx."""
    text = os.environ.get("IMAGEFORM_MAX_PIXELS", "").strip()
    if not text:
        return DEFAULT_MAX_PIXELS
    try:
        value = int(float(text))
    except (ValueError, OverflowError):
        raise InvalidInputError(
            f"expected IMAGEFORM_MAX_PIXELS as a positive number of pixels, got {text!r}"
        ) from None
    if value <= 0:
        raise InvalidInputError(f"expected IMAGEFORM_MAX_PIXELS > 0, got {text!r}")
    return value


def image_format(path: str | Path) -> str:
    """Return the format of ``path`` from its suffix (png, jpeg, tiff, npy, heif...); else raise.

    Examples
    --------
    >>> image_format("a.JPG")
    'jpeg'
    """
    p = as_path(path, "path")
    suffix = p.suffix.lower()
    if suffix not in IMAGE_FORMATS:
        valid = ", ".join(IMAGE_FORMATS)
        written = ", ".join(
            s
            for s, f in IMAGE_FORMATS.items()
            if f in _WRITTEN
            and (f != "netpbm" or s in _NETPBM_WRITTEN)
            and s not in _READ_ONLY_TIFF
        )
        shown = shorten(p)
        raise InvalidInputError(
            f"unknown image file type {suffix[:20]!r} of {shown}; imageform reads {valid} "
            f"and writes {written}"
        )
    return IMAGE_FORMATS[suffix]


def _natural_key(name: str) -> list[Any]:
    """Sort key of a file name with its digit runs compared as numbers (``cam2`` < ``cam10``)."""
    return [(0, int(t), "") if t.isdigit() else (1, 0, t.lower()) for t in re.split(r"(\d+)", name)]


def image_files(folder: str | Path) -> list[Path]:
    """Return the image files in ``folder`` (not its subfolders), in natural order.

    An image file is one whose suffix :data:`IMAGE_FORMATS` names (any case); hidden files
    (a leading ``.``) and everything else are left out. Natural order compares runs of digits
    as numbers, so ``frame2.png`` comes before ``frame10.png`` as a camera or a video export
    numbers them (names alike but for case keep their order by case). This is how every
    command that takes a folder of images (``calibrate``, ``stereo-calibrate``,
    ``flatfield``, the frames of ``reconstruct`` and ``track``) lists it.

    Raises
    ------
    InvalidInputError
        ``folder`` is not a folder, or holds no image file (the message names the suffixes).

    Examples
    --------
    >>> import tempfile
    >>> with tempfile.TemporaryDirectory() as d:
    ...     for name in ("cam10.PNG", "cam2.jpg", "notes.txt", ".hidden.png"):
    ...         _ = (Path(d) / name).write_bytes(b"")
    ...     [p.name for p in image_files(d)]
    ['cam2.jpg', 'cam10.PNG']
    """
    path = as_path(folder, "folder")
    if not path.is_dir():
        raise InvalidInputError(f"expected a folder of images, got {shorten(path)}")
    inside = [
        q
        for q in path.iterdir()
        if q.suffix.lower() in IMAGE_FORMATS and not q.name.startswith(".") and q.is_file()
    ]
    if not inside:
        raise InvalidInputError(
            f"folder {shorten(path)} holds no images ({', '.join(sorted(set(IMAGE_FORMATS)))})"
        )
    return sorted(inside, key=lambda q: (_natural_key(q.name), q.name))


def _suffix_format(path: str | Path) -> str:
    """Return the format of ``path``'s suffix; a DICOM file (``DICM`` at byte 128) under any.

    DICOM files come from scanners and archives with no suffix (``IM000001``) or another one
    (``.IMA``); their first bytes say what they are.
    """
    try:
        return image_format(path)
    except InvalidInputError:
        if not isinstance(path, (str, os.PathLike)):
            raise
        try:
            with Path(path).open("rb") as fh:
                if _dicom_head(fh.read(132)):
                    return "dicom"
        except (OSError, ValueError):  # a missing file, a name with NUL ...
            pass
        suffix = Path(path).suffix.lower()
        if suffix in RAW_SUFFIXES:  # read by develop, not as an image
            raise InvalidInputError(
                f"{shorten(Path(path))} is a camera raw file ({suffix}), not an image: make "
                "one with imageform develop (sfr, characterize, emva and info read raw files "
                "as they are; in Python imageform.io.read_raw)"
            ) from None
        raise


# ---------------------------------------------------------------- headers


def _png_header(path: Path, data: bytes) -> ImageInfo:
    if len(data) < 33 or not data.startswith(_PNG_SIGNATURE) or data[12:16] != b"IHDR":
        raise UnreadableFileError(path, "not a PNG file")
    width, height, depth, ctype, comp, filt, lace = struct.unpack(">IIBBBBB", data[16:29])
    channels = {0: 1, 2: 3, 3: 3, 4: 2, 6: 4}.get(ctype)
    if (
        channels is None
        or width == 0
        or height == 0
        or depth not in _PNG_DEPTHS[ctype]
        or (comp, filt) != (0, 0)
        or lace not in (0, 1)
    ):  # refused here, before libpng prints its warnings about it onto stderr
        raise UnreadableFileError(path, "corrupt PNG header")
    return ImageInfo(width, height, channels, "uint16" if depth == 16 else "uint8", "png")


def _png_has_trns(fh: Any) -> bool:
    """Whether a PNG (``fh`` just past its IHDR) has a ``tRNS`` chunk before its image data.

    libpng turns ``tRNS`` into an alpha channel, so that grey, RGB and palette images with one
    come back with alpha (2 or 4 channels). Only chunk headers are read, up to ``IDAT``.
    """
    while True:
        head = fh.read(8)
        if len(head) < 8:
            return False
        length, kind = struct.unpack(">I4s", head)
        if kind == b"tRNS":
            return True
        if kind in (b"IDAT", b"IEND"):
            return False
        fh.seek(length + 4, os.SEEK_CUR)


def _npy_header(
    path: Path, limit: int | None = None
) -> tuple[ImageInfo, tuple[int, ...], np.dtype[Any]]:
    try:
        with path.open("rb") as fh:
            version = np.lib.format.read_magic(fh)
            if version == (1, 0):
                shape, _, dtype = np.lib.format.read_array_header_1_0(fh)
            else:
                shape, _, dtype = np.lib.format.read_array_header_2_0(fh)
            offset = fh.tell()
    except (ValueError, OSError, EOFError) as exc:
        raise UnreadableFileError(path, f"not a .npy file ({_one_line(exc)})") from None
    if dtype.hasobject:
        raise UnreadableFileError(path, "object arrays are not images")
    if len(shape) not in (2, 3):
        raise UnreadableFileError(
            path, f"expected an image of shape (H, W) or (H, W, C), got {shape}"
        )
    channels = shape[2] if len(shape) == 3 else 1
    if not 1 <= channels <= 4:
        raise UnreadableFileError(path, f"expected 1 to 4 channels, got {channels} (shape {shape})")
    info = ImageInfo(shape[1], shape[0], channels, str(dtype), "npy")
    if limit is not None:
        _check_pixels(path, info, limit)
    need = int(np.prod(shape, dtype=np.float64)) * dtype.itemsize
    if limit is not None:  # before reading: the header is not trusted
        check_memory(need, str(path), f"a {format_shape(tuple(shape))} {dtype} array")
    if path.stat().st_size - offset < need:
        raise UnreadableFileError(path, "the file is truncated")
    return info, shape, dtype


#: tifffile's axis letters, in words (tifffile's ``TIFF.AXES_NAMES``).
_AXES_WORDS = {"T": "time points", "Z": "z-planes", "C": "channels", "Q": "pages",
               "I": "pages", "P": "positions", "R": "tiles", "E": "wavelengths", "H": "lifetimes",
               "A": "angles", "L": "exposures", "V": "phases", "S": "samples"}  # fmt: skip


def _stack_axes(axes: str, shape: tuple[int, ...]) -> tuple[tuple[str, int], ...]:
    """Return the axes of a TIFF series other than the image plane (Y, X, samples), in words."""
    return tuple((_AXES_WORDS.get(a, f"{a} axis"), int(n))
                 for a, n in zip(axes, shape, strict=True) if a not in "YXS")  # fmt: skip


def _tiff_stack(axes: str, shape: tuple[int, ...]) -> str:
    """Say in words what a TIFF of more than one image holds, and how to read one.

    ``axes`` ``"TZYX"`` of shape ``(7, 5, 167, 439)``: "a stack of 35 images of 439 x 167 px
    (7 time points x 5 z-planes); read one with frame=N ...".
    """
    if "Y" not in axes or "X" not in axes:
        return f"a TIFF of shape {shape} with no image plane in it (axes {axes})"
    w, h = shape[axes.index("X")], shape[axes.index("Y")]
    stack = _stack_axes(axes, shape)
    count = math.prod(n for _, n in stack)
    parts = " x ".join(f"{n} {what}" for what, n in stack)
    return (
        f"a stack of {count} images of {w} x {h} px ({parts}); read one with frame=N, "
        f"0 to {count - 1} (imageform's commands: --frame N)"
    )


def _check_frame(path: Path, frame: object, count: int) -> int:
    """Return ``frame`` as an index into the ``count`` images of ``path``, else one line."""
    if isinstance(frame, bool) or not isinstance(frame, (int, np.integer)):
        raise InvalidInputError(f"expected frame as an int >= 0, got {frame!r}")
    if not 0 <= int(frame) < count:
        held = "one image (frame 0)" if count == 1 else f"{count} images (frames 0 to {count - 1})"
        raise InvalidInputError(f"frame {int(frame)} is out of range: {path} holds {held}")
    return int(frame)


#: tifffile's series kinds of a plain multi-page TIFF: pages as written (``generic``) or
#: with tifffile's own shape metadata (``shaped``: one series per ``imwrite`` call).
_PLAIN_SERIES = ("generic", "shaped")


def _tiff_images(tif: Any) -> list[Any]:
    """Return the series of a TIFF that are images of their own, the first first.

    A plain multi-page TIFF (tifffile's generic or shaped series: a fax, a scan of several
    sheets, a page per size) whose pages differ in size or sample type is several series; each is an
    image (or a stack of them) as a stack's pages are. Reduced-resolution pages (thumbnails,
    NewSubfileType 1) and transparency masks (4) are not. A slide scanner's, OME or ImageJ
    TIFF is its first series (its other series are a label, a macro photograph, a thumbnail).
    """
    first = tif.series[0]
    if first.kind not in _PLAIN_SERIES:
        return [first]
    return [first] + [
        s for s in tif.series[1:]
        if s.kind in _PLAIN_SERIES and not int(getattr(s.keyframe, "subfiletype", 0) or 0) & 5
    ]  # fmt: skip


def _series_count(series: Any) -> int:
    """Count the images one TIFF series holds (its axes but Y, X, samples; 1 if none)."""
    return math.prod(n for _, n in _stack_axes(series.axes, series.shape))


def _tiff_pick(tif: Any, path: Path, frame: int | None) -> tuple[Any, int | None]:
    """Return the series holding image ``frame`` of a TIFF and the frame within that series.

    A TIFF of several images of their own (:func:`_tiff_images`) without ``frame`` is
    refused in one line naming their sizes; ``frame`` counts over them in the file's order.
    """
    images = _tiff_images(tif)
    if len(images) == 1:
        return images[0], frame
    counts = [_series_count(s) for s in images]
    total = sum(counts)
    if frame is None:
        sizes = "; ".join(
            (f"{n} x " if n > 1 else "")
            + f"{s.shape[s.axes.index('X')]} x {s.shape[s.axes.index('Y')]} px, "
            + f"{s.shape[s.axes.index('S')] if 'S' in s.axes else 1} channel(s), "
            + ("bilevel" if s.dtype == np.bool_ else str(s.dtype))
            for s, n in zip(images[:6], counts, strict=False)
            if "X" in s.axes and "Y" in s.axes
        ) + ("; ..." if len(images) > 6 else "")
        raise UnreadableFileError(
            path,
            f"a multi-page TIFF of {total} images of different sizes or types ({sizes}); read "
            f"one with frame=N, 0 to {total - 1} (imageform's commands: --frame N)",
        )
    index = _check_frame(path, frame, total)
    for s, n in zip(images, counts, strict=True):
        if index < n:
            return s, (index if n > 1 else None)
        index -= n
    raise AssertionError("unreachable: frame checked against the total")


def _tiff_series(
    tif: Any, path: Path, frame: int | None = None
) -> tuple[Any, ImageInfo, int | None]:
    """Return the series of a TIFF holding its image, what one image of it is, the inner frame.

    ``frame`` picks one of several images (a stack's, or a multi-page file's); the frame
    returned is the index within the series picked (None where it holds one image).
    """
    if not tif.series:
        raise UnreadableFileError(path, "the TIFF holds no image")
    series, frame = _tiff_pick(tif, path, frame)
    axes = series.axes
    shape = series.shape
    if "Y" not in axes or "X" not in axes:
        raise UnreadableFileError(path, _tiff_stack(axes, shape))
    stack = _stack_axes(axes, shape)
    if stack and frame is None:
        # pages, time points, z-planes or channels of their own (axes QYX, CYX...): a stack
        raise UnreadableFileError(path, _tiff_stack(axes, shape))
    if frame is not None:
        _check_frame(path, frame, math.prod(n for _, n in stack))
    channels = shape[axes.index("S")] if "S" in axes else 1
    page = _frame_page(tif, series, frame)
    _refuse_tiff_samples(path, series.dtype, page)
    if channels in (4, 5) and _tiff_cmyk_profile(page) is not None:  # read as sRGB (+ alpha)
        channels -= 1
    if channels > 4:  # refused here, so that image_info says what read_image does
        raise UnreadableFileError(
            path,
            f"a TIFF of {channels} samples per pixel (a multispectral "
            "image, or extra channels); imageform reads images of 1 to 4 channels (grey or "
            "RGB, with alpha): save the channels you need as their own TIFF (tifffile.imread, "
            "then imwrite of those channels)",
        )
    width, height = shape[axes.index("X")], shape[axes.index("Y")]
    dtype = "uint8" if series.dtype == np.bool_ else str(series.dtype)  # bilevel: 0/255
    if _read_as_numbers(series.dtype):  # int8/16/32, uint32: floats, each number as stored
        dtype = str(_numbers_as_float(series.dtype))
    elif series.dtype == np.float16:  # widened, as read_image returns it
        dtype = "float32"
    if int(page.photometric) == 3 and page.colormap is not None:  # palette: RGB, as read
        cmap = np.asarray(page.colormap)
        eight = int(cmap.max(initial=0)) < 256 or not np.any(cmap % 257)
        channels, dtype = 3, "uint8" if eight else "uint16"
    info = ImageInfo(width, height, channels, dtype, "tiff")
    return series, info, frame


def image_frames(path: str | Path) -> ImageFrames:
    """Count the images a file holds: a TIFF stack's, a DICOM's frames, a GIF's or WebP's.

    A TIFF's first series (what :func:`read_image` reads) is a stack when it has axes other
    than the image plane: pages, z-planes, time points, channels of their own (tifffile's
    series axes, from ImageJ or OME metadata or the pages); its images are counted without
    decoding any. Other files hold one image.

    Raises
    ------
    InvalidInputError
        The file is missing or not an image of a known format.

    Examples
    --------
    >>> import tifffile
    >>> p = getfixture("tmp_path") / "zt.ome.tif"
    >>> tifffile.imwrite(p, np.zeros((3, 2, 4, 5), np.uint16), metadata={"axes": "TZYX"})
    >>> image_frames(p)
    ImageFrames(total=6, axes=(('time points', 3), ('z-planes', 2)))
    >>> read_image(p, frame=5).shape
    (4, 5, 1)
    """
    fmt = _suffix_format(path) if isinstance(path, (str, os.PathLike)) else ""
    p = _existing(path)
    fmt = _content_format(p, fmt)
    axes: tuple[tuple[str, int], ...] = ()
    if fmt == "tiff":
        try:
            with _tifffile().TiffFile(p) as tif:
                images = _tiff_images(tif) if tif.series else []
                if len(images) > 1:  # pages of different sizes or types
                    axes = (("pages", sum(_series_count(s) for s in images)),)
                elif images:
                    axes = _stack_axes(images[0].axes, images[0].shape)
        except Exception as exc:
            raise UnreadableFileError(p, f"{_one_line(exc)}") from None
    elif fmt == "dicom":
        from imageform.io import dicom

        head = dicom.open_dicom(p, pixels=False)
        n = dicom.header(p, head).frames
        axes = (("frames", n),) if n > 1 and dicom.slide_tiles(p, head) is None else ()
    elif fmt in ("gif", "webp"):
        try:
            with _pillow_open(p) as im:
                if getattr(im, "is_animated", False):
                    axes = (("frames", int(im.n_frames)),)
        except (OSError, SyntaxError, ValueError) as exc:
            raise UnreadableFileError(p, f"{_one_line(exc)}") from None
    else:
        image_info(p)  # a file of one image: readable?
    return ImageFrames(math.prod(n for _, n in axes), axes)


def pixel_size_um(path: str | Path) -> tuple[float, float] | None:
    r"""Return the pixel size in micrometres (x, y) a microscopy or X-ray file states, or None.

    As OpenSlide reads it (its ``openslide.mpp-x`` / ``mpp-y``), of the full-resolution
    level:

    - OME-XML ``PhysicalSizeX`` / ``PhysicalSizeY`` (Bio-Formats, QuPath's exports), in
      their unit (µm by default; nm, mm, cm, m);
    - an Aperio SVS header's ``MPP = ...``;
    - a Philips TIFF's ``DICOM_PIXEL_SPACING`` (mm, rows then columns: the first of its
      pixel data representation sequence, the full resolution);
    - a Ventana BIF's ``ScanRes`` in its XMP ``iScan`` element (µm);
    - an ImageJ TIFF's resolution with ``unit=micron`` (µm, um, nm, mm, cm, m; not inch)
      in its description;
    - else the TIFF resolution tags in pixels per centimetre (Hamamatsu NDPI, QPTIFF,
      libvips, tifffile and imageform's own pyramids; an X-ray detector's or a macro
      camera's 50-400 µm) when they give under 1000 µm and are not a screen's 72 or 96 dpi
      converted (352.8 and 264.6 µm: photo software writes those to any file; libvips writes
      1000 µm to a file of unknown resolution); in inches they are never read (every
      photograph states 72 or 300 dpi);
    - a DICOM slide-microscopy image's Pixel Spacing (mm, modality SM).

    Other formats: None.

    Raises
    ------
    InvalidInputError
        The file is missing.

    Examples
    --------
    >>> import tifffile
    >>> p = getfixture("tmp_path") / "s.ome.tif"
    >>> tifffile.imwrite(p, np.zeros((4, 4, 3), np.uint8), metadata={"PhysicalSizeX": 0.25,
    ...     "PhysicalSizeY": 0.25, "PhysicalSizeXUnit": "µm", "PhysicalSizeYUnit": "µm"})
    >>> pixel_size_um(p)
    (0.25, 0.25)
    """
    p = _existing(path)
    fmt = _content_format(p, "")
    if fmt == "dicom":
        return _dicom_pixel_size(p)
    if fmt != "tiff":
        return None
    tifffile = _tifffile()
    try:
        with tifffile.TiffFile(p) as tif:
            page = tif.pages[0]
            desc = page.description or ""
            xmp = page.tags.get(700)
            xmp_text = _tag_text(xmp.value) if xmp is not None else ""
            res = _resolution(page)
    except Exception:
        return None
    um = _stated_microns(desc, xmp_text, res)
    if um is None or not all(math.isfinite(v) and v > 0 for v in um):  # 0: not stated
        return None
    return um


def _tag_text(value: Any) -> str:
    """Return a tag's value as text (XMP is bytes)."""
    if isinstance(value, (bytes, bytearray)):
        return bytes(value).decode("utf-8", "replace")
    return str(value)


def _resolution(page: Any) -> tuple[float, float, int] | None:
    """Return a TIFF page's resolution (pixels per unit, x and y) and unit, or None."""
    tags = page.tags
    if "XResolution" not in tags or "YResolution" not in tags:
        return None
    xr, yr = tags["XResolution"].value, tags["YResolution"].value
    if not (xr[0] and xr[1] and yr[0] and yr[1]):
        return None
    unit = int(tags["ResolutionUnit"].value) if "ResolutionUnit" in tags else 2
    return xr[0] / xr[1], yr[0] / yr[1], unit


#: The largest pixel (µm, exclusive) a TIFF's resolution tags in centimetres are read as: a
#: microscope's 0.1-50 µm, a macro photograph's or an X-ray detector's 50-200 µm, a binned
#: fluoroscopy panel's 300-400 µm. libvips writes 10 px/cm (1 px/mm, 1000 µm) to a file of
#: unknown resolution, and other writers 1 px/cm: neither is a pixel size.
_MAX_TAG_MICRONS = 1000.0
#: Screen resolutions photo and office software write to any file (72 and 96 dpi), in the
#: pixels per centimetre some of them store (352.8 and 264.6 µm): not a pixel size.
_SCREEN_DPI = (72.0, 96.0)
#: Micrometres per unit of OME's PhysicalSize units and ImageJ's ``unit=`` (its spellings).
_MICRONS_PER_UNIT = {"nm": 1e-3, "µm": 1.0, "um": 1.0, "\u03bcm": 1.0, "micron": 1.0,
                     "microns": 1.0, "mm": 1e3, "cm": 1e4, "m": 1e6}  # fmt: skip
#: TIFF ResolutionUnit (3 cm; 4 mm and 5 µm, tifffile's extensions) in µm.
_RESOLUTION_UNIT_MICRONS = {3: 1e4, 4: 1e3, 5: 1.0}


def _tag_microns(res: tuple[float, float, int]) -> tuple[float, float] | None:
    """Return the pixel size (µm) of TIFF resolution tags in a metric unit, else None.

    Inches are never read (every photograph states 72 or 300 dpi); centimetres are read
    below :data:`_MAX_TAG_MICRONS`, unless they are a screen's 72 or 96 dpi converted.
    """
    per = _RESOLUTION_UNIT_MICRONS.get(res[2])
    if per is None:
        return None
    x, y = per / res[0], per / res[1]
    if not (0.0 < x < _MAX_TAG_MICRONS and 0.0 < y < _MAX_TAG_MICRONS):
        return None
    screen = (25400.0 / dpi for dpi in _SCREEN_DPI)
    if any(abs(x - s) < 1e-3 * s and abs(y - s) < 1e-3 * s for s in screen):
        return None
    return x, y


def _stated_microns(
    desc: str, xmp: str, res: tuple[float, float, int] | None
) -> tuple[float, float] | None:
    """Return the pixel size (x, y) in µm a TIFF's description, XMP or resolution tags state."""
    import re

    number = r"([0-9]*\.?[0-9]+(?:[eE][+-]?[0-9]+)?)"
    if "Aperio" in desc[:200]:
        m = re.search(r"\bMPP\s*=\s*" + number, desc)
        return (float(m.group(1)),) * 2 if m else None
    xs = re.search(r'PhysicalSizeX="' + number + '"', desc)
    if xs:
        ys = re.search(r'PhysicalSizeY="' + number + '"', desc)
        ux = re.search(r'PhysicalSizeXUnit="([^"]*)"', desc)
        uy = re.search(r'PhysicalSizeYUnit="([^"]*)"', desc)
        kx = _MICRONS_PER_UNIT.get(ux.group(1) if ux else "µm")  # OME's default: µm
        ky = _MICRONS_PER_UNIT.get(uy.group(1) if uy else "µm")
        if kx is None or ky is None:
            return None
        x = float(xs.group(1)) * kx
        return x, float(ys.group(1)) * ky if ys else x
    if "DPUfsImport" in desc[:2000]:  # Philips: DICOM_PIXEL_SPACING "row" "column" in mm
        q = r'\s*(?:&quot;|")'
        found = list(
            re.finditer(r'Name="DICOM_PIXEL_SPACING"[^>]*>' + q + number + q + q + number, desc)
        )
        seq = desc.find("PIIM_PIXEL_DATA_REPRESENTATION_SEQUENCE")
        inside = [m for m in found if seq >= 0 and m.start() > seq]  # the full resolution's
        if not found:
            return None
        first = (inside or found)[0]
        return float(first.group(2)) * 1000.0, float(first.group(1)) * 1000.0
    if "<iScan" in xmp:  # Ventana BIF
        m = re.search(r'ScanRes="' + number + '"', xmp)
        return (float(m.group(1)),) * 2 if m else None
    if desc.startswith("ImageJ=") and res is not None:
        m = re.search(r"^unit=(.*)$", desc, re.MULTILINE)
        unit = m.group(1).strip().replace("\\u00B5", "µ") if m else ""
        k = _MICRONS_PER_UNIT.get(unit)  # not inch, pixel
        return (k / res[0], k / res[1]) if k is not None else None
    if res is not None:
        return _tag_microns(res)
    return None


def _dicom_pixel_size(p: Path) -> tuple[float, float] | None:
    """Return a DICOM slide-microscopy image's pixel size in µm (x, y), or None."""
    from imageform.io.dicom import dicom_info

    try:
        d = dicom_info(p)
    except Exception:
        return None
    if d.modality != "SM" or d.pixel_spacing_mm is None:
        return None
    rows, cols = d.pixel_spacing_mm  # between rows (y), between columns (x)
    return float(cols) * 1000.0, float(rows) * 1000.0


def image_info(path: str | Path, *, frame: int | None = None) -> ImageInfo:
    """Width, height, channels and sample type from the file's header, without decoding.

    Width and height are those of the image :func:`read_image` returns: an EXIF orientation
    of 5 to 8 (a photograph taken upright, stored on its side) swaps the stored ones.

    Parameters
    ----------
    path : str or Path
        An image file of :data:`IMAGE_FORMATS`.
    frame : int, optional
        The image of a file holding several (a TIFF stack, a multi-frame DICOM, an animated
        GIF or WebP; :func:`image_frames` counts them), from 0, as :func:`read_image` takes it.

    Raises
    ------
    InvalidInputError
        The file is missing or not an image of a known format; a file of several images
        without ``frame``; a ``frame`` out of range.
    """
    fmt = _suffix_format(path) if isinstance(path, (str, os.PathLike)) else ""
    p = _existing(path)
    fmt = _content_format(p, fmt)
    if frame is not None and fmt not in _FRAMED:
        _check_frame(p, frame, 1)
    if fmt == "png":
        with p.open("rb") as fh:
            head = _png_header(p, fh.read(33))
            if head.channels in (1, 3) and _png_has_trns(fh):  # read as alpha
                head = head._replace(channels=head.channels + 1)
            fh.seek(33)
            return _upright(head, _png_file_orientation(fh))
    if fmt == "npy":
        return _npy_header(p)[0]
    if fmt == "tiff":
        tifffile = _tifffile()
        try:
            with tifffile.TiffFile(p) as tif:
                series, head, inner = _tiff_series(tif, p, frame)
                tag = _frame_page(tif, series, inner).tags.get(274)
                return _upright(head, int(tag.value) if tag is not None else 1)
        except InvalidInputError:
            raise
        except Exception as exc:
            raise UnreadableFileError(p, f"{_one_line(exc)}") from None
    if fmt == "netpbm":
        with p.open("rb") as fh:
            nh = _netpbm.header(fh.read(1 << 16), p)
        return ImageInfo(nh.width, nh.height, nh.channels, nh.dtype, "netpbm")
    if fmt == "pfm":
        with p.open("rb") as fh:
            ph = _pfm.header(fh.read(256), p)
        _pfm.check_size(ph, p.stat().st_size, p)  # uncompressed: its size is known
        return ImageInfo(ph.width, ph.height, ph.channels, "float32", "pfm")
    if fmt == "hdr":
        data = p.read_bytes()
        hh = _hdr.header(data[: 1 << 16], p)
        _hdr.check_size(hh, data, p)  # its scanlines stepped over, not decoded
        return ImageInfo(hh.width, hh.height, 3, "float32", "hdr")
    if fmt == "heif":
        return _heif_info(_open_heif(p))  # libheif's size: its rotation applied
    if fmt == "dicom":
        from imageform.io import dicom

        head = dicom.open_dicom(p, pixels=False)
        d = dicom.header(p, head)
        tiles = dicom.slide_tiles(p, head)
        if tiles is not None:  # a whole-slide image: its frames are tiles of one image
            d = dicom.slide_info(d, tiles)
        if frame is not None:
            _check_frame(p, frame, d.frames)
        elif d.frames > 1:  # refused, as read_image refuses it
            raise dicom.multi_frame(p, d)
        return ImageInfo(d.width, d.height, d.channels, d.dtype, "dicom")
    try:
        with _pillow_open(p) as im:
            _pillow_frame(p, im, fmt, frame)
            w, h = im.size
            head = ImageInfo(w, h, _pillow_channels(im, fmt), "uint8", fmt or "jpeg")
            return _upright(head, _pillow_orientation(im))
    except InvalidInputError:
        raise
    except (OSError, SyntaxError, ValueError) as exc:  # UnidentifiedImageError is an OSError
        raise UnreadableFileError(p, f"{_one_line(exc)}") from None


def _upright(info: ImageInfo, orientation: int) -> ImageInfo:
    """``info`` with the width and height of the upright image (EXIF orientation 5-8 turn it)."""
    if orientation in (5, 6, 7, 8):
        return info._replace(width=info.height, height=info.width)
    return info


def _png_file_orientation(fh: Any) -> int:
    """Return the EXIF orientation of a PNG's ``eXIf`` chunk (``fh`` past IHDR), else 1.

    Only chunk headers are read, up to ``eXIf`` or ``IEND``.
    """
    while True:
        head = fh.read(8)
        if len(head) < 8:
            return 1
        length, kind = struct.unpack(">I4s", head)
        if kind == b"eXIf":
            return _png_orientation(_PNG_SIGNATURE + head + fh.read(length))
        if kind == b"IEND":
            return 1
        fh.seek(length + 4, os.SEEK_CUR)


# ---------------------------------------------------------------- Pillow: JPEG, WebP, BMP, GIF


@contextlib.contextmanager
def _pillow_open(p: Path) -> Iterator[Any]:
    """Open ``p`` with Pillow (its header only) with Pillow's own pixel cap off.

    imageform's limit (:func:`max_pixels`) is checked instead, before decoding; Pillow's
    (``Image.MAX_IMAGE_PIXELS``) would refuse at open a 180 Mpx image that ``max_pixels=``
    allows and warn on stderr from 90 Mpx. That cap and the warnings filter are process-wide
    settings, hence the lock; it is held only while Pillow reads the header and counts the
    frames (``is_animated``, ``n_frames``: GIF frames are checked against the cap as they are
    seeked), the steps that consult them. The decoding (``load``, ``convert``) runs after,
    outside it, so that images decoded in threads of one process decode at the same time.
    """
    from PIL import Image

    with _pillow_lock, warnings.catch_warnings():
        warnings.simplefilter("ignore", Image.DecompressionBombWarning)
        saved, Image.MAX_IMAGE_PIXELS = Image.MAX_IMAGE_PIXELS, None
        try:
            im = Image.open(p)
            try:
                if getattr(im, "is_animated", False):  # seeks frames; both are cached
                    _ = im.n_frames  # type: ignore[attr-defined]
            except BaseException:
                im.close()
                raise
        finally:
            Image.MAX_IMAGE_PIXELS = saved
    with im:
        yield im


def _pillow_frame(p: Path, im: Any, fmt: str, frame: int | None) -> None:
    """Seek an animated GIF or WebP to ``frame``; refuse one without it, as a stack TIFF is.

    Pillow composes each frame of a GIF over the ones before it (its disposal methods), so a
    frame comes as the viewer shows it at that point, not as its own patch.
    """
    count = int(getattr(im, "n_frames", 1)) if getattr(im, "is_animated", False) else 1
    if frame is None:
        if count == 1:
            return
        name = {"gif": "GIF", "webp": "WebP"}.get(fmt, fmt.upper())
        raise UnreadableFileError(
            p,
            f"an animated {name} of {count} frames; read one with frame=N, 0 to {count - 1} "
            "(imageform's commands: --frame N)",
        )
    if _check_frame(p, frame, count):
        im.seek(int(frame))


def _refuse_short_raw(p: Path, im: Any) -> None:
    """Refuse an uncompressed image (a BMP) whose rows the file does not hold, before decoding.

    Pillow's tile of raw rows gives their offset and stride: a header promising more bytes
    than the file has is refused before the image's memory is allocated.
    """
    tiles = getattr(im, "tile", None) or []
    if len(tiles) != 1 or tiles[0][0] != "raw":
        return
    _, extents, offset, args = tiles[0]
    stride = args[1] if isinstance(args, tuple) and len(args) > 1 else 0
    if not isinstance(stride, int) or stride <= 0:
        return
    need = int(offset) + stride * (int(extents[3]) - int(extents[1]))
    have = p.stat().st_size
    if have < need:
        raise UnreadableFileError(
            p, f"the file is truncated ({have} bytes, its header promises {need})"
        )


def _pillow_orientation(im: Any) -> int:
    """Return the EXIF orientation in a JPEG's APP1 or a WebP's EXIF chunk, else 1."""
    try:
        value = int(im.getexif().get(0x0112, 1) or 1)
    except (OSError, SyntaxError, ValueError, TypeError):
        return 1
    return value if 1 <= value <= 8 else 1


def _exif_color_space(im: Any) -> tuple[Any, Any]:
    """Return EXIF's ColorSpace (0xA001) and interoperability index.

    (None, None) where the EXIF block cannot be parsed (a PNG's eXIf chunk of junk: the
    pixels are still readable, and the orientation reader ignores such a block too).
    """
    try:
        exif = im.getexif()
        return exif.get_ifd(0x8769).get(0xA001), exif.get_ifd(0xA005).get(0x0001)
    except (OSError, SyntaxError, ValueError, TypeError, KeyError, struct.error):
        return None, None


def _transparent(im: Any, fmt: str) -> bool:
    """Whether a Pillow image has a transparent colour or index (GIF, palette BMP)."""
    return fmt != "jpeg" and im.info.get("transparency") is not None


def _pillow_channels(im: Any, fmt: str) -> int:
    """Return the channels :func:`_read_pillow` gives for ``im`` (before the alpha rule)."""
    mode = im.mode
    if mode in ("P", "PA"):
        return 4 if mode == "PA" or _transparent(im, fmt) else 3
    if mode in ("CMYK", "YCbCr"):
        return 3
    if mode in ("1", "L", "RGB") and _transparent(im, fmt):
        return 2 if mode in ("1", "L") else 4
    return 1 if mode.startswith("I;16") else len(im.getbands())


# ---------------------------------------------------------------- reading


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__


def _existing(path: str | Path) -> Path:
    if not isinstance(path, (str, os.PathLike)):
        raise InvalidInputError(f"expected a file path, got {type(path).__name__}")
    p = Path(path)
    if not p.exists():
        raise InvalidInputError(f"input file {p} does not exist")
    if not p.is_file():
        raise InvalidInputError(f"input {p} {not_a_regular_file(p) or 'is not a regular file'}")
    if p.stat().st_size == 0:  # before any decoder says "cannot identify" or "not a PNG file"
        raise UnreadableFileError(p, "an empty file (0 bytes)")
    if (lfs := git_lfs_pointer(p)) is not None:
        raise UnreadableFileError(p, lfs)
    return p


#: ISO base-media brands of HEIF still images (ISO/IEC 23008-12) that libheif decodes.
_HEIF_BRANDS = (b"heic", b"heix", b"heim", b"heis", b"hevc", b"hevx", b"mif1", b"msf1")


def _content_format(p: Path, fmt: str) -> str:
    """Return the format ``p``'s first bytes show, else ``fmt`` (the suffix's).

    The bytes decide which decoder reads a file: a PNG named ``.jpg`` (common among
    downloaded images) is read as the PNG it is (16 bits, alpha, eXIf orientation), not
    through Pillow as if it were a JPEG. A format imageform does not read (AVIF, JPEG XL)
    under a readable suffix is refused naming what it is.
    """
    try:
        with p.open("rb") as fh:
            first = fh.read(132)  # DICOM's "DICM" is at byte 128
    except OSError:
        return fmt  # the format's own reader says why
    found = None
    if fmt == "dicom" and _dicom_head(first):  # a DICOM-TIFF's preamble is a TIFF header
        return fmt
    head = first[:32]
    if head.startswith(_PNG_SIGNATURE):
        found = "png"
    elif head.startswith(b"\xff\xd8\xff"):
        found = "jpeg"
    elif head[:4] in (b"II*\0", b"MM\0*", b"II+\0", b"MM\0+"):
        found = "tiff"
    elif head.startswith(b"\x93NUMPY"):
        found = "npy"
    elif head[4:8] == b"ftyp":
        brands = [head[i : i + 4] for i in range(8, len(head) - 3, 4) if i != 12]
        if any(b in (b"avif", b"avis") for b in brands):  # AVIF lists mif1 too
            found = "AVIF"
        elif any(b in _HEIF_BRANDS for b in brands):
            found = "heif"
    elif head.startswith((b"GIF87a", b"GIF89a")):
        found = "gif"
    elif head[:4] == b"RIFF" and head[8:12] == b"WEBP":
        found = "webp"
    elif head.startswith(b"BM") and len(head) >= 18 and head[14] in (12, 40, 52, 56, 108, 124):
        found = "bmp"  # its DIB header's size, so that text starting "BM" is not one
    elif is_netpbm(head):
        found = "netpbm"
    elif _pfm.is_pfm(head):
        found = "pfm"
    elif _hdr.is_hdr(head):
        found = "hdr"
    elif head[:4] == b"\0\0\1\0" and fmt == "ico":  # ICONDIR, type 1 (no magic of its own)
        found = "ico"
    elif head.startswith(b"qoif"):
        found = "qoi"
    elif head.startswith((b"\xff\x0a", b"\0\0\0\x0cJXL ")):
        found = "JPEG XL"
    elif _dicom_head(first):
        found = "dicom"
    if found is None or found == fmt:
        return fmt
    if found not in IMAGE_FORMATS.values():
        raise UnreadableFileError(
            p,
            f"it holds {'an' if found[0] in 'AEIOU' else 'a'} {found} image, "
            f"not {fmt.upper()}; imageform reads "
            "PNG, JPEG, TIFF, WebP, BMP, GIF, Netpbm, PFM, Radiance HDR, TGA, QOI, ICO, .npy, "
            "HEIF and DICOM (convert it to one of them)",
        )
    return found


def _dicom_head(head: bytes) -> bool:
    """Whether a file's first 132 bytes are a DICOM file's: ``DICM`` at byte 128 (PS3.10 7.1)."""
    return len(head) >= 132 and head[128:132] == b"DICM"


def is_dicom_file(path: str | Path) -> bool:
    """Whether ``path`` is a regular file with ``DICM`` at byte 128 (any suffix).

    Not a regular file (a folder, a FIFO: never opened) or unreadable: False.
    """
    p = Path(path)
    try:
        if not p.is_file():
            return False
        with p.open("rb") as fh:
            return _dicom_head(fh.read(132))
    except OSError:
        return False


def _pixels(n: int) -> str:
    """Format a pixel count: ``"768 px"`` below 0.1 Mpx, else 3 digits (``"0.123 Mpx"``)."""
    if n < 100_000:
        return f"{n} px"
    mpx = float(f"{n / 1e6:.3g}")  # 3 significant digits, then as many decimals as they need
    decimals = max(0, 2 - math.floor(math.log10(mpx)))
    return f"{mpx:.{decimals}f} Mpx"


#: What :func:`_check_pixels` suggests for an image above the pixel limit.
_RAISE_LIMIT = (
    "raise it with --max-pixels or IMAGEFORM_MAX_PIXELS, or process it block by block with "
    "imageform chunked"
)


def _check_pixels(
    path: Path | str, info: ImageInfo, limit: int, remedy: str = _RAISE_LIMIT
) -> None:
    """Refuse an image (or a video's frames) of more than ``limit`` pixels, in one line."""
    n = info.width * info.height
    if n > limit:
        size, cap = _pixels(n), _pixels(limit)
        if size == cap:  # 3 digits do not tell them apart
            size, cap = f"{n} px", f"{limit} px"
        raise InvalidInputError(
            f"{path} is {info.width} x {info.height} = {size}, above the limit of {cap} ({remedy})"
        )


def _orient(a: np.ndarray, orientation: int) -> np.ndarray:
    """Apply EXIF orientation 1-8 to an (H, W, ...) array (the viewer's upright image)."""
    if orientation == 2:
        return a[:, ::-1]
    if orientation == 3:
        return a[::-1, ::-1]
    if orientation == 4:
        return a[::-1]
    if orientation == 5:
        return np.swapaxes(a, 0, 1)
    if orientation == 6:
        return np.swapaxes(a, 0, 1)[:, ::-1]
    if orientation == 7:
        return np.swapaxes(a, 0, 1)[::-1, ::-1]
    if orientation == 8:
        return np.swapaxes(a, 0, 1)[::-1]
    return a


def _png_orientation(data: bytes) -> int:
    """Return the EXIF orientation stored in a PNG's eXIf chunk (1 when there is none)."""
    pos = len(_PNG_SIGNATURE)
    while pos + 8 <= len(data):
        length, kind = struct.unpack(">I4s", data[pos : pos + 8])
        if kind == b"eXIf":
            from PIL import Image

            exif = Image.Exif()
            try:
                exif.load(data[pos + 8 : pos + 8 + length])
            except Exception:
                return 1
            return int(exif.get(0x0112, 1) or 1)
        if kind == b"IEND":
            break
        pos += 12 + length
    return 1


def _read_png(p: Path, limit: int) -> np.ndarray:
    import imagecodecs

    data = p.read_bytes()
    info = _png_header(p, data)
    _check_pixels(p, info, limit)
    try:
        # Adam7-interlaced (IHDR's last byte): libpng warns of imagecodecs' call; an eXIf
        # chunk libpng finds invalid: it says so on stderr (the pixels are fine)
        quiet = data[28] == 1 or _png_has_chunk(data, b"eXIf") or _png_out_of_order(data)
        decode = _png_decode_interlaced if quiet else imagecodecs.png_decode
        arr = decode(data)
    except Exception as exc:
        raise UnreadableFileError(p, f"{_one_line(exc)}") from None
    return _orient(np.asarray(arr), _png_orientation(data))


_stderr_lock = threading.Lock()


#: Chunks PNG places before PLTE (colour space, significant bits: PNG 3rd ed. table 7), and
#: those it places after it (transparency, background, histogram).
_PNG_BEFORE_PLTE = (b"cHRM", b"gAMA", b"iCCP", b"sBIT", b"sRGB", b"cICP")
_PNG_AFTER_PLTE = (b"tRNS", b"bKGD", b"hIST")


def _png_out_of_order(data: bytes) -> bool:
    """Whether a PNG's chunks before its image data break PNG's order around PLTE.

    libpng then says "PLTE: out of place" (libavif's ``circle-trns-before-plte.png``: tRNS
    before PLTE) or "gAMA: out of place" on stderr, a second line beside a command's one,
    and decodes the pixels as they are: such a file is decoded with its notes as warnings.
    """
    pos, seen = len(_PNG_SIGNATURE), []
    while pos + 8 <= len(data):
        length, kind = struct.unpack(">I4s", data[pos : pos + 8])
        if kind in (b"IDAT", b"IEND"):
            break
        seen.append(kind)
        pos += 12 + length
    if b"PLTE" not in seen:
        return False
    at = seen.index(b"PLTE")
    return any(k in _PNG_AFTER_PLTE for k in seen[:at]) or any(
        k in _PNG_BEFORE_PLTE for k in seen[at + 1 :]
    )


def _png_has_chunk(data: bytes, kind: bytes) -> bool:
    """Whether a PNG holds a chunk of type ``kind`` before its image data."""
    pos = len(_PNG_SIGNATURE)
    while pos + 8 <= len(data):
        length, got = struct.unpack(">I4s", data[pos : pos + 8])
        if got == kind:
            return True
        if got in (b"IDAT", b"IEND"):
            return False
        pos += 12 + length
    return False


def _png_cicp(p: Path) -> tuple[int, int, int, int] | None:
    """Return a PNG's ``cICP`` chunk (H.273 primaries, transfer, matrix, full range) or None.

    PNG 3rd ed. sec. 11.3.2.6: the chunk comes before the image data; a decoder that knows it
    ignores ``iCCP``, ``sRGB``, ``gAMA`` and ``cHRM`` (sec. 4.3). The chunk headers are read
    one by one (seeking past each body), not the file.
    """
    with p.open("rb") as fh:
        fh.seek(len(_PNG_SIGNATURE))
        while True:
            head = fh.read(8)
            if len(head) < 8:
                return None
            length, kind = struct.unpack(">I4s", head)
            if kind in (b"IDAT", b"IEND"):
                return None
            if kind == b"cICP":
                body = fh.read(length)
                if length != 4 or len(body) != 4:
                    return None
                return body[0], body[1], body[2], body[3]
            fh.seek(length + 4, os.SEEK_CUR)


def _png_decode_interlaced(data: bytes) -> Any:
    """Decode an interlaced PNG, or one with an eXIf chunk, without libpng's notes.

    imagecodecs reads every PNG with ``png_read_image`` and libpng then writes "PNG warning:
    Interlace handling should be turned on when using png_read_image" onto ``sys.stderr``
    (the pixels are right: PngSuite's interlaced images equal OpenCV's decoding), a second
    line beside a command's one. That line is dropped; any other libpng message becomes a
    warning (libpng's "eXIf: invalid" for an EXIF block it cannot parse, "PLTE: out of place"
    for chunks out of PNG's order, which the pixels do not need). imagecodecs logs them
    (its ``imagecodecs`` logger, which without a handler prints onto ``sys.stderr``): the
    logger's records and ``sys.stderr`` are both taken for the decode (these PNGs only),
    under a lock.
    """
    import contextlib
    import io
    import logging

    import imagecodecs

    class _Taken(logging.Handler):
        def __init__(self) -> None:
            super().__init__()
            self.lines: list[str] = []

        def emit(self, record: logging.LogRecord) -> None:
            self.lines.append(record.getMessage())

    taken = _Taken()
    logger = logging.getLogger("imagecodecs")
    with _stderr_lock, contextlib.redirect_stderr(io.StringIO()) as said:
        propagate, logger.propagate = logger.propagate, False
        logger.addHandler(taken)
        try:
            arr = imagecodecs.png_decode(data)
        finally:
            logger.removeHandler(taken)
            logger.propagate = propagate
    for line in [*taken.lines, *said.getvalue().splitlines()]:
        if line.strip() and "Interlace handling should be turned on" not in line:
            warnings.warn(line.strip(), stacklevel=4)
    return arr


def _read_pillow(p: Path, limit: int, fmt: str = "jpeg", frame: int | None = None) -> np.ndarray:
    """Decode a JPEG, WebP, BMP or GIF with Pillow, upright (EXIF orientation of JPEG, WebP).

    A palette (BMP, GIF) comes as RGB, or RGBA where an index is transparent; a grey GIF with
    a transparent value as grey + alpha; bilevel as 0/255. The pixel limit is checked from the
    header before anything is decoded; an animated GIF or WebP is refused.
    """
    try:
        with _pillow_open(p) as im:
            _pillow_frame(p, im, fmt, frame)
            w, h = im.size
            _check_pixels(p, ImageInfo(w, h, len(im.getbands()), "uint8", fmt), limit)
            _refuse_short_raw(p, im)
            orientation = _pillow_orientation(im)
            im.load()
            mode = im.mode
            if mode in ("I;16", "I;16L", "I;16B"):
                arr = np.asarray(im, dtype=np.uint16)
            elif mode in ("L", "RGB") and _transparent(im, fmt):
                arr = np.asarray(im.convert("LA" if mode == "L" else "RGBA"))
            elif mode in ("L", "RGB", "LA", "RGBA"):
                arr = np.asarray(im)
            elif mode == "P":
                arr = np.asarray(im.convert("RGBA" if _transparent(im, fmt) else "RGB"))
            elif mode == "PA":
                arr = np.asarray(im.convert("RGBA"))
            elif mode == "1":
                arr = np.asarray(im.convert("L"))
            elif mode == "CMYK":
                arr = _cmyk_to_rgb(p, im)
            elif mode == "YCbCr":
                arr = np.asarray(im.convert("RGB"))
            else:
                raise UnreadableFileError(p, f"unsupported image mode {mode}")
    except InvalidInputError:
        raise
    except (OSError, SyntaxError, ValueError) as exc:  # UnidentifiedImageError is an OSError
        raise UnreadableFileError(p, f"{_one_line(exc)}") from None
    out = _orient(arr, orientation)
    # Pillow's buffer is read-only: numba compiles a kernel again for a read-only array (a
    # JPEG's first undistort compiled 3.8 s of CPU after cache --warm had compiled the PNG's)
    return out if out.flags.writeable else out.copy()


def _cmyk_profile(im: Any) -> bytes | None:
    """Return the CMYK ICC profile embedded in a CMYK JPEG (APP2), else None."""
    icc = im.info.get("icc_profile")
    return bytes(icc) if icc and len(icc) >= 20 and icc[16:20] == b"CMYK" else None


def _cmyk_to_rgb(p: Path, im: Any) -> np.ndarray:
    """Return a CMYK JPEG as sRGB: through its embedded CMYK ICC profile, else naively.

    With a profile (a printer's or press's: what Photoshop embeds), LittleCMS (Pillow's
    ``ImageCms``) converts from it to sRGB with ImageCms's defaults (perceptual intent), as
    a colour-managed viewer shows the file; without one, Pillow's naive ``R = (1 - C)(1 - K)``
    (G from M, B from Y). Adobe's inverted CMYK (an APP14 ``Adobe`` segment, what
    Photoshop and libjpeg write) is undone by Pillow before either: the profile sees the
    inks as they mean.
    """
    profile = _cmyk_profile(im)
    if profile is None:
        return np.asarray(im.convert("RGB"))
    import io

    try:
        from PIL import ImageCms
    except ImportError:  # a Pillow built without LittleCMS: the naive path would be wrong
        raise UnreadableFileError(
            p,
            "a CMYK JPEG with an ICC profile needs Pillow's ImageCms "
            "(LittleCMS), which this Pillow lacks",
        ) from None
    try:
        src = ImageCms.ImageCmsProfile(io.BytesIO(profile))
        out = ImageCms.profileToProfile(im, src, _srgb_cms_profile(), outputMode="RGB")
    except (ImageCms.PyCMSError, OSError, ValueError) as exc:
        raise UnreadableFileError(
            p, f"its CMYK ICC profile cannot be applied ({_one_line(exc)})"
        ) from None
    return np.asarray(out)


def _srgb_cms_profile() -> Any:
    """Return LittleCMS's built-in sRGB profile (ImageCms), the target of CMYK conversions."""
    from PIL import ImageCms

    return ImageCms.createProfile("sRGB")


def _tifffile() -> Any:
    import tifffile

    return tifffile


def _frame_page(tif: Any, series: Any, frame: int | None) -> Any:
    """Return the page whose tags describe image ``frame`` of a series (else the first page).

    Pages of a stack share their shape and sample type but may each have their own colour
    map (a palette per page), photometric or orientation: a stack stored a page per image
    takes that page's. A page tifffile loads as a TiffFrame (no tags of its own) is described
    by its key frame.
    """
    first = tif.pages[0] if series is tif.series[0] else series.keyframe
    if frame is None or not frame:
        return first
    stack = [n for a, n in zip(series.axes, series.shape, strict=True) if a not in "YXS"]
    if len(series.pages) != math.prod(stack):
        return first
    page = series.pages[frame]
    return page if hasattr(page, "tags") else series.keyframe


def _tiff_frame(series: Any, path: Path, frame: int | None) -> tuple[np.ndarray, str]:
    """Decode one image of a TIFF series (``frame`` of a stack, else its one image).

    Returns the samples and their axes (``YX``, ``YXS`` or ``SYX``). A stack stored one page
    per image (ImageJ, OME, tifffile's pages) decodes that page alone; another layout decodes
    the series, its memory checked first, and takes the image from it.
    """
    axes, shape = series.axes, series.shape
    plane = "".join(a for a in axes if a in "YXS")
    stack = [n for a, n in zip(axes, shape, strict=True) if a not in "YXS"]
    if frame is None or not stack:
        return np.asarray(series.asarray()), plane
    if len(series.pages) == math.prod(stack):  # one page per image
        return np.asarray(series.asarray(key=frame)), str(series.keyframe.axes)
    need = math.prod(shape) * np.dtype(series.dtype).itemsize
    check_memory(need, str(path), f"a TIFF series of shape {format_shape(tuple(shape))}")
    index = np.unravel_index(frame, stack)
    whole = np.asarray(series.asarray())
    pick = iter(index)
    return whole[tuple(next(pick) if a not in "YXS" else slice(None) for a in axes)], plane


def _read_as_numbers(dtype: Any) -> bool:
    """Whether a TIFF's integer samples are read as floats holding the numbers.

    int8, int16, int32 (signed) and uint32 (beyond uint16, the widest integer an image
    comes as).
    """
    dt = np.dtype(dtype)
    return (dt.kind == "i" and dt.itemsize <= 4) or dt == np.uint32


def _numbers_as_float(dtype: Any) -> np.dtype[Any]:
    """Return the float type a TIFF's int8/16/32 or uint32 samples are read as: each exactly.

    float32 holds int8 and int16 exactly, float64 int32 and uint32 (float32's 24-bit
    mantissa does not), as a DICOM's signed samples come as float32, float64 beyond 24
    stored bits.
    """
    return np.dtype(np.float32 if np.dtype(dtype).itemsize <= 2 else np.float64)


def _refuse_tiff_samples(path: Path, dtype: Any, page: Any) -> None:
    """Refuse, in one line, a TIFF whose samples are no image's: complex, 64-bit integers.

    A complex sample (SampleFormat 5 or 6: a radar's SLC, a Fourier transform, an MR's
    k-space) is two numbers; which one is an image (its magnitude, phase, real part) is the
    caller's choice. 64-bit integers do not fit a float64 exactly.
    """
    dt = np.dtype(dtype)
    if dt.kind == "c":
        fmt = int(getattr(page, "sampleformat", 6) or 6)
        bits = int(getattr(page, "bitspersample", 8 * dt.itemsize) or 8 * dt.itemsize) // 2
        part = f"int{bits}" if fmt == 5 else f"float{bits}"
        raise UnreadableFileError(
            path,
            f"a TIFF of complex {part} samples (SampleFormat {fmt}: a radar's, a Fourier "
            "transform's or k-space's values); a complex number is not an image: save the "
            "part you mean as a float TIFF and read that, e.g. "
            "tifffile.imwrite(out, numpy.abs(tifffile.imread(in))) (or .real, numpy.angle)",
        )
    if dt.kind in "iu" and dt.itemsize > 4:
        raise UnreadableFileError(
            path,
            f"a TIFF of {dt} samples; imageform reads integers of 8 to 32 bits (uint32 and "
            "int32 as float64, exact): save it as float64 or a narrower integer first",
        )


def _read_tiff(p: Path, limit: int, frame: int | None = None) -> tuple[np.ndarray, bool]:
    tifffile = _tifffile()
    try:
        with tifffile.TiffFile(p) as tif:
            series, info, frame = _tiff_series(tif, p, frame)
            _check_pixels(p, info, limit)
            page = _frame_page(tif, series, frame)
            tag = page.tags.get(274)
            orientation = int(tag.value) if tag is not None else 1
            axes = series.axes
            extra = len(getattr(page, "extrasamples", ()) or ())
            photometric = int(page.photometric)
            bits = int(page.bitspersample)
            colormap = page.colormap if photometric == 3 else None
            cmyk = _tiff_cmyk_profile(page)
            if cmyk is None:
                _refuse_tiff_color(p, photometric, int(page.compression))
            arr, axes = _tiff_frame(series, p, frame)
    except InvalidInputError:
        raise
    except MemoryError:
        raise UnreadableFileError(p, "not enough memory to decode it") from None
    except Exception as exc:  # tifffile, zlib, imagecodecs errors: one line naming the file
        raise UnreadableFileError(p, f"{_one_line(exc)}") from None
    if arr.ndim == 3 and "S" in axes and axes.index("S") < axes.index("Y"):
        arr = np.moveaxis(arr, 0, -1)
    if cmyk is not None:
        return _orient(_tiff_cmyk_to_rgb(p, arr, cmyk), orientation), extra > 0
    arr = _tiff_samples(p, arr, photometric, bits, colormap)
    if _read_as_numbers(arr.dtype):  # int8/16/32, uint32: the numbers, as floats
        arr = arr.astype(_numbers_as_float(arr.dtype))
    return _orient(arr, orientation), extra > 0


def _tiff_cmyk_profile(page: Any) -> bytes | None:
    """Return the CMYK ICC profile of a CMYK TIFF page (photometric 5, InkSet CMYK), else None.

    Such a page is read through its profile (:func:`_tiff_cmyk_to_rgb`); one without a profile,
    or with a profile of another colour space, is refused as before (no exact conversion).
    """
    if int(page.photometric) != 5 or int(getattr(page, "inkset", 1) or 1) != 1:
        return None
    tag = page.tags.get(34675)
    icc = bytes(tag.value) if tag is not None else b""
    return icc if len(icc) >= 20 and icc[16:20] == b"CMYK" else None


def _tiff_cmyk_to_rgb(p: Path, arr: np.ndarray, profile: bytes) -> np.ndarray:
    """Convert a CMYK TIFF's samples (uint8 or uint16; alpha after them kept) to sRGB.

    LittleCMS (imagecodecs' ``cms_transform``) from the embedded CMYK profile to LittleCMS's
    built-in sRGB with the perceptual intent: what :func:`_cmyk_to_rgb` does for a CMYK JPEG
    through Pillow's ImageCms (the same library; equal codes on 8 bits), here for 16 bits too.
    TIFF's CMYK is not inverted (0 is no ink), as the profile expects.
    """
    import imagecodecs

    if arr.ndim != 3 or arr.shape[-1] not in (4, 5) or arr.dtype not in (np.uint8, np.uint16):
        raise UnreadableFileError(
            p, f"a CMYK TIFF of {arr.dtype} samples of shape {arr.shape}; imageform converts "
            "8 and 16-bit CMYK (+ alpha) through the embedded profile"
        )  # fmt: skip
    from PIL import ImageCms

    srgb = ImageCms.ImageCmsProfile(_srgb_cms_profile()).tobytes()
    try:
        rgb = imagecodecs.cms_transform(
            np.ascontiguousarray(arr[..., :4]), profile, srgb, colorspace="cmyk",
            outcolorspace="rgb", intent=0, outdtype=arr.dtype,
        )  # fmt: skip
    except Exception as exc:  # a corrupt or unusable profile
        raise UnreadableFileError(
            p, f"its CMYK ICC profile cannot be applied ({_one_line(exc)})"
        ) from None
    rgb = np.asarray(rgb).reshape(*arr.shape[:2], 3)
    if arr.shape[-1] == 5:
        rgb = np.concatenate([rgb, arr[..., 4:]], axis=-1)
    return rgb


#: TIFF photometric interpretations whose samples are not RGB or grey values (TIFF 6.0,
#: TIFF-F/FX, libtiff): read as they are stored, they would pass for RGB.
_TIFF_NOT_RGB = {5: "CMYK (separated, no CMYK ICC profile)", 8: "CIELab", 9: "ICCLab",
                 10: "ITULab", 32844: "LogL", 32845: "LogLuv"}  # fmt: skip


def _refuse_tiff_color(p: Path, photometric: int, compression: int) -> None:
    """Refuse a TIFF whose samples are not RGB or grey: CMYK, Lab, LogLuv, raw YCbCr.

    YCbCr is read only JPEG-compressed (compression 7), where the JPEG decoder turns it
    into RGB; stored as it is, tifffile returns the Y, Cb, Cr samples themselves.
    """
    what = _TIFF_NOT_RGB.get(photometric)
    if what is None and photometric == 6 and compression != 7:
        what = "YCbCr (not JPEG-compressed)"
    if what is not None:
        raise UnreadableFileError(
            p,
            f"a {what} TIFF; imageform reads RGB, grey and palette TIFFs (convert it to RGB first)",
        )


def _tiff_samples(
    p: Path, arr: np.ndarray, photometric: int, bits: int, colormap: Any
) -> np.ndarray:
    """Return the stored samples of a TIFF as the values they mean.

    A palette image (photometric 3) becomes RGB through its colour map (uint8 where the map
    holds 8-bit values, as Pillow reads it; else uint16); a bilevel image (1 bit) becomes
    uint8 0/255; WhiteIsZero (photometric 0) is inverted so that 0 is black. Integer samples
    of fewer bits than their container (10, 12, 14 bits in uint16) stay as stored: they are
    a sensor's numbers (DN), which the measuring commands read as such.
    """
    if photometric == 3 and colormap is not None:
        cmap = np.asarray(colormap)
        if arr.ndim != 2 or cmap.ndim != 2 or cmap.shape[0] != 3:
            raise UnreadableFileError(p, f"a palette TIFF of shape {arr.shape}")
        index = arr.astype(np.intp)
        if index.size and int(index.max()) >= cmap.shape[1]:
            raise UnreadableFileError(
                p, f"palette index {int(index.max())} beyond its {cmap.shape[1]} colours"
            )
        if int(cmap.max(initial=0)) < 256:  # a map of 8-bit values (some writers)
            cmap = cmap.astype(np.uint8)
        elif not np.any(cmap % 257):  # 8-bit colours stored as v * 257
            cmap = (cmap // 257).astype(np.uint8)
        else:
            cmap = cmap.astype(np.uint16)
        return np.ascontiguousarray(cmap.T[index])
    if arr.dtype == np.bool_:
        arr, bits = arr.astype(np.uint8) * np.uint8(255), 8
    if photometric == 0:  # WhiteIsZero
        if arr.dtype.kind != "u":
            raise UnreadableFileError(
                p, f"WhiteIsZero {arr.dtype} samples (only integers are inverted)"
            )
        full = 8 * arr.dtype.itemsize
        top = (1 << bits) - 1 if 0 < bits < full else np.iinfo(arr.dtype).max
        arr = np.asarray(top - np.minimum(arr, top), dtype=arr.dtype)  # white at 2**bits - 1
    return arr


def _read_netpbm(p: Path, limit: int) -> tuple[np.ndarray, bool]:
    """Read a PBM, PGM, PPM or PAM file (:mod:`imageform.io._netpbm` states the rules)."""
    with p.open("rb") as fh:
        head = _netpbm.header(fh.read(1 << 16), p)
    info = ImageInfo(head.width, head.height, head.channels, head.dtype, "netpbm")
    _check_pixels(p, info, limit)
    return _netpbm.read(p, p.read_bytes())


def _read_npy(p: Path, limit: int) -> np.ndarray:
    _npy_header(p, limit)
    try:
        return np.load(p, allow_pickle=False)
    except (ValueError, OSError, EOFError) as exc:
        raise UnreadableFileError(p, f"{_one_line(exc)}") from None


def _normalise(p: Path, arr: np.ndarray, alpha: str, has_alpha: bool) -> np.ndarray:
    if arr.ndim == 2:
        arr = arr[:, :, None]
    if arr.ndim != 3 or not 1 <= arr.shape[-1] <= 4:
        raise InvalidInputError(
            f"{p}: expected an image (H, W) or (H, W, C) with 1 to 4 channels, got {arr.shape}"
        )
    if arr.dtype == np.float16:
        arr = arr.astype(np.float32)
    if arr.dtype not in (np.uint8, np.uint16, np.float32, np.float64):
        raise InvalidInputError(
            f"{p}: unsupported sample type {arr.dtype}; expected uint8, uint16 or float"
        )
    if arr.shape[0] == 0 or arr.shape[1] == 0:
        raise InvalidInputError(f"{p}: the image is empty ({arr.shape[1]} x {arr.shape[0]} px)")
    if has_alpha and arr.shape[-1] in (2, 4) and alpha != "keep":
        a = arr[..., -1]
        opaque_value = 1.0 if arr.dtype.kind == "f" else np.iinfo(arr.dtype).max
        transparent = int(np.count_nonzero(a != opaque_value))
        if transparent and alpha == "reject":
            raise InvalidInputError(
                f"{p} has transparent pixels ({transparent} with alpha < 1); flatten it, or "
                "pass --alpha drop to ignore the alpha channel"
            )
        arr = arr[..., :-1]
    return np.ascontiguousarray(arr)


def read_image(
    path: str | Path,
    *,
    alpha: str = "reject",
    max_pixels: int | None = None,
    frame: int | None = None,
) -> np.ndarray:
    """Read an image file as ``(H, W, C)``: uint8/uint16 as stored, floats as stored.

    Parameters
    ----------
    path : str or Path
        A ``.png``, ``.jpg``/``.jpeg``, ``.tif``/``.tiff``, ``.npy``, ``.webp``, ``.bmp``,
        ``.gif``, Netpbm (``.pgm``, ``.ppm``, ``.pbm``, ``.pnm``, ``.pam``), ``.pfm``,
        ``.hdr``, ``.tga``, ``.qoi``, ``.ico``
        or HEIF file (:data:`IMAGE_FORMATS`), or a DICOM file under any name (the
        ``dicom`` extra; its values through the Modality LUT, see :func:`read_dicom`).
    alpha : {"reject", "drop", "keep"}
        An alpha channel with any transparent pixel: an error (``reject``), ignored
        (``drop``), or returned as the last channel (``keep``). A fully opaque alpha channel
        is dropped unless ``keep``.
    max_pixels : int, optional
        Refuse images with more pixels (default :func:`max_pixels`), checked from the header
        before decoding.
    frame : int, optional
        The image to read of a file that holds several, from 0: a TIFF stack's (pages,
        z-planes, time points, channels of their own: the flat index over them, in the
        file's order, tifffile's ``key``), a multi-frame DICOM's, an animated GIF's or WebP's.
        :func:`image_frames` counts them. None: the file must hold one image. A file of one
        image takes ``frame=0``.

    Returns
    -------
    ndarray (H, W, C)
        ``C`` is 1 (grey) or 3 (RGB), plus alpha with ``alpha="keep"``.

    Raises
    ------
    InvalidInputError
        Missing, unreadable, truncated or corrupt file; too many pixels; transparent pixels
        with ``alpha="reject"``; an unsupported sample type or shape; a TIFF stack, an
        animated GIF or WebP or a multi-frame DICOM (more than one image) without ``frame``;
        a ``frame`` out of range.
    UnknownOptionError
        An unknown ``alpha``.

    Examples
    --------
    >>> import tempfile, os
    >>> p = os.path.join(tempfile.mkdtemp(), "grey.png")
    >>> _ = write_image(p, np.array([[0.0, 1.0]]))
    >>> read_image(p).shape, read_image(p).dtype
    ((1, 2, 1), dtype('uint8'))
    """
    alpha = check_option(alpha, _ALPHA, "alpha handling")
    limit = _pixel_limit(max_pixels)
    fmt = _suffix_format(path) if isinstance(path, (str, os.PathLike)) else ""
    p = _existing(path)
    fmt = _content_format(p, fmt)
    if frame is not None and fmt not in _FRAMED:
        _check_frame(p, frame, 1)
    has_alpha = False
    if fmt == "png":
        arr = _read_png(p, limit)
        has_alpha = arr.ndim == 3 and arr.shape[-1] in (2, 4)
    elif fmt == "jpeg":
        arr = _read_pillow(p, limit)
    elif fmt in ("webp", "bmp", "gif", "tga", "qoi"):
        arr = _read_pillow(p, limit, fmt, frame)
        has_alpha = arr.ndim == 3 and arr.shape[-1] in (2, 4)
    elif fmt == "tiff":
        arr, has_alpha = _read_tiff(p, limit, frame)
    elif fmt == "heif":
        arr = _read_heif(p, limit)
        has_alpha = arr.ndim == 3 and arr.shape[-1] in (2, 4)
    elif fmt == "dicom":
        arr = _read_dicom(p, limit, frame, whole=True)
    elif fmt == "netpbm":
        arr, has_alpha = _read_netpbm(p, limit)
    elif fmt == "pfm":
        with p.open("rb") as fh:
            ph = _pfm.header(fh.read(256), p)
        _check_pixels(p, ImageInfo(ph.width, ph.height, ph.channels, "float32", fmt), limit)
        arr = _pfm.read(p, p.read_bytes())
    elif fmt == "hdr":
        with p.open("rb") as fh:
            hh = _hdr.header(fh.read(1 << 16), p)
        _check_pixels(p, ImageInfo(hh.width, hh.height, 3, "float32", fmt), limit)
        arr = _hdr.read(p, p.read_bytes())
    elif fmt == "ico":
        arr = _read_pillow(p, limit, fmt)
        has_alpha = arr.ndim == 3 and arr.shape[-1] in (2, 4)
    else:
        arr = _read_npy(p, limit)
    return _normalise(p, arr, alpha, has_alpha)


def _read_dicom(
    p: Path, limit: int, frame: object = None, window: Any = None, whole: bool = False
) -> np.ndarray:
    from imageform.io import dicom

    def check(info: Any) -> None:
        _check_pixels(p, ImageInfo(info.width, info.height, info.channels, info.dtype, ""), limit)

    return dicom.read(p, check, frame=frame, window=window, whole=whole)


def read_dicom(
    path: str | Path,
    *,
    frame: int | None = None,
    window: str | tuple[float, float] | None = None,
    max_pixels: int | None = None,
) -> np.ndarray:
    """Read one frame of a DICOM file, as modality values or windowed for display.

    Needs pydicom (the ``dicom`` extra). Without ``frame`` and ``window`` it returns what
    :func:`read_image` does: the stored values through the Modality LUT (integers where the
    rescale is the identity, else float32), MONOCHROME1 inverted to MONOCHROME2's sense,
    colour as RGB (docs/design.md, "Images").

    Parameters
    ----------
    path : str or Path
        A DICOM file (``DICM`` at byte 128; any suffix).
    frame : int, optional
        The frame of a multi-frame file, from 0. None: the file must hold one frame.
    window : "auto" or (center, width), optional
        Apply a VOI window (:func:`dicom_window`) and return float32 display values in
        [0, 1], 0 black (a MONOCHROME1 image is inverted after the window): ``"auto"`` the
        file's first Window Center/Width with its VOI LUT Function (else its VOI LUT
        Sequence, else the image's own range, min to max); ``(center, width)`` in modality
        units with the linear function. Grey images only.
    max_pixels : int, optional
        Refuse frames with more pixels (default :func:`max_pixels`).

    Returns
    -------
    ndarray (H, W, C)
        ``C`` is 1 (grey) or 3 (RGB).

    Raises
    ------
    InvalidInputError
        A missing, corrupt, truncated or non-DICOM file; a frame out of range; no frame given
        for a multi-frame file; a window for a colour image; compressed pixel data that
        pydicom cannot decode without a plugin (the line names it).
    MissingExtraError
        pydicom is not installed.
    """
    limit = _pixel_limit(max_pixels)
    p = _existing(path)
    return _normalise(p, _read_dicom(p, limit, frame, window), "reject", False)


def _open_heif(p: Path) -> Any:
    """Open a HEIF file with libheif (pillow-heif), its header only; one line if it cannot."""
    from imageform._optional import require

    pillow_heif = require("pillow_heif", what=f"reading {p.name} (HEIF)")
    try:
        return pillow_heif.open_heif(p, convert_hdr_to_8bit=False)
    except (OSError, ValueError, RuntimeError) as exc:
        raise UnreadableFileError(p, f"{_one_line(exc)}") from None


def _heif_info(f: Any) -> ImageInfo:
    """Read the header of an open HEIF file: 10 and 12 bits come as uint16."""
    w, h = f.size
    deep = int(f.info.get("bit_depth", 8) or 8) > 8
    return ImageInfo(w, h, len(f.mode.split(";")[0]), "uint16" if deep else "uint8", "heif")


def _read_heif(p: Path, limit: int) -> np.ndarray:
    """Decode a HEIF image: uint8, or uint16 (10/12 bits scaled to 16) for deeper ones."""
    f = _open_heif(p)
    _check_pixels(p, _heif_info(f), limit)
    try:
        arr = np.asarray(f)
    except (OSError, ValueError, RuntimeError) as exc:
        raise UnreadableFileError(p, f"{_one_line(exc)}") from None
    if arr.dtype not in (np.uint8, np.uint16):
        raise UnreadableFileError(p, f"unsupported HEIF samples {arr.dtype}")
    return np.array(arr)  # its own memory, not libheif's buffer


def _pixel_limit(value: object) -> int:
    if value is None:
        return max_pixels()
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or int(value) <= 0:
        raise InvalidInputError(f"expected max_pixels as a positive integer, got {describe(value)}")
    return int(value)


# ---------------------------------------------------------------- writing


#: Samples quantised at a time (a band of rows): the float temporaries of quantising a 100 Mpx
#: image stay a few times this, not a few times the image.
_QUANTISE_BAND = 2**23


def _quantise(a: np.ndarray, bits: int, out_of_range: str, path: Path) -> tuple[np.ndarray, int]:
    """Return ``a`` as ``bits``-bit integers and how many values were outside [0, 1] (clipped).

    A large image is quantised a band of rows at a time (same values, bounded temporaries).
    """
    top = 2**bits - 1
    if a.dtype in (np.uint8, np.uint16) and np.iinfo(a.dtype).max == top:
        return a, 0
    per_row = a[:1].size
    if a.ndim < 2 or a.size <= _QUANTISE_BAND or per_row == 0:
        return _quantise_all(a, bits, out_of_range, path)
    rows = max(1, _QUANTISE_BAND // per_row)
    out = np.empty(a.shape, dtype=np.uint8 if bits == 8 else np.uint16)
    outside = 0
    for r0 in range(0, a.shape[0], rows):
        q, n = _quantise_all(a[r0 : r0 + rows], bits, "clip", path)
        out[r0 : r0 + rows] = q
        outside += n
    if outside and out_of_range == "error":
        lo, hi = float(a.min()), float(a.max())
        raise InvalidInputError(
            f"{outside} values outside [0, 1] (min {lo:.4g}, max {hi:.4g}) cannot be stored in "
            f"the {bits}-bit {path.name}; keep them in a float .tif or .npy, or clip them "
            "(--out-of-range clip)"
        )
    return out, outside


def _quantise_all(
    a: np.ndarray, bits: int, out_of_range: str, path: Path
) -> tuple[np.ndarray, int]:
    dtype = np.uint8 if bits == 8 else np.uint16
    top = 2**bits - 1
    if a.dtype in (np.uint8, np.uint16):
        src_top = np.iinfo(a.dtype).max
        if src_top == top:
            return a, 0
        return np.round(a.astype(np.float64) * (top / src_top)).astype(dtype), 0
    if a.dtype.kind != "f":
        raise InvalidInputError(
            f"expected floats in [0, 1], uint8 or uint16 to write {path}, got {a.dtype}"
        )
    if not np.all(np.isfinite(a)):
        raise InvalidInputError(f"the image to write to {path} contains NaN or inf")
    q, outside = float_codes(a, bits)
    if outside and out_of_range == "error":
        lo, hi = float(a.min()), float(a.max())
        raise InvalidInputError(
            f"{outside} values outside [0, 1] (min {lo:.4g}, max {hi:.4g}) cannot be stored in "
            f"the {bits}-bit {path.name}; keep them in a float .tif or .npy, or clip them "
            "(--out-of-range clip)"
        )
    return q, outside


def float_codes(a: np.ndarray, bits: int) -> tuple[np.ndarray, int]:
    """Return finite floats ``a`` as ``bits``-bit codes, and how many lay outside the codes.

    The code of ``v`` is ``round(v (2^bits - 1))`` clipped to ``[0, 2^bits - 1]``; a value
    counts as outside [0, 1] when the clip changes its code, i.e. when it is beyond 0 or 1
    by half a code or more. A value a rounding error outside (-1.7e-7 after a Lab round
    trip) has its own code and is stored as it is, not counted as clipped. The one rule of
    :func:`write_image` and of the commands that quantise a band of rows at a time.
    """
    top = 2**bits - 1
    r = np.round(a * top)
    outside = int(np.count_nonzero((r < 0) | (r > top)))
    return np.clip(r, 0, top).astype(np.uint8 if bits == 8 else np.uint16), outside


@_deprecate.parameters(renamed={"bits": "bit_depth"})
def write_image(
    path: str | Path,
    image: ArrayLike,
    *,
    bit_depth: int | None = None,
    out_of_range: str = "error",
    quality: int = 95,
    clip: bool | None = None,
    color_space: str | None = None,
) -> WrittenImage:
    """Write an image atomically; the format follows the suffix.

    Parameters
    ----------
    path : str or Path
        ``.png``, ``.jpg``/``.jpeg``, ``.tif``/``.tiff``, ``.npy``, ``.pgm`` (grey) /
        ``.ppm`` (RGB): binary Netpbm of maxval 255 or 65535, with no colour profile, or
        ``.pfm`` (grey or RGB float32, little-endian; integers as ``v / (2**bits - 1)``; any
        float stored as it is, no profile).
    image : array_like (H, W) or (H, W, C), C in 1..4
        Floats in [0, 1] (encoded values), uint8 or uint16.
    bit_depth : {8, 16}, optional
        Bits per sample for PNG and PGM/PPM (JPEG: 8 only) and for integer TIFF (``bits`` is its
        deprecated name). Default: the integer
        input's depth, 8 for floats in PNG/JPEG; TIFF and ``.npy`` store floats as floats.
    out_of_range : {"error", "clip"}
        Float values outside [0, 1] when quantising: an error, or clip them (the count is
        returned).
    quality : int
        JPEG quality, 1 to 100.
    clip : bool, optional
        Deprecated: ``clip=True`` is ``out_of_range="clip"``.
    color_space : str, optional
        The space the values are in. An RGB space's ICC profile (:func:`icc_profile`) is
        embedded in a PNG (``iCCP``), JPEG or TIFF so that viewers and
        :func:`image_color_space` read the colours as meant. None or ``srgb``: nothing is
        embedded (sRGB is what an untagged file means). A TIFF in a space without a shipped
        profile (``lab``, ``xyz``, ``linear_rec2020`` ...: any of
        :data:`imageform.color.SPACES`) records its name in the ImageDescription JSON
        tifffile writes, ``{"shape": [...], "imageform_color_space": "lab"}``, which
        :func:`image_color_space` reads back; a PNG or JPEG in such a space is refused.

    Returns
    -------
    WrittenImage
        ``(bit_depth, out_of_range)``.

    Raises
    ------
    InvalidInputError
        Unknown suffix, bad shape or dtype, NaN/inf, values outside [0, 1] with
        ``out_of_range="error"``, 16 bits or alpha in JPEG.

    Examples
    --------
    >>> import tempfile, os
    >>> p = os.path.join(tempfile.mkdtemp(), "a.png")
    >>> write_image(p, np.array([[[0.0, 0.5, 1.0]]]), bit_depth=16)
    WrittenImage(bit_depth=16, out_of_range=0)
    >>> read_image(p).tolist()
    [[[0, 32768, 65535]]]
    """
    if clip is not None:
        warnings.warn(
            "write_image(clip=...) is deprecated; use out_of_range='clip' or 'error'",
            DeprecationWarning,
            stacklevel=2,
        )
        out_of_range = "clip" if clip else "error"
    p = check_writable(path, "path")
    shown = p.with_name(final_name(p.name))  # the user's name in messages, not a temporary's
    fmt = image_format(p)
    if p.suffix.lower() in _READ_ONLY_TIFF:
        raise InvalidInputError(
            f"imageform reads {p.suffix.lower()} slides but writes TIFF as .tif or .tiff, got "
            f"{shown}"
        )
    out_of_range = check_option(out_of_range, _OUT_OF_RANGE, "out-of-range policy")
    profile, recorded = None, None
    if color_space is not None:
        from imageform.color import space_name
        from imageform.io.icc import RGB_PROFILED, embedded_profile

        name = space_name(color_space, "color_space")
        if fmt == "tiff" and name not in RGB_PROFILED:
            recorded = name  # no profile to embed: named in the TIFF's description
        else:
            profile = embedded_profile(name)  # refuses a space without one
    bits = bit_depth
    if bits is not None and (isinstance(bits, bool) or bits not in (8, 16)):
        raise InvalidInputError(f"expected bit_depth 8 or 16, got {describe(bits)}")
    a = np.asarray(image)
    if a.ndim and not a.flags.c_contiguous:  # a turned or cropped view: codecs need C order
        a = np.ascontiguousarray(a)
    if a.ndim == 3 and a.shape[-1] == 1 and fmt != "npy":
        a = a[..., 0]
    if a.ndim not in (2, 3) or (a.ndim == 3 and not 1 <= a.shape[-1] <= 4) or a.size == 0:
        raise InvalidInputError(
            f"expected an image (H, W) or (H, W, C) with 1 to 4 channels to write {p}, "
            f"got shape {a.shape}"
        )
    if a.dtype.kind not in "fu" or a.dtype.itemsize > 8:
        raise InvalidInputError(f"expected floats, uint8 or uint16 to write {p}, got {a.dtype}")
    if fmt == "netpbm" and p.suffix.lower() not in _NETPBM_WRITTEN:
        fmt = {".pbm": "PBM", ".pam": "PAM"}.get(p.suffix.lower(), "PNM")  # read only
    if fmt not in _WRITTEN:
        name = {"heif": "HEIF", "webp": "WebP", "hdr": "Radiance HDR"}.get(fmt, fmt.upper())
        raise InvalidInputError(
            f"imageform reads {name} but does not write it; write a .png, .jpg, .tif, .pgm, "
            ".ppm or .pfm file"
        )
    if fmt == "npy":
        atomic_write(p, lambda t: np.save(t, a, allow_pickle=False))
        return WrittenImage(None, 0)
    if fmt == "pfm":
        return _write_pfm(p, shown, a, bits, color_space)
    if fmt == "tiff":
        tifffile = _tifffile()
        n_out = 0
        if bits is not None:
            a, n_out = _quantise(a, bits, out_of_range, shown)
        channels = a.shape[-1] if a.ndim == 3 else 1
        extra: dict[str, Any] = {"extrasamples": ["unassalpha"]} if channels in (2, 4) else {}
        photometric = "rgb" if channels in (3, 4) else "minisblack"
        if profile is not None and channels in (3, 4):
            extra["iccprofile"] = profile
        if recorded is not None:  # tifffile's JSON description, {"shape": [...]}, gets a key
            extra["metadata"] = {_TIFF_COLOR_SPACE_KEY: recorded}
        atomic_write(p, lambda t: tifffile.imwrite(t, a, photometric=photometric, **extra))
        return WrittenImage(bits if a.dtype.kind == "u" else None, n_out)
    depth = bits if bits is not None else (16 if a.dtype == np.uint16 else 8)
    if fmt == "netpbm":
        want = _NETPBM_WRITTEN[p.suffix.lower()]
        have = a.shape[-1] if a.ndim == 3 else 1
        if have != want:
            kind = {1: "grey", 2: "grey with alpha", 3: "RGB", 4: "RGB with alpha"}[have]
            other = shown.stem + {1: ".pgm", 3: ".ppm"}.get(have, ".png")
            raise InvalidInputError(
                f"{p.suffix.upper()[1:]} holds {'grey' if want == 1 else 'RGB'} images, this "
                f"one is {kind}; write {other}"
            )
        if profile is not None:
            raise InvalidInputError(
                f"Netpbm has no colour profile; write {shown.stem}.png or .tif to declare "
                f"{color_space}"
            )
        q, n_out = _quantise(a, depth, out_of_range, shown)
        atomic_write(p, lambda t: t.write_bytes(_netpbm.encode(q)))
        return WrittenImage(depth, n_out)
    if fmt == "jpeg":
        if depth != 8:
            raise InvalidInputError(f"JPEG holds 8 bits per sample; write {shown.stem}.png for 16")
        if a.ndim == 3 and a.shape[-1] in (2, 4):
            raise InvalidInputError(f"JPEG has no alpha channel; write {shown.stem}.png to keep it")
    q, n_out = _quantise(a, depth, out_of_range, shown)
    rgb = q.ndim == 3 and q.shape[-1] in (3, 4)
    if fmt == "png":
        import imagecodecs

        def png(t: Path) -> None:
            data = bytes(imagecodecs.png_encode(q, level=6))
            t.write_bytes(_with_iccp(data, profile) if profile is not None and rgb else data)

        atomic_write(p, png)
    else:
        from PIL import Image

        if not isinstance(quality, int) or not 1 <= quality <= 100:
            raise InvalidInputError(f"expected JPEG quality 1 to 100, got {quality!r}")
        icc = {"icc_profile": profile} if profile is not None and rgb else {}
        atomic_write(p, lambda t: Image.fromarray(q).save(t, format="JPEG", quality=quality, **icc))
    return WrittenImage(depth, n_out)


def _write_pfm(
    p: Path, shown: Path, a: np.ndarray, bits: int | None, color_space: str | None
) -> WrittenImage:
    """Write a grey (``Pf``) or RGB (``PF``) PFM: float32, little-endian, rows bottom-up.

    Floats are stored as they are (values above 1, negative disparities, ``inf`` included);
    uint8 and uint16 as the encoded values they mean, ``v / (2**bits - 1)``.
    """
    have = a.shape[-1] if a.ndim == 3 else 1
    if have not in (1, 3):
        kind = {2: "grey with alpha", 4: "RGB with alpha"}[have]
        raise InvalidInputError(
            f"PFM holds grey or RGB images, this one is {kind}; write {shown.stem}.tif"
        )
    if bits is not None:
        raise InvalidInputError(f"PFM stores float32 samples: bit_depth {bits} has no meaning")
    if color_space is not None and str(color_space).strip().lower() != "srgb":
        raise InvalidInputError(
            f"PFM has no colour profile; write {shown.stem}.tif to declare {color_space}"
        )
    if a.dtype.kind == "u":
        if a.dtype not in (np.uint8, np.uint16):
            raise InvalidInputError(f"expected floats, uint8 or uint16 to write {p}, got {a.dtype}")
        a = a.astype(np.float32) / np.float32(np.iinfo(a.dtype).max)
    atomic_write(p, lambda t: t.write_bytes(_pfm.encode(a)))
    return WrittenImage(None, 0)


def _with_iccp(png: bytes, profile: bytes) -> bytes:
    """``png`` with an ``iCCP`` chunk (PNG 3rd ed. sec. 11.3.2.3) right after ``IHDR``."""
    import struct
    import zlib

    body = b"icc\0\0" + zlib.compress(profile)  # name, NUL, compression method 0
    chunk = struct.pack(">I", len(body)) + b"iCCP" + body
    chunk += struct.pack(">I", zlib.crc32(b"iCCP" + body) & 0xFFFFFFFF)
    end = 8 + 8 + 13 + 4  # signature, IHDR's length and type, its 13 bytes, its CRC
    return png[:end] + chunk + png[end:]


def image_color_space(path: str | Path) -> DeclaredColorSpace:
    """Return the colour space an image file declares.

    In this order: an embedded ICC profile (JPEG APP2, PNG ``iCCP``, TIFF tag 34675, HEIF's
    ``colr`` box, WebP's ``ICCP`` chunk, a GIF's ICC extension, a BMP's BITMAPV5HEADER
    profile) named by
    :func:`identify_icc` (a CMYK JPEG's CMYK profile: ``srgb``, what :func:`read_image`
    converts it to); HEIF's ``nclx`` colour description (H.273 code points:
    BT.709/sRGB, Display P3 or BT.2020 primaries with the sRGB, BT.709 or a
    linear transfer); a PNG's ``cICP`` chunk before all of these (PNG 3rd ed.: it overrides
    ``iCCP``, ``sRGB``, ``gAMA``, ``cHRM``; the same code points, source ``png-cicp``; PQ,
    HLG or a BT.470 gamma give ``name`` None with the code points described); PNG's ``sRGB``
    chunk; PNG's ``gAMA`` and ``cHRM`` chunks (gAMA
    1/2.2 within 5 % is sRGB's curve, 1.0 a ``linear_`` space; source ``png-gama`` or
    ``png-chrm``; a gamma or primaries of no space give ``name`` None with the chunks
    described); EXIF ``ColorSpace`` 1 (sRGB), or
    uncalibrated with the interoperability index ``R03`` (Adobe RGB, the DCF option camera
    JPEGs use); a TIFF without a profile whose ImageDescription JSON names a space under
    ``imageform_color_space`` (what :func:`write_image` records for a space without a
    profile: ``lab``, ``xyz`` ...; source ``tiff-description``); a Radiance HDR file's linear
    RGB, ``linear_srgb`` (Rec. 709 primaries, Radiance's default) unless its ``PRIMARIES=``
    line gives others (then None; source ``radiance``). A profile imageform does not
    recognise gives ``name`` None with its description; ``.npy`` files and files that
    declare nothing give ``(None, "none", "")``.

    Parameters
    ----------
    path : str or Path
        An image file of :data:`IMAGE_FORMATS`.

    Returns
    -------
    DeclaredColorSpace

    Raises
    ------
    InvalidInputError
        A missing or unreadable file, or a corrupt embedded profile.

    Examples
    --------
    >>> import tempfile, os
    >>> import numpy as np
    >>> from imageform.io import image_color_space, write_image
    >>> p = os.path.join(tempfile.mkdtemp(), "p3.png")
    >>> _ = write_image(p, np.full((2, 2, 3), 0.5), color_space="display_p3")
    >>> image_color_space(p)
    DeclaredColorSpace(name='display_p3', source='icc', description='sP3')
    """
    from imageform.io.icc import (
        DeclaredColorSpace,
        declared_by_png_chunks,
        declared_by_profile,
        parse_icc,
    )

    fmt = _suffix_format(path)
    p = Path(path)
    if not p.is_file():
        raise UnreadableFileError(p, "no such file")
    fmt = _content_format(p, fmt)
    if fmt in ("npy", "netpbm", "pfm"):
        return DeclaredColorSpace(None, "none", "")
    if fmt == "hdr":
        with p.open("rb") as fh:
            name, said = _hdr.declared(fh.read(1 << 16), p)
        return DeclaredColorSpace(name, "radiance", said)
    if fmt == "bmp":
        icc_bmp = _bmp_profile(p)
        if icc_bmp:
            return declared_by_profile(icc_bmp)
    if fmt == "dicom":
        from imageform.io import dicom

        icc_dicom = dicom.icc_profile_of(dicom.open_dicom(p, pixels=False))
        return declared_by_profile(icc_dicom) if icc_dicom else DeclaredColorSpace(None, "none", "")
    if fmt == "heif":
        info = _open_heif(p).info
        if info.get("icc_profile"):
            return declared_by_profile(info["icc_profile"])
        return _nclx_space(info.get("nclx_profile"))
    if fmt == "tiff":  # tifffile: Pillow opens no float or 16-bit RGB TIFF
        try:
            with _tifffile().TiffFile(p) as tif:
                page = tif.pages.first
                tag = page.tags.get(34675)
                icc_tiff = bytes(tag.value) if tag is not None else b""
                description = page.description
                cmyk_tiff = _tiff_cmyk_profile(page) is not None
        except Exception as exc:
            raise UnreadableFileError(p, f"{_one_line(exc)}") from None
        if cmyk_tiff:  # read_image converts it through its profile to sRGB
            desc = parse_icc(icc_tiff).description
            return DeclaredColorSpace("srgb", "icc", f"{desc} (CMYK, read as sRGB)")
        if icc_tiff:
            return declared_by_profile(icc_tiff)
        recorded = _recorded_space(description)
        if recorded is not None:
            return DeclaredColorSpace(recorded, "tiff-description", "")
        return DeclaredColorSpace(None, "none", "")
    cicp = _png_cicp(p) if fmt == "png" else None
    if cicp is not None:  # PNG 3rd ed.: it overrides iCCP, sRGB, gAMA and cHRM
        prim, trc, matrix, full = cicp
        text = f"cICP primaries {prim}, transfer {trc}, matrix {matrix}, full range {full}"
        name = _NCLX.get((prim, trc)) if matrix == 0 and full == 1 else None
        return DeclaredColorSpace(name, "png-cicp", text)
    try:
        with _pillow_open(p) as im:
            icc = im.info.get("icc_profile")
            cmyk = fmt == "jpeg" and im.mode == "CMYK" and _cmyk_profile(im) is not None
            srgb_chunk = fmt == "png" and "srgb" in im.info
            gamma = im.info.get("gamma") if fmt == "png" else None
            chrm = im.info.get("chromaticity") if fmt == "png" else None
            cs, interop = _exif_color_space(im)
    except (OSError, ValueError, SyntaxError) as err:  # UnidentifiedImageError is an OSError
        raise UnreadableFileError(p, f"{_one_line(err)}") from None
    if cmyk:  # read_image converts it through its profile to sRGB
        prof = parse_icc(icc)
        return DeclaredColorSpace("srgb", "icc", f"{prof.description} (CMYK, read as sRGB)")
    if icc:
        return declared_by_profile(icc)
    if srgb_chunk:
        return DeclaredColorSpace("srgb", "png-srgb", "")
    chunks = declared_by_png_chunks(gamma, chrm) if fmt == "png" else None
    if chunks is not None:  # PNG 3rd ed.: iCCP and sRGB take precedence over gAMA and cHRM
        return chunks
    if cs == 1:
        return DeclaredColorSpace("srgb", "exif", "")
    if cs == 0xFFFF and isinstance(interop, str) and interop.strip("\0") == "R03":
        return DeclaredColorSpace("adobe_rgb", "exif", "")
    return DeclaredColorSpace(None, "none", "")


#: A BITMAPV5HEADER's bV5CSType PROFILE_EMBEDDED, ``'MBED'`` as a little-endian DWORD.
_BMP_PROFILE_EMBEDDED = b"DEBM"


def _bmp_profile(p: Path) -> bytes | None:
    """Return the ICC profile a BMP embeds (BITMAPV5HEADER, PROFILE_EMBEDDED), else None.

    The V5 header (124 bytes, at byte 14) holds bV5CSType at its byte 56 and bV5ProfileData,
    bV5ProfileSize at 112 and 116, the profile's offset counted from the header's start
    (Microsoft's BITMAPV5HEADER reference). Pillow does not read it. An offset or size past
    the end of the file is refused in one line.
    """
    with p.open("rb") as fh:
        head = fh.read(14 + 124)
        if len(head) < 138 or struct.unpack("<I", head[14:18])[0] != 124:
            return None
        if head[70:74] != _BMP_PROFILE_EMBEDDED:
            return None
        offset, size = struct.unpack("<II", head[126:134])
        fh.seek(14 + offset)
        data = fh.read(size)
    if size == 0 or len(data) != size:
        raise UnreadableFileError(
            p, f"its embedded ICC profile ({size} bytes at {14 + offset}) is past the file's end"
        )
    return data


def _recorded_space(description: str) -> str | None:
    """Return the space :func:`write_image` recorded in a TIFF's ImageDescription, or None.

    Only a JSON object holding ``_TIFF_COLOR_SPACE_KEY`` with a space of
    :data:`imageform.color.SPACES` counts; any other description (another tool's text, XML,
    tifffile's own ``{"shape": ...}``, a name imageform does not know) declares nothing.
    """
    import json

    text = description.strip() if isinstance(description, str) else ""
    if not text.startswith("{") or len(text) > 65536:  # an OME-XML, an Aperio header ...
        return None
    try:
        data = json.loads(text)
    except ValueError:
        return None
    value = data.get(_TIFF_COLOR_SPACE_KEY) if isinstance(data, dict) else None
    if not isinstance(value, str):
        return None
    from imageform.color import space_name

    try:
        return space_name(value, _TIFF_COLOR_SPACE_KEY)
    except InvalidInputError:
        return None


#: HEIF's ``nclx`` colour description (ITU-T H.273 code points): (colour primaries, transfer
#: characteristics) -> imageform's space. Primaries 1: BT.709/sRGB, 9: BT.2020, 12: P3 with
#: D65 (SMPTE EG 432-1); transfer 13: sRGB (IEC 61966-2-1), 1/6/14/15: the BT.709 OETF's
#: family, 8: linear.
_NCLX = {
    (1, 13): "srgb",
    (12, 13): "display_p3",
    (1, 1): "rec709",
    (1, 6): "rec709",
    (1, 14): "rec709",
    (1, 15): "rec709",
    (9, 1): "rec2020",
    (9, 6): "rec2020",
    (9, 14): "rec2020",
    (9, 15): "rec2020",
    (1, 8): "linear_srgb",
    (12, 8): "linear_display_p3",
    (9, 8): "linear_rec2020",
}


def _nclx_space(nclx: Any) -> DeclaredColorSpace:
    """Name the space a HEIF ``nclx`` box declares (H.273 code points), or None."""
    from imageform.io.icc import DeclaredColorSpace

    if not isinstance(nclx, dict):
        return DeclaredColorSpace(None, "none", "")
    prim = int(nclx.get("color_primaries", 2) or 2)
    trc = int(nclx.get("transfer_characteristics", 2) or 2)
    if prim == 2 and trc == 2:  # both "unspecified"
        return DeclaredColorSpace(None, "none", "")
    text = f"nclx primaries {prim}, transfer {trc}"
    return DeclaredColorSpace(_NCLX.get((prim, trc)), "nclx", text)
