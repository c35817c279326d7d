"""HEIF/HEIC images (what phones write) read through libheif (the ``heif`` extra).

Files are written here with pillow-heif (libheif's encoder): 8-bit and 10-bit RGB, grey,
RGBA, an embedded Display P3 profile, an ``nclx`` description of P3.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imageform.errors import InvalidInputError
from imageform.io import (
    DeclaredColorSpace,
    icc_profile,
    image_color_space,
    image_info,
    read_image,
    write_image,
)

pillow_heif = pytest.importorskip("pillow_heif")


def _smooth(h: int = 48, w: int = 64, top: int = 255) -> np.ndarray:
    v, u = np.mgrid[0:h, 0:w] / np.array([h, w])[:, None, None]
    rgb = np.stack([u, v, 0.5 * (u + v)], axis=-1)
    return np.round(rgb * top).astype(np.uint8 if top == 255 else np.uint16)


def _heic(path: Path, a: np.ndarray, mode: str, **kw: object) -> Path:
    h = pillow_heif.from_bytes(mode=mode, size=(a.shape[1], a.shape[0]), data=a.tobytes())
    h.save(path, quality=-1, **kw)  # lossless
    return path


def test_8_and_10_bit(tmp_path: Path) -> None:
    a = _smooth()
    got = read_image(_heic(tmp_path / "a.heic", a, "RGB"))
    assert got.dtype == np.uint8 and got.shape == (48, 64, 3)
    err = np.abs(got.astype(int) - a)  # "lossless" HEVC still goes through Y'CbCr
    assert err.max() <= 8 and err.mean() < 1.5
    deep = _smooth(top=65535) & np.uint16(0xFFC0)  # 10 significant bits, as libheif scales
    p = _heic(tmp_path / "b.heif", deep, "RGB;16")
    info = image_info(p)
    assert (info.width, info.height, info.channels, info.dtype, info.format) == (
        64, 48, 3, "uint16", "heif")  # fmt: skip
    got16 = read_image(p)
    assert got16.dtype == np.uint16 and got16.shape == (48, 64, 3)
    assert np.abs(got16.astype(int) - deep).max() < 65535 * 0.02


def test_grey_and_alpha(tmp_path: Path) -> None:
    g = _smooth()[..., 0]
    grey = read_image(_heic(tmp_path / "g.heic", np.ascontiguousarray(g), "L"))
    assert grey.shape[-1] in (1, 3)  # libheif may hand a monochrome image back as RGB
    rgba = np.concatenate([_smooth(), np.full((48, 64, 1), 255, np.uint8)], axis=-1)
    rgba[0, 0, 3] = 0
    p = _heic(tmp_path / "t.heic", rgba, "RGBA")
    with pytest.raises(InvalidInputError, match="transparent"):
        read_image(p)
    assert read_image(p, alpha="keep").shape == (48, 64, 4)
    assert read_image(p, alpha="drop").shape == (48, 64, 3)


def test_declared_spaces(tmp_path: Path) -> None:
    a = _smooth()
    p = _heic(tmp_path / "p3.heic", a, "RGB", icc_profile=icc_profile("display_p3"))
    assert image_color_space(p) == DeclaredColorSpace("display_p3", "icc", "sP3")
    n = _heic(tmp_path / "n.heic", a, "RGB",
              nclx_profile={"color_primaries": 12, "transfer_characteristics": 13,
                            "matrix_coefficients": 6, "full_range_flag": 1})  # fmt: skip
    got = image_color_space(n)
    assert got.name == "display_p3" and got.source == "nclx"


def test_convert_reads_a_phone_s_p3_heic(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    from imageform.cli import main
    from imageform.color import convert

    a = _smooth()
    p = _heic(tmp_path / "IMG_0001.HEIC", a, "RGB", icc_profile=icc_profile("display_p3"))
    out = tmp_path / "lab.tif"
    assert main(["convert", str(p), "-o", str(out), "--to", "lab"]) == 0
    assert "declares display_p3 in its ICC profile" in capsys.readouterr().err
    want = np.asarray(convert(read_image(p), "display_p3", "lab"))
    np.testing.assert_allclose(read_image(out), want, atol=1e-3)


def test_limits_and_errors(tmp_path: Path) -> None:
    p = _heic(tmp_path / "a.heic", _smooth(), "RGB")
    with pytest.raises(InvalidInputError, match="pixels"):
        read_image(p, max_pixels=100)
    bad = tmp_path / "bad.heic"
    bad.write_bytes(b"\0\0\0\x18ftypheic" + b"\0" * 40)
    with pytest.raises(InvalidInputError, match=r"cannot read .*bad\.heic"):
        read_image(bad)
    with pytest.raises(InvalidInputError, match="does not write it"):
        write_image(tmp_path / "out.heic", np.zeros((4, 4, 3)))
    assert not (tmp_path / "out.heic").exists()


def test_without_the_extra(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import sys

    from imageform._optional import MissingExtraError

    p = _heic(tmp_path / "a.heic", _smooth(), "RGB")
    monkeypatch.setitem(sys.modules, "pillow_heif", None)  # an import of it fails
    with pytest.raises(MissingExtraError, match=r'pip install "imageform\[heif\]"'):
        read_image(p)
