"""Where keypoints may be in an endoscope's frames: its field of view, without the highlights.

An endoscope's video shows the scene through a round (or octagonal) aperture inside black
corners, often with burned-in text, and its light, which rides on the tip, paints specular
highlights that move with the camera instead of with the tissue. A keypoint on the edge of
the aperture, on the text or on a highlight stays put, or moves the wrong way, while the
camera moves: structure from motion takes such matches for the scene and its poses go wrong
or never start. These two functions say where keypoints may be;
:func:`imageform.geometry.reconstruct_sequence` takes them as ``masks``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from imageform._colormath import luma_601_matmul
from imageform._typing import ArrayLike
from imageform._validate import as_int, as_real, describe
from imageform.errors import InvalidInputError

__all__ = [
    "blurred_frames",
    "field_of_view_mask",
    "frame_sharpness",
    "highlight_mask",
    "still_mask",
]

#: At most this many frames, evenly spaced, enter the field of view's statistics.
_MAX_FRAMES = 64


def _unit(image: object, name: str) -> NDArray[np.float32]:
    """Return ``image`` as float32 in [0, 1]: (H, W) or (H, W, 3), the alpha dropped."""
    a = np.asarray(image)
    if a.ndim == 3 and a.shape[-1] in (3, 4):
        a = a[..., :3]
    elif a.ndim == 3 and a.shape[-1] == 1:
        a = a[..., 0]
    if (
        a.ndim not in (2, 3)
        or (a.ndim == 3 and a.shape[-1] != 3)
        or a.size == 0
        or (a.dtype.kind not in "uif")
    ):
        raise InvalidInputError(
            f"expected {name} as (H, W), (H, W, 3) or (H, W, 4) numbers, got {describe(image)}"
        )
    if a.dtype.kind in "ui":
        return a.astype(np.float32) / np.float32(np.iinfo(a.dtype).max)
    f = a.astype(np.float32)
    if not np.all(np.isfinite(f)):
        raise InvalidInputError(f"expected {name} without NaN or inf")
    return f / np.float32(255.0) if float(f.max()) > 1.0 else f


def _disc(radius: int) -> NDArray[np.uint8]:
    d = 2 * radius + 1
    yy, xx = np.mgrid[:d, :d] - radius
    return (xx**2 + yy**2 <= radius**2 + radius).astype(np.uint8)


def field_of_view_mask(
    images: Sequence[ArrayLike] | ArrayLike,
    *,
    dark: float = 0.1,
    margin: int = 8,
    overlays: bool = True,
    still: float = 0.004,
) -> NDArray[np.bool_]:
    r"""Return where an endoscope's frames see the scene: its aperture, without overlays.

    From the frames of one video (one camera, one aperture): the per-pixel median
    :math:`m(x)` of the grey frames (the mean of the colour channels) over up to 64 frames,
    evenly spaced. The aperture is the largest 8-connected region where
    :math:`m(x) > \text{dark} \cdot m_{99}`, :math:`m_{99}` the 99th percentile of
    :math:`m` (the black corners and borders are out), its holes filled (a dark lumen in the
    middle is scene). With ``overlays`` and three frames or more, the pixels that never
    change, :math:`\operatorname{std}_t I(x, t) < \text{still}` on the [0, 1] scale
    (burned-in text, an icon, a clock: what moves with the camera moves in the image),
    are taken out too, unless they are half the aperture or more (a camera that did not
    move: nothing to tell the overlays by); and so are the overlays :func:`still_mask` finds
    3 px or more inside the aperture (from 8 frames on: a caption compressed with the
    video changes by the codec's noise, more than ``still``). The region is then eroded by
    a disc of radius ``margin`` pixels: SIFT's descriptor of a keypoint near the edge sees
    the edge, which stands still while the tissue moves (Lowe 2004, IJCV 60(2), sec. 6.1:
    the descriptor window is 16 x 16 samples at the keypoint's scale).

    Parameters
    ----------
    images : sequence of array_like (H, W), (H, W, 3) or (H, W, 4), or one of them
        The frames (uint8, other integers over their type's range, or floats in [0, 1]).
        One frame gives the aperture alone.
    dark : float
        The border's level as a share of :math:`m_{99}`, in (0, 1).
    margin : int
        Pixels taken off the aperture's edge and around each overlay, >= 0.
    overlays : bool
        Take out the pixels that never change.
    still : float
        The temporal standard deviation (of [0, 1] grey) under which a pixel never changes;
        a video codec's noise on a fixed caption is a few thousandths.

    Returns
    -------
    ndarray of bool (H, W)
        True where keypoints may be.

    Raises
    ------
    InvalidInputError
        Frames of different sizes or not images, parameters out of range, or an aperture
        that the margin erodes away.

    References
    ----------
    D. G. Lowe, "Distinctive image features from scale-invariant keypoints", IJCV 60(2),
    2004. Endoscopic SLAM systems mask the same regions with a drawn image (e.g. NR-SLAM's
    ``data/endomapper/endoscopy_borders.png``, github.com/endomapper/NR-SLAM); this finds
    it from the frames.

    Examples
    --------
    >>> frame = np.zeros((60, 80), np.uint8)
    >>> yy, xx = np.mgrid[:60, :80]
    >>> frame[(xx - 40) ** 2 + (yy - 30) ** 2 < 25**2] = 120
    >>> m = field_of_view_mask([frame], margin=3)
    >>> bool(m[30, 40]), bool(m[30, 14]), bool(m[0, 0])
    (True, False, False)
    """
    from imageform._optional import require

    cv2 = require("cv2", what="field_of_view_mask")
    d = as_real(dark, "dark", positive=True, maximum=0.999)
    r = as_int(margin, "margin", minimum=0, maximum=10_000)
    st = as_real(still, "still", nonnegative=True, maximum=1.0)
    if not isinstance(overlays, bool | np.bool_):
        raise InvalidInputError(f"expected overlays as True or False, got {describe(overlays)}")
    if isinstance(images, list | tuple):
        frames: list[object] = list(images)
    elif hasattr(images, "__array__") and getattr(images, "ndim", 0) >= 2:
        arr = np.asarray(images)
        one = arr.ndim == 2 or (arr.ndim == 3 and arr.shape[-1] <= 4)
        frames = [arr] if one else list(arr)
    else:
        raise InvalidInputError(
            f"expected images as a list of frames or an array, got {describe(images)}"
        )
    if not frames:
        raise InvalidInputError("expected at least one frame, got none")
    pick = np.unique(np.linspace(0, len(frames) - 1, min(len(frames), _MAX_FRAMES)).round())
    greys = []
    for i in pick.astype(int).tolist():
        g = _unit(frames[i], f"images[{i}]")
        greys.append(g.mean(axis=2) if g.ndim == 3 else g)
    shapes = {g.shape for g in greys}
    if len(shapes) != 1:
        raise InvalidInputError(f"expected frames of one size, got {sorted(shapes)}")
    stack = np.stack(greys)
    med = np.median(stack, axis=0)
    top = float(np.percentile(med, 99))
    bright = (med > d * top).astype(np.uint8) if top > 0 else np.zeros(med.shape, np.uint8)
    n, labels, stats, _ = cv2.connectedComponentsWithStats(bright, connectivity=8)
    if n < 2:
        raise InvalidInputError("expected frames with a bright aperture, got black frames")
    big = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    inside = labels == big
    # holes: the parts of the outside that the image's border does not reach
    outside = (~inside).astype(np.uint8)
    h, w = outside.shape
    flood = np.pad(outside, 1, constant_values=1)
    cv2.floodFill(flood, np.zeros((h + 4, w + 4), np.uint8), (0, 0), 2)
    inside |= flood[1:-1, 1:-1] == 1
    keep = inside.copy()
    if overlays and stack.shape[0] >= 3:
        fixed = inside & (stack.std(axis=0) < st)
        if fixed.sum() < 0.5 * inside.sum():
            keep &= ~fixed
        # a caption compressed with the video changes by the codec's noise: still_mask's
        # edges that stand still, 3 px or more inside the aperture (its rim is out already)
        core = cv2.erode(inside.astype(np.uint8), _disc(3), borderValue=0) > 0
        keep &= ~(still_mask(frames, margin=0) & core)
    if r:
        # erode: a pixel stays when no pixel out of ``keep`` lies within the disc
        keep = cv2.erode(keep.astype(np.uint8), _disc(r), borderValue=0) > 0
    if not keep.any():
        raise InvalidInputError(
            f"the field of view is empty after a margin of {r} px: expected a smaller margin"
        )
    return keep


#: The fewest still edge pixels, all regions together, that make an overlay: a few regions
#: of 16 to 30 pixels stand still by chance where a texture is mirrored (the room's
#: facade at the camera's focus of expansion: 22 pixels in 8 frames of its walk at 320 x
#: 240), an overlay's text or logo holds hundreds (325 at the least in
#: benchmarks/results/still-mask-2026-12-03a.md's 96 runs).
_MIN_STILL = 64


def still_mask(
    images: Sequence[ArrayLike],
    *,
    still: float = 0.02,
    edge: float = 0.1,
    margin: int = 8,
    min_area: int = 16,
    min_frames: int = 8,
) -> NDArray[np.bool_]:
    r"""Return what stands still in the frames while the camera moves: overlays, a rim.

    Burned-in text (a timestamp, a patient's ID), an icon, an endoscope's aperture rim
    and its black corners stay at the same pixels in every frame; what the camera sees
    moves. A keypoint on them matches the same place in every other frame, and a frame of
    another scene carrying the same overlay matches the sequence there only: text's
    letters match along its lines, a translation along them that an essential matrix
    fits. From the grey frames :math:`I_t` (the mean of the colour channels, [0, 1]) over
    up to 64 frames, evenly spaced, a pixel is an overlay's when

    .. math::

        \operatorname{std}_t I(x, t) < \text{still} \quad \text{and} \quad
        \max_{N_3(x)} \bar I - \min_{N_3(x)} \bar I \ge \text{edge},

    it never changes and the mean frame :math:`\bar I` has an edge there (its 3 x 3
    morphological gradient): a flat region that stays flat (a wall, the sky, a black
    border's inside) holds no keypoint and is left alone, and a pixel of flat texture
    whose noise happens to stay under ``still`` has no edge. The overlay's regions (its
    pixels within 2 px of each other: a glyph's strokes, one pixel wide where the text's
    anti-aliased outline blends with the scene) with fewer than ``min_area`` pixels are
    dropped, and the rest grown by a disc of ``margin`` pixels: SIFT's descriptor of a
    keypoint beside the text sees the text (Lowe 2004, sec. 6.1).

    Nothing is returned when the camera did not move, so that nothing tells an overlay
    from the scene: when the temporal standard deviation on three quarters of the first
    frame's edges (its 3 x 3 range ``edge`` or more) is under twice ``still`` (the noise
    of a camera that stood still; an endoscope's black corners, flat, are no edges).
    Nothing either from fewer than ``min_frames`` frames: in a few frames of a repeated
    texture (a facade's windows) some pixels stay within ``still`` by chance (a walk of
    3 to 6 rendered frames: regions of 1 000 to 57 000 pixels at ``still`` 0.02, none
    from 8 frames on), and nothing when the regions hold fewer than 64 such pixels in all
    (a texture mirrored at the focus of expansion of a camera moving forward keeps a few
    pixels still by chance; a caption or a logo has hundreds).

    Parameters
    ----------
    images : sequence of array_like (H, W), (H, W, 3) or (H, W, 4)
        The frames of one video (uint8, other integers over their type's range, or floats
        in [0, 1]), all of one size.
    still : float
        The temporal standard deviation (of [0, 1] grey) under which a pixel never
        changes: a caption compressed with the video (JPEG at quality 85) keeps most of
        its pixels under 0.02.
    edge : float
        The least 3 x 3 range of the mean frame at an overlay's pixel, in (0, 1].
    margin : int
        Pixels added around the overlay, >= 0.
    min_area : int
        The fewest pixels of one overlay region, >= 1.
    min_frames : int
        The fewest frames (of the up to 64 taken) that can tell an overlay, 3 to 64.

    Returns
    -------
    ndarray of bool (H, W)
        True on the overlays (where keypoints should not be).

    Raises
    ------
    InvalidInputError
        Frames of different sizes or not images, parameters out of range.

    See Also
    --------
    field_of_view_mask : the aperture of an endoscope's frames, its overlays taken out.

    References
    ----------
    D. G. Lowe, "Distinctive image features from scale-invariant keypoints", IJCV 60(2),
    2004.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> frames = [rng.integers(0, 256, (40, 60), dtype=np.uint8) for _ in range(8)]
    >>> for f in frames:
    ...     f[5:15, 5:25] = 0
    ...     f[8:12, 8:22] = 255   # a caption: the same white bar on black in every frame
    >>> m = still_mask(frames, margin=2)
    >>> bool(m[10, 15]), bool(m[30, 45])
    (True, False)
    """
    from imageform._optional import require

    cv2 = require("cv2", what="still_mask")
    st = as_real(still, "still", nonnegative=True, maximum=1.0)
    e = as_real(edge, "edge", positive=True, maximum=1.0)
    r = as_int(margin, "margin", minimum=0, maximum=10_000)
    a_min = as_int(min_area, "min_area", minimum=1, maximum=10**9)
    n_min = as_int(min_frames, "min_frames", minimum=3, maximum=_MAX_FRAMES)
    if not isinstance(images, list | tuple) and not (
        hasattr(images, "__array__") and getattr(images, "ndim", 0) >= 3
    ):
        raise InvalidInputError(
            f"expected images as a list of frames or an array of them, got {describe(images)}"
        )
    frames = list(images)
    if not frames:
        raise InvalidInputError("expected at least one frame, got none")
    pick = np.unique(np.linspace(0, len(frames) - 1, min(len(frames), _MAX_FRAMES)).round())
    total: NDArray[np.float64] | None = None
    total2: NDArray[np.float64] | None = None
    first: NDArray[np.float32] | None = None
    for i in pick.astype(int).tolist():
        g = _unit(frames[i], f"images[{i}]")
        g = g.mean(axis=2) if g.ndim == 3 else g
        g64 = g.astype(np.float64)
        if total is None or total2 is None:
            total, total2, first = g64.copy(), g64 * g64, g
        elif g64.shape != total.shape:
            raise InvalidInputError(
                f"expected frames of one size, got {total.shape} and {g64.shape} (images[{i}])"
            )
        else:
            total += g64
            total2 += g64 * g64
    assert total is not None and total2 is not None
    out = np.zeros(total.shape, bool)
    m = pick.size
    if m < n_min:
        return out
    mean = total / m
    var = np.maximum(total2 / m - mean * mean, 0.0) * (m / (m - 1))
    sd = np.sqrt(var)
    fixed = sd < st
    box = np.ones((3, 3), np.uint8)

    def gradient(a: NDArray[np.floating]) -> NDArray[np.float32]:
        a32 = np.ascontiguousarray(a, np.float32)
        return np.asarray(cv2.dilate(a32, box) - cv2.erode(a32, box))

    # the camera moved when a quarter of the first frame's edges or more change by twice
    # ``still`` or more (an aperture's rim and an overlay may be most of the edges of
    # smooth tissue); a camera that stood still changes them by its noise alone
    edges = gradient(first) >= e  # type: ignore[arg-type]
    if not edges.any():
        return out
    if float(np.percentile(sd[edges], 75)) < 2.0 * st:
        return out
    grad = gradient(mean)
    cand = fixed & (grad >= e)
    if not cand.any():
        return out
    # regions: the pixels within 2 px of each other (a glyph's strokes, broken where the
    # text's anti-aliased outline blends with the scene), each with its pixels counted
    near = cv2.dilate(cand.astype(np.uint8), _disc(2))
    _, labels = cv2.connectedComponents(near, connectivity=8)
    area = np.bincount(labels[cand], minlength=int(labels.max()) + 1)
    big = np.flatnonzero(area >= a_min)
    if big.size == 0 or int(area[big].sum()) < _MIN_STILL:
        return out
    out = cand & np.isin(labels, big)
    if r:
        out = cv2.dilate(out.astype(np.uint8), _disc(r)) > 0
    return np.asarray(out, bool)


def highlight_mask(
    image: ArrayLike,
    *,
    value: float = 0.9,
    saturation: float = 0.3,
    grow: int = 4,
) -> NDArray[np.bool_]:
    r"""Return the specular highlights of a frame: bright, nearly white pixels, grown.

    A highlight is where the endoscope's light is mirrored by wet tissue: the brightest
    channel is near full scale and the colour nearly white,

    .. math::

        V = \max(R, G, B) \ge \text{value}, \qquad
        S = \frac{\max(R, G, B) - \min(R, G, B)}{\max(R, G, B)} \le \text{saturation},

    (HSV's value and saturation on the [0, 1] scale; a grey frame: :math:`V \ge` value),
    then grown by a disc of ``grow`` pixels, the halo around the saturated core. Bright
    tissue saturates one channel (red) but keeps its colour, so it stays. The highlights
    move with the light, not with the tissue: a keypoint on one matches the same highlight
    in the next frame, a match that no rigid scene explains.

    Parameters
    ----------
    image : array_like (H, W), (H, W, 3) or (H, W, 4)
        One frame: uint8, other integers over their type's range, or floats in [0, 1].
    value : float
        The least brightness of a highlight, in (0, 1].
    saturation : float
        The most saturation of a highlight, in [0, 1].
    grow : int
        Pixels added around each highlight, >= 0.

    Returns
    -------
    ndarray of bool (H, W)
        True on the highlights (where keypoints should not be).

    References
    ----------
    M. Arnold, A. Ghosh, S. Ameling, G. Lacey, "Automatic segmentation and inpainting of
    specular highlights for endoscopic imaging", EURASIP J. Image Video Process. 2010,
    814319 (thresholds on brightness and saturation, then dilation).

    Examples
    --------
    >>> frame = np.zeros((20, 20, 3), np.uint8)
    >>> frame[:] = (200, 90, 70)        # tissue
    >>> frame[8:11, 8:11] = 255         # a highlight
    >>> m = highlight_mask(frame, grow=1)
    >>> int(m.sum()), bool(m[0, 0])
    (25, False)
    """
    from imageform._optional import require

    cv2 = require("cv2", what="highlight_mask")
    v = as_real(value, "value", positive=True, maximum=1.0)
    s = as_real(saturation, "saturation", nonnegative=True, maximum=1.0)
    g = as_int(grow, "grow", minimum=0, maximum=10_000)
    a = _unit(image, "image")
    if a.ndim == 2:
        spec = a >= v
    else:
        hi = a.max(axis=2)
        lo = a.min(axis=2)
        with np.errstate(invalid="ignore", divide="ignore"):
            sat = np.where(hi > 0, (hi - lo) / hi, 0.0)
        spec = (hi >= v) & (sat <= s)
    if g and spec.any():
        spec = cv2.dilate(spec.astype(np.uint8), _disc(g)) > 0
    return spec


def frame_sharpness(image: ArrayLike, mask: ArrayLike | None = None) -> float:
    r"""Return a frame's sharpness: the variance of its Laplacian inside ``mask``.

    The grey image :math:`g` (BT.601 weights, [0, 1]) and its 3 x 3 Laplacian
    :math:`\nabla^2 g` (OpenCV's ``Laplacian``, ``ksize=1``: the 4-neighbour kernel);
    the variance of :math:`\nabla^2 g` over the pixels of ``mask`` shrunk by 2 px (the
    Laplacian of the mask's edge, e.g. an endoscope's aperture, is no texture). Blur
    removes the high frequencies the Laplacian keeps: a blurred frame's variance drops
    (Pech-Pacheco et al. 2000, "Diatom autofocusing in brightfield microscopy: a
    comparative study", ICPR, the variance of the Laplacian as a focus measure).

    Parameters
    ----------
    image : array_like (H, W), (H, W, 3) or (H, W, 4)
        One frame: uint8, other integers over their type's range, or floats in [0, 1].
    mask : array_like (H, W), optional
        Where the scene is (nonzero), e.g. :func:`field_of_view_mask`; None: everywhere.

    Returns
    -------
    float
        The variance (grey levels in [0, 1]); 0 when the mask leaves no pixel.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> frame = rng.random((64, 64))
    >>> frame_sharpness(frame) > 10 * frame_sharpness(np.full((64, 64), 0.5) + 0.0)
    True
    """
    return _sharpness(image, mask, "image")


def _sharpness(image: ArrayLike, mask: ArrayLike | None, name: str) -> float:
    """Return :func:`frame_sharpness` of ``image``, its errors naming it ``name``."""
    from imageform._optional import require

    cv2 = require("cv2", what="frame_sharpness")
    a = _unit(image, name)
    g = a if a.ndim == 2 else luma_601_matmul(np, a, np.float32)  # Rec. 601, float32 weights
    lap = cv2.Laplacian(np.ascontiguousarray(g, np.float32), cv2.CV_32F, ksize=1)
    if mask is None:
        inside = np.ones(g.shape, bool)
        inside[:1], inside[-1:], inside[:, :1], inside[:, -1:] = False, False, False, False
    else:
        m = np.asarray(mask)
        if m.shape != g.shape:
            raise InvalidInputError(
                f"expected mask of the frame's size {g.shape[1]} x {g.shape[0]} px, "
                f"got {describe(mask)}"
            )
        inside = cv2.erode((m > 0).astype(np.uint8), _disc(2), borderValue=0) > 0
    v = lap[inside].astype(np.float64)
    return float(v.var()) if v.size else 0.0


def blurred_frames(
    images: Sequence[ArrayLike],
    mask: ArrayLike | None = None,
    *,
    window: int = 3,
    ratio: float = 0.5,
) -> NDArray[np.bool_]:
    r"""Find the blurred frames of a video: sharpness well below their neighbours'.

    Each frame's :func:`frame_sharpness` :math:`s_i` is compared with the median
    :math:`\tilde s_i` of the frames within ``window`` of it (itself excluded): frame
    :math:`i` is blurred when :math:`s_i < \text{ratio}\; \tilde s_i`. Relative to the
    neighbours, because the sharpness of a video's frames follows what they show (the
    tissue's texture, the distance, the light), and only a drop from one frame to the next
    is motion blur or a defocus.

    Parameters
    ----------
    images : sequence of array_like
        The frames, in order, all of one size.
    mask : array_like (H, W), optional
        Where the scene is (:func:`field_of_view_mask`); None: everywhere.
    window : int
        Neighbours on each side, >= 1.
    ratio : float
        The share of the neighbours' median below which a frame is blurred, in (0, 1).

    Returns
    -------
    ndarray of bool (n,)
        True for the blurred frames (none when the video has fewer than 3 frames).
    """
    w = as_int(window, "window", minimum=1, maximum=10_000)
    r = as_real(ratio, "ratio", positive=True, maximum=1.0)
    if r >= 1.0:
        raise InvalidInputError(f"expected ratio in (0, 1), got {r:g}")
    if isinstance(images, (str, bytes)) or not (
        isinstance(images, Sequence) or (isinstance(images, np.ndarray) and images.ndim >= 3)
    ):
        raise InvalidInputError(f"expected images as a sequence of frames, got {describe(images)}")
    frames = list(images)
    s = np.array([_sharpness(f, mask, f"images[{i}]") for i, f in enumerate(frames)], np.float64)
    n = s.size
    out = np.zeros(n, bool)
    if n < 3:
        return out
    for i in range(n):
        near = np.r_[s[max(0, i - w) : i], s[i + 1 : i + 1 + w]]
        out[i] = bool(s[i] < r * float(np.median(near)))
    return out
