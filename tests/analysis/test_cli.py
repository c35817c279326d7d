"""CLI: ``imageform segment``, ``stain-normalize``, ``fit-correction`` and ``harmonize`` on
files (the generated grammar: output ``-o/--out``, an unknown method is a usage error, exit 2;
the old ``harmonize --chart-a/--chart-b/--apply/--save`` is ``fit-correction`` then
``harmonize --correction``)."""

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
        "-o",
        str(out),
        "--overlay",
        str(ov),
        "--json",
    ]
    assert main(argv) == 0
    res = json.loads(capsys.readouterr().out)
    mask = read_image(out)[..., 0] == 255
    assert res["mask"] == str(out) and res["overlay"] == str(ov)
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
    assert main(["segment", str(src), "--h", "a:b", "--out", str(tmp_path / "m.png")]) == 2
    assert "LOW:HIGH" in capsys.readouterr().err  # checked with the options: a usage error
    # the docs' OpenCV S and V without --opencv-ranges: the flag is named, not the keyword
    args = ["segment", str(src), "--s", "30:255", "--out", str(tmp_path / "m.png")]
    assert main(args) == 1
    err = capsys.readouterr().err
    assert (
        "expected --s bounds in [0, 1] (unit range), got (30.0, 255.0); OpenCV's 0 to 255 " in err
    )
    assert err.rstrip().endswith("codes with --opencv-ranges") and "opencv_ranges=" not in err


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
        "-o",
        str(out),
        "--method",
        method,
        "--target",
        str(pb),
        "--save-target",
        str(stats),
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
                "-o",
                str(out2),
                "--method",
                method,
                "--target",
                str(stats),
            ]
        )
        == 0
    )
    np.testing.assert_array_equal(read_image(out2), read_image(out))
    if method == "macenko":  # --scale-by mean: the API's reference="mean"
        out4 = tmp_path / "out4.png"
        argv = ["stain-normalize", str(pa), "-o", str(out4), "--target", str(stats)]
        assert main([*argv, "--scale-by", "mean"]) == 0
        from imageform.analysis import MacenkoStains, macenko_normalize

        api = macenko_normalize(read_image(pa), MacenkoStains.from_json(stats), reference="mean")
        got = read_image(out4).astype(np.float64)
        assert np.abs(got - np.clip(np.asarray(api) * 255, 0, 255)).max() <= 1.0
        assert not np.array_equal(read_image(out4), read_image(out))
    else:  # --scale-by mean is Macenko's: with reinhard a usage error, nothing written
        out4 = tmp_path / "out4.png"
        argv = ["stain-normalize", str(pa), "-o", str(out4), "--target", str(stats)]
        assert main([*argv, "--method", "reinhard", "--scale-by", "mean"]) == 2
        assert "--scale-by mean goes with --method macenko only" in capsys.readouterr().err
        assert not out4.exists()
    # the other method with these statistics: which method saved them, not 'got kind'
    other = "reinhard" if method == "macenko" else "macenko"
    argv = ["stain-normalize", str(pa), "-o", str(tmp_path / "o3.png"), "--method", other]
    assert main([*argv, "--target", str(stats)]) == 1
    err = capsys.readouterr().err
    assert f"was saved by --method {method}: normalise with --method {method}" in err


def test_stain_normalize_errors(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    a, _, _ = synthetic_stain_image((32, 32), rng=0)
    pa = _u8(tmp_path / "a.png", a)
    white = _u8(tmp_path / "w.png", np.full((32, 32, 3), 0.98))
    assert (
        main(
            [
                "stain-normalize",
                str(pa),
                "-o",
                str(tmp_path / "o.png"),
                "--method",
                "vahadane",
                "--target",
                str(pa),
            ]
        )
        == 2
    )
    assert "valid: macenko, reinhard" in capsys.readouterr().err
    o = str(tmp_path / "o.png")
    assert main(["stain-normalize", str(pa), "-o", o, "--target", str(white)]) == 1
    assert "is there tissue" in capsys.readouterr().err
    assert main(["stain-normalize", str(pa), "-o", str(pa), "--target", str(white), "--force"]) == 1
    assert "also an input" in capsys.readouterr().err
    assert main(["stain-normalize", str(pa), "-o", o]) == 2  # --target is required
    assert "--target" in capsys.readouterr().err


def test_stain_normalize_defaults_to_macenko_and_keeps_16_bit(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    a, _, _ = synthetic_stain_image((48, 48), max_concentration=(0.6, 1.0), rng=0)
    b, _, _ = synthetic_stain_image((48, 48), rng=1)
    pa, pb = tmp_path / "a.png", tmp_path / "b.png"
    write_image(pa, np.round(a * 65535).astype(np.uint16))
    write_image(pb, np.round(b * 65535).astype(np.uint16))
    out = tmp_path / "o.png"
    assert main(["stain-normalize", str(pa), "-o", str(out), "--target", str(pb), "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["method"] == "macenko" and len(res["target_stain_matrix"]) == 2
    assert read_image(out).dtype == np.uint16


def test_fit_correction_then_harmonize(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    """fit-correction writes the file harmonize --correction reads; the corrected chart is
    device B's (ΔE00 7+ before, under 1.5 after), 16-bit in gives 16-bit out."""
    chart_b = synthetic_chart_image()
    ca, cb = _u8(tmp_path / "a.png", device_a(chart_b)), _u8(tmp_path / "b.png", chart_b)
    corr, out = tmp_path / "corr.json", tmp_path / "fixed.png"
    argv = ["fit-correction", str(ca), str(cb), "-o", str(corr), "--method", "root-polynomial"]
    assert main([*argv, "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["method"] == "root_polynomial" and res["patches_fitted"] == 24
    assert res["mean_before"] > 7 and res["mean_after"] < 1.5
    assert len(res["delta_e00_after"]) == 24
    assert json.loads(corr.read_text())["kind"] == "color_correction"
    assert main(argv) == 1 and "pass --force" in capsys.readouterr().err
    assert main([*argv, "--force"]) == 0
    assert "patch  ΔE00 before  after" in capsys.readouterr().out
    assert main(["harmonize", str(ca), "-o", str(out), "--correction", str(corr)]) == 0
    fixed = read_image(out).astype(float) / 255
    assert np.abs(fixed - chart_b).mean() < np.abs(device_a(chart_b) - chart_b).mean() / 3
    a16 = tmp_path / "a16.png"
    write_image(a16, np.round(device_a(chart_b) * 65535).astype(np.uint16))
    out16 = tmp_path / "fixed16.png"
    assert main(["harmonize", str(a16), "-o", str(out16), "--correction", str(corr)]) == 0
    got = read_image(out16)
    assert got.dtype == np.uint16
    assert np.abs(got / 65535.0 - fixed).max() < 2.5 / 255  # the 8-bit run, one code apart
    capsys.readouterr()
    assert main(["harmonize", str(ca), "-o", str(tmp_path / "x.png"), "--correction", str(ca)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "imageform: error:" in err


def test_fit_correction_csv(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    from imageform.analysis.synthetic import COLORCHECKER_SRGB8

    ref = np.asarray(COLORCHECKER_SRGB8) / 255
    meas = device_a(ref)
    csv = tmp_path / "p.csv"
    lines = ["a_r,a_g,a_b,b_r,b_g,b_b"] + [
        ",".join(f"{v:.6f}" for v in (*m, *r)) for m, r in zip(meas, ref, strict=True)
    ]
    csv.write_text("\n".join(lines) + "\n")
    assert main(["fit-correction", str(csv), "-o", str(tmp_path / "c.json"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["mean_after"] < 2.0
    bad = tmp_path / "bad.csv"
    bad.write_text("r,g,b\n0.1,0.2,0.3\n")
    assert main(["fit-correction", str(bad), "-o", str(tmp_path / "d.json")]) == 1
    assert "expected CSV columns" in capsys.readouterr().err
    assert main(["fit-correction", str(csv), str(csv), "-o", str(tmp_path / "d.json")]) == 1
    assert "CHART_A CHART_B" in capsys.readouterr().err
    assert not (tmp_path / "d.json").exists()


@pytest.mark.parametrize("method", ["macenko", "reinhard"])
def test_stain_normalize_samples_a_large_image_as_chunked_does(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch, method: str
) -> None:
    """Past the sample's pixels, the statistics come from every step-th row and column (the
    same budget as ``imageform chunked``'s), with a note; the whole image is normalised, within
    a few codes of the statistics of every pixel; a mask image is sampled alike."""
    from imageform.batch import chunked
    from imageform.workflows import analysis as wf

    assert wf._STAIN_SAMPLE_PIXELS == chunked.STAIN_SAMPLE_PIXELS
    a, _, _ = synthetic_stain_image(
        (96, 128), stains=(RUIFROK_HEMATOXYLIN, RUIFROK_DAB), max_concentration=(0.6, 1.0), rng=0
    )
    b, _, _ = synthetic_stain_image((64, 64), stains=(RUIFROK_HEMATOXYLIN, RUIFROK_DAB), rng=1)
    pa, pb = _u8(tmp_path / "a.png", a), _u8(tmp_path / "b.png", b)
    mask = tmp_path / "m.png"
    write_image(mask, np.full((96, 128), 255, np.uint8))
    argv = ["stain-normalize", str(pa), "--target", str(pb), "--method", method, "--mask"]
    assert main([*argv, str(mask), "-o", str(tmp_path / "all.png")]) == 0
    assert "stain statistics measured" not in capsys.readouterr().err
    monkeypatch.setattr(wf, "_STAIN_SAMPLE_PIXELS", 96 * 128 // 4)  # a step of 2
    assert wf._sample_step(np.zeros((96, 128))) == 2
    assert wf._sample_step(np.zeros((97, 128))) == 3  # 49 x 64 rows and columns: one too many
    assert main([*argv, str(mask), "-o", str(tmp_path / "some.png")]) == 0
    err = capsys.readouterr().err
    assert "one row and column in 2 (64 x 48 px)" in err
    full, some = read_image(tmp_path / "all.png"), read_image(tmp_path / "some.png")
    assert some.shape == full.shape == (96, 128, 3)
    diff = np.abs(full.astype(int) - some.astype(int))
    # a quarter of 12 288 pixels: percentiles move a few codes (a 6.6 Mpx slide sampled to a
    # quarter: 0.06 mean CIEDE2000)
    assert np.median(diff) <= 3 and diff.max() <= 12, (np.median(diff), diff.max())
