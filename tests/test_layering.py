"""The layering contract, checked on the source with ``ast`` (no import is executed).

The layers, lowest first, are declared once: the table of docs/design.md between its
``<!-- layers -->`` markers, which the documentation renders and :func:`declared_layers`
reads here (0 core: imageform.errors and every private top-level module imageform._*, the
documented internal modules; then spectral, color, ...). A module imports only from its own
layer or lower ones.

Rules, for every import in a module (top-level and function-local, ``import`` and
``from ... import``, relative imports, ``importlib.import_module("...")`` with a literal
name):

- **layer**: the imported package is in the importer's layer or a lower one;
- **private name**: no name with a leading underscore is imported from another package
  (``from imageform.color.hsv import _srgb_to_hsv``), none is reached as an attribute of
  another package's module (``ycbcr._coeffs``), and no private module of another package is
  imported (``imageform.geometry._normalize``). The core modules ``imageform._*`` are
  documented internal modules: their public names are for every package;
- **package cycle**: packages of the same layer may import each other only one way;
- **module cycle**: the modules of one package do not import each other in a cycle (the
  renderer imports the scene, never the other way round).

``imageform/__init__.py`` (the lazy namespace) and ``imageform/__main__.py`` (the entry
point) are exempt. Type-checking-only imports count like any other.
"""

from __future__ import annotations

import ast
import re
from collections import defaultdict
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"
PACKAGE = SRC / "imageform"

DESIGN = SRC.parent / "docs" / "design.md"


def declared_layers(text: str) -> tuple[dict[str, int], list[str]]:
    """``({package: layer}, core modules listed)`` from the layers table of docs/design.md.

    The table sits between ``<!-- layers -->`` and ``<!-- /layers -->``; each row is
    ``| N [name] | `pkg`, `pkg` | what lives there |``. The core row (``0 core``) lists
    ``errors`` and the private top-level modules; every one of them is layer ``core``.
    """
    m = re.search(r"<!-- layers -->\n(.*?)<!-- /layers -->", text, re.S)
    if m is None:
        raise AssertionError("docs/design.md has no <!-- layers --> ... <!-- /layers --> table")
    layers: dict[str, int] = {}
    core: list[str] = []
    for row in m.group(1).splitlines():
        cells = [c.strip() for c in row.strip().strip("|").split("|")]
        if len(cells) < 3 or not re.match(r"\d+\b", cells[0]):
            continue  # the header and the |---| line
        level = int(cells[0].split()[0])
        names = re.findall(r"`([A-Za-z_]\w*)`", cells[1])
        if level == 0:
            core = names
            layers["core"] = 0
        else:
            for name in names:
                layers[name] = level
    return layers, core


#: Layer of each package, as docs/design.md declares it; "core" is imageform.errors and the
#: private imageform._* modules.
LAYERS, CORE_LISTED = declared_layers(DESIGN.read_text(encoding="utf-8"))

#: The namespace and the entry point: they may import anything.
EXEMPT = {"imageform", "imageform.__main__"}

#: Known violations: ``(file under src/imageform, what is imported, rule)``. Empty since
#: issue 15's workflow layer (cli/ and batch/ no longer import each other); an entry that
#: matches nothing fails ``test_allowlist_is_current``.
ALLOWED: set[tuple[str, str, str]] = set()


@dataclass(frozen=True)
class Import:
    """One import of an imageform module (``name``: the imported name, if a ``from``)."""

    path: str  # relative to src/imageform
    line: int
    module: str  # dotted module imported (or imported from)
    name: str | None = None

    @property
    def target(self) -> str:
        return f"{self.module}.{self.name}" if self.name else self.module


@dataclass(frozen=True)
class Violation:
    path: str  # relative to src/imageform
    line: int
    target: str
    rule: str

    def __str__(self) -> str:
        return f"src/imageform/{self.path}:{self.line}: {self.target}: {self.rule}"

    @property
    def key(self) -> tuple[str, str, str]:
        return (self.path, self.target, self.rule)


def package_of(module: str) -> str:
    """``core``, a subpackage name, or ``imageform`` for the namespace itself."""
    parts = module.split(".")
    if len(parts) == 1:
        return "imageform"
    if parts[1] == "errors" or parts[1].startswith("_"):
        return "core"
    return parts[1]


def _private(part: str) -> bool:
    return part.startswith("_") and not part.startswith("__")


class Source:
    """The modules of an ``imageform`` package folder (``src``: the folder holding it)."""

    def __init__(self, src: Path) -> None:
        self.package = src / "imageform"
        self.modules: dict[str, Path] = {}
        for p in sorted(self.package.rglob("*.py")):
            parts = list(p.relative_to(src).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts.pop()
            self.modules[".".join(parts)] = p

    def rel(self, module: str) -> str:
        return self.modules[module].relative_to(self.package).as_posix()

    def imports(self, module: str) -> tuple[list[Import], dict[str, str]]:
        """Every import of an imageform module in ``module`` (anywhere in it), and the local
        names bound to imageform modules (for attribute access)."""
        path = self.modules[module]
        rel = self.rel(module)
        is_package = path.name == "__init__.py"
        found: list[Import] = []
        bound: dict[str, str] = {}
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    if alias.name.split(".")[0] == "imageform":
                        found.append(Import(rel, node.lineno, alias.name))
                        if alias.asname:
                            bound[alias.asname] = alias.name
                        else:
                            bound["imageform"] = "imageform"
            elif isinstance(node, ast.ImportFrom):
                source = _resolve_from(module, is_package, node)
                if source.split(".")[0] != "imageform":
                    continue
                for alias in node.names:
                    sub = f"{source}.{alias.name}"
                    if sub in self.modules:  # from package import submodule
                        found.append(Import(rel, node.lineno, sub))
                        bound[alias.asname or alias.name] = sub
                    else:
                        found.append(Import(rel, node.lineno, source, alias.name))
            elif isinstance(node, ast.Call) and _literal_import_module(node):
                arg = node.args[0]
                assert isinstance(arg, ast.Constant)
                found.append(Import(rel, node.lineno, str(arg.value)))
        return found, bound

    def private_attributes(self, module: str, bound: dict[str, str]) -> Iterator[Violation]:
        """``alias._name`` where ``alias`` names another package's module."""
        own = package_of(module)
        path = self.modules[module]
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not (isinstance(node, ast.Attribute) and _private(node.attr)):
                continue
            chain: list[str] = []
            base: ast.expr = node.value
            while isinstance(base, ast.Attribute):
                chain.append(base.attr)
                base = base.value
            if not (isinstance(base, ast.Name) and base.id in bound):
                continue
            owner = ".".join([bound[base.id], *reversed(chain)])
            if owner in self.modules and package_of(owner) not in (own, "core", "imageform"):
                yield Violation(
                    self.rel(module), node.lineno, f"{owner}.{node.attr}", "private name"
                )


def _resolve_from(importer: str, is_package: bool, node: ast.ImportFrom) -> str:
    if not node.level:
        return node.module or ""
    base = importer.split(".")
    if not is_package:
        base = base[:-1]
    base = base[: len(base) - (node.level - 1)]
    return ".".join([*base, *([node.module] if node.module else [])])


def _literal_import_module(node: ast.Call) -> bool:
    """``importlib.import_module("imageform...")`` or ``import_module("imageform...")``."""
    func = node.func
    name = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", None)
    return (
        name == "import_module"
        and bool(node.args)
        and isinstance(node.args[0], ast.Constant)
        and isinstance(node.args[0].value, str)
        and node.args[0].value.split(".")[0] == "imageform"
    )


def _cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one node (Tarjan), sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(edges.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return sorted(found)


def violations(src: Path = SRC) -> list[Violation]:
    """Every break of the contract in the ``imageform`` package under ``src``."""
    tree = Source(src)
    out: list[Violation] = []
    package_edges: dict[tuple[str, str], list[Import]] = defaultdict(list)
    module_edges: dict[str, set[str]] = defaultdict(set)
    module_sites: dict[tuple[str, str], list[Import]] = defaultdict(list)
    for module in tree.modules:
        if module in EXEMPT:
            continue
        own = package_of(module)
        if own not in LAYERS:
            out.append(Violation(tree.rel(module), 1, module, "package missing from LAYERS"))
            continue
        found, bound = tree.imports(module)
        for imp in found:
            # the module an import loads: `from imageform.color.hsv import f` loads hsv
            target_module = imp.target if imp.target in tree.modules else imp.module
            dst = package_of(target_module)
            if dst == "imageform":
                continue  # the namespace: errors and __version__, nothing heavy
            if dst not in LAYERS:
                out.append(Violation(imp.path, imp.line, imp.target, "unknown package"))
                continue
            if LAYERS[dst] > LAYERS[own]:
                rule = f"layer: {own} ({LAYERS[own]}) imports {dst} ({LAYERS[dst]})"
                out.append(Violation(imp.path, imp.line, imp.target, rule))
            if dst == own:
                module_edges[module].add(target_module)
                module_sites[(module, target_module)].append(imp)
            elif dst != "core":
                if imp.name is not None and _private(imp.name):
                    out.append(Violation(imp.path, imp.line, imp.target, "private name"))
                elif any(_private(p) for p in target_module.split(".")[2:]):
                    out.append(Violation(imp.path, imp.line, imp.target, "private module"))
                package_edges[(own, dst)].append(imp)
        out.extend(tree.private_attributes(module, bound))

    # packages importing each other
    graph: dict[str, set[str]] = defaultdict(set)
    for a, b in package_edges:
        if a != "core":
            graph[a].add(b)
    for comp in _cycles(graph):
        rule = "package cycle " + " <-> ".join(comp)
        for (a, b), sites in package_edges.items():
            if a in comp and b in comp:
                out.extend(Violation(i.path, i.line, i.target, rule) for i in sites)

    # modules of one package importing each other in a cycle
    for comp in _cycles(module_edges):
        rule = "module cycle " + " <-> ".join(comp)
        for (a, b), sites in module_sites.items():
            if a in comp and b in comp:
                out.extend(Violation(i.path, i.line, i.target, rule) for i in sites)
    return sorted(set(out), key=lambda v: (v.path, v.line, v.target, v.rule))


def test_layering_contract() -> None:
    found = violations()
    bad = [v for v in found if v.key not in ALLOWED]
    assert not bad, (
        f"{len(bad)} import(s) break the layering contract (see this module's docstring; "
        "share what two packages need through a public name or a documented core module):\n"
        + "\n".join(str(v) for v in bad)
    )


def test_allowlist_is_current() -> None:
    """Every allowlisted violation still exists (delete the entry when it is fixed), and
    the allowlist covers only the packages being rewritten."""
    keys = {v.key for v in violations()}
    stale = sorted(ALLOWED - keys)
    assert not stale, "allowlisted violations that no longer occur (delete them):\n" + "\n".join(
        f"{p}: {t}: {r}" for p, t, r in stale
    )
    assert all(p.startswith(("cli/", "batch/")) for p, _, _ in ALLOWED)


def test_every_package_has_a_layer() -> None:
    on_disk = {
        p.name for p in PACKAGE.iterdir() if (p / "__init__.py").is_file() and p.name[0] != "_"
    }
    assert on_disk <= set(LAYERS), f"packages without a layer: {sorted(on_disk - set(LAYERS))}"
    assert set(LAYERS) - {"core"} <= on_disk, "docs/design.md lists packages that do not exist"


def test_the_declaration_is_the_documented_table() -> None:
    """The layers come from docs/design.md, the page the documentation site renders
    (mkdocs.yml nav), and its core row names every core module that exists."""
    assert re.search(r"^\s*- .*: design\.md$", (SRC.parent / "mkdocs.yml").read_text(), re.M)
    assert LAYERS["core"] == 0 and LAYERS["workflows"] > LAYERS["report"] > LAYERS["simulate"]
    core_on_disk = {"errors"} | {
        p.stem for p in PACKAGE.iterdir() if p.name.startswith("_") and p.name[1] != "_"
    }
    assert core_on_disk == set(CORE_LISTED), (
        "docs/design.md's core row and the private top-level modules differ: "
        f"missing {sorted(core_on_disk - set(CORE_LISTED))}, "
        f"gone {sorted(set(CORE_LISTED) - core_on_disk)}"
    )


def test_the_table_parser() -> None:
    text = (
        "x\n<!-- layers -->\n| layer | packages | what |\n|---|---|---|\n"
        "| 0 core | `errors`, `_a` | c |\n| 1 | `p`, `q` | d |\n<!-- /layers -->\n"
    )
    assert declared_layers(text) == ({"core": 0, "p": 1, "q": 1}, ["errors", "_a"])


# -- the checker itself: it must see each kind of break ------------------------------------


def _check_source(tmp_path: Path, files: dict[str, str]) -> list[str]:
    """The rules run on a made-up imageform package (path under imageform/ -> source)."""
    for rel, text in files.items():
        f = tmp_path / "imageform" / rel
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_text(text, encoding="utf-8")
    return [str(v).removeprefix("src/imageform/") for v in violations(tmp_path)]


def test_checker_finds_each_kind_of_break(tmp_path: Path) -> None:
    got = _check_source(
        tmp_path,
        {
            "__init__.py": "from imageform import cli\n",  # exempt
            "errors.py": "",
            "_kernels/__init__.py": "",
            "_kernels/fast.py": "def f():\n    from imageform.color import x\n",
            "spectral/__init__.py": "",
            "spectral/data.py": "import importlib\nimportlib.import_module('imageform.io.png')\n",
            "color/__init__.py": "",
            "color/cct.py": "from imageform.spectral.data import _parse\n",
            "color/hsv.py": "from . import cct\nfrom ..geometry import _normalize\n",
            "geometry/__init__.py": "",
            "geometry/_normalize.py": "",
            "geometry/camera.py": "from imageform.optics import lens\n",
            "optics/__init__.py": "",
            "optics/lens.py": "import imageform.geometry.camera as cam\ncam._plane_K\n",
            "simulate/__init__.py": "",
            "simulate/render.py": "from imageform.simulate.scene import Scene\n",
            "simulate/scene.py": "def g():\n    from imageform.simulate import render\n",
        },
    )
    assert got == [
        "_kernels/fast.py:2: imageform.color.x: layer: core (0) imports color (2)",
        "color/cct.py:1: imageform.spectral.data._parse: private name",
        "color/hsv.py:2: imageform.geometry._normalize: layer: color (2) imports geometry (3)",
        "color/hsv.py:2: imageform.geometry._normalize: private module",
        "geometry/camera.py:1: imageform.optics.lens: package cycle geometry <-> optics",
        "optics/lens.py:1: imageform.geometry.camera: package cycle geometry <-> optics",
        "optics/lens.py:2: imageform.geometry.camera._plane_K: private name",
        "simulate/render.py:1: imageform.simulate.scene.Scene: module cycle "
        "imageform.simulate.render <-> imageform.simulate.scene",
        "simulate/scene.py:2: imageform.simulate.render: module cycle "
        "imageform.simulate.render <-> imageform.simulate.scene",
        "spectral/data.py:2: imageform.io.png: layer: spectral (1) imports io (4)",
    ]
