"""Vanishing points fed by the LSD segments against the earlier detector (method="simple").

Run::

    OPENBLAS_NUM_THREADS=1 python benchmarks/check_vp_lsd.py

1. Manhattan line renders with a known camera (tests/geometry/scene_render.py, K with
   f = 700 px, 768 x 512): focal-length error, principal-point error, horizon error at the
   image centre and the worst vanishing-point error (relative to its distance from the
   principal point), for several camera rotations.
2. ``imageform simulate``'s built-in scene (rails on a ground, known vanishing point and
   horizon): the simulator's own ``vanishing_point_error_px`` and ``horizon_angle_error_deg``.
3. Kodak photographs of buildings (no ground truth): the focal length found, the horizon's
   tilt and whether a vertical direction was found (the photographs are hand-held, nearly
   level; the 35 mm PhotoCD frames scanned to 768 px wide would put a 35-50 mm lens at
   f = 770-1100 px).

Each case runs ``detect_vanishing_points(image, segments=..., rng=0)`` on segments from
``detect_line_segments(image, method=m)`` for m in ("lsd", "simple").
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from benchmarks._common import header, markdown_table

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / ".." / "shared" / "data" / "kodak"


def _row_at(line: np.ndarray, u: float) -> float:
    return float(-(line[0] * u + line[2]) / line[1])


def _vp(img: np.ndarray, method: str):  # type: ignore[no-untyped-def]
    from imageform.geometry import detect_line_segments, detect_vanishing_points

    seg = detect_line_segments(img, method=method)
    if len(seg) < 2:  # no vanishing point to find (the detector returns an empty set)
        return seg, None
    return seg, detect_vanishing_points(
        segments=seg, image_size=(img.shape[1], img.shape[0]), rng=0
    )


def renders() -> list[tuple[object, ...]]:
    sys.path.insert(0, str(ROOT))
    from imageform.geometry import camera_rotation, horizon_line, vanishing_point
    from tests.geometry.scene_render import render_manhattan

    K = np.array([[700.0, 0.0, 383.5], [0.0, 700.0, 255.5], [0.0, 0.0, 1.0]])
    rows = []
    poses = [
        (0.25, 0.5, 0.03),
        (-0.2, 0.7, -0.05),
        (0.35, -0.45, 0.0),
        (0.1, 0.3, 0.1),
        (-0.3, -0.6, 0.02),
        (0.0, 0.6, 0.0),
    ]
    for seed, (pitch, yaw, roll) in enumerate(poses):
        R = camera_rotation(pitch, yaw, roll)
        img = render_manhattan(K, R, np.zeros(3), seed=seed + 3, n_per_axis=40)
        true_vps = [vanishing_point(K, d, R) for d in np.eye(3)]
        hor = horizon_line(K, R)
        for method in ("lsd", "simple"):
            seg, res = _vp(img, method)
            if res is None:
                rows.append((f"{pitch},{yaw},{roll}", method, len(seg), "-", "-", "-", "-"))
                continue
            f_err = f"{100 * (res.K[0, 0] / 700 - 1):+.2f} %" if res.K is not None else "no K"
            pp = f"{np.hypot(*(res.K[:2, 2] - K[:2, 2])):.1f}" if res.K is not None else "-"
            h_err = (
                f"{_row_at(res.horizon, 383.5) - _row_at(hor, 383.5):+.2f}"
                if res.horizon is not None
                else "-"
            )
            # angle between the back-projected directions K^-1 v (true K), detected vs
            # nearest true: handles points at infinity
            kinv = np.linalg.inv(K)
            worst = 0.0
            for v in res.vanishing_points:
                dv = kinv @ v
                dv /= np.linalg.norm(dv)
                errs = []
                for tv in true_vps:
                    dt = kinv @ tv
                    dt /= np.linalg.norm(dt)
                    errs.append(math.degrees(math.acos(min(1.0, abs(float(dv @ dt))))))
                worst = max(worst, min(errs))
            rows.append(
                (
                    f"{pitch},{yaw},{roll}",
                    method,
                    len(seg),
                    f_err,
                    pp,
                    h_err,
                    f"{worst:.3f}",
                )
            )
    return rows


def simulated() -> list[tuple[object, ...]]:
    from imageform.simulate import default_scene

    rows = _simulated(default_scene(), "built-in scene (k1 = -0.12, k2 = 0.01)")
    undistorted = default_scene().with_changes(camera={"distortion": {"k1": 0.0, "k2": 0.0}})
    return rows + _simulated(undistorted, "built-in scene, distortion off")


def _simulated(scene, label: str) -> list[tuple[object, ...]]:  # type: ignore[no-untyped-def]
    from imageform.simulate import simulate
    from imageform.simulate.truth import VanishingTruth, vanishing_errors

    res = simulate(scene, rng=0)
    assert res.vanishing is not None
    img = np.asarray(res.stages[-1].image)
    truth = res.vanishing.vanishing_point / res.vanishing.vanishing_point[2]
    rows = [
        (
            f"{label}: the simulator's own metric",
            "simple (kept by the simulator)",
            f"{res.metrics['vanishing_point_error_px']}",
            f"{res.metrics['horizon_angle_error_deg']}",
        )
    ]
    for method in ("lsd", "simple"):
        seg, det = _vp(img, method)
        if det is None:
            rows.append((label, method, "none", "none"))
            continue
        vps = [v / v[2] for v in det.vanishing_points if v[2] != 0]
        best = min(vps, key=lambda v: float(np.hypot(*(v[:2] - truth[:2]))))
        e = vanishing_errors(
            VanishingTruth(res.vanishing.vanishing_point, res.vanishing.horizon, best, det.horizon)
        )
        rows.append(
            (
                f"{label} ({len(seg)} segments)",
                method,
                f"{e['vanishing_point_error_px']:.2f}"
                if e["vanishing_point_error_px"] is not None
                else "-",
                f"{e['horizon_angle_error_deg']:.2f}"
                if e["horizon_angle_error_deg"] is not None
                else "-",
            )
        )
    return rows


def kodak() -> list[tuple[object, ...]]:
    from PIL import Image

    rows = []
    for name in ("kodim01", "kodim08", "kodim16", "kodim19", "kodim22", "kodim24"):
        img = np.asarray(Image.open(DATA / f"{name}.png").convert("RGB"))
        for method in ("lsd", "simple"):
            seg, res = _vp(img, method)
            if res is None:
                rows.append((name, method, len(seg), "-", "-", "-", "-"))
                continue
            f = f"{res.K[0, 0]:.0f}" if res.K is not None else "-"
            c = f"({res.K[0, 2]:.0f}, {res.K[1, 2]:.0f})" if res.K is not None else "-"
            tilt = (
                f"{math.degrees(math.atan2(-res.horizon[0], res.horizon[1])):+.2f}"
                if res.horizon is not None
                else "-"
            )
            rows.append((name, method, len(seg), res.perspective, f, c, tilt))
    return rows


def main() -> None:
    print(header("Vanishing points from LSD segments vs the earlier detector"))
    print("## Manhattan renders, f = 700 px, 768 x 512\n")
    print(
        markdown_table(
            (
                "pitch,yaw,roll (rad)",
                "segments",
                "n",
                "f error",
                "pp error px",
                "horizon error px (centre)",
                "worst VP direction error deg",
            ),
            renders(),
        )
    )
    print("## imageform simulate, built-in scene (rails)\n")
    print(
        markdown_table(("scene", "segments", "VP error px", "horizon angle error deg"), simulated())
    )
    print("## Kodak photographs (no ground truth)\n")
    print(
        markdown_table(
            ("image", "segments", "n", "perspective", "f px", "centre", "horizon tilt deg"), kodak()
        )
    )


if __name__ == "__main__":
    main()
