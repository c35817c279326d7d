"""imageform reconstruct (issue 28): a walk through a room against the truth, the four files,
bad input in one line with nothing written, Ctrl-C."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

import imageform.geometry
from imageform.cli import main
from imageform.geometry import Camera, Reconstruction, rvec_to_matrix
from imageform.io import read_camera, write_camera, write_image
from imageform.workflows._ply import read_points_ply, write_points_ply
from tests import sfm_scenes

pytest.importorskip("cv2")
pytest.importorskip("matplotlib")

SIZE = (320, 240)
K = np.array([[240.0, 0, 159.5], [0, 240.0, 119.5], [0, 0, 1]])


def _leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if ".part" in p.name)


def _read(path: Path) -> list[dict[str, str]]:
    with path.open() as fh:
        return list(csv.DictReader(fh))


@pytest.fixture(scope="module")
def room(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, list]:
    """8 frames of the first half of the room's walk (320 x 240 PNGs) and the camera file."""
    folder = tmp_path_factory.mktemp("room")
    truth = sfm_scenes.poses(16)[:8]
    rng = np.random.default_rng(5)
    (folder / "frames").mkdir()
    for i, pose in enumerate(truth):
        write_image(folder / "frames" / f"view{i}.png", sfm_scenes.render(K, pose, SIZE, rng=rng))
    camera = write_camera(folder / "camera.toml", Camera(K, image_size=SIZE))
    return folder / "frames", camera, truth


@pytest.fixture(scope="module")
def run(
    room: tuple[Path, Path, list], tmp_path_factory: pytest.TempPathFactory
) -> tuple[Path, dict, list]:
    frames, camera, truth = room
    out = tmp_path_factory.mktemp("rec") / "out"
    args = ["reconstruct", str(frames), "--camera", str(camera), "-o", str(out)]
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = main([*args, "--max-features", "1000", "--json"])
    assert code == 0
    return out, json.loads(buf.getvalue()), truth


def test_cameras_against_the_truth(run: tuple[Path, dict, list]) -> None:
    out, doc, truth = run
    assert sorted(p.name for p in out.iterdir()) == [
        "camera.toml", "cameras.csv", "metrics.json", "points.ply", "report.html",
    ]  # fmt: skip
    rows = _read(out / "cameras.csv")
    assert list(rows[0]) == [
        "frame", "name", "registered", "rx", "ry", "rz", "tx", "ty", "tz", "rms_px",
    ]  # fmt: skip
    # natural order: view2.png before view10.png; names are the files'
    assert [r["name"] for r in rows] == [f"view{i}.png" for i in range(8)]
    assert all(r["registered"] == "1" for r in rows), doc["notes"]
    C_est = []
    for r in rows:
        R = np.asarray(rvec_to_matrix([float(r[k]) for k in ("rx", "ry", "rz")]))
        t = np.array([float(r[k]) for k in ("tx", "ty", "tz")])
        C_est.append(-R.T @ t)
    C_true = np.array([-R.T @ t for R, t in truth])
    assert sfm_scenes.align_rms(np.array(C_est), C_true) < 0.01  # 1 % of the path
    assert np.median([float(r["rms_px"]) for r in rows]) < 1.0
    assert doc["registered"] == 8 and doc["registered_share"] == 1.0 and doc["frames"] == 8


def test_points_metrics_and_report(run: tuple[Path, dict, list]) -> None:
    out, doc, _ = run
    ply = read_points_ply(out / "points.ply")
    assert list(ply) == ["x", "y", "z", "red", "green", "blue", "track_length"]
    n = ply["x"].size
    assert n > 300 and ply["red"].dtype == np.uint8
    assert ply["track_length"].min() >= 2
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["format"] == "imageform-reconstruction"
    assert metrics["points"] == n == doc["points"]
    assert metrics["track_length_mean"] == pytest.approx(ply["track_length"].mean())
    assert 0 < metrics["reprojection_px_median"] <= metrics["reprojection_px_rms"] < 1.0
    assert metrics["observations"] == int(ply["track_length"].sum())
    assert set(metrics["seconds"]) == {"read", "reconstruct", "write", "report"}
    assert metrics["options"]["max_features"] == 1000 and metrics["unregistered"] == []
    # the camera file's K held, and checked: a bundle adjustment refining f finds it again
    intr = metrics["intrinsics"]
    assert intr["source"] == "camera file" and not intr["refined"]
    assert intr["focal_px"] == 240.0 and intr["focal_px_fit"] == pytest.approx(240.0, rel=0.02)
    assert not any("fits the frames poorly" in n for n in metrics["notes"])
    html = (out / "report.html").read_text()
    for part in ("Cameras and points", "Reprojection errors", "What failed", "view7.png"):
        assert part in html
    assert html.count("data:image/png;base64,") == 2
    trimesh = pytest.importorskip("trimesh")
    cloud = trimesh.load(out / "points.ply")
    np.testing.assert_allclose(cloud.vertices[:, 0], ply["x"], rtol=1e-6)
    np.testing.assert_array_equal(
        cloud.colors[:, :3], np.column_stack([ply[c] for c in ("red", "green", "blue")])
    )


def test_ply_round_trip_ascii_and_binary(tmp_path: Path) -> None:
    rng = np.random.default_rng(0)
    P = rng.normal(size=(5, 3))
    C = rng.integers(0, 256, (5, 3), dtype=np.uint8)
    n = np.arange(2, 7)
    back = read_points_ply(write_points_ply(tmp_path / "p.ply", P, C, n, comment="a\nb é"))
    np.testing.assert_allclose(np.column_stack([back[a] for a in "xyz"]), P, rtol=1e-6)
    np.testing.assert_array_equal(back["track_length"], n)
    text = "ply\nformat ascii 1.0\nelement vertex 2\nproperty double x\nproperty double y\n"
    text += "property double z\nproperty uchar red\nend_header\n1 2 3 255\n4 5 6 0\n"
    (tmp_path / "a.ply").write_text(text)
    a = read_points_ply(tmp_path / "a.ply")
    assert a["z"].tolist() == [3.0, 6.0] and a["red"].tolist() == [255, 0]
    empty = np.zeros((0, 3))
    e = read_points_ply(
        write_points_ply(tmp_path / "e.ply", empty, empty.astype(np.uint8), np.zeros(0, int))
    )
    assert e["x"].size == 0


# ------------------------------------------------------------------ fast runs, a stand-in


def _blank_frames(folder: Path, n: int, size: tuple[int, int] = (64, 48)) -> Path:
    folder.mkdir()
    for i in range(n):
        write_image(folder / f"f{i}.png", np.full((size[1], size[0], 3), 90, np.uint8))
    return folder


def _fake(images: list, K: object, distortion: object = None, **kw: object) -> Reconstruction:
    """A reconstruction of ``len(images)`` frames, the last not registered."""
    n = len(images)
    R = np.stack([np.eye(3)] * n)
    t = np.array([[0.1 * i, 0, 0] for i in range(n)], float)
    reg = np.ones(n, bool)
    reg[-1] = False
    R[-1], t[-1] = np.nan, np.nan
    P = np.random.default_rng(0).normal(size=(40, 3)) + [0, 0, 5]
    C = np.full((40, 3), 200, np.uint8)
    rms = np.where(reg, 0.3, np.nan)
    notes = [f"frame {n - 1}: PnP found 3 inliers (12 needed)"]
    return Reconstruction(R, t, reg, P, C, np.full(40, 2), rms, notes, np.full(80, 0.3))


@pytest.fixture
def stand_in(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> tuple[Path, Path]:
    monkeypatch.setattr(imageform.geometry, "reconstruct_sequence", _fake)
    frames = _blank_frames(tmp_path / "frames", 4)
    camera = write_camera(tmp_path / "cam.toml", Camera(K, image_size=(64, 48)))
    return frames, camera


def test_unregistered_frames_are_nan_rows_and_reported(
    stand_in: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    frames, camera = stand_in
    out = tmp_path / "out"
    assert main(["reconstruct", str(frames), "--camera", str(camera), "-o", str(out)]) == 0
    rows = _read(out / "cameras.csv")
    assert rows[-1]["registered"] == "0" and rows[-1]["tx"] == "nan" == rows[-1]["rms_px"]
    assert rows[1]["tx"] == "0.1"
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["registered"] == 3 and metrics["unregistered"] == ["f3.png"]
    html = (out / "report.html").read_text()
    assert "PnP found 3 inliers" in html and "not registered: 3 (f3.png)" in html
    assert "PnP found 3 inliers" in capsys.readouterr().err
    # --force replaces a previous reconstruction; --every and --max-frames pick the frames
    args = ["reconstruct", str(frames), "--camera", str(camera), "-o", str(out)]
    assert main([*args, "--force", "--every", "2", "--max-frames", "2"]) == 0
    assert [r["name"] for r in _read(out / "cameras.csv")] == ["f0.png", "f2.png"]


def test_ctrl_c_leaves_the_previous_output(
    stand_in: tuple[Path, Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    import imageform.workflows._reconstruct_report as report

    frames, camera = stand_in
    out = tmp_path / "out"
    args = ["reconstruct", str(frames), "--camera", str(camera), "-o", str(out)]
    assert main(args) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}

    def interrupted(*a: object, **k: object) -> None:
        raise KeyboardInterrupt  # after cameras.csv and points.ply, before the report

    monkeypatch.setattr(report, "write_report", interrupted)
    capsys.readouterr()
    assert main([*args, "--force", "--max-frames", "2"]) == 130
    assert capsys.readouterr().err.strip() == "imageform: interrupted; nothing new was written"
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert _leftovers(tmp_path) == []
    assert (
        main(["reconstruct", str(frames), "--camera", str(camera), "-o", str(tmp_path / "new")])
        == 130
    )
    assert not (tmp_path / "new").exists() and _leftovers(tmp_path) == []


# ------------------------------------------------------------------ bad input


def _one_line_error(args: list[str], out: Path, capsys: pytest.CaptureFixture[str]) -> str:
    capsys.readouterr()
    code = main([*args, "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 1, err
    assert err.count("\n") == 1, err
    assert not out.exists() and _leftovers(out.parent) == []
    return err


def test_bad_input_is_one_line_and_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    camera = write_camera(tmp_path / "cam.toml", Camera(K, image_size=(64, 48)))
    cam = ["--camera", str(camera)]
    out = tmp_path / "out"
    one = _blank_frames(tmp_path / "one", 1)
    assert "1 frame; reconstruct needs at least 2" in _one_line_error(
        ["reconstruct", str(one), *cam], out, capsys
    )
    few = _blank_frames(tmp_path / "few", 3)
    assert "1 frame (one in 3)" in _one_line_error(
        ["reconstruct", str(few), *cam, "--every", "3"], out, capsys
    )
    assert "no texture" in _one_line_error(["reconstruct", str(few), *cam], out, capsys)
    mixed = _blank_frames(tmp_path / "mixed", 2)
    write_image(mixed / "f2.png", np.zeros((40, 64, 3), np.uint8))
    assert "64x40 pixels where" in _one_line_error(["reconstruct", str(mixed), *cam], out, capsys)
    # two unrelated textures: keypoints in both, no verified matches
    rng = np.random.default_rng(1)
    import cv2

    unrelated = tmp_path / "unrelated"
    unrelated.mkdir()
    for i in range(2):
        noise = cv2.GaussianBlur(rng.random((120, 160, 3)).astype(np.float32), (0, 0), 1.5)
        write_image(unrelated / f"f{i}.png", np.clip(noise * 3 - 1, 0, 1))
    big = write_camera(tmp_path / "big.toml", Camera(K, image_size=(160, 120)))
    err = _one_line_error(["reconstruct", str(unrelated), "--camera", str(big)], out, capsys)
    assert "no pair of frames has 30 verified matches" in err
    assert "keypoints a frame: median" in err and "the best pair:" in err
    assert "try --auto-mask" in err
    # the camera file: missing, or for another image size
    missing = ["--camera", str(tmp_path / "nope.toml")]
    assert "nope.toml" in _one_line_error(["reconstruct", str(few), *missing], out, capsys)
    other = write_camera(tmp_path / "other.toml", Camera(K, image_size=(320, 240)))
    err = _one_line_error(["reconstruct", str(few), "--camera", str(other)], out, capsys)
    assert "is for 320 x 240 px images" in err and "64 x 48 px frames" in err
    # --refine-distortion with a lens it cannot refine (a fisheye): before any frame is read
    from imageform.geometry import KannalaBrandt

    fish = write_camera(
        tmp_path / "fish.toml",
        Camera(K, distortion=KannalaBrandt(0.1, 0, 0, 0), image_size=(64, 48)),
    )
    err = _one_line_error(
        ["reconstruct", str(few), "--camera", str(fish), "--refine-distortion"], out, capsys
    )
    assert "fish.toml: --refine-distortion refines one radial term k1" in err
    assert "KannalaBrandt" in err
    # an existing output: refused without --force; --force never replaces a user's folder
    out.mkdir()
    (out / "mine.txt").write_text("keep")
    for extra in ([], ["--force"]):
        capsys.readouterr()
        assert main(["reconstruct", str(few), *cam, "-o", str(out), *extra]) == 1
        assert capsys.readouterr().err.count("\n") == 1
    assert (out / "mine.txt").read_text() == "keep" and len(list(out.iterdir())) == 1


def test_a_video_and_a_glob(stand_in: tuple[Path, Path], tmp_path: Path) -> None:
    """A video's frames are named frame_NNNNNN by their index in the video; a glob's by file."""
    pytest.importorskip("av")
    from imageform.io import VideoWriter

    frames, camera = stand_in
    video = tmp_path / "clip.mkv"
    with VideoWriter(video, fps=10, codec="ffv1") as writer:
        for i in range(6):
            writer.write(np.full((48, 64, 3), 40 * i, np.uint8))
    cam = ["--camera", str(camera)]
    out = tmp_path / "v"
    assert main(["reconstruct", str(video), *cam, "-o", str(out), "--every", "2"]) == 0
    names = [r["name"] for r in _read(out / "cameras.csv")]
    assert names == ["frame_000000", "frame_000002", "frame_000004"]
    out = tmp_path / "g"
    assert main(["reconstruct", str(frames / "f[12].png"), *cam, "-o", str(out)]) == 0
    assert [r["name"] for r in _read(out / "cameras.csv")] == ["f1.png", "f2.png"]


def test_mask_option(
    stand_in: tuple[Path, Path],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """--mask: one image for every frame, passed on as booleans; a wrong size is one line."""
    frames, camera = stand_in
    seen: dict[str, object] = {}

    def spy(images: list, K: object, distortion: object = None, **kw: object) -> Reconstruction:
        seen.update(kw)
        return _fake(images, K, distortion)

    monkeypatch.setattr(imageform.geometry, "reconstruct_sequence", spy)
    mask = np.zeros((48, 64), np.uint8)
    mask[8:40, 8:56] = 255  # an endoscope's round field would do as well
    write_image(tmp_path / "mask.png", mask)
    cam = ["--camera", str(camera)]
    assert main(["reconstruct", str(frames), *cam, "--mask", str(tmp_path / "mask.png"),
                 "-o", str(tmp_path / "out")]) == 0  # fmt: skip
    got = np.asarray(seen["masks"])
    assert got.dtype == bool and np.array_equal(got, mask > 0)
    write_image(tmp_path / "small.png", np.full((20, 30), 255, np.uint8))
    err = _one_line_error(
        ["reconstruct", str(frames), *cam, "--mask", str(tmp_path / "small.png")],
        tmp_path / "o2",
        capsys,
    )
    assert "--mask" in err and "30 x 20 px, the frames 64 x 48 px" in err
    write_image(tmp_path / "zero.png", np.zeros((48, 64), np.uint8))
    err = _one_line_error(
        ["reconstruct", str(frames), *cam, "--mask", str(tmp_path / "zero.png")],
        tmp_path / "o3",
        capsys,
    )
    assert "zero everywhere" in err


def test_keep_overlays_option(
    stand_in: tuple[Path, Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The overlays are left out by default; --keep-overlays passes overlays=False."""
    frames, camera = stand_in
    seen: list[object] = []

    def spy(images: list, K: object, distortion: object = None, **kw: object) -> Reconstruction:
        seen.append(kw["overlays"])
        return _fake(images, K, distortion)

    monkeypatch.setattr(imageform.geometry, "reconstruct_sequence", spy)
    cam = ["--camera", str(camera)]
    assert main(["reconstruct", str(frames), *cam, "-o", str(tmp_path / "a")]) == 0
    assert main(["reconstruct", str(frames), *cam, "--keep-overlays",
                 "-o", str(tmp_path / "b")]) == 0  # fmt: skip
    assert seen == [True, False]


def test_burned_in_text_is_left_out_of_the_frames(
    room: tuple[Path, Path, list], tmp_path: Path
) -> None:
    """Frames written with burned-in text (six lines, the same in every frame): the command
    says how much of the frame stood still and registers the walk as without the text."""
    import contextlib
    import io

    from imageform.io import read_image

    frames, camera, _ = room
    burned = tmp_path / "burned"
    burned.mkdir()
    for p in sorted(frames.iterdir()):
        write_image(burned / p.name, sfm_scenes.burn_in(np.asarray(read_image(p))))
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = main(["reconstruct", str(burned), "--camera", str(camera), "--max-features",
                     "1000", "--json", "-o", str(tmp_path / "out")])  # fmt: skip
    assert code == 0
    doc = json.loads(buf.getvalue())
    said = [n for n in doc["notes"] if "stands still while the camera moves" in n]
    assert said, doc["notes"]
    share = float(said[0].split(" %")[0])
    assert 20.0 < share < 60.0, said  # six lines of text across the top of 320 x 240
    rows = _read(tmp_path / "out" / "cameras.csv")
    assert all(r["registered"] == "1" for r in rows), doc["notes"]


# ------------------------------------------------------------------ without a camera file


@pytest.fixture
def seen_K(monkeypatch: pytest.MonkeyPatch) -> list:
    """The stand-in reconstruction, recording the K and distortion it is given."""
    seen: list = []

    def fake(images: list, K: object, distortion: object = None, **kw: object) -> Reconstruction:
        seen.append((np.asarray(K, float), distortion, kw))
        return _fake(images, K, distortion, **kw)

    monkeypatch.setattr(imageform.geometry, "reconstruct_sequence", fake)
    return seen


def test_without_a_camera_file_k_is_guessed_from_exif_or_the_size(
    seen_K: list, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from PIL import Image

    # PNGs without EXIF: COLMAP's guess, f = 1.2 x max(64, 48) = 76.8 px, center (31.5, 23.5)
    frames = _blank_frames(tmp_path / "frames", 3)
    out = tmp_path / "out"
    assert main(["reconstruct", str(frames), "-o", str(out)]) == 0
    K0, dist, _ = seen_K[-1]
    np.testing.assert_allclose(K0, [[76.8, 0, 31.5], [0, 76.8, 23.5], [0, 0, 1]])
    assert dist is None
    err = capsys.readouterr().err
    assert (
        "no camera file: f = 76.8 px from COLMAP's guess 1.2 x max(width, height) (no EXIF" in err
    )
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["camera"] is None
    assert metrics["intrinsics"]["source"] == "guess"
    assert metrics["intrinsics"]["focal_px_initial"] == pytest.approx(76.8)
    # JPEGs whose EXIF gives a 35 mm equivalent of 26 mm: f = 26 sqrt(64^2 + 48^2) / 43.27
    # = 48.07 px (imageform.io.exif_camera; 43.27 mm the 36 x 24 mm frame's diagonal)
    jpegs = tmp_path / "jpegs"
    jpegs.mkdir()
    ex = Image.Exif()
    ex.get_ifd(0x8769).update({0xA405: 26, 0x920A: 4.3})
    for i in range(3):
        Image.fromarray(np.full((48, 64, 3), 90, np.uint8)).save(jpegs / f"p{i}.jpg", exif=ex)
    assert main(["reconstruct", str(jpegs), "-o", str(tmp_path / "o2")]) == 0
    f_exif = 26 * 80 / np.hypot(36, 24)
    np.testing.assert_allclose(seen_K[-1][0][[0, 1], [0, 1]], [f_exif, f_exif])
    assert "the EXIF 35 mm equivalent focal length of p0.jpg" in capsys.readouterr().err
    metrics = json.loads((tmp_path / "o2" / "metrics.json").read_text())
    assert metrics["intrinsics"]["source"] == "exif"
    # --focal gives it
    assert main(["reconstruct", str(jpegs), "--focal", "55", "-o", str(tmp_path / "o3")]) == 0
    np.testing.assert_allclose(seen_K[-1][0], [[55, 0, 31.5], [0, 55, 23.5], [0, 0, 1]])
    assert "f = 55.0 px from --focal" in capsys.readouterr().err


def test_focal_bad_input(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A usage error (exit 2) in one line, nothing written."""
    camera = write_camera(tmp_path / "cam.toml", Camera(K, image_size=(64, 48)))
    frames = _blank_frames(tmp_path / "frames", 3)
    out = tmp_path / "out"

    def usage(args: list[str]) -> str:
        capsys.readouterr()
        code = main([*args, "-o", str(out)])
        err = capsys.readouterr().err
        assert code == 2 and err.count("\n") == 1, err
        assert not out.exists()
        return err

    err = usage(["reconstruct", str(frames), "--camera", str(camera), "--focal", "50"])
    assert "expected --camera FILE or --focal PX, got both" in err
    for bad in ("0", "-3"):
        assert "expected --focal > 0 pixels" in usage(["reconstruct", str(frames), "--focal", bad])
    for bad in ("nan", "inf"):
        assert "expected --focal as a finite number" in usage(
            ["reconstruct", str(frames), "--focal", bad]
        )


def test_room_without_a_camera_file_at_the_true_focal(
    room: tuple[Path, Path, list], tmp_path: Path
) -> None:
    frames, _, truth = room
    out = tmp_path / "out"
    assert main(["reconstruct", str(frames), "--focal", "240", "-o", str(out),
                 "--max-features", "1000"]) == 0  # fmt: skip
    rows = _read(out / "cameras.csv")
    assert all(r["registered"] == "1" for r in rows)
    C_est = []
    for r in rows:
        R = np.asarray(rvec_to_matrix([float(r[k]) for k in ("rx", "ry", "rz")]))
        C_est.append(-R.T @ np.array([float(r[k]) for k in ("tx", "ty", "tz")]))
    C_true = np.array([-R.T @ t for R, t in truth])
    assert sfm_scenes.align_rms(np.array(C_est), C_true) < 0.01


def test_room_without_a_camera_file_refines_the_guess(
    room: tuple[Path, Path, list], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """PNGs without EXIF: f = 1.2 x 320 = 384 px guessed (the truth 240 px: 60 % off), then
    refined by bundle adjustment to within 2 %; the trajectory within 1 % of the path."""
    frames, _, truth = room
    out = tmp_path / "out"
    assert main(["reconstruct", str(frames), "-o", str(out), "--max-features", "1000"]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    intr = metrics["intrinsics"]
    assert intr["source"] == "guess" and intr["focal_px_initial"] == 384.0 and intr["refined"]
    assert intr["focal_px"] == pytest.approx(240.0, rel=0.02)
    assert "refined by bundle adjustment to f = 24" in capsys.readouterr().err
    # the camera found, for the commands downstream: f and the radial term (the room is
    # rendered without distortion: k1 near 0)
    cam = read_camera(out / "camera.toml").camera
    assert cam.K[0, 0] == pytest.approx(intr["focal_px"], rel=1e-9)
    assert intr["distortion_refined"] and abs(intr["k1"]) < 0.02
    assert cam.distortion is not None and cam.distortion.k1 == pytest.approx(intr["k1"])
    rows = _read(out / "cameras.csv")
    assert all(r["registered"] == "1" for r in rows)
    C_est = []
    for r in rows:
        R = np.asarray(rvec_to_matrix([float(r[k]) for k in ("rx", "ry", "rz")]))
        C_est.append(-R.T @ np.array([float(r[k]) for k in ("tx", "ty", "tz")]))
    C_true = np.array([-R.T @ t for R, t in truth])
    assert sfm_scenes.align_rms(np.array(C_est), C_true) < 0.01


def test_refine_focal_is_asked_with_a_camera_file_or_focal(seen_K: list, tmp_path: Path) -> None:
    camera = write_camera(tmp_path / "cam.toml", Camera(K, image_size=(64, 48)))
    frames = _blank_frames(tmp_path / "frames", 3)
    runs = [
        (["--camera", str(camera)], False),
        (["--camera", str(camera), "--refine-focal"], True),
        (["--focal", "50"], False),
        (["--focal", "50", "--refine-focal"], True),
        ([], True),
    ]
    for i, (args, refine) in enumerate(runs):
        out = tmp_path / f"o{i}"
        assert main(["reconstruct", str(frames), *args, "-o", str(out)]) == 0
        assert seen_K[-1][2]["refine_focal"] is refine, args
        assert json.loads((out / "metrics.json").read_text())["intrinsics"]["refined"] is refine


def test_refine_distortion_is_asked_with_a_camera_file_or_focal(
    seen_K: list, tmp_path: Path
) -> None:
    """COLMAP's SIMPLE_RADIAL k1: refined without a camera file, else on --refine-distortion;
    camera.toml holds the camera the reconstruction ends with (here the stand-in's K)."""
    camera = write_camera(tmp_path / "cam.toml", Camera(K, image_size=(64, 48)))
    frames = _blank_frames(tmp_path / "frames", 3)
    runs = [
        (["--camera", str(camera)], False),
        (["--camera", str(camera), "--refine-distortion"], True),
        (["--focal", "50"], False),
        (["--focal", "50", "--refine-distortion"], True),
        ([], True),
    ]
    for i, (args, refine) in enumerate(runs):
        out = tmp_path / f"o{i}"
        assert main(["reconstruct", str(frames), *args, "-o", str(out)]) == 0
        assert seen_K[-1][2]["refine_distortion"] is refine, args
        intr = json.loads((out / "metrics.json").read_text())["intrinsics"]
        assert intr["distortion_refined"] is refine
        written = read_camera(out / "camera.toml").camera
        np.testing.assert_allclose(written.K, seen_K[-1][0])


def test_a_camera_file_whose_focal_length_fits_poorly_is_flagged(
    room: tuple[Path, Path, list], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The room's frames (f = 240 px) with a camera file at 360 px: one note line."""
    frames, _, _ = room
    wrong = K.copy()
    wrong[0, 0] = wrong[1, 1] = 360.0
    camera = write_camera(tmp_path / "wrong.toml", Camera(wrong, image_size=SIZE))
    out = tmp_path / "out"
    args = ["reconstruct", str(frames), "--camera", str(camera), "-o", str(out)]
    assert main([*args, "--max-features", "1000"]) == 0
    fit = json.loads((out / "metrics.json").read_text())["intrinsics"]["focal_px_fit"]
    assert fit < 0.85 * 360.0
    lines = [ln for ln in capsys.readouterr().err.splitlines() if "fits the frames poorly" in ln]
    assert len(lines) == 1, lines
    assert f"finds f = {fit:.1f} px, the camera's is 360.0 px" in lines[0]
    assert "imageform reconstruct --refine-focal" in lines[0]


def test_room_photographs_with_exif_focal_length(
    room: tuple[Path, Path, list], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The room's frames as JPEGs whose EXIF says 26 mm (35 mm equivalent): f = 26 x 400 /
    43.27 = 240.4 px (the truth 240 px), refined; the trajectory within 1 % of the path."""
    from PIL import Image

    frames, _, truth = room
    jpegs = tmp_path / "jpegs"
    jpegs.mkdir()
    ex = Image.Exif()
    ex.get_ifd(0x8769).update({0xA405: 26})
    for png in sorted(frames.glob("*.png")):
        with Image.open(png) as im:
            im.convert("RGB").save(jpegs / (png.stem + ".jpg"), quality=95, exif=ex)
    out = tmp_path / "out"
    assert main(["reconstruct", str(jpegs), "-o", str(out), "--max-features", "1000"]) == 0
    intr = json.loads((out / "metrics.json").read_text())["intrinsics"]
    assert intr["source"] == "exif" and intr["refined"]
    assert intr["focal_px_initial"] == pytest.approx(26 * 400 / np.hypot(36, 24))
    assert intr["focal_px"] == pytest.approx(240.0, rel=0.02)
    assert "the EXIF 35 mm equivalent focal length of view0.jpg" in capsys.readouterr().err
    rows = _read(out / "cameras.csv")
    assert all(r["registered"] == "1" for r in rows)
    C_est = []
    for r in rows:
        R = np.asarray(rvec_to_matrix([float(r[k]) for k in ("rx", "ry", "rz")]))
        C_est.append(-R.T @ np.array([float(r[k]) for k in ("tx", "ty", "tz")]))
    C_true = np.array([-R.T @ t for R, t in truth])
    assert sfm_scenes.align_rms(np.array(C_est), C_true) < 0.01


def test_a_fisheye_without_a_camera_file_is_the_lens_that_fixes_f(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The C3VD colonoscope (a Kannala-Brandt fisheye, f 199 px; tests/data/endo) without a
    camera file: f and one radial term wander along their valley and do not settle (537.6
    -> 466.1 -> 287.9 -> 421.9 px, k1 -0.43): SIMPLE_RADIAL's f is 421.9 +- 103.3 px (24 %),
    not fixed. The equidistant fisheye tried fixes it, 202.0 +- 6.4 px (3 %), and is kept
    though its tracks' robust cost is the higher (1976 against 1764 px^2): a lens whose f the
    frames fix beats one whose f they do not (sfm-model-choice-2026-12-01e.md). Until then
    the camera file was SIMPLE_RADIAL's 421.9 px."""
    endo = Path(__file__).resolve().parents[1] / "data" / "endo"
    out = tmp_path / "rec"
    args = [str(endo / "*.jpg"), "-o", str(out), "--auto-mask", "--contrast-threshold", "0.01"]
    assert main(["reconstruct", *args]) == 0
    err = capsys.readouterr().err
    assert "the fisheye tried (SIMPLE_RADIAL's f = " in err and "not fixed" in err, err
    intr = json.loads((out / "metrics.json").read_text())["intrinsics"]
    assert intr["model"] == "KANNALA_BRANDT", intr
    assert intr["fisheye"].endswith("kept (the fisheye, its f fixed by the frames)"), intr
    # within 5 % of the colonoscope's f or 3 of its own standard deviations (188.9 +- 6.x px
    # on an AMD EPYC with the packages of 2026-12-02; 202.0 where the test was written)
    assert abs(intr["focal_px"] - 199.2) <= max(0.05 * 199.2, 3 * intr["focal_px_sd"]), intr
    assert intr["focal_fixed"] is True and intr["focal_px_sd"] < 0.1 * intr["focal_px"], intr
    assert "+- " in err and "the focal length is not fixed" not in err, err
    # with the working camera the reconstruction settles: no such note
    again = [*args[:2], str(tmp_path / "rec2"), *args[3:], "--camera", str(endo / "camera.toml")]
    assert main(["reconstruct", *again]) == 0
    err = capsys.readouterr().err
    assert "did not settle" not in err and "ran off" not in err


@pytest.mark.parametrize("last, fixed", [(0.64, True), (0.60, False)])
def test_one_verdict_on_f_in_the_notes_the_report_and_metrics(
    last: float,
    fixed: bool,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The held-out KITTI run's case (sfm-model-choice-2026-12-01e.md): the last restart
    still moved f by more than 5 % and a note said the camera "did not settle" and that the
    frames do not fix it, while metrics.json said f fixed (9 %). Scripted (the guess 76.8 px
    -> 0.8, 0.7 and then 0.64 or 0.60 of it, each model's profile 3 % of the guess): the
    move is said in the one verdict, fixed (8 %) or not (13 %), as the camera note, the
    report and metrics.json say it."""
    from dataclasses import replace

    from imageform.geometry import KannalaBrandt, sfm

    steps = iter((0.8, 0.7, last))

    def one_model(images: list, K: object, distortion: object, kw: dict) -> Reconstruction:
        K1 = np.array(K, float)
        if isinstance(distortion, KannalaBrandt):  # tried where f is not fixed: one frame less
            rec = _fake(images, K1)
            return replace(rec, registered=np.arange(len(images)) < 1, K=K1, focal_sd_px=None)
        K1[:2, :2] *= 76.8 * next(steps) / K1[0, 0]
        return replace(_fake(images, K1), K=K1, focal_sd_px=0.03 * 76.8)

    monkeypatch.setattr(sfm, "_one_model", one_model)
    frames = _blank_frames(tmp_path / "frames", 4)
    out = tmp_path / "out"
    assert main(["reconstruct", str(frames), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    intr = json.loads((out / "metrics.json").read_text())["intrinsics"]
    assert intr["focal_px"] == pytest.approx(76.8 * last)
    sd = np.hypot(0.03 * 76.8, 76.8 * (0.7 - last) / np.sqrt(2))
    assert intr["focal_px_sd"] == pytest.approx(sd) and intr["focal_fixed"] is fixed
    said = ", fixed by the frames" if fixed else ", not fixed by the frames"
    assert f"+- {sd:.1f} px{said}" in err, err  # the camera note
    verdict = "the focal length is fixed" if fixed else "the focal length is not fixed"
    assert f"note: {verdict} by the frames: f = {76.8 * last:.1f} px" in err, err
    assert f"the last restart still moved f from {76.8 * 0.7:.1f} to" in err, err
    assert err.count("the last restart still moved f") == 1, err
    assert "did not settle" not in err and "do not fix" not in err, err
    assert ("is not fixed" in err) is not fixed, err
    report = (out / "report.html").read_text()
    assert f"{76.8 * last:.1f} px +- {sd:.1f} px{said}" in report
