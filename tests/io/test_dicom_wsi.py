"""DICOM whole-slide images (VL Whole Slide Microscopy): frames are tiles of one image.

A slide's file holds its total pixel matrix as tiles, one per frame, laid out row by row
(TILED_FULL) or where each frame's Plane Position (Slide) says (TILED_SPARSE); a pyramid's
levels are files of the same series in one folder. They were read as a multi-frame file
("read one with frame=N": one tile) and refused by the chunked commands. Slides are written
here with pydicom, tile by tile from a known matrix, which is the reference; the pixel size
is Pixel Spacing's (PS3.3 C.8.12.4, Shared Functional Groups' Pixel Measures, mm between
rows then between columns).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from imageform.cli import main
from imageform.errors import InvalidInputError
from imageform.io import image_frames, image_info, pixel_size_um, read_dicom, read_image

pydicom = pytest.importorskip("pydicom")
from pydicom.dataset import Dataset, FileMetaDataset  # noqa: E402
from pydicom.sequence import Sequence  # noqa: E402
from pydicom.uid import ExplicitVRLittleEndian, generate_uid  # noqa: E402

WSI = "1.2.840.10008.5.1.4.1.1.77.1.6"
RNG = np.random.default_rng(20261130)
TILE = 16


def _matrix(h: int, w: int) -> np.ndarray:
    """An H&E-like RGB matrix: pink tissue with purple nuclei on white glass, some noise."""
    y, x = np.mgrid[0:h, 0:w]
    img = np.full((h, w, 3), 235.0)
    tissue = (x - w / 2) ** 2 / (0.4 * w) ** 2 + (y - h / 2) ** 2 / (0.4 * h) ** 2 < 1
    img[tissue] = (200, 120, 170)
    nuclei = tissue & ((x // 3 + y // 4) % 5 == 0)
    img[nuclei] = (90, 50, 140)
    img += RNG.normal(0, 3, img.shape)
    return np.clip(img, 0, 255).astype(np.uint8)


def _tiles(m: np.ndarray) -> tuple[list[np.ndarray], list[tuple[int, int]]]:
    """The matrix cut in TILE x TILE frames (edges padded with black), row by row."""
    h, w = m.shape[:2]
    frames, origins = [], []
    for r in range(0, h, TILE):
        for c in range(0, w, TILE):
            t = np.zeros((TILE, TILE, 3), np.uint8)
            part = m[r : r + TILE, c : c + TILE]
            t[: part.shape[0], : part.shape[1]] = part
            frames.append(t)
            origins.append((r, c))
    return frames, origins


def _slide(
    path: Path,
    m: np.ndarray,
    *,
    sparse: bool = False,
    drop: int | None = None,
    series: str | None = None,
    spacing_mm: tuple[float, float] = (0.0005, 0.00025),
    **attrs: object,
) -> Path:
    frames, origins = _tiles(m)
    if sparse:  # stored in another order, each with its position; one may be left out
        order = list(RNG.permutation(len(frames)))
        if drop is not None:
            order.remove(drop)
        frames, origins = [frames[k] for k in order], [origins[k] for k in order]
    ds = Dataset()
    ds.file_meta = FileMetaDataset()
    ds.file_meta.TransferSyntaxUID = ExplicitVRLittleEndian
    ds.file_meta.MediaStorageSOPClassUID = WSI
    ds.file_meta.MediaStorageSOPInstanceUID = generate_uid()
    ds.SOPClassUID, ds.SOPInstanceUID = WSI, ds.file_meta.MediaStorageSOPInstanceUID
    ds.SeriesInstanceUID = series or generate_uid()
    ds.Modality = "SM"
    ds.ImageType = ["ORIGINAL", "PRIMARY", "VOLUME", "NONE"]
    ds.Rows = ds.Columns = TILE
    ds.TotalPixelMatrixRows, ds.TotalPixelMatrixColumns = m.shape[:2]
    ds.NumberOfFrames = len(frames)
    ds.SamplesPerPixel, ds.PhotometricInterpretation, ds.PlanarConfiguration = 3, "RGB", 0
    ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 8, 8, 7, 0
    ds.DimensionOrganizationType = "TILED_SPARSE" if sparse else "TILED_FULL"
    ds.TotalPixelMatrixFocalPlanes, ds.NumberOfOpticalPaths = 1, 1
    measures = Dataset()
    measures.PixelSpacing = list(spacing_mm)
    shared = Dataset()
    shared.PixelMeasuresSequence = Sequence([measures])
    ds.SharedFunctionalGroupsSequence = Sequence([shared])
    if sparse:
        items = []
        for r, c in origins:
            pos = Dataset()
            pos.RowPositionInTotalImagePixelMatrix = r + 1
            pos.ColumnPositionInTotalImagePixelMatrix = c + 1
            item = Dataset()
            item.PlanePositionSlideSequence = Sequence([pos])
            items.append(item)
        ds.PerFrameFunctionalGroupsSequence = Sequence(items)
    for key, value in attrs.items():
        setattr(ds, key, value)
    ds.PixelData = np.stack(frames).tobytes()
    ds.save_as(path, enforce_file_format=True)
    return path


def test_tiled_full_reads_as_its_total_pixel_matrix(tmp_path: Path) -> None:
    m = _matrix(37, 45)  # 3 x 3 tiles, the last row and column cut
    p = _slide(tmp_path / "slide.dcm", m)
    np.testing.assert_array_equal(read_image(p), m)
    assert image_info(p) == (45, 37, 3, "uint8", "dicom")
    assert image_frames(p).total == 1
    np.testing.assert_array_equal(read_image(p, frame=0), m)
    with pytest.raises(InvalidInputError, match=r"frame 1 is out of range: .* one image"):
        read_image(p, frame=1)
    np.testing.assert_array_equal(read_dicom(p, frame=4), m[16:32, 16:32])  # a tile, as stored
    x, y = pixel_size_um(p)  # type: ignore[misc]
    assert (x, y) == pytest.approx((0.25, 0.5))


def test_tiled_sparse_is_placed_by_plane_position_and_gaps_are_glass(tmp_path: Path) -> None:
    m = _matrix(40, 48)  # 3 x 3 tiles
    p = _slide(tmp_path / "sparse.dcm", m, sparse=True)
    np.testing.assert_array_equal(read_image(p), m)
    q = _slide(tmp_path / "gap.dcm", m, sparse=True, drop=4)  # the middle tile left out
    want = m.copy()
    want[16:32, 16:32] = 255  # bright-field glass
    np.testing.assert_array_equal(read_image(q), want)


def test_a_slide_of_several_focal_planes_is_one_line(tmp_path: Path) -> None:
    m = _matrix(32, 32)
    p = _slide(tmp_path / "z.dcm", m, TotalPixelMatrixFocalPlanes=2)
    with pytest.raises(InvalidInputError, match=r"2 focal plane.*one plane and one path") as e:
        read_image(p)
    assert "\n" not in str(e.value)


def _pyramid(tmp_path: Path) -> tuple[Path, np.ndarray, np.ndarray]:
    """Level 0 and a level 1 of one series in a folder, and another slide's file beside them."""
    m = _matrix(64, 96)
    uid = generate_uid()
    p = _slide(tmp_path / "level0.dcm", m, series=uid)
    half = m[::2, ::2]
    _slide(tmp_path / "level1.dcm", half, series=uid, spacing_mm=(0.001, 0.0005))
    _slide(tmp_path / "other.dcm", m[::4, ::4], series=generate_uid())  # another slide
    return p, m, half


def test_info_lists_the_slide_s_levels_and_open_lazy_reads_them(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("dask")
    from imageform.batch.chunked import open_lazy

    p, m, half = _pyramid(tmp_path)
    assert main(["info", str(p), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert (summary["width"], summary["height"]) == (96, 64)
    assert summary["levels"] == [[96, 64], [48, 32]]
    assert main(["info", str(p)]) == 0
    assert "a TILED_FULL slide of 24 tiles of 16 x 16 px" in capsys.readouterr().out
    np.testing.assert_array_equal(np.asarray(open_lazy(p, chunk=32)), m)
    np.testing.assert_array_equal(np.asarray(open_lazy(p, chunk=32, level=-1)), half)


def test_chunked_convert_of_a_slide_keeps_its_levels_and_pixel_size(tmp_path: Path) -> None:
    """It was refused ("expected a TIFF ... or a .zarr array"): level 0 is now the matrix
    exactly (no compression), level 1 the series' smaller file's size, the pixel size
    Pixel Spacing's."""
    tifffile = pytest.importorskip("tifffile")
    pytest.importorskip("dask")
    p, m, _ = _pyramid(tmp_path)
    out = tmp_path / "out.tif"
    argv = ["chunked", "convert", str(p), "-o", str(out), "--to", "srgb", "--compression", "none"]
    assert main([*argv, "--chunk", "32", "--tile", "16"]) == 0
    with tifffile.TiffFile(out) as tf:
        levels = [lv.shape[:2] for lv in tf.series[0].levels]
        np.testing.assert_array_equal(tf.series[0].asarray(), m)
    assert levels == [(64, 96), (32, 48)]
    assert pixel_size_um(out) == pytest.approx((0.25, 0.5))


def test_a_slide_that_states_no_layout_keeps_its_frames(tmp_path: Path) -> None:
    """pathml's small_dicom.dcm (tuning half) has 42 tiles and neither TILED_FULL nor plane
    positions; its tiles run column by column, so row-major placing scrambled them. A layout
    the file does not state is not guessed: it is a multi-frame file, a frame a tile."""
    m = _matrix(32, 48)
    p = _slide(tmp_path / "bare.dcm", m)
    ds = pydicom.dcmread(p)
    del ds.DimensionOrganizationType
    ds.save_as(p)
    assert image_frames(p).total == 6
    with pytest.raises(InvalidInputError, match=r"multi-frame DICOM of 6 frames"):
        read_image(p)
    np.testing.assert_array_equal(read_image(p, frame=1), m[:16, 16:32])


def test_one_frame_larger_than_its_matrix_is_cut_to_it(tmp_path: Path) -> None:
    """OpenSlide's boxes_0.dcm (tuning half): one 64 x 64 JPEG frame of a 16 x 16 matrix was
    read as 64 x 64 (OpenSlide: 16 x 16)."""
    m = _matrix(10, 12)
    p = _slide(tmp_path / "one.dcm", m)  # one 16 x 16 frame, padded
    np.testing.assert_array_equal(read_image(p), m)
    assert image_info(p)[:2] == (12, 10)


def test_chunked_refuses_a_multi_frame_file_that_is_no_slide(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The chunked reader took a multi-frame file of no stated layout for its first frame."""
    pytest.importorskip("dask")
    p = _slide(tmp_path / "bare.dcm", _matrix(32, 48))
    ds = pydicom.dcmread(p)
    del ds.DimensionOrganizationType
    ds.save_as(p)
    out = tmp_path / "o.tif"
    assert main(["chunked", "convert", str(p), "-o", str(out), "--to", "srgb"]) == 1
    err = capsys.readouterr().err
    assert "a multi-frame DICOM of 6 frames" in err and err.count("\n") == 1
    assert not out.exists()


def test_chunked_stain_normalize_measures_a_dicom_slide_on_its_smaller_level(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The held-out pyramid (jcupitt/dicom-wsi-sample) was refused: the statistics' level was
    opened as a TIFF ("pyramid level 1 cannot be decoded (TiffFileError ...)")."""
    tifffile = pytest.importorskip("tifffile")
    pytest.importorskip("dask")
    p, m, _ = _pyramid(tmp_path)
    target = tmp_path / "target.png"
    from imageform.io import write_image

    write_image(target, m)
    out = tmp_path / "sn.tif"
    argv = ["chunked", "stain-normalize", str(p), "-o", str(out), "--target", str(target)]
    assert main([*argv, "--method", "reinhard", "--stats-from", "level", "--json"]) == 0
    assert "pyramid level 1 (48 x 32)" in capsys.readouterr().out
    assert tifffile.imread(out).shape == m.shape
