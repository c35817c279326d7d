"""Interlaced video: detection (FFmpeg idet's rule, idet itself the peer), fields, readers."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.geometry import BrownConrady, Camera, look_at
from imageform.io import (
    deinterlace,
    detect_interlacing,
    field_camera_matrix,
    open_video,
    split_fields,
    write_image,
)
from imageform.io.interlace import _idet

ENDO = Path(__file__).resolve().parents[1] / "data" / "endo"


def _scene(shift: float, h: int = 96, w: int = 200) -> np.ndarray:
    """A smooth picture (vertically correlated, as a camera's) moved ``shift`` px right."""
    y, x = np.mgrid[:h, :w]
    return 128 + 60 * np.sin((x + shift) / 4 + y / 6) + 40 * np.cos((x + shift) / 9 - y / 5)


def _weave(first: np.ndarray, second: np.ndarray, order: str = "top") -> np.ndarray:
    rows = np.arange(first.shape[0]) % 2 == (0 if order == "top" else 1)
    return np.where(rows.reshape((-1,) + (1,) * (first.ndim - 1)), first, second)


def _clip(order: str | None, n: int = 12, step: float = 2.0) -> list[np.ndarray]:
    """``n`` uint8 frames: woven from two instants ``step`` px apart, or progressive (None)."""
    if order is None:
        return [np.round(_scene(2 * step * k)).astype(np.uint8) for k in range(n)]
    return [
        np.round(_weave(_scene(2 * step * k), _scene(2 * step * k + step), order)).astype(np.uint8)
        for k in range(n)
    ]


def _ffmpeg_idet(frames: list[np.ndarray]) -> list[str]:
    """FFmpeg's own idet filter (through PyAV): its single-frame decision for each frame."""
    av = pytest.importorskip("av")
    from av.filter import Graph

    h, w = frames[0].shape
    graph = Graph()
    src = graph.add_buffer(width=w, height=h, format="gray", time_base=Fraction(1, 25))
    idet, sink = graph.add("idet"), graph.add("buffersink")
    src.link_to(idet)
    idet.link_to(sink)
    graph.configure()
    out: list[str] = []

    def drain() -> None:
        while True:
            try:
                frame = graph.pull()
            except (av.error.BlockingIOError, av.error.EOFError):
                return
            out.append(frame.metadata["lavfi.idet.single.current_frame"])

    for i, f in enumerate(frames):
        vf = av.VideoFrame.from_ndarray(np.ascontiguousarray(f), format="gray")
        vf.pts = i
        graph.push(vf)
        drain()
    graph.push(None)
    drain()
    return out


@pytest.mark.parametrize("order", ["top", "bottom", None])
def test_single_frame_rule_is_ffmpeg_idets(order: str | None) -> None:
    frames = _clip(order, 10)
    # a still stretch and a change of direction: undetermined and mixed frames too
    frames += [frames[-1]] * 3 + frames[::-1][:4]
    theirs = _ffmpeg_idet(frames)
    names = {"top": "tff", "bottom": "bff", "progressive": "progressive"}
    f = [a.astype(np.float32) for a in frames]
    ours = [
        names.get(_idet(f[i - 1], f[i], f[i + 1]), "undetermined") for i in range(1, len(f) - 1)
    ]
    assert ours == theirs[1:-1]
    assert {"tff" if order == "top" else "bff" if order == "bottom" else "progressive",
            "undetermined"} <= set(ours)  # fmt: skip


def test_idet_agrees_on_real_endoscope_frames() -> None:
    from imageform.io import read_image

    grey = [
        np.round(read_image(ENDO / f"c3vdv3_f{i:03d}.jpg") @ [0.299, 0.587, 0.114] * 255)
        for i in range(0, 40, 4)
    ]
    woven = [_weave(grey[k], grey[k + 1]).astype(np.uint8) for k in range(len(grey) - 1)]
    frames = [g.astype(np.uint8) for g in grey] + woven
    theirs = _ffmpeg_idet(frames)
    f = [a.astype(np.float32) for a in frames]
    names = {"top": "tff", "bottom": "bff", "progressive": "progressive"}
    ours = [
        names.get(_idet(f[i - 1], f[i], f[i + 1]), "undetermined") for i in range(1, len(f) - 1)
    ]
    assert ours == theirs[1:-1]


@pytest.mark.parametrize("order", ["top", "bottom"])
def test_detects_interlaced_clips_and_their_order(order: str) -> None:
    rgb = [np.repeat(f[..., None], 3, axis=-1) for f in _clip(order)]
    found = detect_interlacing(rgb)
    assert found.interlaced and found.field_order == order
    assert found.frames == 10 and (found.top_first if order == "top" else found.bottom_first) == 10
    assert found.combing > 1.0  # adjacent rows differ more than rows two apart
    assert found.describe().startswith(f"interlaced, {order} field first (")


def test_progressive_and_still_clips_are_not_interlaced() -> None:
    moving = detect_interlacing(_clip(None))
    assert not moving.interlaced and moving.progressive == 10 and moving.combing < 1.0
    assert moving.describe().startswith("progressive (")
    for still in ([_clip(None)[0]] * 6, [_clip("top")[0]] * 6):  # interlacing invisible
        found = detect_interlacing(still)
        assert not found.interlaced and found.undetermined == found.frames == 4
        assert found.field_order is None
        assert found.describe().startswith("no motion to tell interlacing by")


def test_stream_flag_is_reported_and_gives_the_order_only_when_frames_cannot() -> None:
    still = detect_interlacing([_clip(None)[0]] * 4, stream="bb")
    assert (still.interlaced, still.field_order, still.stream) == (False, "bottom", "bb")
    assert "the stream says bb" in still.describe()
    woven = detect_interlacing(_clip("top"), stream="progressive")  # a wrong flag: frames win
    assert woven.interlaced and woven.field_order == "top"
    assert detect_interlacing(_clip("top"), stream="unknown").stream is None


def test_few_frames_decide_nothing() -> None:
    found = detect_interlacing(_clip("top", 2))
    assert found.frames == 0 and not found.interlaced and np.isnan(found.combing)
    assert not detect_interlacing([]).interlaced


def test_detect_bad_input() -> None:
    with pytest.raises(InvalidInputError, match="frames of one size"):
        detect_interlacing([np.zeros((8, 8)), np.zeros((8, 9))])
    with pytest.raises(InvalidInputError, match=r"frames\[0\] as an \(H, W\)"):
        detect_interlacing([np.zeros((8, 8, 2))])
    with pytest.raises(InvalidInputError, match="finite"):
        detect_interlacing([np.full((8, 8), np.nan)])
    with pytest.raises(InvalidInputError, match="frames as an iterable"):
        detect_interlacing(None)  # type: ignore[arg-type]
    with pytest.raises(InvalidInputError, match="stream as a str"):
        detect_interlacing([], stream=3)  # type: ignore[arg-type]


def test_split_fields_rows_and_order() -> None:
    frame = np.arange(5 * 2 * 3).reshape(5, 2, 3)
    top, bottom = split_fields(frame, "top")
    assert np.array_equal(top, frame[0::2]) and np.array_equal(bottom, frame[1::2])
    first, second = split_fields(frame, "bottom")
    assert np.array_equal(first, frame[1::2]) and np.array_equal(second, frame[0::2])
    top[0, 0, 0] = 99
    assert frame[0, 0, 0] == 0  # copies
    with pytest.raises(UnknownOptionError, match="field order"):
        split_fields(frame, "left")
    with pytest.raises(InvalidInputError, match="at least 2 rows"):
        split_fields(np.zeros((1, 4)))
    with pytest.raises(InvalidInputError, match="finite"):
        split_fields(np.full((4, 4), np.inf))


@pytest.mark.parametrize("field", ["top", "bottom"])
def test_field_camera_projects_onto_the_fields_rows(field: str) -> None:
    """A field's camera matrix against the frame's projection: row 2 r + p is field row r."""
    K = np.array([[720.0, 0.3, 359.5], [0, 690.0, 287.5], [0, 0, 1]])
    dist = BrownConrady(k1=-0.2, k2=0.05, p1=1e-3, p2=-5e-4)
    pose = look_at((40.0, -30.0, -500.0), (0.0, 0.0, 0.0), up=(0.0, -1.0, 0.0))
    X = np.random.default_rng(0).uniform(-150, 150, (200, 3)) * [1, 1, 0.3]
    uv = np.asarray(Camera(K, pose.R, pose.t, distortion=dist).project(X)[0])
    Kf = field_camera_matrix(K, field)
    uvf = np.asarray(Camera(Kf, pose.R, pose.t, distortion=dist).project(X)[0])
    p = 0 if field == "top" else 1
    np.testing.assert_allclose(uvf[:, 0], uv[:, 0], atol=1e-9)
    np.testing.assert_allclose(uvf[:, 1], (uv[:, 1] - p) / 2, atol=1e-9)
    assert Kf[1, 1] == 345.0 and Kf[1, 2] == (287.5 - p) / 2 and Kf[0].tolist() == K[0].tolist()


@pytest.mark.parametrize("field", ["top", "bottom"])
def test_field_pose_from_a_rendered_frame_matches_the_truth(field: str) -> None:
    """A board rendered whole, one field tracked with the field's K: the frame's pose."""
    pytest.importorskip("cv2")
    from imageform.geometry import BoardTracker, CharucoBoard
    from tests import video_scenes

    K = np.array([[700.0, 0, 359.5], [0, 700.0, 287.5], [0, 0, 1]])
    tex, origin = video_scenes.board_texture()
    R, t = video_scenes.poses(8, distance=380.0)[1]
    frame = video_scenes.render(tex, origin, K, (R, t), (720, 576), noise=0.0)
    fields = dict(zip(("top", "bottom"), split_fields(frame, "top"), strict=True))
    board = CharucoBoard((7, 5), 30.0, 22.0, "5x5_100")
    pose = BoardTracker(board, field_camera_matrix(K, field)).update(fields[field])
    assert pose.found
    assert np.linalg.norm(pose.tvec - t) / np.linalg.norm(t) < 2e-3
    # the same field with the frame's K (fy, cy not halved) is far off
    wrong = BoardTracker(board, K).update(fields[field])
    assert not wrong.found or np.linalg.norm(wrong.tvec - t) / np.linalg.norm(t) > 0.05


def test_field_camera_matrix_bad_input() -> None:
    with pytest.raises(InvalidInputError, match=r"K of shape \(3, 3\)"):
        field_camera_matrix(np.eye(2), "top")
    with pytest.raises(InvalidInputError, match="last row"):
        field_camera_matrix(np.array([[1.0, 0, 0], [0, 1, 0], [0, 0, 2]]), "top")
    with pytest.raises(UnknownOptionError, match="field"):
        field_camera_matrix(np.eye(3), "middle")


def test_deinterlace_linear_and_blend() -> None:
    frame = np.array([[10], [200], [30], [220], [50]], np.uint8)
    lin = deinterlace(frame, "linear", "top")[:, 0].tolist()
    assert lin == [10, 20, 30, 40, 50]  # the top field kept, the bottom's rows interpolated
    assert deinterlace(frame, "linear", "bottom")[:, 0].tolist() == [200, 200, 210, 220, 220]
    blend = deinterlace(frame.astype(np.float32), "blend")[:, 0]
    np.testing.assert_allclose(blend, [57.5, 110, 120, 130, 92.5])
    still = np.repeat(_clip(None)[0][..., None], 3, axis=-1)  # no combing: little changes
    assert np.abs(deinterlace(still, "linear").astype(int) - still).mean() < 2.5
    with pytest.raises(UnknownOptionError, match="deinterlace method"):
        deinterlace(frame, "yadif")
    with pytest.raises(InvalidInputError, match="at least 2 rows"):
        deinterlace(np.zeros((2, 2, 2, 2)), "blend")


def _folder(tmp_path: Path, frames: list[np.ndarray]) -> Path:
    folder = tmp_path / "frames"
    folder.mkdir(parents=True)
    for i, f in enumerate(frames):
        write_image(folder / f"f{i:03d}.png", np.repeat(f[..., None], 3, axis=-1))
    return folder


def test_reader_auto_splits_an_interlaced_clip_into_fields(tmp_path: Path) -> None:
    frames = _clip("bottom", 8)
    with open_video(_folder(tmp_path, frames), fps=25, deinterlace="auto") as reader:
        got = list(reader)
        assert reader.deinterlaced == "fields" and reader.field_order == "bottom"
        assert reader.interlacing is not None and reader.interlacing.interlaced
    assert len(got) == 16
    assert [f.field for f in got[:4]] == ["bottom", "top", "bottom", "top"]
    assert [f.index for f in got[:3]] == [0, 1, 2]
    np.testing.assert_allclose([f.time_s for f in got[:4]], [0, 0.02, 0.04, 0.06])
    np.testing.assert_array_equal(got[2].image[..., 0], frames[1][1::2])
    np.testing.assert_array_equal(got[3].image[..., 0], frames[1][0::2])


def test_reader_auto_leaves_progressive_and_still_clips_alone(tmp_path: Path) -> None:
    for name, frames in (("moving", _clip(None, 6)), ("still", [_clip("top")[0]] * 6)):
        with open_video(_folder(tmp_path / name, frames), deinterlace="auto") as reader:
            got = list(reader)
            assert reader.deinterlaced == "off" and reader.field_order is None
        assert [f.field for f in got] == [None] * 6
        for f, want in zip(got, frames, strict=True):
            np.testing.assert_array_equal(f.image[..., 0], want)


def test_reader_reads_ahead_within_its_memory_bound(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import imageform.io.video as video

    folder = _folder(tmp_path, _clip("top", 30))
    monkeypatch.setattr(video, "_PROBE_BYTES", 3 * 200 * 96 * 12)  # twelve frames' worth
    with open_video(folder, deinterlace="auto") as reader:
        assert sum(1 for _ in reader) == 60
        assert reader.interlacing is not None and reader.interlacing.frames == 10
    monkeypatch.setattr(video, "_PROBE_BYTES", 1)  # never fewer than 8
    with open_video(folder, deinterlace="auto") as reader:
        assert sum(1 for _ in reader) == 60
        assert reader.interlacing is not None and reader.interlacing.frames == 6


def test_reader_forced_methods_and_off(tmp_path: Path) -> None:
    frames = _clip("top", 5)
    folder = _folder(tmp_path, frames)
    with open_video(folder, deinterlace="fields", field_order="bottom") as reader:
        got = list(reader)
    assert reader.field_order == "bottom" and got[0].field == "bottom" and len(got) == 10
    with open_video(folder, deinterlace="linear") as reader:
        lin = list(reader)
    assert reader.field_order == "top" and lin[0].image.shape == (96, 200, 3)
    np.testing.assert_array_equal(
        lin[2].image, deinterlace(np.stack([frames[2]] * 3, -1), "linear")
    )
    with open_video(folder) as reader:  # off: not even looked at
        assert [f.field for f in reader] == [None] * 5
        assert reader.interlacing is None and reader.deinterlaced == "off"


def test_reader_reads_the_streams_field_order(tmp_path: Path) -> None:
    pytest.importorskip("av")
    from imageform.io import VideoWriter

    path = tmp_path / "clip.mp4"
    with VideoWriter(path, fps=25) as w:
        for f in _clip("top", 6):
            w.write(np.repeat(f[..., None], 3, axis=-1))
    with open_video(path, deinterlace="auto") as reader:
        n = sum(1 for _ in reader)
        assert reader.interlacing is not None
        assert reader.interlacing.stream in (None, "progressive")
        assert reader.interlacing.interlaced and n == 12  # x264 4:2:0 keeps the combing


def _mpeg2(path: Path, frames: list[np.ndarray], field_order: int) -> Path:
    """An MPEG-2 file coded interlaced (ilme, ildct), its container flagged ``field_order``
    (FFmpeg's AVFieldOrder: 2 tt, 3 bb)."""
    av = pytest.importorskip("av")
    with av.open(str(path), "w") as out:
        stream = out.add_stream("mpeg2video", rate=25)
        stream.width, stream.height, stream.pix_fmt = 200, 96, "yuv420p"
        stream.codec_context.field_order = field_order
        stream.options = {"flags": "+ilme+ildct", "qscale": "2"}
        for f in frames:
            vf = av.VideoFrame.from_ndarray(np.repeat(f[..., None], 3, axis=-1), format="rgb24")
            for packet in stream.encode(vf):
                out.mux(packet)
        for packet in stream.encode(None):
            out.mux(packet)
    return path


def test_reader_reads_an_interlaced_mpeg2_files_flag(tmp_path: Path) -> None:
    """The container's field order (``bb``) beside the frames' verdict; a still clip so
    flagged is left alone, the flag giving only the order a forced split would use."""
    woven = _mpeg2(tmp_path / "bff.mkv", _clip("bottom", 10), 3)
    with open_video(woven, deinterlace="auto") as reader:
        got = list(reader)
        found = reader.interlacing
    assert found is not None and found.stream == "bb"
    assert found.interlaced and found.field_order == "bottom" and len(got) == 20
    assert got[0].field == "bottom" and got[0].image.shape == (48, 200, 3)
    still = _mpeg2(tmp_path / "still.mkv", [_clip("bottom")[0]] * 8, 3)
    with open_video(still, deinterlace="auto") as reader:
        got = list(reader)
        found = reader.interlacing
        assert reader.deinterlaced == "off" and len(got) == 8
    assert found is not None and not found.interlaced and found.field_order == "bottom"
    with open_video(still, deinterlace="fields") as reader:
        assert next(iter(reader)).field == "bottom"  # the stream's order when frames cannot tell
        reader.close()


def test_reader_bad_options(tmp_path: Path) -> None:
    folder = _folder(tmp_path, _clip(None, 3))
    with pytest.raises(UnknownOptionError, match="deinterlace method"):
        open_video(folder, deinterlace="yadif")
    with pytest.raises(UnknownOptionError, match="field order"):
        open_video(folder, deinterlace="fields", field_order="first")
    with pytest.raises(UnknownOptionError, match="auto_method"):
        open_video(folder, deinterlace="auto", auto_method="off")


def test_reader_auto_method(tmp_path: Path) -> None:
    frames = _clip("top", 6)
    with open_video(_folder(tmp_path, frames), deinterlace="auto", auto_method="linear") as r:
        got = list(r)
        assert r.deinterlaced == "linear" and r.field_order == "top" and len(got) == 6
