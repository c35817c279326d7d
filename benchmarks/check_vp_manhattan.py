"""Vanishing points, K, zenith and horizon on cluttered renders of a York-Urban-like camera.

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/check_vp_manhattan.py [--n 60]

A stand-in for the York Urban DB (not available here), scored with its metrics. Each scene:
a 640 x 480 camera with f = 675 px and the principal point 17 px off the image centre
(York Urban's calibration: f = 674.9 px, (307.6, 251.5)); a hand-held pose (pitch and roll
within 12 and 4 degrees, any heading); segments along the three world axes at random places
in front of the camera, with a share of clutter (segments in random 3-D directions, 35 % of
all) and, in some scenes, only two of the three axes (a level camera at an angle to a
wall: verticals, parallel in the image, and one horizontal direction - no focal length can
be had from that, only the horizon; or a floor: two horizontal directions); then blur,
noise and JPEG compression. ``detect_vanishing_points(image)`` runs with its defaults
(principal point at the image centre).

Metrics, as York Urban evaluations report them: the focal-length error relative to the
truth; the zenith error, the angle between the vertical direction the detected horizon
gives with the true K (``Kᵀ l``) and the true one; the horizon error, the larger vertical
distance between the detected and the true horizon at the image's left and right edges,
over the image height. A scene where no K (or no horizon) is found counts as an infinite
error (it raises the median); the wall scenes have no K to find.
"""

from __future__ import annotations

import argparse
import io
import math

import numpy as np

from benchmarks._common import header, markdown_table

W, H = 640, 480
F = 675.0
PP = (307.6, 251.5)


def _rot(pitch: float, yaw: float, roll: float) -> np.ndarray:
    cx, sx = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    cz, sz = math.cos(roll), math.sin(roll)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ rx @ ry  # world -> camera (y down in both)


def scene(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, str]:
    """Return (image uint8 grey, K, R, kind)."""
    from PIL import Image, ImageDraw, ImageFilter

    rng = np.random.default_rng(seed)
    K = np.array([[F, 0, PP[0]], [0, F, PP[1]], [0, 0, 1.0]])
    kind = ("three", "three", "wall", "floor")[seed % 4] if seed % 3 == 0 else "three"
    pitch = math.radians(rng.uniform(-12, 12)) if kind != "wall" else 0.0
    roll = math.radians(rng.uniform(-4, 4)) if kind != "wall" else 0.0
    yaw = math.radians(rng.uniform(-45, 45))
    if kind == "wall":  # a level camera at an angle to the wall: verticals stay parallel
        yaw = math.copysign(math.radians(rng.uniform(15, 45)), yaw)
    R = _rot(pitch, yaw, roll)
    axes = {"three": (0, 1, 2), "wall": (0, 1), "floor": (0, 2)}[kind]
    s = 3
    img = Image.new("L", (W * s, H * s), int(rng.uniform(60, 120)))
    draw = ImageDraw.Draw(img)
    n_total = 150
    n_clutter = int(0.35 * n_total)
    dirs = []
    for a in axes:
        e = np.zeros(3)
        e[a] = 1.0
        dirs += [e] * ((n_total - n_clutter) // len(axes))
    for _ in range(n_clutter):
        v = rng.normal(size=3)
        dirs.append(v / np.linalg.norm(v))
    for d in dirs:
        for _ in range(20):  # a segment in view, in front of the camera
            depth = rng.uniform(4, 25)
            p0 = R.T @ (
                np.array(
                    [rng.uniform(-1, 1) * depth * 0.6, rng.uniform(-1, 1) * depth * 0.45, depth]
                )
            )
            p1 = p0 + d * rng.uniform(0.8, 3.5)
            q = (K @ (R @ np.stack([p0, p1]).T)).T
            if (q[:, 2] <= 0.5).any():
                continue
            uv = q[:, :2] / q[:, 2:]
            if not (
                (uv[:, 0] > -50) & (uv[:, 0] < W + 50) & (uv[:, 1] > -50) & (uv[:, 1] < H + 50)
            ).all():
                continue
            shade = int(np.clip(rng.normal(200, 40), 0, 255))
            a, b = (uv + 0.5) * s - 0.5
            draw.line([tuple(a), tuple(b)], fill=shade, width=int(rng.integers(1, 4)) * s)
            break
    img = img.resize((W, H), Image.Resampling.BOX).filter(
        ImageFilter.GaussianBlur(rng.uniform(0.3, 1.2))
    )
    arr = np.asarray(img, dtype=np.float64) + rng.normal(0, rng.uniform(1, 6), (H, W))
    buf = io.BytesIO()
    Image.fromarray(np.clip(arr, 0, 255).astype(np.uint8)).save(
        buf, "JPEG", quality=int(rng.integers(60, 95))
    )
    out = np.asarray(Image.open(io.BytesIO(buf.getvalue())))
    return out, K, R, kind


def _horizon_true(K: np.ndarray, R: np.ndarray) -> np.ndarray:
    up_cam = R @ np.array([0.0, -1.0, 0.0])  # world up is -y
    line = np.linalg.inv(K).T @ up_cam
    return line / math.hypot(line[0], line[1])


def _row(line: np.ndarray, u: float) -> float:
    return float(-(line[0] * u + line[2]) / line[1])


def measure(
    n: int, principal_point: str = "center"
) -> tuple[list[tuple[object, ...]], dict[str, list[float]]]:
    from imageform.geometry import detect_vanishing_points

    rows: list[tuple[object, ...]] = []
    errs: dict[str, list[float]] = {"f": [], "zenith": [], "horizon": []}
    for seed in range(n):
        img, K, R, kind = scene(seed)
        # none found: an empty set, horizon None
        res = detect_vanishing_points(img, principal_point=principal_point)
        truth = _horizon_true(K, R)
        if res is None or res.horizon is None:
            errs["f"].append(math.inf)
            errs["zenith"].append(math.inf)
            errs["horizon"].append(math.inf)
            rows.append((seed, kind, "-", "-", "-"))
            continue
        fe = math.inf if res.K is None else 100 * abs(res.K[0, 0] / F - 1)
        up_true = R @ np.array([0.0, -1.0, 0.0])
        up_est = K.T @ res.horizon  # the direction the detected horizon gives, with the true K
        up_est /= np.linalg.norm(up_est)
        if up_est @ up_true < 0:
            up_est = -up_est
        ze = math.degrees(math.acos(float(np.clip(up_est @ up_true, -1, 1))))
        he = 100 * max(abs(_row(res.horizon, u) - _row(truth, u)) for u in (0.0, W - 1.0)) / H
        errs["f"].append(fe)
        errs["zenith"].append(ze)
        errs["horizon"].append(he)
        rows.append(
            (seed, kind, f"{fe:.1f} %" if res.K is not None else "-", f"{ze:.2f}", f"{he:.2f} %")
        )
    return rows, errs


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=60)
    ap.add_argument(
        "--principal-point",
        choices=("center", "estimate"),
        default="center",
        help="detect_vanishing_points' principal_point (the default: the image centre)",
    )
    args = ap.parse_args()
    n = args.n
    rows, errs = measure(n, args.principal_point)
    print(header("Vanishing points on cluttered renders of a York-Urban-like camera"))
    summary = []
    for key, unit, target in (
        ("f", "%", "3 %"),
        ("zenith", "deg", "1 deg"),
        ("horizon", "% of H", "2 %"),
    ):
        e = np.array(errs[key])
        summary.append(
            (
                key,
                f"{np.median(e):.2f} {unit}",
                f"{np.percentile(e, 75):.2f} {unit}",
                f"{int(np.isfinite(e).sum())} / {n}",
                target,
            )
        )
    print("## Summary\n")
    print(
        markdown_table(
            ("error", "median", "75th percentile", "found", "York Urban target"), summary
        )
    )
    print("## Per scene\n")
    print(markdown_table(("seed", "scene", "f error", "zenith error deg", "horizon error"), rows))
    print(
        "Command: `OPENBLAS_NUM_THREADS=1 PYTHONPATH=src python benchmarks/check_vp_manhattan.py "
        f"--n {n}`"
    )


if __name__ == "__main__":
    main()
