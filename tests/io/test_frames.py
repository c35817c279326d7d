"""One image of a file that holds several: ``frame=`` of read_image / image_info, image_frames,
``imageform info`` listing them and ``info`` / ``convert --frame N``.

Stacks are written here by tifffile in the layouts microscopes and ImageJ save (pages, an OME
``TZYX`` hyperstack, an ImageJ ``ZCYX`` hyperstack, planar RGB pages) and animated GIFs by
Pillow; the reference for each image is the array written, and tifffile's own
``imread(key=N)`` (the page the library decodes for frame N).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imageform.cli import main
from imageform.errors import InvalidInputError
from imageform.io import ImageFrames, image_frames, image_info, read_image, write_image

tifffile = pytest.importorskip("tifffile")
RNG = np.random.default_rng(20261130)


def _stack(tmp_path: Path, layout: str) -> tuple[Path, np.ndarray, tuple[tuple[str, int], ...]]:
    """A TIFF stack and its images as (N, H, W, C), in frame order."""
    if layout == "pages":
        a = RNG.integers(0, 65535, (3, 6, 8)).astype(np.uint16)
        p = tmp_path / "pages.tif"
        tifffile.imwrite(p, a, photometric="minisblack")
        return p, a[..., None], (("pages", 3),)
    if layout == "ome":
        a = RNG.integers(0, 255, (4, 2, 6, 8)).astype(np.uint8)
        p = tmp_path / "tz.ome.tif"
        tifffile.imwrite(p, a, metadata={"axes": "TZYX"})
        return p, a.reshape(8, 6, 8, 1), (("time points", 4), ("z-planes", 2))
    if layout == "imagej":
        a = RNG.integers(0, 255, (3, 2, 6, 8)).astype(np.uint8)
        p = tmp_path / "zc.tif"
        tifffile.imwrite(p, a, imagej=True, metadata={"axes": "ZCYX"})
        return p, a.reshape(6, 6, 8, 1), (("z-planes", 3), ("channels", 2))
    a = RNG.integers(0, 255, (3, 3, 6, 8)).astype(np.uint8)  # planar RGB pages: QSYX
    p = tmp_path / "planar.tif"
    tifffile.imwrite(p, a, photometric="rgb", planarconfig="separate")
    return p, np.moveaxis(a, 1, -1), (("pages", 3),)


@pytest.mark.parametrize("layout", ["pages", "ome", "imagej", "planar"])
def test_each_frame_of_a_tiff_stack_is_the_image_written(tmp_path: Path, layout: str) -> None:
    p, images, axes = _stack(tmp_path, layout)
    assert image_frames(p) == ImageFrames(len(images), axes)
    for k, want in enumerate(images):
        got = read_image(p, frame=k)
        np.testing.assert_array_equal(got, want)
        page = np.asarray(tifffile.imread(p, key=k))  # the peer: tifffile's page k
        np.testing.assert_array_equal(got.reshape(-1), np.moveaxis(page, 0, -1).reshape(-1)
                                      if layout == "planar" else page.reshape(-1))  # fmt: skip
        h, w, c = want.shape
        assert image_info(p, frame=k) == (w, h, c, str(want.dtype), "tiff")


@pytest.mark.parametrize("layout", ["pages", "ome"])
def test_a_stack_without_frame_is_refused_in_one_line_naming_frame(
    tmp_path: Path, layout: str
) -> None:
    p, images, _ = _stack(tmp_path, layout)
    n = len(images)
    for fn in (read_image, image_info):
        with pytest.raises(InvalidInputError) as err:
            fn(p)
        text = str(err.value)
        assert f"a stack of {n} images" in text and f"frame=N, 0 to {n - 1}" in text
        assert "\n" not in text
    with pytest.raises(InvalidInputError, match=rf"frame {n} is out of range: .* holds {n} im"):
        read_image(p, frame=n)
    for bad in (-1, 1.0, True, "0"):
        with pytest.raises(InvalidInputError):
            read_image(p, frame=bad)  # type: ignore[arg-type]


def test_a_file_of_one_image_takes_frame_zero_alone(tmp_path: Path) -> None:
    p = tmp_path / "one.png"
    write_image(p, np.full((3, 4, 3), 0.5))
    assert image_frames(p) == ImageFrames(1, ())
    np.testing.assert_array_equal(read_image(p, frame=0), read_image(p))
    assert image_info(p, frame=0) == image_info(p)
    with pytest.raises(InvalidInputError, match=r"frame 1 is out of range: .* one image"):
        read_image(p, frame=1)
    t = tmp_path / "one.tif"
    write_image(t, np.full((3, 4, 3), 0.25, np.float32))
    np.testing.assert_array_equal(read_image(t, frame=0), read_image(t))
    with pytest.raises(InvalidInputError, match="frame 2 is out of range"):
        image_info(t, frame=2)


def test_an_animated_gif_frame_is_read_as_pillow_composes_it(tmp_path: Path) -> None:
    from PIL import Image

    frames = [Image.fromarray(RNG.integers(0, 255, (5, 6, 3)).astype(np.uint8)) for _ in "abc"]
    p = tmp_path / "a.gif"
    frames[0].save(p, save_all=True, append_images=frames[1:], duration=40)
    assert image_frames(p) == ImageFrames(3, (("frames", 3),))
    with pytest.raises(InvalidInputError, match="an animated GIF of 3 frames; read one with fr"):
        read_image(p)
    with Image.open(p) as im:
        for k in range(3):
            im.seek(k)
            want = np.asarray(im.convert("RGB"))
            np.testing.assert_array_equal(read_image(p, frame=k), want)


def test_cli_info_lists_the_images_and_describes_one(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    p, _, _ = _stack(tmp_path, "ome")
    assert main(["info", str(p)]) == 0
    out = capsys.readouterr().out
    assert "8 images (4 time points x 2 z-planes), each 8 x 6 px, 1 channel(s), uint8" in out
    assert "frames 0 to 7" in out and "frame N = 2 x (time point) + (z-plane)" in out
    assert main(["info", str(p), "--frame", "5", "--json"]) == 0
    import json

    summary = json.loads(capsys.readouterr().out)
    assert (summary["frames"], summary["frame"], summary["width"]) == (8, 5, 8)
    assert main(["info", str(p), "--frame", "8"]) == 1
    err = capsys.readouterr().err
    assert "frame 8 is out of range" in err and "Traceback" not in err
    assert main(["info", str(p), "--frame", "-1"]) == 2


def test_cli_convert_writes_the_frame_asked_and_refuses_without_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    p, images, _ = _stack(tmp_path, "imagej")
    out = tmp_path / "z.png"
    assert main(["convert", str(p), "-o", str(out), "--from", "gray", "--to", "gray"]) == 1
    err = capsys.readouterr().err
    assert "holds 6 images (3 z-planes x 2 channels); convert one with --frame N (0 to 5)" in err
    assert not out.exists()  # nothing half-written
    for k in (0, 3, 5):
        argv = ["convert", str(p), "-o", str(out), "--from", "gray", "--to", "gray", "--force"]
        assert main([*argv, "--frame", str(k)]) == 0
        np.testing.assert_array_equal(read_image(out), images[k])
