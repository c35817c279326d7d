"""The public API of imageform as text, and the command that rewrites its snapshot.

The published API is package-level (as scikit-image's ``__init__.pyi`` makes it): the
namespaces are ``imageform`` and the modules its ``__all__`` lists (its subpackages and
:mod:`imageform.errors`), and every name of their ``__all__`` is listed: functions with their
signature, classes with their constructor signature and public members (methods,
properties, class attributes), other objects with their type. The submodules of a package
(``imageform.geometry.checkerboard_grid``, ...) are its implementation: import from the
package; a name that only a submodule's ``__all__`` lists is shared inside imageform and its
tests, is not in the API reference and may change without a deprecation (docs/design.md,
"Public API"). Objects marked deprecated by :mod:`imageform._deprecate` (``__deprecated__``)
say so, and a module ``__getattr__`` built by :func:`imageform._deprecate.module_getattr`
lists the old names it still serves.

``tests/test_api_snapshot.py`` compares this text with ``tests/api_snapshot.txt``. After a
deliberate API change, rewrite the snapshot from the repository root and commit it with the
change (and a CHANGELOG.md entry)::

    PYTHONPATH=src python -m tests.regen_api_snapshot
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re
import sys
from pathlib import Path
from types import ModuleType
from typing import Any, ForwardRef

SNAPSHOT = Path(__file__).with_name("api_snapshot.txt")
REGEN = "PYTHONPATH=src python -m tests.regen_api_snapshot"

_ADDRESS = re.compile(r" at 0x[0-9a-fA-F]+")
_P = inspect.Parameter


def public_namespaces() -> list[ModuleType]:
    """The published namespaces, by name: ``imageform`` and the modules of its ``__all__``."""
    import imageform

    names = [
        f"imageform.{name}"
        for name in imageform.__all__
        if inspect.ismodule(getattr(imageform, name, None))
    ]
    return [importlib.import_module(n) for n in ["imageform", *sorted(names)]]


def public_modules() -> list[ModuleType]:
    """``imageform`` and every public submodule that defines ``__all__``, by name.

    More than :func:`public_namespaces`: the checks of every public signature (spellings,
    registries, docstrings) also read the submodules, the implementation of the packages.
    """
    import imageform

    names = ["imageform"]
    for info in pkgutil.walk_packages(imageform.__path__, "imageform."):
        if not any(part.startswith("_") for part in info.name.split(".")):
            names.append(info.name)
    mods = [importlib.import_module(n) for n in sorted(names)]
    return [m for m in mods if hasattr(m, "__all__")]


def _annotation(a: Any) -> str:
    if isinstance(a, str):
        return a
    if isinstance(a, ForwardRef):  # NamedTuple fields under `from __future__ import annotations`
        return a.__forward_arg__
    return inspect.formatannotation(a)


def _default(v: Any) -> str:
    return _ADDRESS.sub("", repr(v))


def format_signature(sig: inspect.Signature, *, drop_first: bool = False) -> str:
    """``(a: int, /, b: str = 'x', *, c: float, **kw: Any) -> R``, annotations unquoted."""
    params = list(sig.parameters.values())[1 if drop_first else 0 :]
    out: list[str] = []
    slash = star = False
    for i, p in enumerate(params):
        if p.kind is _P.POSITIONAL_ONLY:
            slash = True
        elif slash:
            out.append("/")
            slash = False
        if p.kind is _P.KEYWORD_ONLY and not star:
            out.append("*")
            star = True
        if p.kind is _P.VAR_POSITIONAL:
            star = True
        text = {_P.VAR_POSITIONAL: "*", _P.VAR_KEYWORD: "**"}.get(p.kind, "") + p.name
        if p.annotation is not _P.empty:
            text += f": {_annotation(p.annotation)}"
        if p.default is not _P.empty:
            text += (" = " if p.annotation is not _P.empty else "=") + _default(p.default)
        out.append(text)
        if i == len(params) - 1 and slash:
            out.append("/")
    ret = ""
    if sig.return_annotation is not inspect.Signature.empty:
        ret = f" -> {_annotation(sig.return_annotation)}"
    return f"({', '.join(out)}){ret}"


def _deprecation(obj: Any) -> str:
    target = obj.fget if isinstance(obj, property) else obj
    target = getattr(target, "__func__", target)
    note = getattr(target, "__deprecated__", None)
    return f"  [deprecated: {note}]" if note else ""


def _signature(obj: Any, *, drop_first: bool = False) -> str:
    try:
        return format_signature(inspect.signature(obj), drop_first=drop_first)
    except (TypeError, ValueError):
        return "(...)"


def _fields(cls: type) -> set[str]:
    return set(getattr(cls, "__dataclass_fields__", {})) | set(getattr(cls, "_fields", ()))


def _kind(cls: type) -> str:
    if hasattr(cls, "_fields") and tuple in cls.__bases__:
        return "NamedTuple"
    params = getattr(cls, "__dataclass_params__", None)
    if params is not None:
        return "frozen dataclass" if params.frozen else "dataclass"
    bases = [b.__qualname__ for b in cls.__bases__ if b is not object]
    return f"bases: {', '.join(bases)}" if bases else ""


def _class_lines(name: str, cls: type) -> list[str]:
    head = f"  class {name}"
    own_init = any(
        "__init__" in vars(k) or "__new__" in vars(k)
        for k in cls.__mro__
        if k.__module__.startswith("imageform")
    )
    if _fields(cls) or own_init:
        head += _signature(cls).removesuffix(" -> None")
    kind = _kind(cls)
    lines = [head + (f"  [{kind}]" if kind else "") + _deprecation(cls)]
    fields = _fields(cls)
    for key in sorted(vars(cls)):
        if key.startswith("_") or key in fields:
            continue
        raw = vars(cls)[key]
        if isinstance(raw, property):
            lines.append(f"    .{key}: property{_deprecation(raw)}")
        elif isinstance(raw, classmethod):
            sig = _signature(raw.__func__, drop_first=True)
            lines.append(f"    .{key}{sig}  [classmethod]{_deprecation(raw)}")
        elif isinstance(raw, staticmethod):
            lines.append(f"    .{key}{_signature(raw.__func__)}  [staticmethod]{_deprecation(raw)}")
        elif inspect.isfunction(raw):
            lines.append(f"    .{key}{_signature(raw, drop_first=True)}{_deprecation(raw)}")
        else:
            lines.append(f"    .{key}: {type(raw).__name__}")
    return lines


def module_lines(mod: ModuleType) -> list[str]:
    """The snapshot lines of one module."""
    lines = [mod.__name__]
    for name in sorted(mod.__all__):
        obj = getattr(mod, name)
        if inspect.isclass(obj):
            lines += _class_lines(name, obj)
        elif inspect.ismodule(obj):
            lines.append(f"  {name}: module {obj.__name__}")
        elif callable(obj) and not inspect.isclass(obj):
            lines.append(f"  def {name}{_signature(obj)}{_deprecation(obj)}")
        else:
            lines.append(f"  {name}: {type(obj).__name__}")
    getter = vars(mod).get("__getattr__")
    for old, new in sorted(getattr(getter, "__deprecated_names__", {}).items()):
        lines.append(f"  {old}  [deprecated: use {new}]")
    return lines


def render() -> str:
    """The whole snapshot text."""
    out: list[str] = [
        "# The public API of imageform: every name of the __all__ of imageform and of each",
        "# namespace its __all__ lists; submodules are implementation (generated).",
        f"# Regenerate after a deliberate change: {REGEN}",
    ]
    for mod in public_namespaces():
        out += ["", *module_lines(mod)]
    return "\n".join(out) + "\n"


def main() -> int:
    text = render()
    SNAPSHOT.write_text(text, encoding="utf-8")
    n = sum(
        1 for line in text.splitlines() if line.startswith("  ") and not line.startswith("    ")
    )
    print(f"wrote {SNAPSHOT} ({len(public_namespaces())} namespaces, {n} public names)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
