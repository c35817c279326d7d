"""Camera files through the command line, no hand edits: what one command writes, the next
reads, every field honoured.

- calibrate -> undistort -> vanishing, and calibrate -> pose -> triangulate on OpenCV's
  chessboard views (../shared/data/opencv-left);
- project with a calibrated file equals cv2.projectPoints with the same K and coefficients
  (a labelled cross-check, to 1e-9 px);
- calibrate on boards rendered through a known camera recovers the truth camera file field
  by field;
- vanishing on a distorted render honours the file's distortion and pose.
"""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from imageform.cli import main
from imageform.geometry import (
    BrownConrady,
    Camera,
    camera_rotation,
    checkerboard_points,
    horizon_line,
    remap_bilinear,
    rvec_to_matrix,
)
from imageform.geometry.checkerboard import find_checkerboard
from imageform.io import read_camera, read_image, write_camera, write_image

cv2 = pytest.importorskip("cv2")

VIEWS = [f"left{i:02d}.jpg" for i in (1, 2, 3, 4, 5, 6, 7, 8, 9, 11, 12, 13, 14)]


def _cli(*args: str) -> dict[str, Any]:
    """Run ``imageform ARGS --json``; its JSON result (exit code 0 asserted)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([*args, "--json"])
    assert code == 0, err.getvalue()
    return json.loads(out.getvalue())  # type: ignore[no-any-return]


@pytest.fixture(scope="module")
def calibrated(shared_data: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``imageform calibrate`` on the 13 views: cam.toml and corners.csv in a folder."""
    folder = tmp_path_factory.mktemp("calibrated")
    images = [str(shared_data / "opencv-left" / v) for v in VIEWS]
    _cli("calibrate", *images, "--board", "9x6", "--square", "25mm",
         "-o", str(folder / "cam.toml"), "--corners", str(folder / "corners.csv"))  # fmt: skip
    return folder


def _bend(image: np.ndarray) -> float:
    """Largest distance (px) of a board corner from the straight line of its row or column."""
    c = find_checkerboard(image[..., 0], (9, 6)).corners
    assert c is not None
    grid = c.reshape(6, 9, 2)
    worst = 0.0
    for line in [*grid, *grid.transpose(1, 0, 2)]:
        m = line - line.mean(0)
        normal = np.linalg.svd(m)[2][1]
        worst = max(worst, float(np.abs(m @ normal).max()))
    return worst


def test_calibrate_undistort_vanishing(calibrated: Path, shared_data: Path) -> None:
    src = shared_data / "opencv-left" / "left01.jpg"
    und, und_cam = calibrated / "und.png", calibrated / "und.toml"
    s = _cli("undistort", str(src), "-o", str(und), "--camera", str(calibrated / "cam.toml"),
             "--camera-out", str(und_cam))  # fmt: skip
    assert s["model"] == "brown_conrady" and len(s["coefficients"]) == 8
    # the calibrated distortion is removed: the board's rows and columns become straight
    assert _bend(read_image(src)) > 1.0
    assert _bend(read_image(und)) < 0.35
    flat = read_camera(und_cam)
    cal = read_camera(calibrated / "cam.toml")
    assert flat.camera.distortion is None and flat.provenance.based_on == "cam.toml"
    np.testing.assert_array_equal(np.asarray(flat.camera.K), np.asarray(cal.camera.K))
    # vanishing on the undistorted image with its camera, and on the original image with the
    # calibrated camera (undistorted inside): the file's K is used, the same directions found.
    # On left13, whose board fills the view: in left01 the board's vertical edges compete
    # with the room's verticals and the monitor's lines (three real directions), and which
    # of them RANSAC's candidates take depends on the seed in both paths alike
    src13, und13, cam13 = src.with_name("left13.jpg"), calibrated / "und13.png", und_cam
    _cli("undistort", str(src13), "-o", str(und13), "--camera", str(calibrated / "cam.toml"),
         "--camera-out", str(cam13), "--force")  # fmt: skip
    a = _cli("vanishing", str(und13), "--camera", str(cam13))
    b = _cli("vanishing", str(src13), "--camera", str(calibrated / "cam.toml"))
    K = np.asarray(cal.camera.K)
    for p in (a, b):
        np.testing.assert_array_equal(np.asarray(p["K"]), K)
        assert p["K_source"] == "camera file" and p["vertical_index"] is not None
    da = np.linalg.solve(K, np.asarray(a["vanishing_points"]).T).T
    db = np.linalg.solve(K, np.asarray(b["vanishing_points"]).T).T
    # the two strongest directions (the board's two families of lines) agree within 0.3 deg
    for i in range(2):
        cos = abs(da[i] @ db[i]) / np.linalg.norm(da[i]) / np.linalg.norm(db[i])
        assert np.degrees(np.arccos(min(1.0, cos))) < 0.3


def test_calibrate_pose_triangulate(calibrated: Path) -> None:
    """Poses of two views from the calibrated camera and the detected corners, then the
    corners triangulated back: the board points, within 0.3 mm (25 mm squares)."""
    cam, corners = calibrated / "cam.toml", calibrated / "corners.csv"
    poses = []
    for view in ("left01.jpg", "left02.jpg"):
        out = calibrated / view.replace(".jpg", ".toml")
        s = _cli("pose", str(cam), str(corners), "--view", view, "-o", str(out))
        assert s["inliers"] == 54 and s["rms_px"] < 0.3
        posed = read_camera(out)
        assert posed.has_pose and posed.provenance.images == (view,)
        assert posed.camera.distortion == read_camera(cam).camera.distortion
        poses.append(str(out))
    xyz = calibrated / "X.csv"
    rms = read_camera(calibrated / "cam.toml").provenance.rms_px  # the corners' noise
    s = _cli("triangulate", str(corners), *poses, "--views", "left01.jpg,left02.jpg",
             "--sigma", str(rms), "-o", str(xyz))  # fmt: skip
    assert s["points"] == 54 and s["valid"] == 54
    got = np.loadtxt(xyz, delimiter=",", skiprows=1)
    board = checkerboard_points((9, 6), 25.0)
    err = np.linalg.norm(got[:, :3] - board, axis=1)
    assert np.sqrt(np.mean(err**2)) < 0.3 and err.max() < 1.0
    # with --sigma the corners' RMS, the standard deviations are of the size of the errors
    sd = np.linalg.norm(got[:, 3:6], axis=1)
    assert 0.2 < np.median(err) / np.median(sd) < 5


@pytest.mark.parametrize("n", [500, 30_000])  # 30 000: the fused numba kernel
def test_project_with_calibrated_file_equals_cv2(calibrated: Path, n: int) -> None:
    """``project --camera`` applies the calibrated distortion (and a pose): the same pixels
    as cv2.projectPoints with the file's K and (k1, k2, p1, p2, k3), to 1e-9 px."""
    cal = read_camera(calibrated / "cam.toml")
    K = np.asarray(cal.camera.K)
    dist = np.asarray(cal.camera.distortion.coeffs[:5])
    rvec, t = np.array([0.1, -0.2, 0.05]), np.array([-20.0, 15.0, 400.0])
    posed = write_camera(
        calibrated / f"posed{n}.toml",
        Camera(K, rvec_to_matrix(rvec), t, cal.camera.image_size, distortion=cal.camera.distortion),
        has_pose=True,
    )
    rng = np.random.default_rng(n)
    for file, rv, tv in ((calibrated / "cam.toml", np.zeros(3), np.zeros(3)), (posed, rvec, t)):
        R = np.asarray(rvec_to_matrix(rv))
        cam_pts = np.column_stack([rng.uniform(-0.45, 0.45, (n, 2)), np.ones(n)])
        cam_pts *= rng.uniform(200.0, 800.0, (n, 1))
        X = (cam_pts - tv) @ R  # world points that lie in front, inside the field of view
        pts, out = calibrated / "X.csv", calibrated / f"uv{n}.csv"
        np.savetxt(pts, X, delimiter=",", header="X,Y,Z", comments="", fmt="%.17g")
        s = _cli("project", str(pts), "--camera", str(file), "-o", str(out), "--force")
        assert s["valid"] == n and s["distortion"] == "brown_conrady"
        got = np.loadtxt(out, delimiter=",", skiprows=1)
        want = cv2.projectPoints(X, rv, tv, K, dist)[0][:, 0, :]
        assert np.abs(got[:, :2] - want).max() < 1e-9
        assert got[:, 2].all()


# ---------------------------------------------------------------- rendered truth

TRUTH_K = np.array([[620.0, 0.0, 322.5], [0.0, 615.0, 236.8], [0.0, 0.0, 1.0]])
TRUTH_D = BrownConrady(-0.18, 0.06, 5e-4, -3e-4, 0.0)
BOARD_VIEWS = [
    ([0.35, 0.0, 0.0], [0, 0, 480]),
    ([-0.35, 0.1, 0.05], [40, -30, 470]),
    ([0.0, 0.4, -0.1], [-60, 40, 500]),
    ([0.1, -0.4, 0.1], [70, 50, 520]),
    ([0.3, 0.3, 0.2], [-90, -60, 560]),
    ([-0.3, -0.3, -0.2], [90, 60, 560]),
    ([0.2, -0.2, 0.4], [-100, 70, 600]),
    ([-0.2, 0.25, -0.3], [100, -70, 600]),
]


def test_calibrate_rendered_views_recovers_the_truth_camera_file(tmp_path: Path) -> None:
    """Boards rendered through a known camera (distortion included), written as a camera
    file as the simulator writes its truth; ``imageform calibrate`` on the renders gives a
    camera file that agrees field by field: the same image size and model, each parameter
    within 3 of its standard deviations (+ a small floor), the same pixel for every ray within
    0.5 px."""
    from tests.geometry.checkerboard_support import render_board_through

    cols, rows, square = 8, 6, 30.0
    truth = write_camera(
        tmp_path / "truth.toml", Camera(TRUTH_K, image_size=(640, 480), distortion=TRUTH_D)
    )
    centre = np.array([cols - 1, rows - 1, 0.0]) * square / 2
    files = []
    for i, (rv, offset) in enumerate(BOARD_VIEWS):
        R = np.asarray(rvec_to_matrix(rv))
        cam = Camera(TRUTH_K, R, -R @ centre + offset, (640, 480), distortion=TRUTH_D)
        path = tmp_path / f"view{i}.png"
        write_image(path, np.clip(render_board_through(cam, cols, rows, square), 0.0, 1.0))
        files.append(str(path))
    _cli("calibrate", *files, "--board", f"{cols}x{rows}", "--square", "30mm",
         "-o", str(tmp_path / "cal.toml"))  # fmt: skip
    want, got = read_camera(truth), read_camera(tmp_path / "cal.toml")
    assert got.camera.image_size == want.camera.image_size == (640, 480)
    assert got.distortion_model == want.distortion_model == "brown_conrady"
    assert got.camera.image_plane == want.camera.image_plane and not got.has_pose
    Kg, Kw = np.asarray(got.camera.K), np.asarray(want.camera.K)
    fields = {"fx": (0, 0), "fy": (1, 1), "cx": (0, 2), "cy": (1, 2)}
    for name, ij in fields.items():
        assert abs(Kg[ij] - Kw[ij]) < 3 * got.std[name] + 0.05, name
    assert Kg[0, 1] == Kw[0, 1] == 0.0 and got.std["skew"] == 0.0  # fixed, as documented
    for name, g, w in zip(("k1", "k2", "p1", "p2", "k3"), got.camera.distortion.coeffs,
                          want.camera.distortion.coeffs, strict=False):  # fmt: skip
        assert abs(g - w) < 3 * got.std[name] + 1e-4, name
    # the camera as a whole: each true ray lands on the same pixel within 0.5 px wherever the
    # boards were seen (the central 80 % of the image; the extreme corners are extrapolation)
    vv, uu = np.mgrid[48:432:8, 64:576:8].astype(float)
    xy = np.asarray(want.camera.undistort_pixels(np.stack([uu, vv], -1)))
    rays = np.concatenate([xy, np.ones((*xy.shape[:-1], 1))], -1).reshape(-1, 3)
    uv = np.asarray(got.camera.project(rays).uv).reshape(xy.shape)
    assert np.hypot(uv[..., 0] - uu, uv[..., 1] - vv).max() < 0.5
    assert got.provenance.views_used == len(BOARD_VIEWS) and got.provenance.rms_px < 0.05


def test_vanishing_honours_distortion_and_pose(tmp_path: Path) -> None:
    """A Manhattan render distorted by a Brown-Conrady lens: with the full camera file the
    horizon is found within 1 px of the truth, the three directions are orthogonal within
    0.2 deg and each is matched to its world axis through the pose; the same file without
    its distortion puts the horizon tens of pixels off."""
    from tests.geometry.scene_render import render_manhattan

    K = np.array([[700.0, 0.0, 383.5], [0.0, 700.0, 255.5], [0.0, 0.0, 1.0]])
    R = np.asarray(camera_rotation(0.25, 0.5, 0.03))
    ideal = render_manhattan(K, R, np.zeros(3), seed=3)
    lens = Camera(K, R, np.zeros(3), (768, 512), distortion=BrownConrady(k1=-0.3, k2=0.08))
    vv, uu = np.mgrid[0:512, 0:768].astype(float)
    xy = np.asarray(lens.undistort_pixels(np.stack([uu, vv], -1)))
    distorted = np.asarray(remap_bilinear(ideal, xy @ K[:2, :2].T + K[:2, 2], fill=40 / 255))
    img = tmp_path / "distorted.png"
    write_image(img, np.clip(distorted, 0.0, 1.0))
    full = write_camera(tmp_path / "full.toml", lens, has_pose=True)
    pinhole = write_camera(tmp_path / "pinhole.toml", Camera(K, image_size=(768, 512)))
    truth = np.asarray(horizon_line(K, R))

    def horizon_error(p: dict[str, Any]) -> float:
        a, b, c = p["horizon"]
        rows = [(-(a * u + c) / b, -(truth[0] * u + truth[2]) / truth[1]) for u in (0, 767)]
        return max(abs(x - y) for x, y in rows)

    p = _cli("vanishing", str(img), "--camera", str(full), "-o", str(tmp_path / "ov.png"))
    assert horizon_error(p) < 1.5  # measured 1.05 px with LSD segments (0.46 with "simple")
    assert all(abs(a["angle"] - 90.0) < 0.2 for a in p["vp_angles_deg"])
    assert sorted(a["axis"] for a in p["world_axes"]) == ["x", "y", "z"]
    assert all(a["angle_deg"] < 0.2 for a in p["world_axes"])
    assert abs(p["focal_error_px"]) < 5 and p["principal_point_error_px"] < 5
    assert read_image(tmp_path / "ov.png").shape == (512, 768, 3)
    q = _cli("vanishing", str(img), "--camera", str(pinhole))
    assert horizon_error(q) > 20.0
    # the camera file's principal point for the estimated K: the focal length alone is fitted
    c = _cli("vanishing", str(img), "--camera", str(full), "--principal-point", "camera")
    assert c["principal_point_error_px"] == pytest.approx(0.0, abs=1e-9)
    assert abs(c["focal_error_px"]) < 5
    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        assert main(["vanishing", str(img), "--principal-point", "camera"]) == 1
    assert "--principal-point camera needs --camera" in err.getvalue()


def test_vanishing_says_why_there_is_no_focal_length(tmp_path: Path) -> None:
    """A one-point-perspective render (the camera looks along a scene axis): three points,
    the horizon, and a line saying why K is not given (it said nothing)."""
    from tests.geometry.scene_render import render_manhattan

    K = np.array([[700.0, 0.0, 383.5], [0.0, 700.0, 255.5], [0.0, 0.0, 1.0]])
    img = tmp_path / "hall.png"
    write_image(img, render_manhattan(K, np.eye(3), np.zeros(3), seed=3))
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["vanishing", str(img)]) == 0
    text = out.getvalue()
    assert "3 vanishing points" in text and "horizon:" in text
    assert "K: not determined: fewer than two of the points are finite" in text
