"""An existing output that is not a regular file (a FIFO, a device, a link to one, a folder) is
refused in one line, whatever the flags; a symbolic link to a regular file is replaced, never
followed. ``/dev/null`` is never used as a victim: the special files are made in ``tmp_path``."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import numpy as np
import pytest

from imageform._files import Outputs, atomic_write
from imageform.cli import main
from imageform.errors import InvalidInputError
from imageform.io import write_image


@pytest.fixture
def rgb(tmp_path: Path) -> Path:
    src = tmp_path / "in.png"
    write_image(src, np.full((4, 4, 3), 100, np.uint8))
    return src


def _fifo(path: Path) -> Path:
    os.mkfifo(path)
    return path


def _char_device(path: Path) -> Path:
    """A character device node (1, 3), the numbers of /dev/null, made in tmp (needs root)."""
    try:
        os.mknod(path, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
    except PermissionError:
        pytest.skip("making a device node needs root")
    return path


def _one_error_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("imageform: error: "), err
    return lines[0]


@pytest.mark.parametrize("force", [False, True])
@pytest.mark.parametrize(
    ("make", "said"),
    [(_fifo, "is a FIFO"), (_char_device, "is a character device")],
)
def test_special_file_output_is_refused_whatever_the_flags(
    rgb: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    make: object,
    said: str,
    force: bool,
) -> None:
    victim = make(tmp_path / "out.png")  # type: ignore[operator]
    before = os.lstat(victim)
    args = ["white-balance", str(rgb), "-o", str(victim)] + (["--force"] if force else [])
    assert main(args) == 1
    line = _one_error_line(capsys.readouterr().err)
    assert said in line and str(victim) in line and "pass --force" not in line
    after = os.lstat(victim)
    assert (after.st_mode, after.st_ino, after.st_rdev) == (
        before.st_mode,
        before.st_ino,
        before.st_rdev,
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.png", "out.png"]


def test_link_to_a_regular_file_is_replaced_not_followed(
    rgb: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    target = tmp_path / "target.png"
    target.write_bytes(b"keep me")
    link = tmp_path / "link.png"
    link.symlink_to(target)
    assert main(["white-balance", str(rgb), "-o", str(link)]) == 1
    assert "exists; pass --force" in capsys.readouterr().err
    assert main(["white-balance", str(rgb), "-o", str(link), "--force"]) == 0
    assert not link.is_symlink() and link.read_bytes()[:4] == b"\x89PNG"
    assert target.read_bytes() == b"keep me"


@pytest.mark.parametrize("force", [False, True])
def test_link_to_a_fifo_is_refused(
    rgb: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], force: bool
) -> None:
    fifo = _fifo(tmp_path / "pipe")
    link = tmp_path / "link.png"
    link.symlink_to(fifo)
    args = ["white-balance", str(rgb), "-o", str(link)] + (["--force"] if force else [])
    assert main(args) == 1
    line = _one_error_line(capsys.readouterr().err)
    assert "link to a FIFO" in line and str(link) in line
    assert link.is_symlink() and stat.S_ISFIFO(os.stat(link).st_mode)


@pytest.mark.parametrize("link", [False, True])
def test_folder_or_link_to_a_folder_as_a_file_output_is_refused(
    rgb: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], link: bool
) -> None:
    folder = tmp_path / "dir.png"
    folder.mkdir()
    (folder / "mine.txt").write_text("mine")
    out = folder
    if link:
        out = tmp_path / "link.png"
        out.symlink_to(folder)
    assert main(["white-balance", str(rgb), "-o", str(out), "--force"]) == 1
    line = _one_error_line(capsys.readouterr().err)
    assert "folder" in line and str(out) in line
    assert (folder / "mine.txt").read_text() == "mine" and out.is_symlink() == link


def test_second_output_that_is_a_fifo_is_refused_before_any_work(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """simulate's --raw (a second output) and its output folder holding a FIFO."""
    fifo = _fifo(tmp_path / "raw.dng")
    out = tmp_path / "sim"
    args = ["simulate", "-o", str(out), "--raw", str(fifo), "--force"]
    assert main(args) == 1
    line = _one_error_line(capsys.readouterr().err)
    assert "is a FIFO" in line and "raw.dng" in line
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode) and not out.exists()


def test_output_folder_holding_a_special_file_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """--force swaps an output folder whole: never one that holds a FIFO or a device."""
    out = tmp_path / "sim"
    out.mkdir()
    (out / "report.html").write_text("old")
    (out / "metrics.json").write_text("{}")
    (out / "stages").mkdir()
    _fifo(out / "stages" / "pipe")
    assert main(["simulate", "-o", str(out), "--force"]) == 1
    line = _one_error_line(capsys.readouterr().err)
    assert "pipe" in line and "FIFO" in line
    assert stat.S_ISFIFO(os.lstat(out / "stages" / "pipe").st_mode)
    assert (out / "report.html").read_text() == "old"


def test_outputs_recheck_at_commit(tmp_path: Path) -> None:
    """A FIFO that appears at the final name while the command runs is not replaced."""
    final = tmp_path / "a.txt"
    with pytest.raises(InvalidInputError, match="FIFO"), Outputs(force=True) as outs:
        outs.file(final).write_text("a")
        _fifo(final)
    assert stat.S_ISFIFO(os.lstat(final).st_mode)
    assert [p.name for p in tmp_path.iterdir()] == ["a.txt"]


def test_atomic_write_refuses_a_special_file(tmp_path: Path) -> None:
    """The library's writers (write_image, write_camera) commit through the same check."""
    dev = _char_device(tmp_path / "null.png")
    with pytest.raises(InvalidInputError, match="character device"):
        atomic_write(dev, lambda t: t.write_text("x"))
    with pytest.raises(InvalidInputError, match="character device"):
        write_image(dev, np.zeros((2, 2, 3)))
    assert stat.S_ISCHR(os.lstat(dev).st_mode)
    assert [p.name for p in tmp_path.iterdir()] == ["null.png"]


def test_chunked_and_batch_never_replace_a_fifo(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """chunked unlinked an existing output with --force (a FIFO, a folder named out.tif);
    batch renames each job's output over the old one."""
    src = tmp_path / "in.tif"
    write_image(src, np.full((16, 16, 3), 0.5, np.float32))
    fifo = _fifo(tmp_path / "out.tif")
    args = ["chunked", "convert", str(src), "--to", "linear-srgb", "--force", "-o"]
    assert main([*args, str(fifo)]) == 1
    assert "is a FIFO" in _one_error_line(capsys.readouterr().err)
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    folder = tmp_path / "dir.tif"
    folder.mkdir()
    (folder / "mine.txt").write_text("mine")
    assert main([*args, str(folder)]) == 1
    assert "is a folder" in _one_error_line(capsys.readouterr().err)
    assert (folder / "mine.txt").read_text() == "mine"
    inputs, out = tmp_path / "inputs", tmp_path / "out"
    inputs.mkdir()
    out.mkdir()
    write_image(inputs / "a.png", np.full((8, 8, 3), 100, np.uint8))
    _fifo(out / "a.png")  # where the job writes its output
    code = main(["batch", "white-balance", str(inputs / "*.png"), "-o", str(out), "--force"])
    assert code == 1
    line = _one_error_line(capsys.readouterr().err)
    assert "FIFO" in line and str(out / "a.png") in line
    assert stat.S_ISFIFO(os.lstat(out / "a.png").st_mode)
