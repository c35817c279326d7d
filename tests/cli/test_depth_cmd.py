"""``imageform depth``: a stereo pair and its stereo camera file to depth, disparity, points.

The rig file is written as ``imageform stereo-calibrate`` writes it
(``StereoCameraFile.from_calibration`` of a ``stereo_calibrate`` result, on exact
projections of a board seen by the rendered pair's two cameras); the pair is the ray-cast
scene of ``tests/stereo_scenes.py`` with known depth. The rendered-and-calibrated chain
(distortion, a rotated rig) is in ``tests/geometry/test_stereo_simulated.py``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from imageform.cli import main
from imageform.geometry import (
    checkerboard_points,
    project_points_distorted,
    rvec_to_matrix,
    stereo_calibrate,
)
from imageform.io import (
    StereoCameraFile,
    read_image,
    read_stereo_camera,
    write_camera,
    write_image,
    write_stereo_camera,
)
from imageform.workflows._ply import read_points_ply

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from stereo_scenes import StereoScene, render_pair

W, H = 320, 240


def _rig(
    scene: StereoScene, R: np.ndarray | None = None, T: np.ndarray | None = None
) -> StereoCameraFile:
    """The pair's rig calibrated from exact board projections (stereo-calibrate's file)."""
    K = np.array([[scene.f, 0, (W - 1) / 2], [0, scene.f, (H - 1) / 2], [0, 0, 1]])
    R = np.eye(3) if R is None else R
    T = np.array([-scene.baseline, 0.0, 0.0]) if T is None else T
    obj = checkerboard_points((9, 6), 60.0)
    views = [
        ([0.3, 0.1, 0], [-240, -150, 700]),
        ([-0.2, 0.3, 0.1], [-220, -160, 760]),
        ([0.1, -0.35, -0.1], [-260, -120, 720]),
        ([0.2, 0.2, 0.3], [-200, -180, 740]),
    ]
    uvl, uvr = [], []
    for r, t in views:
        Rk = np.asarray(rvec_to_matrix(r))
        uvl.append(project_points_distorted(obj, K, Rk, t, None)[0])
        uvr.append(project_points_distorted(obj, K, R @ Rk, R @ np.asarray(t) + T, None)[0])
    res = stereo_calibrate([obj] * 4, uvl, uvr, (W, H), fix=("k1", "k2", "p1", "p2", "k3"))
    return StereoCameraFile.from_calibration(res, command="imageform stereo-calibrate")


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, StereoScene]:
    scene = render_pair(W, H)
    d = tmp_path_factory.mktemp("depth")
    write_stereo_camera(d / "rig.toml", _rig(scene))
    write_image(d / "left.png", (scene.left * 255).round().astype(np.uint8))
    write_image(d / "right.png", (scene.right * 255).round().astype(np.uint8))
    return d, scene


def _line(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


def test_depth_disparity_and_points(
    files: tuple[Path, StereoScene], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    d, scene = files
    rig = read_stereo_camera(d / "rig.toml")
    assert abs(np.linalg.norm(rig.T) - scene.baseline) < 1e-6
    base = ["depth", str(d / "left.png"), str(d / "right.png"), "--camera", str(d / "rig.toml")]
    base += ["--num-disparities", "48"]
    out, ply = tmp_path / "z.tiff", tmp_path / "cloud.ply"
    assert main([*base, "-o", str(out), "--points", str(ply), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    z = np.asarray(read_image(out))[..., 0]
    assert z.dtype == np.float32 and z.shape == (H, W)
    ok = scene.visible & np.isfinite(z)
    assert ok.mean() > 0.75  # measured 83 % of all pixels
    rel = np.abs(z - scene.depth)[ok] / scene.depth[ok]
    assert np.median(rel) < 0.01 and np.mean(rel < 0.05) > 0.98  # measured 0.55 % median, 99.8 %
    assert summary["valid_fraction"] == pytest.approx(np.isfinite(z).mean())
    assert summary["vertical"] is False
    assert summary["n_points"] == int(np.isfinite(z).sum())
    cloud = read_points_ply(ply)
    assert set(cloud) == {"x", "y", "z", "red", "green", "blue"}
    assert cloud["z"].size == summary["n_points"]
    np.testing.assert_allclose(np.sort(cloud["z"]), np.sort(z[np.isfinite(z)]), rtol=1e-5)
    # --disparity: f B / Z
    dout = tmp_path / "d.npy"
    assert main([*base, "--disparity", "-o", str(dout)]) == 0
    disp = np.load(dout)
    fin = np.isfinite(disp)
    np.testing.assert_array_equal(fin, np.isfinite(z))
    np.testing.assert_allclose(disp[fin] * z[fin], scene.f * scene.baseline, rtol=1e-3)


def test_depth_subpixel_and_median_options(files: tuple[Path, StereoScene], tmp_path: Path) -> None:
    """--subpixel and --median-filter reach stereo_disparity: the parabola moves the
    sub-pixel values (by less than a pixel), the median fills holes, an unknown fit exits 2,
    and the choices are the library's."""
    from typing import get_args

    from imageform.geometry.stereo_matching import SUBPIXEL_FITS
    from imageform.workflows.stereo import Subpixel

    assert get_args(Subpixel) == SUBPIXEL_FITS
    d, _ = files
    base = ["depth", str(d / "left.png"), str(d / "right.png"), "--camera", str(d / "rig.toml")]
    base += ["--num-disparities", "48", "--disparity"]
    maps = {}
    for extra in ([], ["--subpixel", "parabola"], ["--median-filter"]):
        out = tmp_path / f"d{len(maps)}.npy"
        assert main([*base, *extra, "-o", str(out)]) == 0
        maps[" ".join(extra)] = np.load(out)
    plain, parabola, median = maps[""], maps["--subpixel parabola"], maps["--median-filter"]
    both = np.isfinite(plain) & np.isfinite(parabola)
    assert 0 < np.abs(plain[both] - parabola[both]).max() < 1.0  # the fits differ below 1 px
    assert np.isfinite(median).sum() >= np.isfinite(plain).sum()  # the median fills holes
    assert main([*base, "--subpixel", "cubic", "-o", str(tmp_path / "x.npy")]) == 2


def test_depth_census_threshold_option(files: tuple[Path, StereoScene], tmp_path: Path) -> None:
    """--census-threshold reaches stereo_disparity: the map is the function's on the same
    rectified pair with that threshold (it differs from the plain census's), 0 is the
    default, and a negative threshold exits 2."""
    d, _ = files
    base = ["depth", str(d / "left.png"), str(d / "right.png"), "--camera", str(d / "rig.toml")]
    base += ["--num-disparities", "48", "--disparity"]
    maps = []
    for extra in ([], ["--census-threshold", "0"], ["--census-threshold", "3"]):
        out = tmp_path / f"c{len(maps)}.npy"
        assert main([*base, *extra, "-o", str(out)]) == 0
        maps.append(np.load(out))
    np.testing.assert_array_equal(maps[0], maps[1])
    assert not np.array_equal(maps[0], maps[2], equal_nan=True)
    both = np.isfinite(maps[0]) & np.isfinite(maps[2])
    assert both.mean() > 0.5 and np.median(np.abs(maps[0][both] - maps[2][both])) < 0.1
    assert main([*base, "--census-threshold", "-1", "-o", str(tmp_path / "x.npy")]) == 2


def test_depth_census_step_option(files: tuple[Path, StereoScene], tmp_path: Path) -> None:
    """--census-step reaches stereo_disparity: 4 is the default (the graded census), 0 the
    plain census (stereo_disparity's census_step=None, the same map), and -1 exits 2."""
    d, _ = files
    base = ["depth", str(d / "left.png"), str(d / "right.png"), "--camera", str(d / "rig.toml")]
    base += ["--num-disparities", "48", "--disparity"]
    maps = []
    for extra in ([], ["--census-step", "4"], ["--census-step", "0"]):
        out = tmp_path / f"s{len(maps)}.npy"
        assert main([*base, *extra, "-o", str(out)]) == 0
        maps.append(np.load(out))
    np.testing.assert_array_equal(maps[0], maps[1])
    assert not np.array_equal(maps[0], maps[2], equal_nan=True)
    assert main([*base, "--census-step", "-1", "-o", str(tmp_path / "x.npy")]) == 2


def test_depth_plane_fill_option(files: tuple[Path, StereoScene], tmp_path: Path) -> None:
    """--plane-fill is the default and reaches stereo_disparity; --no-plane-fill gives the
    function's map with plane_fill=False (the same or, where a flat region took a plane,
    different values)."""
    d, _ = files
    base = ["depth", str(d / "left.png"), str(d / "right.png"), "--camera", str(d / "rig.toml")]
    base += ["--num-disparities", "48", "--disparity"]
    maps = []
    for extra in ([], ["--plane-fill"], ["--no-plane-fill"]):
        out = tmp_path / f"p{len(maps)}.npy"
        assert main([*base, *extra, "-o", str(out)]) == 0
        maps.append(np.load(out))
    np.testing.assert_array_equal(maps[0], maps[1])
    assert maps[2].shape == maps[0].shape
    assert main([*base, "--plane-fill=3", "-o", str(tmp_path / "x.npy")]) == 2


def test_depth_slant_prior_option(files: tuple[Path, StereoScene], tmp_path: Path) -> None:
    """--slant-prior reaches stereo_disparity (off by default): a different map on the
    rendered pair's slanted plane; it takes no value (exit 2)."""
    d, _ = files
    base = ["depth", str(d / "left.png"), str(d / "right.png"), "--camera", str(d / "rig.toml")]
    base += ["--num-disparities", "48", "--disparity"]
    maps = []
    for extra in ([], ["--slant-prior"]):
        out = tmp_path / f"s{len(maps)}.npy"
        assert main([*base, *extra, "-o", str(out)]) == 0
        maps.append(np.load(out))
    assert not np.array_equal(maps[0], maps[1], equal_nan=True)
    assert main([*base, "--slant-prior=3", "-o", str(tmp_path / "x.npy")]) == 2


def test_depth_cost_window_option(
    files: tuple[Path, StereoScene], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """--cost-window reaches stereo_disparity: 3 is the default, 1 each pixel's cost alone (a
    different map); a block too large is a usage error (exit 2), an even one refused (as an
    even --block-size), each in one line."""
    d, _ = files
    base = ["depth", str(d / "left.png"), str(d / "right.png"), "--camera", str(d / "rig.toml")]
    base += ["--num-disparities", "48", "--disparity"]
    maps = []
    for extra in ([], ["--cost-window", "3"], ["--cost-window", "1"]):
        out = tmp_path / f"w{len(maps)}.npy"
        assert main([*base, *extra, "-o", str(out)]) == 0
        maps.append(np.load(out))
    np.testing.assert_array_equal(maps[0], maps[1])
    assert not np.array_equal(maps[0], maps[2], equal_nan=True)
    for bad, code in (("2", 1), ("9", 2)):
        capsys.readouterr()
        assert main([*base, "--cost-window", bad, "-o", str(tmp_path / "x.npy")]) == code
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "cost_window" in err[0].replace("-", "_"), err


#: the vertical rig: the right camera 60 mm below the left (or above: y negated), turned 2 deg
R_VERT = np.asarray(rvec_to_matrix([0.02, 0.01, -0.03]))
T_VERT = np.array([1.5, -60.0, 2.0])


def _vertical_pair(
    d: Path, scene: StereoScene, below: bool, rig: Path | None = None
) -> tuple[list[str], np.ndarray, np.ndarray]:
    """A vertical rig rendered by the ray-cast scene, its file as stereo-calibrate writes it
    (or ``rig``, a file of the same rig), and the true depth of the rectified left pixels:
    (the command's arguments, the true depth, the true disparity)."""
    from stereo_scenes import hit_points, render_view

    from imageform.geometry import stereo_rectify

    K = np.array([[scene.f, 0, (W - 1) / 2], [0, scene.f, (H - 1) / 2], [0, 0, 1]])
    R = R_VERT
    T = T_VERT * (1, 1 if below else -1, 1)
    if rig is None:
        rig = d / "rig.toml"
        write_stereo_camera(rig, _rig(scene, R, T))
    for name, Rc, tc in (("top", np.eye(3), np.zeros(3)), ("bottom", R, T)):
        img = render_view(K, None, Rc, tc, (W, H), ss=2)
        write_image(d / f"{name}.png", (img * 255).round().astype(np.uint8))
    rect = stereo_rectify(K, None, K, None, (W, H), R, T)
    assert rect.vertical
    v, u = np.mgrid[0:H, 0:W].astype(np.float64)
    rays = np.stack([u, v, np.ones_like(u)], -1) @ np.linalg.inv(rect.P1[:, :3]).T @ rect.R1
    z = (hit_points(np.zeros(3), rays) @ rect.R1.T)[..., 2]
    args = [str(d / "top.png"), str(d / "bottom.png"), "--camera", str(rig)]
    return args, z, rect.P1[0, 0] * np.linalg.norm(T) / z


def _board_view(
    K: np.ndarray, R: np.ndarray, t: np.ndarray, board: tuple[int, int] = (9, 6),
    square: float = 25.0, ss: int = 2,
) -> np.ndarray:  # fmt: skip
    """8-bit view of a checkerboard (a white margin of one square) by a pinhole camera
    ``X_cam = R X_board + t``, ``ss x ss`` rays a pixel; the board's inner corners are
    ``checkerboard_points(board, square)``."""
    v, u = np.mgrid[0:H, 0:W].astype(float)
    o = -R.T @ t
    acc = np.zeros((H, W))
    cols, rows = board
    for dy in (np.arange(ss) + 0.5) / ss - 0.5:
        for dx in (np.arange(ss) + 0.5) / ss - 0.5:
            x, y = (u + dx - K[0, 2]) / K[0, 0], (v + dy - K[1, 2]) / K[1, 1]
            r = np.stack([x, y, np.ones_like(u)], -1) @ R  # Rᵀ (x, y, 1) per pixel
            lam = -o[2] / r[..., 2]
            P = o + lam[..., None] * r
            bx, by = P[..., 0] / square, P[..., 1] / square
            inside = (bx > -1) & (bx < cols) & (by > -1) & (by < rows)
            margin = (bx > -2) & (bx < cols + 1) & (by > -2) & (by < rows + 1)
            val = np.where((np.floor(bx) + np.floor(by)) % 2 == 0, 0.1, 0.9)
            acc += np.where(lam > 0, np.where(inside, val, np.where(margin, 0.9, 0.45)), 0.05)
    return np.round(255 * acc / ss**2).astype(np.uint8)


def test_stereo_calibrate_skips_unreadable_files_then_depth(
    files: tuple[Path, StereoScene], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``stereo-calibrate`` on folders (or quoted glob patterns) holding files that cannot be
    read (an empty .png, as OpenCV's stereo sample data3 of github.com/dreameer/stereocalibrate
    holds empty .jpg files; one that is no image): each pair with one is left out with one
    note naming both files, the rig comes from the others, and ``depth`` reads the file it
    wrote (the vertical rig of the boards, rendered; depth against the truth). A file named
    that cannot be read is still an error, and so are too few readable pairs."""
    _, scene = files
    K = np.array([[scene.f, 0, (W - 1) / 2], [0, scene.f, (H - 1) / 2], [0, 0, 1]])
    top, bottom = tmp_path / "top", tmp_path / "bottom"
    top.mkdir()
    bottom.mkdir()
    rng = np.random.default_rng(1)
    center = np.array([4 * 25.0, 2.5 * 25.0, 0.0])
    for k in range(8):
        Rk = np.asarray(rvec_to_matrix(rng.uniform(-0.35, 0.35, 3) * (1, 1, 0.6)))
        tk = np.array([rng.uniform(-15, 15), 30 + rng.uniform(-10, 10), 620]) - Rk @ center
        write_image(top / f"view{k}.png", _board_view(K, Rk, tk))
        write_image(bottom / f"view{k}.png", _board_view(K, R_VERT @ Rk, R_VERT @ tk + T_VERT))
    (top / "view3.png").write_bytes(b"")  # its pair partner bottom/view3.png is fine
    (bottom / "view6.png").write_bytes(b"not an image")
    for side in (top, bottom):  # a pair of two empty files, as data3's
        (side / "view7.png").write_bytes(b"")
    rig = tmp_path / "rig.toml"
    argv = ["stereo-calibrate", str(top), str(bottom), "--board", "9x6", "--square", "25mm"]
    argv += [a for c in ("k1", "k2", "p1", "p2", "k3") for a in ("--fix", c)]  # a pinhole
    assert main([*argv, "-o", str(rig), "--json"]) == 0
    captured = capsys.readouterr()
    summary = json.loads(captured.out)
    assert summary["pairs_used"] == 5 and summary["pairs_total"] == 8
    # (the other notes: the views span little of the frame, true of these synthetic ones)
    err = [e for e in captured.err.strip().splitlines() if " be read (" in e]
    assert len(err) == 3, captured.err
    assert err[0] == (
        f"imageform: warning: {top / 'view3.png'}: skipped with its pair "
        f"{bottom / 'view3.png'}, cannot be read (an empty file)"
    )
    assert err[1].startswith(
        f"imageform: warning: {bottom / 'view6.png'}: skipped with its pair {top / 'view6.png'}"
    )
    assert err[2] == (
        f"imageform: warning: {top / 'view7.png'} and its pair {bottom / 'view7.png'}: skipped, "
        "neither can be read (an empty file)"
    )
    sf = read_stereo_camera(rig)
    assert "view3.png" not in sf.left.provenance.images and len(sf.left.provenance.images) == 5
    assert np.linalg.norm(sf.T - T_VERT) < 0.02 * 60  # measured 0.50 mm (0.8 %)
    # the same files by quoted glob patterns: the same notes, the same rig
    globs = ["stereo-calibrate", str(top / "*.png"), str(bottom / "view*.png"), *argv[3:]]
    assert main([*globs, "-o", str(tmp_path / "g.toml")]) == 0
    assert capsys.readouterr().err.count(" be read (") == 3
    np.testing.assert_array_equal(read_stereo_camera(tmp_path / "g.toml").T, sf.T)
    # depth with the file written: the vertical rig matched along columns
    args, z_true, _ = _vertical_pair(tmp_path, scene, below=True, rig=rig)
    out = tmp_path / "z.tiff"
    assert main(["depth", *args, "--num-disparities", "48", "-o", str(out)]) == 0
    capsys.readouterr()
    z = np.asarray(read_image(out))[..., 0]
    ok = np.isfinite(z) & np.isfinite(z_true)
    rel = np.abs(z - z_true)[ok] / z_true[ok]
    # measured: 78.6 % valid, median error 0.53 %, 99.5 % within 5 %
    assert ok.mean() > 0.7 and np.median(rel) < 0.01 and np.mean(rel < 0.05) > 0.98
    # a file named that cannot be read: an error, one line, nothing written
    named = ["stereo-calibrate", str(top / "view3.png"), str(bottom / "view3.png"), *argv[3:]]
    assert main([*named, "-o", str(tmp_path / "n.toml")]) == 1
    line = _line(capsys)
    assert line.startswith(f"imageform: error: cannot read {top / 'view3.png'}")
    # too few readable pairs left: one line saying so
    few_t, few_b = tmp_path / "few_top", tmp_path / "few_bottom"
    few_t.mkdir()
    few_b.mkdir()
    for k in (0, 1, 3):
        (few_t / f"view{k}.png").write_bytes((top / f"view{k}.png").read_bytes())
        (few_b / f"view{k}.png").write_bytes((bottom / f"view{k}.png").read_bytes())
    few = ["stereo-calibrate", str(few_t), str(few_b), *argv[3:], "-o", str(tmp_path / "f.toml")]
    assert main(few) == 1
    line = _line(capsys)
    assert "2 of the 3 pairs can be read" in line and "needs at least 3" in line, line
    assert not (tmp_path / "f.toml").exists() and not (tmp_path / "n.toml").exists()


def test_depth_of_a_vertical_rig(
    files: tuple[Path, StereoScene], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Cameras stacked vertically (a stereo endoscope held sideways, a phone in portrait):
    rectified to shared columns and matched along them; the depth map, in the rectified
    left camera's pixels (not transposed), against the true depth as the side-by-side pair
    above. Measured: 75 % of the pixels valid (the band of 47 rows the range leaves out of
    240), median error 0.47 %, 99.1 % within 5 %; the disparity y_left - y_right."""
    _, scene = files
    args, z_true, d_true = _vertical_pair(tmp_path, scene, below=True)
    out, ply = tmp_path / "z.tiff", tmp_path / "cloud.ply"
    argv = ["depth", *args, "--num-disparities", "48", "-o", str(out), "--points", str(ply)]
    assert main([*argv, "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    z = np.asarray(read_image(out))[..., 0]
    assert z.shape == (H, W)
    assert np.isnan(z[:47]).all() and np.isfinite(z[47:]).mean() > 0.85  # the top band
    ok = np.isfinite(z) & np.isfinite(z_true)
    assert ok.mean() > 0.7 and summary["valid_fraction"] == pytest.approx(np.isfinite(z).mean())
    assert summary["vertical"] is True
    cloud = read_points_ply(ply)  # the points' z is the depth map's
    np.testing.assert_allclose(np.sort(cloud["z"]), np.sort(z[np.isfinite(z)]), rtol=1e-5)
    rel = np.abs(z - z_true)[ok] / z_true[ok]
    assert np.median(rel) < 0.01 and np.mean(rel < 0.05) > 0.98, (np.median(rel), ok.mean())
    dout = tmp_path / "d.npy"
    assert main(["depth", *args, "--num-disparities", "48", "--disparity", "-o", str(dout)]) == 0
    disp = np.load(dout)
    assert np.median(np.abs(disp - d_true)[ok]) < 0.25  # px, along the columns


def test_depth_of_a_vertical_rig_whose_right_camera_is_above(
    files: tuple[Path, StereoScene], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The right camera above the left: negative disparities (Q's sign, as OpenCV's). The
    default range (0 to 63 px) would put every point behind the cameras: refused in one line
    naming the range to search; with it, the depth as with the camera below."""
    _, scene = files
    args, z_true, _ = _vertical_pair(tmp_path, scene, below=False)
    out = tmp_path / "z.tiff"
    assert main(["depth", *args, "-o", str(out)]) == 1
    line = _line(capsys)
    assert "0 to 63 px" in line and "above the left one" in line and "--min-disparity -63" in line
    assert not out.exists()
    assert main(["depth", *args, "--min-disparity", "-47", "--num-disparities", "48",
                 "-o", str(out)]) == 0  # fmt: skip
    z = np.asarray(read_image(out))[..., 0]
    assert np.isnan(z[-47:]).all()  # the invalid band is at the bottom now
    ok = np.isfinite(z) & np.isfinite(z_true)
    rel = np.abs(z - z_true)[ok] / z_true[ok]
    assert ok.mean() > 0.7 and np.median(rel) < 0.01 and np.mean(rel < 0.05) > 0.98


def test_depth_refusals_write_nothing(
    files: tuple[Path, StereoScene], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    d, scene = files
    left, right, rig = str(d / "left.png"), str(d / "right.png"), str(d / "rig.toml")
    out = tmp_path / "z.tiff"
    ok = ["--camera", rig, "-o", str(out)]
    write_image(tmp_path / "small.png", np.zeros((100, 120), np.uint8))
    nan = np.asarray(scene.right, dtype=np.float32).copy()
    nan[5, 5] = np.nan
    np.save(tmp_path / "nan.npy", nan[..., None])
    sf = read_stereo_camera(rig)
    from dataclasses import replace

    from imageform.geometry import Camera

    c = sf.right.camera
    for name, t, std in (("zero", [0.0, 0.0, 0.0], None), ("near", [-0.01, 0.0, 0.0], 0.02)):
        cam = Camera(c.K, c.R, t, c.image_size, distortion=c.distortion)
        second = replace(sf.right, camera=cam)
        if std is not None:  # a baseline within its own uncertainty of zero
            second = replace(second, std={**second.std, "t": (std, std, std)})
        write_stereo_camera(tmp_path / f"{name}.toml", replace(sf, right=second))
    single = tmp_path / "single.toml"
    single.write_text("[intrinsics]\nfx = 400.0\nfy = 400.0\ncx = 160.0\ncy = 120.0\n")
    v1 = tmp_path / "cam.toml"
    (tmp_path / "uv.csv").write_text("X,Y,Z,u,v\n0,0,1,160,120\n")
    write_camera(v1, replace(sf.left, path=None))
    cases = [
        ([left, str(tmp_path / "small.png"), *ok], "small.png is 120 x 100 px"),
        ([left, str(tmp_path / "nan.npy"), *ok], "nan.npy"),
        ([left, left, *ok], "left and right are both"),
        ([left, right, *ok, "--block-size", "4"], "--block-size must be 3, 5 or 7"),
        ([left, right, *ok, "--p1", "20", "--p2", "10"], "--p2 (10) must exceed --p1 (20)"),
        ([left, right, *ok, "--points", str(tmp_path / "c.txt")], "give a .ply name"),
        ([left, right, "--camera", str(tmp_path / "zero.toml"), "-o", str(out)], "baseline of"),
        ([left, right, "--camera", str(tmp_path / "near.toml"), "-o", str(out)], "within 3 st"),
        ([left, right, "--camera", str(single), "-o", str(out)], "single.toml"),
        ([left, right, "--camera", str(tmp_path / "none.toml"), "-o", str(out)], "none.toml"),
        # a newcomer's mistakes: calibrate's single-camera file, an image as the camera file
        ([left, right, "--camera", str(v1), "-o", str(out)], "written by imageform stereo-"),
        ([left, right, "--camera", left, "-o", str(out)], "not a stereo camera file: not text"),
        ([left, right, "--camera", rig, "-o", str(tmp_path / "z.png")], "z.png"),
    ]
    for args, needle in cases:
        assert main(["depth", *args]) != 0, args
        line = _line(capsys)
        assert needle in line, (args, line)
        assert not out.exists() and not (tmp_path / "c.txt").exists()
    # the command line's own range check (a usage error, exit 2)
    # the other way round: the rig file where one camera's file is read
    assert main(["pose", rig, str(tmp_path / "uv.csv"), "-o", str(tmp_path / "p.toml")]) == 1
    assert "a stereo camera file, as stereo-calibrate writes it" in _line(capsys)
    assert main(["depth", left, right, *ok, "--num-disparities", "0"]) == 2
    assert "expected --num-disparities >= 1, got 0" in capsys.readouterr().err
    # a failure after the depth map is computed leaves neither output: --points is refused
    # by name first, so check an unwritable points folder instead
    bad_ply = tmp_path / "no-such-folder" / "c.ply"
    assert main(["depth", left, right, *ok, "--points", str(bad_ply)]) != 0
    capsys.readouterr()
    assert not out.exists() and not bad_ply.exists()
