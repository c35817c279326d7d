"""ArUco square fiducial markers: the dictionaries, marker images, detection and decoding.

An ArUco marker is a black square whose inner ``s x s`` cells carry a binary code (white =
1), surrounded by a black border one cell wide (Garrido-Jurado et al., 2014). A dictionary
is a set of codes chosen far apart in Hamming distance under the four rotations, so a
marker's identity and orientation are read from its bits, and up to the dictionary's
correction capacity of misread bits are corrected.

Detection (the pipeline of Garrido-Jurado et al. and of OpenCV's ``ArucoDetector``, written
here from the paper's description): local-mean adaptive thresholding at a few window sizes
→ dark connected components (4-connectivity) → a quadrilateral per component (convex hull
reduced to its four extreme vertices, accepted when the quad covers the hull) → sub-pixel
sides (a line fitted to the component's boundary pixels along each side, corners where the
lines meet) → the cells sampled through the quad's homography → Otsu's threshold on the
cell means → border check → dictionary lookup over the four rotations (Hamming distance).

The dictionaries are OpenCV's predefined ones (``DICT_4X4_1000`` ... ``DICT_7X7_1000`` and
``DICT_ARUCO_ORIGINAL``; the ``_50``, ``_100`` and ``_250`` variants are their prefixes),
shipped as bit tables in ``geometry/data/aruco_dictionaries.npz`` (source: OpenCV 5.0's
``objdetect/aruco`` predefined dictionaries, Apache-2.0, read with
``cv2.aruco.Dictionary.getBitsFromByteList``), so markers printed for OpenCV are read here.

Conventions: pixel centres at integer ``(u, v)``, the top-left pixel's centre at (0, 0);
a marker's corners in OpenCV's order: its top-left, top-right, bottom-right, bottom-left as
printed (clockwise on screen for a marker seen from the front).

References
----------
S. Garrido-Jurado, R. Muñoz-Salinas, F. J. Madrid-Cuevas, M. J. Marín-Jiménez, "Automatic
generation and detection of highly reliable fiducial markers under occlusion", Pattern
Recognition 47(6):2280-2292, 2014.
"""

from __future__ import annotations

import contextlib
import math
import threading
import weakref
from collections.abc import Iterator
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources
from typing import Any

import numpy as np
from numpy.typing import NDArray

from imageform._colormath import luma_601_matmul
from imageform._typing import ArrayLike
from imageform._validate import as_int, as_real, describe, format_shape
from imageform.errors import InvalidInputError, UnknownOptionError

__all__ = [
    "ARUCO_DICTIONARIES",
    "ArucoDictionary",
    "ArucoMarkers",
    "aruco_dictionary",
    "aruco_marker_image",
    "detect_aruco_markers",
    "identify_aruco_dictionary",
]

#: Dictionary names: ``"4x4_50"`` ... ``"7x7_1000"`` (OpenCV's ``DICT_4X4_50`` ...) and
#: ``"aruco_original"`` (``DICT_ARUCO_ORIGINAL``, 1024 markers of 5 x 5 bits).
ARUCO_DICTIONARIES: tuple[str, ...] = (
    *(f"{s}x{s}_{n}" for s in (4, 5, 6, 7) for n in (50, 100, 250, 1000)),
    "aruco_original",
)

#: OpenCV's maxCorrectionBits of each predefined dictionary (bits a marker may differ from its
#: code and still be read), as ``cv2.aruco.getPredefinedDictionary(...).maxCorrectionBits``.
_CORRECTION_BITS = {
    4: (1, 1, 1, 0),
    5: (3, 3, 2, 2),
    6: (6, 5, 5, 4),
    7: (9, 8, 8, 6),
}
_COUNTS = (50, 100, 250, 1000)

#: Largest image the detector takes (pixels), so a mistaken array cannot run for hours.
_MAX_PIXELS = 100_000_000


@dataclass(frozen=True)
class ArucoDictionary:
    """A marker dictionary: ``codes[i]`` is marker ``i``'s ``s x s`` bits (1 = white).

    ``max_correction_bits``: how many bits may be misread and still be corrected to the
    nearest code (OpenCV's value for its predefined dictionaries).
    """

    name: str
    marker_size: int
    codes: NDArray[np.uint8] = field(repr=False)
    max_correction_bits: int

    def __post_init__(self) -> None:
        """Check the name, the marker size and the codes' shape and bits."""
        if not isinstance(self.name, str):
            raise InvalidInputError(f"expected name as a str, got {describe(self.name)}")
        s = as_int(self.marker_size, "marker_size", minimum=2, maximum=16)
        codes = self.codes
        if not isinstance(codes, np.ndarray) or codes.ndim != 3 or codes.shape[1:] != (s, s):
            raise InvalidInputError(
                f"expected codes as an (n, {s}, {s}) array of 0/1, got {describe(codes)}"
            )
        if (
            codes.shape[0] < 1
            or codes.dtype.kind not in "uib"
            or np.any((codes != 0) & (codes != 1))
        ):
            raise InvalidInputError(
                f"expected codes of 0 and 1 (at least one), got {describe(codes)}"
            )
        corr = as_int(self.max_correction_bits, "max_correction_bits", minimum=0, maximum=s * s)
        object.__setattr__(self, "marker_size", s)
        object.__setattr__(self, "max_correction_bits", corr)
        frozen = np.array(codes, dtype=np.uint8)
        frozen.setflags(write=False)
        object.__setattr__(self, "codes", frozen)

    @property
    def size(self) -> int:
        """How many markers the dictionary holds."""
        return int(self.codes.shape[0])


@lru_cache(maxsize=1)
def _tables() -> dict[str, NDArray[np.uint8]]:
    ref = resources.files("imageform.geometry").joinpath("data", "aruco_dictionaries.npz")
    with ref.open("rb") as fh, np.load(fh) as npz:
        return {k: npz[k] for k in npz.files}


def aruco_dictionary(name: str | ArucoDictionary = "6x6_250") -> ArucoDictionary:
    """Return the predefined dictionary ``name`` (one of :data:`ARUCO_DICTIONARIES`).

    Parameters
    ----------
    name : str or ArucoDictionary
        ``"4x4_50"`` ... ``"7x7_1000"`` or ``"aruco_original"`` (case-insensitive; OpenCV's
        spelling ``"DICT_6X6_250"`` is accepted too). A dictionary is returned as it is.

    Returns
    -------
    ArucoDictionary

    Raises
    ------
    UnknownOptionError
        Not a predefined dictionary.

    Examples
    --------
    >>> d = aruco_dictionary("4x4_50")
    >>> d.size, d.marker_size, d.max_correction_bits
    (50, 4, 1)
    >>> d.codes[0].astype(int).tolist()
    [[1, 0, 1, 1], [0, 1, 0, 1], [0, 0, 1, 1], [0, 0, 1, 0]]
    """
    if isinstance(name, ArucoDictionary):
        return name
    if not isinstance(name, str):
        raise TypeError(f"expected dictionary as a name such as '6x6_250', got {describe(name)}")
    key = name.strip().lower().removeprefix("dict_")
    if key not in ARUCO_DICTIONARIES:
        shown = name if len(name) <= 40 else name[:40] + "..."
        raise UnknownOptionError(
            f"unknown ArUco dictionary name {shown!r}; expected 4x4_50 ... 7x7_1000 "
            "(sizes 4-7, counts 50/100/250/1000) or aruco_original"
        )
    return _named(key)


@lru_cache(maxsize=32)
def _named(key: str) -> ArucoDictionary:
    """Make the predefined dictionary ``key`` (once: it is immutable)."""
    tables = _tables()
    if key == "aruco_original":
        s, n, corr = 5, 1024, 1
        packed = tables["aruco_original"]
    else:
        s, n = int(key[0]), int(key.split("_")[1])
        corr = _CORRECTION_BITS[s][_COUNTS.index(n)]
        packed = tables[f"{s}x{s}"][:n]
    codes = np.unpackbits(packed, axis=1, count=s * s).reshape(n, s, s)
    return ArucoDictionary(key, s, codes, corr)


def aruco_marker_image(
    marker_id: int,
    dictionary: str | ArucoDictionary = "6x6_250",
    *,
    size_px: int = 200,
    border_bits: int = 1,
) -> NDArray[np.uint8]:
    """Draw the printable image of marker ``marker_id`` (uint8, 0 black, 255 white).

    Equal to OpenCV's ``cv2.aruco.generateImageMarker(dictionary, id, size_px, borderBits)``
    (tested): ``s + 2 border_bits`` cells per side, each cell a block of pixels (the
    nearest cell of each pixel centre when ``size_px`` is not a multiple of the cells).

    Parameters
    ----------
    marker_id : int
        Index in the dictionary.
    dictionary : str or ArucoDictionary
        See :func:`aruco_dictionary`.
    size_px : int, keyword-only
        Side of the image in pixels (at least the number of cells).
    border_bits : int, keyword-only
        Width of the black border in cells (1 in OpenCV's detector).

    Returns
    -------
    ndarray, shape (size_px, size_px), uint8

    Examples
    --------
    >>> img = aruco_marker_image(0, "4x4_50", size_px=6)
    >>> (img // 255).tolist()[1]
    [0, 1, 0, 1, 1, 0]
    """
    d = aruco_dictionary(dictionary)
    mid = as_int(marker_id, "marker_id", minimum=0, maximum=d.size - 1)
    border = as_int(border_bits, "border_bits", minimum=1, maximum=16)
    cells = d.marker_size + 2 * border
    size = as_int(size_px, "size_px", minimum=cells, maximum=20000)
    grid = np.zeros((cells, cells), dtype=np.uint8)
    grid[border:-border, border:-border] = d.codes[mid] * 255
    # OpenCV resizes the cell grid with INTER_NEAREST: source index floor(i * cells / size)
    idx = (np.arange(size) * cells) // size
    return grid[np.ix_(idx, idx)]


@dataclass(frozen=True)
class ArucoMarkers:
    """Markers found in an image.

    ``ids`` (n,) int64; ``corners`` (n, 4, 2) float64: each marker's top-left, top-right,
    bottom-right and bottom-left corner (as printed) in pixels; ``hamming`` (n,) int64: the
    bits corrected; ``dictionary``: the dictionary's name.
    """

    ids: NDArray[np.int64]
    corners: NDArray[np.float64]
    hamming: NDArray[np.int64]
    dictionary: str

    def __len__(self) -> int:
        """How many markers were found."""
        return int(self.ids.shape[0])

    @property
    def centers(self) -> NDArray[np.float64]:
        """The markers' centres (n, 2): where the diagonals of the corners cross."""
        if len(self) == 0:
            return np.zeros((0, 2))
        return np.stack([_diagonal_cross(c) for c in self.corners])


def _diagonal_cross(q: NDArray[np.float64]) -> NDArray[np.float64]:
    a = np.cross(np.append(q[0], 1.0), np.append(q[2], 1.0))
    b = np.cross(np.append(q[1], 1.0), np.append(q[3], 1.0))
    p = np.cross(a, b)
    if abs(p[2]) < 1e-12:
        return np.asarray(q.mean(axis=0))
    return np.asarray(p[:2] / p[2])


#: The grey images :func:`_gray01` made (new arrays, never the caller's), so that passing one
#: on (``detect_charuco`` to ``detect_aruco_markers``) is not converted and checked again.
_MADE: weakref.WeakValueDictionary[int, NDArray[np.float64]] = weakref.WeakValueDictionary()


def _gray01(image: object, *, scratch: bool = False) -> NDArray[np.float64]:
    """``image`` as grey values in [0, 1] (float64; an image this function made, as it is).

    ``scratch``: a uint8 grey image of up to ``_MAX_KEPT`` pixels is converted into this
    thread's work buffer (valid until the next such call in the thread: for a detection
    that does not hand the grey image back), sparing a fresh array's page faults; a larger
    one into the buffer of the tracker whose frame this is (:func:`_working`), when one is.
    """
    if isinstance(image, np.ndarray) and _MADE.get(id(image)) is image:
        return image
    area = getattr(_WORK, "area", None)
    if (
        scratch
        and isinstance(image, np.ndarray)
        and image.dtype == np.uint8
        and image.ndim == 2
        and min(image.shape) >= 8
        and (image.size <= _MAX_KEPT or (area is not None and image.size <= _MAX_PIXELS))
    ):
        if image.size > _MAX_KEPT and area is not None:
            g = area.take("grey", image.size, np.float64).reshape(image.shape)
        else:
            buf = getattr(_WORK, "grey", None)
            if buf is None or buf.size < image.size:
                buf = np.empty(max(image.size, 1 << 20))
                _WORK.grey = buf
            g = buf[: image.size].reshape(image.shape)
        from imageform._backend import use_numba

        if use_numba(image):
            from imageform._kernels.aruco import unit_grey

            unit_grey(np.ascontiguousarray(image), g)  # the same values as true_divide
        else:
            np.true_divide(image, 255.0, out=g)  # as _gray01_checked: the same values
        _MADE[id(g)] = g
        return g
    g = _gray01_checked(image)
    if g is not image:
        _MADE[id(g)] = g
    return g


def _luma_u8_numpy(rgb: NDArray[np.uint8]) -> NDArray[np.uint8]:
    """:func:`imageform._kernels.aruco.luma_u8`'s NumPy twin: the same codes."""
    r, g, b = (rgb[..., k].astype(np.int32) for k in range(3))
    return np.asarray((r * 299 + g * 587 + b * 114 + 500) // 1000, dtype=np.uint8)


def _grey_u8(rgb: NDArray[np.uint8]) -> NDArray[np.uint8]:
    """Return an RGB(A) uint8 frame's grey uint8: the detector's luma weights, rounded.

    Written into the buffer of the tracker whose frame this is (:func:`_working`; valid
    for the frame) when it is larger than ``_MAX_KEPT`` pixels, a new array otherwise.
    """
    from imageform._backend import use_numba

    c = np.ascontiguousarray(rgb[..., :3])
    if not use_numba(c):
        return _luma_u8_numpy(c)
    from imageform._kernels.aruco import luma_u8_into

    area = getattr(_WORK, "area", None)
    size = c.shape[0] * c.shape[1]
    if area is not None and size > _MAX_KEPT:
        out = area.take("grey8", size, np.uint8).reshape(c.shape[:2])
    else:
        out = np.empty(c.shape[:2], dtype=np.uint8)
    luma_u8_into(c, out)
    return out


def _grey_source(image: object) -> object:
    """Return a uint8 RGB(A) image as its grey uint8 (:func:`_grey_u8`), once; else ``image``.

    The detector then reads a colour frame as it reads a grey one: its threshold in integers
    on the codes (``dark_components_u8``), the float grey in the reused buffers (a 12 Mpx
    frame's three float64 planes, 300 MB, are never made). The grey is rounded to whole
    codes (as OpenCV's ``cvtColor`` makes it): half a code at most from the float luma.
    """
    if (
        isinstance(image, np.ndarray)
        and image.dtype == np.uint8
        and image.ndim == 3
        and image.shape[2] in (3, 4)
        and min(image.shape[:2]) >= 8
        and image.shape[0] * image.shape[1] <= _MAX_PIXELS
    ):
        return _grey_u8(image)
    return image


def _gray01_checked(image: object) -> NDArray[np.float64]:
    arr = np.asarray(image) if not isinstance(image, np.ndarray) else image
    if arr.dtype.kind not in "uif" or arr.dtype.kind == "c":
        raise InvalidInputError(f"expected image as a real array, got {describe(image)}")
    if arr.ndim == 3 and arr.shape[2] in (3, 4):
        arr = arr[..., :3]
    elif arr.ndim == 3 and arr.shape[2] == 1:
        arr = arr[..., 0]
    if arr.ndim not in (2, 3) or min(arr.shape[:2]) < 8:
        raise InvalidInputError(
            "expected image of shape (H, W) or (H, W, 3) with H, W >= 8, got "
            f"{format_shape(arr.shape)}"
        )
    if arr.shape[0] * arr.shape[1] > _MAX_PIXELS:
        raise InvalidInputError(
            f"image has {arr.shape[0] * arr.shape[1]} pixels, more than {_MAX_PIXELS}"
        )
    if arr.dtype.kind == "u" and arr.ndim == 2:
        # integers need no finiteness check; one pass to [0, 1]
        return np.asarray(np.true_divide(arr, float(np.iinfo(arr.dtype).max), dtype=np.float64))
    g = np.asarray(arr, dtype=np.float64)
    lo, hi = float(np.min(g)), float(np.max(g))  # NaN or inf anywhere shows in one of them
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise InvalidInputError("image contains NaN or inf")
    if g.ndim == 3:
        g = luma_601_matmul(np, g)  # Rec. 601 luma
        lo, hi = float(np.min(g)), float(np.max(g))
    if arr.dtype.kind == "u":
        g = g / float(np.iinfo(arr.dtype).max)
    elif arr.dtype.kind == "i" or hi > 1.0:
        g = (g - lo) / (hi - lo) if hi > lo else np.zeros_like(g)
    return g


def _homography(src: NDArray[np.float64], dst: NDArray[np.float64]) -> NDArray[np.float64]:
    """Estimate the 3x3 homography mapping 4 (or more) ``src`` points to ``dst`` (DLT, SVD)."""
    src, dst = np.asarray(src, dtype=np.float64), np.asarray(dst, dtype=np.float64)
    x, y = src[:, 0], src[:, 1]
    u, v = -dst[:, 0], -dst[:, 1]
    one, zero = np.ones_like(x), np.zeros_like(x)
    # the two rows of each point side by side, then split: (x y 1 0 0 0 -ux -uy -u) and
    # (0 0 0 x y 1 -vx -vy -v), point by point
    cols = (x, y, one, zero, zero, zero, u * x, u * y, u, zero, zero, zero, x, y, one)
    rows = np.array((*cols, v * x, v * y, v)).T.reshape(-1, 9)
    # the thin SVD has the same V when there are at least 9 rows (5 points or more)
    _, _, vt = np.linalg.svd(rows, full_matrices=len(rows) < 9)
    h = vt[-1].reshape(3, 3)
    return np.asarray(h / h[2, 2]) if abs(h[2, 2]) > 1e-15 else np.asarray(h)


def _apply_h(h: NDArray[np.float64], pts: NDArray[np.float64]) -> NDArray[np.float64]:
    x, y = pts[:, 0], pts[:, 1]
    w = h[2, 0] * x + h[2, 1] * y + h[2, 2]
    out = np.empty((len(pts), 2))
    out[:, 0] = (h[0, 0] * x + h[0, 1] * y + h[0, 2]) / w
    out[:, 1] = (h[1, 0] * x + h[1, 1] * y + h[1, 2]) / w
    return out


def _bilinear(g: NDArray[np.float64], uv: NDArray[np.float64]) -> NDArray[np.float64]:
    h, w = g.shape
    u = np.clip(uv[:, 0], 0.0, w - 1.0)
    v = np.clip(uv[:, 1], 0.0, h - 1.0)
    u0 = np.minimum(np.floor(u).astype(np.int64), w - 2)
    v0 = np.minimum(np.floor(v).astype(np.int64), h - 2)
    fu, fv = u - u0, v - v0
    return np.asarray(
        (1 - fv) * ((1 - fu) * g[v0, u0] + fu * g[v0, u0 + 1])
        + fv * ((1 - fu) * g[v0 + 1, u0] + fu * g[v0 + 1, u0 + 1])
    )


def _quad(pts: NDArray[np.float64], area: float) -> NDArray[np.float64] | None:
    """Find four extreme boundary points of a component, clockwise on screen.

    None unless the quad through them has the component's area (a quadrilateral blob, not an
    L or a disc).
    """
    c = pts.mean(axis=0)
    i0 = int(np.argmax(np.sum((pts - c) ** 2, axis=1)))
    i2 = int(np.argmax(np.sum((pts - pts[i0]) ** 2, axis=1)))
    d = pts[i2] - pts[i0]
    side = d[0] * (pts[:, 1] - pts[i0, 1]) - d[1] * (pts[:, 0] - pts[i0, 0])
    i1, i3 = int(np.argmax(side)), int(np.argmin(side))
    if side[i1] <= 0 or side[i3] >= 0:
        return None
    quad = pts[[i0, i1, i2, i3]]
    x, y = quad[:, 0], quad[:, 1]
    xn, yn = x[[1, 2, 3, 0]], y[[1, 2, 3, 0]]
    signed = 0.5 * float(np.sum(x * yn - y * xn))
    perimeter = float(np.sum(np.hypot(xn - x, yn - y)))
    # the quad runs through boundary pixel centres: about half a pixel inside the blob
    expected = area - 0.5 * perimeter
    if abs(abs(signed) - expected) > 0.12 * area:
        return None
    if signed < 0:  # clockwise on screen (v down) is a positive signed area in (u, v)
        quad = quad[::-1]
    return np.asarray(quad, dtype=np.float64)


def _line_normal(centred: NDArray[np.float64]) -> NDArray[np.float64]:
    """Return the unit normal of the total-least-squares line through centred points.

    It is the eigenvector of the 2x2 scatter matrix with the smaller eigenvalue, in closed
    form.
    """
    sxx = float(centred[:, 0] @ centred[:, 0])
    syy = float(centred[:, 1] @ centred[:, 1])
    sxy = float(centred[:, 0] @ centred[:, 1])
    theta = 0.5 * math.atan2(2.0 * sxy, sxx - syy)  # direction of the line
    return np.array([-math.sin(theta), math.cos(theta)])


def _refine_sides(
    quad: NDArray[np.float64], boundary: NDArray[np.float64]
) -> NDArray[np.float64] | None:
    """Find the corners where the four sides meet; None when a side has too few pixels.

    Each side is a line fitted to the component's boundary pixels along it and moved half a
    pixel outwards (the boundary pixels' centres lie half a pixel inside the dark region's
    edge).
    """
    center = quad.mean(axis=0)
    lines = []
    for k in range(4):
        a, b = quad[k], quad[(k + 1) % 4]
        d = b - a
        length = float(np.hypot(*d))
        if length < 1e-9:
            return None
        t = ((boundary - a) @ d) / length**2
        n = np.array([-d[1], d[0]]) / length
        dist = np.abs((boundary - a) @ n)
        sel = (t > 0.12) & (t < 0.88) & (dist < max(1.5, 0.06 * length))
        p = boundary[sel]
        if len(p) < 4:
            return None
        m = p.mean(axis=0)
        normal = _line_normal(p - m)
        if float(normal @ (m - center)) < 0:
            normal = -normal  # pointing out of the quad
        lines.append(np.array([normal[0], normal[1], -float(normal @ m) - 0.5]))
    out = np.empty_like(quad)
    for k in range(4):
        a1, b1, c1 = lines[(k - 1) % 4]
        a2, b2, c2 = lines[k]
        det = a1 * b2 - a2 * b1
        if abs(det) < 1e-12:
            return None
        out[k] = ((b1 * c2 - b2 * c1) / det, (c1 * a2 - c2 * a1) / det)
    shortest = float(np.min(np.hypot(*(np.roll(quad, -1, axis=0) - quad).T)))
    if np.max(np.hypot(*(out - quad).T)) > max(3.0, 0.12 * shortest):
        return None  # as imageform._kernels.aruco._corner_tolerance
    return out


def _fill_holes(mask: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """``mask`` with the background regions that do not touch its border filled."""
    from scipy import ndimage

    bg, n = ndimage.label(~mask)
    if n == 0:
        return mask
    edge = np.unique(np.concatenate([bg[0], bg[-1], bg[:, 0], bg[:, -1]]))
    inside = np.ones(n + 1, dtype=bool)
    inside[edge] = False
    inside[0] = False
    return np.asarray(mask | inside[bg])


def _spans_thin(own: NDArray[np.bool_]) -> bool:
    """Whether a component's rows' spans fill less than 70 % of their convex hull.

    ``own``: the component in its bounding box (every row holds a pixel). Row ``i``'s span
    runs from its first to its last pixel; the hull is that of the spans' end pixels'
    centres (SciPy's Qhull; its area by the shoelace formula in integers). As
    :func:`imageform._kernels.aruco._span_hull` and ``component_quads``' status 6.
    """
    from scipy.spatial import ConvexHull, QhullError

    from imageform._kernels.aruco import SPAN_DEN, SPAN_NUM

    hh, ww = own.shape
    first = np.argmax(own, axis=1).astype(np.int64)
    last = (ww - 1 - np.argmax(own[:, ::-1], axis=1)).astype(np.int64)
    spans = int(np.sum(last - first + 1))
    rows = np.arange(hh, dtype=np.int64)
    pts = np.unique(np.concatenate([np.stack([first, rows], 1), np.stack([last, rows], 1)]), axis=0)
    if len(pts) < 3 or np.ptp(pts[:, 0]) == 0 or np.ptp(pts[:, 1]) == 0:
        return False  # a line: no area
    try:
        v = pts[ConvexHull(pts.astype(np.float64)).vertices]
    except QhullError:
        return False  # collinear
    x, y = v[:, 0], v[:, 1]
    twice = abs(int(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)))
    return 2 * SPAN_DEN * spans < SPAN_NUM * twice


def _otsu(values: NDArray[np.float64]) -> float:
    """Otsu's threshold of a few values: the split maximising the between-class variance."""
    v = np.sort(values)
    n = len(v)
    i = np.arange(1, n)
    csum = np.cumsum(v)
    m0 = csum[:-1] / i
    m1 = (csum[-1] - csum[:-1]) / (n - i)
    between = (i / n) * (1 - i / n) * (m0 - m1) ** 2
    k = int(np.argmax(between))
    return float(0.5 * (v[k] + v[k + 1]))


def _read_bits(
    g: NDArray[np.float64], quad: NDArray[np.float64], cells: int
) -> tuple[NDArray[np.bool_], float] | None:
    """Read the cell colours (True = white) of a quad seen as ``cells x cells`` and the contrast."""
    unit = np.array([[0.0, 0.0], [cells, 0.0], [cells, cells], [0.0, cells]])
    h = _homography(unit, quad)
    sub = np.array([0.3, 0.5, 0.7])
    su, sv = np.meshgrid(sub, sub)
    offs = np.column_stack([su.ravel(), sv.ravel()])
    ci, cj = np.meshgrid(np.arange(cells), np.arange(cells))
    base = np.column_stack([ci.ravel(), cj.ravel()]).astype(np.float64)  # (x = col, y = row)
    pts = (base[:, None, :] + offs[None]).reshape(-1, 2)
    means = _bilinear(g, _apply_h(h, pts)).reshape(cells * cells, -1).mean(axis=1)
    contrast = float(means.max() - means.min())
    if contrast < 0.08:
        return None
    thr = _otsu(means)
    return (means > thr).reshape(cells, cells), contrast


def _match(
    bits: NDArray[np.bool_], d: ArucoDictionary, rotated: NDArray[np.uint8], max_bits: int
) -> tuple[int, int, int] | None:
    """``(id, rotation, distance)`` of the nearest code, or None."""
    flat = bits.reshape(-1).astype(np.uint8)
    dist = np.count_nonzero(rotated != flat[None, None, :], axis=2)  # (n, 4)
    best = int(np.argmin(dist))
    mid, rot = divmod(best, 4)
    dmin = int(dist[mid, rot])
    if dmin > max_bits:
        return None
    return mid, rot, dmin


@lru_cache(maxsize=16)
def _rotated_codes(name: str) -> NDArray[np.uint8]:
    d = aruco_dictionary(name)
    return np.stack([np.stack([np.rot90(c, k).reshape(-1) for k in range(4)]) for c in d.codes])


def detect_aruco_markers(
    image: ArrayLike,
    dictionary: str | ArucoDictionary = "6x6_250",
    *,
    min_side_px: float | None = None,
    windows: tuple[int, ...] | None = None,
    error_correction_rate: float = 0.6,
    max_border_errors: float = 0.35,
    all_sightings: bool = False,
) -> ArucoMarkers:
    """Find and decode the ArUco markers of ``dictionary`` in ``image``.

    Parameters
    ----------
    image : array_like, shape (H, W) or (H, W, 3)
        Grey or RGB (uint8, uint16, or floats: [0, 1] or any scale).
    dictionary : str or ArucoDictionary
        See :func:`aruco_dictionary`.
    min_side_px : float, optional, keyword-only
        Smallest marker side, in pixels, looked for. Default (None): on an image up to
        1600 px on its larger side, 6 px (a 4x4 marker's six cells at a pixel each still
        decode in photographs; a smaller one gives no more markers but false ones in
        clutter); on a larger image the candidates are found on the image reduced
        ``f = 2, 4, ...`` times (the largest ``f`` that keeps a marker of 0.75 % of the
        larger side, OpenCV's smallest by its ``minMarkerPerimeterRate`` 0.03, at least
        6 px wide there), then fitted and read at full resolution: the smallest marker found
        is then about ``6 f`` px (12 px from a larger side of 1600 px, 24 px from 3200 px),
        still below OpenCV's. A number: markers down to that side, the image reduced only
        as far as that allows (``min_side_px=6`` searches a 12 Mpx photograph at full
        resolution: slower, and small markers with thin margins are kept).
    windows : tuple of int, optional, keyword-only
        Side lengths (pixels, odd) of the adaptive threshold's local-mean windows; default
        three sizes scaled with the image (about 1.5 %, 4 % and 10 % of its larger side).
    error_correction_rate : float, keyword-only
        Fraction in [0, 1] of the dictionary's ``max_correction_bits`` corrected (OpenCV's
        ``errorCorrectionRate``, 0.6).
    max_border_errors : float, keyword-only
        Largest fraction of border cells that may read white (OpenCV's
        ``maxErroneousBitsInBorderRate``, 0.35).
    all_sightings : bool, keyword-only
        Report every place an id is read (a second print, a reflection, a misread marker:
        OpenCV's ``detectMarkers`` does), the clearest first; default (False): one per id,
        the clearest (the highest contrast less bits corrected). A caller that knows where
        its markers should be (a marker map, the previous frame) chooses among them.

    Returns
    -------
    ArucoMarkers
        Sorted by id; a marker seen at several threshold windows is reported once (with
        ``all_sightings``, two sightings of an id whose centres are nearer than half the
        smaller one's side are one).

    Raises
    ------
    InvalidInputError
        ``image`` is not a grey or RGB image of real numbers.

    Examples
    --------
    >>> import numpy as np
    >>> canvas = np.full((240, 320), 255, np.uint8)
    >>> canvas[60:180, 100:220] = aruco_marker_image(7, "4x4_50", size_px=120)
    >>> m = detect_aruco_markers(canvas, "4x4_50")
    >>> m.ids.tolist(), np.round(m.corners[0], 1).tolist()
    ([7], [[99.5, 59.5], [219.5, 59.5], [219.5, 179.5], [99.5, 179.5]])
    """
    return _detect(
        image,
        dictionary,
        min_side_px=min_side_px,
        windows=windows,
        error_correction_rate=error_correction_rate,
        max_border_errors=max_border_errors,
        all_sightings=all_sightings,
    )


def _detect(
    image: ArrayLike,
    dictionary: str | ArucoDictionary = "6x6_250",
    *,
    source: object = None,
    min_side_px: float | None = None,
    windows: tuple[int, ...] | None = None,
    error_correction_rate: float = 0.6,
    max_border_errors: float = 0.35,
    all_sightings: bool = False,
) -> ArucoMarkers:
    """Find the markers as :func:`detect_aruco_markers` does, given the caller's image.

    ``source``: the caller's image that ``image`` (already :func:`_gray01`) was made from;
    when it is a uint8 grey image its codes give the threshold in integers (the same pixels,
    :func:`imageform._kernels.aruco.dark_components_u8`).
    """
    d = aruco_dictionary(dictionary)
    if source is None:
        image = source = _grey_source(image)  # a colour frame read on its grey, once
    g = _gray01(image, scratch=True)
    g8 = (
        source
        if isinstance(source, np.ndarray)
        and source.dtype == np.uint8
        and source.ndim == 2
        and source.shape == g.shape
        else None
    )
    if min_side_px is None:
        min_side, most = 6.0, None
    else:
        min_side = most = as_real(min_side_px, "min_side_px", positive=True, maximum=1e5)
    rate = as_real(error_correction_rate, "error_correction_rate", nonnegative=True, maximum=1.0)
    border_rate = as_real(max_border_errors, "max_border_errors", nonnegative=True, maximum=1.0)
    hgt, wid = g.shape
    if windows is None:
        big = max(hgt, wid)
        wins = sorted({max(3, int(big * f) | 1) for f in (0.015, 0.04, 0.10)})
    else:
        if not isinstance(windows, tuple | list) or not windows:
            raise InvalidInputError(f"expected windows as a tuple of ints, got {describe(windows)}")
        wins = [as_int(w, "windows", minimum=3, maximum=4001) | 1 for w in windows]
    max_bits = math.floor(d.max_correction_bits * rate)
    rotated = (
        _rotated_codes(d.name)
        if isinstance(dictionary, str)
        else np.stack([np.stack([np.rot90(c, k).reshape(-1) for k in range(4)]) for c in d.codes])
    )
    from imageform._backend import use_numba

    args = (g, sorted(wins, reverse=True), d, rotated, min_side, max_bits, border_rate)
    if use_numba(g):
        found = _search_numba(*args, reduce=_reduction(g.shape, most), g8=g8)
    else:
        found = _search_numpy(*args)
    kept = [
        (i, sighting)
        for i in sorted(found)
        for sighting in (_sightings(found[i]) if all_sightings else [_clearest(found[i])])
    ]
    ids = np.array([i for i, _ in kept], dtype=np.int64)
    corners = np.array([c for _, (_, c, _) in kept], dtype=np.float64).reshape(-1, 4, 2)
    hamming = np.array([h for _, (_, _, h) in kept], dtype=np.int64)
    return ArucoMarkers(ids, corners, hamming, d.name)


#: One sighting of a marker: (score, corners (4, 2) in printed order, bits corrected), the
#: score its contrast minus the bits corrected.
_Sighting = tuple[float, NDArray[np.float64], int]
#: What a search returns: each marker id's sightings, in the order found.
_Found = dict[int, list[_Sighting]]


def _clearest(sightings: list[_Sighting]) -> _Sighting:
    """Return the sighting of the best score (the first found of equal ones)."""
    best = sightings[0]
    for s in sightings[1:]:
        if s[0] > best[0]:
            best = s
    return best


def _sightings(sightings: list[_Sighting]) -> list[_Sighting]:
    """Return the distinct sightings of an id, the clearest first.

    Two whose centres are nearer than half the smaller one's side are one marker (found
    twice, e.g. at windows that gave it boxes of different sizes): the clearer is kept.
    """
    order = sorted(range(len(sightings)), key=lambda k: -sightings[k][0])  # stable: ties kept
    out: list[_Sighting] = []
    for k in order:
        c = sightings[k][1]
        centre, side = c.mean(axis=0), _mean_side(c)
        if all(
            float(np.hypot(*(centre - o[1].mean(axis=0)))) >= 0.5 * min(side, _mean_side(o[1]))
            for o in out
        ):
            out.append(sightings[k])
    return out


def _mean_side(c: NDArray[np.float64]) -> float:
    """Return a quadrilateral's mean side (pixels)."""
    return float(np.mean(np.hypot(*(np.roll(c, -1, axis=0) - c).T)))


def _reduction(shape: tuple[int, int], min_side: float | None) -> int:
    """Return the factor (1, 2, 4, ...) by which an image of ``shape`` is reduced for candidates.

    OpenCV's detector looks for markers of a perimeter at least 3 % of the image's larger
    side (``minMarkerPerimeterRate``), a side of 0.75 %: on a large image such a marker is
    still 6 pixels wide on the image reduced ``f`` times, so the thresholds and components
    are found there (``f²`` times fewer pixels) and each candidate's quad fitted again at
    full resolution (OpenCV's ``aprilTagQuadDecimate`` and Aruco3's
    ``minMarkerLengthRatioOriginalImg`` do the same). 1 up to a larger side of 1600 px.
    ``min_side`` (the caller's ``min_side_px``): no further than keeps such a marker 6 px wide.
    """
    f = 1
    while 0.0075 * max(shape) / (2 * f) >= 6.0 and (min_side is None or 12.0 * f <= min_side):
        f *= 2
    return f


#: Each thread's work buffer for :func:`_table` (a fresh table of a few megabytes costs
#: more in page faults, zeroed by the system, than the sums written into it).
_WORK = threading.local()
#: Largest table kept between calls (entries: 32 MB).
_MAX_KEPT = 4_000_000


class _WorkArea:
    """A tracker's work buffers for frames larger than ``_MAX_KEPT`` pixels, kept by name.

    A 12 Mpx frame's float grey image is 100 MB: a fresh one each frame costs its page
    faults (tens of milliseconds, the system zeroing it) more than the values written into
    it. A tracker owns one area (freed with it) and lends it to the detector for the length
    of a frame (:func:`_working`); a buffer is valid until the next frame. One thread at a
    time may use an area (as a tracker's own state: a tracker follows one video).
    """

    __slots__ = ("buffers",)

    def __init__(self) -> None:
        self.buffers: dict[str, NDArray[Any]] = {}

    def take(self, name: str, size: int, dtype: Any) -> NDArray[Any]:
        """Return the buffer ``name`` as ``size`` entries of ``dtype`` (1-D; reused, grown)."""
        buf = self.buffers.get(name)
        if buf is None or buf.dtype != dtype or buf.size < size:
            buf = np.empty(size, dtype=dtype)
            self.buffers[name] = buf
        return buf[:size]


def _grey32(image: object) -> NDArray[np.float32] | None:
    """Return a uint8 grey ``image`` as :func:`refine_corners` reads it, in a lent buffer.

    ``float32(code) / 255`` (``as_image``'s values, the same numbers) into the buffer of the
    tracker whose frame this is (:func:`_working`); None without one, or for another image
    (the caller then converts as usual).
    """
    area = getattr(_WORK, "area", None)
    if (
        area is None
        or not isinstance(image, np.ndarray)
        or image.dtype != np.uint8
        or image.ndim != 2
        or min(image.shape) < 16
    ):
        return None
    out = area.take("grey32", image.size, np.float32).reshape(image.shape)
    np.true_divide(image, np.float32(255.0), out=out, dtype=np.float32)
    return out


@contextlib.contextmanager
def _working(area: _WorkArea) -> Iterator[None]:
    """Lend ``area`` to this thread's detections (:func:`_gray01`, :func:`_table`) meanwhile."""
    before = getattr(_WORK, "area", None)
    _WORK.area = area
    try:
        yield
    finally:
        _WORK.area = before


def _table(g: NDArray[np.float64] | NDArray[np.uint8], pad: int) -> NDArray[Any]:
    """Return :func:`imageform._kernels.aruco.box_integral` of ``g``, in a work buffer.

    ``box_integral_u8`` (int32) of a uint8 ``g``; in this thread's buffer when small enough:
    valid until the next call in the same thread.
    """
    from imageform._kernels.aruco import box_integral_roi, box_integral_u8

    hgt, wid = g.shape
    shape = (hgt + 2 * pad + 1, wid + 2 * pad + 1)
    size = shape[0] * shape[1]
    dtype = np.int32 if g.dtype == np.uint8 else np.float64
    key = "table32" if dtype == np.int32 else "table"
    area = getattr(_WORK, "area", None)
    if size > _MAX_KEPT and area is not None:
        out = area.take(key, size, dtype).reshape(shape)
    elif size > _MAX_KEPT:
        out = np.empty(shape, dtype=dtype)
    else:
        buf = getattr(_WORK, key, None)
        if buf is None or buf.size < size:
            buf = np.empty(max(size, 1 << 20), dtype=dtype)
            setattr(_WORK, key, buf)
        out = buf[:size].reshape(shape)
    if dtype == np.int32:
        return np.asarray(box_integral_u8(g, pad, out))
    return np.asarray(box_integral_roi(g, pad, 0, hgt, 0, wid, out))


def _components(
    g: NDArray[np.float64] | NDArray[np.uint8],
    integral: NDArray[np.float64] | NDArray[np.int32],
    pad: int,
    win: int,
    cap: list[int],
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]]:
    """Label the dark components of ``g`` (:func:`imageform._kernels.aruco.dark_components`).

    ``dark_components_u8`` of a uint8 ``g``; asked again with more room (``cap[0]`` runs,
    kept for the next window) when its runs overflow.
    """
    from imageform._kernels.aruco import dark_components, dark_components_u8

    hgt, wid = g.shape
    # room for the runs (a photograph has about one run in 20 pixels, a row at most (W + 1) / 2)
    # and the labels (half the runs: photographs start one in 3 to 10): four times more when a
    # window needs it
    worst = hgt * ((wid + 1) // 2) + 2
    if cap[0] <= 0:
        cap[0] = min(worst, hgt * wid // 16 + 4096)
    while True:
        c = min(cap[0], worst)
        cap_labels = c if c == worst else c // 2 + 1024
        if g.dtype == np.uint8:
            out = dark_components_u8(g, integral, pad, int(win), c, cap_labels)
        else:
            out = dark_components(g, integral, pad, int(win), 0.02, c, cap_labels)
        if len(out[3]) or c == worst:
            return out
        cap[0] = min(worst, 4 * c)


def _sized(
    stats: NDArray[np.int64], min_side: float, max_area: float, boxes: NDArray[np.float64]
) -> NDArray[np.int64]:
    """Return the components of ``stats`` large enough for a marker, not decoded already."""
    if len(stats) < 2:
        return np.zeros(0, dtype=np.int64)
    area = stats[:, 0]
    hh = stats[:, 2] - stats[:, 1] + 1
    ww = stats[:, 4] - stats[:, 3] + 1
    ok = (area >= min_side * min_side * 0.5) & (hh >= min_side * 0.7) & (ww >= min_side * 0.7)
    ok &= hh * ww <= max_area
    ok[0] = False
    cand = np.nonzero(ok)[0]
    if len(cand) == 0:
        return cand
    cy = 0.5 * (stats[cand, 1] + stats[cand, 2] + 1)
    cx = 0.5 * (stats[cand, 3] + stats[cand, 4] + 1)
    size = (hh * ww)[cand].astype(np.float64)
    return cand[~_inside(boxes, cx, cy, size)]  # decoded already, at a larger window


def _search_numba(
    g: NDArray[np.float64],
    wins: list[int],
    d: ArucoDictionary,
    rotated: NDArray[np.uint8],
    min_side: float,
    max_bits: int,
    border_rate: float,
    reduce: int = 1,
    g8: NDArray[np.uint8] | None = None,
) -> _Found:
    """Find the markers of ``g`` at each threshold window (largest first): numba kernels.

    The same steps and verdicts as :func:`_search_numpy` (tested): the per-pixel and
    per-component work in ``imageform._kernels.aruco``, the decoding batched over the
    candidates of a window. With ``reduce`` > 1 (:func:`_reduction`) the components are
    found on ``g`` reduced that many times (block means, the window reduced too) and each
    one with a quad there is found again in its neighbourhood at full resolution, with the
    full image's threshold (:func:`imageform._kernels.aruco.box_integral_roi`): the markers
    and corners are those of the full-resolution search, less the markers under ``reduce``
    times ``min_side``.
    """
    from imageform._kernels.aruco import block_means, component_quads

    hgt, wid = g.shape
    cells = d.marker_size + 2
    found: _Found = {}
    max_area = 0.9 * hgt * wid
    boxes = np.zeros((0, 5))
    cap = [0]
    if reduce > 1:
        small = block_means(g, reduce)
        wins_small = [max(3, (w // reduce) | 1) for w in wins]
        pad = max(wins_small) // 2
        integral = _table(small, pad)
        full: list[NDArray[np.float64]] = []
        spent = [0]
    else:
        pad = max(wins) // 2
        hgt_p, wid_p = hgt + 2 * pad, wid + 2 * pad
        if g8 is not None and 255 * hgt_p * wid_p < 2**31 and 2 * pad + 1 <= 917:
            g8 = np.ascontiguousarray(g8)
            integral = _table(g8, pad)  # in integers, exact (dark_components_u8)
        else:
            g8 = None
            integral = _table(g, pad)  # every window's local means from one table
    for w_i, win in enumerate(wins):
        if reduce == 1:
            runs, comp_runs, comp_ptr, stats = _components(
                g if g8 is None else g8, integral, pad, win, cap
            )
            cand = _sized(stats, min_side, max_area, boxes)
            if len(cand) == 0:
                continue
            quads, status = component_quads(runs, comp_runs, comp_ptr, cand, stats, float(min_side))
            good = np.nonzero(status == 0)[0]
            quads, st = quads[good], stats[cand[good]]
        else:
            quads, st = _search_reduced(
                g,
                small,
                integral,
                pad,
                wins_small[w_i],
                win,
                reduce,
                cap,
                full,
                spent,
                max(wins) // 2,
                min_side,
                max_area,
                boxes,
                (d, rotated, max_bits, border_rate),
            )
        if len(quads) == 0:
            continue
        decoded = _decoded(_cell_means(g, quads, cells), rotated, cells, max_bits, border_rate)
        new_boxes: list[tuple[float, float, float, float, float]] = []
        for quad, row, hit in zip(quads, st.tolist(), decoded, strict=True):
            if hit is None:
                continue
            _, top, bottom, left, right = row
            s_cx, s_cy = 0.5 * (left + right + 1), 0.5 * (top + bottom + 1)
            s_size = float((bottom - top + 1) * (right - left + 1))
            if any(
                b[0] <= s_cx <= b[2] and b[1] <= s_cy <= b[3] and 0.7 < s_size / b[4] < 1.4
                for b in new_boxes
            ):
                continue  # decoded already, at this window (an earlier component)
            mid, rot, dist, contrast = hit
            # observed == np.rot90(code, rot) (counter-clockwise turns): the printed top-left
            # corner is the observed corner (4 - rot) % 4
            ordered = quad[[(0 - rot) % 4, (1 - rot) % 4, (2 - rot) % 4, (3 - rot) % 4]]
            score = contrast - dist
            found.setdefault(mid, []).append((score, ordered, dist))
            (x0, x1), (y0, y1) = (
                (float(quad[:, 0].min()), float(quad[:, 0].max())),
                (float(quad[:, 1].min()), float(quad[:, 1].max())),
            )
            new_boxes.append((x0, y0, x1, y1, s_size))
        if new_boxes:
            boxes = np.vstack([boxes, np.array(new_boxes)])
    return found


def _decoded(
    means: NDArray[np.float64],
    rotated: NDArray[np.uint8],
    cells: int,
    max_bits: int,
    border_rate: float,
    min_contrast: float = 0.08,
) -> list[tuple[int, int, int, float] | None]:
    """:func:`_decode` by :func:`imageform._kernels.aruco.decode_cells` (the same verdicts)."""
    from imageform._kernels.aruco import decode_cells

    code, rot, dist, contrast = decode_cells(
        means, np.ascontiguousarray(rotated), cells, max_bits, border_rate, min_contrast
    )
    return [
        None if k < 0 else (k, r, t, c)
        for k, r, t, c in zip(
            code.tolist(), rot.tolist(), dist.tolist(), contrast.tolist(), strict=True
        )
    ]


def _cell_means(
    g: NDArray[np.float64], quads: NDArray[np.float64], cells: int
) -> NDArray[np.float64]:
    """:func:`imageform._kernels.aruco.cell_means` of ``quads`` (m, 4, 2) in ``g``."""
    from imageform._kernels.aruco import cell_means

    return np.asarray(cell_means(g, np.ascontiguousarray(quads), cells))


def _search_reduced(
    g: NDArray[np.float64],
    small: NDArray[np.float64],
    integral: NDArray[np.float64],
    pad: int,
    win_small: int,
    win: int,
    f: int,
    cap: list[int],
    full: list[NDArray[np.float64]],
    spent: list[int],
    pad_full: int,
    min_side: float,
    max_area: float,
    boxes: NDArray[np.float64],
    read: tuple[ArucoDictionary, NDArray[np.uint8], int, float],
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Find one window's full-resolution quads (m, 4, 2) and component stats (m, 5).

    The candidates come from ``small`` (``g`` reduced ``f`` times).

    Each component of ``small`` with a quad gives a region of ``g`` (its box scaled up, with
    a margin of a quarter of its side and ``2 f`` pixels), thresholded there with the full
    image's local means (the region's own
    :func:`imageform._kernels.aruco.box_integral_roi` while the regions' tables, ``spent[0]``
    entries so far, cost less than half the image's; then ``full[0]``, the image's
    :func:`imageform._kernels.aruco.box_integral` padded by ``pad_full``); its components
    that do not touch the region's border (a component that does may go on outside it) are
    the full image's own, and go through the same size checks and quad fitting as in the
    full-resolution search.
    A quad of ``small`` at least 3 pixels a cell whose cells read nowhere near a marker
    there (contrast under half the decoder's, or not a code within one more bit, with a
    border 15 % more wrong) is not looked at again.
    """
    from imageform._kernels.aruco import box_integral, box_integral_roi, component_quads

    hgt, wid = g.shape
    runs, comp_runs, comp_ptr, stats = _components(small, integral, pad, win_small, cap)
    cand = _sized(stats, min_side, max_area / (f * f), boxes / np.array([f, f, f, f, f * f]))
    empty = np.zeros((0, 4, 2)), np.zeros((0, 5), dtype=np.int64)
    if len(cand) == 0:
        return empty
    quads, status = component_quads(runs, comp_runs, comp_ptr, cand, stats, float(min_side))
    good = np.nonzero(status == 0)[0]
    if len(good) == 0:
        return empty
    d, rotated, max_bits, border_rate = read
    cells = d.marker_size + 2
    q = quads[good]
    e = np.roll(q, -1, axis=1) - q
    shortest = np.hypot(e[..., 0], e[..., 1]).min(axis=1)
    hits = _decoded(
        _cell_means(small, q, cells), rotated, cells, max_bits + 1, border_rate + 0.15, 0.04
    )
    good = good[[h is not None or s < 3 * cells for h, s in zip(hits, shortest, strict=True)]]
    if len(good) == 0:
        return empty
    out_q: list[NDArray[np.float64]] = []
    out_s: list[NDArray[np.int64]] = []
    regions: list[tuple[int, int, int, int]] = []
    for j in good.tolist():
        _, top, bottom, left, right = stats[cand[j]].tolist()
        side = f * max(bottom - top + 1, right - left + 1)
        m = side // 4 + 2 * f
        r0, r1 = max(0, top * f - m), min(hgt, (bottom + 1) * f + m)
        c0, c1 = max(0, left * f - m), min(wid, (right + 1) * f + m)
        if any(a0 <= r0 and r1 <= a1 and b0 <= c0 and c1 <= b1 for a0, a1, b0, b1 in regions):
            continue  # inside a region searched already
        regions.append((r0, r1, c0, c1))
        # the region's own table while the regions' tables cost less than the image's
        half = win // 2
        cost = (r1 - r0 + 2 * half) * (c1 - c0 + 2 * half)
        if not full and spent[0] + cost <= (hgt + 2 * pad_full) * (wid + 2 * pad_full) // 2:
            spent[0] += cost
            view = np.empty((r1 - r0 + 2 * half + 1, c1 - c0 + 2 * half + 1))
            view, p_view = box_integral_roi(g, half, r0, r1, c0, c1, view), half
        else:
            if not full:
                full.append(box_integral(g, pad_full))
            # the region's rows and columns: padded row r0 - pad_full is the image's row r0
            view = full[0][r0 : r1 + 2 * pad_full + 1, c0 : c1 + 2 * pad_full + 1]
            p_view = pad_full
        sub = g[r0:r1, c0:c1]
        runs_r, comp_runs_r, comp_ptr_r, st = _components(sub, view, p_view, win, [0])
        if len(st) < 2:
            continue
        h_r, w_r = r1 - r0, c1 - c0
        inner = (
            ((st[:, 1] > 0) | (r0 == 0))
            & ((st[:, 2] < h_r - 1) | (r1 == hgt))
            & ((st[:, 3] > 0) | (c0 == 0))
            & ((st[:, 4] < w_r - 1) | (c1 == wid))
        )
        st_full = st + np.array([0, r0, r0, c0, c0])
        cand_r = _sized(st_full, min_side, max_area, boxes)
        cand_r = cand_r[inner[cand_r]]
        if len(cand_r) == 0:
            continue
        q_r, status_r = component_quads(
            runs_r, comp_runs_r, comp_ptr_r, cand_r, st, float(min_side)
        )
        ok = np.nonzero(status_r == 0)[0]
        if len(ok):
            out_q.append(q_r[ok] + np.array([c0, r0], dtype=np.float64))
            out_s.append(st_full[cand_r[ok]])
    if not out_q:
        return empty
    return np.concatenate(out_q), np.concatenate(out_s)


def _inside(
    boxes: NDArray[np.float64],
    cx: NDArray[np.float64],
    cy: NDArray[np.float64],
    size: NDArray[np.float64],
) -> NDArray[np.bool_]:
    """Whether each centre lies in a decoded marker's box of a similar size (0.7-1.4x)."""
    if len(boxes) == 0:
        return np.zeros(len(cx), dtype=bool)
    b = boxes[None, :, :]
    ratio = size[:, None] / b[..., 4]
    return np.asarray(
        np.any(
            (b[..., 0] <= cx[:, None])
            & (cx[:, None] <= b[..., 2])
            & (b[..., 1] <= cy[:, None])
            & (cy[:, None] <= b[..., 3])
            & (ratio > 0.7)
            & (ratio < 1.4),
            axis=1,
        )
    )


def _decode(
    means: NDArray[np.float64],
    d: ArucoDictionary,
    cells: int,
    rotated: NDArray[np.uint8],
    max_bits: int,
    border_rate: float,
    min_contrast: float = 0.08,
) -> list[tuple[int, int, int, float] | None]:
    """Read the cells of several quads at once: ``(id, rotation, distance, contrast)`` or None.

    Each quad's cell means are split by Otsu's threshold (white above), its border cells
    checked (at most ``border_rate`` of them white) and its inner bits matched to the nearest
    code under the four rotations (at most ``max_bits`` apart), as :func:`_read_bits` and
    :func:`_match` for one quad.
    """
    m, n = means.shape
    contrast = means.max(axis=1) - means.min(axis=1)
    v = np.sort(means, axis=1)
    i = np.arange(1, n)
    csum = np.cumsum(v, axis=1)
    m0 = csum[:, :-1] / i
    m1 = (csum[:, -1:] - csum[:, :-1]) / (n - i)
    between = (i / n) * (1 - i / n) * (m0 - m1) ** 2
    k = np.argmax(between, axis=1)
    rows = np.arange(m)
    thr = 0.5 * (v[rows, k] + v[rows, k + 1])
    bits = (means > thr[:, None]).reshape(m, cells, cells)
    border = np.ones((cells, cells), dtype=bool)
    border[1:-1, 1:-1] = False
    bad = np.count_nonzero(bits[:, border], axis=1) > border_rate * border.sum()
    inner = bits[:, 1:-1, 1:-1].reshape(m, -1).astype(np.uint8)
    dist = np.count_nonzero(rotated[None] != inner[:, None, None, :], axis=3)  # (m, n, 4)
    flat = dist.reshape(m, -1)
    best = np.argmin(flat, axis=1)
    dmin = flat[rows, best]
    out: list[tuple[int, int, int, float] | None] = []
    for j in range(m):
        if contrast[j] < min_contrast or bad[j] or dmin[j] > max_bits:
            out.append(None)
            continue
        mid, rot = divmod(int(best[j]), 4)
        out.append((mid, rot, int(dmin[j]), float(contrast[j])))
    return out


def _search_numpy(
    g: NDArray[np.float64],
    wins: list[int],
    d: ArucoDictionary,
    rotated: NDArray[np.uint8],
    min_side: float,
    max_bits: int,
    border_rate: float,
) -> _Found:
    """Find the markers as :func:`_search_numba`, with NumPy and SciPy, one component at a time.

    The twin run when numba is disabled (``IMAGEFORM_DISABLE_NUMBA``).
    """
    from scipy import ndimage

    hgt, wid = g.shape
    cells = d.marker_size + 2
    border_mask = np.ones((cells, cells), dtype=bool)
    border_mask[1:-1, 1:-1] = False
    found: _Found = {}
    min_area = min_side * min_side * 0.5
    max_area = 0.9 * hgt * wid
    structure = np.array([[0, 1, 0], [1, 1, 1], [0, 1, 0]], dtype=bool)
    boxes: list[tuple[float, float, float, float, int]] = []
    g32 = g.astype(np.float32)  # the local means only threshold: float32 is ample
    for win in wins:
        mean = ndimage.uniform_filter(g32, size=win, mode="reflect")
        dark = g < mean - 0.02
        labels, n = ndimage.label(dark, structure=structure)
        if n == 0:
            continue
        areas = np.bincount(labels.ravel(), minlength=n + 1)
        slices = ndimage.find_objects(labels)
        sized = np.nonzero(areas >= min_area)[0]
        for k in sized[sized > 0].tolist():
            sl = slices[k - 1]
            if sl is None:
                continue
            hh, ww = sl[0].stop - sl[0].start, sl[1].stop - sl[1].start
            if hh < min_side * 0.7 or ww < min_side * 0.7 or hh * ww > max_area:
                continue
            # holes filled: only the outer boundary counts (a small window leaves a ring)
            if areas[k] < min_area:
                continue
            cy, cx = 0.5 * (sl[0].start + sl[0].stop), 0.5 * (sl[1].start + sl[1].stop)
            if any(
                b[0] <= cx <= b[2] and b[1] <= cy <= b[3] and 0.7 < (hh * ww) / b[4] < 1.4
                for b in boxes
            ):
                continue  # decoded already, at a larger window
            own = labels[sl] == k
            if _spans_thin(own):
                continue  # its rows' spans fill too little of their hull: no quadrilateral
            sub = _fill_holes(own)
            if int(np.count_nonzero(sub)) == int(areas[k]):
                continue  # no holes: a solid blob, not a marker (its code has white cells)
            # boundary pixels: in the component with a 4-neighbour outside it
            pad = np.pad(sub, 1)
            inner = pad[:-2, 1:-1] & pad[2:, 1:-1] & pad[1:-1, :-2] & pad[1:-1, 2:]
            edge = sub & ~inner
            vv, uu = np.nonzero(edge)
            pts = np.column_stack([uu + sl[1].start, vv + sl[0].start]).astype(np.float64)
            if len(pts) < 12:
                continue
            quad = _quad(pts, float(sub.sum()))
            if quad is None:
                continue
            sides = np.hypot(*(np.roll(quad, -1, axis=0) - quad).T)
            if sides.min() < min_side or sides.min() < 0.25 * sides.max():
                continue
            refined = _refine_sides(quad, pts)
            if refined is None:
                continue
            quad = refined
            read = _read_bits(g, quad, cells)
            if read is None:
                continue
            bits, contrast = read
            if np.count_nonzero(bits[border_mask]) > border_rate * border_mask.sum():
                continue
            hit = _match(bits[1:-1, 1:-1], d, rotated, max_bits)
            if hit is None:
                continue
            mid, rot, dist = hit
            # observed == np.rot90(code, rot) (counter-clockwise turns): the printed top-left
            # corner is the observed corner (4 - rot) % 4
            ordered = np.roll(quad, rot, axis=0)
            score = contrast - dist
            found.setdefault(mid, []).append((score, ordered, dist))
            lo, hi = quad.min(axis=0), quad.max(axis=0)
            boxes.append((lo[0], lo[1], hi[0], hi[1], hh * ww))
    return found


def identify_aruco_dictionary(image: ArrayLike, *, min_markers: int = 2) -> str | None:
    """Name the predefined dictionary whose markers an image shows, or None.

    OpenCV's predefined dictionaries of one marker size are prefixes of each other
    (``4x4_50`` is the first 50 codes of ``4x4_1000``), so each family is searched once, with
    its largest dictionary and no bit correction (an exact match only: a false code is then
    unlikely); the family with the most markers wins, and the smallest dictionary of that
    family holding the largest id found is returned (a larger one of the same family reads
    the same markers with the same ids). Meant for error messages and for a user
    holding a board of unknown origin; it costs one detection per family (five in all).

    Parameters
    ----------
    image : array_like, shape (H, W) or (H, W, 3)
        Grey or RGB image (as :func:`detect_aruco_markers`).
    min_markers : int, keyword-only
        Fewest markers (at least 1) for a family to be named.

    Returns
    -------
    str or None
        A name of :data:`ARUCO_DICTIONARIES`, or None when no family reaches ``min_markers``.

    Raises
    ------
    InvalidInputError
        ``image`` is not a grey or RGB image of real numbers, or ``min_markers`` is not a
        positive integer.

    Examples
    --------
    >>> import numpy as np
    >>> canvas = np.full((240, 480), 255, np.uint8)
    >>> canvas[60:180, 40:160] = aruco_marker_image(7, "5x5_100", size_px=120)
    >>> canvas[60:180, 280:400] = aruco_marker_image(63, "5x5_100", size_px=120)
    >>> identify_aruco_dictionary(canvas)
    '5x5_100'
    """
    need = as_int(min_markers, "min_markers", minimum=1, maximum=10000)
    g = _gray01(image)
    best: tuple[int, str, int] | None = None
    for family in ("4x4_1000", "5x5_1000", "6x6_1000", "7x7_1000", "aruco_original"):
        found = detect_aruco_markers(g, family, error_correction_rate=0.0)
        if len(found) >= need and (best is None or len(found) > best[0]):
            best = (len(found), family, int(found.ids.max()))
    if best is None:
        return None
    _, family, top = best
    if family == "aruco_original":
        return family
    size = family.split("_")[0]
    return next(f"{size}_{n}" for n in _COUNTS if top < n)
