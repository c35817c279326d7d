"""Smoke test of benchmarks/bench_gpu.py on tiny inputs (CPU): every row is produced."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest


def test_bench_gpu_runs_tiny(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    pytest.importorskip("torch")
    pytest.importorskip("kornia")
    from benchmarks import bench_gpu

    out = tmp_path / "gpu.md"
    argv = ["bench_gpu.py", "--device", "cpu", "--smoke", "--note", "tiny", "--out", str(out)]
    monkeypatch.setattr(sys, "argv", argv)
    bench_gpu.main()
    text = out.read_text()
    rows = [r.split(" | ") for r in text.splitlines() if r.startswith("| ") and "ms" not in r]
    for dtype in ("float32", "float64"):
        impls = [r[2] for r in rows if r[1] == dtype]
        # Lab, ΔE00, 9 more colour calls, remap, projection, projection + distortion,
        # distort, undistort, undistort image; Lab, 3 colour calls, remap, projection and
        # the four geometry rows for kornia; the Array-API path of the 11 colour calls
        assert impls.count("imageform") == 17 and impls.count("kornia") == 10
        assert impls.count("imageform array-API") == 11
        assert {"imageform bilinear", "imageform malvar", "kornia bilinear"} <= set(impls)
    kernels = {(r[0].removeprefix("| ").split()[0], r[1], r[2]): int(r[8]) for r in rows}
    assert 0 < kernels[("sRGB→Lab", "float32", "imageform")] < 40  # counted per call
    assert "projection 1.0e+03 pts (2 x 5.0e+02)" in text and "tiny" in text
    assert "projection + distortion" in text and "undistort image 16x24" in text
    assert "failed:" not in text
