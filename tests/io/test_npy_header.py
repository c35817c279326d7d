"""Issue 16: a .npy header is not trusted: channels and memory checked before reading."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imageform.errors import InvalidInputError
from imageform.io import read_image


def _header_only(path: Path, shape: tuple[int, ...]) -> Path:
    with path.open("wb") as fh:
        np.lib.format.write_array_header_1_0(
            fh, {"descr": "<f8", "fortran_order": False, "shape": shape}
        )
    return path


def test_npy_many_channels_refused_from_header(tmp_path: Path) -> None:
    path = _header_only(tmp_path / "a.npy", (2, 2, 10**9))
    with pytest.raises(InvalidInputError, match="1 to 4 channels"):
        read_image(path)


def test_npy_memory_refused_from_header(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("IMAGEFORM_MAX_MEMORY", "1M")
    path = _header_only(tmp_path / "b.npy", (1000, 1000, 3))
    with pytest.raises(InvalidInputError, match="GiB") as info:
        read_image(path)
    assert "\n" not in str(info.value)


def test_camera_file_fields_checked() -> None:
    import numpy as np

    from imageform.geometry import Camera
    from imageform.io import CameraFile

    cam = Camera(np.array([[500.0, 0, 4], [0, 500.0, 3], [0, 0, 1]]))
    with pytest.raises(InvalidInputError, match="version"):
        CameraFile(cam, version=float("nan"))  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="has_pose"):
        CameraFile(cam, has_pose="yes")  # type: ignore[arg-type]
    assert CameraFile(cam, version=np.int64(1)).version == 1
