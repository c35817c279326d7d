"""Slanted-edge e-SFR on real images against a port of Burns's ``sfrmat3``: edges found, MTF50.

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_sfr_real.py IMAGE_DIR \\
        [--out benchmarks/results/sfr-real-2026-11-29b.md] [--large s3_ISO_DSC_300_mono.jpg]

``IMAGE_DIR`` holds real photographs or crops of slanted edges (PNG, JPEG, TIFF, BMP; 8 or 16
bits, grey or RGB). The images of ``benchmarks/results/sfr-real-2026-11-29.md`` are not in
the repository; they came from public repositories:

- pringithub/sfrmat3 (Peter Burns's ``sfrmat3`` v2.0 distribution, BSD licence for the
  MATLAB code) ``data/``: ``ISO_DSC_300a.jpg`` and ``ISO_DSC_300_mono.jpg`` (a digital camera's
  photograph of a camera SFR/OECF chart, a dark square turned 5 deg on a grey surround, JPEG,
  1218 x 1164), ``h_edge.tif``, ``v_edge.tif``, ``h_edge_mono.tif``, ``v_edge_mono.tif``
  (300 x 125 edge crops);
- t-kuha/sfrmat5 (BSD-3, Burns's ``sfrmat5`` example images) ``Example_Images/``:
  ``Test_edge1.tif``, ``Test_edge1_mono.tif`` (343 x 124 edge crops) and ``ISO 12233-2023
  chart.jpg`` (the ISO 12233:2023 e-SFR chart as a file, 2500 x 1686, JPEG);
- JorgeGIlG/MTF_Estimator (GPL-3, data only read) ``data/baotou_CALVAL_..._MTF_12196_7333.tif``
  (a satellite image of the Baotou calibration target, 16-bit, 101 x 101).

Each image is decoded from sRGB to linear (as ``imageform sfr`` does by default) and its
edges found by :func:`imageform.analysis.find_slanted_edges`. Each found ROI is measured by
imageform (``slanted_edge_sfr``) and by :func:`sfrmat3`, a NumPy re-implementation (for this
check only) of ``sfrmat3``'s steps with its defaults (4x binning along the rows, the ``[0.5,
-0.5]`` centroid derivative, two-pass Hamming-windowed centroids, a line fit, the rows cut
to whole phase cycles, ``cos(atan(slope))`` frequency scaling, the ``[0.5, 0, -0.5]`` LSF
derivative and its ``fir2fix`` correction, a centred Hamming window, MTF50 by linear
interpolation on the DFT grid). Columns: the luminance MTF50 of both (cycles/pixel) and their
ratio, the largest SFR difference up to Nyquist, the angles, and imageform's MTF50 on the
image transposed (the edge turned 90 deg: the same edge) and on the image JPEG-compressed
again (quality 50, Pillow; both methods on the same pixels). Each image is also searched
inverted (its largest value minus the linear image: light squares on a dark surround) and
the ROIs found there compared with the upright image's. ``--large NAME`` times
``find_slanted_edges`` (median of 3 after one run) on the image ``NAME`` enlarged 3x
(bilinear; ``s3_ISO_DSC_300_mono.jpg`` gives 3654 x 3492, 12.8 megapixels).
"""

from __future__ import annotations

import argparse
import io
import math
import os
import time
from pathlib import Path

import numpy as np

from benchmarks._common import header, markdown_table

SUFFIXES = {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp"}


# --- sfrmat3, re-implemented (Burns, sfrmat3 v2.0, 2015; MATLAB indices are 1-based) --------


def _mround(x: float) -> int:
    """MATLAB's round: halves away from zero."""
    return math.floor(abs(x) + 0.5) * (1 if x >= 0 else -1)


def _ahamming(n: int, mid: float) -> np.ndarray:
    i = np.arange(1, n + 1, dtype=float)
    wid = max(mid - 1, n - mid)
    return np.asarray(0.54 + 0.46 * np.cos(np.pi * (i - mid) / wid))


def _deriv1(row: np.ndarray, fil: np.ndarray) -> np.ndarray:
    nn, npix = len(fil), len(row)
    full = np.convolve(fil, row)
    b = np.zeros(npix)
    b[nn - 1 : npix] = full[nn - 1 : npix]
    b[nn - 2] = b[nn - 1]
    return b


def _centroid(x: np.ndarray) -> float:
    s = float(x.sum())
    return 0.0 if s < 1e-4 else float((np.arange(1, len(x) + 1) * x).sum() / s)


def _cent(a: np.ndarray, center: int) -> np.ndarray:
    n = len(a)
    b = np.zeros(n)
    d = _mround(center - _mround((n + 1) / 2))
    if d > 0:
        b[: n - d] = a[d:]
    else:
        b[-d:] = a[: n + d]
    return b


def _fir2fix(n: int, m: int) -> np.ndarray:
    c = np.ones(n)
    m -= 1
    for i in range(2, n + 1):
        x = np.pi * i * m / (2 * (n + 1))
        c[i - 1] = min(abs(x / math.sin(x)), 10.0)
    return c


def _project(bb: np.ndarray, slope: float, fac: int) -> np.ndarray:
    nlin, npix = bb.shape
    nn = npix * fac
    offset = _mround(-fac * (nlin - 1) * slope)
    d = abs(offset)
    offset = min(offset, 0)
    cnt = np.zeros(nn + d + 102)
    sm = np.zeros_like(cnt)
    x = np.arange(npix)[None, :]
    y = np.arange(nlin)[:, None]
    ling = np.ceil((x - y * slope) * fac).astype(int) + 1 - offset
    np.add.at(cnt, ling.ravel(), 1.0)
    np.add.at(sm, ling.ravel(), bb.ravel())
    start = 1 + _mround(0.5 * d)
    for i in range(start, start + nn):
        if cnt[i] == 0:
            cnt[i] = cnt[i + 1] if i == 1 else (cnt[i - 1] + cnt[i + 1]) / 2
    return np.asarray(sm[start : start + nn] / cnt[start : start + nn])


def sfrmat3(
    a: np.ndarray, weight: tuple[float, float, float] = (0.213, 0.715, 0.072), nbin: int = 4
) -> tuple[np.ndarray, np.ndarray, float]:
    """Frequencies (cycles/pixel), the luminance (or grey) SFR and the edge angle (deg)."""
    a = np.asarray(a, dtype=float)
    if a.ndim == 3:
        a = (weight[0] * a[:, :, 0] + weight[1] * a[:, :, 1] + weight[2] * a[:, :, 2])[..., None]
    else:
        a = a[:, :, None]
    k = 3
    testv = abs(a[-1 - k, :, 0].mean() - a[k - 1, :, 0].mean())
    testh = abs(a[:, -1 - k, 0].mean() - a[:, k - 1, 0].mean())
    if testv > testh:
        a = np.rot90(a)
    lum = a[:, :, 0]
    nlin, npix = lum.shape
    fil1, fil2 = np.array([0.5, -0.5]), np.array([0.5, 0.0, -0.5])
    if lum[:, 0:5].sum() > lum[:, npix - 6 : npix].sum():
        fil1, fil2 = -fil1, -fil2
    c = np.stack([_deriv1(lum[n], fil1) for n in range(nlin)])
    win1 = _ahamming(npix, (npix + 1) / 2)
    loc = np.array([_centroid(c[n] * win1) - 0.5 for n in range(nlin)])
    fit = np.polyfit(np.arange(nlin), loc, 1)
    loc = np.array(
        [
            _centroid(c[n - 1] * _ahamming(npix, fit[1] + fit[0] * n)) - 0.5
            for n in range(1, nlin + 1)
        ]
    )
    slope = float(np.polyfit(np.arange(nlin), loc, 1)[0])
    nlin1 = _mround(math.floor(nlin * abs(slope)) / abs(slope))
    lum = lum[:nlin1]
    dl = math.cos(math.atan(slope))
    nn = npix * nbin
    nn2 = nn // 2 + 1
    freq = nbin * np.arange(nn) / (dl * nn)
    point = _project(lum, slope, nbin)
    lsf = _deriv1(point, fil2)
    lsf = _cent(lsf, _mround(_centroid(lsf))) * _ahamming(nn, (nn + 1) / 2)
    t = np.abs(np.fft.fft(lsf, nn))
    mtf = t[:nn2] / t[0] * _fir2fix(nn2, 3)
    keep = _mround(nn2 / 2)
    return freq[:keep], mtf[:keep], math.degrees(math.atan(slope))


def crossing(f: np.ndarray, m: np.ndarray, level: float) -> float:
    """``sfrmat3``'s ``findfreq``: the first sample below ``level``, interpolated linearly."""
    below = np.nonzero(m < level)[0]
    if below.size == 0 or below[0] == 0:
        return math.nan
    x = int(below[0]) - 1
    return float(f[x] + (m[x] - level) * (f[x + 1] - f[x]) / (m[x] - m[x + 1]))


# --- the check ---------------------------------------------------------------------------------


def _load(path: Path) -> np.ndarray:
    from imageform.io import read_image

    arr = np.asarray(read_image(path))
    return arr[..., 0] if arr.ndim == 3 and arr.shape[2] == 1 else arr


def _linear(arr: np.ndarray) -> np.ndarray:
    from imageform.color import srgb_to_linear

    if arr.ndim == 3:
        arr = arr[..., :3] if arr.shape[2] >= 3 else arr[..., 0]
    if arr.dtype.kind == "f":
        return arr.astype(np.float64)
    scale = 65535.0 if arr.dtype == np.uint16 else 255.0
    return np.asarray(srgb_to_linear(arr.astype(np.float64) / scale))


def _jpeg(arr: np.ndarray, quality: int) -> np.ndarray:
    from PIL import Image

    a8 = arr if arr.dtype == np.uint8 else np.rint(arr / 257.0).astype(np.uint8)
    buf = io.BytesIO()
    Image.fromarray(a8).save(buf, format="JPEG", quality=quality)
    buf.seek(0)
    return np.asarray(Image.open(buf))


def _pair(
    lin: np.ndarray, roi: tuple[int, int, int, int]
) -> tuple[float, float, float, float, float]:
    """imageform's and sfrmat3's MTF50, the largest SFR gap to Nyquist, the two angles."""
    from imageform.analysis import slanted_edge_sfr

    x, y, w, h = roi
    r = slanted_edge_sfr(lin, roi)
    f3, m3, a3 = sfrmat3(lin[y : y + h, x : x + w])
    sel = r.frequency <= 0.5
    gap = float(np.abs(r.sfr[sel, -1] - np.interp(r.frequency[sel], f3, m3)).max())
    return float(r.mtf50[-1]), crossing(f3, m3, 0.5), gap, r.angle, a3


def _fmt(v: float, nd: int = 4) -> str:
    return "nan" if not math.isfinite(v) else f"{v:.{nd}f}"


def main() -> None:
    from imageform.analysis import find_slanted_edges, slanted_edge_sfr

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("images", type=Path)
    ap.add_argument("--out", type=Path)
    ap.add_argument("--large", help="an image of IMAGE_DIR to time enlarged 3x")
    args = ap.parse_args()
    files = sorted(p for p in args.images.iterdir() if p.suffix.lower() in SUFFIXES)
    found_rows, rows = [], []
    ratios: list[float] = []
    # one-off costs out of the first image's seconds: imports, loading numba's compiled kernels
    find_slanted_edges(np.pad(np.full((40, 40), 0.2), 20, constant_values=0.8))
    t0 = time.perf_counter()
    for path in files:
        raw = _load(path)
        lin = _linear(raw)
        t = time.perf_counter()
        try:
            rois = find_slanted_edges(lin)
            note = ""
        except Exception as e:  # the table reports every failure
            rois, note = [], f"{type(e).__name__}: {e}"
        dt = time.perf_counter() - t
        kind = f"{raw.dtype}, {'RGB' if raw.ndim == 3 else 'grey'}, {raw.shape[1]}x{raw.shape[0]}"
        try:
            inv = find_slanted_edges(lin.max() - lin)
            same = len({r.roi for r in inv} & {r.roi for r in rois})
            inverted = f"{len(inv)} ({same})"
        except Exception as e:
            inverted = f"{type(e).__name__}: {e}"
        found_rows.append([path.name, kind, len(rois), f"{dt:.2f}", inverted, note])
        jp = _linear(_jpeg(raw, 50))
        for roi in rois:
            cells: list[str] = [path.name, ",".join(map(str, roi.roi)), roi.side]
            try:
                m_if, m_s3, gap, a_if, a_s3 = _pair(lin, roi.roi)
                ratios.append(m_if / m_s3)
                x, y, w, h = roi.roi
                tr = lin.transpose(1, 0, 2) if lin.ndim == 3 else lin.T
                m_tr = float(slanted_edge_sfr(tr, (y, x, h, w)).mtf50[-1])
                j_if, j_s3, _g, _a, _b = _pair(jp, roi.roi)
                cells += [
                    _fmt(a_if, 2),
                    _fmt(a_s3, 2),
                    _fmt(m_if),
                    _fmt(m_s3),
                    _fmt(m_if / m_s3, 3),
                    _fmt(gap, 3),
                    _fmt(m_tr),
                    f"{_fmt(j_if)} / {_fmt(j_s3)}",
                ]
            except Exception as e:
                cells += [f"{type(e).__name__}: {e}"] + [""] * 7
            rows.append(cells)
    text = header("Slanted-edge e-SFR on real images: imageform against sfrmat3 (re-implemented)")
    text += (
        f"\nCommand: `OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_sfr_real.py "
        f"IMAGE_DIR` ({len(files)} images; sources in the script's docstring). Total "
        f"{time.perf_counter() - t0:.1f} s on a loaded machine (load average "
        f"{os.getloadavg()[0]:.1f}): the seconds are indicative only.\n\n"
        "## Edges found (find_slanted_edges)\n\n"
    )
    text += markdown_table(
        ("image", "pixels", "edges", "s", "edges inverted (same ROIs)", "error"), found_rows
    )
    text += "\n## Each edge: imageform (IF) and sfrmat3 (S3), luminance, cycles/pixel\n\n"
    text += markdown_table(
        (
            "image",
            "ROI x,y,w,h",
            "side",
            "angle IF",
            "angle S3",
            "MTF50 IF",
            "MTF50 S3",
            "IF/S3",
            "max dSFR <= Nyq",
            "MTF50 IF transposed",
            "MTF50 JPEG q50 IF / S3",
        ),
        rows,
    )
    if ratios:
        r = np.asarray(ratios)
        text += (
            f"\nIF/S3 MTF50 over {r.size} edges: median {np.median(r):.4f}, range "
            f"{r.min():.4f} - {r.max():.4f}.\n"
        )
    if args.large:
        from scipy import ndimage

        big = ndimage.zoom(_linear(_load(args.images / args.large)), 3, order=1)
        found = find_slanted_edges(big)
        times = []
        for _ in range(3):
            t = time.perf_counter()
            find_slanted_edges(big)
            times.append(time.perf_counter() - t)
        text += (
            f"\n## find_slanted_edges on a {big.shape[1]} x {big.shape[0]} photograph "
            f"({big.size / 1e6:.1f} Mpx: {args.large} enlarged 3x, bilinear)\n\n"
            f"{len(found)} edges, median {np.median(times):.2f} s of 3 runs after one "
            f"(load average {os.getloadavg()[0]:.1f}); ROIs "
            + "; ".join(",".join(map(str, r.roi)) for r in found)
            + ".\n"
        )
    print(text)
    if args.out:
        args.out.write_text(text)


if __name__ == "__main__":
    main()
