"""How much memory a simulation needs, known before anything is allocated.

The simulator keeps every stage (eight images of ``(H, W, 3)`` float32 and the raw mosaic)
beside the renderer's float64 maps (electron rate, depth, vignetting, object index), the
lens's blurred layers and the demosaicing and colour steps' float64 intermediates; the
report then encodes each stage as a PNG. Measured with ``/usr/bin/time -v`` (maximum
resident set) on the built-in scene at 1280x720 and 2560x1440, ``imageform simulate``
grows by 370-400 bytes per pixel over a fixed ~0.4 GB (Python, NumPy, numba, matplotlib);
the render's supersampling changes the time (S² rays per pixel), not the memory (rays are
cast in bands of rows). :data:`BYTES_PER_PIXEL` rounds that up.

:func:`imageform.simulate.load_scene` refuses a scene whose image would not fit in the
memory this machine has available (:func:`available_memory_bytes`), naming the key and
the estimate, instead of failing later with a ``MemoryError``.
"""

from __future__ import annotations

import os
from pathlib import Path

from imageform._validate import as_int, as_real

__all__ = [
    "BYTES_PER_PIXEL",
    "available_memory_bytes",
    "estimate_memory_bytes",
    "format_bytes",
]

#: Memory one simulated pixel costs, stages and report included (measured 370-400, rounded up).
BYTES_PER_PIXEL = 450


def estimate_memory_bytes(width: int, height: int) -> int:
    """Estimate the memory (bytes) simulating and reporting a ``width`` x ``height`` image needs.

    That is on top of the loaded libraries: :data:`BYTES_PER_PIXEL` per pixel.

    Examples
    --------
    >>> estimate_memory_bytes(1280, 720) / 1e9
    0.41472
    """
    w = as_int(width, "width", minimum=0)
    h = as_int(height, "height", minimum=0)
    return w * h * BYTES_PER_PIXEL


def _meminfo_available(path: Path = Path("/proc/meminfo")) -> int | None:
    try:
        for line in path.read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024  # kB
    except (OSError, ValueError, IndexError):
        return None
    return None


def _cgroup_available(root: Path = Path("/sys/fs/cgroup")) -> int | None:
    """Return what a cgroup v2 memory limit leaves (None without a limit)."""
    try:
        limit = (root / "memory.max").read_text().strip()
        if limit == "max":
            return None
        used = int((root / "memory.current").read_text().strip())
        return max(int(limit) - used, 0)
    except (OSError, ValueError):
        return None


def available_memory_bytes() -> int | None:
    """Return the memory this process can still use (bytes).

    The smaller of the system's available memory (Linux ``MemAvailable``; elsewhere the physical
    memory) and what a cgroup v2 limit leaves; ``None`` when neither can be read (then no scene is
    refused for its size).
    """
    found = [v for v in (_meminfo_available(), _cgroup_available()) if v is not None]
    if not found:
        try:
            found = [os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")]
        except (AttributeError, ValueError, OSError):
            return None
    return min(found)


def format_bytes(n: float) -> str:
    """``n`` bytes in the largest unit that keeps a number >= 1 (decimal units).

    Examples
    --------
    >>> format_bytes(414_720_000), format_bytes(2.5e12)
    ('415 MB', '2500 GB')
    """
    n = as_real(n, "n", nonnegative=True)
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}" if n / scale < 1000 else f"{n / scale:.0f} {unit}"
    return f"{n:.0f} B"
