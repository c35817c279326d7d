r"""Chart patches from whatever image holds the chart: the one place that decides how.

:func:`sample_chart` takes an image with a colour chart in it and returns its patches
(:class:`~imageform.analysis.ChartPatches`) with where they were sampled:

- ``layout="cropped"``: the chart fills the frame as a ``rows × cols`` grid
  (:func:`~imageform.analysis.chart_patches`);
- ``layout="detect"``: a ColorChecker anywhere in a photograph, at any rotation and
  perspective (:func:`~imageform.analysis.detect_colorchecker` then
  :func:`~imageform.analysis.measure_chart_patches`);
- ``layout="auto"`` (the default): the grid sampling is tried first and kept when it
  *validates*: at most ``max(1, N // 12)`` of its ``N`` cells are not flat (missing) and,
  for the 4 × 6 ColorChecker, the chart's published colours are an affine function of the
  measured ones in linear light with :math:`R^2 \ge` ``min_score`` (the detector's own
  colour test, so a cropped chart turned upside down, or a photograph whose grid cells
  happen to be flat, is not taken for a cropped chart); otherwise the chart is detected.

:func:`~imageform.analysis.fit_color_correction`,
:func:`~imageform.analysis.correction_report` and :func:`chart_white_balance` accept such
images directly through it (``chart_layout=``); ``imageform fit-correction``,
``imageform harmonize --chart`` and ``imageform white-balance --method chart`` through
``--chart-layout``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from imageform import _deprecate
from imageform._colormath import srgb_decode, srgb_encode
from imageform._typing import ArrayLike
from imageform._validate import (
    as_bool,
    as_int,
    as_real,
    as_real_ndarray,
    check_option,
    describe,
)
from imageform.analysis._arrays import image_in, is_dask
from imageform.analysis.chart_detect import (
    ChartDetection,
    ChartNotFoundError,
    _colour_fit,
    detect_colorchecker,
    measure_chart_patches,
)
from imageform.analysis.chart_grid import ChartPatches, ChartWarning, chart_patches
from imageform.color.white_balance import WhiteBalanceResult
from imageform.errors import DegenerateConfigurationError, InvalidInputError

__all__ = [
    "CHART_LAYOUTS",
    "COLORCHECKER_NEUTRALS",
    "ChartSample",
    "chart_white_balance",
    "sample_chart",
]

#: How :func:`sample_chart` finds the chart in an image; the first is the default.
CHART_LAYOUTS = ("auto", "cropped", "detect")
#: The ColorChecker's neutral patches (0-based, row by row): white 9.5 to black 2.
COLORCHECKER_NEUTRALS = (18, 19, 20, 21, 22, 23)


@_deprecate.renamed_fields({"centres": "centers"})
@dataclass(frozen=True)
class ChartSample:
    """A chart's patches and where they were sampled in the image (:func:`sample_chart`).

    Positions are image pixels ``(u, v)`` (column, row; pixel centres at integers).
    """

    #: Mean encoded sRGB of every patch, row by row, with the saturated / missing flags.
    patches: ChartPatches
    #: ``"cropped"`` (grid over the whole frame) or ``"detect"`` (found in the photograph).
    layout: str
    #: (4, 2) the sampled chart's outline: the frame for a cropped chart, the outer corners
    #: of the patch lattice for a detected one (top left, top right, bottom right, bottom
    #: left of the upright chart).
    outline: np.ndarray
    #: (N, 2) patch centres.
    centers: np.ndarray
    #: (N, 4, 2) the quadrilaterals that were averaged, corners in the order of ``outline``.
    quads: np.ndarray
    #: The detection (``layout="detect"``), else None.
    detection: ChartDetection | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready lists (the detection's own fields under ``"detection"``)."""
        return {
            "layout": self.layout,
            "outline": self.outline.tolist(),
            "centers": self.centers.tolist(),
            "quads": self.quads.tolist(),
            "means_srgb": self.patches.means.tolist(),
            "saturated": self.patches.saturated.tolist(),
            "missing": self.patches.missing.tolist(),
            "detection": None if self.detection is None else self.detection.to_dict(),
        }


def _grid_geometry(
    hgt: int, wid: int, rows: int, cols: int, margin: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return the outline, centres and sampling quads of :func:`chart_patches`' grid.

    The cell ``[x0, x1)`` averages pixels ``xa = ceil(x0 + d) .. xb - 1 = floor(x1 - d) - 1``,
    whose squares span ``[xa - 0.5, xb - 0.5]`` (pixel centres at integers).
    """
    outline = np.array([[-0.5, -0.5], [wid - 0.5, -0.5], [wid - 0.5, hgt - 0.5], [-0.5, hgt - 0.5]])
    centres, quads = [], []
    for i in range(rows):
        for j in range(cols):
            y0, y1 = hgt * i / rows, hgt * (i + 1) / rows
            x0, x1 = wid * j / cols, wid * (j + 1) / cols
            dy, dx = (y1 - y0) * margin, (x1 - x0) * margin
            ya = int(np.ceil(y0 + dy))
            yb = max(int(np.floor(y1 - dy)), ya + 1)
            xa = int(np.ceil(x0 + dx))
            xb = max(int(np.floor(x1 - dx)), xa + 1)
            lo_u, hi_u, lo_v, hi_v = xa - 0.5, xb - 0.5, ya - 0.5, yb - 0.5
            quads.append([[lo_u, lo_v], [hi_u, lo_v], [hi_u, hi_v], [lo_u, hi_v]])
            centres.append([(xa + xb - 1) / 2.0, (ya + yb - 1) / 2.0])
    return outline, np.asarray(centres, dtype=np.float64), np.asarray(quads, dtype=np.float64)


def _cropped(
    rgb: Any, rows: int, cols: int, margin: float, max_std: float, saturation: float
) -> ChartSample:
    pat = chart_patches(rgb, rows, cols, margin=margin, max_std=max_std, saturation=saturation)
    outline, centres, quads = _grid_geometry(
        int(rgb.shape[0]), int(rgb.shape[1]), rows, cols, margin
    )
    return ChartSample(pat, "cropped", outline, centres, quads)


def _looks_cropped(pat: ChartPatches, rows: int, cols: int, min_score: float) -> bool:
    """Tell whether the grid sampling validates.

    Few non-flat cells and, for a ColorChecker, colours that match the published ones (the
    detector's affine linear-light R²).
    """
    n = rows * cols
    if int(pat.missing.sum()) > max(1, n // 12):
        return False
    if (rows, cols) != (4, 6):
        return True
    from imageform.analysis.synthetic import COLORCHECKER_SRGB8

    ref_lin = srgb_decode(np, np.asarray(COLORCHECKER_SRGB8, dtype=np.float64) / 255.0)
    means = np.where(np.isfinite(pat.means), pat.means, 0.0)
    r2, _ = _colour_fit(means, ref_lin, ~pat.missing)
    return bool(r2 >= min_score)


def sample_chart(
    image: ArrayLike,
    layout: str = "auto",
    *,
    rows: int = 4,
    cols: int = 6,
    margin: float = 0.25,
    max_std: float = 0.04,
    saturation: float = 1.0,
    min_score: float = 0.8,
    max_size: int = 1024,
    name: str = "image",
) -> ChartSample:
    """Sample the colour chart in ``image``, cropped or anywhere in a photograph.

    Parameters
    ----------
    image : array_like, shape (H, W, 3)
        Encoded sRGB (uint8, uint16, floats in [0, 1]; Dask is computed for a detection):
        a chart cropped to fill the frame, or a photograph with a ColorChecker in it.
    layout : {"auto", "cropped", "detect"}
        ``"cropped"``: :func:`~imageform.analysis.chart_patches` on a ``rows × cols`` grid;
        ``"detect"``: :func:`~imageform.analysis.detect_colorchecker` and
        :func:`~imageform.analysis.measure_chart_patches` (4 × 6 only); ``"auto"``: the grid
        when it validates (see the module notes), else the detection.
    rows, cols : int, keyword-only
        The grid of a cropped chart (4 × 6 for the ColorChecker Classic).
    margin : float, keyword-only
        Cropped layout: fraction of each cell left out on every side.
    max_std, saturation : float, keyword-only
        Flatness and clipping levels of a usable patch (both samplers).
    min_score : float, keyword-only
        Least :math:`R^2` of the colour fit that accepts a chart (both the ``"auto"``
        validation of a grid and the detection).
    max_size : int, keyword-only
        Long side of the detection's working image.
    name : str, keyword-only
        The argument's name in error messages.

    Returns
    -------
    ChartSample

    Raises
    ------
    ChartNotFoundError
        ``"auto"`` or ``"detect"``: no valid grid and no ColorChecker in the photograph (one
        line naming ``name``; pass ``layout="cropped"`` for a chart that fills the frame).

    Examples
    --------
    >>> from imageform.analysis import synthetic_chart_image, synthetic_chart_photo
    >>> sample_chart(synthetic_chart_image()).layout
    'cropped'
    >>> photo = synthetic_chart_photo(rng=3, cast=(1.0, 1.0, 1.0), noise=0.0)
    >>> s = sample_chart(photo.image)
    >>> s.layout, bool(np.abs(s.patches.means - photo.patches).max() < 0.01)
    ('detect', True)
    """
    how = check_option(layout, CHART_LAYOUTS, "chart layout (layout)")
    rows = as_int(rows, "rows", minimum=1)
    cols = as_int(cols, "cols", minimum=1)
    margin = as_real(margin, "margin")
    max_std = as_real(max_std, "max_std", nonnegative=True)
    saturation = as_real(saturation, "saturation", positive=True)
    min_score = as_real(min_score, "min_score", minimum=-1.0, maximum=1.0)
    max_size = as_int(max_size, "max_size", minimum=64, maximum=100_000)
    label = str(name)
    if how == "detect" and (rows, cols) != (4, 6):
        raise InvalidInputError(
            f"layout='detect' finds the 4x6 ColorChecker only, got rows x cols = {rows}x{cols}"
        )
    if how == "cropped":
        return _cropped(image_in(image, label), rows, cols, margin, max_std, saturation)
    rgb = image_in(image, label)
    if rgb.ndim != 3:
        raise InvalidInputError(f"expected {label} of shape (H, W, 3), got {describe(rgb)}")
    if how == "auto":
        colorchecker = (rows, cols) == (4, 6)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ChartWarning)
            try:
                grid: ChartSample | None = _cropped(rgb, rows, cols, margin, max_std, saturation)
            except InvalidInputError:  # too small for the grid, or no flat cell at all
                if not colorchecker:  # nothing else to try: the grid's own message
                    raise
                grid = None
        if grid is not None and _looks_cropped(grid.patches, rows, cols, min_score):
            for w in caught:
                warnings.warn(w.message, w.category, stacklevel=2)
            return grid
        if not colorchecker:
            raise ChartNotFoundError(
                f"{label} is not a {rows}x{cols} chart that fills the frame (detection finds "
                "the 4x6 ColorChecker only); crop it to the chart"
            )
    if is_dask(rgb):
        rgb = np.asarray(rgb.compute())
    det = detect_colorchecker(rgb, max_size=max_size, min_score=min_score)
    if not det.found:
        grid_note = "" if how == "detect" else "neither a chart that fills the frame nor "
        raise ChartNotFoundError(
            f"no ColorChecker found in {label} ({grid_note}a chart in the photograph); pass "
            "layout='cropped' for a chart cropped to fill the frame, or the patch values"
        )
    pat = measure_chart_patches(
        rgb, det, max_std=max_std, saturation=saturation
    )  # its ChartWarning names the patches left out
    return ChartSample(pat, "detect", det.corners, det.centers, det.quads, det)


def _as_chart_patches(chart: object, name: str, layout: str = "auto") -> Any:
    """Return ``chart`` as patch values.

    A :class:`ChartSample`'s patches, an image's (through :func:`sample_chart`), or ``chart``
    itself (a ChartPatches or an (N, 3) array).
    """
    if isinstance(chart, ChartSample):
        return chart.patches
    if isinstance(chart, ChartPatches):
        return chart
    if getattr(chart, "ndim", None) == 3 or (
        not hasattr(chart, "ndim") and isinstance(chart, list | tuple) and np.ndim(chart) == 3
    ):
        return sample_chart(chart, layout, name=name).patches
    return chart


def _neutral_reference(idx: np.ndarray, space: str) -> np.ndarray:
    """Return the neutral patches' published values in linear ``space``, adapted to its white.

    The chart's sRGB values (D65) go to XYZ, are adapted to the space's white by Bradford's
    transform (a balanced image shows the space's white as neutral) and converted to the
    space's linear RGB.
    """
    from imageform.analysis.synthetic import COLORCHECKER_SRGB8
    from imageform.color import (
        RGB_SPACES,
        chromatic_adaptation,
        linear_rgb_to_xyz,
        xyz_to_linear_rgb,
    )

    ref = srgb_decode(np, np.asarray(COLORCHECKER_SRGB8, dtype=np.float64)[idx] / 255.0)
    if space == "srgb":
        return np.asarray(ref)
    xyz = np.asarray(linear_rgb_to_xyz(ref, "srgb"), dtype=np.float64)
    white = RGB_SPACES[space].white_xy
    if not np.allclose(white, RGB_SPACES["srgb"].white_xy):
        xyz = np.asarray(chromatic_adaptation(xyz, "D65", np.asarray(white)), dtype=np.float64)
    return np.asarray(xyz_to_linear_rgb(xyz, space), dtype=np.float64)


def _neutral_illuminant(
    pat: ChartPatches,
    neutrals: tuple[int, ...],
    transfer: str = "srgb",
    space: str = "srgb",
) -> np.ndarray:
    r"""Estimate the illuminant's linear RGB from the neutral patches.

    :math:`e_c = \sum_i m_{ic} r_{ic} / \sum_i r_{ic}^2` (least squares of measured = e × ref),
    the measured means decoded with ``transfer``, the references in linear ``space``.
    """
    from imageform.color import decode

    if pat.means.shape[0] != 24:
        raise InvalidInputError(
            f"expected the 24 patches of a ColorChecker, got {pat.means.shape[0]} patches"
        )
    idx = np.array([k for k in neutrals if pat.valid[k]], dtype=int)
    if idx.size == 0:
        raise DegenerateConfigurationError(
            f"every neutral patch {list(neutrals)} of the chart is saturated or missing: no "
            "white balance from it"
        )
    ref = _neutral_reference(idx, space)
    meas = np.asarray(
        decode(np.clip(np.asarray(pat.means, dtype=np.float64)[idx], 0.0, None), transfer),
        dtype=np.float64,
    )
    e = np.sum(meas * ref, axis=0) / np.sum(ref * ref, axis=0)
    if not np.all(e > 0):
        raise DegenerateConfigurationError(
            f"the chart's neutral patches give a zero channel (illuminant {e.tolist()})"
        )
    return np.asarray(e)


def _balance_block(
    rgb: np.ndarray, gains: np.ndarray, clip: bool, transfer: str = "srgb"
) -> np.ndarray:
    from imageform.color import decode, encode

    if transfer == "srgb":  # the common case, without the generic dispatch
        lin = srgb_decode(np, rgb) * gains.astype(rgb.dtype)
    else:
        lin = np.asarray(decode(rgb, transfer)) * gains.astype(rgb.dtype)
    if clip:
        lin = np.clip(lin, 0.0, 1.0)
    out = srgb_encode(np, lin) if transfer == "srgb" else encode(lin, transfer)
    return np.asarray(out, dtype=rgb.dtype)


def chart_white_balance(
    image: ArrayLike,
    chart: ArrayLike | ChartSample | ChartPatches | None = None,
    *,
    chart_layout: str = "auto",
    normalize: str = "mean",
    clip: bool = False,
    transfer: str = "srgb",
    space: str = "srgb",
) -> WhiteBalanceResult:
    r"""White-balance an image from the neutral patches of a ColorChecker.

    The illuminant's linear RGB is fitted on the chart's grey row (patches 18-23, those
    neither saturated nor missing), :math:`e_c = \sum_i m_{ic} r_{ic} / \sum_i r_{ic}^2`
    with :math:`m_i` the measured and :math:`r_i` the published linear values, and divided
    out as :func:`imageform.color.white_balance` does:

    .. math:: \rho'_c = g_c \rho_c,\quad g_c = \bar e / e_c\ (\text{normalize="mean"}),
        \quad g_c = e_G / e_c\ (\text{normalize="green"})

    Parameters
    ----------
    image : array_like, shape (H, W, 3)
        Encoded sRGB (uint8, uint16, floats in [0, 1]; Dask chunk-wise) to balance.
    chart : optional
        Where the chart is: an image with a ColorChecker in it (cropped to fill the frame,
        or a photograph: see :func:`sample_chart`), a :class:`ChartSample`, a
        :class:`~imageform.analysis.ChartPatches` or the (24, 3) patch means (encoded
        sRGB). Default: ``image`` itself (the photograph holds the chart).
    chart_layout : {"auto", "cropped", "detect"}, keyword-only
        How the chart is found in an image (:func:`sample_chart`).
    normalize : {"mean", "green"}, keyword-only
        Keep the mean grey of the illuminant, or the green channel.
    clip : bool, keyword-only
        Clip the balanced linear values to [0, 1] before encoding.
    transfer : str, keyword-only
        The image's (and the chart's patch means') encoding, a key of
        :data:`imageform.color.TRANSFER_FUNCTIONS`: ``"srgb"``, ``"linear"`` for linear
        light, ``"adobe_rgb"``, ``"prophoto"``, ... (what the file declares).
    space : str, keyword-only
        The image's RGB space (a key of :data:`imageform.color.RGB_SPACES`): the chart's
        published neutrals are taken into it (Bradford-adapted to its white, so ProPhoto's
        D50 white counts as neutral) before the fit.

    Returns
    -------
    imageform.color.WhiteBalanceResult
        ``(image, gains)``: the balanced image (floats, encoded with ``transfer``) and the
        gains (3,).

    Raises
    ------
    ChartNotFoundError
        No chart in ``chart`` (or in ``image``).
    DegenerateConfigurationError
        Every neutral patch saturated or missing.

    Notes
    -----
    Von Kries diagonal gains (J. von Kries 1905; the form of
    :func:`imageform.color.white_balance`), the illuminant measured on the grey patches of a
    chart of known reflectance, as raw converters' "white balance from a grey card" do.

    Examples
    --------
    >>> from imageform.analysis import synthetic_chart_photo
    >>> photo = synthetic_chart_photo(cast=(1.0, 0.8, 0.6), shading=0.0, noise=0.0, rng=3)
    >>> out, gains = chart_white_balance(photo.image)
    >>> (gains / gains[1]).round(2).tolist()
    [0.8, 1.0, 1.33]
    """
    norm = check_option(normalize, ("mean", "green"), "gain normalisation (normalize)")
    clip = as_bool(clip, "clip")
    check_option(chart_layout, CHART_LAYOUTS, "chart layout (chart_layout)")
    from imageform.color import RGB_SPACES, TRANSFER_FUNCTIONS

    transfer = check_option(transfer, tuple(TRANSFER_FUNCTIONS), "transfer function (transfer)")
    space = check_option(space, tuple(RGB_SPACES), "RGB space (space)")
    rgb = image_in(image)
    if rgb.ndim != 3:
        raise InvalidInputError(f"expected image of shape (H, W, 3), got {describe(rgb)}")
    src = rgb if chart is None else chart
    pat = _as_chart_patches(src, "image" if chart is None else "chart", chart_layout)
    if not isinstance(pat, ChartPatches):
        arr = as_real_ndarray(pat, "image" if chart is None else "chart", finite=False)
        if arr.shape != (24, 3) or not np.all(np.isfinite(arr)):
            raise InvalidInputError(
                f"expected chart as an image, ChartPatches or (24, 3) finite patch means, got "
                f"{describe(pat)}"
            )
        pat = ChartPatches(arr, np.zeros_like(arr), np.zeros(24, bool), np.zeros(24, bool))
    e = _neutral_illuminant(pat, COLORCHECKER_NEUTRALS, transfer, space)
    ref = float(np.mean(e)) if norm == "mean" else float(e[1])
    gains = ref / e
    if is_dask(rgb):
        out = rgb.map_blocks(_balance_block, gains, clip, transfer, dtype=rgb.dtype)
    else:
        out = _balance_block(np.asarray(rgb), gains, clip, transfer)
    return WhiteBalanceResult(out, gains)
