"""CPU time and minor page faults of each stage of ``develop(read_raw(p)).to_integer(16)``.

For ``benchmarks/results/raw-2026-11-28b.md``: the stages of this checkout (reading, the checks
and matrices, the fused pass) or, run with ``PYTHONPATH`` on a checkout before the fused pass
(commit 223b51e), its six stages (white balance, mirror padding, bilinear demosaicing, matrix
and sRGB, rounding). ``time.process_time`` (user + system) and ``ru_minflt`` around each stage,
medians of ``n`` calls, after a warm-up. The DNG is one of ``bench_raw.py``'s.

    NUMBA_NUM_THREADS=1 OMP_NUM_THREADS=1 python benchmarks/profile_raw.py FILE.dng [n]
"""

from __future__ import annotations

import resource
import statistics
import sys
import time
from collections.abc import Callable
from typing import Any

import numba
import numpy as np


def measure(fn: Callable[[], Any], n: int) -> tuple[float, int, float]:
    """Median CPU seconds, minor page faults and wall seconds of ``fn()``."""
    cpu, faults, wall = [], [], []
    for _ in range(n):
        r0 = resource.getrusage(resource.RUSAGE_SELF)
        c0, w0 = time.process_time(), time.perf_counter()
        out = fn()
        c1, w1 = time.process_time(), time.perf_counter()
        r1 = resource.getrusage(resource.RUSAGE_SELF)
        cpu.append(c1 - c0)
        faults.append(r1.ru_minflt - r0.ru_minflt)
        wall.append(w1 - w0)
        del out
    return statistics.median(cpu), int(statistics.median(faults)), statistics.median(wall)


def main() -> None:
    import imageform._kernels.raw_develop as kern
    from imageform.io import develop, read_raw
    from imageform.io import raw as raw_module

    path, n = sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 5
    develop(read_raw(path)).to_integer(16)  # compiled and loaded
    raw = read_raw(path)
    dev = develop(raw)
    rows = [("read_raw (LibRaw unpack, copy, DNG tags)", measure(lambda: read_raw(path), n))]
    if hasattr(kern, "develop_rows"):
        rows.append(("develop() (checks, matrices, table)", measure(lambda: develop(raw), n)))
        rows.append(("fused pass to uint16", measure(lambda: dev._fused(kern.MODE_UINT16), n)))
        rows.append(("fused pass to float32", measure(lambda: dev._fused(kern.MODE_FLOAT), n)))
    else:  # before the fused pass: its stages one by one
        import imageform._kernels.demosaic_bilinear as bil

        black = np.asarray(raw.black_level, np.float32)
        idx = np.array(raw_module._cfa_indices(str(raw.cfa_pattern))).reshape(2, 2)
        span = raw.white_level - np.asarray(raw.black_level, np.float64)
        scale = (dev.gains[idx] / span).astype(np.float32)
        h, w = raw.mosaic.shape

        def balance() -> np.ndarray:
            out = np.empty(raw.mosaic.shape, np.float32)
            kern.balance_mosaic(raw.mosaic, black, scale, out)  # type: ignore[attr-defined]
            return out

        balanced = balance()
        padded = np.pad(balanced, ((2, 2), (2, 2)), mode="reflect")
        cam = bil.bilinear_numba(padded, 2, 2, h, w)
        lut = raw_module._transfer_table("srgb")
        eye = np.eye(3, dtype=np.float32)

        def render() -> np.ndarray:
            out = np.empty(cam.shape, np.float32)
            kern.render_rows(0, cam.shape[0], cam, eye, lut, True, out)
            return out

        image = render()

        def quantize() -> np.ndarray:
            out = np.empty(image.shape, np.uint16)
            kern.quantize(image.reshape(-1), np.float32(65535), out.reshape(-1))
            return out

        pad = ((2, 2), (2, 2))
        threads = numba.get_num_threads()
        rows += [
            ("levels and white balance", measure(balance, n)),
            ("mirror padding (np.pad)", measure(lambda: np.pad(balanced, pad, mode="reflect"), n)),
            (
                f"bilinear demosaicing ({threads} threads)",
                measure(lambda: bil.bilinear_numba(padded, 2, 2, h, w), n),
            ),
            ("matrix, clipping, sRGB table", measure(render, n)),
            ("rounding to uint16", measure(quantize, n)),
        ]
    rows.append(("whole call", measure(lambda: develop(read_raw(path)).to_integer(16), n)))
    print(f"{'stage':42s} {'CPU ms':>8s} {'wall ms':>8s} {'minflt':>8s}")
    for name, (cpu, faults, wall) in rows:
        print(f"{name:42s} {cpu * 1000:8.1f} {wall * 1000:8.1f} {faults:8d}")


if __name__ == "__main__":
    main()
