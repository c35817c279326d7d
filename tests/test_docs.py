"""Every ```python block in docs/*.md runs (blocks of one page share a namespace, in order).

Examples run from the repository root, so ``../shared/data/...`` paths work as in the docs;
they must not write files (use a temporary directory if they need to).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[1] / "docs"
PAGES = sorted(DOCS.glob("*.md"))
_BLOCK = re.compile(r"```python\n(.*?)```", re.DOTALL)


@pytest.mark.parametrize("page", PAGES, ids=[p.name for p in PAGES])
def test_doc_examples_run(page: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    blocks = _BLOCK.findall(page.read_text())
    monkeypatch.chdir(DOCS.parent)
    if (
        "../shared/data" in page.read_text()
        and not (DOCS.parent.parent / "shared" / "data").is_dir()
    ):
        pytest.skip("reference data not found")
    namespace: dict[str, object] = {"__name__": f"docs_{page.stem}"}
    for i, code in enumerate(blocks):
        if "torch" in code:
            pytest.importorskip("torch")
        try:
            exec(compile(code, f"{page.name}[block {i}]", "exec"), namespace)
        except Exception as exc:  # pragma: no cover - the message is the point
            pytest.fail(f"{page.name} block {i} failed: {type(exc).__name__}: {exc}")
