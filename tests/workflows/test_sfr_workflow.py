"""``imageform sfr`` through the workflow layer (execute), on synthetic edges and charts."""

from __future__ import annotations

import csv
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
