"""Vanishing points, the focal length and the horizon on fresh photographs of known cameras.

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python -m benchmarks.check_vp_fresh \\
        --data /tmp/vpg/data --half tune [--peers] [--cli 4]

``--data`` is a folder made by copying photographs and their cameras, at the commit named,
from three public repositories nobody on the project had used for vanishing points
(``DIR/truth.json`` records, per file, the repository, commit, path, SHA-256 and the truth;
no photograph is in this repository):

- ``tune/scannet``: the 30 ScanNet frames (15 pairs, 1296 x 968, rooms, clutter, motion blur)
  of magicleap/SuperGluePretrainedNetwork @ ddcf11f (``assets/scannet_sample_images``; its
  licence: academic or non-commercial research), each with its calibrated K and each pair's
  relative pose (``assets/scannet_sample_pairs_with_gt.txt``).
- ``tune/tum_fr3``: 20 frames (640 x 480, an office, clutter) of TUM RGB-D
  fr3/long_office_household, 17 from the same repository (``assets/freiburg_sequence``) and 3
  from luigifreda/pyslam @ 8a7b88b (``test/data/tum_office``, GPL-3; a fourth is the same file
  as one of the 17), with fr3's published K (fx 535.4, fy 539.2, cx 320.1, cy 247.6; fr3's
  frames are distortion-free).
- ``tune/kitti06``: 8 frames of KITTI odometry sequence 06 (1226 x 370, a road, rectified) of
  luigifreda/pyslam @ 8a7b88b (``test/data/kitti06-*.png``), with K from its
  ``settings/KITTI04-12.yaml`` (f 707.09 px; principal point (601.9, 183.1), 11 px left of
  the centre).
- ``held/strecha``: the 103 photographs (3072 x 2048, six scenes: a castle's courtyard, a
  church, a fountain, an entrance) of Strecha et al. 2008's benchmark as mirrored by
  openMVG/SfM_quality_evaluation @ 348a981 (``Benchmarking_Camera_Calibration_2008``; no
  licence stated; the benchmark is free for research), each with its ground-truth camera
  from a laser scan (``gt_dense_cameras``: K, f = 2759.5 px, the rotation and the centre;
  the photographs are distortion-free).

The split is by repository and was frozen (SHA-256 of each held-out file) before anything
ran: the tuning half is the 58 photographs of the first two repositories, the held-out half
the 103 of the third (``--half held``).

For each photograph, the segments are detected once (``detect_line_segments``) and
``detect_vanishing_points`` runs with the default settings (principal point at the centre)
and with the calibrated principal point (``principal_point=(cx, cy)``). Measured:

- **f**: K found, and the focal length's error against the calibrated one (the mean of fx and
  fy).
- **Directions** (Strecha): with the calibrated K, each vanishing point is a direction in the
  camera; for two photographs of the same scene (consecutive by name) whose ground-truth
  rotations give their relative rotation, each direction of the first is
  rotated into the second and its angle to the nearest direction found there is taken (up to
  sign; a direction found in one and not the other counts as far off: the error is then the
  angle to whatever is nearest).
- **Vertical and horizon** (Strecha): the laser scans' world z axis is taken as the vertical
  (the scanner is levelled); its direction in each camera gives the true zenith and the true
  horizon ``K^-T up``. The zenith error is the angle between the vertical vanishing point's
  direction and it; the horizon error is York Urban's and HLW's measure: the larger distance
  between the found and the true horizon at the image's left and right edges, over the
  height (no horizon counts as infinite).
- **Peer**: lu-vp-detect 1.0.4 (Lu et al. 2017's 2-line exhaustive search, OpenCV's LSD),
  given the calibrated K (it cannot estimate f), length threshold 60 px at 640 px width
  scaled with the width, seed 1337: its three directions, scored as above.
- Time per photograph: segments and vanishing points, default settings (wall clock, the
  machine shared with other jobs: indicative).

``--cli N``: ``imageform vanishing IMAGE --json`` on the first N photographs of each source,
checking that the command's K equals the library's. ``--seeds N``: K for RANSAC seeds 0 to
N - 1 (how often it appears, goes or moves by more than 1 %). ``--max-size N``: also
``detect_vanishing_points(image, max_size=N)`` (segments on a copy at most N px on its long
side). ``--upsample F``: each photograph enlarged F times (bicubic; K scaled with it) first.
``--limit N``: the first N photographs of each source only.
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks._common import header, markdown_table


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _directions(vps: np.ndarray, K: np.ndarray) -> np.ndarray:
    """Unit directions (camera frame) of homogeneous vanishing points under K."""
    if len(vps) == 0:
        return np.zeros((0, 3))
    return _unit(np.linalg.solve(K, np.asarray(vps, float).T).T)


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    """Angle in degrees between two directions, up to sign."""
    c = abs(float(np.dot(_unit(a), _unit(b))))
    return math.degrees(math.acos(min(1.0, c)))


def _nearest(d: np.ndarray, others: np.ndarray) -> float:
    if len(others) == 0:
        return 90.0
    return min(_angle(d, o) for o in others)


def _horizon_error(h: np.ndarray | None, truth: np.ndarray, w: int, hgt: int) -> float:
    """York Urban / HLW: the larger distance at the left and right edges over the height."""
    if h is None or abs(h[1]) < 1e-12:
        return math.inf
    rows = [-(h[0] * u + h[2]) / h[1] for u in (0.0, w - 1.0)]
    true = [-(truth[0] * u + truth[2]) / truth[1] for u in (0.0, w - 1.0)]
    return max(abs(a - b) for a, b in zip(rows, true, strict=True)) / hgt


class _Cv2Shim:
    """OpenCV as lu-vp-detect 1.0.4 expects it: LSD's lines as (N, 1, 4) (OpenCV 5 gives (N, 4))."""

    def __init__(self, cv2: Any) -> None:
        self._cv2 = cv2

    def __getattr__(self, name: str) -> Any:
        return getattr(self._cv2, name)

    def createLineSegmentDetector(self, *args: Any) -> Any:
        lsd = self._cv2.createLineSegmentDetector(*args)

        class _Lsd:
            def detect(self, img: np.ndarray) -> tuple[np.ndarray, ...]:
                out = lsd.detect(img)
                lines = np.zeros((0, 4), np.float32) if out[0] is None else out[0]
                return (np.asarray(lines, np.float32).reshape(-1, 1, 4), *out[1:])

        return _Lsd()


def _lu(img: np.ndarray, K: np.ndarray) -> tuple[np.ndarray, float]:
    """lu-vp-detect's three directions (camera frame) given K, and its time."""
    import cv2
    import lu_vp_detect.vp_detection as lu
    from lu_vp_detect import VPDetection

    if not isinstance(lu.cv2, _Cv2Shim):
        lu.cv2 = _Cv2Shim(cv2)

    bgr = img if img.ndim == 2 else cv2.cvtColor(img, cv2.COLOR_RGB2BGR)
    thresh = 60.0 * img.shape[1] / 640.0
    det = VPDetection(thresh, (float(K[0, 2]), float(K[1, 2])), float(K[0, 0]), 1337)
    t0 = time.perf_counter()
    vps = np.asarray(det.find_vps(bgr), float)
    dt = time.perf_counter() - t0
    # its directions are (x, y, z) in the camera, y down: its 2-D points are f (x, y) / z + c
    vps = vps[np.all(np.isfinite(vps), axis=1)]
    return (_unit(vps) if len(vps) else np.zeros((0, 3))), dt


def measure(
    data: Path,
    half: str,
    peers: bool,
    seeds: int = 1,
    max_size: int | None = None,
    upsample: float = 1.0,
    limit: int = 0,
) -> list[dict[str, Any]]:
    from imageform.geometry import detect_line_segments, detect_vanishing_points
    from imageform.io import read_image

    truth = json.loads((data / "truth.json").read_text())
    rows = []
    keys = sorted(k for k in truth if k.startswith(half + "/"))
    if limit:
        keys = [
            k
            for k in keys
            if sum(x.split("/")[1] == k.split("/")[1] for x in keys[: keys.index(k)]) < limit
        ]
    for key in keys:
        t = truth[key]
        img = np.asarray(read_image(data / key))
        if img.ndim == 3 and img.shape[2] == 4:
            img = img[..., :3]
        K = np.array(t["K"], float)
        if upsample != 1.0:
            import cv2

            img = cv2.resize(img, None, fx=upsample, fy=upsample, interpolation=cv2.INTER_CUBIC)
            S = np.diag([upsample, upsample, 1.0])
            S[:2, 2] = 0.5 * upsample - 0.5  # pixel centres: u' = (u + 0.5) s - 0.5
            K = S @ K
        hgt, w = img.shape[:2]
        f_true = 0.5 * (K[0, 0] + K[1, 1])
        t0 = time.perf_counter()
        seg = detect_line_segments(img)
        res = detect_vanishing_points(segments=seg, image_size=(w, hgt))
        t2 = time.perf_counter()
        res_pp = detect_vanishing_points(
            segments=seg, image_size=(w, hgt), principal_point=(K[0, 2], K[1, 2])
        )
        row: dict[str, Any] = {
            "key": key,
            "source": key.split("/")[1],
            "name": key.split("/")[2],
            "size": (w, hgt),
            "segments": len(seg),
            "time": t2 - t0,
            "n_vp": len(res.vanishing_points),
            "f": None if res.K is None else float(res.K[0, 0]),
            "f_pp": None if res_pp.K is None else float(res_pp.K[0, 0]),
            "f_true": f_true,
            "K_reason": res.K_reason,
            "dirs": _directions(res.vanishing_points, K),
            "vertical": res.vertical,
            "horizon": res.horizon,
            "t": t,
            "K": K,
        }
        if max_size is not None:
            rv = detect_vanishing_points(img, max_size=max_size) if max(w, hgt) > max_size else res
            row["ms_f"] = None if rv.K is None else float(rv.K[0, 0])
            row["ms_dirs"] = _directions(rv.vanishing_points, K)
            row["ms_vertical"] = rv.vertical
            row["ms_horizon"] = rv.horizon
            row["max_size"] = max_size
        row["seed_f"] = [row["f"]]
        for seed in range(1, seeds):
            rs = detect_vanishing_points(segments=seg, image_size=(w, hgt), rng=seed)
            row["seed_f"].append(None if rs.K is None else float(rs.K[0, 0]))
        if "R_cam_to_world" in t:
            R = np.array(t["R_cam_to_world"], float)
            up = R.T @ np.array([0.0, 0.0, 1.0])
            row["up"] = up
            row["horizon_true"] = np.linalg.inv(K).T @ up
        if peers:
            row["lu_dirs"], row["lu_time"] = _lu(img, K)
        rows.append(row)
        print(
            f"{key}: {len(seg)} segments, {row['n_vp']} points, f {row['f']} / {f_true:.1f}, "
            f"{row['time']:.2f} s",
            file=sys.stderr,
            flush=True,
        )
    return rows


def _rotations(rows: list[dict[str, Any]]) -> list[tuple[int, int, np.ndarray]]:
    """(i, j, R_i_to_j) for consecutive photographs of one scene with known absolute rotations.

    ScanNet's pairs are not used: no convention of their relative poses (``T_0to1`` or its
    inverse, in OpenCV's or OpenGL's camera axes) makes the three orthogonal directions that
    lu-vp-detect finds in the two views agree on more than 3 of the 15 pairs.
    """
    out = []
    by_scene: dict[str, list[int]] = {}
    for i, r in enumerate(rows):
        if "R_cam_to_world" in r["t"]:
            by_scene.setdefault(r["t"]["scene"], []).append(i)
    for idx in by_scene.values():
        for i, j in itertools.pairwise(idx):
            Ri = np.array(rows[i]["t"]["R_cam_to_world"])
            Rj = np.array(rows[j]["t"]["R_cam_to_world"])
            out.append((i, j, Rj.T @ Ri))
    return out


def _vertical_of(row: dict[str, Any], who: str) -> np.ndarray | None:
    """The detector's vertical direction: imageform's vertical point, or the direction of
    lu-vp-detect's three nearest the image's columns (its own choice of a vertical)."""
    if who != "lu_":
        v = row[who + "vertical"]
        return None if v is None else row[who + "dirs"][v]
    if len(row["lu_dirs"]) == 0:
        return None
    return max(row["lu_dirs"], key=lambda d: abs(d[1]))


def _detectors(rows: list[dict[str, Any]], peers: bool) -> list[tuple[str, str]]:
    """(name, field prefix) of the detectors measured."""
    out = [("imageform", "")]
    if rows and "ms_f" in rows[0]:
        out.append((f"imageform, max_size={rows[0]['max_size']}", "ms_"))
    if peers:
        out.append(("lu-vp-detect", "lu_"))
    return out


def _hrow(who: str, n: int, zen: list[float], hor: list[float]) -> list[object]:
    """A row of the vertical and horizon table."""
    return [
        who,
        n,
        len(zen),
        _fmt(_median(zen), ".2f", "°"),
        sum(z <= 1 for z in zen),
        int(sum(np.isfinite(hor))),
        _fmt(_median(hor) * 100 if hor else None, ".2f", " %"),
        sum(h <= 0.02 for h in hor),
        sum(h <= 0.05 for h in hor),
    ]


def _fmt(x: float | None, spec: str = ".1f", unit: str = "") -> str:
    if x is None:
        return "-"
    if math.isinf(x):
        return "inf"
    return f"{x:{spec}}{unit}"


def _median(xs: list[float]) -> float | None:
    return statistics.median(xs) if xs else None


def tables(rows: list[dict[str, Any]], peers: bool) -> str:
    out = []
    sources = sorted({r["source"] for r in rows})
    # focal length
    variant = bool(rows) and "ms_f" in rows[0]
    frows = []
    for s in [*sources, "all"]:
        rs = [r for r in rows if s in ("all", r["source"])]
        e = [abs(r["f"] / r["f_true"] - 1) * 100 for r in rs if r["f"] is not None]
        ep = [abs(r["f_pp"] / r["f_true"] - 1) * 100 for r in rs if r["f_pp"] is not None]
        row = [
            s,
            len(rs),
            len(e),
            _fmt(_median(e), ".1f", " %"),
            sum(x <= 5 for x in e),
            sum(x > 20 for x in e),
            len(ep),
            _fmt(_median(ep), ".1f", " %"),
            sum(x <= 5 for x in ep),
            sum(x > 20 for x in ep),
        ]
        if variant:
            em = [abs(r["ms_f"] / r["f_true"] - 1) * 100 for r in rs if r["ms_f"] is not None]
            row += [len(em), _fmt(_median(em), ".1f", " %"), sum(x <= 5 for x in em)]
            row += [sum(x > 20 for x in em)]
        frows.append([*row, _fmt(_median([r["time"] for r in rs]), ".2f", " s")])
    out.append("### Focal length (K from the vanishing points)\n")
    out.append(
        markdown_table(
            [
                "source",
                "photographs",
                "K found (centre)",
                "median |f error|",
                "within 5 %",
                "off > 20 %",
                "K found (calibrated principal point)",
                "median |f error|",
                "within 5 %",
                "off > 20 %",
                *(
                    [
                        f"K found (centre, max_size={rows[0]['max_size']})",
                        "median |f error|",
                        "within 5 %",
                        "off > 20 %",
                    ]
                    if variant
                    else []
                ),
                "median time per photograph",
            ],
            frows,
        )
    )
    # directions against known relative rotations
    rot = _rotations(rows)
    if rot:
        drows = []
        for who, pre in _detectors(rows, peers):
            field = pre + "dirs"
            for s in [*sources, "all"]:
                errs = []
                for i, j, Rij in rot:
                    if s not in ("all", rows[i]["source"]):
                        continue
                    for d in rows[i][field]:
                        errs.append(_nearest(Rij @ d, rows[j][field]))
                    for d in rows[j][field]:
                        errs.append(_nearest(Rij.T @ d, rows[i][field]))
                if not errs:
                    continue
                drows.append(
                    [
                        who,
                        s,
                        len(errs),
                        _fmt(_median(errs), ".2f", "°"),
                        sum(e <= 1 for e in errs),
                        sum(e <= 3 for e in errs),
                        sum(e > 10 for e in errs),
                    ]
                )
        vrows = []
        for who, pre in _detectors(rows, peers):
            for s in [*sources, "all"]:
                pairs = [x for x in rot if s in ("all", rows[x[0]]["source"])]
                if not pairs:
                    continue
                errs = []
                for i, j, Rij in pairs:
                    a, b = _vertical_of(rows[i], pre), _vertical_of(rows[j], pre)
                    if a is not None and b is not None:
                        errs.append(_angle(Rij @ a, b))
                vrows.append(
                    [
                        who,
                        s,
                        len(pairs),
                        len(errs),
                        _fmt(_median(errs), ".2f", "°"),
                        sum(e <= 1 for e in errs),
                        sum(e > 5 for e in errs),
                    ]
                )
        out.append(
            "\n### The vertical direction of two views against their known relative rotation "
            "(calibrated K)\n"
        )
        out.append(
            markdown_table(
                [
                    "detector",
                    "source",
                    "pairs",
                    "both with a vertical",
                    "median angle",
                    "within 1°",
                    "off > 5°",
                ],
                vrows,
            )
        )
        out.append(
            "\n### Vanishing directions against the known relative rotations (calibrated K)\n"
        )
        out.append(
            markdown_table(
                [
                    "detector",
                    "source",
                    "directions",
                    "median angle to the other view's nearest",
                    "within 1°",
                    "within 3°",
                    "off > 10°",
                ],
                drows,
            )
        )
    # vertical and horizon
    vr = [r for r in rows if "up" in r]
    if vr:
        hrows = []
        for who, pre in _detectors(rows, False):
            zen = [
                _angle(r[pre + "dirs"][r[pre + "vertical"]], r["up"])
                for r in vr
                if r[pre + "vertical"] is not None
            ]
            hor = [_horizon_error(r[pre + "horizon"], r["horizon_true"], *r["size"]) for r in vr]
            hrows.append(_hrow(f"{who} (its vertical point; its horizon)", len(vr), zen, hor))
        if peers:
            zl, hl = [], []
            for r in vr:
                if len(r["lu_dirs"]) == 0:
                    hl.append(math.inf)
                    continue
                K = r["K"]
                # its vertical: the direction nearest the image's columns (y axis)
                dv = max(r["lu_dirs"], key=lambda d: abs(d[1]))
                zl.append(_angle(dv, r["up"]))
                hl.append(_horizon_error(np.linalg.inv(K).T @ dv, r["horizon_true"], *r["size"]))
            hrows.append(
                _hrow(
                    "lu-vp-detect (calibrated K; the direction nearest the columns)",
                    len(vr),
                    zl,
                    hl,
                )
            )
        out.append("\n### Vertical and horizon against the laser scans' vertical\n")
        out.append(
            markdown_table(
                [
                    "detector",
                    "photographs",
                    "vertical found",
                    "median zenith error",
                    "within 1°",
                    "horizon found",
                    "median horizon error, % of H (none: inf)",
                    "within 2 %",
                    "within 5 %",
                ],
                hrows,
            )
        )
    if peers:
        lt = [r["lu_time"] for r in rows]
        it = [r["time"] for r in rows]
        out.append(
            f"\nTime per photograph (median): imageform {statistics.median(it):.2f} s "
            f"(segments and points), lu-vp-detect {statistics.median(lt):.2f} s "
            "(its own segments and points).\n"
        )
    n_seeds = len(rows[0]["seed_f"]) if rows else 1
    if n_seeds > 1:
        srows = []
        for s in [*sources, "all"]:
            rs = [r for r in rows if s in ("all", r["source"])]
            changed = 0
            errs: list[list[float]] = [[] for _ in range(n_seeds)]
            for r in rs:
                fs = r["seed_f"]
                base = fs[0]
                if any(
                    (f is None) != (base is None) or (f is not None and abs(f / base - 1) > 0.01)
                    for f in fs[1:]
                ):
                    changed += 1
                for i, f in enumerate(fs):
                    if f is not None:
                        errs[i].append(abs(f / r["f_true"] - 1) * 100)
            found = [len(e) for e in errs]
            med = [_median(e) for e in errs]
            srows.append(
                [
                    s,
                    len(rs),
                    changed,
                    f"{min(found)}-{max(found)}",
                    f"{_fmt(min(m for m in med if m is not None), '.1f')}-"
                    f"{_fmt(max(m for m in med if m is not None), '.1f')} %"
                    if any(m is not None for m in med)
                    else "-",
                    f"{min(sum(x > 20 for x in e) for e in errs)}-"
                    f"{max(sum(x > 20 for x in e) for e in errs)}",
                ]
            )
        out.append(f"\n### RANSAC's seed: seeds 0-{n_seeds - 1}\n")
        out.append(
            markdown_table(
                [
                    "source",
                    "photographs",
                    "K changes (appears, goes or f moves > 1 %) against seed 0",
                    "K found",
                    "median |f error|",
                    "off > 20 %",
                ],
                srows,
            )
        )
    # per photograph
    prow = []
    for r in rows:
        f_err = None if r["f"] is None else (r["f"] / r["f_true"] - 1) * 100
        fp_err = None if r["f_pp"] is None else (r["f_pp"] / r["f_true"] - 1) * 100
        extra = "-"
        if "up" in r:
            z = _angle(r["dirs"][r["vertical"]], r["up"]) if r["vertical"] is not None else None
            h = _horizon_error(r["horizon"], r["horizon_true"], *r["size"])
            extra = f"{_fmt(z, '.2f', '°')}, {_fmt(h * 100, '.2f', ' %')}"
        ms_err = None if not variant or r["ms_f"] is None else (r["ms_f"] / r["f_true"] - 1) * 100
        prow.append(
            [
                r["key"].split("/", 1)[1],
                r["segments"],
                r["n_vp"],
                _fmt(f_err, "+.1f", " %"),
                _fmt(fp_err, "+.1f", " %"),
                *([_fmt(ms_err, "+.1f", " %")] if variant else []),
                extra,
                (r["K_reason"] or "")[:70],
            ]
        )
    out.append("\n### Per photograph\n")
    out.append(
        markdown_table(
            [
                "photograph",
                "segments",
                "points",
                "f error (centre)",
                "f error (calibrated pp)",
                *(["f error (max_size)"] if variant else []),
                "zenith, horizon error",
                "why no K",
            ],
            prow,
        )
    )
    return "\n".join(out)


def cli_check(data: Path, rows: list[dict[str, Any]], n: int) -> str:
    """``imageform vanishing --json`` against the library on the first n of each source."""
    lines = []
    for s in sorted({r["source"] for r in rows}):
        for r in [r for r in rows if r["source"] == s][:n]:
            out = subprocess.run(
                [sys.executable, "-m", "imageform", "vanishing", str(data / r["key"]), "--json"],
                capture_output=True,
                text=True,
                check=False,
            )
            if out.returncode not in (0, 1):
                lines.append(f"- {r['key']}: exit {out.returncode}: {out.stderr.strip()}")
                continue
            js = json.loads(out.stdout) if out.stdout.strip().startswith("{") else {}
            k = js.get("K")
            f_cli = None if k is None else k[0][0]
            same_f = (f_cli is None) == (r["f"] is None) and (
                f_cli is None or abs(f_cli - r["f"]) < 1e-6 * r["f"]
            )
            lines.append(
                f"- {r['key']}: exit {out.returncode}, f {_fmt(f_cli)} "
                f"({'the same as' if same_f else 'DIFFERENT from'} the library's), "
                f"horizon {js.get('horizon_source')}"
            )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", type=Path, required=True, help="the folder with truth.json")
    parser.add_argument("--half", choices=["tune", "held"], required=True)
    parser.add_argument("--peers", action="store_true", help="run lu-vp-detect too")
    parser.add_argument("--cli", type=int, default=0, help="check the command on N per source")
    parser.add_argument("--seeds", type=int, default=1, help="RANSAC seeds 0 .. N-1 for K")
    parser.add_argument(
        "--max-size", type=int, help="also detect_vanishing_points(image, max_size=N)"
    )
    parser.add_argument("--limit", type=int, default=0, help="the first N of each source only")
    parser.add_argument(
        "--upsample", type=float, default=1.0, help="enlarge each photograph (bicubic) first"
    )
    args = parser.parse_args()
    rows = measure(
        args.data, args.half, args.peers, args.seeds, args.max_size, args.upsample, args.limit
    )
    name = "tuning" if args.half == "tune" else "held-out"
    up = f", enlarged {args.upsample:g} times" if args.upsample != 1 else ""
    print(header(f"Vanishing points on fresh photographs of known cameras: {name} half{up}"))
    print(tables(rows, args.peers))
    if args.cli:
        print("\n### `imageform vanishing --json` against the library\n")
        print(cli_check(args.data, rows, args.cli))
    print(
        "\nCommand: `OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python -m benchmarks.check_vp_fresh "
        f"--data DIR --half {args.half}{' --peers' if args.peers else ''}"
        f"{f' --cli {args.cli}' if args.cli else ''}"
        f"{f' --seeds {args.seeds}' if args.seeds > 1 else ''}"
        f"{f' --max-size {args.max_size}' if args.max_size else ''}"
        f"{f' --upsample {args.upsample:g}' if args.upsample != 1 else ''}`\n"
    )


if __name__ == "__main__":
    main()
