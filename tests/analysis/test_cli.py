"""CLI: ``imageform segment``, ``stain-normalize`` and ``harmonize`` on files."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from imageform.analysis import (
    mask_iou,
    synthetic_chart_image,
    synthetic_endoscopy_image,
    synthetic_stain_image,
)
from imageform.analysis.synthetic import RUIFROK_DAB, RUIFROK_HEMATOXYLIN
from imageform.cli import main
from imageform.io import read_image, write_image

from .test_harmonize import device_a


def _u8(path: Path, img: np.ndarray) -> Path:
    write_image(path, np.round(img * 255).astype(np.uint8))
    return path


def test_segment(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    img, truth = synthetic_endoscopy_image((128, 128), rng=0)
    src = _u8(tmp_path / "endo.png", img)
    out, ov = tmp_path / "mask.png", tmp_path / "overlay.png"
    argv = [
        "segment",
        str(src),
        "--h",
        "170:20",
        "--s",
        "30:255",
        "--v",
        "80:255",
        "--opencv-ranges",
        "--out",
        str(out),
        "--overlay",
        str(ov),
        "--json",
    ]
    assert main(argv) == 0
    res = json.loads(capsys.readouterr().out)
    mask = read_image(out)[..., 0] == 255
    assert res["tissue_fraction"] == pytest.approx(mask.mean())
    assert res["h_degrees"] == [340.0, 40.0]
    assert mask_iou(mask, truth) > 0.98
    assert read_image(ov).shape == (128, 128, 3)
    assert main(argv) == 1  # outputs exist: --force needed
    assert "pass --force" in capsys.readouterr().err
    assert main([*argv, "--force"]) == 0
    capsys.readouterr()
    # lecture defaults, human output
    assert main(["segment", str(src), "--out", str(tmp_path / "m2.png")]) == 0
    assert "tissue fraction" in capsys.readouterr().out


def test_segment_refuses_to_overwrite_input(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    src = _u8(tmp_path / "endo.png", synthetic_endoscopy_image((64, 64), rng=0)[0])
    assert main(["segment", str(src), "--out", str(src), "--force"]) == 1
    assert "also an input" in capsys.readouterr().err
    assert main(["segment", str(src), "--h", "a:b", "--out", str(tmp_path / "m.png")]) == 1
    assert "LOW:HIGH" in capsys.readouterr().err


def test_segment_empty_mask_is_reported(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    src = _u8(tmp_path / "grey.png", np.full((32, 32, 3), 0.5))
    assert main(["segment", str(src), "--out", str(tmp_path / "m.png")]) == 0
    captured = capsys.readouterr()
    assert "tissue fraction 0.00 %" in captured.out and "empty mask" in captured.err


@pytest.mark.parametrize("method", ["macenko", "reinhard"])
def test_stain_normalize(tmp_path: Path, capsys, method: str) -> None:  # type: ignore[no-untyped-def]
    a, _, _ = synthetic_stain_image(
        (64, 64), stains=(RUIFROK_HEMATOXYLIN, RUIFROK_DAB), max_concentration=(0.6, 1.0), rng=0
    )
    b, _, _ = synthetic_stain_image((64, 64), stains=(RUIFROK_HEMATOXYLIN, RUIFROK_DAB), rng=1)
    pa, pb = _u8(tmp_path / "a.png", a), _u8(tmp_path / "b.png", b)
    out, stats = tmp_path / "out.png", tmp_path / "stats.json"
    argv = [
        "stain-normalize",
        str(pa),
        str(out),
        "--method",
        method,
        "--target",
        str(pb),
        "--save-target",
        str(stats),
        "--clip",
        "--json",
    ]
    assert main(argv) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["method"] == method and read_image(out).shape == (64, 64, 3)
    assert json.loads(stats.read_text())["kind"] in ("macenko_stains", "reinhard_stats")
    out2 = tmp_path / "out2.png"  # the saved statistics give the same result
    assert (
        main(
            [
                "stain-normalize",
                str(pa),
                str(out2),
                "--method",
                method,
                "--target",
                str(stats),
                "--clip",
            ]
        )
        == 0
    )
    np.testing.assert_array_equal(read_image(out2), read_image(out))


def test_stain_normalize_errors(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    a, _, _ = synthetic_stain_image((32, 32), rng=0)
    pa = _u8(tmp_path / "a.png", a)
    white = _u8(tmp_path / "w.png", np.full((32, 32, 3), 0.98))
    assert (
        main(
            [
                "stain-normalize",
                str(pa),
                str(tmp_path / "o.png"),
                "--method",
                "vahadane",
                "--target",
                str(pa),
            ]
        )
        == 1
    )
    assert "'macenko', 'reinhard'" in capsys.readouterr().err
    assert main(["stain-normalize", str(pa), str(tmp_path / "o.png"), "--target", str(white)]) == 1
    assert "is there tissue" in capsys.readouterr().err
    assert main(["stain-normalize", str(pa), str(pa), "--target", str(white), "--force"]) == 1
    assert "also an input" in capsys.readouterr().err


def test_harmonize_charts_apply_save(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    chart_b = synthetic_chart_image()
    ca, cb = _u8(tmp_path / "a.png", device_a(chart_b)), _u8(tmp_path / "b.png", chart_b)
    corr, out = tmp_path / "corr.json", tmp_path / "fixed.png"
    assert (
        main(
            [
                "harmonize",
                "--chart-a",
                str(ca),
                "--chart-b",
                str(cb),
                "--method",
                "root-polynomial",
                "--apply",
                str(ca),
                str(out),
                "--save",
                str(corr),
                "--clip",
                "--json",
            ]
        )
        == 0
    )
    res = json.loads(capsys.readouterr().out)
    assert res["method"] == "root_polynomial" and res["patches_fitted"] == 24
    assert res["mean_before"] > 7 and res["mean_after"] < 1.5
    assert len(res["delta_e00_after"]) == 24
    fixed = read_image(out).astype(float) / 255
    assert np.abs(fixed - chart_b).mean() < np.abs(device_a(chart_b) - chart_b).mean() / 3
    assert json.loads(corr.read_text())["kind"] == "color_correction"
    assert main(["harmonize", "--chart-a", str(ca), "--chart-b", str(cb)]) == 0
    assert "patch  ΔE00 before  after" in capsys.readouterr().out


def test_harmonize_csv(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    from imageform.analysis.synthetic import COLORCHECKER_SRGB8

    ref = np.asarray(COLORCHECKER_SRGB8) / 255
    meas = device_a(ref)
    csv = tmp_path / "p.csv"
    lines = ["a_r,a_g,a_b,b_r,b_g,b_b"] + [
        ",".join(f"{v:.6f}" for v in (*m, *r)) for m, r in zip(meas, ref, strict=True)
    ]
    csv.write_text("\n".join(lines) + "\n")
    assert main(["harmonize", "--patches-csv", str(csv), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["mean_after"] < 2.0
    bad = tmp_path / "bad.csv"
    bad.write_text("r,g,b\n0.1,0.2,0.3\n")
    assert main(["harmonize", "--patches-csv", str(bad)]) == 1
    assert "expected CSV columns" in capsys.readouterr().err
    assert main(["harmonize"]) == 1
    assert "--chart-a and --chart-b" in capsys.readouterr().err
