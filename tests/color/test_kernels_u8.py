"""8-bit in, 8-bit out: the uint8 Lab / HSV kernels, ``convert(dtype="uint8", out=)``, and
the integer bilinear demosaicing kernel, against their twins, the float64 reference and
OpenCV (benchmark peer). Stated bounds: Lab and HSV within one code of the float result
rounded (``to_opencv``); CIEDE2000 of the decoded 8-bit Lab at most 1.0 and within 0.15 of
the rounding floor of the lab8 encoding itself (0.88 over all 2^24 colours,
benchmarks/results/8bit-2026-11-25.md);
the float32 result from uint8 input at most 0.5 (it is below 1e-3); the integer demosaicing
within half a code of 255 x the float64 bilinear result and equal to OpenCV's interior.
"""

from __future__ import annotations

import numpy as np
import pytest

from imageform._kernels import color_u8, demosaic_bilinear
from imageform.color import convert, delta_e_ciede2000, from_opencv, to_opencv
from imageform.errors import InvalidInputError
from imageform.sensor import CFA_PATTERNS, demosaic
from imageform.sensor.cfa import _red_offset


def _cube(step: int = 3) -> np.ndarray:
    """A grid of 8-bit colours (every ``step``-th code, 0 and 255 included)."""
    v = np.unique(np.r_[np.arange(0, 256, step), 255]).astype(np.uint8)
    r, g, b = np.meshgrid(v, v, v, indexing="ij")
    return np.stack([r, g, b], axis=-1).reshape(len(v) ** 2, len(v), 3)


CUBE = _cube()


def _twin(x: np.ndarray, dst: str, monkeypatch: pytest.MonkeyPatch) -> np.ndarray:
    with monkeypatch.context() as m:
        m.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
        return np.asarray(convert(x, "srgb", dst, dtype="uint8"))


def _hue_diff(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    d = np.abs(a.astype(np.int32) - b.astype(np.int32))
    d[..., 0] = np.minimum(d[..., 0], 180 - d[..., 0])
    return d


def test_lab8_kernel_against_twin(monkeypatch: pytest.MonkeyPatch) -> None:
    ours = convert(CUBE, "srgb", "lab", dtype="uint8")
    twin = _twin(CUBE, "lab", monkeypatch)
    assert ours.dtype == twin.dtype == np.uint8
    d = np.abs(ours.astype(np.int32) - twin)
    assert d.max() <= 1
    assert (d > 0).mean() < 0.01


def test_lab8_ciede2000_bound() -> None:
    ref = convert(CUBE.astype(np.float64) / 255.0, "srgb", "lab")
    de = delta_e_ciede2000(
        from_opencv(convert(CUBE, "srgb", "lab", dtype="uint8"), "lab8").astype(np.float64), ref
    )
    floor = delta_e_ciede2000(from_opencv(to_opencv(ref, "lab8"), "lab8"), ref)
    assert float(de.max()) <= 1.0
    assert float(de.max()) <= float(floor.max()) + 0.15
    assert float(de.mean()) <= float(floor.mean()) + 0.01
    de32 = delta_e_ciede2000(convert(CUBE, "srgb", "lab").astype(np.float64), ref)
    assert float(de32.max()) <= 0.5


def test_lab8_published_values() -> None:
    # sRGB red (255, 0, 0) is L* a* b* = 53.24, 80.09, 67.20 (IEC 61966-2-1, D65, CIE 15)
    # -> lab8 (135.8, 208.1, 195.2) rounded; white -> (255, 128, 128); black -> (0, 128, 128)
    x = np.zeros((64, 64, 3), np.uint8)
    x[0, 0] = (255, 0, 0)
    x[0, 1] = (255, 255, 255)
    got = convert(x, "srgb", "lab", dtype="uint8")
    assert got[0, 0].tolist() == [136, 208, 195]
    assert got[0, 1].tolist() == [255, 128, 128]
    assert got[0, 2].tolist() == [0, 128, 128]


def test_lab8_against_opencv() -> None:
    cv2 = pytest.importorskip("cv2")
    ours = convert(CUBE, "srgb", "lab", dtype="uint8").astype(np.int32)
    cv = cv2.cvtColor(CUBE, cv2.COLOR_RGB2Lab).astype(np.int32)
    # OpenCV's 8-bit path interpolates a table: within a few codes of the exact one
    assert np.abs(ours - cv).max() <= 6
    assert np.abs(ours - cv).mean() < 0.5


def test_hsv8_against_twin_and_opencv(monkeypatch: pytest.MonkeyPatch) -> None:
    ours = convert(CUBE, "srgb", "hsv", dtype="uint8")
    assert ours.dtype == np.uint8 and int(ours[..., 0].max()) < 180
    assert _hue_diff(ours, _twin(CUBE, "hsv", monkeypatch)).max() <= 1
    cv2 = pytest.importorskip("cv2")
    assert _hue_diff(ours, cv2.cvtColor(CUBE, cv2.COLOR_RGB2HSV)).max() <= 1


def test_hsv8_published_values() -> None:
    # OpenCV's documented layout: pure blue H = 240 deg -> 120; S = V = 255
    x = np.zeros((64, 64, 3), np.uint8)
    x[0, 0] = (0, 0, 255)
    x[0, 1] = (255, 0, 0)
    x[0, 2] = (128, 128, 128)
    got = convert(x, "srgb", "hsv", dtype="uint8")
    assert got[0, 0].tolist() == [120, 255, 255]
    assert got[0, 1].tolist() == [0, 255, 255]
    assert got[0, 2].tolist() == [0, 0, 128]


def test_decode_lut_exact() -> None:
    v = np.arange(256) / 255.0
    ref = np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)
    np.testing.assert_allclose(color_u8.DECODE_LUT, ref, rtol=1e-7, atol=1e-9)


def test_lab8_other_white_takes_float_path() -> None:
    got = convert(CUBE, "srgb", "lab", dtype="uint8", white="D50")
    ref = to_opencv(convert(CUBE / 255.0, "srgb", "lab", white="D50"), "lab8")
    assert np.abs(got.astype(np.int32) - ref).max() <= 1  # float32 vs float64 rounding


@pytest.mark.parametrize(
    ("dst", "dtype"),
    [
        ("lab", None),
        ("lab", "uint8"),
        ("hsv", None),
        ("hsv", "uint8"),
        ("linear_srgb", None),
        ("ycbcr", None),
        ("xyz", None),
    ],
)
@pytest.mark.parametrize("src_dtype", [np.uint8, np.float32, np.float64])
def test_out_equals_allocated(dst: str, dtype: str | None, src_dtype: type) -> None:
    img = CUBE if src_dtype == np.uint8 else (CUBE / 255.0).astype(src_dtype)
    want = convert(img, "srgb", dst, dtype=dtype)
    buf = np.full(want.shape, 7, want.dtype)
    got = convert(img, "srgb", dst, dtype=dtype, out=buf)
    assert got is buf
    np.testing.assert_array_equal(buf, want)


def test_out_small_image_and_alpha() -> None:
    x = CUBE[:2, :3]  # below the numba size threshold: the array path, copied into out
    buf = np.empty((2, 3, 3), np.uint8)
    assert convert(x, "srgb", "hsv", dtype="uint8", out=buf) is buf
    np.testing.assert_array_equal(buf, convert(x, "srgb", "hsv", dtype="uint8"))
    xa = np.concatenate([CUBE / 255.0, np.ones(CUBE.shape[:-1] + (1,))], axis=-1)
    buf4 = np.empty(CUBE.shape[:-1] + (4,), np.float64)
    convert(xa, "srgb", "lab", alpha="keep", out=buf4)
    np.testing.assert_array_equal(buf4, convert(xa, "srgb", "lab", alpha="keep"))


@pytest.mark.parametrize(
    ("out", "match"),
    [
        (np.empty(CUBE.shape, np.float64), "dtype float32"),
        (np.empty(CUBE.shape[:-1], np.float32), "shape"),
        (np.empty(CUBE.shape[::-1], np.float32).T, "C-contiguous"),
        ([0.0], "NumPy array"),
    ],
)
def test_out_rejects(out: object, match: str) -> None:
    with pytest.raises((InvalidInputError, TypeError), match=match) as err:
        convert(CUBE, "srgb", "lab", out=out)
    assert "\n" not in str(err.value) and len(str(err.value)) < 200


def test_out_rejects_readonly_and_overlap() -> None:
    ro = np.empty(CUBE.shape, np.float32)
    ro.flags.writeable = False
    with pytest.raises(InvalidInputError, match="writeable"):
        convert(CUBE, "srgb", "lab", out=ro)
    f = CUBE / 255.0
    with pytest.raises(InvalidInputError, match="overlapping"):
        convert(f, "srgb", "lab", out=f)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"dst": "xyz", "dtype": "uint8"}, "dst 'xyz'"),
        ({"dst": "lab", "dtype": "uint16"}, "dtype None or 'uint8'"),
        ({"dst": "lab", "dtype": "uint8", "alpha": "keep"}, "alpha"),
    ],
)
def test_dtype_rejects(kw: dict[str, object], match: str) -> None:
    dst = kw.pop("dst")
    with pytest.raises(InvalidInputError, match=match):
        convert(CUBE, "srgb", dst, **kw)  # type: ignore[arg-type]


# --- integer bilinear demosaicing -----------------------------------------------------------


@pytest.mark.parametrize("pattern", CFA_PATTERNS)
@pytest.mark.parametrize("dtype", [np.uint8, np.uint16])
@pytest.mark.parametrize("shape", [(2, 2), (6, 8), (7, 9), (40, 66), (13, 64), (10, 44)])
def test_int_bilinear_kernel_twin(pattern: str, dtype: type, shape: tuple[int, int]) -> None:
    rng = np.random.default_rng(5)
    raw = rng.integers(0, np.iinfo(dtype).max + 1, shape, dtype=dtype)
    ry, rx = _red_offset(pattern)
    got = demosaic_bilinear.bilinear_int_numba(raw, ry, rx, np.empty((*shape, 3), dtype))
    np.testing.assert_array_equal(got, demosaic_bilinear.bilinear_int_numpy(raw, ry, rx))
    pub = demosaic(raw, pattern, "bilinear", keep_dtype=True, allow_odd=True)
    assert pub.dtype == dtype
    np.testing.assert_array_equal(pub, got)
    ref = (
        demosaic(raw.astype(np.float64) / np.iinfo(dtype).max, pattern, "bilinear", allow_odd=True)
        * np.iinfo(dtype).max
    )
    assert np.abs(got - ref).max() <= 0.5 + 1e-6
    assert np.abs(got.astype(np.float64) - np.rint(ref)).max() <= 1


def test_int_bilinear_avg2_exact() -> None:
    # the loops' 2-mean written with bit operations: (a | b) - ((a ^ b) >> 1); all uint8
    # pairs, and uint16 against the extremes
    a = np.arange(256, dtype=np.int64)[:, None]
    b = np.arange(256, dtype=np.int64)[None, :]
    np.testing.assert_array_equal((a | b) - ((a ^ b) >> 1), (a + b + 1) >> 1)
    a = np.arange(1 << 16, dtype=np.int64)[:, None]
    b = np.array([0, 1, 2, 255, 256, 32767, 32768, 65534, 65535], np.int64)[None, :]
    np.testing.assert_array_equal((a | b) - ((a ^ b) >> 1), (a + b + 1) >> 1)


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16])
@pytest.mark.parametrize("parallel", [False, True])
@pytest.mark.parametrize("shape", [(9, 131), (8, 130), (5, 7)])
def test_int_bilinear_extremes_any_width(
    dtype: type, parallel: bool, shape: tuple[int, int]
) -> None:
    # codes 0, 1, max - 1, max (carries and rounding at the limits), odd and even widths
    top = np.iinfo(dtype).max
    rng = np.random.default_rng(7)
    raw = rng.choice(np.array([0, 1, top - 1, top], dtype), shape)
    for ry in (0, 1):
        for rx in (0, 1):
            out = np.empty((*shape, 3), dtype)
            got = demosaic_bilinear.bilinear_int_numba(raw, ry, rx, out, parallel=parallel)
            np.testing.assert_array_equal(got, demosaic_bilinear.bilinear_int_numpy(raw, ry, rx))


def test_int_bilinear_flat_and_batch() -> None:
    raw = np.full((3, 8, 10, 1), 77, np.uint8)
    got = demosaic(raw, "GRBG", "bilinear", keep_dtype=True)
    assert got.shape == (3, 8, 10, 3) and (got == 77).all()


@pytest.mark.parametrize(
    ("pattern", "code"),
    [("RGGB", "BayerBG"), ("BGGR", "BayerRG"), ("GRBG", "BayerGB"), ("GBRG", "BayerGR")],
)
def test_int_bilinear_equals_opencv_interior(pattern: str, code: str) -> None:
    cv2 = pytest.importorskip("cv2")
    rng = np.random.default_rng(6)
    raw = rng.integers(0, 256, (64, 96), dtype=np.uint8)
    ours = demosaic(raw, pattern, "bilinear", keep_dtype=True)
    cv = cv2.cvtColor(raw, getattr(cv2, f"COLOR_{code}2RGB"))
    np.testing.assert_array_equal(ours[1:-1, 1:-1], cv[1:-1, 1:-1])


def test_int_bilinear_rejects() -> None:
    raw = np.zeros((8, 8), np.uint8)
    with pytest.raises(InvalidInputError, match="bilinear"):
        demosaic(raw, "RGGB", "menon", keep_dtype=True)
    with pytest.raises(InvalidInputError, match="allow_odd"):
        demosaic(np.zeros((7, 8), np.uint8), "RGGB", "bilinear", keep_dtype=True)
    with pytest.raises(InvalidInputError, match="2x2"):
        demosaic(np.zeros((1, 8), np.uint8), "RGGB", "bilinear", keep_dtype=True)
    f = demosaic(np.zeros((8, 8), np.float32), "RGGB", "bilinear", keep_dtype=True)
    assert f.dtype == np.float32


# --- srgb8_to_lab: float Lab of 8-bit sRGB from the tables ----------------------------------


def test_srgb8_to_lab_all_colours_within_0p09() -> None:
    from imageform.color import srgb8_to_lab
    from imageform.color._fast import lab_tables
    from imageform.color.convert import _srgb8_to_lab_numpy

    ours = srgb8_to_lab(CUBE)
    assert ours.dtype == np.float32 and ours.shape == CUBE.shape
    ref = convert(CUBE.astype(np.float64) / 255.0, "srgb", "lab")
    de = delta_e_ciede2000(ours.astype(np.float64), ref)
    assert float(de.max()) <= 0.09 and float(de.mean()) <= 0.004  # measured 0.087, 0.0035
    m = lab_tables("srgb", 2)
    assert m is not None
    np.testing.assert_allclose(_srgb8_to_lab_numpy(CUBE, m), ours, atol=2e-4, rtol=0)


def test_srgb8_to_lab_published_values_out_and_fallbacks(monkeypatch: pytest.MonkeyPatch) -> None:
    from imageform.color import srgb8_to_lab

    x = np.zeros((70, 70, 3), np.uint8)
    x[0, 0] = (255, 0, 0)  # L* a* b* = 53.24, 80.09, 67.20 (IEC 61966-2-1, D65, CIE 15)
    x[0, 1] = (255, 255, 255)
    lab = srgb8_to_lab(x)
    np.testing.assert_allclose(lab[0, 0], [53.24, 80.09, 67.20], atol=0.02)
    np.testing.assert_allclose(lab[0, 1], [100.0, 0.0, 0.0], atol=0.01)
    np.testing.assert_allclose(lab[0, 2], [0.0, 0.0, 0.0], atol=1e-6)
    out = np.empty(x.shape, np.float32)
    assert srgb8_to_lab(x, out=out) is out
    np.testing.assert_array_equal(out, lab)
    # a warmer white (D50): t leaves the table, convert runs (exact)
    d50 = srgb8_to_lab(x, white="D50")
    np.testing.assert_allclose(d50, convert(x, "srgb", "lab", white="D50"), atol=1e-6)
    monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
    np.testing.assert_allclose(srgb8_to_lab(x), lab, atol=2e-4)


def test_srgb8_to_lab_refusals() -> None:
    from imageform.color import srgb8_to_lab

    x = np.zeros((4, 4, 3), np.uint8)
    with pytest.raises(InvalidInputError, match="uint8"):
        srgb8_to_lab(x.astype(np.float32))
    with pytest.raises(InvalidInputError, match="uint8"):
        srgb8_to_lab([[1, 2, 3]])
    with pytest.raises(InvalidInputError, match=r"\(\.\.\., 3\)"):
        srgb8_to_lab(np.zeros((4, 4), np.uint8))
    with pytest.raises(InvalidInputError, match="dtype float32"):
        srgb8_to_lab(x, out=np.empty((4, 4, 3), np.float64))
    with pytest.raises(InvalidInputError, match="shape"):
        srgb8_to_lab(x, out=np.empty((4, 3, 3), np.float32))
    before = x.copy()
    srgb8_to_lab(x)
    np.testing.assert_array_equal(x, before)
