"""Slanted-edge e-SFR on fresh real images, split into a tuning half and a held-out half.

Run (once per half; the held-out half once, with the final code)::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_sfr_fresh.py DIR \\
        --refs REFS [--overlays OUT_DIR] [--out benchmarks/results/sfr-fresh-2026-11-30e.md]

``DIR`` holds the images of one half (file names as below), ``REFS`` the reference files
(``mitre_oecf.txt``, ``mitre_SFROUT.txt``, ``rayxie_mtf.csv``). None of the images is in the
repository; they were taken from public repositories (``git show COMMIT:PATH``), none of them
used by ``benchmarks/check_sfr_real.py``:

=============================== ============================================= ========== =====
file                            repository, commit, path                      licence    half
=============================== ============================================= ========== =====
mtfm_orientation_example.jpg    peytondmurray/mtfmapper (MTF Mapper, F. van   BSD-3      tune
                                den Bergh) 65ca7e93, doc/figures/
                                orientation_example.jpg: a camera's photograph
                                of MTF Mapper's lens-grid chart, 1024 x 1074,
                                MTF Mapper's own annotations drawn over it
mtfm_perpendicular_target.jpg   same, doc/figures/perpendicular_target.jpg    BSD-3      tune
                                (a photograph of MTF Mapper's square chart)
mtfm_perspective_sample_photo   same, doc/figures/perspective_sample_photo    BSD-3      tune
.jpg                            .jpg (a photograph of the chart, 800 x 530)
mtfm_single_roi_input.jpg       same, doc/figures/single_roi_input.jpg (a     BSD-3      tune
                                camera's crop of one edge, grey, 234 x 400)
bwk_edge_Image5.dcm,            BwKodex/dicomimagetools 193c5d99,             MIT        tune
bwk_edge_Image9.dcm,            tests/test_data/io/Edge-fantom/ImageN.dcm:
bwk_edge_Image10.dcm            an intra-oral X-ray sensor's (Sirona) images
                                of an edge phantom, 12 bits, MONOCHROME1,
                                1200 x 854, 30 um pixels
mitre_Edge_box.tif              Redlnn/SFR_Calculation 84ab9017, Mitre/SFR    BSD (MITRE tune
                                _1.4.2/testcase/Edge_box.tif: MITRE SFR       / ISO Annex
                                1.4.2's test edge (left 400 x 400: the image  A notice)
                                with its ROI drawn; right: a zoomed view, not
                                measured), its output SFROUT.txt and OECF
mitre_mtf66_test.tif            same, Mitre/MTF_6.6/TestCase/test.tif (MITRE  same       tune
                                MTF 6.6's sine/bar target: no slanted edge)
sfrmat2_edge01.tif,             same, sfrmat/sfrmat2/data/edge0N.tif (Burns's same (BSD) tune
sfrmat2_edge03.tif              sfrmat2 v2.1 samples: 64 x 64 grey, 30 x 176
                                RGB edge crops)
niqa_edge20mm_0000.tif,         neutronimaging/ImagingQuality 902c7886,       GPL-3      held
niqa_edge20mm_0003.tif,         data/edges/edge20mm_000N.tif: neutron         (read
niqa_edge20mm_0007.tif          radiographs of a Gd edge square (16-bit, 600  only)
                                x 600, raw: gamma spots, no flat field)
niqa_normalized_edge.tif        same, applications/NIQualityAssessment/       GPL-3      held
                                python/normalized_edge.tif (float crop)
quickmtf_Test.jpg               Lorrytoolcenter/quickMTF 015a85ed, image/     none       held
                                Test.jpg (a phone's photograph of an Imatest  (read
                                SFR chart, 4000 x 3000)                       only)
quickmtf_1.6.png                same, image/1.6.png (a camera frame with a    none       held
                                slanted black rectangle on paper)
asplund_x0552_y1976_F16.png,    carlasplund/SFR_calculation_code 5100bff8,    CC0        held
asplund_x2084_y0616_F2.png,     edge_samples/*.png (74 x 74 edge crops of a
asplund_x2088_y0616_F2_8.png    lens at f/16, f/2, f/2.8)
asplund_televinken.jpg          same, televinken.jpg (a photograph of a       CC0        held
                                puppet: a natural scene, no chart)
rayxie_original_img.bmp         RayXie29/SFR_Calculation d1eefc8b, imgs/      none       held
                                original_img.bmp (a fisheye webcam's photo of
                                the ISO 12233:2000 chart, 640 x 480) and its
                                ref/mtf.csv (that repository's SFR of a hand-
                                cropped ROI on the central bar)
=============================== ============================================= ========== =====

The split was made by repository before anything was run (the images had been looked at as
thumbnails to choose them): tuning = MTF Mapper, BwKodex, Redlnn (11 images); held-out =
ImagingQuality, quickMTF, carlasplund, RayXie29 (11 images). The held-out files, frozen
before the first run (SHA-256)::

    31ca21872c41e88c5138cb9ab09449fb8cf2872726dbf66c0cb3f73c1996eed9  asplund_televinken.jpg
    6993d92033688fe4dbe005e061c9301421498c49659ccca017fb58a5aff99618  asplund_x0552_y1976_F16.png
    c7b9b7175b3c783f9bf354d4c7fff06f3956d9609328297bd4c66335d1020f55  asplund_x2084_y0616_F2.png
    5371003abba19556493a5dfbd90662fc83f9589cd4768a77455e135c7366b302  asplund_x2088_y0616_F2_8.png
    68ca47ccc7d84ceab1a5605d23af3b1a897a5153024c09f53ca01a75a8717746  niqa_edge20mm_0000.tif
    0ab516d83d1dd4627e1350259b90a81c193a61a4eb4b416f656e5627df019d57  niqa_edge20mm_0003.tif
    437868d586ff2a97253acc581df649075ac84600d30dc0b4ac826b72e6743549  niqa_edge20mm_0007.tif
    b7d23e84acf79dde730e9aa4bac198b854e285e44e9f74480d718bfca8986ea7  niqa_normalized_edge.tif
    064dc9d72fb10b4f1e42b2f82a677edfa164426944533985d08c7716862b6aa4  quickmtf_1.6.png
    046510cc649c1e8ea32ed96cb099cd8c9fa179df0230ee5954cfeb09707f336f  quickmtf_Test.jpg
    967b0d946e5766dba3222752f1769cb004abb71e3c6d1d0a4d7861da66da52a4  rayxie_original_img.bmp

Each image is read as ``imageform sfr`` reads it (its ``_edge_image``, ``--transfer auto``:
8- and 16-bit photographs decoded from sRGB, DICOM and float images taken as linear; the
neutron TIFFs are 16-bit and so decoded from sRGB too, as the CLI would unless told
``--transfer linear``), its edges found by :func:`imageform.analysis.find_slanted_edges`
(default 2-10 deg) and each measured by ``slanted_edge_sfr`` and by the ``sfrmat3``
re-implementation of ``benchmarks/check_sfr_real.py`` on the same pixels (luminance). Further
columns: the MTF50 with ``--transfer linear`` (the pixel values as they are), and the ROI's
distance to the image border, and imageform's MTF50 over ``sfrmat3``'s with ``sfrmat3``
given imageform's edge angle (its own fit otherwise: tells a difference in the edge fit from
one in the later steps). ``--overlays`` writes each image with its ROIs drawn (to look
at by eye). Published values: MITRE SFR 1.4.2's SFROUT.txt (its ROI, shrunk by one pixel
inside the box drawn on it, through its OECF, 500 ppi) and RayXie29's ref curve (the ROI
it was cut from is not recorded; the nearest found ROI on the central bar is compared).
"""

from __future__ import annotations

import argparse
import math
import os
import time
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks import check_sfr_real as s3
from benchmarks._common import header, markdown_table
from benchmarks.check_sfr_real import crossing, sfrmat3

SUFFIXES = {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp", ".dcm"}
#: the part of a file that is the image (MITRE's Edge_box.tif: the left panel)
PANELS = {"mitre_Edge_box.tif": (slice(0, 400), slice(0, 400))}
#: MITRE's ROI x, y, w, h inside the box drawn at cols 130-249, rows 66-325; 500 ppi
MITRE_ROI = (131, 67, 118, 258)
MITRE_CY_PER_MM_PER_CY_PER_PX = 500 / 25.4


def _load(path: Path, transfer: str) -> np.ndarray:
    from imageform.workflows.sharpness import SfrOptions, _edge_image

    arr = np.asarray(_edge_image(path, SfrOptions(transfer=transfer))[0])  # type: ignore[arg-type]
    rows, cols = PANELS.get(path.name, (slice(None), slice(None)))
    return np.ascontiguousarray(arr[rows, cols])


def _sfrmat3_at(a: np.ndarray, angle_deg: float) -> float:
    """``sfrmat3``'s luminance MTF50 with its edge angle replaced by ``angle_deg`` (magnitude).

    Tells a difference in the edge fit from one in the later steps: the re-implementation's
    own fit is kept but for its slope, which gets ``angle_deg``'s magnitude and its own sign.
    """
    fit = np.polyfit
    calls = [0]

    def second_fit_slope(x: Any, y: Any, deg: int) -> Any:
        p = fit(x, y, deg)
        calls[0] += 1
        if calls[0] == 2:  # sfrmat3's second (final) line fit
            mid = (len(x) - 1) / 2
            slope = math.copysign(math.tan(math.radians(abs(angle_deg))), p[0])
            p = np.array([slope, p[1] + (p[0] - slope) * mid])
        return p

    s3.np.polyfit = second_fit_slope  # type: ignore[assignment]
    try:
        f, m, _a = sfrmat3(a)
    finally:
        s3.np.polyfit = fit
    return crossing(f, m, 0.5)


def _fmt(v: float, nd: int = 4) -> str:
    return "nan" if not math.isfinite(v) else f"{v:.{nd}f}"


def _border(roi: tuple[int, int, int, int], shape: tuple[int, ...]) -> int:
    x, y, w, h = roi
    return int(min(x, y, shape[1] - x - w, shape[0] - y - h))


def _overlay(lin: np.ndarray, rois: list[Any], out: Path) -> None:
    from PIL import Image, ImageDraw

    g = lin if lin.ndim == 2 else lin.mean(axis=2)
    lo, hi = np.percentile(g, [1, 99])
    v = np.clip((g - lo) / max(hi - lo, 1e-12), 0, 1) ** (1 / 2.2) * 255
    im = Image.fromarray(v.astype(np.uint8)).convert("RGB")
    d = ImageDraw.Draw(im)
    for k, r in enumerate(rois):
        x, y, w, h = r.roi
        d.rectangle((x, y, x + w - 1, y + h - 1), outline=(255, 0, 0))
        d.text((x + 1, y + 1), str(k), fill=(0, 160, 255))
    im.save(out)


def _mitre(images: Path, refs: Path) -> list[str] | None:
    """imageform and sfrmat3 on MITRE's ROI through its OECF, against its SFROUT.txt."""
    from imageform.analysis import slanted_edge_sfr

    path = images / "mitre_Edge_box.tif"
    if not path.exists():
        return None
    oecf = np.loadtxt(refs / "mitre_oecf.txt")  # reflectance, grey level
    grey = _load(path, "linear") * 255.0
    lin = np.interp(grey, oecf[:, 1], oecf[:, 0])
    f_pub, s_pub = [], []
    for line in (refs / "mitre_SFROUT.txt").read_text().splitlines():
        parts = line.split()
        if len(parts) >= 2 and "." in parts[0] and parts[0][0].isdigit():
            try:
                f_pub.append(float(parts[0]) / MITRE_CY_PER_MM_PER_CY_PER_PX)
                s_pub.append(float(parts[1]))
            except ValueError:
                continue
            if len(f_pub) > 1 and f_pub[-1] < f_pub[-2]:  # the ESF table that follows
                f_pub.pop()
                s_pub.pop()
                break
    fp, sp = np.asarray(f_pub), np.asarray(s_pub)
    pub50 = crossing(fp, sp, 0.5)
    x, y, w, h = MITRE_ROI
    r = slanted_edge_sfr(lin, MITRE_ROI)
    f3, m3, _a = sfrmat3(lin[y : y + h, x : x + w])
    sel = r.frequency <= 0.5
    gap = float(np.abs(r.sfr[sel, 0] - np.interp(r.frequency[sel], fp, sp)).max())
    m_if = float(r.mtf50[0])
    return [
        "MITRE SFR 1.4.2, Edge_box.tif (ROI " + ",".join(map(str, MITRE_ROI)) + ", its OECF)",
        _fmt(pub50),
        _fmt(m_if),
        _fmt(crossing(f3, m3, 0.5)),
        _fmt(m_if / pub50, 3),
        _fmt(gap, 3),
    ]


def _rayxie(images: Path, refs: Path, found: dict[str, list[Any]]) -> list[str] | None:
    """imageform on the found ROI nearest RayXie29's crop, against its ref/mtf.csv."""
    from imageform.analysis import slanted_edge_sfr

    name = "rayxie_original_img.bmp"
    if name not in found or not found[name]:
        return None
    ref = np.loadtxt(refs / "rayxie_mtf.csv", delimiter=",")
    # the crop shown in its README (cropping.PNG): about x 296-322, y 129-170
    cx, cy = 309.0, 150.0
    best = min(found[name], key=lambda r: math.hypot(r.center[0] - cx, r.center[1] - cy))
    lin = _load(images / name, "linear")  # their code reads the 8-bit values as they are
    r = slanted_edge_sfr(lin, best.roi)
    return [
        "RayXie29 ref/mtf.csv (its own ROI; found ROI " + ",".join(map(str, best.roi)) + ")",
        _fmt(crossing(ref[:, 0], ref[:, 1], 0.5)),
        _fmt(float(r.mtf50[-1])),
        "",
        _fmt(float(r.mtf50[-1]) / crossing(ref[:, 0], ref[:, 1], 0.5), 3),
        "",
    ]


def main() -> None:
    from imageform.analysis import find_slanted_edges, slanted_edge_sfr

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("images", type=Path)
    ap.add_argument("--refs", type=Path, required=True)
    ap.add_argument("--overlays", type=Path)
    ap.add_argument("--out", type=Path)
    ap.add_argument("--title", default="")
    args = ap.parse_args()
    files = sorted(p for p in args.images.iterdir() if p.suffix.lower() in SUFFIXES)
    if args.overlays:
        args.overlays.mkdir(parents=True, exist_ok=True)
    find_slanted_edges(np.pad(np.full((40, 40), 0.2), 20, constant_values=0.8))  # compile
    found_rows, rows = [], []
    found: dict[str, list[Any]] = {}
    ratios: list[tuple[float, float, float]] = []  # IF/S3, S3's MTF50, IF/S3 at IF's angle
    t0 = time.perf_counter()
    for path in files:
        lin = _load(path, "auto")
        raw = _load(path, "linear")
        t = time.perf_counter()
        try:
            rois = find_slanted_edges(lin)
            note = ""
        except Exception as e:  # the table reports every failure
            rois, note = [], f"{type(e).__name__}: {e}"
        dt = time.perf_counter() - t
        found[path.name] = rois
        kind = f"{'RGB' if lin.ndim == 3 else 'grey'} {lin.shape[1]}x{lin.shape[0]}"
        found_rows.append([path.name, kind, len(rois), f"{dt:.2f}", note])
        if args.overlays:
            _overlay(lin, rois, args.overlays / f"{path.stem}_rois.png")
        for k, roi in enumerate(rois):
            x, y, w, h = roi.roi
            cells: list[str] = [path.name, str(k), ",".join(map(str, roi.roi)), roi.side]
            try:
                r = slanted_edge_sfr(lin, roi.roi)
            except Exception as e:  # imageform refuses an ROI its own finder gave
                rows.append(cells + [f"{type(e).__name__}: {e}"] + [""] * 7)
                continue
            m_if = float(r.mtf50[-1])
            crop = lin[y : y + h, x : x + w]
            try:
                f3, m3, a3 = sfrmat3(crop)
                m_s3 = crossing(f3, m3, 0.5)
                at = m_if / _sfrmat3_at(crop, r.angle)
            except Exception as e:  # the reference re-implementation fails on its own
                a3 = m_s3 = at = math.nan
                s3_note = f"S3: {type(e).__name__}"
            else:
                s3_note = ""
            ratios.append((m_if / m_s3, m_s3, at))
            try:  # the pixel values as they are: the edge may move too little in them
                m_raw = _fmt(float(slanted_edge_sfr(raw, roi.roi).mtf50[-1]))
            except Exception as e:
                m_raw = type(e).__name__
            cells += [
                _fmt(abs(r.angle), 2),
                _fmt(abs(a3), 2),
                _fmt(m_if),
                s3_note or _fmt(m_s3),
                _fmt(m_if / m_s3, 3),
                _fmt(at, 3),
                m_raw,
                str(_border(roi.roi, lin.shape)),
            ]
            rows.append(cells)
    title = "Slanted-edge e-SFR on fresh real images" + (f": {args.title}" if args.title else "")
    text = header(title)
    text += (
        "\nCommand: `OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/"
        f"check_sfr_fresh.py DIR --refs REFS` ({len(files)} images of {args.images.name}; "
        f"sources in the script's docstring). Total {time.perf_counter() - t0:.1f} s on a "
        f"loaded machine (load average {os.getloadavg()[0]:.1f}).\n\n"
        "### Edges found (find_slanted_edges, default 2-10 deg)\n\n"
    )
    text += markdown_table(("image", "pixels", "edges", "s", "error"), found_rows)
    text += "\n### Each edge: imageform (IF) and sfrmat3 (S3), luminance, cycles/pixel\n\n"
    text += markdown_table(
        (
            "image",
            "edge",
            "ROI x,y,w,h",
            "side",
            "angle IF (abs)",
            "angle S3 (abs)",
            "MTF50 IF",
            "MTF50 S3",
            "IF/S3",
            "IF/S3 at IF's angle",
            "MTF50 IF, values as they are",
            "px to border",
        ),
        rows,
    )
    arr = np.asarray(ratios, dtype=np.float64).reshape(-1, 3)
    ok = np.isfinite(arr[:, 0])
    for label, sel in (
        ("every edge where both reach 0.5 below 1 cycle/pixel", ok),
        ("the edges with MTF50 below Nyquist (S3 <= 0.5 cycle/pixel)", ok & (arr[:, 1] <= 0.5)),
    ):
        r, at = arr[sel, 0], arr[sel, 2]
        if r.size:
            text += (
                f"\nIF/S3 MTF50 over {label}: {r.size} of {len(arr)} edges, median "
                f"{np.median(r):.4f}, range {r.min():.4f} - {r.max():.4f}, within 2 %: "
                f"{int((np.abs(r - 1) <= 0.02).sum())}; at IF's angle: median "
                f"{np.nanmedian(at):.4f}, range {np.nanmin(at):.4f} - {np.nanmax(at):.4f}, within "
                f"2 %: {int((np.abs(at - 1) <= 0.02).sum())}.\n"
            )
    pub = (_mitre(args.images, args.refs), _rayxie(args.images, args.refs, found))
    pub_rows = [p for p in pub if p is not None]
    if pub_rows:
        text += "\n### Against published values (cycles/pixel)\n\n"
        text += markdown_table(
            ("reference", "published MTF50", "MTF50 IF", "MTF50 S3", "IF/published",
             "max dSFR <= Nyq"),
            pub_rows,
        )  # fmt: skip
    print(text)
    if args.out:
        args.out.write_text(text)


if __name__ == "__main__":
    main()
