"""Colour correction from a colour chart: one device to another, or camera RGB to sRGB.

The lecture's question 14: the same tissue scanned at two sites gives different RGB. Image
one chart on both devices, fit a correction from device A's patch values to device B's
(the reference) in linear light, check CIEDE2000 per patch before and after, and apply it
to A's images. Two models: a 3×3 matrix, and the root-polynomial expansion of Finlayson,
Mackiewicz & Hurlbert (2015), whose terms all scale linearly with exposure.

:func:`fit_color_correction` is imageform's one colour-correction fit: the simulator's
camera-RGB-to-linear-sRGB matrix is the same fit on linear patch values
(``transfer="linear"``). The matrix applies to row vectors, ``terms @ matrix.T`` (the
project's convention for points and colours).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any, Literal

import numpy as np

from imageform._colormath import srgb_decode, srgb_encode
from imageform._typing import Array, ArrayLike
from imageform._validate import (
    as_bool,
    as_float,
    as_image,
    as_int,
    as_real,
    check_option,
    describe,
    format_shape,
    real_array,
)
from imageform.analysis._arrays import image_in, is_dask, read_json, write_json
from imageform.analysis.chart_grid import ChartPatches, ChartWarning, chart_patches
from imageform.analysis.chart_input import _as_chart_patches
from imageform.color.convert import convert
from imageform.color.delta_e import delta_e
from imageform.errors import DegenerateConfigurationError, InvalidInputError

__all__ = [
    "CORRECTION_METHODS",
    "ChartPatches",
    "ChartWarning",
    "ColorCorrection",
    "CorrectionReport",
    "chart_patches",
    "correction_report",
    "fit_color_correction",
    "root_polynomial_terms",
]

#: Encodings of the patch values (and of the images a correction applies to).
_TRANSFERS = ("srgb", "linear")

#: Correction models and the degrees they accept (read-only).
CORRECTION_METHODS: MappingProxyType[str, tuple[int, ...]] = MappingProxyType(
    {"linear": (1,), "root_polynomial": (1, 2, 3)}
)


#: Number of root-polynomial terms per degree (Finlayson et al. 2015).
_N_TERMS = {1: 3, 2: 6, 3: 13}


def root_polynomial_terms(rgb: ArrayLike, degree: int) -> np.ndarray:
    r"""Root-polynomial expansion of linear RGB (Finlayson et al. 2015, eq. (9)-(10)).

    degree 1: (R, G, B); degree 2 adds :math:`\sqrt{RG}, \sqrt{GB}, \sqrt{RB}` (6 terms);
    degree 3 adds :math:`\sqrt[3]{RG^2}, \sqrt[3]{GB^2}, \sqrt[3]{RB^2}, \sqrt[3]{GR^2},
    \sqrt[3]{BG^2}, \sqrt[3]{BR^2}, \sqrt[3]{RGB}` (13 terms). Every term is of degree
    one in exposure: :math:`t(kx) = k\,t(x)`. Roots are sign-preserving
    (:math:`\operatorname{sign}(p)|p|^{1/n}`) so small negative noise values stay finite.

    Examples
    --------
    >>> root_polynomial_terms(np.array([0.25, 1.0, 0.04]), 2).round(6).tolist()
    [0.25, 1.0, 0.04, 0.5, 0.2, 0.1]
    """
    deg = as_int(degree, "degree", minimum=1, maximum=3)
    x = rgb if isinstance(rgb, np.ndarray) and rgb.dtype.kind == "f" else real_array(rgb, "rgb")
    if x.ndim < 1 or x.shape[-1] != 3:
        raise InvalidInputError(
            f"expected rgb of shape (..., 3), got {format_shape(tuple(np.shape(x)))}"
        )
    r, g, b = x[..., 0], x[..., 1], x[..., 2]

    def root(p: Any, n: float) -> Any:
        return np.sign(p) * np.abs(p) ** (1.0 / n)

    terms = [r, g, b]
    if deg >= 2:
        terms += [root(r * g, 2), root(g * b, 2), root(r * b, 2)]
    if deg >= 3:
        terms += [
            root(r * g * g, 3),
            root(g * b * b, 3),
            root(r * b * b, 3),
            root(g * r * r, 3),
            root(b * g * g, 3),
            root(b * r * r, 3),
            root(r * g * b, 3),
        ]
    return np.stack(terms, axis=-1)


def _linear_light(x: np.ndarray, transfer: str) -> np.ndarray:
    """Values in linear light: as they are (``"linear"``) or decoded from sRGB."""
    return x if transfer == "linear" else np.asarray(srgb_decode(np, x))


def _apply_block(
    rgb: np.ndarray, matrix: np.ndarray, degree: int, clip: bool, transfer: str
) -> np.ndarray:
    lin = _linear_light(rgb, transfer)
    out = root_polynomial_terms(lin, degree) @ matrix.T.astype(rgb.dtype)
    enc = out if transfer == "linear" else np.asarray(srgb_encode(np, out), dtype=rgb.dtype)
    return np.clip(enc, 0.0, 1.0) if clip else enc


@dataclass(frozen=True)
class ColorCorrection:
    """A fitted colour correction from device A to the reference.

    ``matrix`` (3, n_terms) maps the expanded linear RGB of device A to linear RGB of the reference
    (row vectors: ``terms @ matrix.T``).

    ``transfer`` is the encoding of the values it was fitted on and applies to: ``"srgb"``
    (decoded to linear light, corrected, re-encoded) or ``"linear"`` (corrected as is).
    """

    method: str
    degree: int
    matrix: np.ndarray
    n_patches: int = 0
    transfer: str = "srgb"

    def __post_init__(self) -> None:
        """Check for a known method and degree, and a finite matrix of the matching shape."""
        key = check_option(self.method, CORRECTION_METHODS, "correction method")
        deg = as_int(self.degree, "degree")
        if deg not in CORRECTION_METHODS[key]:
            raise InvalidInputError(
                f"expected degree in {CORRECTION_METHODS[key]} for {key}, got {deg}"
            )
        n_terms = _N_TERMS[deg]
        matrix = real_array(self.matrix, "matrix", (3, n_terms))
        object.__setattr__(self, "method", key)
        object.__setattr__(self, "degree", deg)
        object.__setattr__(self, "matrix", matrix)
        object.__setattr__(self, "n_patches", as_int(self.n_patches, "n_patches", minimum=0))
        tf = check_option(self.transfer, _TRANSFERS, "correction transfer")
        object.__setattr__(self, "transfer", tf)

    def apply(self, image: ArrayLike, *, clip: bool = False) -> Array:
        """Correct an image from device A (NumPy, uint8/uint16, or Dask chunk-wise).

        With ``transfer="srgb"`` the encoded sRGB image is decoded to linear light,
        corrected and re-encoded; with ``"linear"`` the linear image is corrected as is
        (``image @ matrix.T`` for the 3×3 model). Values outside [0, 1] are kept unless
        ``clip=True``.

        Examples
        --------
        >>> c = ColorCorrection("linear", 1, np.eye(3) * 0.5)
        >>> c.apply(np.array([[[1.0, 1.0, 1.0]]])).round(4).tolist()
        [[[0.7354, 0.7354, 0.7354]]]
        >>> ColorCorrection("linear", 1, np.eye(3) * 0.5, transfer="linear").apply(
        ...     np.array([[[1.0, 1.0, 1.0]]])).tolist()
        [[[0.5, 0.5, 0.5]]]
        """
        tf = check_option(self.transfer, _TRANSFERS, "correction transfer")
        rgb = image_in(image, range_check=tf == "srgb")
        matrix = np.asarray(self.matrix, dtype=np.float64)
        args = (matrix, int(self.degree), as_bool(clip, "clip"), tf)
        if is_dask(rgb):
            return rgb.map_blocks(_apply_block, *args, dtype=rgb.dtype)
        return _apply_block(rgb, *args)

    def to_json(self, path: str | Path) -> None:
        """Save as JSON (``kind: "color_correction"``)."""
        write_json(
            path,
            {
                "kind": "color_correction",
                "space": "linear_srgb",
                "transfer": self.transfer,
                "method": self.method,
                "degree": int(self.degree),
                "matrix": np.asarray(self.matrix).tolist(),
                "n_patches": int(self.n_patches),
            },
        )

    @classmethod
    def from_json(cls, path: str | Path) -> ColorCorrection:
        """Load a correction saved by :meth:`to_json`."""
        d = read_json(path, "color_correction")
        try:
            method = check_option(d["method"], CORRECTION_METHODS, "correction method")
            degree = int(d["degree"])
            matrix = np.asarray(d["matrix"], dtype=np.float64)
            transfer = check_option(d.get("transfer", "srgb"), _TRANSFERS, "correction transfer")
        except (KeyError, TypeError, ValueError) as exc:
            raise InvalidInputError(f"malformed colour correction in {path}: {exc}") from exc
        n_terms = root_polynomial_terms(np.ones(3), degree).shape[-1]
        if matrix.shape != (3, n_terms):
            raise InvalidInputError(
                f"expected a matrix of shape (3, {n_terms}) in {path}, got {matrix.shape}"
            )
        return cls(method, degree, matrix, int(d.get("n_patches", 0)), transfer)


def _patches_in(x: object, name: str, layout: str = "auto") -> tuple[np.ndarray, np.ndarray]:
    """Return the patch values (N, 3) and the usable-row mask.

    An image (H, W, 3) or a ChartSample is sampled by :func:`~imageform.analysis.sample_chart`
    first.
    """
    x = _as_chart_patches(x, name, layout)
    if isinstance(x, ChartPatches):
        return np.asarray(x.means, dtype=np.float64), x.valid
    arr = np.asarray(as_float(x, name, finite=False), dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise InvalidInputError(f"expected {name} of shape (N, 3), got {format_shape(arr.shape)}")
    if not np.all(np.isfinite(arr)):
        raise InvalidInputError(f"{name} contains NaN or inf")
    return arr, np.ones(arr.shape[0], dtype=bool)


def _paired_patches(
    measured: object, reference: object, layout: str = "auto"
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Both charts' patch values and validity masks, checked to be the same patches."""
    layout = check_option(layout, ("auto", "cropped", "detect"), "chart layout (chart_layout)")
    a, va = _patches_in(measured, "measured", layout)
    b, vb = _patches_in(reference, "reference", layout)
    if a.shape != b.shape:
        raise InvalidInputError(
            f"expected measured and reference of the same shape, got {format_shape(a.shape)} "
            f"and {format_shape(b.shape)}"
        )
    return a, va, b, vb


def fit_color_correction(
    measured: ArrayLike | ChartPatches,
    reference: ArrayLike | ChartPatches,
    method: str = "linear",
    degree: int = 2,
    *,
    transfer: Literal["srgb", "linear"] = "srgb",
    saturation: float | None = 1.0,
    chart_layout: str = "auto",
    never_worse: bool = True,
) -> ColorCorrection:
    r"""Least-squares colour correction from device A's chart (``measured``) to the reference.

    .. math:: \hat M = \arg\min_M \sum_i \lVert \rho(a_i) M^T - b_i \rVert^2
        = \big((\rho(A)^T \rho(A))^{-1} \rho(A)^T B\big)^T

    with :math:`a_i, b_i` the linear-light RGB of patch *i* (rows of A and B),
    :math:`\rho` the identity (``"linear"``, 3×3) or the root-polynomial expansion of
    ``degree`` (:func:`root_polynomial_terms`). The fitted ``matrix`` is :math:`\hat M`
    for row vectors: the corrected colour is ``rho(a) @ matrix.T``.

    Parameters
    ----------
    measured, reference : array_like, shape (N, 3), ChartPatches, or an image with a chart
        Patch values of the same N patches, encoded as ``transfer`` says. Patches flagged
        in a :class:`ChartPatches` (saturated, missing: mark non-finite rows as missing),
        and patches where either side reaches ``saturation`` in any channel, are left out
        (the latter with a :class:`ChartWarning`). An image, shape (H, W, 3), is a chart
        cropped to fill the frame or a photograph with a ColorChecker anywhere in it: its
        patches are sampled by :func:`~imageform.analysis.sample_chart` (``chart_layout``);
        a :class:`~imageform.analysis.ChartSample` is taken as sampled.
    method : {"linear", "root_polynomial"}
        A 3×3 matrix on linear RGB, or Finlayson's root-polynomial expansion of ``degree``.
    degree : int
        Root-polynomial degree (1, 2 or 3); ignored for ``"linear"``.
    transfer : {"srgb", "linear"}, keyword-only
        ``"srgb"``: encoded sRGB values in [0, 1], decoded to linear light for the fit
        (device to device). ``"linear"``: linear values, fitted as they are (e.g. the
        white-balanced camera RGB of a chart against its linear sRGB ground truth).
    saturation : float or None, keyword-only
        The clipping level; ``None`` leaves no patch out for saturation (linear data above
        1 is not clipped).
    chart_layout : {"auto", "cropped", "detect"}, keyword-only
        How a chart is found in an image given as ``measured`` or ``reference``
        (:func:`~imageform.analysis.sample_chart`: ``"auto"`` takes a chart that fills the
        frame when its grid validates, else detects a ColorChecker in the photograph).
    never_worse : bool, keyword-only
        With ``transfer="srgb"``: a fit whose mean CIEDE2000 to the reference over the
        patches it was fitted on is larger than the uncorrected patches' is replaced by the
        first of the lower-order fits (root-polynomial of a lower degree, then the 3×3
        matrix) that is no worse, else by the identity (no correction), with a
        :class:`ChartWarning` saying so. Least squares in linear light is not least ΔE: a
        chart that is nearly right already, or one bad patch the fit bends to, can come out
        worse than it went in.

    Returns
    -------
    ColorCorrection
        Its ``transfer`` is the patches'; :meth:`ColorCorrection.apply` takes images in the
        same encoding.

    Raises
    ------
    DegenerateConfigurationError
        Fewer usable patches than model terms, or a rank-deficient design (e.g. grey
        patches only).

    Notes
    -----
    Source: G. D. Finlayson, M. Mackiewicz, A. Hurlbert, "Color correction using
    root-polynomial regression", IEEE TIP 24(5), 2015, eq. (9)-(12).

    Examples
    --------
    >>> rng = np.random.default_rng(1)
    >>> a = rng.uniform(0.05, 0.95, (24, 3))
    >>> b = fit_color_correction(a, a).apply(a)
    >>> float(np.abs(b - a).max()) < 1e-9
    True
    >>> M = np.array([[0.9, 0.1, 0.0], [0.05, 0.9, 0.05], [0.0, 0.2, 0.8]])
    >>> c = fit_color_correction(a, a @ M.T, transfer="linear")
    >>> bool(np.allclose(c.matrix, M))  # row vectors: reference = measured @ matrix.T
    True
    """
    tf = check_option(transfer, _TRANSFERS, "patch encoding (transfer)")
    key = check_option(method, CORRECTION_METHODS, "correction method")
    deg = 1 if key == "linear" else as_int(degree, "degree")
    if deg not in CORRECTION_METHODS[key]:
        raise InvalidInputError(
            f"expected degree in {CORRECTION_METHODS[key]} for {key}, got {degree!r}"
        )
    if saturation is not None:
        saturation = as_real(saturation, "saturation", positive=True)
    a, va, b, vb = _paired_patches(measured, reference, chart_layout)
    if saturation is None:
        sat = np.zeros(a.shape[0], dtype=bool)
    else:
        sat = ((a >= saturation).any(axis=1) | (b >= saturation).any(axis=1)) & va & vb
    use = va & vb & ~sat
    if sat.any():
        warnings.warn(
            f"fit_color_correction: saturated patch(es) {np.flatnonzero(sat).tolist()} "
            f"(a channel >= {saturation:g}) left out of the fit",
            ChartWarning,
            stacklevel=2,
        )
    terms = root_polynomial_terms(_linear_light(a[use], tf), deg)
    n_terms = terms.shape[1]
    if terms.shape[0] < n_terms:
        raise DegenerateConfigurationError(
            f"{key} correction of degree {deg} has {n_terms} terms per channel but only "
            f"{terms.shape[0]} usable patches"
        )
    if np.linalg.matrix_rank(terms) < n_terms:
        raise DegenerateConfigurationError(
            f"the chart does not determine a {key} correction of degree {deg}: its patches "
            "span too few independent colours (rank-deficient design)"
        )
    sol, *_ = np.linalg.lstsq(terms, _linear_light(b[use], tf), rcond=None)
    fit = ColorCorrection(key, deg, sol.T.copy(), int(use.sum()), tf)
    if not as_bool(never_worse, "never_worse") or tf != "srgb":
        return fit
    return _no_worse(fit, a[use], b[use])


def _mean_delta_e(corr: ColorCorrection | None, a: np.ndarray, lab_b: np.ndarray) -> float:
    """Mean CIEDE2000 of ``a`` corrected (``None``: as it is) to the reference's Lab."""
    x = a if corr is None else corr.apply(a[:, None, :])[:, 0, :]  # as correction_report
    return float(np.mean(delta_e(lab_b, np.asarray(convert(x, "srgb", "lab")))))


def _no_worse(fit: ColorCorrection, a: np.ndarray, b: np.ndarray) -> ColorCorrection:
    """``fit``, or the first lower-order fit (or the identity) no worse than no correction."""
    lab_b = np.asarray(convert(b, "srgb", "lab"))
    before = _mean_delta_e(None, a, lab_b)
    after = _mean_delta_e(fit, a, lab_b)
    if after <= before:
        return fit
    n = len(a)
    lower = [("root_polynomial", d) for d in range(fit.degree - 1, 1, -1)]
    if fit.method == "root_polynomial":
        lower.append(("linear", 1))
    chosen = ColorCorrection("linear", 1, np.eye(3), n, fit.transfer)
    name, value = "no correction (the identity)", before
    for method, degree in lower:
        terms = root_polynomial_terms(_linear_light(a, "srgb"), degree)
        if terms.shape[0] < terms.shape[1] or np.linalg.matrix_rank(terms) < terms.shape[1]:
            continue
        sol, *_ = np.linalg.lstsq(terms, _linear_light(b, "srgb"), rcond=None)
        cand = ColorCorrection(method, degree, sol.T.copy(), n, fit.transfer)
        value = _mean_delta_e(cand, a, lab_b)
        if value <= before:
            chosen, name = cand, f"the {method} fit (degree {degree})"
            break
    else:
        value = before
    warnings.warn(
        f"fit_color_correction: the {fit.method} fit (degree {fit.degree}) makes the chart "
        f"worse (mean CIEDE2000 {before:.2f} -> {after:.2f} on {n} patches); using {name} "
        f"instead (mean {value:.2f})",
        ChartWarning,
        stacklevel=3,
    )
    return chosen


@dataclass(frozen=True)
class CorrectionReport:
    """CIEDE2000 per patch between device B's chart and device A's, before and after.

    ``valid`` marks the patches usable on both charts (not saturated or missing when
    :class:`ChartPatches` were given); :meth:`summary` is taken over those.
    """

    delta_e_before: np.ndarray
    delta_e_after: np.ndarray
    valid: np.ndarray

    def __post_init__(self) -> None:
        """Check two ΔE00 vectors (N,) and the ``valid`` booleans (N,).

        The ΔE00 values are finite and >= 0 on the valid patches (NaN allowed where a patch is not
        valid).
        """
        before = real_array(self.delta_e_before, "delta_e_before", (None,), finite=False)
        n = before.shape[0]
        after = real_array(self.delta_e_after, "delta_e_after", (None,), finite=False)
        if after.shape != (n,):
            raise InvalidInputError(
                f"expected delta_e_before and delta_e_after of one length, got {n} and "
                f"{after.shape[0]}"
            )
        flag = self.valid
        valid = np.asarray(flag) if not isinstance(flag, str | bytes) else None
        if valid is None or valid.dtype != np.bool_ or valid.shape != (n,):
            raise InvalidInputError(
                f"expected valid as booleans of shape ({n},), got {describe(flag)}"
            )
        for name, arr in (("delta_e_before", before), ("delta_e_after", after)):
            used = arr[valid]
            if not np.all(np.isfinite(used)) or np.any(used < 0):
                raise InvalidInputError(
                    f"expected {name} as finite values >= 0 on the valid patches"
                )
            object.__setattr__(self, name, arr)
        object.__setattr__(self, "valid", valid)

    def summary(self) -> dict[str, float]:
        """Mean, median and maximum ΔE00 before and after, over the valid patches."""
        if not self.valid.any():
            raise DegenerateConfigurationError(
                "CorrectionReport.summary: no valid patch (every patch is saturated or missing)"
            )
        out: dict[str, float] = {}
        for key, v in (("before", self.delta_e_before), ("after", self.delta_e_after)):
            v = v[self.valid]
            out[f"mean_{key}"] = float(np.mean(v))
            out[f"median_{key}"] = float(np.median(v))
            out[f"max_{key}"] = float(np.max(v))
        return out


def correction_report(
    measured: ArrayLike | ChartPatches,
    reference: ArrayLike | ChartPatches,
    correction: ColorCorrection,
    *,
    chart_layout: str = "auto",
) -> CorrectionReport:
    r"""Return the CIEDE2000 per patch before and after the correction.

    Before: :math:`\Delta E_{00}(\mathrm{Lab}(b_i), \mathrm{Lab}(a_i))`; after:
    :math:`\Delta E_{00}(\mathrm{Lab}(b_i), \mathrm{Lab}(f(a_i)))`.

    Lab from encoded sRGB with its D65 white. Patches fitted on are scored too: report
    ΔE on patches left out of the fit (or another chart) to judge generalisation.
    ``measured`` and ``reference`` take what :func:`fit_color_correction` takes, images with
    a chart included (found as ``chart_layout`` says; pass the
    :class:`~imageform.analysis.ChartSample` of :func:`~imageform.analysis.sample_chart` to
    sample a photograph once for both calls).

    Source: CIE 142:2001 / Sharma, Wu & Dalal 2005 (CIEDE2000).

    Examples
    --------
    >>> a = np.array([[0.5, 0.4, 0.3]] * 3); b = np.array([[0.5, 0.4, 0.3]] * 3)
    >>> r = correction_report(a, b, ColorCorrection("linear", 1, np.eye(3)))
    >>> r.delta_e_before.tolist(), r.delta_e_after.tolist()
    ([0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    """
    if not isinstance(correction, ColorCorrection):
        raise TypeError(
            f"expected correction as a ColorCorrection, got {type(correction).__name__}"
        )
    a, va, b, vb = _paired_patches(measured, reference, chart_layout)
    # encoded sRGB in [0, 1]: 0-255 codes are refused naming the argument, not "srgb image"
    as_image(np.where(va[:, None], a, 0.0), "measured", finite=False)
    as_image(np.where(vb[:, None], b, 0.0), "reference", finite=False)
    lab_b = np.asarray(convert(b, "srgb", "lab"))
    before = np.asarray(delta_e(lab_b, np.asarray(convert(a, "srgb", "lab"))))
    fixed = correction.apply(a[:, None, :])[:, 0, :]
    after = np.asarray(delta_e(lab_b, np.asarray(convert(fixed, "srgb", "lab"))))
    return CorrectionReport(before, after, np.asarray(va & vb))
