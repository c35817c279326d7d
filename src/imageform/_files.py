"""All-or-nothing file outputs (internal core module, shared by every package that writes).

Every output is first written to a temporary sibling (same folder, a hidden name that keeps
the suffix, so writers that choose the format from the suffix still work) and renamed onto
its final name only when everything succeeded:

- an error, Ctrl-C (``KeyboardInterrupt``) or a second output that cannot be written leaves
  nothing new behind, and earlier outputs untouched;
- the rename replaces a symbolic link at the final name instead of writing through it, and an
  input reached through another path, a symbolic or a hard link is recognised by its device
  and inode, never overwritten;
- several outputs of one command are renamed together at the end, with SIGINT and SIGTERM
  held back for the few microseconds the renames take;
- a folder output (``imageform simulate``'s) is built beside the old one and swapped in whole.

Temporary names carry the writing process's id, so a later run removes the leftovers of a
killed one (and only those: two live runs into one folder never delete each other's files).
"""

from __future__ import annotations

import contextlib
import glob
import os
import re
import secrets
import shutil
import signal
import threading
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from types import TracebackType

from imageform.errors import ImageformError, InvalidInputError

__all__ = [
    "Outputs",
    "atomic_write",
    "check_output",
    "check_writable",
    "remove_stale_parts",
    "same_file",
    "signals_deferred",
]

_PART = ".part"


def same_file(a: Path, b: Path) -> bool:
    """Tell whether ``a`` and ``b`` name one file.

    Same device and inode when both exist (links included), else the same resolved path.
    """
    try:
        return os.path.samefile(a, b)
    except OSError:
        return Path(os.path.abspath(a)).resolve() == Path(os.path.abspath(b)).resolve()


def _inside(path: Path, folder: Path) -> bool:
    try:
        Path(os.path.abspath(path)).resolve().relative_to(Path(os.path.abspath(folder)).resolve())
    except ValueError:
        return False
    return True


def check_output(
    out: Path, *, inputs: Iterable[Path] = (), force: bool = False, folder: bool = False
) -> Path:
    """Refuse an output that is an input, that exists without ``force``, or whose folder is missing.

    Returns ``out``.

    A dangling symbolic link counts as existing (it is replaced, never followed).

    Raises
    ------
    InvalidInputError
        With a one-line reason naming ``out``.
    """
    out = Path(out)
    for p in inputs:
        p = Path(p)
        if same_file(p, out) or (folder and _inside(p, out)):
            what = "contains the input" if folder and not same_file(p, out) else "is also an input"
            raise InvalidInputError(f"output {out} {what} {p}; choose another path")
    if os.path.lexists(out):
        if out.is_dir() and not out.is_symlink() and not folder:
            raise InvalidInputError(f"output {out} is a folder; give a file name")
        if folder and not out.is_dir():
            raise InvalidInputError(f"output {out} exists and is not a folder")
        if not force:
            raise InvalidInputError(f"output {out} exists; pass --force to overwrite it")
    parent = out.parent if str(out.parent) else Path(".")
    if not parent.is_dir():
        raise InvalidInputError(f"output folder {parent} does not exist")
    return out


def _part_name(final: Path, token: str) -> Path:
    return final.with_name(f".{final.name}.{os.getpid()}-{token}{_PART}{final.suffix}")


def _pid_alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def remove_stale_parts(final: Path) -> int:
    """Remove temporary siblings of ``final`` left by processes that no longer run.

    Returns how many were removed.
    """
    final = Path(final)
    folder = final.parent if str(final.parent) else Path(".")
    if not folder.is_dir():
        return 0
    n = 0
    prefix = f".{final.name}."
    for entry in folder.iterdir():
        name = entry.name
        if not name.startswith(prefix) or _PART not in name:
            continue
        tag = name[len(prefix) :].split(_PART, 1)[0]
        pid_text = tag.split("-", 1)[0]
        if not pid_text.isdigit() or _pid_alive(int(pid_text)):
            continue
        with contextlib.suppress(OSError):
            if entry.is_dir() and not entry.is_symlink():
                shutil.rmtree(entry)
            else:
                entry.unlink()
            n += 1
    return n


@contextlib.contextmanager
def signals_deferred() -> Iterator[None]:
    """Hold SIGINT and SIGTERM back (delivered on exit) in the main thread; a no-op elsewhere."""
    if threading.current_thread() is not threading.main_thread() or not hasattr(
        signal, "pthread_sigmask"
    ):
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def _fsync(path: Path) -> None:
    with contextlib.suppress(OSError), open(path, "rb") as fh:
        os.fsync(fh.fileno())


def _remove(path: Path) -> None:
    with contextlib.suppress(OSError):
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path)
        elif os.path.lexists(path):
            path.unlink()


class Outputs:
    """The outputs of one command, written all or nothing.

    ``file(final)`` / ``folder(final)`` check ``final`` (:func:`check_output`) and return the
    temporary path to write instead; leaving the ``with`` block normally renames every
    temporary onto its final name, leaving it by an exception (``KeyboardInterrupt``
    included) removes them all.

    Examples
    --------
    >>> import tempfile
    >>> d = Path(tempfile.mkdtemp())
    >>> with Outputs() as outs:
    ...     _ = outs.file(d / "a.txt").write_text("a")
    ...     _ = outs.file(d / "b.txt").write_text("b")
    >>> sorted(p.name for p in d.iterdir())
    ['a.txt', 'b.txt']
    >>> try:
    ...     with Outputs(force=True) as outs:
    ...         _ = outs.file(d / "a.txt").write_text("new")
    ...         raise KeyboardInterrupt
    ... except KeyboardInterrupt:
    ...     pass
    >>> (d / "a.txt").read_text(), len(list(d.iterdir()))
    ('a', 2)
    """

    def __init__(self, *, inputs: Iterable[Path] = (), force: bool = False) -> None:
        self.inputs = tuple(Path(p) for p in inputs)
        self.force = force
        self._items: list[tuple[Path, Path, bool]] = []  # (temporary, final, is_folder)
        self._token = secrets.token_hex(4)
        self._done = False

    def _add(self, final: str | Path, folder: bool) -> Path:
        final = Path(final)
        for _, other, _ in self._items:
            if other == final or same_file(other, final):
                raise InvalidInputError(f"output {final} is given twice")
        check_output(final, inputs=self.inputs, force=self.force, folder=folder)
        remove_stale_parts(final)
        part = _part_name(final, self._token)
        if folder:
            part.mkdir()
        self._items.append((part, final, folder))
        return part

    def file(self, final: str | Path) -> Path:
        """Return the temporary path to write for the output file ``final``."""
        return self._add(final, False)

    def folder(self, final: str | Path) -> Path:
        """Make a new, empty temporary folder to fill for the output folder ``final``."""
        return self._add(final, True)

    @property
    def finals(self) -> tuple[Path, ...]:
        """The final names, in the order they were added."""
        return tuple(f for _, f, _ in self._items)

    def part(self, final: str | Path) -> Path | None:
        """Return the temporary path of an output added before (None if ``final`` was not added)."""
        for part, other, _ in self._items:
            if other == Path(final):
                return part
        return None

    def commit(self) -> None:
        """Rename every temporary onto its final name (all of them, or none on an error)."""
        for part, final, _ in self._items:
            if not os.path.lexists(part):
                raise ImageformError(f"output {final} was not written")
        for part, _, folder in self._items:
            if not folder:
                _fsync(part)
        with signals_deferred():
            for part, final, folder in self._items:
                if folder and os.path.lexists(final):
                    old = final.with_name(f".{final.name}.{os.getpid()}-{self._token}.old{_PART}")
                    os.replace(final, old)
                    os.replace(part, final)
                    _remove(old)
                else:
                    os.replace(part, final)
        self._done = True

    def discard(self) -> None:
        """Remove every temporary (the final names are untouched)."""
        for part, _, _ in self._items:
            _remove(part)
        self._done = True

    def __enter__(self) -> Outputs:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if self._done:
            return
        if exc_type is None:
            try:
                self.commit()
            except BaseException:
                self.discard()
                raise
        else:
            self.discard()


def atomic_write(final: str | Path, write: Callable[[Path], object]) -> None:
    """Call ``write(temporary_path)``, then rename the temporary onto ``final`` (overwriting it).

    On any error the temporary is removed and ``final`` is untouched.

    Examples
    --------
    >>> import tempfile
    >>> p = Path(tempfile.mkdtemp()) / "x.txt"
    >>> atomic_write(p, lambda t: t.write_text("hello"))
    >>> p.read_text()
    'hello'
    """
    final = Path(final)
    part = _part_name(final, secrets.token_hex(4))
    try:
        write(part)
        if not os.path.lexists(part):
            raise ImageformError(f"output {final} was not written")
        _fsync(part)
        with signals_deferred():
            os.replace(part, final)
    except BaseException:
        _remove(part)
        raise


# --- h16wf ---

_WILDCARDS = re.compile(r"[*?\[]")


def glob_base(pattern: str) -> Path:
    """Return the fixed folder prefix of ``pattern`` (the part before the first wildcard)."""
    parts = Path(pattern).parts
    fixed: list[str] = []
    for part in parts[:-1]:
        if _WILDCARDS.search(part):
            break
        fixed.append(part)
    return Path(*fixed) if fixed else Path(".")


def glob_regex(pattern: str) -> re.Pattern[str]:
    """Build a regex for absolute paths that ``glob.glob(pattern, recursive=True)`` would match."""
    pat = os.path.abspath(pattern)
    out, i = "", 0
    while i < len(pat):
        if pat.startswith("**/", i):
            out, i = out + "(?:.*/)?", i + 3
        elif pat.startswith("**", i):
            out, i = out + ".*", i + 2
        elif pat[i] == "*":
            out, i = out + "[^/]*", i + 1
        elif pat[i] == "?":
            out, i = out + "[^/]", i + 1
        elif pat[i] == "[" and "]" in pat[i + 1 :]:
            j = pat.index("]", i + 1)
            body = pat[i + 1 : j]
            out, i = out + "[" + ("^" + body[1:] if body.startswith("!") else body) + "]", j + 1
        else:
            out, i = out + re.escape(pat[i]), i + 1
    return re.compile(out + r"\Z")


def glob_paths(pattern: str) -> list[str]:
    """Return the paths matching ``pattern`` as ``glob.glob(pattern, recursive=True)`` finds them.

    But ``**`` enters each real folder once: a symbolic link to an ancestor (a loop) is not
    followed again, where glob would recurse until the path is too long (minutes).
    """
    if "**" not in pattern:
        return glob.glob(pattern)
    matcher = glob_regex(pattern)
    found: list[str] = []
    seen: set[tuple[int, int]] = set()
    for root, dirs, files in os.walk(str(glob_base(pattern)), followlinks=True):
        try:
            st = os.stat(root)
        except OSError:
            dirs[:] = []
            continue
        if (st.st_dev, st.st_ino) in seen:
            dirs[:] = []
            continue
        seen.add((st.st_dev, st.st_ino))
        dirs[:] = sorted(d for d in dirs if not d.startswith("."))
        found += [
            p
            for p in (os.path.join(root, f) for f in files if not f.startswith("."))
            if matcher.match(os.path.abspath(p))
        ]
    return found


# --- i25 (library writers) ---


def _shown(path: Path, width: int = 80) -> str:
    text = str(path)
    return text if len(text) <= width else "..." + text[-(width - 3) :]


def check_writable(path: object, name: str = "path") -> Path:
    """Refuse, before writing, an output file that cannot be written (the library writers' check).

    Returns ``path`` as a :class:`~pathlib.Path`. Refused in one line naming ``name`` (long
    paths shortened): not a ``str`` or path; a folder; an existing file that is not a regular
    file (a device such as ``/dev/null``, a FIFO, a socket: the temporary would be renamed
    over it); a missing parent folder, or a parent that is not a folder. A symbolic link is
    accepted: :func:`atomic_write` replaces it, never follows it.

    Examples
    --------
    >>> check_writable("/dev/null", "path")
    Traceback (most recent call last):
    ...
    imageform.errors.InvalidInputError: path: /dev/null is not a regular file (a device, FIFO or socket); give a file name
    """  # noqa: E501
    import stat

    if isinstance(path, bytes) or not isinstance(path, str | os.PathLike):
        kind = type(path).__name__
        raise InvalidInputError(f"expected {name} as a file name (str or Path), got {kind}")
    out = Path(os.fspath(path))
    if not str(path).strip() or "\0" in str(path):
        raise InvalidInputError(f"expected {name} as a file name, got {_shown(out)!r}")
    try:
        st = os.lstat(out)
    except (FileNotFoundError, NotADirectoryError):  # the parent check below says which
        st = None
    except OSError as exc:  # too long, a parent that is a file, no permission ...
        reason = exc.strerror or type(exc).__name__
        raise InvalidInputError(f"{name}: cannot write {_shown(out)} ({reason})") from None
    if st is not None and stat.S_ISDIR(st.st_mode):
        raise InvalidInputError(f"{name}: {_shown(out)} is a folder; give a file name")
    if st is not None and not (stat.S_ISREG(st.st_mode) or stat.S_ISLNK(st.st_mode)):
        raise InvalidInputError(
            f"{name}: {_shown(out)} is not a regular file (a device, FIFO or socket); "
            "give a file name"
        )
    parent = out.parent if str(out.parent) else Path(".")
    if not parent.is_dir():
        what = "is not a folder" if os.path.lexists(parent) else "does not exist"
        raise InvalidInputError(f"{name}: the folder {_shown(parent)} {what}")
    return out
