"""Issue 16 for imageform.io: a wrong object where a calibration result is expected is a
TypeError naming ``result`` (it was an AttributeError), and ``read_raw`` checks the pixel
limit from the raw header before LibRaw decodes anything."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imageform.errors import InvalidInputError
from imageform.io import CameraFile, StereoCameraFile


@pytest.mark.parametrize("bad", [None, True, 0, "abc", object()])
def test_from_calibration_refuses_other_objects(bad: object) -> None:
    with pytest.raises(TypeError, match="expected result as a CalibrationResult") as exc:
        CameraFile.from_calibration(bad)  # type: ignore[arg-type]
    assert len(str(exc.value)) <= 200
    with pytest.raises(TypeError, match="expected result as a StereoCalibrationResult"):
        StereoCameraFile.from_calibration(bad)  # type: ignore[arg-type]


def test_read_raw_pixel_limit_from_the_header(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    pytest.importorskip("rawpy")
    from imageform.io import read_raw, write_dng

    path = write_dng(
        tmp_path / "a.dng",
        np.zeros((24, 36), np.uint16),
        cfa_pattern="RGGB",
        black_level=64,
        white_level=4095,
        color_matrix=np.eye(3),
    )
    assert read_raw(path).mosaic.shape == (24, 36)
    with pytest.raises(InvalidInputError, match=r"36 x 24 = 0\.0 Mpx, above the limit"):
        read_raw(path, max_pixels=863)
    assert read_raw(path, max_pixels=864).mosaic.shape == (24, 36)
    monkeypatch.setenv("IMAGEFORM_MAX_PIXELS", "100")
    with pytest.raises(InvalidInputError, match="IMAGEFORM_MAX_PIXELS"):
        read_raw(path)
    for bad in (0, -1, 1.5, True, "100"):
        with pytest.raises(InvalidInputError, match="max_pixels"):
            read_raw(path, max_pixels=bad)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="path"):
        read_raw(None)  # type: ignore[arg-type]
