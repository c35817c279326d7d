"""Raw files in and out: DNG writing, LibRaw reading and imageform's own development.

DNG written with tifffile, any raw LibRaw reads (through rawpy, the optional
``imageform[raw]`` extra), and imageform's own development of a raw file, step by step
(docs/raw.md).

- :func:`write_dng`: a Bayer mosaic as a DNG 1.4 file (one uncompressed 16-bit CFA IFD,
  PhotometricInterpretation 32803, with CFARepeatPatternDim/CFAPattern, BlackLevel,
  WhiteLevel, ColorMatrix1, AsShotNeutral, CalibrationIlluminant1, UniqueCameraModel).
  Adobe, *Digital Negative (DNG) Specification*, version 1.4.0.0 (2012), chapter 4.
- :func:`read_raw`: the mosaic, black and white levels, CFA pattern, as-shot white balance
  and colour matrices of a raw file (DNG, CR2, NEF, ARW, ...), as a :class:`RawImage`.
- :func:`develop`: linearise, white balance, demosaic
  (:func:`imageform.sensor.demosaic`), camera RGB to XYZ from the colour matrix, chromatic
  adaptation to the output space's white, encoding; every stage kept in a
  :class:`Development`.
"""

from __future__ import annotations

import functools
import importlib.util
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np

from imageform import _deprecate
from imageform._files import RAW_SUFFIXES, atomic_write, check_writable, git_lfs_pointer
from imageform._typing import ArrayLike
from imageform._validate import describe
from imageform.errors import InvalidInputError, UnreadableFileError

__all__ = [
    "CALIBRATION_ILLUMINANTS",
    "RAW_MAX_PIXELS",
    "RAW_SUFFIXES",
    "Development",
    "RawImage",
    "develop",
    "read_raw",
    "write_dng",
]

#: The default pixel limit of :func:`read_raw` (the header's raw size, margins included):
#: above the 151 Mpx of the largest medium-format sensors (Phase One IQ4), so every camera's
#: raw reads without ``IMAGEFORM_MAX_PIXELS``.
RAW_MAX_PIXELS = 200_000_000

#: EXIF LightSource codes of the DNG CalibrationIlluminant tags (EXIF 2.3, tag 0x9208) that
#: name a CIE illuminant imageform knows, by name.
CALIBRATION_ILLUMINANTS: dict[str, int] = {
    "A": 17,
    "B": 18,
    "C": 19,
    "D55": 20,
    "D65": 21,
    "D75": 22,
    "D50": 23,
}

# TIFF/DNG tag codes (DNG specification 1.4.0.0, chapter 4; TIFF/EP for the CFA tags).
_DNG_VERSION = 50706
_DNG_BACKWARD_VERSION = 50707
_UNIQUE_CAMERA_MODEL = 50708
_CFA_REPEAT_PATTERN_DIM = 33421
_CFA_PATTERN = 33422
_CFA_PLANE_COLOR = 50710
_CFA_LAYOUT = 50711
_LINEARIZATION_TABLE = 50712
_BLACK_LEVEL_DELTA_H = 50715
_BLACK_LEVEL_DELTA_V = 50716
_ACTIVE_AREA = 50829
_BLACK_LEVEL_REPEAT_DIM = 50713
_BLACK_LEVEL = 50714
_WHITE_LEVEL = 50717
_COLOR_MATRIX_1 = 50721
_COLOR_MATRIX_2 = 50722
_CAMERA_CALIBRATION_1 = 50723
_CAMERA_CALIBRATION_2 = 50724
_ANALOG_BALANCE = 50727
_AS_SHOT_NEUTRAL = 50728
_AS_SHOT_WHITE_XY = 50729
_BASELINE_EXPOSURE = 50730
_OPCODE_LIST_3 = 51022
_CALIBRATION_ILLUMINANT_1 = 50778
_CALIBRATION_ILLUMINANT_2 = 50779
_PHOTOMETRIC_CFA = 32803
# TIFF field types
_BYTE, _ASCII, _SHORT, _LONG, _RATIONAL, _SRATIONAL = 1, 2, 3, 4, 5, 10
#: Denominator of the rationals written (ColorMatrix1, AsShotNeutral): 1e-6 resolution.
_DEN = 1_000_000


def _rawpy() -> Any:
    from imageform._optional import require

    return require("rawpy", what="reading raw files (LibRaw)")


def _rationals(values: np.ndarray, what: str, *, signed: bool) -> list[int]:
    out: list[int] = []
    lim = (2**31 - 1) if signed else (2**32 - 1)
    for v in np.ravel(values):
        scaled = float(v) * _DEN
        if not math.isfinite(scaled) or abs(scaled) > lim + 1:  # round() of inf overflows
            raise InvalidInputError(f"expected {what} to fit a DNG rational, got {float(v)!r}")
        num = round(scaled)
        if abs(num) > lim or (not signed and num < 0):
            raise InvalidInputError(f"expected {what} to fit a DNG rational, got {float(v)!r}")
        out += [int(num), _DEN]
    return out


def _vignette_opcode_list(params: ArrayLike) -> bytes:
    """Return an OpcodeList holding one FixVignetteRadial opcode (big-endian, DNG 1.3.0.0)."""
    import struct

    try:
        v = np.asarray(params, dtype=np.float64)
    except (TypeError, ValueError):
        v = np.zeros(0)
    if v.shape != (7,) or not np.all(np.isfinite(v)) or not np.all((v[5:] >= 0) & (v[5:] <= 1)):
        raise InvalidInputError(
            "expected fix_vignette_radial as 7 finite numbers k0..k4, cx, cy (cx, cy in "
            f"[0, 1]), got {describe(params)}"
        )
    body = struct.pack(">7d", *v.tolist())
    # count, then the opcode: id 3, its DNG version 1.3.0.0, flags 0, the parameters' size
    return struct.pack(">I4I", 1, 3, 0x01030000, 0, len(body)) + body


def _cfa_indices(pattern: str) -> tuple[int, int, int, int]:
    return tuple("RGB".index(c) for c in pattern)  # type: ignore[return-value]


def write_dng(
    path: str | Path,
    mosaic: ArrayLike,
    *,
    cfa_pattern: str = "RGGB",
    black_level: float = 0.0,
    white_level: float | None = None,
    color_matrix: ArrayLike,
    as_shot_neutral: ArrayLike = (1.0, 1.0, 1.0),
    calibration_illuminant: str = "D65",
    camera_model: str = "imageform simulated camera",
    baseline_exposure_ev: float = 0.0,
    fix_vignette_radial: ArrayLike | None = None,
) -> Path:
    r"""Write a Bayer mosaic as a DNG file that raw developers open.

    Raw developers such as LibRaw, darktable, RawTherapee and Adobe Camera Raw.

    One IFD (NewSubfileType 0) holding the raw CFA image, uncompressed, 16 bits per sample,
    PhotometricInterpretation 32803 (CFA), DNGVersion 1.4.0.0, DNGBackwardVersion 1.1.0.0,
    and the colour tags of the DNG specification 1.4.0.0, chapter 4:

    - CFARepeatPatternDim (2, 2) and CFAPattern (0 = red, 1 = green, 2 = blue);
    - BlackLevel (one value for every photosite) and WhiteLevel;
    - ColorMatrix1: XYZ to camera RGB under CalibrationIlluminant1 (SRATIONAL, stored to
      1e-6), :math:`\mathbf c = C\,\mathbf{XYZ}`;
    - AsShotNeutral: the camera RGB of a neutral in the scene (white balance gains are its
      reciprocals);
    - BaselineExposure (when not 0): how many stops a developer should brighten the
      linear rendering, :math:`2^{EV}` (Adobe's readers apply it; LibRaw does not;
      ``develop(baseline_exposure=True)`` does);
    - OpcodeList3 with one FixVignetteRadial opcode (DNG 1.3, opcode 3), when given: the
      lens-shading correction a developer applies to the demosaiced camera RGB,
      :math:`g = 1 + \sum_{i=0}^{4} k_i r^{2(i+1)}` with :math:`r` the distance from the
      optical centre over the distance to the farthest corner (:func:`develop` and Adobe's
      readers apply it; LibRaw does not);
    - UniqueCameraModel.

    Parameters
    ----------
    path : str or Path
        The file to write (``.dng``).
    mosaic : array_like (H, W)
        Integer digital numbers in [0, 65535], H and W even.
    cfa_pattern : str
        The 2x2 Bayer tile, read row by row (``"RGGB"``, ``"BGGR"``, ``"GRBG"``, ``"GBRG"``).
    black_level, white_level : float
        The code of no light and the largest code (default: the mosaic's dtype maximum for
        uint16 data, else 65535).
    color_matrix : array_like (3, 3)
        XYZ (Y = 1 for the illuminant's white) to camera RGB, as DNG's ColorMatrix1.
    as_shot_neutral : array_like (3,)
        Camera RGB of a scene neutral (any scale; written as is, each in (0, 1e3)).
    calibration_illuminant : str
        The illuminant of ``color_matrix``: a name of :data:`CALIBRATION_ILLUMINANTS`.
    camera_model : str
        UniqueCameraModel.
    baseline_exposure_ev : float
        BaselineExposure in stops (EV), a finite number in [-16, 16]; 0 writes no tag.
    fix_vignette_radial : array_like (7,), optional
        The FixVignetteRadial opcode's parameters as the DNG stores them: ``k0..k4`` and the
        optical centre ``(cx, cy)`` in fractions of the width and height (each in [0, 1]).

    Returns
    -------
    Path
        The file written.
    """
    import tifffile

    from imageform.sensor import cfa_pattern as _pattern

    out = check_writable(path, "path")
    pattern = _pattern(cfa_pattern)
    arr = np.asarray(mosaic)
    if (
        arr.ndim != 2
        or arr.shape[0] < 2
        or arr.shape[1] < 2
        or arr.shape[0] % 2
        or arr.shape[1] % 2
    ):
        raise InvalidInputError(
            f"expected mosaic as an (H, W) array, H and W even, got {describe(arr)}"
        )
    if arr.dtype.kind not in "ui" and not (
        arr.dtype.kind == "f" and np.all(np.isfinite(arr)) and np.all(arr == np.round(arr))
    ):
        raise InvalidInputError(f"expected mosaic of integer digital numbers, got {describe(arr)}")
    if arr.size and (arr.min() < 0 or arr.max() > 65535):
        raise InvalidInputError(f"expected mosaic values in [0, 65535], got {describe(arr)}")
    data = arr.astype(np.uint16)
    if white_level is None:
        white_level = 65535.0
    white = float(white_level)
    black = float(black_level)
    if not (0 <= black < white <= 65535) or black != round(black) or white != round(white):
        raise InvalidInputError(
            "expected integer black_level < white_level in [0, 65535], "
            f"got {black_level!r} and {white_level!r}"
        )
    cm = np.asarray(color_matrix, dtype=np.float64)
    if cm.shape != (3, 3) or not np.all(np.isfinite(cm)) or abs(np.linalg.det(cm)) < 1e-12:
        raise InvalidInputError(
            f"expected color_matrix as an invertible (3, 3) matrix, got {describe(cm)}"
        )
    neutral = np.asarray(as_shot_neutral, dtype=np.float64)
    if neutral.shape != (3,) or not np.all(np.isfinite(neutral)) or np.any(neutral <= 0):
        raise InvalidInputError(
            f"expected as_shot_neutral as 3 positive numbers, got {describe(neutral)}"
        )
    ill = str(calibration_illuminant).upper()
    if ill not in CALIBRATION_ILLUMINANTS:
        raise InvalidInputError(
            f"unknown calibration_illuminant {calibration_illuminant!r}; "
            f"valid: {', '.join(CALIBRATION_ILLUMINANTS)}"
        )
    if not isinstance(camera_model, str) or not camera_model or not camera_model.isascii():
        raise InvalidInputError(
            f"expected camera_model as a non-empty ASCII string, got {describe(camera_model)}"
        )
    try:
        ev = float(baseline_exposure_ev)
    except (TypeError, ValueError):
        ev = math.nan
    if isinstance(baseline_exposure_ev, bool) or not (math.isfinite(ev) and abs(ev) <= 16):
        raise InvalidInputError(
            "expected baseline_exposure_ev as a number of stops in [-16, 16], got "
            f"{describe(baseline_exposure_ev)}"
        )
    tags = [
        (_DNG_VERSION, _BYTE, 4, (1, 4, 0, 0), True),
        (_DNG_BACKWARD_VERSION, _BYTE, 4, (1, 1, 0, 0), True),
        (_UNIQUE_CAMERA_MODEL, _ASCII, 0, camera_model, True),
        (_CFA_REPEAT_PATTERN_DIM, _SHORT, 2, (2, 2), True),
        (_CFA_PATTERN, _BYTE, 4, _cfa_indices(pattern), True),
        (_CFA_PLANE_COLOR, _BYTE, 3, (0, 1, 2), True),
        (_CFA_LAYOUT, _SHORT, 1, 1, True),
        (_BLACK_LEVEL_REPEAT_DIM, _SHORT, 2, (1, 1), True),
        (_BLACK_LEVEL, _LONG, 1, int(black), True),
        (_WHITE_LEVEL, _LONG, 1, int(white), True),
        (_COLOR_MATRIX_1, _SRATIONAL, 9, _rationals(cm, "color_matrix", signed=True), True),
        (
            _AS_SHOT_NEUTRAL,
            _RATIONAL,
            3,
            _rationals(neutral, "as_shot_neutral", signed=False),
            True,
        ),
        (_CALIBRATION_ILLUMINANT_1, _SHORT, 1, CALIBRATION_ILLUMINANTS[ill], True),
    ]
    if ev != 0.0:
        rational = _rationals(np.array([ev]), "baseline_exposure_ev", signed=True)
        tags.append((_BASELINE_EXPOSURE, _SRATIONAL, 1, rational, True))
    if fix_vignette_radial is not None:
        opcodes = _vignette_opcode_list(fix_vignette_radial)
        tags.append((_OPCODE_LIST_3, 7, len(opcodes), opcodes, True))
    atomic_write(
        out,
        lambda tmp: tifffile.imwrite(
            tmp,
            data,
            photometric=_PHOTOMETRIC_CFA,
            subfiletype=0,
            extratags=tags,
            metadata=None,
            software="imageform",
        ),
    )
    return out


@dataclass(frozen=True)
class RawImage:
    """A raw file's sensor data and colour description (:func:`read_raw`).

    Attributes
    ----------
    mosaic : ndarray (H, W) or (H, W, 3) uint16
        The visible Bayer mosaic in digital numbers, in the sensor's orientation; for a
        linear raw (a DNG with PhotometricInterpretation LinearRaw, as phones and
        converters write them: already demosaiced) the three channels of every pixel; for
        a monochrome sensor (no colour filters: Leica Monochrom, scientific cameras) its
        one grey value a pixel, (H, W) with ``cfa_pattern`` None.
    black_level : ndarray (2, 2), (3,) or (1,)
        The black level of each photosite of the 2x2 tile (the mosaic's ``[0:2, 0:2]``);
        of each channel for a linear raw; the one level of a monochrome sensor.
    white_level : float
        The largest code (saturation).
    cfa_pattern : str or None
        The 2x2 tile read row by row (``"RGGB"``, ...); None for a linear raw and a
        monochrome sensor (:attr:`monochrome` tells them apart).
    white_balance : ndarray (3,) or None
        The as-shot white balance gains (R, G, B) with green 1 (None if the file has none).
    xyz_to_camera : ndarray (3, 3) or None
        The camera's colour matrix, XYZ to camera RGB (DNG ColorMatrix, LibRaw's
        ``rgb_xyz_matrix``), under ``calibration_illuminant``.
    camera_to_srgb : ndarray (3, 3)
        LibRaw's ``rgb_cam``: white-balanced camera RGB to linear sRGB.
    calibration_illuminant : str or None
        The illuminant of ``xyz_to_camera`` (``"D65"`` where the file does not say).
    metadata : dict
        What else is known: ``raw_type``, ``color_desc``, ``daylight_white_balance``,
        ``camera_model`` (DNG UniqueCameraModel), ``path``; ``baseline_exposure_ev`` (a
        DNG's BaselineExposure, stops) where the file has one.
    orientation : int
        How the image is turned for display, as LibRaw's ``sizes.flip`` (from the EXIF/TIFF
        Orientation tag): 0 none, 3 half a turn, 5 a quarter turn anticlockwise, 6 a
        quarter turn clockwise; bit 4 transposes, then bit 2 flips rows and bit 1 columns.
        :func:`develop` applies it as LibRaw's ``postprocess`` does.
    """

    mosaic: np.ndarray
    black_level: np.ndarray
    white_level: float
    cfa_pattern: str | None
    white_balance: np.ndarray | None
    xyz_to_camera: np.ndarray | None
    camera_to_srgb: np.ndarray
    calibration_illuminant: str | None
    metadata: dict[str, Any] = field(default_factory=dict)
    orientation: int = 0

    @property
    def monochrome(self) -> bool:
        """True for a monochrome sensor: a 2-D mosaic with no colour filter array."""
        return self.cfa_pattern is None and np.ndim(self.mosaic) == 2


#: The first four bytes of a TIFF (and BigTIFF) file, little- and big-endian.
_TIFF_MAGIC = (b"II*\x00", b"MM\x00*", b"II+\x00", b"MM\x00+")
#: ``_raw_page_opcodes`` of a file with no opcode to apply.
_NO_OPCODES: Any = ([], [], [], [], (0, 0), None, None, 0)
#: Bytes a raw may lack of its image data's end before it is refused unread (more than this
#: and 1 % of the data): fewer are left to LibRaw, which reads some files whose last strip's
#: count runs past the end.
_CUT_MARGIN = 65536


def _dng_header(path: Path, *, opcodes: bool = True) -> tuple[dict[str, Any], Any, int]:
    """Return a DNG's colour tags, opcodes and data's end, in one read.

    :func:`_colour_tags` (IFD 0), :func:`_raw_page_opcodes` and :func:`_page_data_end`;
    ``({}, _NO_OPCODES, 0)`` for a file that is not TIFF-based; ``opcodes=False`` reads the
    colour tags and the data's end only. The IFDs are read by
    :func:`imageform.io._tiff_ifd.read_header` (the tags used, nothing else: a fifth to a
    third of tifffile's time), with tifffile's values; a header it does not take exactly as
    tifffile does (BigTIFF, an odd tag) is read with tifffile.
    """
    from imageform.io._tiff_ifd import Unusual, read_header

    try:
        with path.open("rb") as f:  # a DNG is a TIFF: RW2, ORF, ... are left alone (tifffile
            if f.read(4) not in _TIFF_MAGIC:  # would warn on their own magic numbers)
                return {}, _NO_OPCODES, 0
        try:
            first = read_header(path)
        except Unusual:
            import tifffile

            with tifffile.TiffFile(path) as tf:
                return _header_of(tf, opcodes=opcodes)
        return _header_of(_Header([first]), opcodes=opcodes)
    except Exception:  # not a TIFF-based raw: nothing more to read
        return {}, _NO_OPCODES, 0


@dataclass(frozen=True)
class _Header:
    """IFD 0 as :func:`imageform.io._tiff_ifd.read_header` reads it, where tifffile's are."""

    pages: list[Any]


def _header_of(tf: Any, *, opcodes: bool) -> tuple[dict[str, Any], Any, int]:
    """:func:`_dng_header` of an open file (tifffile's, or a :class:`_Header`)."""
    tags = tf.pages[0].tags
    colour = _colour_tags(tags)
    end = _page_data_end(tf)
    if not opcodes or _DNG_VERSION not in tags:
        return colour, _NO_OPCODES, end
    try:
        return colour, _raw_page_opcodes(tf), end
    except Exception:  # an IFD that cannot be read: no opcodes
        return colour, _NO_OPCODES, end


def _colour_tags(tags: Any) -> dict[str, Any]:
    """Return the colour tags and UniqueCameraModel of one IFD's tifffile tags.

    ColorMatrix1/2, CameraCalibration1/2, CalibrationIlluminant1/2, AnalogBalance and
    AsShotWhiteXY and BaselineExposure, by short names (``cm1``, ``cc1``, ``ill1``, ``ab``,
    ``white_xy``, ``baseline_ev``, ...).
    """
    found: dict[str, Any] = {}
    for code, name in (
        (_COLOR_MATRIX_1, "cm1"),
        (_COLOR_MATRIX_2, "cm2"),
        (_CAMERA_CALIBRATION_1, "cc1"),
        (_CAMERA_CALIBRATION_2, "cc2"),
        (_CALIBRATION_ILLUMINANT_1, "ill1"),
        (_CALIBRATION_ILLUMINANT_2, "ill2"),
        (_ANALOG_BALANCE, "ab"),
        (_AS_SHOT_WHITE_XY, "white_xy"),
        (_BASELINE_EXPOSURE, "baseline_ev"),
        (_UNIQUE_CAMERA_MODEL, "model"),
    ):
        if code in tags:
            tag = tags[code]
            found[name] = tag.value if name in ("model", "ill1", "ill2") else _tag_reals(tag)
    return found


def _baseline_ev(tags: dict[str, Any], meta: dict[str, Any]) -> None:
    """Put a DNG's BaselineExposure (stops) in ``meta["baseline_exposure_ev"]`` when finite."""
    ev = np.ravel(np.asarray(tags.get("baseline_ev", ()), np.float64))
    if ev.size and np.isfinite(ev[0]):
        meta["baseline_exposure_ev"] = float(ev[0])


def _tag_reals(tag: Any) -> np.ndarray:
    """Return a tifffile tag's values as floats.

    A (S)RATIONAL's numerator/denominator pairs divided; any other type's values as they are.
    """
    v = np.asarray(tag.value if not isinstance(tag.value, bytes) else list(tag.value))
    v = v.ravel().astype(np.float64)
    if int(tag.dtype) in (5, 10) and v.size % 2 == 0:  # RATIONAL, SRATIONAL
        den = v[1::2]
        return np.divide(v[0::2], den, out=np.zeros(den.size), where=den != 0)
    return v


def _matrix(value: Any) -> np.ndarray:
    return np.asarray(value, dtype=np.float64).ravel()[:9].reshape(3, 3)


#: EXIF LightSource codes LibRaw takes as daylight when it picks a DNG's colour matrix:
#: Daylight, D55, D75, D50 and Flash (after D65 itself).
_DAYLIGHT_CODES = (1, 20, 22, 23, 4)


def _dng_colour(tags: dict[str, Any]) -> tuple[np.ndarray | None, int]:
    r"""Return a DNG's XYZ-to-camera matrix and its illuminant's code, as LibRaw picks them.

    With two matrices and both illuminants given, the one of D65, else the first of a
    daylight kind (:data:`_DAYLIGHT_CODES`); otherwise the last matrix in the file
    (ColorMatrix2 when there are two). The matrix is :math:`\mathrm{diag}(AB)\,CC\,CM`:
    the AnalogBalance, the CameraCalibration of the same index and the ColorMatrix, as the
    DNG specification (1.4, chapter 6) composes them and LibRaw's ``identify`` does; where no
    matrix is picked by illuminant, LibRaw (dcraw's ``parse_tiff_ifd``) also scales the
    columns by AsShotWhiteXY over D65's white, and so does this.
    """
    cms = {i: _matrix(tags[f"cm{i}"]) for i in (1, 2) if f"cm{i}" in tags}
    if not cms:
        return None, 0
    ills = {i: int(np.ravel(tags.get(f"ill{i}", 0))[0]) for i in (1, 2)}
    pick = None
    if len(cms) == 2 and ills[1] > 0 and ills[2] > 0:
        pick = next((i for i in (1, 2) if ills[i] == 21), None)
        if pick is None:
            pick = next((i for i in (1, 2) if ills[i] in _DAYLIGHT_CODES), None)
    by_illuminant = pick is not None
    if pick is None:
        pick = max(cms)
    cc = np.eye(3)
    if by_illuminant:
        if f"cc{pick}" in tags:
            cc = _matrix(tags[f"cc{pick}"])
    else:  # the last calibration in the file, as the TIFF parser keeps it
        for i in (1, 2):
            if f"cc{i}" in tags:
                cc = _matrix(tags[f"cc{i}"])
    ab = np.asarray(tags["ab"], np.float64)[:3] if "ab" in tags else np.ones(3)
    m = np.diag(ab) @ cc @ cms[pick]
    if not by_illuminant and "white_xy" in tags:
        x, y = np.asarray(tags["white_xy"], np.float64)[:2]
        d65 = np.array([0.950456, 1.0, 1.088754])  # LibRaw_constants::d65_white
        m = m * (np.array([x, y, 1.0 - x - y]) / d65)[None, :]
    return m, ills[pick]


def read_raw(path: str | Path, *, max_pixels: int | None = None, opcodes: bool = True) -> RawImage:
    """Read a raw file with LibRaw (rawpy): DNG, CR2, CR3, NEF, ARW, RAF, ORF, RW2, ...

    Needs the optional extra ``imageform[raw]`` (rawpy), except for DNGs, which are read with
    tifffile when rawpy is not installed or LibRaw cannot decode them (JPEG XL, ...), to the
    values LibRaw gives (:func:`_read_dng`). Bayer sensors with a 2x2 RGB tile give their
    mosaic; linear (demosaiced) raws their three channels; monochrome sensors their one;
    Fujifilm's X-Trans is demosaiced by LibRaw's linear interpolation and given as a linear
    raw (``metadata["xtrans"]``). Four-colour sensors are refused.

    Parameters
    ----------
    path : str or Path
        The raw file.
    max_pixels : int, optional
        Refuse a file whose header declares more pixels than this (before anything is
        decoded); default ``IMAGEFORM_MAX_PIXELS`` when set, else :data:`RAW_MAX_PIXELS`
        (200 Mpx: medium-format sensors reach 151 Mpx, and a raw header counts the masked
        margins too; images have 100 Mpx, :func:`imageform.io.max_pixels`).
    opcodes : bool
        Apply a DNG's GainMap opcodes (its OpcodeList2: the lens-shading correction phones
        write, one map per photosite of the tile) to the mosaic, as the DNG specification
        asks and Adobe's readers do (LibRaw does not: False gives LibRaw's values), with
        the list's FixVignetteRadial, Scale/DeltaPerRow/Column and MapPolynomial, and
        OpcodeList1's FixBadPixelsConstant. The WarpRectilinear (lens distortion),
        FixVignetteRadial and GainMap opcodes of its OpcodeList3 are kept in
        ``metadata["opcodes_stage3"]`` for :func:`develop`, which applies them to the
        demosaiced camera RGB. A lossy DNG's MapPolynomials are its samples' decoding,
        applied when decoded (by LibRaw too), not again: ``metadata["opcodes_decoded"]``
        names them. Other opcodes are not applied: ``metadata["opcodes_skipped"]`` names
        them; ``metadata["opcodes_applied"]`` counts the GainMaps and
        ``metadata["opcodes_applied_other"]`` names the other opcodes applied.

    Returns
    -------
    RawImage
        The visible mosaic, levels, CFA pattern, as-shot white balance and colour matrices.
        For a DNG, ``xyz_to_camera`` is its colour matrix as LibRaw picks and composes it
        (:func:`_dng_colour`); for other files LibRaw's ``rgb_xyz_matrix``.

    Raises
    ------
    InvalidInputError
        Missing file, a file LibRaw cannot read, or a non-Bayer sensor.
    imageform.errors.ImageformError
        rawpy is not installed (the message names ``pip install "imageform[raw]"``).
    """
    raw, found = _read_raw(path, max_pixels, opcodes=opcodes)
    return _with_opcodes(raw, found) if opcodes else raw


def _with_opcodes(raw: RawImage, found: Any) -> RawImage:
    """Return ``raw`` with its DNG's OpcodeList2 applied (:mod:`imageform.io._dng_opcodes`).

    ``found`` is :func:`_raw_page_opcodes` of the file. ``metadata["opcodes_applied"]``
    counts the GainMaps, ``["opcodes_applied_other"]`` names the other opcodes applied
    (``"OpcodeList2:ScalePerRow"``), ``["opcodes_decoded"]`` the MapPolynomials a lossy
    DNG's samples were decoded with (:func:`imageform.io._dng_opcodes.lossy_dng_curves`).
    The OpcodeList3 opcodes it can apply (after demosaicing) are kept for :func:`develop`
    in ``metadata["opcodes_stage3"]`` with ``metadata["opcodes_area"]`` (offset, (H, W)).
    """
    import dataclasses

    from imageform.io._dng_opcodes import (
        apply_stage2,
        fix_bad_pixels_constant,
        stage2_name,
        stage3_name,
    )

    stage1, maps, stage3, skipped, offset, area, origin, decoded = found
    if not stage1 and not maps and not stage3 and not skipped and not decoded:
        return raw
    meta = dict(raw.metadata)
    meta["opcodes_skipped"] = skipped
    if decoded:
        meta["opcodes_decoded"] = ["OpcodeList2:MapPolynomial"] * decoded
    mosaic = raw.mosaic
    expected = None if area is None else (area[0] - offset[0], area[1] - offset[1])
    fits = expected is None or tuple(mosaic.shape[:2]) == expected
    names1 = ["OpcodeList1:FixBadPixelsConstant"] * len(stage1)
    if stage1 and fits and origin is not None and raw.cfa_pattern is not None:
        for fix in stage1:  # on the codes as stored (no LinearizationTable: origin is None)
            mosaic = fix_bad_pixels_constant(mosaic, fix, origin)
        meta["opcodes_applied_other"] = names1
    elif stage1:
        meta["opcodes_skipped"] = [*meta["opcodes_skipped"], *names1]
    names = [stage2_name(op) for op in maps]
    if maps and fits and raw.metadata.get("xtrans") is None:
        levels = np.asarray(raw.black_level, np.float64)
        # one black level (the common case) passed as one: no plane of it made and read
        one = bool(np.all(levels == levels.flat[0]))
        black = np.asarray(levels.flat[0]) if one else _black_plane(raw)
        mosaic = apply_stage2(mosaic, black, raw.white_level, maps, offset=offset, shape=area)
        meta["opcodes_applied"] = names.count("OpcodeList2:GainMap")
        meta["opcodes_applied_other"] = [
            *meta.get("opcodes_applied_other", []),
            *(n for n in names if n != "OpcodeList2:GainMap"),
        ]
    elif maps:
        meta["opcodes_skipped"] = [*meta["opcodes_skipped"], *names]
    if stage3 and fits:
        meta["opcodes_stage3"] = tuple(stage3)
        meta["opcodes_area"] = (offset, area)
    elif stage3:
        meta["opcodes_skipped"] = [*meta["opcodes_skipped"], *map(stage3_name, stage3)]
    return dataclasses.replace(raw, mosaic=mosaic, metadata=meta)


def _raw_page_opcodes(tf: Any) -> Any:
    """Return a DNG raw IFD's opcodes to apply, the ones not, offset, size, origin, decoded.

    ``tf`` is the open tifffile of a DNG. The opcodes of OpcodeList1, 2 and 3
    (:func:`imageform.io._dng_opcodes.read_opcodes`). The offset is where the mosaic's
    first pixel sits in the ActiveArea (LibRaw starts a CFA image's crop at an even row and
    column), the size the area's (H, W) (None: the raw image's), the origin where it sits in
    the stored image (None where a LinearizationTable changes the stored codes: OpcodeList1
    applies to them); decoded, how many MapPolynomials of a lossy DNG (Compression 34892)
    its samples were decoded with (LibRaw's reading and :func:`_read_dng`'s apply them:
    :func:`imageform.io._dng_opcodes.lossy_dng_curves`). :data:`_NO_OPCODES` for a file
    with no raw IFD.
    """
    from imageform.io._dng_opcodes import lossy_dng_curves, read_opcodes

    page = _dng_raw_page(tf)
    if page is None:
        return _NO_OPCODES
    decoded = 0
    if int(page.tags.valueof(259, 1)) == _COMPRESSION_LOSSY_JPEG and _OPCODE_LIST_2 in page.tags:
        decoded = lossy_dng_curves(_tag_bytes(page.tags[_OPCODE_LIST_2].value))[1]
    stage1, maps, stage3, skipped = read_opcodes(page, decoded=decoded)
    area = [int(v) for v in np.ravel(page.tags.valueof(_ACTIVE_AREA, ()))]
    cfa = int(page.tags.valueof(262, 0)) == _PHOTOMETRIC_CFA
    linearized = _LINEARIZATION_TABLE in page.tags
    if len(area) == 4 and area[2] > area[0] and area[3] > area[1]:
        top, left, bottom, right = area
        offset = (top & 1, left & 1) if cfa else (0, 0)  # LibRaw's crop starts even
        origin = None if linearized else (top + offset[0], left + offset[1])
        size = (bottom - top, right - left)
        return stage1, maps, stage3, skipped, offset, size, origin, decoded
    return stage1, maps, stage3, skipped, (0, 0), None, None if linearized else (0, 0), decoded


def _page_data_end(tf: Any) -> int:
    """Return the byte where a DNG's raw image's last strip or tile ends (0: cannot say).

    ``tf`` is the open TIFF; 0 where it has no raw page or its IFD cannot be read.
    """
    try:
        page = _dng_raw_page(tf)
        if page is None:
            return 0
        ends = np.asarray(page.dataoffsets, np.int64) + np.asarray(page.databytecounts)
        return int(ends.max()) if ends.size else 0
    except Exception:  # an IFD tifffile cannot read
        return 0


def _truncated(p: Path, end: int, size: int) -> UnreadableFileError:
    """Refuse a raw whose image data ends at byte ``end`` of a file of ``size`` bytes."""
    return UnreadableFileError(
        p,
        f"the file is truncated (its raw image's data ends at byte {end}, the file has "
        f"{size} bytes)",
    )


def _tag_bytes(value: Any) -> bytes:
    """Return an UNDEFINED tag's value as bytes (tifffile gives bytes or a tuple of ints)."""
    return value if isinstance(value, bytes) else bytes(np.asarray(value, np.uint8).ravel())


def _read_raw(
    path: str | Path, max_pixels: int | None, *, opcodes: bool = False
) -> tuple[RawImage, Any]:
    """:func:`read_raw` without the opcodes, and :func:`_raw_page_opcodes` of the file.

    The DNG header is read once for the colour tags and, with ``opcodes``, the opcodes.
    """
    from imageform.io.image_io import ImageInfo, _check_pixels, _pixel_limit

    limit = (
        RAW_MAX_PIXELS
        if max_pixels is None and not os.environ.get("IMAGEFORM_MAX_PIXELS", "").strip()
        else _pixel_limit(max_pixels)
    )
    if not isinstance(path, str | os.PathLike):
        raise TypeError(f"expected path as a file path, got {describe(path)}")
    p = Path(path)
    if not p.is_file():
        raise InvalidInputError(f"raw file {p} does not exist")
    if (lfs := git_lfs_pointer(p)) is not None:
        raise UnreadableFileError(p, lfs)
    if importlib.util.find_spec("rawpy") is None:
        # without LibRaw, a DNG as imageform writes it (one uncompressed CFA image) is read
        # with tifffile; any other raw file needs the extra (the message says so)
        own = _read_dng(p, limit)
        if own is not None:
            return own, _dng_header(p, opcodes=opcodes)[1]
    header = _dng_header(p, opcodes=opcodes)  # before LibRaw, read once
    n_bytes = p.stat().st_size
    if (end := header[2]) - n_bytes > max(_CUT_MARGIN, end // 100):
        # cut off in transfer (an interrupted copy): said before LibRaw prints its own
        # "Unexpected end of file" onto stderr; a few bytes short is left to LibRaw's reading
        raise _truncated(p, end, n_bytes)
    rawpy = _rawpy()
    r = rawpy.RawPy()
    try:
        r.open_file(str(p))  # the header only: sizes are known before anything is decoded
        size = r.sizes
        _check_pixels(p, ImageInfo(int(size.raw_width), int(size.raw_height), 1, "", "raw"), limit)
        r.unpack()
    except InvalidInputError:
        r.close()
        raise
    except Exception as exc:  # LibRawFileUnsupportedError, LibRawIOError, ...
        r.close()
        # a DNG LibRaw cannot decode (JPEG XL of DNG 1.7, deflate or LZW integers): tifffile
        own = _read_dng(p, limit)
        if own is not None:
            own.metadata["libraw"] = type(exc).__name__
            return own, header[1]
        if end > n_bytes:  # cut off in transfer
            raise _truncated(p, end, n_bytes) from None
        if (code := _dng_compression(p)) in _DNG_COMPRESSIONS:  # a DNG: name what stops it
            kind, who = _DNG_COMPRESSIONS[code]
            raise UnreadableFileError(
                p,
                f"a DNG whose raw image is compressed with {kind}, Compression {code}, which "
                f"LibRaw as rawpy builds it does not decode ({type(exc).__name__}) {who}",
            ) from None
        raise UnreadableFileError(
            p, _not_raw(p) or f"not a raw file LibRaw can read ({type(exc).__name__})"
        ) from None
    with r:
        desc = r.color_desc.decode("ascii", "replace")
        per_channel = np.asarray(r.black_level_per_channel, dtype=np.float64)
        pattern: str | None
        xtrans: str | None = None
        if r.num_colors == 1:  # a monochrome sensor (no CFA): one grey value a pixel
            visible = np.asarray(r.raw_image_visible)
            if visible.ndim == 3:
                visible = visible[..., 0]
            mosaic = np.array(visible, dtype=np.uint16, copy=True)
            pattern = None
            black = per_channel[:1].copy()
        elif r.raw_pattern is None:  # a linear raw (LinearRaw DNG): every pixel has its colours
            visible = np.asarray(r.raw_image_visible)
            if visible.ndim != 3 or r.num_colors != 3 or any(c not in "RGB" for c in desc[:3]):
                raise InvalidInputError(
                    f"{p}: a linear raw of {r.num_colors} colours ({desc!r}) is not "
                    "supported: only RGB"
                )
            mosaic = np.empty(visible.shape[:2] + (3,), np.uint16)
            for c in range(3):  # a channel at a time: 4x faster than one copy of [..., :3]
                mosaic[..., c] = visible[..., c]
            pattern = None
            black = per_channel[:3].copy()
        elif (
            np.shape(r.raw_pattern) == (6, 6)
            and r.num_colors == 3
            and all(c in "RGB" for c in desc[:3])
        ):  # X-Trans: demosaiced by LibRaw's linear interpolation, as its LINEAR mode does
            try:
                mosaic = _libraw_linear_demosaic(r)
            except Exception as exc:  # LibRaw's own failure, named in one line
                raise InvalidInputError(
                    f"{p}: LibRaw could not demosaic its X-Trans CFA ({type(exc).__name__})"
                ) from None
            pattern = None
            black = np.zeros(3)
            xtrans = "".join(desc[int(i)] for i in np.asarray(r.raw_pattern)[0])
        else:
            pat = np.asarray(r.raw_pattern)
            if r.num_colors != 3 or pat.shape != (2, 2) or any(c not in "RGB" for c in desc[:3]):
                raise InvalidInputError(
                    f"{p}: {_cfa_name(pat, desc, r.num_colors)} is not supported: only 2x2 "
                    "RGB Bayer tiles (LibRaw's own postprocess develops it)"
                )
            pattern = "".join(desc[int(i)] for i in pat.ravel()).replace("G2", "G")
            pattern = "".join("G" if c not in "RB" else c for c in pattern)
            mosaic = np.array(r.raw_image_visible, dtype=np.uint16, copy=True)
            black = per_channel[pat].astype(np.float64)
        flip = int(r.sizes.flip)
        white = float(r.white_level) if xtrans is None else 65535.0
        wb4 = np.asarray(r.camera_whitebalance, dtype=np.float64)
        gains = None
        if wb4[1] > 0 and wb4[0] > 0 and wb4[2] > 0:
            gains = np.array([wb4[0] / wb4[1], 1.0, wb4[2] / wb4[1]])
        day = np.asarray(r.daylight_whitebalance, dtype=np.float64)
        rgb_cam = np.array(r.color_matrix, dtype=np.float64)[:3, :3]
        cam_xyz = np.array(r.rgb_xyz_matrix, dtype=np.float64)[:3, :3]
        raw_type = str(r.raw_type).split(".")[-1].lower()
    if not np.any(mosaic):  # LibRaw opens floating-point DNGs but decodes no sample
        own = _read_dng(p, limit)
        floats = own is not None and own.metadata["raw_type"] == "float"
        if own is not None and floats and own.mosaic.shape == mosaic.shape:
            mosaic, black, white = own.mosaic, own.black_level, own.white_level
            raw_type = "float"
        elif end > n_bytes:  # LibRaw reads zeros
            raise _truncated(p, end, n_bytes)
    libraw_white = None
    # a white level below most of the samples is wrong, not the scene (LibRaw gives 255 for a
    # Nikon Coolscan's 16-bit NEF; saturated photosites sit at white, not above it): the
    # samples' own bit depth, with a note, instead of an all-white development
    top = int(mosaic.max(initial=0))
    if xtrans is None and top > white and np.count_nonzero(mosaic > white) > mosaic.size // 2:
        libraw_white, white = white, float(2 ** top.bit_length() - 1)
    photosites = mosaic.shape[0] * mosaic.shape[1]
    if (size := p.stat().st_size) * 8 < photosites and np.count_nonzero(mosaic) < mosaic.size / 100:
        # under one bit a photosite and (nearly) all zero: the data is missing, LibRaw read zeros
        raise UnreadableFileError(
            p,
            f"the file is truncated ({size} bytes for {photosites} photosites, under one bit "
            "each, and LibRaw decodes zeros)",
        )
    meta: dict[str, Any] = {
        "path": str(p),
        "raw_type": raw_type,
        "color_desc": desc,
        "daylight_white_balance": (day[:3] / day[1]).tolist() if day[1] > 0 else None,
        "camera_model": None,
    }
    if libraw_white is not None:
        meta["white_level_libraw"] = libraw_white
    illum: str | None = None
    xyz_to_camera: np.ndarray | None = cam_xyz if np.any(cam_xyz) else None
    tags, found, _ = header
    if tags:
        names = {v: k for k, v in CALIBRATION_ILLUMINANTS.items()}
        if "model" in tags:
            meta["camera_model"] = str(tags["model"]).strip("\x00")
        _baseline_ev(tags, meta)
        dng_matrix, code = _dng_colour(tags)
        if dng_matrix is not None:
            xyz_to_camera = dng_matrix
            illum = names.get(code, "D65")
            meta["calibration_illuminant_code"] = code
    if xyz_to_camera is not None and illum is None:
        illum = "D65"  # LibRaw's matrices are for D65
    if xtrans is not None:
        meta["xtrans"] = xtrans.replace("G2", "G")  # the first row of the 6x6 pattern
        raw_type = "xtrans"
        meta["raw_type"] = raw_type
    if mosaic.ndim == 2 and pattern is None:  # monochrome: no colours to balance or convert
        gains, xyz_to_camera, illum = None, None, None
        rgb_cam = np.zeros((3, 3))
        meta["monochrome"] = True
    raw = RawImage(
        mosaic=mosaic,
        black_level=black,
        white_level=white,
        cfa_pattern=pattern,
        white_balance=gains,
        xyz_to_camera=xyz_to_camera,
        camera_to_srgb=rgb_cam,
        calibration_illuminant=illum,
        metadata=meta,
        orientation=flip if flip in _FLIPS else 0,
    )
    return raw, found


#: LibRaw's flip codes (``sizes.flip``) of the eight TIFF/EXIF orientations, by EXIF code.
_EXIF_TO_FLIP = {1: 0, 2: 1, 3: 3, 4: 2, 5: 4, 6: 6, 7: 7, 8: 5}
_FLIPS = frozenset(_EXIF_TO_FLIP.values())


def _libraw_linear_demosaic(r: Any) -> np.ndarray:
    """Return camera RGB of a raw LibRaw has open, demosaiced by LibRaw's linear interpolation.

    For colour filter arrays imageform's demosaicing does not take (Fujifilm's 6x6 X-Trans):
    ``postprocess`` with LibRaw's LINEAR method (dcraw's ``lin_interpolate``, which any
    periodic CFA takes: each missing colour the weighted mean of its 3x3 neighbours, weight 2
    beside, 1 across), no white balance (gains 1), camera colours (``output_color`` raw), linear
    16-bit output, no brightening, sensor orientation: the black level subtracted and white at
    65535, per pixel three camera channels that the rest of :func:`develop` takes as a linear
    raw. Demosaicing is linear, so balancing before or after it gives the same values (below
    clipping).
    """
    rawpy = _rawpy()
    return np.ascontiguousarray(
        r.postprocess(
            demosaic_algorithm=rawpy.DemosaicAlgorithm.LINEAR,
            use_camera_wb=False,
            use_auto_wb=False,
            user_wb=[1.0, 1.0, 1.0, 1.0],
            output_color=rawpy.ColorSpace.raw,
            gamma=(1, 1),
            no_auto_bright=True,
            output_bps=16,
            user_flip=0,
            adjust_maximum_thr=0.0,
        ),
        dtype=np.uint16,
    )


def _cfa_name(pattern: np.ndarray, desc: str, colours: int) -> str:
    """Name a colour filter array in a refusal: its size, its kind and its first row."""
    rows, cols = pattern.shape if pattern.ndim == 2 else (0, 0)
    kind = "X-Trans " if (rows, cols) == (6, 6) else ""
    letters = (
        "".join(desc[int(i)] if int(i) < len(desc) else "?" for i in pattern[0]) if rows else ""
    )
    if colours != 3:
        kind = f"{colours}-colour ({desc}) "
    return f"a {rows}x{cols} {kind}CFA (first row {letters})"


def _orient(image: np.ndarray, flip: int) -> np.ndarray:
    """Turn ``image`` (H, W, ...) for display as LibRaw does for ``sizes.flip``: a view.

    LibRaw's output pixel (r, c) is the input's ``flip_index(r, c)``: rows and columns
    swapped when bit 4 is set, then rows reversed for bit 2 and columns for bit 1
    (dcraw's ``flip_index``).
    """
    a = image
    if flip & 1:
        a = a[:, ::-1]
    if flip & 2:
        a = a[::-1]
    if flip & 4:
        a = a.swapaxes(0, 1)
    return a


#: sRGB (D65) to XYZ as LibRaw writes it (``LibRaw_constants::xyz_rgb``): its ``rgb_cam`` for
#: a DNG is computed from the file's colour matrix with these values (dcraw's
#: ``cam_xyz_coeff``), so :func:`_read_dng` uses them too.
_LIBRAW_XYZ_RGB = np.array(
    [
        [0.4124564, 0.3575761, 0.1804375],
        [0.2126729, 0.7151522, 0.0721750],
        [0.0193339, 0.1191920, 0.9503041],
    ]
)


def _libraw_rgb_cam(xyz_to_camera: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""Return LibRaw's ``rgb_cam`` and daylight multipliers of a colour matrix.

    dcraw's ``cam_xyz_coeff``, as LibRaw computes it for a DNG:

    :math:`P = C\,S` (camera RGB of each sRGB primary), each row scaled to sum 1 (the
    reciprocal of its sum is that channel's daylight multiplier), ``rgb_cam`` = :math:`P^{-1}`.
    """
    cam_rgb = xyz_to_camera @ _LIBRAW_XYZ_RGB
    sums = cam_rgb.sum(axis=1)
    rgb_cam = np.linalg.inv(cam_rgb / sums[:, None])
    daylight = (1.0 / sums) / (1.0 / sums[1])
    return rgb_cam, daylight


#: PhotometricInterpretation of a DNG's raw image: a colour filter array, or LinearRaw.
_PHOTOMETRIC_LINEAR_RAW = 34892
#: Compression of a lossy DNG's samples (8-bit JPEG, DNG 1.4), and the OpcodeList2 tag.
_COMPRESSION_LOSSY_JPEG = 34892
_OPCODE_LIST_2 = 51009


def _ints(value: Any) -> list[int]:
    """Return a TIFF tag's values as integers (BYTE tags come from tifffile as bytes)."""
    if isinstance(value, bytes | bytearray):
        return list(value)
    return [int(v) for v in np.ravel(value)]


def _dng_raw_page(tf: Any) -> Any:
    """Return a DNG's full-resolution raw IFD: IFD 0 or one of its SubIFDs, or None.

    The first page whose NewSubfileType says "full resolution" (bit 0 clear) and whose
    PhotometricInterpretation is CFA or LinearRaw, as LibRaw looks for it.
    """
    first = tf.pages[0]
    for page in [first, *(getattr(first, "pages", None) or [])]:
        tags = page.tags
        if int(tags.valueof(254, 0)) & 1:
            continue  # a reduced-resolution preview
        if int(tags.valueof(262, 0)) in (_PHOTOMETRIC_CFA, _PHOTOMETRIC_LINEAR_RAW):
            return page
    return None


#: A frame whose brightest photosite is under this fraction of the way from black to white is
#: noted as nearly black when developed (a Pixel 7's dark frame: 0.84 %).
_NEARLY_BLACK = 0.02

#: Compressions of DNG raw images that LibRaw (as rawpy builds it) does not decode: the name
#: and what else was tried, in the refusal when :func:`_read_dng` could not read the file.
_DNG_COMPRESSIONS = {
    9: (
        "GoPro's VC-5 (a GPR file)",
        "and imageform's own VC-5 decoder found no raw image it reads in the file (a Bayer "
        "image of one sample a pixel in a DNG raw IFD)",
    ),
    52546: ("JPEG XL", "nor tifffile (with imagecodecs' JPEG XL) decodes"),
}
#: Compression of a GoPro GPR's raw image (VC-5, SMPTE ST 2073): :mod:`imageform.io._vc5`.
_COMPRESSION_VC5 = 9


def _read_vc5(p: Path, page: Any, fh: Any) -> np.ndarray:
    """Return the raw image of a GPR's DNG page, decoded by :mod:`imageform.io._vc5`.

    A bitstream that cannot be decoded is refused in one line (:class:`UnreadableFileError`).
    """
    from imageform.io._vc5 import Vc5Error, decoded_tiles

    try:
        return decoded_tiles(page, fh)
    except Vc5Error as exc:
        raise UnreadableFileError(
            p, f"its raw image, GoPro's VC-5 (a GPR file, Compression 9), is corrupt: {exc}"
        ) from None


def _dng_compression(p: Path) -> int | None:
    """Return the Compression of a DNG's raw image; None for a file that is no DNG."""
    import tifffile

    try:
        with tifffile.TiffFile(p) as tf:
            if _DNG_VERSION not in tf.pages[0].tags:  # type: ignore[union-attr]
                return None
            page = _dng_raw_page(tf)
            return None if page is None else int(page.tags.valueof(259, 1))
    except Exception:  # not a TIFF
        return None


def _read_dng(p: Path, limit: int) -> RawImage | None:
    """Read a DNG with tifffile, as LibRaw reads it: for DNGs LibRaw cannot decode, or no LibRaw.

    What LibRaw does, here for any raw IFD tifffile (with imagecodecs) decodes: JPEG XL (DNG
    1.7, as recent phones write), deflate, LZW or uncompressed, tiled or in strips, integers
    or floats (scaled so that the white level, 1.0 unless WhiteLevel says otherwise, is
    65535; values above it clipped, as the development clips highlights); a 2x2 RGB CFA,
    LinearRaw of three samples, or one sample (monochrome). The LinearizationTable is
    applied, the image cut to its ActiveArea (the CFA pattern starts at the area's corner;
    like LibRaw, a CFA image's crop starts at an even row and column), BlackLevel (with
    BlackLevelRepeatDim) and WhiteLevel read (default 2^bits - 1), BlackLevelDeltaH/V
    subtracted from the samples; the colour matrix picked and composed by
    :func:`_dng_colour`, ``rgb_cam`` by LibRaw's formula (:func:`_libraw_rgb_cam`),
    AsShotNeutral as the gains, the Orientation tag. DefaultCrop and opcode lists are not
    applied (LibRaw applies neither). None for a file that is not such a DNG, or that tifffile
    cannot decode.
    """
    import tifffile

    from imageform.io.image_io import ImageInfo, _check_pixels

    try:
        with tifffile.TiffFile(p) as tf:
            ifd0 = tf.pages[0].tags  # type: ignore[union-attr]
            if _DNG_VERSION not in ifd0:
                return None
            page = _dng_raw_page(tf)
            if page is None:
                return None
            objects = {t.code: t for t in page.tags}
            tags = {code: t.value for code, t in objects.items()}
            levels_of = {  # read while the file is open (tifffile loads large tags lazily)
                code: _tag_reals(objects[code])
                for code in (_BLACK_LEVEL, _WHITE_LEVEL, _BLACK_LEVEL_DELTA_H, _BLACK_LEVEL_DELTA_V)
                if code in objects
            }
            neutral_tag = objects.get(_AS_SHOT_NEUTRAL, ifd0.get(_AS_SHOT_NEUTRAL))
            neutral = None if neutral_tag is None else _tag_reals(neutral_tag)
            colour = _colour_tags(ifd0)
            info = ImageInfo(int(tags[256]), int(tags[257]), 1, "", "raw")
            _check_pixels(p, info, limit)
            vc5 = int(tags.get(259, 1)) == _COMPRESSION_VC5
            data = _read_vc5(p, page, tf.filehandle) if vc5 else np.asarray(page.asarray())
            flip = _EXIF_TO_FLIP.get(int(ifd0.valueof(274, 1)), 0)
            lossy = int(tags.get(259, 1)) == _COMPRESSION_LOSSY_JPEG and data.dtype == np.uint8
            list2 = _tag_bytes(objects[_OPCODE_LIST_2].value) if _OPCODE_LIST_2 in objects else None
    except InvalidInputError:
        raise
    except Exception:  # not a TIFF, or one tifffile cannot decode: LibRaw's business
        return None
    linear_raw = int(tags.get(262, 0)) == _PHOTOMETRIC_LINEAR_RAW
    if linear_raw and data.ndim == 3 and data.shape[2] == 1:
        data = data[..., 0]
    if linear_raw and not (data.ndim == 2 or data.shape[2] >= 3):
        return None
    pattern: str | None = None
    if not linear_raw:
        dims = tuple(int(v) for v in np.ravel(tags.get(_CFA_REPEAT_PATTERN_DIM, ())))
        cfa = _ints(tags.get(_CFA_PATTERN, ()))
        planes = _ints(tags.get(_CFA_PLANE_COLOR, (0, 1, 2)))
        letters = "".join("RGB"[planes[c]] if c < len(planes) and planes[c] < 3 else "?"
                          for c in cfa)  # fmt: skip
        if dims != (2, 2) or len(cfa) != 4 or sorted(letters) != ["B", "G", "G", "R"]:
            raise InvalidInputError(
                f"{p}: a {dims[0] if dims else 0}x{dims[1] if len(dims) > 1 else 0} CFA "
                f"(first row {letters[: dims[1] if len(dims) > 1 else 0]}) is not supported: "
                "only 2x2 RGB Bayer tiles"
            )
        pattern = letters
        if data.ndim != 2:
            return None
    if lossy:  # 8-bit JPEG samples, decoded through LibRaw's curves to 0..65535
        from imageform.io._dng_opcodes import lossy_dng_curves

        curves = lossy_dng_curves(list2)[0]
        if data.ndim == 2:
            data = curves[0][data]
        else:
            data = np.stack([curves[min(c, 3)][data[..., c]] for c in range(data.shape[2])], -1)
    floats = data.dtype.kind == "f"
    values = data  # integers stay integers unless a table, deltas or scaling need floats
    if _LINEARIZATION_TABLE in tags and not floats:
        table = np.asarray(tags[_LINEARIZATION_TABLE], dtype=np.float64).ravel()
        values = table[np.clip(data.astype(np.int64), 0, table.size - 1)]
    area = [int(v) for v in np.ravel(tags.get(_ACTIVE_AREA, ()))]
    if len(area) == 4 and area[2] > area[0] and area[3] > area[1]:
        top, left, bottom, right = area
        if pattern is not None:  # the CFA starts at the area's corner; LibRaw's crop at an
            dt, dl = top & 1, left & 1  # even row and column, the pattern shifted to match
            pattern = "".join(pattern[2 * ((i + dt) % 2) + (j + dl) % 2]
                              for i in (0, 1) for j in (0, 1))  # fmt: skip
            top, left = top + dt, left + dl
        values = values[top:bottom, left:right]
    h, w = values.shape[:2]
    for code, axis in ((_BLACK_LEVEL_DELTA_H, 1), (_BLACK_LEVEL_DELTA_V, 0)):
        if code in levels_of:
            delta = levels_of[code]
            if delta.size >= (w if axis == 1 else h):
                shape = (1, w) if axis == 1 else (h, 1)
                step = delta[: shape[axis]].reshape(shape)
                values = np.asarray(values, np.float64) - (
                    step[..., None] if values.ndim == 3 else step
                )
    channels = 1 if values.ndim == 2 else values.shape[2]
    bits = int(np.ravel(tags.get(258, 16))[0])
    white = (
        65535.0  # a lossy DNG's curves end at 65535, as LibRaw's maximum
        if lossy
        else float(np.min(levels_of[_WHITE_LEVEL]))
        if _WHITE_LEVEL in levels_of
        else (1.0 if floats else float(2**bits - 1))
    )
    levels = levels_of.get(_BLACK_LEVEL, np.zeros(1))
    rep = tuple(int(v) for v in np.ravel(tags.get(_BLACK_LEVEL_REPEAT_DIM, (1, 1))))
    if pattern is not None:
        black = (
            levels.reshape(2, 2)
            if rep == (2, 2) and levels.size == 4
            else np.full((2, 2), float(levels.mean()))
        )
    else:
        want = min(channels, 3)
        black = levels[:want] if levels.size >= want else np.full(want, float(levels[0]))
    if not np.isfinite(white) or white <= 0:
        return None
    scale = 65535.0 / white if (floats or white > 65535) else 1.0
    if values.ndim == 3:
        values = values[..., :3]
    if values.dtype in (np.uint8, np.uint16) and scale == 1.0:  # the samples as they are
        mosaic = np.ascontiguousarray(values, dtype=np.uint16)
    else:
        codes = np.nan_to_num(np.asarray(values, np.float64), nan=0.0) * scale
        mosaic = np.round(np.clip(codes, 0.0, 65535.0, out=codes), out=codes).astype(np.uint16)
    black = np.asarray(black, np.float64) * scale
    white *= scale
    cam_xyz, code = _dng_colour(colour)
    names = {v: k for k, v in CALIBRATION_ILLUMINANTS.items()}
    model = colour.get("model")
    meta: dict[str, Any] = {
        "path": str(p),
        "raw_type": "float" if floats else ("stack" if mosaic.ndim == 3 else "flat"),
        "color_desc": "RGBG",
        "daylight_white_balance": None,
        "camera_model": str(model).strip("\x00") if model is not None else None,
        "reader": "imageform VC-5" if vc5 else "tifffile",
    }
    _baseline_ev(colour, meta)
    gains = None
    rgb_cam = np.zeros((3, 3))
    illum: str | None = None
    if mosaic.ndim == 2 and pattern is None:  # monochrome
        meta["monochrome"] = True
        cam_xyz = None
    elif cam_xyz is not None:
        rgb_cam, daylight = _libraw_rgb_cam(cam_xyz)
        meta["daylight_white_balance"] = daylight.tolist()
        meta["calibration_illuminant_code"] = code
        illum = names.get(code, "D65")
    usable = neutral is not None and neutral.size >= 3 and bool(np.all(neutral[:3] > 0))
    if usable and neutral is not None and not meta.get("monochrome"):
        gains = (1.0 / neutral[:3]) / (1.0 / neutral[1])
    return RawImage(
        mosaic=mosaic,
        black_level=black,
        white_level=white,
        cfa_pattern=pattern,
        white_balance=gains,
        xyz_to_camera=cam_xyz,
        camera_to_srgb=rgb_cam,
        calibration_illuminant=illum,
        metadata=meta,
        orientation=flip,
    )


class Development:
    """Every stage of :func:`develop`, in order.

    Every stage is computed when first read (:func:`develop` checks the inputs and builds
    the matrices): for a Bayer mosaic developed bilinearly, ``image`` and ``camera_rgb`` come
    from the raw digital numbers in one fused pass over strips of rows
    (:func:`imageform._kernels.raw_develop.develop_rows`), and :meth:`to_integer` writes the
    integers from that same pass when ``image`` has not been read, so a 24 Mpx development
    makes no full-size float temporary. ``image`` is kept once read; the other stages are
    computed again at each reading. Every three-channel stage is turned for display
    (:attr:`RawImage.orientation`, as LibRaw does); the mosaic stages stay in the sensor's
    orientation, where the CFA is defined.

    Attributes
    ----------
    linear : ndarray (H, W) or (H, W, 3)
        The mosaic linearised: :math:`(DN - B) / (W - B)`.
    white_balanced : ndarray (H, W) or (H, W, 3)
        ``linear`` times the gain of each photosite's colour, clipped to [0, 1].
    camera_rgb : ndarray (H', W', 3)
        Demosaiced, white-balanced camera RGB.
    xyz : ndarray (H', W', 3)
        CIE XYZ adapted to the output space's white (Y = 1 for white).
    linear_rgb : ndarray (H', W', 3)
        Linear RGB of the output space, clipped to [0, 1].
    image : ndarray (H', W', 3) float32
        The encoded output in [0, 1] (``linear_rgb`` itself for linear output).
    gains : ndarray (3,)
        The white balance gains applied (R, G, B; the smallest is 1).
    camera_to_xyz : ndarray (3, 3)
        White-balanced camera RGB to XYZ, white-balanced white on D65's white.
    adaptation : ndarray (3, 3)
        Bradford, D65's white to the output space's white.
    space, transfer, demosaic : str
        The output space, its encoding and the demosaicing method (``"none"`` for a linear
        raw).
    orientation : int
        The flip applied (:attr:`RawImage.orientation`; 0 when ``orient=False``).
    notes : tuple of str
        What the development had to assume (no colour matrix in the file, say).
    brightness : float
        The factor on the linear output (``develop(auto_bright=True)`` or
        ``baseline_exposure=True``; 1 otherwise).
    highlight_rolloff : bool
        The brightened values roll off below white (:func:`_highlight_shoulder`) instead of
        clipping (``develop(highlight_rolloff=True)`` with a brightness above 1).
    """

    def __init__(
        self,
        *,
        raw: RawImage,
        gains: np.ndarray,
        camera_rgb: np.ndarray | None,
        render: np.ndarray,
        table: np.ndarray | None,
        camera_to_xyz: np.ndarray,
        adaptation: np.ndarray,
        space: str,
        transfer: str,
        demosaic: str,
        orientation: int,
        notes: tuple[str, ...],
        device: str = "cpu",
        site_gains: np.ndarray | None = None,
    ) -> None:
        self._raw = raw
        # the sensor's orientation: given for a linear raw and the other demosaicing methods;
        # None for the fused bilinear pass (computed from the mosaic when read)
        self._camera_rgb = camera_rgb
        self._render = render  # float32 (3, 3): camera RGB to the output's linear RGB
        self._table = table  # the transfer table; None for linear output
        self._image: np.ndarray | None = None
        self.gains = gains
        # the gain of each photosite of a Bayer mosaic's 2x2 tile: the colours' gains, except
        # for LibRaw's automatic white balance, which scales the two greens apart
        self._site_gains: np.ndarray = np.asarray(
            site_gains
            if site_gains is not None
            else (
                gains[np.array(_cfa_indices(raw.cfa_pattern)).reshape(2, 2)]
                if raw.cfa_pattern is not None
                else gains
            ),
            np.float64,
        )
        self.camera_to_xyz = camera_to_xyz
        self.adaptation = adaptation
        self.space = space
        self.transfer = transfer
        self.demosaic = demosaic
        self.orientation = orientation
        self.notes = notes
        self._device = device  # "cuda": the fused pass runs as one CUDA kernel
        self.brightness = 1.0  # auto_bright's factor on the linear output
        # the brightening rolled off below white (develop(highlight_rolloff=True)), not clipped
        self.highlight_rolloff = False
        # a DNG's OpcodeList3 opcodes to apply to the demosaiced camera RGB (the opcodes, the
        # offset, the area: develop sets them), applied when camera RGB is first read (then
        # kept) or, for a warp, in the render's own pass; None: none, or applied
        self._stage3: tuple[tuple[Any, ...], tuple[int, int], Any] | None = None

    def _pass_args(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, int, int]:
        """Return the fused pass's mosaic, black and scale per photosite, red's row, column."""
        raw = self._raw
        black = np.asarray(raw.black_level, np.float64)
        scale = (self._site_gains / (raw.white_level - black)).astype(np.float32)
        red = str(raw.cfa_pattern).index("R")
        mosaic = np.ascontiguousarray(raw.mosaic, dtype=np.uint16)
        return mosaic, np.ascontiguousarray(black, dtype=np.float32), scale, red // 2, red % 2

    def _fused(self, mode: int) -> np.ndarray:
        """Run the fused pass over the mosaic (``mode``: camera RGB, float or uint16 output)."""
        from imageform._kernels.jit import run_tasks
        from imageform._kernels.raw_develop import MODE_PLANAR, MODE_UINT16, develop_rows

        raw = self._raw
        h, w = raw.mosaic.shape
        black = np.asarray(raw.black_level, np.float64)
        scale = (self._site_gains / (raw.white_level - black)).astype(np.float32)
        red = str(raw.cfa_pattern).index("R")
        if self._device == "cuda":
            from imageform._cuda.demosaic import develop_bayer

            return develop_bayer(
                raw.mosaic,
                black.astype(np.float32),
                scale,
                red // 2,
                red % 2,
                self.demosaic,
                self._render,
                self._table,
                mode,
            )
        shape = (3, h, w) if mode == MODE_PLANAR else (h, w, 3)
        out_f = np.empty(shape if mode != MODE_UINT16 else (0, 0, 3), np.float32)
        out_u = np.empty(shape if mode == MODE_UINT16 else (0, 0, 3), np.uint16)
        table = self._table if self._table is not None else np.zeros(2, np.float32)
        run_tasks(
            develop_rows,
            h,
            np.ascontiguousarray(raw.mosaic, dtype=np.uint16),
            np.ascontiguousarray(black, dtype=np.float32),
            scale,
            red // 2,
            red % 2,
            self._render,
            table,
            self._table is not None,
            mode,
            out_f,
            out_u,
            0,
            threads=None if h * w >= _THREADS_MIN_PIXELS else 1,
        )
        return out_u if mode == MODE_UINT16 else out_f

    def _demosaiced(self) -> np.ndarray:
        """Return the demosaiced camera RGB, before OpcodeList3 (sensor orientation)."""
        if self._camera_rgb is not None:
            return self._camera_rgb
        from imageform._kernels.raw_develop import MODE_CAMERA

        return self._fused(MODE_CAMERA)

    def _sensor_camera_rgb(self) -> np.ndarray:
        if self._stage3 is not None:  # applied once, then kept
            from imageform.io._dng_opcodes import apply_stage3

            ops, offset, area = self._stage3
            self._camera_rgb = apply_stage3(self._demosaiced(), ops, offset=offset, shape=area)
            self._stage3 = None
        return self._demosaiced()

    def _warped_image(self) -> np.ndarray:
        """Return the image of OpcodeList3 ending in a warp: the warp and the render in one pass.

        The opcodes before the warp applied to the camera RGB first; a Bayer mosaic developed
        bilinearly on the CPU demosaiced straight into the planes the warp reads. The same
        values, bit for bit, as the opcodes applied, then the render.
        """
        from imageform.io._dng_opcodes import apply_stage3, render_warped, render_warped_mosaic

        assert self._stage3 is not None
        ops, offset, area = self._stage3
        *before, warp = ops
        if not before and self._camera_rgb is None and self._device == "cpu":
            banded = render_warped_mosaic(self._pass_args(), warp, self._render, self._table,
                                          offset=offset, shape=area)  # fmt: skip
            if banded is not None:
                return banded
        if before or self._camera_rgb is not None or self._device != "cpu":
            cam = self._demosaiced()
            if before:
                cam = apply_stage3(cam, before, offset=offset, shape=area)
            planes = np.moveaxis(cam, -1, 0)
        else:
            from imageform._kernels.raw_develop import MODE_PLANAR

            planes = self._fused(MODE_PLANAR)
        return render_warped(planes, warp, self._render, self._table, offset=offset, shape=area)

    def _sensor_image(self) -> np.ndarray:
        if self._image is None:
            from imageform.io._dng_opcodes import WarpRectilinear

            if self._stage3 is not None and isinstance(self._stage3[0][-1], WarpRectilinear):
                self._image = self._warped_image()
            elif self._camera_rgb is None and self._stage3 is None:
                from imageform._kernels.raw_develop import MODE_FLOAT

                self._image = self._fused(MODE_FLOAT)
            else:
                from imageform._kernels.jit import run_tasks
                from imageform._kernels.raw_develop import render_rows

                cam = self._sensor_camera_rgb()
                table = self._table if self._table is not None else np.zeros(2, np.float32)
                image = np.empty(cam.shape, np.float32)
                h, w = cam.shape[:2]
                run_tasks(render_rows, h, cam, self._render, table, self._table is not None,
                          image, threads=None if h * w >= _THREADS_MIN_PIXELS else 1)  # fmt: skip
                self._image = image
        return self._image

    def __repr__(self) -> str:
        """Size, method, space and gains (not the arrays)."""
        h, w = self.image.shape[:2]
        return (
            f"Development({w}x{h}, {self.demosaic} demosaicing, {self.space} "
            f"({self.transfer}), gains {np.round(self.gains, 4).tolist()})"
        )

    @property
    def linear(self) -> np.ndarray:
        """The mosaic linearised, :math:`(DN - B) / (W - B)` (float32, sensor orientation)."""
        raw = self._raw
        black = _black_plane(raw).astype(np.float32)
        out = raw.mosaic.astype(np.float32)
        out -= black
        out /= np.float32(raw.white_level) - black
        return out

    @property
    def white_balanced(self) -> np.ndarray:
        """``linear`` times each photosite's gain, clipped to [0, 1] (sensor orientation)."""
        raw = self._raw
        out = self.linear
        if raw.monochrome:
            pass  # one grey channel: no colours to balance (the gains are 1)
        elif raw.cfa_pattern is None:
            out *= self.gains.astype(np.float32)
        else:
            for i in (0, 1):
                for j in (0, 1):
                    out[i::2, j::2] *= np.float32(self._site_gains[i, j])
        return np.clip(out, 0.0, 1.0, out=out)

    @property
    def camera_rgb(self) -> np.ndarray:
        """Demosaiced, white-balanced camera RGB (float32, turned for display)."""
        return _orient(self._sensor_camera_rgb(), self.orientation)

    @property
    def xyz(self) -> np.ndarray:
        """CIE XYZ adapted to the output space's white (float32, turned for display)."""
        m = (self.adaptation @ self.camera_to_xyz).astype(np.float32)
        return self.camera_rgb @ m.T

    @property
    def linear_rgb(self) -> np.ndarray:
        """The output space's linear RGB (times :attr:`brightness`), clipped to [0, 1]."""
        from imageform.color import rgb_to_xyz_matrix

        to_rgb = np.linalg.inv(np.asarray(rgb_to_xyz_matrix(self.space), np.float64))
        if self.highlight_rolloff:  # brightened in the table, with its shoulder
            m = (to_rgb @ self.adaptation @ self.camera_to_xyz).astype(np.float32)
            out = np.clip(self.camera_rgb @ m.T, 0.0, 1.0)
            return _highlight_shoulder(self.brightness * out, self.brightness).astype(np.float32)
        m = (to_rgb @ self.adaptation @ self.camera_to_xyz * self.brightness).astype(np.float32)
        out = self.camera_rgb @ m.T
        return np.clip(out, 0.0, 1.0, out=out)

    @property
    def image(self) -> np.ndarray:
        """The encoded output in [0, 1] (float32, turned for display; kept once read)."""
        image = self._sensor_image()
        if self._raw.monochrome:  # the three equal channels of a grey development: one
            image = image[..., 0]
        return _orient(image, self.orientation)

    @_deprecate.parameters(renamed={"bits": "bit_depth"})
    def to_integer(self, bit_depth: int = 16) -> np.ndarray:
        """Return the output image as uint8 (``bit_depth=8``) or uint16 (``bit_depth=16``), rounded.

        Rounded half up (the values are in [0, 1]), turned for display. 16 bits of a Bayer
        mosaic developed bilinearly whose ``image`` has not been read: written by the fused
        pass itself (no float image is made), to the same values. ``bits=`` is the
        deprecated spelling of ``bit_depth=``.
        """
        if bit_depth not in (8, 16):
            raise InvalidInputError(f"expected bit_depth 8 or 16, got {describe(bit_depth)}")
        if (bit_depth == 16 and self._image is None and self._camera_rgb is None
                and self._stage3 is None):  # fmt: skip
            from imageform._kernels.raw_develop import MODE_UINT16

            out = self._fused(MODE_UINT16)
        else:
            from imageform._kernels.raw_develop import quantize

            image = self._sensor_image()
            out = np.empty(image.shape, np.uint8 if bit_depth == 8 else np.uint16)
            quantize(image.reshape(-1), np.float32(2**bit_depth - 1), out.reshape(-1))
        if self._raw.monochrome:
            out = out[..., 0]
        return np.ascontiguousarray(_orient(out, self.orientation))


#: Demosaicing methods that ``develop(device="cuda")`` runs on the GPU.
_CUDA_METHODS = ("bilinear", "malvar")

#: Mosaics of fewer pixels are developed in the calling thread (waking the pool costs more).
_THREADS_MIN_PIXELS = 1 << 16


def _black_plane(raw: RawImage) -> np.ndarray:
    """Return the black level of every photosite (or channel), broadcastable to the mosaic."""
    black = np.asarray(raw.black_level, np.float64)
    if raw.mosaic.ndim == 3:
        return black.reshape(1, 1, -1)
    if raw.monochrome:
        return black.reshape(1, 1)
    h, w = raw.mosaic.shape
    return np.tile(black, (h // 2 + 1, w // 2 + 1))[:h, :w]


def _transfer_table(transfer: str, gain: float = 1.0) -> np.ndarray:
    """Return the transfer function sampled uniformly in sqrt(x) (the render kernel's table).

    ``gain`` above 1: the table maps the unbrightened linear value v to the encoding of
    :func:`_highlight_shoulder` (``gain`` v): the brightening and its highlight roll-off in
    the table (``transfer`` ``"linear"``: no encoding). A copy of a table computed once per
    ``(transfer, gain)`` (5 ms each: a third of developing a small DNG), kept read-only: the
    copy is writable because the render kernels take it (numba types a read-only array apart,
    which :func:`~imageform._kernels.raw_develop.develop_rows`'s one signature refuses).
    """
    return _transfer_table_cached(transfer, float(gain)).copy()


@functools.lru_cache(maxsize=32)
def _transfer_table_cached(transfer: str, gain: float) -> np.ndarray:
    from imageform._kernels.raw_develop import LUT_SIZE
    from imageform.color import encode

    u = np.linspace(0.0, 1.0, LUT_SIZE + 1)
    v = u * u
    if gain > 1.0:
        v = _highlight_shoulder(gain * v, gain)
    encoded = v if transfer == "linear" else np.asarray(encode(v, transfer), np.float64)
    table = encoded.astype(np.float32)
    table.setflags(write=False)  # computed once (lru_cache): read, never written
    return table


#: Where the highlight roll-off starts, in the output's linear values (below it the
#: brightened values are kept as they are).
_SHOULDER_KNEE = 0.8


def _highlight_shoulder(y: np.ndarray, gain: float, knee: float = _SHOULDER_KNEE) -> np.ndarray:
    r"""Roll brightened linear values in [0, ``gain``] off into [0, 1] instead of clipping them.

    .. math::

        f(y) = \begin{cases} y & y \le k \\
        k + (1 - k)\,\dfrac{s\,t}{1 + (s - 1)\,t},\quad
        t = \dfrac{y - k}{g - k},\ s = \dfrac{g - k}{1 - k} & y > k \end{cases}

    with g the gain (the brightened sensor white) and k the knee: the identity up to k, then
    a rational (Reinhard-like) shoulder continuous with slope 1 at the knee, increasing, that
    reaches 1 exactly at the sensor's white (slope 1/s there): no value clips that the sensor
    did not clip. A gain of 1 or less clips nothing: the identity.
    """
    y = np.asarray(y, np.float64)
    g = float(gain)
    if g <= 1.0:
        return np.minimum(y, 1.0)
    k = float(knee)
    s = (g - k) / (1.0 - k)
    t = np.clip((y - k) / (g - k), 0.0, 1.0)
    return np.where(y <= k, y, k + (1.0 - k) * s * t / (1.0 + (s - 1.0) * t))


def develop(
    raw: RawImage | str | Path,
    *,
    demosaic: str = "bilinear",
    white_balance: Literal["camera", "auto", "daylight", "none"] | ArrayLike = "camera",
    space: str = "srgb",
    linear: bool = False,
    orient: bool = True,
    device: str = "cpu",
    transfer: str | None = None,
    auto_bright: bool = False,
    baseline_exposure: bool = False,
    highlight_rolloff: bool = False,
) -> Development:
    r"""Develop a raw image with imageform's own pipeline, keeping every stage.

    1. Linearise: :math:`x = (DN - B) / (W - B)` with B the black level of each photosite.
    2. White balance: :math:`x \cdot g_c` with the as-shot gains (or the ones given),
       scaled so the smallest gain is 1, clipped to [0, 1] (LibRaw's default highlight
       clipping).
    3. Demosaic with :func:`imageform.sensor.demosaic` (``demosaic`` names the method); a
       linear raw has every colour already and is not demosaiced. A DNG's OpcodeList3
       opcodes that :func:`read_raw` kept (WarpRectilinear, FixVignetteRadial, GainMap:
       ``metadata["opcodes_stage3"]``) are applied to this camera RGB, on the CPU, with a
       note (:mod:`imageform.io._dng_opcodes`).
    4. Camera RGB to XYZ: :math:`M = C^{-1}\,\mathrm{diag}(C\,\mathbf w)`, with C the
       colour matrix (XYZ to camera) and :math:`\mathbf w` the XYZ of D65's white (Y = 1),
       so that white-balanced white (1, 1, 1) maps to :math:`\mathbf w` (the normalisation
       of dcraw/LibRaw's ``cam_xyz_coeff``, which scales the rows of :math:`C` by its
       camera response to white). The file's calibration illuminant chooses between two
       matrices (:func:`read_raw`, LibRaw's rule) but is not adapted from: LibRaw, and
       Adobe's DNG SDK for a single matrix, take a white-balanced white as the output's
       white whatever the matrix's illuminant. A file with no colour matrix at all (LibRaw
       knows none for the camera either) is developed as if camera RGB were linear sRGB,
       with a note (:attr:`Development.notes`); a monochrome raw stays grey.
    5. Bradford chromatic adaptation from D65 to the output space's white (identity for
       sRGB, Display P3, Rec. 2020; D65 to D50 for ProPhoto RGB).
    6. XYZ to the output space's linear RGB, clipped to [0, 1], encoded with the space's
       transfer function (``linear=True``: not encoded).
    7. Turned for display as the file's orientation says (LibRaw's ``user_flip``).

    For a Bayer mosaic developed bilinearly, steps 1-6 are one pass over strips of rows, in
    float32, on numba's threads (:mod:`imageform._kernels.raw_develop`), run when the result
    is first read (:attr:`Development.image`, :meth:`Development.to_integer`); other methods
    demosaic the white-balanced mosaic first, then steps 4-6 are one pass.

    Parameters
    ----------
    raw : RawImage, str or Path
        From :func:`read_raw`, or a raw file's path.
    demosaic : str
        A method of :data:`imageform.sensor.DEMOSAIC_METHODS`.
    white_balance : "camera", "auto", "daylight", "none" or array_like (3,)
        The as-shot gains (a file with none: ``"auto"``, with a note, as LibRaw does),
        LibRaw's automatic white balance (the reciprocal of each colour's mean over the
        unsaturated 8 x 8 blocks, dcraw's ``-a``), LibRaw's daylight gains, none, or R, G, B
        gains. A monochrome raw has no colours to balance: its gains are 1.
    space : str
        An RGB space of :data:`imageform.color.RGB_SPACES` (``"srgb"``, ``"display_p3"``,
        ``"prophoto"``, ...).
    linear : bool
        Leave the output linear (no transfer function).
    orient : bool
        Turn the result as the file's orientation tag says (as LibRaw does by default);
        False keeps the sensor's orientation.
    transfer : str, optional
        The output's encoding, a name of :data:`imageform.color.TRANSFER_FUNCTIONS` other
        than ``"gamma"``; default the space's own (``"linear"`` is ``linear=True``).
        ``"rec709"`` is LibRaw's default curve (``gamma=(2.222, 4.5)``, BT.709).
    auto_bright : bool
        Brighten as LibRaw does by default (its ``no_auto_bright`` off): the linear output
        scaled so that 1 % of the pixels of its brightest channel reach white
        (:func:`_auto_bright`, :attr:`Development.brightness`). Off by default: the
        development's white is the sensor's.
    baseline_exposure : bool
        Brighten by the DNG's BaselineExposure, :math:`2^{EV}` on the linear output, as
        Adobe's DNG SDK does (DNG specification 1.4.0.0, chapter 4: the camera's
        recommended exposure offset; ``metadata["baseline_exposure_ev"]``, 1 where the
        file has none, with a note). LibRaw ignores the tag. Not with ``auto_bright``.
    highlight_rolloff : bool
        With ``baseline_exposure`` or ``auto_bright`` (a brightness g above 1): roll the
        brightened highlights off into white instead of clipping them. The linear output is
        kept up to 0.8 (the knee), then compressed by a smooth shoulder
        (:func:`_highlight_shoulder`, per channel) that reaches white exactly at the sensor's
        white (g): nothing clips that the sensor did not. Off by default: values above
        1/g of the sensor's white clip, as in Adobe's DNG SDK, whose exposure ramp
        (``dng_function_exposure_ramp``) clips them before its tone curve.
    device : {"cpu", "cuda"}
        Where steps 1-6 of a Bayer mosaic run. ``"cuda"``: bilinear and Malvar development
        as one CUDA kernel (:func:`imageform._cuda.demosaic.develop_bayer`: the mosaic copied
        to the GPU, every stage fused per pixel in float32, the result copied back; the CPU
        pass's arithmetic); other methods and linear raws stay on the CPU, with a note.
        Raises when no CUDA device is usable.

    Returns
    -------
    Development
        Every stage; ``.image`` is the result, ``.to_integer(8 or 16)`` its integer form.

    Raises
    ------
    InvalidInputError
        An unknown method, space or white balance; a raw file with no photosite above its
        black level (nothing to develop); ``device="cuda"`` with no usable CUDA device.
    """
    from imageform.color import RGB_SPACES
    from imageform.sensor import DEMOSAIC_METHODS
    from imageform.sensor import demosaic as _demosaic

    if isinstance(raw, (str, Path)):
        raw = read_raw(raw)
    if not isinstance(raw, RawImage):
        raise InvalidInputError(
            f"expected raw as a RawImage (read_raw) or a path, got {describe(raw)}"
        )
    if auto_bright and baseline_exposure:
        raise InvalidInputError(
            "auto_bright and baseline_exposure both set the brightness: give one of them"
        )
    where_to = str(device).lower()
    if where_to not in ("cpu", "cuda"):
        raise InvalidInputError(f"unknown device {device!r}; valid: cpu, cuda")
    if where_to == "cuda":
        from imageform._cuda.geometry import require_cuda

        require_cuda("device='cuda'")
    method = str(demosaic).lower().replace("-", "_")
    if method not in DEMOSAIC_METHODS:
        raise InvalidInputError(
            f"unknown demosaic method {demosaic!r}; valid: {', '.join(DEMOSAIC_METHODS)}"
        )
    key = str(space).lower().replace("-", "_")
    if key not in RGB_SPACES:
        raise InvalidInputError(f"unknown space {space!r}; valid: {', '.join(RGB_SPACES)}")
    out_space = RGB_SPACES[key]
    encoding = "linear" if linear else out_space.transfer
    if transfer is not None:
        from imageform.color import TRANSFER_FUNCTIONS

        named = str(transfer).lower().replace("-", "_")
        valid = [t for t in TRANSFER_FUNCTIONS if t != "gamma"]
        if named not in valid:
            raise InvalidInputError(f"unknown transfer {transfer!r}; valid: {', '.join(valid)}")
        if linear and named != "linear":
            raise InvalidInputError(f"linear=True and transfer={transfer!r} disagree")
        encoding = named
    notes: list[str] = []
    if (said := raw.metadata.get("white_level_libraw")) is not None:
        notes.append(
            f"note: the file's white level ({said:g}) is below most of its samples: "
            f"developed with white at {raw.white_level:g}, the samples' bit depth"
        )
    gains, site_gains = _gains(raw, white_balance, notes)
    where = raw.metadata.get("path") or "the raw image"
    black = np.asarray(raw.black_level, np.float64)
    peak = float(raw.mosaic.max()) if raw.mosaic.size else 0.0  # one pass over the mosaic
    if raw.mosaic.size == 0 or peak <= float(black.min()):
        raise InvalidInputError(
            f"{where}: no photosite is above the black level ({black.min():g}): nothing to develop"
        )
    span = raw.white_level - black
    if np.any(span <= 0):
        raise InvalidInputError(
            f"{where}: white level {raw.white_level:g} is not above the black level"
        )
    top = (peak - float(black.min())) / float(np.max(span))
    if top < _NEARLY_BLACK and not auto_bright and not baseline_exposure:
        notes.append(
            f"note: the frame is nearly black: its brightest photosite is {100 * top:.2g} % of "
            "the way from the black level to white (a dark frame, a lens cap?); "
            "auto_bright (--auto-bright) brightens it"
        )
    on_gpu = where_to == "cuda" and raw.cfa_pattern is not None and method in _CUDA_METHODS
    if where_to == "cuda" and not on_gpu:
        what = method + " demosaicing"
        if raw.cfa_pattern is None:
            what = "a monochrome raw" if raw.monochrome else "a linear raw"
        notes.append(
            f"note: {what} is developed on the CPU (the CUDA kernel does bilinear and malvar "
            "Bayer mosaics)"
        )
    h, w = raw.mosaic.shape[:2]
    if h < 2 or w < 2:
        raise InvalidInputError(
            f"{where}: expected a raw image of at least 2x2 pixels, got {h}x{w}"
        )
    # 1-3. linearise and white-balance, demosaic: the fused pass for a bilinear Bayer mosaic
    cam: np.ndarray | None = None
    if raw.cfa_pattern is None:  # a linear raw (every pixel has its colours) or a grey one
        cam = (raw.mosaic[..., None] if raw.monochrome else raw.mosaic).astype(np.float32)
        # each row's samples as one run of W * C against the channels' values repeated W
        # times: the same float32 operations as broadcasting the (C,) values, ten times faster
        # (a broadcast over a last axis of 3 runs numpy's inner loop 3 samples at a time)
        zero, factor = (
            black.astype(np.float32),
            (gains[: cam.shape[-1]] / span).astype(np.float32),
        )
        if zero.ndim == 1 and factor.ndim == 1 and zero.size == factor.size == cam.shape[-1]:
            rows = cam.reshape(cam.shape[0], -1)
            rows -= np.tile(zero, cam.shape[1])
            rows *= np.tile(factor, cam.shape[1])
        else:  # levels of another shape (a RawImage made by hand): broadcast as given
            cam -= zero
            cam *= factor
        np.clip(cam, 0.0, 1.0, out=cam)
        if raw.monochrome:  # the three channels of a grey image
            cam = np.repeat(cam, 3, axis=-1)
        xtrans = raw.metadata.get("xtrans")
        if xtrans and method != "bilinear":
            notes.append(
                f"note: an X-Trans CFA (first row {xtrans}) is demosaiced by LibRaw's linear "
                f"interpolation; {method} demosaicing is for 2x2 Bayer tiles"
            )
        method = "libraw_linear" if xtrans else "none"
    elif method != "bilinear" and not on_gpu:
        scale = (site_gains / span).astype(np.float32)
        black32 = black.astype(np.float32)
        balanced = raw.mosaic.astype(np.float32)
        for i in (0, 1):
            for j in (0, 1):
                site = balanced[i::2, j::2]
                site -= black32[i, j]
                site *= scale[i, j]
        np.clip(balanced, 0.0, 1.0, out=balanced)
        cam = np.asarray(_demosaic(balanced, raw.cfa_pattern, method, allow_odd=True))
        del balanced
        cam = np.ascontiguousarray(cam, dtype=np.float32)
    # 4. camera RGB -> XYZ, white-balanced white on D65's (LibRaw's cam_xyz_coeff); the
    # cached matrices are read-only: the Development gets its own (a caller may change them)
    white, srgb_to_xyz, cat, to_rgb = _space_matrices(key)
    if raw.xyz_to_camera is not None:
        C = np.asarray(raw.xyz_to_camera, np.float64)
        cam_to_xyz = np.linalg.inv(C) @ np.diag(C @ white)
    elif raw.monochrome:  # grey in linear sRGB: grey in any output space
        cam_to_xyz = srgb_to_xyz.copy()
    elif np.any(np.asarray(raw.camera_to_srgb)):  # LibRaw's camera -> sRGB only
        cam_to_xyz = srgb_to_xyz @ np.asarray(raw.camera_to_srgb, np.float64)
    else:  # no colour matrix, and LibRaw knows none for this camera
        cam_to_xyz = srgb_to_xyz.copy()
        notes.append(
            "note: the file has no colour matrix and LibRaw knows none for this camera: "
            "camera RGB developed as if it were linear sRGB"
        )
    # 5. adaptation to the output space's white (cat); 6. output space, clip, encode: one pass
    m = (to_rgb @ cat @ cam_to_xyz).astype(np.float32)
    dev = Development(
        raw=raw,
        gains=gains,
        camera_rgb=cam,
        render=m,
        table=None if encoding == "linear" else _transfer_table(encoding),
        camera_to_xyz=cam_to_xyz,
        adaptation=cat.copy(),
        space=key,
        transfer=encoding,
        demosaic=method,
        orientation=raw.orientation if orient else 0,
        notes=tuple(notes),
        device="cuda" if on_gpu else "cpu",
        site_gains=site_gains if raw.cfa_pattern is not None else None,
    )
    stage3 = raw.metadata.get("opcodes_stage3") or ()
    if stage3:  # OpcodeList3: on the demosaiced camera RGB, before the matrix (on the CPU)
        from imageform.io._dng_opcodes import stage3_name

        offset, area = raw.metadata.get("opcodes_area") or ((0, 0), None)
        dev._stage3 = (tuple(stage3), offset, area)  # applied when first read
        names = ", ".join(dict.fromkeys(stage3_name(op) for op in stage3))
        where_run = " (on the CPU, after the GPU's demosaicing)" if on_gpu else ""
        dev.notes = (*dev.notes, f"applied the DNG's {names} after demosaicing{where_run}")
    if auto_bright:
        dev.brightness = _auto_bright(dev._sensor_camera_rgb(), m)
        dev._render = (m * np.float32(dev.brightness)).astype(np.float32)
    elif baseline_exposure:
        ev = raw.metadata.get("baseline_exposure_ev")
        if ev is None:
            dev.notes = (*dev.notes, "the file has no BaselineExposure: not brightened")
        else:
            dev.brightness = float(2.0 ** float(ev))
            dev._render = (m * np.float32(dev.brightness)).astype(np.float32)
    if highlight_rolloff and dev.brightness > 1.0:
        # the gain and its shoulder in the transfer table: the matrix stays unbrightened, so
        # the linear values reach the table unclipped up to the sensor's white
        dev.highlight_rolloff = True
        dev._render = m
        dev._table = _transfer_table(encoding, dev.brightness)
    elif highlight_rolloff:  # asked for, but nothing brightened to roll off
        dev.notes = (
            *dev.notes,
            "highlight roll-off changes nothing here: nothing was brightened (it acts with "
            "baseline_exposure on a positive BaselineExposure, or with auto_bright)",
        )
    return dev


@functools.cache
def _space_matrices(key: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Return D65's white (XYZ), sRGB to XYZ, the adaptation to ``key``'s white, XYZ to ``key``.

    Computed once per space, read-only.
    """
    from imageform.color import (
        RGB_SPACES,
        chromatic_adaptation_matrix,
        rgb_to_xyz_matrix,
        whitepoint_xy,
        xy_to_xyz_white,
    )

    out_space = RGB_SPACES[key]
    white = np.asarray(xy_to_xyz_white(whitepoint_xy("D65")), np.float64)
    srgb_to_xyz = np.asarray(rgb_to_xyz_matrix("srgb"), np.float64)
    dst_white = np.asarray(xy_to_xyz_white(out_space.white_xy), np.float64)
    src_xy = white[:2] / white.sum()
    if np.allclose(src_xy, np.asarray(out_space.white_xy), atol=5e-4):  # the same white
        cat = np.eye(3)
    else:
        cat = np.asarray(chromatic_adaptation_matrix(white, dst_white, "bradford"), np.float64)
    to_rgb = np.linalg.inv(np.asarray(rgb_to_xyz_matrix(key), np.float64))
    out = (white, srgb_to_xyz, cat, to_rgb)
    for m in out:
        m.setflags(write=False)  # computed once (functools.cache): read, never written
    return out


def _not_raw(p: Path) -> str | None:
    """Name the ordinary image LibRaw was given (``develop photo.png``), else ``None``.

    Named by its first bytes (whatever its suffix), not a TIFF (several cameras' raw files
    are TIFFs): a photograph is not developed.
    """
    from imageform.io.image_io import _content_format

    try:
        fmt = _content_format(p, "")  # "" when no image format's signature is there
    except UnreadableFileError:  # an image format imageform does not read either
        return None
    if fmt in ("", "tiff", "npy"):
        return None
    name = {"jpeg": "JPEG", "netpbm": "Netpbm", "dicom": "DICOM", "heif": "HEIF"}.get(
        fmt, fmt.upper()
    )
    return (
        f"it is a {name} image, not a camera raw file (a DNG, CR2, NEF, ARW, RAF, ... as the "
        "camera wrote it): it has been developed already (imageform convert reads it)"
    )


def _auto_bright(camera_rgb: np.ndarray, render: np.ndarray) -> float:
    """Return LibRaw's automatic brightening factor of a development (dcraw's auto-bright).

    LibRaw's ``dcraw_make_mem_image`` (``no_auto_bright`` off, ``auto_bright_thr`` 0.01,
    ``bright`` 1): a histogram of each channel of the linear output as 16-bit codes in bins
    of 8; from the top, the first bin above 32 at which more than 1 % of the pixels lie at or
    above it; the largest such bin over the channels, times 8, is taken as white (the factor
    65535 over it, at least 1). Computed on the output's linear RGB, clipped to [0, 1].
    """
    lin = camera_rgb.reshape(-1, 3) @ np.asarray(render, np.float32).T
    np.clip(lin, 0.0, 1.0, out=lin)
    perc = int(lin.shape[0] * 0.01)
    t_white = 0
    for c in range(3):
        bins = np.bincount((lin[:, c] * 65535.0).astype(np.int64) >> 3, minlength=8192)[:8192]
        above = np.cumsum(bins[::-1])[::-1]  # pixels at or above each bin
        hit = np.nonzero(above[33:] > perc)[0]
        t_white = max(t_white, 33 + int(hit[-1]) if hit.size else 32)
    return 65535.0 / (8.0 * t_white)


def _auto_gains(raw: RawImage) -> np.ndarray:
    """Return LibRaw's automatic white balance multipliers of a raw image.

    dcraw's ``-a`` (LibRaw's ``use_auto_wb``, and its fallback for ``use_camera_wb`` when a
    file has no as-shot balance): the image is cut into 8 x 8 blocks from its top-left
    corner; a block with any photosite above ``white_level - 25`` is skipped; over the
    others each colour's multiplier is its count over its sum of (DN - black, floored at 0),
    the reciprocal of its mean. For a Bayer mosaic, the multiplier of each photosite of the
    2x2 tile, (2, 2): LibRaw counts the two greens as two colours (its ``pre_mul[1]`` and
    ``[3]``) and scales them apart, which takes out the sensor's green imbalance (pooled, a
    real Canon file developed 0.18 ΔE00 from LibRaw, apart 0.02); for a linear raw, (R, G, B).
    Unnormalised (None where a colour has no sum).
    """
    m = np.asarray(raw.mosaic)
    h, w = m.shape[:2]
    hb, wb = -(-h // 8), -(-w // 8)
    pad = np.zeros((hb * 8, wb * 8, *m.shape[2:]), m.dtype)
    pad[:h, :w] = m
    # block reductions in two steps, the 8 rows then the 8 columns (six times faster than
    # one reduction over a 5-D view)
    rest = m.shape[2:]
    peak = pad.reshape(hb, 8, wb * 8, *rest).max(axis=1).reshape(hb, wb, 8, *rest).max(axis=2)
    ok = (peak.max(axis=-1) if m.ndim == 3 else peak) <= raw.white_level - 25
    val = pad.astype(np.float32)  # the padding: 0, below black, so it adds nothing
    del pad

    def real(n: int, blocks: int, parity: int, step: int) -> np.ndarray:
        """How many of each block's rows (columns) are in the image, of one parity."""
        return np.array(
            [len(range(8 * k + parity, min(8 * k + 8, n), step)) for k in range(blocks)], float
        )

    if m.ndim == 3:
        val -= np.asarray(raw.black_level, np.float32)
        np.maximum(val, 0.0, out=val)
        rows = val.reshape(hb, 8, wb * 8, 3).sum(axis=1, dtype=np.float64)
        sums = rows.reshape(hb, wb, 8, 3).sum(axis=2)[ok].sum(axis=0)
        inside = np.outer(real(h, hb, 0, 1), real(w, wb, 0, 1))
        counts = np.full(3, float(inside[ok].sum()))
    else:
        tile = val.reshape(hb * 4, 2, wb * 4, 2)
        tile -= np.asarray(raw.black_level, np.float32).reshape(1, 2, 1, 2)
        np.maximum(val, 0.0, out=val)
        # each block's sum over each photosite of the tile: (hb, 2, wb, 2)
        rows = val.reshape(hb, 4, 2, wb * 8).sum(axis=1, dtype=np.float64)  # (hb, 2, W)
        per = rows.reshape(hb, 2, wb, 4, 2).sum(axis=3)  # (hb, 2, wb, 2)
        sums = per.transpose(0, 2, 1, 3)[ok].sum(axis=0)
        counts = np.array(
            [
                [np.outer(real(h, hb, i, 2), real(w, wb, j, 2))[ok].sum() for j in (0, 1)]
                for i in (0, 1)
            ]
        )
    if np.any(sums <= 0):
        return np.ones(sums.shape)
    return np.asarray(counts / sums, np.float64)


def _gains(raw: RawImage, white_balance: Any, notes: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """Return the white balance gains (R, G, B) and each photosite's; notes in ``notes``.

    The second value is the gain of each photosite of a Bayer mosaic's 2x2 tile (its
    colour's gain, but for the automatic white balance, whose two greens have their own
    gains, as LibRaw's); the gains of the three channels for a linear raw. The smallest
    gain is 1. ``"camera"`` for a file with no as-shot white balance falls back, as
    LibRaw's ``use_camera_wb`` does, to its automatic white balance (:func:`_auto_gains`),
    with a note; a monochrome sensor has no colours to balance (gains 1, whatever was
    asked).
    """
    bayer = raw.cfa_pattern is not None
    idx = np.array(_cfa_indices(str(raw.cfa_pattern))).reshape(2, 2) if bayer else None
    if raw.monochrome:
        return np.ones(3), np.ones(3)
    if isinstance(white_balance, str):
        wb = white_balance.lower()
        if wb == "camera" and raw.white_balance is None:
            notes.append(
                "note: the file has no as-shot white balance: gains from the image's "
                "average (LibRaw's automatic white balance)"
            )
            wb = "auto"
        if wb == "camera":
            g = np.asarray(raw.white_balance, np.float64)
        elif wb == "auto":
            mul = _auto_gains(raw)
            if idx is None:
                return mul / mul.min(), mul / mul.min()
            g = np.zeros(3)
            for c in range(3):  # a colour's gain: its first photosite's in the tile
                g[c] = mul[np.argwhere(idx == c)[0][0], np.argwhere(idx == c)[0][1]]
            return g / mul.min(), mul / mul.min()
        elif wb == "daylight":
            day = raw.metadata.get("daylight_white_balance")
            if day is None:
                raise InvalidInputError("white_balance='daylight': the file has no daylight gains")
            g = np.asarray(day, np.float64)
        elif wb == "none":
            g = np.ones(3)
        else:
            raise InvalidInputError(
                f"unknown white_balance {white_balance!r}; valid: camera, auto, daylight, "
                "none, or three gains"
            )
    else:
        g = np.asarray(white_balance, np.float64)
        if g.shape != (3,) or not np.all(np.isfinite(g)) or np.any(g <= 0):
            raise InvalidInputError(
                f"expected white_balance as 3 positive gains, got {describe(white_balance)}"
            )
    g = g / g.min()
    return g, (g[idx] if idx is not None else g)
