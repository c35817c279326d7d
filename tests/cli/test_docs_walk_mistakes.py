"""Mistakes a newcomer makes on the documented command lines: one clear line, a non-zero exit,
nothing written, the inputs untouched (found walking docs/*.md's shell commands)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imageform.cli import main
from imageform.geometry import BrownConrady, Camera
from imageform.io import write_camera, write_image


def _files(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


@pytest.fixture
def distorted(tmp_path: Path) -> tuple[Path, Path]:
    rng = np.random.default_rng(5)
    write_image(tmp_path / "in.png", rng.random((30, 40, 3)))
    cam = Camera(
        [[40.0, 0, 19.5], [0, 40.0, 14.5], [0, 0, 1]],
        image_size=(40, 30),
        distortion=BrownConrady(k1=-0.2),
    )
    write_camera(tmp_path / "cam.toml", cam)
    return tmp_path / "in.png", tmp_path / "cam.toml"


def test_two_outputs_on_one_path_are_refused(
    distorted: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``-o u.png --camera-out u.png`` wrote the camera file over the image and said it wrote
    both; now refused before any work, naming both options."""
    image, cam = distorted
    before = _files(tmp_path)
    out = tmp_path / "u.png"
    for other in (str(out), str(tmp_path / "." / "u.png")):
        code = main(
            ["undistort", str(image), "-o", str(out), "--camera", str(cam)]
            + ["--camera-out", other]
        )
        err = capsys.readouterr().err
        assert code == 1 and err.count("\n") == 1
        assert "-o/--out and --camera-out both name" in err
        assert _files(tmp_path) == before  # nothing written, inputs untouched
    # distinct paths still work
    assert (
        main(
            [
                "undistort",
                str(image),
                "-o",
                str(out),
                "--camera",
                str(cam),
                "--camera-out",
                str(tmp_path / "u.toml"),
            ]
        )
        == 0
    )


def test_camera_out_is_dated_when_written(distorted: tuple[Path, Path], tmp_path: Path) -> None:
    """``undistort --camera-out`` copied the source file's provenance date (and version): the
    schema's ``date`` is when the file was written."""
    from dataclasses import replace
    from datetime import UTC, datetime

    from imageform.io import read_camera

    image, cam = distorted
    old = read_camera(cam)
    stamped = replace(
        old.provenance, date=datetime(2020, 1, 2, 3, 4, 5, tzinfo=UTC), imageform_version="0.0.1"
    )
    write_camera(cam, replace(old, provenance=stamped))
    start = datetime.now(UTC).replace(microsecond=0)
    out_cam = tmp_path / "flat.toml"
    assert (
        main(
            [
                "undistort",
                str(image),
                "-o",
                str(tmp_path / "u.png"),
                "--camera",
                str(cam),
                "--camera-out",
                str(out_cam),
            ]
        )
        == 0
    )
    prov = read_camera(out_cam).provenance
    assert prov.date is not None and prov.date >= start
    assert prov.imageform_version != "0.0.1" and prov.based_on == "cam.toml"


@pytest.mark.parametrize("command", ["convert", "demosaic"])
def test_sixteen_bit_jpeg_is_refused_up_front(
    command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``-o x.jpg --bit-depth 16`` named the writer's temporary file in its error
    (``write .x.jpg.31536-132c161e.part.png for 16``) after the work; now refused first."""
    src = tmp_path / "in.png"
    rgb = np.random.default_rng(1).random((8, 10, 3))
    write_image(src, rgb[..., 1] if command == "demosaic" else rgb)
    before = _files(tmp_path)
    code = main([command, str(src), "-o", str(tmp_path / "x.jpg"), "--bit-depth", "16"])
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1 and ".part" not in err
    assert "JPEG holds 8 bits per sample: --bit-depth 16 needs a .png or .tif output" in err
    assert _files(tmp_path) == before


def test_write_image_names_the_final_file_not_its_temporary(tmp_path: Path) -> None:
    """The library writer's own messages name the user's file when given a temporary."""
    from imageform._files import Outputs
    from imageform.errors import InvalidInputError

    with pytest.raises(InvalidInputError) as info, Outputs() as outs:
        write_image(outs.file(tmp_path / "q.jpg"), np.zeros((4, 4, 3)), bit_depth=16)
    assert str(info.value) == "JPEG holds 8 bits per sample; write q.png for 16"
    with pytest.raises(InvalidInputError) as info, Outputs() as outs:
        write_image(outs.file(tmp_path / "r.png"), np.full((4, 4, 3), 1.5), bit_depth=8)
    assert "the 8-bit r.png;" in str(info.value) and ".part" not in str(info.value)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("reply", [None, b"HTTP/1.1 400 Bad Request\r\n\r\n"])
def test_batch_scheduler_address_that_is_not_a_scheduler(
    reply: bytes | None, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``--scheduler`` at a server that never answers (a web server, the dashboard's port) hung
    for good; one that answers in another protocol gave "not enough memory" and a traceback at
    exit. Both are now one line within dask's connect timeout, and nothing is written."""
    import socket
    import threading
    import time

    import dask

    pytest.importorskip("distributed")
    write_image(tmp_path / "a.png", np.zeros((4, 6, 3)))
    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]
    stop = threading.Event()

    def serve() -> None:
        server.settimeout(0.1)
        held = []
        while not stop.is_set():
            try:
                conn, _ = server.accept()
            except OSError:
                continue
            held.append(conn)
            if reply is not None:
                conn.sendall(reply)
        for c in held:
            c.close()

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    try:
        start = time.monotonic()
        with dask.config.set({"distributed.comm.timeouts.connect": "1s"}):
            code = main(
                ["batch", "convert", f"{tmp_path}/*.png", "-o", str(tmp_path / "o"), "--to", "lab"]
                + ["--suffix", ".npy", "--scheduler", f"tcp://127.0.0.1:{port}"]
            )
        took = time.monotonic() - start
    finally:
        stop.set()
        thread.join()
        server.close()
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1 and took < 20
    assert err.startswith(f"imageform: error: cannot reach the scheduler tcp://127.0.0.1:{port}: ")
    assert ("no dask scheduler answered" if reply is None else "not a dask scheduler") in err
    assert not (tmp_path / "o").exists()


def test_vanishing_with_a_camera_says_why_no_K_was_estimated(
    shared_data: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """docs/geometry.md's ``vanishing photo.jpg --camera cam.toml --principal-point camera``
    ("fit f alone") printed nothing about the fit when it was refused (left01.jpg with the
    page's calibration: the focal length's spread over resamples 2.5 %, over the limit); the
    reason was only in ``--json`` (K_reason). The refusal is forced here: near the limit the
    real answer flips with the file's last digits."""
    from dataclasses import replace

    import imageform.geometry

    real = imageform.geometry.detect_vanishing_points
    reason = "not determined: the points converge too loosely to fix it (f would be 538 px)"

    def refused(*args: object, **kwargs: object) -> object:
        return replace(real(*args, **kwargs), K=None, K_reason=reason)  # type: ignore[type-var]

    monkeypatch.setattr(imageform.geometry, "detect_vanishing_points", refused)
    cam = Camera(
        [[532.61, 0, 342.46], [0, 532.72, 234.11], [0, 0, 1]],
        image_size=(640, 480),
        distortion=BrownConrady(k1=-0.2903, k2=0.06651, p1=0.001059, p2=0.000161, k3=0.1154),
    )
    write_camera(tmp_path / "cam.toml", cam)
    argv = ["vanishing", str(shared_data / "opencv-left" / "left01.jpg"), "--camera"]
    argv += [str(tmp_path / "cam.toml"), "--principal-point", "camera"]
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert f"K from the vanishing points: {reason}" in text
    assert "K: f = 532.6 px" in text  # the file's K, as before


@pytest.mark.parametrize(
    ("extra", "says"),
    [
        (
            ["--to", "lab", "--code-bits", "10"],
            "--standard, --range and --code-bits apply to a "
            "conversion from or to ycbcr, not the file's space -> lab",
        ),
        (
            ["--from", "srgb", "--to", "lab", "--gray-method", "rec709"],
            "--gray-method applies to a conversion from or to gray, not srgb -> lab",
        ),
        (
            ["--to", "hsv", "--white", "D50"],
            "--white applies to a conversion from or to lab or "
            "lch or luv or xyy, not the file's space -> hsv",
        ),
        (["--to", "ycbcr", "--code-bits", "9"], "expected --code-bits 8, 10 or 12, got 9"),
    ],
)
def test_convert_options_the_conversion_does_not_use(
    extra: list[str], says: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``convert --to lab --code-bits 10`` answered in the library's parameter names
    ("parameter(s) bit_depth not used converting srgb -> lab; valid here: alpha, observer,
    white"), after reading the image; now in the command's flags, before reading it."""
    write_image(tmp_path / "in.png", np.random.default_rng(2).random((6, 8, 3)))
    code = main(["convert", str(tmp_path / "in.png"), "-o", str(tmp_path / "o.tif"), *extra])
    err = capsys.readouterr().err
    assert code == 1 and err == f"imageform: error: {says}\n"
    assert not (tmp_path / "o.tif").exists()


def test_convert_code_bits_twelve_and_the_defaults_help_states(tmp_path: Path) -> None:
    """--help now states the defaults: bt601, full range, analog values; 12 bits is accepted
    (the help said 8, 10)."""
    from imageform.color import rgb_to_ycbcr

    rgb = np.random.default_rng(3).random((6, 8, 3))
    write_image(tmp_path / "in.png", rgb, bit_depth=16)
    src = tmp_path / "in.png"
    assert main(["convert", str(src), "-o", str(tmp_path / "a.npy"), "--to", "ycbcr"]) == 0
    assert (
        main(
            [
                "convert",
                str(src),
                "-o",
                str(tmp_path / "b.npy"),
                "--to",
                "ycbcr",
                "--standard",
                "bt601",
                "--range",
                "full",
            ]
        )
        == 0
    )
    np.testing.assert_array_equal(np.load(tmp_path / "a.npy"), np.load(tmp_path / "b.npy"))
    assert (
        main(
            [
                "convert",
                str(src),
                "-o",
                str(tmp_path / "c.npy"),
                "--to",
                "ycbcr",
                "--range",
                "limited",
                "--code-bits",
                "12",
            ]
        )
        == 0
    )
    expect = rgb_to_ycbcr(np.round(rgb * 65535) / 65535, signal_range="limited", bit_depth=12)
    np.testing.assert_allclose(np.load(tmp_path / "c.npy"), expect, rtol=0, atol=1e-3)


@pytest.mark.parametrize("command", ["convert", "white-balance", "stain-normalize"])
def test_chunked_help_lists_only_what_chunked_honours(
    command: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """``imageform chunked convert --help`` listed --alpha and --max-pixels (ignored: a 100 Mpx
    default limit read as applying to a slide larger than memory) and --standard, --frame ...
    (refused when given); it lists what chunked processing takes."""
    from imageform.workflows.color import CHUNKED_OPTIONS

    assert main(["chunked", command, "--help"]) == 0
    text = capsys.readouterr().out
    for flag in ("--alpha ", "--max-pixels", "--standard", "--frame", "--save-target PATH"):
        assert flag not in text
    assert "--chunk" in text and "--dtype" in text
    assert len(CHUNKED_OPTIONS[command.replace("-", "_")]) >= 2
    # a flag no longer listed is a usage error, not silently ignored
    assert main(["chunked", command, "x.tif", "-o", "y.tif", "--max-pixels", "10"]) == 2


def test_from_lines_estimate_without_distortion_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``undistort --from-lines --estimate lens.toml`` on a photograph without distortion said
    "wrote lens.toml (the estimated camera, none distortion)"."""
    from imageform.io import read_camera

    v, u = np.mgrid[0:240, 0:320]
    board = ((u // 40 + v // 40) % 2).astype(np.float64) * 0.8 + 0.1
    write_image(tmp_path / "flat.png", board)
    argv = ["undistort", str(tmp_path / "flat.png"), "--from-lines", "-o"]
    argv += [str(tmp_path / "out.png"), "--estimate", str(tmp_path / "lens.toml")]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert read_camera(tmp_path / "lens.toml").distortion_model == "none"
    assert "wrote " in out and "(the estimated camera, no distortion found: model none)" in out
    assert "none distortion" not in out


def test_help_describes_the_positional_inputs(capsys: pytest.CaptureFixture[str]) -> None:
    """``pose --help`` never said what POINTS holds, nor ``triangulate --help`` OBSERVATIONS,
    nor ``palette-check --help`` COLORS: every command's help now gives each input's own text."""
    from imageform.workflows.registry import WORKFLOWS

    for name, expect in (
        ("pose", "POINTS: CSV of X, Y, Z, u, v"),
        ("triangulate", "OBSERVATIONS: CSV of u1, v1, u2, v2"),
        ("palette-check", "COLORS: Comma-separated hex colours"),
    ):
        assert main([name, "--help"]) == 0
        assert expect in " ".join(capsys.readouterr().out.split())
    for wf in WORKFLOWS.values():
        assert main([wf.name, "--help"]) == 0
        text = " ".join(capsys.readouterr().out.split())
        for inp in wf.inputs:
            assert " ".join(inp.help.split()) in text, (wf.name, inp.name)


def test_an_image_given_as_the_camera_file(
    distorted: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``undistort left01.jpg --camera photo.png`` answered "'utf-8' codec can't decode byte
    0x89 in position 0: invalid start byte"."""
    image, _ = distorted
    before = _files(tmp_path)
    code = main(["undistort", str(image), "-o", str(tmp_path / "u.png"), "--camera", str(image)])
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1 and "codec" not in err
    assert f"{image} is not a camera file: not UTF-8 text (byte 0)" in err
    assert _files(tmp_path) == before


@pytest.mark.parametrize(
    ("argv", "flag"),
    [
        (["chunked", "convert", "s.tif", "-o", "o.tif", "--chunk", "0"], "--chunk"),
        (["chunked", "convert", "s.tif", "-o", "o.tif", "--tile", "7"], "--tile"),
        (["batch", "convert", "*.png", "-o", "o", "--workers", "0"], "--workers"),
    ],
)
def test_scale_out_numbers_are_refused_by_their_flag(
    argv: list[str], flag: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """--chunk 0, --tile 7, --workers 0 were refused in the library's names ("expected chunk
    >= 1", "expected n_workers >= 1"); now as usage errors naming the flag."""
    assert main(argv) == 2
    assert f"Invalid value for '{flag}'" in capsys.readouterr().err
