"""Projection of a large point cloud: imageform vs cv2.projectPoints vs a NumPy matrix product.

Issue 2's target: 10^7 points through a Camera at least 5x faster than cv2.projectPoints,
agreeing to 1e-9 px. Run::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_geometry.py [--n 10000000] [--repeat 5]

Prints a Markdown table (median seconds, ratio to OpenCV, max |Δuv| against a float64
NumPy reference that divides exactly); commit it under benchmarks/results/.
"""

from __future__ import annotations

import argparse

import numpy as np

from benchmarks._common import header, markdown_table, median_time


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=10_000_000)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()

    import cv2

    from imageform.geometry import Camera, intrinsic_matrix, rvec_to_matrix

    rng = np.random.default_rng(0)
    X = rng.uniform(-1.0, 1.0, size=(args.n, 3))
    X[:, 2] += 4.0
    K = intrinsic_matrix(800.0, 810.0, 640.0, 360.0)
    rvec = np.array([0.1, -0.2, 0.05])
    R = rvec_to_matrix(rvec)
    t = np.array([0.1, 0.2, 0.3])
    cam = Camera(K, R, t)

    def reference() -> np.ndarray:
        Xc = X @ R.T + t
        return np.stack(
            (K[0, 0] * Xc[:, 0] / Xc[:, 2] + K[0, 2], K[1, 1] * Xc[:, 1] / Xc[:, 2] + K[1, 2]),
            axis=-1,
        )

    def numpy_matmul() -> np.ndarray:
        h = X @ (K @ R).T + K @ t
        return h[:, :2] / h[:, 2:]

    ref = reference()
    results = {}
    runs = {
        "imageform Camera.project (numba)": lambda: cam.project(X),
        "cv2.projectPoints": lambda: cv2.projectPoints(X, rvec, t, K, None),
        "NumPy matmul (P X, no z check)": numpy_matmul,
    }
    outputs = {
        "imageform Camera.project (numba)": cam.project(X).uv,
        "cv2.projectPoints": cv2.projectPoints(X, rvec, t, K, None)[0][:, 0],
        "NumPy matmul (P X, no z check)": numpy_matmul(),
    }
    for name, fn in runs.items():
        results[name] = median_time(fn, repeat=args.repeat, warmup=1)
    cv = results["cv2.projectPoints"]
    rows = []
    for name, sec in results.items():
        err = float(np.max(np.abs(outputs[name] - ref)))
        rows.append([name, f"{sec * 1e3:.1f}", f"{cv / sec:.1f}x", f"{err:.2e}"])
    print(header(f"Projection of {args.n:.0e} points (float64), median of {args.repeat}"))
    print(
        markdown_table(["method", "ms", "speed-up vs OpenCV", "max |Δuv| px vs float64 ref"], rows)
    )


if __name__ == "__main__":
    main()
