"""CLI tests: ``imageform cvd``, ``imageform gamut``, ``imageform palette-check``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from PIL import Image

from imageform.cli import main
from imageform.color import simulate_cvd


def _png(path: Path) -> Path:
    arr = np.random.default_rng(0).integers(0, 256, (12, 16, 3), dtype=np.uint8)
    Image.fromarray(arr).save(path)
    return path


def test_cvd(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    src = _png(tmp_path / "in.png")
    out = tmp_path / "out.png"
    args = ["cvd", str(src), "-o", str(out), "--type", "deutan", "--severity", "1"]
    assert main([*args, "--method", "machado2009", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["method"] == "machado2009" and info["values_clipped"] >= 0
    got = np.asarray(Image.open(out))
    want = simulate_cvd(np.asarray(Image.open(src)), "deutan", 1.0, clip=True)
    assert np.max(np.abs(got / 255.0 - want)) <= 0.5 / 255 + 1e-6
    # existing output needs --force; the input is never overwritten
    assert main(args) == 1
    assert "exists" in capsys.readouterr().err
    assert main([*args[:3], str(src), *args[4:], "--force"]) == 1
    assert main([*args, "--force", "--method", "brettel1997"]) == 0
    assert main([*args, "--force", "--severity", "2"]) == 1
    assert "severity" in capsys.readouterr().err


def test_gamut(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    plot = tmp_path / "diagram.png"
    assert main(["gamut", "--spaces", "srgb,display-p3,rec2020", "-o", str(plot)]) == 0
    text = capsys.readouterr().out
    assert "sRGB" in text and "33.5%" in text and plot.exists()
    assert main(["gamut", "--spaces", "srgb", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert round(data["spaces"][0]["coverage_xy"], 1) == 33.5
    assert main(["gamut", "--spaces", "srgb,ntsc"]) == 1
    assert "ntsc" in capsys.readouterr().err


def test_palette_check(capsys) -> None:  # type: ignore[no-untyped-def]
    assert main(["palette-check", "#E69F00,#56B4E9,#009E73"]) == 0
    text = capsys.readouterr().out
    assert "deutan" in text and "pass" in text
    # a palette that fails a condition: the check fails, exit code 3
    assert main(["palette-check", "#D7191C,#FDAE61,#FFFFBF,#A6D96A,#1A9641", "--json"]) == 3
    data = json.loads(capsys.readouterr().out)
    assert data["passes"]["deutan"] is False
    assert main(["palette-check", "#ZZZZZZ,#000000"]) == 1
