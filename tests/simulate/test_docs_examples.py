"""The Python examples of docs/simulate.md and docs/simulate-report.md run as written."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _blocks(doc: str) -> list[str]:
    return re.findall(r"```python\n(.*?)```", (ROOT / "docs" / doc).read_text(), flags=re.S)


@pytest.mark.parametrize("doc", ["simulate.md", "simulate-report.md"])
def test_doc_examples_run(
    doc: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    if doc == "simulate-report.md":
        pytest.importorskip("matplotlib")
    blocks = _blocks(doc)
    assert blocks
    monkeypatch.chdir(tmp_path)
    namespace: dict[str, object] = {}
    for code in blocks:
        exec(compile(code, f"{doc} example", "exec"), namespace)
    out = capsys.readouterr().out
    if doc == "simulate.md":
        assert "2856" in out and "(240, 320, 3)" in out and "ColorCheckerConfig" in out
