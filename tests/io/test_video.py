"""Video in and out (issue 27): files, image sequences, devices; bad input in one line."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from imageform.errors import ImageformError, InvalidInputError
from imageform.io import VideoWriter, open_video, write_image

av = pytest.importorskip("av")


def _frames(n: int = 12, h: int = 64, w: int = 96) -> list[np.ndarray]:
    """A bright square moving right over a gradient: each frame different, easy to encode."""
    y, x = np.mgrid[0:h, 0:w]
    base = np.stack([x * 255 // w, y * 255 // h, np.full_like(x, 90)], -1).astype(np.uint8)
    out = []
    for i in range(n):
        f = base.copy()
        f[20:40, 4 * i : 4 * i + 20] = (250, 250, 30)
        out.append(f)
    return out


def _psnr(a: np.ndarray, b: np.ndarray) -> float:
    mse = np.mean((a.astype(np.float64) - b) ** 2)
    return float(10 * np.log10(255.0**2 / mse)) if mse else np.inf


@pytest.mark.parametrize("suffix", [".mp4", ".mkv", ".avi", ".mov"])
def test_round_trip(tmp_path: Path, suffix: str) -> None:
    frames = _frames()
    path = tmp_path / f"clip{suffix}"
    with VideoWriter(path, fps=25) as video:
        for f in frames:
            video.write(f)
    assert video.frames == len(frames)
    with open_video(path) as reader:
        info = reader.info
        got = list(reader)
    assert (info.width, info.height, info.kind) == (96, 64, "file")
    assert info.fps == pytest.approx(25)
    assert len(got) == len(frames)
    assert [g.index for g in got] == list(range(len(frames)))
    np.testing.assert_allclose([g.time_s for g in got], np.arange(len(frames)) / 25, atol=1e-6)
    for g, f in zip(got, frames, strict=True):
        assert g.image.shape == (64, 96, 3) and g.image.dtype == np.uint8
        assert _psnr(g.image, f) > 30


def test_image_sequence_folder_and_glob(tmp_path: Path) -> None:
    frames = _frames(n=11)
    for i, f in enumerate(frames):  # natural order: f2 before f10
        write_image(tmp_path / f"f{i}.png", f)
    (tmp_path / "notes.txt").write_text("not a frame")
    with open_video(tmp_path, fps=10) as reader:
        assert reader.info.frames == 11 and reader.info.kind == "sequence"
        got = list(reader)
    for g, f in zip(got, frames, strict=True):
        np.testing.assert_array_equal(g.image, f)
    assert got[10].time_s == pytest.approx(1.0)
    with open_video(str(tmp_path / "f1*.png")) as reader:  # f1, f10
        assert [g.index for g in reader] == [0, 1]


def test_image_sequence_skips_frames_that_cannot_be_read(tmp_path: Path) -> None:
    """A frame cut short in a copy, or an empty file, among the frames (the first one too):
    left out with one warning each naming it, the others read with their own numbers and
    times; a folder none of whose files can be read is refused as the first one is."""
    from imageform.errors import ImageformWarning, UnreadableFileError

    frames = _frames(n=6)
    for i, f in enumerate(frames):
        write_image(tmp_path / f"f{i}.png", f)
    (tmp_path / "f0.png").write_bytes(b"")  # the first: its header cannot be read
    whole = (tmp_path / "f3.png").read_bytes()
    (tmp_path / "f3.png").write_bytes(whole[: len(whole) // 3])  # header whole, data cut
    with pytest.warns(ImageformWarning) as caught, open_video(tmp_path, fps=10) as reader:
        got = list(reader)
    assert [g.index for g in got] == [1, 2, 4, 5]
    assert got[2].time_s == pytest.approx(0.4)
    for g in got:
        np.testing.assert_array_equal(g.image, frames[g.index])
    assert [f.name for f, _ in reader.skipped] == ["f0.png", "f3.png"]
    assert reader.skipped[0][1] == "an empty file (0 bytes)"
    texts = [str(w.message) for w in caught]
    assert texts[0] == f"{tmp_path / 'f0.png'}: skipped, cannot be read (an empty file)"
    assert texts[1].startswith(f"{tmp_path / 'f3.png'}: skipped, cannot be read (")
    bad = tmp_path / "bad"
    bad.mkdir()
    for i in range(2):
        (bad / f"f{i}.png").write_bytes(b"")
    with pytest.raises(UnreadableFileError, match=r"f0\.png: an empty file"):
        open_video(bad)


def test_image_sequence_of_bmp_frames(tmp_path: Path) -> None:
    # capture cards (endoscopy towers, old microscopes) save BMP frames: read as a sequence
    from PIL import Image

    frames = _frames(n=3)
    for i, f in enumerate(frames):
        Image.fromarray(f).save(tmp_path / f"cap{i}.bmp")
    Image.fromarray(frames[0]).save(tmp_path / "cap3.webp", lossless=True)
    with open_video(tmp_path) as reader:
        got = [g.image for g in reader]
    assert len(got) == 4
    for g, f in zip(got, [*frames, frames[0]], strict=True):
        np.testing.assert_array_equal(g, f)


def test_sequence_grey_and_16_bit(tmp_path: Path) -> None:
    write_image(tmp_path / "a.png", np.full((4, 6, 1), 128, np.uint8))
    write_image(tmp_path / "b.png", np.full((4, 6, 3), 65535, np.uint16))
    got = [f.image for f in open_video(tmp_path)]
    np.testing.assert_array_equal(got[0], np.full((4, 6, 3), 128, np.uint8))
    np.testing.assert_array_equal(got[1], np.full((4, 6, 3), 255, np.uint8))


def test_sequence_of_mixed_sizes(tmp_path: Path) -> None:
    write_image(tmp_path / "a.png", np.zeros((4, 6, 3), np.uint8))
    write_image(tmp_path / "b.png", np.zeros((6, 6, 3), np.uint8))
    with pytest.raises(InvalidInputError, match="first image has 6x4") as e:
        list(open_video(tmp_path))
    assert "\n" not in str(e.value)


def test_frames_above_the_pixel_limit(tmp_path: Path) -> None:
    """The same one line as an image above the limit (image_io's check), for both sources."""
    write_image(tmp_path / "a.png", np.zeros((30, 40, 3), np.uint8))
    with pytest.raises(InvalidInputError) as e:
        open_video(tmp_path, max_pixels=1000)
    _one_line(e, "a frame is 40 x 30 = 1200 px, above the limit of 1000 px", "IMAGEFORM_MAX")
    path = tmp_path / "clip.mp4"
    with VideoWriter(path, fps=25) as video:
        for f in _frames(2):
            video.write(f)
    with pytest.raises(InvalidInputError) as e:
        open_video(path, max_pixels=6000)
    _one_line(e, "a frame is 96 x 64 = 6144 px, above the limit of 6000 px")


def _one_line(exc: pytest.ExceptionInfo[BaseException], *words: str) -> None:
    msg = str(exc.value)
    assert "\n" not in msg, msg
    for w in words:
        assert w in msg, msg


def test_bad_sources(tmp_path: Path) -> None:
    with pytest.raises(InvalidInputError) as e:
        open_video(tmp_path / "missing.mp4")
    _one_line(e, "does not exist")
    text = tmp_path / "notes.mp4"
    text.write_text("this is not a video\n" * 100)
    with pytest.raises(InvalidInputError) as e:
        open_video(text)
    _one_line(e, "not a video FFmpeg can read")
    with pytest.raises(InvalidInputError) as e:
        open_video("/dev/video97")
    _one_line(e, "capture device /dev/video97 does not exist")
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(InvalidInputError) as e:
        open_video(empty)
    _one_line(e, "holds no images")
    with pytest.raises(InvalidInputError) as e:
        open_video(str(tmp_path / "*.png"))
    _one_line(e, "no image matches")
    with pytest.raises(InvalidInputError) as e:
        open_video(tmp_path / "f.png", fps=0)
    _one_line(e, "fps")


def test_truncated_file(tmp_path: Path) -> None:
    path = tmp_path / "clip.avi"  # MJPEG: every frame on its own, so a cut keeps the first
    with VideoWriter(path, fps=25) as video:
        for f in _frames(n=20):
            video.write(f)
    data = path.read_bytes()
    cut = tmp_path / "cut.avi"
    cut.write_bytes(data[: len(data) // 2])
    frames = []
    try:
        with open_video(cut) as reader:
            frames.extend(reader)
    except InvalidInputError as exc:  # FFmpeg noticed: one line, after the frames it had
        assert "\n" not in str(exc) and "truncated or corrupt" in str(exc)
    assert 0 < len(frames) < 20
    tiny = tmp_path / "tiny.mp4"
    tiny.write_bytes(data[:300])
    with pytest.raises(InvalidInputError) as e:
        list(open_video(tiny))
    assert "\n" not in str(e.value)


def test_zero_frames(tmp_path: Path) -> None:
    path = tmp_path / "none.mkv"
    container = av.open(str(path), mode="w")  # a video stream, no frame
    stream = container.add_stream("ffv1", rate=25)
    stream.width, stream.height, stream.pix_fmt = 16, 16, "yuv444p"
    container.start_encoding()
    container.close()
    assert path.stat().st_size > 0
    with pytest.raises(InvalidInputError) as e:
        list(open_video(path))
    _one_line(e, "no video frames")


def test_writer_bad_input(tmp_path: Path) -> None:
    with pytest.raises(InvalidInputError, match="video file name"):
        VideoWriter(tmp_path / "x.gif", fps=25)
    with pytest.raises(InvalidInputError, match="fps"):
        VideoWriter(tmp_path / "x.mp4", fps=float("nan"))
    with pytest.raises(InvalidInputError, match="preset one of ultrafast, superfast"):
        VideoWriter(tmp_path / "x.mp4", fps=25, preset="warp")
    with VideoWriter(tmp_path / "x.mp4", fps=25) as video:
        with pytest.raises(InvalidInputError, match="even frame size"):
            video.write(np.zeros((5, 6, 3), np.uint8))
        with pytest.raises(InvalidInputError, match="uint8 RGB"):
            video.write(np.zeros((4, 6, 3), np.float32))
        video.write(np.zeros((4, 6, 3), np.uint8))
        with pytest.raises(InvalidInputError, match="like the first"):
            video.write(np.zeros((6, 6, 3), np.uint8))


def test_preset_ultrafast(tmp_path: Path) -> None:
    """x264's fastest preset (track's overlay): every frame, the same quality."""
    frames = _frames()
    with VideoWriter(tmp_path / "fast.mp4", fps=25, preset="ultrafast") as video:
        for f in frames:
            video.write(f)
    with open_video(tmp_path / "fast.mp4") as reader:
        got = list(reader)
    assert len(got) == len(frames)
    assert min(_psnr(g.image, f) for g, f in zip(got, frames, strict=True)) > 30


def test_iterated_once(tmp_path: Path) -> None:
    write_image(tmp_path / "a.png", np.zeros((4, 6, 3), np.uint8))
    reader = open_video(tmp_path)
    list(reader)
    with pytest.raises(InvalidInputError, match="iterated once"):
        list(reader)


def test_missing_extra(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "av", None)
    clip = tmp_path / "x.mp4"
    clip.write_bytes(b"\x00" * 64)
    with pytest.raises(ImageformError, match=r'pip install "imageform\[video\]"') as e:
        open_video(clip)
    assert "\n" not in str(e.value)
    # an image sequence needs no PyAV
    write_image(tmp_path / "a.png", np.zeros((4, 6, 3), np.uint8))
    assert len(list(open_video(str(tmp_path / "*.png")))) == 1
