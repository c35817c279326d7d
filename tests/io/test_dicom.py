"""DICOM images read through pydicom (the ``dicom`` extra): values, colour, frames, windows.

Every file is written here with pydicom (a dataset and its file meta, to ``tmp_path``); the
values are compared with pydicom's own decoding and LUT functions (``pixel_array``,
``apply_modality_lut``, ``apply_voi_lut``, ``convert_color_space``), and the VOI window with
the published cases of DICOM PS3.3 C.11.2.1.2.1. Files shipped inside pydicom's wheel
(``pydicom.data``, MIT) are read where present (JPEG baseline, a palette image, JPEG-LS).
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from imageform.errors import InvalidInputError
from imageform.io import (
    dicom_info,
    dicom_window,
    icc_profile,
    image_color_space,
    image_info,
    read_dicom,
    read_image,
    write_image,
)

pydicom = pytest.importorskip("pydicom")

from pydicom.dataset import Dataset, FileMetaDataset  # noqa: E402
from pydicom.pixels import (  # noqa: E402
    apply_modality_lut,
    apply_voi_lut,
    convert_color_space,
)
from pydicom.uid import ExplicitVRLittleEndian, RLELossless, generate_uid  # noqa: E402

# pydicom's own notes on its test files' quirks (an implicit VR where explicit was declared)
pytestmark = pytest.mark.filterwarnings("ignore:Expected explicit VR:UserWarning")

SECONDARY_CAPTURE = "1.2.840.10008.5.1.4.1.1.7"


def _dataset(
    arr: np.ndarray,
    *,
    photometric: str = "MONOCHROME2",
    bits_stored: int | None = None,
    signed: bool = False,
    frames: int = 1,
    **attrs: Any,
) -> Dataset:
    """A Secondary Capture dataset holding ``arr`` ((frames,) rows, cols (, samples)) as stored."""
    ds = Dataset()
    ds.file_meta = FileMetaDataset()
    ds.file_meta.TransferSyntaxUID = ExplicitVRLittleEndian
    ds.file_meta.MediaStorageSOPClassUID = SECONDARY_CAPTURE
    ds.file_meta.MediaStorageSOPInstanceUID = generate_uid()
    ds.SOPClassUID = SECONDARY_CAPTURE
    ds.SOPInstanceUID = ds.file_meta.MediaStorageSOPInstanceUID
    ds.Modality = attrs.pop("Modality", "OT")
    spp = 3 if photometric in ("RGB", "YBR_FULL", "YBR_FULL_422") else 1
    shape = arr.shape[1:] if frames > 1 else arr.shape
    ds.Rows, ds.Columns = int(shape[0]), int(shape[1])
    if frames > 1:
        ds.NumberOfFrames = frames
    ds.SamplesPerPixel = spp
    ds.PhotometricInterpretation = photometric
    if spp == 3:
        ds.PlanarConfiguration = attrs.pop("PlanarConfiguration", 0)
    ds.BitsAllocated = arr.dtype.itemsize * 8
    ds.BitsStored = bits_stored or ds.BitsAllocated
    ds.HighBit = ds.BitsStored - 1
    ds.PixelRepresentation = 1 if signed else 0
    for key, value in attrs.items():
        setattr(ds, key, value)
    ds.PixelData = arr.tobytes()
    return ds


def _save(ds: Dataset, path: Path) -> Path:
    ds.save_as(path, enforce_file_format=True)
    return path


def _ref(path: Path) -> np.ndarray:
    """pydicom's modality values of a file: ``apply_modality_lut(pixel_array)``."""
    ds = pydicom.dcmread(path)
    return np.asarray(apply_modality_lut(ds.pixel_array, ds))


def _testfile(name: str) -> Path:
    """A file shipped inside pydicom's wheel (pydicom.data, MIT), or skip."""
    from pydicom.data import get_testdata_file

    try:
        found = get_testdata_file(name, download=False)
    except Exception:
        found = None
    if not found or not Path(str(found)).is_file():
        pytest.skip(f"{name} does not ship with this pydicom")
    return Path(str(found))


_RNG = np.random.default_rng(7)


# ---------------------------------------------------------------- grey values


def test_12_bits_in_16_masked_and_kept_as_uint16(tmp_path: Path) -> None:
    stored = _RNG.integers(0, 4096, (6, 5)).astype(np.uint16)
    junk = stored | np.uint16(0xA000)  # bits above Bits Stored: not part of the value
    p = _save(_dataset(junk, bits_stored=12), tmp_path / "xray.dcm")
    got = read_image(p)
    assert got.dtype == np.uint16 and got.shape == (6, 5, 1)
    np.testing.assert_array_equal(got[..., 0], stored)
    np.testing.assert_array_equal(got[..., 0], _ref(p))
    assert image_info(p) == (5, 6, 1, "uint16", "dicom")


def test_8_bit_monochrome2_is_uint8(tmp_path: Path) -> None:
    a = _RNG.integers(0, 256, (4, 7)).astype(np.uint8)
    p = _save(_dataset(a), tmp_path / "a.dcm")
    got = read_image(p)
    assert got.dtype == np.uint8
    np.testing.assert_array_equal(got[..., 0], a)


def test_monochrome1_is_inverted_to_monochrome2_sense(tmp_path: Path) -> None:
    a = _RNG.integers(0, 4096, (5, 6)).astype(np.uint16)
    p = _save(_dataset(a, photometric="MONOCHROME1", bits_stored=12), tmp_path / "cr.dcm")
    got = read_image(p)
    assert got.dtype == np.uint16
    np.testing.assert_array_equal(got[..., 0], 4095 - a)  # white at 2**12 - 1, as WhiteIsZero
    b = _RNG.integers(0, 256, (3, 4)).astype(np.uint8)
    np.testing.assert_array_equal(
        read_image(_save(_dataset(b, photometric="MONOCHROME1"), tmp_path / "b.dcm"))[..., 0],
        255 - b,
    )
    # with a rescale: f(lo) + f(hi) - f(v), the stored range [0, 4095] through f
    q = _save(
        _dataset(a, photometric="MONOCHROME1", bits_stored=12, RescaleSlope="0.5",
                 RescaleIntercept="-10"),
        tmp_path / "c.dcm",
    )  # fmt: skip
    f = lambda v: 0.5 * v - 10  # noqa: E731
    got_f = read_image(q)
    assert got_f.dtype == np.float32
    np.testing.assert_allclose(got_f[..., 0], f(0) + f(4095) - _ref(q), rtol=0, atol=1e-4)


def test_signed_ct_through_rescale(tmp_path: Path) -> None:
    hu = _RNG.integers(-1024, 3000, (8, 9))
    stored = (hu + 1024).astype(np.int16)  # a CT's stored values, intercept -1024
    stored[0, 0] = -2000  # padding below the air value: signed samples
    p = _save(
        _dataset(stored, signed=True, Modality="CT", RescaleSlope="1",
                 RescaleIntercept="-1024", RescaleType="HU", WindowCenter="40",
                 WindowWidth="400", PixelSpacing=["0.5", "0.25"]),
        tmp_path / "ct.dcm",
    )  # fmt: skip
    got = read_image(p)
    assert got.dtype == np.float32 and got.shape == (8, 9, 1)
    np.testing.assert_array_equal(got[..., 0], _ref(p).astype(np.float32))
    assert got[0, 0, 0] == -3024 and got[1, 1, 0] == hu[1, 1]
    info = dicom_info(p)
    assert (info.modality, info.signed, info.rescale_intercept, info.rescale_type) == (
        "CT", True, -1024.0, "HU")  # fmt: skip
    assert info.window_center == (40.0,) and info.window_width == (400.0,)
    assert info.pixel_spacing_mm == (0.5, 0.25) and info.imager_pixel_spacing_mm is None
    assert image_info(p).dtype == "float32"


def test_signed_without_rescale_is_float(tmp_path: Path) -> None:
    a = np.array([[-5, 0, 7]], dtype=np.int16)
    got = read_image(_save(_dataset(a, signed=True), tmp_path / "s.dcm"))
    assert got.dtype == np.float32
    np.testing.assert_array_equal(got[..., 0], a)


def test_modality_lut_sequence(tmp_path: Path) -> None:
    a = _RNG.integers(0, 256, (4, 4)).astype(np.uint16)
    item = Dataset()
    item.LUTDescriptor = [256, 0, 16]
    item.ModalityLUTType = "OD"
    lut = (np.arange(256) ** 2 // 4).astype(np.uint16)
    item.add_new(0x00283006, "US", lut.tolist())  # LUT Data
    ds = _dataset(a, bits_stored=8)
    ds.ModalityLUTSequence = [item]
    p = _save(ds, tmp_path / "lut.dcm")
    got = read_image(p)
    assert got.dtype == np.uint16 and image_info(p).dtype == "uint16"
    np.testing.assert_array_equal(got[..., 0], lut[a])
    np.testing.assert_array_equal(got[..., 0], _ref(p))


def test_enhanced_image_functional_groups(tmp_path: Path) -> None:
    stack = _RNG.integers(0, 4096, (2, 4, 5)).astype(np.uint16)
    ds = _dataset(stack, frames=2, bits_stored=12)
    transform, measures = Dataset(), Dataset()
    transform.RescaleSlope, transform.RescaleIntercept, transform.RescaleType = 2, -100, "US"
    measures.PixelSpacing = [0.25, 0.5]
    shared = Dataset()
    shared.PixelValueTransformationSequence = [transform]
    shared.PixelMeasuresSequence = [measures]
    ds.SharedFunctionalGroupsSequence = [shared]
    frames = []
    for c, w in ((1000, 2000), (3000, 500)):  # a window per frame (Frame VOI LUT)
        voi, item = Dataset(), Dataset()
        voi.WindowCenter, voi.WindowWidth = c, w
        item.FrameVOILUTSequence = [voi]
        frames.append(item)
    ds.PerFrameFunctionalGroupsSequence = frames
    p = _save(ds, tmp_path / "enhanced.dcm")
    info = dicom_info(p)
    assert (info.rescale_slope, info.rescale_intercept, info.pixel_spacing_mm) == (
        2.0, -100.0, (0.25, 0.5))  # fmt: skip
    assert info.window_center == (1000.0,) and info.window_width == (2000.0,)
    for i, (c, w) in enumerate(((1000, 2000), (3000, 500))):
        values = read_dicom(p, frame=i)[..., 0]
        assert values.dtype == np.float32
        np.testing.assert_array_equal(values, stack[i] * 2.0 - 100)
        np.testing.assert_allclose(
            read_dicom(p, frame=i, window="auto")[..., 0],
            dicom_window(stack[i] * 2.0 - 100, c, w), rtol=0, atol=1e-6,
        )  # fmt: skip


# ---------------------------------------------------------------- colour


def test_rgb_interleaved_and_planar(tmp_path: Path) -> None:
    rgb = _RNG.integers(0, 256, (5, 6, 3)).astype(np.uint8)
    p = _save(_dataset(rgb, photometric="RGB"), tmp_path / "rgb.dcm")
    np.testing.assert_array_equal(read_image(p), rgb)
    planar = np.ascontiguousarray(np.moveaxis(rgb, -1, 0))  # R plane, G plane, B plane
    ds = _dataset(planar.reshape(3 * 5, 6), photometric="RGB", PlanarConfiguration=1)
    ds.Rows, ds.Columns = 5, 6
    q = _save(ds, tmp_path / "planar.dcm")
    np.testing.assert_array_equal(read_image(q), rgb)
    assert image_info(q) == (6, 5, 3, "uint8", "dicom")
    assert image_color_space(q).name is None  # no ICC profile: read as sRGB


def test_ybr_full_and_full_422_to_rgb(tmp_path: Path) -> None:
    rgb = _RNG.integers(0, 256, (4, 6, 3)).astype(np.uint8)
    rgb[:, 1::2] = rgb[:, ::2]  # one colour per pair of columns: 4:2:2 loses nothing
    ybr = convert_color_space(rgb, "RGB", "YBR_FULL")
    p = _save(_dataset(ybr, photometric="YBR_FULL"), tmp_path / "ybr.dcm")
    want = convert_color_space(ybr, "YBR_FULL", "RGB")
    np.testing.assert_array_equal(read_image(p), want)
    assert np.abs(read_image(p).astype(int) - rgb).max() <= 2
    # YBR_FULL_422 stored: Y1 Y2 Cb Cr for each pair of pixels (PS3.3 C.7.6.3.1.2)
    y, cb, cr = ybr[..., 0], ybr[:, ::2, 1], ybr[:, ::2, 2]
    packed = np.stack([y[:, ::2], y[:, 1::2], cb, cr], axis=-1).reshape(4, 12)
    ds = _dataset(packed.astype(np.uint8), photometric="YBR_FULL_422")
    ds.Rows, ds.Columns = 4, 6
    q = _save(ds, tmp_path / "ybr422.dcm")
    got = read_image(q)
    assert got.shape == (4, 6, 3) and got.dtype == np.uint8
    np.testing.assert_array_equal(got, pydicom.dcmread(q).pixel_array)
    np.testing.assert_array_equal(got, want)


def test_icc_profile_is_what_the_file_declares(tmp_path: Path) -> None:
    rgb = _RNG.integers(0, 256, (3, 4, 3)).astype(np.uint8)
    ds = _dataset(rgb, photometric="RGB")
    ds.ICCProfile = icc_profile("display_p3")
    p = _save(ds, tmp_path / "wsi.dcm")
    assert image_color_space(p).name == "display_p3"
    assert dicom_info(p).icc
    from imageform.cli import main

    out = tmp_path / "srgb.png"
    assert main(["convert", str(p), "-o", str(out)]) == 0  # --from auto: its profile
    assert not np.array_equal(read_image(out), rgb)  # P3 -> sRGB changed the values


def test_palette_color_from_pydicom_data() -> None:
    p = _testfile("examples_palette.dcm")
    from pydicom.pixels import apply_color_lut

    ds = pydicom.dcmread(p)
    np.testing.assert_array_equal(read_image(p), apply_color_lut(ds.pixel_array, ds))


@pytest.mark.parametrize(
    "name",
    [
        "SC_rgb_jpeg.dcm",  # JPEG baseline, RGB: through Pillow
        "SC_rgb_jpeg_dcmtk.dcm",  # JPEG baseline, YBR_FULL
        "SC_rgb_dcmtk_+eb+cy+s2.dcm",  # JPEG baseline, YBR_FULL_422
        "SC_rgb_rle.dcm",
        "SC_rgb_small_odd_big_endian.dcm",
        "MR_small_bigendian.dcm",  # signed, big endian
        "image_dfl.dcm",  # deflated
        "CT_small.dcm",
    ],
)
def test_pydicom_data_files_as_pydicom_reads_them(name: str) -> None:
    p = _testfile(name)
    ds = pydicom.dcmread(p)
    want = np.asarray(ds.pixel_array)
    got = read_image(p)
    if ds.SamplesPerPixel == 1:
        want = apply_modality_lut(want, ds)[..., None]
    assert got.dtype == np.dtype(image_info(p).dtype)
    np.testing.assert_array_equal(got, want)


def test_a_compression_without_its_plugin_is_one_line() -> None:
    p = _testfile("MR_small_jpeg_ls_lossless.dcm")
    for plugin in ("jpeg_ls", "pylibjpeg", "gdcm"):
        try:
            __import__(plugin)
        except ImportError:
            continue
        pytest.skip(f"{plugin} is installed: JPEG-LS decodes")
    with pytest.raises(InvalidInputError, match=r"JPEG-LS.*pip install pyjpegls") as e:
        read_image(p)
    assert "\n" not in str(e.value)


# ---------------------------------------------------------------- frames, compression


def test_multi_frame_refused_and_read_by_frame(tmp_path: Path) -> None:
    stack = _RNG.integers(0, 256, (3, 4, 5)).astype(np.uint8)
    p = _save(_dataset(stack, frames=3), tmp_path / "cine.dcm")
    with pytest.raises(InvalidInputError, match=r"multi-frame DICOM of 3 frames.*frame=N, 0 to 2"):
        read_image(p)
    with pytest.raises(InvalidInputError, match="3 frames"):
        image_info(p)  # as read_image, like a TIFF stack
    for i in range(3):
        np.testing.assert_array_equal(read_dicom(p, frame=i)[..., 0], stack[i])
    assert dicom_info(p).frames == 3
    with pytest.raises(InvalidInputError, match="no frame 3"):
        read_dicom(p, frame=3)
    with pytest.raises(InvalidInputError, match="frame as an integer"):
        read_dicom(p, frame=True)  # type: ignore[arg-type]


def test_rle_lossless(tmp_path: Path) -> None:
    a = _RNG.integers(0, 4096, (16, 12)).astype(np.uint16)
    ds = _dataset(a, bits_stored=12)
    ds.compress(RLELossless, a)
    p = _save(ds, tmp_path / "rle.dcm")
    assert pydicom.dcmread(p).file_meta.TransferSyntaxUID == RLELossless
    np.testing.assert_array_equal(read_image(p)[..., 0], a)
    rgb = _RNG.integers(0, 256, (2, 8, 6, 3)).astype(np.uint8)
    ds = _dataset(rgb, photometric="RGB", frames=2)
    ds.compress(RLELossless, rgb)
    q = _save(ds, tmp_path / "rle2.dcm")
    np.testing.assert_array_equal(read_dicom(q, frame=1), rgb[1])


# ---------------------------------------------------------------- bad files


def test_truncated_file_is_one_line_and_the_cli_writes_nothing(tmp_path: Path) -> None:
    from imageform.cli import main

    a = _RNG.integers(0, 256, (32, 32)).astype(np.uint8)
    whole = _save(_dataset(a), tmp_path / "whole.dcm").read_bytes()
    for cut in (len(whole) - 100, 200, 140):  # in the pixel data, in the header, after DICM
        p = tmp_path / f"cut{cut}.dcm"
        p.write_bytes(whole[:cut])
        with pytest.raises(InvalidInputError, match=f"cannot read {p}") as e:
            read_image(p)
        assert "\n" not in str(e.value)
        out = tmp_path / f"cut{cut}.png"
        assert main(["convert", str(p), "-o", str(out)]) == 1
        assert not out.exists() and not list(tmp_path.glob(f".cut{cut}*"))


def test_corrupt_compressed_data_is_one_line_naming_no_plugin(tmp_path: Path) -> None:
    a = _RNG.integers(0, 4096, (16, 12)).astype(np.uint16)
    ds = _dataset(a)
    ds.compress(RLELossless, a)
    data = bytearray(_save(ds, tmp_path / "rle.dcm").read_bytes())
    pixel = data.index(b"\xe0\x7f\x10\x00")  # (7FE0,0010) Pixel Data
    items = [k for k in range(pixel, len(data) - 3) if data[k : k + 4] == b"\xfe\xff\x00\xe0"]
    frame = items[1] + 8  # after the offset table: the frame's RLE header
    data[frame : frame + 4] = (15).to_bytes(4, "little")  # 15 segments, not 2
    p = tmp_path / "bad.dcm"
    p.write_bytes(bytes(data))
    with pytest.raises(InvalidInputError, match="RLE Lossless pixel data cannot be decoded") as e:
        read_image(p)
    assert "\n" not in str(e.value) and "plugin" not in str(e.value).split("(")[0]


def test_not_a_dicom_file_named_dcm(tmp_path: Path) -> None:
    p = tmp_path / "notes.dcm"
    p.write_text("patient list\n" * 30)
    with pytest.raises(InvalidInputError, match="not a DICOM file") as e:
        read_image(p)
    assert "\n" not in str(e.value)
    q = tmp_path / "photo.dcm"  # a PNG under .dcm: read as the PNG it is
    write_image(tmp_path / "photo.png", np.full((2, 3, 3), 0.5))
    q.write_bytes((tmp_path / "photo.png").read_bytes())
    assert read_image(q).shape == (2, 3, 3) and image_info(q).format == "png"


def test_any_suffix_or_none(tmp_path: Path) -> None:
    a = _RNG.integers(0, 256, (3, 3)).astype(np.uint8)
    for name in ("IM000001", "scan.IMA", "x.dicom"):
        p = _save(_dataset(a), tmp_path / name)
        np.testing.assert_array_equal(read_image(p)[..., 0], a)
        assert image_info(p).format == "dicom"
    with pytest.raises(InvalidInputError, match="does not write it"):
        write_image(tmp_path / "out.dcm", np.zeros((2, 2)))


def test_a_tiff_header_in_the_preamble_is_dicom_under_dcm(tmp_path: Path) -> None:
    a = _RNG.integers(0, 256, (3, 4)).astype(np.uint8)
    ds = _dataset(a)
    ds.preamble = b"II*\x00" + bytes(124)  # a dual-personality DICOM-TIFF's first bytes
    p = _save(ds, tmp_path / "slide.dcm")
    assert p.read_bytes()[:4] == b"II*\x00"
    np.testing.assert_array_equal(read_image(p)[..., 0], a)


def test_a_header_of_bad_values_is_one_line(tmp_path: Path) -> None:
    ds = _dataset(np.zeros((2, 2), np.uint8))
    ds.ModalityLUTSequence = [Dataset()]  # an item without its LUT Descriptor
    p = _save(ds, tmp_path / "bad.dcm")
    for fn in (read_image, image_info, dicom_info):
        with pytest.raises(InvalidInputError, match="corrupt DICOM header") as e:
            fn(p)
        assert "\n" not in str(e.value)


def test_no_image_and_pixel_limit(tmp_path: Path) -> None:
    ds = _dataset(np.zeros((2, 2), np.uint8))
    for key in ("Rows", "Columns", "PixelData"):
        delattr(ds, key)
    ds.SOPClassUID = ds.file_meta.MediaStorageSOPClassUID = "1.2.840.10008.5.1.4.1.1.88.11"
    p = _save(ds, tmp_path / "report.dcm")
    with pytest.raises(InvalidInputError, match=r"no image \(Basic Text SR Storage\)"):
        read_image(p)
    ds.SOPClassUID = ds.file_meta.MediaStorageSOPClassUID = SECONDARY_CAPTURE
    q = _save(ds, tmp_path / "cut.dcm")  # an image's class without its rows: cut short
    with pytest.raises(InvalidInputError, match=r"without its Rows \(no image in it, or the"):
        read_image(q)
    big = _save(_dataset(np.zeros((40, 30), np.uint8)), tmp_path / "big.dcm")
    with pytest.raises(InvalidInputError, match="above the limit"):
        read_image(big, max_pixels=1000)


def test_missing_pydicom_names_the_extra(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from imageform._optional import MissingExtraError

    p = _save(_dataset(np.zeros((2, 2), np.uint8)), tmp_path / "a.dcm")
    monkeypatch.setitem(sys.modules, "pydicom", None)  # import pydicom raises ImportError
    with pytest.raises(MissingExtraError, match=r'pip install "imageform\[dicom\]"') as e:
        read_image(p)
    assert "\n" not in str(e.value)


# ---------------------------------------------------------------- the VOI window


#: DICOM PS3.3 C.11.2.1.2.1, notes: (center, width) -> (x, y) with output range 0 to 255.
_PUBLISHED = {
    (2048, 4096): [(0, 0), (-5, 0), (4095, 255), (4096, 255), (2047.5, 127.5)],
    (2048, 1): [(2047.5, 0), (2047.6, 255), (0, 0), (4095, 255)],
    (0, 100): [(-50, 0), (-49, (0.5 / 99 + 0.5 - 49 / 99) * 255), (49, 255), (50, 255),
               (0, (0.5 / 99 + 0.5) * 255)],
    (0, 1): [(-0.5, 0), (-0.4, 255), (-1, 0), (0, 255)],
}  # fmt: skip


@pytest.mark.parametrize("cw", list(_PUBLISHED), ids=str)
def test_window_linear_published_cases(cw: tuple[float, float]) -> None:
    xs, ys = zip(*_PUBLISHED[cw], strict=True)
    got = dicom_window(np.array(xs, dtype=float), *cw) * 255
    np.testing.assert_allclose(got, ys, rtol=0, atol=1e-9)


def _pydicom_window(x: np.ndarray, c: float, w: float, function: str) -> np.ndarray:
    """pydicom's apply_voi_lut of ``x`` (unsigned 16 bits, no rescale), scaled to [0, 1]."""
    ds = Dataset()
    ds.PhotometricInterpretation = "MONOCHROME2"
    ds.BitsStored, ds.PixelRepresentation = 16, 0
    ds.WindowCenter, ds.WindowWidth = c, w
    ds.VOILUTFunction = function.upper()
    with np.errstate(over="ignore"):  # pydicom's sigmoid, far below the center
        return np.asarray(apply_voi_lut(x.copy(), ds)) / 65535


@pytest.mark.parametrize("function", ["linear", "linear_exact", "sigmoid"])
@pytest.mark.parametrize("cw", [(40.0, 400.0), (2048.0, 1.0), (1000.5, 37.0), (0.0, 1.5)])
def test_window_equals_pydicom(function: str, cw: tuple[float, float]) -> None:
    x = np.concatenate([_RNG.uniform(-200, 4200, 500), np.arange(-2, 4100, 0.5)])
    x = np.concatenate([x, [cw[0] - 0.5 - (cw[1] - 1) / 2, cw[0] - 0.5 + (cw[1] - 1) / 2]])
    got = dicom_window(x, *cw, function=function)
    np.testing.assert_allclose(got, _pydicom_window(x, *cw, function), rtol=0, atol=1e-12)
    assert got.min() >= 0 and got.max() <= 1


def test_window_bad_input() -> None:
    with pytest.raises(InvalidInputError, match="width >= 1"):
        dicom_window([1.0], 0, 0.5)
    with pytest.raises(InvalidInputError, match="width > 0"):
        dicom_window([1.0], 0, 0, function="sigmoid")
    with pytest.raises(InvalidInputError, match="finite window center"):
        dicom_window([1.0], float("nan"), 10)
    with pytest.raises(InvalidInputError, match="as a number"):
        dicom_window([1.0], "40", 10)  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="NaN or inf"):
        dicom_window([np.nan], 0, 10)
    with pytest.raises(InvalidInputError, match="numeric values"):
        dicom_window(["a"], 0, 10)
    from imageform.errors import UnknownOptionError

    with pytest.raises(UnknownOptionError):
        dicom_window([1.0], 0, 10, function="gamma")


def test_read_dicom_window_auto_equals_pydicom(tmp_path: Path) -> None:
    stored = _RNG.integers(0, 4096, (6, 7)).astype(np.int16)
    p = _save(
        _dataset(stored, signed=True, RescaleSlope="1", RescaleIntercept="-1024",
                 WindowCenter=["40", "500"], WindowWidth=["400", "2000"]),
        tmp_path / "ct.dcm",
    )  # fmt: skip
    got = read_dicom(p, window="auto")
    assert got.dtype == np.float32 and got.shape == (6, 7, 1)
    ds = pydicom.dcmread(p)
    ref = apply_voi_lut(apply_modality_lut(ds.pixel_array, ds), ds)  # the first window
    lo, hi = -(2**15) - 1024, 2**15 - 1 - 1024  # pydicom's output range for signed + rescale
    np.testing.assert_allclose(got[..., 0], (ref - lo) / (hi - lo), rtol=0, atol=1e-6)
    np.testing.assert_allclose(
        read_dicom(p, window=(500, 2000))[..., 0],
        dicom_window(_ref(p), 500, 2000), rtol=0, atol=1e-6,
    )  # fmt: skip
    # MONOCHROME1: the window on the values as stored, then inverted (Presentation LUT INVERSE)
    ds.PhotometricInterpretation = "MONOCHROME1"
    q = _save(ds, tmp_path / "m1.dcm")
    np.testing.assert_allclose(read_dicom(q, window="auto"), 1 - got, rtol=0, atol=1e-6)
    with pytest.raises(InvalidInputError, match="no VOI window"):
        read_dicom(_save(_dataset(np.zeros((2, 2, 3), np.uint8), photometric="RGB"),
                         tmp_path / "c.dcm"), window="auto")  # fmt: skip


def test_window_auto_without_a_window_and_with_a_voi_lut(tmp_path: Path) -> None:
    a = np.array([[100, 200], [300, 500]], dtype=np.uint16)
    p = _save(_dataset(a, bits_stored=12), tmp_path / "plain.dcm")
    np.testing.assert_allclose(read_dicom(p, window="auto")[..., 0], (a - 100) / 400, atol=1e-7)
    ds = _dataset(a, bits_stored=12)
    item = Dataset()
    item.LUTDescriptor = [1024, 0, 16]
    item.add_new(0x00283006, "US", (np.arange(1024) * 64).tolist())  # LUT Data
    ds.VOILUTSequence = [item]
    q = _save(ds, tmp_path / "voilut.dcm")
    got = read_dicom(q, window="auto")[..., 0]
    np.testing.assert_allclose(got, a * 64 / 65535, rtol=0, atol=1e-7)
    ref = apply_voi_lut(a, pydicom.dcmread(q))
    np.testing.assert_allclose(got, ref / 65535, rtol=0, atol=1e-7)


# ---------------------------------------------------------------- the command line


def test_cli_info_and_convert(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import json

    from imageform.cli import main

    stored = _RNG.integers(0, 2000, (10, 12)).astype(np.int16)
    p = _save(
        _dataset(stored, signed=True, Modality="CT", RescaleSlope="1", RescaleIntercept="-1024",
                 RescaleType="HU", WindowCenter="40", WindowWidth="400",
                 PixelSpacing=["0.7", "0.7"]),
        tmp_path / "ct.dcm",
    )  # fmt: skip
    assert main(["info", str(p)]) == 0
    text = capsys.readouterr().out
    assert "dicom, 12 x 10 px, 1 channel(s), float32" in text
    assert "modality CT, MONOCHROME2, 16 of 16 bits stored (signed)" in text
    assert "intercept -1024 (HU)" in text and "window center/width: 40/400" in text
    assert "pixel spacing: 0.7 x 0.7 mm" in text
    assert main(["info", str(p), "--json"]) == 0
    js = json.loads(capsys.readouterr().out)
    assert js["format"] == "dicom" and js["dicom"]["window_center"] == [40.0]

    out = tmp_path / "ct.png"
    assert main(["convert", str(p), "-o", str(out)]) == 1  # HU are no colours
    assert "--window auto" in capsys.readouterr().err and not out.exists()
    assert main(["convert", str(p), "-o", str(out), "--window", "auto", "--to", "gray"]) == 0
    want = np.round(dicom_window(_ref(p), 40, 400) * 255).astype(np.uint8)
    np.testing.assert_array_equal(read_image(out)[..., 0], want)
    assert main(["convert", str(p), "-o", str(out), "--window", "40,400", "--to", "gray",
                 "--force"]) == 0  # fmt: skip
    np.testing.assert_array_equal(read_image(out)[..., 0], want)
    assert main(["convert", str(p), "-o", str(out), "--window", "40", "--force"]) == 2
    png = tmp_path / "a.png"
    write_image(png, np.zeros((2, 2)))
    assert main(["convert", str(png), "-o", str(tmp_path / "b.png"), "--window", "auto"]) == 1
    assert "applies to DICOM input" in capsys.readouterr().err


def test_cli_convert_a_frame_of_a_multi_frame_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``convert --frame N`` writes frame N of a cine; without it the refusal names the option."""
    from imageform.cli import main

    rgb = _RNG.integers(0, 256, (3, 6, 8, 3)).astype(np.uint8)
    p = _save(_dataset(rgb, photometric="RGB", frames=3), tmp_path / "cine.dcm")
    assert main(["info", str(p)]) == 0
    assert "3 frames (read one: --frame N)" in capsys.readouterr().out
    out = tmp_path / "f.png"
    assert main(["convert", str(p), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert "multi-frame DICOM of 3 frames; convert one with --frame N (0 to 2)" in err
    assert not out.exists()
    for i in (0, 2):
        assert main(["convert", str(p), "-o", str(out), "--frame", str(i), "--force"]) == 0
        np.testing.assert_array_equal(read_image(out), rgb[i])
    before = out.read_bytes()
    assert main(["convert", str(p), "-o", str(out), "--frame", "3", "--force"]) == 1
    assert "has 3 frame(s) (0 to 2), no frame 3" in capsys.readouterr().err
    assert main(["convert", str(p), "-o", str(out), "--frame", "-1", "--force"]) == 2
    assert "expected --frame >= 0" in capsys.readouterr().err
    assert main(["convert", str(p), "-o", str(out), "--frame", "x", "--force"]) == 2
    assert out.read_bytes() == before  # nothing half-written by the refusals
    png = tmp_path / "a.png"
    write_image(png, np.zeros((2, 2)))
    assert main(["convert", str(png), "-o", str(tmp_path / "b.png"), "--frame", "1"]) == 1
    assert "frame 1 is out of range" in capsys.readouterr().err  # a PNG holds frame 0 alone
    # a CT run's frame holds Hounsfield units: --window still needed, and it applies per frame
    hu = _RNG.integers(0, 2000, (2, 5, 4)).astype(np.int16)
    ct = _save(
        _dataset(hu, signed=True, frames=2, RescaleSlope="1", RescaleIntercept="-1024",
                 WindowCenter="40", WindowWidth="400"),
        tmp_path / "run.dcm",
    )  # fmt: skip
    gray = tmp_path / "g.png"
    assert main(["convert", str(ct), "-o", str(gray), "--frame", "1", "--to", "gray"]) == 1
    assert "--window auto" in capsys.readouterr().err
    assert main(["convert", str(ct), "-o", str(gray), "--frame", "1", "--to", "gray",
                 "--window", "auto"]) == 0  # fmt: skip
    want = read_dicom(ct, frame=1, window="auto")
    np.testing.assert_array_equal(read_image(gray)[..., 0], np.round(want[..., 0] * 255))


def test_a_folder_of_dicom_frames_is_an_image_sequence(tmp_path: Path) -> None:
    """An endoscopy series exported as one DICOM file a frame: open_video reads the folder in
    natural order (frame2 before frame10), as a folder of PNGs."""
    from imageform.io import open_video

    rng = np.random.default_rng(0)
    frames = [rng.integers(0, 256, (6, 8, 3), dtype=np.uint8) for _ in range(11)]
    for i, f in enumerate(frames):
        _save(_dataset(f, photometric="RGB"), tmp_path / f"frame{i}.dcm")
    (tmp_path / "notes.txt").write_text("series 1")
    with open_video(tmp_path, fps=25) as video:
        got = [frame.image for frame in video]
    assert len(got) == 11
    for want, have in zip(frames, got, strict=True):
        np.testing.assert_array_equal(have, want)


def test_a_multi_frame_dicom_file_is_a_video(tmp_path: Path) -> None:
    """A cine (multi-frame) DICOM file opens as a video: its Frame Time gives the rate, every
    frame as stored (8-bit RGB), grey frames of 12 bits scaled by their stored range."""
    from imageform.io import open_video

    rng = np.random.default_rng(1)
    rgb = rng.integers(0, 256, (5, 6, 8, 3), dtype=np.uint8)
    cine = _save(_dataset(rgb, photometric="RGB", frames=5, FrameTime=40.0), tmp_path / "c.dcm")
    with open_video(cine) as video:
        assert (video.info.fps, video.info.frames, video.info.codec) == (25.0, 5, "dicom")
        got = list(video)
    assert [f.index for f in got] == list(range(5))
    assert [f.time_s for f in got] == [0.0, 0.04, 0.08, 0.12, 0.16]
    for want, have in zip(rgb, got, strict=True):
        np.testing.assert_array_equal(have.image, want)
    grey = rng.integers(0, 4096, (3, 6, 8), dtype=np.uint16)
    run = _save(_dataset(grey, bits_stored=12, frames=3, CineRate=15), tmp_path / "x.dcm")
    with open_video(run, fps=99) as video:
        assert video.info.fps == 15.0
        frames = [f.image for f in video]
    want = np.round(grey.astype(np.float64) / 4095 * 255).astype(np.uint8)
    for w, have in zip(want, frames, strict=True):
        assert have.shape == (6, 8, 3)
        np.testing.assert_array_equal(have[..., 0], w)


def test_is_dicom_file_reads_regular_files_only(tmp_path: Path) -> None:
    """One test of ``DICM`` at byte 128 serves the readers, video and chunked commands: any
    suffix; a folder or a FIFO is never opened (a FIFO would block); a short file is not."""
    import os

    from imageform.io.image_io import is_dicom_file

    (tmp_path / "scan.bin").write_bytes(b"\0" * 128 + b"DICM" + b"\0" * 8)
    (tmp_path / "short.dcm").write_bytes(b"\0" * 130)
    os.mkfifo(tmp_path / "pipe.dcm")
    assert is_dicom_file(tmp_path / "scan.bin") and is_dicom_file(str(tmp_path / "scan.bin"))
    assert not is_dicom_file(tmp_path / "short.dcm")
    assert not is_dicom_file(tmp_path / "pipe.dcm") and not is_dicom_file(tmp_path)
    assert not is_dicom_file(tmp_path / "missing.dcm")
