"""How much the vanishing points, K and the horizon depend on RANSAC's seed.

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python -m benchmarks.check_vp_seed --photos DIR ...

For each photograph (the folders' ``*.jpg`` / ``*.png`` with their optional ``truth.csv``, as
``benchmarks/check_vp_real.py`` reads them) and OpenCV's 13 checkerboard views (undistorted
with their published calibration, f = 536.07 px), the line segments are detected once and
``detect_vanishing_points(segments=..., rng=s)`` runs for each seed ``s`` (default 0 to 4),
the default settings otherwise. Against seed 0, a seed's answer *changes*

- the points: when the sets of vanishing points differ, two points matching when their
  directions ``(u - cx, v - cy, f w)`` (f the known focal length, else the image diagonal)
  are within 1 degree of each other (up to sign);
- K: when one seed gives K and the other not, or their focal lengths differ by more than 1 %;
- the horizon: when one seed gives a horizon and the other not, or its rows at the image's
  left and right edges differ by more than 1 % of the height.

Per seed: the median focal-length error over the photographs with a known focal length that
got K, how many got K, how many are off by more than 20 % ("wrong K"), and the CPU time of the
vanishing-point stage (segments excluded; median per photograph, ``time.process_time``).
"""

from __future__ import annotations

import argparse
import csv
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks._common import header, markdown_table

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / ".." / "shared" / "data" / "opencv-left"


def _inputs(folders: list[Path], views: bool) -> list[tuple[str, str, np.ndarray, float | None]]:
    """``(set, name, rgb or grey image, known f)`` for every photograph and view."""
    from imageform.io import read_image

    out: list[tuple[str, str, np.ndarray, float | None]] = []
    for folder in folders:
        truth: dict[str, float] = {}
        if (folder / "truth.csv").is_file():
            with open(folder / "truth.csv", newline="") as fh:
                for r in csv.DictReader(fh):
                    if r.get("f_px"):
                        truth[r["file"]] = float(r["f_px"])
        paths = sorted(p for p in folder.iterdir() if p.suffix.lower() in (".jpg", ".jpeg", ".png"))
        for path in paths:
            img = np.asarray(read_image(path))
            rgb = img[..., :3] if img.ndim == 3 else np.repeat(img[..., None], 3, axis=-1)
            if rgb.dtype != np.uint8:
                rgb = np.clip(np.round(np.asarray(rgb, dtype=np.float64) * 255), 0, 255)
                rgb = rgb.astype(np.uint8)
            out.append((folder.name, path.name, rgb, truth.get(path.name)))
    if views:
        from PIL import Image

        from benchmarks.check_vp_real import F_TRUE, D, K
        from imageform.geometry import undistort_image
        from imageform.geometry.distortion import BrownConrady

        for path in sorted(DATA.glob("left*.jpg")):
            img = np.asarray(Image.open(path).convert("L"))
            und = undistort_image(img, K, BrownConrady.from_opencv(D), keep_dtype=True)
            out.append(("opencv", path.name, und, F_TRUE))
    return out


def _dirs(vps: np.ndarray, c: np.ndarray, f: float) -> np.ndarray:
    d = np.column_stack([vps[:, 0] - c[0] * vps[:, 2], vps[:, 1] - c[1] * vps[:, 2], f * vps[:, 2]])
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def _same_points(a: np.ndarray, b: np.ndarray) -> bool:
    if len(a) != len(b):
        return False
    if not len(a):
        return True
    cos = np.abs(a @ b.T)
    used: set[int] = set()
    for i in range(len(a)):
        j = int(np.argmax(np.where([k in used for k in range(len(b))], -1.0, cos[i])))
        if j in used or cos[i, j] < math.cos(math.radians(1.0)):
            return False
        used.add(j)
    return True


def _rows(h: np.ndarray | None, w: int) -> tuple[float, float] | None:
    if h is None or abs(float(h[1])) < 1e-9:
        return None
    a, b, c = (float(x) for x in h)
    return (-c / b, -(a * (w - 1) + c) / b)


def measure(
    items: list[tuple[str, str, np.ndarray, float | None]],
    seeds: list[int],
    cache: Path | None = None,
) -> dict[str, list[dict[str, Any]]]:
    from imageform.geometry import LineSegments, detect_line_segments, detect_vanishing_points

    per: dict[str, list[dict[str, Any]]] = {}
    for group, name, img, ft in items:
        path = None if cache is None else cache / f"{group}-{name}.npz"
        if path is not None and path.is_file():
            z = np.load(path)
            seg = LineSegments(z["endpoints"], z["widths"], z["log10_nfa"])
        else:
            seg = detect_line_segments(img)
            if path is not None:
                path.parent.mkdir(parents=True, exist_ok=True)
                np.savez(path, endpoints=seg.endpoints, widths=seg.widths, log10_nfa=seg.log10_nfa)
        h, w = img.shape[:2]
        c = np.array([(w - 1) / 2, (h - 1) / 2])
        fref = ft or math.hypot(w, h)
        res = []
        for s in seeds:
            t0 = time.process_time()
            r = detect_vanishing_points(segments=seg, image_size=(w, h), rng=s)
            dt = time.process_time() - t0
            res.append((r, dt))
        r0 = res[0][0]
        d0 = _dirs(r0.vanishing_points, c, fref)
        h0 = _rows(r0.horizon, w)
        ch_pts = ch_k = ch_h = 0
        for r, _ in res[1:]:
            ch_pts += not _same_points(d0, _dirs(r.vanishing_points, c, fref))
            if (r.K is None) != (r0.K is None):
                ch_k += 1
            elif r.K is not None and r0.K is not None:
                ch_k += abs(r.K[0, 0] / r0.K[0, 0] - 1) > 0.01
            hh = _rows(r.horizon, w)
            if (hh is None) != (h0 is None):
                ch_h += 1
            elif hh is not None and h0 is not None:
                ch_h += max(abs(hh[0] - h0[0]), abs(hh[1] - h0[1])) > 0.01 * h
        per.setdefault(group, []).append(
            {
                "name": name,
                "ft": ft,
                "f": [None if r.K is None else float(r.K[0, 0]) for r, _ in res],
                "t": [dt for _, dt in res],
                "changes": (ch_pts, ch_k, ch_h),
            }
        )
    return per


def tables(per: dict[str, list[dict[str, Any]]], seeds: list[int]) -> str:
    out = []
    stab: list[tuple[object, ...]] = []
    acc: list[tuple[object, ...]] = []
    for group, photos in per.items():
        n = len(photos)
        anyp = sum(p["changes"][0] > 0 for p in photos)
        anyk = sum(p["changes"][1] > 0 for p in photos)
        anyh = sum(p["changes"][2] > 0 for p in photos)
        pairs = n * (len(seeds) - 1)
        stab.append(
            (
                group,
                n,
                f"{anyp} ({sum(p['changes'][0] for p in photos)} of {pairs})",
                f"{anyk} ({sum(p['changes'][1] for p in photos)} of {pairs})",
                f"{anyh} ({sum(p['changes'][2] for p in photos)} of {pairs})",
                f"{1000 * float(np.median([t for p in photos for t in p['t']])):.0f}",
            )
        )
        known = [p for p in photos if p["ft"]]
        for k, s in enumerate(seeds):
            e = np.array(
                [abs(p["f"][k] / p["ft"] - 1) * 100 if p["f"][k] else math.inf for p in known]
            )
            found = np.isfinite(e)
            acc.append(
                (
                    group,
                    s,
                    f"{int(found.sum())} of {len(known)}",
                    f"{np.median(e[found]):.1f} %" if found.any() else "-",
                    int((e <= 5).sum()),
                    int((found & (e > 20)).sum()),
                )
            )
    out.append("## Stability against seed 0\n")
    out.append(
        markdown_table(
            (
                "set",
                "photographs",
                "points change (seed pairs)",
                "K changes (seed pairs)",
                "horizon changes (seed pairs)",
                "median ms per call (CPU)",
            ),
            stab,
        )
    )
    out.append("## Focal length per seed (photographs with a known focal length)\n")
    out.append(
        markdown_table(
            ("set", "seed", "K found", "median f error", "within 5 %", "wrong K (off by > 20 %)"),
            acc,
        )
    )
    changed = [
        (
            group,
            p["name"],
            *p["changes"],
            ", ".join("-" if f is None else f"{f:.0f}" for f in p["f"]),
        )
        for group, photos in per.items()
        for p in photos
        if any(p["changes"])
    ]
    out.append("## Photographs whose answer changes with the seed\n")
    out.append(
        markdown_table(("set", "photograph", "points", "K", "horizon", "f per seed (px)"), changed)
    )
    return "\n".join(out)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--photos", type=Path, nargs="*", default=[], help="photograph folders")
    parser.add_argument("--no-views", action="store_true", help="leave out OpenCV's views")
    parser.add_argument("--seeds", type=int, default=5, help="seeds 0 .. N-1 (default 5)")
    parser.add_argument(
        "--cache",
        type=Path,
        help="a folder to keep the detected segments in (outside the repository)",
    )
    args = parser.parse_args()
    seeds = list(range(args.seeds))
    items = _inputs(args.photos, not args.no_views)
    per = measure(items, seeds, args.cache)
    print(header("Vanishing points: dependence on RANSAC's seed"))
    print(tables(per, seeds))
    print(
        "Command: `OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python -m benchmarks.check_vp_seed "
        "--photos DIR ...`\n"
    )


if __name__ == "__main__":
    main()
