"""imageform.batch.process_chunked / ``imageform chunked``: a tiled TIFF or Zarr array processed
block by block gives the in-memory numbers, with memory bounded by a band, not the image."""

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
from imageform.color import convert, white_balance
from imageform.errors import InvalidInputError, UnknownOptionError

tifffile = pytest.importorskip("tifffile")
zarr = pytest.importorskip("zarr")
pytest.importorskip("dask.array")

H, W, TILE = 1024, 1536, 256


def _image(h: int = H, w: int = W) -> np.ndarray:
    """A smooth colour ramp with noise (all 256 codes present, no empty channel)."""
    rng = np.random.default_rng(3)
    yy, xx = np.mgrid[0:h, 0:w]
    base = np.stack([xx / w, yy / h, 0.5 + 0.4 * np.sin(xx / 37.0)], axis=-1) * 230 + 10
    return np.clip(base + rng.normal(0, 8, base.shape), 0, 255).astype(np.uint8)


@pytest.fixture(scope="module")
def tiled(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, np.ndarray]:
    img = _image()
    path = tmp_path_factory.mktemp("chunked") / "slide.tif"
    tifffile.imwrite(path, img, tile=(TILE, TILE), photometric="rgb")
    return path, img


def _read(path: Path) -> np.ndarray:
    if path.suffix == ".zarr":
        return np.asarray(zarr.open(str(path), mode="r")[...])
    with tifffile.TiffFile(path) as tf:
        assert tf.pages[0].is_tiled
        return tf.asarray()


def test_convert_equals_in_memory(tiled: tuple[Path, np.ndarray], tmp_path: Path) -> None:
    src, img = tiled
    ref = np.asarray(convert(img, "srgb", "linear_srgb"))
    r = process_chunked(
        src, tmp_path / "lin.zarr", "convert", {"to": "linear_srgb"}, chunk=512, dtype="float32"
    )
    assert (r.shape, r.dtype, r.clipped) == ((H, W, 3), "float32", 0)
    np.testing.assert_array_equal(_read(r.output), ref)


def test_convert_to_tiled_tiff_uint8(tiled: tuple[Path, np.ndarray], tmp_path: Path) -> None:
    src, img = tiled
    ref = np.asarray(convert(img, "srgb", "display_p3"))
    r = process_chunked(src, tmp_path / "p3.tif", "convert", {"to": "display_p3"}, chunk=512)
    assert r.dtype == "uint8"
    codes = np.round(ref.astype(np.float64) * 255)  # clipped: the values whose code the clip moves
    assert r.clipped == int(np.count_nonzero((codes < 0) | (codes > 255)))
    expected = np.round(np.clip(ref, 0, 1) * 255).astype(np.uint8)
    np.testing.assert_array_equal(_read(r.output), expected)
    # the output is itself a valid chunked input (Zarr store of the tiled TIFF)
    r2 = process_chunked(r.output, tmp_path / "back.zarr", "convert", {"to": "srgb"}, chunk=256)
    assert _read(r2.output).shape == (H, W, 3)


@pytest.mark.parametrize(
    ("options", "kw"),
    [
        ({"method": "gray-world"}, {}),
        ({"method": "shades-of-gray", "p": 6.0}, {"p": 6.0}),
        ({"method": "manual", "illuminant": "A", "normalize": "green"}, {}),
    ],
)
def test_white_balance_global_gains(
    tiled: tuple[Path, np.ndarray], tmp_path: Path, options: dict, kw: dict
) -> None:
    """The grey-world / shades-of-grey illuminant is a reduction over every block (float64
    sums): the gains and the image equal the in-memory white_balance of the image in float64.

    (The in-memory path on uint8/float32 input accumulates its means in float32 along a
    strided axis, which is off by ~5e-4 relative on this 1.6 Mpx image; the chunked
    reduction is the more accurate one, so float64 is the reference.)"""
    src, img = tiled
    method = options["method"].replace("-", "_")
    extra = {k: options[k] for k in ("illuminant", "normalize") if k in options}
    ref, gains = white_balance(img / 255.0, method, **kw, **extra)
    r = process_chunked(
        src, tmp_path / "wb.tif", "white_balance", options, chunk=512, dtype="float32"
    )
    np.testing.assert_allclose(r.gains, np.asarray(gains), rtol=1e-5)
    np.testing.assert_allclose(_read(r.output), np.asarray(ref), rtol=1e-5, atol=1e-6)


def test_zarr_input_and_cli(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    img = _image(300, 500)
    src = tmp_path / "in.zarr"
    z = zarr.create_array(store=str(src), shape=img.shape, chunks=(128, 128, 3), dtype="uint8")
    z[...] = img
    out = tmp_path / "out.tif"
    argv = ["chunked", "white-balance", str(src), "-o", str(out), "--chunk", "256", "--json"]
    assert main(argv) == 0
    info = json.loads(capsys.readouterr().out)
    expected, _ = white_balance(img / 255.0)
    q = np.round(np.clip(np.asarray(expected), 0, 1) * 255).astype(np.uint8)
    got = _read(out)
    assert info["dtype"] == "uint8" and info["shape"] == [300, 500, 3]
    assert np.abs(got.astype(int) - q).max() <= 1  # float32 sums may move a code at a .5
    assert main(argv) == 1 and "exists; pass --force" in capsys.readouterr().err
    assert main([*argv, "--force"]) == 0


def test_errors(tiled: tuple[Path, np.ndarray], tmp_path: Path) -> None:
    src, _ = tiled
    with pytest.raises(
        UnknownOptionError, match="valid: 'convert', 'stain_normalize', 'white_balance'"
    ):
        process_chunked(src, tmp_path / "o.zarr", "demosaic")
    streams = "streams the white-balance methods 'gray_world', 'shades_of_gray', 'manual' only"
    with pytest.raises(UnknownOptionError, match=f"{streams}, got 'white-patch'"):
        process_chunked(src, tmp_path / "o.zarr", "white_balance", {"method": "white-patch"})
    with pytest.raises(UnknownOptionError, match="valid: 'gray_world', 'manual', 'shades_of_gray'"):
        process_chunked(src, tmp_path / "o.zarr", "white_balance", {"method": "nope"})
    with pytest.raises(InvalidInputError, match="is the input"):
        process_chunked(src, src, "convert", {"to": "srgb"})
    with pytest.raises(InvalidInputError, match="use float32"):
        process_chunked(src, tmp_path / "o.zarr", "convert", {"to": "lab"}, dtype="uint8")
    with pytest.raises(InvalidInputError, match="multiple of tile"):
        process_chunked(src, tmp_path / "o.tif", "convert", {"to": "srgb"}, chunk=300)
    with pytest.raises(InvalidInputError, match=r"tiled \.tif/\.tiff or a \.zarr"):
        process_chunked(src, tmp_path / "o.png", "convert", {"to": "srgb"})
    assert not list(tmp_path.iterdir())  # nothing half-written


_CHILD = textwrap.dedent(
    """
    import resource, sys, tempfile, pathlib
    import numpy as np, tifffile
    from imageform.batch import process_chunked

    src, chunk, cmd = pathlib.Path(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
    opts = {"to": "display_p3"} if cmd == "convert" else {}
    d = pathlib.Path(tempfile.mkdtemp(dir=src.parent))
    warm = d / "warm.tif"  # imports, numba compilation and thread pools before measuring
    tifffile.imwrite(warm, np.full((chunk, chunk, 3), 128, np.uint8), tile=(256, 256),
                     photometric="rgb")
    process_chunked(warm, d / "w.tif", cmd, opts, chunk=chunk, num_workers=2)
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    process_chunked(src, d / "out.tif", cmd, opts, chunk=chunk, num_workers=2)
    after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    print(before * 1024, after * 1024)
    """
)


@pytest.mark.parametrize(
    "command", ["convert", pytest.param("white_balance", marks=pytest.mark.slow)]
)
def test_memory_bounded(tmp_path: Path, command: str) -> None:
    """sRGB -> Display P3 (one pass), or white balance (two: a global reduction, then the
    pointwise pass; slow), of a 4096 x 4096 RGB tiled TIFF (48 MiB as uint8; 192 MiB per
    float32 copy, which the in-memory path makes several of) in a fresh process: the peak
    RSS grows by less than the uint8 image itself (measured: ~32 MiB; a band of 512 rows is
    6 MiB, a block 3 MiB per float32 copy). benchmarks/bench_chunked.py goes to 20000^2."""
    n = 4096
    src = tmp_path / "big.tif"

    def tiles():  # written tile by tile: the test process never holds the image
        rng = np.random.default_rng(0)
        for _ in range((n // TILE) ** 2):
            yield rng.integers(0, 256, (TILE, TILE, 3), dtype=np.uint8)

    tifffile.imwrite(
        src, tiles(), shape=(n, n, 3), dtype=np.uint8, tile=(TILE, TILE), photometric="rgb"
    )
    import imageform

    env = {**os.environ, "PYTHONPATH": str(Path(imageform.__file__).parents[1])}
    proc = subprocess.run(
        [sys.executable, "-c", _CHILD, str(src), "512", command],
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
        check=True,
    )
    before, after = (int(v) for v in proc.stdout.split())
    image_bytes = n * n * 3
    assert after - before < image_bytes, (before, after)


def _strip_tiff(path: Path, n: int) -> None:
    """An n x n RGB uint8 TIFF in one uncompressed strip (tifffile's and many scanners'
    default layout), written band by band: the test process never holds the image."""
    rng = np.random.default_rng(0)
    with tifffile.TiffWriter(path) as tw:
        tw.write(shape=(n, n, 3), dtype=np.uint8, photometric="rgb", rowsperstrip=n)
        for _ in range(n // TILE):
            tw.filehandle.write(rng.integers(0, 256, (TILE, n, 3), dtype=np.uint8).tobytes())


@pytest.mark.parametrize("layout", ["one strip", "zlib strips"])
def test_strip_tiffs_equal_in_memory(tmp_path: Path, layout: str) -> None:
    img = _image(600, 700)
    src = tmp_path / "strips.tif"
    if layout == "one strip":
        tifffile.imwrite(src, img, photometric="rgb")
        with tifffile.TiffFile(src) as tf:
            assert not tf.pages[0].is_tiled and len(tf.pages[0].dataoffsets) == 1
    else:
        tifffile.imwrite(src, img, photometric="rgb", rowsperstrip=16, compression="zlib")
    ref = np.asarray(convert(img, "srgb", "display_p3"))
    r = process_chunked(src, tmp_path / "p3.tif", "convert", {"to": "display_p3"}, chunk=256)
    expected = np.round(np.clip(ref, 0, 1) * 255).astype(np.uint8)
    np.testing.assert_array_equal(_read(r.output), expected)


def test_memory_bounded_on_a_one_strip_tiff(tmp_path: Path) -> None:
    """The same bound on an untiled TIFF stored as one uncompressed strip, which tifffile's
    Zarr store offers as one chunk (the whole image, read again for every block: measured
    +190 MiB at 4096^2 and +522 MiB at 8192^2 before, benchmarks/results/chunked-strips-*):
    the strip is read row band by row band."""
    n = 4096
    src = tmp_path / "big.tif"
    _strip_tiff(src, n)
    import imageform

    env = {**os.environ, "PYTHONPATH": str(Path(imageform.__file__).parents[1])}
    proc = subprocess.run(
        [sys.executable, "-c", _CHILD, str(src), "512", "convert"],
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
        check=True,
    )
    before, after = (int(v) for v in proc.stdout.split())
    assert after - before < n * n * 3, (before, after)


def _he_slide(tmp_path: Path, shape: tuple[int, int], seed: int) -> tuple[Path, np.ndarray]:
    from imageform.analysis import synthetic_he_tile

    img = np.round(synthetic_he_tile(shape, rng=seed).image * 255).astype(np.uint8)
    path = tmp_path / f"slide{seed}.tif"
    tifffile.imwrite(path, img, tile=(256, 256), photometric="rgb")
    return path, img


@pytest.mark.parametrize("method", ["macenko", "reinhard"])
def test_stain_normalize_equals_in_memory(
    tmp_path: Path, method: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """A slide below the sample budget: its statistics come from every pixel, so the chunked
    result equals `imageform stain-normalize` in memory (same target JSON), to one code;
    through `imageform chunked stain-normalize` too."""
    from imageform import analysis
    from imageform.io import read_image

    src, _img = _he_slide(tmp_path, (640, 768), 0)
    _, ref = _he_slide(tmp_path, (256, 256), 1)
    measure = analysis.macenko_stains if method == "macenko" else analysis.reinhard_stats
    target = tmp_path / "target.json"
    measure(ref).to_json(target)
    r = process_chunked(
        src,
        tmp_path / "out.tif",
        "stain_normalize",
        {"target": target, "method": method},
        chunk=256,
    )
    assert r.dtype == "uint8" and r.shape == (640, 768, 3)
    out = tifffile.imread(r.output)
    assert (
        main(
            [
                "stain-normalize",
                str(src),
                "--target",
                str(target),
                "--method",
                method,
                "-o",
                str(tmp_path / "mem.png"),
            ]
        )
        == 0
    )
    mem = read_image(tmp_path / "mem.png")
    mem8 = np.round(mem * 255).astype(int) if mem.dtype.kind == "f" else mem.astype(int)
    assert np.abs(out.astype(int) - mem8).max() <= 1
    capsys.readouterr()
    argv = [
        "chunked",
        "stain-normalize",
        str(src),
        "-o",
        str(tmp_path / "cli.zarr"),
        "--target",
        str(target),
        "--method",
        method,
        "--chunk",
        "256",
        "--dtype",
        "float32",
    ]
    assert main(argv) == 0, capsys.readouterr().err
    z = np.asarray(zarr.open(str(tmp_path / "cli.zarr"), mode="r"))
    assert np.abs(z * 255 - out).max() <= 0.51


def test_stain_normalize_scale_by_mean_equals_in_memory(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`chunked stain-normalize --scale-by mean` is Macenko's mean-concentration reference, as
    `stain-normalize --scale-by mean` in memory (to one code), unlike the default; with
    reinhard it is refused in one line and nothing is written."""
    from imageform import analysis
    from imageform.io import read_image

    src, _img = _he_slide(tmp_path, (384, 384), 4)
    _, ref = _he_slide(tmp_path, (256, 256), 5)
    target = tmp_path / "target.json"
    analysis.macenko_stains(ref).to_json(target)
    opts = {"target": target, "method": "macenko", "scale_by": "mean"}
    r = process_chunked(src, tmp_path / "out.tif", "stain_normalize", opts, chunk=128)
    out = tifffile.imread(r.output).astype(int)
    argv = ["stain-normalize", str(src), "--target", str(target), "--scale-by", "mean"]
    assert main([*argv, "-o", str(tmp_path / "mem.png")]) == 0
    assert np.abs(out - read_image(tmp_path / "mem.png").astype(int)).max() <= 1
    default = process_chunked(src, tmp_path / "max.tif", "stain_normalize", {"target": target})
    assert not np.array_equal(tifffile.imread(default.output), out)
    capsys.readouterr()
    bad = tmp_path / "bad.tif"
    argv = ["chunked", "stain-normalize", str(src), "-o", str(bad), "--target", str(target)]
    assert main([*argv, "--method", "reinhard", "--scale-by", "mean"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--scale-by mean goes with --method macenko only" in err
    assert not bad.exists()


def test_stain_normalize_statistics_from_a_subsample(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Above the budget the slide's stains come from every s-th row and column: with the
    budget cut to a quarter of the slide (s = 2), the stain vectors are within 1 degree of the
    full image's and the output within 2 codes."""
    import imageform.batch.chunked as ch
    from imageform import analysis

    src, img = _he_slide(tmp_path, (512, 512), 2)
    _, ref = _he_slide(tmp_path, (256, 256), 3)
    target = tmp_path / "t.json"
    analysis.macenko_stains(ref).to_json(target)
    monkeypatch.setattr(ch, "STAIN_SAMPLE_PIXELS", 512 * 512 // 4)
    r = process_chunked(src, tmp_path / "o.tif", "stain_normalize", {"target": target}, chunk=256)
    out = tifffile.imread(r.output).astype(int)
    full = analysis.macenko_normalize(img, analysis.MacenkoStains.from_json(target))
    assert np.abs(out - np.round(np.asarray(full) * 255)).max() <= 2
    sub = analysis.macenko_stains(img[::2, ::2])
    whole = analysis.macenko_stains(img)
    for k in range(2):
        assert analysis.stain_angle(sub.stain_matrix[k], whole.stain_matrix[k]) < 1.0


def test_stain_normalize_refusals(tmp_path: Path) -> None:
    src, _ = _he_slide(tmp_path, (256, 256), 0)
    with pytest.raises(InvalidInputError, match="target"):
        process_chunked(
            src,
            tmp_path / "o.tif",
            "stain_normalize",
            {"target": tmp_path / "missing.json"},
            chunk=256,
        )
    with pytest.raises(InvalidInputError, match="save-target"):
        process_chunked(
            src,
            tmp_path / "o.tif",
            "stain_normalize",
            {"target": src, "save_target": tmp_path / "s.json"},
            chunk=256,
        )
    assert not (tmp_path / "o.tif").exists()


@pytest.mark.parametrize(
    ("layout", "decodes"),
    [("one-tile", 1), ("big-tiles", 4), ("strips", 1024 // 64)],
)
def test_each_tile_or_strip_is_decoded_once(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, layout: str, decodes: int
) -> None:
    """Issue 25: a whole-image tile (or strip) was decoded again for every block inside it (a
    16384^2 single-tile TIFF took > 420 s). Each TIFF tile or strip is decoded once, while
    the blocks inside it are processed; the output is the in-memory one."""
    img = _image(1024, 1024)
    src = tmp_path / f"{layout}.tif"
    kw: dict[str, object] = {
        "one-tile": {"tile": (1024, 1024)},
        "big-tiles": {"tile": (512, 512)},
        "strips": {"rowsperstrip": 64},
    }[layout]  # type: ignore[assignment]
    tifffile.imwrite(src, img, photometric="rgb", compression="zlib", **kw)
    calls = []
    real = tifffile.TiffPage.decode.func  # a cached_property: the function that makes it

    def counting(self):  # type: ignore[no-untyped-def]
        fn = real(self)

        def decode(*a, **k):  # type: ignore[no-untyped-def]
            calls.append(1)
            return fn(*a, **k)

        return decode

    monkeypatch.setattr(tifffile.TiffPage, "decode", property(lambda self: counting(self)))
    r = process_chunked(src, tmp_path / "out.zarr", "convert", {"to": "display_p3"}, chunk=128)
    assert len(calls) == decodes
    ref = np.asarray(convert(img, "srgb", "display_p3"))
    got = _read(r.output)
    np.testing.assert_allclose(got / np.iinfo(got.dtype).max, np.clip(ref, 0, 1), atol=0.51 / 255)


def test_convert_of_a_linear_tagged_integer_tiff(tmp_path: Path) -> None:
    """A uint8 TIFF tagged linear (scRGB profile): its codes are linear light / 255."""
    from imageform.io import icc_profile

    img = _image(256, 512)
    src = tmp_path / "linear.tif"
    tifffile.imwrite(src, img, tile=(TILE, TILE), photometric="rgb",
                     iccprofile=icc_profile("linear_srgb"))  # fmt: skip
    r = process_chunked(src, tmp_path / "s.zarr", "convert", {"to": "srgb"}, dtype="float32")
    ref = np.asarray(convert(img.astype(np.float32) / 255, "linear_srgb", "srgb"))
    np.testing.assert_allclose(_read(r.output), ref, atol=1e-6)


def test_the_output_declares_its_colour_space(tmp_path: Path) -> None:
    """What ``chunked`` writes, ``info`` and every ``--from auto`` reader read back: a space
    without a profile (Lab) named in the description, a profiled one embedded, and white
    balance keeping the input's profile (they all read back as sRGB; a Lab output converted
    'from auto' was copied as sRGB and clipped)."""
    from imageform.io import image_color_space, read_image

    src = tmp_path / "in.tif"
    img = _image(256, 384)
    tifffile.imwrite(src, img, tile=(128, 128), photometric="rgb")
    lab = tmp_path / "lab.tif"
    assert main(["chunked", "convert", str(src), "--to", "lab", "-o", str(lab)]) == 0
    declared = image_color_space(lab)
    assert (declared.name, declared.source) == ("lab", "tiff-description")
    back = tmp_path / "back.tif"
    assert main(["convert", str(lab), "--from", "auto", "--to", "srgb", "-o", str(back)]) == 0
    np.testing.assert_allclose(read_image(back), img / 255.0, atol=1e-4)
    p3 = tmp_path / "p3.tif"
    assert main(["chunked", "convert", str(src), "--to", "display-p3", "-o", str(p3)]) == 0
    assert image_color_space(p3).name == "display_p3"
    wb = tmp_path / "wb.tif"
    assert main(["chunked", "white-balance", str(p3), "-o", str(wb)]) == 0
    assert image_color_space(wb).name == "display_p3"
    # an sRGB output declares nothing, as write_image writes it
    srgb = tmp_path / "srgb.tif"
    assert main(["chunked", "convert", str(lab), "--from", "auto", "-o", str(srgb)]) == 0
    assert image_color_space(srgb).name is None


def test_white_balance_of_a_linear_file_is_linear(tmp_path: Path) -> None:
    """A file that declares linear light is balanced as linear, by the single command and by
    chunked alike (both decoded it with sRGB's curve: gains 0.51/1.22/4.90 for a grey world
    tinted 0.9/0.6/0.3 in linear light, where 2/3, 1, 2 balance it)."""
    from imageform.io import image_color_space, read_image, write_image

    rng = np.random.default_rng(1)
    lin = (rng.random((256, 256, 3)) * [0.9, 0.6, 0.3]).astype(np.float32)
    src = tmp_path / "tint.tif"
    write_image(src, lin, color_space="linear_srgb")
    one, many = tmp_path / "one.tif", tmp_path / "many.tif"
    assert main(["white-balance", str(src), "-o", str(one), "--json"]) == 0
    assert main(["chunked", "white-balance", str(src), "-o", str(many), "--chunk", "128"]) == 0
    gains = lin.mean(axis=(0, 1)).mean() / lin.mean(axis=(0, 1))
    np.testing.assert_allclose(gains, [2 / 3, 1, 2], rtol=0.02)
    for out in (one, many):
        np.testing.assert_allclose(read_image(out), lin * gains, atol=1e-5)
        assert image_color_space(out).name == "linear_srgb"
