"""DNG opcode lists: the GainMap of OpcodeList2 (lens shading) applied to a raw's mosaic.

A DNG may carry three opcode lists (DNG 1.3+, Adobe DNG Specification 1.7.1, chapter 7):
OpcodeList1 for the raw data as stored, OpcodeList2 once it is linearized (black subtracted,
scaled to [0, 1]), OpcodeList3 after demosaicing. Phones write their lens-shading
correction as GainMap opcodes in OpcodeList2 (often four, one per photosite of the 2x2
tile); a reader that skips them (LibRaw does) gives an image that darkens and changes
colour towards the corners. Here the GainMaps are applied; every other opcode is named
in the raw's metadata as not applied.

Each list is big-endian: the opcode count, then per opcode its id, the DNG version it
needs, flags (bit 0: optional) and the byte count of its parameters. A GainMap's
parameters are an area (top, left, bottom, right, plane, planes, row pitch, column pitch)
and a map: points vertically and horizontally, the spacing and origin of the points
(as fractions of the image's height and width), the map's planes and its float32 gains,
point by point (rows, columns, planes). A pixel at row ``r`` of an image of height ``H``
sits at ``v = (r + 0.5) / H``; its map row is ``(v - origin) / spacing``, clamped to the
map, and the gain is bilinear between the four nearest points (the DNG SDK's
``dng_gain_map_interpolator``). The linear value ``x`` becomes ``min(x * gain, 1)``.

OpcodeList3 applies to the demosaiced linear camera RGB, before the colour matrix; three of
its opcodes are parsed here and applied by :func:`imageform.io.develop`
(:func:`apply_stage3`), as Adobe's DNG SDK does (``dng_filter_warp``,
``dng_opcode_FixVignetteRadial``), for an image of ``H`` rows and ``W`` columns (the raw
image after its ActiveArea crop; pixel ``(r, c)`` is at ``(r, c)``, its centre, for the warp,
at ``(r + 0.5, c + 0.5)`` for the vignette, as the SDK counts):

- WarpRectilinear (id 1): per plane ``kr0..kr3, kt0, kt1`` and the optical centre
  ``(cx, cy)`` in fractions of the width and height. The centre sits at ``(cy H, cx W)``;
  distances are normalised by ``R``, the largest distance from it to the image's corners
  ``(0, 0), (0, W), (H, 0), (H, W)``. An output pixel at ``(dy, dx)`` from the centre
  (normalised: ``(y, x) = (dy, dx) / R``, ``r2 = min(x^2 + y^2, 1)``) samples the input at
  ``centre + R ((y, x) f + (ty, tx))`` with ``f = kr0 + kr1 r2 + kr2 r2^2 + kr3 r2^3``,
  ``ty = kt0 (r2 + 2 y^2) + 2 kt1 x y`` and ``tx = kt1 (r2 + 2 x^2) + 2 kt0 x y``. The
  position is clamped to the image; the value is the SDK's resampling: Keys' bicubic
  kernel (a = -0.75), 4 x 4 taps, the fraction floored to 1/32 of a pixel, edge pixels
  repeated, the result clamped to [0, 1]. One plane of coefficients serves every plane.
- FixVignetteRadial (id 3): ``k0..k4`` and the centre ``(cx, cy)``; with ``R`` the
  distance from the centre to the farthest corner of the image's bounding box and
  ``r2 = min(d^2 / R^2, 1)`` (``d`` the distance of the pixel's centre), the value ``x``
  becomes ``min(x g, 1)``, ``g = 1 + k0 r2 + k1 r2^2 + k2 r2^3 + k3 r2^4 + k4 r2^5``
  (computed exactly here; the SDK reads ``g`` from a 16-bit table of ``r2``, within about
  1e-4 of it).
- GainMap (id 9), as in OpcodeList2 but on the demosaiced planes (DJI's drones write their
  lens and colour shading there, one map plane per colour): each plane ``p`` of the
  opcode's range takes map plane ``min(p, map planes - 1)`` (the SDK's
  ``dng_opcode_GainMap``), over the area's lattice, ``x`` becoming ``min(x g, 1)``.
"""

from __future__ import annotations

import functools
import struct
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "OPCODE_NAMES",
    "AreaOpcode",
    "FixBadPixelsConstant",
    "FixVignetteRadial",
    "GainMap",
    "WarpRectilinear",
    "apply_gain_maps",
    "apply_stage2",
    "apply_stage3",
    "bicubic_sample",
    "fix_bad_pixels_constant",
    "gain_map_gains",
    "lossy_dng_curves",
    "parse_opcode_list",
    "read_opcodes",
    "render_warped",
    "render_warped_mosaic",
    "stage2_name",
    "stage3_name",
    "vignette_gains",
    "warp_source_positions",
]

#: The opcodes of the DNG specification 1.7.1, by id.
OPCODE_NAMES = {
    1: "WarpRectilinear",
    2: "WarpFisheye",
    3: "FixVignetteRadial",
    4: "FixBadPixelsConstant",
    5: "FixBadPixelsList",
    6: "TrimBounds",
    7: "MapTable",
    8: "MapPolynomial",
    9: "GainMap",
    10: "DeltaPerRow",
    11: "DeltaPerColumn",
    12: "ScalePerRow",
    13: "ScalePerColumn",
    14: "WarpRectilinear2",
}

_OPCODE_LISTS = {51008: "OpcodeList1", 51009: "OpcodeList2", 51022: "OpcodeList3"}
_GAIN_MAP = 9
_WARP_RECTILINEAR = 1
_FIX_VIGNETTE_RADIAL = 3
_FIX_BAD_PIXELS_CONSTANT = 4


@dataclass(frozen=True)
class GainMap:
    """One GainMap opcode: where it applies and its gains.

    ``top, left, bottom, right`` bound the pixels it applies to (the raw image after its
    ActiveArea crop), every ``row_pitch``-th row and ``col_pitch``-th column from the
    top left; ``plane, planes`` the samples (0 for a CFA mosaic); ``gains`` (points_v,
    points_h, map_planes) float32 at ``origin + k * spacing`` (fractions of the image).
    """

    top: int
    left: int
    bottom: int
    right: int
    plane: int
    planes: int
    row_pitch: int
    col_pitch: int
    spacing: tuple[float, float]
    origin: tuple[float, float]
    gains: np.ndarray


def _parse_gain_map(data: bytes) -> GainMap | None:
    """Return the GainMap of an opcode's parameters, or None where they do not parse."""
    if len(data) < 76:
        return None
    top, left, bottom, right, plane, planes, rp, cp = struct.unpack(">8I", data[:32])
    nv, nh = struct.unpack(">2I", data[32:40])
    sv, sh, ov, oh = struct.unpack(">4d", data[40:72])
    (map_planes,) = struct.unpack(">I", data[72:76])
    if nv == 1:
        sv, ov = 1.0, 0.0
    if nh == 1:
        sh, oh = 1.0, 0.0
    n = nv * nh * map_planes
    ok = nv >= 1 and nh >= 1 and map_planes >= 1 and sv > 0 and sh > 0 and rp >= 1 and cp >= 1
    if not ok or len(data) < 76 + 4 * n or not (np.isfinite(ov) and np.isfinite(oh)):
        return None
    gains = np.frombuffer(data, dtype=">f4", count=n, offset=76).astype(np.float32)
    return GainMap(
        top, left, bottom, right, plane, max(planes, 1), rp, cp, (sv, sh), (ov, oh),
        gains.reshape(nv, nh, map_planes),
    )  # fmt: skip


@dataclass(frozen=True)
class AreaOpcode:
    """A per-row, per-column or per-value opcode of OpcodeList2 over an area of the image.

    ``name`` is ``"MapPolynomial"``, ``"DeltaPerRow"``, ``"DeltaPerColumn"``,
    ``"ScalePerRow"`` or ``"ScalePerColumn"``; ``area`` (top, left, bottom, right, plane,
    planes, row pitch, column pitch) as a GainMap's (an empty rectangle: the whole image);
    ``values`` the polynomial's coefficients (constant first) or the table, one value per
    row (column) of the area's lattice.
    """

    name: str
    area: tuple[int, int, int, int, int, int, int, int]
    values: np.ndarray


_AREA_OPCODES = {8: "MapPolynomial", 10: "DeltaPerRow", 11: "DeltaPerColumn",
                 12: "ScalePerRow", 13: "ScalePerColumn"}  # fmt: skip


def _parse_area_opcode(op: int, data: bytes) -> AreaOpcode | None:
    """Return an area opcode's parameters, or None where they do not parse (the SDK's checks).

    MapPolynomial: the area, the degree (at most 8), its coefficients (float64). The
    others: the area, the count (``ceil(rows / row pitch)`` or ``ceil(columns / column
    pitch)`` of the area), the table (float32).
    """
    if len(data) < 36:
        return None
    area = struct.unpack(">8I", data[:32])
    (n,) = struct.unpack(">I", data[32:36])
    top, left, bottom, right, _plane, _planes, rp, cp = area
    if rp < 1 or cp < 1 or bottom < top or right < left:
        return None
    name = _AREA_OPCODES[op]
    if name == "MapPolynomial":
        if n > 8 or len(data) != 36 + 8 * (n + 1):
            return None
        values = np.frombuffer(data, ">f8", n + 1, 36).astype(np.float64)
    else:
        span, pitch = (bottom - top, rp) if name.endswith("Row") else (right - left, cp)
        if n != -(-span // pitch) or len(data) != 36 + 4 * n:
            return None
        values = np.frombuffer(data, ">f4", n, 36).astype(np.float64)
    if not np.all(np.isfinite(values)):
        return None
    return AreaOpcode(name, area, values)


def parse_opcode_list(data: bytes) -> list[tuple[int, int, bytes]]:
    """Return ``(id, flags, parameters)`` of each opcode of a list; [] where it is broken."""
    if len(data) < 4:
        return []
    (count,) = struct.unpack(">I", data[:4])
    out: list[tuple[int, int, bytes]] = []
    at = 4
    for _ in range(count):
        if at + 16 > len(data):
            return []
        op, _version, flags, size = struct.unpack(">4I", data[at : at + 16])
        at += 16
        if at + size > len(data):
            return []
        out.append((op, flags, data[at : at + size]))
        at += size
    return out


@dataclass(frozen=True)
class FixBadPixelsConstant:
    """One FixBadPixelsConstant opcode (OpcodeList1): the bad pixels' code and Bayer phase.

    ``bayer_phase`` (0 to 3) says which pixels are green, by the SDK's rule: those where
    ``row + col + phase + phase // 2`` is even (``dng_opcode_FixBadPixelsConstant::IsGreen``).
    """

    constant: int
    bayer_phase: int


def _parse_bad_pixels_constant(data: bytes) -> FixBadPixelsConstant | None:
    """Return the opcode's parameters (8 bytes: constant, phase), or None."""
    if len(data) != 8:
        return None
    constant, phase = struct.unpack(">2I", data)
    return FixBadPixelsConstant(constant, phase) if phase <= 3 else None


def fix_bad_pixels_constant(
    mosaic: np.ndarray, op: FixBadPixelsConstant, origin: tuple[int, int] = (0, 0)
) -> np.ndarray:
    """Return ``mosaic`` (a 2-D uint16 CFA) with the pixels equal to the constant replaced.

    As the SDK's ``dng_opcode_FixBadPixelsConstant``: a green pixel (``(row + col + phase +
    phase // 2)`` even, in the coordinates of the stored image: ``origin`` is where the
    mosaic's first pixel sits there) takes the mean of its four diagonal neighbours, a red
    or blue one of the four two pixels away in its row and column, each counted only where
    it is not bad itself, rounded half up; a pixel with no good neighbour stays. Neighbours
    outside the mosaic are not counted (the SDK reads them from the stored image's margin).
    """
    m = np.asarray(mosaic)
    bad = m == op.constant
    if m.ndim != 2 or not bad.any():
        return m
    h, w = m.shape
    r, c = np.nonzero(bad)
    green = ((r + origin[0] + c + origin[1] + op.bayer_phase + (op.bayer_phase >> 1)) & 1) == 0
    steps_green = ((-1, -1), (-1, 1), (1, -1), (1, 1))
    steps_other = ((-2, 0), (2, 0), (0, -2), (0, 2))
    total = np.zeros(r.size, np.int64)
    count = np.zeros(r.size, np.int64)
    for (gy, gx), (oy, ox) in zip(steps_green, steps_other, strict=True):
        rr = np.where(green, r + gy, r + oy)
        cc = np.where(green, c + gx, c + ox)
        inside = (rr >= 0) & (rr < h) & (cc >= 0) & (cc < w)
        value = m[np.clip(rr, 0, h - 1), np.clip(cc, 0, w - 1)].astype(np.int64)
        good = inside & (value != op.constant)
        total += np.where(good, value, 0)
        count += good
    out = m.copy()
    fixed = count > 0
    out[r[fixed], c[fixed]] = (total[fixed] + (count[fixed] >> 1)) // count[fixed]
    return out


@dataclass(frozen=True)
class WarpRectilinear:
    """One WarpRectilinear opcode: ``coefficients`` (planes, 6) ``kr0..kr3, kt0, kt1``.

    ``center`` is the optical centre ``(cx, cy)``, fractions of the width and height.
    """

    coefficients: np.ndarray
    center: tuple[float, float]


@dataclass(frozen=True)
class FixVignetteRadial:
    """One FixVignetteRadial opcode: ``k`` the five coefficients ``k0..k4``, ``center`` (cx, cy)."""

    k: tuple[float, float, float, float, float]
    center: tuple[float, float]


#: An opcode of OpcodeList3 that :func:`apply_stage3` applies.
Stage3Opcode = WarpRectilinear | FixVignetteRadial | GainMap

#: An opcode of OpcodeList2 that :func:`apply_stage2` applies.
Stage2Opcode = GainMap | FixVignetteRadial | AreaOpcode


def _parse_warp(data: bytes) -> WarpRectilinear | None:
    """Return the WarpRectilinear of an opcode's parameters, or None where they do not parse.

    As the SDK checks: the byte count exactly ``4 + 48 planes + 16``, a centre inside
    [0, 1], finite coefficients; the planes 1 or 3 (one set for every colour, or one each
    of camera RGB: the SDK's rule that they are 1 or the image's colour count).
    """
    if len(data) < 4:
        return None
    (planes,) = struct.unpack(">I", data[:4])
    if planes not in (1, 3) or len(data) != 4 + 48 * planes + 16:
        return None
    values = np.array(struct.unpack(f">{6 * planes + 2}d", data[4:]), np.float64)
    cx, cy = (float(v) for v in values[-2:])
    if not np.all(np.isfinite(values)) or not (0 <= cx <= 1 and 0 <= cy <= 1):
        return None
    return WarpRectilinear(values[:-2].reshape(planes, 6), (cx, cy))


def _parse_vignette(data: bytes) -> FixVignetteRadial | None:
    """Return the FixVignetteRadial of an opcode's parameters, or None where they do not parse."""
    if len(data) != 56:
        return None
    values = struct.unpack(">7d", data)
    cx, cy = values[5:]
    if not all(np.isfinite(values)) or not (0 <= cx <= 1 and 0 <= cy <= 1):
        return None
    k0, k1, k2, k3, k4 = values[:5]
    return FixVignetteRadial((k0, k1, k2, k3, k4), (cx, cy))


@functools.lru_cache(maxsize=1)
def _srgb_decoding_curve() -> np.ndarray:
    """Return LibRaw's curve of a lossy DNG without MapPolynomial: 256 codes to 0..65535.

    dcraw's ``gamma_curve(1/2.4, 12.92, 1, 255)``: the inverse of a power 1/2.4 with a linear
    segment of slope 12.92 near black, the junction ``t`` and offset ``a = t (2.4 - 1)``
    solved so that both the curve and its slope are continuous (48 bisections, as dcraw),
    ``x = v / 12.92`` below ``t``, ``((v + a) / (1 + a))^2.4`` above; times 65536,
    65535 at v = 255.
    """
    g, slope = 1 / 2.4, 12.92
    lo, hi = 0.0, 1.0
    t = 0.5
    for _ in range(48):
        t = (lo + hi) / 2
        if ((t / slope) ** -g - 1) / g - 1 / t > -1:
            hi = t
        else:
            lo = t
    a = t * (1 / g - 1)
    v = np.arange(256) / 255.0
    x = np.where(v < t, v / slope, ((v + a) / (1 + a)) ** (1 / g))
    curve = np.minimum(np.floor(x * 65536.0), 65535).astype(np.uint16)
    curve.flags.writeable = False  # computed once (lru_cache): read, never written
    return curve


def lossy_dng_curves(data: bytes | None) -> tuple[np.ndarray, int]:
    """Return the curves LibRaw maps a lossy DNG's 8-bit samples with, and the opcodes used.

    A lossy DNG (Compression 34892, 8-bit JPEG; Adobe's converters write them) stores its
    samples encoded; LibRaw's ``lossy_dng_load_raw`` decodes them through a 256-entry
    curve per sample plane, taken from the MapPolynomial opcodes of OpcodeList2 (``data``):
    each, in the list's order, sets its plane's curve to ``floor(65535 p(v / 255))`` (its
    area and pitch not read), until one's plane is over 3 or its degree over 8. Without an
    OpcodeList2 every plane gets :func:`_srgb_decoding_curve`, as it does here for a plane
    no polynomial sets (LibRaw leaves that one undefined). Returns the (4, 256) uint16
    curves and how many of the list's first MapPolynomials they used: those are applied
    when decoding, and not again. The curves are computed once per OpcodeList2 and are
    read-only (index with them; copy them to change them).
    """
    return _lossy_dng_curves(bytes(data or b""))


@functools.lru_cache(maxsize=16)
def _lossy_dng_curves(data: bytes) -> tuple[np.ndarray, int]:
    """:func:`lossy_dng_curves`, computed once per OpcodeList2 (a camera's): read only."""
    curves = np.tile(_srgb_decoding_curve(), (4, 1))
    used = 0
    v = np.arange(256) / 255.0
    for op, _flags, params in parse_opcode_list(data):
        if op != 8:
            continue
        if len(params) < 36:
            break
        plane = struct.unpack(">I", params[16:20])[0]
        degree = struct.unpack(">I", params[32:36])[0]
        if plane > 3 or degree > 8 or len(params) < 36 + 8 * (degree + 1):
            break
        c = np.frombuffer(params, ">f8", degree + 1, 36).astype(np.float64)
        total = sum(c[j] * v**j for j in range(degree + 1))
        curves[plane] = np.clip(np.floor(total * 65535.0), 0, 65535).astype(np.uint16)
        used += 1
    curves.flags.writeable = False
    return curves, used


def read_opcodes(
    page: Any, *, decoded: int = 0
) -> tuple[list[FixBadPixelsConstant], list[Stage2Opcode], list[Stage3Opcode], list[str]]:
    """Return the opcodes of OpcodeList1, 2 and 3 to apply, and the names of the rest.

    ``decoded``: how many of OpcodeList2's first MapPolynomials the decoder applied (a
    lossy DNG's, :func:`lossy_dng_curves`); they are left out (neither applied nor named).

    ``page`` is the tifffile page of the raw image. OpcodeList1's (FixBadPixelsConstant),
    OpcodeList2's (GainMap,
    FixVignetteRadial, MapPolynomial, Delta/ScalePerRow/Column) and OpcodeList3's
    (WarpRectilinear, FixVignetteRadial) are in their list's order. The names of the
    opcodes not applied are ``"OpcodeList1:FixBadPixelsList"`` (an unknown id by its
    number; an opcode this module applies whose parameters do not parse as
    ``"OpcodeList3:WarpRectilinear:unreadable"``; a list that does not parse as
    ``"OpcodeList2:unreadable"``).
    """
    stage1: list[FixBadPixelsConstant] = []
    maps: list[Stage2Opcode] = []
    stage3: list[Stage3Opcode] = []
    skipped: list[str] = []
    tags = page.tags
    left_out = decoded
    for code, name in _OPCODE_LISTS.items():
        if code not in tags:
            continue
        value = tags[code].value
        data = bytes(value) if not isinstance(value, bytes) else value
        ops = parse_opcode_list(data)
        if not ops and len(data) > 4 and struct.unpack(">I", data[:4])[0] > 0:
            skipped.append(f"{name}:unreadable")
            continue
        for op, _flags, params in ops:
            label = f"{name}:{OPCODE_NAMES.get(op, str(op))}"
            if code == 51009 and op == 8 and left_out > 0:
                left_out -= 1
                continue
            if code == 51008 and op == _FIX_BAD_PIXELS_CONSTANT:
                fix = _parse_bad_pixels_constant(params)
                if fix is not None:
                    stage1.append(fix)
                    continue
                label += ":unreadable"
            elif code == 51009 and op in (_GAIN_MAP, _FIX_VIGNETTE_RADIAL, *_AREA_OPCODES):
                stage2: Stage2Opcode | None
                if op == _GAIN_MAP:
                    stage2 = _parse_gain_map(params)
                elif op == _FIX_VIGNETTE_RADIAL:
                    stage2 = _parse_vignette(params)
                else:
                    stage2 = _parse_area_opcode(op, params)
                if stage2 is not None:
                    maps.append(stage2)
                    continue
                label += ":unreadable"
            elif op in (_WARP_RECTILINEAR, _FIX_VIGNETTE_RADIAL, _GAIN_MAP) and code == 51022:
                parse3 = {_WARP_RECTILINEAR: _parse_warp, _FIX_VIGNETTE_RADIAL: _parse_vignette,
                          _GAIN_MAP: _parse_gain_map}[op]  # fmt: skip
                parsed = parse3(params)
                if parsed is not None:
                    stage3.append(parsed)
                    continue
                label += ":unreadable"
            skipped.append(label)
    return stage1, maps, stage3, skipped


def stage3_name(op: Stage3Opcode) -> str:
    """Return an OpcodeList3 opcode's name, ``"OpcodeList3:WarpRectilinear"``."""
    return "OpcodeList3:" + type(op).__name__


def stage2_name(op: Stage2Opcode) -> str:
    """Return an OpcodeList2 opcode's name, ``"OpcodeList2:GainMap"``."""
    return "OpcodeList2:" + (op.name if isinstance(op, AreaOpcode) else type(op).__name__)


def _center_and_radius(
    center: tuple[float, float], shape: tuple[int, int]
) -> tuple[float, float, float]:
    """Return the centre (row, column) in pixels and the distance to the farthest corner."""
    h, w = shape
    cy, cx = center[1] * h, center[0] * w
    radius = float(np.hypot(max(cy, h - cy), max(cx, w - cx)))
    return cy, cx, radius


def warp_source_positions(
    warp: WarpRectilinear,
    rows: np.ndarray,
    cols: np.ndarray,
    shape: tuple[int, int],
    plane: int = 0,
) -> tuple[np.ndarray, np.ndarray]:
    """Return where the output pixels ``(rows, cols)`` sample the input (row, column).

    ``rows`` and ``cols`` broadcast together; ``shape`` is the image's (H, W). The SDK's
    ``dng_filter_warp::GetSrcPixelPosition`` (square pixels), not clamped to the image.
    """
    cy, cx, radius = _center_and_radius(warp.center, shape)
    kr0, kr1, kr2, kr3, kt0, kt1 = (
        float(v) for v in warp.coefficients[min(plane, len(warp.coefficients) - 1)]
    )
    y = (np.asarray(rows, np.float64) - cy) / radius
    x = (np.asarray(cols, np.float64) - cx) / radius
    r2 = np.minimum(x * x + y * y, 1.0)
    f = kr0 + r2 * (kr1 + r2 * (kr2 + r2 * kr3))
    ty = kt0 * (r2 + 2 * y * y) + 2 * kt1 * x * y
    tx = kt1 * (r2 + 2 * x * x) + 2 * kt0 * x * y
    return cy + radius * (y * f + ty), cx + radius * (x * f + tx)


def _keys(t: np.ndarray) -> np.ndarray:
    """Keys' cubic convolution kernel with a = -0.75 (the SDK's ``dng_resample_bicubic``)."""
    a = -0.75
    t = np.abs(t)
    near = ((a + 2) * t - (a + 3)) * t * t + 1
    far = ((a * t - 5 * a) * t + 8 * a) * t - 4 * a
    return np.where(t < 1, near, np.where(t < 2, far, 0.0))


def bicubic_sample(image: np.ndarray, src_rows: np.ndarray, src_cols: np.ndarray) -> np.ndarray:
    """Return ``image`` (H, W, C) at the positions, resampled as the DNG SDK's warp does.

    Positions are clamped to the image; 4 x 4 taps of Keys' kernel (a = -0.75) at the
    fraction floored to 1/32 pixel (``kResampleSubsampleCount2D``), edge pixels repeated,
    the weights normalised to sum 1; the result clamped to [0, 1]. Shape (..., C).
    """
    h, w = image.shape[:2]
    sr = np.clip(src_rows, 0.0, h - 1.0)
    sc = np.clip(src_cols, 0.0, w - 1.0)
    r0 = np.floor(sr)
    c0 = np.floor(sc)
    fr = np.floor((sr - r0) * 32.0) / 32.0
    fc = np.floor((sc - c0) * 32.0) / 32.0
    r0i = r0.astype(np.int64)
    c0i = c0.astype(np.int64)
    taps = np.arange(-1, 3)
    wr = _keys(taps - fr[..., None]).astype(np.float32)  # (..., 4)
    wc = _keys(taps - fc[..., None]).astype(np.float32)
    wr /= wr.sum(axis=-1, keepdims=True)
    wc /= wc.sum(axis=-1, keepdims=True)
    out = np.zeros((*sr.shape, image.shape[2]), np.float32)
    for i in range(4):
        ri = np.clip(r0i + taps[i], 0, h - 1)
        row = np.zeros_like(out)
        for j in range(4):
            cj = np.clip(c0i + taps[j], 0, w - 1)
            row += wc[..., j, None] * image[ri, cj]
        out += wr[..., i, None] * row
    return np.clip(out, 0.0, 1.0, out=out)


def vignette_gains(
    vig: FixVignetteRadial, rows: np.ndarray, cols: np.ndarray, shape: tuple[int, int]
) -> np.ndarray:
    """Return the FixVignetteRadial gains at ``rows`` x ``cols`` (an outer grid) of (H, W)."""
    cy, cx, radius = _center_and_radius(vig.center, shape)
    y = (np.asarray(rows, np.float64) + 0.5 - cy) / radius
    x = (np.asarray(cols, np.float64) + 0.5 - cx) / radius
    r2 = np.minimum(y[:, None] ** 2 + x[None, :] ** 2, 1.0)
    g = np.zeros_like(r2)
    for k in vig.k[::-1]:
        g = r2 * (k + g)
    return g + 1.0


def apply_stage3(
    image: np.ndarray,
    ops: list[Stage3Opcode] | tuple[Stage3Opcode, ...],
    *,
    offset: tuple[int, int] = (0, 0),
    shape: tuple[int, int] | None = None,
    kernel: bool = True,
    rows_per_chunk: int = 256,
) -> np.ndarray:
    """Return ``image`` (H, W, C) float in [0, 1] with the OpcodeList3 opcodes applied in order.

    ``offset`` is where the image's first pixel sits in the image the opcodes describe (the
    raw image after its ActiveArea crop), ``shape`` that image's (H, W) (default: the
    image's plus offset). A warp samples within the image given (its edge pixels repeated
    where the warp reaches beyond it). float32 out. ``kernel``: the warp as the numba kernel
    :func:`imageform._kernels.dng_warp.warp_rows` (False: with NumPy, ``rows_per_chunk``
    rows at a time; the same values within float32 rounding).
    """
    out = np.ascontiguousarray(image, dtype=np.float32)
    h, w = out.shape[:2]
    dt, dl = offset
    full = shape if shape is not None else (h + dt, w + dl)
    rows = np.arange(h) + dt
    cols = np.arange(w) + dl
    for op in ops:
        if isinstance(op, FixVignetteRadial):
            g = vignette_gains(op, rows, cols, full).astype(np.float32)
            out = np.minimum(out * g[..., None], np.float32(1.0))
            continue
        if isinstance(op, GainMap):  # per plane: map plane min(plane, map planes - 1)
            box, pitch = (op.top, op.left, op.bottom, op.right), (op.row_pitch, op.col_pitch)
            rr, cc = _lattice(box, pitch, offset, full, (h, w))
            if rr.size and cc.size:
                out = out.copy()
                ix = _lattice_slices(rr, cc, pitch, offset)
                for k in range(op.plane, min(op.plane + op.planes, out.shape[2])):
                    sub = out[..., k][ix]  # a view: changed in place
                    sub *= gain_map_gains(op, rr, cc, full, k).astype(np.float32)
                    np.minimum(sub, np.float32(1.0), out=sub)
            continue
        warped = np.empty_like(out)
        if kernel:
            from imageform._kernels.dng_warp import warp_rows
            from imageform._kernels.jit import run_tasks

            coef, geometry = _warp_kernel_args(op, offset, full)
            src = np.ascontiguousarray(np.moveaxis(out, -1, 0))  # the kernel's (C, H, W)
            run_tasks(warp_rows, h, src, warped, coef, geometry,
                      threads=None if h * w >= 1 << 16 else 1)  # fmt: skip
            out = warped
            continue
        same = bool(np.all(op.coefficients == op.coefficients[0]))
        planes = [None] if same else list(range(out.shape[2]))
        for start in range(0, h, rows_per_chunk):
            rr = rows[start : start + rows_per_chunk, None]
            for plane in planes:
                sr, sc = warp_source_positions(op, rr, cols[None, :], full, plane or 0)
                sr = np.clip(sr, 0.0, full[0] - 1.0) - dt
                sc = np.clip(sc, 0.0, full[1] - 1.0) - dl
                if plane is None:
                    warped[start : start + rows_per_chunk] = bicubic_sample(out, sr, sc)
                else:
                    sub = bicubic_sample(out[..., plane : plane + 1], sr, sc)
                    warped[start : start + rows_per_chunk, :, plane] = sub[..., 0]
        out = warped
    return out


def _warp_kernel_args(
    op: WarpRectilinear, offset: tuple[int, int], full: tuple[int, int]
) -> tuple[np.ndarray, np.ndarray]:
    """Return the coefficients and geometry the warp's kernel takes.

    :func:`imageform._kernels.dng_warp.warp_rows`; the coefficients one row when every
    plane's are equal.
    """
    cy, cx, radius = _center_and_radius(op.center, full)
    geometry = np.array([offset[0], offset[1], full[0], full[1], cy, cx, radius], np.float64)
    coef = np.ascontiguousarray(op.coefficients, np.float64)
    if np.all(coef == coef[0]):
        coef = coef[:1]
    return coef, geometry


def render_warped(
    planes: np.ndarray,
    op: WarpRectilinear,
    render: np.ndarray,
    table: np.ndarray | None,
    *,
    offset: tuple[int, int] = (0, 0),
    shape: tuple[int, int] | None = None,
) -> np.ndarray:
    """Return camera RGB planes (3, H, W) warped by ``op`` and rendered, in one pass.

    ``render`` (3, 3) float32 and ``table`` (the transfer table; None: linear) as
    :func:`imageform._kernels.raw_develop.render_rows` takes them; ``offset`` and ``shape``
    as for :func:`apply_stage3`. The same values, bit for bit, as :func:`apply_stage3` of
    ``[op]`` on the (H, W, 3) image followed by the render, without the warped image made
    (:func:`imageform._kernels.dng_warp.warp_render_rows`). (H, W, 3) float32 out.
    """
    from imageform._kernels.dng_warp import warp_render_rows
    from imageform._kernels.jit import run_tasks

    planes = np.ascontiguousarray(planes, dtype=np.float32)
    _, h, w = planes.shape
    full = shape if shape is not None else (h + offset[0], w + offset[1])
    coef, geometry = _warp_kernel_args(op, offset, full)
    lut = table if table is not None else np.zeros(2, np.float32)
    out = np.empty((h, w, 3), np.float32)
    run_tasks(warp_render_rows, h, planes, coef, geometry, render, lut, table is not None, out,
              threads=None if h * w >= 1 << 16 else 1)  # fmt: skip
    return out


#: Output rows the warp renders from one band of demosaiced rows (render_warped_mosaic).
_WARP_BAND = 64


def render_warped_mosaic(
    fused: tuple[np.ndarray, np.ndarray, np.ndarray, int, int],
    op: WarpRectilinear,
    render: np.ndarray,
    table: np.ndarray | None,
    *,
    offset: tuple[int, int] = (0, 0),
    shape: tuple[int, int] | None = None,
) -> np.ndarray | None:
    """Return :func:`render_warped` of a Bayer mosaic's camera RGB, demosaiced band by band.

    ``fused``: the fused pass's mosaic, black and scale per photosite, red's row and column
    (:func:`imageform._kernels.raw_develop.develop_rows`). The same values, bit for bit, as
    the mosaic demosaiced whole, then warped and rendered, without the demosaiced image
    made (:func:`imageform._kernels.dng_warp.develop_warp_render_rows`). None where the
    warp's coefficients differ by plane or a band of rows would read more than twice its
    rows (a strong warp: the bands would demosaic too much again).
    """
    from imageform._kernels.dng_warp import band_source_rows, develop_warp_render_rows
    from imageform._kernels.jit import run_tasks

    mosaic, black, scale, ry, rx = fused
    h, w = mosaic.shape
    full = shape if shape is not None else (h + offset[0], w + offset[1])
    coef, geometry = _warp_kernel_args(op, offset, full)
    if coef.shape[0] != 1 or band_source_rows(coef, geometry, h, w, _WARP_BAND) > 2 * _WARP_BAND:
        return None
    lut = table if table is not None else np.zeros(2, np.float32)
    out = np.empty((h, w, 3), np.float32)
    run_tasks(develop_warp_render_rows, h, mosaic, black, scale, ry, rx, coef, geometry, render,
              lut, table is not None, _WARP_BAND, out,
              threads=None if h * w >= 1 << 16 else 1)  # fmt: skip
    return out


def _axis_weights(
    positions: np.ndarray, size: int, origin: float, spacing: float, points: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return the lower map index, the upper one and the weight of the upper, per position."""
    f = ((positions + 0.5) / size - origin) / spacing
    f = np.clip(f, 0.0, float(points - 1))
    lo = np.minimum(np.floor(f).astype(np.int64), points - 1)
    hi = np.minimum(lo + 1, points - 1)
    return lo, hi, f - lo


def gain_map_gains(gm: GainMap, rows: np.ndarray, cols: np.ndarray, shape: tuple[int, int],
                   map_plane: int = 0) -> np.ndarray:  # fmt: skip
    """Return the gains at ``rows`` x ``cols`` (an outer grid) of an image of ``shape`` (H, W).

    Bilinear between the map's points, clamped at its edges, as the DNG SDK interpolates.
    """
    g = gm.gains[..., min(map_plane, gm.gains.shape[2] - 1)].astype(np.float64)
    r0, r1, wr = _axis_weights(rows.astype(np.float64), shape[0], gm.origin[0], gm.spacing[0],
                               g.shape[0])  # fmt: skip
    c0, c1, wc = _axis_weights(cols.astype(np.float64), shape[1], gm.origin[1], gm.spacing[1],
                               g.shape[1])  # fmt: skip
    along = g[r0] * (1 - wr)[:, None] + g[r1] * wr[:, None]  # (rows, map columns)
    out = along[:, c0]  # then along the columns, in place (the same sums, fewer temporaries)
    out *= (1 - wc)[None, :]
    right = along[:, c1]
    right *= wc[None, :]
    out += right
    return out


def apply_gain_maps(
    mosaic: np.ndarray,
    black: np.ndarray,
    white: float,
    maps: list[GainMap],
    *,
    offset: tuple[int, int] = (0, 0),
    shape: tuple[int, int] | None = None,
) -> np.ndarray:
    """Return ``mosaic`` (uint16 codes) with the GainMaps applied to its linear values.

    ``black`` is the black level of every pixel (broadcastable to the mosaic), ``white`` the
    white level: a code ``m`` becomes ``black + min((m - black) * gain, white - black)``.
    ``offset`` is where the mosaic's first pixel sits in the image the maps describe (after
    the ActiveArea crop), ``shape`` that image's (H, W) (default: the mosaic's plus offset).
    :func:`apply_stage2` with GainMaps alone (one implementation of their arithmetic).
    """
    return apply_stage2(mosaic, black, white, list(maps), offset=offset, shape=shape)


def _lattice(
    area: tuple[int, int, int, int], pitch: tuple[int, int], offset: tuple[int, int],
    full: tuple[int, int], size: tuple[int, int],
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Return the rows and columns (of the full image) of an area's lattice inside the mosaic.

    An empty area is the whole image (the SDK's ``dng_area_spec``).
    """
    top, left, bottom, right = area
    if bottom <= top or right <= left:
        top, left, bottom, right = 0, 0, full[0], full[1]
    (dt, dl), (h, w), (rp, cp) = offset, size, pitch
    r_start = top + max(0, -(-(dt - top) // rp)) * rp
    c_start = left + max(0, -(-(dl - left) // cp)) * cp
    rows = np.arange(r_start, min(bottom, full[0], h + dt), rp)
    cols = np.arange(c_start, min(right, full[1], w + dl), cp)
    return rows, cols


def _map_polynomial(x: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Return ``c0 + c1 x + c2 x^2 + ...``; below 0 mirrored about ``c0`` (the SDK's sign rule)."""
    a = np.abs(x)
    y = np.zeros_like(a)
    for coefficient in c[:0:-1]:
        y = (y + coefficient) * a
    return c[0] + np.sign(x) * y


#: Rows of the strips :func:`apply_stage2` works in (even: a strip keeps the CFA's phase).
_STRIP_ROWS = 64


def apply_stage2(
    mosaic: np.ndarray,
    black: np.ndarray,
    white: float,
    ops: list[Stage2Opcode],
    *,
    offset: tuple[int, int] = (0, 0),
    shape: tuple[int, int] | None = None,
    kernel: bool = True,
) -> np.ndarray:
    """Return ``mosaic`` (uint16 codes) with OpcodeList2's opcodes applied in order.

    On the linear values ``x = (m - black) / (white - black)``, as the SDK's stage 2 (the
    linearised image in [0, 1]): a GainMap or FixVignetteRadial multiplies by its gain,
    ScalePerRow/Column by the row's (column's) scale, DeltaPerRow/Column adds the delta,
    MapPolynomial maps ``x`` to ``c0 + c1 x + ... + cn x^n``; each result is clipped at 1
    (white). ``offset`` and ``shape`` as for :func:`apply_gain_maps`. Every opcode here
    works pixel by pixel: the image is done in strips of ``_STRIP_ROWS`` rows (each the
    same as the whole would give), whose float64 values stay in the cache. ``kernel``: a
    list of GainMaps alone on a 2-D mosaic (a phone's lens shading) as the numba kernel
    :func:`imageform._kernels.dng_warp.gain_map_rows`, the same values bit for bit (False:
    with NumPy).
    """
    h, w = mosaic.shape[:2]
    dt, dl = offset
    full = shape if shape is not None else (h + dt, w + dl)
    if kernel and mosaic.ndim == 2 and ops and all(isinstance(op, GainMap) for op in ops):
        return _gain_maps_kernel(mosaic, black, white, ops, offset, full)  # type: ignore[arg-type]
    if h > 2 * _STRIP_ROWS:
        out = np.empty(mosaic.shape, np.uint16)
        levels = np.asarray(black, np.float64)
        per_row = levels.ndim >= 2 and levels.shape[0] == h
        for r0 in range(0, h, _STRIP_ROWS):
            r1 = min(r0 + _STRIP_ROWS, h)
            out[r0:r1] = apply_stage2(mosaic[r0:r1], levels[r0:r1] if per_row else levels,
                                      white, ops, offset=(dt + r0, dl), shape=full,
                                      kernel=kernel)  # fmt: skip
        return out
    blk = np.broadcast_to(np.asarray(black, np.float64), mosaic.shape)
    span = white - blk
    x = np.asarray(mosaic, np.float64) - blk
    x /= span
    n_planes = 1 if x.ndim == 2 else x.shape[2]
    for op in ops:
        if isinstance(op, FixVignetteRadial):
            g = vignette_gains(op, np.arange(h) + dt, np.arange(w) + dl, full)
            x *= g if x.ndim == 2 else g[..., None]
            np.minimum(x, 1.0, out=x)
            continue
        if isinstance(op, GainMap):
            box, pitch = (op.top, op.left, op.bottom, op.right), (op.row_pitch, op.col_pitch)
            first, count = op.plane, op.planes
        else:
            box, (first, count), pitch = op.area[:4], op.area[4:6], op.area[6:]
        rows, cols = _lattice(box, pitch, offset, full, (h, w))
        if rows.size == 0 or cols.size == 0:
            continue
        ix = _lattice_slices(rows, cols, pitch, offset)  # a view: changed in place
        for plane in range(first, min(first + max(count, 1), n_planes)):
            sub = x[ix] if x.ndim == 2 else x[..., plane][ix]
            if isinstance(op, GainMap):
                sub *= gain_map_gains(op, rows, cols, full, plane)
            elif op.name == "MapPolynomial":
                sub[...] = _map_polynomial(sub, op.values)
            else:
                along_rows = op.name.endswith("Row")
                k = (rows - box[0]) // pitch[0] if along_rows else (cols - box[1]) // pitch[1]
                table = op.values[np.minimum(k, op.values.size - 1)]
                table = table[:, None] if along_rows else table[None, :]
                if op.name.startswith("Scale"):
                    sub *= table
                else:
                    sub += table
            np.minimum(sub, 1.0, out=sub)
    x *= span
    x += blk
    np.clip(x, 0.0, 65535.0, out=x)
    return np.rint(x, out=x).astype(np.uint16)


def _gain_maps_kernel(
    mosaic: np.ndarray, black: np.ndarray, white: float, ops: list[GainMap],
    offset: tuple[int, int], full: tuple[int, int],
) -> np.ndarray:  # fmt: skip
    """Return :func:`apply_stage2` of GainMaps alone on a 2-D mosaic, by the numba kernel."""
    from imageform._kernels.dng_warp import gain_map_rows
    from imageform._kernels.jit import run_tasks

    h, w = mosaic.shape
    dt, dl = offset
    grids: list[np.ndarray] = []
    row_w: list[np.ndarray] = []
    col_w: list[np.ndarray] = []
    maps: list[list[int]] = []
    sizes = [0, 0, 0]  # the offsets in the grids, the rows' and the columns' weights
    for op in ops:
        box, pitch = (op.top, op.left, op.bottom, op.right), (op.row_pitch, op.col_pitch)
        rr, cc = _lattice(box, pitch, offset, full, (h, w))
        if rr.size == 0 or cc.size == 0:
            continue
        for plane in range(op.plane, min(op.plane + max(op.planes, 1), 1)):
            g = op.gains[..., min(plane, op.gains.shape[2] - 1)].astype(np.float64)
            rw = _axis_weights(rr.astype(np.float64), full[0], op.origin[0], op.spacing[0],
                               g.shape[0])  # fmt: skip
            cw = _axis_weights(cc.astype(np.float64), full[1], op.origin[1], op.spacing[1],
                               g.shape[1])  # fmt: skip
            maps.append([sizes[0], g.shape[1], sizes[1], int(rr[0]) - dt, pitch[0], rr.size,
                         sizes[2], int(cc[0]) - dl, pitch[1], cc.size])  # fmt: skip
            grids.append(g.ravel())
            row_w.append(np.array(rw, np.float64))
            col_w.append(np.array(cw, np.float64))
            sizes = [sizes[0] + g.size, sizes[1] + rr.size, sizes[2] + cc.size]
    out = np.empty((h, w), np.uint16)
    table = np.array(maps, np.int64).reshape(-1, 10)
    grid = np.concatenate(grids) if grids else np.zeros(1)
    rows = np.concatenate(row_w, axis=1) if row_w else np.zeros((3, 1))
    cols = np.concatenate(col_w, axis=1) if col_w else np.zeros((3, 1))
    blk = np.asarray(black, np.float64)
    rows_of = (h, w) if blk.ndim == 2 and blk.shape[0] == h else (1, w)  # per row, or one
    blk = np.ascontiguousarray(np.broadcast_to(blk, rows_of))
    run_tasks(gain_map_rows, h, np.ascontiguousarray(mosaic, np.uint16), blk, float(white),
              table, grid, rows, cols, out, threads=None if h * w >= 1 << 16 else 1)  # fmt: skip
    return out


def _lattice_slices(
    rows: np.ndarray, cols: np.ndarray, pitch: tuple[int, int], offset: tuple[int, int]
) -> tuple[slice, slice]:
    """Return the slices of an image (its first pixel at ``offset``) that give a lattice."""
    (dt, dl), (rp, cp) = offset, pitch
    return (slice(int(rows[0]) - dt, int(rows[-1]) - dt + 1, rp),
            slice(int(cols[0]) - dl, int(cols[-1]) - dl + 1, cp))  # fmt: skip
