"""Slide scanners' files as pathology users bring them (benchmarks/check_wsi_real.py's cases).

Each test writes a tiny file with tifffile (or pydicom) that has the property a real file of the
sweep had: an Aperio ``.svs`` or Hamamatsu ``.ndpi`` name (refused as an unknown suffix before),
the pixel size in resolution tags in centimetres (NDPI: 43826 px/cm, 0.228 um, dropped from
the chunked output's reading before), a Philips, Ventana or ImageJ pixel size, a DICOM
slide-microscopy image's pixel spacing and total pixel matrix; ``imageform info`` lists the
levels, pixel size and scanner format.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from imageform.batch import process_chunked
from imageform.cli import main
from imageform.errors import InvalidInputError
from imageform.io import pixel_size_um, read_image, write_image

tifffile = pytest.importorskip("tifffile")
pytest.importorskip("zarr")
pytest.importorskip("dask.array")

TILE = 64
APERIO = "Aperio Image Library v12.0.15\r\n256x192 [0,0 256x192] (64x64) JPEG/RGB Q=70|AppMag = 20|MPP = 0.4990"  # noqa: E501


def _image(h: int, w: int, seed: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:h, 0:w]
    base = np.stack([200 - xx % 50, 120 + yy % 60, 180 + (xx + yy) % 40], axis=-1)
    return np.clip(base + rng.integers(0, 10, base.shape), 0, 255).astype(np.uint8)


def _half(a: np.ndarray) -> np.ndarray:
    h, w, c = a.shape
    return a.reshape(h // 2, 2, w // 2, 2, c).mean(axis=(1, 3)).round().astype(np.uint8)


def _svs(path: Path) -> np.ndarray:
    """An Aperio-like SVS: tiled level 0 with the Aperio header, a reduced level as a page."""
    img = _image(192, 256)
    with tifffile.TiffWriter(path) as tw:
        tw.write(img, tile=(TILE, TILE), photometric="rgb", description=APERIO)
        tw.write(_half(img), tile=(TILE, TILE), photometric="rgb", subfiletype=1,
                 description="Aperio Image Library v12.0.15\r\n128x96 -> 128x96")  # fmt: skip
    return img


def _ndpi_like(path: Path) -> np.ndarray:
    """A pyramid whose pixel size is in resolution tags, in px/cm (as NDPI's)."""
    img = _image(256, 256)
    kw = {"tile": (TILE, TILE), "photometric": "rgb", "resolutionunit": 3}
    with tifffile.TiffWriter(path) as tw:
        tw.write(img, subifds=1, resolution=(43826.0, 43826.0), **kw)
        tw.write(_half(img), subfiletype=1, resolution=(21913.0, 21913.0), **kw)
    return img


@pytest.mark.parametrize("suffix", [".svs", ".qptiff", ".bif", ".scn", ".btf"])
def test_scanner_suffixes_are_read_as_tiff(tmp_path: Path, suffix: str) -> None:
    """A slide scanner's TIFF under its own suffix is read (it was 'unknown image file type').

    (Not .ndpi: tifffile reads a file of that name with NDPI's 64-bit offsets, so a plain TIFF
    named .ndpi is not one; the sweep's real NDPI files are read.)"""
    img = _image(64, 64)
    p = tmp_path / f"s{suffix}"
    tifffile.imwrite(p, img, tile=(TILE, TILE), photometric="rgb")
    np.testing.assert_array_equal(read_image(p), img)


def test_scanner_suffix_is_not_written(tmp_path: Path) -> None:
    """imageform writes .tif: a plain TIFF named .svs would pass for a scanner's file."""
    with pytest.raises(InvalidInputError, match=r"reads \.svs slides but writes TIFF as \.tif"):
        write_image(tmp_path / "o.svs", np.zeros((4, 4, 3), np.uint8))
    assert not (tmp_path / "o.svs").exists()


def test_chunked_reads_svs_and_keeps_its_levels_and_pixel_size(tmp_path: Path) -> None:
    """An .svs goes through chunked convert (refused by its suffix before): level 0 exact, its
    2 levels back, the Aperio MPP carried into the output's resolution tags and read back."""
    src = tmp_path / "slide.svs"
    img = _svs(src)
    r = process_chunked(
        src, tmp_path / "out.tif", "convert", {"to": "srgb"}, chunk=128, compression="none"
    )
    assert r.levels == ((192, 256), (96, 128))
    with tifffile.TiffFile(r.output) as tf:
        np.testing.assert_array_equal(tf.series[0].levels[0].asarray(), img)
    assert pixel_size_um(r.output) == pytest.approx((0.499, 0.499), rel=1e-6)


def test_chunked_output_of_ndpi_keeps_the_pixel_size(tmp_path: Path) -> None:
    """Resolution tags in px/cm are the pixel size (NDPI, 0.2282 um) in and out of chunked."""
    src = tmp_path / "slide.tif"
    _ndpi_like(src)
    assert pixel_size_um(src) == pytest.approx((1e4 / 43826,) * 2)
    tgt = tmp_path / "target.png"
    write_image(tgt, _image(64, 64, seed=5))
    r = process_chunked(src, tmp_path / "sn.tif", "stain_normalize", {"target": tgt,
                        "method": "reinhard"}, chunk=128)  # fmt: skip
    assert r.levels == ((256, 256), (128, 128))
    assert pixel_size_um(r.output) == pytest.approx((1e4 / 43826,) * 2, rel=1e-6)


@pytest.mark.parametrize(
    ("resolution", "unit", "expected"),
    [
        ((43826.0, 43826.0), 3, (1e4 / 43826,) * 2),  # NDPI, px/cm
        ((28.346, 28.346), 3, None),  # 72 dpi in px/cm (photo software): 353 um, not a pixel size
        ((72.0, 72.0), 2, None),  # inches: never read
        ((20000.0, 10000.0), 3, (0.5, 1.0)),
    ],
)
def test_pixel_size_from_resolution_tags(
    tmp_path: Path,
    resolution: tuple[float, float],
    unit: int,
    expected: tuple[float, float] | None,
) -> None:
    p = tmp_path / "r.tif"
    tifffile.imwrite(p, _image(16, 16), resolution=resolution, resolutionunit=unit)
    got = pixel_size_um(p)
    assert got == (None if expected is None else pytest.approx(expected))


def test_pixel_size_of_philips_ventana_imagej(tmp_path: Path) -> None:
    """Philips' DICOM_PIXEL_SPACING (mm, rows then columns; the full resolution's, inside its
    representation sequence), Ventana's XMP ScanRes, ImageJ's unit=micron, as OpenSlide."""
    philips = (
        '<?xml version="1.0" encoding="UTF-8" ?><DataObject ObjectType="DPUfsImport">'
        '<Attribute Name="DICOM_PIXEL_SPACING" Group="0x0028" Element="0x0030" '
        'PMSVR="IDoubleArray">&quot;0.000226907&quot; &quot;0.000226891&quot;</Attribute>'
        '<Attribute Name="PIIM_PIXEL_DATA_REPRESENTATION_SEQUENCE"><Array><DataObject>'
        '<Attribute Name="DICOM_PIXEL_SPACING" Group="0x0028" Element="0x0030" '
        'PMSVR="IDoubleArray">&quot;0.000227273&quot; &quot;0.000227272&quot;</Attribute>'
        "</DataObject></Array></Attribute></DataObject>"
    )
    p = tmp_path / "philips.tiff"
    tifffile.imwrite(p, _image(16, 16), description=philips, software="Philips DP v1.0")
    assert pixel_size_um(p) == pytest.approx((0.227272, 0.227273))
    xmp = b'<?xml version="1.0"?><Metadata><iScan Magnification="40" ScanRes="0.2325"/></Metadata>'
    p = tmp_path / "ventana.bif"
    tifffile.imwrite(p, _image(16, 16), extratags=[(700, 1, len(xmp), xmp, True)])
    assert pixel_size_um(p) == (0.2325, 0.2325)
    p = tmp_path / "imagej.tif"
    tifffile.imwrite(p, _image(16, 16)[..., 0], imagej=True, resolution=(4.0, 2.0),
                     metadata={"unit": "micron"})  # fmt: skip
    assert pixel_size_um(p) == pytest.approx((0.25, 0.5))


def test_pixel_size_of_dicom_slide_microscopy(tmp_path: Path) -> None:
    """A DICOM VL whole-slide image (modality SM): Pixel Spacing in its shared functional
    groups, 0.000499 mm -> 0.499 um, and info's total pixel matrix (the frames are tiles)."""
    pydicom = pytest.importorskip("pydicom")
    from pydicom.dataset import Dataset, FileMetaDataset
    from pydicom.uid import ExplicitVRLittleEndian, generate_uid

    wsi = "1.2.840.10008.5.1.4.1.1.77.1.6"
    ds = Dataset()
    ds.file_meta = FileMetaDataset()
    ds.file_meta.TransferSyntaxUID = ExplicitVRLittleEndian
    ds.file_meta.MediaStorageSOPClassUID = wsi
    ds.file_meta.MediaStorageSOPInstanceUID = generate_uid()
    ds.SOPClassUID, ds.SOPInstanceUID = wsi, ds.file_meta.MediaStorageSOPInstanceUID
    ds.Modality = "SM"
    ds.Rows = ds.Columns = 32
    ds.TotalPixelMatrixRows, ds.TotalPixelMatrixColumns = 24, 20
    ds.NumberOfFrames = 1
    ds.SamplesPerPixel, ds.PhotometricInterpretation, ds.PlanarConfiguration = 3, "RGB", 0
    ds.BitsAllocated = ds.BitsStored = 8
    ds.HighBit, ds.PixelRepresentation = 7, 0
    measures = Dataset()
    measures.PixelSpacing = [0.000499, 0.000499]
    shared = Dataset()
    shared.PixelMeasuresSequence = pydicom.Sequence([measures])
    ds.SharedFunctionalGroupsSequence = pydicom.Sequence([shared])
    ds.PixelData = _image(32, 32).tobytes()
    p = tmp_path / "wsi.dcm"
    ds.save_as(p, enforce_file_format=True)
    assert pixel_size_um(p) == pytest.approx((0.499, 0.499))
    rc = main(["info", str(p), "--json"])
    assert rc == 0


def test_info_lists_levels_pixel_size_and_scanner(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """imageform info of an .svs and of a generic pyramid: levels (width x height), pixel
    size in um and the format, in its text and its JSON."""
    svs = tmp_path / "slide.svs"
    _svs(svs)
    assert main(["info", str(svs), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["levels"] == [[256, 192], [128, 96]]
    assert out["pixel_size_um"] == [0.499, 0.499]
    assert out["vendor"] == "aperio"
    pyr = tmp_path / "pyr.tif"
    _ndpi_like(pyr)
    assert main(["info", str(pyr)]) == 0
    text = capsys.readouterr().out
    assert "2 level(s): 256 x 256, 128 x 128" in text
    assert "pixel size: 0.228175 x 0.228175 µm" in text
    flat = tmp_path / "flat.tif"
    tifffile.imwrite(flat, _image(16, 16))
    assert main(["info", str(flat), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["vendor"] is None and out["pixel_size_um"] is None


def test_open_lazy_reads_a_pyramid_level(tmp_path: Path) -> None:
    """open_lazy(level=k) is level k of the pyramid (SubIFDs or pages; -1 the smallest), so a
    tissue mask runs on a reduced level; a level the file lacks is refused in one line."""
    from imageform.analysis import tissue_mask
    from imageform.batch.chunked import open_lazy

    src = tmp_path / "slide.svs"
    img = _svs(src)
    np.testing.assert_array_equal(open_lazy(src, 64, level=1).compute(), _half(img))
    np.testing.assert_array_equal(open_lazy(src, 64, level=-1).compute(), _half(img))
    np.testing.assert_array_equal(open_lazy(src, 64).compute(), img)
    sub = tmp_path / "sub.tif"
    _ndpi_like(sub)
    small = np.asarray(open_lazy(sub, level=-1).compute())
    assert small.shape == (128, 128, 3)
    assert tissue_mask(small, pixel_size_um=2 * 1e4 / 43826).shape == (128, 128)
    flat = tmp_path / "flat.tif"
    tifffile.imwrite(flat, _image(16, 16))  # uncompressed strips: read by rows
    assert open_lazy(flat, level=-1).shape == (16, 16, 3)
    with pytest.raises(InvalidInputError, match=r"has 2 pyramid level\(s\) \(0 to 1"):
        open_lazy(src, level=2)
    with pytest.raises(InvalidInputError, match="has 1 pyramid level"):
        open_lazy(flat, level=1)


def test_two_levels_or_block_sizes_of_one_file_share_no_blocks(tmp_path: Path) -> None:
    """Two levels of one pyramid in one graph, or one strip TIFF at two block sizes, each keep
    their own blocks: dask's keys name the level and the block size (level 1 once took level
    0's blocks where both were decoded tile by tile into smaller blocks)."""
    from imageform.batch.chunked import open_lazy

    src = tmp_path / "slide.svs"
    img = _svs(src)
    a0, a1 = open_lazy(src, TILE // 2), open_lazy(src, TILE // 2, level=1)
    assert a0.name != a1.name
    both = (a0[: a1.shape[0], : a1.shape[1]].astype(np.int16) - a1).compute()
    np.testing.assert_array_equal(both, img[:96, :128].astype(np.int16) - _half(img))
    flat = tmp_path / "flat.tif"
    tifffile.imwrite(flat, _image(32, 32))  # uncompressed strips
    b8, b16 = open_lazy(flat, 8), open_lazy(flat, 16)
    assert b8.name != b16.name
    np.testing.assert_array_equal(
        (b8 + b16.rechunk(8)).compute(), 2 * _image(32, 32).astype(np.uint16) % 256
    )


def _damaged_jpeg_svs(path: Path) -> None:
    """An .svs whose first JPEG tile has a bogus marker length (OpenSlide's unreadable.svs)."""
    img = _image(128, 128)
    tifffile.imwrite(path, img, tile=(TILE, TILE), photometric="rgb", compression="jpeg",
                     description=APERIO)  # fmt: skip
    with tifffile.TiffFile(path) as tf:
        offset = int(tf.pages[0].dataoffsets[0])
    with open(path, "r+b") as fh:
        fh.seek(offset + 2)  # after SOI: the next marker's length
        fh.write(b"\xff\xdb\x00\x01")


def test_damaged_tile_is_refused_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A tile the codec cannot decode is refused naming the file and the tile's rows and
    columns (imagecodecs' Jpeg8Error came out of the block computation as 'unexpected')."""
    from imageform.batch.chunked import open_lazy
    from imageform.errors import UnreadableFileError

    src = tmp_path / "bad.svs"
    _damaged_jpeg_svs(src)
    with pytest.raises(UnreadableFileError, match=r"rows 0-64, columns 0-64 cannot be decoded"):
        process_chunked(src, tmp_path / "o.tif", "convert", {"to": "srgb"}, chunk=64)
    with pytest.raises(UnreadableFileError, match="cannot be decoded"):
        open_lazy(src, 128).compute()
    assert main(["chunked", "convert", str(src), "-o", str(tmp_path / "o.tif")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unexpected" not in err[0] and "bad.svs" in err[0]
    assert not (tmp_path / "o.tif").exists()
