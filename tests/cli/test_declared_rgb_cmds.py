"""The RGB commands read the colour space a file declares (``--from auto``, the default).

``segment``, ``stain-normalize``, ``fit-correction``, ``harmonize`` and ``cvd`` work on sRGB
values (HSV thresholds, stain statistics, the ColorChecker's published sRGB, the CVD models'
sRGB primaries): a Display P3-tagged copy of an image must give what the sRGB original gives,
and ``--from srgb`` reads the pixels as they are (what every version before did).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from imageform.analysis.synthetic import COLORCHECKER_SRGB8
from imageform.cli import main
from imageform.color import convert
from imageform.io import image_color_space, read_image, write_image


def _pair(tmp_path: Path, a: np.ndarray, name: str) -> tuple[str, str]:
    """``a`` (sRGB) as NAME.png and as a Display P3-tagged NAME-p3.png (both 16-bit)."""
    write_image(tmp_path / f"{name}.png", a, bit_depth=16)
    p3 = np.clip(np.asarray(convert(a, "srgb", "display_p3")), 0, 1)
    write_image(tmp_path / f"{name}-p3.png", p3, color_space="display_p3", bit_depth=16)
    return str(tmp_path / f"{name}.png"), str(tmp_path / f"{name}-p3.png")


def _tissue(seed: int = 0, noise: float = 0.04) -> np.ndarray:
    """A slide-like sRGB image: glass on top, pink and purple stained tissue below."""
    rng = np.random.default_rng(seed)
    img = np.empty((96, 128, 3))
    img[:] = [0.93, 0.92, 0.95]
    pink = rng.normal([0.86, 0.55, 0.72], noise, (64, 64, 3))
    purple = rng.normal([0.45, 0.30, 0.62], 1.25 * noise, (64, 64, 3))
    img[32:, :64], img[32:, 64:] = pink, purple
    return np.asarray(np.clip(img, 0.02, 0.98))


def _read(path: Path | str) -> np.ndarray:
    return np.asarray(read_image(path), dtype=np.float64) / 65535.0


def test_segment_reads_the_declared_space(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    srgb, p3 = _pair(tmp_path, _tissue(noise=0.01), "t")
    # the pink's saturation is 0.36 in sRGB; its Display P3 code values read as sRGB give 0.31
    args = ["--h", "300:345", "--s", "0.335:1", "--v", "0.5:1", "--min-area", "0"]
    outs = [tmp_path / f"m{i}.png" for i in range(3)]
    assert main(["segment", srgb, "-o", str(outs[0]), *args]) == 0
    capsys.readouterr()
    assert main(["segment", p3, "-o", str(outs[1]), *args, "--json"]) == 0
    got = capsys.readouterr()
    assert json.loads(got.out)["from"] == "display_p3"
    assert "t-p3.png declares display_p3" in got.err
    assert main(["segment", p3, "-o", str(outs[2]), *args, "--from", "srgb"]) == 0
    masks = [np.asarray(read_image(p)) > 0 for p in outs]
    assert masks[0].mean() > 0.2
    assert np.mean(masks[0] != masks[1]) < 0.002  # the same tissue, read as sRGB
    assert np.mean(masks[0] != masks[2]) > 0.2  # P3 codes read as sRGB: less saturated


def test_stain_normalize_reads_the_declared_space(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    srgb, p3 = _pair(tmp_path, _tissue(0), "t")
    target = str(tmp_path / "target.png")
    write_image(target, _tissue(1) ** 1.2, bit_depth=16)
    outs = [str(tmp_path / f"n{i}.png") for i in range(3)]
    for src, dst, extra in (
        (srgb, outs[0], []),
        (p3, outs[1], []),
        (p3, outs[2], ["--from", "srgb"]),
    ):
        assert main(["stain-normalize", src, "--target", target, "-o", dst, *extra]) == 0
    capsys.readouterr()
    a, b, c = (_read(p) for p in outs)
    assert np.abs(a - b).mean() * 255 < 0.5  # written as sRGB, whatever the input declared
    assert np.abs(a - c).mean() * 255 > 3.0
    assert image_color_space(outs[1]).name is None  # an sRGB output carries no profile


def _chart(values: np.ndarray, size: int = 24) -> np.ndarray:
    """A 4 x 6 chart cropped to the frame: patches of ``values`` (24, 3) on a dark grid."""
    img = np.full((4 * size, 6 * size, 3), 0.05)
    for i, v in enumerate(values):
        r, c = divmod(i, 6)
        img[r * size + 3 : (r + 1) * size - 3, c * size + 3 : (c + 1) * size - 3] = v
    return img


def test_fit_correction_and_harmonize_read_the_declared_space(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    ref = np.asarray(COLORCHECKER_SRGB8, dtype=np.float64) / 255.0
    device = np.clip(ref**1.15 * [0.92, 1.0, 0.85] + 0.02, 0, 1)  # device A's rendering
    chart, chart_p3 = _pair(tmp_path, _chart(device), "chart")
    corr = [str(tmp_path / f"c{i}.json") for i in range(2)]
    for src, dst in ((chart, corr[0]), (chart_p3, corr[1])):
        assert main(["fit-correction", src, "-o", dst, "--chart-layout", "cropped"]) == 0
    capsys.readouterr()
    m0, m1 = (np.asarray(json.loads(Path(p).read_text())["matrix"]) for p in corr)
    assert np.abs(m0 - m1).max() < 2e-3
    image, image_p3 = _pair(tmp_path, _tissue(), "img")
    outs = [str(tmp_path / f"h{i}.png") for i in range(3)]
    for src, dst, extra in (
        (image, outs[0], []),
        (image_p3, outs[1], []),
        (image_p3, outs[2], ["--from", "srgb"]),
    ):
        assert main(["harmonize", src, "-o", dst, "--correction", corr[0], *extra]) == 0
    # a chart corrected by a fit on itself (--chart the same file): P3 copy as the original
    for src, dst in ((chart, "hc.png"), (chart_p3, "hc-p3.png")):
        assert main(["harmonize", src, "-o", str(tmp_path / dst), "--chart", src]) == 0
    capsys.readouterr()
    a, b, c = (_read(p) for p in outs)
    assert np.abs(a - b).mean() * 255 < 0.5
    assert np.abs(a - c).mean() * 255 > 3.0
    fixed, fixed_p3 = (_read(tmp_path / n) for n in ("hc.png", "hc-p3.png"))
    assert np.abs(fixed - fixed_p3).mean() * 255 < 0.5


def test_cvd_keeps_the_declared_space(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(2)
    srgb, p3 = _pair(tmp_path, rng.random((24, 32, 3)) * 0.8 + 0.1, "c")
    a_out, b_out = str(tmp_path / "a.png"), str(tmp_path / "b.png")
    assert main(["cvd", srgb, "--type", "deutan", "-o", a_out]) == 0
    assert main(["cvd", p3, "--type", "deutan", "-o", b_out]) == 0
    capsys.readouterr()
    assert image_color_space(b_out).name == "display_p3"  # the output stays in the input's space
    back = np.asarray(convert(_read(b_out), "display_p3", "srgb"))
    seen = _read(a_out)
    inside = ((seen > 0) & (seen < 1)).all(axis=-1)  # the models leave sRGB's gamut at times
    assert inside.mean() > 0.6
    assert np.abs(back - seen)[inside].max() * 255 < 0.5


@pytest.mark.parametrize("command", ["segment", "stain-normalize", "harmonize", "cvd"])
def test_from_must_be_an_rgb_space(tmp_path: Path, capsys, command: str) -> None:  # type: ignore[no-untyped-def]
    srgb, _ = _pair(tmp_path, _tissue(), "t")
    extra = {
        "stain-normalize": ["--target", srgb],
        "harmonize": ["--chart", srgb],
        "cvd": ["--type", "protan"],
    }.get(command, [])
    out = tmp_path / "out.png"
    assert main([command, srgb, "-o", str(out), *extra, "--from", "lab"]) == 2
    assert "give an RGB space" in capsys.readouterr().err
    assert not out.exists()


def test_batch_segment_reads_each_files_space(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    _pair(tmp_path, _tissue(noise=0.01), "t")  # t.png and t-p3.png
    args = ["--h", "300:345", "--s", "0.335:1", "--v", "0.5:1", "--min-area", "0"]
    out = tmp_path / "masks"
    assert main(["batch", "segment", str(tmp_path / "t*.png"), "-o", str(out), *args]) == 0
    capsys.readouterr()
    a, b = (np.asarray(read_image(out / n)) > 0 for n in ("t.png", "t-p3.png"))
    assert a.mean() > 0.2 and np.mean(a != b) < 0.002
