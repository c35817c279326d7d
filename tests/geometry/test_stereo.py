"""Stereo calibration and rectification: synthetic rigs with known truth, and OpenCV.

Measured on the noisy rig below (18 views of a 9 x 6 board, 0.1 px noise, OpenCV 5.0):
with the intrinsics fixed at the single-camera results, R within 3e-7 deg and T within
3e-8 (relative) of ``cv2.stereoCalibrate(flags=CALIB_FIX_INTRINSIC)``; in the joint mode R
within 2e-5 deg and T within 3e-7 of ``cv2.stereoCalibrate(flags=CALIB_FIX_K3)``; rectified
R1/R2 identical to ``cv2.stereoRectify`` to 1e-15 and P1/P2 to 1e-5 px for every alpha.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imageform.errors import DegenerateConfigurationError, InvalidInputError
from imageform.geometry import (
    BrownConrady,
    StereoCalibrationResult,
    checkerboard_points,
    project_points_distorted,
    rectification_map,
    remap_bilinear,
    stereo_calibrate,
    stereo_rectify,
)
from imageform.geometry.rotations import matrix_to_rvec, rvec_to_matrix

cv2 = pytest.importorskip("cv2")

SIZE = (640, 480)
K1 = np.array([[810.0, 0, 322], [0, 805, 238], [0, 0, 1]])
D1 = BrownConrady(-0.12, 0.08, 0.001, -0.0005, 0.0)
K2 = np.array([[790.0, 0, 315], [0, 792, 245], [0, 0, 1]])
D2 = BrownConrady(-0.09, 0.05, -0.0008, 0.0006, 0.0)
R_TRUE = np.asarray(rvec_to_matrix([0.02, -0.08, 0.01]))
T_TRUE = np.array([-120.0, 2.0, 3.0])
OBJ = checkerboard_points((9, 6), 25.0)


def _rig(noise: float, seed: int = 1, n_views: int = 18) -> tuple[list, list, list, list, list]:
    """Views of the board seen whole by both cameras: (objs, left, right, clean l, clean r)."""
    rng = np.random.default_rng(seed)
    objs, uvl, uvr, cl, cr = [], [], [], [], []
    while len(objs) < n_views:
        Rk = np.asarray(rvec_to_matrix(rng.normal(0, 0.25, 3)))
        t = np.array([-40 + rng.normal(0, 30), -62 + rng.normal(0, 30), 550 + rng.normal(0, 60)])
        a = np.asarray(project_points_distorted(OBJ, K1, Rk, t, D1)[0])
        b = np.asarray(project_points_distorted(OBJ, K2, R_TRUE @ Rk, R_TRUE @ t + T_TRUE, D2)[0])
        inside = all(
            p[:, 0].min() > 5 and p[:, 1].min() > 5 and p[:, 0].max() < 634 and p[:, 1].max() < 474
            for p in (a, b)
        )
        if not inside:
            continue
        objs.append(OBJ)
        cl.append(a)
        cr.append(b)
        uvl.append(a + rng.normal(0, noise, a.shape))
        uvr.append(b + rng.normal(0, noise, b.shape))
    return objs, uvl, uvr, cl, cr


def _angle_deg(A: np.ndarray, B: np.ndarray) -> float:
    return float(np.degrees(np.linalg.norm(np.asarray(matrix_to_rvec(A @ B.T)))))


def _dist(d: BrownConrady) -> np.ndarray:
    return np.array(d.coeffs[:5])


@pytest.fixture(scope="module")
def noisy() -> tuple:
    return _rig(0.1)


@pytest.fixture(scope="module")
def joint(noisy: tuple) -> StereoCalibrationResult:
    objs, uvl, uvr, _, _ = noisy
    return stereo_calibrate(objs, uvl, uvr, SIZE, fix=("k3",))


def test_noise_free_rig_is_recovered_exactly() -> None:
    objs, uvl, uvr, _, _ = _rig(0.0, seed=3, n_views=8)
    res = stereo_calibrate(objs, uvl, uvr, SIZE, fix=("k3",))
    assert res.rms < 1e-6
    assert _angle_deg(res.R, R_TRUE) < 1e-6
    np.testing.assert_allclose(res.T, T_TRUE, atol=1e-5)
    np.testing.assert_allclose(res.left.K, K1, atol=1e-5)
    np.testing.assert_allclose(res.right.K, K2, atol=1e-5)
    np.testing.assert_allclose(res.right.distortion.coeffs, D2.coeffs, atol=1e-8)


def test_noisy_rig_within_its_standard_deviations(joint: StereoCalibrationResult) -> None:
    res = joint
    assert 0.12 < res.rms < 0.16  # 0.1 px per coordinate: sqrt(2) * 0.1 less the fit's dof
    drv = np.asarray(matrix_to_rvec(res.R @ R_TRUE.T))
    assert np.all(np.abs(drv) < 4 * res.std_rvec + 1e-9), (drv, res.std_rvec)
    assert np.all(np.abs(res.T - T_TRUE) < 4 * res.std_T), (res.T, res.std_T)
    assert _angle_deg(res.R, R_TRUE) < 0.3
    assert np.linalg.norm(res.T - T_TRUE) / np.linalg.norm(T_TRUE) < 0.005
    assert abs(res.left.K[0, 0] - 810) < 4 * res.left.std["fx"]
    assert abs(res.right.K[1, 1] - 792) < 4 * res.right.std["fy"]
    assert res.left.std["k3"] == 0.0 and "k3" in res.left.fixed
    assert res.per_view_rms.shape == (18, 2)
    # E and F: the epipolar constraint x_r^T F x_l = 0 on ideal (undistorted) pixels
    X = np.array([[10.0, 20.0, 600.0], [-50.0, 30.0, 500.0]])
    xl = (X / X[:, 2:]) @ res.left.K.T
    Xr = X @ res.R.T + res.T
    xr = (Xr / Xr[:, 2:]) @ res.right.K.T
    np.testing.assert_allclose(np.einsum("ni,ij,nj->n", xr, res.F, xl), 0.0, atol=1e-9)
    assert res.baseline == pytest.approx(np.linalg.norm(res.T))


def test_fixed_intrinsics_matches_opencv(noisy: tuple) -> None:
    """Issue 17: R within 0.01 deg and T within 0.1 % of cv2.stereoCalibrate
    (CALIB_FIX_INTRINSIC with the same single-camera results). Measured 3e-7 deg, 3e-8."""
    objs, uvl, uvr, _, _ = noisy
    res = stereo_calibrate(objs, uvl, uvr, SIZE, fix=("k3",), fix_intrinsics=True)
    crit = (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 200, 1e-12)
    rms, *_, R, T, _, _ = cv2.stereoCalibrate(
        [o.astype(np.float32) for o in objs],
        [a.astype(np.float32) for a in uvl],
        [b.astype(np.float32) for b in uvr],
        res.left.K.copy(),
        _dist(res.left.distortion),
        res.right.K.copy(),
        _dist(res.right.distortion),
        SIZE,
        flags=cv2.CALIB_FIX_INTRINSIC,
        criteria=crit,
    )
    assert _angle_deg(res.R, R) < 1e-4
    assert np.linalg.norm(res.T - T.ravel()) / np.linalg.norm(T) < 1e-5
    assert res.rms == pytest.approx(rms, rel=1e-5)
    assert res.fixed_intrinsics and res.left.std["fx"] == 0.0


def test_joint_mode_matches_opencv(noisy: tuple, joint: StereoCalibrationResult) -> None:
    """The free (joint) mode against cv2.stereoCalibrate's own joint mode. Measured 2e-5 deg,
    3e-7 relative, K within 4e-4 px."""
    objs, uvl, uvr, _, _ = noisy
    crit = (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 200, 1e-12)
    rms, Kl, _, Kr, _, R, T, _, _ = cv2.stereoCalibrate(
        [o.astype(np.float32) for o in objs],
        [a.astype(np.float32) for a in uvl],
        [b.astype(np.float32) for b in uvr],
        None,
        None,
        None,
        None,
        SIZE,
        flags=cv2.CALIB_FIX_K3,
        criteria=crit,
    )
    assert _angle_deg(joint.R, R) < 0.01 * 0.1
    assert np.linalg.norm(joint.T - T.ravel()) / np.linalg.norm(T) < 1e-3 * 0.1
    assert joint.rms == pytest.approx(rms, rel=1e-5)
    np.testing.assert_allclose(joint.left.K, Kl, atol=0.01)
    np.testing.assert_allclose(joint.right.K, Kr, atol=0.01)


@pytest.mark.parametrize("alpha", [-1.0, 0.0, 0.5, 1.0])
@pytest.mark.parametrize("zero_disparity", [True, False])
def test_rectify_matches_opencv(alpha: float, zero_disparity: bool) -> None:
    ours = stereo_rectify(
        K1, D1, K2, D2, SIZE, R_TRUE, T_TRUE, alpha=alpha, zero_disparity=zero_disparity
    )
    flags = cv2.CALIB_ZERO_DISPARITY if zero_disparity else 0
    R1, R2, P1, P2, Q, _, _ = cv2.stereoRectify(
        K1, _dist(D1), K2, _dist(D2), SIZE, R_TRUE, T_TRUE.reshape(3, 1), flags=flags, alpha=alpha
    )
    np.testing.assert_allclose(ours.R1, R1, atol=1e-12)
    np.testing.assert_allclose(ours.R2, R2, atol=1e-12)
    # OpenCV undistorts the corners in float32 with 5 iterations: 1e-5 relative
    np.testing.assert_allclose(ours.P1, P1, rtol=1e-5, atol=1e-3)
    np.testing.assert_allclose(ours.P2, P2, rtol=1e-5, atol=1e-3)
    np.testing.assert_allclose(ours.Q, Q, rtol=1e-5, atol=1e-6)
    assert not ours.vertical


@pytest.mark.parametrize("alpha", [-1.0, 0.0, 1.0])
def test_rectify_a_lens_model_folding_before_the_corners(alpha: float) -> None:
    """A fitted distortion that folds back before the image's corners (its Newton inverse is
    NaN there) still rectifies: the image's middle stands for the corners' mean.

    The rig is OpenCV's 320 x 240 stereo sample (imgdata/data2 of github.com/dreameer/
    stereocalibrate) as imageform's stereo-calibrate fits it: the right camera's k3 = -0.42
    makes r (1 + k1 r^2 + k2 r^4 + k3 r^6) fall beyond r of about 0.9, so none of its four
    corners has an undistorted position; the rectification was NaN and ``imageform depth``
    failed with "P contains NaN or inf". OpenCV's five fixed-point steps return numbers there
    anyway: the principal points agree within 5 px.
    """
    Kl = np.array([[177.0612, 0.0, 160.0935], [0.0, 227.9343, 109.3003], [0.0, 0.0, 1.0]])
    Kr = np.array([[178.0914, 0.0, 155.0410], [0.0, 229.2347, 106.6747], [0.0, 0.0, 1.0]])
    Dl = BrownConrady(k1=-0.046305, k2=0.147670, p1=0.0024532, p2=-0.0053017, k3=-0.124595)
    Dr = BrownConrady(k1=-0.069118, k2=0.326607, p1=-0.0009321, p2=-0.0068832, k3=-0.423859)
    R = np.array(
        [
            [0.99975701, -0.00658542, 0.02103705],
            [0.00612258, 0.99973944, 0.02199033],
            [-0.02117638, -0.02185619, 0.99953683],
        ]
    )
    T = np.array([-1.38358437, -0.01609417, 0.08163698])
    corners = np.array([[0.0, 0.0], [319.0, 0.0], [0.0, 239.0], [319.0, 239.0]])
    xy = (corners - Kr[:2, 2]) / np.diag(Kr)[:2]
    assert not Dr.undistort(xy).valid.any()  # the premise: no corner can be undistorted
    ours = stereo_rectify(Kl, Dl, Kr, Dr, (320, 240), R, T, alpha=alpha)
    for m in (ours.P1, ours.P2, ours.Q):
        assert np.all(np.isfinite(m))
    P1 = cv2.stereoRectify(Kl, _dist(Dl), Kr, _dist(Dr), (320, 240), R, T.reshape(3, 1), alpha=-1)[
        2
    ]
    if alpha == -1.0:
        np.testing.assert_allclose(ours.P1[:2, 2], P1[:2, 2], atol=5.0)
        np.testing.assert_allclose(ours.P1[0, 0], P1[0, 0], rtol=1e-9)  # f comes before
    m = rectification_map(Kr, Dr, ours.R2, ours.P2, ours.image_size)
    assert np.isfinite(m).all(axis=-1).mean() > 0.5  # most rectified pixels have a source


def test_rectify_vertical_pair_matches_opencv() -> None:
    T = np.array([1.5, -100.0, 2.0])
    ours = stereo_rectify(K1, D1, K2, D2, SIZE, R_TRUE, T)
    R1, _, _, P2, Q, _, _ = cv2.stereoRectify(
        K1, _dist(D1), K2, _dist(D2), SIZE, R_TRUE, T.reshape(3, 1), alpha=-1
    )
    assert ours.vertical
    np.testing.assert_allclose(ours.R1, R1, atol=1e-12)
    np.testing.assert_allclose(ours.P2, P2, rtol=1e-5, atol=1e-3)
    np.testing.assert_allclose(ours.Q, Q, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("alpha", [-1.0, 0.0, 1.0])
@pytest.mark.parametrize("below", [True, False], ids=["below", "above"])
def test_rectify_vertical_rig_maps_match_opencv(alpha: float, below: bool) -> None:
    """A vertical rig (the second camera 100 mm below or above the first, turned 4.8 deg):
    ``R1, R2, P1, P2, Q`` as ``cv2.stereoRectify``'s and both maps as
    ``cv2.initUndistortRectifyMap``'s on them; the true projections of points seen by both
    land on the same columns, and ``Q`` of their row difference gives the points back."""
    T = np.array([1.5, -100.0 if below else 100.0, 2.0])
    ours = stereo_rectify(K1, D1, K2, D2, SIZE, R_TRUE, T, alpha=alpha)
    R1, R2, P1, P2, Q, _, _ = cv2.stereoRectify(
        K1, _dist(D1), K2, _dist(D2), SIZE, R_TRUE, T.reshape(3, 1), alpha=alpha
    )
    assert ours.vertical
    np.testing.assert_allclose(ours.R1, R1, atol=1e-12)
    np.testing.assert_allclose(ours.R2, R2, atol=1e-12)
    np.testing.assert_allclose(ours.P1, P1, rtol=1e-5, atol=1e-3)
    np.testing.assert_allclose(ours.P2, P2, rtol=1e-5, atol=1e-3)
    np.testing.assert_allclose(ours.Q, Q, rtol=1e-5, atol=1e-6)
    assert ours.P2[0, 3] == 0.0 and (ours.P2[1, 3] < 0) == below  # f T'_y: the baseline in y
    for K, D, Rr, P in ((K1, D1, ours.R1, ours.P1), (K2, D2, ours.R2, ours.P2)):
        m = rectification_map(K, D, Rr, P, SIZE)
        mx, my = cv2.initUndistortRectifyMap(K, _dist(D), Rr, P, SIZE, cv2.CV_32FC1)
        fin = np.isfinite(m).all(axis=-1)
        assert fin.all()
        assert float(np.abs(m[..., 0] - mx).max()) < 1e-3  # OpenCV's float32 maps
        assert float(np.abs(m[..., 1] - my).max()) < 1e-3
    X = np.array([[10.0, 20.0, 600.0], [-80.0, 30.0, 900.0], [60.0, -40.0, 1500.0]])
    uv1 = np.asarray(project_points_distorted(X, K1, np.eye(3), np.zeros(3), D1)[0])
    uv2 = np.asarray(project_points_distorted(X, K2, R_TRUE, T, D2)[0])
    a = _rectified(uv1, K1, D1, ours.R1, ours.P1)
    b = _rectified(uv2, K2, D2, ours.R2, ours.P2)
    assert float(np.abs(a[:, 0] - b[:, 0]).max()) < 1e-6  # shared columns
    assert ((a[:, 1] - b[:, 1] > 0) == below).all()  # d = y_first - y_second
    h = np.stack([a[:, 0], a[:, 1], a[:, 1] - b[:, 1], np.ones(3)], -1) @ ours.Q.T
    np.testing.assert_allclose((h[:, :3] / h[:, 3:]) @ ours.R1, X, rtol=1e-8)


@pytest.mark.parametrize("alpha", [-1.0, 0.0, 1.0])
@pytest.mark.parametrize("T", [T_TRUE, np.array([1.5, -100.0, 2.0])], ids=["horiz", "vert"])
def test_rectify_new_image_size_matches_opencv(alpha: float, T: np.ndarray) -> None:
    """``new_image_size`` (OpenCV's ``newImageSize``): measured within 1e-5 px of OpenCV."""
    ours = stereo_rectify(K1, D1, K2, D2, SIZE, R_TRUE, T, alpha=alpha, new_image_size=(800, 500))
    _, _, P1, P2, Q, _, _ = cv2.stereoRectify(
        K1,
        _dist(D1),
        K2,
        _dist(D2),
        SIZE,
        R_TRUE,
        T.reshape(3, 1),
        alpha=alpha,
        newImageSize=(800, 500),
    )
    assert ours.image_size == (800, 500)
    np.testing.assert_allclose(ours.P1, P1, rtol=1e-6, atol=1e-4)
    np.testing.assert_allclose(ours.P2, P2, rtol=1e-6, atol=1e-4)
    np.testing.assert_allclose(ours.Q, Q, rtol=1e-6, atol=1e-4)


def _rectified(uv: np.ndarray, K: np.ndarray, d: BrownConrady, Rr: np.ndarray, P: np.ndarray):
    y = (uv[:, 1] - K[1, 2]) / K[1, 1]
    x = (uv[:, 0] - K[0, 2]) / K[0, 0]
    xy = np.asarray(d.undistort(np.stack([x, y], -1)).xy)
    X = np.concatenate([xy, np.ones((len(xy), 1))], 1) @ Rr.T
    return (X / X[:, 2:]) @ P[:, :3].T


def test_rectified_rows_are_aligned(noisy: tuple, joint: StereoCalibrationResult) -> None:
    """Issue 17: after rectification with the estimated rig, corresponding points have
    equal rows to 0.1 px (the true projections; measured max 0.05 px, median 0.007 px)."""
    _, _, _, cl, cr = noisy
    rect = joint.rectify()
    a = _rectified(np.concatenate(cl), joint.left.K, joint.left.distortion, rect.R1, rect.P1)
    b = _rectified(np.concatenate(cr), joint.right.K, joint.right.distortion, rect.R2, rect.P2)
    assert float(np.abs(a[:, 1] - b[:, 1]).max()) < 0.1
    # with the true rig the rows agree to rounding
    true = stereo_rectify(K1, D1, K2, D2, SIZE, R_TRUE, T_TRUE)
    a = _rectified(np.concatenate(cl), K1, D1, true.R1, true.P1)
    b = _rectified(np.concatenate(cr), K2, D2, true.R2, true.P2)
    assert float(np.abs(a[:, 1] - b[:, 1]).max()) < 1e-6
    # zero disparity: points at infinity land on the same pixel; Q gives back depth
    X = np.array([[10.0, 20.0, 600.0]])  # in the left camera frame
    pl = _rectified(
        np.asarray(project_points_distorted(X, K1, np.eye(3), np.zeros(3), D1)[0]),
        K1,
        D1,
        true.R1,
        true.P1,
    )
    pr = _rectified(
        np.asarray(project_points_distorted(X, K2, R_TRUE, T_TRUE, D2)[0]),
        K2,
        D2,
        true.R2,
        true.P2,
    )
    h = true.Q @ np.array([pl[0, 0], pl[0, 1], pl[0, 0] - pr[0, 0], 1.0])
    Xr = h[:3] / h[3]  # in the rectified left frame
    np.testing.assert_allclose(true.R1.T @ Xr, X[0], rtol=1e-9)


def test_rectification_map_matches_opencv_and_remaps() -> None:
    rect = stereo_rectify(K1, D1, K2, D2, SIZE, R_TRUE, T_TRUE)
    m = rectification_map(K2, D2, rect.R2, rect.P2, SIZE)
    mx, my = cv2.initUndistortRectifyMap(K2, _dist(D2), rect.R2, rect.P2, SIZE, cv2.CV_32FC1)
    assert m.shape == (480, 640, 2)
    assert float(np.abs(m[..., 0] - mx).max()) < 1e-3  # OpenCV's float32 maps
    assert float(np.abs(m[..., 1] - my).max()) < 1e-3
    img = np.random.default_rng(0).random((480, 640))
    ours = remap_bilinear(img, m, fill=0.0)
    ref = cv2.remap(img.astype(np.float32), mx, my, cv2.INTER_LINEAR, borderValue=0.0)
    inner = (slice(40, 440), slice(60, 580))
    assert float(np.abs(ours[inner] - ref[inner]).max()) < 0.01


def test_given_single_camera_calibrations_are_used(noisy: tuple) -> None:
    from imageform.geometry import calibrate_camera

    objs, uvl, uvr, _, _ = noisy
    left = calibrate_camera(objs[:10], uvl[:10], SIZE, fix=("k3",))
    right = calibrate_camera(objs[:10], uvr[:10], SIZE, fix=("k3",))
    res = stereo_calibrate(
        objs[10:], uvl[10:], uvr[10:], SIZE, left=left, right=right, fix_intrinsics=True
    )
    np.testing.assert_array_equal(res.left.K, left.K)
    assert _angle_deg(res.R, R_TRUE) < 0.5


def test_bad_input() -> None:
    objs, uvl, uvr, _, _ = _rig(0.0, seed=5, n_views=3)
    with pytest.raises(InvalidInputError, match="object-point"):
        stereo_calibrate(objs, uvl, uvr[:2], SIZE)
    with pytest.raises(InvalidInputError, match="image_size"):
        stereo_calibrate(objs, uvl, uvr, (640,))  # type: ignore[arg-type]
    with pytest.raises(DegenerateConfigurationError, match="at least 2 views"):
        stereo_calibrate(objs[:1], uvl[:1], uvr[:1], SIZE)
    with pytest.raises(InvalidInputError, match="CalibrationResult"):
        stereo_calibrate(objs, uvl, uvr, SIZE, left="cam.toml")  # type: ignore[arg-type]
    with pytest.raises(DegenerateConfigurationError, match="baseline"):
        stereo_rectify(K1, None, K2, None, SIZE, np.eye(3), np.zeros(3))
    with pytest.raises(InvalidInputError, match="shape"):
        stereo_rectify(K1, None, K2, None, SIZE, np.eye(2), T_TRUE)
    with pytest.raises(InvalidInputError, match="P of shape"):
        rectification_map(K1, None, np.eye(3), np.eye(2), SIZE)


def test_stereo_camera_file_round_trip(joint: StereoCalibrationResult, tmp_path: Path) -> None:
    from imageform.io import (
        StereoCameraFile,
        read_camera,
        read_stereo_camera,
        write_camera,
        write_stereo_camera,
    )

    sf = StereoCameraFile.from_calibration(joint, command="test")
    p = write_stereo_camera(tmp_path / "rig.toml", sf)
    back = read_stereo_camera(p)
    np.testing.assert_allclose(back.R, joint.R, atol=1e-15)
    np.testing.assert_allclose(back.T, joint.T, rtol=1e-15)
    np.testing.assert_allclose(back.std_rvec, joint.std_rvec, rtol=1e-15)
    np.testing.assert_allclose(back.std_T, joint.std_T, rtol=1e-15)
    np.testing.assert_allclose(back.left.camera.K, joint.left.K, rtol=1e-15)
    assert back.right.camera.distortion == joint.right.distortion
    assert back.provenance.rms_px == pytest.approx(joint.rms)
    assert back.left.std["fx"] == pytest.approx(joint.left.std["fx"])
    # a single-camera file is refused with a hint, and the right camera can be extracted
    single = write_camera(tmp_path / "cam.toml", back.left)
    with pytest.raises(InvalidInputError, match="read_camera"):
        read_stereo_camera(single)
    right = read_camera(write_camera(tmp_path / "right.toml", back.right))
    np.testing.assert_allclose(right.camera.t, joint.T, rtol=1e-15)


def test_stereo_camera_file_errors(tmp_path: Path) -> None:
    from imageform.errors import UnknownOptionError
    from imageform.io import read_stereo_camera

    base = 'format = "imageform-stereo"\nversion = 1\n'
    cam = "[{s}.intrinsics]\nfx = 500\nfy = 500\ncx = 320\ncy = 240\n"
    pose = "[right.pose]\nR = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\nt = [-100, 0, 0]\n"
    cases = [
        (base + cam.format(s="left"), InvalidInputError, "right: missing"),
        (base + cam.format(s="left") + cam.format(s="right"), InvalidInputError, "right.pose"),
        (base.replace("1", "2") + cam.format(s="left"), InvalidInputError, "newer"),
        (base + "colour = 1\n", UnknownOptionError, "colour"),
        (
            base
            + cam.format(s="left")
            + cam.format(s="right").replace("fx = 500", "fx = -1")
            + pose,
            InvalidInputError,
            r"\[right\]: intrinsics.fx",
        ),
    ]
    for i, (text, err, match) in enumerate(cases):
        p = tmp_path / f"bad{i}.toml"
        p.write_text(text)
        with pytest.raises(err, match=match):
            read_stereo_camera(p)
    p = tmp_path / "ok.toml"
    p.write_text(base + cam.format(s="left") + cam.format(s="right") + pose)
    assert read_stereo_camera(p).T.tolist() == [-100.0, 0.0, 0.0]


DOCS = Path(__file__).resolve().parents[2] / "docs"


def test_stereo_files_in_the_docs_are_valid(tmp_path: Path) -> None:
    import re

    from imageform.io import read_stereo_camera

    blocks = [
        b
        for page in sorted(DOCS.glob("*.md"))
        for b in re.findall(r"```toml\n(.*?)```", page.read_text(), re.DOTALL)
        if 'format = "imageform-stereo"' in b
    ]
    assert blocks, "docs/camera-file.md shows a stereo file"
    for i, block in enumerate(blocks):
        path = tmp_path / f"stereo-{i}.toml"
        path.write_text(block)
        sf = read_stereo_camera(path)
        assert sf.left.camera.image_size == (640, 480) and sf.T[0] < 0
