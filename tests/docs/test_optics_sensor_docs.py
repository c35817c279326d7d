"""The Python examples in docs/optics.md, docs/sensor.md and docs/distortion.md run."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[2] / "docs"
PAGES = ["optics.md", "sensor.md", "distortion.md"]


def _blocks(page: str) -> list[str]:
    text = (DOCS / page).read_text(encoding="utf-8")
    return re.findall(r"```python\n(.*?)```", text, flags=re.S)


@pytest.mark.parametrize("page", PAGES)
def test_doc_examples_run(page: str, capsys: pytest.CaptureFixture[str]) -> None:
    blocks = _blocks(page)
    assert blocks, f"{page} has no python examples"
    for code in blocks:
        exec(compile(code, f"{page}", "exec"), {"__name__": "__doc_example__"})
    capsys.readouterr()
