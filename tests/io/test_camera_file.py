"""The one camera file: round trips of every field, the earlier formats, and one-line errors."""

from __future__ import annotations

import os
from datetime import UTC, datetime
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.geometry import (
    BrownConrady,
    CalibrationResult,
    Camera,
    DivisionModel,
    KannalaBrandt,
    calibrate_camera,
    checkerboard_points,
    project_points_distorted,
    rvec_to_matrix,
)
from imageform.io import (
    CAMERA_FILE_VERSION,
    DISTORTION_MODELS,
    CameraFile,
    Provenance,
    read_camera,
    write_camera,
)
from imageform.io.camera_file import distortion_name

K0 = np.array([[812.5, 1.25, 330.75], [0.0, 808.0, 241.5], [0.0, 0.0, 1.0]])
R0 = np.asarray(rvec_to_matrix([0.1, -0.25, 0.05]))
T0 = np.array([0.3, -0.2, 4.5])


def _same_camera(a: Camera, b: Camera) -> None:
    np.testing.assert_array_equal(np.asarray(a.K), np.asarray(b.K))
    np.testing.assert_array_equal(np.asarray(a.t), np.asarray(b.t))
    np.testing.assert_array_equal(np.asarray(a.R), np.asarray(b.R))
    assert a.image_size == b.image_size and a.image_plane == b.image_plane
    assert a.distortion == b.distortion


@pytest.mark.parametrize(
    "model",
    [None, BrownConrady(-0.2, 0.05, 1e-3, -2e-4, 0.01), BrownConrady(0.1, k4=0.02, k6=-1e-3)]
    + [KannalaBrandt(0.01, -0.002, 3e-4, -1e-5), DivisionModel(-0.3, 0.04)],
    ids=["none", "brown_conrady", "rational", "kannala_brandt", "division"],
)
def test_round_trip_every_field(tmp_path: Path, model: object) -> None:
    cam = Camera(K0, R0, T0, (640, 480), distortion=model)
    std = {"fx": 0.5, "fy": 0.25, "cx": 0.125, "cy": 0.0625, "rvec": (1e-3, 2e-3, 3e-3)}
    when = datetime(2026, 11, 24, 10, 15, 0, tzinfo=UTC)
    prov = Provenance(
        imageform_version="0.1.0",
        date=when,
        command='imageform calibrate --board 9x6 --square "25 mm"',
        based_on="cam.toml",
        rms_px=0.18,
        views_used=13,
        points_used=54,
        images=("left01.jpg", 'a "quoted"\\name.png'),
        fixed=("skew", "k3"),
    )
    path = write_camera(tmp_path / "cam.toml", CameraFile(cam, True, std, prov))
    back = read_camera(path)
    _same_camera(back.camera, cam)  # floats are written with repr: exact
    assert back.has_pose and back.version == CAMERA_FILE_VERSION and back.path == path
    assert dict(back.std) == std
    assert back.provenance == prov
    assert back.distortion_model == distortion_name(model)
    assert back.distortion_model in DISTORTION_MODELS
    text = path.read_text()
    assert text.count("format = ") == 1 and f"version = {CAMERA_FILE_VERSION}" in text


def test_without_pose_and_size(tmp_path: Path) -> None:
    cam = Camera(K0, R0, T0)  # the pose is not written unless has_pose
    back = read_camera(write_camera(tmp_path / "c.toml", cam))
    assert not back.has_pose and back.camera.image_size is None
    np.testing.assert_array_equal(np.asarray(back.camera.R), np.eye(3))
    assert back.provenance.imageform_version and back.provenance.date is not None
    assert back.provenance.date.tzinfo is not None
    assert "[pose]" not in (tmp_path / "c.toml").read_text()


def test_real_image_plane_round_trip(tmp_path: Path) -> None:
    cam = Camera(K0, image_plane="real")
    assert read_camera(write_camera(tmp_path / "c.toml", cam)).camera.image_plane == "real"


@settings(max_examples=40, deadline=None)
@given(
    f=st.floats(1.0, 1e5),
    aspect=st.floats(0.5, 2.0),
    c=st.tuples(st.floats(-1e3, 1e4), st.floats(-1e3, 1e4)),
    rvec=st.tuples(*(st.floats(-3.0, 3.0),) * 3),
    t=st.tuples(*(st.floats(-1e4, 1e4),) * 3),
    k=st.tuples(*(st.floats(-1.0, 1.0),) * 5),
)
def test_round_trip_property(
    tmp_path_factory: pytest.TempPathFactory,
    f: float,
    aspect: float,
    c: tuple[float, float],
    rvec: tuple[float, float, float],
    t: tuple[float, float, float],
    k: tuple[float, ...],
) -> None:
    """Any valid camera comes back bit for bit."""
    K = np.array([[f, 0.0, c[0]], [0.0, f * aspect, c[1]], [0.0, 0.0, 1.0]])
    cam = Camera(K, np.asarray(rvec_to_matrix(rvec)), t, (1920, 1080), distortion=BrownConrady(*k))
    path = tmp_path_factory.mktemp("prop") / "c.toml"
    _same_camera(read_camera(write_camera(path, cam, has_pose=True)).camera, cam)


def test_from_calibration_matches_the_result(tmp_path: Path) -> None:
    obj = checkerboard_points((9, 6), 25.0)
    K = np.array([[800.0, 0, 320], [0, 800, 240], [0, 0, 1]])
    d = BrownConrady(k1=-0.2, k2=0.05)
    views = [([0.3, 0.1, 0], [-100, -60, 380]), ([-0.2, 0.3, 0.1], [-90, -70, 400])]
    views += [([0.1, -0.35, -0.1], [-110, -50, 390]), ([0.4, 0.3, 0.3], [-80, -90, 450])]
    uv = [project_points_distorted(obj, K, rvec_to_matrix(r), tv, d)[0] for r, tv in views]
    res = calibrate_camera([obj] * 4, uv, (640, 480))
    cf = CameraFile.from_calibration(res, images=("a.png", "b.png", "c.png", "d.png"))
    back = read_camera(write_camera(tmp_path / "cal.toml", cf))
    np.testing.assert_array_equal(np.asarray(back.camera.K), res.K)
    assert back.camera.distortion == res.distortion and back.camera.image_size == (640, 480)
    assert dict(back.std) == pytest.approx(res.std)
    assert back.provenance.rms_px == res.rms and back.provenance.views_used == 4
    assert back.provenance.fixed == res.fixed and not back.has_pose
    _same_camera(res.camera, back.camera)


# ---------------------------------------------------------------- earlier formats


def test_reads_calibration_result_to_toml(tmp_path: Path) -> None:
    """Files written by ``CalibrationResult.to_toml`` (deprecated) keep working."""
    res = CalibrationResult(
        K=K0 * [[1, 0, 1], [1, 1, 1], [1, 1, 1]],
        distortion=BrownConrady(-0.25, 0.1, 1e-3, 2e-4, -0.05),
        image_size=(640, 480),
        rvecs=np.zeros((3, 3)),
        tvecs=np.zeros((3, 3)),
        rms=0.4087,
    )
    path = tmp_path / "old.toml"
    with pytest.warns(DeprecationWarning, match="imageform.io.write_camera"):
        res.to_toml(path)
    cf = read_camera(path)
    assert cf.version == 0 and not cf.has_pose
    np.testing.assert_array_equal(np.asarray(cf.camera.K), res.K)
    assert cf.camera.distortion == res.distortion and cf.camera.image_size == (640, 480)
    assert cf.provenance.rms_px == 0.4087 and cf.provenance.views_used == 3
    with pytest.warns(DeprecationWarning, match="imageform.io.read_camera"):
        assert CalibrationResult.from_toml(path).rms == 0.4087


def test_reads_earlier_pose_and_undistort_files(tmp_path: Path) -> None:
    posed = tmp_path / "posed.toml"  # what `imageform pose` wrote before the versioned file
    posed.write_text(
        "[camera]\nfx = 800.0\nfy = 800.0\ncx = 320.0\ncy = 240.0\nskew = 0.0\n"
        "width = 640\nheight = 480\nk1 = -0.1\nk2 = 0.0\np1 = 0.0\np2 = 0.0\nk3 = 0.0\n"
        "rvec = [0.0, -0.15, 0.0]\nt = [-1.0, 0.0, 0.1]\n"
    )
    cf = read_camera(posed)
    assert cf.has_pose and cf.distortion_model == "brown_conrady"
    np.testing.assert_allclose(np.asarray(cf.camera.R), rvec_to_matrix([0.0, -0.15, 0.0]))
    fisheye = tmp_path / "fe.toml"  # the undistort command's keys: a model name
    fisheye.write_text('model = "kannala-brandt"\nfx = 300\nfy = 300\ncx = 1\ncy = 1\nk1 = 0.01\n')
    assert read_camera(fisheye).camera.distortion == KannalaBrandt(k1=0.01)
    plain = tmp_path / "p.toml"  # project's keys: no distortion at all
    plain.write_text(
        'fx = 500\nfy = 500\ncx = 320\ncy = 240\nt = [0, 0, 2]\nimage_plane = "real"\n'
    )
    cf = read_camera(plain)
    assert cf.camera.distortion is None and cf.has_pose and cf.camera.image_plane == "real"


# ---------------------------------------------------------------- errors


def _v1(body: str) -> str:
    return f'format = "imageform-camera"\nversion = 1\n{body}'


_GOOD = "[intrinsics]\nfx = 500.0\nfy = 500.0\ncx = 320.0\ncy = 240.0\n"


_CASES = [
    (
        _v1(_GOOD.replace("500.0\nfy", "-500.0\nfy")),
        InvalidInputError,
        r"intrinsics\.fx: .* > 0, got -500",
    ),
    (
        _v1(_GOOD.replace("fy = 500.0", "fy = 0")),
        InvalidInputError,
        r"intrinsics\.fy: .* > 0, got 0",
    ),
    (
        _v1(_GOOD.replace("500.0\nfy", "nan\nfy")),
        InvalidInputError,
        r"intrinsics\.fx: expected a finite",
    ),
    (
        _v1(_GOOD.replace("500.0\nfy", "inf\nfy")),
        InvalidInputError,
        r"intrinsics\.fx: expected a finite",
    ),
    (
        _v1(_GOOD.replace("500.0\nfy", "true\nfy")),
        InvalidInputError,
        r"intrinsics\.fx: expected a number",
    ),
    (
        _v1(_GOOD + "focal = 3\n"),
        UnknownOptionError,
        r"unknown key\(s\) intrinsics\.focal; valid in \[intrinsics\]: fx, fy",
    ),
    (
        _v1(_GOOD + "[lens]\nf = 1\n"),
        UnknownOptionError,
        r"unknown key\(s\) lens; valid: format, version, image",
    ),
    (
        _v1("[intrinsics]\nfx = 1.0\n"),
        InvalidInputError,
        r"intrinsics: missing fy, cx, cy",
    ),
    (
        _v1(_GOOD + '[distortion]\nmodel = "fisheye"\n'),
        UnknownOptionError,
        r"distortion\.model: unknown distortion model 'fisheye'; valid: none, brown_conrady",
    ),
    (
        _v1(_GOOD + '[distortion]\nmodel = "division"\np1 = 0.1\n'),
        InvalidInputError,
        r"distortion\.p1: not a coefficient of the division model \(k1, k2\)",
    ),
    (
        _v1(_GOOD + "[distortion]\nk1 = 0.1\n"),
        InvalidInputError,
        r"distortion\.model: missing",
    ),
    (
        _v1(_GOOD + "[pose]\nR = [[1, 0, 0], [0, 1, 0], [0, 0, 2]]\nt = [0, 0, 0]\n"),
        InvalidInputError,
        r"pose\.R: expected a rotation matrix",
    ),
    (
        _v1(_GOOD + "[pose]\nR = [[1, 0, 0], [0, 1, 0], [0, 0, -1]]\nt = [0, 0, 0]\n"),
        InvalidInputError,
        r"pose\.R: expected a proper rotation .* det R = -1",
    ),
    (
        _v1(_GOOD + "[pose]\nR = [[1, 0, 0], [0, 1, 0]]\nt = [0, 0, 0]\n"),
        InvalidInputError,
        r"pose\.R: expected 3 rows",
    ),
    (
        _v1(
            _GOOD
            + "[pose]\nrvec = [0, 0, 0]\nR = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\nt = [0, 0, 0]\n"
        ),
        InvalidInputError,
        r"pose\.R: give the rotation as R or rvec, not both",
    ),
    (
        _v1(_GOOD + "[pose]\nrvec = [0, 0, 0]\n"),
        InvalidInputError,
        r"pose\.t: missing",
    ),
    (
        _v1(_GOOD + "[pose]\nrvec = [0, 0]\nt = [0, 0, 1]\n"),
        InvalidInputError,
        r"pose\.rvec: expected a list of 3 numbers",
    ),
    (
        _v1(_GOOD + "[std]\nfx = -1.0\n"),
        InvalidInputError,
        r"std\.fx: expected a number >= 0",
    ),
    (
        _v1(_GOOD + "[std]\nk1 = 0.1\n"),
        InvalidInputError,
        r"std\.k1: a standard deviation of a parameter this camera does not have",
    ),
    (
        _v1(_GOOD + "[image]\nwidth = 640\n"),
        InvalidInputError,
        r"image: expected both width and height",
    ),
    (
        _v1(_GOOD + "[image]\nwidth = 640\nheight = 0\n"),
        InvalidInputError,
        r"image\.height: expected an integer >= 1",
    ),
    (
        _v1(_GOOD + "[provenance]\nrms_px = -1\n"),
        InvalidInputError,
        r"provenance\.rms_px: expected a number >= 0",
    ),
    (
        _v1(_GOOD + '[provenance]\ndate = "yesterday"\n'),
        InvalidInputError,
        r"provenance\.date: expected a date-time",
    ),
    (
        _GOOD.replace("[intrinsics]\n", 'format = "imageform-camera"\nversion = 2\n[intrinsics]\n'),
        InvalidInputError,
        r"version: version 2 is newer than this imageform reads \(1\); upgrade imageform",
    ),
    (
        'format = "other"\nversion = 1\n' + _GOOD,
        InvalidInputError,
        r"format: expected 'imageform-camera'",
    ),
    (
        'format = "imageform-camera"\n' + _GOOD,
        InvalidInputError,
        r"version: missing",
    ),
    (
        "fx = 1\nfy = 1\ncx = 0\ncy = 0\nfocal = 3\n",
        UnknownOptionError,
        r"unknown key\(s\) focal; valid: fx, fy, .* version = 1\)",
    ),
    (
        "fx = -500\nfy = 500\ncx = 0\ncy = 0\n",
        InvalidInputError,
        r": fx: expected a focal length in pixels > 0, got -500",
    ),
    (
        "[camera]\nfx = 1\n",
        InvalidInputError,
        r"camera: missing fy, cx, cy",
    ),
    (
        "[camera]\nfx = 1\nfy = 1\ncx = 0\ncy = 0\nk1 = 0.1\nmodel = 'division'\np2 = 1\n",
        InvalidInputError,
        r"camera\.p2: not a coefficient of the division model",
    ),
    (
        "fx = = 1",
        InvalidInputError,
        r"not valid TOML",
    ),
    (  # tomllib raises ValueError past Python's 4300-digit integer limit
        "fx = " + "1" * 5000 + "\n",
        InvalidInputError,
        r"not valid TOML: Exceeds the limit \(4300 digits\)",
    ),
]


@pytest.mark.parametrize(("text", "error", "match"), _CASES)
def test_errors_name_the_file_and_the_key(
    tmp_path: Path, text: str, error: type[Exception], match: str
) -> None:
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(error, match=match) as info:
        read_camera(path)
    msg = str(info.value)
    assert msg.startswith(str(path)) and "\n" not in msg


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(InvalidInputError, match=r"camera file .*nope.toml does not exist"):
        read_camera(tmp_path / "nope.toml")


def test_odd_paths_are_refused_in_one_line(tmp_path: Path) -> None:
    """A FIFO, a folder and a name the file system refuses: one line, the name shortened."""
    import os

    fifo = tmp_path / "cam.toml"
    os.mkfifo(fifo)
    with pytest.raises(InvalidInputError, match=r"cam.toml is a FIFO"):
        read_camera(fifo)
    with pytest.raises(InvalidInputError, match=r"is a folder"):
        read_camera(tmp_path)
    long = tmp_path / ("x" * 300 + ".toml")
    with pytest.raises(InvalidInputError) as info:
        read_camera(long)
    msg = str(info.value)
    assert "\n" not in msg and len(msg) < 200 and "xxx..." in msg


def test_writing_is_atomic(tmp_path: Path) -> None:
    """A camera that cannot be written leaves the previous file untouched and no temporary."""
    path = write_camera(tmp_path / "cam.toml", Camera(K0))
    before = path.read_bytes()
    with pytest.raises(InvalidInputError, match="rms_px"):  # refused when built (issue 25)
        Provenance(rms_px=float("nan"))
    bad = Provenance()
    object.__setattr__(bad, "rms_px", float("nan"))  # past the check: the writer refuses it
    with pytest.raises(InvalidInputError, match="rms_px"):
        write_camera(path, CameraFile(Camera(K0)), provenance=bad)
    assert path.read_bytes() == before and os.listdir(tmp_path) == ["cam.toml"]


def test_camera_file_refuses_bad_fields() -> None:
    with pytest.raises(InvalidInputError, match="Camera"):
        CameraFile(K0)  # type: ignore[arg-type]
    with pytest.raises(UnknownOptionError, match="unknown key"):
        CameraFile(Camera(K0), std={"focal": 1.0})
    assert set(DISTORTION_MODELS) == {"none", "brown_conrady", "kannala_brandt", "division"}


DOCS = Path(__file__).resolve().parents[2] / "docs"


@pytest.mark.parametrize("page", sorted(DOCS.glob("*.md")), ids=lambda p: p.name)
def test_camera_files_in_the_docs_are_valid(page: Path, tmp_path: Path) -> None:
    """Every complete camera file shown in the docs (a TOML block with the format marker)
    is read without error."""
    import re

    blocks = [
        b
        for b in re.findall(r"```toml\n(.*?)```", page.read_text(), re.DOTALL)
        if 'format = "imageform-camera"' in b
    ]
    for i, block in enumerate(blocks):
        path = tmp_path / f"{page.stem}-{i}.toml"
        path.write_text(block)
        cf = read_camera(path)
        assert cf.version == CAMERA_FILE_VERSION and cf.camera.image_size == (640, 480)
