"""The public API is package-level: import from the package, submodules are implementation.

The published namespaces are ``imageform`` and the modules its ``__all__`` lists (the
subpackages and :mod:`imageform.errors`); ``tests/api_snapshot.txt`` lists those and nothing
else. A name only a submodule's ``__all__`` lists (``imageform.geometry.checkerboard_grid.
label_lattice``) is shared inside imageform and its tests; the documentation never shows it
as API: the reference pages render packages, and the pages, the README and the gallery import
from packages (docs/design.md, "Public API").
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re
from collections.abc import Iterator
from pathlib import Path

import imageform
from tests.regen_api_snapshot import SNAPSHOT, public_namespaces

ROOT = Path(__file__).resolve().parents[1]

_FROM = re.compile(
    r"^[ \t]*(?:>>>[ \t]*|\.\.\.[ \t]*)?from[ \t]+(imageform(?:\.\w+)*)[ \t]+import[ \t]+"
    r"(\([^)]*\)|[^\n]*)",
    re.MULTILINE,
)
_IMPORT = re.compile(
    r"^[ \t]*(?:>>>[ \t]*|\.\.\.[ \t]*)?import[ \t]+(imageform(?:\.\w+)+)", re.MULTILINE
)
_DOTTED = re.compile(r"\bimageform\.([a-z]\w*)\.([a-z]\w*)\.(\w+)")
_DIRECTIVE = re.compile(r"^:::\s*(\S+)", re.MULTILINE)


def _user_files() -> list[Path]:
    """What users read and copy: the pages, the README and the gallery's scripts."""
    return sorted([*ROOT.glob("docs/*.md"), ROOT / "README.md", *ROOT.glob("examples/**/*.py")])


def _namespace_names() -> set[str]:
    return {m.__name__ for m in public_namespaces()}


def _is_public(dotted: str) -> bool:
    return not any(part.startswith("_") for part in dotted.split("."))


def test_the_snapshot_lists_the_package_level_namespaces_only() -> None:
    headers = [
        line for line in SNAPSHOT.read_text(encoding="utf-8").splitlines() if line[:1].isalpha()
    ]
    assert headers == [m.__name__ for m in public_namespaces()]
    for mod in public_namespaces()[1:]:
        # a subpackage, or a module right below imageform (imageform.errors)
        assert mod.__name__.count(".") == 1, mod.__name__


def test_every_public_subpackage_is_a_namespace() -> None:
    """A new public subpackage is listed in imageform.__all__ (and so in the snapshot)."""
    on_disk = {
        f"imageform.{info.name}"
        for info in pkgutil.iter_modules(imageform.__path__)
        if info.ispkg and not info.name.startswith("_")
    }
    assert on_disk - _namespace_names() == set()


def _import_problems(text: str, where: str) -> list[str]:
    """The imports in ``text`` that are not from a published namespace or name something
    that namespace's ``__all__`` does not export."""
    wrong: list[str] = []
    namespaces = _namespace_names()
    for m in _FROM.finditer(text):
        at = f"{where}:{text.count(chr(10), 0, m.start()) + 1}"
        module = m.group(1)
        if not _is_public(module):
            continue  # a page on internals may show a private module
        if module not in namespaces:
            wrong.append(f"{at}: from {module} import ... (import from its package)")
            continue
        names = re.findall(r"(\w+)(?:\s+as\s+\w+)?", re.sub(r"#.*", "", m.group(2)))
        exported = set(importlib.import_module(module).__all__)
        wrong += [f"{at}: {module}.{x} is not exported" for x in names if x not in exported]
    for m in _IMPORT.finditer(text):
        if _is_public(m.group(1)) and m.group(1) not in namespaces:
            at = f"{where}:{text.count(chr(10), 0, m.start()) + 1}"
            wrong.append(f"{at}: import {m.group(1)} (import its package)")
    return wrong


def test_the_pages_import_from_packages() -> None:
    """Every import the pages, the README and the gallery show is from a published namespace,
    and names only what that namespace's ``__all__`` exports."""
    wrong: list[str] = []
    for path in _user_files():
        wrong += _import_problems(path.read_text(encoding="utf-8"), str(path.relative_to(ROOT)))
    assert wrong == [], "\n".join(wrong)


def _documented() -> Iterator[tuple[str, object]]:
    """``(name, object)`` for every namespace and every function, class and method of their
    ``__all__``: what the API reference renders, docstring examples included."""
    for mod in public_namespaces():
        yield mod.__name__, mod
        for name in mod.__all__:
            obj = getattr(mod, name)
            if inspect.isfunction(obj) or inspect.isclass(obj):
                yield f"{mod.__name__}.{name}", obj
            if inspect.isclass(obj):
                for key, raw in vars(obj).items():
                    fn = getattr(raw, "__func__", getattr(raw, "fget", raw))
                    if not key.startswith("_") and inspect.isfunction(fn):
                        yield f"{mod.__name__}.{name}.{key}", fn


def test_the_reference_docstrings_import_from_packages() -> None:
    """The examples of the docstrings the API reference renders import from packages too."""
    wrong: list[str] = []
    for where, obj in _documented():
        wrong += _import_problems(inspect.getdoc(obj) or "", where)
    assert wrong == [], "\n".join(sorted(set(wrong)))


def test_the_pages_name_exported_objects_by_their_package() -> None:
    """Prose may point at an implementation (``imageform.simulate.stages.diffraction_blur``),
    but a name the package exports is written as the package's (``imageform.simulate.
    diffraction_psf_kernel``, not ``imageform.simulate.stages.diffraction_psf_kernel``)."""
    wrong: list[str] = []
    for path in _user_files():
        for m in _DOTTED.finditer(path.read_text(encoding="utf-8")):
            pkg = importlib.import_module(f"imageform.{m.group(1)}")
            sub = f"imageform.{m.group(1)}.{m.group(2)}"
            if not hasattr(pkg, "__path__") or m.group(3) not in pkg.__all__:
                continue
            try:
                importlib.import_module(sub)
            except ImportError:
                continue  # imageform.pkg.Class.method: already the package's name
            wrong.append(
                f"{path.relative_to(ROOT)}: {m.group(0)} -> imageform.{m.group(1)}.{m.group(3)}"
            )
    assert wrong == [], "\n".join(wrong)


def test_the_reference_pages_document_packages() -> None:
    """Each ``::: target`` of docs/reference is a published namespace. The one exception is
    a function that shares its name with its module (``imageform.color.convert``): the
    package exports the function, but mkdocstrings resolves the package's attribute to the
    submodule, so the page names it ``imageform.color.convert.convert``."""
    wrong: list[str] = []
    namespaces = _namespace_names()
    for page in sorted((ROOT / "docs" / "reference").glob("*.md")):
        for target in _DIRECTIVE.findall(page.read_text(encoding="utf-8")):
            if target in namespaces:
                continue
            pkg_name, _, rest = target.rpartition(".")
            pkg_name, _, sub = pkg_name.rpartition(".")
            ok = (
                pkg_name in namespaces
                and rest == sub
                and sub in getattr(importlib.import_module(pkg_name), "__all__", ())
                and getattr(importlib.import_module(pkg_name), sub)
                is getattr(importlib.import_module(f"{pkg_name}.{sub}"), sub)
            )
            if not ok:
                wrong.append(f"{page.relative_to(ROOT)}: ::: {target}")
    assert wrong == [], "document the package, not a submodule:\n" + "\n".join(wrong)
