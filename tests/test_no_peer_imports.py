"""imageform computes everything itself: the peers (colour-science, ...) are test cross-checks."""

from __future__ import annotations

import re
from pathlib import Path

import imageform

SRC = Path(imageform.__file__).parent


def test_library_never_imports_colour_science() -> None:
    pattern = re.compile(r"^\s*(import colour\b|from colour(\.\w+)* import)", re.MULTILINE)
    for f in SRC.rglob("*.py"):
        assert not pattern.search(f.read_text(encoding="utf-8")), f
