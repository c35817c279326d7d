"""Known findings of the fuzz test, not fixed yet (issue 16)."""

from __future__ import annotations

KNOWN: dict[tuple[str, str, str], str] = {}
