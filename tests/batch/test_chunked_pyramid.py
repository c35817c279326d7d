"""imageform.batch.process_chunked on pyramidal TIFFs (whole-slide images): the levels come
back, each the box mean of the processed level above, level 0 equal to the in-memory result,
tiles, compression and resolution as the input's, memory bounded by a band."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from imageform.batch import process_chunked
from imageform.cli import main
from imageform.color import convert
from imageform.errors import InvalidInputError, UnknownOptionError

tifffile = pytest.importorskip("tifffile")
pytest.importorskip("zarr")
pytest.importorskip("dask.array")

TILE = 256


def _image(h: int, w: int, seed: int = 3) -> np.ndarray:
    """A smooth colour ramp with noise (all codes present, no empty channel)."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:h, 0:w]
    base = np.stack([xx / w, yy / h, 0.5 + 0.4 * np.sin(xx / 37.0)], axis=-1) * 230 + 10
    return np.clip(base + rng.normal(0, 8, base.shape), 0, 255).astype(np.uint8)


def _box(a: np.ndarray, f: int) -> np.ndarray:
    """The reference f x f box mean (partial boxes at the edges average what they have),
    rounded half up, in float64 (numpy only, independent of the code under test)."""
    h, w = a.shape[:2]
    out = np.empty((-(-h // f), -(-w // f), a.shape[2]))
    for i in range(out.shape[0]):
        rows = a[i * f : (i + 1) * f].astype(np.float64)
        for j in range(out.shape[1]):
            out[i, j] = rows[:, j * f : (j + 1) * f].reshape(-1, a.shape[2]).mean(axis=0)
    return np.floor(out + 0.5)


def _box2(a: np.ndarray) -> np.ndarray:
    """The 2 x 2 box mean of an even-sized image, vectorised (same numbers as _box)."""
    h, w, c = a.shape
    return np.floor(a.reshape(h // 2, 2, w // 2, 2, c).astype(np.float64).mean(axis=(1, 3)) + 0.5)


def _pyramid(path: Path, levels: list[np.ndarray], **kw: object) -> None:
    """A tiled pyramidal TIFF as tifffile and OME-TIFF write it: level 0, the reduced levels
    as its SubIFDs."""
    opts = {"tile": (TILE, TILE), "photometric": "rgb", **kw}
    with tifffile.TiffWriter(path) as tw:
        tw.write(levels[0], subifds=len(levels) - 1, **opts)
        for lv in levels[1:]:
            tw.write(lv, subfiletype=1, **opts)


@pytest.fixture(scope="module")
def slide(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, np.ndarray]:
    """2048 x 2048, 3 levels, zlib, 256-px tiles, 40000 px/cm (0.25 um/px)."""
    img = _image(2048, 2048)
    path = tmp_path_factory.mktemp("pyramid") / "slide.tif"
    lv1 = _box2(img).astype(np.uint8)
    _pyramid(
        path,
        [img, lv1, _box2(lv1).astype(np.uint8)],
        compression="zlib",
        resolution=(40000.0, 40000.0),
        resolutionunit="CENTIMETER",
    )
    return path, img


def _levels(path: Path) -> list[np.ndarray]:
    with tifffile.TiffFile(path) as tf:
        return [lv.asarray() for lv in tf.series[0].levels]


def test_pyramid_in_and_out(slide: tuple[Path, np.ndarray], tmp_path: Path) -> None:
    """sRGB -> Display P3 of a 3-level pyramid: 3 levels back, halved, tiled 256, zlib,
    resolution scaled per level; level 0 equals the in-memory conversion quantised to
    uint8; each reduced level equals the box mean of the processed level above (to the
    rounding, within 1 code) and of level 0 over 4 x 4 within 1 code."""
    src, img = slide
    r = process_chunked(src, tmp_path / "p3.tif", "convert", {"to": "display_p3"}, chunk=512)
    assert r.levels == ((2048, 2048), (1024, 1024), (512, 512))
    assert r.compression == "zlib" and r.dtype == "uint8"
    with tifffile.TiffFile(r.output) as tf:
        series = tf.series[0]
        assert [lv.shape for lv in series.levels] == [
            (2048, 2048, 3),
            (1024, 1024, 3),
            (512, 512, 3),
        ]
        for k, lv in enumerate(series.levels):
            page = lv.keyframe
            assert page.is_tiled and (page.tilewidth, page.tilelength) == (TILE, TILE)
            assert page.compression == tifffile.COMPRESSION.ADOBE_DEFLATE
            assert page.photometric == tifffile.PHOTOMETRIC.RGB
            assert page.tags["XResolution"].value[0] / page.tags["XResolution"].value[1] == (
                pytest.approx(40000.0 / 2**k)
            )
            assert page.tags["ResolutionUnit"].value == tifffile.RESUNIT.CENTIMETER
    out = _levels(r.output)
    ref = np.round(np.clip(np.asarray(convert(img, "srgb", "display_p3")), 0, 1) * 255)
    np.testing.assert_array_equal(out[0], ref.astype(np.uint8))
    np.testing.assert_array_equal(out[1], _box2(out[0]))  # integer box mean, half up
    np.testing.assert_array_equal(out[2], _box2(out[1]))
    assert np.abs(out[2].astype(int) - _box(out[0], 4)).max() <= 1


def test_pyramid_cli_and_none(
    slide: tuple[Path, np.ndarray], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    src, _ = slide
    out = tmp_path / "cli.tif"
    argv = ["chunked", "convert", str(src), "-o", str(out), "--to", "display-p3"]
    assert main([*argv, "--chunk", "512", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["levels"] == [[2048, 2048], [1024, 1024], [512, 512]]
    assert info["compression"] == "zlib"
    assert main([*argv, "--chunk", "512", "--pyramid", "none", "--force"]) == 0
    assert "2048 x 2048 uint8, " in capsys.readouterr().out
    with tifffile.TiffFile(out) as tf:
        assert len(tf.series[0].levels) == 1 and len(tf.pages) == 1
    # a pyramid into Zarr: level 0 only
    r = process_chunked(src, tmp_path / "o.zarr", "convert", {"to": "display_p3"}, chunk=512)
    assert r.levels == ((2048, 2048),) and r.compression is None


def test_build_a_pyramid_for_a_flat_input(tmp_path: Path) -> None:
    """A flat, odd-sized input with pyramid="build": halvings (ceil) until the short side
    fits in a tile; partial boxes at the edges average the pixels they have."""
    img = _image(1000, 1300)
    src = tmp_path / "flat.tif"
    tifffile.imwrite(src, img, tile=(TILE, TILE), photometric="rgb")
    r = process_chunked(src, tmp_path / "b.tif", "convert", {"to": "display_p3"}, chunk=512)
    assert r.levels == ((1000, 1300),)  # auto: a flat input stays flat
    r = process_chunked(
        src,
        tmp_path / "b.tif",
        "convert",
        {"to": "display_p3"},
        chunk=512,
        pyramid="build",
        force=True,
    )
    assert r.levels == ((1000, 1300), (500, 650), (250, 325))
    out = _levels(r.output)
    assert [o.shape[:2] for o in out] == list(r.levels)
    np.testing.assert_array_equal(out[1], _box(out[0], 2))
    np.testing.assert_array_equal(out[2], _box(out[1], 2))


def test_factor_four_pyramid_with_floor_sizes(tmp_path: Path) -> None:
    """An SVS-like pyramid, each level a quarter of the one above, sizes floored (1030 x 770
    -> 257 x 192): the same sizes come back, each level the 4 x 4 box mean within 1 code
    (the floored edge drops the partial box)."""
    img = _image(770, 1030, seed=5)
    lv1 = _box(img, 4)[:192, :257].astype(np.uint8)
    src = tmp_path / "svs.tif"
    _pyramid(src, [img, lv1], compression="zlib")
    r = process_chunked(src, tmp_path / "o.tif", "convert", {"to": "display_p3"}, chunk=512)
    assert r.levels == ((770, 1030), (192, 257))
    out = _levels(r.output)
    np.testing.assert_array_equal(out[1], _box(out[0], 4)[:192, :257])


def test_jpeg_slide_stays_jpeg_unless_float(tmp_path: Path) -> None:
    """A JPEG pyramid (as scanners write: YCbCr JPEG tiles) gives JPEG tiles back for uint8
    output, zlib for float32 output (JPEG holds 8 bits)."""
    img = _image(1024, 1024)
    src = tmp_path / "jpeg.tif"
    _pyramid(src, [img, _box2(img).astype(np.uint8)], compression="jpeg")
    r = process_chunked(src, tmp_path / "j.tif", "convert", {"to": "display_p3"}, chunk=512)
    assert r.compression == "jpeg" and len(r.levels) == 2
    with tifffile.TiffFile(r.output) as tf:
        assert tf.pages[0].compression == tifffile.COMPRESSION.JPEG
        decoded = tf.series[0].levels[0].asarray()
    with tifffile.TiffFile(src) as tf:
        ref_in = tf.series[0].levels[0].asarray()
    ref = np.round(np.clip(np.asarray(convert(ref_in, "srgb", "display_p3")), 0, 1) * 255)
    # one more JPEG generation (quality 90) costs about what the first did (noisy content)
    first = np.abs(ref_in.astype(float) - img).mean()
    assert np.abs(decoded.astype(float) - ref).mean() < 1.5 * first
    r = process_chunked(
        src, tmp_path / "f.tif", "convert", {"to": "linear_srgb"}, chunk=512, dtype="float32"
    )
    assert r.compression == "zlib"
    with pytest.raises(InvalidInputError, match="uint8 output for JPEG"):
        process_chunked(
            src,
            tmp_path / "g.tif",
            "convert",
            {"to": "linear_srgb"},
            chunk=512,
            dtype="float32",
            compression="jpeg",
        )


def _he_pyramid(tmp_path: Path) -> tuple[Path, Path]:
    """A 1024 x 1024 H&E-like slide (a synthetic tile mirrored 4 x 4) with 2 reduced levels,
    and a Macenko target measured on another tile."""
    from imageform.analysis import macenko_stains, synthetic_he_tile

    t = np.round(synthetic_he_tile((256, 256), rng=0).image * 255).astype(np.uint8)
    row = np.concatenate([t, t[:, ::-1], t, t[:, ::-1]], axis=1)
    img = np.concatenate([row, row[::-1], row, row[::-1]], axis=0)
    lv1 = _box2(img).astype(np.uint8)
    src = tmp_path / "he.tif"
    _pyramid(src, [img, lv1, _box2(lv1).astype(np.uint8)], compression="zlib")
    ref = np.round(synthetic_he_tile((256, 256), rng=1).image * 255).astype(np.uint8)
    target = tmp_path / "target.json"
    macenko_stains(ref).to_json(target)
    return src, target


def test_stain_statistics_from_a_reduced_level(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """stats_from="level" (auto on a pyramid) measures the slide on its largest level of at
    most STAIN_SAMPLE_PIXELS, read whole: the output within 3 codes of the statistics from
    every pixel of level 0 (subsample, below the budget), mean difference under 1 code."""
    import imageform.batch.chunked as ch

    src, target = _he_pyramid(tmp_path)
    opts = {"target": target, "method": "macenko"}
    full = process_chunked(
        src, tmp_path / "full.tif", "stain_normalize", opts, chunk=512, stats_from="subsample"
    )
    assert full.stats_from == "level 0, every pixel"
    mp = pytest.MonkeyPatch()
    mp.setattr(ch, "STAIN_SAMPLE_PIXELS", 512 * 512)
    try:
        lvl = process_chunked(src, tmp_path / "lvl.tif", "stain_normalize", opts, chunk=512)
    finally:
        mp.undo()
    assert lvl.stats_from == "pyramid level 1 (512 x 512)"
    argv = ["chunked", "stain-normalize", str(src), "-o", str(tmp_path / "cli.tif")]
    argv += ["--target", str(target), "--stats-from", "level", "--chunk", "512", "--json"]
    assert main(argv) == 0
    assert json.loads(capsys.readouterr().out)["stats_from"] == "pyramid level 1 (512 x 512)"
    a, b = _levels(full.output)[0].astype(int), _levels(lvl.output)[0].astype(int)
    assert np.abs(a - b).max() <= 3 and np.abs(a - b).mean() < 1.0  # measured: 2, 0.52


def test_bad_pyramids_and_options(tmp_path: Path) -> None:
    """One-line refusals: a level that is not a whole factor smaller, a non-RGB level,
    statistics from a level of a flat input, a pyramid into Zarr."""
    img = _image(512, 512)
    bad = tmp_path / "bad.tif"
    _pyramid(bad, [img, _image(200, 300)])
    with pytest.raises(InvalidInputError, match=r"level 1 is 300 x 200, not level 0 \(512 x 512\)"):
        process_chunked(bad, tmp_path / "o.tif", "convert", {"to": "display_p3"}, chunk=512)
    grey = tmp_path / "grey.tif"
    with tifffile.TiffWriter(grey) as tw:
        tw.write(img, subifds=1, tile=(TILE, TILE), photometric="rgb")
        tw.write(img[::2, ::2, 0], subfiletype=1, tile=(TILE, TILE), photometric="minisblack")
    with pytest.raises(InvalidInputError, match=r"level 1 is uint8 \(256, 256\); expected RGB"):
        process_chunked(grey, tmp_path / "o.tif", "convert", {"to": "display_p3"}, chunk=512)
    flat = tmp_path / "flat.tif"
    tifffile.imwrite(flat, img, tile=(TILE, TILE), photometric="rgb")
    _, target = _he_pyramid(tmp_path)
    with pytest.raises(InvalidInputError, match="stats-from level needs a pyramidal"):
        process_chunked(
            flat, tmp_path / "o.tif", "stain_normalize", {"target": target}, stats_from="level"
        )
    with pytest.raises(InvalidInputError, match=r"pyramid build needs a \.tif"):
        process_chunked(flat, tmp_path / "o.zarr", "convert", {"to": "srgb"}, pyramid="build")
    with pytest.raises(UnknownOptionError, match="pyramid"):
        process_chunked(flat, tmp_path / "o.tif", "convert", {"to": "srgb"}, pyramid="all")
    with pytest.raises(UnknownOptionError, match="compression"):
        process_chunked(flat, tmp_path / "o.tif", "convert", {"to": "srgb"}, compression="lzma")
    assert not (tmp_path / "o.tif").exists() and not (tmp_path / "o.zarr").exists()
    assert not list(tmp_path.glob(".*"))  # no temporaries or spooled levels left


_CHILD = textwrap.dedent(
    """
    import resource, sys, tempfile, pathlib
    import numpy as np, tifffile
    from imageform.batch import process_chunked

    src, chunk = pathlib.Path(sys.argv[1]), int(sys.argv[2])
    opts = {"to": "display_p3"}
    d = pathlib.Path(tempfile.mkdtemp(dir=src.parent))
    warm = d / "warm.tif"  # imports, numba compilation and thread pools before measuring
    tifffile.imwrite(warm, np.full((chunk, chunk, 3), 128, np.uint8), tile=(256, 256),
                     photometric="rgb")
    process_chunked(warm, d / "w.tif", "convert", opts, chunk=chunk, num_workers=2,
                    pyramid="build")
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    r = process_chunked(src, d / "out.tif", "convert", opts, chunk=chunk, num_workers=2)
    after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    print(before * 1024, after * 1024, len(r.levels))
    """
)


def test_memory_bounded_on_a_pyramid(tmp_path: Path) -> None:
    """A 4096 x 4096, 3-level zlib pyramid (48 MiB as uint8 at level 0; 12 MiB at level 1)
    processed in a fresh process: the peak RSS grows by less than levels 0 and 1 written
    (measured: 41 MiB, after a warm-up on one 512-px block; a band of 512 rows is 6 MiB);
    the reduced levels are spooled to disk, never held whole, and the in-memory path would
    hold level 0 plus its float copies (192 MiB each)."""
    n = 4096
    src = tmp_path / "big.tif"

    def tiles(m: int):  # written tile by tile: the test process never holds the image
        rng = np.random.default_rng(0)
        for _ in range((m // TILE) ** 2):
            yield rng.integers(0, 256, (TILE, TILE, 3), dtype=np.uint8)

    opts = {"dtype": np.uint8, "tile": (TILE, TILE), "photometric": "rgb", "compression": "zlib"}
    with tifffile.TiffWriter(src) as tw:
        tw.write(tiles(n), shape=(n, n, 3), subifds=2, **opts)
        for m in (n // 2, n // 4):
            tw.write(tiles(m), shape=(m, m, 3), subfiletype=1, **opts)
    import imageform

    env = {**os.environ, "PYTHONPATH": str(Path(imageform.__file__).parents[1])}
    proc = subprocess.run(
        [sys.executable, "-c", _CHILD, str(src), "512"],
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
        check=True,
    )
    before, after, levels = (int(v) for v in proc.stdout.split())
    assert levels == 3
    assert after - before < n * n * 3 * 5 // 4, (before, after)


def test_ome_tiff_pyramid_keeps_its_pixel_size(tmp_path: Path) -> None:
    """An OME-TIFF pyramid (0.25 um/px in its OME-XML) gives an OME-TIFF pyramid with the
    same PhysicalSizeX/Y, and resolution tags of 40000 px/cm at level 0, 20000 at level 1;
    an Aperio header's MPP is read the same way."""
    from imageform.io import pixel_size_um

    img = _image(512, 512)
    src = tmp_path / "in.ome.tif"
    kw = {"tile": (TILE, TILE), "photometric": "rgb"}
    with tifffile.TiffWriter(src, ome=True) as tw:
        meta = {"axes": "YXS", "PhysicalSizeX": 0.25, "PhysicalSizeY": 0.25}
        tw.write(img, subifds=1, metadata=meta, **kw)
        tw.write(_box2(img).astype(np.uint8), subfiletype=1, **kw)
    r = process_chunked(src, tmp_path / "out.ome.tif", "convert", {"to": "display_p3"}, chunk=256)
    assert r.levels == ((512, 512), (256, 256))
    with tifffile.TiffFile(r.output) as tf:
        assert tf.is_ome
        assert 'PhysicalSizeX="0.25"' in tf.pages[0].description
        levels = tf.series[0].levels
        assert [lv.keyframe.tags["XResolution"].value for lv in levels] == [(40000, 1), (20000, 1)]
    header = "Aperio Image Library v10.0.51\r\n46920x33014 (256x256) JPEG/RGB Q=30|MPP = 0.4990"
    svs = tmp_path / "aperio.tif"
    tifffile.imwrite(svs, img[:64, :64], description=header)
    assert pixel_size_um(svs) == (0.499, 0.499)
