"""One JSON writer (issue 30): every JSON file goes through
:func:`imageform._jsonio.write_json` (atomic, NaN as ``null``), every JSON text through
:func:`imageform._jsonio.dumps`.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from imageform._jsonio import write_json

SRC = Path(__file__).resolve().parents[1] / "src" / "imageform"

#: ``json.dump(s)`` calls allowed outside _jsonio.py, with the reason.
ALLOWED = {
    # a TOML string literal (JSON's escaping is TOML's basic string), not a JSON file
    "simulate/_lab_steps.py": "TOML string value",
    # prints the cache report on stdout, no file
    "cli/_cache.py": "stdout",
}

_DUMP = re.compile(r"\bjson\.dumps?\(")
_HAND_WRITTEN = re.compile(r"write_text\(\s*dumps\(")


def _sources() -> list[tuple[str, str]]:
    return [
        (p.relative_to(SRC).as_posix(), p.read_text(encoding="utf-8"))
        for p in sorted(SRC.rglob("*.py"))
    ]


def test_no_json_dump_outside_the_writer() -> None:
    bad = [
        rel
        for rel, text in _sources()
        if rel != "_jsonio.py" and rel not in ALLOWED and _DUMP.search(text)
    ]
    assert not bad, f"json.dump(s) outside imageform._jsonio (use write_json / dumps): {bad}"


def test_no_hand_written_json_file() -> None:
    """``path.write_text(dumps(...))`` is neither atomic nor one writer: use write_json."""
    bad = [rel for rel, text in _sources() if _HAND_WRITTEN.search(text)]
    assert not bad, bad


def test_allow_list_is_not_stale() -> None:
    texts = dict(_sources())
    assert all(_DUMP.search(texts[rel]) for rel in ALLOWED)


def test_write_json_nan_safe_and_atomic(tmp_path: Path) -> None:
    p = tmp_path / "m.json"
    write_json(p, {"a": np.array([1.0, np.nan, np.inf]), "name": "NaNa.png", "p": tmp_path})
    assert json.loads(p.read_text(encoding="utf-8")) == {
        "a": [1.0, None, None],
        "name": "NaNa.png",
        "p": str(tmp_path),
    }
    # an object that cannot be written leaves the old file as it was, and no temporary
    with pytest.raises(TypeError, match="cannot write"):
        write_json(p, {"x": object()})
    assert json.loads(p.read_text(encoding="utf-8"))["name"] == "NaNa.png"
    assert sorted(q.name for q in tmp_path.iterdir()) == ["m.json"]


def test_write_json_refuses_a_folder(tmp_path: Path) -> None:
    from imageform.errors import InvalidInputError

    with pytest.raises(InvalidInputError):
        write_json(tmp_path, {})


def test_analysis_write_json_is_the_one_writer(tmp_path: Path) -> None:
    """The stain/statistics files (analysis._arrays.write_json) are NaN-safe now."""
    from imageform.analysis._arrays import write_json as analysis_write_json

    analysis_write_json(tmp_path / "s.json", {"kind": "x", "v": [float("nan")]})
    assert json.loads((tmp_path / "s.json").read_text()) == {"kind": "x", "v": [None]}
