"""Fast remapping paths (issue 19): 8-bit images sampled directly, float32 maps used as they
are, the fused Brown-Conrady kernel against the map path, and equality with OpenCV 5's
``cv2.remap`` / ``cv2.undistort`` on float images (exact bilinear there) to 1e-3."""

from __future__ import annotations

import numpy as np
import pytest

from imageform.errors import InvalidInputError
from imageform.geometry.distortion import BrownConrady
from imageform.geometry.undistort import (
    _remap_bilinear_numpy,
    remap_bilinear,
    undistort_image,
    undistortion_map,
)

cv2 = pytest.importorskip("cv2")

K = np.array([[180.0, 0, 99.5], [0, 182, 74.5], [0, 0, 1]])
D = np.array([-0.26509039, -0.0467422, 0.00183302, -0.00031469, 0.25231221])


def _image(c: int, dtype: type, h: int = 150, w: int = 200) -> np.ndarray:
    v, u = np.mgrid[0:h, 0:w]
    planes = [0.5 + 0.45 * np.sin(u / (5.0 + k) + v / (7.0 + k)) for k in range(c)]
    img = np.stack(planes, axis=-1) if c > 1 else planes[0]
    if dtype == np.uint8:
        return np.round(img * 255).astype(np.uint8)
    return img.astype(dtype)


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.float32, np.float64])
@pytest.mark.parametrize("c", [1, 3, 4])
def test_remap_kernel_matches_twin_all_dtypes(dtype: type, c: int) -> None:
    from imageform._kernels.remap import remap_bilinear as kernel

    rng = np.random.default_rng(c)
    img = (
        (rng.random((2, 30, 40, c)) * np.iinfo(dtype).max).astype(dtype)
        if np.dtype(dtype).kind == "u"
        else rng.random((2, 30, 40, c)).astype(dtype)
    )
    m = rng.uniform(-2, 42, (25, 35, 2))
    m[0, 0] = np.nan
    m[1, 1] = (39.0, 29.0)  # the last pixel exactly
    scale = 1.0 / np.iinfo(dtype).max if np.dtype(dtype).kind == "u" else 1.0
    for mdt in (np.float64, np.float32):
        mm = m.astype(mdt)
        out = np.empty((2, 25, 35, c), np.float64)
        kernel(img, mm, scale, 0.5, out, np.empty(0), np.empty(0, np.int64), 0.0)
        twin = _remap_bilinear_numpy(img.astype(np.float64) * scale, mm[..., 0], mm[..., 1], 0.5)
        np.testing.assert_allclose(out, twin, atol=1e-12)
        assert out[0, 0, 0, 0] == 0.5


@pytest.mark.parametrize("c", [1, 3])
@pytest.mark.parametrize("dtype", [np.uint8, np.float32])
def test_remap_equals_cv2_remap_float(c: int, dtype: type) -> None:
    img = _image(c, dtype)
    m = undistortion_map(img.shape[:2], K, BrownConrady.from_opencv(D)).astype(np.float32)
    ours = remap_bilinear(img, m)
    assert ours.dtype == np.float32 and ours.shape == img.shape
    f = img.astype(np.float32) / 255 if dtype == np.uint8 else img
    ref = cv2.remap(f, m[..., 0].copy(), m[..., 1].copy(), cv2.INTER_LINEAR)
    assert np.abs(ours - ref).max() < 1e-3
    if dtype == np.uint8:  # OpenCV's 8-bit output: our float result rounded, within 1 code
        ref8 = cv2.remap(img, m[..., 0].copy(), m[..., 1].copy(), cv2.INTER_LINEAR)
        assert np.abs(ours * 255 - ref8).max() <= 1.0


@pytest.mark.parametrize("c", [1, 3])
@pytest.mark.parametrize("dtype", [np.uint8, np.float32])
def test_undistort_equals_cv2_undistort_float(c: int, dtype: type) -> None:
    img = _image(c, dtype)
    ours = undistort_image(img, K, BrownConrady.from_opencv(D))
    f = img.astype(np.float32) / 255 if dtype == np.uint8 else img
    mx, my = cv2.initUndistortRectifyMap(K, D, None, K, img.shape[1::-1], cv2.CV_32FC1)
    ref = cv2.remap(f, mx, my, cv2.INTER_LINEAR)  # OpenCV with float maps: exact bilinear
    assert ours.dtype == np.float32
    assert np.abs(ours - ref).max() < 1e-3
    # cv2.undistort quantises the positions to 1/32 px (fixed-point maps): the difference
    # is bounded by the image gradient (here <= 0.2 / px) times 1/64 px
    assert np.abs(ours - cv2.undistort(f, K, D)).max() < 5e-3


def test_uint8_path_equals_float_path() -> None:
    img = _image(3, np.uint8)
    model = BrownConrady.from_opencv(D)
    a = undistort_image(img, K, model)
    b = undistort_image(img.astype(np.float32) / 255, K, model)
    np.testing.assert_allclose(a, b, atol=1e-6)
    m = undistortion_map(img.shape[:2], K, model)
    np.testing.assert_allclose(remap_bilinear(img, m), a, atol=1e-6)  # fused == map path


def test_float32_map_is_used_as_is_and_matches_float64_map() -> None:
    img = _image(3, np.float64)
    m = undistortion_map(img.shape[:2], K, BrownConrady.from_opencv(D))
    a = remap_bilinear(img, m)
    b = remap_bilinear(img, m.astype(np.float32))
    assert np.abs(a - b).max() < 1e-4  # float32 positions: ~1e-5 px at 200 px


def test_plain_path_scales_integer_images(monkeypatch: pytest.MonkeyPatch) -> None:
    img = _image(3, np.uint8, 30, 40)
    m = np.random.default_rng(2).uniform(0, 30, (10, 12, 2))
    fast = remap_bilinear(img, m)
    monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
    plain = remap_bilinear(img, m)
    assert plain.dtype == fast.dtype == np.float32
    np.testing.assert_allclose(plain, fast, atol=1e-6)


def test_non_contiguous_and_batched_inputs() -> None:
    img = _image(3, np.float32)
    m = undistortion_map(img.shape[:2], K, BrownConrady.from_opencv(D))
    flipped = img[:, ::-1]
    np.testing.assert_allclose(
        remap_bilinear(flipped, m[::2, ::2]), remap_bilinear(flipped.copy(), m[::2, ::2].copy())
    )
    batch = np.stack([img, img[..., ::-1]])
    out = undistort_image(batch, K, BrownConrady.from_opencv(D))
    ref = undistort_image(img[..., ::-1], K, BrownConrady.from_opencv(D))
    np.testing.assert_allclose(out[1], ref)


def test_bad_inputs_fast_path() -> None:
    with pytest.raises(InvalidInputError, match=r"map_uv of shape \(H, W, 2\)"):
        remap_bilinear(np.zeros((5, 5), np.uint8), np.zeros((5, 5, 3), np.float32))
    with pytest.raises(InvalidInputError, match="shape"):
        remap_bilinear(np.zeros(5, np.uint8), np.zeros((5, 5, 2), np.float32))
    with pytest.raises(InvalidInputError, match="dtype int32"):
        remap_bilinear(np.zeros((5, 5), np.int32), np.zeros((5, 5, 2)))
    with pytest.raises(InvalidInputError, match="non-empty"):
        undistort_image(np.zeros((0, 5), np.uint8), K, None)
