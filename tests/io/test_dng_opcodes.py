"""DNG GainMap opcodes (OpcodeList2, lens shading) applied by ``read_raw``.

The files are DNGs written here (``write_dng``, then re-written with tifffile to add the
opcode list and an ActiveArea), their opcodes packed as the Adobe DNG Specification 1.7.1
(chapter 7) lays them out. The interpolation is checked against the specification's rule
worked by hand, and end to end: a flat field darkened by the inverse of its map comes back
flat, with LibRaw (rawpy) and without it (tifffile), through ``imageform develop`` too.
"""

from __future__ import annotations

import importlib.util
import struct
import sys
from pathlib import Path

import numpy as np
import pytest

from imageform.io import develop, read_raw, write_dng
from imageform.io._dng_opcodes import (
    GainMap,
    apply_gain_maps,
    gain_map_gains,
    parse_opcode_list,
)

CM = np.eye(3)
GAIN_MAP, WARP_RECTILINEAR = 9, 1


def _gain_map_op(
    gains: np.ndarray,
    *,
    area: tuple[int, int, int, int],
    plane: int = 0,
    planes: int = 1,
    pitch: tuple[int, int] = (1, 1),
    spacing: tuple[float, float] | None = None,
    origin: tuple[float, float] = (0.0, 0.0),
) -> bytes:
    """One GainMap opcode (id, version, flags, size, parameters), big-endian."""
    nv, nh, mp = gains.shape
    if spacing is None:
        spacing = (1.0 / max(nv - 1, 1), 1.0 / max(nh - 1, 1))
    params = struct.pack(">8I", *area, plane, planes, *pitch)
    params += struct.pack(">2I4d", nv, nh, *spacing, *origin)
    params += struct.pack(">I", mp) + gains.astype(">f4").tobytes()
    return struct.pack(">4I", GAIN_MAP, 0x01030000, 1, len(params)) + params


def _other_op(opcode: int, size: int = 8) -> bytes:
    return struct.pack(">4I", opcode, 0x01030000, 1, size) + bytes(size)


def _op_list(*ops: bytes) -> bytes:
    return struct.pack(">I", len(ops)) + b"".join(ops)


def _dng(
    path: Path,
    mosaic: np.ndarray,
    *,
    lists: dict[int, bytes],
    active_area: tuple[int, int, int, int] | None = None,
    black: float = 64.0,
    white: float = 4095.0,
) -> Path:
    """A DNG of ``mosaic`` (RGGB) with the opcode lists (tag code -> bytes) given."""
    import tifffile

    base = write_dng(path.with_suffix(".base.dng"), mosaic, black_level=black,
                     white_level=white, color_matrix=CM)  # fmt: skip
    with tifffile.TiffFile(base) as tf:
        tags = [(t.code, t.dtype, t.count, t.value, True) for t in tf.pages[0].tags
                if t.code >= 33421]  # fmt: skip
        data = tf.pages[0].asarray()
    extra = [(code, 7, len(b), b, True) for code, b in lists.items()]
    if active_area is not None:
        extra.append((50829, 3, 4, active_area, True))
    tifffile.imwrite(path, data, photometric=32803, extratags=[*tags, *extra])
    return path


def _radial_map(nv: int = 5, nh: int = 7, strength: float = 1.2) -> np.ndarray:
    v, h = np.meshgrid(np.linspace(0, 1, nv), np.linspace(0, 1, nh), indexing="ij")
    return (1 + 2 * strength * ((v - 0.5) ** 2 + (h - 0.5) ** 2)).astype(np.float32)[..., None]


def _vignetted(gm: GainMap, shape: tuple[int, int], level: float, black: float) -> np.ndarray:
    """A flat field at ``level`` darkened by the map's gains (what the map undoes)."""
    g = gain_map_gains(gm, np.arange(shape[0]), np.arange(shape[1]), shape)
    return np.round(black + (level - black) / g).astype(np.uint16)


def test_interpolation_worked_by_hand() -> None:
    """The specification's rule on a 2 x 2 map [[1, 2], [3, 4]] spanning a 4 x 4 image:
    pixel (1, 2) sits at v = 1.5 / 4 = 0.375, h = 2.5 / 4 = 0.625, so its gain is
    (1 * 0.375 + 2 * 0.625) * 0.625 + (3 * 0.375 + 4 * 0.625) * 0.375 = 2.375; pixels
    before the first point or past the last take the edge's gain (clamped)."""
    g = np.array([[1, 2], [3, 4]], np.float32)[..., None]
    gm = GainMap(0, 0, 4, 4, 0, 1, 1, 1, (1.0, 1.0), (0.0, 0.0), g)
    gains = gain_map_gains(gm, np.arange(4), np.arange(4), (4, 4))
    assert gains[1, 2] == pytest.approx(2.375)
    # origin 0.25 and spacing 0.5: row 0 (v = 0.125) is before the map's first row
    gm2 = GainMap(0, 0, 4, 4, 0, 1, 1, 1, (0.5, 0.5), (0.25, 0.25), g)
    edge = gain_map_gains(gm2, np.array([0, 3]), np.array([0, 3]), (4, 4))
    np.testing.assert_allclose(edge, [[1, 2], [3, 4]])
    # a map of one point is one gain everywhere
    one = GainMap(0, 0, 4, 4, 0, 1, 1, 1, (1.0, 1.0), (0.0, 0.0), np.full((1, 1, 1), 1.5, "f4"))
    np.testing.assert_allclose(gain_map_gains(one, np.arange(4), np.arange(4), (4, 4)), 1.5)


def test_gain_applies_to_linear_values_and_clips_at_white() -> None:
    """A code m becomes black + min((m - black) * gain, white - black)."""
    gm = GainMap(0, 0, 2, 2, 0, 1, 1, 1, (1.0, 1.0), (0.0, 0.0), np.full((1, 1, 1), 2.0, "f4"))
    m = np.array([[64, 1064], [3000, 64]], np.uint16)
    out = apply_gain_maps(m, np.full((2, 2), 64.0), 4095.0, [gm])
    np.testing.assert_array_equal(out, [[64, 2064], [4095, 64]])
    assert m[0, 1] == 1064  # the input untouched


@pytest.mark.parametrize("reader", ["libraw", "tifffile"])
def test_vignetted_flat_field_comes_back_flat(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, reader: str
) -> None:
    if reader == "libraw" and importlib.util.find_spec("rawpy") is None:
        pytest.skip("rawpy not installed")
    shape, black = (64, 96), 64.0
    g = _radial_map()
    gm = GainMap(0, 0, *shape, 0, 1, 1, 1, (1 / 4, 1 / 6), (0.0, 0.0), g)
    mosaic = _vignetted(gm, shape, 2000.0, black)
    lists = {51009: _op_list(_gain_map_op(g, area=(0, 0, *shape)))}
    path = _dng(tmp_path / "v.dng", mosaic, lists=lists)
    if reader == "tifffile":
        monkeypatch.setitem(sys.modules, "rawpy", None)
    raw = read_raw(path)
    assert raw.metadata["opcodes_applied"] == 1 and raw.metadata["opcodes_skipped"] == []
    assert raw.mosaic.dtype == np.uint16
    assert np.abs(raw.mosaic.astype(float) - 2000).max() <= 1.0
    plain = read_raw(path, opcodes=False)  # LibRaw's values: the shading left in
    np.testing.assert_array_equal(plain.mosaic, mosaic)
    assert "opcodes_applied" not in plain.metadata
    img = develop(raw, linear=True).image
    assert np.ptp(img[4:-4, 4:-4, 1]) < 2e-3  # flat, the border's interpolation aside
    shaded = develop(plain, linear=True).image
    assert np.ptp(shaded[4:-4, 4:-4, 1]) > 0.1


def test_one_map_per_photosite_with_pitch_two(tmp_path: Path) -> None:
    """Phones write four maps, one per photosite of the tile (row and column pitch 2, the
    area starting at the site): here red gains 2, blue 1.5, the greens 1 and 1.25."""
    shape = (32, 48)
    site_gain = {(0, 0): 2.0, (0, 1): 1.0, (1, 0): 1.25, (1, 1): 1.5}
    mosaic = np.zeros(shape, np.uint16)
    ops = []
    for (r, c), gain in site_gain.items():
        mosaic[r::2, c::2] = np.round(64 + 1000 / gain)
        ops.append(_gain_map_op(np.full((2, 2, 1), gain, np.float32), area=(r, c, *shape),
                                pitch=(2, 2)))  # fmt: skip
    raw = read_raw(_dng(tmp_path / "p.dng", mosaic, lists={51009: _op_list(*ops)}))
    assert raw.metadata["opcodes_applied"] == 4
    assert np.abs(raw.mosaic.astype(float) - 1064).max() <= 1.0


def test_active_area_at_an_odd_row_shifts_the_map(tmp_path: Path) -> None:
    """The map's coordinates are the ActiveArea's; the mosaic LibRaw (and the tifffile
    reader) give starts one row and column further in when the area starts at odd ones."""
    full, area = (70, 100), (3, 5, 67, 97)  # top, left, bottom, right
    ah, aw = area[2] - area[0], area[3] - area[1]
    g = _radial_map(4, 6, 1.5)
    gm = GainMap(0, 0, ah, aw, 0, 1, 1, 1, (1 / 3, 1 / 5), (0.0, 0.0), g)
    data = np.full(full, 64, np.uint16)
    data[area[0] : area[2], area[1] : area[3]] = _vignetted(gm, (ah, aw), 3000.0, 64.0)
    path = _dng(tmp_path / "a.dng", data, active_area=area,
                lists={51009: _op_list(_gain_map_op(g, area=(0, 0, ah, aw)))})  # fmt: skip
    raw = read_raw(path)
    assert raw.mosaic.shape == (ah - 1, aw - 1)
    assert raw.metadata["opcodes_applied"] == 1
    assert np.abs(raw.mosaic.astype(float) - 3000).max() <= 1.0


def test_other_opcodes_are_named_not_applied(tmp_path: Path) -> None:
    mosaic = np.full((16, 16), 1000, np.uint16)
    lists = {51022: _op_list(_other_op(WARP_RECTILINEAR)),
             51008: _op_list(_other_op(4)), 51009: b"\x00\x00\x00\x02\x00"}  # fmt: skip
    raw = read_raw(_dng(tmp_path / "o.dng", mosaic, lists=lists))
    assert sorted(raw.metadata["opcodes_skipped"]) == [
        "OpcodeList1:FixBadPixelsConstant",
        "OpcodeList2:unreadable",
        "OpcodeList3:WarpRectilinear",
    ]
    np.testing.assert_array_equal(raw.mosaic, mosaic)


def test_parse_opcode_list_refuses_truncated_lists() -> None:
    op = _gain_map_op(np.ones((2, 2, 1), np.float32), area=(0, 0, 4, 4))
    assert [o[0] for o in parse_opcode_list(_op_list(op, _other_op(6)))] == [GAIN_MAP, 6]
    assert parse_opcode_list(_op_list(op)[:-3]) == []
    assert parse_opcode_list(b"") == []


def test_develop_command_applies_and_names_opcodes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from imageform.cli import main
    from imageform.io import read_image

    shape = (32, 48)
    g = _radial_map(3, 3, 1.0)
    gm = GainMap(0, 0, *shape, 0, 1, 1, 1, (0.5, 0.5), (0.0, 0.0), g)
    lists = {51009: _op_list(_gain_map_op(g, area=(0, 0, *shape))),
             51022: _op_list(_other_op(WARP_RECTILINEAR))}  # fmt: skip
    path = _dng(tmp_path / "c.dng", _vignetted(gm, shape, 2000.0, 64.0), lists=lists)
    assert main(["develop", str(path), "-o", str(tmp_path / "on.tif"), "--linear"]) == 0
    err = capsys.readouterr().err
    assert "applied the DNG's 1 GainMap opcode (lens shading)" in err
    assert "DNG opcodes not applied: OpcodeList3:WarpRectilinear" in err
    assert main(["develop", str(path), "-o", str(tmp_path / "off.tif"), "--linear",
                 "--no-opcodes"]) == 0  # fmt: skip
    assert "GainMap opcode" not in capsys.readouterr().err
    on = read_image(tmp_path / "on.tif")[2:-2, 2:-2, 1]
    off = read_image(tmp_path / "off.tif")[2:-2, 2:-2, 1]
    assert np.ptp(on) < 2e-3 < 0.1 < np.ptp(off)
    assert main(["info", str(path)]) == 0
    assert "applied the DNG's 1 GainMap opcode" in capsys.readouterr().out
