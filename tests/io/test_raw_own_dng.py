"""The DNG imageform writes develops without the ``raw`` extra (issue 25).

``imageform simulate --raw`` writes a DNG; ``imageform develop`` of that file needed rawpy
(LibRaw), which README's install does not bring. Without rawpy, :func:`read_raw` reads a DNG
with tifffile, to the values LibRaw gives.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

from imageform.errors import ImageformError
from imageform.io import develop, read_raw, write_dng

#: XYZ (D65) to camera RGB of a made-up camera (rows: R, G, B).
CM = np.array([[1.20, -0.30, -0.10], [-0.40, 1.30, 0.10], [-0.05, 0.20, 0.60]])


def _mosaic(seed: int = 0, shape: tuple[int, int] = (12, 16)) -> np.ndarray:
    return np.random.default_rng(seed).integers(64, 4096, size=shape).astype(np.uint16)


@pytest.mark.parametrize("pattern", ["RGGB", "BGGR", "GRBG", "GBRG"])
def test_own_dng_reads_without_rawpy(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, pattern: str
) -> None:
    mosaic = _mosaic()
    path = write_dng(
        tmp_path / "x.dng",
        mosaic,
        cfa_pattern=pattern,
        black_level=64,
        white_level=4095,
        color_matrix=CM,
        as_shot_neutral=(0.5, 1.0, 0.25),
        camera_model="bench camera",
    )
    monkeypatch.setitem(sys.modules, "rawpy", None)
    raw = read_raw(path)
    assert raw.metadata["reader"] == "tifffile"
    np.testing.assert_array_equal(raw.mosaic, mosaic)
    assert raw.mosaic.dtype == np.uint16
    assert raw.cfa_pattern == pattern
    np.testing.assert_array_equal(raw.black_level, np.full((2, 2), 64.0))
    assert raw.white_level == 4095.0
    np.testing.assert_allclose(raw.white_balance, [2.0, 1.0, 4.0])
    np.testing.assert_allclose(raw.xyz_to_camera, CM, atol=1e-6)
    assert raw.calibration_illuminant == "D65"
    assert raw.metadata["camera_model"] == "bench camera"
    dev = develop(raw)
    assert dev.image.shape == (12, 16, 3)


def test_own_dng_same_values_as_libraw(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    pytest.importorskip("rawpy")
    path = write_dng(
        tmp_path / "x.dng",
        _mosaic(1, (64, 96)),  # LibRaw refuses images this side of 22 pixels
        black_level=64,
        white_level=4095,
        color_matrix=CM,
        as_shot_neutral=(0.6, 1.0, 0.3),
    )
    libraw = read_raw(path)
    monkeypatch.setitem(sys.modules, "rawpy", None)
    own = read_raw(path)
    np.testing.assert_array_equal(own.mosaic, libraw.mosaic)
    np.testing.assert_array_equal(own.black_level, libraw.black_level)
    assert own.white_level == libraw.white_level
    assert own.cfa_pattern == libraw.cfa_pattern
    np.testing.assert_allclose(own.white_balance, libraw.white_balance, rtol=1e-6)
    np.testing.assert_allclose(own.xyz_to_camera, libraw.xyz_to_camera, atol=1e-9)
    # LibRaw's rgb_cam (float32) by LibRaw's own formula and constants
    np.testing.assert_allclose(own.camera_to_srgb, libraw.camera_to_srgb, atol=1e-5)
    np.testing.assert_allclose(
        own.metadata["daylight_white_balance"],
        libraw.metadata["daylight_white_balance"],
        rtol=1e-5,
    )
    np.testing.assert_allclose(develop(own).image, develop(libraw).image, atol=1e-5)


def test_develop_command_without_rawpy(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from imageform.cli import main
    from imageform.io import read_image

    path = write_dng(
        tmp_path / "x.dng", _mosaic(2), black_level=64, white_level=4095, color_matrix=CM
    )
    monkeypatch.setitem(sys.modules, "rawpy", None)
    assert main(["develop", str(path), "-o", str(tmp_path / "x.png")]) == 0
    assert read_image(tmp_path / "x.png").shape == (12, 16, 3)
    # a raw file that is not such a DNG still names the extra, in one line
    other = tmp_path / "y.dng"
    other.write_bytes(b"II*\x00" + bytes(64))
    assert main(["develop", str(other), "-o", str(tmp_path / "y.png")]) == 1
    err = capsys.readouterr().err
    assert 'pip install "imageform[raw]"' in err and err.count("\n") == 1
    assert not (tmp_path / "y.png").exists()


def test_cropped_dng_reads_without_rawpy_as_libraw(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """An ActiveArea (masked margins cut) is read without LibRaw too, to LibRaw's values; a
    file that is no DNG still needs the extra."""
    import tifffile

    path = write_dng(tmp_path / "x.dng", _mosaic(3, (64, 96)), white_level=4095, color_matrix=CM)
    with tifffile.TiffFile(path) as tf:
        tags = [
            (t.code, t.dtype, t.count, t.value, True) for t in tf.pages[0].tags if t.code >= 33421
        ]
        data = tf.pages[0].asarray()
    cropped = tmp_path / "cropped.dng"
    tifffile.imwrite(
        cropped, data, photometric=32803, extratags=[*tags, (50829, 3, 4, (2, 4, 62, 92), True)]
    )
    libraw = read_raw(cropped) if importlib.util.find_spec("rawpy") else None
    monkeypatch.setitem(sys.modules, "rawpy", None)
    own = read_raw(cropped)
    np.testing.assert_array_equal(own.mosaic, data[2:62, 4:92])
    if libraw is not None:
        np.testing.assert_array_equal(own.mosaic, libraw.mosaic)
        assert own.cfa_pattern == libraw.cfa_pattern
    other = tmp_path / "y.nef"
    other.write_bytes(b"II*\x00" + bytes(64))
    with pytest.raises(ImageformError, match=r"imageform\[raw\]"):
        read_raw(other)


def test_own_dng_orientation_without_rawpy(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import tifffile

    path = write_dng(tmp_path / "x.dng", _mosaic(), white_level=4095, color_matrix=CM)
    with tifffile.TiffFile(path) as tf:
        tags = [(t.code, t.dtype, t.count, t.value, True) for t in tf.pages[0].tags]
        data = tf.pages[0].asarray()
    turned = tmp_path / "turned.dng"
    extra = [t for t in tags if t[0] >= 33421] + [(274, 3, 1, 8, True)]  # EXIF 8: 90° anticlockwise
    tifffile.imwrite(turned, data, photometric=32803, extratags=extra)
    monkeypatch.setitem(sys.modules, "rawpy", None)
    raw = read_raw(turned)
    assert raw.orientation == 5  # LibRaw's flip code for it
    dev = develop(raw)
    assert dev.image.shape == (16, 12, 3)
    np.testing.assert_array_equal(dev.image, np.rot90(develop(raw, orient=False).image))
