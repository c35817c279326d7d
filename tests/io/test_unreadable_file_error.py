"""UnreadableFileError: every reader says "cannot read PATH: REASON" with the parts kept.

A caller reading a folder (``imageform calibrate``) tells a file it cannot decode from any
other refusal by this class; these tests hold each reader to it and keep the other
refusals (a pixel limit, transparent pixels) out of it.
"""

from __future__ import annotations

import pickle
from pathlib import Path

import numpy as np
import pytest

from imageform.errors import InvalidInputError, UnreadableFileError
from imageform.io import read_image


def test_message_parts_and_pickling() -> None:
    """The message is built from path and reason, both kept; a pickled copy (a worker's
    error sent back to the scheduler) is equal in all three."""
    exc = UnreadableFileError(Path("/x/a.png"), "not a PNG file")
    assert str(exc) == "cannot read /x/a.png: not a PNG file"
    assert (exc.path, exc.reason, exc.brief) == ("/x/a.png", "not a PNG file", "not a PNG file")
    named = UnreadableFileError("/x/e.jpg", "cannot identify image file '/x/e.jpg'")
    assert named.brief == "cannot identify image file"
    assert UnreadableFileError("/x/e.jpg", "an empty file (0 bytes)").brief == "an empty file"
    assert isinstance(exc, InvalidInputError) and isinstance(exc, ValueError)
    back = pickle.loads(pickle.dumps(exc))
    assert type(back) is UnreadableFileError
    assert (str(back), back.path, back.reason) == (str(exc), exc.path, exc.reason)


def _refusal(path: Path) -> UnreadableFileError:
    before = path.read_bytes()
    with pytest.raises(UnreadableFileError) as info:
        read_image(path)
    assert path.read_bytes() == before  # the input untouched
    assert info.value.path == str(path)
    assert str(info.value) == f"cannot read {path}: {info.value.reason}"
    assert "\n" not in str(info.value)
    return info.value


def test_empty_not_png_and_truncated_images(tmp_path: Path) -> None:
    from PIL import Image

    empty = tmp_path / "empty.jpg"
    empty.write_bytes(b"")
    assert _refusal(empty).reason == "an empty file (0 bytes)"
    fake = tmp_path / "fake.png"
    fake.write_bytes(b"not a png at all, just text\n" * 4)
    assert "PNG" in _refusal(fake).reason
    whole = tmp_path / "whole.png"
    Image.fromarray(np.random.default_rng(0).integers(0, 255, (64, 64, 3), np.uint8)).save(whole)
    cut = tmp_path / "cut.png"
    cut.write_bytes(whole.read_bytes()[:200])
    assert _refusal(cut).reason


def test_animated_gif_and_not_dicom(tmp_path: Path) -> None:
    from PIL import Image

    frames = [Image.new("L", (8, 8), v) for v in (0, 128, 255)]
    gif = tmp_path / "anim.gif"
    frames[0].save(gif, save_all=True, append_images=frames[1:])
    assert "animated" in _refusal(gif).reason
    dcm = tmp_path / "scan.dcm"
    dcm.write_bytes(b"\x00" * 300)
    assert "DICOM" in _refusal(dcm).reason


def test_truncated_raw(tmp_path: Path) -> None:
    from imageform.io import read_raw, write_dng

    pytest.importorskip("rawpy")
    mosaic = np.random.default_rng(1).integers(0, 4096, (64, 96)).astype(np.uint16)
    cm = np.eye(3)
    whole = write_dng(tmp_path / "whole.dng", mosaic, black_level=64, white_level=4095,
                      color_matrix=cm)  # fmt: skip
    cut = tmp_path / "cut.dng"
    cut.write_bytes(whole.read_bytes()[: whole.stat().st_size // 2])
    with pytest.raises(UnreadableFileError, match=r"cut\.dng: the file is truncated") as info:
        read_raw(cut)
    assert info.value.path == str(cut)


def test_other_refusals_are_not_unreadable(tmp_path: Path) -> None:
    """A file read whole but refused for what it holds is an InvalidInputError of another
    kind: calibrate must not skip it as if it could not be read."""
    from PIL import Image

    rgba = np.zeros((16, 16, 4), np.uint8)
    rgba[..., 3] = 10  # transparent pixels
    path = tmp_path / "alpha.png"
    Image.fromarray(rgba).save(path)
    with pytest.raises(InvalidInputError) as info:
        read_image(path, alpha="reject")
    assert not isinstance(info.value, UnreadableFileError)
    big = tmp_path / "big.png"
    Image.fromarray(np.zeros((64, 64), np.uint8)).save(big)
    with pytest.raises(InvalidInputError) as info:
        read_image(big, max_pixels=100)
    assert not isinstance(info.value, UnreadableFileError)
