"""Focal length in pixels from a photograph's EXIF, against known cameras and the vanishing points.

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/check_exif_focal.py DIR [DIR ...]

Each ``DIR`` holds photographs and a ``truth.csv`` (columns ``file``, ``f_px``, ``note``: the
focal length in pixels where the camera is known, from the lens's focal length over the
sensor's width on the maker's data sheet times the image's width, as
``benchmarks/check_vp_real.py``'s folders have it). For every photograph whose EXIF names a
camera (:func:`imageform.io.exif_camera`): the estimate from the 35 mm equivalent
(:math:`f_{35}\\, d / 43.27`, what imageform uses), the one the focal-plane resolution would
give (the focal length times FocalPlaneXResolution in pixels per mm, times the image's width
over PixelXDimension; not used by imageform), the known focal length, and the vanishing
points' (:func:`imageform.geometry.detect_vanishing_points`, defaults), each with its error
against the known one where there is one.

The photographs used for ``exif-focal-2026-11-30a.md`` are the dev and held folders of
``check_vp_real.py`` (236 photographs from public repositories, none in this repository; that
script's docstring names them); only 11 carry EXIF camera tags.
"""

from __future__ import annotations

import csv
import math
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks._common import header, markdown_table  # noqa: E402

_UNITS_MM = {1: 25.4, 2: 25.4, 3: 10.0, 4: 1.0, 5: 1e-3}


def _focal_plane_px(path: Path) -> float | None:
    """The focal length times the focal-plane resolution (what imageform does not use)."""
    from PIL import Image

    with Image.open(path) as im:
        sub = im.getexif().get_ifd(0x8769)
        width = im.size[0]
    focal, res, unit = sub.get(0x920A), sub.get(0xA20E), sub.get(0xA210, 2)
    if not focal or not res:
        return None
    recorded = sub.get(0xA002)
    scale = width / float(recorded) if recorded else 1.0
    return float(focal) * float(res) / _UNITS_MM.get(int(unit), 25.4) * scale


def _pct(value: float | None, truth: float | None) -> str:
    if value is None or truth is None:
        return "-"
    return f"{100 * (value / truth - 1):+.1f} %"


def _num(value: float | None) -> str:
    return "-" if value is None else f"{value:.0f}"


def main() -> None:
    import numpy as np

    from imageform.geometry import detect_vanishing_points
    from imageform.io import exif_camera, read_image

    rows = []
    for folder in map(Path, sys.argv[1:]):
        truth: dict[str, float] = {}
        tp = folder / "truth.csv"
        if tp.is_file():
            with tp.open() as fh:
                for r in csv.DictReader(fh):
                    if r.get("f_px"):
                        truth[r["file"]] = float(r["f_px"])
        for path in sorted(folder.iterdir()):
            if path.suffix.lower() not in (".jpg", ".jpeg", ".png", ".tif", ".tiff", ".webp"):
                continue
            cam = exif_camera(path)
            if not cam.found:
                continue
            img = read_image(path)
            arr = img[..., 0] if img.shape[-1] == 1 else img[..., :3]
            vp = detect_vanishing_points(np.asarray(arr), rng=0)
            f_vp = None if vp.K is None else float(vp.K[0, 0])
            known = truth.get(path.name)
            plane = _focal_plane_px(path)
            rows.append([
                path.name,
                cam.describe().replace("|", "/"),
                f"{cam.width_px} x {cam.height_px}",
                _num(known),
                _num(cam.focal_length_px),
                _pct(cam.focal_length_px, known),
                _num(plane),
                _pct(plane, known),
                _num(f_vp),
                _pct(f_vp, known),
                _pct(f_vp, cam.focal_length_px),
            ])  # fmt: skip
            print(rows[-1], file=sys.stderr, flush=True)
    print(header("Focal length in pixels from the EXIF"))
    print(
        "Photographs whose EXIF names a camera. Known f: the lens's focal length over the "
        "sensor's width (data sheet) times the image's width, from truth.csv. f35: "
        f"the 35 mm equivalent times the diagonal over {math.hypot(36, 24):.2f} mm (imageform's "
        "estimate); focal plane: the focal length times FocalPlaneXResolution (not used). "
        "VP: the vanishing points' f, defaults, seed 0.\n"
    )
    cols = [
        "photograph",
        "camera (EXIF)",
        "size px",
        "known f px",
        "f35 estimate px",
        "vs known",
        "focal-plane px",
        "vs known",
        "VP f px",
        "VP vs known",
        "VP vs f35",
    ]
    print(markdown_table(cols, rows))


if __name__ == "__main__":
    main()
