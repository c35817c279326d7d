r"""Stain separation and normalisation in optical density (Macenko 2009, Vahadane 2016).

Bright-field microscopy obeys Beer-Lambert: the optical density of each RGB channel,
:math:`OD = -\ln(I / I_0)`, is linear in the stain concentrations, :math:`OD = C S` with
one row of ``S`` per stain. Macenko's method finds the two stain vectors as the extreme
directions of the tissue's OD cloud in its principal plane; Vahadane's
(:func:`vahadane_stains`) as a sparse non-negative factorisation. Both rescale
the concentrations to a target's.

Convention (the reference code's, since 0.x): natural-log OD, the incident light
:math:`I_0` estimated from the slide's background (or given), the transparent-pixel
threshold β = 0.15 applied to that OD. The earlier convention (log10, I₀ = 1) is
``base="10", i0=1.0``; β = 0.15 there equals β = 0.345 in ln units, which drops most
eosin-stained pixels of real H&E tiles.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any, Literal

import numpy as np

from imageform import _deprecate
from imageform._typing import Array, ArrayLike
from imageform._validate import (
    as_float,
    as_int,
    as_matrix,
    as_real,
    check_nonzero_rows,
    check_option,
    describe,
    format_shape,
    real_array,
)
from imageform.analysis._arrays import (
    image_in,
    is_dask,
    read_json,
    target_source,
    write_json,
)
from imageform.analysis._blockpass import BlockPasses, Family, block_quantiles
from imageform.analysis._sparse_nmf import lattice_rows, sparse_nmf
from imageform.analysis._tissue_rules import DEFAULTS as MASK_DEFAULTS
from imageform.analysis._tissue_rules import keep_mask, pixel_artefacts
from imageform.errors import DegenerateConfigurationError, InvalidInputError

__all__ = [
    "I0_SOURCES",
    "MIN_INTENSITY",
    "OD_BASES",
    "REFERENCE_I0",
    "STAIN_VECTOR_METHODS",
    "TRANSPARENT_RULES",
    "BackgroundEstimate",
    "MacenkoStains",
    "background_intensity",
    "estimate_background",
    "macenko_normalize",
    "macenko_stains",
    "optical_density",
    "stain_angle",
    "stain_concentrations",
    "vahadane_stains",
]

#: Default floor of intensities before the logarithm: the smallest non-zero 8-bit code.
MIN_INTENSITY = 1.0 / 255.0

#: The incident light of Macenko's reference code and torchstain (``Io = 240`` of 255),
#: the fallback of ``i0="auto"`` when a tile has no background.
REFERENCE_I0 = 240.0 / 255.0

#: Logarithm bases of the optical density: ``"e"`` (reference code, default) or ``"10"``.
OD_BASES = ("e", "10")


_LN10 = float(np.log(10.0))

#: The most alternating rounds :func:`vahadane_stains` runs (it stops earlier on convergence).
MAX_ITERATIONS = 100_000


def _base(base: object) -> str:
    return check_option(str(base) if isinstance(base, int) else base, OD_BASES, "OD log base")


def _i0_value(i0: object, name: str = "i0", *, complete: bool = False) -> np.ndarray:
    """Return a given incident light: a scalar or three values in (0, 1] (``complete``: three)."""
    v = np.full(1, np.nan)
    try:
        raw = np.asarray(i0)
        if raw.dtype.kind in "iuf":  # never bool, complex, object or strings
            v = raw.astype(np.float64)
    except (TypeError, ValueError, RuntimeError):
        pass
    if complete and v.shape != (3,):
        v = np.full(1, np.nan)
    if v.shape not in ((), (3,)) or not np.all((v > 0.0) & (v <= 1.0)):
        raise InvalidInputError(
            f"expected {name} = 'auto', a number or 3 numbers in (0, 1] (encoded intensity "
            f"of the background, 240/255 in the reference code), got {describe(i0)}"
        )
    return np.broadcast_to(v, (3,)).copy()


#: Where the incident light of :attr:`MacenkoStains.i0` came from: measured on the slide's
#: glass, the reference code's default (:data:`REFERENCE_I0`, no glass found) or given.
I0_SOURCES = ("glass", "default", "given")


@dataclass(frozen=True)
class BackgroundEstimate:
    """The incident light :math:`I_0` and whether it was measured on glass.

    ``i0`` (3,) is the estimate, or :data:`REFERENCE_I0` for every channel when no glass was
    found (``found`` False; ``reason`` says why, in one line, and is empty otherwise).
    ``glass_fraction`` is the share of the pixels within ``max_tint`` of ``i0`` in every
    channel (the glass; of the candidate when no glass was found, 0 when the candidate was
    rejected before counting).
    """

    i0: np.ndarray
    found: bool
    glass_fraction: float
    reason: str = ""


def _glass_mode(flat: Any, cand: np.ndarray, tol: float) -> tuple[np.ndarray, float]:
    """Per-channel mode of the pixels within ``tol`` (ln units) of ``cand`` in every channel.

    Histograms of those pixels in bins of one 8-bit code, smoothed by (1, 2, 1)/4; the mode
    is the centroid of the tallest bin and its two neighbours (sub-code). Also returns the
    share of such pixels (the mode is ``cand`` when there are none).
    """
    lo, hi = cand * np.exp(-tol), cand * np.exp(tol)
    parts: list[Any]

    def histograms(arr: np.ndarray) -> list[Any]:
        # channel by channel (a reduction over a last axis of 3 is slow): the same pixels
        near = (arr[:, 0] >= lo[0]) & (arr[:, 0] <= hi[0])
        for c in (1, 2):
            near &= (arr[:, c] >= lo[c]) & (arr[:, c] <= hi[c])
        sel = arr[near]
        out = [np.array(sel.shape[0])]
        for c in range(3):
            v = sel[:, c].astype(np.float64)
            idx = np.clip((v * 255.0 + 0.5).astype(np.int64), 0, 255)
            out += [np.bincount(idx, minlength=256), np.bincount(idx, weights=v, minlength=256)]
        return out

    if isinstance(flat, BlockPasses):  # Dask: one task per block
        got = flat.run(lambda a, u, i: {f"sum:{k}": h for k, h in enumerate(histograms(a))})
        parts = [got[f"sum:{k}"] for k in range(7)]
        rows = flat.rows
    else:
        parts = histograms(np.asarray(flat))
        rows = int(flat.shape[0])
    count = float(parts[0])
    share = count / max(rows, 1)
    if count == 0.0:
        return np.asarray(cand, dtype=np.float64), 0.0
    mode = np.empty(3)
    for c in range(3):
        counts = np.asarray(parts[1 + 2 * c], dtype=np.float64)
        sums = np.asarray(parts[2 + 2 * c], dtype=np.float64)
        smooth = np.convolve(counts, [0.25, 0.5, 0.25], mode="same")
        k = int(np.argmax(smooth))
        sl = slice(max(k - 1, 0), k + 2)
        mode[c] = sums[sl].sum() / counts[sl].sum()
    return mode, share


#: Rounds of :func:`_climb` (each moves I0 by at most ``max_tint``; it stops when I0 stays).
_GLASS_ROUNDS = 8


def _climb(
    flat: Any, mode: np.ndarray, share: float, tol: float, min_background: float
) -> tuple[np.ndarray, float]:
    """Re-centre the window on the mode until it stays (hill-climbing to the glass's mode).

    The percentile can lie more than ``tol`` above the glass in one channel (the noise tail,
    a brighter strip of glass), and then the window around it misses most of the glass. A
    move that would leave the glass (darker than ``min_background`` or tinted by more than
    ``tol``) is not taken.
    """
    for _ in range(_GLASS_ROUNDS):
        moved, near = _glass_mode(flat, mode, tol)
        if near == 0.0 or not np.all(moved >= min_background):
            break
        if float(np.log(moved.max() / moved.min())) > tol:
            break
        step = float(np.max(np.abs(moved - mode)))
        mode, share = moved, near
        if step < 0.5 / 255.0:
            break
    return mode, share


def estimate_background(
    image: ArrayLike,
    *,
    percentile: float = 99.0,
    min_background: float = 0.8,
    max_tint: float = 0.04,
    min_glass: float = 0.01,
) -> BackgroundEstimate:
    r"""Incident light :math:`I_0` per channel from the slide's glass, or the default.

    No pixel of a bright-field slide transmits more than the incident light, and the glass
    is the brightest part of a tile: the candidate is the ``percentile``-th percentile of
    each channel (a robust maximum). It is glass only when

    1. it is bright: at least ``min_background`` in every channel;
    2. it is neutral, as a white-balanced scanner renders glass:
       :math:`\ln(\max_c I_c / \min_c I_c) \le` ``max_tint`` (pale tissue is tinted:
       eosin absorbs green, hematoxylin red and green);
    3. pixels form a bright mode there: at least ``min_glass`` of them lie within
       ``max_tint`` of it in every channel (the per-channel percentiles of two tissues, one
       pink and one blue, can make a neutral candidate that no pixel is near).

    :math:`I_0` is then the glass's most frequent value, not the percentile: the percentile
    lies in the upper tail of the glass's noise, JPEG ringing and brighter strips of glass
    (4-10 codes above the glass on real scans), so glass rendered darker than it comes out
    stained after normalisation. Per channel, the histogram (bins of one 8-bit code,
    smoothed by (1, 2, 1)/4) of the pixels within ``max_tint`` of the current estimate in
    every channel gives the mode (centroid of the tallest bin and its neighbours); the
    window is re-centred on it until it stays (at most 8 rounds; a move to a darker than
    ``min_background`` or tinted mode is not taken). HistomicsTK likewise takes the median
    of the background pixels.

    Otherwise the tile has no glass and :math:`I_0` is :data:`REFERENCE_I0` (240/255,
    Macenko's reference code and torchstain) for every channel, with ``found`` False and the
    failed check in ``reason``.

    Parameters
    ----------
    image : array_like, shape (..., 3)
        Encoded RGB (uint8/uint16/floats in [0, 1]) or Dask (block-wise passes, exact
        percentiles: the same I0).
    percentile : float
        Percentile of each channel taken as the candidate (99: at least 1 % glass).
    min_background : float
        The darkest glass accepted, in (0, 1].
    max_tint : float
        The largest spread of the glass between channels, and of glass pixels around
        :math:`I_0`, in ln units (0.04: about 10 codes of 255 at 240), in [0, 1].
    min_glass : float
        The smallest share of pixels in the bright mode, in [0, 1].

    Returns
    -------
    BackgroundEstimate

    Notes
    -----
    Source: Macenko et al. 2009, sec. 2 (I₀, "the intensity of the incident light"; the
    reference code fixes it at 240 of 255); the mode as a background estimate: HistomicsTK's
    ``background_intensity`` (median of background samples).

    Examples
    --------
    >>> img = np.full((10, 10, 3), 0.3); img[:2] = (0.95, 0.94, 0.96)
    >>> est = estimate_background(img)
    >>> est.found, est.i0.round(2).tolist(), est.glass_fraction
    (True, [0.95, 0.94, 0.96], 0.2)
    >>> pale = np.full((10, 10, 3), (0.94, 0.83, 0.93))  # pale eosin, no glass
    >>> est = estimate_background(pale)
    >>> est.found, est.i0.round(4).tolist()
    (False, [0.9412, 0.9412, 0.9412])
    >>> print(est.reason)
    no glass: the brightest pixels (0.94, 0.83, 0.93) are tinted (0.12 > max_tint 0.04 in ln units)
    """
    rgb = image_in(image, nonempty=True)
    percentile = as_real(percentile, "percentile", minimum=0.0, maximum=100.0)
    min_background = as_real(min_background, "min_background")
    if not 0.0 < min_background <= 1.0:
        raise InvalidInputError(
            f"expected min_background in (0, 1], got {describe(min_background)}"
        )
    max_tint = as_real(max_tint, "max_tint", minimum=0.0, maximum=1.0)
    min_glass = as_real(min_glass, "min_glass", minimum=0.0, maximum=1.0)
    flat: Any = rgb.reshape((-1, 3))
    if is_dask(flat):  # block-wise passes (the percentiles: a histogram over [0, 1], a gather)
        flat = BlockPasses(rgb)

        def channel(c: int) -> Any:
            return lambda a, u: a[:, c]

        q = (float(percentile),)
        fams = [Family(f"c{c}", channel(c), flat.rows, 0.0, 1.0, q) for c in range(3)]
        i0 = np.array([row[0] for row in block_quantiles(flat, fams)])
    else:  # channel by channel, as float64 (a contiguous copy partitions faster): the same
        arr = np.asarray(flat)
        i0 = np.array([np.percentile(arr[:, c].astype(np.float64), percentile) for c in range(3)])
    default = np.full(3, REFERENCE_I0)
    seen = "(" + ", ".join(f"{v:.2f}" for v in i0) + ")"
    if not np.all(i0 >= float(min_background)):
        why = f"the brightest pixels {seen} are darker than min_background {min_background:g}"
        return BackgroundEstimate(default, False, 0.0, f"no glass: {why}")
    tint = float(np.log(i0.max() / i0.min()))
    if tint > max_tint:
        why = (
            f"the brightest pixels {seen} are tinted ({tint:.2f} > max_tint {max_tint:g} "
            "in ln units)"
        )
        return BackgroundEstimate(default, False, 0.0, f"no glass: {why}")
    mode, share = _glass_mode(flat, i0, float(max_tint))
    if share >= min_glass:
        mode, share = _climb(flat, mode, share, float(max_tint), float(min_background))
    if share < min_glass:
        why = (
            f"{share:.2%} of the pixels are near {seen} (within max_tint {max_tint:g}), "
            f"fewer than min_glass {min_glass:g}"
        )
        return BackgroundEstimate(default, False, share, f"no glass: {why}")
    # the percentile sits in the upper tail of the glass's noise and JPEG's ringing: I0 is
    # the glass's most frequent intensity
    return BackgroundEstimate(np.minimum(mode, 1.0), True, share)


def background_intensity(
    image: ArrayLike,
    *,
    percentile: float = 99.0,
    min_background: float = 0.8,
    max_tint: float = 0.04,
    min_glass: float = 0.01,
) -> np.ndarray:
    """Incident light :math:`I_0` per channel: :func:`estimate_background`'s ``i0``.

    The ``percentile``-th percentile of each channel when it is glass (bright, neutral and
    the centre of a bright mode, see :func:`estimate_background`), else :data:`REFERENCE_I0`
    (240/255, Macenko's reference code) for every channel.

    Parameters
    ----------
    image : array_like, shape (..., 3)
        Encoded RGB (uint8/uint16/floats in [0, 1]) or Dask (block-wise passes, exact
        percentiles: the same I0).
    percentile, min_background, max_tint, min_glass
        As in :func:`estimate_background`.

    Returns
    -------
    ndarray, shape (3,)
        :math:`I_0` as encoded intensity in (0, 1].

    Examples
    --------
    >>> img = np.full((10, 10, 3), 0.3); img[:2] = (0.95, 0.94, 0.96)
    >>> background_intensity(img).round(2).tolist()
    [0.95, 0.94, 0.96]
    >>> background_intensity(np.full((4, 4, 3), 0.3)).round(4).tolist()  # no background
    [0.9412, 0.9412, 0.9412]
    """
    return estimate_background(
        image,
        percentile=percentile,
        min_background=min_background,
        max_tint=max_tint,
        min_glass=min_glass,
    ).i0


def _resolve_i0(image: object, i0: object) -> np.ndarray:
    return _resolve_i0_source(image, i0)[0]


def _resolve_i0_source(image: object, i0: object) -> tuple[np.ndarray, str]:
    """I0 and where it came from (:data:`I0_SOURCES`).

    A :class:`BackgroundEstimate` (of this image, made once by the caller) is taken as
    ``"auto"`` would make it: its ``i0``, from the glass or the default.
    """
    if isinstance(i0, BackgroundEstimate):
        return _i0_value(i0.i0, complete=True), "glass" if i0.found else "default"
    if isinstance(i0, str):
        if i0.strip().lower() != "auto":
            _i0_value(i0)  # raises with the message
        est = estimate_background(image)
        return est.i0, "glass" if est.found else "default"
    return _i0_value(i0), "given"


def optical_density(
    image: ArrayLike,
    *,
    min_intensity: float = MIN_INTENSITY,
    i0: Literal["auto"] | float | ArrayLike = 1.0,
    base: str = "e",
) -> Array:
    r"""Optical density per channel: :math:`OD = -\ln(\max(I, I_{min}) / I_0)`.

    ``I`` is the encoded value in [0, 1] read as transmitted intensity (as Macenko and
    Ruifrok do with 8-bit scans). A pixel of 0 has unbounded OD; it is read as
    ``min_intensity`` (default 1/255, the smallest non-zero 8-bit code) — an explicit,
    documented floor. Pixels brighter than :math:`I_0` have a negative OD.

    Parameters
    ----------
    image : array_like, shape (..., 3)
        Encoded RGB, uint8/uint16, or Dask (computed lazily).
    min_intensity : float
        Floor of intensities, in (0, 1].
    i0 : float or sequence of 3 floats or "auto"
        Incident light (encoded, in (0, 1]); ``"auto"``: :func:`background_intensity`.
    base : {"e", "10"}
        Logarithm base: natural (the reference code, torchstain; default) or decimal
        (Ruifrok & Johnston; imageform before this version). :math:`OD_{10} = OD_e/\ln 10`.

    Returns
    -------
    array, shape (..., 3)

    Notes
    -----
    Source: Ruifrok & Johnston 2001, eq. (1); Macenko et al. 2009, sec. 2.

    Examples
    --------
    >>> optical_density(np.array([0.1, 0.5, 0.01]), base="10").round(6).tolist()
    [1.0, 0.30103, 2.0]
    >>> optical_density(np.array([0.5, 1.0, 0.25])).round(6).tolist()
    [0.693147, 0.0, 1.386294]
    """
    rgb = image_in(image)
    min_intensity = as_real(min_intensity, "min_intensity")
    if not 0.0 < min_intensity <= 1.0:
        raise InvalidInputError(f"expected min_intensity in (0, 1], got {min_intensity!r}")
    key = _base(base)
    i0v = _resolve_i0(rgb, i0)
    floor = rgb.dtype.type(min_intensity)
    scale = (1.0 / _LN10) if key == "10" else 1.0
    if is_dask(rgb):
        import dask.array as da

        log_i0 = (np.log(i0v) * scale).astype(rgb.dtype)
        return log_i0 - da.log(da.maximum(rgb, floor)) * rgb.dtype.type(scale)
    if key == "10" and np.all(i0v == 1.0):
        return -np.log10(np.maximum(rgb, floor))
    log_i0 = (np.log(i0v) * scale).astype(rgb.dtype)
    return log_i0 - np.log(np.maximum(rgb, floor)) * rgb.dtype.type(scale)


def stain_angle(u: ArrayLike, v: ArrayLike) -> float:
    r"""Angle in degrees between two stain (OD) vectors: :math:`\arccos(\hat u \cdot \hat v)`.

    Examples
    --------
    >>> round(stain_angle([1, 0, 0], [1, 1, 0]), 6)
    45.0
    """
    a = real_array(u, "u", (3,))
    b = real_array(v, "v", (3,))
    na, nb = np.linalg.norm(a), np.linalg.norm(b)
    for name, n in (("u", na), ("v", nb)):
        if not n > 0.0:
            raise InvalidInputError(f"expected {name} as a non-zero stain vector, got length 0")
        if not np.isfinite(n):
            raise InvalidInputError(f"expected {name} with a finite length, got {n:g}")
    c = (a / na) @ (b / nb)
    return float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))))


@dataclass(frozen=True)
class MacenkoStains:
    """Stain matrix and 99th-percentile stain concentrations, with the convention of measurement.

    The stain matrix has rows for the first and second stain (unit OD vectors); the 99th-percentile
    concentration of each stain is ``max_concentrations``. The convention they were measured in: the
    incident light ``i0`` (per channel), the OD log ``base`` (the concentrations are in that base's
    units) and the estimator ``method``. ``n_pixels`` of the ``n_total`` pixels passed the
    transparent-pixel threshold. ``i0_source`` says where ``i0`` came from (:data:`I0_SOURCES`):
    ``"glass"`` (measured on the slide), ``"default"`` (no glass found: 240/255, the reference
    code's) or ``"given"``. ``mean_concentrations``: each stain's mean concentration over the
    same pixels as the percentile (the scale-invariant reference of
    :func:`macenko_normalize`'s ``reference="mean"``); None when unknown (a JSON file written
    before it).
    """

    stain_matrix: np.ndarray
    max_concentrations: np.ndarray
    n_pixels: int = 0
    i0: tuple[float, float, float] = (1.0, 1.0, 1.0)
    base: str = "e"
    method: str = "macenko"
    n_total: int = 0
    i0_source: str = "given"
    mean_concentrations: np.ndarray | None = None

    def __post_init__(self) -> None:
        """Two finite stain vectors of non-zero length, two finite concentrations."""
        s = real_array(self.stain_matrix, "stain_matrix", (2, 3))
        check_nonzero_rows(s, "stain_matrix")
        m = real_array(self.max_concentrations, "max_concentrations", (2,))
        object.__setattr__(self, "stain_matrix", s)
        object.__setattr__(self, "max_concentrations", m)
        object.__setattr__(self, "n_pixels", as_int(self.n_pixels, "n_pixels", minimum=0))
        object.__setattr__(self, "n_total", as_int(self.n_total, "n_total", minimum=0))
        i0 = _i0_value(self.i0, "i0", complete=True)
        object.__setattr__(self, "i0", (float(i0[0]), float(i0[1]), float(i0[2])))
        object.__setattr__(self, "base", _base(self.base))
        object.__setattr__(
            self, "method", check_option(self.method, STAIN_VECTOR_METHODS, "method")
        )
        object.__setattr__(self, "i0_source", check_option(self.i0_source, I0_SOURCES, "i0_source"))
        if self.mean_concentrations is not None:
            mean = real_array(self.mean_concentrations, "mean_concentrations", (2,))
            object.__setattr__(self, "mean_concentrations", mean)

    def to_json(self, path: str | Path) -> None:
        """Save as JSON (``kind: "macenko_stains"``)."""
        write_json(
            path,
            {
                "kind": "macenko_stains",
                "stain_matrix": np.asarray(self.stain_matrix).tolist(),
                "max_concentrations": np.asarray(self.max_concentrations).tolist(),
                "n_pixels": int(self.n_pixels),
                "i0": [float(v) for v in self.i0],
                "od_base": str(self.base),
                "method": str(self.method),
                "n_total": int(self.n_total),
                "i0_source": str(self.i0_source),
                **(
                    {}
                    if self.mean_concentrations is None
                    else {"mean_concentrations": np.asarray(self.mean_concentrations).tolist()}
                ),
            },
        )

    @classmethod
    def from_json(cls, path: str | Path) -> MacenkoStains:
        """Load stains saved by :meth:`to_json`.

        Files without ``od_base`` were written before the ln convention: they are read as base 10
        with I₀ = 1.
        """
        d = read_json(path, "macenko_stains")
        try:
            s = as_matrix(d["stain_matrix"], "stain_matrix", (2, 3), batch=False)
            m = np.asarray(d["max_concentrations"], dtype=np.float64)
            n = int(d.get("n_pixels", 0))
            base = _base(str(d.get("od_base", "10")))
            i0 = _i0_value(d.get("i0", 1.0), "i0")
            method = check_option(str(d.get("method", "macenko")), STAIN_VECTOR_METHODS, "method")
            n_total = int(d.get("n_total", 0))
            i0_source = check_option(str(d.get("i0_source", "given")), I0_SOURCES, "i0_source")
            mean = d.get("mean_concentrations")
            mean = None if mean is None else np.asarray(mean, dtype=np.float64)
        except (KeyError, TypeError, ValueError) as exc:
            raise InvalidInputError(f"malformed Macenko stains in {path}: {exc}") from exc
        if m.shape != (2,):
            raise InvalidInputError(f"expected 2 max_concentrations in {path}, got {m.shape}")
        i0t = (float(i0[0]), float(i0[1]), float(i0[2]))
        s64 = np.asarray(s, dtype=np.float64)
        if mean is not None and mean.shape != (2,):
            raise InvalidInputError(f"expected 2 mean_concentrations in {path}, got {mean.shape}")
        return cls(s64, m, n, i0t, base, method, n_total, i0_source, mean)

    @property
    def fraction(self) -> float:
        """Fraction of the pixels that passed the transparent-pixel threshold (0 if unknown)."""
        return self.n_pixels / self.n_total if self.n_total else 0.0


def stain_concentrations(
    image: ArrayLike,
    stain_matrix: ArrayLike,
    *,
    min_intensity: float = MIN_INTENSITY,
    i0: float | ArrayLike = 1.0,
    base: str = "e",
) -> Array:
    r"""Colour deconvolution: least-squares concentrations :math:`C = OD\, S^+`.

    Parameters
    ----------
    image : array_like, shape (..., 3)
        RGB intensities (uint8, uint16 or floats on the scale of ``i0``).
    stain_matrix : array_like, shape (k, 3)
        One OD vector per stain (k = 2 or 3); with k = 3 this is Ruifrok's inversion.
    min_intensity, i0, base
        As in :func:`optical_density` (the concentrations are in ``base``'s units).

    Returns
    -------
    array, shape (..., k)

    Notes
    -----
    Source: Ruifrok & Johnston 2001, eq. (4)-(6); Macenko et al. 2009 (least squares).

    Examples
    --------
    >>> S = np.array([[0.6, 0.8, 0.0], [0.0, 0.6, 0.8]])
    >>> img = np.exp(-(np.array([0.5, 0.25]) @ S))
    >>> stain_concentrations(img, S).round(6).tolist()
    [0.5, 0.25]
    """
    s = np.asarray(as_float(stain_matrix, "stain_matrix"), dtype=np.float64)
    if s.shape not in ((2, 3), (3, 3)):
        raise InvalidInputError(
            f"expected stain_matrix of shape (2, 3) or (3, 3), got {format_shape(s.shape)}"
        )
    check_nonzero_rows(s, "stain_matrix")
    od = optical_density(image, min_intensity=min_intensity, i0=i0, base=base)
    pinv = np.linalg.pinv(s).astype(od.dtype)  # (3, k)
    return od @ pinv


#: Rules for transparent (background) pixels: drop a pixel when ...
TRANSPARENT_RULES: MappingProxyType[str, str] = MappingProxyType(
    {
        "any_channel": "any channel's OD < beta (Macenko's reference code)",
        "norm": "the OD vector's length ||OD||_2 < beta (keeps pure stains of any hue)",
    }
)


def _keep_mask(flat: Any, beta: float, rule: str) -> Any:
    if rule == "any_channel":
        return (flat >= beta).all(axis=1)
    return (flat * flat).sum(axis=1) >= beta * beta


def _count(keep: Any, beta: float, min_pixels: int, rule: str, what: str, use: Any = None) -> int:
    n = keep.astype(np.float64).sum()
    lost = 0 if use is None else (~use).astype(np.float64).sum()
    if is_dask(n):
        import dask

        n, lost = dask.compute(n, lost)
    return _enough(int(n), int(lost), beta, min_pixels, rule, what)


def _enough(n: int, lost: int, beta: float, min_pixels: int, rule: str, what: str) -> int:
    """``n``, or the refusal of a fit with fewer than ``min_pixels`` kept pixels."""
    if n < min_pixels:
        why = "is there tissue in the image?"
        if int(lost):
            why = (
                f"the tissue mask left out {int(lost)} pixels (pen ink, black ink, dark "
                "folds: mask=None keeps them)"
            )
        raise DegenerateConfigurationError(
            f"{what}: only {n} pixels have optical density >= beta={beta:g} (transparent "
            f"rule {rule!r}), fewer than min_pixels={describe(min_pixels, 24)}; {why}"
        )
    return n


def _fit(
    od: Any,
    beta: float,
    alpha: float,
    min_pixels: int,
    rule: str,
    what: str = "Macenko",
    use: Any = None,
) -> tuple[np.ndarray, int]:
    """Stain matrix (2, 3) from OD pixels in memory (Dask: :class:`_LazyFit`, same formulas).

    ``use``: flat booleans, the pixels a tissue mask keeps (None: all).
    """
    flat = od.reshape((-1, 3)).astype(np.float64)
    keep = _keep_mask(flat, beta, rule)
    if use is not None:
        keep = keep & use
    w = keep.astype(np.float64)
    n = _count(keep, beta, min_pixels, rule, what, use)
    # covariance of the kept OD vectors as sums, then its eigenvectors
    s1 = (flat * w[:, None]).sum(axis=0)
    s2 = [(flat[:, i] * flat[:, j] * w).sum() for i in range(3) for j in range(i, 3)]
    plane = _plane(n, np.asarray(s1), s2)
    proj = flat @ plane
    phi = np.arctan2(proj[:, 1], proj[:, 0])
    lo, hi = (float(v) for v in np.percentile(phi[keep], [alpha, 100.0 - alpha]))
    return _extremes(plane, lo, hi, n, beta, what), n


def _plane(n: int, s1: np.ndarray, s2: Any) -> np.ndarray:
    """Return the plane (3, 2) of the covariance's two largest eigenvectors, from its sums."""
    mean = s1 / n
    m2 = np.empty((3, 3))
    k = 0
    for i in range(3):
        for j in range(i, 3):
            m2[i, j] = m2[j, i] = float(s2[k]) - n * mean[i] * mean[j]
            k += 1
    cov = m2 / (n - 1)
    _, vecs = np.linalg.eigh(cov)
    plane = vecs[:, [2, 1]]  # the two largest
    return plane * np.where(plane[0] < 0, -1.0, 1.0)  # point along +R (Macenko's code)


def _extremes(plane: np.ndarray, lo: float, hi: float, n: int, beta: float, what: str) -> Any:
    """Return the stain matrix (2, 3) of the extreme angles ``lo``, ``hi`` in ``plane``."""
    v_min = plane @ np.array([np.cos(lo), np.sin(lo)])
    v_max = plane @ np.array([np.cos(hi), np.sin(hi)])
    # hematoxylin first: the vector with the larger red OD component (Macenko's heuristic)
    stains = np.stack([v_min, v_max] if v_min[0] > v_max[0] else [v_max, v_min])
    stains = stains / np.linalg.norm(stains, axis=1, keepdims=True)
    sv = np.linalg.svd(stains, compute_uv=False)
    if not sv[-1] > 1e-6 * sv[0]:
        raise DegenerateConfigurationError(
            f"{what}: the {n} pixels with optical density >= beta={beta:g} all have one "
            "colour (the extreme directions of their OD coincide), so two stains cannot be "
            "separated; is this a tile of one flat colour (blank, black, a pen mark)?"
        )
    return stains


#: Pixels within this of :math:`I_0` in every channel (ln units, :func:`estimate_background`'s
#: ``max_tint``) are glass for :func:`macenko_stains`'s maximum concentrations.
_GLASS_TOLERANCE = 0.04


def _max_conc(
    od: Any, stains: np.ndarray, percentile: float, base: str, use: Any = None
) -> tuple[np.ndarray, np.ndarray]:
    """Percentile and mean of each stain's concentration over the pixels that are not glass.

    Glass (every channel's OD within 0.04 of 0) holds no stain: counted,
    it would lower the percentile with the share of glass in the tile, and a tile that is
    mostly glass would be normalised several times darker than the same tissue without.
    """
    flat = od.reshape((-1, 3)).astype(np.float64)
    c = flat @ np.linalg.pinv(stains)
    tol = _GLASS_TOLERANCE / (_LN10 if base == "10" else 1.0)
    keep = (abs(flat) > tol).any(axis=1)
    if use is not None:
        keep = keep & use
    tissue = c[keep] if keep.any() else c
    return np.percentile(tissue, percentile, axis=0), tissue.mean(axis=0)


class _LazyFit:
    """A stain fit on Dask: :func:`_fit` and :func:`_max_conc` in block-wise passes.

    Each pass is one task per block of the OD (:mod:`._blockpass`) computing every statistic
    the step needs at once; the first keeps the tissue mask of each block (packed), so the
    mask's ``map_overlap`` runs once per fit, not once per reduction. Five passes (the
    covariance sums with the counts and the OD's range; a histogram and a gather for the
    two angles; the same for the two concentrations) where the Dask expressions took nine
    computations of the whole graph. The percentiles are exact (NumPy's).
    """

    def __init__(
        self, od: Any, use: Any, beta: float, rule: str, base: str, *, tissue: bool = False
    ) -> None:
        self.beta, self.rule = beta, rule
        self.tol = _GLASS_TOLERANCE / (_LN10 if base == "10" else 1.0)
        shape = tuple(od.shape[:-1])
        if use is not None and not is_dask(use):
            import dask.array as da

            use = da.from_array(np.asarray(use).reshape(shape), chunks=od.chunks[:-1])
        self.blocks = BlockPasses(od, None if use is None else use.reshape(shape))

        def stats(flat: np.ndarray, u: Any, index: Any) -> dict[str, Any]:
            keep = self._keep(flat, u)
            w = keep.astype(np.float64)
            glass = self._tissue(flat, u)
            out = {
                "sum:n": np.array([w.sum(), 0.0 if u is None else (~u).sum(), glass.sum()]),
                "sum:st": np.stack([flat[glass].sum(axis=0), flat.sum(axis=0)]),
                "sum:s1": (flat * w[:, None]).sum(axis=0),
                "sum:s2": np.array(
                    [(flat[:, i] * flat[:, j] * w).sum() for i in range(3) for j in range(i, 3)]
                ),
                "min:od": np.stack([_ends(flat[glass], np.min), _ends(flat, np.min)]),
                "max:od": np.stack([_ends(flat[glass], np.max), _ends(flat, np.max)]),
            }
            if tissue:  # the kept pixels themselves, with their flat positions
                out["cat:tissue"] = flat[keep]
                out["cat:index"] = index[keep]
            return out

        got = self.blocks.run(stats, index=tissue, keep_mask=True)
        self.n, self.lost, self.n_tissue = (int(v) for v in got["sum:n"])
        self.s1, self.s2, self.s_tissue = got["sum:s1"], got["sum:s2"], got["sum:st"]
        self.od_min, self.od_max = got["min:od"], got["max:od"]
        if tissue:
            order = np.argsort(got["cat:index"], kind="stable")
            self.tissue, self.index = got["cat:tissue"][order], got["cat:index"][order]

    def _keep(self, flat: np.ndarray, u: Any) -> Any:
        keep = _keep_mask(flat, self.beta, self.rule)
        return keep if u is None else keep & u

    def _tissue(self, flat: np.ndarray, u: Any) -> Any:
        keep = (abs(flat) > self.tol).any(axis=1)
        return keep if u is None else keep & u

    def stains(self, alpha: float, min_pixels: int, what: str) -> tuple[np.ndarray, int]:
        """:func:`_fit`'s stain matrix and kept-pixel count."""
        n = _enough(self.n, self.lost, self.beta, min_pixels, self.rule, what)
        plane = _plane(n, np.asarray(self.s1), self.s2)

        def angles(flat: np.ndarray, u: Any) -> np.ndarray:
            proj = flat @ plane
            return np.arctan2(proj[:, 1], proj[:, 0])[self._keep(flat, u)]

        fam = Family("phi", angles, n, -np.pi, np.pi, (alpha, 100.0 - alpha))
        lo, hi = block_quantiles(self.blocks, [fam])[0]
        return _extremes(plane, lo, hi, n, self.beta, what), n

    def max_conc(self, stains: np.ndarray, percentile: float) -> tuple[np.ndarray, np.ndarray]:
        """:func:`_max_conc`: each stain's percentile and mean over the pixels not glass."""
        pinv = np.linalg.pinv(stains)
        every = self.n_tissue == 0  # no pixel off the glass: all of them (as in memory)
        n = int(np.prod(self.blocks.od.shape[:-1])) if every else self.n_tissue
        lo, hi = self.od_min[1 if every else 0], self.od_max[1 if every else 0]
        fams = []
        for i in range(2):
            col = pinv[:, i]
            # the range of OD @ col over the box of the OD's range, widened by its rounding
            a = float(np.minimum(col * lo, col * hi).sum())
            b = float(np.maximum(col * lo, col * hi).sum())
            pad = 1e-9 * (abs(a) + abs(b) + 1.0)

            def conc(flat: np.ndarray, u: Any, i: int = i) -> np.ndarray:
                c = flat @ pinv
                return c[:, i] if every else c[:, i][self._tissue(flat, u)]

            fams.append(Family(f"c{i}", conc, n, a - pad, b + pad, (percentile,)))
        mean = np.asarray(self.s_tissue[1 if every else 0]) @ pinv / max(n, 1)
        return np.array([row[0] for row in block_quantiles(self.blocks, fams)]), mean


def _ends(x: np.ndarray, fn: Any) -> np.ndarray:
    """``fn`` (min or max) per channel of ``x`` (rows), or the identity of ``fn`` if none."""
    if x.shape[0]:
        return fn(x, axis=0)
    return np.full(3, np.inf if fn is np.min else -np.inf)


#: What ``mask=`` accepts in the stain estimators: ``"auto"`` (:func:`~imageform.analysis.
#: tissue_mask`'s artefact rules), ``None`` (every pixel) or booleans per pixel.
MASK_CHOICES = ("auto", "he", "none")


def _mask_flat(mask: object, rgb: Any, i0v: np.ndarray, found: dict[str, Any] | None = None) -> Any:
    """Flat booleans of the pixels to use, or None for all of them.

    ``"auto"``: :func:`~imageform.analysis.tissue_mask` without its glass rule (the
    transparent-pixel rule and the glass tolerance of the maximum concentrations are the
    estimators' own), with the estimator's I0. Under a wash of ink (in memory) the ink's
    OD, ln units, goes to ``found["ink_od"]`` (:func:`_without_ink`).
    """
    if mask is None:
        return None
    if isinstance(mask, str):
        key = check_option(mask, MASK_CHOICES, "mask")
        if key == "none":
            return None
        he: bool | str = True if key == "he" else "auto"  # auto: the H&E rules on H&E
        if rgb.ndim < 3:  # a list of pixels: the per-pixel rules, no neighbours
            return ~pixel_artefacts(rgb, i0v, he).reshape(-1)
        # under a wash of ink every pixel holds the ink's OD: the ink's is subtracted (dense
        # ink, or Dask: every pixel dropped)
        params = {**MASK_DEFAULTS, "he": he, "wash": "subtract"}
        return keep_mask(rgb, i0v, params, False, 0.0, found).reshape(-1)
    shape = tuple(rgb.shape[:-1])
    if not is_dask(mask):
        arr = np.asarray(mask)
        if arr.dtype != np.bool_ or tuple(arr.shape) != shape:
            raise InvalidInputError(
                f"expected mask as 'auto', None or booleans of shape {format_shape(shape)}, "
                f"got {describe(mask)}"
            )
        return arr.reshape(-1)
    lazy: Any = mask
    if np.dtype(lazy.dtype) != np.bool_ or tuple(lazy.shape) != shape:
        raise InvalidInputError(
            f"expected mask as 'auto', None or booleans of shape {format_shape(shape)}, "
            f"got {describe(mask)}"
        )
    return lazy.reshape(-1)


def _without_ink(od: Any, found: dict[str, Any], base: str) -> Any:
    """``od`` less the ink's OD that :func:`_mask_flat` found under a wash (Beer-Lambert)."""
    ink = found.get("ink_od")
    if ink is None:
        return od
    scale = 1.0 / _LN10 if base == "10" else 1.0
    return od - (ink * scale).astype(od.dtype)


def _check_params(beta: float, alpha: float, max_percentile: float) -> None:
    for name, val, lo, hi in (
        ("beta", beta, 0.0, 10.0),
        ("alpha", alpha, 0.0, 50.0),
        ("max_percentile", max_percentile, 0.0, 100.0),
    ):
        if not lo <= as_real(val, name) <= hi:
            raise InvalidInputError(f"expected {name} in [{lo:g}, {hi:g}], got {val!r}")


def macenko_stains(
    image: ArrayLike,
    *,
    beta: float = 0.15,
    alpha: float = 1.0,
    max_percentile: float = 99.0,
    min_pixels: int = 100,
    min_intensity: float = MIN_INTENSITY,
    transparent: Literal["any_channel", "norm"] = "any_channel",
    i0: Literal["auto"] | float | ArrayLike | BackgroundEstimate = "auto",
    base: str = "e",
    method: Literal["macenko", "vahadane"] = "macenko",
    mask: Literal["auto", "he", "none"] | ArrayLike | None = "auto",
) -> MacenkoStains:
    r"""Estimate the two stain vectors and their maximum concentrations (Macenko 2009).

    1. :math:`OD = -\ln(I / I_0)`, :math:`I_0` from the background
       (:func:`background_intensity`) or given; keep pixels with OD ≥ β in every channel
       that the tissue mask keeps (``mask``: by default pen ink, black ink and dark folds
       are dropped, :func:`~imageform.analysis.tissue_mask`).
    2. Eigenvectors of the covariance of the kept OD: the plane of the two largest.
    3. Angle of each projected pixel, :math:`\varphi = \operatorname{atan2}(t_2, t_1)`;
       the α-th and (100-α)-th percentiles of φ give the extreme stain vectors
       :math:`v = V(\cos\varphi, \sin\varphi)^T`, the one with larger red OD first
       (hematoxylin).
    4. Concentrations :math:`C = OD\, S^+` (least squares, all pixels); their 99th
       percentile per stain over the pixels that are not glass (glass: every channel's
       :math:`|OD| \le 0.04`, ``max_tint`` of :func:`estimate_background`)
       is the robust maximum. The reference code takes it over every pixel, glass
       included, so the maximum falls with the share of glass in the tile (a tile that is
       90 % glass is normalised several times darker than the same tissue without glass);
       on tiles without glass the two agree.
    5. Raises :class:`DegenerateConfigurationError` when the two vectors coincide (a tile of
       one flat colour: blank, black, a pen mark) rather than returning them.

    The defaults are the reference code's (Macenko's MATLAB code, its Python port
    ``HEnorm_python``, torchstain): ln OD, β = 0.15, α = 1. With I₀ = 240/255 given and
    8-bit input the stain vectors agree with torchstain 1.4.1 to 0.03° (see
    docs/biomedical.md). The former imageform convention, β on log10 OD with I₀ = 1, is
    ``base="10", i0=1.0``.

    Parameters
    ----------
    image : array_like, shape (..., 3)
        Encoded RGB of a bright-field slide (uint8/uint16/floats), or Dask: the covariance
        is a reduction and the percentiles are exact two-pass Dask quantiles, so the result
        equals the in-memory one.
    beta : float
        OD threshold for transparent (background) pixels, in ``base``'s units (0.15 in
        the paper and the reference code, ln units).
    alpha : float
        Percentile (in %) for the robust extreme angles (1 in the paper).
    max_percentile : float
        Percentile of concentrations taken as the maximum (99 in the paper), over the
        pixels that are not glass.
    min_pixels : int
        Fewer kept pixels raise :class:`DegenerateConfigurationError` (no tissue).
    min_intensity : float
        Floor of intensities before the logarithm (see :func:`optical_density`).
    transparent : {"any_channel", "norm"}
        Which pixels count as transparent: ``"any_channel"`` drops a pixel when any
        channel's OD is below β (Macenko's reference code); ``"norm"`` when
        :math:`\lVert OD \rVert_2 < \beta`. Stains that barely absorb in one channel
        (Ruifrok's eosin, OD 0.07 in red) lose their pure pixels under ``"any_channel"``
        and the estimated vector moves towards the other stain; use ``"norm"`` there.
    i0 : "auto" or float or sequence of 3 floats or BackgroundEstimate
        Incident light (encoded, in (0, 1]): ``"auto"`` estimates it from the background
        (:func:`background_intensity`; 240/255 when the tile has none). The
        :func:`estimate_background` of this image, made once, is taken as ``"auto"``
        would make it (``i0_source`` "glass" or "default"), without estimating it again
        (on a 6.6-megapixel slide the estimate takes about a tenth of this function's
        CPU time; :func:`~imageform.analysis.tissue_mask` takes it too).
    base : {"e", "10"}
        Logarithm base of the OD (see :func:`optical_density`).
    method : {"macenko", "vahadane"}
        ``"vahadane"`` delegates to :func:`vahadane_stains`
        (same I₀, base, β, ``max_percentile`` and ``mask``; ``alpha`` and ``transparent``
        unused).
    mask : "auto" or None or array_like of bool, shape (...)
        The pixels to estimate from (the stain vectors and the maximum concentrations):
        ``"auto"`` drops what :func:`~imageform.analysis.tissue_mask` finds as pen ink,
        black ink or a dark fold (its artefact rules; the glass is β's), and on an image
        that holds eosin (``he="auto"``: H&E, not IHC) brown margin dye and grey as
        ``"he"`` does (HistoQC's ``small_pen_green`` thumbnail: 34.1° -> 10.2° from the
        stains without its ink and dye; colour cannot tell the dye from DAB, the eosin
        around it can tell the slide from IHC), ``None`` or
        ``"none"`` uses every pixel (the reference code), booleans (True: use) a mask of
        your own. A flat marker covering 0.5-5 % of a tile turns a stain vector by up to
        27° without it. Under ink laid over the whole image (a wash, as
        :func:`~imageform.analysis.tissue_mask` finds it) every pixel holds the ink's OD,
        and by Beer-Lambert OD adds: ``"auto"`` subtracts the ink's OD at each pixel (the
        OD of the ink over glass nearby, averaged with a Gaussian weight of 16 pixels)
        and keeps the tissue under it. Where the ink over glass is dense (its median
        :math:`\lVert OD\rVert` over 1.1: a third of the light left) or there is none,
        or the image is Dask, every pixel is dropped and the estimate refused. On 43
        scanned blue-washed patches whose clean scan Macenko measures
        (smujiang/WSIPenMarkingRemoval) 25 are measured, 5.45° from the clean scan's
        stains at the median (90th percentile 14.8°); every pixel gives 26.7°.

    Returns
    -------
    MacenkoStains

    Notes
    -----
    Source: M. Macenko et al., "A method for normalizing histology slides for quantitative
    analysis", ISBI 2009, pp. 1107-1110, sec. 2 and Fig. 1; reference code
    github.com/mitkovetta/staining-normalization (Io = 240, beta = 0.15, alpha = 1).

    Examples
    --------
    >>> from imageform.analysis import synthetic_stain_image
    >>> img, S, _ = synthetic_stain_image(rng=0)
    >>> est = macenko_stains(img, transparent="norm", i0=1.0)  # the generator's I0
    >>> [round(stain_angle(est.stain_matrix[i], S[i]), 1) for i in range(2)]
    [0.4, 0.3]
    """
    m = check_option(method, STAIN_VECTOR_METHODS, "stain method")
    if m != "macenko":
        return STAIN_VECTOR_METHODS[m](
            image,
            beta=beta,
            max_percentile=max_percentile,
            min_pixels=min_pixels,
            min_intensity=min_intensity,
            i0=i0,
            base=base,
            mask=mask,
        )
    _check_params(beta, alpha, max_percentile)
    min_pixels = as_int(min_pixels, "min_pixels", minimum=0)
    rule = check_option(transparent, TRANSPARENT_RULES, "transparent-pixel rule")
    key = _base(base)
    rgb = image_in(image, nonempty=True)
    i0v, i0_from = _resolve_i0_source(rgb, i0)
    found: dict[str, Any] = {}
    use = _mask_flat(mask, rgb, i0v, found)
    od = _without_ink(
        optical_density(rgb, min_intensity=min_intensity, i0=i0v, base=key), found, key
    )
    if is_dask(od):
        fit = _LazyFit(od, use, float(beta), rule, key)
        stains, n = fit.stains(float(alpha), max(min_pixels, 2), "Macenko")
        maxc, meanc = fit.max_conc(stains, float(max_percentile))
    else:
        stains, n = _fit(od, float(beta), float(alpha), max(min_pixels, 2), rule, use=use)
        maxc, meanc = _max_conc(od, stains, float(max_percentile), key, use)
    n_total = int(np.prod(rgb.shape[:-1]))
    i0t = (float(i0v[0]), float(i0v[1]), float(i0v[2]))
    return MacenkoStains(stains, maxc, n, i0t, key, "macenko", n_total, i0_from, meanc)


def _target(target: object, **kw: Any) -> MacenkoStains:
    if isinstance(target, MacenkoStains):
        return target
    src = target_source(target, "target", "MacenkoStains")
    if isinstance(src, Path):
        return MacenkoStains.from_json(src)
    return macenko_stains(image_in(src, "target", nonempty=True), **kw)


#: The concentration references of :func:`macenko_normalize` (``reference``).
_CONCENTRATION_REFERENCES = ("max", "mean")


def _ln_units(st: MacenkoStains, reference: str = "max", name: str = "target") -> np.ndarray:
    """Return the reference concentrations in ln-OD units (base-10 ones times ln 10)."""
    if reference == "mean":
        if st.mean_concentrations is None:
            raise InvalidInputError(
                f"expected {name} stains with mean_concentrations for reference='mean' (a JSON "
                "file written before they were saved: measure the image again)"
            )
        m = np.asarray(st.mean_concentrations, dtype=np.float64)
    else:
        m = np.asarray(st.max_concentrations, dtype=np.float64)
    return m * _LN10 if _base(st.base) == "10" else m


#: Pixels per piece of :func:`_reconstruct` (its float64 temporaries stay in cache-sized runs).
_RECONSTRUCT_PIXELS = 1 << 16


def _reconstruct(
    od: np.ndarray,
    pinv_src: np.ndarray,
    scale: np.ndarray,
    stains_t: np.ndarray,
    i0_t: np.ndarray,
) -> np.ndarray:
    """``i0_t exp(-(OD S_s^+ diag(scale)) S_t)``: one 3 x 3 matrix, in pieces of pixels."""
    m = (pinv_src * scale) @ stains_t
    flat = od.reshape((-1, 3))
    out = np.empty(flat.shape, dtype=od.dtype)
    for k in range(0, flat.shape[0], _RECONSTRUCT_PIXELS):
        part = flat[k : k + _RECONSTRUCT_PIXELS].astype(np.float64) @ m
        np.negative(part, out=part)
        np.exp(part, out=part)
        part *= i0_t
        out[k : k + _RECONSTRUCT_PIXELS] = part
    return out.reshape(od.shape)


def macenko_normalize(
    image: ArrayLike,
    target: ArrayLike,
    *,
    source: MacenkoStains | None = None,
    beta: float = 0.15,
    alpha: float = 1.0,
    max_percentile: float = 99.0,
    min_pixels: int = 100,
    min_intensity: float = MIN_INTENSITY,
    transparent: Literal["any_channel", "norm"] = "any_channel",
    i0: Literal["auto"] | float | ArrayLike | BackgroundEstimate = "auto",
    base: str = "e",
    method: Literal["macenko", "vahadane"] = "macenko",
    mask: Literal["auto", "he", "none"] | ArrayLike | None = "auto",
    reference: Literal["max", "mean"] = "max",
) -> Array:
    r"""Re-render ``image`` with ``target``'s stain vectors and concentration range.

    .. math:: C = OD\,S_s^+, \quad C' = C \,\frac{C^{99}_t}{C^{99}_s}, \quad
        I' = I_{0,t}\, e^{-C' S_t}

    with OD taken with the source's :math:`I_0` and the output lit by the target's
    :math:`I_{0,t}` (its background). Stains measured in another base (a JSON file from
    before the ln convention) are converted: :math:`C_e = C_{10} \ln 10`. With
    ``reference="mean"`` the ratio is of the mean concentrations over the same pixels,
    :math:`\bar C_t / \bar C_s`, instead of the 99th percentiles.

    The 99th percentile depends on the pixel size: a pixel of a slide's lower pyramid level
    averages nuclei with the stroma around them, so the densest concentrations fall while
    their mean stays (a mean is linear; the percentile of a blurred map is not). A
    thumbnail normalised against a tile measured at full resolution comes out too dark:
    laurapurcaro-bit/FolDet's study 5 thumbnail, hematoxylin 99th percentile 0.73 against
    the dense target tile's 2.19 (its mean 0.31 against 0.37), CIEDE2000 from the target's
    mean tissue colour 13.2 (``"max"``) against 0.9 (``"mean"``). Six tiles area-averaged
    2, 4 and 8 times move the output's mean tissue colour by up to 16.2 (``"max"``) and
    3.0 (``"mean"``) from the full-resolution output's
    (benchmarks/results/stain-scale-2026-12-01e.md). ``"max"`` is the paper's (and
    torchstain's); use ``"mean"`` when the image and the target are at different pixel
    sizes or tissue densities.

    Parameters
    ----------
    image : array_like, shape (..., 3)
        Encoded RGB (uint8/uint16/floats) or Dask (statistics as exact reductions, the
        transform chunk-wise).
    target : array_like or MacenkoStains or path
        Target image, its :class:`MacenkoStains`, or a JSON file saved by
        :meth:`MacenkoStains.to_json`.
    source : MacenkoStains, optional
        Precomputed stains of ``image`` (their ``i0`` and ``base`` are used).
    beta, alpha, max_percentile, min_pixels, min_intensity, transparent, i0, base, method
        As in :func:`macenko_stains` (used for the image and for a target image; a
        :class:`BackgroundEstimate` given as ``i0`` is the image's, a target image gets
        ``"auto"``).
    mask : "auto" or None or array_like of bool
        The pixels of ``image`` the stains are estimated from, as in
        :func:`macenko_stains` (a target image gets ``"auto"`` when this is an array);
        every pixel is normalised.
    reference : {"max", "mean"}
        The concentrations matched: ``"max"`` the ``max_percentile``-th percentiles (Macenko
        2009), ``"mean"`` the means (:attr:`MacenkoStains.mean_concentrations`; stains
        loaded from a JSON file written before them raise :class:`InvalidInputError`).

    Returns
    -------
    array, shape (..., 3)
        Transmitted intensity in (0, I₀,t] for non-negative concentrations (negative
        least-squares concentrations can give values above it; nothing is clipped).

    Notes
    -----
    Source: Macenko et al. 2009, sec. 2 (normalisation step).

    Examples
    --------
    >>> from imageform.analysis import synthetic_stain_image
    >>> a, _, _ = synthetic_stain_image(max_concentration=(0.6, 1.0), rng=0)
    >>> b, _, _ = synthetic_stain_image(rng=1)
    >>> out = macenko_normalize(a, b, i0=1.0)  # the generator's I0 (no glass to estimate it)
    >>> mo, mb = macenko_stains(out, i0=1.0), macenko_stains(b, i0=1.0)
    >>> np.round(mo.max_concentrations / mb.max_concentrations, 2).tolist()
    [1.0, 0.99]
    """
    kw: dict[str, Any] = {
        "beta": beta,
        "alpha": alpha,
        "max_percentile": max_percentile,
        "min_pixels": min_pixels,
        "min_intensity": min_intensity,
        "transparent": transparent,
        "i0": i0,
        "base": base,
        "method": method,
    }
    if source is not None and not isinstance(source, MacenkoStains):
        raise TypeError(f"expected source as MacenkoStains or None, got {type(source).__name__}")
    ref = check_option(reference, _CONCENTRATION_REFERENCES, "concentration reference")
    tgt_mask = mask if mask is None or isinstance(mask, str) else "auto"
    # an estimate of the image's background is the image's: a target image gets its own
    tgt = _target(
        target, **{**kw, "i0": "auto" if isinstance(i0, BackgroundEstimate) else i0}, mask=tgt_mask
    )
    rgb = image_in(image, nonempty=True)
    src = macenko_stains(rgb, **kw, mask=mask) if source is None else source
    od = optical_density(rgb, min_intensity=min_intensity, i0=np.asarray(src.i0), base="e")
    src_max, tgt_max = _ln_units(src, ref, "source"), _ln_units(tgt, ref, "target")
    what = (
        "the means"
        if ref == "mean"
        else f"the max_percentile-th percentile, here {describe(max_percentile, 12)},"
    )
    for name, mx in (("source", src_max), ("target", tgt_max)):
        if np.any(np.asarray(mx) <= 0):
            raise DegenerateConfigurationError(
                f"Macenko: {name} {ref} concentrations "
                f"{np.round(np.asarray(mx), 4).tolist()} are not positive (they are "
                f"{what} of each stain's concentrations)"
            )
    scale = tgt_max / src_max
    sv = np.linalg.svd(np.asarray(src.stain_matrix, dtype=np.float64), compute_uv=False)
    if not sv[-1] > 1e-6 * sv[0]:
        raise DegenerateConfigurationError(
            "Macenko: source stain_matrix is singular (its two stain vectors are parallel)"
        )
    pinv_src = np.linalg.pinv(np.asarray(src.stain_matrix))
    args = (
        pinv_src,
        scale,
        np.asarray(tgt.stain_matrix, dtype=np.float64),
        np.asarray(tgt.i0, dtype=np.float64),
    )
    if is_dask(od):
        return od.map_blocks(_reconstruct, *args, dtype=od.dtype)
    return _reconstruct(od, *args)


def vahadane_stains(
    image: ArrayLike,
    *,
    lam: float = 0.1,
    beta: float = 0.15,
    max_percentile: float = 99.0,
    min_pixels: int = 100,
    min_intensity: float = MIN_INTENSITY,
    i0: Literal["auto"] | float | ArrayLike | BackgroundEstimate = "auto",
    base: str = "e",
    max_pixels: int = 20_000,
    iterations: int = 1000,
    mask: Literal["auto", "he", "none"] | ArrayLike | None = "auto",
) -> MacenkoStains:
    r"""Estimate two stain vectors by sparse non-negative factorisation (Vahadane 2016).

    1. :math:`OD = -\ln(I / I_0)` (:math:`I_0` as in
       :func:`~imageform.analysis.macenko_stains`); tissue pixels are those with
       :math:`\lVert OD \rVert_2 \ge \beta` (Vahadane's code thresholds luminance;
       the OD norm is the same idea in OD units).
    2. Sparse NMF of the tissue OD (at most ``max_pixels`` of them, on a fixed lattice):
       :math:`\min \tfrac{1}{2n}\lVert OD - WH\rVert_F^2 + \tfrac{\lambda}{n}
       \lVert W\rVert_1` with :math:`W, H \ge 0`, :math:`\lVert h_k\rVert_2 \le 1`,
       started from Macenko's vectors (Vahadane et al. 2016, eq. (3)-(4)).
       Solved in NumPy by block-coordinate descent: each round solves the codes ``W``
       exactly (two atoms: a closed form per pixel) and then the 2 x 3 dictionary ``H``
       (projected gradient to convergence), so the objective never increases. It stops
       when a round changes ``H`` by less than :math:`10^{-7}` relatively
       (:math:`\lVert H_k - H_{k-1}\rVert_F < 10^{-7} \lVert H_k\rVert_F`) or after
       ``iterations`` rounds (the tests' crops: 65-139). The reference implementations
       (Vahadane's MATLAB code, StainTools) use SPAMS' online dictionary learning
       (``trainDL``) on the same objective with no convergence test: StainTools keeps
       SPAMS' default ``iter=-1``, one second of mini-batches of 512 pixels from random
       starts; run 3000 rounds, SPAMS gives these vectors to 0.01-1.1 deg
       (``tests/analysis/test_tissue_mask.py``).
       The pixels factorised are those of the tissue with the ``max_pixels`` smallest
       keys ``position x 0x9E3779B97F4A7C15 mod 2**64`` (Fibonacci hashing, spread evenly
       over the image): a pixel more or less in the mask changes at most one of them, so
       the result does not move with a few mask pixels (< 0.001 deg measured).
    3. Rows of ``H`` normalised, hematoxylin (larger red OD) first; the concentrations
       and their 99th percentile as in Macenko (least squares over all pixels, the
       percentile over those that are not glass), so the
       result normalises with :func:`~imageform.analysis.macenko_normalize`.

    Parameters
    ----------
    image : array_like, shape (..., 3)
        Encoded RGB of a bright-field slide (uint8/uint16/floats) or Dask (the tissue
        pixels are gathered into memory, at most ``max_pixels`` of them are used).
    lam : float
        Sparsity weight λ (0.1 in the paper and StainTools), per pixel.
    beta : float
        Tissue threshold on the OD norm, in ``base``'s units.
    max_percentile, min_pixels, min_intensity, i0, base
        As in :func:`~imageform.analysis.macenko_stains`.
    max_pixels : int
        Tissue pixels used by the factorisation (the fixed lattice above). The objective
        can be flat: on one of the tests' crops two lattices of 20 000 of its 64 826
        tissue pixels give vectors up to 5.45 deg apart (0.13 deg on the other); more
        pixels, slower and steadier.
    iterations : int
        At most this many rounds (they stop earlier on convergence, above).
    mask : "auto" or None or array_like of bool
        As in :func:`~imageform.analysis.macenko_stains` (by default pen ink, black ink
        and dark folds are not factorised).

    Returns
    -------
    MacenkoStains
        With ``method = "vahadane"``.

    Notes
    -----
    Source: A. Vahadane et al., "Structure-preserving color normalization and sparse stain
    separation for histological images", IEEE Trans. Med. Imaging 35(8), 2016,
    pp. 1962-1971, eq. (3)-(4) (λ = 0.1).

    Examples
    --------
    >>> from imageform.analysis import synthetic_stain_image
    >>> img, S, _ = synthetic_stain_image(rng=0)
    >>> est = vahadane_stains(img)
    >>> [bool(stain_angle(est.stain_matrix[i], S[i]) < 1.0) for i in range(2)]
    [True, True]
    """
    _check_params(beta, 1.0, max_percentile)
    lam = as_real(lam, "lam", minimum=0.0, maximum=10.0)
    min_pixels = as_int(min_pixels, "min_pixels", minimum=0)
    max_pixels = as_int(max_pixels, "max_pixels")
    iterations = as_int(iterations, "iterations", maximum=MAX_ITERATIONS)
    if max_pixels < 2 or iterations < 1:
        raise InvalidInputError(
            f"expected max_pixels >= 2 and iterations >= 1, got {max_pixels} and {iterations}"
        )
    key = _base(base)
    rgb = image_in(image, nonempty=True)
    i0v, i0_from = _resolve_i0_source(rgb, i0)
    found: dict[str, Any] = {}
    use = _mask_flat(mask, rgb, i0v, found)
    od = _without_ink(
        optical_density(rgb, min_intensity=min_intensity, i0=i0v, base=key), found, key
    )
    fit = _LazyFit(od, use, float(beta), "norm", key, tissue=True) if is_dask(od) else None
    if fit is not None:  # the tissue pixels gathered with the first pass's sums
        h0, n = fit.stains(1.0, max(int(min_pixels), 2), "Vahadane")
        tissue, index = fit.tissue, fit.index
    else:
        flat = od.reshape((-1, 3)).astype(np.float64)
        keep = _keep_mask(flat, float(beta), "norm")
        if use is not None:
            keep = keep & use
        n = _count(keep, float(beta), max(int(min_pixels), 2), "norm", "Vahadane", use)
        h0, _ = _fit(od, float(beta), 1.0, max(int(min_pixels), 2), "norm", "Vahadane", use)
        tissue, index = flat[keep], np.flatnonzero(keep)
    x = np.asarray(tissue)[lattice_rows(np.asarray(index), max_pixels)]
    _, h, _ = sparse_nmf(x, np.maximum(h0, 0.0), float(lam), iterations)
    norms = np.linalg.norm(h, axis=1, keepdims=True)
    if np.any(norms == 0.0):
        h = h0  # a stain vanished (one-stain tile): keep Macenko's
        norms = np.linalg.norm(h, axis=1, keepdims=True)
    h = h / norms
    if h[0, 0] < h[1, 0]:
        h = h[::-1]
    if fit is not None:
        maxc, meanc = fit.max_conc(h, float(max_percentile))
    else:
        maxc, meanc = _max_conc(od, h, float(max_percentile), key, use)
    i0t = (float(i0v[0]), float(i0v[1]), float(i0v[2]))
    n_total = int(np.prod(rgb.shape[:-1]))
    return MacenkoStains(h.copy(), maxc, n, i0t, key, "vahadane", n_total, i0_from, meanc)


#: Stain-vector estimators, each name mapped to its function (read-only): ``"macenko"``
#: (Macenko et al. 2009, :func:`macenko_stains`) and ``"vahadane"`` (Vahadane et al. 2016,
#: :func:`vahadane_stains`); both return :class:`MacenkoStains`. Not the stain
#: *normalisation* methods (:data:`imageform.analysis.STAIN_NORMALIZATION_METHODS`).
STAIN_VECTOR_METHODS: MappingProxyType[str, Any] = MappingProxyType(
    {"macenko": macenko_stains, "vahadane": vahadane_stains}
)

__getattr__ = _deprecate.module_getattr(
    "imageform.analysis.macenko", {"STAIN_METHODS": ("STAIN_VECTOR_METHODS", STAIN_VECTOR_METHODS)}
)
