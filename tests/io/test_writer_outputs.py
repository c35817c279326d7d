"""Every library writer refuses an output it cannot write, in one line naming ``path`` (issue 25).

A folder, a missing parent folder, a parent that is a file, and an existing output that is not
a regular file (``/dev/null``) are refused with :class:`InvalidInputError` before anything is
written: no temporary is left behind and ``/dev/null`` is never replaced.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from imageform.errors import InvalidInputError
from tests.fuzz.values import V, resolve


def _write_camera(p: Path) -> Any:
    from imageform.io import write_camera

    return write_camera(p, resolve(V("camera")))


def _write_stereo_camera(p: Path) -> Any:
    from imageform.io import write_stereo_camera

    return write_stereo_camera(p, resolve(V("stereo_file_obj")))


def _write_dng(p: Path) -> Any:
    from imageform.io import write_dng

    return write_dng(p, np.full((4, 6), 100, np.uint16), color_matrix=np.eye(3))


def _write_simulated_dng(p: Path) -> Any:
    from imageform.simulate import write_simulated_dng

    return write_simulated_dng(resolve(V("result")), resolve(V("scene")), p)


def _to_toml(p: Path) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        return resolve(V("calibration")).to_toml(p)


def _to_json(fixture: str) -> Callable[[Path], Any]:
    return lambda p: resolve(V(fixture)).to_json(p)


def _write_image(p: Path) -> Any:
    from imageform.io import write_image

    return write_image(p, np.zeros((2, 3)))


WRITERS: dict[str, tuple[Callable[[Path], Any], str]] = {
    "write_camera": (_write_camera, ".toml"),
    "write_stereo_camera": (_write_stereo_camera, ".toml"),
    "write_dng": (_write_dng, ".dng"),
    "write_simulated_dng": (_write_simulated_dng, ".dng"),
    "CalibrationResult.to_toml": (_to_toml, ".toml"),
    "ReinhardStats.to_json": (_to_json("reinhard"), ".json"),
    "MacenkoStains.to_json": (_to_json("macenko"), ".json"),
    "ColorCorrection.to_json": (_to_json("correction"), ".json"),
    "write_image": (_write_image, ".png"),
}


@pytest.mark.parametrize("writer", sorted(WRITERS))
@pytest.mark.parametrize("case", ["folder", "missing_parent", "parent_is_file"])
def test_writer_refuses_an_output_it_cannot_write(writer: str, case: str, tmp_path: Path) -> None:
    write, suffix = WRITERS[writer]
    if case == "folder":
        out = tmp_path / f"out{suffix}"
        out.mkdir()
        match = "path: .* is a folder"
    elif case == "missing_parent":
        out = tmp_path / "missing" / f"out{suffix}"
        match = "path: the folder .* does not exist"
    else:
        (tmp_path / "file").write_text("x")
        out = tmp_path / "file" / f"out{suffix}"
        match = "path: the folder .* is not a folder"
    before = sorted(os.listdir(tmp_path))
    with pytest.raises(InvalidInputError, match=match) as info:
        write(out)
    assert "\n" not in str(info.value)
    assert sorted(os.listdir(tmp_path)) == before  # nothing half-written, no temporary


@pytest.mark.parametrize("writer", sorted(WRITERS))
def test_writer_refuses_a_device(writer: str) -> None:
    if not os.path.exists("/dev/null"):
        pytest.skip("no /dev/null on this system")
    write, _ = WRITERS[writer]
    with pytest.raises(InvalidInputError, match="path: /dev/null is a character device, not"):
        write(Path("/dev/null"))
    assert not Path("/dev/null").is_file()


@pytest.mark.parametrize("writer", sorted(WRITERS))
def test_writer_refuses_a_huge_path_without_echoing_it(writer: str, tmp_path: Path) -> None:
    write, suffix = WRITERS[writer]
    with pytest.raises(InvalidInputError, match="path") as info:
        write(tmp_path / ("x" * 100_000 + suffix))
    assert len(str(info.value)) < 200


def test_write_dng_refuses_an_as_shot_neutral_beyond_a_rational(tmp_path: Path) -> None:
    from imageform.io import write_dng

    with pytest.raises(InvalidInputError, match="as_shot_neutral"):
        write_dng(
            tmp_path / "a.dng",
            np.full((4, 6), 100, np.uint16),
            color_matrix=np.eye(3),
            as_shot_neutral=(1e308, 1.0, 1.0),
        )
    with pytest.raises(InvalidInputError, match="as_shot_neutral"):
        write_dng(
            tmp_path / "a.dng",
            np.full((4, 6), 100, np.uint16),
            color_matrix=np.eye(3),
            as_shot_neutral=1e308,
        )
    assert not list(tmp_path.iterdir())
