"""Illuminant estimation on raw colour-constancy sets with measured illuminants.

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_illuminant_fresh.py \
        ROOT [--held-out]

``ROOT`` holds three public repositories' samples, as ``fetch`` brings them (none is in this
repository; their commits are printed with the table):

- tuning, ``ROOT/tune/c5/images``: mahmoudnafifi/C5 (Apache-2.0), 30 INTEL-TAU photographs of
  the Sony IMX135 phone sensor, 16-bit PNG of 384 x 256, black level and colour shading
  already corrected (the ``BLCCSC`` in their names), the truth in the JSON beside each;
  pixels at 65535 in some channel are clipped.
- tuning, ``ROOT/tune/pcc/dataset/CC2018``: shuwei666/Color-Constancy-PCC (no licence given),
  the 568 photographs of the Gehler-Shi set with the "recommended" truth (Hemrit et al.
  2018), black level subtracted, the chart set to zero, resized to 64 x 64 and scaled to a
  maximum of 1 (float32 ``.npy``).
- held out, ``ROOT/held/dataset``: shuwei666/DMCC-Cross-sensor-color-constancy (no licence
  given), the same preparation of Cube+ (1707, Canon 550D), the NUS 8-camera set (1853) and
  INTEL-TAU (7005, Canon 5DSR, Nikon D810, Sony IMX135).

The split is by repository and was made before anything ran; the held-out files are frozen
by SHA-256 (``HELD_OUT``: per folder, the SHA-256 of the ``sha256sum`` listing of its files
in sorted order); the script refuses a held-out folder whose files differ.

Each image is given to :func:`~imageform.color.estimate_illuminant` as linear RGB
(``transfer="linear"``) with the method's defaults (and ``gray_edge`` at p 1, sigma 2), with
``mask`` (the sets' convention: the chart left out, and the clipped pixels grown by one
pixel, as ``general_cc`` of van de Weijer et al. 2007 does; the 64 x 64 files were scaled
to a maximum of 1, so their clipped pixels cannot be told) and without. The ``ref`` rows are
a plain NumPy/SciPy implementation written from the papers on the same pixels and mask:
``general_cc``'s Gaussian derivative filters (SciPy's) and Minkowski norms, a border of
``sigma + 1`` left out of the derivatives, and Cheng et al. 2014's PCA (the 3.5 % darkest
and brightest pixels by their projection on the mean colour, the leading eigenvector of
their second-moment matrix). Published figures are on full-size images with each method's
parameters tuned by its authors; those of the 64 x 64 sets here are not the same pixels.

The error is the recovery angular error (Hordley & Finlayson 2006) in degrees; the
statistics are those of Gijsenij, Gevers & van de Weijer 2011 (mean, median, trimean
(Q1 + 2 Q2 + Q3) / 4, mean of the best and of the worst 25 %). An image a method refuses
(``DegenerateConfigurationError``: nothing to measure the light by) is left as it came, the
estimate (1, 1, 1), counted in the ``refused`` column.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from scipy import ndimage

from benchmarks._common import header, markdown_table
from imageform.color import estimate_illuminant
from imageform.errors import DegenerateConfigurationError

#: The held-out folders, frozen before any run: number of files, SHA-256 of their listing.
HELD_OUT = {
    "Cube+": (3414, "e2fc7624eae8c8b15043e0e490d577d9517aa141da942ce2c91cf18c84039709"),
    "NUS-C1": (518, "bd6216d9cd9252c9ae7b23fcd2352563222cb54872837887ac332058ebf86a2c"),
    "NUS-Canon600D": (400, "c4d5cbf230033b9e4a47b9dba9b71346d099e57fbb959f2361e21ff816c7b231"),
    "NUS-Fuji": (392, "c6ddd9193467da620e59b00236c884457d26a9f6c95c9f453128afd2e2605003"),
    "NUS-NikonD5200": (634, "0749121da66b52ba5c53c118c9f014bb91ab948107c4fe429934a6e4d91d8f82"),
    "NUS-Olympus": (416, "ba65d147f89cba96ea120652292a8f18b3f40c945d64fcf0a9e6b682bc72d186"),
    "NUS-Panasonic": (406, "d8f83b8596757f072e1dc33df02d982baf2326ffd02aac29fdeb1286e3707335"),
    "NUS-Samsung": (404, "d0831fa16d678532cf3e3cf6ad218fd9f00f5998be5f5403245cd04bc574ecae"),
    "NUS-Sony": (536, "f03f82a1f934908d5a83adfe8ac16c23f036bd1239e246468c221a27bb1aca21"),
    "TAU_C_5DSR": (4216, "7cd96eaf345a2b8ce0032c203dac109b5efe2709fcb02198f0aad65e4ae66d88"),
    "TAU_N_D810": (5568, "00e68fde0cf011b123ad5de1f17edc6225e3a9f2ca857e0e4dcc29ba1ebea83a"),
    "TAU_S_IMX135": (4226, "3ecd38545eb49e71b89284350477a478a89624b9245db80808b0e179d914427a"),
}
#: The repositories, at the commits measured.
SOURCES = (
    ("mahmoudnafifi/C5", "dca92361d43c8e737697fb27ac6eb9aa5d640bc4", "Apache-2.0", "tuning"),
    (
        "shuwei666/Color-Constancy-PCC",
        "8268951399d2149332562f8f2176f425bfc1a23e",
        "none given",
        "tuning",
    ),
    (
        "shuwei666/DMCC-Cross-sensor-color-constancy",
        "48d9c361291c25464e7d988f4a7b37370f0ae903",
        "none given",
        "held out",
    ),
)

Image = tuple[str, np.ndarray, np.ndarray, np.ndarray]  # name, rgb, usable mask, truth

#: Published statistics (mean, median, trimean, best 25 %, worst 25 %), full-size images, each
#: method's parameters tuned by its authors. Gehler-Shi: Cheng, Price, Cohen & Brown 2015
#: (CVPR), Table 1 (google/ffcc, GehlerShiBaselines.m), the older ground truth; grayness
#: index: Qian et al. 2019 as quoted by Kim et al. 2025 (CCMNet), Table 1. Cube+ and NUS-8
#: (the grayness index only: that table's other NUS-8 rows are Cheng et al.'s Sony A57 row,
#: compared per camera below): Kim et al. 2025 (CCMNet), Table 1.
PUBLISHED = {
    "Gehler-Shi": {
        "gray_world": (6.36, 6.28, 6.28, 2.33, 10.58),
        "max_rgb": (7.55, 5.68, 6.35, 1.45, 16.12),
        "shades_of_gray p6": (4.93, 4.01, 4.23, 1.14, 10.20),
        "gray_edge p1 s2": (5.33, 4.52, 4.73, 1.86, 10.03),
        "grayness_index": (3.07, 1.87, 2.16, 0.43, 7.62),
        "pca": (3.52, 2.14, 2.47, 0.50, 8.74),
    },
    "Cube+": {
        "gray_world": (3.52, 2.55, 2.82, 0.60, 7.98),
        "shades_of_gray p6": (3.22, 2.12, 2.44, 0.43, 7.77),
        "gray_edge p1 s2": (3.06, 2.05, 2.32, 0.55, 7.22),
    },
    "NUS-8": {"grayness_index": (2.91, 1.97, 2.13, 0.56, 6.67)},
}
#: NUS per camera, mean / median: Cheng et al. 2015, Table 2 (google/ffcc, ChengResults.m)
#: for grey world, white patch (max-RGB), shades of grey, 1st-order grey edge, PCA (Cheng et
#: al. 2014).
PUBLISHED_NUS = {
    "NUS-C1": ((5.16, 4.15), (7.99, 6.19), (3.81, 2.73), (3.45, 2.48), (2.93, 2.01)),
    "NUS-Canon600D": ((3.89, 2.88), (10.96, 12.44), (3.23, 2.58), (3.22, 2.07), (2.81, 1.89)),
    "NUS-Fuji": ((4.16, 3.30), (10.20, 10.59), (3.56, 2.81), (3.13, 1.99), (3.15, 2.15)),
    "NUS-NikonD5200": ((4.38, 3.39), (11.64, 11.67), (3.45, 2.56), (3.37, 2.22), (2.90, 2.08)),
    "NUS-Olympus": ((3.44, 2.58), (9.78, 9.50), (3.16, 2.42), (3.02, 2.11), (2.76, 1.87)),
    "NUS-Panasonic": ((3.82, 3.06), (13.41, 18.00), (3.22, 2.30), (2.99, 2.16), (2.96, 2.02)),
    "NUS-Samsung": ((3.90, 3.00), (11.97, 12.99), (3.17, 2.33), (3.09, 2.23), (2.91, 2.03)),
    "NUS-Sony": ((4.59, 3.46), (9.91, 7.44), (3.67, 2.94), (3.35, 2.58), (2.93, 2.33)),
}
NUS_METHODS = ("gray_world", "max_rgb", "shades_of_gray p6", "gray_edge p1 s2", "pca")


def _sha_listing(folder: Path) -> tuple[int, str]:
    lines = []
    for f in sorted(p for p in folder.rglob("*") if p.is_file()):
        digest = hashlib.sha256(f.read_bytes()).hexdigest()
        lines.append(f"{digest}  ./{f.relative_to(folder).as_posix()}\n")
    return len(lines), hashlib.sha256("".join(lines).encode()).hexdigest()


def load_c5(folder: Path) -> list[Image]:
    import cv2

    out = []
    for png in sorted(folder.glob("*.png")):
        raw = cv2.imread(str(png), cv2.IMREAD_UNCHANGED)[..., ::-1]
        meta = json.loads(png.with_name(png.stem + "_metadata.json").read_text())
        # the clipped pixels grown by one pixel (general_cc's convention: their neighbours
        # are partly clipped too, the more so in an image made smaller)
        clipped = ndimage.binary_dilation(raw.max(axis=-1) >= 65535, np.ones((3, 3), bool))
        rgb = raw.astype(np.float64) / 65535.0
        out.append((png.stem[:34], rgb, ~clipped, np.asarray(meta["illuminant_color_raw"])))
    return out


def load_npy(folder: Path) -> list[Image]:
    out = []
    for f in sorted((folder / "numpy_data").glob("*.npy")):
        rgb = np.load(f).astype(np.float64)
        truth = np.load(folder / "numpy_labels" / f.name).astype(np.float64)
        out.append((f.stem, rgb, rgb.max(axis=-1) > 0, truth))  # the chart is set to zero
    return out


def angle(e: np.ndarray, t: np.ndarray) -> float:
    e = np.asarray(e, dtype=np.float64)
    c = float(e @ t / (np.linalg.norm(e) * np.linalg.norm(t) + 1e-300))
    return math.degrees(math.acos(min(1.0, max(-1.0, c))))


def stats(err: list[float]) -> list[float]:
    a = np.sort(np.asarray(err))
    q1, q2, q3 = np.percentile(a, [25, 50, 75])
    k = max(1, round(len(a) / 4))
    return [float(a.mean()), float(q2), float((q1 + 2 * q2 + q3) / 4), a[:k].mean(), a[-k:].mean()]


# --- the reference, written from the papers (van de Weijer's general_cc; Cheng et al.) ---


def _ref_mask(ok: np.ndarray, sigma: float) -> np.ndarray:
    """Usable pixels: the set's mask, for derivatives a border of sigma + 1 left out."""
    m = ok.copy()
    b = int(sigma + 1) if sigma > 0 else 0
    if b:
        m[:b], m[-b:], m[:, :b], m[:, -b:] = False, False, False, False
    return m


def ref_general(rgb: np.ndarray, ok: np.ndarray, order: int, p: float, sigma: float):
    m = _ref_mask(ok, sigma if order else 0.0)
    if order == 0:
        x = ndimage.gaussian_filter(rgb, (sigma, sigma, 0)) if sigma > 0 else rgb
        v = x[m]
    else:
        chans = []
        for c in range(3):
            ch = rgb[..., c]
            if order == 1:
                gx = ndimage.gaussian_filter(ch, sigma, order=(0, 1))
                gy = ndimage.gaussian_filter(ch, sigma, order=(1, 0))
                chans.append(np.sqrt(gx**2 + gy**2))
            else:
                gxx = ndimage.gaussian_filter(ch, sigma, order=(0, 2))
                gyy = ndimage.gaussian_filter(ch, sigma, order=(2, 0))
                gxy = ndimage.gaussian_filter(ch, sigma, order=(1, 1))
                chans.append(np.sqrt(gxx**2 + 4 * gxy**2 + gyy**2))
        v = np.stack(chans, -1)[m]
    if math.isinf(p):
        return v.max(axis=0)
    return (np.abs(v) ** p).mean(axis=0) ** (1.0 / p)


def ref_pca(rgb: np.ndarray, ok: np.ndarray, q: float = 3.5) -> np.ndarray:
    v = rgb[_ref_mask(ok, 0.0)]
    t = v @ v.mean(axis=0)
    n = max(1, math.ceil(len(v) * q / 100.0))
    order = np.argsort(t)
    s = v[np.concatenate([order[:n], order[-n:]])]
    _, vec = np.linalg.eigh(s.T @ s)
    e = vec[:, -1]
    return e if e.sum() > 0 else -e


# --- the methods ---


def _if(method: str, **kw: Any) -> Callable[[np.ndarray, np.ndarray, bool], np.ndarray]:
    def run(rgb: np.ndarray, ok: np.ndarray, masked: bool) -> np.ndarray:
        extra = {"mask": ok} if masked else {}
        return np.asarray(estimate_illuminant(rgb, method, transfer="linear", **kw, **extra))

    return run


METHODS: dict[str, Callable[[np.ndarray, np.ndarray, bool], np.ndarray]] = {
    "gray_world": _if("gray_world"),
    "white_patch (99)": _if("white_patch"),
    "max_rgb": _if("max_rgb"),
    "shades_of_gray p6": _if("shades_of_gray"),
    "gray_edge p6 s1": _if("gray_edge"),
    "gray_edge p1 s2": _if("gray_edge", p=1.0, sigma=2.0),
    "grayness_index": _if("grayness_index"),
    "pca": _if("pca"),
}
REFS: dict[str, Callable[[np.ndarray, np.ndarray], np.ndarray]] = {
    "ref gray_world": lambda x, ok: ref_general(x, ok, 0, 1.0, 0.0),
    "ref max_rgb": lambda x, ok: ref_general(x, ok, 0, math.inf, 0.0),
    "ref shades_of_gray p6": lambda x, ok: ref_general(x, ok, 0, 6.0, 0.0),
    "ref gray_edge p6 s1": lambda x, ok: ref_general(x, ok, 1, 6.0, 1.0),
    "ref gray_edge p1 s2": lambda x, ok: ref_general(x, ok, 1, 1.0, 2.0),
    "ref pca": ref_pca,
}


#: Per set and row: how many images the method refused (no estimate: the image is left as it
#: came, the estimate (1, 1, 1), and its error counts so).
FAILED: dict[str, int] = {}


def _or_none(fn: Callable[[], np.ndarray], key: str) -> np.ndarray:
    try:
        return fn()
    except DegenerateConfigurationError:
        FAILED[key] = FAILED.get(key, 0) + 1
        return np.ones(3)


def evaluate(images: list[Image], masked_too: bool) -> dict[str, list[float]]:
    FAILED.clear()
    err: dict[str, list[float]] = {"none": [angle(np.ones(3), t) for _, _, _, t in images]}
    for name, fn in METHODS.items():
        for masked in (False, True) if masked_too else (True,):
            key = f"{name}{' mask' if masked else ''}" if masked_too else name
            err[key] = [
                angle(_or_none(lambda: fn(x, ok, masked), key), t)  # noqa: B023
                for _, x, ok, t in images
            ]
    for name, rfn in REFS.items():
        err[name] = [angle(rfn(x, ok), t) for _, x, ok, t in images]
    return err


def table(err: dict[str, list[float]]) -> str:
    rows = [[k, *(f"{v:.2f}" for v in stats(e)), FAILED.get(k, 0)] for k, e in err.items()]
    cols = ("method", "mean", "median", "trimean", "best 25 %", "worst 25 %", "refused")
    return markdown_table(cols, rows)


def _fmt(v: Any) -> str:
    return " / ".join(f"{x:.2f}" for x in v)


def compare(results: dict[str, dict[str, list[float]]]) -> str:
    """Markdown: our masked rows beside the published ones, per set."""
    out = []
    short = {k.split(" (")[0]: v for k, v in results.items()}
    nus = [k for k in short if k.startswith("NUS-")]
    pooled: dict[str, list[float]] = {}
    if nus:  # the NUS convention: the statistics per camera, averaged over the cameras
        for m in ("grayness_index",):
            per = np.array([stats(short[k][f"{m} mask"]) for k in nus])
            pooled[m] = list(per.mean(axis=0))
    rows = []
    for set_name, pub in PUBLISHED.items():
        for m, v in pub.items():
            if set_name == "NUS-8":
                if m not in pooled:
                    continue
                ours = pooled[m]
            else:
                key = next((k for k in results if k.startswith(set_name)), None)
                if key is None:
                    continue
                ours = stats(results[key][f"{m} mask"])
            rows.append([set_name, m, _fmt(v), _fmt(ours)])
    if rows:
        cols = ("set", "method (ours)", "published", "imageform, mask")
        out.append("### Published tables (mean / median / trimean / best 25 % / worst 25 %)\n")
        out.append(markdown_table(cols, rows))
    rows = []
    for cam in nus:
        pub = PUBLISHED_NUS[cam]
        row = [cam]
        for m, (mean, med) in zip(NUS_METHODS, pub, strict=True):
            e = np.asarray(short[cam][f"{m} mask"])
            row.append(f"{mean:.2f} / {med:.2f} -> {e.mean():.2f} / {np.median(e):.2f}")
        rows.append(row)
    if rows:
        out.append("### NUS per camera: Cheng et al. 2015 Table 2 -> imageform (mean / median)\n")
        out.append(markdown_table(("camera", *NUS_METHODS), rows))
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("root", type=Path)
    ap.add_argument("--held-out", action="store_true", help="run the frozen held-out half")
    a = ap.parse_args(argv)
    print(header("Illuminant estimation on raw colour-constancy sets (fresh, 2026-11-30)"))
    sets: list[tuple[str, list[Image]]] = [
        ("INTEL-TAU IMX135 (C5 sample, 384 x 256)", load_c5(a.root / "tune/c5/images")),
        ("Gehler-Shi CC2018 (PCC, 64 x 64)", load_npy(a.root / "tune/pcc/dataset/CC2018")),
    ]
    if a.held_out:
        base = a.root / "held/dataset"
        for name, (n, digest) in HELD_OUT.items():
            if _sha_listing(base / name) != (n, digest):
                print(f"held-out folder {name} differs from its frozen SHA-256", file=sys.stderr)
                return 1
            sets.append((f"{name} (DMCC, 64 x 64)", load_npy(base / name)))
    results: dict[str, dict[str, list[float]]] = {}
    for i, (name, images) in enumerate(sets):
        if i == 2:
            print("# Held-out half (run once)\n")
        t0 = time.perf_counter()
        err = evaluate(images, masked_too=True)
        results[name] = err
        print(f"## {name}: {len(images)} images ({time.perf_counter() - t0:.0f} s)\n")
        print(table(err))
    print("## Against the published tables\n")
    print(compare(results))
    print("## Sources\n")
    print(markdown_table(("repository", "commit", "licence", "half"), SOURCES))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
