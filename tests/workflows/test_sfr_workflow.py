"""``imageform sfr`` through the workflow layer (execute), on synthetic edges and charts."""

from __future__ import annotations

import csv
import re
from pathlib import Path

import numpy as np
import pytest

from imageform.analysis import render_sfr_chart, render_slanted_edge, slanted_edge_sfr
from imageform.errors import InvalidInputError
from imageform.workflows import execute, get_workflow


def test_sfr_chart_npy_to_csv(tmp_path: Path) -> None:
    chart = render_sfr_chart((160, 200), grid=(1, 1), angle_deg=5.0, sigma=0.8, supersampling=4)
    src = tmp_path / "chart.npy"
    np.save(src, chart.astype(np.float32))
    out = tmp_path / "sfr.csv"
    res = execute("sfr", image=src, out=out)
    edges = res.summary["edges"]
    assert len(edges) == 4
    assert all(abs(abs(e["angle_deg"]) - 5.0) < 0.05 for e in edges)
    m50 = [e["channels"]["Y"]["mtf50"] for e in edges]
    assert np.allclose(m50, 0.2201, rtol=0.02)
    with out.open() as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["edge", "channel", "frequency_cy_per_px", "sfr"]
    assert float(rows[1][3]) == pytest.approx(1.0)


def test_sfr_roi_srgb_png(tmp_path: Path) -> None:
    from imageform.color import linear_to_srgb
    from imageform.io import write_image

    lin = render_slanted_edge((96, 64), angle_deg=4.0, sigma=0.8)
    big = np.full((120, 100), 0.2)
    big[10:106, 20:84] = lin
    src = tmp_path / "edge.png"
    write_image(src, np.round(np.asarray(linear_to_srgb(big)) * 65535).astype(np.uint16))
    opts = get_workflow("sfr").make_options(roi="20,10,64,96")
    res = execute("sfr", image=src, out=None, options=opts)
    (edge,) = res.summary["edges"]
    ref = float(slanted_edge_sfr(lin).mtf50[0])
    assert edge["channels"]["Y"]["mtf50"] == pytest.approx(ref, rel=0.01)
    # read as if linear, the sRGB curve bends the edge: a (slightly) different MTF50
    opts = get_workflow("sfr").make_options(roi="20,10,64,96", transfer="linear")
    bad = execute("sfr", image=src, out=None, options=opts).summary["edges"][0]
    assert bad["channels"]["Y"]["mtf50"] != pytest.approx(ref, rel=0.01)


def test_sfr_refusals(tmp_path: Path) -> None:
    src = tmp_path / "flat.npy"
    np.save(src, np.full((64, 64), 0.5, dtype=np.float32))
    with pytest.raises(InvalidInputError, match="no slanted edge"):
        execute("sfr", image=src, out=None)
    with pytest.raises(InvalidInputError, match="--roi"):
        get_workflow("sfr").make_options(roi="1,2,3").check()
    # an ROI off the image names the flag and the image (the library said 'roi')
    opts = get_workflow("sfr").make_options(roi="10,10,100,20")
    with pytest.raises(InvalidInputError, match=r"expected --roi x,y,w,h inside the 64x64 image"):
        execute("sfr", image=src, out=None, options=opts)


@pytest.mark.parametrize(
    ("values", "words"),
    [
        ({"min_angle": 50}, "expected --min-angle <= 40, got 50"),
        ({"min_angle": 20, "max_angle": 10}, "expected --min-angle <= --max-angle, got 20 > 10"),
    ],
)
def test_sfr_angle_bounds_name_the_flags(values: dict[str, float], words: str) -> None:
    """The edge finder's angle bounds are refused with the options (they were the library's
    'min_angle <= 40' after the image was read)."""
    with pytest.raises(InvalidInputError, match=re.escape(words)):
        get_workflow("sfr").make_options(**values)


def test_sfr_of_a_raw_file_is_measured_on_its_mosaic(tmp_path: Path) -> None:
    """A DNG (what ``simulate --lab`` writes for its edge): black level removed, the CFA's
    four photosites balanced, one channel ``raw`` with the grey chart's MTF50 (0.2201, as
    test_sfr_chart_npy_to_csv); a colour cast (gains 0.5, 1, 0.7 on R, G, B) changes nothing."""
    from imageform.io import write_dng

    lin = render_sfr_chart((160, 200), grid=(1, 1), angle_deg=5.0, sigma=0.8, supersampling=4)
    gains = np.ones_like(lin)
    gains[0::2, 0::2] = 0.5  # R of RGGB
    gains[1::2, 1::2] = 0.7  # B
    black, white = 64.0, 4095.0
    dn = np.round(black + (white - black) * 0.9 * lin * gains).astype(np.uint16)
    src = tmp_path / "edge.dng"
    write_dng(src, dn, cfa_pattern="RGGB", black_level=black, white_level=white,
              color_matrix=np.eye(3))  # fmt: skip
    before = src.read_bytes()
    res = execute("sfr", image=src, out=tmp_path / "sfr.csv")
    edges = res.summary["edges"]
    assert len(edges) == 4
    assert all(list(e["channels"]) == ["raw"] for e in edges)
    m50 = [e["channels"]["raw"]["mtf50"] for e in edges]
    assert np.allclose(m50, 0.2201, rtol=0.03), m50
    assert res.summary["transfer"] == "linear"
    assert src.read_bytes() == before  # the input untouched
    with (tmp_path / "sfr.csv").open() as fh:
        assert {row[1] for row in list(csv.reader(fh))[1:]} == {"raw"}


def test_sfr_of_monochrome_and_linear_raws(tmp_path: Path) -> None:
    """A monochrome raw is measured on its one channel (``raw``), a linear (demosaiced) raw on
    its three; both crashed in the reader (a 2x2 black-level tile taken for granted)."""
    import tifffile

    from imageform.io import write_dng

    lin = render_sfr_chart((160, 200), grid=(1, 1), angle_deg=5.0, sigma=0.8, supersampling=4)
    black, white = 64.0, 4095.0
    dn = np.round(black + (white - black) * 0.9 * lin).astype(np.uint16)
    base = write_dng(tmp_path / "base.dng", dn, cfa_pattern="RGGB", black_level=black,
                     white_level=white, color_matrix=np.eye(3))  # fmt: skip
    with tifffile.TiffFile(base) as tf:
        tags = [(t.code, t.dtype, t.count, t.value, True) for t in tf.pages[0].tags]
    keep = [t for t in tags if t[0] >= 50706 and t[0] not in (50710, 50711, 50728)]
    mono = tmp_path / "mono.dng"
    tifffile.imwrite(mono, dn, photometric=1, extratags=keep)
    with tifffile.TiffFile(mono) as tf:
        at = tf.pages[0].tags[262].valueoffset  # type: ignore[union-attr]
    with mono.open("r+b") as fh:  # LinearRaw with one sample (tifffile writes three only)
        fh.seek(at)
        fh.write(np.uint16(34892).tobytes())
    linear = tmp_path / "linear.dng"
    tifffile.imwrite(linear, np.repeat(dn[..., None], 3, axis=-1), photometric=34892,
                     extratags=keep)  # fmt: skip
    for path, channels in ((mono, ["raw"]), (linear, ["R", "G", "B", "Y"])):
        edges = execute("sfr", image=path, out=None).summary["edges"]
        assert len(edges) == 4, path.name
        for e in edges:
            assert list(e["channels"]) == channels
            m50 = [c["mtf50"] for c in e["channels"].values()]
            assert np.allclose(m50, 0.2201, rtol=0.03), (path.name, m50)


def _dx_dicom(path: Path, values: np.ndarray, **attrs: object) -> Path:
    """A 12-bit DX (digital X-ray) image of ``values`` written with pydicom."""
    pytest.importorskip("pydicom")
    from pydicom.dataset import Dataset, FileMetaDataset
    from pydicom.uid import ExplicitVRLittleEndian, generate_uid

    ds = Dataset()
    ds.file_meta = FileMetaDataset()
    ds.file_meta.TransferSyntaxUID = ExplicitVRLittleEndian
    ds.file_meta.MediaStorageSOPClassUID = ds.SOPClassUID = "1.2.840.10008.5.1.4.1.1.1.1"
    ds.file_meta.MediaStorageSOPInstanceUID = ds.SOPInstanceUID = generate_uid()
    ds.Modality, ds.SamplesPerPixel, ds.PhotometricInterpretation = "DX", 1, "MONOCHROME2"
    ds.Rows, ds.Columns = values.shape
    ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 16, 12, 11, 0
    for key, value in attrs.items():
        setattr(ds, key, value)
    ds.PixelData = np.round(values * 4000).astype(np.uint16).tobytes()
    ds.save_as(path, enforce_file_format=True)
    return path


def _chart_lp(res_edges: list[dict[str, object]], channel: str = "Y") -> list[float]:
    return [e["channels"][channel]["mtf50_lp_per_mm"] for e in res_edges]  # type: ignore[index]


def test_sfr_of_an_x_ray_dicom_in_line_pairs_per_mm(tmp_path: Path) -> None:
    """A DX image of the chart (Gaussian blur sigma 0.8 px: MTF50 0.2201 cycles/pixel, as
    test_sfr_chart_npy_to_csv) is measured on its values as linear (decoding them as sRGB
    would bend the edge), and the detector's Imager Pixel Spacing (0.139 mm; the Pixel
    Spacing at the patient, 0.12 mm, is not the detector's) scales it: 0.2201 / 0.139 =
    1.583 lp/mm."""
    lin = render_sfr_chart((160, 200), grid=(1, 1), angle_deg=5.0, sigma=0.8, supersampling=4)
    src = _dx_dicom(tmp_path / "dx.dcm", lin, ImagerPixelSpacing=[0.139, 0.139],
                    PixelSpacing=[0.12, 0.12])  # fmt: skip
    before = src.read_bytes()
    out = tmp_path / "sfr.csv"
    res = execute("sfr", image=src, out=out)
    s = res.summary
    assert s["transfer"] == "linear"
    assert s["pixel_pitch_mm"] == {"rows": 0.139, "columns": 0.139,
                                   "source": "the DICOM's imager pixel spacing"}  # fmt: skip
    m50 = [e["channels"]["Y"]["mtf50"] for e in s["edges"]]
    assert len(m50) == 4 and np.allclose(m50, 0.2201, rtol=0.02)
    assert np.allclose(_chart_lp(s["edges"]), np.array(m50) / 0.139, rtol=1e-12)
    assert np.allclose(_chart_lp(s["edges"]), 1.583, rtol=0.02)
    assert "pixel pitch 139 um" in res.text[0]
    with out.open() as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["edge", "channel", "frequency_cy_per_px", "sfr", "frequency_lp_per_mm"]
    f_px, f_mm = np.array([[float(r[2]), float(r[4])] for r in rows[1:]]).T
    assert np.allclose(f_mm, f_px / 0.139)
    assert src.read_bytes() == before
    # decoded as sRGB (asked for), the same values give another MTF50
    srgb = get_workflow("sfr").make_options(transfer="srgb")
    bent = execute("sfr", image=src, out=None, options=srgb).summary
    assert bent["transfer"] == "srgb"
    assert not np.allclose([e["channels"]["Y"]["mtf50"] for e in bent["edges"]], m50,
                           rtol=0.01)  # fmt: skip


def test_sfr_pixel_pitch_sources_and_units(tmp_path: Path) -> None:
    """Pixel Spacing where the Imager Pixel Spacing is absent; --pixel-pitch over either, in
    um by default; a pitch that differs between rows and columns is taken across each edge
    (between columns for a vertical edge); no pitch, no lp/mm."""
    lin = render_slanted_edge((96, 64), angle_deg=4.0, sigma=0.8)
    ref = float(slanted_edge_sfr(lin).mtf50[0])
    wf = get_workflow("sfr")
    ps = _dx_dicom(tmp_path / "ps.dcm", lin, PixelSpacing=[0.1, 0.1])
    (e,) = execute("sfr", image=ps, out=None).summary["edges"]
    assert e["channels"]["Y"]["mtf50_lp_per_mm"] == pytest.approx(ref / 0.1, rel=0.01)
    for pitch in ("3.76um", "3.76", "0.00376mm", "3.76 µm"):
        s = execute("sfr", image=ps, out=None, options=wf.make_options(pixel_pitch=pitch)).summary
        assert s["pixel_pitch_mm"]["source"] == "--pixel-pitch"
        lp = s["edges"][0]["channels"]["Y"]["mtf50_lp_per_mm"]
        assert lp == pytest.approx(ref / 0.00376, rel=0.01), pitch
    aniso = _dx_dicom(tmp_path / "aniso.dcm", lin, ImagerPixelSpacing=[0.2, 0.1])
    (e,) = execute("sfr", image=aniso, out=None).summary["edges"]
    assert e["orientation"] == "vertical"
    assert e["channels"]["Y"]["mtf50_lp_per_mm"] == pytest.approx(ref / 0.1, rel=0.01)
    (e,) = execute("sfr", image=_dx_dicom(tmp_path / "h.dcm", lin.T.copy(),
                   ImagerPixelSpacing=[0.2, 0.1]), out=None).summary["edges"]  # fmt: skip
    assert e["orientation"] == "horizontal"
    assert e["channels"]["Y"]["mtf50_lp_per_mm"] == pytest.approx(ref / 0.2, rel=0.01)
    plain = tmp_path / "edge.npy"
    np.save(plain, lin.astype(np.float32))
    s = execute("sfr", image=plain, out=None).summary
    assert "pixel_pitch_mm" not in s and "mtf50_lp_per_mm" not in s["edges"][0]["channels"]


@pytest.mark.parametrize("bad", ["-3um", "0", "abc", "5parsec", "nan", "1e30", "0.01um", "2cm"])
def test_sfr_bad_pixel_pitch_is_one_line(bad: str) -> None:
    with pytest.raises(InvalidInputError, match="--pixel-pitch") as err:
        get_workflow("sfr").make_options(pixel_pitch=bad).check()
    assert "\n" not in str(err.value)


def test_sfr_pixel_pitch_range() -> None:
    """1e30 (um) gave MTF50 0.000 lp/mm without a word; the bounds themselves are taken."""
    with pytest.raises(InvalidInputError, match=r"expected --pixel-pitch from 0.1um to 10mm"):
        get_workflow("sfr").make_options(pixel_pitch="1e30")
    for ok in ("0.1um", "10mm", "139um", "3.76"):
        assert get_workflow("sfr").make_options(pixel_pitch=ok).pitch_mm() is not None


def test_sfr_pixel_pitch_on_the_command_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``imageform sfr EDGE --pixel-pitch 5.5um --json``: lp/mm in the JSON; a bad pitch is
    bad usage (exit 2, one line saying why and where the options are listed), nothing written."""
    import json

    from imageform.cli import main

    lin = render_slanted_edge((96, 64), angle_deg=4.0, sigma=0.8)
    src = tmp_path / "edge.npy"
    np.save(src, lin.astype(np.float32))
    assert main(["sfr", str(src), "--pixel-pitch", "5.5um", "--json"]) == 0
    m50 = json.loads(capsys.readouterr().out)["edges"][0]["channels"]["Y"]
    assert m50["mtf50_lp_per_mm"] == pytest.approx(m50["mtf50"] / 0.0055)
    out = tmp_path / "sfr.csv"
    assert main(["sfr", str(src), "--pixel-pitch", "-1", "-o", str(out)]) == 2  # bad usage
    err = capsys.readouterr().err
    assert err.strip().splitlines() == [
        "imageform sfr: error: expected --pixel-pitch > 0, got '-1' (see 'imageform sfr --help')"
    ]
    assert not out.exists()


def test_sfr_auto_takes_a_detectors_16_bit_grey_tiff_as_linear(tmp_path: Path) -> None:
    """A 16-bit grey TIFF that declares no colour space (an X-ray, neutron or microscope
    camera's; sfrmat3 takes such input as linear) is measured as linear values, with a note;
    the same edge as a 16-bit PNG and an 8-bit grey TIFF stay photographs (sRGB)."""
    import tifffile

    from imageform.color import linear_to_srgb
    from imageform.io import image_color_space, write_image

    lin = render_slanted_edge((96, 64), angle_deg=4.0, sigma=0.8)
    ref = float(slanted_edge_sfr(lin).mtf50[0])
    raw = tmp_path / "detector.tif"
    tifffile.imwrite(raw, np.round(lin * 60000).astype(np.uint16))
    assert image_color_space(raw).source == "none"
    s = execute("sfr", image=raw, out=None).summary
    assert s["transfer"] == "linear"
    assert s["edges"][0]["channels"]["Y"]["mtf50"] == pytest.approx(ref, rel=0.01)
    forced = get_workflow("sfr").make_options(transfer="srgb")
    assert execute("sfr", image=raw, out=None, options=forced).summary["transfer"] == "srgb"
    png = tmp_path / "developed.png"
    write_image(png, np.round(np.asarray(linear_to_srgb(lin)) * 65535).astype(np.uint16))
    s = execute("sfr", image=png, out=None).summary
    assert s["transfer"] == "srgb"  # a PNG stays a photograph (imageform's declare nothing)
    assert s["edges"][0]["channels"]["Y"]["mtf50"] == pytest.approx(ref, rel=0.01)
    eight = tmp_path / "grey8.tif"
    tifffile.imwrite(eight, np.round(np.asarray(linear_to_srgb(lin)) * 255).astype(np.uint8))
    assert execute("sfr", image=eight, out=None).summary["transfer"] == "srgb"


def test_sfr_says_when_it_takes_a_tiff_as_linear(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import tifffile

    from imageform.cli import main

    raw = tmp_path / "detector.tif"
    lin = render_slanted_edge((96, 64), angle_deg=4.0, sigma=0.8)
    tifffile.imwrite(raw, np.round(lin * 60000).astype(np.uint16))
    assert main(["sfr", str(raw)]) == 0
    err = capsys.readouterr().err
    assert "detector.tif is a 16-bit grey TIFF that declares no colour space" in err
    assert main(["sfr", str(raw), "--transfer", "linear"]) == 0
    assert "declares no colour space" not in capsys.readouterr().err
