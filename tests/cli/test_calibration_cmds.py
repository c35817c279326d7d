"""``imageform calibrate / pose / triangulate``: outputs, tables, bad input."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pytest

from imageform.cli import main
from imageform.errors import InvalidInputError
from imageform.geometry import Camera, KannalaBrandt
from imageform.geometry.calibration_refine import rodrigues
from imageform.io import read_camera, write_camera
from imageform.workflows.calibration import MAX_BOARD_CORNERS, MIN_VIEWS, parse_board

if TYPE_CHECKING:
    from imageform.geometry import CharucoBoard

K = np.array([[800.0, 0.0, 320.0], [0.0, 800.0, 240.0], [0.0, 0.0, 1.0]])


def test_calibrate_opencv_left(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pattern = str(shared_data / "opencv-left" / "left0[1-6].jpg")
    out, plot = tmp_path / "cam.toml", tmp_path / "err.png"
    code = main(["calibrate", pattern, "--board", "9x6", "--square", "25mm", "-o", str(out),
                 "--plot", str(plot)])  # fmt: skip
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert "left03.jpg" in captured.out and "RMS" in captured.out
    assert plot.stat().st_size > 1000
    cf = read_camera(out)
    assert 500 < cf.camera.K[0, 0] < 570 and cf.camera.image_size == (640, 480)
    assert cf.distortion_model == "brown_conrady" and not cf.has_pose
    assert cf.provenance.views_used == 6 and cf.provenance.images[2] == "left03.jpg"
    assert cf.provenance.rms_px is not None and cf.provenance.rms_px < 0.5
    assert cf.std["fx"] > 0 and cf.std["skew"] == 0.0 and "skew" in cf.provenance.fixed
    assert "--board 9x6 --square 25mm" in (cf.provenance.command or "")
    # output exists now: refused without --force
    assert main(["calibrate", pattern, "--board", "9x6", "-o", str(out)]) == 1
    assert "--force" in capsys.readouterr().err
    assert main(["calibrate", pattern, "--board", "9x6", "-o", str(out), "--force", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["views_used"] == 6 and len(summary["per_view"]) == 6
    assert summary["distortion"]["model"] == "brown_conrady"


def test_calibrate_square_units_and_corners(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """--square goes through the one unit table: 2.5cm is 25 mm in the corner table; the
    camera does not depend on the unit."""
    pattern = str(shared_data / "opencv-left" / "left0[1-4].jpg")
    corners = tmp_path / "c.csv"
    args = ["calibrate", pattern, "--board", "9x6", "-o", str(tmp_path / "a.toml")]
    assert main([*args, "--square", "2.5cm", "--corners", str(corners)]) == 0
    rows = corners.read_text().splitlines()
    assert rows[0] == "image,X,Y,Z,u,v" and len(rows) == 1 + 4 * 54
    assert [float(v) for v in rows[2].split(",")[1:4]] == [25.0, 0.0, 0.0]
    a = read_camera(tmp_path / "a.toml").camera
    args[-1] = str(tmp_path / "b.toml")
    assert main([*args, "--square", "1in"]) == 0
    b = read_camera(tmp_path / "b.toml").camera
    np.testing.assert_allclose(np.asarray(a.K), np.asarray(b.K), rtol=1e-7)
    capsys.readouterr()
    assert main([*args, "--square", "25 furlongs", "--force"]) == 2
    assert "unknown unit 'furlongs' for --square; valid: m, cm, mm" in capsys.readouterr().err
    assert main([*args, "--square", "-25mm", "--force"]) == 2
    assert "expected --square > 0" in capsys.readouterr().err


def test_calibrate_bad_input(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = str(tmp_path / "cam.toml")
    assert main(["calibrate", str(tmp_path / "*.jpg"), "--board", "9x6", "-o", out]) == 1
    assert "no files match" in capsys.readouterr().err
    bad = tmp_path / "bad.jpg"
    bad.write_bytes(b"not an image")
    assert main(["calibrate", str(bad), "--board", "9x6", "-o", out]) == 1
    assert "cannot read" in capsys.readouterr().err
    # no board: the pattern size is wrong for every view
    one = str(shared_data / "opencv-left" / "left01.jpg")
    assert main(["calibrate", one, "--board", "7x7", "-o", out]) == 1
    err = capsys.readouterr().err
    assert "no 7x7 checkerboard found in any of the 1 images (left01.jpg: " in err
    # images of different sizes
    from PIL import Image

    small = tmp_path / "small.png"
    Image.open(one).resize((320, 240)).save(small)
    assert main(["calibrate", one, str(small), "--board", "9x6", "-o", out]) == 1
    assert "one size" in capsys.readouterr().err
    # patterns that cannot be a board: bad usage (exit 2)
    for board in ("nine", "1x5", "0x0", "9x1", f"{MAX_BOARD_CORNERS + 1}x6", "9x6x2"):
        assert main(["calibrate", one, "--board", board, "-o", out]) == 2, board
        assert "COLSxROWS" in capsys.readouterr().err
    # a board too fine for the image: each square needs pixels
    assert main(["calibrate", one, "--board", "190x120", "-o", out]) == 1
    assert "cannot be seen in 640 x 480 px images" in capsys.readouterr().err
    # too few views for the full model: an error, no file
    copy = tmp_path / "only.jpg"
    shutil.copy(one, copy)
    assert main(["calibrate", str(copy), "--board", "9x6", "-o", out]) == 1
    err = capsys.readouterr().err
    assert f"in 1 view(s) (only.jpg) of 1; calibrate needs at least {MIN_VIEWS}" in err
    two = [one, str(shared_data / "opencv-left" / "left02.jpg")]
    assert main(["calibrate", *two, "--board", "9x6", "-o", out]) == 1
    assert "in 2 view(s)" in capsys.readouterr().err
    assert not Path(out).exists()
    assert main(["calibrate", one, "--board", "9x6", "-o", out, "--fix", "focal"]) == 2
    assert "unknown --fix 'focal'; valid: fx, fy" in capsys.readouterr().err


def test_calibrate_plot_suffix_checked_first(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A --plot matplotlib cannot write is a usage error before any view is read, not a
    ValueError from matplotlib after the calibration (nothing written)."""
    one = str(shared_data / "opencv-left" / "left01.jpg")
    out = tmp_path / "cam.toml"
    args = ["calibrate", one, "--board", "9x6", "-o", str(out)]
    assert main([*args, "--plot", str(tmp_path / "errors.txt")]) == 2
    err = capsys.readouterr().err
    assert "expected --plot as a .png, .svg or .pdf file, got 'errors.txt'" in err
    assert "ValueError" not in err and not out.exists()


def test_calibrate_square_out_of_any_board_s_range(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """--square 1e-30mm calibrated OpenCV's views to RMS 3 px with every k at 0, and 1e12m did
    not converge: a usage error now; 0.1um and 1000m, the bounds, still calibrate alike."""
    views = str(shared_data / "opencv-left" / "left0[1-4].jpg")
    for square in ("1e-30mm", "0.05um", "1001m", "1e12m"):
        out = tmp_path / "bad.toml"
        assert main(["calibrate", views, "--board", "9x6", "--square", square, "-o", str(out)]) == 2
        assert "expected --square from 0.1um to 1000m" in capsys.readouterr().err
        assert not out.exists()
    fx = []
    for square in ("0.1um", "25mm", "1000m"):
        out = tmp_path / f"{square}.toml"
        assert main(["calibrate", views, "--board", "9x6", "--square", square, "-o", str(out)]) == 0
        fx.append(read_camera(out).camera.K[0, 0])
    assert max(fx) - min(fx) < 1e-3, fx


def test_calibrate_literal_bracket_names(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A file called ``view[1].jpg`` that exists is that file, not a glob pattern."""
    names = []
    for i in (1, 2, 3):
        dst = tmp_path / f"view[{i}].jpg"
        shutil.copy(shared_data / "opencv-left" / f"left0{i}.jpg", dst)
        names.append(str(dst))
    out = tmp_path / "cam.toml"
    assert main(["calibrate", *names, "--board", "9x6", "-o", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["views_used"] == 3
    assert read_camera(out).provenance.images == ("view[1].jpg", "view[2].jpg", "view[3].jpg")


def test_calibrate_a_folder_of_views(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A folder stands for its image files, sorted by name: as the same files given one by one.

    Files of other kinds in it (notes, hidden files, subfolders) are left out; a folder
    without images is one line naming the suffixes read.
    """
    views = tmp_path / "views"
    views.mkdir()
    for i in (3, 1, 2):
        shutil.copy(shared_data / "opencv-left" / f"left0{i}.jpg", views / f"left0{i}.JPG")
    (views / "notes.txt").write_text("board 9x6")
    (views / ".left00.jpg").write_bytes(b"not an image")
    (views / "sub").mkdir()
    out = tmp_path / "cam.toml"
    assert main(["calibrate", str(views), "--board", "9x6", "-o", str(out), "--json"]) == 0
    folder = json.loads(capsys.readouterr().out)
    names = [str(views / f"left0{i}.JPG") for i in (1, 2, 3)]
    one_by_one = tmp_path / "one.toml"
    assert main(["calibrate", *names, "--board", "9x6", "-o", str(one_by_one), "--json"]) == 0
    files = json.loads(capsys.readouterr().out)
    assert read_camera(out).provenance.images == ("left01.JPG", "left02.JPG", "left03.JPG")
    assert folder["rms_px"] == files["rms_px"] and folder["views_used"] == 3
    empty = tmp_path / "empty"
    empty.mkdir()
    (empty / "notes.txt").write_text("")
    assert main(["calibrate", str(empty), "--board", "9x6", "-o", str(tmp_path / "e.toml")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"imageform: error: folder {empty} holds no images")
    assert not (tmp_path / "e.toml").exists()


def test_calibrate_skips_unreadable_files_of_a_folder(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A file of a folder (or of a glob pattern) that cannot be read (an empty .jpg, as in
    OpenCV's stereo sample data3 of github.com/dreameer/stereocalibrate; one that is no
    image) is skipped with one note naming it, the camera as from the other files; a file
    named that cannot be read is still an error; too few readable views, one line."""
    views = tmp_path / "views"
    views.mkdir()
    for i in (1, 2, 3, 4):
        shutil.copy(shared_data / "opencv-left" / f"left0{i}.jpg", views / f"left0{i}.jpg")
    (views / "left05.jpg").write_bytes(b"")
    (views / "left06.png").write_bytes(b"not an image")
    out = tmp_path / "cam.toml"
    assert main(["calibrate", str(views), "--board", "9x6", "-o", str(out), "--json"]) == 0
    captured = capsys.readouterr()
    summary = json.loads(captured.out)
    assert summary["views_used"] == 4 and summary["views_total"] == 6
    assert captured.err.strip().splitlines() == [
        f"imageform: warning: {views / 'left05.jpg'}: skipped, cannot be read (an empty file)",
        f"imageform: warning: {views / 'left06.png'}: skipped, cannot be read (not a PNG file)",
    ]
    names = [str(views / f"left0{i}.jpg") for i in (1, 2, 3, 4)]
    assert main(["calibrate", *names, "--board", "9x6", "-o", str(tmp_path / "4.toml")]) == 0
    capsys.readouterr()
    np.testing.assert_array_equal(
        np.asarray(read_camera(out).camera.K), np.asarray(read_camera(tmp_path / "4.toml").camera.K)
    )
    # a quoted glob pattern stands for its files as a folder does
    pattern = str(views / "left0*")
    assert main(["calibrate", pattern, "--board", "9x6", "-o", str(tmp_path / "g.toml")]) == 0
    assert capsys.readouterr().err.count("cannot be read") == 2
    # named, the empty file is an error (one line, nothing written)
    bad = tmp_path / "bad.toml"
    assert main(["calibrate", *names, str(views / "left05.jpg"), "--board", "9x6",
                 "-o", str(bad)]) == 1  # fmt: skip
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"imageform: error: cannot read {views}/left05")
    # too few readable views
    (views / "left03.jpg").unlink()
    (views / "left04.jpg").unlink()
    assert main(["calibrate", str(views), "--board", "9x6", "-o", str(bad)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert "in 2 view(s) (left01.jpg, left02.jpg) of 2 read (2 others cannot be)" in err[0]
    for f in views.glob("left0[12].jpg"):
        f.write_bytes(b"")
    assert main(["calibrate", str(views), "--board", "9x6", "-o", str(bad)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "none of the 4 images can be read" in err[0], err
    assert not bad.exists()


def test_calibrate_refinement_option(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--refinement``: the corners written are find_checkerboard's with that method
    (symmetric by default, gradient: OpenCV's cornerSubPix alone); a bad name is one line."""
    from imageform.geometry import find_checkerboard
    from imageform.io import read_image

    views = [shared_data / "opencv-left" / f"left0{i}.jpg" for i in (1, 2, 3)]
    for method in ("symmetric", "gradient"):
        out, corners = tmp_path / f"{method}.toml", tmp_path / f"{method}.csv"
        args = ["calibrate", *map(str, views), "--board", "9x6", "-o", str(out)]
        args += ["--corners", str(corners)] + (["--refinement", method] * (method != "symmetric"))
        assert main(args) == 0, capsys.readouterr().err
        capsys.readouterr()
        rows = np.genfromtxt(corners, delimiter=",", names=True, dtype=None, encoding="utf-8")
        for view in views:
            mine = rows[rows["image"] == view.name]
            want = find_checkerboard(read_image(view), (9, 6), method=method).corners
            assert want is not None
            np.testing.assert_allclose(np.c_[mine["u"], mine["v"]], want, atol=1e-6)
    bad = ["calibrate", *map(str, views), "--board", "9x6", "-o", str(tmp_path / "b.toml")]
    assert main([*bad, "--refinement", "sb"]) == 2  # a usage error, as every bad choice
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        "imageform calibrate: error: unknown --refinement 'sb'; valid: symmetric, gradient "
        "(see 'imageform calibrate --help')"
    ]
    assert not (tmp_path / "b.toml").exists()


def test_calibrate_board_auto(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """--board auto: the size most views show, every view found as with --board 9x6, the same
    camera; the camera file's command names the size; a view showing another board is searched
    again for the set's size."""
    views = sorted((shared_data / "opencv-left").glob("left*.jpg"))[:6]
    a, b = tmp_path / "auto.toml", tmp_path / "given.toml"
    assert main(["calibrate", *map(str, views), "--board", "auto", "-o", str(a), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["board"]["inner_corners"] == [9, 6] and summary["board"]["read_as"] == "auto"
    assert summary["views_used"] == 6
    assert main(["calibrate", *map(str, views), "--board", "9x6", "-o", str(b)]) == 0
    capsys.readouterr()
    ca, cb = read_camera(a), read_camera(b)
    np.testing.assert_allclose(np.asarray(ca.camera.K), np.asarray(cb.camera.K), rtol=1e-6)
    assert "--board 9x6 " in (ca.provenance.command or "")
    # the plain output's first line says how the size was found
    assert main(["calibrate", *map(str, views), "--board", "auto", "-o", str(a), "--force"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("board: checkerboard, 9x6 inner corners = 10x7 squares (--board auto: ")
    # a view that shows a smaller complete board (its right part blanked): searched again, named
    from PIL import Image

    img = np.asarray(Image.open(views[0]).convert("L")).copy()
    img[:, 400:] = 160
    odd = tmp_path / "cut.png"
    Image.fromarray(img).save(odd)
    argv = ["calibrate", str(odd), *map(str, views[1:]), "--board", "auto", "-o", str(a)]
    assert main([*argv, "--force"]) == 0
    err = capsys.readouterr().err
    assert "cut.png: no 9x6 board found" in err


def test_calibrate_board_auto_refusals(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """No board in any view: one line naming the first view's reason, exit 1, nothing
    written; the same from stereo-calibrate."""
    out = tmp_path / "cam.toml"
    kodak = [str(shared_data / "kodak" / f"kodim0{k}.png") for k in (1, 2, 3)]
    assert main(["calibrate", *kodak, "--board", "auto", "-o", str(out)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no checkerboard found in any of the 3 images (kodim01.png: " in err[0]
    assert "give the board's size with --board COLSxROWS" in err[0]
    assert not out.exists()
    argv = ["stereo-calibrate", kodak[0], kodak[1], "--board", "auto", "-o", str(out)]
    assert main(argv) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no checkerboard found in any of the 2 images" in err[0]
    assert not out.exists()


def test_parse_board() -> None:
    assert parse_board("9x6") == (9, 6) and parse_board(" 8 X 5 ") == (8, 5)
    for bad in ("1x6", "0x0", "9", "x6", f"{MAX_BOARD_CORNERS + 1}x2"):
        with pytest.raises(InvalidInputError, match="COLSxROWS"):
            parse_board(bad)


def _camera_file(path: Path, rvec: list[float], t: list[float], model: object = None) -> Path:
    cam = Camera(K, rodrigues(np.array([rvec]))[0], t, (640, 480), distortion=model)
    return write_camera(path, cam, has_pose=True)


def _row(a: np.ndarray, b: np.ndarray) -> str:
    return ",".join(repr(float(v)) for v in (*a, *b))


POSES = [([0.0, 0.0, 0.0], [0.0, 0.0, 0.0]), ([0.0, -0.15, 0.0], [-1.0, 0.0, 0.1])]


@pytest.mark.parametrize("model", [None, KannalaBrandt(0.05, -0.01, 2e-3, -1e-4)])
def test_pose_and_triangulate(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], model: object
) -> None:
    """Pose from correspondences, then triangulation with the written camera: both use the
    camera file's distortion model (a fisheye here, not only Brown-Conrady)."""
    rng = np.random.default_rng(0)
    X = rng.uniform(-1, 1, (20, 3)) + [0, 0, 6]
    cams = [Camera(K, rodrigues(np.array([r]))[0], t, distortion=model) for r, t in POSES]
    uvs = [np.asarray(c.project(X).uv) for c in cams]
    cam_toml = _camera_file(tmp_path / "cam.toml", *POSES[0], model)
    pts = tmp_path / "pairs.csv"
    pts.write_text("X,Y,Z,u,v\n" + "\n".join(_row(a, b) for a, b in zip(X, uvs[1], strict=True)))
    out = tmp_path / "posed.toml"
    assert main(["pose", str(cam_toml), str(pts), "-o", str(out), "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(s["t"], POSES[1][1], atol=1e-8)
    assert s["inliers"] == 20 and s["rms_px"] < 1e-6
    posed = read_camera(out)
    assert posed.has_pose and posed.camera.distortion == model
    assert posed.provenance.based_on == "cam.toml" and posed.provenance.points_used == 20
    assert main(["pose", str(cam_toml), str(pts), "--ransac"]) == 0
    assert "20/20 inliers" in capsys.readouterr().out
    # triangulate with the camera written by `pose`
    obs = tmp_path / "obs.csv"
    obs.write_text("\n".join(_row(a, b) for a, b in zip(uvs[0], uvs[1], strict=True)))
    res_csv = tmp_path / "X.csv"
    code = main(["triangulate", str(obs), str(cam_toml), str(out), "-o", str(res_csv)])
    assert code == 0, capsys.readouterr().err
    got = np.loadtxt(res_csv, delimiter=",", skiprows=1)
    np.testing.assert_allclose(got[:, :3], X, atol=1e-7)
    assert got[:, 7].all()


def test_pose_triangulate_bad_input(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cam_toml = _camera_file(tmp_path / "cam.toml", [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    pts = tmp_path / "p.csv"
    pts.write_text("1,2,3,4\n")
    assert main(["pose", str(cam_toml), str(pts)]) == 1
    assert "5 columns" in capsys.readouterr().err
    pts.write_text("0,0,5,320,240\n1,0,5,480,240\n0,1,5,320,400\n")
    assert main(["pose", str(cam_toml), str(pts)]) == 1
    assert "at least 4 points" in capsys.readouterr().err
    pts.write_text("0,0,5,320,240\nnan,0,5,480,240\n0,1,5,320,400\n1,1,5,480,400\n")
    assert main(["pose", str(cam_toml), str(pts)]) == 1
    assert "p.csv:2: expected finite numbers" in capsys.readouterr().err
    obs = tmp_path / "obs.csv"
    obs.write_text("1,2,3\n")
    out = str(tmp_path / "X.csv")
    other = _camera_file(tmp_path / "b.toml", [0.0, 0.1, 0.0], [-1.0, 0.0, 0.0])
    assert main(["triangulate", str(obs), str(cam_toml), str(other), "-o", out]) == 1
    assert "expected 4 columns" in capsys.readouterr().err
    # one camera, cameras without a pose, cameras at one place: errors, not "0 valid"
    obs.write_text("320,240,300,240\n")
    assert main(["triangulate", str(obs), str(cam_toml), "-o", out]) == 1
    assert "2 or more camera files" in capsys.readouterr().err
    nopose = write_camera(tmp_path / "nopose.toml", Camera(K))
    assert main(["triangulate", str(obs), str(nopose), str(other), "-o", out]) == 1
    assert "nopose.toml has no pose" in capsys.readouterr().err
    same = _camera_file(tmp_path / "same.toml", [0.0, 0.3, 0.0], [0.0, 0.0, 0.0])
    assert main(["triangulate", str(obs), str(cam_toml), str(same), "-o", out]) == 1
    assert "same centre" in capsys.readouterr().err
    # every point behind the cameras: nothing to triangulate is a failure
    side = _camera_file(tmp_path / "side.toml", [0.0, 0.0, 0.0], [-1.0, 0.0, 0.0])
    obs.write_text("240,240,400,240\n")  # rays that meet only at z = -5
    assert main(["triangulate", str(obs), str(cam_toml), str(side), "-o", out]) == 1
    assert "none of the 1 points could be triangulated" in capsys.readouterr().err
    assert not Path(out).exists()


def _charuco_scene() -> tuple[CharucoBoard, int, np.ndarray, np.ndarray, np.ndarray]:
    """A 9 x 7 ChArUco board (20 mm squares, 15 mm markers), its printed image at 64 px a
    square, and the camera the ChArUco tests render it through: K and Brown-Conrady k1, k2."""
    from imageform.geometry import CharucoBoard

    board = CharucoBoard((9, 7), 20.0, 15.0, "6x6_250")
    px = 64
    K_true = np.array([[700.0, 0, 322.0], [0, 705.0, 238.0], [0, 0, 1]])
    dist = np.array([-0.12, 0.05, 0.0, 0.0, 0.0])
    return board, px, board.image(px, margin_px=px), K_true, dist


def test_calibrate_charuco_views(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """`imageform calibrate --board charuco:9x7`: ten views of a ChArUco board rendered
    through a camera with distortion (three cut by the image border, so a checkerboard
    calibration could not use them) give back K within 0.5 % and k1 within 10 %; the corners
    table holds each view's own subset of board points; the camera file is what
    `imageform undistort` reads."""
    from PIL import Image

    from tests.geometry.test_charuco import _render_view

    board, px, art, K_true, dist = _charuco_scene()
    rng = np.random.default_rng(5)
    for k in range(10):
        rvec = np.array([rng.uniform(-0.6, 0.6), rng.uniform(-0.6, 0.6), rng.uniform(-0.3, 0.3)])
        shift = (110.0 if k % 2 else -110.0) if k % 3 == 2 else 0.0
        tvec = np.array([-90.0 + shift + rng.uniform(-40, 40), -70.0 + rng.uniform(-30, 30), 330])
        img = _render_view(board, art, px, K_true, dist, rvec, tvec, (640, 480))
        Image.fromarray(img).save(tmp_path / f"view{k:02d}.png")
    out, table = tmp_path / "cam.toml", tmp_path / "corners.csv"
    argv = ["calibrate", str(tmp_path / "view*.png"), "--board", "charuco:9x7"]
    argv += ["--square", "20mm", "--marker", "15mm", "--corners", str(table), "-o", str(out)]
    assert main(argv) == 0, capsys.readouterr().err
    cam = read_camera(out).camera
    np.testing.assert_allclose(
        np.asarray(cam.K)[[0, 1, 0, 1], [0, 1, 2, 2]], [700.0, 705.0, 322.0, 238.0], rtol=5e-3
    )
    assert abs(cam.distortion.k1 + 0.12) < 0.012
    rows = table.read_text().splitlines()[1:]
    per_view = {r.split(",")[0] for r in rows}
    assert len(per_view) == 10 and len(rows) < 10 * board.n_corners  # partial views used
    assert (
        main(
            [
                "undistort",
                str(tmp_path / "view00.png"),
                "--camera",
                str(out),
                "-o",
                str(tmp_path / "u.png"),
            ]
        )
        == 0
    )


@pytest.mark.parametrize("refinement", ["symmetric", "gradient"])
def test_calibrate_charuco_refinement(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], refinement: str
) -> None:
    """`--refinement` picks detect_charuco's method for a ChArUco board too (symmetric by
    default): the corners table holds that method's corners, and the other method's differ."""
    import csv

    import cv2
    from PIL import Image

    from imageform.geometry import detect_charuco
    from tests.geometry.test_charuco import _render_view

    board, px, art, K_true, dist = _charuco_scene()
    rng = np.random.default_rng(5)
    views = []
    for k in range(4):
        rvec = np.array([rng.uniform(-0.6, 0.6), rng.uniform(-0.6, 0.6), rng.uniform(-0.3, 0.3)])
        tvec = np.array([-90.0 + rng.uniform(-40, 40), -70.0 + rng.uniform(-30, 30), 330])
        img = _render_view(board, art, px, K_true, dist, rvec, tvec, (640, 480))
        img = np.clip(cv2.GaussianBlur(img.astype(np.float64), (0, 0), 1.0) + 0.5, 0, 255)
        views.append(img.astype(np.uint8))
        Image.fromarray(views[-1]).save(tmp_path / f"view{k:02d}.png")
    out, table = tmp_path / "cam.toml", tmp_path / "corners.csv"
    argv = ["calibrate", str(tmp_path / "view*.png"), "--board", "charuco:9x7"]
    argv += ["--square", "20mm", "--marker", "15mm", "--corners", str(table), "-o", str(out)]
    if refinement != "symmetric":
        argv += ["--refinement", refinement]
    assert main(argv) == 0, capsys.readouterr().err
    with table.open() as f:
        rows = [r for r in csv.DictReader(f) if r["image"] == "view00.png"]
    got = np.array([[float(r["u"]), float(r["v"])] for r in rows])
    mine = detect_charuco(views[0], board, method=refinement)  # type: ignore[arg-type]
    other = detect_charuco(
        views[0], board, method="gradient" if refinement == "symmetric" else "symmetric"
    )
    np.testing.assert_allclose(got, mine.corners, atol=1e-6)
    assert np.abs(got - other.corners).max() > 1e-2


def test_calibrate_charuco_legacy_board(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A board of even rows printed by OpenCV before 4.6 (markers in the other squares) is
    calibrated from with the plain --board charuco:8x6, and the output says how it was read
    (it gave no corner: 'found ... in 0 view(s)')."""
    from PIL import Image

    from imageform.geometry import CharucoBoard
    from tests.geometry.test_charuco import _render_view

    board = CharucoBoard((8, 6), 20.0, 15.0, "6x6_250", legacy=True)
    px = 64
    art = board.image(px, margin_px=px)
    K_true = np.array([[700.0, 0, 322.0], [0, 705.0, 238.0], [0, 0, 1]])
    rng = np.random.default_rng(6)
    for k in range(5):
        rvec = np.array([rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), rng.uniform(-0.3, 0.3)])
        tvec = np.array([-80.0 + rng.uniform(-20, 20), -60.0 + rng.uniform(-20, 20), 330])
        img = _render_view(board, art, px, K_true, np.zeros(5), rvec, tvec, (640, 480))
        Image.fromarray(img).save(tmp_path / f"view{k:02d}.png")
    out = tmp_path / "cam.toml"
    argv = ["calibrate", str(tmp_path / "view*.png"), "--board", "charuco:8x6"]
    argv += ["--square", "20mm", "--marker", "15mm", "-o", str(out)]
    assert main(argv) == 0, capsys.readouterr().err
    assert "legacy layout" in capsys.readouterr().err
    cam = read_camera(out).camera
    np.testing.assert_allclose(np.asarray(cam.K)[[0, 1], [0, 1]], [700.0, 705.0], rtol=1e-2)


def test_calibrate_charuco_board_from_a_later_marker(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """--first-marker: a board whose markers start at 60 of 6x6_250 (a rig's second board)
    is calibrated from; without it no view has a marker of the board."""
    from PIL import Image

    from imageform.geometry import CharucoBoard
    from tests.geometry.test_charuco import _render_view

    board = CharucoBoard((7, 5), 20.0, 15.0, "6x6_250", first_marker=60)
    px = 64
    art = board.image(px, margin_px=px)
    K_true = np.array([[700.0, 0, 322.0], [0, 705.0, 238.0], [0, 0, 1]])
    rng = np.random.default_rng(7)
    for k in range(4):
        rvec = np.array([rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), rng.uniform(-0.3, 0.3)])
        tvec = np.array([-70.0 + rng.uniform(-20, 20), -50.0 + rng.uniform(-20, 20), 300])
        img = _render_view(board, art, px, K_true, np.zeros(5), rvec, tvec, (640, 480))
        Image.fromarray(img).save(tmp_path / f"view{k:02d}.png")
    out = tmp_path / "cam.toml"
    argv = ["calibrate", str(tmp_path / "view*.png"), "--board", "charuco:7x5"]
    argv += ["--square", "20mm", "--marker", "15mm", "-o", str(out)]
    assert main(argv) == 1
    assert "in 0 view(s)" in capsys.readouterr().err
    assert main([*argv, "--first-marker", "60"]) == 0, capsys.readouterr().err
    cam = read_camera(out).camera
    np.testing.assert_allclose(np.asarray(cam.K)[[0, 1], [0, 1]], [700.0, 705.0], rtol=1e-2)
    assert (
        main(
            [
                "calibrate",
                str(tmp_path / "view00.png"),
                "--board",
                "9x6",
                "--first-marker",
                "4",
                "-o",
                str(out),
            ]
        )
        == 2
    )
    assert "--first-marker is for a ChArUco" in capsys.readouterr().err


def test_calibrate_charuco_refusals(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from PIL import Image

    img = tmp_path / "v.png"
    Image.fromarray(np.full((120, 160), 200, np.uint8)).save(img)
    out = str(tmp_path / "cam.toml")
    base = ["calibrate", str(img), "-o", out, "--square", "30mm"]
    assert main([*base, "--board", "charuco:7x5"]) == 2
    assert "needs --marker" in capsys.readouterr().err
    assert main([*base, "--board", "charuco:7x5", "--marker", "40mm"]) == 2
    assert "--marker smaller than --square" in capsys.readouterr().err
    assert main([*base, "--board", "charuco:2x5", "--marker", "20mm"]) == 2
    assert "charuco:COLSxROWS with 3 to" in capsys.readouterr().err
    assert main([*base, "--board", "9x6", "--marker", "20mm"]) == 2
    assert "--marker is for a ChArUco" in capsys.readouterr().err
    assert main([*base, "--board", "charuco:7x5", "--marker", "20mm", "--dictionary", "9x9"]) == 2
    assert "9x9" in capsys.readouterr().err
    # no board in the view: an error naming what was seen, nothing written
    assert main([*base, "--board", "charuco:7x5", "--marker", "20mm"]) == 1
    assert "0 markers, 0 corners" in capsys.readouterr().err
    assert not Path(out).exists()
    left, right = str(img), str(img)
    argv = ["stereo-calibrate", left, right, "--board", "charuco:7x5", "-o", out]
    assert main(argv) == 2
    assert "checkerboard --board" in capsys.readouterr().err


def test_calibrate_charuco_wrong_dictionary_hint(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A 4x4_50 board calibrated with the default --dictionary 6x6_250 finds no marker; the
    error names the dictionary the markers do belong to, and nothing is written."""
    from PIL import Image

    from imageform.geometry import CharucoBoard

    art = CharucoBoard((7, 5), 20.0, 15.0, "4x4_50").image(60, margin_px=60)
    Image.fromarray(art).save(tmp_path / "v.png")
    out = tmp_path / "cam.toml"
    argv = ["calibrate", str(tmp_path / "v.png"), "--board", "charuco:7x5", "-o", str(out)]
    assert main([*argv, "--square", "20mm", "--marker", "15mm"]) == 1
    err = capsys.readouterr().err
    assert "try --dictionary 4x4_50" in err and len(err.strip().splitlines()) == 1, err
    assert not out.exists()


def test_identify_aruco_dictionary() -> None:
    from imageform.geometry import CharucoBoard, aruco_marker_image, identify_aruco_dictionary

    # a board uses ids 0, 1, ...: the smallest dictionary of its family reads it
    for name in ("4x4_50", "5x5_250", "6x6_1000", "7x7_100", "aruco_original"):
        art = CharucoBoard((5, 5), 20.0, 15.0, name).image(50, margin_px=50)
        want = name if name == "aruco_original" else name.split("_")[0] + "_50"
        assert identify_aruco_dictionary(art) == want, name
    canvas = np.full((240, 480), 255, np.uint8)
    canvas[60:180, 40:160] = aruco_marker_image(700, "6x6_1000", size_px=120)
    canvas[60:180, 280:400] = aruco_marker_image(3, "6x6_1000", size_px=120)
    assert identify_aruco_dictionary(canvas) == "6x6_1000"
    assert identify_aruco_dictionary(canvas, min_markers=3) is None
    assert identify_aruco_dictionary(np.full((200, 200), 255, np.uint8)) is None
    with pytest.raises(InvalidInputError, match="min_markers"):
        identify_aruco_dictionary(np.zeros((50, 50)), min_markers=0)


def _fisheye_board(K, d, rvec, tvec, size, board=(9, 6), square=25.0, ss=2) -> np.ndarray:
    """8-bit grey view of a checkerboard (one white square of margin) by a fisheye camera.

    Each of ``ss x ss`` samples per pixel is unwarped by ``d`` (Kannala-Brandt) to its ray,
    which meets the board plane ``Z = 0`` at ``λ Rᵀ d - Rᵀ t``; rays beyond 90 deg are dark.
    """
    w, h = size
    R = rodrigues(np.asarray(rvec, float)[None])[0]
    Rt_t = R.T @ np.asarray(tvec, float)
    v, u = np.mgrid[0:h, 0:w].astype(float)
    acc = np.zeros((h, w))
    cols, rows = board
    for dy in (np.arange(ss) + 0.5) / ss - 0.5:
        for dx in (np.arange(ss) + 0.5) / ss - 0.5:
            xd = np.stack([(u + dx - K[0, 2]) / K[0, 0], (v + dy - K[1, 2]) / K[1, 1]], -1)
            xy, ok = d.undistort(xd.reshape(-1, 2))
            rb = np.c_[xy, np.ones(len(xy))] @ R
            lam = Rt_t[2] / rb[:, 2]
            bx, by = ((lam[:, None] * rb - Rt_t)[:, :2] / square).T
            inside = (bx > -1) & (bx < cols) & (by > -1) & (by < rows)
            margin = (bx > -2) & (bx < cols + 1) & (by > -2) & (by < rows + 1)
            val = np.where((np.floor(bx) + np.floor(by)) % 2 == 0, 0.1, 0.9)
            img = np.where(inside, val, np.where(margin, 0.9, 0.45))
            acc += np.where(np.asarray(ok) & (lam > 0), img, 0.05).reshape(h, w)
    return np.round(255 * acc / ss**2).astype(np.uint8)


def test_calibrate_fisheye_then_undistort(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`imageform calibrate --model kannala-brandt` on views rendered through a fisheye
    (about 180 deg across the width) gives back K and the distortion of the rendering; the
    camera file says kannala_brandt, and `imageform undistort` with it straightens the
    board's rows (the corners found in the undistorted view lie on lines within 0.3 px)."""
    from PIL import Image

    from imageform.geometry.checkerboard import find_checkerboard

    K_true = np.array([[200.0, 0.0, 321.0], [0.0, 201.0, 238.0], [0.0, 0.0, 1.0]])
    d_true = KannalaBrandt(0.03, -0.01, 0.002, 0.0)
    rng = np.random.default_rng(2)
    for k in range(7):
        rvec = [rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), rng.uniform(-0.3, 0.3)]
        tvec = [-112.0 + rng.uniform(-80, 80), -62.0 + rng.uniform(-60, 60), rng.uniform(150, 220)]
        img = _fisheye_board(K_true, d_true, rvec, tvec, (640, 480))
        Image.fromarray(img).save(tmp_path / f"view{k:02d}.png")
    out = tmp_path / "fish.toml"
    argv = ["calibrate", str(tmp_path / "view*.png"), "--board", "9x6", "--square", "25mm"]
    assert main([*argv, "--model", "kannala-brandt", "-o", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["model"] == "kannala_brandt" and summary["rms_px"] < 0.2
    assert set(summary["distortion"]) == {"model", "k1", "k2", "k3", "k4"}
    cf = read_camera(out)
    assert cf.distortion_model == "kannala_brandt"
    assert "--model kannala-brandt" in (cf.provenance.command or "")
    np.testing.assert_allclose(np.asarray(cf.camera.K), K_true, atol=1.0)
    assert abs(cf.camera.distortion.k1 - 0.03) < 0.01
    flat = tmp_path / "flat.png"
    assert (
        main(["undistort", str(tmp_path / "view00.png"), "--camera", str(out), "-o", str(flat)])
        == 0
    )
    det = find_checkerboard(np.asarray(Image.open(flat), dtype=float) / 255.0, (9, 6))
    assert det.found
    for row in np.asarray(det.corners).reshape(6, 9, 2):
        centred = row - row.mean(axis=0)
        assert np.linalg.svd(centred, compute_uv=False)[1] / np.sqrt(9) < 0.3
    capsys.readouterr()
    # --fix names of another model are refused in one line
    assert main([*argv, "--model", "kannala-brandt", "--fix", "p1", "-o", str(out), "--force"]) == 2
    assert "unknown --fix (--model kannala-brandt) 'p1'" in capsys.readouterr().err
    assert main([*argv, "--model", "fisheye", "-o", str(out), "--force"]) == 2
    assert "fisheye" in capsys.readouterr().err
