"""Image undistortion by remapping: kernel vs twin, OpenCV cross-checks, round trip, errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imageform.errors import InvalidInputError
from imageform.geometry.distortion import BrownConrady, KannalaBrandt
from imageform.geometry.undistort import (
    _remap_bilinear_numpy,
    remap_bilinear,
    undistort_image,
    undistortion_map,
)

cv2 = pytest.importorskip("cv2")

LEFT_K = np.array([[536.07345314, 0, 342.37046827], [0, 536.01636274, 235.53687064], [0, 0, 1.0]])
LEFT_D = np.array([-0.26509039, -0.0467422, 0.00183302, -0.00031469, 0.25231221])


def _smooth_image(h: int = 120, w: int = 160) -> np.ndarray:
    v, u = np.mgrid[0:h, 0:w]
    img = np.stack(
        [0.5 + 0.4 * np.sin(u / 9.0), 0.5 + 0.4 * np.cos(v / 7.0), (u + v) / (h + w)], axis=-1
    )
    return img


def test_bilinear_value_by_hand() -> None:
    img = np.array([[0.0, 0.2], [0.4, 0.6]])
    out = remap_bilinear(img, [[[0.25, 0.5], [1.0, 1.0], [1.5, 0.0], [-0.1, 0.0]]], fill=-1.0)
    # (0.25, 0.5): 0.75*0.5*0 + 0.25*0.5*0.2 + 0.75*0.5*0.4 + 0.25*0.5*0.6 = 0.25
    np.testing.assert_allclose(out, [[0.25, 0.6, -1.0, -1.0]], atol=1e-15)


def test_remap_kernel_matches_twin() -> None:
    from imageform._kernels.remap import remap_bilinear as kernel

    rng = np.random.default_rng(0)
    img = rng.random((2, 30, 40, 3))
    m = rng.uniform(-2, 42, (25, 35, 2))
    m[0, 0] = np.nan
    out = np.empty((2, 25, 35, 3))
    kernel(img, m, 1.0, 0.5, out, np.empty(0), np.empty(0, np.int32), 0.0)
    twin = _remap_bilinear_numpy(img, m[..., 0], m[..., 1], 0.5)
    np.testing.assert_allclose(out, twin, atol=1e-12)
    assert out[0, 0, 0, 0] == 0.5


def test_identity_map_returns_image() -> None:
    img = _smooth_image()
    out = undistort_image(img, LEFT_K, BrownConrady())
    np.testing.assert_allclose(out, img, atol=1e-12)


def test_cross_check_cv2_remap_with_our_map() -> None:
    img = _smooth_image().astype(np.float32)
    K = np.array([[150.0, 0, 79.5], [0, 150, 59.5], [0, 0, 1]])
    m = undistortion_map(img.shape[:2], K, BrownConrady(k1=-0.3, k2=0.05))
    ref = cv2.remap(
        img,
        m[..., 0].astype(np.float32),
        m[..., 1].astype(np.float32),
        cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_CONSTANT,
        borderValue=0,
    )
    ours = undistort_image(img, K, BrownConrady(k1=-0.3, k2=0.05))
    # OpenCV interpolates with 1/32-pixel weights (INTER_TAB_SIZE = 32)
    inner = np.s_[2:-2, 2:-2]
    assert np.abs(ours - ref)[inner].max() < 2e-3


def test_cross_check_cv2_undistort_on_chessboard(shared_data: Path) -> None:
    img = cv2.imread(str(shared_data / "opencv-left" / "left01.jpg"), cv2.IMREAD_GRAYSCALE)
    ours = undistort_image(img, LEFT_K, BrownConrady.from_opencv(LEFT_D))
    ref = cv2.undistort(img.astype(np.float32) / 255, LEFT_K, LEFT_D)
    inner = np.s_[5:-5, 5:-5]
    diff = np.abs(ours - ref)[inner]
    assert ours.dtype == np.float32 and ours.shape == img.shape
    assert diff.mean() < 1e-3 and diff.max() < 0.02  # 1/32 px quantisation in OpenCV


def test_distort_then_undistort_image_round_trip() -> None:
    img = _smooth_image()
    K = np.array([[150.0, 0, 79.5], [0, 150, 59.5], [0, 0, 1]])
    model = BrownConrady(k1=-0.2)
    # synthesise the distorted image: at distorted pixel p sample the ideal image at undistort(p)
    h, w = img.shape[:2]
    v, u = np.mgrid[0:h, 0:w].astype(float)
    xd = np.stack([(u - K[0, 2]) / K[0, 0], (v - K[1, 2]) / K[1, 1]], axis=-1)
    xu, ok = model.undistort(xd)
    assert ok.all()
    src = np.stack([xu[..., 0] * K[0, 0] + K[0, 2], xu[..., 1] * K[1, 1] + K[1, 2]], axis=-1)
    distorted = remap_bilinear(img, src, fill=np.nan)
    back = undistort_image(distorted, K, model, fill=np.nan)
    good = np.isfinite(back).all(axis=-1)
    good[:10], good[-10:], good[:, :10], good[:, -10:] = False, False, False, False
    assert np.abs(back - img)[good].max() < 0.01  # two bilinear resamplings of a smooth image


def test_fisheye_and_batch_and_gray() -> None:
    img = _smooth_image(40, 50)
    K = np.array([[30.0, 0, 24.5], [0, 30, 19.5], [0, 0, 1]])
    batch = np.stack([img, img[..., ::-1]])
    out = undistort_image(batch, K, KannalaBrandt(k1=0.02))
    assert out.shape == batch.shape
    np.testing.assert_allclose(out[1], undistort_image(img[..., ::-1], K, KannalaBrandt(k1=0.02)))
    gray = undistort_image(img[..., 0], K, KannalaBrandt(k1=0.02))
    np.testing.assert_allclose(gray, out[0, ..., 0])


def test_dtypes() -> None:
    img8 = (np.random.default_rng(1).random((20, 30, 3)) * 255).astype(np.uint8)
    K = np.array([[40.0, 0, 14.5], [0, 40, 9.5], [0, 0, 1]])
    assert undistort_image(img8, K, BrownConrady(k1=0.1)).dtype == np.float32
    assert undistort_image(img8 / 255.0, K, BrownConrady(k1=0.1)).dtype == np.float64
    assert undistort_image((img8 / 255).astype(np.float32), K, None).dtype == np.float32


def test_bad_inputs() -> None:
    K = np.array([[40.0, 0, 14.5], [0, 40, 9.5], [0, 0, 1]])
    with pytest.raises(InvalidInputError, match="shape"):
        undistort_image(np.zeros(5), K, None)
    with pytest.raises(InvalidInputError, match=r"K of shape \(3, 3\)"):
        undistort_image(np.zeros((5, 5)), np.eye(2), None)
    with pytest.raises(InvalidInputError, match="upper triangular"):
        undistort_image(np.zeros((5, 5)), np.zeros((3, 3)), None)
    with pytest.raises(InvalidInputError, match="map_uv"):
        remap_bilinear(np.zeros((5, 5)), np.zeros((5, 5)))


def test_fused_brown_conrady_kernel_matches_map_twin(monkeypatch: pytest.MonkeyPatch) -> None:
    img = _smooth_image(60, 80)
    K = np.array([[70.0, 0.3, 39.5], [0, 72, 29.5], [0, 0, 1]])
    new_K = np.array([[60.0, 0, 40.0], [0, 60, 30.0], [0, 0, 1]])
    model = BrownConrady(k1=-0.2, k2=0.03, p1=0.002, p2=-0.001, k3=0.01, k4=0.05)
    fused = undistort_image(img, K, model, new_K=new_K, out_shape=(50, 70), fill=-1.0)
    m = undistortion_map((50, 70), K, model, new_K=new_K)
    twin = _remap_bilinear_numpy(img[None], m[..., 0], m[..., 1], -1.0)[0]
    np.testing.assert_allclose(fused, twin, atol=1e-12)
    monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
    plain = undistort_image(img, K, model, new_K=new_K, out_shape=(50, 70), fill=-1.0)
    np.testing.assert_allclose(plain, twin, atol=1e-12)
