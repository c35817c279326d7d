r"""The one numba policy of imageform's kernels: every kernel cached, and where the cache lives.

Every kernel module decorates with :func:`njit` from here instead of ``numba.njit``: the same
options, plus ``cache=True``, so numba's compilation (seconds per kernel: 15-25 s for the
first ``imageform pose`` or ``demosaic`` in a fresh process) is paid once per machine, not
once per process. A kernel that cannot be cached (a closure, or one that takes another jitted
function as an argument) says ``cache=False`` where it is defined: only the ``rgb`` closure of
``demosaic_bilinear._make_rows``, which is inlined into the cached loops that call it.

Where the cache lives (:func:`cache_location`, ``docs/performance.md``):

1. ``NUMBA_CACHE_DIR`` when the user set it (numba's own variable: it wins);
2. else ``__pycache__`` beside the kernels' source, numba's default, when that folder is
   writable (an editable checkout, a virtual environment the user owns);
3. else (a wheel installed read-only, system-wide) the user's cache folder,
   ``$XDG_CACHE_HOME/imageform/numba`` or ``~/.cache/imageform/numba`` on Linux,
   ``~/Library/Caches/imageform/numba`` on macOS, ``%LOCALAPPDATA%\imageform\numba`` on
   Windows: :func:`configure_cache` exports it as ``NUMBA_CACHE_DIR`` before numba is imported
   (numba reads it then, and again whenever its environment changes), so child processes
   (``imageform batch`` workers) share it.

Importing this module imports numba; ``import imageform`` does not (``_backend.have_numba``
and the kernel modules import it on first use). numba's cache is keyed on the content of each
kernel's own file: a kernel that calls a jitted function of another file
(``project_distort`` calls ``distortion.bc_distort_point``) keeps its cached code when only
the other file changes; ``imageform cache --clear`` after editing kernels by hand.
"""

from __future__ import annotations

import os
import sys
import tempfile
import types
from collections.abc import Callable
from pathlib import Path
from typing import Any, Literal

__all__ = [
    "cache_location",
    "configure_cache",
    "njit",
    "parallel_pays",
    "serial_twin",
    "user_cache_dir",
]

#: Where :func:`configure_cache` put the cache (see :func:`cache_location`).
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


def _writable(folder: Path) -> bool:
    # as numba checks it: create the folder and a file in it (os.access says yes to root on a
    # read-only file system, and no to nothing it cannot know about)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        tempfile.TemporaryFile(dir=folder).close()
    except OSError:
        return False
    return True


def cache_location() -> tuple[Path, Literal["NUMBA_CACHE_DIR", "in-tree", "user"]]:
    """Where numba caches imageform's kernels in this process, and why.

    ``("NUMBA_CACHE_DIR", path)`` when the variable is set (by the user, or by
    :func:`configure_cache` because the package folder is read-only: then ``path`` is
    :func:`user_cache_dir` and the reason ``"user"``); else ``"in-tree"``: the
    ``__pycache__`` folder beside the kernels' source.
    """
    env = os.environ.get("NUMBA_CACHE_DIR", "")
    if env:
        reason: Literal["NUMBA_CACHE_DIR", "user"] = (
            "user" if os.environ.get("_IMAGEFORM_NUMBA_CACHE_DIR") == env else "NUMBA_CACHE_DIR"
        )
        return Path(env), reason
    return _HERE / "__pycache__", "in-tree"


def configure_cache() -> None:
    """Point numba's cache at the user's cache folder when the package folder is read-only.

    Call before numba is imported; a no-op when ``NUMBA_CACHE_DIR`` is set or the kernels'
    ``__pycache__`` is writable. When numba is already imported (by the caller's own code),
    its configuration is updated too.
    """
    if os.environ.get("NUMBA_CACHE_DIR") or _writable(_HERE / "__pycache__"):
        return
    folder = str(user_cache_dir())
    os.environ["NUMBA_CACHE_DIR"] = folder
    os.environ["_IMAGEFORM_NUMBA_CACHE_DIR"] = folder  # marks it as ours (cache_location)
    config = sys.modules.get("numba.core.config")
    if config is not None:
        config.CACHE_DIR = folder  # type: ignore[attr-defined]


configure_cache()

import numba  # noqa: E402  (after configure_cache: numba reads NUMBA_CACHE_DIR on import)


def njit(fn: Callable[..., Any] | None = None, /, **options: Any) -> Any:
    """``numba.njit`` with imageform's defaults: ``cache=True`` unless the kernel says otherwise.

    Used as ``@njit``, ``@njit(parallel=True, ...)`` or ``njit(**options)(function)``, exactly
    as ``numba.njit``; every other option is numba's.
    """
    options.setdefault("cache", True)
    if getattr(numba.config, "BOUNDSCHECK", None):
        # numba's cache key has no bounds-check flag: checked code saved into the shared cache
        # would be loaded by every later run (a remap 30 times slower), so none is saved
        options["cache"] = False
    if fn is None:
        return numba.njit(**options)
    return numba.njit(fn, **options)


def serial_twin(kernel: Any, /, **options: Any) -> Any:
    """Compile a ``parallel=True`` kernel's loops again, serially (``prange`` runs as ``range``).

    For small inputs, where waking numba's thread pool costs more than it gains. The twin is
    a copy of the kernel's Python function under the name ``<name>_serial``: numba names a
    kernel's cache files after the function's qualified name and first line and keys their
    entries on the signature and the bytecode, not on ``parallel``, so
    ``njit(**options)(kernel.py_func)`` would share the kernel's cache entries, and whichever
    of the two compiled first was loaded for both (the parallel remap then ran on one thread
    on every machine whose cache the serial twin had filled first).

    Parameters
    ----------
    kernel : numba dispatcher
        The parallel kernel.
    **options
        Options of the twin, as :func:`njit`'s (``parallel`` is not passed on).

    Returns
    -------
    numba dispatcher
        The serial twin, cached under its own name.
    """
    fn = kernel.py_func
    twin = types.FunctionType(
        fn.__code__, fn.__globals__, fn.__name__ + "_serial", fn.__defaults__, fn.__closure__
    )
    twin.__qualname__ = fn.__qualname__ + "_serial"
    twin.__module__ = fn.__module__
    twin.__doc__ = fn.__doc__
    twin.__kwdefaults__ = fn.__kwdefaults__
    options.pop("parallel", None)
    return njit(twin, **options)


def parallel_pays(n: int, threshold: int) -> bool:
    """Whether to run the parallel kernel for ``n`` items rather than its serial twin.

    True when ``n`` reaches ``threshold`` and numba's pool has more than one thread: with one
    thread the parallel kernel only adds the pool's scheduling (a 1 MP uint8 HSV conversion:
    1.005 ms against 0.954 ms serially).
    """
    return n >= threshold and numba.get_num_threads() > 1
