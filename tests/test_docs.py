"""Every ```python block in docs/*.md runs (blocks of one page share a namespace, in order).

Examples run in a temporary folder whose ``../shared`` links to the reference data, so the
docs' ``../shared/data/...`` paths work as from the repository root and files an example
writes land in the temporary folder, never in the repository.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[1] / "docs"
PAGES = sorted(DOCS.glob("*.md"))
_BLOCK = re.compile(r"```python\n(.*?)```", re.DOTALL)


@pytest.mark.parametrize("page", PAGES, ids=[p.name for p in PAGES])
def test_doc_examples_run(page: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    blocks = _BLOCK.findall(page.read_text())
    shared = DOCS.parent.parent / "shared"
    if "../shared/data" in page.read_text() and not (shared / "data").is_dir():
        pytest.skip("reference data not found")
    work = tmp_path / "repo"
    work.mkdir()
    if shared.is_dir():
        (tmp_path / "shared").symlink_to(shared.resolve(), target_is_directory=True)
    monkeypatch.chdir(work)
    namespace: dict[str, object] = {"__name__": f"docs_{page.stem}"}
    for i, code in enumerate(blocks):
        if "torch" in code:
            pytest.importorskip("torch")
        if "rawpy" in code:
            pytest.importorskip("rawpy")
        try:
            exec(compile(code, f"{page.name}[block {i}]", "exec"), namespace)
        except Exception as exc:  # pragma: no cover - the message is the point
            pytest.fail(f"{page.name} block {i} failed: {type(exc).__name__}: {exc}")
