"""numba's cache of imageform's kernels: one decorator policy, and a deterministic location.

``imageform._kernels.jit``: every kernel is cached; where the package folder cannot be written
(a wheel installed read-only, system-wide) and ``NUMBA_CACHE_DIR`` is not set, the cache is
the user's cache folder (``$XDG_CACHE_HOME/imageform/numba``), so the second process loads
what the first compiled. Each check runs in fresh interpreters (subprocesses).
"""

from __future__ import annotations

import importlib
import json
import os
import pkgutil
import shutil
import stat
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import imageform._kernels as kernels_pkg
from imageform._kernels import jit

SRC = Path(__file__).resolve().parents[1] / "src"


def _kernels() -> list[tuple[str, Any]]:
    """``("module.name", dispatcher)`` for every numba dispatcher defined in imageform._kernels."""
    from numba.core.registry import CPUDispatcher

    out = []
    for info in pkgutil.iter_modules(kernels_pkg.__path__):
        module = importlib.import_module(f"imageform._kernels.{info.name}")
        for name, value in vars(module).items():
            if isinstance(value, CPUDispatcher) and value.__module__ == module.__name__:
                out.append((f"{info.name}.{name}", value))
    return out


def test_every_kernel_is_cached() -> None:
    """The one policy: every numba dispatcher of imageform._kernels caches (cache=True)."""
    from numba.core.caching import NullCache

    kernels = _kernels()
    assert len(kernels) > 90
    assert [n for n, k in kernels if isinstance(k._cache, NullCache)] == []


def test_no_two_kernels_share_cache_files() -> None:
    """Each dispatcher has cache files of its own.

    numba names them after the function's qualified name and first line and keys their
    entries on signature, bytecode and closed-over values, not on ``parallel``: a serial
    twin made with ``njit(...)(kernel.py_func)`` shared the parallel kernel's entries, and
    whichever compiled first was loaded for both (the parallel remap ran on one thread).
    """
    owner: dict[str, str] = {}
    clashes = []
    for label, kernel in _kernels():
        cache = kernel._cache
        if not hasattr(cache, "_cache_file") or kernel.py_func.__closure__:
            continue  # closures: the entries' keys hold the closed-over values
        index = cache._cache_file._index_name
        if index in owner and owner[index] != label:
            clashes.append((owner[index], label, index))
        owner.setdefault(index, label)
    assert len(owner) > 90
    assert clashes == []


def _python(code: str, env: dict[str, str]) -> str:
    """Run ``code`` in a fresh interpreter with ``env``; its stdout (a failure shows stderr)."""
    done = subprocess.run(
        [sys.executable, "-c", code], env=env, timeout=600, capture_output=True, text=True
    )
    assert done.returncode == 0, done.stdout + done.stderr[-2000:]
    return done.stdout


def test_serial_twin_is_its_own_kernel() -> None:
    from numba import prange

    @jit.njit(parallel=True, cache=False)
    def total(a):  # type: ignore[no-untyped-def]
        s = 0.0
        for i in prange(a.size):
            s += a[i]
        return s

    twin = jit.serial_twin(total, cache=False)
    assert twin.py_func is not total.py_func
    assert twin.py_func.__qualname__.endswith("total_serial")
    assert not twin.targetoptions.get("parallel") and total.targetoptions.get("parallel")
    assert twin(np.arange(10.0)) == total(np.arange(10.0)) == 45.0


def test_serial_first_cache_keeps_the_parallel_kernel_parallel(tmp_path: Path) -> None:
    """Fill a fresh cache with the serial remap first; the parallel one, loaded from that
    cache in a new process, still runs its rows on numba's threads (its code calls the
    parallel scheduler)."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path), "PYTHONPATH": str(SRC)}
    env.pop("NUMBA_BOUNDSCHECK", None)
    setup = (
        "import numpy as np\n"
        "from imageform._kernels import remap as R\n"
        "img = np.zeros((1, 8, 8, 1), np.uint8); m = np.zeros((8, 8, 2), np.float32)\n"
        "out = np.empty_like(img); a = np.empty(0, np.float32); k = np.empty(0, np.int32)\n"
    )
    _python(setup + "R.remap_bilinear_serial(img, m, 1.0, 0.0, out, a, k, 255.0)\n", env)
    second = setup + (
        "R.remap_bilinear(img, m, 1.0, 0.0, out, a, k, 255.0)\n"
        "(cres,) = R.remap_bilinear.overloads.values()\n"
        "print(sum(R.remap_bilinear.stats.cache_hits.values()),"
        " 'do_scheduling' in cres.library.get_llvm_str())\n"
    )
    assert _python(second, env).split() == ["0", "True"]


def test_boundscheck_compiles_are_not_cached(tmp_path: Path) -> None:
    """numba's cache key has no bounds-check flag: under NUMBA_BOUNDSCHECK=1 nothing is saved
    (checked code in the shared cache would slow every later run)."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path), "PYTHONPATH": str(SRC)}
    env["NUMBA_BOUNDSCHECK"] = "1"
    code = (
        "from imageform._kernels import jit\n"
        "from numba.core.caching import NullCache\n"
        "f = jit.njit(lambda x: x + 1)\n"
        "print(isinstance(f._cache, NullCache), f(1))\n"
    )
    assert _python(code, env).split() == ["True", "2"]


def test_kernels_use_the_policy_decorator() -> None:
    """No kernel module calls numba.njit / numba.jit itself (one policy, in jit.py)."""
    for path in Path(kernels_pkg.__path__[0]).glob("*.py"):
        if path.name == "jit.py":
            continue
        text = path.read_text()
        for bad in ("nb.njit", "numba.njit", "from numba import njit", "nb.jit(", "@jit"):
            assert bad not in text, f"{path.name} uses {bad}: use imageform._kernels.jit.njit"


def test_njit_defaults_and_overrides() -> None:
    @jit.njit
    def one(x):  # type: ignore[no-untyped-def]
        return x + 1

    @jit.njit(cache=False, error_model="numpy")
    def two(x):  # type: ignore[no-untyped-def]
        return x + 2

    from numba.core.caching import NullCache

    assert not isinstance(one._cache, NullCache) and one(1) == 2
    assert isinstance(two._cache, NullCache) and two(1) == 3


@pytest.mark.skipif(sys.platform in ("win32", "darwin"), reason="XDG layout: Linux and BSD")
def test_user_cache_dir_follows_xdg(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert jit.user_cache_dir() == tmp_path / "imageform" / "numba"
    monkeypatch.setenv("XDG_CACHE_HOME", "relative/ignored")  # the spec: absolute paths only
    assert jit.user_cache_dir() == Path.home() / ".cache" / "imageform" / "numba"
    monkeypatch.delenv("XDG_CACHE_HOME")
    assert jit.user_cache_dir() == Path.home() / ".cache" / "imageform" / "numba"


_PROBE = r"""
import json, os, sys
from imageform._kernels.jit import cache_location, njit
import numba

@njit
def probe(x):
    return x * 2.0 + 1.0

value = probe(1.5)
where, reason = cache_location()
print(json.dumps({"value": value, "where": str(where), "reason": reason,
                  "numba": numba.config.CACHE_DIR, "env": os.environ.get("NUMBA_CACHE_DIR"),
                  "hits": sum(probe.stats.cache_hits.values()),
                  "misses": sum(probe.stats.cache_misses.values())}))
"""


def _read_only_copy(tmp_path: Path) -> Path:
    """A copy of imageform whose folders cannot be written (as an installed wheel, chmod
    a-w); the probe script lives in it too, so that numba's in-tree cache is ruled out."""
    site = tmp_path / "site"
    shutil.copytree(
        SRC / "imageform", site / "imageform", ignore=shutil.ignore_patterns("__pycache__")
    )
    (site / "probe_kernel.py").write_text(_PROBE)
    # where numba's in-tree cache would go, a plain file: no one, root included, can make
    # the folder there (root writes through chmod a-w, and a checkout or a virtual
    # environment under a private folder cannot be read by another user)
    for folder in (site, site / "imageform" / "_kernels"):
        (folder / "__pycache__").write_text("not a folder\n")
    for root, _dirs, files in os.walk(site):
        for name in files:
            p = Path(root) / name
            p.chmod(p.stat().st_mode & ~(stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH))
        Path(root).chmod(0o555)
    return site


def test_read_only_package_caches_in_the_user_cache() -> None:
    # not pytest's tmp_path: its parents are private to the user running the tests
    tmp_path = Path(tempfile.mkdtemp(prefix="imageform-ro-"))
    tmp_path.chmod(0o755)
    site = _read_only_copy(tmp_path)
    home = tmp_path / "home"
    home.mkdir()
    home.chmod(0o777)
    env = {k: v for k, v in os.environ.items() if not k.startswith(("NUMBA_", "_IMAGEFORM"))}
    env.update(PYTHONPATH=str(site), HOME=str(home), XDG_CACHE_HOME=str(home / "cache"))
    runs = []
    try:
        for _ in range(2):
            done = subprocess.run(
                [sys.executable, str(site / "probe_kernel.py")],
                env=env,
                capture_output=True,
                text=True,
                check=False,
                cwd=home,
            )
            assert done.returncode == 0, done.stderr[-2000:]
            runs.append(json.loads(done.stdout))
        expected = str(home / "cache" / "imageform" / "numba")
        first, second = runs
        assert first["value"] == second["value"] == 4.0
        assert first["reason"] == "user" and first["where"] == expected
        assert first["numba"] == first["env"] == expected
        assert (first["misses"], first["hits"]) == (1, 0)
        assert (second["misses"], second["hits"]) == (0, 1), "the second process compiled again"
        cached = list(Path(expected).rglob("probe_kernel.probe-*.nbi"))
        assert len(cached) == 1
        assert not list(site.rglob("*.nbi")), "nothing is written beside the read-only source"
        assert (site / "imageform" / "_kernels" / "__pycache__").is_file()
    finally:
        for root, _, _ in os.walk(site):
            Path(root).chmod(0o755)
        shutil.rmtree(tmp_path, ignore_errors=True)


def test_numba_cache_dir_wins(tmp_path: Path) -> None:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("NUMBA_", "_IMAGEFORM"))}
    env.update(PYTHONPATH=str(SRC), NUMBA_CACHE_DIR=str(tmp_path / "mine"), MPLBACKEND="Agg")
    done = subprocess.run(
        [sys.executable, "-m", "imageform", "cache", "--json"],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    out = json.loads(done.stdout)
    assert out["cache_dir"] == str(tmp_path / "mine") and out["reason"] == "NUMBA_CACHE_DIR"
    assert out["files"] == 0


def test_cache_clear_removes_only_imageforms_kernels(tmp_path: Path) -> None:
    import hashlib

    src = os.path.abspath(os.path.dirname(jit.__file__))
    ours = tmp_path / "_".join([os.path.basename(src), hashlib.sha1(src.encode()).hexdigest()])
    other = tmp_path / "elsewhere_0123"
    for folder in (ours, other):
        folder.mkdir()
        (folder / "k.f-1.py311.nbi").write_bytes(b"x")
        (folder / "k.f-1.py311.1.nbc").write_bytes(b"yy")
    env = {k: v for k, v in os.environ.items() if not k.startswith(("NUMBA_", "_IMAGEFORM"))}
    env.update(PYTHONPATH=str(SRC), NUMBA_CACHE_DIR=str(tmp_path))
    argv = [sys.executable, "-m", "imageform", "cache", "--json"]
    listed = json.loads(subprocess.run(argv, env=env, capture_output=True, check=True).stdout)
    assert (listed["files"], listed["bytes"]) == (2, 3)
    done = subprocess.run([*argv, "--clear"], env=env, capture_output=True, check=True)
    cleared = json.loads(done.stdout)
    assert (cleared["removed"], cleared["files"]) == (2, 0)
    assert not list(ours.iterdir()) and len(list(other.iterdir())) == 2


def test_warm_runs_each_command_and_reports_failures(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    from imageform.cli import _cache

    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("PYTHONPATH", str(SRC))
    monkeypatch.setattr(_cache, "_jobs", lambda work: [["--version"], ["no-such-command"]])
    done = _cache.warm_cache(jobs=2)
    assert sorted(name for name, _, _ in done) == ["--version", "no-such-command"]
    errors = {name: why for name, _, why in done}
    assert errors["--version"] == ""
    assert "no-such-command" in errors["no-such-command"]
