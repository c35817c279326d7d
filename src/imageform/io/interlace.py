"""Interlaced video: find the combing from the frames, split the fields, deinterlace.

An interlaced frame (PAL 720 x 576 and NTSC 720 x 480 SD outputs of endoscopy towers, frame
grabbers) holds two fields half a frame period apart: the even rows (the *top* field, row 0
first) and the odd rows (the *bottom* field). When something moves, the two fields of one
frame disagree and the edges comb; when nothing moves, an interlaced frame is a progressive
one.

:func:`detect_interlacing` decides per clip from the frames, by FFmpeg's ``idet`` filter's
single-frame rule (``libavfilter/vf_idet.c``). For each frame with its previous and next
frame, and every row ``y`` of the frame, the row predicted from its two neighbours (rows
``y - 1`` and ``y + 1``, the other field of the frame) is compared with row ``y`` of the
previous frame and of the next frame; the sums ``alpha[0]`` (previous frame's even rows, next
frame's odd rows) and ``alpha[1]`` (previous odd, next even) and ``delta`` (the frame's own
row ``y``) of the absolute differences decide: top field first when ``alpha[0] > 1.04
alpha[1]``, bottom field first when ``alpha[1] > 1.04 alpha[0]``, progressive when
``alpha[1] > 1.5 delta``, else undetermined (a still scene). The clip is interlaced when its
frames decided interlaced outnumber those decided progressive (and there are at least two);
its order is the more frequent one. A static clip is all undetermined: not interlaced,
nothing changes.

:func:`split_fields` gives the two fields at half height; :func:`field_camera_matrix` the
camera matrix of a field: a field's row ``r`` is the frame's row ``2 r + p`` (``p`` 0 for the
top field, 1 for the bottom), so ``fy`` and ``cy`` become ``fy / 2`` and ``(cy - p) / 2``
(pixel centres at integer coordinates) and the projection is exact: the distortion acts on
normalised coordinates and is unchanged. :func:`deinterlace` gives full-size frames:
``"linear"`` keeps the first field and fills the other field's rows with the mean of the rows
above and below; ``"blend"`` averages the two fields (a vertical ``[1, 2, 1] / 4`` filter).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from imageform._colormath import luma_601
from imageform._typing import ArrayLike
from imageform._validate import as_matrix, check_option, describe
from imageform.errors import InvalidInputError

__all__ = [
    "DEINTERLACE_METHODS",
    "FIELD_ORDERS",
    "Interlacing",
    "deinterlace",
    "detect_interlacing",
    "field_camera_matrix",
    "split_fields",
]

#: The deinterlacing choices of :func:`imageform.io.open_video` (``"auto"``: ``"fields"``
#: when :func:`detect_interlacing` finds combing, else ``"off"``).
DEINTERLACE_METHODS = ("auto", "off", "fields", "linear", "blend")

#: Field orders: the field first in time.
FIELD_ORDERS = ("top", "bottom")

#: FFmpeg idet's thresholds (its ``intl_thres`` and ``prog_thres`` defaults).
_INTERLACE_THRESHOLD = 1.04
_PROGRESSIVE_THRESHOLD = 1.5

#: The stream's field order (PyAV's ``codec_context.field_order``) to the field first in time.
_STREAM_ORDERS = {"tt": "top", "tb": "top", "bb": "bottom", "bt": "bottom"}

#: FFmpeg's ``AVFieldOrder`` values (PyAV gives the number).
_AV_FIELD_ORDERS = ("unknown", "progressive", "tt", "bb", "tb", "bt")


@dataclass(frozen=True)
class Interlacing:
    """Whether a clip is interlaced, and its field order.

    Attributes
    ----------
    interlaced : bool
        The frames comb (FFmpeg idet's rule decided more frames interlaced than progressive).
    field_order : {"top", "bottom"} or None
        The field first in time when ``interlaced`` (else the stream's flag when it says one,
        else None).
    frames : int
        Frames measured (each with its previous and next frame).
    top_first, bottom_first, progressive, undetermined : int
        idet's decisions on the measured frames.
    combing : float
        The median over the frames of the mean squared difference of adjacent rows (opposite
        fields) over that of rows two apart (the same field): below 1 for a smooth
        progressive picture, above 1 where strong moving edges comb. Informative only (small
        motion over a whole frame barely moves it): idet's rule decides.
    stream : str or None
        The stream's field-order flag (``"progressive"``, ``"tt"``, ``"bb"``, ``"tb"``,
        ``"bt"``) when the container says one.
    """

    interlaced: bool
    field_order: str | None
    frames: int
    top_first: int
    bottom_first: int
    progressive: int
    undetermined: int
    combing: float
    stream: str | None = None

    def describe(self) -> str:
        """Say in words what was found (for a workflow's notes)."""
        flag = f"; the stream says {self.stream}" if self.stream else ""
        counts = (
            f"{self.top_first} top first, {self.bottom_first} bottom first, "
            f"{self.progressive} progressive, {self.undetermined} undetermined of "
            f"{self.frames} frames"
        )
        if self.interlaced:
            return f"interlaced, {self.field_order} field first ({counts}{flag})"
        if self.frames and self.undetermined == self.frames:
            return f"no motion to tell interlacing by: read as progressive ({counts}{flag})"
        return f"progressive ({counts}{flag})"


def _luma(image: ArrayLike, name: str) -> np.ndarray:
    a = np.asarray(image)
    if a.ndim == 3 and a.shape[-1] in (1, 3, 4):
        a = a[..., 0] if a.shape[-1] == 1 else luma_601(np, a)  # Rec. 601, channel by channel
    if a.ndim != 2 or a.dtype.kind not in "uif" or a.shape[0] < 2:
        raise InvalidInputError(
            f"expected {name} as an (H, W) or (H, W, 3) image of at least 2 rows, got {describe(a)}"
        )
    out = np.asarray(a, np.float32)
    if not np.all(np.isfinite(out)):
        raise InvalidInputError(f"expected {name} with finite values")
    return out


def _combing(y: np.ndarray) -> float:
    """Mean squared difference of adjacent rows over that of rows two apart."""
    if y.shape[0] < 3:
        return float("nan")
    near = float(np.mean((y[1:] - y[:-1]) ** 2))
    far = float(np.mean((y[2:] - y[:-2]) ** 2))
    return near / far if far > 0 else (1.0 if near == 0 else float("inf"))


def _idet(prev: np.ndarray, cur: np.ndarray, nxt: np.ndarray) -> str:
    """FFmpeg idet's single-frame decision: "top", "bottom", "progressive" or "undetermined"."""
    h = cur.shape[0]
    if h < 5:
        return "undetermined"
    rows = np.arange(2, h - 2)
    pred = cur[rows - 1] + cur[rows + 1]
    v_prev = np.abs(pred - 2 * prev[rows]).sum(axis=1, dtype=np.float64)
    v_next = np.abs(pred - 2 * nxt[rows]).sum(axis=1, dtype=np.float64)
    delta = float(np.abs(pred - 2 * cur[rows]).sum(dtype=np.float64))
    even = rows % 2 == 0
    alpha0 = float(v_prev[even].sum() + v_next[~even].sum())
    alpha1 = float(v_next[even].sum() + v_prev[~even].sum())
    if alpha0 > _INTERLACE_THRESHOLD * alpha1:
        return "top"
    if alpha1 > _INTERLACE_THRESHOLD * alpha0:
        return "bottom"
    if alpha1 > _PROGRESSIVE_THRESHOLD * delta:
        return "progressive"
    return "undetermined"


def detect_interlacing(frames: Iterable[ArrayLike], *, stream: str | None = None) -> Interlacing:
    """Decide whether consecutive frames are interlaced, and which field comes first.

    FFmpeg idet's single-frame rule on each frame with its neighbours (the module's
    docstring); the clip is interlaced when more frames are decided interlaced than
    progressive, at least two of them.

    Parameters
    ----------
    frames : iterable of array_like (H, W) or (H, W, 3)
        Consecutive frames of one clip, all one size (three at least to decide anything).
    stream : str, optional
        The container's field-order flag (``"progressive"``, ``"tt"``, ``"bb"``, ``"tb"``,
        ``"bt"``, ``"unknown"``): reported, and the order when the frames cannot tell it.

    Returns
    -------
    Interlacing

    Examples
    --------
    >>> y, x = np.mgrid[:64, :300]
    >>> scene = 128 + 60 * np.sin(x / 4 + y / 6) + 40 * np.cos(x / 9 - y / 5)
    >>> times = [scene[:, 2 * s : 2 * s + 200] for s in range(20)]  # 2 px a field
    >>> woven = [np.where(np.arange(64)[:, None] % 2 == 0, times[k], times[k + 1])
    ...          for k in range(0, 20, 2)]
    >>> found = detect_interlacing(woven)
    >>> found.interlaced, found.field_order, detect_interlacing(times[::2]).interlaced
    (True, 'top', False)
    """
    if stream is not None and not isinstance(stream, str):
        raise InvalidInputError(f"expected stream as a str, got {describe(stream)}")
    if isinstance(frames, str | bytes) or not isinstance(frames, Iterable):
        raise InvalidInputError(f"expected frames as an iterable of images, got {describe(frames)}")
    flag = None if stream in (None, "", "unknown") else stream
    counts = {"top": 0, "bottom": 0, "progressive": 0, "undetermined": 0}
    combing: list[float] = []
    window: list[np.ndarray] = []
    for i, f in enumerate(frames):
        y = _luma(f, f"frames[{i}]")
        if window and y.shape != window[-1].shape:
            raise InvalidInputError(
                f"expected frames of one size, frame {i} is {y.shape[1]}x{y.shape[0]} after "
                f"{window[-1].shape[1]}x{window[-1].shape[0]}"
            )
        window = (window + [y])[-3:]
        if len(window) == 3:
            counts[_idet(*window)] += 1
            combing.append(_combing(window[1]))
    measured = sum(counts.values())
    woven = counts["top"] + counts["bottom"]
    interlaced = woven >= 2 and woven > counts["progressive"]
    if interlaced:
        order: str | None = "top" if counts["top"] >= counts["bottom"] else "bottom"
    else:
        order = _STREAM_ORDERS.get(flag or "")
    return Interlacing(
        interlaced,
        order,
        measured,
        counts["top"],
        counts["bottom"],
        counts["progressive"],
        counts["undetermined"],
        float(np.median(combing)) if combing else float("nan"),
        flag,
    )


def _image(image: ArrayLike, name: str = "image") -> np.ndarray:
    a = np.asarray(image)
    if a.ndim not in (2, 3) or a.shape[0] < 2 or a.shape[1] < 1 or a.dtype.kind not in "uif":
        raise InvalidInputError(
            f"expected {name} as an (H, W) or (H, W, C) image of at least 2 rows, got {describe(a)}"
        )
    if a.dtype.kind == "f" and not np.all(np.isfinite(a)):
        raise InvalidInputError(f"expected {name} with finite values")
    return a


def _order(field_order: str) -> str:
    return check_option(field_order, FIELD_ORDERS, "field order")


def split_fields(image: ArrayLike, field_order: str = "top") -> tuple[np.ndarray, np.ndarray]:
    """Split an interlaced frame into its two fields, the first in time first.

    Parameters
    ----------
    image : array_like (H, W) or (H, W, C)
        An interlaced frame.
    field_order : {"top", "bottom"}
        The field first in time: ``"top"`` (rows 0, 2, 4, ...) or ``"bottom"`` (rows 1, 3, ...).

    Returns
    -------
    first, second : ndarray
        The fields at half height (rows ``0::2`` and ``1::2``), copies; use
        :func:`field_camera_matrix` for their cameras.

    Examples
    --------
    >>> frame = np.arange(12).reshape(4, 3)
    >>> [f.tolist() for f in split_fields(frame, "bottom")]
    [[[3, 4, 5], [9, 10, 11]], [[0, 1, 2], [6, 7, 8]]]
    """
    a = _image(image)
    top, bottom = a[0::2].copy(), a[1::2].copy()
    return (top, bottom) if _order(field_order) == "top" else (bottom, top)


def field_camera_matrix(K: ArrayLike, field: str) -> np.ndarray:
    """Return the camera matrix of one field of a frame whose camera matrix is ``K``.

    A field's row ``r`` is the frame's row ``2 r + p`` (``p`` 0 for ``"top"``, 1 for
    ``"bottom"``; pixel centres at integers), so ``fy``, the skew's row and ``cy`` become
    ``fy / 2``, ``0`` and ``(cy - p) / 2``: points project onto a field exactly where they
    project onto the frame's rows of that field.

    Parameters
    ----------
    K : array_like (3, 3)
        The frame's camera matrix (``K[2] == (0, 0, 1)``).
    field : {"top", "bottom"}
        Which field.

    Returns
    -------
    ndarray (3, 3)

    Examples
    --------
    >>> K = np.array([[800.0, 0, 359.5], [0, 820.0, 287.5], [0, 0, 1]])
    >>> field_camera_matrix(K, "bottom")[1].tolist()
    [0.0, 410.0, 143.25]
    """
    k = np.array(as_matrix(K, "K", (3, 3), batch=False), dtype=np.float64)
    if not np.allclose(k[2], (0.0, 0.0, 1.0)):
        raise InvalidInputError(f"expected K with last row (0, 0, 1), got {k[2].tolist()}")
    p = 0.0 if check_option(field, FIELD_ORDERS, "field") == "top" else 1.0
    k[1, 1] /= 2.0
    k[1, 2] = (k[1, 2] - p) / 2.0
    return k


def deinterlace(image: ArrayLike, method: str, field_order: str = "top") -> np.ndarray:
    """Deinterlace one frame at full size: ``"linear"`` or ``"blend"``.

    Parameters
    ----------
    image : array_like (H, W) or (H, W, C)
        An interlaced frame.
    method : {"linear", "blend"}
        ``"linear"``: the first field's rows kept, the other field's rows the mean of the rows
        above and below (the edge row copied): the first field's instant, the vertical
        resolution of one field. ``"blend"``: every row ``[1, 2, 1] / 4`` with its neighbours
        (edge rows repeated): the two instants mixed, no combing, motion doubled into a
        ghost.
    field_order : {"top", "bottom"}
        The field first in time (``"linear"`` keeps it).

    Returns
    -------
    ndarray
        The frame's shape and dtype (integers rounded).

    Examples
    --------
    >>> frame = np.array([[0], [100], [0], [100]], np.uint8)
    >>> deinterlace(frame, "linear")[:, 0].tolist(), deinterlace(frame, "blend")[:, 0].tolist()
    ([0, 0, 0, 0], [25, 50, 50, 75])
    """
    a = _image(image)
    how = check_option(method, ("linear", "blend"), "deinterlace method")
    order = _order(field_order)
    f = a.astype(np.float64)
    up = np.concatenate([f[:1], f[:-1]])  # row y - 1 (edge repeated)
    down = np.concatenate([f[1:], f[-1:]])  # row y + 1
    if how == "blend":
        out = (up + 2 * f + down) / 4
    else:
        h = f.shape[0]
        rows = np.arange(h).reshape((h,) + (1,) * (f.ndim - 1))
        both = np.where(rows == 0, down, np.where(rows == h - 1, up, (up + down) / 2))
        keep = 0 if order == "top" else 1
        out = np.where(rows % 2 == keep, f, both)
    if a.dtype.kind == "u":
        info = np.iinfo(a.dtype)
        return np.clip(np.round(out), info.min, info.max).astype(a.dtype)
    if a.dtype.kind == "i":
        return np.round(out).astype(a.dtype)
    return out.astype(a.dtype)
