"""Issue 16 for imageform.io: a wrong object where a calibration result is expected is a
TypeError naming ``result`` (it was an AttributeError), and ``read_raw`` checks the pixel
limit from the raw header before LibRaw decodes anything."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imageform.errors import InvalidInputError
from imageform.io import CameraFile, StereoCameraFile


@pytest.mark.parametrize("bad", [None, True, 0, "abc", object()])
def test_from_calibration_refuses_other_objects(bad: object) -> None:
    with pytest.raises(TypeError, match="expected result as a CalibrationResult") as exc:
        CameraFile.from_calibration(bad)  # type: ignore[arg-type]
    assert len(str(exc.value)) <= 200
    with pytest.raises(TypeError, match="expected result as a StereoCalibrationResult"):
        StereoCameraFile.from_calibration(bad)  # type: ignore[arg-type]


def test_read_raw_pixel_limit_from_the_header(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    pytest.importorskip("rawpy")
    from imageform.io import read_raw, write_dng

    path = write_dng(
        tmp_path / "a.dng",
        np.zeros((24, 36), np.uint16),
        cfa_pattern="RGGB",
        black_level=64,
        white_level=4095,
        color_matrix=np.eye(3),
    )
    assert read_raw(path).mosaic.shape == (24, 36)
    with pytest.raises(InvalidInputError, match=r"36 x 24 = 864 px, above the limit of 863 px"):
        read_raw(path, max_pixels=863)
    assert read_raw(path, max_pixels=864).mosaic.shape == (24, 36)
    monkeypatch.setenv("IMAGEFORM_MAX_PIXELS", "100")
    with pytest.raises(InvalidInputError, match="IMAGEFORM_MAX_PIXELS"):
        read_raw(path)
    for bad in (0, -1, 1.5, True, "100"):
        with pytest.raises(InvalidInputError, match="max_pixels"):
            read_raw(path, max_pixels=bad)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="path"):
        read_raw(None)  # type: ignore[arg-type]


def _camera_file() -> CameraFile:
    from imageform.geometry import Camera

    return CameraFile(Camera([[500.0, 0, 320], [0, 500, 240], [0, 0, 1]], image_size=(640, 480)))


@pytest.mark.parametrize("bad", [object(), "abc", True, 0])
def test_camera_file_std_and_provenance_are_typed(bad: object, tmp_path: Path) -> None:
    """Optional fields with a None default (not reached by the fuzz table): a wrong type was
    an AttributeError, a raw ValueError or "'int' object is not iterable"."""
    from imageform.io import write_camera

    cam = _camera_file().camera
    with pytest.raises(TypeError, match="expected std as a mapping"):
        CameraFile(cam, std=bad)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="expected provenance as a Provenance"):
        CameraFile(cam, provenance=bad)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="expected std as a mapping"):
        write_camera(tmp_path / "c.toml", cam, std=bad)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="expected provenance as a Provenance"):
        write_camera(tmp_path / "c.toml", cam, provenance=bad)  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="has_pose"):
        write_camera(tmp_path / "c.toml", cam, has_pose="yes")  # type: ignore[arg-type]
    assert not (tmp_path / "c.toml").exists()


@pytest.mark.parametrize("bad", [None, object(), True, 0, "a.png"])
def test_from_calibration_images_are_a_list_of_paths(bad: object) -> None:
    from tests.fuzz.values import V, resolve

    stereo = resolve(V("stereo_result"))
    cf = CameraFile.from_calibration(stereo.left, images=["a.png", Path("b.png")])
    assert cf.provenance.images == ("a.png", "b.png")
    with pytest.raises(TypeError, match="expected images as a list of image paths"):
        CameraFile.from_calibration(stereo.left, images=bad)  # type: ignore[arg-type]
    for side in ("images_left", "images_right"):
        with pytest.raises(TypeError, match=f"expected {side} as a list of image paths"):
            StereoCameraFile.from_calibration(stereo, **{side: bad})


@pytest.mark.parametrize(
    "text",
    [
        'x = "' + "a" * 100_000 + '"\n',  # a legacy file with an unknown key
        'format = "imageform-camera"\nversion = 1\n[intrinsics]\n' + "k" * 5000 + " = 1\n",
        'format = "imageform-camera"\nversion = 1\n[std]\n' + "k" * 5000 + " = 1\n",
    ],
)
def test_unknown_camera_file_keys_are_one_short_line(tmp_path: Path, text: str) -> None:
    """The unknown-key message listed every valid key (and echoed the key) past 200 chars."""
    from imageform.errors import UnknownOptionError
    from imageform.io import read_camera

    p = tmp_path / "c.toml"
    p.write_text(text)
    with pytest.raises(UnknownOptionError, match="unknown key") as exc:
        read_camera(p)
    msg = str(exc.value)
    assert "\n" not in msg and len(msg) <= 200 + len(str(p)), msg
