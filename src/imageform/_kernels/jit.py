r"""The one numba policy of imageform's kernels: every kernel cached, once per machine.

Every kernel module decorates with :func:`njit` from here instead of ``numba.njit``: the same
options, plus ``cache=True``, so numba's compilation is paid once per machine, not once per
process. A kernel that cannot be cached (a closure, or one that takes another jitted function
as an argument) says ``cache=False`` where it is defined: only the ``rgb`` closure of
``demosaic_bilinear._make_rows``, which is inlined into the cached loops that call it.

Where the cache lives (:func:`cache_location`, ``docs/performance.md``): one folder per
machine, not per clone. numba's own cache sits in ``__pycache__`` beside the source, or under
``NUMBA_CACHE_DIR`` in a sub-folder named after the source folder's path, so a second clone,
a reinstall elsewhere or a new virtual environment compiled everything again. imageform's
kernels use a cache locator of their own (:class:`PackageCacheLocator`, put first in numba's
list of locators; it serves only the files of this folder) that puts them in

1. ``NUMBA_CACHE_DIR/imageform-<version>-<digest>`` when ``NUMBA_CACHE_DIR`` is set (numba's
   own variable: it wins), else
2. the user's cache folder, ``$XDG_CACHE_HOME/imageform/numba/imageform-<version>-<digest>``
   or ``~/.cache/...`` on Linux, ``~/Library/Caches/imageform/numba/...`` on macOS,
   ``%LOCALAPPDATA%\imageform\numba\...`` on Windows;

where ``<digest>`` is a hash of the content of every kernel source file of this folder, with
imageform's, numba's and Python's versions. Every copy of the same kernels on the machine finds
the same folder, whatever its path or its files' times; a kernel edited anywhere in the folder
(a kernel that calls a jitted function of another file keeps that function's code inlined)
gives a new folder, so nothing stale is ever loaded. numba's own key (the signature, the
target CPU, the bytecode) still decides which entry of a kernel's index is loaded. When that
folder cannot be written, numba's own locators take over (``__pycache__`` beside the source).

Importing this module imports numba; ``import imageform`` does not (``_backend.have_numba``
and the kernel modules import it on first use).
"""

from __future__ import annotations

import functools
import hashlib
import os
import sys
import tempfile
import threading
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Any, Literal

import numba
from numba.core import caching

__all__ = [
    "Deferred",
    "PackageCacheLocator",
    "cache_location",
    "cache_root",
    "configure_cache",
    "njit",
    "parallel_pays",
    "run_tasks",
    "user_cache_dir",
]

#: The folder of imageform's kernels: the files :class:`PackageCacheLocator` serves.
_HERE = Path(__file__).resolve().parent


def user_cache_dir() -> Path:
    """Return the user's cache folder for imageform's compiled kernels (platform conventions)."""
    if sys.platform == "win32":
        base = Path(os.environ.get("LOCALAPPDATA") or Path.home() / "AppData" / "Local")
    elif sys.platform == "darwin":
        base = Path.home() / "Library" / "Caches"
    else:
        xdg = os.environ.get("XDG_CACHE_HOME", "")
        base = Path(xdg) if os.path.isabs(xdg) else Path.home() / ".cache"
    return base / "imageform" / "numba"


@functools.lru_cache(maxsize=1)
def kernels_digest() -> str:
    """Hash of every kernel source file's content, with imageform's, numba's, Python's versions.

    Neither the files' paths nor their times: two clones or installs of the same code on one
    machine give the same digest.
    """
    imageform = sys.modules.get("imageform")
    h = hashlib.sha256()
    for part in (
        getattr(imageform, "__version__", "?"),
        numba.__version__,
        sys.implementation.cache_tag or "",
        sys.version,
    ):
        h.update(part.encode() + b"\0")
    for path in sorted(_HERE.glob("*.py")):
        h.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    return h.hexdigest()[:20]


def cache_root() -> tuple[Path, Literal["NUMBA_CACHE_DIR", "user"]]:
    """Return the folder of imageform's cache folders and why: ``NUMBA_CACHE_DIR`` or user's."""
    env = os.environ.get("NUMBA_CACHE_DIR", "")
    if env:
        return Path(env), "NUMBA_CACHE_DIR"
    return user_cache_dir(), "user"


def _folder() -> Path:
    imageform = sys.modules.get("imageform")
    version = getattr(imageform, "__version__", "0")
    return cache_root()[0] / f"imageform-{version}-{kernels_digest()}"


@functools.lru_cache(maxsize=8)
def _writable(folder: Path) -> bool:
    # as numba checks it: create the folder and a file in it (os.access says yes to root on a
    # read-only file system, and no to nothing it cannot know about); once per process
    try:
        folder.mkdir(parents=True, exist_ok=True)
        tempfile.TemporaryFile(dir=folder).close()
    except OSError:
        return False
    return True


class PackageCacheLocator(caching._CacheLocator):
    """numba cache locator for imageform's kernels: one folder per machine and kernel code.

    The folder is :func:`cache_location`'s; the source stamp of every kernel is
    :func:`kernels_digest` (already in the folder's name), not the path or the time of its
    file. Serves the files of ``imageform/_kernels`` only: for every other file, and when the
    folder cannot be written, :meth:`from_function` returns ``None`` and numba's own locators
    take over.
    """

    def __init__(self, py_func: Any, py_file: str) -> None:
        self._py_file = py_file
        self._lineno = py_func.__code__.co_firstlineno
        self._cache_path = str(_folder())

    def ensure_cache_path(self) -> None:
        if not _writable(Path(self._cache_path)):
            raise OSError(f"cannot write {self._cache_path}")

    def get_cache_path(self) -> str:
        return self._cache_path

    def get_source_stamp(self) -> str:
        return kernels_digest()

    def get_disambiguator(self) -> str:
        return str(self._lineno)

    @classmethod
    def from_function(cls, py_func: Any, py_file: str) -> PackageCacheLocator | None:
        if os.path.dirname(os.path.realpath(py_file)) != str(_HERE):
            return None
        self = cls(py_func, py_file)
        try:
            self.ensure_cache_path()
        except OSError:
            return None
        return self


def cache_location() -> tuple[Path, Literal["NUMBA_CACHE_DIR", "user", "in-tree"]]:
    """Where numba caches imageform's kernels in this process, and why.

    ``(folder, "NUMBA_CACHE_DIR")`` when the variable is set, ``(folder, "user")`` in the
    user's cache folder otherwise (see the module's documentation); ``(__pycache__ beside the
    kernels, "in-tree")`` when that folder cannot be written (numba's own default then).
    """
    folder = _folder()
    if _writable(folder):
        return folder, cache_root()[1]
    return _HERE / "__pycache__", "in-tree"


def configure_cache() -> None:
    """Put :class:`PackageCacheLocator` first in numba's list of cache locators (idempotent).

    Done when this module is imported, before any kernel is defined.
    """
    impl = vars(caching).get("CacheImpl") or vars(caching)["_CacheImpl"]  # older numba: _CacheImpl
    if PackageCacheLocator not in impl._locator_classes:
        impl._locator_classes.insert(0, PackageCacheLocator)


configure_cache()


#: While a second process compiles kernels ahead (:mod:`imageform._kernels.ahead`), its
#: ``ready("module.kernel")``: called before a kernel compiles (or loads from the cache).
_WAIT: Callable[[str], None] | None = None


def _waits(dispatcher: Any) -> Any:
    """Make ``dispatcher`` call :data:`_WAIT` with its name before it compiles a signature.

    numba calls a dispatcher's ``compile`` for every new signature: at a call from Python, and
    while typing a kernel that calls it; so the wait covers callees compiled inside a caller.
    """
    if not isinstance(dispatcher, numba.core.dispatcher.Dispatcher):
        return dispatcher
    fn = dispatcher.py_func
    name = f"{(fn.__module__ or '').rpartition('.')[2]}.{fn.__qualname__}"
    plain = dispatcher.compile

    def compile(sig: Any) -> Any:
        if _WAIT is not None:
            _WAIT(name)
        return plain(sig)

    dispatcher.compile = compile  # type: ignore[method-assign]
    return dispatcher


def njit(fn: Callable[..., Any] | str | None = None, /, **options: Any) -> Any:
    """``numba.njit`` with imageform's defaults: ``cache=True`` unless the kernel says otherwise.

    Used as ``@njit``, ``@njit(parallel=True, ...)``, ``@njit("signature", ...)`` (compiled
    for that signature alone, when the module is imported) or ``njit(**options)(function)``,
    exactly as ``numba.njit``; every other option is numba's. ``@njit("signature", lazy=True)``
    compiles for that signature alone too, but at the first call (:class:`Deferred`): importing
    the module compiles nothing, so a second process can compile its callees ahead
    (:mod:`imageform._kernels.ahead`).
    """
    options.setdefault("cache", True)
    lazy = bool(options.pop("lazy", False))
    if getattr(numba.config, "BOUNDSCHECK", None):
        # numba's cache key has no bounds-check flag: checked code saved into the shared cache
        # would be loaded by every later run (a remap 30 times slower), so none is saved
        options["cache"] = False
    if lazy:
        if not isinstance(fn, str):
            raise TypeError("njit(lazy=True) takes the signature to compile for")
        signature = fn
        return lambda function: Deferred(_waits(numba.njit(**options)(function)), signature)
    if fn is None:
        return lambda function: _waits(numba.njit(**options)(function))
    if isinstance(fn, str):  # an explicit signature: compiled now, when the module is imported
        return numba.njit(fn, **options)
    return _waits(numba.njit(fn, **options))


class Deferred:
    """A kernel compiled for one signature at its first call, then for no other.

    As ``numba.njit("signature")`` (arguments converted to that signature's types, or a
    ``TypeError``) without compiling when its module is imported. The first call waits for a
    second process that may be compiling its callees (:func:`imageform._kernels.ahead.ready`).
    Called from Python only (a jitted caller calls :attr:`dispatcher`).
    """

    def __init__(self, dispatcher: Any, signature: str) -> None:
        self.dispatcher = dispatcher
        self.signature = signature
        self.__wrapped__ = dispatcher.py_func
        self.__doc__ = dispatcher.py_func.__doc__
        self._lock = threading.Lock()
        self._compiled = False

    def compile(self) -> None:
        """Compile (or load from the cache) the kernel for its signature; once."""
        with self._lock:
            if self._compiled:
                return
            self.dispatcher.compile(self.signature)
            self.dispatcher.disable_compile()
            self._compiled = True

    def __call__(self, *args: Any) -> Any:
        if not self._compiled:
            self.compile()
        return self.dispatcher(*args)

    def __getattr__(self, name: str) -> Any:  # py_func, signatures, overloads, ...
        return getattr(self.dispatcher, name)

    def __repr__(self) -> str:
        return f"Deferred({self.dispatcher.py_func.__qualname__}, {self.signature!r})"


def parallel_pays(n: int, threshold: int) -> bool:
    """Whether to run the parallel kernel for ``n`` items rather than its serial one.

    True when ``n`` reaches ``threshold`` and numba's pool has more than one thread: with one
    thread the parallel kernel only adds the pool's scheduling (a 1 MP uint8 HSV conversion:
    1.005 ms against 0.954 ms serially).
    """
    return n >= threshold and numba.get_num_threads() > 1


_POOL: ThreadPoolExecutor | None = None
_POOL_SIZE = 0
_POOL_LOCK = threading.Lock()


def _reset_pool() -> None:  # in a forked child: the parent's threads do not exist there
    global _POOL, _POOL_SIZE
    _POOL, _POOL_SIZE = None, 0


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_reset_pool)


def _pool(workers: int) -> ThreadPoolExecutor:
    global _POOL, _POOL_SIZE
    with _POOL_LOCK:
        if _POOL is None or workers > _POOL_SIZE:
            if _POOL is not None:
                _POOL.shutdown(wait=False)
            _POOL = ThreadPoolExecutor(workers, thread_name_prefix="imageform-kernel")
            _POOL_SIZE = workers
        return _POOL


def run_tasks(kernel: Any, n_tasks: int, *args: Any, threads: int | None = None) -> None:
    """Run ``kernel(t0, t1, *args)`` over the tasks ``0 .. n_tasks - 1`` on numba's threads.

    The tasks are cut into one contiguous run per thread (as ``prange``'s static schedule);
    the calling thread runs the first. ``kernel`` is a serial kernel compiled with
    ``nogil=True`` that loops ``for t in range(t0, t1)``: compiling it costs seconds less than
    the same loop as a ``parallel=True`` ``prange`` (numba's parallel lowering and its gufunc,
    about 3 s of CPU for the Menon demosaic on a first run), and one compiled kernel serves
    the small inputs run serially too (no serial twin to compile). ``threads``: default
    ``numba.get_num_threads()`` (``NUMBA_NUM_THREADS``, ``numba.set_num_threads``); 1 runs
    every task in the calling thread.
    """
    k = min(n_tasks, threads if threads is not None else numba.get_num_threads())
    if k <= 1:
        if n_tasks > 0:
            kernel(0, n_tasks, *args)
        return
    if isinstance(kernel, numba.core.dispatcher.Dispatcher):
        # compiled (or loaded) in this thread, never in the pool's: a Ctrl-C that lands in a
        # compilation here while a worker compiles too left llvmlite's lock held by this
        # thread, and the worker, which this thread then waits for, waiting on it (a hang)
        kernel(0, 0, *args)
    cut = [n_tasks * i // k for i in range(k + 1)]
    pool = _pool(k - 1)
    futures: list[Future[Any]] = [
        pool.submit(kernel, cut[i], cut[i + 1], *args) for i in range(1, k)
    ]
    try:
        kernel(cut[0], cut[1], *args)
    finally:
        for f in futures:
            f.result()
