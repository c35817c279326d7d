"""Image IO: PNG 8/16-bit round trips (own codec and Pillow), TIFF float, .npy, errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imageform.errors import InvalidInputError
from imageform.io import read_image, read_png, write_image, write_png

RNG = np.random.default_rng(40)


@pytest.mark.parametrize("channels", [1, 2, 3, 4])
@pytest.mark.parametrize("dtype", [np.uint8, np.uint16])
def test_png_round_trip(tmp_path: Path, channels: int, dtype: type) -> None:
    a = RNG.integers(0, np.iinfo(dtype).max + 1, (7, 9, channels)).astype(dtype)
    write_png(tmp_path / "a.png", a)
    b = read_png(tmp_path / "a.png")
    assert b.dtype == dtype
    np.testing.assert_array_equal(b, a)


def test_png_16bit_cross_check_opencv(tmp_path: Path) -> None:
    # Cross-check: OpenCV reads our 16-bit PNG identically (BGR order), and we read its.
    cv2 = pytest.importorskip("cv2")
    a = RNG.integers(0, 65536, (6, 5, 3)).astype(np.uint16)
    write_png(tmp_path / "a.png", a)
    np.testing.assert_array_equal(
        cv2.imread(str(tmp_path / "a.png"), cv2.IMREAD_UNCHANGED), a[..., ::-1]
    )
    cv2.imwrite(str(tmp_path / "b.png"), a[..., ::-1])  # OpenCV uses adaptive row filters
    np.testing.assert_array_equal(read_png(tmp_path / "b.png"), a)


def test_png_8bit_read_by_pillow(tmp_path: Path) -> None:
    from PIL import Image

    a = RNG.integers(0, 256, (5, 4, 3)).astype(np.uint8)
    Image.fromarray(a).save(tmp_path / "p.png")
    np.testing.assert_array_equal(read_image(tmp_path / "p.png"), a)


def test_float_quantisation_and_no_silent_clipping(tmp_path: Path) -> None:
    write_image(tmp_path / "q.png", np.array([[[0.0, 0.5, 1.0]]]), bits=8)
    assert read_image(tmp_path / "q.png").tolist() == [[[0, 128, 255]]]
    with pytest.raises(InvalidInputError, match="outside"):
        write_image(tmp_path / "r.png", np.array([[[0.0, 1.2, 1.0]]]))
    write_image(tmp_path / "r.png", np.array([[[0.0, 1.2, -1.0]]]), clip=True)
    assert read_image(tmp_path / "r.png").tolist() == [[[0, 255, 0]]]
    with pytest.raises(InvalidInputError, match="NaN"):
        write_image(tmp_path / "s.png", np.array([[[0.0, np.nan, 1.0]]]))
    with pytest.raises(InvalidInputError, match="PNG bit depth"):
        write_image(tmp_path / "s.png", np.zeros((2, 2, 3)), bits=12)


def test_tiff_and_npy_exact(tmp_path: Path) -> None:
    a = RNG.normal(size=(4, 5, 3)).astype(np.float32) * 50
    write_image(tmp_path / "a.tif", a)
    np.testing.assert_array_equal(read_image(tmp_path / "a.tif"), a)
    write_image(tmp_path / "a.npy", a.astype(np.float64))
    np.testing.assert_array_equal(read_image(tmp_path / "a.npy"), a.astype(np.float64))


def test_errors(tmp_path: Path) -> None:
    with pytest.raises(InvalidInputError, match=r"unknown image file type '\.jpg'"):
        read_image(tmp_path / "a.jpg")
    with pytest.raises(InvalidInputError, match="does not exist"):
        read_image(tmp_path / "missing.png")
    (tmp_path / "fake.png").write_bytes(b"not a png")
    with pytest.raises(InvalidInputError, match="not a PNG"):
        read_image(tmp_path / "fake.png")
    with pytest.raises(InvalidInputError, match="uint8 or uint16"):
        write_png(tmp_path / "x.png", np.zeros((2, 2, 3), np.int32))
