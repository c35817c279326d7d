"""DICOM images (X-ray, CT, MR, endoscopy, microscopy) through pydicom, the ``dicom`` extra.

:func:`~imageform.io.read_image` reads a DICOM file like any other image (``image_io`` calls
this module); :func:`~imageform.io.read_dicom` picks a frame or applies the VOI window. The
rules (docs/design.md, "Images"):

- **Values**: the stored values through the Modality LUT (PS3.3 C.11.1): Rescale Slope and
  Intercept, or a Modality LUT Sequence. Integers stay integers (uint8 / uint16) where the
  samples are unsigned and the rescale is the identity (slope 1, intercept 0); a Modality LUT
  Sequence gives uint8 or uint16 as its descriptor's bits; anything else (signed samples, a
  CT's Hounsfield units, a slope other than 1) comes as float32 (float64 beyond 24 stored
  bits). Bits above Bits Stored are masked and signed samples sign-extended (pydicom).
- **MONOCHROME1** (bright is low, as on film) is inverted to MONOCHROME2's sense, 0 dark, as
  a WhiteIsZero TIFF is: the modality values ``v`` become ``f(lo) + f(hi) - v``, with ``lo``
  and ``hi`` the stored range and ``f`` the Modality LUT. The window of the file applies to the
  values before that inversion; :func:`read_dicom` with ``window=`` windows them, then inverts
  (PS3.3's Presentation LUT INVERSE, after the VOI LUT).
- **Colour**: RGB as stored; YBR_FULL and YBR_FULL_422 (and JPEG's YCbCr) converted to RGB
  by pydicom; PALETTE COLOR through its palette (RGB). The ICC profile (0028,2000) is what
  :func:`~imageform.io.image_color_space` declares; without one the RGB is read as sRGB.
- **Frames**: one image per file, as for TIFF: a multi-frame file is refused by
  :func:`read_image`; :func:`read_dicom` reads one frame (``frame=``).
- **Whole-slide images** (Modality SM with a Total Pixel Matrix): the frames are tiles of one
  image, which :func:`read_image` returns assembled (:func:`slide_tiles`: TILED_FULL, the
  tiles row by row, PS3.3 C.7.6.17.3; TILED_SPARSE, each frame where its Plane Position
  (Slide) says, gaps white for colour and 0 for grey); ``read_dicom(frame=k)`` still reads
  tile ``k``. One focal plane and one optical path (more are refused in one line). The
  pyramid's smaller levels are the files of the same series in the same folder
  (:func:`slide_levels`), which the chunked commands read a tile at a time
  (:class:`SlideLevel`); the pixel size is Pixel Spacing's.
"""

from __future__ import annotations

import math
import os
import threading
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from imageform._typing import ArrayLike
from imageform._validate import check_option, describe
from imageform.errors import InvalidInputError, UnreadableFileError

if TYPE_CHECKING:
    from collections.abc import Callable

__all__ = ["DICOM_WINDOW_FUNCTIONS", "DicomInfo", "dicom_info", "dicom_window"]

#: The VOI LUT Functions (0028,1056) :func:`dicom_window` implements (PS3.3 C.11.2.1.2-3).
DICOM_WINDOW_FUNCTIONS = ("linear", "linear_exact", "sigmoid")

_GREY = ("MONOCHROME1", "MONOCHROME2")
_RGB_LIKE = ("RGB", "YBR_FULL", "YBR_FULL_422", "YBR_ICT", "YBR_RCT", "YBR_PARTIAL_420")

#: What decodes each family of compressed transfer syntaxes (pydicom's plugins).
_PLUGINS = (
    ("1.2.840.10008.1.2.4.8", "pip install pyjpegls (JPEG-LS)"),
    ("1.2.840.10008.1.2.4.9", "pip install pylibjpeg pylibjpeg-openjpeg (JPEG 2000)"),
    ("1.2.840.10008.1.2.4.20", "pip install pylibjpeg pylibjpeg-openjpeg (HTJ2K)"),
    ("1.2.840.10008.1.2.4.5", "pip install pylibjpeg pylibjpeg-libjpeg (JPEG)"),
    ("1.2.840.10008.1.2.4.7", "pip install pylibjpeg pylibjpeg-libjpeg (JPEG lossless)"),
)


class DicomInfo(NamedTuple):
    """What a DICOM file's header says about its image.

    ``width``, ``height``, ``channels`` and ``dtype`` are those of the image
    :func:`~imageform.io.read_image` returns (after the Modality LUT); ``frames`` the count of
    frames; ``modality`` (``"CR"``, ``"CT"``, ``"ES"``, ``"SM"`` ...), ``photometric`` (the
    Photometric Interpretation), ``bits_allocated``, ``bits_stored``, ``signed`` (Pixel
    Representation 1); ``rescale_slope`` and ``rescale_intercept`` (1 and 0 when absent),
    ``rescale_type`` (``"HU"`` ...), ``modality_lut`` (a Modality LUT Sequence is applied
    instead); ``window_center`` and ``window_width`` (the file's VOI windows, in modality
    units, empty when none) and ``window_function`` (the VOI LUT Function, lower case);
    ``pixel_spacing_mm`` and ``imager_pixel_spacing_mm`` ((row, column) spacing in mm: between
    rows first, as DICOM lists it; None when absent); ``transfer_syntax`` (its name); ``icc``
    (an ICC profile is embedded). An enhanced image's rescale, window and spacing come from its
    functional groups (those of the first frame).
    """

    width: int
    height: int
    channels: int
    dtype: str
    frames: int
    modality: str
    photometric: str
    bits_allocated: int
    bits_stored: int
    signed: bool
    rescale_slope: float
    rescale_intercept: float
    rescale_type: str
    modality_lut: bool
    window_center: tuple[float, ...]
    window_width: tuple[float, ...]
    window_function: str
    pixel_spacing_mm: tuple[float, float] | None
    imager_pixel_spacing_mm: tuple[float, float] | None
    transfer_syntax: str
    icc: bool


#: pydicom's notes on what it reads leniently (``warnings`` and its logger): silenced while it
#: reads, under this lock, since ``warnings.catch_warnings`` changes a process-wide filter.
_quiet_lock = threading.RLock()


def _one_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0].strip() if text else type(exc).__name__


def _pydicom(p: Path) -> Any:
    from imageform._optional import require

    return require("pydicom", what=f"reading {p.name} (DICOM)")


def open_dicom(p: Path, *, pixels: bool) -> Any:
    """Read ``p`` with pydicom (``pixels=False``: up to the pixel data); one line if it cannot."""
    pydicom = _pydicom(p)
    try:
        with _quiet_lock, warnings.catch_warnings():  # pydicom's notes: not our line
            warnings.simplefilter("ignore")
            return pydicom.dcmread(p, stop_before_pixels=not pixels)
    except pydicom.errors.InvalidDicomError:
        raise UnreadableFileError(
            p, "not a DICOM file (no 'DICM' at byte 128 and no DICOM header)"
        ) from None
    except MemoryError:
        raise UnreadableFileError(p, "not enough memory to read it") from None
    except Exception as exc:  # truncated or corrupt: pydicom's EOFError, ValueError, KeyError...
        raise UnreadableFileError(p, f"corrupt DICOM file ({_one_line(exc)})") from None


def _value(ds: Any, keyword: str, frame: int = 0) -> Any:
    """Return an attribute of ``ds``, or of its frame's functional groups (enhanced images).

    Enhanced CT, MR and X-ray images and whole-slide images keep the rescale, the window and
    the pixel spacing in items of the Per-frame or Shared Functional Groups Sequences (PS3.3
    C.7.6.16: Pixel Value Transformation, Frame VOI LUT, Pixel Measures) rather than at the
    top level; the frame's own item comes before the shared one.
    """
    value = ds.get(keyword, None)
    if value is not None and value != "":
        return value.value if hasattr(value, "VR") else value
    groups = []
    per_frame = ds.get("PerFrameFunctionalGroupsSequence", None)
    if per_frame is not None and 0 <= frame < len(per_frame):
        groups.append(per_frame[frame])
    shared = ds.get("SharedFunctionalGroupsSequence", None)
    if shared:
        groups.append(shared[0])
    for group in groups:
        for elem in group:
            if elem.VR == "SQ" and len(elem.value) and keyword in elem.value[0]:
                return elem.value[0][keyword].value
    return None


def _number(ds: Any, keyword: str, default: float, frame: int = 0) -> float:
    value = _value(ds, keyword, frame)
    if value is None or value == "":
        return default
    try:
        out = float(value[0] if _multi(value) else value)
    except (TypeError, ValueError):
        return default
    return out if math.isfinite(out) else default


def _multi(value: Any) -> bool:
    return not isinstance(value, (str, bytes)) and hasattr(value, "__len__")


def _numbers(ds: Any, keyword: str, frame: int = 0) -> tuple[float, ...]:
    value = _value(ds, keyword, frame)
    if value is None or value == "":
        return ()
    items = list(value) if _multi(value) else [value]
    try:
        out = tuple(float(v) for v in items)
    except (TypeError, ValueError):
        return ()
    return out if all(math.isfinite(v) for v in out) else ()


def _spacing(ds: Any, keyword: str, frame: int = 0) -> tuple[float, float] | None:
    values = _numbers(ds, keyword, frame)
    return (values[0], values[1]) if len(values) == 2 and min(values) > 0 else None


def _lut_bits(ds: Any, keyword: str) -> int:
    """Return the bits of a LUT's entries: a palette's descriptor, or a LUT Sequence's first."""
    if keyword.endswith("Descriptor"):  # (0028,1101): entries, first value, bits
        return int(ds[keyword].value[2])
    return int(ds[keyword][0].LUTDescriptor[2])


def header(p: Path, ds: Any, frame: int = 0) -> DicomInfo:
    """Return :class:`DicomInfo` of a dataset ``ds`` read from ``p``; refuse what is no image.

    The rescale, window and spacing are those of ``frame`` (they may differ per frame). A
    header whose values cannot be read (a text where a number belongs, a LUT without its
    descriptor) is one line.
    """
    try:
        return _header(p, ds, frame)
    except InvalidInputError:
        raise
    except (ValueError, TypeError, AttributeError, KeyError, IndexError, OverflowError) as exc:
        raise UnreadableFileError(p, f"corrupt DICOM header ({_one_line(exc)})") from None


def _header(p: Path, ds: Any, frame: int) -> DicomInfo:
    for keyword in ("Rows", "Columns", "BitsAllocated", "PhotometricInterpretation"):
        if ds.get(keyword, None) in (None, ""):
            meta = getattr(ds, "file_meta", None) or {}
            sop = ds.get("SOPClassUID", None) or meta.get("MediaStorageSOPClassUID", None)
            name = str(getattr(sop, "name", "") or "")
            if len(ds) == 0:  # nothing after the file meta information
                raise UnreadableFileError(p, "the DICOM file ends in its header")
            if "Image" in name:  # an image's class without its image attributes
                raise UnreadableFileError(
                    p,
                    f"a {name} file without its {keyword} (no image in it, or "
                    "the file is cut short)",
                )
            what = f" ({name})" if name else ""
            raise UnreadableFileError(p, f"a DICOM file with no image{what}: {keyword} is missing")
    photometric = str(ds.PhotometricInterpretation).strip().upper()
    rows, cols = int(ds.Rows), int(ds.Columns)
    allocated = int(ds.BitsAllocated)
    stored = int(ds.get("BitsStored", None) or allocated)
    signed = int(ds.get("PixelRepresentation", 0) or 0) == 1
    spp = int(ds.get("SamplesPerPixel", 1) or 1)
    frames = int(_number(ds, "NumberOfFrames", 1))
    slope = _number(ds, "RescaleSlope", 1.0, frame)
    intercept = _number(ds, "RescaleIntercept", 0.0, frame)
    modality_lut = photometric in _GREY and "ModalityLUTSequence" in ds
    if rows <= 0 or cols <= 0 or frames <= 0 or allocated not in (1, 8, 16, 32, 64):
        raise UnreadableFileError(
            p,
            f"a DICOM header of {cols} x {rows} px, {frames} frame(s), {allocated} bits allocated",
        )
    if photometric in _GREY:
        if spp != 1:
            raise UnreadableFileError(p, f"{photometric} with {spp} samples/pixel")
        channels = 1
        if modality_lut:
            dtype = "uint8" if _lut_bits(ds, "ModalityLUTSequence") <= 8 else "uint16"
        elif allocated in (1, 8, 16) and not signed and slope == 1.0 and intercept == 0.0:
            dtype = "uint16" if allocated == 16 else "uint8"
        else:
            dtype = "float32" if stored <= 24 else "float64"
    elif photometric in _RGB_LIKE:
        if spp != 3 or allocated not in (8, 16) or signed:
            raise UnreadableFileError(
                p,
                f"{photometric} with {spp} samples/pixel of {allocated} bits"
                f"{' (signed)' if signed else ''}; imageform reads colour of 8 or 16 bits",
            )
        channels, dtype = 3, "uint16" if allocated == 16 else "uint8"
    elif photometric == "PALETTE COLOR":
        channels = 3
        dtype = "uint8" if _lut_bits(ds, "RedPaletteColorLookupTableDescriptor") <= 8 else "uint16"
    else:
        raise UnreadableFileError(
            p,
            f"a {photometric} DICOM image; imageform reads MONOCHROME1, "
            "MONOCHROME2, RGB, YBR_FULL(_422) and PALETTE COLOR",
        )
    meta = getattr(ds, "file_meta", None)
    syntax = meta.get("TransferSyntaxUID", None) if meta is not None else None
    function = str(_value(ds, "VOILUTFunction", frame) or "LINEAR").strip().lower()
    centers = _numbers(ds, "WindowCenter", frame)
    widths = _numbers(ds, "WindowWidth", frame)
    n = min(len(centers), len(widths))
    return DicomInfo(
        width=cols,
        height=rows,
        channels=channels,
        dtype=dtype,
        frames=frames,
        modality=str(ds.get("Modality", "") or ""),
        photometric=photometric,
        bits_allocated=allocated,
        bits_stored=stored,
        signed=signed,
        rescale_slope=slope,
        rescale_intercept=intercept,
        rescale_type=str(_value(ds, "RescaleType", frame) or ""),
        modality_lut=modality_lut,
        window_center=centers[:n],
        window_width=widths[:n],
        window_function=function,
        pixel_spacing_mm=_spacing(ds, "PixelSpacing", frame),
        imager_pixel_spacing_mm=_spacing(ds, "ImagerPixelSpacing", frame),
        transfer_syntax=str(getattr(syntax, "name", syntax) or "implicit VR little endian"),
        icc=icc_profile_of(ds) is not None,
    )


def icc_profile_of(ds: Any) -> bytes | None:
    """Return the ICC profile (0028,2000) of ``ds``, or of its first optical path (microscopy)."""
    icc = ds.get("ICCProfile", None)
    if not icc:
        paths = ds.get("OpticalPathSequence", None)
        icc = paths[0].get("ICCProfile", None) if paths else None
    return bytes(icc) if icc else None


def dicom_info(path: str | Path) -> DicomInfo:
    """Return what a DICOM file's header says: size, frames, modality, bits, window, spacing.

    Needs pydicom (the ``dicom`` extra). The pixel data is not read.

    Parameters
    ----------
    path : str or Path
        A DICOM file (Part 10, with or without the 128-byte preamble).

    Returns
    -------
    DicomInfo

    Raises
    ------
    InvalidInputError
        A missing, unreadable or non-DICOM file, or one that holds no image.
    MissingExtraError
        pydicom is not installed.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise InvalidInputError(f"expected a file path, got {type(path).__name__}")
    p = Path(path)
    if not p.is_file():
        raise InvalidInputError(f"input file {p} does not exist or is not a regular file")
    return header(p, open_dicom(p, pixels=False))


def _plugin_error(p: Path, ds: Any, exc: BaseException) -> InvalidInputError:
    """One line for compressed pixel data that pydicom cannot decode here, naming the remedy.

    A plugin is named where pydicom lacks one (its "missing dependencies"), or where the one it
    has does not take the data (Pillow and 12-bit or lossless JPEG); otherwise the data is
    corrupt, and pydicom's reason is given, its lines joined.
    """
    syntax = ds.file_meta.get("TransferSyntaxUID", None) if hasattr(ds, "file_meta") else None
    uid = str(syntax or "")
    name = str(getattr(syntax, "name", uid) or "its transfer syntax")
    why = " ".join(line.strip() for line in str(exc).splitlines() if line.strip())
    hint = next((h for prefix, h in _PLUGINS if uid.startswith(prefix)), None)
    if hint is not None and ("missing dependencies" in why or "does not support" in why):
        return UnreadableFileError(
            p, f"its pixel data is {name}, which pydicom decodes here only with a plugin: {hint}"
        )
    why = why[:300] or type(exc).__name__
    return UnreadableFileError(p, f"its {name} pixel data cannot be decoded ({why})")


def decode(
    p: Path,
    ds: Any,
    info: DicomInfo,
    frame: int,
    window: Any = None,
) -> np.ndarray:
    """Decode ``frame`` of ``ds`` (read from ``p``) as :func:`read_image` returns it, or windowed.

    ``window``: None (the modality values), ``"auto"`` or ``(center, width)`` (display values
    in [0, 1]).
    """
    _pydicom(p)  # the missing extra in one line, before pydicom.pixels is imported
    from pydicom.pixels import apply_color_lut, apply_modality_lut, pixel_array

    index = frame if info.frames > 1 else None
    try:
        with _quiet_lock, warnings.catch_warnings():
            warnings.simplefilter("ignore")
            arr = np.asarray(pixel_array(ds, index=index))
            if info.photometric == "PALETTE COLOR":
                arr = np.asarray(apply_color_lut(arr, ds))
            elif info.modality_lut:
                arr = np.asarray(apply_modality_lut(arr, ds))
    except MemoryError:
        raise UnreadableFileError(p, "not enough memory to decode it") from None
    except (RuntimeError, NotImplementedError) as exc:  # no plugin for its compression
        raise _plugin_error(p, ds, exc) from None
    except Exception as exc:  # truncated pixel data, a bad LUT, a bad value ...
        raise UnreadableFileError(
            p, f"its pixel data cannot be decoded ({_one_line(exc)})"
        ) from None
    if info.channels == 3 or info.photometric == "PALETTE COLOR":
        if window is not None:
            raise InvalidInputError(
                f"{p}: a {info.photometric} image has no VOI window (a window is for grey images)"
            )
        return np.ascontiguousarray(arr.astype(np.dtype(info.dtype), copy=False))
    if info.bits_allocated == 1:  # bilevel: 0/255, as a bilevel TIFF
        arr = arr.astype(np.uint8) * np.uint8(255)
        lo, hi = 0.0, 255.0
    else:
        lo, hi = _stored_range(info)
    if info.modality_lut:  # the LUT's entries: 0 to 2**bits - 1
        lo, hi = 0.0, float(2 ** _lut_bits(ds, "ModalityLUTSequence") - 1)
    values, lo, hi = _modality(arr, info, lo, hi)
    if window is None:
        if info.photometric == "MONOCHROME1":
            values = _invert(values, lo, hi)
        return np.ascontiguousarray(values)
    y = _apply_window(p, ds, info, values, window)
    if info.photometric == "MONOCHROME1":
        y = 1.0 - y
    return np.ascontiguousarray(y.astype(np.float32))


def _stored_range(info: DicomInfo) -> tuple[float, float]:
    bits = info.bits_stored
    if info.signed:
        return -float(2 ** (bits - 1)), float(2 ** (bits - 1) - 1)
    return 0.0, float(2**bits - 1)


def _modality(
    arr: np.ndarray, info: DicomInfo, lo: float, hi: float
) -> tuple[np.ndarray, float, float]:
    """Return the Modality LUT's output (the header's dtype) and the output's range."""
    dtype = np.dtype(info.dtype)
    if dtype.kind == "u":  # the stored values, or a Modality LUT Sequence's entries
        return arr.astype(dtype, copy=False), lo, hi
    m, b = info.rescale_slope, info.rescale_intercept
    values = (arr.astype(np.float64) * m + b).astype(dtype, copy=False)
    ends = (lo * m + b, hi * m + b)
    return values, min(ends), max(ends)


def _invert(values: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """MONOCHROME1 to MONOCHROME2's sense: ``lo + hi - v`` (integers stay integers)."""
    if values.dtype.kind == "u":
        top = np.asarray(hi, dtype=np.float64).astype(values.dtype)
        return np.asarray(top - np.minimum(values, top), dtype=values.dtype)
    return np.asarray((lo + hi) - values.astype(np.float64)).astype(values.dtype)


def _apply_window(p: Path, ds: Any, info: DicomInfo, values: np.ndarray, window: Any) -> Any:
    """Window the modality values to [0, 1]: the file's first window, a VOI LUT, or explicit."""
    if isinstance(window, str):
        if window.strip().lower() != "auto":
            raise InvalidInputError(
                f"expected window 'auto' or (center, width), got {window[:40]!r}"
            )
        if info.window_center:
            function = info.window_function
            if function not in DICOM_WINDOW_FUNCTIONS:
                function = "linear"
            c, w = info.window_center[0], info.window_width[0]
            return dicom_window(values, c, w, function=function)
        if "VOILUTSequence" in ds:
            from pydicom.pixels import apply_voi_lut

            top = float(2 ** _lut_bits(ds, "VOILUTSequence") - 1)
            with _quiet_lock, warnings.catch_warnings():
                warnings.simplefilter("ignore")
                out = np.asarray(apply_voi_lut(values, ds), dtype=np.float64)
            return np.clip(out / top, 0.0, 1.0)
        lo, hi = float(np.min(values)), float(np.max(values))  # the image's own range
        return dicom_window(values, (lo + hi) / 2, max(hi - lo, 1e-12), function="linear_exact")
    c, w = _center_width(window)
    return dicom_window(values, c, w)


def _center_width(window: Any) -> tuple[float, float]:
    try:
        c, w = (float(v) for v in window)
    except (TypeError, ValueError):
        raise InvalidInputError(
            f"expected window 'auto' or (center, width), got {describe(window)}"
        ) from None
    return c, w


def dicom_window(
    values: ArrayLike, center: float, width: float, *, function: str = "linear"
) -> np.ndarray:
    """Map values through a DICOM VOI window to [0, 1] (display values; 1 is white).

    The VOI LUT Functions of DICOM PS3.3, with output range ``ymin = 0``, ``ymax = 1``:

    - ``linear`` (C.11.2.1.2.1, the default): ``y = 0`` where
      ``x <= c - 0.5 - (w - 1) / 2``, ``y = 1`` where ``x > c - 0.5 + (w - 1) / 2``, else
      ``y = (x - (c - 0.5)) / (w - 1) + 0.5``; ``w >= 1`` (``w = 1`` is a threshold at
      ``c - 0.5``);
    - ``linear_exact`` (C.11.2.1.3.2): ``y = 0`` where ``x <= c - w / 2``, ``y = 1`` where
      ``x > c + w / 2``, else ``y = (x - c) / w + 0.5``; ``w > 0``;
    - ``sigmoid`` (C.11.2.1.3.1): ``y = 1 / (1 + exp(-4 (x - c) / w))``; ``w > 0``.

    Parameters
    ----------
    values : array_like
        Modality values (the output of the Modality LUT: what :func:`read_image` returns for a
        MONOCHROME2 DICOM image; Hounsfield units for CT).
    center, width : float
        Window Center (0028,1050) and Window Width (0028,1051), in the same units.
    function : {"linear", "linear_exact", "sigmoid"}
        VOI LUT Function (0028,1056).

    Returns
    -------
    ndarray of float64, the shape of ``values``

    Raises
    ------
    InvalidInputError
        Non-numeric or non-finite values, center or width; a width below 1 (``linear``) or
        not above 0.
    UnknownOptionError
        An unknown ``function``.

    Examples
    --------
    >>> dicom_window([-1000.0, 40.0, 1000.0], 40, 400).round(4).tolist()  # a CT soft-tissue window
    [0.0, 0.5013, 1.0]
    """
    function = check_option(function, DICOM_WINDOW_FUNCTIONS, "VOI LUT function")
    for name, v in (("center", center), ("width", width)):
        if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
            raise InvalidInputError(f"expected window {name} as a number, got {describe(v)}")
        if not math.isfinite(float(v)):
            raise InvalidInputError(f"expected a finite window {name}, got {v!r}")
    c, w = float(center), float(width)
    if function == "linear" and w < 1:
        raise InvalidInputError(f"expected window width >= 1 for the linear function, got {w:g}")
    if w <= 0:
        raise InvalidInputError(f"expected window width > 0, got {w:g}")
    x = np.asarray(values)
    if x.dtype.kind not in "biuf":
        raise InvalidInputError(f"expected numeric values to window, got {describe(values)}")
    x = x.astype(np.float64, copy=False)
    if not np.all(np.isfinite(x)):
        raise InvalidInputError("the values to window contain NaN or inf")
    if function == "sigmoid":
        with np.errstate(over="ignore"):  # far below the center: exp overflows, y is 0
            return np.asarray(1.0 / (1.0 + np.exp(-4.0 * (x - c) / w)))
    if function == "linear_exact":
        lo, hi = c - w / 2, c + w / 2
        y = (x - c) / w + 0.5
    else:
        lo, hi = c - 0.5 - (w - 1) / 2, c - 0.5 + (w - 1) / 2
        with np.errstate(divide="ignore", invalid="ignore"):  # w = 1: only the two ends
            y = (x - (c - 0.5)) / (w - 1) + 0.5 if w > 1 else np.zeros_like(x)
    y = np.where(x <= lo, 0.0, np.where(x > hi, 1.0, y))
    return np.asarray(y, dtype=np.float64)


def check_index(frame: object) -> int:
    """Return ``frame`` as an int, or refuse what is no integer in one line."""
    if isinstance(frame, bool) or not isinstance(frame, (int, np.integer)):
        raise InvalidInputError(f"expected frame as an integer, got {describe(frame)}")
    return int(frame)


def check_frame(p: Path, info: DicomInfo, frame: object) -> int:
    """Return ``frame`` as an index into the file's frames, or refuse it in one line."""
    k = check_index(frame)
    if not 0 <= k < info.frames:
        raise InvalidInputError(
            f"{p} has {info.frames} frame(s) (0 to {info.frames - 1}), no frame {k}"
        )
    return k


def multi_frame(p: Path, info: DicomInfo) -> InvalidInputError:
    """Return the one-line refusal of a multi-frame file by ``read_image`` (a TIFF stack's)."""
    return UnreadableFileError(
        p,
        f"a multi-frame DICOM of {info.frames} frames of {info.width} x "
        f"{info.height} px; read one with frame=N, 0 to {info.frames - 1} (imageform's "
        "commands: --frame N)",
    )


def read(
    p: Path,
    check: Callable[[DicomInfo], None],
    *,
    frame: object = None,
    window: Any = None,
    whole: bool = False,
) -> np.ndarray:
    """Read a DICOM image: ``check`` sees the header first (the pixel limit); see :func:`decode`.

    ``frame=None``: a single-frame file's image, or a tiled slide's total pixel matrix
    (:func:`assemble`); another multi-frame file is refused. ``whole``: a tiled slide is one
    image (``frame`` 0 or None, as ``read_image`` counts it), else ``frame`` is one tile.
    """
    head = open_dicom(p, pixels=False)
    info = header(p, head)  # the header alone, for the pixel limit
    tiles = slide_tiles(p, head)
    if tiles is not None and (frame is None or whole):
        k = 0 if frame is None else check_index(frame)
        if k:
            raise InvalidInputError(
                f"frame {k} is out of range: {p} holds one image (frame 0; a slide of "
                f"{info.frames} tiles)"
            )
        check(slide_info(info, tiles))  # the whole matrix against the pixel limit
        ds = open_dicom(p, pixels=True)
        if "PixelData" not in ds:
            raise UnreadableFileError(p, "the DICOM file has no pixel data")
        if (
            isinstance(window, str)
            and info.channels == 1
            and not info.window_center
            and "VOILUTSequence" not in ds
        ):  # "auto" without a window of its own: the whole slide's range, not each tile's
            values = assemble(p, ds, info, tiles).astype(np.float64)
            lo, hi = float(np.min(values)), float(np.max(values))
            y = dicom_window(values, (lo + hi) / 2, max(hi - lo, 1e-12), function="linear_exact")
            return np.ascontiguousarray(y.astype(np.float32))
        return assemble(p, ds, info, tiles, window)
    if frame is None and info.frames > 1:
        raise multi_frame(p, info)
    index = 0 if frame is None else check_frame(p, info, frame)
    check(info)  # before any pixel data is read
    ds = open_dicom(p, pixels=True)
    if "PixelData" not in ds and "FloatPixelData" not in ds and "DoubleFloatPixelData" not in ds:
        raise UnreadableFileError(p, "the DICOM file has no pixel data")
    if index:
        info = header(p, ds, index)  # that frame's rescale and window
    return decode(p, ds, info, index, window)


# ---------------------------------------------------------------- whole-slide images (tiles)


class SlideTiles(NamedTuple):
    """Where the frames of a tiled whole-slide DICOM image lie in its total pixel matrix.

    ``width`` and ``height``: the Total Pixel Matrix Columns and Rows; ``tile`` the frame's
    (columns, rows); ``origins`` each frame's top-left (row, column) in the matrix, from 0;
    ``organization``: ``"TILED_FULL"`` (the frames in row-major order of tiles, PS3.3
    C.7.6.17.3) or ``"TILED_SPARSE"`` (each frame's Plane Position (Slide), (0048,021E/021F)
    Column/Row Position In Total Image Pixel Matrix, from 1).
    """

    width: int
    height: int
    tile: tuple[int, int]
    origins: tuple[tuple[int, int], ...]
    organization: str


def slide_tiles(p: Path, ds: Any) -> SlideTiles | None:
    """Return the tile layout of a slide image (Modality SM with a total pixel matrix).

    None for anything else: a single-frame image, and a multi-frame one that states no layout
    (neither TILED_FULL nor the frames' plane positions), whose frames stay frames.
    A slide of several focal planes or optical paths is refused in one line (imageform
    reads one image: a plane's would need choosing), and so is a layout whose frames do not
    fill their places (a TILED_FULL count other than its tiles', a position off the matrix).
    """
    if str(ds.get("Modality", "") or "") != "SM" or "TotalPixelMatrixColumns" not in ds:
        return None
    try:
        width, height = int(ds.TotalPixelMatrixColumns), int(ds.TotalPixelMatrixRows)
        tw, th = int(ds.Columns), int(ds.Rows)
        frames = int(ds.get("NumberOfFrames", 1) or 1)
        planes = int(ds.get("TotalPixelMatrixFocalPlanes", 1) or 1)
        paths = int(ds.get("NumberOfOpticalPaths", 1) or 1)
    except (TypeError, ValueError, AttributeError) as exc:
        raise UnreadableFileError(p, f"corrupt slide header ({_one_line(exc)})") from None
    if frames == 1 and (width > tw or height > th or (width, height) == (tw, th)):
        return None  # one frame: the image, as read before
    # one frame larger than the matrix (OpenSlide's boxes_0.dcm: a 64 x 64 JPEG frame of a
    # 16 x 16 matrix) is a TILED_FULL slide of one tile, cut to the matrix
    if min(width, height, tw, th) < 1:
        raise UnreadableFileError(p, f"a slide of {width} x {height} px in tiles of {tw} x {th}")
    organization = str(ds.get("DimensionOrganizationType", "") or "").strip().upper()
    if planes > 1 or paths > 1:
        raise UnreadableFileError(
            p,
            f"a slide of {planes} focal plane(s) x {paths} optical path(s); imageform reads "
            "slides of one plane and one path",
        )
    across, down = -(-width // tw), -(-height // th)
    per_frame = ds.get("PerFrameFunctionalGroupsSequence", None)
    stated = per_frame is not None and any("PlanePositionSlideSequence" in i for i in per_frame)
    if organization != "TILED_FULL" and not stated:
        # no layout stated: frames of their own (pathml's small_dicom.dcm has its tiles
        # column by column, which row-major TILED_FULL would scramble), read by --frame
        return None
    if organization == "TILED_FULL":
        if frames != across * down:
            raise UnreadableFileError(
                p,
                f"a TILED_FULL slide of {frames} frames; its {width} x {height} px in tiles of "
                f"{tw} x {th} are {across * down}",
            )
        origins = tuple((r * th, c * tw) for r in range(down) for c in range(across))
        return SlideTiles(width, height, (tw, th), origins, "TILED_FULL")
    if per_frame is None or len(per_frame) != frames:
        raise UnreadableFileError(
            p,
            f"a {organization or 'tiled'} slide of {frames} frames without a plane position "
            "for each (Per-frame Functional Groups)",
        )
    found = []
    for k, item in enumerate(per_frame):
        pos = item.get("PlanePositionSlideSequence", None)
        try:
            col = int(pos[0].ColumnPositionInTotalImagePixelMatrix) - 1
            row = int(pos[0].RowPositionInTotalImagePixelMatrix) - 1
        except (TypeError, ValueError, AttributeError, IndexError):
            raise UnreadableFileError(p, f"frame {k} of the slide has no plane position") from None
        if not (0 <= row < height and 0 <= col < width):
            raise UnreadableFileError(
                p,
                f"frame {k} lies at row {row + 1}, column {col + 1}, off the {width} x "
                f"{height} matrix",
            )
        found.append((row, col))
    return SlideTiles(width, height, (tw, th), tuple(found), "TILED_SPARSE")


def _background(info: DicomInfo) -> float:
    """Return what a TILED_SPARSE slide's uncovered pixels hold.

    White for colour (bright-field glass), 0 for grey (a fluorescence channel's background).
    """
    if info.channels == 3:
        return float(np.iinfo(np.dtype(info.dtype)).max) if info.dtype.startswith("u") else 1.0
    return 0.0


def assemble(
    p: Path,
    ds: Any,
    info: DicomInfo,
    tiles: SlideTiles,
    window: Any = None,
) -> np.ndarray:
    """Return the slide's total pixel matrix, frame by frame.

    Each frame is decoded as :func:`decode` decodes it (its Modality LUT, its colour) and put at
    its origin (:func:`place`).
    """
    dtype = np.dtype("float32" if window is not None else info.dtype)
    return place(info, tiles, lambda k: decode(p, ds, info, k, window), dtype)


def place(
    info: DicomInfo,
    tiles: SlideTiles,
    frame_of: Callable[[int], np.ndarray],
    dtype: Any,
    rows: tuple[int, int] | None = None,
    cols: tuple[int, int] | None = None,
) -> np.ndarray:
    """Put the frames ``frame_of(k)`` that cover ``rows`` x ``cols`` of the matrix in place.

    A tile past the matrix's right or bottom edge is cut (TILED_FULL's last column and row);
    where TILED_SPARSE frames leave gaps, :func:`_background`; a later frame over an earlier
    one wins.
    """
    r0, r1 = rows or (0, tiles.height)
    c0, c1 = cols or (0, tiles.width)
    tw, th = tiles.tile
    shape = (r1 - r0, c1 - c0) + ((info.channels,) if info.channels > 1 else ())
    out = np.full(shape, _background(info), dtype=dtype)
    for k, (top, left) in enumerate(tiles.origins):
        a0, a1 = max(top, r0), min(top + th, r1)
        b0, b1 = max(left, c0), min(left + tw, c1)
        if a0 >= a1 or b0 >= b1:
            continue
        frame = np.asarray(frame_of(k)).reshape(th, tw, *shape[2:])
        out[a0 - r0 : a1 - r0, b0 - c0 : b1 - c0] = frame[
            a0 - top : a1 - top, b0 - left : b1 - left
        ]
    return out


class SlideLevel:
    """A tiled slide's total pixel matrix, read a region at a time (a Zarr-like array).

    ``shape`` (rows, columns, 3), ``chunks`` a tile's, ``dtype``; ``a[r0:r1, c0:c1]``
    decodes the frames that cover it, each read from the file alone (pydicom's
    ``pixel_array(path, index=k)``: the frame's bytes, not the whole Pixel Data), as RGB.
    """

    def __init__(self, p: Path) -> None:
        head = open_dicom(p, pixels=False)
        info = header(p, head)
        tiles = slide_tiles(p, head)
        if tiles is None and info.frames > 1:  # frames of their own: no one image to read
            raise multi_frame(p, info)
        if tiles is None:
            tiles = SlideTiles(info.width, info.height, (info.width, info.height), ((0, 0),), "")
        self.path, self.info, self.tiles = p, info, tiles
        c = (info.channels,) if info.channels > 1 else ()
        self.shape = (tiles.height, tiles.width, *c)
        self.chunks = (tiles.tile[1], tiles.tile[0], *c)
        self.dtype, self.ndim = np.dtype(info.dtype), len(self.shape)

    def _frame(self, k: int) -> np.ndarray:
        from pydicom.pixels import pixel_array

        index = k if self.info.frames > 1 else None
        try:
            with _quiet_lock, warnings.catch_warnings():
                warnings.simplefilter("ignore")
                return np.asarray(pixel_array(str(self.path), index=index))
        except (RuntimeError, NotImplementedError) as exc:  # no plugin for its compression
            raise _plugin_error(self.path, open_dicom(self.path, pixels=False), exc) from None

    def __getitem__(self, key: Any) -> np.ndarray:
        if not isinstance(key, tuple):
            key = (key,)
        key = key + (slice(None),) * (self.ndim - len(key))
        r0, r1, rs = key[0].indices(self.shape[0])
        c0, c1, cs = key[1].indices(self.shape[1])
        a = place(self.info, self.tiles, self._frame, self.dtype, (r0, max(r1, r0)),
                  (c0, max(c1, c0)))  # fmt: skip
        return a[(slice(None, None, rs), slice(None, None, cs), *key[2:])]


#: The attributes :func:`slide_levels` reads of each file in a slide's folder.
_LEVEL_TAGS = ("SeriesInstanceUID", "PyramidUID", "Modality", "ImageType",
               "TotalPixelMatrixColumns", "TotalPixelMatrixRows", "SOPInstanceUID")  # fmt: skip


def slide_levels(p: Path) -> list[tuple[Path, int, int]]:
    """Return the pyramid of a slide image: ``p`` and the smaller levels of its series.

    A DICOM slide's levels are files of one series (Series Instance UID, and Pyramid UID
    where given) in one folder, each a VOLUME image (Image Type's third value; labels,
    overviews and thumbnails are not levels). The file given is level 0, as
    :func:`read_image` reads it; the files of its series with a smaller total pixel matrix
    follow, largest first, as ``(path, width, height)``.
    """
    with _quiet_lock, warnings.catch_warnings():  # pydicom's notes on odd UIDs: not our lines
        warnings.simplefilter("ignore")
        return _slide_levels(p)


def _slide_levels(p: Path) -> list[tuple[Path, int, int]]:
    pydicom = _pydicom(p)

    def tags(f: Path) -> Any:
        return pydicom.dcmread(f, stop_before_pixels=True, specific_tags=list(_LEVEL_TAGS))

    me = tags(p)

    def key(ds: Any) -> tuple[str, str]:
        return str(ds.get("SeriesInstanceUID", "") or ""), str(ds.get("PyramidUID", "") or "")

    def size(ds: Any) -> tuple[int, int] | None:
        try:
            w, h = int(ds.TotalPixelMatrixColumns), int(ds.TotalPixelMatrixRows)
        except (AttributeError, TypeError, ValueError):
            return None
        kind = [str(v).upper() for v in (ds.get("ImageType", None) or [])]
        ok = str(ds.get("Modality", "") or "") == "SM" and (len(kind) < 3 or kind[2] == "VOLUME")
        return (w, h) if ok else None

    top = size(me)
    if top is None or not key(me)[0]:
        return [(p, *top)] if top is not None else []
    levels = [(p, *top)]
    for f in sorted(p.parent.iterdir()):
        if f == p or not f.is_file():
            continue
        try:
            with f.open("rb") as fh:
                if fh.read(132)[128:132] != b"DICM":
                    continue
            ds = tags(f)
        except Exception:  # not a DICOM file we can read: not a level
            continue
        s = size(ds)
        same = str(ds.get("SOPInstanceUID", "")) == str(me.get("SOPInstanceUID", ""))
        known = any((w, h) == s for _, w, h in levels)  # one file a level (another plane ...)
        smaller = s is not None and s[0] < top[0] and s[1] <= top[1]
        if smaller and key(ds) == key(me) and not same and not known:
            levels.append((f, *s))  # type: ignore[misc]
    return [levels[0], *sorted(levels[1:], key=lambda t: -t[1])]


def slide_info(info: DicomInfo, tiles: SlideTiles) -> DicomInfo:
    """``info`` of a tiled slide as its whole image: the total pixel matrix, one frame."""
    return info._replace(width=tiles.width, height=tiles.height, frames=1)
