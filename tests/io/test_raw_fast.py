"""The fused development pass (issue 26): the same values as the stages computed one by one.

:func:`imageform.io.develop` of a Bayer mosaic, bilinearly, runs one pass over rows from the
digital numbers to the output (:func:`imageform._kernels.raw_develop.develop_rows`). These
tests hold it to a NumPy reference of every stage (white balance, bilinear demosaicing by
:func:`imageform.sensor.demosaic`, matrix, clipping, transfer table), bit for bit, on every
CFA phase, odd sizes, per-photosite black levels and both thread counts; the 16-bit output
written by the pass equals the rounded float image; the transfer table is within 1e-6 of
the exact curve; and no full-size float temporary is made.
"""

from __future__ import annotations

import tracemalloc

import numba
import numpy as np
import pytest

from imageform.io import RawImage, develop

#: XYZ (D65) to camera RGB of a made-up camera (rows: R, G, B).
CM = np.array([[1.20, -0.30, -0.10], [-0.40, 1.30, 0.10], [-0.05, 0.20, 0.60]])


def _raw(shape: tuple[int, int], pattern: str, *, seed: int = 0, flip: int = 0) -> RawImage:
    rng = np.random.default_rng(seed)
    black = np.array([[60.0, 64.0], [66.0, 70.0]])
    return RawImage(
        mosaic=rng.integers(40, 4200, size=shape).astype(np.uint16),  # some clip, some below
        black_level=black,
        white_level=4095.0,
        cfa_pattern=pattern,
        white_balance=np.array([1.9, 1.0, 1.6]),
        xyz_to_camera=CM,
        camera_to_srgb=np.eye(3),
        calibration_illuminant="D65",
        orientation=flip,
    )


def _reference(raw: RawImage, dev: object, *, encode: bool) -> tuple[np.ndarray, np.ndarray]:
    """Camera RGB and the float output, stage by stage in NumPy (float32, the pass's order)."""
    from imageform.io.raw import _cfa_indices, _transfer_table
    from imageform.sensor import demosaic

    pattern = str(raw.cfa_pattern)
    idx = np.array(_cfa_indices(pattern)).reshape(2, 2)
    black = np.asarray(raw.black_level, np.float64)
    scale = (dev.gains[idx] / (raw.white_level - black)).astype(np.float32)  # type: ignore[attr-defined]
    bal = raw.mosaic.astype(np.float32)
    for i in (0, 1):
        for j in (0, 1):
            bal[i::2, j::2] = (bal[i::2, j::2] - np.float32(black[i, j])) * scale[i, j]
    np.clip(bal, np.float32(0), np.float32(1), out=bal)
    cam = np.asarray(demosaic(bal, pattern, "bilinear", allow_odd=True), np.float32)
    m = dev._render  # type: ignore[attr-defined]
    r, g, b = cam[..., 0], cam[..., 1], cam[..., 2]
    out = np.empty_like(cam)
    for k in range(3):
        out[..., k] = np.clip(m[k, 0] * r + m[k, 1] * g + m[k, 2] * b, 0, 1)
    if encode:
        lut = _transfer_table("srgb")
        t = np.sqrt(out) * np.float32(lut.size - 1)
        e = np.minimum(t.astype(np.int32), lut.size - 2)
        f = t - e.astype(np.float32)
        out = lut[e] + f * (lut[e + 1] - lut[e])
    return cam, out


@pytest.mark.parametrize("pattern", ["RGGB", "BGGR", "GRBG", "GBRG"])
@pytest.mark.parametrize("shape", [(2, 2), (3, 5), (6, 9), (17, 24)])
@pytest.mark.parametrize("linear", [False, True])
def test_fused_pass_equals_the_stages(pattern: str, shape: tuple[int, int], linear: bool) -> None:
    raw = _raw(shape, pattern)
    dev = develop(raw, linear=linear)
    cam, ref = _reference(raw, dev, encode=not linear)
    np.testing.assert_array_equal(dev.camera_rgb, cam)
    np.testing.assert_array_equal(dev.image, ref)


@pytest.mark.parametrize("pattern", ["RGGB", "GBRG"])
def test_planar_camera_rgb_is_the_camera_rgb(pattern: str) -> None:
    """The pass's planes (3, H, W) of camera RGB, the DNG warp's source, are camera RGB's."""
    from imageform._kernels.raw_develop import MODE_PLANAR

    dev = develop(_raw((17, 24), pattern))
    planes = dev._fused(MODE_PLANAR)
    assert planes.shape == (3, 17, 24) and planes.flags.c_contiguous
    np.testing.assert_array_equal(np.moveaxis(planes, 0, -1), dev.camera_rgb)


@pytest.mark.parametrize("encode", [False, True])
def test_planar_row_render_is_the_render(encode: bool) -> None:
    """render_planar_row (one row given as planes) gives render_rows' values bit for bit:
    the same matrix, clipping, square root and table, in loops the compiler vectorises."""
    from imageform._kernels.raw_develop import render_planar_row, render_rows
    from imageform.io.raw import _transfer_table

    rng = np.random.default_rng(4)
    cam = rng.uniform(-0.1, 1.2, (5, 301, 3)).astype(np.float32)
    m = (CM / CM.sum(axis=1, keepdims=True)).astype(np.float32)
    lut = _transfer_table("srgb")
    ref = np.empty_like(cam)
    render_rows(0, 5, cam, m, lut, encode, ref)
    out = np.empty_like(cam)
    idx = np.empty((3, 301), np.int32)
    for i in range(5):
        planes = np.ascontiguousarray(np.moveaxis(cam[i], -1, 0))
        render_planar_row(planes[0], planes[1], planes[2], m, lut, encode, out[i], idx)
    np.testing.assert_array_equal(out, ref)


@pytest.mark.parametrize("threads", [1, 2])
def test_threads_give_the_same_values(threads: int) -> None:
    if threads > numba.config.NUMBA_NUM_THREADS:
        pytest.skip(f"numba has {numba.config.NUMBA_NUM_THREADS} thread(s)")
    raw = _raw((260, 258), "GRBG", seed=1)  # above the threshold of the threaded pass
    before = numba.get_num_threads()
    numba.set_num_threads(threads)
    try:
        dev = develop(raw)
        out, image = dev.to_integer(16), dev.image
    finally:
        numba.set_num_threads(before)
    _, ref = _reference(raw, dev, encode=True)
    np.testing.assert_array_equal(image, ref)
    np.testing.assert_array_equal(
        out, (ref * np.float32(65535) + np.float32(0.5)).astype(np.uint16)
    )


@pytest.mark.parametrize("flip", [0, 3, 5, 6])
def test_16_bits_from_the_pass_equal_the_rounded_image(flip: int) -> None:
    raw = _raw((14, 20), "BGGR", seed=2, flip=flip)
    direct = develop(raw).to_integer(16)  # image never read: written by the pass
    dev = develop(raw)
    image = dev.image  # read first: to_integer rounds it
    np.testing.assert_array_equal(direct, dev.to_integer(16))
    np.testing.assert_array_equal(
        direct, (image * np.float32(65535) + np.float32(0.5)).astype(np.uint16)
    )
    assert direct.flags.c_contiguous and direct.shape == image.shape


@pytest.mark.parametrize("transfer", ["srgb", "rec709", "adobe_rgb", "prophoto"])
def test_transfer_table_within_1e6(transfer: str) -> None:
    from imageform.color import encode
    from imageform.io.raw import _transfer_table

    lut = _transfer_table(transfer)
    x = np.concatenate([np.linspace(0, 1, 200_001), np.geomspace(1e-9, 1e-2, 20_001)])
    if transfer == "rec709":  # BT.709's rounded constants jump by 3e-4 at 0.018: not the table's
        x = x[np.abs(x - 0.018) > 1e-4]
    t = np.sqrt(x.astype(np.float32)) * np.float32(lut.size - 1)
    e = np.minimum(t.astype(np.int32), lut.size - 2)
    f = t - e.astype(np.float32)
    got = lut[e] + f * (lut[e + 1] - lut[e])
    exact = np.asarray(encode(x.astype(np.float32).astype(np.float64), transfer))
    tol = 2e-6 if transfer == "adobe_rgb" else 1e-6  # a pure power law: 2e-6
    assert np.abs(got - exact).max() <= tol


def test_no_full_size_float_temporary() -> None:
    raw = _raw((600, 800), "RGGB", seed=3)
    develop(raw).to_integer(16)  # compiled and loaded before measuring
    tracemalloc.start()
    try:
        out = develop(raw).to_integer(16)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    # the uint16 output and small tables; a float32 RGB image alone would be twice the output
    assert peak < 1.25 * out.nbytes, (peak, out.nbytes)


def test_raw_caches_are_read_only_and_not_copied() -> None:
    """The cached matrices and curves are read-only and handed out as they are; what a
    caller may change (a Development's matrices, the kernels' table) is its own copy."""
    from imageform.io._dng_opcodes import lossy_dng_curves
    from imageform.io.icc import _references
    from imageform.io.raw import _space_matrices, _transfer_table, _transfer_table_cached

    mats = _space_matrices("display_p3")
    assert all(not m.flags.writeable for m in mats)
    assert all(a is b for a, b in zip(mats, _space_matrices("display_p3"), strict=True))
    # D65 (IEC 61966-2-1: x 0.3127, y 0.3290, 4 decimals): X = x / y, Z = (1 - x - y) / y
    np.testing.assert_allclose(mats[0], [0.3127 / 0.3290, 1.0, 0.3583 / 0.3290], rtol=2e-4)
    curves, used = lossy_dng_curves(None)
    assert used == 0 and not curves.flags.writeable and curves is lossy_dng_curves(None)[0]
    assert curves[0, 255] == 65535
    assert all(not a.flags.writeable for ref in _references() for a in ref[1:])
    lut = _transfer_table("srgb")  # the render kernels' one signature takes writable arrays
    assert lut.flags.writeable and not _transfer_table_cached("srgb", 1.0).flags.writeable
    np.testing.assert_array_equal(lut, _transfer_table_cached("srgb", 1.0))
