"""One-line messages that tell the truth: what failed, about which file (the user's name, never a
temporary one), and the cause, not an error of the error handler."""

from __future__ import annotations

import errno
import os
from pathlib import Path

import numpy as np
import pytest

import imageform.errors
import imageform.io
from imageform.cli import main
from imageform.io import write_image


def _line(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("imageform: error: "), err
    assert "Traceback" not in err
    return lines[0]


@pytest.fixture
def rgb(tmp_path: Path) -> Path:
    src = tmp_path / "in.png"
    write_image(src, np.full((4, 4, 3), 100, np.uint8))
    return src


def _no_leftovers(folder: Path) -> None:
    assert [p.name for p in folder.iterdir() if ".part" in p.name] == []


# ---------------------------------------------------------------- simulate's unexpected errors


def test_simulate_unexpected_error_shows_its_own_type(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """simulate has no input file: the handler read files[0] of an empty list (IndexError)."""
    import imageform.simulate

    def broken(*args: object, **kwargs: object) -> None:
        raise ZeroDivisionError("float division by zero")

    monkeypatch.setattr(imageform.simulate, "simulate", broken)
    out = tmp_path / "sim"
    assert main(["simulate", "-o", str(out)]) == 1
    line = _line(capsys)
    assert line == (
        "imageform: error: unexpected ZeroDivisionError: float division by zero "
        "(run again with --traceback to see where)"
    )
    assert not out.exists()
    _no_leftovers(tmp_path)


def test_simulate_too_deep_scene_says_so_naming_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    scene = tmp_path / "deep.toml"
    scene.write_text("x = " + "[" * 100_000 + "]" * 100_000 + "\n")
    assert main(["simulate", "--scene", str(scene), "-o", str(tmp_path / "sim")]) == 1
    line = _line(capsys)
    assert str(scene) in line and "nested too deeply" in line and "IndexError" not in line


def test_simulate_full_disk_names_the_output_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    import imageform.report.html

    def full(*args: object, **kwargs: object) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(imageform.report.html, "write_report", full)
    out = tmp_path / "sim"
    assert main(["simulate", "-o", str(out)]) == 1
    assert _line(capsys) == f"imageform: error: no space left on device writing {out}"
    assert not out.exists()
    _no_leftovers(tmp_path)


# ---------------------------------------------------------------- a full disk, an unwritable output


def _failing_write(exc_of: object) -> object:
    def write(path: object, *args: object, **kwargs: object) -> None:
        Path(str(path)).write_bytes(b"half")
        raise exc_of(str(path))  # type: ignore[operator]

    return write


@pytest.mark.parametrize("named", [False, True])
def test_full_disk_blames_the_output_not_the_input(
    rgb: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    named: bool,
) -> None:
    """ENOSPC without a file name (numpy, PIL) or naming the temporary file."""

    def enospc(path: str) -> OSError:
        if named:
            return OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), path)
        return OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(imageform.io, "write_image", _failing_write(enospc))
    out = tmp_path / "out.png"
    assert main(["white-balance", str(rgb), "-o", str(out)]) == 1
    assert _line(capsys) == f"imageform: error: no space left on device writing {out}"
    assert not out.exists()
    _no_leftovers(tmp_path)


def test_unwritable_output_shows_the_users_name(
    rgb: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    def denied(path: str) -> OSError:
        return PermissionError(errno.EACCES, os.strerror(errno.EACCES), path)

    monkeypatch.setattr(imageform.io, "write_image", _failing_write(denied))
    out = tmp_path / "out.png"
    assert main(["white-balance", str(rgb), "-o", str(out)]) == 1
    line = _line(capsys)
    assert line == f"imageform: error: permission denied writing {out}", line
    _no_leftovers(tmp_path)


def test_unwritable_file_inside_an_output_folder_shows_its_final_name(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    import imageform.report.html

    def denied(result: object, folder: Path, **kwargs: object) -> None:
        target = Path(folder) / "stages" / ".01.png.77-ab12cd34.part.png"
        raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(target))

    monkeypatch.setattr(imageform.report.html, "write_report", denied)
    out = tmp_path / "sim"
    assert main(["simulate", "-o", str(out)]) == 1
    line = _line(capsys)
    assert line == f"imageform: error: permission denied writing {out / 'stages' / '01.png'}"


# ---------------------------------------------------------------- what a path is


def test_output_whose_parent_is_a_file_says_so(
    rgb: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    good = tmp_path / "good.png"
    good.write_bytes(b"mine")
    assert main(["white-balance", str(rgb), "-o", str(good / "out.png")]) == 1
    assert _line(capsys) == f"imageform: error: output folder {good} is not a folder"
    deeper = good / "x" / "out.png"
    assert main(["white-balance", str(rgb), "-o", str(deeper)]) == 1
    assert _line(capsys) == (
        f"imageform: error: output folder {deeper.parent} does not exist ({good} is not a folder)"
    )
    missing = tmp_path / "nope" / "x" / "out.png"
    assert main(["white-balance", str(rgb), "-o", str(missing)]) == 1
    assert _line(capsys) == f"imageform: error: output folder {missing.parent} does not exist"
    assert good.read_bytes() == b"mine"


@pytest.mark.parametrize(
    ("kind", "said"),
    [("fifo", "is a FIFO (named pipe), not a regular file"), ("folder", "is a folder")],
)
def test_fifo_or_folder_as_input_says_what_it_is(
    rgb: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], kind: str, said: str
) -> None:
    """Never "file not found" (and a FIFO is never opened: reading it would block)."""
    odd = tmp_path / "odd.png"
    if kind == "fifo":
        os.mkfifo(odd)
    else:
        odd.mkdir()
    out = tmp_path / "out.png"
    assert main(["white-balance", str(odd), "-o", str(out)]) == 1
    assert said in _line(capsys)
    assert main(["undistort", str(rgb), "--camera", str(odd), "-o", str(out)]) == 1
    line = _line(capsys)
    assert f"--camera {odd} {said}" in line
    assert main(["simulate", "--scene", str(odd), "-o", str(tmp_path / "sim")]) == 1
    assert f"--scene {odd} {said}" in _line(capsys)
    scene = tmp_path / "scene.toml"
    scene.write_text(f'[[objects]]\ntype = "image"\ncenter_m = [0, 0, 0]\npath = "{odd.name}"\n')
    assert main(["simulate", "--scene", str(scene), "-o", str(tmp_path / "sim")]) == 1
    line = _line(capsys)
    assert f"'{odd.name}' {said}" in line and "not found" not in line
    assert not out.exists()


# ---------------------------------------------------------------- sizes


@pytest.mark.parametrize(
    ("size", "limit", "said"),
    [
        ((4, 4), 10, "4 x 4 = 16 px, above the limit of 10 px"),
        ((300, 400), 100_000, "400 x 300 = 0.120 Mpx, above the limit of 0.100 Mpx"),
        ((1000, 1000), 999_999, "1000 x 1000 = 1000000 px, above the limit of 999999 px"),
    ],
)
def test_pixel_limit_message_shows_small_sizes(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    size: tuple[int, int],
    limit: int,
    said: str,
) -> None:
    """Never "0.0 Mpx, above the limit of 0.0 Mpx"."""
    src = tmp_path / "in.png"
    write_image(src, np.zeros((*size, 3), np.uint8))
    out = tmp_path / "out.png"
    assert main(["white-balance", str(src), "-o", str(out), "--max-pixels", str(limit)]) == 1
    line = _line(capsys)
    assert said in line, line


# ---------------------------------------------------------------- calibration commands


def test_stereo_calibrate_refuses_one_folder_for_both_cameras(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    views = tmp_path / "views"
    views.mkdir()
    for k in range(3):
        write_image(views / f"v{k}.png", np.full((8, 8, 3), 100, np.uint8))
    other = tmp_path / "other"
    other.mkdir()
    out = tmp_path / "rig.toml"
    base = ["stereo-calibrate", "--board", "9x6", "-o", str(out)]
    assert main([*base, str(views), str(views)]) == 1
    assert f"left and right are both {views}" in _line(capsys)
    glob = str(views / "*.png")
    assert main([*base, glob, glob]) == 1
    assert "left and right are both" in _line(capsys)
    assert main([*base, str(views / "v[01].png"), glob]) == 1
    assert "left and right both name the image" in _line(capsys)
    assert main([*base, str(views), str(other)]) == 1  # a folder stands for its images
    line = _line(capsys)
    assert line.startswith(f"imageform: error: folder {other} holds no images (.")
    assert ".bmp, " in line and ".png, " in line
    assert not out.exists()


def test_calibrate_advises_its_own_max_iter_option(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The library says "raise max_iter": the command has --max-iter and says so."""
    pattern = str(shared_data / "opencv-left" / "left0[1-4].jpg")
    out = tmp_path / "cam.toml"
    args = ["calibrate", pattern, "--board", "9x6", "-o", str(out)]
    assert main([*args, "--max-iter", "2"]) == 1
    line = _line(capsys)
    assert "did not converge in 2 iterations" in line and "raise --max-iter (now 2)" in line
    assert not out.exists()
    assert main([*args, "--max-iter", "500"]) == 0


def test_calibrate_says_the_views_hold_one_orientation(
    shared_data: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Boards held at one orientation with the principal point off the centre (0.1 px of
    noise) said "did not converge ... raise --max-iter" (more iterations do not help); the
    command now says what the views leave open and what to do, in one line, exit 1, and
    writes nothing. The views are the simulator's (the library test's), put in place of the
    corners found in four real views."""
    import imageform.geometry as geometry
    from tests.geometry.test_calibration import _one_orientation

    real = geometry.calibrate_camera

    def one_orientation(objs, corners, size, **kw):  # type: ignore[no-untyped-def]
        obj, uv = _one_orientation(0.1, centre=(150.0, 112.0), seed=4)
        return real([obj] * 10, uv, (320, 240), **kw)

    monkeypatch.setattr(geometry, "calibrate_camera", one_orientation)
    pattern = str(shared_data / "opencv-left" / "left0[1-4].jpg")
    out = tmp_path / "cam.toml"
    corners = tmp_path / "corners.csv"
    args = ["calibrate", pattern, "--board", "9x6", "-o", str(out), "--corners", str(corners)]
    assert main(args) == 1
    line = _line(capsys)
    assert "nearly one orientation in every view" in line, line
    assert "about different axes" in line and "max-iter" not in line
    assert not out.exists() and not corners.exists()


# ---------------------------------------------------------------- tables


@pytest.mark.parametrize(
    ("csv", "said"),
    [
        ("X,Y\n1,2\n3,4\n", "needs the columns X, Y, Z"),
        ("X,Y,depth\n1,2,3\n", "its header has x, y, depth, no Z"),
        ("a,b\n1,2\n", "needs the columns X, Y, Z"),
    ],
)
def test_project_refuses_a_table_without_x_y_z(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], csv: str, said: str
) -> None:
    """A header X,Y was read as X, Y and an empty Z: exit 0 with NaN pixels."""
    pts = tmp_path / "pts.csv"
    pts.write_text(csv)
    out = tmp_path / "uv.csv"
    assert main(["project", str(pts), "--fx", "500", "-o", str(out)]) == 1
    line = _line(capsys)
    assert said in line and str(pts) in line, line
    assert not out.exists()


def test_project_reads_named_or_unnamed_columns(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Still read: a header naming X, Y, Z in any order, one naming none of 3 columns, none."""
    for i, csv in enumerate(["z,X,Y\n2,0.1,0.2\n", "a,b,c\n0.1,0.2,2\n", "0.1,0.2,2\n"]):
        pts = tmp_path / f"p{i}.csv"
        pts.write_text(csv)
        out = tmp_path / f"uv{i}.csv"
        assert main(["project", str(pts), "--fx", "500", "-o", str(out)]) == 0
        assert out.read_text().splitlines()[1] == "25.0,50.0,1"
    capsys.readouterr()


# ---------------------------------------------------------------- chart


def test_chart_counts_add_up(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A noisy photo: the library counted a saturated, not flat patch twice ("1 saturated",
    "20 missing" for 20 patches left out of 24 segmented); each patch is left out once, for
    one reason, and the counts add up."""
    import json
    import re

    from imageform.analysis import synthetic_chart_photo

    photo = synthetic_chart_photo(cast=(1.0, 0.85, 0.7), rng=3, noise=0.04)
    src = tmp_path / "noisy.png"
    write_image(src, np.round(np.clip(photo.image, 0, 1) * 255).astype(np.uint8))
    out = tmp_path / "c.json"
    assert main(["chart", str(src), "-o", str(out)]) == 0
    cap = capsys.readouterr()
    m = re.search(r"(\d+) of 24 patches segmented, (\d+) usable, (\d+) left out", cap.out)
    assert m is not None, cap.out
    _, usable, left = (int(g) for g in m.groups())
    assert usable + left == 24 and left > 0
    notes = cap.err.strip().splitlines()
    assert len(notes) == 1 and "missing" not in cap.err, cap.err
    assert notes[0].startswith(f"imageform: note: {left} of 24 patches left out of the fit: ")
    counts = [int(n) for n in re.findall(r"(\d+) [a-z][^\[]*\[", notes[0].split(": ", 3)[3])]
    assert sum(counts) == left
    assert main(["chart", str(src), "-o", str(out), "--force", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    why = summary["patches_left_out"]
    every = [i for idx in why.values() for i in idx]
    assert len(every) == len(set(every)) == left == 24 - summary["patches_valid"]


# ---------------------------------------------------------------- --board: corners or squares


def test_board_counts_corners_or_squares_and_says_which(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A checkerboard counts inner corners, a ChArUco board squares: both spellings are
    accepted (9x6corners, 10x7squares), and the output says how --board was read."""
    import json

    pattern = str(shared_data / "opencv-left" / "left0[1-4].jpg")
    base = ["calibrate", pattern, "-o", str(tmp_path / "cam.toml"), "--force"]
    assert main([*base, "--board", "10x7squares", "--json"]) == 0
    board = json.loads(capsys.readouterr().out)["board"]
    assert board == {
        "type": "checkerboard",
        "inner_corners": [9, 6],
        "squares": [10, 7],
        "read_as": "squares",
    }
    assert main([*base, "--board", "9x6"]) == 0
    first = capsys.readouterr().out.splitlines()[0]
    assert first == (
        "board: checkerboard, 9x6 inner corners = 10x7 squares "
        "('9x6' counts inner corners, the default for a checkerboard)"
    )
    # squares counted but given bare: the hint gives the spelling that counts squares
    assert main([*base, "--board", "10x7"]) == 1
    err = capsys.readouterr().err
    assert "'10x7' counts inner corners; a board of 10x7 squares is --board 10x7squares" in err


def test_board_spellings() -> None:
    from imageform.workflows.calibration import board_reading, parse_board, parse_charuco

    assert parse_board("9x6") == parse_board("9x6 corners") == parse_board("10X7 Squares")
    assert parse_charuco("charuco:7x5") == parse_charuco("charuco:6x4corners") == (7, 5)
    assert parse_charuco("charuco:7x5squares") == (7, 5)
    r = board_reading("charuco:6x4corners")
    assert (r["type"], r["squares"], r["inner_corners"], r["read_as"]) == (
        "charuco",
        [7, 5],
        [6, 4],
        "inner corners",
    )
    assert "the default for ChArUco" in board_reading("charuco:7x5")["line"]
    with pytest.raises(imageform.errors.InvalidInputError, match="2 to"):
        parse_board("2x7squares")  # one inner corner per row


# ---------------------------------------------------------------- lens units


def test_lens_help_shows_the_units(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["lens", "--help"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    for flag in ("--focal", "--focus", "--coc"):
        assert f"{flag} LENGTH" in out
    assert "a bare number is in mm" in out and "a bare number is in m)" in out
    assert "keys ending _m" in out


def test_lens_units_explicit_or_bare(capsys: pytest.CaptureFixture[str]) -> None:
    """50mm, 5cm and 0.05m are one focal length; 2m, 2000mm, '2 m' and a bare 2 one focus;
    a bare number that looks given in the other unit is read as documented, with a note."""
    import json

    def summary(*args: str) -> dict[str, float]:
        assert main(["lens", "--f-number", "2.8", *args, "--json"]) == 0
        return json.loads(capsys.readouterr().out)

    ref = summary("--focal", "50", "--focus", "2")
    for focal, focus in (("50mm", "2m"), ("5cm", "2000mm"), ("0.05m", "2 m"), ("50 mm", "0.002km")):
        if focus.endswith("km"):
            assert main(["lens", "--f-number", "2.8", "--focal", focal, "--focus", focus]) == 2
            assert "unknown unit 'km'" in capsys.readouterr().err
            continue
        got = summary("--focal", focal, "--focus", focus)
        assert got["focal_length_m"] == pytest.approx(0.05)
        assert got["focus_m"] == pytest.approx(2.0) and got["near_m"] == pytest.approx(
            ref["near_m"]
        )
    assert main(["lens", "--f-number", "2.8", "--focal", "50", "--focus", "2000"]) == 0
    err = capsys.readouterr().err
    assert "--focus 2000 is read as 2000 m" in err and "write 2000mm" in err


def test_outputs_explain_names_every_output_for_an_anonymous_full_disk(tmp_path: Path) -> None:
    import imageform._files as files

    outs = files.Outputs()
    outs.file(tmp_path / "a.png")
    outs.folder(tmp_path / "sim")
    err = outs.explain(OSError(errno.ENOSPC, "No space left on device"))
    assert err is not None and isinstance(err, OSError) and err.errno == errno.ENOSPC
    assert str(err) == f"no space left on device writing {tmp_path / 'a.png'}, {tmp_path / 'sim'}"
    # an error about something else (a decoder's OSError without a file) is not an output's
    assert outs.explain(OSError("broken data stream")) is None
    outs.discard()
