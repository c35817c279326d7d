"""The one JSON writer (internal core module, shared by every package).

Every JSON file imageform writes goes through :func:`write_json` (atomic: a temporary
renamed at the end, or in place inside an all-or-nothing :func:`imageform._files.publish`
set; NaN-safe), every JSON text through :func:`dumps` (``tests/test_json_writer.py``
checks that nothing else in ``src`` calls ``json.dump``/``json.dumps``).

JSON has no NaN or infinity. imageform writes them as ``null`` (a missing value) by walking
the object, never by rewriting the text, so a string such as ``"NaNa.png"`` stays intact.
NumPy arrays and scalars become lists and numbers, paths become strings, tuples lists,
dataclasses and NamedTuples objects.
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Mapping
from pathlib import Path, PurePath
from typing import Any

__all__ = ["dumps", "json_ready", "write_json"]


def json_ready(obj: Any) -> Any:
    """``obj`` as plain JSON values: NaN and ±inf become ``None``.

    Examples
    --------
    >>> import numpy as np
    >>> json_ready({"a": np.array([1.0, np.nan]), "b": ("NaNa.png", float("inf"))})
    {'a': [1.0, None], 'b': ['NaNa.png', None]}
    """
    if obj is None or isinstance(obj, (bool, str)):
        return obj
    if isinstance(obj, int):
        return int(obj)
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, PurePath):
        return str(obj)
    if isinstance(obj, Mapping):
        return {str(k): json_ready(v) for k, v in obj.items()}
    if isinstance(obj, tuple) and hasattr(obj, "_asdict"):  # NamedTuple
        return json_ready(obj._asdict())
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return json_ready({f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)})
    if isinstance(obj, (list, tuple, set, frozenset)):
        return [json_ready(v) for v in obj]
    if hasattr(obj, "tolist"):  # numpy arrays and scalars (and array-likes that offer it)
        return json_ready(obj.tolist())
    if hasattr(obj, "item"):
        return json_ready(obj.item())
    raise TypeError(f"cannot write a {type(obj).__name__} as JSON")


def dumps(obj: Any, *, indent: int | None = 2) -> str:
    """JSON text of ``obj`` (see :func:`json_ready`), UTF-8 characters kept.

    Examples
    --------
    >>> dumps({"x": float("nan"), "name": "NaNa.png"}, indent=None)
    '{"x": null, "name": "NaNa.png"}'
    """
    return json.dumps(json_ready(obj), indent=indent, ensure_ascii=False, allow_nan=False)


def write_json(path: str | Path, obj: Any, *, indent: int | None = 2) -> Path:
    r"""Write ``obj`` as JSON (:func:`dumps`, one final newline) to ``path``, atomically.

    The text is built first (an object that cannot be written raises before any file is
    touched), then written to a temporary sibling that replaces ``path`` (or in place
    when ``path`` is a temporary of an all-or-nothing set, :func:`imageform._files.publish`).
    An output that cannot be written (a folder, a device, a missing folder) is refused in
    one line naming ``path``. Returns the path written.

    Examples
    --------
    >>> import tempfile
    >>> p = write_json(Path(tempfile.mkdtemp()) / "m.json", {"x": float("nan")}, indent=None)
    >>> p.read_text()
    '{"x": null}\n'
    """
    from imageform._files import atomic_write, check_writable

    text = dumps(obj, indent=indent) + "\n"
    final = check_writable(path, "path")
    atomic_write(final, lambda tmp: tmp.write_text(text, encoding="utf-8"))
    return final
