"""``imageform mosaic`` and ``imageform demosaic`` on files."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from imageform.cli import main


def _rgb_png(path: Path, h: int = 24, w: int = 32) -> np.ndarray:
    from PIL import Image

    yy, xx = np.mgrid[0:h, 0:w]
    img = np.stack([(yy * 7 + xx * 3) % 256, (xx * 5) % 256, (yy * 9) % 256], -1).astype(np.uint8)
    Image.fromarray(img).save(path)
    return img


def test_mosaic_then_demosaic_png(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from PIL import Image

    img = _rgb_png(tmp_path / "in.png")
    raw, out = tmp_path / "raw.png", tmp_path / "out.png"
    assert main(["mosaic", str(tmp_path / "in.png"), str(raw), "--pattern", "GRBG"]) == 0
    mosaic_u8 = np.asarray(Image.open(raw))
    assert mosaic_u8.dtype == np.uint8 and mosaic_u8.shape == (24, 32)
    assert mosaic_u8[0, 0] == img[0, 0, 1] and mosaic_u8[0, 1] == img[0, 1, 0]  # G R / B G
    capsys.readouterr()
    rc = main(["demosaic", str(raw), str(out), "--pattern", "GRBG", "--method", "menon", "--json"])
    assert rc == 0
    info = json.loads(capsys.readouterr().out)
    assert info["pattern"] == "GRBG" and info["shape"] == [24, 32, 3]
    rgb = np.asarray(Image.open(out))
    assert rgb.shape == (24, 32, 3) and rgb.dtype == np.uint8
    # measured samples come back exactly
    assert rgb[0, 0, 1] == img[0, 0, 1] and rgb[1, 0, 2] == img[1, 0, 2]


def test_demosaic_json_and_16_bit(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    raw = np.random.default_rng(0).random((16, 20)).astype(np.float32)
    np.save(tmp_path / "raw.npy", raw)
    out = tmp_path / "out.png"
    rc = main(
        [
            "demosaic",
            str(tmp_path / "raw.npy"),
            str(out),
            "--method",
            "malvar",
            "--bits",
            "16",
            "--json",
        ]
    )
    assert rc == 0
    info = json.loads(capsys.readouterr().out)
    assert info["method"] == "malvar" and info["shape"] == [16, 20, 3]
    assert info["clipped_values"] == info["out_of_range_values"] >= 0
    head = out.read_bytes()[:25]
    assert head[:8] == b"\x89PNG\r\n\x1a\n" and head[24] == 16  # 16-bit RGB PNG


def test_demosaic_npy_keeps_overshoot(tmp_path: Path) -> None:
    raw = np.zeros((12, 12), np.float32)
    raw[6, 6] = 1.0
    np.save(tmp_path / "raw.npy", raw)
    assert (
        main(["demosaic", str(tmp_path / "raw.npy"), str(tmp_path / "o.npy"), "--method", "malvar"])
        == 0
    )
    assert np.load(tmp_path / "o.npy").min() < 0
    assert (
        main(
            [
                "demosaic",
                str(tmp_path / "raw.npy"),
                str(tmp_path / "c.npy"),
                "--method",
                "malvar",
                "--clip",
            ]
        )
        == 0
    )
    assert np.load(tmp_path / "c.npy").min() == 0


def test_errors(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    _rgb_png(tmp_path / "in.png")
    raw = tmp_path / "raw.png"
    assert main(["mosaic", str(tmp_path / "in.png"), str(raw), "--pattern", "RGBX"]) == 1
    assert "unknown CFA pattern 'RGBX'" in capsys.readouterr().err
    assert main(["mosaic", str(tmp_path / "in.png"), str(raw)]) == 0
    assert main(["mosaic", str(tmp_path / "in.png"), str(raw)]) == 1
    assert "exists; pass --force" in capsys.readouterr().err
    assert main(["mosaic", str(tmp_path / "in.png"), str(raw), "--force"]) == 0
    out = tmp_path / "out.png"
    assert main(["demosaic", str(raw), str(out), "--method", "vng"]) == 1
    assert "unknown demosaicing method 'vng'" in capsys.readouterr().err
    # a colour image is not a mosaic
    assert main(["demosaic", str(tmp_path / "in.png"), str(out)]) == 1
    assert "single-channel raw mosaic" in capsys.readouterr().err
    assert main(["demosaic", str(raw), str(raw)]) == 1
    assert "is also an input" in capsys.readouterr().err
    assert main(["demosaic", str(tmp_path / "missing.png"), str(out)]) == 1
    assert "does not exist" in capsys.readouterr().err
