"""``import imageform`` is lazy (PEP 562): cheap to import, every subpackage one attribute away.

Each check runs in a fresh interpreter (a subprocess), where nothing is imported yet.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import pytest

import imageform

SRC = Path(__file__).resolve().parents[1] / "src"

#: Modules a bare ``import imageform`` must not load.
HEAVY = ("numpy", "scipy", "numba", "matplotlib", "dask", "PIL", "tifffile", "typer", "rich")


def _env() -> dict[str, str]:
    # this checkout's imageform first; one BLAS thread so that timings are comparable
    path = os.pathsep.join(p for p in (str(SRC), os.environ.get("PYTHONPATH", "")) if p)
    return {**os.environ, "PYTHONPATH": path, "OPENBLAS_NUM_THREADS": "1"}


def _python(code: str) -> str:
    done = subprocess.run(
        [sys.executable, "-c", code], env=_env(), capture_output=True, text=True, check=False
    )
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_bare_import_loads_nothing_heavy() -> None:
    out = json.loads(
        _python(
            "import json, sys\n"
            "import imageform\n"
            f"loaded = [m for m in {HEAVY!r} if m in sys.modules]\n"
            "convert = imageform.color.convert\n"
            "rgb = convert([1.0, 0.5, 0.0], 'srgb', 'hsv').round(6).tolist()\n"
            "print(json.dumps({'loaded': loaded, 'convert': convert.__module__, 'hsv': rgb,\n"
            "                  'version': imageform.__version__,\n"
            "                  'error': imageform.InvalidInputError.__module__}))\n"
        )
    )
    assert out["loaded"] == [], f"import imageform loaded {out['loaded']}"
    # the subpackage is one attribute away after a bare import, and works
    assert out["convert"] == "imageform.color.convert"
    assert out["hsv"] == [30.0, 1.0, 1.0]
    assert out["version"] == imageform.__version__
    assert out["error"] == "imageform.errors"


def test_every_subpackage_is_an_attribute() -> None:
    on_disk = {
        p.name
        for p in (SRC / "imageform").iterdir()
        if (p / "__init__.py").is_file() and not p.name.startswith("_")
    }
    subpackages = set(imageform._SUBPACKAGES)
    assert subpackages == on_disk, "imageform._SUBPACKAGES must list every public subpackage"
    assert subpackages <= set(imageform.__all__)
    assert subpackages <= set(dir(imageform))
    for name in sorted(subpackages - {"cli", "batch"}):  # front ends: exercised elsewhere
        assert getattr(imageform, name).__name__ == f"imageform.{name}"
    with pytest.raises(AttributeError, match="no attribute 'colour'"):
        _ = imageform.colour  # type: ignore[attr-defined]


def test_library_subpackages_import_without_scipy_numba_matplotlib() -> None:
    """scipy, numba and matplotlib load when a function needs them, not on import."""
    packages = ["spectral", "color", "geometry", "optics", "sensor", "io", "analysis"]
    out = json.loads(
        _python(
            "import importlib, json, sys\n"
            "first = {}\n"
            f"for p in {packages!r}:\n"
            "    importlib.import_module('imageform.' + p)\n"
            "    for m in ('scipy', 'numba', 'matplotlib'):\n"
            "        if m in sys.modules:\n"
            "            first.setdefault(m, p)\n"
            "print(json.dumps(first))\n"
        )
    )
    assert out == {}, f"imported on import (module: first subpackage to load it): {out}"


def _median_import_seconds(statement: str, runs: int) -> float:
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", statement], env=_env(), check=True)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def test_import_costs_less_than_numpy() -> None:
    """``python -c "import imageform"`` takes at most 1.5x ``python -c "import numpy"``
    (median of 5 runs each; the interpreter's own start is in both)."""
    numpy_s = _median_import_seconds("import numpy", 5)
    imageform_s = _median_import_seconds("import imageform", 5)
    assert imageform_s <= 1.5 * numpy_s, (
        f"import imageform: {imageform_s * 1e3:.0f} ms, import numpy: {numpy_s * 1e3:.0f} ms"
    )


def test_help_imports_no_numerical_code() -> None:
    """``imageform --help`` and ``imageform COMMAND --help`` load the command definitions
    only: no NumPy, SciPy, numba or plotting (issue 19: help under 0.5 s)."""
    out = json.loads(
        _python(
            "import contextlib, io, json, sys\n"
            "from imageform.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()) as text:\n"
            "    codes = [main(['--help']), main(['simulate', '--help']),"
            " main(['batch', '--help'])]\n"
            f"loaded = [m for m in {HEAVY!r} if m in sys.modules]\n"
            "print(json.dumps({'codes': codes, 'loaded': loaded,"
            " 'help': text.getvalue()[:200]}))\n"
        )
    )
    assert out["codes"] == [0, 0, 0]
    assert "Usage: imageform" in out["help"]
    assert out["loaded"] == [], f"imageform --help loaded {out['loaded']}"


def test_help_is_quick() -> None:
    """``imageform --help`` takes under 0.5 s (issue 19), or, on a loaded machine, at most 4x
    ``import numpy`` measured in the same run (median of 5 each). Measured in a fresh CI
    clone: 446 ms against 129 ms for ``import numpy``."""
    numpy_s = _median_import_seconds("import numpy", 5)
    help_s = _median_import_seconds(
        "import contextlib, io\n"
        "from imageform.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    main(['--help'])",
        5,
    )
    assert help_s <= 0.5 or help_s <= 4.0 * numpy_s, (
        f"imageform --help: {help_s * 1e3:.0f} ms, import numpy: {numpy_s * 1e3:.0f} ms"
    )
