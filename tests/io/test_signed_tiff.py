"""Signed-integer TIFFs (int8, int16, int32: a CT slice, a microscope's offset-corrected counts).

They were refused ("unsupported sample type int16"). They are read as floats holding the
stored numbers, as a DICOM's signed samples are (``imageform.io.dicom``): float32 for int8
and int16, float64 for int32 (float32's 24-bit mantissa would round it), each number exact;
``image_info`` says what ``read_image`` returns and ``imageform info`` what is stored. The
reference is the array tifffile wrote and reads back.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from imageform.cli import main
from imageform.io import image_frames, image_info, read_image

tifffile = pytest.importorskip("tifffile")
RNG = np.random.default_rng(20261130)


@pytest.mark.parametrize(
    ("stored", "read_as"),
    [(np.int8, np.float32), (np.int16, np.float32), (np.int32, np.float64)],
)
@pytest.mark.parametrize("channels", [1, 3])
def test_signed_samples_are_read_as_the_stored_numbers(
    tmp_path: Path, stored: type, read_as: type, channels: int
) -> None:
    lo, hi = np.iinfo(stored).min, np.iinfo(stored).max
    a = RNG.integers(lo, hi, (5, 7, channels), endpoint=True).astype(stored)
    a[0, :2, 0] = (lo, hi)
    p = tmp_path / "s.tif"
    tifffile.imwrite(p, a if channels == 3 else a[..., 0], photometric=
                     "rgb" if channels == 3 else "minisblack")  # fmt: skip
    got = read_image(p)
    assert got.dtype == read_as and got.shape == a.shape
    np.testing.assert_array_equal(got, a.astype(np.float64))
    np.testing.assert_array_equal(got.astype(np.float64), tifffile.imread(p).reshape(a.shape))
    assert image_info(p) == (7, 5, channels, np.dtype(read_as).name, "tiff")


def test_a_signed_stack_frame_and_info(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """An OME z-stack of int8 (the shape of libvips' multi-channel-z-series.ome.tif, whose
    --frame was refused for its int8 samples) reads frame by frame; info says int8."""
    a = RNG.integers(-128, 127, (3, 4, 6, 8)).astype(np.int8)
    p = tmp_path / "cz.ome.tif"
    tifffile.imwrite(p, a, metadata={"axes": "CZYX"})
    assert image_frames(p).total == 12
    np.testing.assert_array_equal(read_image(p, frame=5)[..., 0], a.reshape(12, 6, 8)[5])
    assert main(["info", str(p), "--frame", "5", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert (summary["dtype"], summary["stored_dtype"]) == ("float32", "int8")
    assert main(["info", str(p), "--frame", "5"]) == 0
    assert "float32 (stored int8, signed: read as the numbers)" in capsys.readouterr().out


def test_colour_commands_refuse_signed_numbers_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A CT's numbers are no colours: convert says what the file holds; the stain and
    segmentation commands refuse floats beyond [0, 1] as they do any such image."""
    ct = (np.arange(64 * 64).reshape(64, 64) - 1024).astype(np.int16)
    p = tmp_path / "ct.tif"
    tifffile.imwrite(p, ct)
    out = tmp_path / "o.png"
    assert main(["convert", str(p), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert "holds int16 samples (signed numbers, -1024 to 3071" in err
    assert err.count("\n") == 1 and not out.exists()
    # a measuring command takes the numbers as they are: a flat field of counts in int16
    counts = tmp_path / "counts.tif"
    tifffile.imwrite(counts, (3000 - np.hypot(*np.mgrid[-32:32, -32:32]) * 20).astype(np.int16))
    ff = tmp_path / "ff"
    assert main(["flatfield", str(counts), "-o", str(ff), "--method", "radial"]) == 0
