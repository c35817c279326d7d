"""Real PFM, Radiance HDR and multi-page TIFF files (tests/data/formats, README there).

Peers: Pillow for the PFM (it keeps the stored numbers, as imageform does; OpenCV divides
them by the scale, 2.5 here), OpenCV for the new-style RLE HDR (plus Radiance's half step),
tifffile's pages for the TIFF. The old-style RLE HDR has no peer here (OpenCV refuses it):
its runs must rebuild every scanline to the width, and its values be finite and positive.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imageform.cli import main
from imageform.io import ImageFrames, image_frames, image_info, read_image

DATA = Path(__file__).resolve().parents[1] / "data" / "formats"


def test_big_endian_pfm_with_a_scale_reads_as_pillow_reads_it() -> None:
    from PIL import Image

    p = DATA / "hopper_be.pfm"
    got = read_image(p)
    with Image.open(p) as im:
        np.testing.assert_array_equal(got[..., 0], np.asarray(im))
    cv2 = pytest.importorskip("cv2")
    np.testing.assert_allclose(cv2.imread(str(p), cv2.IMREAD_UNCHANGED) * 2.5, got[..., 0],
                               rtol=1e-6)  # fmt: skip
    assert image_info(p) == (128, 128, 1, "float32", "pfm")


def test_radiance_hdr_new_rle_is_opencv_plus_half_a_step() -> None:
    cv2 = pytest.importorskip("cv2")
    p = DATA / "rgbr4x4.hdr"
    got = read_image(p)
    cv = cv2.imread(str(p), cv2.IMREAD_UNCHANGED)[..., ::-1].astype(np.float64)
    top = cv.max(axis=-1, keepdims=True)
    step = np.exp2(np.floor(np.log2(top)) - 7)  # 2**(E - 136): the largest mantissa is 128-255
    np.testing.assert_allclose(got, cv + 0.5 * step, rtol=1e-6)


def test_radiance_hdr_old_runs_rebuild_every_scanline(
    capsys: pytest.CaptureFixture[str],
) -> None:
    p = DATA / "old-rle.hdr"
    got = read_image(p)
    assert got.shape == (276, 551, 3) and got.dtype == np.float32
    assert np.all(np.isfinite(got)) and got.min() > 0
    assert main(["info", str(p)]) == 0
    assert "linear_srgb (radiance)" in capsys.readouterr().out


def test_multipage_tiff_pages_are_tifffile_s() -> None:
    tifffile = pytest.importorskip("tifffile")
    p = DATA / "multipage.tiff"
    # the third page, of another size, is an image too (it was left out: a series of its own)
    assert image_frames(p) == ImageFrames(3, (("pages", 3),))
    with tifffile.TiffFile(p) as tif:
        for k in range(3):
            page = tif.pages[k]
            index = page.asarray().astype(np.intp)  # 1-bit palette indices
            want = np.asarray(page.colormap).T[index] // 257  # the palette, 8 bits
            np.testing.assert_array_equal(read_image(p, frame=k), want)
