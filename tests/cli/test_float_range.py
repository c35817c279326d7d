"""A float image of unscaled numbers (a microscope's 0-4000) read by a command that takes
pixels as colours: one line saying what the file holds and what to do, no output. It was an
empty mask from ``segment`` (exit 0), "expected linear values within ±100000" from
``white-balance`` and ``cvd``, NaN from ``stain-normalize``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imageform.cli import main

RNG = np.random.default_rng(5)


def _float_tiff(path: Path, top: float) -> Path:
    import tifffile

    tifffile.imwrite(path, (RNG.random((24, 32, 3)) * top).astype(np.float32), photometric="rgb")
    return path


COMMANDS = {
    "segment": lambda s, o: ["segment", s, "-o", o + ".png"],
    "white-balance": lambda s, o: ["white-balance", s, "-o", o + ".tif"],
    "cvd": lambda s, o: ["cvd", s, "--type", "deutan", "-o", o + ".png"],
    "delta-e": lambda s, o: ["delta-e", s, s],
    "stain-normalize": lambda s, o: [
        "stain-normalize", s, "--target", s, "--method", "reinhard", "-o", o + ".png"
    ],
}  # fmt: skip


@pytest.mark.parametrize("command", list(COMMANDS))
def test_float_counts_are_refused_saying_what_the_file_holds(
    tmp_path: Path, command: str, capsys: pytest.CaptureFixture[str]
) -> None:
    src = _float_tiff(tmp_path / "counts.tif", 4000.0)
    out = tmp_path / "out"
    assert main(COMMANDS[command](str(src), str(out))) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert "counts.tif holds floats from" in err and "to [0, 1]" in err and "divide it by" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["counts.tif"]


@pytest.mark.parametrize("top", [1.0, 1.5])
def test_floats_of_colours_a_little_above_white_still_go_through(
    tmp_path: Path, top: float
) -> None:
    """Processing or a wide gamut leaves some values a little above 1: not refused."""
    src = _float_tiff(tmp_path / "colours.tif", top)
    assert main(["segment", str(src), "-o", str(tmp_path / "mask.png")]) == 0
    assert main(["delta-e", str(src), str(src)]) == 0
