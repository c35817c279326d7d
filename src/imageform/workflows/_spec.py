"""How a workflow is declared: typed options, positional inputs, outputs, and its result.

A workflow is a file-level operation (read, compute, write). Its options are a frozen
dataclass whose fields carry their command-line help in ``metadata`` (see :func:`option`);
the command line and ``imageform batch`` are both generated from these declarations, so a
default, a valid value or a help text exists once.

This module imports nothing heavy: ``imageform --help`` reads every declaration.
"""

from __future__ import annotations

import dataclasses
import importlib
import types
import typing
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from imageform.errors import InvalidInputError, UnknownOptionError

__all__ = [
    "IMAGE_SUFFIXES",
    "Input",
    "Options",
    "Output",
    "Result",
    "Run",
    "Workflow",
    "check_suffix",
    "choice_names",
    "flag_of",
    "normalize_choice",
    "option",
    "option_label",
    "refuse_foreign_folder",
    "resolve",
]

#: Image file suffixes that workflows read and write (.pgm grey, .ppm RGB: Netpbm, no profile).
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".npy", ".pgm", ".ppm", ".pfm")


def option(
    default: Any = dataclasses.MISSING,
    *,
    help: str,
    flag: str | None = None,
    short: str | None = None,
    choices: Sequence[str] | str | None = None,
    metavar: str | None = None,
    hidden: bool = False,
    output: bool = False,
    folder: bool = False,
    input: bool = False,
    minimum: float | None = None,
    maximum: float | None = None,
) -> Any:
    """Declare a field of an options dataclass, with what the command line needs to know.

    Parameters
    ----------
    default
        The default (the one default for the API, the command and ``imageform batch``).
    help : str
        One sentence for ``--help``.
    flag : str, optional
        The long flag; default ``--`` + the field name with ``-`` for ``_``.
    short : str, optional
        A short flag (``-m``).
    choices : sequence of str, or "module:NAME"
        Valid names (or where to find them, imported only when needed). Values are
        normalised (lower case, ``_`` for ``-``), so ``gray-world`` and ``gray_world`` are one.
    metavar : str, optional
        The placeholder shown in ``--help``.
    hidden : bool
        Accepted but not listed in ``--help``.
    output, input : bool
        The field is a path the workflow writes (checked and written all or nothing with the
        main output) or reads (never overwritten by an output).
    folder : bool
        With ``output``: the path is a folder the workflow fills (``--force`` replaces it
        whole), not a file.
    minimum, maximum : float, optional
        Bounds of a number (an ``int`` or ``float`` field), checked when the options are made;
        an ``int`` field without ``maximum`` is at most ``2**62``.
    """
    meta = {
        "help": help,
        "flag": flag,
        "short": short,
        "choices": choices,
        "metavar": metavar,
        "hidden": hidden,
        "output": output,
        "folder": folder,
        "input": input,
        "minimum": minimum,
        "maximum": maximum,
    }
    if isinstance(default, (list, dict, set)):
        raise TypeError("use a tuple for a sequence default")
    return field(default=default, metadata=meta)


def resolve(ref: str) -> Any:
    """Return the object named by ``"package.module:attribute"`` (imported on first use)."""
    module, _, attr = ref.partition(":")
    obj: Any = importlib.import_module(module)
    for part in attr.split("."):
        obj = getattr(obj, part)
    return obj


def choice_names(choices: Sequence[str] | str | Mapping[str, Any]) -> tuple[str, ...]:
    """Return the valid names of a ``choices`` declaration, in their normalised spelling."""
    describe = _describe

    names: Any = choices
    if isinstance(choices, str):
        try:
            names = resolve(choices) if ":" in choices else None
        except (ImportError, AttributeError):
            names = None
    if isinstance(names, str) or not isinstance(names, Sequence | Mapping | set | frozenset):
        raise InvalidInputError(
            'expected choices as names or "module:NAME" of a sequence of names, got '
            f"{describe(choices)}"
        )
    if not all(isinstance(n, str) for n in names):
        raise InvalidInputError(f"expected choices as names (str), got {describe(choices)}")
    return tuple(_norm(n) for n in names)


def _describe(value: object, width: int = 40) -> str:
    """Describe a value for a one-line message, without importing NumPy.

    As ``imageform._validate.describe``, which imports NumPy: ``imageform --help`` must not.
    """
    shape = getattr(value, "shape", None)
    if shape is not None and getattr(value, "ndim", None):
        return f"{type(value).__name__} of shape {tuple(shape)}, {getattr(value, 'dtype', '')}"
    text = repr(value)
    return text if len(text) <= width else text[: width - 3] + "..."


def _norm(value: str) -> str:
    return value.strip().lower().replace("-", "_").replace(" ", "_")


def normalize_choice(value: object, choices: Sequence[str] | str, what: str) -> str:
    """``value`` in its normalised spelling if it is one of ``choices``, else raise.

    Examples
    --------
    >>> normalize_choice("Gray-World", ("gray_world", "white_patch"), "--method")
    'gray_world'
    """
    describe = _describe

    if not isinstance(value, str):
        raise UnknownOptionError(f"expected a name as the {what} value, got {describe(value)}")
    names = choice_names(choices)
    key = _norm(value)
    if key not in names:
        raise UnknownOptionError(f"unknown {what} {describe(value)}; valid: {_shown(names)}")
    return key


def _shown(names: Sequence[str], width: int = 120) -> str:
    """Names for a one-line message: as many as fit ``width`` characters, then how many more."""
    out = ""
    for i, n in enumerate(names):
        part = (", " if out else "") + n.replace("_", "-")
        if len(out) + len(part) > width:
            return out + f", ... ({len(names) - i} more)"
        out += part
    return out


def flag_of(f: dataclasses.Field[Any]) -> str:
    """Return the long command-line flag of an options field."""
    return f.metadata.get("flag") or "--" + f.name.replace("_", "-")


def option_label(f: dataclasses.Field[Any]) -> str:
    """Return how messages name an options field: its flag, and the field name too if it differs.

    The field name is added when the flag spells another word (``--from (src)``), so that API and
    command-line users both see it.
    """
    flag = flag_of(f)
    return flag if flag[2:].replace("-", "_") == f.name else f"{flag} ({f.name})"


#: The largest value of an ``int`` option without a declared ``maximum`` (fits int64).
_INT_MAX = 2**62


_HINTS: dict[str, dict[str, Any]] = {}


def _hints(cls: type) -> dict[str, Any]:
    """Return the evaluated field types of an options class (computed once per class)."""
    key = f"{cls.__module__}.{cls.__qualname__}.{id(cls)}"
    if key not in _HINTS:
        _HINTS[key] = typing.get_type_hints(cls)
    return _HINTS[key]


def _unwrap_optional(tp: Any) -> tuple[Any, bool]:
    """(type, optional) from ``X | None``."""
    if typing.get_origin(tp) in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(tp) if a is not type(None)]
        if len(args) == 1:
            return args[0], True
    return tp, False


def _checked(value: Any, hint: Any, f: dataclasses.Field[Any], label: str) -> Any:
    """Return ``value`` of the options field ``f`` checked against its declared type and bounds.

    NumPy scalars and 0-d arrays are accepted as numbers; the result is the plain Python value;
    otherwise an error in one line names ``label``.
    """
    from imageform._validate import as_bool, as_int, as_path, as_real, describe

    tp, optional = _unwrap_optional(hint)
    if value is None:
        if optional:
            return None
        raise InvalidInputError(f"expected {label} as {_kind(tp)}, got None")
    lo, hi = f.metadata.get("minimum"), f.metadata.get("maximum")
    if tp is bool:
        return as_bool(value, label)
    if tp is int:
        return as_int(value, label, minimum=lo, maximum=_INT_MAX if hi is None else hi)
    if tp is float:
        return as_real(value, label, minimum=lo, maximum=hi)
    if tp is str or typing.get_origin(tp) is typing.Literal:  # Literal: a choice's names
        if isinstance(value, str):
            return str(value)
        raise InvalidInputError(f"expected {label} as text, got {describe(value)}")
    if tp is Path:
        return as_path(value, label)
    if typing.get_origin(tp) is tuple:
        args = typing.get_args(tp)
        if not isinstance(value, tuple | list):
            raise InvalidInputError(f"expected {label} as a sequence, got {describe(value)}")
        if len(args) == 2 and args[1] is Ellipsis:
            kinds = [args[0]] * len(value)
        elif len(value) != len(args):
            raise InvalidInputError(
                f"expected {label} as {len(args)} values, got {len(value)}: {describe(value)}"
            )
        else:
            kinds = list(args)
        pairs = enumerate(zip(value, kinds, strict=True))
        return tuple(_checked(v, k, f, f"{label}[{i}]") for i, (v, k) in pairs)
    return value


def _kind(tp: Any) -> str:
    names = {bool: "True or False", int: "an integer", float: "a number", str: "text"}
    return names.get(tp, "a file name" if tp is Path else "a value")


@dataclass(frozen=True)
class Options:
    """Base of every workflow's options: normalises names given as ``choices``.

    Subclasses add cross-field checks in ``check()``; both run when the options are made,
    whoever makes them (the API, the command line or ``imageform batch``).
    """

    def __post_init__(self) -> None:
        hints = _hints(type(self))
        for f in dataclasses.fields(self):
            label = option_label(f)
            value = _checked(getattr(self, f.name), hints[f.name], f, label)
            choices = f.metadata.get("choices")
            if choices is not None and value is not None:
                value = normalize_choice(value, choices, label)
            object.__setattr__(self, f.name, value)
        self.check()

    def check(self) -> None:
        """Cross-field checks (raise :class:`~imageform.errors.InvalidInputError`)."""

    def check_output(self, path: Path) -> None:
        """Refuse a main output these options cannot write.

        ``imageform batch`` checks every output suffix with it before any job starts.
        """

    @classmethod
    def fields(cls) -> tuple[dataclasses.Field[Any], ...]:
        """Return the dataclass fields, in declaration order."""
        return dataclasses.fields(cls)

    @classmethod
    def types(cls) -> dict[str, Any]:
        """Return the evaluated type of each field."""
        return typing.get_type_hints(cls)

    def paths(self, kind: str) -> tuple[Path, ...]:
        """Return the paths in fields declared ``output=True`` or ``input=True`` (by ``kind``)."""
        out: list[Path] = []
        for f in dataclasses.fields(self):
            if f.metadata.get(kind):
                v = getattr(self, f.name)
                if isinstance(v, (tuple, list)):
                    out += [Path(x) for x in v if x is not None]
                elif v is not None:
                    out.append(Path(v))
        return tuple(out)


@dataclass(frozen=True)
class Input:
    """A positional input of a command: one or more files, or a value.

    A file (``many``: one or more, glob patterns expanded), or a value (``kind="text"``).
    """

    name: str
    help: str
    many: bool = False
    metavar: str | None = None
    kind: str = "file"
    #: A folder given stands for the image files in it (:func:`imageform.io.image_files`).
    folders: bool = False
    #: The file suffixes this input reads, which pick a folder's files in ``imageform batch``
    #: (``develop``: :data:`imageform.io.RAW_SUFFIXES`); None: the image files
    #: (:data:`imageform.io.IMAGE_FORMATS`).
    suffixes: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        if self.metavar is not None and not isinstance(self.metavar, str):
            raise TypeError(
                f"expected metavar as a str (or None), got {type(self.metavar).__name__}"
            )
        sfx = self.suffixes
        if sfx is not None and not (
            isinstance(sfx, tuple) and all(isinstance(x, str) and x.startswith(".") for x in sfx)
        ):
            raise TypeError(
                f"expected suffixes as a tuple of suffixes ('.dng', ...) or None, got "
                f"{type(sfx).__name__}"
            )


@dataclass(frozen=True)
class Output:
    """The main output of a command, always ``-o/--out``.

    ``folder``: the output is a folder the command fills; ``holds`` says what it holds, in a
    few words (``"cameras.csv, points.ply, report.html, metrics.json"``), which the refusal
    of a file name for it quotes (``reconstruct -o room.ply``).
    """

    help: str
    required: bool = True
    default: str | None = None
    folder: bool = False
    holds: str = ""

    def __post_init__(self) -> None:
        if self.default is not None and not isinstance(self.default, str):
            raise TypeError(
                f"expected default as a str (or None), got {type(self.default).__name__}"
            )
        if not isinstance(self.holds, str):
            raise TypeError(f"expected holds as a str, got {type(self.holds).__name__}")


@dataclass(frozen=True)
class Result:
    """What a workflow did.

    Attributes
    ----------
    summary : mapping
        The machine-readable result (``--json`` prints it; ``imageform batch`` keeps it).
    text : tuple
        Lines for a person (str, or a rich renderable such as a table).
    notes : tuple of str
        One-line notes and warnings, printed on stderr.
    check_failed : bool
        A check the command performs failed (exit code 3).
    """

    summary: Mapping[str, Any]
    text: tuple[Any, ...] = ()
    notes: tuple[str, ...] = ()
    check_failed: bool = False


@dataclass
class Run:
    """What a running workflow may use: its outputs, notes for the user, and a progress callback.

    The outputs are written all or nothing.
    """

    outputs: Any  # imageform._files.Outputs (imported lazily: it is cheap, but keep --help lean)
    notes: list[str] = field(default_factory=list)
    progress: Callable[[str, float], None] | None = None
    #: The input files a folder or a glob pattern stood for, not named one by one: a workflow
    #: may skip one it cannot read (with a note); a file named is read or refused.
    gathered: frozenset[Path] = frozenset()

    def __post_init__(self) -> None:
        if self.progress is not None and not callable(self.progress):
            raise TypeError(
                f"expected progress as a callable progress(step, fraction) or None, got "
                f"{type(self.progress).__name__}"
            )

    def file(self, path: str | Path) -> Path:
        """Return the temporary path to write for the output ``path`` (checked on first use)."""
        part = self.outputs.part(path)
        return Path(part) if part is not None else Path(self.outputs.file(path))

    def folder(self, path: str | Path) -> Path:
        """Return a temporary folder to fill for the output folder ``path``."""
        part = self.outputs.part(path)
        return Path(part) if part is not None else Path(self.outputs.folder(path))

    def note(self, text: str) -> None:
        """Add a one-line note for the user (stderr); a note already given is not repeated."""
        if text not in self.notes:
            self.notes.append(text)


def check_suffix(path: Path | None, suffix: str, flag: str, what: str) -> None:
    """Refuse an output ``path`` of ``flag`` that does not end in ``suffix`` (JSON in a .png)."""
    if path is not None and path.suffix.lower() != suffix:
        from imageform._validate import shorten

        raise InvalidInputError(
            f"{flag} writes {what}: give a {suffix} name, not {shorten(repr(path.name), 60)}"
        )


def refuse_foreign_folder(
    out: Path, force: bool, markers: Sequence[str], command: str, previous: str
) -> None:
    """With ``--force``, replace only an output folder that ``imageform COMMAND`` wrote.

    A folder that exists, is not empty and holds none of the command's ``markers`` (the
    files only it writes there) is refused: never a folder of the user's files.
    ``previous`` names what it would have replaced ("a previous simulation").
    """
    marked = any((out / m).exists() for m in markers)
    if out.is_dir() and force and not marked and any(out.iterdir()):
        raise InvalidInputError(
            f"output folder {out} exists and is not an imageform {command} output; "
            f"choose a new folder (--force replaces only {previous})"
        )


@dataclass(frozen=True)
class Workflow:
    """A file-level operation: its name on the command line, its options and its function.

    Attributes
    ----------
    name : str
        Command name (``white-balance``).
    summary : str
        One line for ``imageform --help``.
    function : str
        ``"module:function"`` called as ``function(run, options, out=..., **inputs)``.
    options : type
        The :class:`Options` dataclass.
    inputs : tuple of Input
        Positional inputs, in order.
    output : Output or None
        The main output (``-o/--out``).
    batch : bool
        Runs file by file in ``imageform batch`` (one image in, one image out).
    suffixes : tuple of str
        Output suffixes it can write.
    group : str
        Section of ``imageform --help``.
    description : str
        More help for ``imageform NAME --help``.
    """

    name: str
    summary: str
    function: str
    options: type[Options]
    inputs: tuple[Input, ...] = ()
    output: Output | None = None
    batch: bool = False
    suffixes: tuple[str, ...] = IMAGE_SUFFIXES
    group: str = "tools"
    description: str = ""

    def make_options(self, **values: Any) -> Options:
        """Return the options from keyword values (unknown names refused, with the valid ones)."""
        known = {f.name for f in self.options.fields()}
        old = set(getattr(self.options, "__renamed_fields__", {}))  # kept with a warning
        unknown = sorted(set(values) - known - old)
        if unknown:
            raise UnknownOptionError(
                f"unknown option(s) {', '.join(unknown)} of {self.name}; valid: "
                f"{', '.join(sorted(known)) or 'none'}"
            )
        try:
            return self.options(**values)
        except TypeError as exc:
            raise InvalidInputError(f"{self.name}: {exc}") from None
