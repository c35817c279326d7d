"""Files a scene refers to: paths relative to the scene file, and image textures.

Shared by the scene builder (an image object's aspect ratio) and the renderer (its pixels);
it imports neither, so neither imports the other for it.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

from imageform._files import not_a_regular_file
from imageform._validate import describe
from imageform.errors import InvalidInputError

__all__ = ["load_texture", "resolve_path"]


def resolve_path(path: str, base: Path | None) -> Path:
    """Return ``path`` relative to the scene file's folder ``base``.

    ``base=None`` stands for the working folder; an error names the file when it does not exist.
    """
    if not isinstance(path, str | Path):
        raise TypeError(f"expected path as a file name (str or Path), got {describe(path)}")
    if base is not None and not isinstance(base, str | Path):
        raise TypeError(f"expected base as a folder (str or Path) or None, got {describe(base)}")
    if not str(path).strip():
        raise InvalidInputError("expected path as a file name, got an empty name")
    p = Path(path).expanduser()
    if not p.is_absolute() and base is not None:
        p = Path(base) / p
    try:
        found = p.is_file()
    except OSError as exc:  # a name too long for the file system
        raise InvalidInputError(f"path {describe(str(path), 60)}: {exc.strerror}") from None
    if not found:
        kind = not_a_regular_file(p)
        if kind is not None:
            raise InvalidInputError(f"{describe(str(path), 60)} {kind}")  # as the scene says
        where = "the working folder: base is None" if base is None else "base, the scene's folder"
        raise InvalidInputError(
            f"file not found: {describe(str(p), 100)} (path relative to {where})"
        )
    return p


def load_texture(path: str, base: Path | None) -> np.ndarray:
    """Load an image texture as linear sRGB ``(H, W, 3)`` float64 (decoded from sRGB), read-only.

    Grey images are repeated to three channels; alpha is ignored (the texture is opaque).
    """
    return _texture(str(resolve_path(path, base).resolve()))


@lru_cache(maxsize=8)
def _texture(path: str) -> np.ndarray:
    from imageform._validate import as_image
    from imageform.color import srgb_to_linear
    from imageform.io import read_image

    raw = np.asarray(read_image(path))
    if raw.ndim == 2:
        raw = raw[..., None]
    if raw.shape[-1] == 1:
        raw = np.repeat(raw, 3, axis=-1)
    if raw.shape[-1] == 4:
        raw = raw[..., :3]  # alpha is ignored: the texture is opaque
    img = np.asarray(as_image(raw, "texture"), dtype=np.float64)  # uint8/16 -> [0, 1]
    if img.min() < 0 or img.max() > 1:
        raise InvalidInputError(
            f"texture {path}: expected encoded sRGB in [0, 1], got {img.min():g}..{img.max():g}"
        )
    lin = np.asarray(srgb_to_linear(img))
    lin.setflags(write=False)
    return lin
