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
from typing import Any

import numpy as np
import pytest

from imageform.io import develop, read_raw, write_dng
from imageform.io._dng_opcodes import (
    AreaOpcode,
    FixVignetteRadial,
    GainMap,
    WarpRectilinear,
    apply_gain_maps,
    apply_stage2,
    apply_stage3,
    bicubic_sample,
    gain_map_gains,
    parse_opcode_list,
    vignette_gains,
    warp_source_positions,
)

CM = np.eye(3)
GAIN_MAP, WARP_RECTILINEAR, WARP_FISHEYE, FIX_VIGNETTE_RADIAL = 9, 1, 2, 3


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
    lists = {51022: _op_list(_other_op(WARP_FISHEYE)),
             51008: _op_list(_other_op(5)), 51009: b"\x00\x00\x00\x02\x00"}  # fmt: skip
    raw = read_raw(_dng(tmp_path / "o.dng", mosaic, lists=lists))
    assert sorted(raw.metadata["opcodes_skipped"]) == [
        "OpcodeList1:FixBadPixelsList",
        "OpcodeList2:unreadable",
        "OpcodeList3:WarpFisheye",
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
             51022: _op_list(_other_op(WARP_FISHEYE))}  # fmt: skip
    path = _dng(tmp_path / "c.dng", _vignetted(gm, shape, 2000.0, 64.0), lists=lists)
    assert main(["develop", str(path), "-o", str(tmp_path / "on.tif"), "--linear"]) == 0
    err = capsys.readouterr().err
    assert "applied the DNG's 1 GainMap opcode (lens shading)" in err
    assert "DNG opcodes not applied: OpcodeList3:WarpFisheye" in err
    assert main(["develop", str(path), "-o", str(tmp_path / "off.tif"), "--linear",
                 "--no-opcodes"]) == 0  # fmt: skip
    assert "GainMap opcode" not in capsys.readouterr().err
    on = read_image(tmp_path / "on.tif")[2:-2, 2:-2, 1]
    off = read_image(tmp_path / "off.tif")[2:-2, 2:-2, 1]
    assert np.ptp(on) < 2e-3 < 0.1 < np.ptp(off)
    assert main(["info", str(path)]) == 0
    assert "applied the DNG's 1 GainMap opcode" in capsys.readouterr().out


# -- OpcodeList3: WarpRectilinear and FixVignetteRadial, applied by develop ----------------


def _warp_op(coefficients: list[list[float]], center: tuple[float, float]) -> bytes:
    """One WarpRectilinear opcode: planes, per plane kr0..kr3 kt0 kt1, then cx, cy."""
    params = struct.pack(">I", len(coefficients))
    for row in coefficients:
        params += struct.pack(">6d", *row)
    params += struct.pack(">2d", *center)
    return struct.pack(">4I", WARP_RECTILINEAR, 0x01030000, 1, len(params)) + params


def _vignette_op(k: tuple[float, ...], center: tuple[float, float]) -> bytes:
    params = struct.pack(f">{len(k) + 2}d", *k, *center)
    return struct.pack(">4I", FIX_VIGNETTE_RADIAL, 0x01030000, 1, len(params)) + params


def test_warp_source_position_worked_by_hand() -> None:
    """The SDK's rule on a 40 x 60 image, centre (cx, cy) = (0.25, 0.5): the centre is at
    column 15, row 20; the farthest corner (40, 60) lies hypot(20, 45) = sqrt(2425) away.
    Pixel (row 10, column 40) is at (y, x) = (-10, 25) / sqrt(2425), r2 = 725 / 2425."""
    kr, kt0, kt1 = (1.0, 0.1, -0.05, 0.02), 0.01, -0.02
    warp = WarpRectilinear(np.array([[*kr, kt0, kt1]]), (0.25, 0.5))
    radius = 2425**0.5
    y, x, r2 = -10 / radius, 25 / radius, 725 / 2425
    f = 1 + 0.1 * r2 - 0.05 * r2**2 + 0.02 * r2**3
    row = 20 + radius * (y * f + kt0 * (r2 + 2 * y * y) + 2 * kt1 * x * y)
    col = 15 + radius * (x * f + kt1 * (r2 + 2 * x * x) + 2 * kt0 * x * y)
    sr, sc = warp_source_positions(warp, np.array([10]), np.array([40]), (40, 60))
    assert (sr[0], sc[0]) == (pytest.approx(row, abs=1e-12), pytest.approx(col, abs=1e-12))
    assert (row, col) == (pytest.approx(10.131286, abs=1e-6), pytest.approx(39.745398, abs=1e-6))
    # a corner is at r = 1 (centre (0, 0): the normalisation is the far corner (40, 60))
    corner = WarpRectilinear(np.array([[1.0, 0.1, 0, 0, 0, 0]]), (0.0, 0.0))
    sr, sc = warp_source_positions(corner, np.array([40]), np.array([60]), (40, 60))
    assert (sr[0], sc[0]) == (pytest.approx(44.0), pytest.approx(66.0))
    # r2 is clamped to 1 beyond it, as the SDK does
    sr, sc = warp_source_positions(corner, np.array([80]), np.array([120]), (40, 60))
    assert (sr[0], sc[0]) == (pytest.approx(88.0), pytest.approx(132.0))


def test_bicubic_sample_matches_opencv_cubic_remap() -> None:
    """The SDK's resampler: Keys' kernel (a = -0.75) at 1/32 pixel, edges repeated;
    OpenCV's INTER_CUBIC is the same kernel at 1/32 (rounded, not floored)."""
    cv2 = pytest.importorskip("cv2")
    rng = np.random.default_rng(3)
    img = rng.uniform(0.2, 0.8, (20, 30, 1)).astype(np.float32)
    sr = rng.integers(-64, 21 * 32, 500) / 32.0  # multiples of 1/32, some outside
    sc = rng.integers(-64, 31 * 32, 500) / 32.0
    ours = bicubic_sample(img, sr, sc)[:, 0]
    ref = cv2.remap(img[..., 0], np.clip(sc, 0, 29).astype(np.float32)[None],
                    np.clip(sr, 0, 19).astype(np.float32)[None], cv2.INTER_CUBIC,
                    borderMode=cv2.BORDER_REPLICATE)[0]  # fmt: skip
    np.testing.assert_allclose(ours, np.clip(ref, 0, 1), atol=2e-6)
    # the fraction is floored to 1/32: a ramp sampled at 10.51 reads 10.5
    ramp = (np.arange(30, dtype=np.float32) / 100)[None, :, None].repeat(4, 0)
    assert bicubic_sample(ramp, np.array([1.0]), np.array([10.51]))[0, 0] == pytest.approx(0.105)


def test_warp_straightens_a_grid_rendered_through_opencv_distortion(tmp_path: Path) -> None:
    """Dots on a grid u_k rendered where OpenCV's Brown-Conrady model puts them
    (cv2.projectPoints, fx = fy = R, k1 k2 k3 = kr1 kr2 kr3, p1 = kt0, p2 = kt1: the
    same model as WarpRectilinear's with kr0 = 1) come back to u_k in the development."""
    cv2 = pytest.importorskip("cv2")
    h, w = 96, 128
    kr, kt = (1.0, 0.15, -0.04, 0.01), (0.004, -0.003)
    center = (0.45, 0.55)
    cy, cx = center[1] * h, center[0] * w
    radius = float(np.hypot(max(cy, h - cy), max(cx, w - cx)))
    gy, gx = np.meshgrid(np.arange(12, h - 11, 12.0), np.arange(12, w - 11, 14.0), indexing="ij")
    grid = np.stack([gx.ravel(), gy.ravel()], axis=1)  # (x, y) pixels, output positions
    norm = (grid - [cx, cy]) / radius
    pts = np.concatenate([norm, np.ones((len(norm), 1))], axis=1)[:, None, :]
    k_mat = np.array([[radius, 0, cx], [0, radius, cy], [0, 0, 1]])
    dist = np.array([kr[1], kr[2], kt[0], kt[1], kr[3]])
    seen, _ = cv2.projectPoints(pts, np.zeros(3), np.zeros(3), k_mat, dist)
    seen = seen[:, 0, :]  # where the input shows each dot
    warp = WarpRectilinear(np.array([[*kr, *kt]]), center)
    sr, sc = warp_source_positions(warp, grid[:, 1], grid[:, 0], (h, w))
    np.testing.assert_allclose(np.stack([sc, sr], axis=1), seen, atol=1e-9)
    assert np.abs(seen - grid).max() > 1.5  # the distortion moves dots by pixels
    yy, xx = np.mgrid[0:h, 0:w]
    scene = np.zeros((h, w))
    for x0, y0 in seen:
        scene += np.exp(-((xx - x0) ** 2 + (yy - y0) ** 2) / (2 * 1.6**2))
    mosaic = np.round(64 + 3000 * np.clip(scene, 0, 1)).astype(np.uint16)
    path = _dng(tmp_path / "w.dng", mosaic, lists={51022: _op_list(_warp_op([[*kr, *kt]],
                                                                           center))})  # fmt: skip

    def centroids(img: np.ndarray) -> np.ndarray:
        v = img.mean(axis=2)
        out = []
        for x0, y0 in grid:
            r0, c0 = int(np.rint(y0)), int(np.rint(x0))
            win = v[r0 - 5 : r0 + 6, c0 - 5 : c0 + 6]
            wy, wx = np.mgrid[r0 - 5 : r0 + 6, c0 - 5 : c0 + 6]
            out.append([(win * wx).sum() / win.sum(), (win * wy).sum() / win.sum()])
        return np.array(out)

    raw = read_raw(path)
    assert raw.metadata["opcodes_skipped"] == []
    dev = develop(raw, linear=True, white_balance="none")
    assert any("OpcodeList3:WarpRectilinear" in n for n in dev.notes)
    assert np.abs(centroids(dev.camera_rgb) - grid).max() < 0.08
    plain = develop(read_raw(path, opcodes=False), linear=True, white_balance="none")
    assert np.abs(centroids(plain.camera_rgb) - grid).max() > 1.0
    assert not any("OpcodeList3" in n for n in plain.notes)
    # the same with the tifffile reader and another demosaicing method (not the fused pass)
    mal = develop(raw, linear=True, white_balance="none", demosaic="malvar")
    assert np.abs(centroids(mal.camera_rgb) - grid).max() < 0.08


@pytest.mark.parametrize("reader", ["libraw", "tifffile"])
def test_fix_vignette_radial_flattens_a_flat_field(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, reader: str
) -> None:
    """A flat field darkened by 1 / g, g = 1 + k0 r2 + ... + k4 r2^5 at each pixel's centre
    (r2 its squared distance to the centre over the farthest corner's), comes back flat."""
    if reader == "libraw" and importlib.util.find_spec("rawpy") is None:
        pytest.skip("rawpy not installed")
    h, w = 64, 96
    k, center = (0.5, -0.1, 0.05, 0.0, 0.01), (0.6, 0.4)
    cy, cx = center[1] * h, center[0] * w
    r2 = (((np.arange(h)[:, None] + 0.5 - cy) ** 2 + (np.arange(w) + 0.5 - cx) ** 2)
          / (max(cy, h - cy) ** 2 + max(cx, w - cx) ** 2))  # fmt: skip
    g = 1 + sum(kk * r2 ** (i + 1) for i, kk in enumerate(k))
    np.testing.assert_allclose(vignette_gains(FixVignetteRadial(k, center), np.arange(h),
                                              np.arange(w), (h, w)), g)  # fmt: skip
    mosaic = np.round(64 + 2000 / g).astype(np.uint16)
    path = _dng(tmp_path / "fv.dng", mosaic, lists={51022: _op_list(_vignette_op(k, center))})
    if reader == "tifffile":
        monkeypatch.setitem(sys.modules, "rawpy", None)
    raw = read_raw(path)
    assert [type(op).__name__ for op in raw.metadata["opcodes_stage3"]] == ["FixVignetteRadial"]
    img = develop(raw, linear=True, white_balance="none").camera_rgb
    level = 2000 / (4095 - 64)
    assert np.abs(img[2:-2, 2:-2] - level).max() < 1e-3
    plain = read_raw(path, opcodes=False)
    np.testing.assert_array_equal(plain.mosaic, raw.mosaic)  # LibRaw's values
    assert "opcodes_stage3" not in plain.metadata
    shaded = develop(plain, linear=True, white_balance="none").camera_rgb
    assert np.ptp(shaded[2:-2, 2:-2]) > 0.1


def test_stage3_gain_map_worked_by_hand() -> None:
    """OpcodeList3's GainMap on demosaiced planes (the SDK's dng_opcode_GainMap): planes 1
    and 2 of a three-plane image, a two-plane map (plane 2 takes map plane min(2, 1) = 1),
    every second row from row 1, clipped at 1; plane 0 and the other rows left."""
    image = np.full((4, 6, 3), 0.25, np.float32)
    gains = np.stack([np.full((2, 2), 9.0), np.array([[2.0, 6.0], [2.0, 6.0]])], -1)
    gm = GainMap(1, 0, 4, 6, 1, 2, 2, 1, (1.0, 1.0), (0.0, 0.0), gains.astype(np.float32))
    out = apply_stage3(image, [gm])
    assert out is not image and np.all(image == 0.25)  # the input untouched
    np.testing.assert_array_equal(out[..., 0], 0.25)
    np.testing.assert_array_equal(out[[0, 2], :, 1:], 0.25)
    # columns at (c + 0.5) / 6 of the map's span 0..1: gains 2 + 4 (c + 0.5) / 6
    expected = np.minimum(0.25 * (2 + 4 * (np.arange(6) + 0.5) / 6), 1.0)
    for plane in (1, 2):  # plane 1: map plane 1; plane 2: map plane 1 too
        np.testing.assert_allclose(out[[1, 3], :, plane], np.tile(expected, (2, 1)), rtol=1e-6)
    assert out[1, 5, 1] == 1.0  # 0.25 x 5.67 clipped at white


def test_stage3_gain_map_flattens_colour_shading(tmp_path: Path) -> None:
    """A flat grey field shaded differently in each colour after demosaicing (a DJI drone's
    OpcodeList3 GainMap, one map plane per colour): develop undoes it; --no-opcodes not."""
    h, w, black, level = 64, 96, 64.0, 2000.0
    v, u = np.meshgrid(np.linspace(0, 1, 5), np.linspace(0, 1, 7), indexing="ij")
    bowl = (v - 0.5) ** 2 + (u - 0.5) ** 2
    gains = np.stack([1 + 1.6 * bowl, 1 + 0.8 * bowl, 1 + 2.4 * bowl], -1).astype(np.float32)
    gm = GainMap(0, 0, h, w, 0, 3, 1, 1, (0.25, 1 / 6), (0.0, 0.0), gains)
    site = np.array([[0, 1], [1, 2]])  # RGGB: the colour of each photosite
    colour = np.tile(site, (h // 2, w // 2))
    g = np.stack([gain_map_gains(gm, np.arange(h), np.arange(w), (h, w), p) for p in range(3)])
    shading = np.take_along_axis(g, colour[None], 0)[0]
    mosaic = np.round(black + (level - black) / shading).astype(np.uint16)
    lists = {51022: _op_list(_gain_map_op(gains, area=(0, 0, h, w), planes=3,
                                          spacing=(0.25, 1 / 6)))}  # fmt: skip
    raw = read_raw(_dng(tmp_path / "g3.dng", mosaic, lists=lists, black=black))
    assert [type(op).__name__ for op in raw.metadata["opcodes_stage3"]] == ["GainMap"]
    img = develop(raw, linear=True, white_balance="none").camera_rgb[3:-3, 3:-3]
    flat = (level - black) / (4095 - black)
    assert np.abs(img - flat).max() < 0.01
    shaded = develop(read_raw(tmp_path / "g3.dng", opcodes=False), linear=True,
                     white_balance="none").camera_rgb[3:-3, 3:-3]  # fmt: skip
    assert np.abs(shaded - flat).max() > 0.1


def test_bad_stage3_parameters_are_named_unreadable(tmp_path: Path) -> None:
    good = _warp_op([[1.0, 0.01, 0, 0, 0, 0]], (0.5, 0.5))
    lists = {51022: _op_list(
        _other_op(WARP_RECTILINEAR),  # 8 zero bytes: no planes
        good[:16] + struct.pack(">I", 2) + good[20:],  # two planes, one plane's bytes
        _warp_op([[1.0, 0.01, 0, 0, 0, 0]], (1.5, 0.5)),  # centre outside [0, 1]
        _warp_op([[float("nan"), 0, 0, 0, 0, 0]], (0.5, 0.5)),
        _vignette_op((0.1, 0, 0, 0), (0.5, 0.5)),  # four coefficients
        good,
    )}  # fmt: skip
    mosaic = np.full((16, 16), 1000, np.uint16)
    raw = read_raw(_dng(tmp_path / "b.dng", mosaic, lists=lists))
    assert raw.metadata["opcodes_skipped"] == [
        *["OpcodeList3:WarpRectilinear:unreadable"] * 4,
        "OpcodeList3:FixVignetteRadial:unreadable",
    ]
    assert len(raw.metadata["opcodes_stage3"]) == 1
    develop(raw)  # the good one applies
    # a list cut inside an opcode is unreadable as a whole
    cut = _dng(tmp_path / "t.dng", mosaic, lists={51022: _op_list(good)[:-5]})
    meta = read_raw(cut).metadata
    assert meta["opcodes_skipped"] == ["OpcodeList3:unreadable"]
    assert "opcodes_stage3" not in meta


def test_develop_command_notes_stage3_opcodes(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from imageform.cli import main

    mosaic = np.full((32, 48), 1000, np.uint16)
    lists = {51022: _op_list(_vignette_op((0.2, 0, 0, 0, 0), (0.5, 0.5)),
                             _warp_op([[1.0, 0.02, 0, 0, 0, 0]], (0.5, 0.5)))}  # fmt: skip
    path = _dng(tmp_path / "n.dng", mosaic, lists=lists)
    assert main(["develop", str(path), "-o", str(tmp_path / "on.tif")]) == 0
    err = capsys.readouterr().err
    assert (
        "applied the DNG's OpcodeList3:FixVignetteRadial, OpcodeList3:WarpRectilinear after "
        "demosaicing" in err
    )
    assert "not applied" not in err
    assert main(["develop", str(path), "-o", str(tmp_path / "off.tif"), "--no-opcodes"]) == 0
    assert "OpcodeList3" not in capsys.readouterr().err
    assert main(["info", str(path)]) == 0
    assert "applied when developed (after demosaicing): OpcodeList3:FixVignetteRadial" in (
        capsys.readouterr().out
    )


# -- OpcodeList2: MapPolynomial, Delta/ScalePerRow/Column, FixVignetteRadial on the mosaic --


def _area_op(opcode: int, area: tuple[int, ...], values: list[float], *, poly: bool = False,
             count: int | None = None) -> bytes:  # fmt: skip
    """An area opcode: the area spec (8 uint32), the count (degree), float32 (float64) values."""
    n = (len(values) - 1 if poly else len(values)) if count is None else count
    params = struct.pack(">8I", *area) + struct.pack(">I", n)
    params += struct.pack(f">{len(values)}{'d' if poly else 'f'}", *values)
    return struct.pack(">4I", opcode, 0x01030000, 1, len(params)) + params


def test_area_opcodes_worked_by_hand() -> None:
    """Black 64, white 4095: a code m is x = (m - 64) / 4031 and back 64 + 4031 x."""
    m = np.full((4, 6), 1064, np.uint16)
    black = np.full((4, 6), 64.0)
    x = 1000 / 4031
    # MapPolynomial 0.01 + 1.2 x - 0.3 x^2 over rows 1..3, every column
    poly = AreaOpcode("MapPolynomial", (1, 0, 4, 6, 0, 1, 1, 1), np.array([0.01, 1.2, -0.3]))
    out = apply_stage2(m, black, 4095.0, [poly])
    assert out[0, 0] == 1064
    assert out[1, 0] == round(64 + 4031 * (0.01 + 1.2 * x - 0.3 * x * x)) == 1230
    # ScalePerRow with row pitch 2 from row 1: rows 1 and 3 scaled by 2 and 5 (5 clips at white)
    scale = AreaOpcode("ScalePerRow", (1, 0, 4, 6, 0, 1, 2, 1), np.array([2.0, 5.0]))
    out = apply_stage2(m, black, 4095.0, [scale])
    np.testing.assert_array_equal(out[:, 0], [1064, 2064, 1064, 4095])
    # DeltaPerColumn over columns 2..5, column pitch 3: columns 2 and 5, then a scale of 2:
    # the order of the list counts ((x + d) 2, not x 2 + d)
    delta = AreaOpcode("DeltaPerColumn", (0, 2, 4, 6, 0, 1, 1, 3), np.array([0.1, -0.1]))
    whole = AreaOpcode("ScalePerRow", (0, 0, 0, 0, 0, 1, 1, 1), np.full(4, 2.0))  # empty: all
    out = apply_stage2(m, black, 4095.0, [delta, whole])
    assert out[0, 2] == round(64 + 4031 * (x + 0.1) * 2) == 2870
    assert out[0, 5] == round(64 + 4031 * (x - 0.1) * 2) == 1258
    assert out[0, 0] == 2064
    assert np.all(m == 1064)  # worked on views of a copy: the input is left as it was


@pytest.mark.parametrize("offset", [(0, 0), (1, 1)])
def test_stage2_in_strips_is_the_whole(monkeypatch: pytest.MonkeyPatch, offset: tuple) -> None:
    """apply_stage2 works a tall image in strips of rows: every opcode, pitched lattices
    (row pitch 2 and 3), an offset into the image and a per-photosite black plane give the
    same codes as the image done at once."""
    import imageform.io._dng_opcodes as module

    rng = np.random.default_rng(2)
    h, w = 301, 203
    m = rng.integers(0, 4096, (h, w)).astype(np.uint16)
    black = np.tile([[60.0, 64.0], [66.0, 62.0]], (h // 2 + 1, w // 2 + 1))[:h, :w]
    g = rng.uniform(0.8, 2.5, (5, 7, 1)).astype(np.float32)
    ops = [GainMap(r, c, h + 3, w + 1, 0, 1, 2, 2, (0.25, 1 / 6), (0.0, 0.0), g)
           for r in (0, 1) for c in (0, 1)]  # fmt: skip
    ops += [GainMap(3, 5, 240, 170, 0, 1, 3, 1, (0.3, 0.2), (0.1, -0.05), g),
            AreaOpcode("MapPolynomial", (2, 0, 250, 203, 0, 1, 1, 2), np.array([0.01, 1.1, -0.2])),
            AreaOpcode("ScalePerRow", (1, 0, 301, 203, 0, 1, 2, 1), rng.uniform(0.9, 1.3, 150)),
            AreaOpcode("DeltaPerColumn", (0, 2, 301, 200, 0, 1, 1, 3),
                       rng.uniform(-0.05, 0.05, 66)),
            FixVignetteRadial((0.3, 0.1, 0, 0, 0), (0.4, 0.6))]  # fmt: skip
    full = (h + 3, w + 2) if offset != (0, 0) else None
    monkeypatch.setattr(module, "_STRIP_ROWS", 10**9)
    whole = apply_stage2(m, black, 4095.0, ops, offset=offset, shape=full)
    for rows in (64, 6):
        monkeypatch.setattr(module, "_STRIP_ROWS", rows)
        np.testing.assert_array_equal(apply_stage2(m, black, 4095.0, ops, offset=offset,
                                                   shape=full), whole)  # fmt: skip
    assert not np.array_equal(whole, m)


def test_stage2_opcodes_flatten_a_shaded_mosaic(tmp_path: Path) -> None:
    """Rows darkened by 1 / s_row, columns lifted by d_col and a radial vignette: the file's
    ScalePerRow, DeltaPerColumn (negative deltas) and FixVignetteRadial of OpcodeList2 undo
    them (applied in the list's order to x = (m - black) / (white - black))."""
    h, w, black, white = 32, 40, 64.0, 4095.0
    rows = np.linspace(1.0, 1.5, h)
    cols = np.linspace(0.0, 0.05, w)
    k, center = (0.3, 0.0, 0.0, 0.0, 0.0), (0.5, 0.5)
    g = vignette_gains(FixVignetteRadial(k, center), np.arange(h), np.arange(w), (h, w))
    x = 0.4 / g  # the vignette, undone last
    x = x + cols[None, :]  # the delta, undone second
    x = x / rows[:, None]  # the scale, undone first
    mosaic = np.round(black + (white - black) * x).astype(np.uint16)
    ops = _op_list(_area_op(12, (0, 0, h, w, 0, 1, 1, 1), list(rows)),
                   _area_op(11, (0, 0, h, w, 0, 1, 1, 1), list(-cols)),
                   _vignette_op(k, center))  # fmt: skip
    raw = read_raw(_dng(tmp_path / "s.dng", mosaic, lists={51009: ops}, black=black))
    assert raw.metadata["opcodes_skipped"] == []
    assert raw.metadata["opcodes_applied_other"] == [
        "OpcodeList2:ScalePerRow", "OpcodeList2:DeltaPerColumn", "OpcodeList2:FixVignetteRadial"
    ]  # fmt: skip
    level = black + 0.4 * (white - black)
    assert np.abs(raw.mosaic.astype(float) - level).max() <= 1.0
    np.testing.assert_array_equal(read_raw(tmp_path / "s.dng", opcodes=False).mosaic, mosaic)


def test_bad_area_opcodes_are_named_unreadable(tmp_path: Path) -> None:
    mosaic = np.full((16, 16), 1000, np.uint16)
    ops = _op_list(_area_op(12, (0, 0, 16, 16, 0, 1, 1, 1), [1.0] * 15),  # 16 rows, 15 scales
                   _area_op(8, (0, 0, 16, 16, 0, 1, 1, 1), [0.0] * 10, poly=True),  # degree 9
                   _area_op(10, (0, 0, 16, 16, 0, 1, 0, 1), [0.0] * 16),  # row pitch 0
                   _area_op(13, (0, 0, 16, 16, 0, 1, 1, 1), [float("inf")] * 16),
                   _area_op(11, (0, 0, 16, 16, 0, 1, 1, 1), [0.0] * 15, count=16))  # fmt: skip
    raw = read_raw(_dng(tmp_path / "u.dng", mosaic, lists={51009: ops}))
    assert raw.metadata["opcodes_skipped"] == [
        "OpcodeList2:ScalePerRow:unreadable", "OpcodeList2:MapPolynomial:unreadable",
        "OpcodeList2:DeltaPerRow:unreadable", "OpcodeList2:ScalePerColumn:unreadable",
        "OpcodeList2:DeltaPerColumn:unreadable",
    ]  # fmt: skip
    np.testing.assert_array_equal(raw.mosaic, mosaic)


def _bad_pixels_op(constant: int, phase: int) -> bytes:
    return struct.pack(">4I2I", 4, 0x01030000, 1, 8, constant, phase)


def _fixed_by_hand(stored: np.ndarray, bad: list[tuple[int, int]], constant: int,
                   phase: int) -> dict[tuple[int, int], int]:  # fmt: skip
    """The SDK's rule pixel by pixel on the stored image: green where row + col + phase +
    phase // 2 is even, its four diagonal neighbours, else the four two pixels away; the
    good ones averaged, rounded half up."""
    out = {}
    for r, c in bad:
        green = (r + c + phase + phase // 2) % 2 == 0
        steps = (
            ((-1, -1), (-1, 1), (1, -1), (1, 1)) if green else ((-2, 0), (2, 0), (0, -2), (0, 2))
        )
        vals = [int(stored[r + a, c + b]) for a, b in steps
                if 0 <= r + a < stored.shape[0] and 0 <= c + b < stored.shape[1]
                and stored[r + a, c + b] != constant]  # fmt: skip
        out[(r, c)] = (sum(vals) + len(vals) // 2) // len(vals)
    return out


@pytest.mark.parametrize("phase", [0, 1, 2, 3])
def test_fix_bad_pixels_constant(tmp_path: Path, phase: int) -> None:
    """Pixels at the constant (0) are replaced from their same-colour neighbours as the
    SDK does, in the stored image's coordinates (the ActiveArea starts at row 1, column 3:
    LibRaw's mosaic at stored row 2, column 4); two bad neighbours are not counted."""
    rng = np.random.default_rng(phase)
    stored = rng.integers(500, 3000, (24, 30)).astype(np.uint16)
    bad = [(6, 9), (7, 10), (8, 9), (10, 12), (12, 15), (9, 20)]  # (6, 9) and (8, 9): same colour
    for rc in bad:
        stored[rc] = 0
    want = _fixed_by_hand(stored, bad, 0, phase)
    if phase == 1:  # one pixel by hand: (10, 12) with phase 1 is not green (10 + 12 + 1 odd)
        s = stored
        hand = (int(s[8, 12]) + int(s[12, 12]) + int(s[10, 10]) + int(s[10, 14]) + 2) // 4
        assert want[(10, 12)] == hand
    path = _dng(tmp_path / "bp.dng", stored, active_area=(1, 3, 23, 29),
                lists={51008: _op_list(_bad_pixels_op(0, phase))})  # fmt: skip
    raw = read_raw(path)
    assert raw.metadata["opcodes_applied_other"] == ["OpcodeList1:FixBadPixelsConstant"]
    assert raw.mosaic.shape == (21, 25)  # stored rows 2..22, columns 4..28
    for (r, c), value in want.items():
        assert raw.mosaic[r - 2, c - 4] == value
    untouched = np.ones(raw.mosaic.shape, bool)
    for r, c in bad:
        untouched[r - 2, c - 4] = False
    np.testing.assert_array_equal(raw.mosaic[untouched], stored[2:23, 4:29][untouched])
    assert (read_raw(path, opcodes=False).mosaic == 0).sum() == len(bad)


@pytest.mark.parametrize("planes", [1, 3])
def test_warp_kernel_matches_the_numpy_reference(planes: int) -> None:
    """The numba kernel (develop's path) is the NumPy functions the tests above check,
    one pixel at a time: offset image, a centre off the middle, per-plane coefficients."""
    rng = np.random.default_rng(planes)
    img = rng.uniform(0.0, 1.0, (37, 52, 3)).astype(np.float32)
    coef = [[1.0, 0.12 + 0.02 * p, -0.03, 0.01, 0.003, -0.002] for p in range(planes)]
    ops = [WarpRectilinear(np.array(coef), (0.4, 0.6)),
           FixVignetteRadial((0.2, 0.1, 0, 0, 0), (0.5, 0.5))]  # fmt: skip
    fast = apply_stage3(img, ops, offset=(1, 1), shape=(39, 54))
    slow = apply_stage3(img, ops, offset=(1, 1), shape=(39, 54), kernel=False, rows_per_chunk=7)
    np.testing.assert_allclose(fast, slow, atol=2e-6)
    assert np.abs(fast - img).max() > 0.1


def test_gpu_development_applies_stage3_on_the_cpu(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """device="cuda": the GPU demosaics (here a stand-in giving the CPU pass's values, CI has
    no GPU), then the OpcodeList3 warp runs on the CPU, with a note saying so."""
    cuda_demosaic = pytest.importorskip("imageform._cuda.demosaic")
    import imageform._cuda.geometry as cuda_geometry

    mosaic = np.random.default_rng(5).integers(200, 3000, (24, 32)).astype(np.uint16)
    warp = _warp_op([[1.0, 0.1, 0, 0, 0.002, 0]], (0.5, 0.5))
    raw = read_raw(_dng(tmp_path / "g.dng", mosaic, lists={51022: _op_list(warp)}))
    cpu = develop(raw, linear=True)
    plain = develop(read_raw(tmp_path / "g.dng", opcodes=False), linear=True)
    monkeypatch.setattr(cuda_geometry, "require_cuda", lambda what: None)
    monkeypatch.setattr(cuda_demosaic, "develop_bayer", lambda *a: plain._fused(a[-1]))
    gpu = develop(raw, linear=True, device="cuda")
    assert gpu._device == "cuda"
    assert gpu.notes[-1] == (
        "applied the DNG's OpcodeList3:WarpRectilinear after demosaicing (on the CPU, after "
        "the GPU's demosaicing)"
    )
    np.testing.assert_array_equal(gpu.camera_rgb, cpu.camera_rgb)
    np.testing.assert_allclose(gpu.image, cpu.image, atol=1e-6)
    assert np.abs(gpu.camera_rgb - plain.camera_rgb).max() > 0.05


#: Tags of write_dng's file not copied to a linear (LinearRaw) one: the CFA's and the levels.
_NOT_COPIED = (33421, 33422, 50713, 50714, 50717)


def _lossy_dng(path: Path, list2: bytes | None, h: int = 32, w: int = 256) -> Path:
    """A lossy DNG (Compression 34892, DNG 1.4): a LinearRaw ramp 0..255 in 8-bit JPEG tiles.

    The ramp runs along the rows, equal in the three samples; ``list2`` its OpcodeList2.
    """
    import tifffile

    base = write_dng(path.with_suffix(".base.dng"), np.full((h, w), 100, np.uint16),
                     black_level=0, white_level=4095, color_matrix=CM)  # fmt: skip
    with tifffile.TiffFile(base) as tf:
        tags = [(t.code, t.dtype, t.count, t.value, True) for t in tf.pages[0].tags
                if t.code >= 33421 and t.code not in _NOT_COPIED]  # fmt: skip
    if list2 is not None:
        tags.append((51009, 7, len(list2), list2, True))
    ramp = np.repeat(np.repeat(np.arange(w, dtype=np.uint8)[None, :, None], h, 0), 3, 2)
    tifffile.imwrite(path, ramp, photometric="rgb", compression="jpeg",
                     compressionargs={"level": 100}, tile=(16, 16), extratags=tags)  # fmt: skip
    with tifffile.TiffFile(path, mode="r+") as tf:  # the lossy DNG's codes
        tf.pages[0].tags[259].overwrite(34892)
        tf.pages[0].tags[262].overwrite(34892)
    return path


#: The MapPolynomial Adobe Camera Raw writes in a lossy DNG's OpcodeList2 (one per plane;
#: here from a Canon EOS 6D file Camera Raw 11.3.1 wrote): 1/128 x + 127/128 x^3.
ACR_CUBIC = [0.0, 1 / 128, 0.0, 127 / 128]


def test_lossy_dng_curves_worked_by_hand() -> None:
    """LibRaw's curves of a lossy DNG's 8-bit codes, values LibRaw gave for these codes.

    The polynomial: floor(65535 p(v / 255)), v = 128: 65535 (128/255/128 + 127/128
    (128/255)^3) = 8480.3. Without an OpcodeList2, dcraw's sRGB-like decoding
    (((v / 255 + a) / (1 + a))^2.4, times 65536): v = 51 -> 2169 (sRGB's own 0.03310 x 65536
    = 2169.3), 102 -> 8707, 153 -> 20876, 204 -> 39572, 255 -> 65535.
    """
    from imageform.io._dng_opcodes import lossy_dng_curves

    ops = _op_list(*(_area_op(8, (0, 0, 32, 256, p, 1, 1, 1), ACR_CUBIC, poly=True)
                     for p in range(3)))  # fmt: skip
    curves, used = lossy_dng_curves(ops)
    assert used == 3 and curves.shape == (4, 256) and curves.dtype == np.uint16
    assert curves[0, 128] == curves[2, 128] == 8480
    assert curves[0, 0] == 0 and curves[1, 255] == 65535
    srgb, none = lossy_dng_curves(None)
    assert none == 0
    np.testing.assert_array_equal(srgb[:, [0, 51, 102, 153, 204, 255]],
                                  [[0, 2169, 8707, 20876, 39572, 65535]] * 4)  # fmt: skip
    # LibRaw stops at a polynomial over plane 3 (or of degree over 8): the later ones are not
    # decoding curves, and are applied by read_raw as any MapPolynomial
    ops = _op_list(_area_op(8, (0, 0, 32, 256, 0, 1, 1, 1), ACR_CUBIC, poly=True),
                   _area_op(8, (0, 0, 32, 256, 5, 1, 1, 1), ACR_CUBIC, poly=True),
                   _area_op(8, (0, 0, 32, 256, 1, 1, 1, 1), ACR_CUBIC, poly=True))  # fmt: skip
    curves, used = lossy_dng_curves(ops)
    assert used == 1 and curves[0, 128] == 8480 and curves[1, 128] == srgb[1, 128]


@pytest.mark.parametrize("with_list", [True, False])
def test_lossy_dng_polynomial_is_applied_once(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, with_list: bool
) -> None:
    """A lossy DNG's MapPolynomials are its samples' decoding (LibRaw applies them when it
    decodes): read_raw does not apply them a second time (that made a real Camera Raw file
    nearly black), and the tifffile reader decodes the samples as LibRaw does."""
    import tifffile

    from imageform.io._dng_opcodes import lossy_dng_curves

    ops = _op_list(*(_area_op(8, (0, 0, 32, 256, p, 1, 1, 1), ACR_CUBIC, poly=True)
                     for p in range(3)))  # fmt: skip
    path = _lossy_dng(tmp_path / "lossy.dng", ops if with_list else None)
    with tifffile.TiffFile(path) as tf:
        codes = tf.pages[0].asarray()  # the JPEG's 8-bit samples
    expected = lossy_dng_curves(ops if with_list else None)[0][0][codes]
    raw = read_raw(path)
    assert raw.white_level == 65535
    np.testing.assert_array_equal(raw.mosaic, expected)
    np.testing.assert_array_equal(read_raw(path, opcodes=False).mosaic, expected)
    decoded = ["OpcodeList2:MapPolynomial"] * 3 if with_list else None
    assert raw.metadata.get("opcodes_decoded") == decoded
    assert not raw.metadata.get("opcodes_applied_other")
    if importlib.util.find_spec("rawpy") is not None:
        import rawpy

        with rawpy.imread(str(path)) as r:
            np.testing.assert_array_equal(np.asarray(r.raw_image_visible)[..., :3], expected)
    monkeypatch.setitem(sys.modules, "rawpy", None)
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None)
    own = read_raw(path)
    assert own.metadata["reader"] == "tifffile" and own.white_level == 65535
    np.testing.assert_array_equal(own.mosaic, expected)


def test_info_names_the_decoding_polynomials(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from imageform.cli import main

    ops = _op_list(*(_area_op(8, (0, 0, 32, 256, p, 1, 1, 1), ACR_CUBIC, poly=True)
                     for p in range(3)))  # fmt: skip
    path = _lossy_dng(tmp_path / "lossy.dng", ops)
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "decoded with its OpcodeList2:MapPolynomial" in out
    assert "applied the DNG's" not in out


def test_the_dng_header_is_opened_once(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """After LibRaw, one reading of the header serves the colour tags and the opcodes, and
    tifffile is not opened (imageform.io._tiff_ifd reads it)."""
    pytest.importorskip("rawpy")
    import tifffile

    from imageform.io import _tiff_ifd

    g = _radial_map(5, 5)
    gm = GainMap(0, 0, 32, 40, 0, 1, 1, 1, (0.25, 0.25), (0.0, 0.0), g)
    path = _dng(tmp_path / "g.dng", _vignetted(gm, (32, 40), 2000.0, 64.0),
                lists={51009: _op_list(_gain_map_op(g, area=(0, 0, 32, 40)))})  # fmt: skip
    opened = []
    real = tifffile.TiffFile

    def counting(*args: object, **kwargs: object) -> tifffile.TiffFile:
        opened.append(args[0])
        return real(*args, **kwargs)  # type: ignore[arg-type]

    headers = []
    read_header = _tiff_ifd.read_header

    def counting_headers(p: Path) -> object:
        headers.append(p)
        return read_header(p)

    monkeypatch.setattr(tifffile, "TiffFile", counting)
    monkeypatch.setattr(_tiff_ifd, "read_header", counting_headers)
    raw = read_raw(path)
    assert raw.metadata["opcodes_applied"] == 1 and raw.xyz_to_camera is not None
    assert len(headers) == 1 and not opened


def test_warp_kernel_three_planes_in_one_pass_are_the_per_plane_values() -> None:
    """One row of coefficients and three planes (the fused pass, every plane's taps read
    together) gives, bit for bit, the plane-by-plane loop's values (the same coefficients
    given once per plane), the edges included."""
    from imageform._kernels.dng_warp import warp_rows
    from imageform.io._dng_opcodes import _center_and_radius

    rng = np.random.default_rng(7)
    img = rng.uniform(0.0, 1.0, (41, 57, 3)).astype(np.float32)
    cy, cx, radius = _center_and_radius((0.45, 0.55), (43, 60))
    geometry = np.array([2.0, 1.0, 43.0, 60.0, cy, cx, radius])
    coef = np.array([[1.0, 0.15, -0.04, 0.01, 0.004, -0.003]])
    planes = np.ascontiguousarray(np.moveaxis(img, -1, 0))  # the kernel's (C, H, W)
    fused = np.empty_like(img)
    warp_rows(0, 41, planes, fused, coef, geometry)
    per_plane = np.empty_like(img)
    warp_rows(0, 41, planes, per_plane, np.repeat(coef, 3, axis=0), geometry)
    np.testing.assert_array_equal(fused, per_plane)
    assert np.abs(fused - img).max() > 0.1


def test_warp_kernel_runs_are_the_pixel_by_pixel_values() -> None:
    """The vectorised loop over runs of columns (source blocks inside the image, a column
    apart) gives, bit for bit, the pixel-by-pixel loop's values, for one set of coefficients
    and one per plane, on rows that have long runs, short ones and clamped edge columns."""
    from imageform._kernels.dng_warp import (
        _MIN_RUN,
        _columns,
        _row_runs,
        _row_sources,
        warp_rows,
    )
    from imageform.io._dng_opcodes import _center_and_radius

    h, w = 48, 300
    planes = np.random.default_rng(8).uniform(0.0, 1.0, (3, h, w)).astype(np.float32)
    cy, cx, radius = _center_and_radius((0.45, 0.55), (h + 2, w + 3))
    geometry = np.array([1.0, 2.0, h + 2.0, w + 3.0, cy, cx, radius])
    one = np.array([[1.0, -0.06, 0.03, 0.0, 0.002, -0.001]])
    for coef in (one, one + np.array([[0.0], [0.01], [0.02]]) * [0, 1, 0, 0, 0, 0]):
        runs = np.empty((h, w, 3), np.float32)
        warp_rows(0, h, planes, runs, coef, geometry)
        pixels = np.empty_like(runs)
        warp_rows(0, h, planes, pixels, coef, geometry, False)
        np.testing.assert_array_equal(runs, pixels)
        assert np.abs(runs - np.moveaxis(planes, 0, -1)).max() > 0.05
    buf = np.empty((4, w), np.int32)
    starts, inner = np.empty(w + 1, np.int64), np.empty(w, np.bool_)
    for i, edges in ((20, False), (0, True)):  # row 0 reads row -1: clamped
        _row_sources(i, one[0], _columns(geometry, w), geometry, h, w, *buf)
        n = _row_runs(buf[0], buf[1], h, w, starts, inner)
        lengths = np.diff(starts[: n + 1])
        assert inner[:n].all() != edges
        if not edges:
            assert lengths.max() >= 4 * _MIN_RUN and (lengths < _MIN_RUN).any()


@pytest.mark.parametrize("band", [64, 8, 2])
@pytest.mark.parametrize("case", ["warp", "vignette, warp", "per-plane warp", "malvar", "linear"])
def test_develop_warps_and_renders_in_one_pass(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, case: str, band: int
) -> None:
    """An OpcodeList3 ending in a warp: develop's image, the warp and the render in one pass
    (camera RGB never made; a Bayer mosaic demosaiced band by band of ``band`` output rows,
    or whole where a band would read more than twice its rows: here with 2), is bit for bit
    the image rendered from ``camera_rgb`` (the opcodes applied by apply_stage3, then the
    render), and so are its 16 bits."""
    import imageform.io._dng_opcodes as opcodes
    from imageform._kernels.dng_warp import band_source_rows

    monkeypatch.setattr(opcodes, "_WARP_BAND", band)
    rng = np.random.default_rng(9)
    mosaic = rng.integers(100, 4000, (150, 300)).astype(np.uint16)
    coef = [[1.0, -0.06, 0.03, 0.0, 0.002, -0.001]]
    if case == "per-plane warp":
        coef = [[1.0, -0.06 + 0.01 * p, 0.03, 0.0, 0.002, -0.001] for p in range(3)]
    ops = [_warp_op(coef, (0.45, 0.55))]
    if case == "vignette, warp":
        ops.insert(0, _vignette_op((0.3, -0.1, 0.02, 0.0, 0.0), (0.55, 0.45)))
    path = _dng(tmp_path / "w.dng", mosaic, lists={51022: _op_list(*ops)},
                active_area=(1, 3, 150, 300))  # fmt: skip
    raw = read_raw(path)
    if case == "warp":  # bands of 64 and 8 rows read under twice their rows; of 2, more
        op, (offset, area) = raw.metadata["opcodes_stage3"][0], raw.metadata["opcodes_area"]
        k, geometry = opcodes._warp_kernel_args(op, offset, area)
        rows = band_source_rows(k, geometry, *raw.mosaic.shape, band)
        assert band < rows and (rows <= 2 * band) == (band > 2)
    kwargs: dict[str, Any] = {"demosaic": "malvar"} if case == "malvar" else {}
    if case == "linear":
        kwargs["linear"] = True
    one_pass = develop(raw, **kwargs)
    image = one_pass.image
    if case != "malvar":
        assert one_pass._camera_rgb is None  # no warped (nor demosaiced) image kept
    stages = develop(raw, **kwargs)
    camera = stages.camera_rgb  # the opcodes applied to camera RGB, then rendered from it
    np.testing.assert_array_equal(image, stages.image)
    np.testing.assert_array_equal(develop(raw, **kwargs).to_integer(16), stages.to_integer(16))
    plain = develop(read_raw(path, opcodes=False), **kwargs)
    assert np.abs(camera - plain.camera_rgb).max() > 0.05


@pytest.mark.parametrize(("shape", "offset", "full"),
                         [((37, 53), (0, 0), None), ((301, 410), (3, 5), (306, 418))])  # fmt: skip
def test_gain_map_kernel_matches_the_numpy_path(
    shape: tuple[int, int], offset: tuple[int, int], full: tuple[int, int] | None
) -> None:
    """GainMaps alone on a mosaic (read_raw's path: the numba kernel) give, bit for bit, the
    NumPy path's codes (in strips of 64 rows for the larger mosaic): four per-photosite maps,
    one on every third row of a box with its grid off the image's origin, an empty area (the
    whole image), a map of three planes (plane 0's used), one for plane 1 (not applied);
    black per photosite and one black level; gains up to 2.5, so that values clip at white."""
    rng = np.random.default_rng(3)

    def gm(box: tuple[int, int, int, int], pitch: tuple[int, int], points: tuple[int, int],
           origin: tuple[float, float] = (0.0, 0.0), plane: int = 0,
           map_planes: int = 1) -> GainMap:  # fmt: skip
        g = rng.uniform(0.6, 2.5, (*points, map_planes)).astype(np.float32)
        spacing = (1 / (points[0] - 1), 1 / (points[1] - 1))
        return GainMap(*box, plane, 1, *pitch, spacing, origin, g)

    h, w = shape
    mosaic = rng.integers(0, 4096, shape).astype(np.uint16)
    ops = [gm((r, c, 10**6, 10**6), (2, 2), (13, 17)) for r in (0, 1) for c in (0, 1)]
    ops += [gm((5, 7, 90, 200), (3, 1), (5, 4), origin=(0.1, -0.2)),
            gm((0, 0, 0, 0), (1, 1), (2, 2), map_planes=3),
            gm((0, 0, 50, 50), (1, 1), (3, 3), plane=1)]  # fmt: skip
    tile = np.array([[60.0, 64.0], [62.0, 66.0]])
    for black in (np.tile(tile, (h // 2 + 1, w // 2 + 1))[:h, :w], np.float64(64.0)):
        fast = apply_stage2(mosaic, black, 4000, ops, offset=offset, shape=full)
        slow = apply_stage2(mosaic, black, 4000, ops, offset=offset, shape=full, kernel=False)
        np.testing.assert_array_equal(fast, slow)
        assert (fast != mosaic).mean() > 0.99 and (fast == 4000).any()
