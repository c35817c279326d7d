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
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "OPCODE_NAMES",
    "GainMap",
    "apply_gain_maps",
    "gain_map_gains",
    "parse_opcode_list",
    "read_opcodes",
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


def read_opcodes(page: Any) -> tuple[list[GainMap], list[str]]:
    """Return the GainMaps of a raw IFD's OpcodeList2 and the names of the opcodes not applied.

    ``page`` is the tifffile page of the raw image. Names are ``"OpcodeList3:WarpRectilinear"``
    (an unknown id by its number; a list that does not parse as ``"OpcodeList2:unreadable"``).
    """
    maps: list[GainMap] = []
    skipped: list[str] = []
    tags = page.tags
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
            gm = _parse_gain_map(params) if (op == _GAIN_MAP and code == 51009) else None
            if gm is not None:
                maps.append(gm)
            else:
                skipped.append(f"{name}:{OPCODE_NAMES.get(op, str(op))}")
    return maps, skipped


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
    return along[:, c0] * (1 - wc)[None, :] + along[:, c1] * wc[None, :]


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
    """
    h, w = mosaic.shape[:2]
    dt, dl = offset
    full = shape if shape is not None else (h + dt, w + dl)
    out = np.asarray(mosaic, dtype=np.float64).copy()
    blk = np.broadcast_to(np.asarray(black, np.float64), out.shape)
    n_planes = 1 if out.ndim == 2 else out.shape[2]
    for gm in maps:
        # the first row (column) of the opcode's lattice inside the mosaic
        r_start = gm.top + max(0, -(-(dt - gm.top) // gm.row_pitch)) * gm.row_pitch
        c_start = gm.left + max(0, -(-(dl - gm.left) // gm.col_pitch)) * gm.col_pitch
        rows = np.arange(r_start, min(gm.bottom, full[0], h + dt), gm.row_pitch)
        cols = np.arange(c_start, min(gm.right, full[1], w + dl), gm.col_pitch)
        if rows.size == 0 or cols.size == 0:
            continue
        for plane in range(gm.plane, min(gm.plane + gm.planes, n_planes)):
            gains = gain_map_gains(gm, rows, cols, full, plane)
            ix = np.ix_(rows - dt, cols - dl)
            if out.ndim == 2:
                sub, b = out[ix], blk[ix]
                out[ix] = b + np.minimum((sub - b) * gains, white - b)
            else:
                sub, b = out[..., plane][ix], blk[..., plane][ix]
                out[..., plane][ix] = b + np.minimum((sub - b) * gains, white - b)
    return np.round(np.clip(out, 0.0, 65535.0)).astype(np.uint16)
