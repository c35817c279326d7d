"""Video in and out: files, image sequences and capture devices behind one reader.

Decoding and encoding go through PyAV (FFmpeg's libraries, the optional extra ``video``):

- a **video file** (MP4, MKV, AVI, MOV, ... whatever FFmpeg demuxes and decodes);
- an **image sequence**: a folder of images (PNG, JPEG, TIFF, ``.npy``; natural order, so
  ``frame2.png`` comes before ``frame10.png``) or a glob pattern (``"frames/*.png"``), read
  with :func:`imageform.io.read_image` (no PyAV needed), at a frame rate the caller gives;
- a **capture device**: ``/dev/video0`` (Linux, FFmpeg's ``v4l2`` input), read live until the
  caller stops.

Each frame comes as a :class:`Frame`: its index, its time in seconds (the stream's
presentation time, or ``index / fps`` for a sequence) and the image, ``(H, W, 3)`` uint8
RGB, one new array per frame (FFmpeg's RGB conversion writes it; nothing else is copied).
:class:`VideoWriter` encodes RGB frames to a file (H.264 in MP4/MKV/MOV, MJPEG in AVI by
default). Bad input is one :class:`~imageform.errors.InvalidInputError` line: not a video, a
truncated or corrupt file (after the frames that decoded), no video stream, zero frames, a
device that does not exist.
"""

from __future__ import annotations

import glob as _glob
import math
import os
from collections.abc import Iterator
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from types import TracebackType
from typing import Any

import numpy as np

from imageform._files import git_lfs_pointer
from imageform._typing import ArrayLike
from imageform._validate import describe
from imageform.errors import InvalidInputError, UnreadableFileError
from imageform.io.image_io import IMAGE_FORMATS, _natural_key, image_files, is_dicom_file
from imageform.io.interlace import Interlacing

__all__ = [
    "VIDEO_SUFFIXES",
    "Frame",
    "VideoInfo",
    "VideoReader",
    "VideoWriter",
    "open_video",
]

#: File suffixes read as video files (any other existing file is offered to FFmpeg too).
VIDEO_SUFFIXES = (".mp4", ".m4v", ".mkv", ".avi", ".mov", ".webm", ".mpg", ".mpeg", ".ts")

#: Frames read ahead to decide whether a clip is interlaced (``deinterlace="auto"``), and
#: the most memory they may take (8 frames at least: 120 of PAL, 43 of 1080p, 10 of 4K).
_PROBE_FRAMES = 120
_PROBE_BYTES = 256 * 2**20

#: x264's speed presets, fastest first (:class:`VideoWriter`'s ``preset``).
_X264_PRESETS = (
    "ultrafast", "superfast", "veryfast", "faster", "fast", "medium", "slow", "slower",
    "veryslow",
)  # fmt: skip

#: Image suffixes of an image sequence (a folder or glob of frames): every suffix read_image
#: reads, HEIF and DICOM frames too.
_IMAGE_SUFFIXES = tuple(IMAGE_FORMATS)

#: Encoder by container, first available wins.
_CODECS = {
    ".mp4": ("libx264", "h264", "mpeg4"),
    ".m4v": ("libx264", "h264", "mpeg4"),
    ".mov": ("libx264", "h264", "mpeg4"),
    ".mkv": ("libx264", "h264", "ffv1", "mpeg4"),
    ".avi": ("mjpeg", "mpeg4"),
}


def _av() -> Any:
    from imageform._optional import require

    return require("av", what="reading and writing video")


@dataclass(frozen=True)
class Frame:
    """One frame of a video.

    Attributes
    ----------
    index : int
        0 for the first frame read.
    time_s : float
        Its time in seconds from the start of the stream (``index / fps`` for an image
        sequence; the capture time for a device).
    image : ndarray (H, W, 3) uint8
        RGB.
    path : Path or None
        The image file of an image sequence's frame (None for a video file or a device).
    field : {"top", "bottom"} or None
        The field this image is when the reader splits interlaced frames into their fields
        (``deinterlace="fields"``): half the frame's height, the camera matrix
        :func:`imageform.io.field_camera_matrix`; None for a whole frame.
    """

    index: int
    time_s: float
    image: np.ndarray
    path: Path | None = None
    field: str | None = None


@dataclass(frozen=True)
class VideoInfo:
    """What a video source is.

    Attributes
    ----------
    width, height : int
        Frame size in pixels.
    fps : float
        Frames per second (the stream's average rate; given for an image sequence).
    frames : int or None
        The number of frames when the container says (a sequence always; a device never).
    kind : {"file", "sequence", "device"}
        The kind of source.
    codec : str
        The decoder's name (``"image"`` for a sequence).
    """

    width: int
    height: int
    fps: float
    frames: int | None
    kind: str
    codec: str


def _sequence_files(source: str) -> list[Path] | None:
    """Return the images of a folder or glob pattern in natural order (None: not one)."""
    if Path(source).is_dir():
        return image_files(source)
    if _glob.has_magic(source):
        files = [Path(f) for f in _glob.glob(source) if Path(f).is_file()]
        files = [f for f in files if f.suffix.lower() in _IMAGE_SUFFIXES]
        if not files:
            raise InvalidInputError(f"no image matches {describe(source)}")
        return sorted(files, key=lambda f: (_natural_key(f.name), str(f)))
    return None


def _is_device(source: str) -> bool:
    return source.startswith(("/dev/video", "v4l2:"))


def _rgb8(image: np.ndarray, where: str) -> np.ndarray:
    """Return an image of a sequence as (H, W, 3) uint8 RGB (grey repeated, 16 bits scaled)."""
    a = np.asarray(image)
    if a.ndim == 2:
        a = a[..., None]
    if a.ndim != 3 or a.shape[-1] not in (1, 3):
        raise InvalidInputError(f"{where}: expected a grey or RGB image, got {describe(a)}")
    if a.dtype == np.uint16:
        a = ((a.astype(np.uint32) * 255 + 32767) // 65535).astype(np.uint8)
    elif a.dtype.kind == "f":
        a = np.round(np.clip(a, 0.0, 1.0) * 255).astype(np.uint8)
    elif a.dtype != np.uint8:
        raise InvalidInputError(f"{where}: unsupported sample type {a.dtype}")
    if a.shape[-1] == 1:
        a = np.repeat(a, 3, axis=-1)
    return a


def _first_info(files: list[Path]) -> Any:
    """Return the header of an image sequence's first file that can be read.

    Files before it are skipped with a warning when the frames are read; raises the first
    file's UnreadableFileError when no file's header can be read.
    """
    from imageform.io.image_io import image_info

    first_error: UnreadableFileError | None = None
    for f in files:
        try:
            return image_info(f)
        except UnreadableFileError as exc:
            first_error = first_error or exc
    assert first_error is not None
    raise first_error


class VideoReader:
    """Frames of a video file, an image sequence or a capture device, one at a time.

    Use :func:`open_video`. A context manager and an iterator of :class:`Frame`; iterate
    once. ``info`` says what the source is.

    Parameters
    ----------
    source : str or Path
        A video file, a folder of images, a glob pattern of images, or a capture device
        (``/dev/video0``).
    fps : float, optional
        The frame rate of an image sequence (default 30); for a device, the rate to ask for.
        Ignored for a file, whose stream says.
    max_pixels : int, optional
        Refuse frames with more pixels (default :func:`imageform.io.max_pixels`).
    deinterlace : {"off", "auto", "fields", "linear", "blend"}
        Interlaced frames (:mod:`imageform.io.interlace`): ``"off"`` (the default) as
        decoded; ``"fields"`` each frame as its two fields at half height, first in time
        first, half a frame period apart (:attr:`Frame.field` says which); ``"linear"`` and
        ``"blend"`` full frames (:func:`imageform.io.deinterlace`); ``"auto"``:
        ``"fields"`` when :func:`imageform.io.detect_interlacing` finds combing in the first
        frames (up to 120 read ahead, at most 256 MB of them and 8 at least; a quarter of
        that from a device), else as decoded.
    field_order : {"top", "bottom"}, optional
        The field first in time; default: the one the frames show, else the stream's flag,
        else top.
    auto_method : {"fields", "linear", "blend"}
        What ``deinterlace="auto"`` applies to a clip found interlaced (default
        ``"fields"``: a pose a field for tracking; ``"linear"`` keeps the frame's size and
        camera matrix, for structure from motion).

    Attributes
    ----------
    interlacing : Interlacing or None
        What the first frames showed (set when iteration starts; None with
        ``deinterlace="off"``).
    deinterlaced : str
        The method applied (``"auto"`` resolved to ``"fields"`` or ``"off"`` when iteration
        starts).
    field_order : str or None
        The field order applied (None when ``deinterlaced`` is ``"off"``).
    skipped : list of (Path, str)
        The files of an image sequence left out as they were read, each with the reason: a
        file that cannot be read (:class:`~imageform.errors.UnreadableFileError`: empty, cut
        short, not an image) is skipped with an :class:`~imageform.errors.ImageformWarning`
        and the frames after it keep their numbers and times.
    """

    def __init__(
        self,
        source: str | Path,
        *,
        fps: float | None = None,
        max_pixels: int | None = None,
        deinterlace: str = "off",
        field_order: str | None = None,
        auto_method: str = "fields",
    ) -> None:
        from imageform._validate import check_option
        from imageform.io.image_io import _pixel_limit
        from imageform.io.interlace import DEINTERLACE_METHODS, FIELD_ORDERS

        if not isinstance(source, str | os.PathLike):
            raise TypeError(f"expected source as a path, got {describe(source)}")
        if fps is not None and not (isinstance(fps, int | float) and 0 < fps < 1e4):
            raise InvalidInputError(f"expected fps in (0, 10000), got {describe(fps)}")
        self._deinterlace = check_option(deinterlace, DEINTERLACE_METHODS, "deinterlace method")
        self._order = (
            None if field_order is None else check_option(field_order, FIELD_ORDERS, "field order")
        )
        self._auto = check_option(auto_method, DEINTERLACE_METHODS[2:], "auto_method")
        self.interlacing: Interlacing | None = None
        self.deinterlaced = self._deinterlace
        self.field_order: str | None = None
        self._stream_order: str | None = None
        self._limit = _pixel_limit(max_pixels)
        self._source = str(source)
        self._container: Any = None
        self._files = _sequence_files(self._source)
        self._iterated = False
        self.skipped: list[tuple[Path, str]] = []
        if self._files is not None:
            first = _first_info(self._files)
            self._check_size(first.width, first.height)
            self.info = VideoInfo(
                first.width, first.height, float(fps or 30.0), len(self._files), "sequence",
                "image",
            )  # fmt: skip
            return
        self._dicom: Path | None = None
        if not _is_device(self._source) and is_dicom_file(self._source):
            self._open_dicom(Path(self._source), fps)
            return
        av = _av()
        device = _is_device(self._source)
        path = self._source.removeprefix("v4l2:")
        if not device:
            p = Path(path)
            if not p.exists():
                raise InvalidInputError(f"video {p} does not exist")
            if not p.is_file():
                raise InvalidInputError(f"video {p} is not a regular file")
            if (lfs := git_lfs_pointer(p)) is not None:
                raise UnreadableFileError(p, lfs)
        elif not os.path.exists(path):
            raise InvalidInputError(f"capture device {path} does not exist")
        options = {"framerate": str(fps)} if device and fps else {}
        try:
            self._container = av.open(path, format="v4l2" if device else None, options=options)
        except Exception as exc:  # av.error.InvalidDataError, PermissionError, ...
            if isinstance(exc, EOFError) and not device:
                raise InvalidInputError(
                    f"{path} has no video frames (the file ends before the first)"
                ) from None
            what = "capture device" if device else "video"
            raise InvalidInputError(
                f"{path} is not a {what} FFmpeg can read ({type(exc).__name__})"
            ) from None
        streams = self._container.streams.video
        if not streams:
            self._container.close()
            raise InvalidInputError(f"{path} has no video stream")
        self._stream = streams[0]
        self._stream.thread_type = "AUTO"
        ctx = self._stream.codec_context
        self._stream_order = _field_order_flag(ctx)
        rate = self._stream.average_rate or self._stream.guessed_rate or (fps or 30)
        frames = int(self._stream.frames) or None
        self._check_size(int(ctx.width), int(ctx.height))
        self.info = VideoInfo(
            int(ctx.width),
            int(ctx.height),
            float(rate),
            None if device else frames,
            "device" if device else "file",
            str(ctx.name),
        )

    def _open_dicom(self, path: Path, fps: float | None) -> None:
        """Open a multi-frame DICOM file (an endoscopy or ultrasound cine, a fluoroscopy run).

        The rate is the file's Frame Time (ms a frame), else its Cine Rate or Recommended
        Display Frame Rate, else ``fps`` (default 30).
        """
        from imageform.io.dicom import _number, header, open_dicom

        head = open_dicom(path, pixels=False)
        info = header(path, head)
        self._check_size(info.width, info.height)
        frame_ms = _number(head, "FrameTime", 0.0)
        rates = [1000.0 / frame_ms if frame_ms > 0 else 0.0]
        rates += [_number(head, k, 0.0) for k in ("CineRate", "RecommendedDisplayFrameRate")]
        rate = next((r for r in rates if 0 < r < 1e4), float(fps or 30.0))
        self._dicom = path
        self.info = VideoInfo(info.width, info.height, rate, info.frames, "file", "dicom")

    def _dicom_frames(self) -> Iterator[Frame]:
        """Decode a DICOM file's frames, the file read once.

        8 bits as stored, more bits by their stored range, rescaled (float) values through the
        file's VOI window (``"auto"``: its window, else the frame's range).
        """
        from imageform.io.dicom import decode, header, open_dicom

        assert self._dicom is not None
        ds = open_dicom(self._dicom, pixels=True)
        if "PixelData" not in ds:
            raise UnreadableFileError(self._dicom, "the DICOM file has no pixel data")
        for i in range(int(self.info.frames or 0)):
            info = header(self._dicom, ds, i)
            floats = info.dtype.startswith("float")
            values = decode(self._dicom, ds, info, i, "auto" if floats else None)
            if values.dtype == np.uint16 and info.bits_stored < 16:
                top = float(2**info.bits_stored - 1)
                values = np.clip(values.astype(np.float32) / np.float32(top), 0.0, 1.0)
            yield Frame(i, i / self.info.fps, _rgb8(values, f"{self._dicom} frame {i}"))

    def _check_size(self, width: int, height: int) -> None:
        from imageform.io.image_io import ImageInfo, _check_pixels

        if width <= 0 or height <= 0:
            raise InvalidInputError(f"{self._source}: frames of {width}x{height} pixels")
        info = ImageInfo(width, height, 3, "uint8", "video")
        remedy = "raise it with max_pixels= or IMAGEFORM_MAX_PIXELS"
        _check_pixels(f"{self._source}: a frame", info, self._limit, remedy)

    def __enter__(self) -> VideoReader:
        """Return the reader."""
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        """Close the source."""
        self.close()

    def close(self) -> None:
        """Close the source (a no-op when closed)."""
        if self._container is not None:
            self._container.close()
            self._container = None

    def __iter__(self) -> Iterator[Frame]:
        """Yield the frames in order (once)."""
        if self._iterated:
            raise InvalidInputError(f"{self._source}: a VideoReader is iterated once")
        self._iterated = True
        if self._files is not None:
            raw = self._sequence()
        elif self._dicom is not None:
            raw = self._dicom_frames()
        else:
            raw = self._decode()
        if self._deinterlace == "off":
            yield from raw
        else:
            yield from self._deinterlaced(raw)

    def _deinterlaced(self, raw: Iterator[Frame]) -> Iterator[Frame]:
        """Read ahead, decide (``"auto"``), then deinterlace every frame."""
        from imageform.io.interlace import deinterlace, detect_interlacing, split_fields

        head: list[Frame] = []
        frame_bytes = 3 * self.info.width * self.info.height
        probe = max(8, min(_PROBE_FRAMES, _PROBE_BYTES // frame_bytes))
        if self.info.kind == "device":  # live: a quarter of it, not to hold the first pose
            probe = max(8, probe // 4)
        for f in raw:
            head.append(f)
            if len(head) >= probe:
                break
        found = detect_interlacing((f.image for f in head), stream=self._stream_order)
        self.interlacing = found
        method = self._deinterlace
        if method == "auto":
            method = self._auto if found.interlaced else "off"
        self.deinterlaced = method
        if method == "off":
            yield from head
            yield from raw
            return
        order = self._order or found.field_order or "top"
        self.field_order = order
        second = "bottom" if order == "top" else "top"
        half = 0.5 / self.info.fps
        index = 0
        for f in _chain(head, raw):
            if method != "fields":
                yield Frame(f.index, f.time_s, deinterlace(f.image, method, order), f.path)
                continue
            a, b = split_fields(f.image, order)
            yield Frame(index, f.time_s, a, f.path, order)
            yield Frame(index + 1, f.time_s + half, b, f.path, second)
            index += 2

    def _sequence(self) -> Iterator[Frame]:
        from imageform.io.image_io import read_image

        assert self._files is not None
        shape = (self.info.height, self.info.width)
        for i, f in enumerate(self._files):
            try:
                img = _rgb8(read_image(f, alpha="drop", max_pixels=self._limit), str(f))
            except UnreadableFileError as exc:  # a frame cut short in a copy: go on without it
                self._skip(f, exc)
                continue
            if img.shape[:2] != shape:
                raise InvalidInputError(
                    f"{f}: {img.shape[1]}x{img.shape[0]} pixels where the sequence's first "
                    f"image has {shape[1]}x{shape[0]}"
                )
            yield Frame(i, i / self.info.fps, img, f)

    def _skip(self, f: Path, exc: UnreadableFileError) -> None:
        """Leave out a frame of a sequence that cannot be read, with a warning naming it."""
        import warnings

        from imageform.errors import ImageformWarning

        self.skipped.append((f, exc.reason))
        warnings.warn(f"{f}: skipped, cannot be read ({exc.brief})", ImageformWarning, stacklevel=2)

    def _decode(self) -> Iterator[Frame]:
        av = _av()
        index = 0
        base = self._stream.time_base
        start = self._stream.start_time or 0
        try:
            for packet in self._container.demux(self._stream):
                for frame in packet.decode():
                    if frame.pts is not None and base is not None:
                        t = float((frame.pts - start) * base)
                    else:
                        t = index / self.info.fps
                    yield Frame(index, t, frame.to_ndarray(format="rgb24"))
                    index += 1
        except av.error.FFmpegError as exc:
            if index == 0:
                raise InvalidInputError(
                    f"{self._source}: no frame could be decoded ({type(exc).__name__})"
                ) from None
            raise InvalidInputError(
                f"{self._source} is truncated or corrupt after frame {index - 1} "
                f"({type(exc).__name__})"
            ) from None
        finally:
            self.close()
        if index == 0:
            raise InvalidInputError(f"{self._source} has no video frames")


def _chain(head: list[Frame], rest: Iterator[Frame]) -> Iterator[Frame]:
    yield from head
    yield from rest


def _field_order_flag(ctx: Any) -> str | None:
    """Return the stream's field order as FFmpeg names it (None: not said)."""
    from imageform.io.interlace import _AV_FIELD_ORDERS

    try:
        value = ctx.field_order
    except Exception:  # an older PyAV without it
        return None
    if isinstance(value, int) and 0 <= value < len(_AV_FIELD_ORDERS):
        value = _AV_FIELD_ORDERS[value]
    text = str(getattr(value, "name", value)).lower()
    return text if text in _AV_FIELD_ORDERS[1:] else None


def open_video(
    source: str | Path,
    *,
    fps: float | None = None,
    max_pixels: int | None = None,
    deinterlace: str = "off",
    field_order: str | None = None,
    auto_method: str = "fields",
) -> VideoReader:
    """Open a video file, an image sequence (a folder or a glob) or a capture device.

    Parameters
    ----------
    source : str or Path
        ``clip.mp4``, ``frames/`` (a folder of images), ``"frames/*.png"``, ``/dev/video0``,
        or a multi-frame DICOM file (a cine: ``DICM`` at byte 128, the ``dicom`` extra).
    fps : float, optional
        The frame rate of an image sequence (default 30) or the one to ask a device for; a
        DICOM cine's own Frame Time, Cine Rate or Recommended Display Frame Rate comes first.
    max_pixels : int, optional
        Refuse frames with more pixels (default :func:`imageform.io.max_pixels`).
    deinterlace : {"off", "auto", "fields", "linear", "blend"}
        Interlaced frames: as decoded (the default), split into fields, deinterlaced at full
        size, or ``"auto"`` (fields when the first frames comb): :class:`VideoReader`.
    field_order : {"top", "bottom"}, optional
        The field first in time (default: the frames', else the stream's, else top).
    auto_method : {"fields", "linear", "blend"}
        What ``"auto"`` applies to an interlaced clip (default ``"fields"``).

    Returns
    -------
    VideoReader
        Iterate it for :class:`Frame` objects; ``.info`` is a :class:`VideoInfo`.

    Raises
    ------
    InvalidInputError
        A missing file, folder or device; not a video; no video stream; an empty folder; a
        folder none of whose images can be read (one that cannot be read among others is
        skipped with a warning: :attr:`VideoReader.skipped`).
    imageform.errors.ImageformError
        PyAV is not installed for a file or a device (``pip install "imageform[video]"``).

    Examples
    --------
    >>> import numpy as np, tempfile, pathlib
    >>> from imageform.io import write_image
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> for i in range(3):
    ...     _ = write_image(folder / f"f{i}.png", np.full((4, 6, 3), 40 * i, np.uint8))
    >>> with open_video(folder, fps=10) as video:
    ...     print(video.info.frames, [(f.index, f.time_s, f.image.shape) for f in video])
    3 [(0, 0.0, (4, 6, 3)), (1, 0.1, (4, 6, 3)), (2, 0.2, (4, 6, 3))]
    """
    return VideoReader(
        source,
        fps=fps,
        max_pixels=max_pixels,
        deinterlace=deinterlace,
        field_order=field_order,
        auto_method=auto_method,
    )


class VideoWriter:
    """Encode RGB frames to a video file (PyAV).

    A context manager: frames go in with :meth:`write`; :meth:`close` flushes the encoder.

    Parameters
    ----------
    path : str or Path
        The file; its suffix picks the container (``.mp4``, ``.mkv``, ``.mov``, ``.avi``).
    fps : float
        Frames per second.
    codec : str, optional
        An FFmpeg encoder; default H.264 (``libx264``) for MP4/MKV/MOV, MJPEG for AVI, with
        MPEG-4 part 2 where those are missing.
    quality : int
        For H.264, the constant rate factor (0 lossless to 51; default 18, visually
        lossless); ignored by other encoders.
    preset : str
        For H.264, x264's speed preset, from ``"ultrafast"`` (about three times faster than
        the default ``"veryfast"``, a bigger file at the same quality: for video written
        while it is captured or tracked) to ``"veryslow"``; ignored by other encoders.
    """

    def __init__(
        self,
        path: str | Path,
        fps: float,
        *,
        codec: str | None = None,
        quality: int = 18,
        preset: str = "veryfast",
    ) -> None:
        av = _av()
        p = Path(path)
        suffix = p.suffix.lower()
        if suffix not in _CODECS:
            raise InvalidInputError(
                f"expected a video file name ending in {', '.join(_CODECS)}, got "
                f"{describe(p.name, 60)}"
            )
        if not (isinstance(fps, int | float) and math.isfinite(fps) and 0 < fps < 1e4):
            raise InvalidInputError(f"expected fps in (0, 10000), got {describe(fps)}")
        if isinstance(quality, bool) or not isinstance(quality, int) or not 0 <= quality <= 51:
            raise InvalidInputError(f"expected quality an integer in [0, 51], got {quality!r}")
        if preset not in _X264_PRESETS:
            raise InvalidInputError(
                f"expected preset one of {', '.join(_X264_PRESETS)}, got {describe(preset)}"
            )
        names = (codec,) if codec else _CODECS[suffix]
        chosen = next((c for c in names if c in av.codecs_available), None)
        if chosen is None:
            raise InvalidInputError(f"no encoder among {', '.join(names)} in this FFmpeg")
        self.path = p
        self._fps = Fraction(fps).limit_denominator(1001)
        self._codec = chosen
        self._quality = quality
        self._preset = preset
        self._container = av.open(str(p), mode="w")
        self._stream: Any = None
        self.frames = 0

    def _open_stream(self, width: int, height: int) -> None:
        stream = self._container.add_stream(self._codec, rate=self._fps)
        stream.width, stream.height = width, height
        if self._codec == "mjpeg":
            stream.pix_fmt = "yuvj420p"
            ctx = stream.codec_context  # fixed quantiser 2 of 31: near-lossless JPEG frames
            ctx.qscale = True
            ctx.global_quality = 2 * 118  # FF_QP2LAMBDA
            ctx.qmin = ctx.qmax = 2
        elif self._codec == "ffv1":
            stream.pix_fmt = "yuv444p"
        else:
            stream.pix_fmt = "yuv420p"
        if self._codec == "libx264":
            stream.options = {"crf": str(self._quality), "preset": self._preset}
        self._stream = stream

    def write(self, image: ArrayLike) -> None:
        """Encode one frame: ``(H, W, 3)`` uint8 RGB (every frame the size of the first).

        H.264 and MJPEG with 4:2:0 chroma need an even width and height: an odd one is
        refused.
        """
        av = _av()
        a = np.asarray(image)
        if a.ndim != 3 or a.shape[-1] != 3 or a.dtype != np.uint8:
            raise InvalidInputError(f"expected a frame as (H, W, 3) uint8 RGB, got {describe(a)}")
        h, w = a.shape[:2]
        if self._stream is None:
            if self._codec != "ffv1" and (h % 2 or w % 2):
                raise InvalidInputError(
                    f"expected an even frame size for {self._codec}, got {w}x{h}"
                )
            self._open_stream(w, h)
        elif (h, w) != (self._stream.height, self._stream.width):
            raise InvalidInputError(
                f"expected frames of {self._stream.width}x{self._stream.height} like the "
                f"first, got {w}x{h}"
            )
        frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(a), format="rgb24")
        for packet in self._stream.encode(frame):
            self._container.mux(packet)
        self.frames += 1

    def close(self) -> None:
        """Flush the encoder and close the file (a no-op when closed)."""
        if self._container is None:
            return
        try:
            if self._stream is not None:
                for packet in self._stream.encode(None):
                    self._container.mux(packet)
        finally:
            self._container.close()
            self._container = None

    def __enter__(self) -> VideoWriter:
        """Return the writer."""
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        """Close the file (flushing the encoder)."""
        self.close()
