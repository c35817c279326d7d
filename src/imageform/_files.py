"""All-or-nothing file outputs (internal core module, shared by every package that writes).

Every output is first written to a temporary sibling (same folder, a hidden name that keeps
the suffix, so writers that choose the format from the suffix still work) and renamed onto
its final name only when everything succeeded:

- an error, Ctrl-C (``KeyboardInterrupt``) or a second output that cannot be written leaves
  nothing new behind, and earlier outputs untouched;
- the rename replaces a symbolic link at the final name instead of writing through it, and an
  input reached through another path, a symbolic or a hard link is recognised by its device
  and inode, never overwritten;
- an existing final name that is not a regular file (a FIFO, a device, a socket, or a symbolic
  link to one; a folder where a file is written; a folder output holding one) is refused,
  whatever ``force`` says: checked when the output is added and again just before the rename,
  in :func:`publish`, the one place a temporary becomes an output;
- several outputs of one command are renamed together at the end, with SIGINT and SIGTERM
  held back for the few microseconds the renames take;
- a folder output (``imageform simulate``'s) is built beside the old one and swapped in whole.

Temporary names carry the writing process's id, so a later run removes the leftovers of a
killed one (and only those: two live runs into one folder never delete each other's files).
"""

from __future__ import annotations

import contextlib
import errno
import glob
import os
import re
import secrets
import shutil
import signal
import stat
import threading
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from types import TracebackType

from imageform.errors import ImageformError, InvalidInputError

__all__ = [
    "RAW_SUFFIXES",
    "OutputWriteError",
    "Outputs",
    "atomic_write",
    "check_output",
    "check_writable",
    "final_name",
    "git_lfs_pointer",
    "not_a_regular_file",
    "publish",
    "refuse_special",
    "refuse_special_inside",
    "remove_stale_parts",
    "same_file",
    "signals_deferred",
]

#: Suffixes of camera raw files (any case): DNG and the makers' formats LibRaw reads
#: (:data:`imageform.io.RAW_SUFFIXES`; here, free of NumPy, for the command line's lazy imports).
RAW_SUFFIXES: tuple[str, ...] = (
    ".dng", ".cr2", ".cr3", ".crw", ".nef", ".nrw", ".arw", ".sr2", ".srf", ".raf", ".orf",
    ".rw2", ".rwl", ".raw", ".pef", ".srw", ".3fr", ".fff", ".iiq", ".mos", ".mef", ".mrw",
    ".x3f", ".erf", ".kdc", ".dcr", ".k25", ".gpr",
)  # fmt: skip

_PART = ".part"
_PART_NAME = re.compile(r"^\.(.+)\.\d+-[0-9a-z]+(?:\.old)?\.part")

#: Why writing failed, for the errors that say nothing about the data.
_WRITE_REASONS = {
    errno.ENOSPC: "no space left on device",
    errno.EDQUOT: "disk quota exceeded",
    errno.EROFS: "read-only file system",
    errno.EFBIG: "file too large for the file system",
}


class OutputWriteError(ImageformError, OSError):
    """An output could not be written (a full disk, no permission): one line naming it.

    The user's name of the output, never a temporary name; ``errno`` and ``filename`` are set,
    and the original ``OSError`` is the ``__cause__``.
    """

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


def final_name(name: str) -> str:
    """Return the user's name of a file name, which may be a temporary one of :class:`Outputs`.

    Examples
    --------
    >>> final_name(".out.png.12-ab12cd34.part.png"), final_name("out.png")
    ('out.png', 'out.png')
    """
    return _unpart(name)


def _unpart(name: str) -> str:
    """Return the final name of a temporary name (``.out.png.1-ab.part.png`` -> ``out.png``)."""
    while (m := _PART_NAME.match(name)) is not None:
        name = m.group(1)
    return name


#: A temporary name already (this module's ``.NAME.<pid>-<token>.part[SUFFIX]``, or an
#: ``imageform batch`` job's ``.NAME.<run>-<token>.tmp[SUFFIX]``): written in place, so that
#: temporary names never nest (its owner renames it, or removes it).
_TEMPORARY = re.compile(
    r"\..+\.(?:\d+-[0-9a-f]{8}\.part|[0-9a-f]{12}-[0-9a-f]{12}\.tmp)(?:\.[^.]*)?"
)


def _is_temporary(path: Path) -> bool:
    return _TEMPORARY.fullmatch(path.name) is not None


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


def _what(mode: int) -> str:
    """Name the kind of a file that is not a regular file nor a folder."""
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISCHR(mode):
        return "a character device"
    if stat.S_ISBLK(mode):
        return "a block device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "a special file"


def _special_inside(folder: Path) -> tuple[Path, int] | None:
    """Return the first entry under ``folder`` that an output folder must not hold, with its mode.

    Not a regular file, a folder or a symbolic link (links are not followed); None if none.
    """
    stack = [folder]
    while stack:
        try:
            entries = list(os.scandir(stack.pop()))
        except OSError:
            continue
        for entry in entries:
            try:
                mode = entry.stat(follow_symlinks=False).st_mode
            except OSError:
                continue
            if stat.S_ISDIR(mode):
                stack.append(Path(entry.path))
            elif not (stat.S_ISREG(mode) or stat.S_ISLNK(mode)):
                return Path(entry.path), mode
    return None


def not_a_regular_file(path: str | Path) -> str | None:
    """Say what an existing ``path`` is when it is not a regular file (links followed).

    ``"is a folder"``, ``"is a FIFO (named pipe), not a regular file"`` ...; None for a regular
    file or nothing at all (a missing file is the caller's message).

    Examples
    --------
    >>> import tempfile
    >>> not_a_regular_file(tempfile.mkdtemp())
    'is a folder'
    """
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return None
    if stat.S_ISREG(mode):
        return None
    if stat.S_ISDIR(mode):
        return "is a folder"
    return f"is {_what(mode)}, not a regular file"


#: The first line of a Git LFS pointer file (what a clone without ``git lfs`` holds).
_LFS_POINTER = b"version https://git-lfs.github.com/spec/"


def git_lfs_pointer(path: str | Path) -> str | None:
    r"""Say so when ``path`` is a Git LFS pointer, not the file it stands for.

    A repository cloned without ``git lfs`` holds, under the image's or raw file's name, a
    text file of about 130 bytes naming the real file's hash and size; every decoder would
    call it "not a PNG file" or "not a raw file". Returns the reason (naming the size never
    fetched) or None: not a pointer, or not readable (the decoder's message then).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "photo.png"
    >>> lines = ["version https://git-lfs.github.com/spec/v1", "oid sha256:4d7a", "size 123"]
    >>> _ = p.write_text("\n".join(lines))
    >>> git_lfs_pointer(p)[:50]
    'a Git LFS pointer, not the file: the 123-byte file'
    """
    try:
        if os.stat(path).st_size > 1024:
            return None
        with open(path, "rb") as f:
            text = f.read(1024)
    except (OSError, ValueError):
        return None
    if not text.startswith(_LFS_POINTER):
        return None
    size = next(
        (ln.split()[1] for ln in text.decode("ascii", "replace").splitlines()
         if ln.startswith("size ") and len(ln.split()) == 2),
        "?",
    )  # fmt: skip
    return (
        f"a Git LFS pointer, not the file: the {size}-byte file it stands for was never "
        "fetched (git lfs pull)"
    )


def _folder_problem(parent: Path) -> str:
    """Say why ``parent`` cannot hold an output: missing, or it (or a folder above) is a file."""
    for above in (parent, *parent.parents):
        if os.path.lexists(above):
            if above.is_dir():
                break
            if above == parent:
                return f"output folder {parent} is not a folder"
            return f"output folder {parent} does not exist ({above} is not a folder)"
    return f"output folder {parent} does not exist"


def refuse_special_inside(folder: str | Path) -> None:
    """Refuse a folder that outputs are written into (or that replaces) holding a special file.

    A FIFO, a device or a socket anywhere under ``folder`` (links are not followed).

    Raises
    ------
    InvalidInputError
        In one line naming the file and what it is.
    """
    found = _special_inside(Path(folder))
    if found is not None:
        raise InvalidInputError(
            f"output folder {folder} holds {found[0]}, {_what(found[1])}; outputs never "
            "replace one (choose another folder)"
        )


def refuse_special(out: str | Path, *, folder: bool = False) -> None:
    """Refuse an existing ``out`` that an output must never replace, whatever the flags.

    Replaceable: nothing there, a regular file, a symbolic link to a regular file or a dangling
    one (the link is replaced, never followed); for a folder output (``folder``), a folder (or a
    link to one) holding only regular files, folders and links, and not a mount point.
    Everything else (a FIFO, a device, a socket, a link to one; a folder where a file is
    written) is refused.

    Raises
    ------
    InvalidInputError
        In one line naming ``out`` and what it is.
    """
    out = Path(out)
    try:
        mode = os.lstat(out).st_mode
    except OSError:
        return  # nothing there (or a parent that is not a folder: reported by check_output)
    link = stat.S_ISLNK(mode)
    if link:
        try:
            mode = os.stat(out).st_mode
        except OSError:
            return  # a dangling link: replaced, never followed
    via = "a symbolic link to " if link else ""
    if stat.S_ISREG(mode):
        if folder:
            raise InvalidInputError(f"output {out} exists and is not a folder")
        return
    if stat.S_ISDIR(mode):
        if not folder:
            what = f"{via}a folder" if link else "a folder"
            raise InvalidInputError(f"output {out} is {what}; give a file name")
        if not link:
            if os.path.ismount(out):
                raise InvalidInputError(
                    f"output folder {out} is a mount point; it is never replaced (choose a "
                    "folder inside it)"
                )
            refuse_special_inside(out)
        return
    what = via + _what(mode)
    raise InvalidInputError(
        f"output {out} is {what}, not a regular file; it is never replaced (choose another path)"
    )


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
        refuse_special(out, folder=folder)
        if not force:
            raise InvalidInputError(f"output {out} exists; pass --force to overwrite it")
    parent = out.parent if str(out.parent) else Path(".")
    if not parent.is_dir():
        raise InvalidInputError(_folder_problem(parent))
    return out


def publish(part: Path, final: Path, *, folder: bool = False, token: str | None = None) -> None:
    """Rename the finished temporary ``part`` onto ``final``: the one place an output appears.

    ``final`` is checked again (:func:`refuse_special`) just before the rename: whatever came
    to be there while the output was written, a FIFO or a device is never replaced. A folder
    output is swapped in whole (the old folder moved aside, then removed). Call it with SIGINT
    and SIGTERM held back (:func:`signals_deferred`) when several outputs are published together.

    Raises
    ------
    InvalidInputError
        ``final`` became something an output must not replace (``part`` is left for the caller
        to remove).
    """
    refuse_special(final, folder=folder)
    if folder and os.path.lexists(final):
        tag = token or secrets.token_hex(4)
        old = final.with_name(f".{final.name}.{os.getpid()}-{tag}.old{_PART}")
        os.replace(final, old)
        os.replace(part, final)
        _remove(old)
    else:
        os.replace(part, final)


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
        if not folder and _is_temporary(final):  # a temporary file already: written in place
            self._items.append((final, final, False))
            return final
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

    def final_of(self, path: str | Path) -> Path | None:
        """Return the user's name of ``path`` if it is (or is inside) a temporary of an output.

        A writer's own temporary beside it (``write_image``'s) counts too; None otherwise.
        """
        p = Path(os.path.abspath(path))
        for part, final, folder in self._items:
            a = Path(os.path.abspath(part))
            if p == a or (p.parent == a.parent and p.name.startswith(f".{a.name}.")):
                return final
            if folder and a in p.parents:
                rel = p.relative_to(a).parts
                return final.joinpath(*(_unpart(n) for n in rel))
        return None

    def explain(self, exc: OSError) -> OutputWriteError | None:
        """Return ``exc`` as one line naming the output it failed to write (None: not an output).

        An error naming a temporary names the user's output instead; a full disk, a quota or a
        read-only file system without a file name is about the outputs, never the inputs.
        """
        final = None
        for name in (exc.filename, exc.filename2):
            if isinstance(name, str | os.PathLike) and final is None:
                final = self.final_of(os.fspath(name))
        code = exc.errno
        if final is None:
            if exc.filename is not None or code not in _WRITE_REASONS or not self._items:
                return None
            finals = [str(f) for f in self.finals]
            where = ", ".join(finals[:3]) + (f" (and {len(finals) - 3} more)" if finals[3:] else "")
        else:
            where = str(final)
        reason = _WRITE_REASONS.get(code) if code is not None else None
        if reason is None:
            lines = str(exc).strip().splitlines()
            text = exc.strerror or (lines[0] if lines else "")
            reason = (text[:1].lower() + text[1:]) if text else type(exc).__name__
        err = OutputWriteError(f"{reason} writing {where}")
        err.errno = code
        err.filename = str(final) if final is not None else None
        return err

    def commit(self) -> None:
        """Rename every temporary onto its final name (all of them, or none on an error)."""
        for part, final, _ in self._items:
            if not os.path.lexists(part):
                raise ImageformError(f"output {final} was not written")
        for part, final, folder in self._items:
            if not folder:
                _fsync(part)
            refuse_special(final, folder=folder)  # before any is renamed: all or nothing
        with signals_deferred():
            for part, final, folder in self._items:
                publish(part, final, folder=folder, token=self._token)
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


def atomic_write(
    final: str | Path,
    write: Callable[[Path], object],
    *,
    folder: bool = False,
    part: Path | None = None,
) -> None:
    """Call ``write(temporary_path)``, then rename the temporary onto ``final`` (overwriting it).

    On any error (Ctrl-C included) the temporary is removed and ``final`` is untouched.
    ``folder``: the output is a folder (a Zarr store), swapped in whole (:func:`publish`).
    ``part``: the temporary's path, a sibling of ``final``; by default
    ``.NAME.<pid>-<random>.partSUFFIX``, which :func:`remove_stale_parts` removes once its
    process is gone (``imageform batch`` names its own: its writers run on other hosts).

    Examples
    --------
    >>> import tempfile
    >>> p = Path(tempfile.mkdtemp()) / "x.txt"
    >>> atomic_write(p, lambda t: t.write_text("hello"))
    >>> p.read_text()
    'hello'
    """
    final = Path(final)
    refuse_special(final, folder=folder)
    if _is_temporary(final):  # a temporary file already (its owner renames it): in place
        write(final)
        if not os.path.lexists(final):
            raise ImageformError(f"output {final} was not written")
        return
    if part is None:
        part = _part_name(final, secrets.token_hex(4))
    try:
        write(part)
        if not os.path.lexists(part):
            raise ImageformError(f"output {final} was not written")
        _fsync(part)
        with signals_deferred():
            publish(part, final, folder=folder)
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
    imageform.errors.InvalidInputError: path: /dev/null is a character device, not a regular file; give a file name
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
            f"{name}: {_shown(out)} is {_what(st.st_mode)}, not a regular file; give a file name"
        )
    parent = out.parent if str(out.parent) else Path(".")
    if not parent.is_dir():
        what = "is not a folder" if os.path.lexists(parent) else "does not exist"
        raise InvalidInputError(f"{name}: the folder {_shown(parent)} {what}")
    return out
