"""``imageform chunked white-balance --method``: only the methods chunked processing streams.

Its ``--help`` offered every white-balance method (pca, white-patch, chart ...) though
chunked processing takes three; those three are listed, another is one line (a usage error,
exit 2 on the command line; an ``UnknownOptionError`` from ``process_chunked``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imageform.cli import main
from imageform.errors import UnknownOptionError
from imageform.workflows.color import CHUNKED_CHOICES

STREAMED = ("gray_world", "shades_of_gray", "manual")


def test_help_lists_the_streamed_methods_only(capsys: pytest.CaptureFixture[str]) -> None:
    assert CHUNKED_CHOICES["white_balance"]["method"] == STREAMED
    assert main(["chunked", "white-balance", "--help"]) == 0
    text = capsys.readouterr().out
    (line,) = [ln for ln in text.splitlines() if ln.strip().startswith("--method")]
    assert line.split() == ["--method", "[gray-world|shades-of-gray|manual]"]
    for other in ("white-patch", "max-rgb", "grayness-index", "pca", "chart"):
        assert other not in text
    # the single command still offers every method
    assert main(["white-balance", "--help"]) == 0
    assert "pca" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("method", "words"),
    [
        (
            "pca",
            "--method pca needs the whole image in memory (imageform white-balance takes it); "
            "chunked processing streams gray-world, shades-of-gray, manual",
        ),
        (
            "White_Patch",
            "--method White_Patch needs the whole image in memory (imageform white-balance "
            "takes it); chunked processing streams gray-world, shades-of-gray, manual",
        ),
        ("nope", "unknown --method 'nope'; valid: gray-world, shades-of-gray, manual"),
    ],
)
def test_another_method_is_one_usage_line(
    method: str, words: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "o.tif"
    argv = ["chunked", "white-balance", "in.tif", "-o", str(out), "--method", method]
    assert main(argv) == 2  # before the (absent) input is looked at
    assert capsys.readouterr().err.splitlines() == [
        f"imageform chunked white-balance: error: {words} "
        "(see 'imageform chunked white-balance --help')"
    ]
    assert not out.exists()


def test_a_streamed_method_in_any_spelling_runs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from imageform.io import write_image

    src = tmp_path / "in.tif"
    rgb = np.random.default_rng(0).integers(1, 255, (64, 64, 3), dtype=np.uint8)
    write_image(src, rgb)
    out = tmp_path / "o.zarr"
    argv = ["chunked", "white-balance", str(src), "-o", str(out), "--method", "Shades_Of-Gray"]
    assert main([*argv, "--json"]) == 0, capsys.readouterr().err


@pytest.mark.parametrize("method", ["pca", "white-patch", "gray_edge", "chart"])
def test_process_chunked_refuses_another_method_in_one_line(method: str, tmp_path: Path) -> None:
    from imageform.batch import process_chunked
    from imageform.workflows.color import WhiteBalanceOptions

    streams = "streams the white-balance methods 'gray_world', 'shades_of_gray', 'manual' only"
    for options in ({"method": method}, WhiteBalanceOptions(method=method)):
        with pytest.raises(UnknownOptionError, match=streams) as info:
            process_chunked(tmp_path / "in.tif", tmp_path / "o.zarr", "white_balance", options)
        assert "\n" not in str(info.value)
    assert not (tmp_path / "o.zarr").exists()
