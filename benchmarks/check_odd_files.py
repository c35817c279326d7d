"""Robustness sweep of the command line and the image reader over real-world image files.

Run::

    PYTHONPATH=src:. python benchmarks/check_odd_files.py --gather /work/.mirror FOLDER
    PYTHONPATH=src:. python benchmarks/check_odd_files.py FOLDER

``--chain`` runs :mod:`benchmarks.check_odd_files_chain` instead (commands chained as a
user chains them, their values checked against colour-science; ``--chain --compare BEFORE
AFTER`` sets two of its tables side by side).

``--gather MIRRORS`` first fills FOLDER: the files of :data:`SOURCES` copied out of local bare
git mirrors of their public repositories (``MIRRORS/<owner>+<name>/repo``, the commit named in
the table; nothing is downloaded), and the edge cases of :func:`make_edge_cases` written here
(1x1, 1xN, 65535x1, 16-bit grey, RGBA, truncated, zero bytes, text named .png, animated GIF,
TIFF with 4, 5 and 7 channels, a stack of two narrow grey pages, a CMYK JPEG with and without
a CMYK ICC profile, floats of 0-4000, WebP lossy/lossless/alpha/EXIF-turned/animated,
BMP of 1, 8 and 24 bits, RLE8, RLE4, top-down, GIF with a palette and a transparent index,
spaces and non-ASCII letters in names). The files stay outside the repository. ``--only TEXT``
sweeps the files whose names contain TEXT (a re-run on the files a change touches).

Then every file goes through each command class, in one worker process per file (the CLI's
``main`` called in-process, stdout and stderr captured; a class slower than 120 s counts as a
hang): ``read`` (``read_image`` against another decoder chosen by the file's bytes: OpenCV for
PNG, tifffile and the TIFF 6.0 rules for TIFF, Pillow with ``exif_transpose`` otherwise; shape
after orientation, sample type and values), ``info`` (its size and channels against those
read; the note: the colour space the file declares), ``convert`` (to Lab, TIFF; the note: the
space it read the file in), ``white-balance``, ``delta-e`` (the file against itself: ΔE must
be 0), ``cvd``, ``segment``, ``stain-normalize`` (Reinhard, the file its own target),
``flatfield`` (radial), ``chart``, ``vanishing``, ``undistort --from-lines``, ``sfr``,
``mosaic`` then ``demosaic`` of its mosaic, ``develop``. Each gets one verdict: **fine** (exit
0, outputs of the upright input's size), **error** (exit 1 or 2 with one line on stderr, no
output left behind), **noisy** (exit 1 or 2 with more than that line on stderr), **crash** (a
traceback, an "unexpected" error, an exit code other than 0/1/2), **wrong** (exit 0 but a wrong
result: output of another size than the upright input, ΔE of a file to itself not 0, the
reader disagreeing with the reference decoder), **hang**. The input file's bytes are hashed
before and after every command: a changed input is **wrong**. (What libpng writes straight to
the process's stderr, below Python, is not seen here.)
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import io
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

#: (file name in FOLDER, repository, commit, path in it, licence).
SOURCES: tuple[tuple[str, str, str, str, str], ...] = tuple(
    (name, repo, commit, path, lic)
    for repo, commit, lic, files in (
        (
            "immich-app/test-assets",
            "ec56cc6c1d76c45bc9615dc6ea232470a2b0a3a1",
            "public domain (README)",
            (
                ("immich el_torcal_rocks.jpg", "formats/jpg/el_torcal_rocks.jpg"),
                ("immich IMG_2682.heic", "formats/heic/IMG_2682.heic"),
                ("immich 8bit-sRGB.avif", "formats/avif/8bit-sRGB.avif"),
                ("immich denali.webp", "formats/webp/denali.webp"),
                ("immich 8bit-sRGB.jxl", "formats/jxl/8bit-sRGB.jxl"),
                ("immich density_plot.png", "formats/png/density_plot.png"),
                ("immich portrait-orientation-6.jpg", "metadata/faces/portrait-orientation-6.jpg"),
            ),
        ),
        (
            "recurser/exif-orientation-examples",
            "219294e144531b0c01247913cb58b6f5531b5081",
            "MIT",
            tuple((f"exif Landscape_{k}.jpg", f"Landscape_{k}.jpg") for k in range(9))
            + (("exif Portrait_5.jpg", "Portrait_5.jpg"),),
        ),
        (
            "tlnagy/exampletiffs",
            "b12f16b3397f40bc67f9726305dcda0093da597c",
            "BSD-3-Clause (README table)",
            tuple(
                (f"tiff {n}", n)
                for n in (
                    "spring.tif",
                    "poppies.tif",
                    "capitol.tif",
                    "coffee.tif",
                    "julia.tif",
                    "shapes_jpg.tif",
                    "shapes_lzw_12bps.tif",
                    "shapes_lzw_palette.tif",
                    "shapes_lzw_planar_10bps.tif",
                    "shapes_lzw_predictor3.tif",
                    "shapes_lzw_tiled_planar.tif",
                    "shapes_hyper.tif",
                )
            ),
        ),
        (
            "tlnagy/exampletiffs",
            "b12f16b3397f40bc67f9726305dcda0093da597c",
            "CC BY 4.0 (README table)",
            (
                ("tiff 4D-series.ome.tif", "4D-series.ome.tif"),
                ("tiff single-channel.ome.tif", "ometiff_testdata/singles/single-channel.ome.tif"),
            ),
        ),
        (
            "tlnagy/exampletiffs",
            "b12f16b3397f40bc67f9726305dcda0093da597c",
            "unknown (README table: '?'; MIT? for house.tif)",
            (("tiff flagler.tif", "flagler.tif"), ("tiff house.tif", "house.tif")),
        ),
        (
            "lunapaint/pngsuite",
            "8cd768dd0d0063195174d0d01cacbd5a7d1e5605",
            "PngSuite licence (free use, Willem van Schaik)",
            tuple(
                (f"pngsuite {n}.png", f"png/{n}.png")
                for n in (
                    "basn0g01",
                    "basn0g16",
                    "basn2c16",
                    "basn3p04",
                    "basn4a16",
                    "basn6a16",
                    "tbrn2c08",
                    "tp1n3p08",
                    "exif2c08",
                    "s01i3p01",
                    "xc1n0g08",
                    "xd3n2c08",
                    # file gammas 0.35 to 2.5 in gAMA (no iCCP, no sRGB), sRGB's cHRM
                    "g03n2c08",
                    "g04n2c08",
                    "g05n0g16",
                    "g10n2c08",
                    "g25n2c08",
                    "ccwn2c08",
                )
            ),
        ),
        (
            "lunapaint/pngsuite",
            "8cd768dd0d0063195174d0d01cacbd5a7d1e5605",
            "PngSuite licence (free use, Willem van Schaik)",
            tuple(  # PngSuite as 32-bit BMPs (BITFIELDS, V5 header, alpha; Paint.NET)
                (f"pngsuite {n}.bmp", f"bmp/{n}.bmp") for n in ("basn2c08", "basn6a08", "tbrn2c08")
            ),
        ),
        (
            "mapillary/OpenSfM",
            "238744cdf3b5d50149c50d136a87f7fea25ad5cd",
            "BSD-2-Clause",
            (
                ("opensfm berlin 01.jpg", "data/berlin/images/01.jpg"),
                ("opensfm lund 01.jpg", "data/lund/images/01.jpg"),
                ("opensfm preloader.gif", "viewer/legacy/images/preloader.gif"),
            ),
        ),
        (
            "DurrLab/C3VDv3",
            "ad9391d84fc18fc22fc70d4e4beadfde4e757fa4",
            "CC BY 4.0 (README)",
            (("c3vd aligned_prev_final.gif", "assets/aligned_prev_final.gif"),),
        ),
        (
            "EIDOSLAB/torchstain",
            "c94179d140c0201cd85476032889844bdea37a8a",
            "MIT",
            (("torchstain source.png", "data/source.png"),),
        ),
        (
            "choosehappy/HistoQC",
            "b79561292e49d153e2e4c1401c9c48d3d5f925e1",
            "BSD-3-Clause-Clear",
            (
                ("histoqc pen_green.png", "histoqc/data/models/pen_markings_he/pen_green.png"),
                ("histoqc sort-asc.gif", "histoqc/ui/static/libs/slickgrid/images/sort-asc.gif"),
            ),
        ),
    )
    for name, path in files
)

EXTRA_SUFFIXES = (".gif", ".webp", ".avif", ".jxl", ".bmp")


def gather(mirrors: Path, folder: Path) -> None:
    """Copy :data:`SOURCES` out of the local mirrors and write the edge cases into ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    missing = []
    for name, repo, commit, path, _lic in SOURCES:
        git_dir = mirrors / repo.replace("/", "+") / "repo"
        out = subprocess.run(
            ["git", f"--git-dir={git_dir}", "show", f"{commit}:{path}"],
            capture_output=True,
            check=False,
        )
        if out.returncode != 0 or not out.stdout:
            missing.append(name)
            continue
        (folder / name).write_bytes(out.stdout)
    make_edge_cases(folder)
    if missing:
        print(f"absent from the mirrors (skipped): {', '.join(missing)}", file=sys.stderr)


def make_edge_cases(folder: Path) -> None:
    """Write the generated edge cases (names start with ``made``)."""
    import imagecodecs
    import tifffile
    from PIL import Image

    rng = np.random.default_rng(0)
    photo = (rng.random((48, 64, 3)) * 255).astype(np.uint8)

    def png(name: str, a: np.ndarray, **kw: Any) -> None:
        Image.fromarray(a, **kw).save(folder / name)

    png("made 1x1.png", photo[:1, :1])
    png("made 1x40.png", photo[:1, :40])
    png("made aspect 2000x3.png", np.resize(photo, (3, 2000, 3)))
    Image.fromarray(np.zeros((1, 65535), np.uint8)).save(folder / "made 65535x1.png")
    grey16 = (np.linspace(0, 65535, 64 * 48).reshape(48, 64)).astype(np.uint16)
    (folder / "made grey16.png").write_bytes(bytes(imagecodecs.png_encode(grey16)))
    rgba = np.dstack([photo, np.full(photo.shape[:2], 255, np.uint8)])
    rgba[:10, :10, 3] = 0
    png("made rgba.png", rgba)
    Image.fromarray(photo).save(folder / "made whole.jpg", quality=90)
    data = (folder / "made whole.jpg").read_bytes()
    (folder / "made truncated.jpg").write_bytes(data[: len(data) // 2])
    (folder / "made empty.png").write_bytes(b"")
    rgb16 = (rng.random((48, 64, 3)) * 65535).astype(np.uint16)
    (folder / "made png16 named.jpg").write_bytes(bytes(imagecodecs.png_encode(rgb16)))
    Image.fromarray(photo).save(folder / "made gif named.png", format="GIF")
    (folder / "made text.png").write_text("this is not an image\n")
    frames = [Image.fromarray(np.roll(photo, 5 * k, axis=1)) for k in range(3)]
    frames[0].save(folder / "made animated.gif", save_all=True, append_images=frames[1:])
    tifffile.imwrite(folder / "made 4ch unassoc-alpha.tif", np.dstack([photo, photo[..., :1]]))
    tifffile.imwrite(
        folder / "made rgba-assoc.tif",
        np.dstack([photo, np.full(photo.shape[:2], 255, np.uint8)]),
        photometric="rgb",
        extrasamples=["assocalpha"],
    )
    tifffile.imwrite(
        folder / "made 5ch.tif",
        np.dstack([photo, photo[..., :2]]),
        photometric="rgb",
        extrasamples=["unspecified", "unspecified"],
    )
    tifffile.imwrite(  # a multispectral camera's 7 bands, one page of 7 samples per pixel
        folder / "made 7ch.tif",
        np.dstack([photo, photo, photo[..., :1]]),
        photometric="minisblack",
        planarconfig="contig",
    )
    tifffile.imwrite(folder / "made 2-page narrow.tif", photo[:2, :, :], photometric="minisblack")
    tifffile.imwrite(
        folder / "made cmyk.tif", np.dstack([photo, photo[..., :1]]), photometric="separated"
    )
    tifffile.imwrite(folder / "made ycbcr raw.tif", photo, photometric="ycbcr", subsampling=(1, 1))
    tifffile.imwrite(folder / "made white-is-zero.tif", photo[..., 0], photometric="miniswhite")
    tifffile.imwrite(
        folder / "made 12-bit.tif",
        np.round(photo / 255 * 4095).astype(np.uint16),
        bitspersample=12,
        photometric="rgb",
    )
    tifffile.imwrite(folder / "made float.tif", photo.astype(np.float32) / 255)
    tifffile.imwrite(folder / "made multipage.tif", np.stack([photo, photo[::-1]]))
    Image.fromarray(photo).save(folder / "made ünïcødé 写真.jpg")
    Image.fromarray(photo).convert("CMYK").save(folder / "made cmyk.jpg")
    from benchmarks._cmyk_icc import cmyk_profile

    Image.fromarray(photo).convert("CMYK").save(
        folder / "made cmyk icc.jpg", icc_profile=cmyk_profile()
    )
    Image.fromarray(photo).save(folder / "made progressive.jpg", progressive=True)
    Image.fromarray(photo[..., 0]).save(folder / "made grey.jpg")
    exif = Image.Exif()
    exif[0x0112] = 6
    Image.fromarray(photo).save(folder / "made orient6.png", exif=exif)
    Image.fromarray(photo).save(folder / "made orient6.tif", exif=exif)
    Image.fromarray(photo[..., 0] > 128).save(folder / "made bilevel.png")
    np.save(folder / "made image.npy", photo)
    np.save(folder / "made int32.npy", photo.astype(np.int32))
    _make_pillow_formats(folder, photo)
    counts = (rng.random((48, 64, 3)) * 4000).astype(np.float32)  # a microscope's 0-4000
    tifffile.imwrite(folder / "made float 0-4000.tif", counts, photometric="rgb")
    tifffile.imwrite(folder / "made float grey 0-4000.tif", counts[..., 0])


def _make_pillow_formats(folder: Path, photo: np.ndarray) -> None:
    """WebP, BMP and GIF edge cases: what Pillow writes, and BMPs it does not (RLE, top-down)."""
    import struct

    from PIL import Image

    im = Image.fromarray(photo)
    im.save(folder / "made lossless.webp", lossless=True)
    im.save(folder / "made lossy.webp", quality=75)
    rgba = np.dstack([photo, np.full(photo.shape[:2], 255, np.uint8)])
    rgba[:8, :8, 3] = 0
    Image.fromarray(rgba).save(folder / "made alpha.webp", lossless=True)
    exif = Image.Exif()
    exif[0x0112] = 6
    im.save(folder / "made orient6.webp", quality=90, exif=exif)
    frames = [Image.fromarray(np.roll(photo, 5 * k, axis=1)) for k in range(3)]
    frames[0].save(folder / "made animated.webp", save_all=True, append_images=frames[1:])
    im.save(folder / "made 24-bit.bmp")
    Image.fromarray(photo[..., 0] > 128).save(folder / "made 1-bit.bmp")
    pal = im.convert("P", palette=Image.Palette.ADAPTIVE, colors=16)
    pal.save(folder / "made 8-bit palette.bmp")
    pal.save(folder / "made palette.gif")
    pal.save(folder / "made transparent.gif", transparency=int(np.asarray(pal)[0, 0]))
    index = np.asarray(pal)
    colours = np.array((pal.getpalette() or [])[:48], np.uint8).reshape(16, 3)
    table = b"".join(bytes([b, g, r, 0]) for r, g, b in colours)
    for name, compression, top_down in (
        ("rle8", 1, False),
        ("rle4", 2, False),
        ("top-down", 0, True),
    ):
        h, w = index.shape
        rows = index if top_down else index[::-1]
        if compression:  # encoded runs of one pixel, end of line, end of bitmap
            cell = (lambda v: v) if compression == 1 else (lambda v: v << 4 | v)
            body = b"".join(b"".join(bytes([1, cell(int(v))]) for v in r) + b"\0\0" for r in rows)
            body += b"\0\1"
        else:
            body = b"".join(bytes(r.astype(np.uint8)) for r in rows)  # 64: a multiple of 4
        bits = 4 if compression == 2 else 8
        info = struct.pack("<IiiHHIIiiII", 40, w, -h if top_down else h, 1, bits, compression,
                           len(body), 2835, 2835, 16, 0)  # fmt: skip
        offset = 14 + 40 + len(table)
        head = b"BM" + struct.pack("<IHHI", offset + len(body), 0, 0, offset)
        (folder / f"made {name}.bmp").write_bytes(head + info + table + body)


# ---------------------------------------------------------------- the sweep

TIMEOUT = 120.0


def _reference(path: Path) -> np.ndarray | None:
    """The upright pixels by another decoder, chosen by the file's bytes (not its suffix).

    PNG: OpenCV (libpng, every bit depth) turned by the eXIf orientation; TIFF: tifffile and
    the TIFF 6.0 rules; DICOM: pydicom's modality values (:func:`_dicom_reference`); .npy:
    NumPy; BMP, GIF, WebP: OpenCV; PFM and Radiance HDR: OpenCV (:func:`_float_reference`);
    anything else: Pillow with ``exif_transpose`` (a CMYK JPEG with a CMYK ICC profile
    converted by ImageCms to sRGB; an ICO's largest entry).
    """
    head = path.read_bytes()[:132]
    if head[128:132] == b"DICM":
        return _dicom_reference(path)
    if head.startswith(b"\x93NUMPY"):
        return np.load(path)
    if head[:2] in (b"PF", b"Pf") or head.startswith((b"#?RADIANCE", b"#?RGBE")):
        return _float_reference(path)
    if head[:4] in (b"II*\0", b"MM\0*", b"II+\0", b"MM\0+"):
        return _tiff_reference(path)
    if head.startswith(b"\x89PNG"):
        return _png_reference(path)
    if head.startswith((b"BM", b"GIF8")) or head[:4] == b"RIFF":
        return _opencv_reference(path)
    from PIL import Image, ImageOps

    with Image.open(path) as im:
        up = ImageOps.exif_transpose(im)
        icc = up.info.get("icc_profile") or b""
        if up.mode == "CMYK" and icc[16:20] == b"CMYK":  # LittleCMS: the profile to sRGB
            from PIL import ImageCms

            src = ImageCms.ImageCmsProfile(io.BytesIO(icc))
            srgb = ImageCms.createProfile("sRGB")
            converted = ImageCms.profileToProfile(up, src, srgb, outputMode="RGB")
            assert converted is not None  # None only with inPlace=True
            up = converted
        if up.mode in ("P", "PA"):
            up = up.convert("RGBA" if "transparency" in up.info or up.mode == "PA" else "RGB")
        elif up.mode in ("CMYK", "YCbCr", "1"):
            up = up.convert("RGB" if up.mode != "1" else "L")
        return np.asarray(up)


def _dicom_reference(path: Path) -> np.ndarray | None:
    """A DICOM's modality values by pydicom (``apply_modality_lut(pixel_array)``).

    None (no reference) for a file of several frames (imageform refuses it without a frame)
    and for MONOCHROME1, which imageform inverts to MONOCHROME2's sense.
    """
    import pydicom
    from pydicom.pixels import apply_modality_lut

    ds = pydicom.dcmread(path)
    if int(getattr(ds, "NumberOfFrames", 1) or 1) > 1:
        return None
    if str(getattr(ds, "PhotometricInterpretation", "")) == "MONOCHROME1":
        return None
    arr = np.asarray(ds.pixel_array)
    if arr.ndim == 2:
        arr = np.asarray(apply_modality_lut(arr, ds))
    return arr


def _float_reference(path: Path) -> np.ndarray:
    """A PFM or Radiance HDR by OpenCV, put in the values each format's definition gives.

    PFM: OpenCV divides the stored numbers by the scale's magnitude; the format leaves that
    factor to the application and Pillow does not apply it, so it is multiplied back (the
    samples as stored). HDR: OpenCV's ``rgbe.c`` decodes ``m * 2**(E - 136)``; Radiance's
    ``colr_color`` adds half a mantissa step, ``0.5 * 2**(E - 136)``, ``E`` recovered from the
    pixel's largest value (its mantissa is 128 to 255).
    """
    import re

    import cv2

    a = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if a is None:
        raise ValueError("OpenCV cannot decode it")
    a = a[..., ::-1] if a.ndim == 3 else a[..., None]
    data = path.read_bytes()[:256]
    m = re.match(rb"\AP[Ff]\s+\d+\s+\d+\s+([-+0-9.eE]+)\s", data)
    if m is not None:
        return np.ascontiguousarray(a * np.float32(abs(float(m.group(1)))))
    top = a.max(axis=-1, keepdims=True).astype(np.float64)
    step = np.where(top > 0, np.exp2(np.floor(np.log2(np.where(top > 0, top, 1))) - 7), 0.0)
    return np.ascontiguousarray(a + 0.5 * step, dtype=np.float32)


def _opencv_reference(path: Path) -> np.ndarray:
    """A BMP, GIF or WebP by OpenCV (its own BMP and GIF decoders; libwebp), turned upright
    by the EXIF orientation Pillow reads (OpenCV's ``IMREAD_UNCHANGED`` does not turn it)."""
    import cv2
    from PIL import Image

    a = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if a is None:
        raise ValueError("OpenCV cannot decode it")
    if a.ndim == 3:
        a = a[..., [2, 1, 0, 3]] if a.shape[2] == 4 else a[..., ::-1]
    with Image.open(path) as im:
        orientation = int(im.getexif().get(0x0112, 1) or 1)
    return _turn(a, orientation)


def _png_reference(path: Path) -> np.ndarray:
    import cv2
    from PIL import Image

    a = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if a is None:
        raise ValueError("OpenCV cannot decode it")
    if a.ndim == 3:  # BGR(A) -> RGB(A); a grey PNG comes expanded to BGR(A)
        a = a[..., [2, 1, 0, 3]] if a.shape[2] == 4 else a[..., ::-1]
        if path.read_bytes()[25] in (0, 4):  # IHDR colour type: grey, grey + alpha
            a = a[..., [0, 3]] if a.shape[2] == 4 else a[..., :1]
    with Image.open(path) as im:
        orientation = int(im.getexif().get(0x0112, 1) or 1)
    return _turn(a, orientation)


def _turn(a: np.ndarray, orientation: int) -> np.ndarray:
    """``a`` turned upright for an EXIF orientation, by Pillow's transposes of an index grid."""
    from PIL import Image

    if orientation not in _TRANSPOSE:
        return a
    grid = Image.fromarray(np.arange(a.shape[0] * a.shape[1], dtype=np.int32).reshape(a.shape[:2]))
    idx = np.asarray(grid.transpose(Image.Transpose(_TRANSPOSE[orientation])))
    return a.reshape(-1, *a.shape[2:])[idx]


#: EXIF orientation -> Pillow's transpose (ImageOps.exif_transpose's table).
_TRANSPOSE = {2: 0, 3: 3, 4: 1, 5: 5, 6: 4, 7: 6, 8: 2}


def _tiff_reference(path: Path) -> np.ndarray:
    """A TIFF by tifffile and the TIFF 6.0 rules, turned upright by Pillow's transposes.

    (Pillow itself is no reference here: 13.0 reports a turned size for a palette TIFF with
    an orientation tag but decodes it unturned.)
    """
    import tifffile

    with tifffile.TiffFile(path) as tif:
        series, page = tif.series[0], tif.pages[0]
        a = series.asarray()
        tag = page.tags.get(274)
        orientation = int(tag.value) if tag is not None else 1
        if series.axes.startswith("S"):
            a = np.moveaxis(a, 0, -1)
        if page.photometric == 3:  # palette: 16-bit colour map
            cmap = page.colormap.T
            a = (cmap // 257).astype(np.uint8)[a] if not np.any(cmap % 257) else cmap[a]
        elif a.dtype == bool:
            a = a.astype(np.uint8) * 255
        bits = 8 if a.dtype == np.uint8 else page.bitspersample
        icc = bytes(page.tags[34675].value) if 34675 in page.tags else b""
        if page.photometric == 5 and icc[16:20] == b"CMYK" and a.dtype == np.uint8:
            from PIL import Image, ImageCms  # LittleCMS through Pillow: the profile to sRGB

            src = ImageCms.ImageCmsProfile(io.BytesIO(icc))
            im = Image.fromarray(np.ascontiguousarray(a[..., :4]), "CMYK")
            rgb = ImageCms.profileToProfile(im, src, ImageCms.createProfile("sRGB"),
                                            outputMode="RGB")  # fmt: skip
            assert rgb is not None
            a = np.concatenate([np.asarray(rgb), a[..., 4:]], axis=-1)
        if page.photometric == 0:  # 10/12/14-bit samples stay as stored (DN)
            a = ((1 << bits) - 1 if bits < 8 * a.dtype.itemsize else np.iinfo(a.dtype).max) - a
    return _turn(a, orientation)


def _upright_hw(path: Path) -> tuple[int, int] | None:
    try:
        from imageform.io import read_image

        a = read_image(path, alpha="drop", max_pixels=10**9)
        return a.shape[0], a.shape[1]
    except Exception:
        return None


def _check_read(path: Path) -> tuple[str, str]:
    from imageform.errors import ImageformError
    from imageform.io import read_image

    try:
        got = read_image(path, alpha="keep")
    except ImageformError as exc:
        return "error", str(exc).splitlines()[0]
    except Exception as exc:
        return "crash", f"{type(exc).__name__}: {str(exc)[:120]}"
    try:
        ref = _reference(path)
    except Exception as exc:
        return "fine", f"{got.shape} {got.dtype} (no reference decoder: {type(exc).__name__})"
    if ref is None:
        return "fine", f"{got.shape} {got.dtype}"
    ref = ref[..., None] if ref.ndim == 2 else ref
    ref = ref.astype(np.float32) if ref.dtype == np.float16 else ref  # widened, as documented
    numbers = (ref.dtype.kind == "i" and ref.dtype.itemsize <= 4) or ref.dtype == np.uint32
    if numbers and got.dtype.kind == "f":
        # a TIFF's signed or uint32 samples: their numbers as floats (float64 for 32 bits),
        # documented
        ref = ref.astype(np.float32 if ref.dtype.itemsize <= 2 else np.float64)
    if ref.dtype.kind == "f" and got.dtype.kind == "f" and ref.dtype != got.dtype:
        ref = ref.astype(got.dtype)  # a DICOM's modality values (pydicom: float64)
    if ref.shape[:2] != got.shape[:2]:
        return "wrong", f"read {got.shape[:2]}, upright reference {ref.shape[:2]}"
    if ref.dtype != got.dtype:
        return "wrong", f"read as {got.dtype}, the reference decoder gives {ref.dtype}"
    colour = 3 if min(ref.shape[2], got.shape[2]) >= 3 else 1  # alpha aside (tRNS)
    delta = np.abs(ref[..., :colour].astype(np.float64) - got[..., :colour]).max(axis=-1)
    if ref.shape[2] in (2, 4) and got.shape[2] == ref.shape[2]:
        if not np.array_equal(ref[..., -1], got[..., -1]):
            return "wrong", "alpha differs from the reference decoder"
        delta = delta[ref[..., -1] > 0]  # a fully transparent pixel's colour is undefined
    diff = float(delta.max(initial=0.0))
    if got.dtype.kind == "f":  # float references (PFM, HDR) rescaled by the checker: 1 ulp
        size = np.abs(ref[..., :colour].astype(np.float64)).max(axis=-1)
        size = size[ref[..., -1] > 0] if ref.shape[2] in (2, 4) else size
        worse = delta > 2 * np.finfo(np.float32).eps * size
        if np.any(worse):
            return "wrong", f"values differ from the reference decoder by up to {diff:g}"
        return "fine", f"{got.shape} {got.dtype}"
    if diff > (2 if got.dtype == np.uint8 else 0):
        return "wrong", f"values differ from the reference decoder by up to {diff:g}"
    return "fine", f"{got.shape} {got.dtype}"


def _commands(img: Path, out: Path) -> dict[str, list[list[str]]]:
    s = str(img)
    return {
        "info": [["info", s, "--json"]],
        "convert": [["convert", s, "--to", "lab", "-o", str(out / "convert.tif")]],
        "white-balance": [["white-balance", s, "-o", str(out / "wb.png")]],
        "delta-e": [["delta-e", s, s, "--json"]],
        "cvd": [["cvd", s, "--type", "deutan", "-o", str(out / "cvd.png")]],
        "segment": [["segment", s, "-o", str(out / "segment.png")]],
        "stain-normalize": [
            ["stain-normalize", s, "--target", s, "--method", "reinhard", "-o", str(out / "sn.png")]
        ],
        "flatfield": [["flatfield", s, "--method", "radial", "-o", str(out / "ff")]],
        "chart": [["chart", s, "-o", str(out / "chart.json")]],
        "vanishing": [["vanishing", s, "--json"]],
        "undistort": [["undistort", s, "--from-lines", "-o", str(out / "undistort.png")]],
        "sfr": [["sfr", s, "--json"]],
        "mosaic/demosaic": [
            ["mosaic", s, "-o", str(out / "mosaic.png")],
            ["demosaic", str(out / "mosaic.png"), "-o", str(out / "demosaic.png"), "--allow-odd"],
        ],
        "develop": [["develop", s, "-o", str(out / "develop.png")]],
    }


#: Outputs whose (H, W) must be the upright input's.
SAME_SIZE = ("convert.tif", "wb.png", "cvd.png", "segment.png", "sn.png", "undistort.png")


def _run_cli(argv: list[str]) -> tuple[int, str, str, float]:
    from imageform.cli import main

    so, se = io.StringIO(), io.StringIO()
    t0 = time.perf_counter()
    with contextlib.redirect_stdout(so), contextlib.redirect_stderr(se):
        code = main(argv)
    return code, so.getvalue(), se.getvalue(), time.perf_counter() - t0


def _hash(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest() if path.is_file() else "-"


#: stderr lines a command may add to its one line: its notes and warnings.
_NOTES = ("note:", "warning:", "imageform: note:", "imageform: warning:")


def _verdict(code: int, err: str, seconds: float) -> tuple[str, str]:
    lines = [ln for ln in err.splitlines() if ln.strip() and not ln.startswith(_NOTES)]
    errors = [ln for ln in lines if ln.startswith(("imageform: error:", "Error:"))]
    if seconds > TIMEOUT:
        return "hang", f"{seconds:.0f} s"
    if "Traceback" in err or "unexpected " in err or "internal error" in err:
        return "crash", (errors or lines or ["?"])[-1][:160]
    if code == 0:
        return "fine", ""
    if code in (1, 2) and len(errors) == 1:
        if len(lines) > 1:  # more on stderr than the one line a failure says
            other = next(ln for ln in lines if ln not in errors)
            return "noisy", f"also on stderr: {other[:120]}"
        return "error", errors[0].removeprefix("imageform: error: ")[:160]
    return "crash", f"exit {code}: {(lines or ['no message'])[-1][:140]}"


def sweep_file(path: Path) -> list[dict[str, Any]]:
    """Run every command class on ``path``; one record per class."""
    import warnings

    warnings.simplefilter("ignore")
    rows = []
    verdict, note = _check_read(path)
    rows.append({"file": path.name, "cls": "read", "verdict": verdict, "note": note, "s": 0.0})
    hw = _upright_hw(path)
    before = _hash(path)
    for cls, argvs in _commands(path, Path("OUT")).items():
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp)
            argvs = _commands(path, out)[cls]
            verdict, note, total = "fine", "", 0.0
            for argv in argvs:
                code, so, se, sec = _run_cli(argv)
                total += sec
                verdict, note = _verdict(code, se, sec)
                if verdict != "fine":
                    break
            if verdict == "error" and any(out.iterdir()) and cls != "mosaic/demosaic":
                left = ", ".join(sorted(p.name for p in out.iterdir()))
                verdict, note = "wrong", f"left {left} behind: {note}"
            if verdict == "fine":
                verdict, note = _check_outputs(cls, out, so, hw, path)
        if _hash(path) != before:
            verdict, note = "wrong", "the input file changed"
        rows.append({"file": path.name, "cls": cls, "verdict": verdict, "note": note, "s": total})
    return rows


def _check_outputs(
    cls: str, out: Path, stdout: str, hw: tuple[int, int] | None, path: Path
) -> tuple[str, str]:
    if cls == "info":  # the header's size and channels are what every command reads
        from imageform.io import read_image

        try:
            head = json.loads(stdout)
            said = head["channels"]
            shape = read_image(path, alpha="keep", max_pixels=10**9).shape
        except Exception:
            return "fine", ""
        if said != shape[2]:
            return "wrong", f"says {said} channels, reads {shape[2]}"
        if "height" in head and (head["height"], head["width"]) != shape[:2]:
            size = f"{head['width']} x {head['height']}"
            return "wrong", f"says {size} px, reads {shape[1]} x {shape[0]} (upright)"
        source = head.get("color_space_source", "none")
        return "fine", "" if source == "none" else f"declares {head.get('color_space')} ({source})"
    if cls == "convert":  # the space it read the file in (--from auto): "IMAGE (SPACE) -> ..."
        _, _, rest = stdout.partition(f"{path} (")
        return "fine", f"read as {rest.partition(')')[0]}" if rest else ""
    if cls == "delta-e":
        try:
            mean = json.loads(stdout)["mean"]
        except Exception:
            return "fine", "(no JSON mean)"
        return ("fine", "") if mean == 0 else ("wrong", f"ΔE of the file to itself {mean}")
    from imageform.io import read_image

    for name in SAME_SIZE:
        p = out / name
        if p.is_file() and hw is not None:
            got = read_image(p, alpha="drop", max_pixels=10**9).shape[:2]
            if got != hw:
                return "wrong", f"{name} is {got}, the upright input {hw}"
    return "fine", ""


def _worker(path: Path) -> None:
    for row in sweep_file(path):
        print("ROW " + json.dumps(row, ensure_ascii=False), flush=True)


def run(folder: Path, jobs: int = 2, only: list[str] | None = None) -> list[dict[str, Any]]:
    """Sweep every file of ``folder`` (one worker process each, ``jobs`` at a time).

    ``only``: the files whose name contains one of these texts.
    """
    files = sorted(p for p in folder.iterdir() if p.is_file() and p.name != "SOURCES.tsv")
    if only:
        files = [p for p in files if any(t in p.name for t in only)]
    rows: list[dict[str, Any]] = []
    procs: list[tuple[Path, subprocess.Popen[str], float]] = []
    env = dict(os.environ, PYTHONWARNINGS="ignore")

    def reap(block: bool) -> None:
        for item in list(procs):
            p, proc, t0 = item
            limit = TIMEOUT * 16
            if block or proc.poll() is not None or time.time() - t0 > limit:
                try:
                    so, se = proc.communicate(timeout=max(1.0, limit - (time.time() - t0)))
                except subprocess.TimeoutExpired:
                    proc.kill()
                    so, se = proc.communicate()
                got = [json.loads(ln[4:]) for ln in so.splitlines() if ln.startswith("ROW ")]
                if len(got) < 15:
                    tail = (se.strip().splitlines() or ["?"])[-1][:140]
                    got.append(
                        {"file": p.name, "cls": "worker", "verdict": "crash", "note": tail, "s": 0}
                    )
                rows.extend(got)
                procs.remove(item)
                print(f"done {p.name}", file=sys.stderr, flush=True)
                if not block:
                    return

    for p in files:
        while len(procs) >= jobs:
            reap(block=False)
            time.sleep(0.2)
        cmd = [sys.executable, __file__, "--worker", str(p)]
        procs.append(
            (
                p,
                subprocess.Popen(
                    cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env
                ),
                time.time(),
            )
        )
    while procs:
        reap(block=True)
    return rows


def _sources_note(folder: Path, only: list[str] | None = None) -> list[str]:
    names = {p.name for p in folder.iterdir() if not only or any(t in p.name for t in only)}
    lines = ["| file | repository @ commit | path | licence |", "|---|---|---|---|"]
    for name, repo, commit, path, lic in SOURCES:
        if name in names:
            lines.append(f"| {name} | {repo} @ {commit[:12]} | {path} | {lic} |")
    return lines


def _cell(text: str) -> str:
    """A table cell: no pipes, brackets escaped (mkdocs would read ``[0, 1]`` as a link)."""
    return text.replace("|", "/").replace("[", "\\[").replace("]", "\\]")


def main() -> None:
    from benchmarks._common import header, markdown_table

    if sys.argv[1:2] == ["--chain"]:  # the chained sweep with value checks
        from benchmarks import check_odd_files_chain

        sys.argv[1:2] = []
        check_odd_files_chain.main()
        return

    ap = argparse.ArgumentParser()
    ap.add_argument("folder", type=Path)
    ap.add_argument("--gather", type=Path, metavar="MIRRORS")
    ap.add_argument("--worker", action="store_true")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument(
        "--only", action="append", default=[], metavar="TEXT",
        help="sweep only the files whose name contains TEXT (repeatable)",
    )  # fmt: skip
    args = ap.parse_args()
    if args.worker:
        _worker(args.folder)
        return
    if args.gather:
        if args.folder.exists():
            shutil.rmtree(args.folder)
        gather(args.gather, args.folder)
    rows = run(args.folder, args.jobs, args.only)
    order = {c: i for i, c in enumerate(["read", *_commands(Path("x"), Path("y")), "worker"])}
    rows.sort(key=lambda r: (r["file"], order.get(r["cls"], 99)))
    counts: dict[str, int] = {}
    for r in rows:
        counts[r["verdict"]] = counts.get(r["verdict"], 0) + 1
    files = len({r["file"] for r in rows})
    print(header(f"Odd real-world image files through the command line ({files} files)"))
    only = "".join(f" --only {t!r}" for t in args.only)
    gathered = " --gather /work/.mirror" if args.gather else ""
    print(
        f"`PYTHONPATH=src:. python benchmarks/check_odd_files.py{gathered} {args.folder}{only}` "
        f"(timeout {TIMEOUT:.0f} s a command class; the files are not "
        "committed: their sources are listed at the end).\n"
    )
    print(
        "Verdicts: "
        + ", ".join(f"{k} {v}" for k, v in sorted(counts.items()))
        + f" (of {len(rows)} file x command runs).\n"
    )
    bad = [r for r in rows if r["verdict"] in ("crash", "wrong", "hang", "noisy")]
    print("## Crashes, wrong results, hangs and noisy errors\n")
    print(
        markdown_table(
            ["file", "command", "verdict", "note"],
            [[r["file"], r["cls"], r["verdict"], _cell(r["note"])] for r in bad]
            or [["none", "", "", ""]],
        )
    )
    print("\n## Every run\n")
    print(
        markdown_table(
            ["file", "command", "verdict", "s", "note"],
            [[r["file"], r["cls"], r["verdict"], f"{r['s']:.1f}", _cell(r["note"])] for r in rows],
        )
    )
    print("\n## Sources\n")
    print("\n".join(_sources_note(args.folder, args.only)))


if __name__ == "__main__":
    main()
