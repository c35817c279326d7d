"""Camera, projection, back-projection, P = K[R|t] and its decomposition."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imageform.errors import DegenerateConfigurationError, InvalidInputError, UnknownOptionError
from imageform.geometry import (
    Camera,
    Intrinsics,
    backproject,
    decompose_projection_matrix,
    intrinsic_matrix,
    project_points,
    projected_size,
    projection_matrix,
    rvec_to_matrix,
    unproject,
)
from imageform.geometry import camera as camera_mod

K0 = np.array([[500.0, 0.0, 320.0], [0.0, 500.0, 240.0], [0.0, 0.0, 1.0]])


def random_camera(rng: np.random.Generator, skew: float = 0.0) -> tuple[np.ndarray, ...]:
    K = intrinsic_matrix(
        rng.uniform(300, 1500),
        rng.uniform(300, 1500),
        rng.uniform(200, 800),
        rng.uniform(100, 600),
        skew,
    )
    rvec = rng.normal(size=3) * 0.5
    t = rng.normal(size=3) + [0, 0, 8.0]
    return K, rvec, rvec_to_matrix(rvec), t


# -- the lecture's numbers ---------------------------------------------------------------


def test_lecture_building_image_size() -> None:
    """Lecture: H = 30 m at Z = 100 m, f = 50 mm -> 15 mm; 3000 px at 5 µm pitch."""
    h_mm = projected_size(30.0, 100.0, focal_length=50.0)
    assert h_mm == pytest.approx(15.0)
    assert h_mm * 1000.0 / 5.0 == pytest.approx(3000.0)
    intr = Intrinsics.from_physical(
        focal_length_mm=50.0, pixel_pitch_um=5.0, image_size=(6000, 4000)
    )
    # the same through the camera: a 30 m tall object at 100 m spans 3000 px
    top, bottom = Camera(intr).project([[0.0, -15.0, 100.0], [0.0, 15.0, 100.0]]).uv
    assert bottom[1] - top[1] == pytest.approx(3000.0)


def test_lecture_second_building() -> None:
    """Lecture: H = 20 m at 80 m with f = 35 mm gives 8.75 mm."""
    assert projected_size(20.0, 80.0, focal_length=35.0) == pytest.approx(8.75)


def test_lecture_point_projection() -> None:
    """Lecture: P = (3, -1, 5), f = 100 px -> (60, -20)."""
    uv, valid = project_points([3.0, -1.0, 5.0], intrinsic_matrix(100, 100, 0, 0))
    np.testing.assert_allclose(uv, [60.0, -20.0])
    assert bool(valid)


# -- cross-checks against OpenCV -----------------------------------------------------------


def test_project_matches_opencv_projectpoints() -> None:
    rng = np.random.default_rng(10)
    for _ in range(20):
        K, rvec, R, t = random_camera(rng)
        X = rng.uniform(-2, 2, size=(200, 3))
        uv, valid = project_points(X, K, R, t)
        ref = cv2.projectPoints(X, rvec, t, K, None)[0][:, 0]
        assert valid.all()
        np.testing.assert_allclose(uv, ref, atol=1e-9)


def test_opencv_ignores_skew_we_do_not() -> None:
    K = intrinsic_matrix(500, 500, 320, 240, skew=25.0)
    X = np.array([[0.4, 0.6, 2.0]])
    uv = project_points(X, K).uv[0]
    assert uv[0] == pytest.approx(500 * 0.2 + 25 * 0.3 + 320)
    cv_uv = cv2.projectPoints(X, np.zeros(3), np.zeros(3), K, None)[0][0, 0]
    assert cv_uv[0] == pytest.approx(500 * 0.2 + 320)  # OpenCV drops K[0, 1]


def test_decompose_matches_opencv() -> None:
    rng = np.random.default_rng(11)
    for _ in range(20):
        K, _, R, t = random_camera(rng, skew=rng.uniform(-5, 5))
        P = projection_matrix(K, R, t) * rng.uniform(0.1, 10)
        Kd, Rd, td = decompose_projection_matrix(P)
        Kc, Rc, Cc = cv2.decomposeProjectionMatrix(P)[:3]
        np.testing.assert_allclose(Kd, Kc / Kc[2, 2], rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(Rd, Rc, atol=1e-10)
        np.testing.assert_allclose(-Rd.T @ td, (Cc[:3] / Cc[3]).ravel(), atol=1e-8)
        np.testing.assert_allclose(Kd, K, rtol=1e-9, atol=1e-8)
        np.testing.assert_allclose(Rd, R, atol=1e-10)
        np.testing.assert_allclose(td, t, atol=1e-9)


def test_decompose_negative_scale_gives_proper_rotation() -> None:
    P = -3.0 * projection_matrix(K0, rvec_to_matrix([0.1, 0.2, 0.3]), [0.0, 0.0, 4.0])
    K, R, _ = decompose_projection_matrix(P)
    assert np.linalg.det(R) == pytest.approx(1.0)
    assert (np.diag(K) > 0).all()


def test_decompose_singular() -> None:
    P = np.zeros((3, 4))
    P[:, :2] = np.eye(3)[:, :2]
    with pytest.raises(DegenerateConfigurationError, match="singular"):
        decompose_projection_matrix(P)


# -- z <= 0 and image planes -------------------------------------------------------------


def test_points_behind_camera_are_nan_never_mirrored() -> None:
    X = np.array([[1.0, 1.0, 5.0], [1.0, 1.0, -5.0], [1.0, 1.0, 0.0], [np.inf, 0.0, 1.0]])
    uv, valid = project_points(X, K0)
    np.testing.assert_array_equal(valid, [True, False, False, False])
    assert np.isnan(uv[1:]).all()
    # OpenCV mirrors the point behind the camera to a plausible pixel
    mirrored = cv2.projectPoints(X[1:2], np.zeros(3), np.zeros(3), K0, None)[0][0, 0]
    np.testing.assert_allclose(mirrored, [320 - 100, 240 - 100])


def test_projection_that_overflows_is_invalid_on_both_paths() -> None:
    # finite in the camera frame, but x / z overflows float32: no inf pixel, valid = False
    X = np.zeros((30_000, 3), dtype=np.float32)
    X[:, 2] = 1.0
    X[0] = [3e38, 0.0, 1e-3]
    X[1] = [np.nan, 0.0, 1.0]
    X[2] = [0.0, 0.0, np.inf]
    K = K0.astype(np.float32)
    kernel_uv, kernel_valid = project_points(X, K)  # numba kernel (>= 20 000 points)
    from array_api_compat import numpy as xp

    twin_uv, twin_valid = camera_mod._project_xp(
        X, K, np.eye(3, dtype=np.float32), np.zeros(3, np.float32), xp, identity=True
    )
    for uv, valid in ((kernel_uv, kernel_valid), (twin_uv, twin_valid)):
        np.testing.assert_array_equal(valid[:4], [False, False, False, True])
        assert np.isnan(uv[:3]).all() and np.isfinite(uv[3:]).all()


def test_real_image_plane_is_inverted() -> None:
    X = np.array([[1.0, 0.5, 5.0]])
    virt = project_points(X, K0).uv[0]
    real = project_points(X, K0, image_plane="real").uv[0]
    np.testing.assert_allclose(real, [2 * 320 - virt[0], 2 * 240 - virt[1]])
    cam = Camera(K0, image_plane="real")
    np.testing.assert_allclose(cam.unproject(real, 5.0), X[0])
    with pytest.raises(UnknownOptionError, match="image plane"):
        project_points(X, K0, image_plane="mirror")  # type: ignore[arg-type]


def test_image_plane_K() -> None:
    K = intrinsic_matrix(500.0, 480.0, 320.0, 240.0, 2.0)
    R, t = rvec_to_matrix([0.1, -0.2, 0.05]), np.array([0.2, -0.1, 4.0])
    np.testing.assert_array_equal(Camera(K, R, t).image_plane_K, K)
    real = Camera(K, R, t, image_plane="real")
    # fx, fy and the skew change sign, the principal point does not
    want = np.array([[-500.0, -2.0, 320.0], [0.0, -480.0, 240.0], [0.0, 0.0, 1.0]])
    np.testing.assert_array_equal(real.image_plane_K, want)
    np.testing.assert_array_equal(real.projection_matrix, projection_matrix(want, R, t))
    # P = image_plane_K [R | t] projects like the camera: the inverted image
    X = np.array([[0.3, -0.2, 1.0], [-0.5, 0.4, 2.0]])
    h = np.c_[X, np.ones(2)] @ real.projection_matrix.T
    np.testing.assert_allclose(h[:, :2] / h[:, 2:], real.project(X).uv, rtol=0, atol=1e-9)


# -- numba kernel vs array twin --------------------------------------------------------------


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_kernel_matches_twin(dtype: type) -> None:
    rng = np.random.default_rng(12)
    K, _, R, t = random_camera(rng, skew=3.0)
    X = rng.uniform(-3, 3, size=(50_000, 3)).astype(dtype)
    X[::7, 2] -= 12.0  # some behind the camera
    uv, valid = project_points(X, K, R, t)  # kernel path (>= 20 000 points)
    from array_api_compat import numpy as xp

    Xd = X.astype(dtype)
    twin_uv, twin_valid = camera_mod._project_xp(
        Xd, K.astype(dtype), R.astype(dtype), t.astype(dtype), xp
    )
    assert uv.dtype == dtype
    np.testing.assert_array_equal(valid, twin_valid)
    # Both paths round z_cam differently; a point a hair in front of the camera divides by
    # that rounding, so compare where z_cam > 0.5 (the conditioning is 1/z there).
    z = (Xd.astype(np.float64) @ R.T + t)[:, 2]
    ok = valid & (z > 0.5)
    atol, rtol = (1e-9, 1e-13) if dtype == np.float64 else (1e-2, 1e-5)
    np.testing.assert_allclose(uv[ok], twin_uv[ok], atol=atol, rtol=rtol)
    assert (~valid).sum() > 0 and np.isnan(uv[~valid]).all()


def test_kernel_dispatch_can_be_disabled(monkeypatch: pytest.MonkeyPatch) -> None:
    rng = np.random.default_rng(13)
    X = rng.uniform(-1, 1, size=(30_000, 3)) + [0, 0, 5]
    a = project_points(X, K0).uv
    monkeypatch.setenv("IMAGEFORM_DISABLE_NUMBA", "1")
    b = project_points(X, K0).uv
    np.testing.assert_allclose(a, b, atol=1e-12)


# -- properties --------------------------------------------------------------------------------

_pix = st.floats(0, 1000, allow_nan=False)


@settings(max_examples=60, deadline=None)
@given(u=_pix, v=_pix, z=st.floats(0.01, 1e4), skew=st.floats(-20, 20))
def test_project_unproject_property(u: float, v: float, z: float, skew: float) -> None:
    K = intrinsic_matrix(800, 820, 400, 300, skew)
    R = rvec_to_matrix([0.1, -0.3, 0.2])
    t = np.array([0.5, -0.2, 1.0])
    X = unproject([u, v], z, K, R, t)
    uv, valid = project_points(X, K, R, t)
    assert bool(valid)
    np.testing.assert_allclose(uv, [u, v], atol=1e-7)


@settings(max_examples=60, deadline=None)
@given(
    f=st.floats(50, 5000),
    aspect=st.floats(0.5, 2.0),
    cx=st.floats(-100, 2000),
    cy=st.floats(-100, 2000),
    skew=st.floats(-50, 50),
    r=st.lists(st.floats(-3, 3), min_size=3, max_size=3),
    t=st.lists(st.floats(-100, 100), min_size=3, max_size=3),
    scale=st.floats(-100, 100).filter(lambda s: abs(s) > 1e-3),
)
def test_decompose_compose_property(
    f: float,
    aspect: float,
    cx: float,
    cy: float,
    skew: float,
    r: list[float],
    t: list[float],
    scale: float,
) -> None:
    K = intrinsic_matrix(f, f * aspect, cx, cy, skew)
    R = rvec_to_matrix(r)
    Kd, Rd, td = decompose_projection_matrix(scale * projection_matrix(K, R, t))
    np.testing.assert_allclose(Kd, K, rtol=1e-8, atol=1e-8 * f)
    np.testing.assert_allclose(Rd, R, atol=1e-9)
    np.testing.assert_allclose(td, t, atol=1e-7 * (1 + np.abs(t).max()))


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-1e3, 1e3, allow_nan=False), min_size=3, max_size=3))
def test_points_with_nonpositive_depth_never_valid(p: list[float]) -> None:
    R = rvec_to_matrix([0.2, 0.1, -0.3])
    t = np.array([0.0, 0.0, 2.0])
    uv, valid = project_points(p, K0, R, t)
    z = (R @ np.asarray(p) + t)[2]
    assert bool(valid) == (z > 0)
    if z <= 0:
        assert np.isnan(uv).all()


def test_batched_cameras_broadcast() -> None:
    rng = np.random.default_rng(14)
    Ks = np.stack([random_camera(rng)[0] for _ in range(3)])
    Rs = np.stack([rvec_to_matrix(rng.normal(size=3) * 0.2) for _ in range(3)])
    ts = np.tile([0.0, 0.0, 5.0], (3, 1))
    X = rng.uniform(-1, 1, size=(3, 10, 3))
    uv, valid = project_points(X, Ks, Rs, ts)
    assert uv.shape == (3, 10, 2) and valid.shape == (3, 10)
    for i in range(3):
        np.testing.assert_allclose(uv[i], project_points(X[i], Ks[i], Rs[i], ts[i]).uv)


# -- Camera ------------------------------------------------------------------------------


def test_camera_center_projection_matrix_and_rays() -> None:
    R = rvec_to_matrix([0.0, 0.3, 0.0])
    t = np.array([0.1, 0.2, 3.0])
    cam = Camera(K0, R, t, image_size=(640, 480))
    np.testing.assert_allclose(cam.center, -R.T @ t)
    P = cam.projection_matrix
    X = np.array([0.3, -0.2, 1.0])
    x = P @ np.r_[X, 1.0]
    np.testing.assert_allclose(x[:2] / x[2], cam.project(X).uv)
    d = cam.backproject(cam.project(X).uv)
    np.testing.assert_allclose(d, (X - cam.center) / np.linalg.norm(X - cam.center), atol=1e-12)
    cam2 = Camera.from_projection_matrix(7.0 * P)
    np.testing.assert_allclose(cam2.K, cam.K, atol=1e-9)
    assert cam.intrinsics.fx == 500.0
    np.testing.assert_array_equal(
        cam.in_image([[0.0, 0.0], [640.0, 10.0], [np.nan, 1.0]]), [True, False, False]
    )


def test_camera_look_at() -> None:
    cam = Camera.look_at(K0, eye=[0.0, -1.0, -4.0], target=[0.0, 0.0, 0.0])
    np.testing.assert_allclose(cam.project([0.0, 0.0, 0.0]).uv, [320.0, 240.0], atol=1e-12)


def test_camera_bad_inputs() -> None:
    with pytest.raises(InvalidInputError, match="rotation"):
        Camera(K0, R=np.eye(3) * 2)
    with pytest.raises(InvalidInputError, match="reflection"):
        Camera(K0, R=np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(InvalidInputError, match="singular"):
        Camera(np.diag([500.0, 0.0, 1.0]))
    with pytest.raises(InvalidInputError, match=r"expected K of shape \(3, 3\), got \(4, 4\)"):
        Camera(np.eye(4))
    with pytest.raises(InvalidInputError, match="upper-triangular"):
        Camera(np.array([[500.0, 0, 320], [1, 500, 240], [0, 0, 1]]))
    with pytest.raises(
        InvalidInputError, match=r"expected points of shape \(\.\.\., 3\), got \(4, 2\)"
    ):
        Camera(K0).project(np.zeros((4, 2)))
    with pytest.raises(InvalidInputError, match="NaN"):
        Camera(K0, t=[0.0, np.nan, 1.0])
    with pytest.raises(InvalidInputError, match="depth > 0"):
        Camera(K0).unproject([1.0, 2.0], -1.0)
    with pytest.raises(InvalidInputError, match="image_size"):
        Camera(K0).in_image([1.0, 1.0])


@pytest.mark.parametrize("sign", [(-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)])
def test_negative_focal_lengths_are_refused(sign: tuple[float, float]) -> None:
    """A negative focal length mirrors the image: refused by Camera, Intrinsics and
    intrinsic_matrix (the inverted image of a camera obscura is image_plane="real")."""
    fx, fy = 500.0 * sign[0], 500.0 * sign[1]
    K = np.array([[fx, 0.0, 320.0], [0.0, fy, 240.0], [0.0, 0.0, 1.0]])
    with pytest.raises(InvalidInputError, match=r"fx > 0 and fy > 0.* mirrors"):
        Camera(K)
    with pytest.raises(InvalidInputError, match=r"fx > 0 and fy > 0.*mirrors"):
        Intrinsics(fx, fy, 320.0, 240.0)
    with pytest.raises(InvalidInputError, match=r"fx > 0 and fy > 0.*mirrors"):
        intrinsic_matrix(fx, fy, 320.0, 240.0)
    with pytest.raises(InvalidInputError, match=r"fx > 0 and fy > 0"):
        intrinsic_matrix(np.array([500.0, fx]), np.array([500.0, fy]), 0.0, 0.0)
    # K scaled by -1 overall is the same camera: accepted, normalised to K[2, 2] = 1
    np.testing.assert_allclose(np.asarray(Camera(-K0).K), K0)


# -- Intrinsics ----------------------------------------------------------------------------


def test_intrinsics_physical_and_fov() -> None:
    intr = Intrinsics.from_physical(
        focal_length_mm=50.0, pixel_pitch_um=5.0, image_size=(6000, 4000)
    )
    assert intr.fx == pytest.approx(10_000.0)
    # 30 mm sensor width at 50 mm: 2 atan(15 / 50) = 33.398°
    assert math.degrees(intr.fov_x) == pytest.approx(2 * math.degrees(math.atan(15 / 50)))
    sens = Intrinsics.from_sensor(
        focal_length_mm=50.0, sensor_size_mm=(30.0, 20.0), image_size=(6000, 4000)
    )
    assert sens.fx == pytest.approx(intr.fx) and sens.fy == pytest.approx(intr.fy)
    fov = Intrinsics.from_fov(math.radians(90), (1000, 800))
    assert fov.fx == pytest.approx(500.0)
    assert math.degrees(fov.fov_x) == pytest.approx(90.0)
    assert math.degrees(fov.fov_diagonal) == pytest.approx(
        2 * math.degrees(math.atan(math.hypot(1000, 800) / 1000))
    )
    half = intr.scaled(0.5)
    assert half.cx == pytest.approx((2999.5 + 0.5) * 0.5 - 0.5) and half.image_size == (3000, 2000)


def test_intrinsics_bad() -> None:
    with pytest.raises(InvalidInputError, match="non-zero"):
        Intrinsics(0.0, 1.0, 0.0, 0.0)
    with pytest.raises(InvalidInputError, match="pixel_pitch_um > 0"):
        Intrinsics.from_physical(focal_length_mm=50.0, pixel_pitch_um=-5.0, image_size=(10, 10))
    with pytest.raises(InvalidInputError, match="image_size"):
        _ = Intrinsics(1.0, 1.0, 0.0, 0.0).fov_x
    with pytest.raises(InvalidInputError, match="0 < fov_x < pi"):
        Intrinsics.from_fov(4.0, (10, 10))
    with pytest.raises(InvalidInputError, match="depth > 0"):
        projected_size(1.0, 0.0, focal_length=50.0)
    with pytest.raises(InvalidInputError, match="non-zero focal"):
        intrinsic_matrix(0, 1, 0, 0)


def test_backproject_principal_point_and_float32() -> None:
    d = backproject(np.array([320.0, 240.0], dtype=np.float32), K0)
    assert d.dtype == np.float32
    np.testing.assert_allclose(d, [0, 0, 1])


def test_camera_with_distortion_round_trip() -> None:
    """Camera(distortion=...) projects like cv2.projectPoints with coefficients, and
    unproject inverts it (Newton inverse of the model)."""
    from imageform.geometry import BrownConrady

    dist = BrownConrady(k1=-0.25, k2=0.05, p1=1e-3, p2=-5e-4, k3=0.01)
    R = rvec_to_matrix([0.05, -0.1, 0.02])
    t = np.array([0.1, 0.0, 3.0])
    cam = Camera(K0, R, t, distortion=dist)
    X = np.random.default_rng(7).uniform(-1, 1, size=(50, 3))
    uv, valid = cam.project(X)
    ref = cv2.projectPoints(X, cv2.Rodrigues(R)[0], t, K0, np.array(dist.coeffs))[0][:, 0]
    assert valid.all()
    np.testing.assert_allclose(uv, ref, atol=1e-9)
    depth = (X @ R.T + t)[:, 2]
    np.testing.assert_allclose(cam.unproject(uv, depth), X, atol=1e-9)
    rays = cam.backproject(uv)
    np.testing.assert_allclose(
        rays, (X - cam.center) / np.linalg.norm(X - cam.center, axis=1)[:, None], atol=1e-10
    )
    with pytest.raises(InvalidInputError, match="virtual"):
        Camera(K0, distortion=dist, image_plane="real")
