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
    argv = [
        "bench_gpu.py",
        "--device",
        "cpu",
        "--size",
        "16x24",
        "--points",
        "1000",
        "--chunk",
        "500",
        "--repeat",
        "1",
        "--note",
        "tiny",
        "--out",
        str(out),
    ]
    monkeypatch.setattr(sys, "argv", argv)
    bench_gpu.main()
    text = out.read_text()
    rows = [r.split(" | ")[1] for r in text.splitlines() if r.startswith("| ") and "ms" not in r]
    assert rows.count("imageform") == 3 and rows.count("kornia") == 2  # Lab, ΔE00, projection
    assert {"imageform bilinear", "imageform malvar", "kornia bilinear"} <= set(rows)
    assert "projection 1.0e+03 pts (2 x 5.0e+02)" in text and "tiny" in text
