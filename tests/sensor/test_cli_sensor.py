"""``imageform mosaic`` and ``imageform demosaic`` on files (the generated grammar: the output
is ``-o/--out``; an unknown pattern or method is a usage error, exit 2)."""

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
    assert main(["mosaic", str(tmp_path / "in.png"), "-o", str(raw), "--pattern", "GRBG"]) == 0
    mosaic_u8 = np.asarray(Image.open(raw))
    assert mosaic_u8.dtype == np.uint8 and mosaic_u8.shape == (24, 32)
    assert mosaic_u8[0, 0] == img[0, 0, 1] and mosaic_u8[0, 1] == img[0, 1, 0]  # G R / B G
    capsys.readouterr()
    rc = main(
        ["demosaic", str(raw), "-o", str(out), "--pattern", "GRBG", "--method", "menon", "--json"]
    )
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
            "-o",
            str(out),
            "--method",
            "malvar",
            "--bit-depth",
            "16",
            "--json",
        ]
    )
    assert rc == 0
    info = json.loads(capsys.readouterr().out)
    assert info["method"] == "malvar" and info["shape"] == [16, 20, 3]
    assert info["values_clipped"] >= 0
    head = out.read_bytes()[:25]
    assert head[:8] == b"\x89PNG\r\n\x1a\n" and head[24] == 16  # 16-bit RGB PNG


def test_demosaic_float_outputs_keep_overshoot(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    """One out-of-range policy: float outputs (.npy, .tif) keep every value; integer output
    clips, with one note (the old --clip for .npy is gone: clip with np.clip if needed)."""
    raw = np.zeros((12, 12), np.float32)
    raw[6, 6] = 1.0
    np.save(tmp_path / "raw.npy", raw)
    argv = ["demosaic", str(tmp_path / "raw.npy"), "--method", "malvar"]
    assert main([*argv, "-o", str(tmp_path / "o.npy")]) == 0
    assert np.load(tmp_path / "o.npy").min() < 0
    assert main([*argv, "-o", str(tmp_path / "o.png")]) == 0
    assert "values outside [0, 1] were clipped" in capsys.readouterr().err
    assert main([*argv, "-o", str(tmp_path / "e.png"), "--out-of-range", "error"]) == 1
    assert not (tmp_path / "e.png").exists()


def test_mosaic_demosaic_odd_size_16_bit(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    """imageform demosaic reads the odd-sized mosaic imageform mosaic writes (--allow-odd),
    16-bit in -> 16-bit mosaic -> 16-bit RGB, and measured samples come back exactly."""
    from imageform.io import read_image, write_image

    rng = np.random.default_rng(3)
    img = rng.integers(0, 65536, (25, 33, 3), dtype=np.uint16)
    write_image(tmp_path / "in.png", img)
    raw, out = tmp_path / "raw.png", tmp_path / "out.png"
    assert main(["mosaic", str(tmp_path / "in.png"), "-o", str(raw), "--pattern", "bggr"]) == 0
    assert "--allow-odd" in capsys.readouterr().out
    m = read_image(raw)
    assert m.dtype == np.uint16 and m.shape == (25, 33, 1)
    assert m[0, 0, 0] == img[0, 0, 2] and m[1, 1, 0] == img[1, 1, 0]  # B G / G R
    assert main(["demosaic", str(raw), "-o", str(out), "--pattern", "BGGR"]) == 1
    assert "--allow-odd" in capsys.readouterr().err and not out.exists()
    args = ["demosaic", str(raw), "-o", str(out), "--pattern", "BGGR", "--allow-odd", "--json"]
    assert main([*args, "--method", "bilinear"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["shape"] == [25, 33, 3]
    rgb = read_image(out)
    assert rgb.dtype == np.uint16 and rgb.shape == (25, 33, 3)
    assert rgb[24, 32, 2] == img[24, 32, 2]  # the cut cell's B sample at the corner (even, even)
    assert rgb[0, 0, 2] == img[0, 0, 2] and rgb[1, 1, 0] == img[1, 1, 0]


def test_errors(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    _rgb_png(tmp_path / "in.png")
    raw = tmp_path / "raw.png"
    assert main(["mosaic", str(tmp_path / "in.png"), "-o", str(raw), "--pattern", "RGBX"]) == 2
    assert "unknown --pattern 'RGBX'; valid: rggb" in capsys.readouterr().err
    assert main(["mosaic", str(tmp_path / "in.png"), "-o", str(raw)]) == 0
    assert main(["mosaic", str(tmp_path / "in.png"), "-o", str(raw)]) == 1
    assert "exists; pass --force" in capsys.readouterr().err
    assert main(["mosaic", str(tmp_path / "in.png"), "-o", str(raw), "--force"]) == 0
    out = tmp_path / "out.png"
    assert main(["demosaic", str(raw), "-o", str(out), "--method", "vng"]) == 2
    assert "unknown --method 'vng'; valid: bilinear" in capsys.readouterr().err
    # a colour image is not a mosaic
    assert main(["demosaic", str(tmp_path / "in.png"), "-o", str(out)]) == 1
    assert "single-channel raw mosaic" in capsys.readouterr().err
    assert main(["demosaic", str(raw), "-o", str(raw)]) == 1
    assert "is also an input" in capsys.readouterr().err
    assert main(["demosaic", str(tmp_path / "missing.png"), "-o", str(out)]) == 1
    assert "does not exist" in capsys.readouterr().err
