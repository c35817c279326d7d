"""The manifest of a batch output folder: what produced each output (internal)."""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

from imageform.batch._plan import Job, _stamp

#: The manifest of a batch output folder: what produced each output.
MANIFEST = ".imageform-batch.json"
_MANIFEST_VERSION = 1


def _read_manifest(out_root: Path) -> dict[str, Any]:
    path = out_root / MANIFEST
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    if not isinstance(data, dict) or data.get("version") != _MANIFEST_VERSION:
        return {}
    outputs = data.get("outputs")
    return outputs if isinstance(outputs, dict) else {}


def _write_manifest(out_root: Path, outputs: dict[str, Any]) -> None:
    from imageform._jsonio import write_json

    out_root.mkdir(parents=True, exist_ok=True)
    write_json(out_root / MANIFEST, {"version": _MANIFEST_VERSION, "outputs": outputs}, indent=1)


def _entry(job: Job, producer: dict[str, Any]) -> dict[str, Any] | None:
    try:
        return {**producer, "input": str(job.input), "input_stamp": _stamp(job.input)}
    except OSError:
        return None


class _Manifest:
    """The manifest being updated as jobs finish (saved at most once a second)."""

    def __init__(self, root: Path, outputs: dict[str, Any], producer: dict[str, Any]) -> None:
        self.root, self.outputs, self.producer = root, outputs, producer
        self.saved_at = 0.0
        self.dirty = False

    def done(self, job: Job) -> None:
        entry = _entry(job, self.producer)
        if entry is not None:
            self.outputs[job.output.relative_to(self.root).as_posix()] = entry
            self.dirty = True
        if time.monotonic() - self.saved_at > 1.0:
            self.save()

    def save(self) -> None:
        if self.dirty:
            _write_manifest(self.root, self.outputs)
            self.dirty = False
        self.saved_at = time.monotonic()
