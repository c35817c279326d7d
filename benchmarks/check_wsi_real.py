"""Real whole-slide and pyramidal microscopy files through imageform: info, chunked, tissue mask.

For each file of a folder (Aperio SVS, Hamamatsu NDPI, generic tiled and pyramidal TIFF,
OME-TIFF, DICOM slide microscopy, QPTIFF, ...), in a fresh process each:

- ``imageform info FILE --json``: level 0's size against OpenSlide's (or tifffile's series 0,
  or pydicom's total pixel matrix, else rows/columns), and whether it reports the pyramid
  levels, the pixel size in µm and the scanner's format where OpenSlide
  (``openslide.mpp-x``, ``openslide.vendor``) knows them. A DICOM slide's levels are
  OpenSlide's levels of its series from this file's size down (OpenSlide opens the series;
  imageform takes the file given as level 0), its pixel size its own Pixel Spacing's, and
  a THUMBNAIL, LABEL or OVERVIEW file has no OpenSlide reference (OpenSlide reads its
  series' VOLUME level in its place);
- ``imageform chunked convert FILE -o OUT.tif --from srgb --to srgb --compression none``:
  the output is a TIFF tifffile reads, with the input's stored levels (tifffile's; OpenSlide
  adds levels of its own to NDPI, from JPEG's scaled decoding), the input's pixel size
  (``imageform.io.pixel_size_um`` of the output against OpenSlide's MPP), and level 0 equal
  to the input read by tifffile (exactly) and by OpenSlide / tiffslide (JPEG decoders may
  differ by a code or two: mean |difference| at most 1 code, 99.9th percentile at most 8);
  a DICOM slide's level 0 equal to pydicom's frames put together here (exactly:
  TILED_FULL row by row, else at each frame's plane position) and within those codes of
  OpenSlide's;
- ``imageform chunked stain-normalize FILE -o OUT.tif --target TARGET``: output valid,
  levels and pixel size as for convert; time per megapixel;
- ``imageform stain-normalize FILE -o OUT.png --target TARGET`` (in memory);
- ``imageform.analysis.tissue_mask`` on the smallest pyramid level as
  ``imageform.batch.open_lazy(path, level=-1)`` reads it (tifffile's smallest level's size),
  told that level's pixel size (**missing** where imageform had no way to read a level).

A step is **crash** when the command printed a traceback or an "unexpected" error; **wrong**
when it ran and a check above failed, or refused an RGB TIFF or RGB DICOM slide that
tifffile, pydicom (put together), OpenSlide or tiffslide decodes (a DICOM slide in chunked
counted as **refused** before the chunked commands took DICOM, 2026-11-30j); **slow** when
it took over 10 s and under 0.5 Mpx/s on 1 Mpx or more; a one-line refusal of what the
file holds (not RGB, transparent, too little tissue for Macenko) or of a file no peer
decodes is **refused**.

Data (split by repository before any run; the held-out files' SHA-256 are in the results):
2026-11-30k (DICOM slides): tuning on the 11 DICOM files of the 2026-11-30j sweep, all
seen (ImagingDataCommons/highdicom 49728738, MIT; Dana-Farber-AIOS/pathml fa49ffb6,
GPL-2.0; libvips/libvips 29fd1202, LGPL-2.1; openslide/openslide-python c63ac05b, LGPL-2.1;
Booritas/slideio-tutorial 67cb126e, BSD-3-Clause); held-out: the 12 files of one 12-level
DICOM pyramid of OpenSlide's CMU-1-Small-Region (Google's WSI-to-DICOM converter) in
jcupitt/dicom-wsi-sample (9926a34d), which nobody here had used. 2026-11-30j: tuning from
openslide-python, slideio-tutorial and girder/large_image (ebff6109, Apache-2.0), held-out
from pathml, highdicom and libvips. The files stay outside the repository.

Usage::

    PYTHONPATH=src python benchmarks/check_wsi_real.py /tmp/wsih/tune --target \
        tests/data/stain/torchstain_target_crop.png [--out results.md] [--title TEXT] \
        [--src OTHER_CHECKOUT/src]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
ENV = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "OPENBLAS_NUM_THREADS": "1"}
#: The imageform whose commands run (``--src``: another checkout's, for a before/after);
#: the checks always use this one's readers.
CLI_ENV = dict(ENV)


def _cli(*args: str, timeout: float = 600) -> tuple[int, str, str, float]:
    t0 = time.perf_counter()
    p = subprocess.run(
        [sys.executable, "-m", "imageform", *args],
        capture_output=True,
        text=True,
        env=CLI_ENV,
        timeout=timeout,
    )
    return p.returncode, p.stdout, p.stderr, time.perf_counter() - t0


#: The tissue mask at the smallest level, in a process of the imageform under test.
_MASK = """
import json, sys
import numpy as np
from imageform.analysis import tissue_mask
from imageform.batch.chunked import open_lazy
from imageform.errors import ImageformError
try:
    small = np.asarray(open_lazy(sys.argv[1], level=-1).compute())
except ImageformError as exc:
    print(f"imageform: error: {exc}", file=sys.stderr)
    sys.exit(1)
mpp = json.loads(sys.argv[2])
um = None if mpp is None else float(np.mean(mpp)) * int(sys.argv[3]) / small.shape[1]
m = np.asarray(tissue_mask(small[..., :3], pixel_size_um=um))
print(json.dumps({"shape": list(small.shape), "frac": float(m.mean())}))
"""


def _py(code: str, *args: str) -> tuple[int, str, str, float]:
    t0 = time.perf_counter()
    p = subprocess.run(
        [sys.executable, "-c", code, *args], capture_output=True, text=True, env=CLI_ENV,
        timeout=600,
    )  # fmt: skip
    return p.returncode, p.stdout, p.stderr, time.perf_counter() - t0


def _failed(rc: int, err: str) -> str | None:
    """'crash' for a traceback or an unexpected error, else None (a one-line refusal or ok)."""
    if "Traceback" in err or "unexpected" in err or rc not in (0, 1, 2):
        return "crash"
    return None


#: Refusals about the content (not a stained slide, transparent pixels), not the file.
_CONTENT = ("Macenko", "tissue", "transparent pixels", "expected an RGB image")


def _refusal(ref: dict[str, Any], err: str) -> str:
    """'wrong' for a one-line refusal of an RGB TIFF a peer reads, else 'refused'.

    A refusal of what the file holds (too little tissue, transparency, not RGB) or of a file no
    peer decodes is 'refused'; an RGB DICOM slide (a total pixel matrix) that pydicom or
    OpenSlide decodes counts as an RGB TIFF does (the chunked commands take DICOM slides).
    """
    if any(c in err for c in _CONTENT) or not ref.get("readable"):
        return "refused"
    peer_read = ref.get("tiff_rgb") is not None or ref.get("dicom_total") is not None
    return "wrong" if ref["rgb"] and peer_read else "refused"


def _slow(sec: float, mpx: float) -> bool:
    """Over 10 s and under 0.5 Mpx/s, for an image of 1 Mpx or more (a smaller one's time is
    the command's start-up)."""
    return mpx >= 1 and sec > 10 and mpx / sec < 0.5


def _first(err: str) -> str:
    lines = [ln for ln in err.strip().splitlines() if ln.strip()]
    return (lines[-1] if lines else "")[:150]


def _peer(path: Path) -> dict[str, Any]:
    """What OpenSlide, tifffile and pydicom say of ``path`` (the references)."""
    ref: dict[str, Any] = {"vendor": None, "levels": None, "mpp": None, "rgb": False,
                           "tag_mpp": None}  # fmt: skip
    try:
        import openslide

        vendor = openslide.OpenSlide.detect_format(str(path))
        if vendor is not None:
            with openslide.open_slide(str(path)) as s:
                ref["vendor"] = vendor
                ref["levels"] = [(h, w) for w, h in s.level_dimensions]
                mx, my = s.properties.get("openslide.mpp-x"), s.properties.get("openslide.mpp-y")
                if mx and my:
                    ref["mpp"] = (float(mx), float(my))
                ref["openslide"] = True
                if vendor == "generic-tiff":  # resolution tags: 72 dpi from photo software
                    ref["tag_mpp"], ref["mpp"] = ref["mpp"], None
    except Exception as exc:
        ref["openslide_error"] = str(exc)[:80]
    try:
        import tifffile

        with tifffile.TiffFile(path) as tf:
            s0 = tf.series[0]
            ref["tiff_shape"] = tuple(int(v) for v in s0.shape)
            ref["tiff_levels"] = [
                (int(dict(zip(s0.axes, lv.shape, strict=True)).get("Y", 0)),
                 int(dict(zip(s0.axes, lv.shape, strict=True)).get("X", 0)))
                for lv in s0.levels
            ]  # fmt: skip
            ref["tiff_rgb"] = len(s0.shape) == 3 and s0.shape[-1] == 3 and s0.axes[-1] == "S"
            ref["levels"] = ref["tiff_levels"]  # the stored levels (OpenSlide adds JPEG's)
            ref["rgb"] = ref["tiff_rgb"]
    except Exception as exc:
        ref["tiff_error"] = str(exc)[:80]
    if "tiff_shape" not in ref:
        try:
            import pydicom

            ds = pydicom.dcmread(path, stop_before_pixels=True)
            ref["dicom_size"] = (int(ds.Rows), int(ds.Columns))
            total = (int(getattr(ds, "TotalPixelMatrixRows", 0) or 0),
                     int(getattr(ds, "TotalPixelMatrixColumns", 0) or 0))  # fmt: skip
            ref["dicom_total"] = total if all(total) else None
            ref["dicom_sop"] = str(ds.SOPClassUID.name)
            ref["rgb"] = int(getattr(ds, "SamplesPerPixel", 1)) == 3
            kind = [str(v).upper() for v in (ds.get("ImageType", None) or [])]
            if len(kind) > 2 and kind[2] != "VOLUME":
                # a thumbnail, label or overview: OpenSlide reads its series' VOLUME levels
                # (another file) in its place, so it is no reference for this one
                ref["openslide"] = False
            os_levels = ref["levels"] if ref.get("openslide") else None
            ref["levels"] = [total if all(total) else ref["dicom_size"]]
            if os_levels and ref["levels"][0] in os_levels:
                # OpenSlide opens the whole series (its level 0 the largest file); this file
                # is imageform's level 0, the series' smaller files its next levels
                k = os_levels.index(ref["levels"][0])
                ref["os_level"], ref["levels"] = k, os_levels[k:]
            ref["mpp"] = _dicom_mpp(ds)  # this file's own Pixel Spacing
        except Exception as exc:
            ref["dicom_error"] = str(exc)[:80]
    try:
        ref["readable"] = bool(ref["levels"]) and bool(_level0(path, ref))
    except Exception:
        ref["readable"] = False
    return ref


def _dicom_mpp(ds: Any) -> tuple[float, float] | None:
    """A slide's pixel size in µm (x, y) from its Pixel Spacing (mm between rows, columns)."""
    try:
        groups = ds.SharedFunctionalGroupsSequence[0]
        rows, cols = (float(v) for v in groups.PixelMeasuresSequence[0].PixelSpacing)
    except Exception:
        return None
    return (1000 * cols, 1000 * rows) if rows > 0 and cols > 0 else None


def _dicom_matrix(path: Path) -> np.ndarray | None:
    """A slide's total pixel matrix put together here from pydicom's frames (the reference).

    TILED_FULL frames row by row; with Per-frame Functional Groups, each frame at its Plane
    Position (Slide) (1-based); gaps white (RGB). None for a file that is no tiled slide.
    """
    import pydicom
    from pydicom.pixels import pixel_array

    ds = pydicom.dcmread(path)
    if str(ds.get("Modality", "")) != "SM" or int(ds.get("NumberOfFrames", 1) or 1) < 2:
        return None
    total_h, total_w = int(ds.TotalPixelMatrixRows), int(ds.TotalPixelMatrixColumns)
    th, tw = int(ds.Rows), int(ds.Columns)
    frames = np.asarray(pixel_array(ds))
    out = np.full((total_h + th, total_w + tw, *frames.shape[3:]), 255, frames.dtype)
    if str(ds.get("DimensionOrganizationType", "")) == "TILED_FULL":
        across = -(-total_w // tw)
        spots = [((k // across) * th, (k % across) * tw) for k in range(len(frames))]
    else:
        spots = []
        for item in ds.PerFrameFunctionalGroupsSequence:
            pos = item.PlanePositionSlideSequence[0]
            spots.append((int(pos.RowPositionInTotalImagePixelMatrix) - 1,
                          int(pos.ColumnPositionInTotalImagePixelMatrix) - 1))  # fmt: skip
    for f, (r, c) in zip(frames, spots, strict=True):
        out[r : r + th, c : c + tw] = f
    return out[:total_h, :total_w]


def _level0(path: Path, ref: dict[str, Any]) -> dict[str, np.ndarray]:
    """Level 0 (at most a 2048 x 2048 corner) as tifffile, OpenSlide and tiffslide read it.

    A DICOM slide: as OpenSlide reads this file's level of its series, and as pydicom's
    frames put together (:func:`_dicom_matrix`).
    """
    out: dict[str, np.ndarray] = {}
    h, w = ref["levels"][0] if ref["levels"] else (0, 0)
    h, w = min(h, 2048), min(w, 2048)
    if "dicom_size" in ref:
        try:
            m = _dicom_matrix(path)
            if m is not None:
                out["pydicom"] = m[:h, :w]
        except Exception:
            pass
    try:
        import tifffile

        with tifffile.TiffFile(path) as tf:
            out["tifffile"] = tf.series[0].levels[0].asarray()[:h, :w]
    except Exception:
        pass
    if ref.get("openslide"):
        import openslide

        try:
            with openslide.open_slide(str(path)) as s:
                k = int(ref.get("os_level", 0))
                out["openslide"] = np.asarray(s.read_region((0, 0), k, (w, h)))[..., :3]
        except openslide.OpenSlideError:
            pass
    try:
        import tiffslide

        with tiffslide.TiffSlide(str(path)) as s:
            a = np.asarray(s.read_region((0, 0), 0, (w, h)))
            out["tiffslide"] = a[..., :3] if a.ndim == 3 else a
    except Exception:
        pass
    return out


def _compare(mine: np.ndarray, theirs: np.ndarray, exact: bool) -> str | None:
    """None when equal (``exact``) or within a JPEG decoder's codes; else what differs."""
    if mine.shape != theirs.shape:
        return f"shape {mine.shape} vs {theirs.shape}"
    d = np.abs(mine.astype(np.int32) - theirs.astype(np.int32))
    if exact and d.max() == 0:
        return None
    if not exact and d.mean() <= 1.0 and np.percentile(d, 99.9) <= 8:
        return None
    return f"mean |d| {d.mean():.2f}, max {d.max()}"


def _out_check(out: Path, ref: dict[str, Any]) -> tuple[list[str], Any]:
    """Problems of a chunked output: unreadable, levels, pixel size. And its level 0."""
    import tifffile

    from imageform.io import pixel_size_um

    problems: list[str] = []
    try:
        with tifffile.TiffFile(out) as tf:
            levels = [tuple(int(v) for v in lv.shape[:2]) for lv in tf.series[0].levels]
            a0 = tf.series[0].levels[0].asarray()
    except Exception as exc:
        return [f"output unreadable: {str(exc)[:60]}"], None
    want = [tuple(v) for v in ref["levels"]] if ref["levels"] else None
    if want and levels != want:
        problems.append(f"levels {len(levels)} {levels[:3]} vs {len(want)} {want[:3]}")
    if ref.get("tag_mpp") is not None:  # the resolution tags carried, as OpenSlide reads them
        import openslide

        with openslide.open_slide(str(out)) as s:
            mx = s.properties.get("openslide.mpp-x")
        if mx is None or not np.isclose(float(mx), ref["tag_mpp"][0], rtol=1e-4):
            problems.append(f"resolution {mx} um vs {ref['tag_mpp'][0]}")
    if ref["mpp"] is not None:
        got = pixel_size_um(out)
        if got is None or not np.allclose(got, ref["mpp"], rtol=1e-4):
            problems.append(f"pixel size {got} vs {ref['mpp']}")
    return problems, a0


def sweep_one(path: Path, target: Path, work: Path) -> dict[str, Any]:
    """Run every step on one file; return its row."""

    ref = _peer(path)
    row: dict[str, Any] = {"file": path.name, "ref": ref, "steps": {}}
    steps = row["steps"]
    h0w0 = ref["levels"][0] if ref["levels"] else None
    mpx = h0w0[0] * h0w0[1] / 1e6 if h0w0 else 0.0
    row["size"] = f"{h0w0[1]} x {h0w0[0]}" if h0w0 else "-"
    row["levels0_w"] = h0w0[1] if h0w0 else 0
    row["n_levels"] = len(ref["levels"]) if ref["levels"] else 0
    row["vendor"] = ref["vendor"] or (
        "dicom" if "dicom_size" in ref else "tiff" if "tiff_shape" in ref else "unknown"
    )

    # info
    rc, out, err, _ = _cli("info", str(path), "--json")
    st = _failed(rc, err)
    if st is None and rc != 0:
        st, note = _refusal(ref, err), _first(err)
    elif st is None:
        info = json.loads(out)
        note_parts = []
        got = (info.get("height"), info.get("width"))
        if info.get("levels"):
            got = (info["levels"][0][1], info["levels"][0][0])
        if h0w0 and tuple(got) != tuple(h0w0):
            note_parts.append(f"size {got[1]} x {got[0]} vs {h0w0[1]} x {h0w0[0]}")
        if ref["levels"] and len(ref["levels"]) > 1 and not info.get("levels"):
            note_parts.append("no levels")
        if ref["mpp"] is not None and not info.get("pixel_size_um"):
            note_parts.append("no pixel size")
        if ref["vendor"] not in (None, "generic-tiff") and not info.get("vendor"):
            note_parts.append("no vendor")
        st = "wrong" if note_parts else "ok"
        note = "; ".join(note_parts) or (
            f"{len(info.get('levels') or [1])} level(s), {info.get('pixel_size_um')} um, "
            f"{info.get('vendor')}"
        )
    else:
        note = _first(err)
    steps["info"] = (st, note)

    # chunked convert (identity) and level 0 values
    conv = work / f"{path.stem}.conv.tif"
    rc, out, err, sec = _cli(
        "chunked", "convert", str(path), "-o", str(conv), "--from", "srgb", "--to", "srgb",
        "--compression", "none", "--chunk", "512", "--force", "--json",
    )  # fmt: skip
    st = _failed(rc, err)
    if st is None and rc != 0:
        st, note = _refusal(ref, err), _first(err)
    elif st is None:
        problems, a0 = _out_check(conv, ref)
        if a0 is not None:
            for name, theirs in _level0(path, ref).items():
                h, w = theirs.shape[:2]
                diff = _compare(a0[:h, :w], theirs, exact=name in ("tifffile", "pydicom"))
                if diff is not None:
                    problems.append(f"level 0 vs {name}: {diff}")
        st = "wrong" if problems else ("slow" if _slow(sec, mpx) else "ok")
        note = "; ".join(problems) or f"{sec:.1f} s"
    else:
        note = _first(err)
    steps["chunked convert"] = (st, note)

    # chunked stain-normalize
    sn = work / f"{path.stem}.sn.tif"
    rc, out, err, sec = _cli(
        "chunked", "stain-normalize", str(path), "-o", str(sn), "--target", str(target),
        "--chunk", "512", "--force", "--json",
    )  # fmt: skip
    st = _failed(rc, err)
    if st is None and rc != 0:
        st, note = _refusal(ref, err), _first(err)
    elif st is None:
        problems, _ = _out_check(sn, ref)
        st = "wrong" if problems else ("slow" if _slow(sec, mpx) else "ok")
        note = "; ".join(problems) or f"{sec:.1f} s, {mpx / sec:.2f} Mpx/s"
    else:
        note = _first(err)
    steps["chunked stain-normalize"] = (st, note)

    # in-memory stain-normalize
    png = work / f"{path.stem}.sn.png"
    rc, out, err, sec = _cli(
        "stain-normalize", str(path), "-o", str(png), "--target", str(target), "--force"
    )
    st = _failed(rc, err)
    if st is None and rc != 0:
        st, note = (_refusal(ref, err) if mpx <= 100 else "refused"), _first(err)
    elif st is None:
        st, note = ("slow" if _slow(sec, mpx) else "ok"), f"{sec:.1f} s"
    else:
        note = _first(err)
    steps["stain-normalize"] = (st, note)

    # tissue mask at the smallest level, read by imageform (open_lazy(level=-1))
    rc, out, err, sec = _py(_MASK, str(path), json.dumps(ref["mpp"]), str(row["levels0_w"]))
    st = _failed(rc, err)
    if "unexpected keyword argument 'level'" in err:
        st, note = "missing", "imageform reads level 0 only"
    elif st is None and rc != 0:
        st, note = _refusal(ref, err), _first(err)
    elif st is None:
        got = json.loads(out.strip().splitlines()[-1])
        want = ref["levels"][-1] if ref["levels"] else None
        st = "ok" if want is None or tuple(got["shape"][:2]) == tuple(want) else "wrong"
        note = f"level {got['shape'][1]} x {got['shape'][0]}, tissue {100 * got['frac']:.1f} %"
        if st == "wrong":
            note += f" (tifffile's smallest: {want[1]} x {want[0]})"
    else:
        note = _first(err)
    steps["tissue mask"] = (st, note)
    return row


def _compose(sums: Path, tables: list[Path], findings: Path | None = None) -> str:
    """The results file: what ran, the held-out files' SHA-256, the runs' tables.

    ``findings``: a text of what the runs showed, printed after the summary.
    """
    import platform

    import openslide
    import tifffile
    import tiffslide

    head = [
        "# Real whole-slide and pyramidal files: info, chunked, stain normalisation, tissue mask",
        "",
        f"2026-11-30 · {platform.machine()} · Python {platform.python_version()} · tifffile "
        f"{tifffile.__version__} · OpenSlide {openslide.__library_version__} "
        f"(openslide-python {openslide.__version__}) · tiffslide {tiffslide.__version__} · "
        "2 shared cores",
        "",
        "\n\n".join(__doc__.split("\n\n")[1:5]),
        "",
        "Held-out files (frozen before any run; run once, at the end):",
        "",
        "```text",
        sums.read_text().strip(),
        "```",
        "",
    ]
    summary = ["| run | steps |", "|---|---|"]
    for t in tables:
        lines = t.read_text().splitlines()
        steps = next((ln for ln in lines if ln.startswith("Steps: ")), "Steps: -")
        summary.append(f"| {lines[0].lstrip('# ')} | {steps[len('Steps: ') :]} |")
    head += ["Summary (steps of 5 per file: crash / wrong / slow / missing / refused / ok):", ""]
    head += [*summary, ""]
    if findings is not None:
        head += [findings.read_text().strip(), ""]
    body = [t.read_text().strip() + "\n" for t in tables]
    return "\n".join(head) + "\n" + "\n".join(body)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", type=Path)
    ap.add_argument("--target", type=Path, required=True)
    ap.add_argument("--out", type=Path)
    ap.add_argument("--title", default="")
    ap.add_argument("--one", help="run one file, print its row as JSON (internal)")
    ap.add_argument("--src", type=Path, help="the imageform source folder whose commands run")
    ap.add_argument("--findings", type=Path, help="--compose: what the runs showed (Markdown)")
    ap.add_argument(
        "--compose",
        nargs="+",
        type=Path,
        help="print the results file: a header, the held-out list (SHA256SUMS file first), "
        "then the tables these runs printed",
    )
    args = ap.parse_args()
    if args.compose:
        print(_compose(args.compose[0], args.compose[1:], args.findings))
        return
    if args.src:
        CLI_ENV["PYTHONPATH"] = str(args.src.resolve())
    if args.one:
        with tempfile.TemporaryDirectory() as work:
            row = sweep_one(Path(args.one), args.target, Path(work))
        print(json.dumps(row, default=str))
        return
    files = sorted(p for p in args.folder.iterdir() if p.is_file())
    rows = []
    for p in files:
        r = subprocess.run(
            [sys.executable, __file__, str(args.folder), "--target", str(args.target),
             "--one", str(p), *(["--src", str(args.src)] if args.src else [])],
            capture_output=True, text=True, env=ENV, timeout=3600,
        )  # fmt: skip
        if r.returncode != 0:
            rows.append({"file": p.name, "size": "-", "n_levels": 0, "vendor": "-",
                         "steps": {"sweep": ("crash", _first(r.stderr))}})  # fmt: skip
        else:
            rows.append(json.loads(r.stdout.strip().splitlines()[-1]))
        print(p.name, {k: v[0] for k, v in rows[-1]["steps"].items()}, file=sys.stderr)
    names = ["info", "chunked convert", "chunked stain-normalize", "stain-normalize",
             "tissue mask"]  # fmt: skip
    lines = [f"### {args.title or args.folder}", ""]
    lines.append("| file | format | level 0 | levels | " + " | ".join(names) + " |")
    lines.append("|---|---|---|---|" + "---|" * len(names))
    notes = []
    for r in rows:
        cells = []
        for n in names:
            st, note = r["steps"].get(n, r["steps"].get("sweep", ("-", "")))
            cells.append(st)
            if st not in ("ok", "-"):
                notes.append(f"- {r['file']}, {n}: **{st}**: {note}")
        lines.append(
            f"| {r['file']} | {r['vendor']} | {r['size']} | {r['n_levels']} | "
            + " | ".join(cells)
            + " |"
        )
    count: dict[str, int] = {}
    for r in rows:
        for n in names:
            st = r["steps"].get(n, r["steps"].get("sweep", ("-", "")))[0]
            count[st] = count.get(st, 0) + 1
    lines += ["", "Steps: " + ", ".join(f"{k} {v}" for k, v in sorted(count.items())), ""]
    lines += notes
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out:
        args.out.write_text(text)


if __name__ == "__main__":
    main()
