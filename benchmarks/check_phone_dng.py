"""Real DNG (and other raw) files through read_raw and develop: opcodes, previews, speed.

Run::

    PYTHONPATH=src:. python benchmarks/check_phone_dng.py FOLDER [--out results.md]

FOLDER holds the raw files (any of .dng .cr2 .cr3 .crw .nef .rw2 .raf .mrw .iiq .x3f). The
files checked on 2026-11-30 came from public repositories (read from /tmp, not committed):

- ``photoprism_canon_eos_6d.dng``: photoprism/photoprism 382ffa8, assets/examples/
  canon_eos_6d.dng (AGPL-3.0): a lossy DNG Adobe Camera Raw 11.3.1 wrote of a Canon EOS 6D
  raw, 1224 x 816 LinearRaw in 8-bit JPEG tiles, three MapPolynomials in OpcodeList2, a
  1024 x 683 preview Camera Raw rendered.
- ``tinydng_colorchart.dng``: syoyo/tinydng 40a4dde, colorchart.dng (MIT): Magic Lantern's
  DNG of a Canon EOS 550D (Kiss X4), 1734 x 1156 RGGB, no opcode, no preview.
- ``exiv2_IMG_1361.dng``: Exiv2/exiv2 e84cb9d, test/data/IMG_1361.dng (GPL-2.0): an Apple
  iPhone 12 Pro ProRAW DNG pruned to its 64 kB of metadata (the 29 MB of raw data cut).
- ``exiv2_Canon-R6-pruned.CR3``, ``exiv2_exiv2-canon-powershot-s40.crw``,
  ``exiv2_issue_839_poc.rw2``, ``exiv2_issue_857_poc.raf``: the same commit's test/data
  (pruned or damaged on purpose).
- ``exiftool_*``: exiftool/exiftool 38bdbac, t/images/ (Perl Artistic licence or GPL):
  CanonRaw.cr2/.cr3/.crw, DNG.dng, FujiFilm.raf, Minolta.mrw, Nikon.nef, Panasonic.rw2,
  PhaseOne.iiq, Sigma.x3f, SigmaDP2.x3f, metadata test files with the image data cut.
- ``minhtcai_test.dng``: minhtcai/camera e1f1c38, images/test.dng (no licence named): a
  640 x 480 10-bit GBRG DNG of a small camera module, no opcode, no preview.
- ``mde_Issue_247-1..4.nef``: drewnoakes/metadata-extractor-images 4beba64, nef/ (no licence
  named): Nikon files of a metadata-extractor issue, 380 to 470 kB.

No phone DNG carrying GainMap or WarpRectilinear opcodes could be had: every one found
(DJI Phantom 4, LG Nexus 5X, Leica T, Leica X Vario, Pentax Q-S1 in metadata-extractor-images,
Ricoh GR III in immich-app/test-assets, tinydng's pixel3.dng) is over the 4 MiB the
repository snapshots keep.

For each file: the opcodes its raw IFD carries (by list: L1, L2, L3), what ``read_raw``
did with them (applied, decoded with the samples, kept for develop, skipped), whether
``develop`` gives an image (not black: median above 0.01) or the one-line refusal. Against
the file's largest embedded preview (the maker's or converter's own rendering, the DNG's
DefaultCrop of the development taken, both brought to the preview's size): the median
brightness ratio (ours / preview, sRGB-encoded values), the corner / centre ratio of the
linear luminance (the mean of the four corner eighths over the central one; ours first
mapped onto the preview's luminance by their quantiles, which takes out the converter's
tone curve: lens shading left in shows as a ratio below the preview's), with and without
the opcodes, and the displacement
of corner tiles against the preview (phase correlation of 128 px tiles at the four corners,
mean length in preview pixels: lens distortion shows as a displacement that a warp
removes). Time: read_raw + develop (bilinear, camera white balance, sRGB) against rawpy's
``postprocess`` at matched settings (LINEAR demosaicing, camera white balance, no auto
brightness, 16 bits), medians of 5 interleaved runs, and their ratio. Last, for a DNG,
imageform's own reader (tifffile, used without LibRaw or where LibRaw cannot decode)
against LibRaw's mosaic. Then, for speed at a phone's size, a synthetic 12 Mpx DNG with a
Pixel's opcode set (written to a temporary folder): read_raw + develop with and without its
opcodes against LibRaw's postprocess, each in its own worker process, ``--samples`` (9)
interleaved runs of each; ``--against SRC`` times another checkout's ``src`` (main's, say:
``git archive main src | tar -x -C /tmp/main``) in the same interleaving.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks._common import header, markdown_table

RAW_EXTENSIONS = {".dng", ".cr2", ".cr3", ".crw", ".nef", ".rw2", ".raf", ".mrw", ".iiq", ".x3f"}
_LISTS = {51008: "L1", 51009: "L2", 51022: "L3"}


def _text(value: Any, width: int = 70) -> str:
    """One table cell: no pipes, no square brackets (mkdocs reads them as links)."""
    s = str(value).replace("|", "/").replace("[", "(").replace("]", ")").replace("\n", " ")
    return s if len(s) <= width else s[: width - 3] + "..."


def _tiff_pages(path: Path) -> tuple[Any, list[Any]] | None:
    """The open tifffile of a TIFF-based raw and its pages with their SubIFDs, or None."""
    import tifffile

    with path.open("rb") as f:
        if f.read(4) not in (b"II*\x00", b"MM\x00*"):
            return None
    try:
        tf = tifffile.TiffFile(path)
    except Exception:
        return None
    pages = []
    for page in tf.pages:
        pages.append(page)
        pages.extend(getattr(page, "pages", None) or [])
    return tf, pages


def _opcodes_in_file(pages: list[Any]) -> str:
    """The opcodes of every IFD's lists, by name and count: ``L2: 3 MapPolynomial``."""
    from imageform.io._dng_opcodes import OPCODE_NAMES, parse_opcode_list

    out = []
    for page in pages:
        for code, name in _LISTS.items():
            if code not in page.tags:
                continue
            value = page.tags[code].value
            ops = parse_opcode_list(value if isinstance(value, bytes) else bytes(value))
            names = [OPCODE_NAMES.get(op, str(op)) for op, _, _ in ops]
            counted = ", ".join(f"{names.count(n)} {n}" for n in dict.fromkeys(names))
            out.append(f"{name}: {counted or 'unreadable'}")
    return "; ".join(out) or "none"


def _preview(pages: list[Any]) -> np.ndarray | None:
    """The largest reduced-resolution 8-bit RGB image of the file, in [0, 1], or None."""
    best = None
    for page in pages:
        subfile = int(page.tags.valueof(254, 0))
        if not subfile & 1 or int(page.tags.valueof(277, 1)) != 3:
            continue
        if int(np.ravel(page.tags.valueof(258, 8))[0]) != 8:
            continue
        if best is None or page.shape[0] * page.shape[1] > best.shape[0] * best.shape[1]:
            best = page
    if best is None:
        return None
    try:
        return np.asarray(best.asarray(), np.float64)[..., :3] / 255.0
    except Exception:
        return None


def _default_crop(tf: Any, raw: Any) -> tuple[int, int, int, int] | None:
    """The raw IFD's DefaultCrop as (top, left, height, width) of the mosaic, or None."""
    from imageform.io.raw import _dng_raw_page

    page = _dng_raw_page(tf)
    if page is None or 50719 not in page.tags or 50720 not in page.tags:
        return None
    origin = [float(v) for v in np.ravel(page.tags[50719].value)]
    size = [float(v) for v in np.ravel(page.tags[50720].value)]
    if len(origin) == 4:  # RATIONAL pairs
        origin = [origin[0] / origin[1], origin[2] / origin[3]]
    if len(size) == 4:
        size = [size[0] / size[1], size[2] / size[3]]
    left, top = (round(v) for v in origin[:2])
    width, height = (round(v) for v in size[:2])
    h, w = raw.mosaic.shape[:2]
    if top + height > h or left + width > w:
        return None
    return top, left, height, width


def _luminance(srgb: np.ndarray) -> np.ndarray:
    from imageform.color import decode

    linear = decode(np.clip(srgb, 0.0, 1.0), "srgb")
    return linear @ np.array([0.2126, 0.7152, 0.0722])


def _corner_ratio(y: np.ndarray) -> float:
    """Mean of the four corner eighths of ``y`` over that of the central eighth."""
    h, w = y.shape
    bh, bw = max(h // 8, 1), max(w // 8, 1)
    corners = [y[:bh, :bw], y[:bh, -bw:], y[-bh:, :bw], y[-bh:, -bw:]]
    centre = y[h // 2 - bh // 2 : h // 2 + bh // 2 + 1, w // 2 - bw // 2 : w // 2 + bw // 2 + 1]
    return float(np.mean([c.mean() for c in corners]) / max(centre.mean(), 1e-9))


def _tone_matched(ours: np.ndarray, preview: np.ndarray) -> np.ndarray:
    """Our linear luminance mapped onto the preview's by their quantiles (one monotone curve).

    The preview went through the converter's tone curve; matching the distributions takes
    that curve out, so the corner / centre ratio compares where the light falls.
    """
    y, ref = _luminance(ours), _luminance(preview)
    q = np.linspace(0.0, 1.0, 257)
    src, dst = np.quantile(y, q), np.quantile(ref, q)
    src = src + np.arange(src.size) * 1e-12  # strictly increasing for the interpolation
    return np.interp(y, src, dst)


def _corner_shift(ours: np.ndarray, preview: np.ndarray, tile: int = 128) -> float:
    """Mean length of the phase-correlation shift of the four corner tiles, in pixels."""
    import cv2

    a = _luminance(ours).astype(np.float32)
    b = _luminance(preview).astype(np.float32)
    h, w = a.shape
    t = min(tile, h // 3, w // 3)
    window = cv2.createHanningWindow((t, t), cv2.CV_32F)
    shifts = []
    for r, c in ((0, 0), (0, w - t), (h - t, 0), (h - t, w - t)):
        ta, tb = a[r : r + t, c : c + t], b[r : r + t, c : c + t]
        (dx, dy), _ = cv2.phaseCorrelate(ta / max(ta.mean(), 1e-9), tb / max(tb.mean(), 1e-9),
                                         window)  # fmt: skip
        shifts.append(float(np.hypot(dx, dy)))
    return float(np.mean(shifts))


def _to_preview(image: np.ndarray, crop: Any, preview: np.ndarray) -> np.ndarray:
    import cv2

    if crop is not None:
        top, left, height, width = crop
        image = image[top : top + height, left : left + width]
    return cv2.resize(image.astype(np.float32), (preview.shape[1], preview.shape[0]),
                      interpolation=cv2.INTER_AREA).astype(np.float64)  # fmt: skip


def _libraw(path: Path) -> np.ndarray:
    import rawpy

    with rawpy.imread(str(path)) as r:
        return r.postprocess(demosaic_algorithm=rawpy.DemosaicAlgorithm.LINEAR,
                             use_camera_wb=True, no_auto_bright=True, output_bps=16)  # fmt: skip


def _ours(path: Path, opcodes: bool = True) -> tuple[Any, np.ndarray]:
    from imageform.io import develop, read_raw

    raw = read_raw(path, opcodes=opcodes)
    return raw, np.asarray(develop(raw).image, np.float64)


def _applied_twice(path: Path, raw: Any, preview: np.ndarray | None, crop: Any) -> str:
    """A lossy DNG developed with its decoding MapPolynomials applied once more (the error
    read_raw made before 2026-11-30): the median and the brightness against the preview."""
    import dataclasses

    import tifffile

    from imageform.io import develop
    from imageform.io._dng_opcodes import apply_stage2, read_opcodes
    from imageform.io.raw import _black_plane, _dng_raw_page

    with tifffile.TiffFile(path) as tf:
        maps = read_opcodes(_dng_raw_page(tf))[1]
    mosaic = apply_stage2(raw.mosaic, _black_plane(raw), raw.white_level, maps)
    image = np.asarray(develop(dataclasses.replace(raw, mosaic=mosaic)).image, np.float64)
    text = f"{path.name}: its decoding MapPolynomials applied again give median "
    text += f"{np.median(image):.3f}"
    if preview is not None:
        ratio = np.median(_to_preview(image, crop, preview)) / max(np.median(preview), 1e-9)
        text += f", brightness / preview {ratio:.2f}"
    return text


#: Lines said under the table (the lossy DNGs' second application).
NOTES: list[str] = []


def _own_reader(path: Path, raw: Any) -> str:
    """imageform's tifffile DNG reader (no LibRaw) against LibRaw's mosaic."""
    from imageform.io.raw import _read_dng

    if path.suffix.lower() != ".dng":
        return "not a DNG"
    try:
        own = _read_dng(path, 1 << 40)
    except Exception as exc:
        return _text(f"{type(exc).__name__}", 40)
    if own is None:
        return "not read"
    if own.mosaic.shape != raw.mosaic.shape:
        return f"shape {own.mosaic.shape} against {raw.mosaic.shape}"
    diff = int(np.abs(own.mosaic.astype(np.int64) - raw.mosaic.astype(np.int64)).max())
    return "equal" if diff == 0 else f"max difference {diff}"


def _check(path: Path) -> list[str]:
    from imageform.workflows.raw import stage3_names

    opened = _tiff_pages(path)
    tf, pages = opened if opened is not None else (None, [])
    in_file = _opcodes_in_file(pages) if pages else "not a TIFF"
    try:
        raw, image = _ours(path)
    except Exception as exc:  # the one-line refusal is the result
        if tf is not None:
            tf.close()
        line = str(exc).replace(str(path), path.name)
        return [path.name, "", in_file, "", _text(f"{type(exc).__name__}: {line}", 110)] + [""] * 5
    meta = raw.metadata
    did = []
    if meta.get("opcodes_applied"):
        did.append(f"applied {meta['opcodes_applied']} GainMap")
    did += [f"applied {n}" for n in dict.fromkeys(meta.get("opcodes_applied_other") or [])]
    did += [f"decoded with {n}" for n in dict.fromkeys(meta.get("opcodes_decoded") or [])]
    did += [f"at develop {n}" for n in dict.fromkeys(stage3_names(meta))]
    did += [f"skipped {n}" for n in dict.fromkeys(meta.get("opcodes_skipped") or [])]
    median = float(np.median(image))
    state = f"{image.shape[1]} x {image.shape[0]}, median {median:.3f}"
    state += "" if median > 0.01 else " BLACK"
    preview = _preview(pages) if pages else None
    bright = corners = shift = "no preview"
    crop = _default_crop(tf, raw) if tf is not None and raw.orientation == 0 else None
    if meta.get("opcodes_decoded"):
        NOTES.append(_applied_twice(path, raw, preview, crop))
    if preview is not None:
        on = _to_preview(image, crop, preview)
        off = _to_preview(_ours(path, opcodes=False)[1], crop, preview)
        bright = f"{np.median(on) / max(np.median(preview), 1e-9):.2f}"
        ratios = [_corner_ratio(_luminance(preview)), _corner_ratio(_tone_matched(on, preview)),
                  _corner_ratio(_tone_matched(off, preview))]  # fmt: skip
        corners = "preview {:.3f}, ours {:.3f} (no opcodes {:.3f})".format(*ratios)
        shift = f"{_corner_shift(on, preview):.2f} (no opcodes {_corner_shift(off, preview):.2f})"
    if tf is not None:
        tf.close()
    ours_t, libraw_t = [], []
    try:
        _libraw(path)
        for _ in range(5):
            t0 = time.perf_counter()
            _ours(path)
            ours_t.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            _libraw(path)
            libraw_t.append(time.perf_counter() - t0)
        a, b = statistics.median(ours_t), statistics.median(libraw_t)
        timing = f"{a:.3f} / {b:.3f} s ({a / b:.2f}x)"
    except Exception as exc:
        timing = _text(f"LibRaw: {type(exc).__name__}", 40)
    model = meta.get("camera_model") or "camera not named"
    from imageform.io import read_raw

    own = _own_reader(path, read_raw(path, opcodes=False))
    return [path.name, _text(model, 30), in_file, "; ".join(did) or "none", state, bright,
            corners, shift, timing, own]  # fmt: skip


def _phone_like(folder: Path, h: int = 3024, w: int = 4032) -> Path:
    """A synthetic 12 Mpx DNG with a Pixel's opcode set: four GainMaps, WarpRectilinear.

    An RGGB mosaic of noise (black 64, white 1023, as Pixels store 10 bits), OpcodeList2 four
    17 x 13 maps (one per photosite of the tile: pitch 2), OpcodeList3 one WarpRectilinear.
    """
    import struct

    import tifffile

    from imageform.io import write_dng

    rng = np.random.default_rng(0)
    mosaic = (64 + rng.integers(0, 900, (h, w))).astype(np.uint16)
    v, u = np.meshgrid(np.linspace(0, 1, 13), np.linspace(0, 1, 17), indexing="ij")
    gains = (1 + 1.5 * ((v - 0.5) ** 2 + (u - 0.5) ** 2)).astype(">f4")[..., None]

    def gain_map(r: int, c: int) -> bytes:
        params = struct.pack(">8I", r, c, h, w, 0, 1, 2, 2)
        params += struct.pack(">2I4d", 13, 17, 1 / 12, 1 / 16, 0.0, 0.0)
        params += struct.pack(">I", 1) + gains.tobytes()
        return struct.pack(">4I", 9, 0x01030000, 1, len(params)) + params

    warp = struct.pack(">I", 1) + struct.pack(">8d", 1.0, -0.02, 0.01, 0, 0, 0, 0.5, 0.5)
    list2 = struct.pack(">I", 4) + b"".join(gain_map(r, c) for r in (0, 1) for c in (0, 1))
    list3 = struct.pack(">I", 1) + struct.pack(">4I", 1, 0x01030000, 1, len(warp)) + warp
    base = write_dng(folder / "base.dng", mosaic, black_level=64, white_level=1023,
                     color_matrix=np.eye(3))  # fmt: skip
    with tifffile.TiffFile(base) as tf:
        page: Any = tf.pages[0]
        tags = [(t.code, t.dtype, t.count, t.value, True) for t in page.tags if t.code >= 33421]
        data = page.asarray()
    path = folder / "phone_like.dng"
    lists = [(51009, 7, len(list2), list2, True), (51022, 7, len(list3), list3, True)]
    tifffile.imwrite(path, data, photometric=32803, extratags=[*tags, *lists])
    return path


def _worker(path: Path) -> None:
    """Time developments of ``path`` as asked on stdin, one a line: ``on`` (read_raw +
    develop with the opcodes), ``off`` (--no-opcodes) or ``libraw``; print the seconds,
    elapsed and of CPU (the process's, every thread's).

    Run in a subprocess by :func:`_phone_like_timing`, with the imageform of its
    ``PYTHONPATH`` (this checkout's, or the one ``--against`` names).
    """
    import sys

    runs = {"on": lambda: _ours(path), "off": lambda: _ours(path, False),
            "libraw": lambda: _libraw(path)}  # fmt: skip
    for run in runs.values():  # compiled, cached, warm
        run()
    print("ready", flush=True)
    for line in sys.stdin:
        t0, c0 = time.perf_counter(), time.process_time()
        runs[line.strip()]()
        print(time.perf_counter() - t0, time.process_time() - c0, flush=True)


def _phone_like_timing(samples: int, against: Path | None, name: str) -> str:
    """The table of read_raw + develop on :func:`_phone_like` against LibRaw's postprocess.

    Each development in its own worker process (:func:`_worker`), the samples interleaved:
    this checkout's with and without opcodes, LibRaw's, and, with ``against`` (another
    checkout's ``src``, e.g. main's), that one's with the opcodes.
    """
    import subprocess
    import sys
    import tempfile

    import imageform

    here = Path(imageform.__file__).resolve().parents[1]
    root = Path(__file__).resolve().parents[1]
    sources = {"this": here} | ({"against": against} if against is not None else {})
    loads: list[float] = []
    with tempfile.TemporaryDirectory() as tmp:
        path = _phone_like(Path(tmp))
        workers = {}
        for key, src in sources.items():
            env = dict(os.environ, PYTHONPATH=f"{src}{os.pathsep}{root}")
            workers[key] = subprocess.Popen(
                [sys.executable, __file__, "--worker", str(path)], env=env, text=True,
                stdin=subprocess.PIPE, stdout=subprocess.PIPE,
            )  # fmt: skip
        for worker in workers.values():
            assert worker.stdout is not None and worker.stdout.readline().strip() == "ready"
        plan = [("this", "on"), ("this", "off"), ("this", "libraw")]
        plan += [("against", "on")] if against is not None else []
        times: dict[tuple[str, str], list[float]] = {step: [] for step in plan}
        cpu: dict[tuple[str, str], list[float]] = {step: [] for step in plan}
        for _ in range(samples):
            for key, what in plan:
                worker = workers[key]
                assert worker.stdin is not None and worker.stdout is not None
                worker.stdin.write(what + "\n")
                worker.stdin.flush()
                elapsed, used = worker.stdout.readline().split()
                times[(key, what)].append(float(elapsed))
                cpu[(key, what)].append(float(used))
            loads.append(os.getloadavg()[0])
        for worker in workers.values():
            assert worker.stdin is not None
            worker.stdin.close()
            worker.wait()
    med = {step: statistics.median(t) for step, t in times.items()}
    med_cpu = {step: statistics.median(t) for step, t in cpu.items()}
    lib, lib_cpu = med[("this", "libraw")], med_cpu[("this", "libraw")]
    names = {("this", "on"): "read_raw + develop, opcodes applied",
             ("this", "off"): "read_raw + develop, --no-opcodes",
             ("this", "libraw"): "LibRaw postprocess (no opcodes)",
             ("against", "on"): f"{name}: read_raw + develop, opcodes applied"}  # fmt: skip
    rows = [[names[step], f"{med[step]:.3f}", f"{med[step] / lib:.2f}x", f"{med_cpu[step]:.3f}",
             f"{med_cpu[step] / lib_cpu:.2f}x"] for step in plan]  # fmt: skip
    columns = ["development", "seconds", "against LibRaw", "CPU seconds", "CPU against LibRaw"]
    text = (
        "\nSynthetic 12 Mpx (4032 x 3024) DNG with a Pixel's opcode set (four per-photosite "
        f"GainMaps in OpcodeList2, a WarpRectilinear in OpcodeList3), medians of {samples} "
        "interleaved runs, each development in its own process (against LibRaw: its time "
        "over LibRaw's, below 1 faster; CPU: the process's, every thread's):\n\n"
        + markdown_table(columns, rows)
    )
    if against is not None:
        this, before = ("this", "on"), ("against", "on")
        text += (
            f"\nWith the opcodes, {name}'s time over this one's: "
            f"{med[before] / med[this]:.2f}x (CPU {med_cpu[before] / med_cpu[this]:.2f}x).\n"
        )
    return text + f"\nLoad average during the runs: {min(loads):.1f} to {max(loads):.1f}.\n"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("folder", type=Path, nargs="?", default=None,
                        help="the real raws (none: the synthetic DNG's timing alone)")  # fmt: skip
    parser.add_argument("--out", type=Path, default=None)
    parser.add_argument("--samples", type=int, default=9,
                        help="interleaved runs of each synthetic development")  # fmt: skip
    parser.add_argument("--against", type=Path, default=None,
                        help="another checkout's src folder, timed with this")  # fmt: skip
    parser.add_argument("--against-name", default="main", help="its name in the table")
    parser.add_argument("--worker", type=Path, default=None, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker is not None:
        _worker(args.worker)
        return
    text = header("Real DNG and raw files: opcodes, previews, speed")
    if args.folder is not None:
        files = sorted(p for p in args.folder.iterdir() if p.suffix.lower() in RAW_EXTENSIONS)
        rows = [_check(path) for path in files]
        columns = ["file", "camera", "opcodes in the file", "read_raw did", "develop",
                   "brightness / preview", "corner / centre luminance", "corner shift px",
                   "ours / LibRaw time", "tifffile reader vs LibRaw"]  # fmt: skip
        text += f"\n{len(files)} files from {args.folder.name}/ (sources in the script).\n\n"
        text += markdown_table(columns, rows)
        if NOTES:
            text += "\n" + "\n".join(f"- {n}" for n in NOTES) + "\n"
    text += _phone_like_timing(args.samples, args.against, args.against_name)
    text += f"\nLoad average at the end: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores.\n"
    print(text)
    if args.out is not None:
        args.out.write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
