"""A photograph's EXIF camera and its focal length in pixels (``imageform.io.exif_camera``).

The files are written here with Pillow, their EXIF set tag by tag (Exif 2.3 numbers). The
focal length in pixels is checked against the 35 mm equivalent's definition worked by hand
(the 36 x 24 mm frame's diagonal is sqrt(36^2 + 24^2) = 43.2666 mm).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from imageform.errors import InvalidInputError
from imageform.io import ExifCamera, exif_camera
from imageform.io.exif import FULL_FRAME_DIAGONAL_MM

Image = pytest.importorskip("PIL.Image")


def _photo(path: Path, size: tuple[int, int] = (400, 300), **tags: object) -> Path:
    """A JPEG of ``size`` (w, h) with EXIF: top-level tags by number in ``tags['top']``,
    Exif IFD tags in ``tags['exif']``."""
    ex = Image.Exif()
    for k, v in dict(tags.get("top", {})).items():  # type: ignore[call-overload]
        ex[k] = v
    ex.get_ifd(0x8769).update(dict(tags.get("exif", {})))  # type: ignore[call-overload]
    Image.fromarray(np.zeros((size[1], size[0], 3), np.uint8)).save(path, exif=ex)
    return path


PHONE = {0xA405: 24, 0x920A: 6.81, 0x829D: 1.85, 0x829A: 1 / 120, 0x8827: 50,
         0xA434: "back camera 6.81mm f/1.85"}  # fmt: skip


def test_full_frame_diagonal() -> None:
    assert abs(FULL_FRAME_DIAGONAL_MM - 43.2666) < 1e-4


def test_focal_length_from_the_35mm_equivalent(tmp_path: Path) -> None:
    """A 400 x 300 image (diagonal 500 px) at a 24 mm equivalent: 24 x 500 / 43.2666 =
    277.35 px; the same photograph stored on its side (EXIF orientation 6) has the same."""
    cam = exif_camera(_photo(tmp_path / "a.jpg", top={0x010F: "Google", 0x0110: "Pixel 7"},
                             exif=PHONE))  # fmt: skip
    assert isinstance(cam, ExifCamera) and cam.found
    assert cam.focal_length_px == pytest.approx(24 * 500 / 43.2666, rel=1e-6)
    assert cam.focal_length_px == pytest.approx(277.35, abs=0.01)
    assert cam.focal_length_px_source == "35 mm equivalent"
    assert (cam.make, cam.model) == ("Google", "Pixel 7")
    assert cam.lens_model == "back camera 6.81mm f/1.85"
    assert (cam.focal_length_mm, cam.equivalent_focal_length_mm) == (6.81, 24.0)
    assert cam.f_number == pytest.approx(1.85) and cam.iso == 50
    assert cam.exposure_time_s == pytest.approx(1 / 120)
    assert (cam.width_px, cam.height_px) == (400, 300)
    assert cam.describe() == (
        "Google Pixel 7, back camera 6.81mm f/1.85; 6.81 mm (35 mm equivalent 24 mm), f/1.85, "
        "1/120 s, ISO 50"
    )
    turned = exif_camera(_photo(tmp_path / "b.jpg", top={0x0112: 6}, exif=PHONE))
    assert (turned.width_px, turned.height_px) == (300, 400)
    assert turned.focal_length_px == pytest.approx(cam.focal_length_px)


def test_resizing_scales_the_estimate(tmp_path: Path) -> None:
    """The diagonal scales with the image: half the size, half the focal length in px."""
    big = exif_camera(_photo(tmp_path / "big.jpg", (800, 600), exif={0xA405: 35}))
    small = exif_camera(_photo(tmp_path / "small.jpg", (400, 300), exif={0xA405: 35}))
    assert big.focal_length_px == pytest.approx(2 * small.focal_length_px)  # type: ignore[operator]


def test_focal_plane_resolution_alone_gives_no_estimate(tmp_path: Path) -> None:
    """Without a 35 mm equivalent there is no estimate: the focal-plane resolution describes
    the camera's own image and is wrong on resized files (module notes)."""
    cam = exif_camera(_photo(tmp_path / "c.jpg", top={0x010F: "Canon", 0x0110: "Canon EOS 6D"},
                             exif={0x920A: 17.0, 0xA20E: 1520.0, 0xA210: 3}))  # fmt: skip
    assert cam.found and cam.focal_length_mm == 17.0
    assert cam.focal_length_px is None and cam.focal_length_px_source is None
    assert cam.describe() == "Canon Canon EOS 6D; 17 mm"


@pytest.mark.parametrize("value", [0, -5, float("nan"), "abc"])
def test_unusable_values_are_left_out(tmp_path: Path, value: object) -> None:
    exif = {0xA405: value, 0x829A: value} if not isinstance(value, str) else {0xA434: ""}
    cam = exif_camera(_photo(tmp_path / "d.jpg", top={0x010F: "X"}, exif=exif))
    assert cam.focal_length_px is None and cam.exposure_time_s is None


def test_files_without_exif(tmp_path: Path) -> None:
    from imageform.io import write_image

    png = tmp_path / "a.png"
    write_image(png, np.zeros((8, 8, 3), np.uint8))
    npy = tmp_path / "a.npy"
    np.save(npy, np.zeros((8, 8, 3), np.float32))
    plain = tmp_path / "plain.jpg"
    Image.fromarray(np.zeros((8, 8, 3), np.uint8)).save(plain)
    for p in (png, npy, plain):
        cam = exif_camera(p)
        assert not cam.found and cam.focal_length_px is None and cam.make is None
        assert (cam.width_px, cam.height_px) == (8, 8)


def test_bad_input_is_one_line(tmp_path: Path) -> None:
    with pytest.raises(InvalidInputError) as err:
        exif_camera(tmp_path / "missing.jpg")
    assert "\n" not in str(err.value)
    junk = tmp_path / "junk.jpg"
    junk.write_text("not an image")
    with pytest.raises(InvalidInputError):
        exif_camera(junk)


def test_info_and_vanishing_report_it(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from imageform.cli import main

    photo = _photo(tmp_path / "p.jpg", top={0x010F: "Google", 0x0110: "Pixel 7"}, exif=PHONE)
    assert main(["info", str(photo)]) == 0
    out = capsys.readouterr().out
    assert "camera (EXIF): Google Pixel 7" in out
    assert "focal length ~ 277 px (from the EXIF's 35 mm equivalent" in out
    assert main(["info", str(photo), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["exif_camera"]["focal_length_px"] == pytest.approx(277.35, abs=0.01)
    assert "found" not in data["exif_camera"]


def test_vanishing_compares_its_focal_length_with_the_exif(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A rendered room seen by f = 700 px (768 x 512), saved with a 35 mm equivalent of 33 mm
    (704 px): the vanishing points' f (within 3 % of 700, as in test_line_segments_vp) is
    reported against it."""
    from imageform.cli import main
    from imageform.geometry import camera_rotation
    from tests.geometry.scene_render import render_manhattan

    K = np.array([[700.0, 0.0, 383.5], [0.0, 700.0, 255.5], [0.0, 0.0, 1.0]])
    img = render_manhattan(K, camera_rotation(0.25, 0.5, 0.03), np.zeros(3), seed=3)
    eq = 700.0 * FULL_FRAME_DIAGONAL_MM / math.hypot(768, 512)  # 32.8 mm: 33 mm in the EXIF
    p = tmp_path / "room.jpg"
    ex = Image.Exif()
    ex.get_ifd(0x8769).update({0xA405: round(eq)})
    Image.fromarray((img * 255).round().astype(np.uint8)).save(p, exif=ex, quality=95)
    assert main(["vanishing", str(p)]) == 0
    out = capsys.readouterr().out
    assert "EXIF: f ~ 704 px (from its 35 mm equivalent); the vanishing points' f is" in out
    assert main(["vanishing", str(p), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["exif_focal_length_source"] == "35 mm equivalent"
    assert data["exif_focal_length_px"] == pytest.approx(33 * math.hypot(768, 512) / 43.2666)
    assert data["K"][0][0] == pytest.approx(700.0, rel=0.03)
