"""``imageform flatfield``: what it writes, and ``--flat`` reading what it wrote."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from imageform.cli import main
from imageform.io import read_image, write_image
from imageform.workflows import execute, get_workflow


def _tiles(folder: Path, n: int = 12, size: int = 32) -> np.ndarray:
    """Write ``n`` 16-bit 'cell' tiles under a known shading; return the shading."""
    rng = np.random.default_rng(0)
    y, x = np.mgrid[0:size, 0:size] / (size - 1)
    flat = 1.2 - 0.8 * ((x - 0.4) ** 2 + (y - 0.55) ** 2)
    folder.mkdir()
    for i in range(n):
        img = np.full((size, size), rng.uniform(0.2, 0.4))
        for _ in range(6):
            cy, cx = rng.uniform(0, size, 2)
            img += 0.3 * np.exp(-((y * (size - 1) - cy) ** 2 + (x * (size - 1) - cx) ** 2) / 8)
        write_image(
            folder / f"tile{i:02d}.png", np.round(img * flat / 1.5 * 65535).astype(np.uint16)
        )
    return flat


def test_flatfield_writes_and_flat_reads(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    flat = _tiles(tmp_path / "tiles")
    out = tmp_path / "out"
    rc = main(["flatfield", str(tmp_path / "tiles"), "-o", str(out), "--apply", "--json"])
    summary = json.loads(capsys.readouterr().out)
    assert rc == 0
    assert summary["images"] == 12 and summary["method"] == "basic"
    assert summary["flatfield_file"] == "flatfield.tif" and summary["darkfield_file"] is None
    assert len(summary["corrected"]) == 12 and summary["converged"] is True
    assert sorted(p.name for p in out.iterdir()) == ["corrected", "flatfield.json", "flatfield.tif"]
    f = read_image(out / "flatfield.tif")[..., 0]
    assert f.dtype == np.float32 and f.shape == (32, 32)
    assert f.mean() == pytest.approx(1.0, abs=1e-5)
    assert float(np.corrcoef(f.ravel(), flat.ravel())[0, 1]) > 0.9
    record = json.loads((out / "flatfield.json").read_text())
    assert record["format"] == "imageform-flatfield" and len(record["baseline"]) == 12
    applied = read_image(out / "corrected" / "tile03.tif")
    assert applied.dtype == np.float32

    # the written flat field, applied with --flat, gives the same corrected images
    out2 = tmp_path / "out2"
    rc = main(
        [
            "flatfield",
            str(tmp_path / "tiles" / "*.png"),
            "-o",
            str(out2),
            "--flat",
            str(out / "flatfield.tif"),
        ]
    )
    assert rc == 0
    assert sorted(p.name for p in out2.iterdir()) == ["corrected", "flatfield.json"]
    again = read_image(out2 / "corrected" / "tile03.tif")
    np.testing.assert_allclose(again, applied, rtol=1e-5)


def test_flatfield_radial_npy_and_darkfield(tmp_path: Path) -> None:
    _tiles(tmp_path / "tiles", n=6)
    wf = get_workflow("flatfield")
    one = tmp_path / "tiles" / "tile00.png"
    res = execute(
        wf, images=[one], out=tmp_path / "r", options=wf.make_options(method="radial", format="npy")
    )
    assert res.summary["method"] == "radial"
    assert np.load(tmp_path / "r" / "flatfield.npy").shape == (32, 32)
    res = execute(
        wf, images=[tmp_path / "tiles"], out=tmp_path / "d", options=wf.make_options(darkfield=True)
    )
    assert (tmp_path / "d" / "darkfield.tif").exists() and res.summary["darkfield_mean"] is not None


def test_flatfield_refusals(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    _tiles(tmp_path / "tiles", n=3)
    tiles = str(tmp_path / "tiles")
    assert main(["flatfield", tiles, "-o", tiles, "--force"]) == 1
    assert "holds the input" in capsys.readouterr().err
    assert main(["flatfield", tiles + "/tile00.png", "-o", str(tmp_path / "a")]) == 1
    assert "--method radial" in capsys.readouterr().err
    assert (
        main(["flatfield", tiles, "-o", str(tmp_path / "b"), "--dark", tiles + "/tile00.png"]) == 2
    )
    assert "--dark is subtracted with a measured --flat" in capsys.readouterr().err
    np.save(tmp_path / "small.npy", np.ones((4, 4)))
    assert (
        main(["flatfield", tiles, "-o", str(tmp_path / "c"), "--flat", str(tmp_path / "small.npy")])
        == 1
    )
    err = capsys.readouterr().err
    assert (
        "tile00.png with --flat" in err and "(4, 4)" in err and len(err.strip().splitlines()) == 1
    )
    assert not (tmp_path / "c").exists()  # all or nothing
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "keep.txt").write_text("mine")
    assert main(["flatfield", tiles, "-o", str(foreign), "--force"]) == 1
    assert "not an imageform flatfield output" in capsys.readouterr().err
    assert (foreign / "keep.txt").exists()
    assert main(["flatfield", str(tmp_path / "missing"), "-o", str(tmp_path / "e")]) == 1
    assert "does not exist" in capsys.readouterr().err


def test_flatfield_in_help(capsys: pytest.CaptureFixture[str]) -> None:
    main(["--help"])
    out = capsys.readouterr().out
    assert "flatfield" in out.split("Biomedical colour analysis")[1]


ENDO = Path(__file__).resolve().parents[1] / "data" / "endo"


def test_flatfield_radial_mask_on_colonoscope_frames(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    frames = [str(ENDO / f"c3vdv3_f{i:03d}.jpg") for i in (0, 4, 8)]
    # without a mask the black surround breaks the radial fit: refused, nothing written
    assert main(["flatfield", *frames, "-o", str(tmp_path / "no"), "--method", "radial"]) == 1
    err = capsys.readouterr().err
    assert "--mask auto" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "no").exists()
    out = tmp_path / "out"
    argv = ["flatfield", *frames, "-o", str(out), "--method", "radial", "--mask", "auto"]
    assert main([*argv, "--apply", "--center", "mask", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["method"] == "radial" and summary["mask"] == "auto"
    assert summary["mask_file"] == "mask.png" and 0.8 < summary["mask_share"] < 0.95
    assert summary["center"] == "mask" and len(summary["corrected"]) == 3
    names = sorted(p.name for p in out.iterdir())
    assert names == ["corrected", "flatfield.json", "flatfield.tif", "mask.png"]
    mask = read_image(out / "mask.png")[..., 0] > 0
    flat = read_image(out / "flatfield.tif")[..., 0]
    assert flat.shape == mask.shape == (448, 445) and float(flat.min()) > 0
    assert float(flat[mask].mean()) == pytest.approx(1.0, abs=1e-4)
    # the pixels outside the field of view are kept as they were
    src = read_image(ENDO / "c3vdv3_f004.jpg").astype(np.float32) / 255
    fixed = read_image(out / "corrected" / "c3vdv3_f004.tif")
    np.testing.assert_array_equal(fixed[~mask], src[~mask])
    # the written mask, given as a file, gives the same flat field
    again = tmp_path / "again"
    assert main(["flatfield", *frames, "-o", str(again), "--method", "radial", "--mask",
                 str(out / "mask.png")]) == 0  # fmt: skip
    np.testing.assert_allclose(read_image(again / "flatfield.tif")[..., 0], flat, rtol=1e-6)
    assert not (again / "mask.png").exists()


def test_flatfield_mask_refusals(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    frame, frame4 = str(ENDO / "c3vdv3_f000.jpg"), str(ENDO / "c3vdv3_f004.jpg")
    write_image(tmp_path / "small.png", np.full((8, 8), 255, np.uint8))
    write_image(tmp_path / "black.png", np.zeros((448, 445), np.uint8))
    cases = [
        (["--method", "radial", "--mask", str(tmp_path / "small.png")], 1, "8 x 8 px"),
        (["--method", "radial", "--mask", str(tmp_path / "black.png")], 1, "zero everywhere"),
        (["--method", "radial", "--mask", str(tmp_path / "none.png")], 1, "does not exist"),
        (["--mask", "auto"], 2, "BaSiC takes no mask"),
        (["--method", "radial", "--center", "mask"], 1, "give --mask"),
        (["--center", "fit"], 1, "--center is an option of --method radial"),
    ]
    for i, (extra, rc, message) in enumerate(cases):
        out = tmp_path / f"o{i}"
        assert main(["flatfield", frame, frame4, "-o", str(out), *extra]) == rc, extra
        err = capsys.readouterr().err
        assert message in err.strip().splitlines()[-1], err
        assert len(err.strip().splitlines()) == 1, err  # usage errors too (exit 2)
        assert not out.exists()
