"""CLI tests: ``imageform delta-e`` and ``imageform white-balance``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from imageform.cli import main


def _png(path: Path, arr: np.ndarray) -> Path:
    Image.fromarray(arr).save(path)
    return path


@pytest.fixture
def pair(tmp_path: Path) -> tuple[Path, Path]:
    rng = np.random.default_rng(0)
    a = rng.integers(0, 256, (16, 20, 3), dtype=np.uint8)
    b = a.copy()
    b[:, :10, 0] = np.clip(b[:, :10, 0].astype(int) + 40, 0, 255).astype(np.uint8)
    return _png(tmp_path / "a.png", a), _png(tmp_path / "b.png", b)


def test_delta_e_json_and_heatmap(pair, tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    a, b = pair
    heat = tmp_path / "heat.png"
    assert main(["delta-e", str(a), str(b), "--json", "--heatmap", str(heat)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["method"] == "ciede2000" and out["pixels"] == 320
    assert 0 < out["mean"] <= out["max"]
    assert set(out["percentiles"]) == {"p50", "p90", "p95", "p99"}
    assert np.asarray(Image.open(heat)).shape == (16, 20, 3)
    # same image: zero difference, the lecture's "imperceptible"
    assert main(["delta-e", str(a), str(a), "--json", "--method", "cie76"]) == 0
    same = json.loads(capsys.readouterr().out)
    assert same["max"] == 0.0 and same["reading"] == "imperceptible"


def test_delta_e_text_and_errors(pair, tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    a, b = pair
    assert main(["delta-e", str(a), str(b)]) == 0
    assert "mean" in capsys.readouterr().out
    small = _png(tmp_path / "small.png", np.zeros((4, 4, 3), np.uint8))
    assert main(["delta-e", str(a), str(small)]) == 1
    assert "differ in size" in capsys.readouterr().err
    assert main(["delta-e", str(a), str(b), "--method", "cie2001"]) == 2
    assert "valid: ciede2000, cie76" in capsys.readouterr().err
    assert main(["delta-e", str(a), str(b), "--heatmap", str(a)]) == 1
    assert "also an input" in capsys.readouterr().err


def test_white_balance_command(pair, tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    a, _ = pair
    out = tmp_path / "wb.png"
    assert main(["white-balance", str(a), "-o", str(out), "--method", "gray-world", "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert len(res["gains"]) == 3 and out.exists()
    assert main(["white-balance", str(a), "-o", str(out)]) == 1
    assert "--force" in capsys.readouterr().err
    tif = tmp_path / "wb.tif"
    assert main(["white-balance", str(a), "-o", str(tif), "--method", "white-patch"]) == 0
    assert "gains" in capsys.readouterr().out
    x = str(tmp_path / "x.png")
    # a usage error (exit 2) naming the flag, before the image is read (clipolish)
    assert main(["white-balance", str(a), "-o", x, "--method", "shades-of-gray", "--p", "0.5"]) == 2
    assert "expected --p >= 1, got 0.5" in capsys.readouterr().err
    y = str(tmp_path / "y.png")
    assert main(["white-balance", str(a), "-o", y, "--method", "nope"]) == 2
    assert "gray-world" in capsys.readouterr().err


def test_delta_e_reads_each_file_s_declared_space(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The same picture exported in sRGB and in Display P3 (with its profile): 0.13 dE00
    apart read as declared; read both as sRGB (the old behaviour, or an untagged export)
    2.6 apart, nearly every pixel above 1."""
    from imageform.color import convert
    from imageform.io import write_image

    a = np.random.default_rng(0).random((20, 30, 3)) * 0.8 + 0.1
    write_image(tmp_path / "ref.png", a, bit_depth=16)
    p3 = np.clip(np.asarray(convert(a, "srgb", "display_p3")), 0, 1)
    write_image(tmp_path / "p3.png", p3, color_space="display_p3", bit_depth=16)
    write_image(tmp_path / "bare.png", p3, bit_depth=16)
    ref, tagged, bare = (str(tmp_path / n) for n in ("ref.png", "p3.png", "bare.png"))
    assert main(["delta-e", ref, tagged, "--json"]) == 0
    got = capsys.readouterr()
    payload = json.loads(got.out)
    assert payload["spaces"] == ["srgb", "display_p3"] and payload["mean"] < 0.05
    assert "p3.png declares display_p3" in got.err
    assert main(["delta-e", ref, bare, "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["mean"] > 1.0
    assert main(["delta-e", ref, bare, "--from", "lab"]) == 2  # a usage error
    assert "delta-e compares RGB images" in capsys.readouterr().err


def test_correction_files_are_json_and_read_as_such(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A correction or patch table is not written under an image's name (JSON in f.png), and
    an image given as a correction file is refused in one line, not a UnicodeDecodeError."""
    from imageform.analysis import synthetic_chart_image

    chart = _png(tmp_path / "chart.png", (synthetic_chart_image() * 255).round().astype(np.uint8))
    c = str(chart)
    for args, needle, code in (
        (["fit-correction", c, "-o", str(tmp_path / "f.png")], "give -o a .json name", 1),
        (["chart", c, "-o", str(tmp_path / "c.txt")], "give -o a .json name", 1),
        (["chart", c, "-o", str(tmp_path / "c.json"), "--csv", str(tmp_path / "p.json")],
         "--csv writes the patch table (CSV): give a .csv name, not 'p.json'", 2),
        (["chart", c, "-o", str(tmp_path / "c.json"), "--correction", str(tmp_path / "k.png")],
         "--correction writes the correction (JSON)", 2),
        (["harmonize", c, "-o", str(tmp_path / "h.png"), "--chart", c, "--save-correction",
          str(tmp_path / "s.png")], "--save-correction writes the correction (JSON)", 2),
        (["harmonize", c, "-o", str(tmp_path / "h.png"), "--correction", c],
         "chart.png is not a 'color_correction' file: not text", 1),
        (["stain-normalize", c, "-o", str(tmp_path / "n.png"), "--target", c, "--save-target",
          str(tmp_path / "t.png")], "--save-target writes the target's statistics (JSON)", 2),
    ):  # fmt: skip
        assert main(args) == code, args
        err = capsys.readouterr().err
        assert needle in err and "Unicode" not in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["chart.png"]


def test_stain_normalize_too_little_tissue_names_the_image_and_the_flag(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The library's "mask=None keeps them" read as a Python keyword on the command line: the
    refusal names the image (--target or the input) and ``--mask none``, and with it the
    command runs."""
    from imageform.io import write_image

    img = np.full((64, 64, 3), 12, np.uint8)  # a black (dark artefact) field, a little pink
    img[:8, :8] = (200, 120, 180)
    src, out = tmp_path / "dark.png", tmp_path / "o.png"
    write_image(src, img)
    args = ["stain-normalize", str(src), "--target", str(src), "-o", str(out)]
    assert main(args) == 1
    err = capsys.readouterr().err
    assert f"--target {src}: Macenko: only" in err and "--mask none keeps them" in err
    assert "mask=None" not in err and err.count("\n") == 1 and not out.exists()
    assert main([*args, "--mask", "none"]) == 0 and out.exists()
