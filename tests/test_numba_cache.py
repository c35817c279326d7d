"""numba's cache of imageform's kernels: one decorator policy, and a deterministic location.

``imageform._kernels.jit``: every kernel is cached; where the package folder cannot be written
(a wheel installed read-only, system-wide) and ``NUMBA_CACHE_DIR`` is not set, the cache is
the user's cache folder (``$XDG_CACHE_HOME/imageform/numba``), so the second process loads
what the first compiled. Each check runs in fresh interpreters (subprocesses).
"""

from __future__ import annotations

import importlib
import importlib.util
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
            value = value.dispatcher if isinstance(value, jit.Deferred) else value
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


def test_run_tasks_cuts_the_tasks_over_the_threads() -> None:
    """jit.run_tasks: every task once, one contiguous run per thread (the caller's first);
    threads=1 runs them all in the calling thread."""
    import threading

    seen: list[tuple[int, int, int]] = []

    def kernel(t0: int, t1: int, tag: str) -> None:
        assert tag == "x"
        seen.append((t0, t1, threading.get_ident()))

    jit.run_tasks(kernel, 10, "x", threads=3)
    assert sorted((a, b) for a, b, _ in seen) == [(0, 3), (3, 6), (6, 10)]
    assert next(i for a, _, i in seen if a == 0) == threading.get_ident()
    assert len({i for _, _, i in seen}) >= 2  # the caller and the pool (a worker may run two)
    seen.clear()
    jit.run_tasks(kernel, 10, "x", threads=1)
    assert seen == [(0, 10, threading.get_ident())]
    seen.clear()
    jit.run_tasks(kernel, 0, "x", threads=4)
    assert seen == []


def test_run_tasks_compiles_in_the_calling_thread_only() -> None:
    """A kernel's first run through jit.run_tasks compiles in the calling thread, never in a
    worker (a Ctrl-C in the caller's compilation while a worker compiled hung the command)."""
    import threading

    from numba.core import event

    @jit.njit(nogil=True, cache=False)
    def kernel(t0, t1, out):  # type: ignore[no-untyped-def]
        for t in range(t0, t1):
            out[t] = 2.0 * t

    where: list[int] = []

    class Seen(event.Listener):
        def on_start(self, e: Any) -> None:
            where.append(threading.get_ident())

        def on_end(self, e: Any) -> None:
            pass

    out = np.zeros(8)
    with event.install_listener("numba:compile", Seen()):
        jit.run_tasks(kernel, 8, out, threads=4)
    assert where and set(where) == {threading.get_ident()}
    assert out.tolist() == [2.0 * t for t in range(8)]


def test_small_and_large_remaps_share_one_compiled_kernel() -> None:
    """The remap in the calling thread (small images) and on numba's threads is one kernel:
    one compilation, where a serial twin and a parallel=True kernel were two."""
    from imageform._kernels import remap as R

    img = np.arange(64, dtype=np.uint8).reshape(1, 8, 8, 1)
    m = np.stack(np.meshgrid(np.arange(8.0), np.arange(8.0)), axis=-1).astype(np.float32)
    outs = []

    def compiled() -> set[object]:  # one-channel images have a kernel of their own
        return {*R._remap_tasks.signatures, *R._remap_grey_tasks.signatures}

    before = compiled()  # other tests may have compiled other dtypes
    for run in (R.remap_bilinear_serial, R.remap_bilinear):
        out = np.zeros_like(img)
        run(img, m, 1.0, 0.0, out, np.empty(0, np.float32), np.empty(0, np.int32), 255.0)
        outs.append(out)
    np.testing.assert_array_equal(outs[0], img)
    np.testing.assert_array_equal(outs[1], img)
    # the small and the large call added at most one compilation (none if already there)
    assert len(compiled() - before) <= 1


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


def _read_only_copy(tmp_path: Path) -> Path:
    """A copy of imageform whose folders cannot be written (as an installed wheel, chmod
    a-w)."""
    site = tmp_path / "site"
    shutil.copytree(
        SRC / "imageform", site / "imageform", ignore=shutil.ignore_patterns("__pycache__")
    )
    # where numba's in-tree cache would go, a plain file: no one, root included, can make
    # the folder there (root writes through chmod a-w, and a checkout or a virtual
    # environment under a private folder cannot be read by another user)
    (site / "imageform" / "_kernels" / "__pycache__").write_text("not a folder\n")
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
    try:
        first, second = (json.loads(_python(_SHARED_PROBE, env)) for _ in range(2))
        expected = home / "cache" / "imageform" / "numba"
        assert Path(first["where"]).parent == expected
        assert (first["misses"], first["hits"]) == (1, 0)
        assert (second["misses"], second["hits"]) == (0, 1), "the second process compiled again"
        assert len(list(expected.rglob("color_simple._hsv_serial-*.nbi"))) == 1
        assert not list(site.rglob("*.nbi")), "nothing is written beside the read-only source"
        assert (site / "imageform" / "_kernels" / "__pycache__").is_file()
    finally:
        for root, _, _ in os.walk(site):
            Path(root).chmod(0o755)
        shutil.rmtree(tmp_path, ignore_errors=True)


def _cache_json(env: dict[str, str], *args: str) -> dict[str, Any]:
    argv = [sys.executable, "-m", "imageform", "cache", "--json", *args]
    done = subprocess.run(argv, env=env, capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    out: dict[str, Any] = json.loads(done.stdout)
    return out


def test_numba_cache_dir_wins(tmp_path: Path) -> None:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("NUMBA_", "_IMAGEFORM"))}
    env.update(PYTHONPATH=str(SRC), NUMBA_CACHE_DIR=str(tmp_path / "mine"), MPLBACKEND="Agg")
    out = _cache_json(env)
    assert Path(out["cache_dir"]).parent == tmp_path / "mine"
    assert out["reason"] == "NUMBA_CACHE_DIR" and out["files"] == 0


def test_cache_clear_removes_only_imageforms_kernels(tmp_path: Path) -> None:
    """--clear empties this version's folder and removes imageform's stale ones (another
    version, edited kernels); other numba caches under the same root stay."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("NUMBA_", "_IMAGEFORM"))}
    env.update(PYTHONPATH=str(SRC), NUMBA_CACHE_DIR=str(tmp_path))
    ours = Path(_cache_json(env)["cache_dir"])
    stale = tmp_path / "imageform-0.0.1-0123456789abcdef0123"
    other = tmp_path / "elsewhere_0123"
    for folder in (ours, stale, other):
        folder.mkdir(exist_ok=True)
        (folder / "k.f-1.py311.nbi").write_bytes(b"x")
        (folder / "k.f-1.py311.1.nbc").write_bytes(b"yy")
    listed = _cache_json(env)
    assert (listed["files"], listed["bytes"]) == (2, 3)
    cleared = _cache_json(env, "--clear")
    assert (cleared["removed"], cleared["files"]) == (4, 0)
    assert not list(ours.iterdir()) and not stale.exists() and len(list(other.iterdir())) == 2


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


def test_warm_inputs_hold_every_jobs_input(tmp_path: Path) -> None:
    """Each command of ``cache --warm`` reads files its inputs script wrote (numba off)."""
    from imageform.cli import _cache

    env = {**os.environ, "PYTHONPATH": str(SRC), "IMAGEFORM_DISABLE_NUMBA": "1"}
    subprocess.run([sys.executable, "-c", _cache._INPUTS, str(tmp_path)], env=env, check=True)
    jobs = _cache._jobs(tmp_path)
    want = {"simulate", "calibrate", "depth", "track", "develop", "characterize"}
    if importlib.util.find_spec("cv2") is not None:
        want.add("reconstruct")
    assert {j[0] for j in jobs} >= want
    # a GoPro GPR: the VC-5 decoder's kernels (about 15 s at its first decode otherwise)
    gpr = [j for j in jobs if j[0] == "develop" and j[1].endswith(".gpr")]
    assert len(gpr) == 1
    data = Path(__file__).resolve().parent / "data" / "vc5" / "synthetic.gpr"
    assert Path(gpr[0][1]).read_bytes() == data.read_bytes()
    # the DNG carries a GainMap (OpcodeList2), whose kernel phones' DNGs and GPRs need
    from imageform.io import read_raw

    assert read_raw(tmp_path / "raw.dng").metadata["opcodes_applied"] == 1
    for job in jobs:
        outs = {job[i + 1] for i, a in enumerate(job) if a == "-o"}
        for arg in job:
            if arg.startswith(str(tmp_path)) and arg not in outs:
                assert list(tmp_path.glob(arg[len(str(tmp_path)) + 1 :])), (job, arg)


# ---- one cache per machine (issue 25): the same kernels, wherever they are, share it ----

_SHARED_PROBE = r"""
import json, sys
import numpy as np
from imageform._kernels import color_simple as k
from imageform._kernels.jit import cache_location
src = np.zeros(6, np.float32); dst = np.empty_like(src); stats = np.zeros((1, 2))
k._hsv_serial(src, dst, np.float32(1.0), stats, 0)
st = k._hsv_serial.stats
print(json.dumps({"hits": sum(st.cache_hits.values()), "misses": sum(st.cache_misses.values()),
                  "where": str(cache_location()[0]), "file": k.__file__}))
"""


def _copy_package(dest: Path) -> Path:
    """A copy of imageform at ``dest``: new paths, new file times (shutil.copy, not copy2)."""
    shutil.copytree(
        SRC / "imageform",
        dest / "imageform",
        ignore=shutil.ignore_patterns("__pycache__"),
        copy_function=shutil.copy,
    )
    return dest


def _probe(site: Path, cache: Path) -> dict[str, Any]:
    env = {k: v for k, v in os.environ.items() if not k.startswith(("NUMBA_", "_IMAGEFORM"))}
    env.update(PYTHONPATH=str(site), NUMBA_CACHE_DIR=str(cache))
    out: dict[str, Any] = json.loads(_python(_SHARED_PROBE, env))
    assert out["file"].startswith(str(site))
    return out


def test_two_copies_of_the_package_share_one_cache(tmp_path: Path) -> None:
    """A second clone (or reinstall) of the same code at another path loads what the first
    compiled: numba's own cache sub-folder is named after the source folder's path, so it
    compiled everything again."""
    a = _copy_package(tmp_path / "clone-a")
    b = _copy_package(tmp_path / "clone-b")
    cache = tmp_path / "cache"
    first, second = _probe(a, cache), _probe(b, cache)
    assert (first["misses"], first["hits"]) == (1, 0)
    assert (second["misses"], second["hits"]) == (0, 1), "the second clone compiled again"
    assert first["where"] == second["where"]
    assert Path(first["where"]).parent == cache
    assert Path(first["where"]).name.startswith("imageform-")


def test_new_file_times_same_content_still_hit(tmp_path: Path) -> None:
    site = _copy_package(tmp_path / "site")
    cache = tmp_path / "cache"
    assert _probe(site, cache)["misses"] == 1
    for path in (site / "imageform" / "_kernels").glob("*.py"):
        os.utime(path, (1.0e9, 1.0e9))  # a checkout, an unpacked wheel: other times
    again = _probe(site, cache)
    assert (again["misses"], again["hits"]) == (0, 1)


def test_an_edited_kernel_file_is_never_loaded_stale(tmp_path: Path) -> None:
    """Editing any kernel file (here another one than the probe's: a kernel inlines the jitted
    functions it calls from other files) gives a new cache folder: nothing stale is loaded."""
    site = _copy_package(tmp_path / "site")
    cache = tmp_path / "cache"
    first = _probe(site, cache)
    other = site / "imageform" / "_kernels" / "distortion.py"
    other.write_text(other.read_text() + "\n# edited\n")
    again = _probe(site, cache)
    assert (again["misses"], again["hits"]) == (1, 0)
    assert again["where"] != first["where"]


def test_without_numba_cache_dir_the_users_cache_folder(tmp_path: Path) -> None:
    """No NUMBA_CACHE_DIR: the kernels are cached in the user's cache folder, per machine,
    not in ``__pycache__`` beside the source (which is per clone)."""
    site = _copy_package(tmp_path / "site")
    env = {k: v for k, v in os.environ.items() if not k.startswith(("NUMBA_", "_IMAGEFORM"))}
    env.update(PYTHONPATH=str(site), XDG_CACHE_HOME=str(tmp_path / "xdg"))
    out = json.loads(_python(_SHARED_PROBE, env))
    assert Path(out["where"]).parent == tmp_path / "xdg" / "imageform" / "numba"
    assert list(Path(out["where"]).glob("color_simple._hsv_serial-*.nbi"))
    assert not list(site.rglob("*.nbi")), "nothing is written beside the source"


def test_checkerboard_candidates_compile_one_kernel() -> None:
    """uint8, uint16, float16, float32, float64 and read-only images share one compiled
    saddle kernel (an 8-bit and a float32 image in, one of them empty): each specialisation
    costs seconds of compilation on a first run (the float16 image of issue 25: 25-40 s)."""
    from imageform._kernels.checkerboard import _saddle_maxima
    from imageform.geometry.checkerboard_candidates import find_candidates

    rng = np.random.default_rng(0)
    base = rng.uniform(0, 1, (40, 48))
    ro = base.astype(np.float32)
    ro.flags.writeable = False
    ro8 = (base * 255).astype(np.uint8)
    ro8.flags.writeable = False
    images = [
        (base * 65535).astype(np.uint16),
        base.astype(np.float16),
        base.astype(np.float32),
        base,
        ro,
        (base * 255).astype(np.uint8),
        ro8,
    ]
    before = set(_saddle_maxima.signatures)  # other tests call the kernel directly
    results = [find_candidates(im, 1.5) for im in images]
    added = set(_saddle_maxima.signatures) - before
    kinds = {
        (str(sig[0].dtype), sig[0].mutable, str(sig[1].dtype), sig[1].mutable) for sig in added
    }
    assert kinds <= {("uint8", True, "float32", True)}, kinds
    # the conversion gives the same bits as the kernel's own (float32 then / scale)
    np.testing.assert_array_equal(results[2].xy, results[4].xy)


def test_corner_refinement_compiles_one_kernel_for_float32_and_float64() -> None:
    """float32 and float64 images share one compiled refinement kernel (characterize refines
    on both), with the same numbers: float32 values are read as float64 either way."""
    from imageform._kernels.checkerboard import _refine_corners, refine_corners_numba

    v, u = np.mgrid[0:40, 0:40] * 1.0
    img = np.where((u < 20.3) ^ (v < 19.6), 0.9, 0.1)
    img32 = img.astype(np.float32)
    pts = np.array([[19.0, 21.0], [21.5, 18.5]])
    before = set(_refine_corners.signatures)
    a = refine_corners_numba(img32, pts, 5, 5, 30, 1e-3)
    b = refine_corners_numba(img32.astype(np.float64), pts, 5, 5, 30, 1e-3)
    assert len(set(_refine_corners.signatures) - before) <= 1
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])
