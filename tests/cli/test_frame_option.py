"""``--frame N`` on every command that reads image files (one option, declared once).

``--frame`` was on ``info`` and ``convert`` alone; a TIFF stack, a multi-frame DICOM or an
animated GIF was refused by every other command ("read one with frame=N") with no way to
choose one. It is a field of :class:`imageform.workflows._images.ImageIn`, which every
image-reading command's options inherit, and ``read`` takes it. Files that go with the input
(a mask, a flat field, a stain target) hold one image and are read without it.
"""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from imageform.cli import main
from imageform.io import read_image, write_image
from imageform.workflows import WORKFLOWS
from imageform.workflows._images import ImageIn

tifffile = pytest.importorskip("tifffile")
SRC = Path(__file__).resolve().parents[2] / "src" / "imageform" / "workflows"
IMAGE_COMMANDS = sorted(k for k, w in WORKFLOWS.items() if issubclass(w.options, ImageIn))


def _stack(tmp_path: Path) -> tuple[Path, np.ndarray]:
    """Five RGB pages of 24 x 32 px, each a different warm tint over a gradient."""
    y, x = np.mgrid[0:24, 0:32]
    pages = []
    for k in range(5):
        r = 120 + 20 * k + x
        g = 80 + 3 * y + 5 * k
        b = 60 + 2 * x - 4 * k
        pages.append(np.stack([r, g, b], axis=-1).clip(0, 255).astype(np.uint8))
    a = np.stack(pages)
    p = tmp_path / "stack.tif"
    tifffile.imwrite(p, a, photometric="rgb")
    return p, a


def test_every_image_reading_command_takes_frame_from_the_shared_options() -> None:
    assert {"cvd", "segment", "white-balance", "stain-normalize", "sfr", "calibrate"} <= set(
        IMAGE_COMMANDS
    )
    declared = {f.name: f for f in ImageIn.fields()}["frame"]
    assert declared.metadata["minimum"] == 0
    for name in [*IMAGE_COMMANDS, "info"]:
        (f,) = [f for f in WORKFLOWS[name].options.fields() if f.name == "frame"]
        same = {k: v for k, v in f.metadata.items() if k != "help"}
        assert same == {k: v for k, v in declared.metadata.items() if k != "help"}, name
        assert f.default is None
    # declared once: every ``frame`` field of an options class is frame_option()'s
    for module in SRC.glob("*.py"):
        tree = ast.parse(module.read_text(encoding="utf-8"))
        for cls in (n for n in ast.walk(tree) if isinstance(n, ast.ClassDef)):
            for s in cls.body:
                if not (isinstance(s, ast.AnnAssign) and isinstance(s.target, ast.Name)):
                    continue
                if s.target.id == "frame":
                    assert isinstance(s.value, ast.Call) and isinstance(s.value.func, ast.Name)
                    assert s.value.func.id == "frame_option", (module.name, cls.name)


@pytest.mark.parametrize("command", ["cvd", "segment", "vanishing", "mosaic"])
def test_frame_out_of_range_and_negative_are_one_line(
    tmp_path: Path, command: str, capsys: pytest.CaptureFixture[str]
) -> None:
    p, _ = _stack(tmp_path)
    extra = {"cvd": ["--type", "deutan"], "mosaic": []}.get(command, [])
    out = ["-o", str(tmp_path / "o.png")] if command != "vanishing" else []
    assert main([command, str(p), *out, *extra, "--frame", "5"]) == 1
    err = capsys.readouterr().err.strip()
    assert "frame 5 is out of range" in err and "holds 5 images (frames 0 to 4)" in err
    assert "\n" not in err and not (tmp_path / "o.png").exists()
    assert main([command, str(p), *out, *extra, "--frame", "-1"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (
        f"imageform {command}: error: expected --frame >= 0, got -1 "
        f"(see 'imageform {command} --help')"
    )
    assert main([command, str(p), *out, *extra]) == 1  # without it: how to choose one
    err = capsys.readouterr().err.strip()
    assert "a stack of 5 images" in err and "--frame N" in err and "\n" not in err


def test_a_stack_frame_through_two_commands_is_that_page(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``cvd --frame 2`` then ``segment`` of its output == the same on page 2 as its own file;
    ``white-balance --frame 2 --mask M`` reads the mask (one image) as it is."""
    p, pages = _stack(tmp_path)
    page2 = tmp_path / "page2.png"
    write_image(page2, pages[2])
    a, b = tmp_path / "a.png", tmp_path / "b.png"
    assert main(["cvd", str(p), "--frame", "2", "--type", "protan", "-o", str(a)]) == 0
    assert main(["cvd", str(page2), "--type", "protan", "-o", str(b)]) == 0
    np.testing.assert_array_equal(read_image(a), read_image(b))
    ma, mb = tmp_path / "ma.png", tmp_path / "mb.png"
    assert main(["segment", str(a), "-o", str(ma)]) == 0
    assert main(["segment", str(b), "-o", str(mb)]) == 0
    np.testing.assert_array_equal(read_image(ma), read_image(mb))
    mask = tmp_path / "mask.png"
    write_image(mask, np.pad(np.ones((12, 16), np.uint8) * 255, ((6, 6), (8, 8))))
    wa, wb = tmp_path / "wa.png", tmp_path / "wb.png"
    argv = ["white-balance", "--mask", str(mask)]
    assert main([*argv, str(p), "--frame", "2", "-o", str(wa)]) == 0
    assert main([*argv, str(page2), "-o", str(wb)]) == 0
    np.testing.assert_array_equal(read_image(wa), read_image(wb))
    capsys.readouterr()


def test_a_raw_file_takes_frame_0_and_refuses_another(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``sfr`` and ``info`` of a raw file ignored ``--frame 3`` (they read the raw directly);
    a raw holds one image: ``--frame 0`` is it, another is out of range as for a PNG. The
    commands that read images, not raws, say in one line what to do with it."""
    from imageform.analysis import render_sfr_chart
    from imageform.io import write_dng

    lin = render_sfr_chart((96, 120), grid=(1, 1), angle_deg=5.0, sigma=0.8, supersampling=2)
    dn = np.round(64 + (4095 - 64) * 0.9 * lin).astype(np.uint16)
    raw = write_dng(tmp_path / "edge.dng", dn, cfa_pattern="RGGB", black_level=64.0,
                    white_level=4095.0, color_matrix=np.eye(3))  # fmt: skip
    for argv in (["sfr", str(raw)], ["info", str(raw)]):
        assert main([*argv, "--frame", "3"]) == 1
        err = capsys.readouterr().err
        assert f"frame 3 is out of range: {raw} holds one image (frame 0)" in err
        assert err.count("\n") == 1
    assert main(["info", str(raw), "--frame", "0"]) == 0
    capsys.readouterr()
    out = tmp_path / "o.png"
    assert main(["cvd", str(raw), "--type", "deutan", "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert "is a camera raw file (.dng), not an image: make one with imageform develop" in err
    assert err.count("\n") == 1 and not out.exists()


def test_info_of_a_multi_frame_dicom_checks_frame(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``info x.dcm --frame 9`` described the file as if no frame were given."""
    pydicom = pytest.importorskip("pydicom")
    from pydicom.dataset import Dataset, FileMetaDataset
    from pydicom.uid import ExplicitVRLittleEndian, generate_uid

    ds = Dataset()
    ds.file_meta = FileMetaDataset()
    ds.file_meta.TransferSyntaxUID = ExplicitVRLittleEndian
    ds.file_meta.MediaStorageSOPClassUID = "1.2.840.10008.5.1.4.1.1.7"
    ds.file_meta.MediaStorageSOPInstanceUID = generate_uid()
    ds.SOPClassUID = ds.file_meta.MediaStorageSOPClassUID
    ds.SOPInstanceUID = ds.file_meta.MediaStorageSOPInstanceUID
    ds.Modality = "OT"
    ds.Rows, ds.Columns, ds.NumberOfFrames = 4, 5, 3
    ds.SamplesPerPixel, ds.PhotometricInterpretation = 1, "MONOCHROME2"
    ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 8, 8, 7, 0
    ds.PixelData = np.arange(60, dtype=np.uint8).tobytes()
    p = tmp_path / "cine.dcm"
    ds.save_as(p, enforce_file_format=True)
    assert pydicom.dcmread(p).NumberOfFrames == 3
    assert main(["info", str(p), "--frame", "9"]) == 1
    err = capsys.readouterr().err
    assert "frame 9 is out of range" in err and err.count("\n") == 1
    assert main(["info", str(p), "--frame", "2"]) == 0
    assert "frame 2 of 3" in capsys.readouterr().out
