"""The simulation report's colour and sensor figures (matplotlib, Agg).

Patch chromaticities through the white balance, ΔE00 and SNR per ColorChecker patch, the
photon-transfer curve.

Each function returns a matplotlib Figure, or ``None`` when the result has nothing to draw
(no ColorChecker, no photon-transfer data); the report then leaves the section out with a
note. matplotlib is imported inside the functions (the optional ``plot`` extra).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, overload

import numpy as np

from imageform.report._checks import check_measurements, check_result
from imageform.report.patches import PatchMeasurements
from imageform.simulate.result import SimulationResult

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = [
    "DELTA_E_BANDS",
    "photon_transfer_summary",
    "plot_delta_e",
    "plot_patch_chromaticity",
    "plot_patch_snr",
    "plot_photon_transfer",
    "truth_xy",
]

#: The lecture's ΔE bands (see :func:`imageform.color.describe_delta_e`): limits drawn on the
#: ΔE00 chart.
DELTA_E_BANDS = (
    (1.0, "imperceptible below 1"),
    (3.0, "just noticeable below 3"),
    (10.0, "obviously different above 10"),
)

_MARKERS = ("s", "o", "^", "D", "v", "P")


def _pyplot() -> Any:
    import matplotlib

    if matplotlib.get_backend().lower() != "agg":
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _subplots(*args: Any, **kwargs: Any) -> Any:
    """``plt.subplots`` for the report's figures: titles at a fixed height above the axes.

    matplotlib otherwise moves each title above whatever sits on top of the axes, measuring
    every tick label at each draw (a tenth of the report's drawing time); none of these
    figures has anything there, so the title lands where it did.
    """
    import matplotlib

    plt = _pyplot()
    with matplotlib.rc_context({"axes.titley": 1.0}):
        return plt.subplots(*args, **kwargs)


def truth_xy(measurements: PatchMeasurements) -> np.ndarray:
    """Chromaticity xy ``(24, 2)`` of the ground-truth patches (CIELAB under D65 -> XYZ -> xy).

    Examples
    --------
    >>> from imageform.report.patches import PatchMeasurements
    >>> m = PatchMeasurements(("white",), np.array([[100.0, 0, 0]]), np.zeros((1, 3)),
    ...     np.zeros(1), ("imperceptible",), np.zeros(1), "s", np.ones((1, 3)))
    >>> truth_xy(m).round(4).tolist()
    [[0.3127, 0.329]]
    """
    from imageform.color.chromaticity import xyz_to_xy
    from imageform.color.cielab import lab_to_xyz

    check_measurements(measurements)
    return np.asarray(xyz_to_xy(lab_to_xyz(measurements.lab_truth, white="srgb"), white="srgb"))


def _zoom_background(ax: Any) -> None:
    """Draw the lines of the chromaticity diagram without the coloured fill, for the zoomed panel.

    The lines are the spectral locus, the sRGB gamut and the Planckian locus with CCT ticks.
    """
    from imageform.color.chromaticity import spectral_locus
    from imageform.color.gamut import gamut_triangle
    from imageform.report.chromaticity_plot import CCT_TICKS, planckian_locus

    _, locus = spectral_locus(observer=2, coords="xy")
    ring = np.vstack([locus, locus[:1]])
    ax.plot(ring[:, 0], ring[:, 1], color="k", lw=1.0)
    tri = gamut_triangle("srgb", "xy")
    ring = np.vstack([tri, tri[:1]])
    ax.plot(ring[:, 0], ring[:, 1], "-", color="k", lw=1.2, label="sRGB")
    pl = planckian_locus(np.geomspace(1500.0, 20000.0, 40))
    ax.plot(pl[:, 0], pl[:, 1], color="0.4", lw=1.0, label="Planckian locus")
    ticks = planckian_locus(CCT_TICKS)
    ax.plot(ticks[:, 0], ticks[:, 1], "o", ms=2.5, color="0.4")
    for t_k, p in zip(CCT_TICKS, ticks, strict=True):
        ax.annotate(
            f"{t_k:g} K",
            p,
            textcoords="offset points",
            xytext=(3, -9),
            fontsize=6,
            annotation_clip=True,
        )


def plot_patch_chromaticity(
    result: SimulationResult, measurements: PatchMeasurements | None = None
) -> Figure | None:
    """Plot every patch at each stage of ``result.patch_xy`` on the CIE 1931 xy diagram.

    The stages are e.g. before and after white balance, after colour correction; a thin line joins
    each patch's positions in order, and the ground truth (from ``lab_d65``) is drawn when
    ``measurements`` is given. Left: the whole diagram; right: zoomed on the patches. ``None`` when
    ``patch_xy`` is empty.

    Raises
    ------
    InvalidInputError
        The ``patch_xy`` arrays are not all of one shape ``(n, 2)``.
    """
    check_result(result)
    from imageform.errors import InvalidInputError
    from imageform.report.chromaticity_plot import plot_chromaticity_diagram

    sets = {k: np.asarray(v, dtype=np.float64) for k, v in result.patch_xy.items()}
    if not sets:
        return None
    shapes = {v.shape for v in sets.values()}
    if len(shapes) != 1 or next(iter(shapes))[-1:] != (2,) or len(next(iter(shapes))) != 2:
        raise InvalidInputError(
            f"expected every patch_xy array of one shape (n, 2), got {sorted(shapes)}"
        )
    stages = dict(sets)
    if measurements is not None:
        sets["ground truth (D65)"] = truth_xy(measurements)
    fig, axes = _subplots(1, 2, figsize=(12.5, 6.2))
    fig.subplots_adjust(left=0.06, right=0.98, bottom=0.09, top=0.94, wspace=0.18)
    plot_chromaticity_diagram(("srgb",), ax=axes[0], resolution=160)
    _zoom_background(axes[1])
    paths = np.stack(list(stages.values()), axis=0)
    for ax in axes:
        for j in range(paths.shape[1]):
            ax.plot(paths[:, j, 0], paths[:, j, 1], "-", color="0.35", lw=0.6, zorder=3)
        for i, (name, xy) in enumerate(sets.items()):
            ax.plot(
                xy[:, 0],
                xy[:, 1],
                _MARKERS[i % len(_MARKERS)],
                ms=5,
                mec="k",
                mfc=f"C{i}",
                label=name.replace("_", " "),
                zorder=4,
                ls="none",
            )
        ax.legend(loc="upper right", fontsize=7)
    stacked = np.concatenate(list(sets.values()), axis=0)
    finite = stacked[np.all(np.isfinite(stacked), axis=1)]
    if finite.size:
        lo, hi = finite.min(axis=0), finite.max(axis=0)
        pad = 0.08 * max(float((hi - lo).max()), 0.05)
        axes[1].set_xlim(lo[0] - pad, hi[0] + pad)
        axes[1].set_ylim(lo[1] - pad, hi[1] + pad)
    axes[1].set_aspect("equal")
    axes[1].set_xlabel("x")
    axes[1].set_ylabel("y")
    axes[1].grid(True, lw=0.3)
    axes[1].set_title("zoomed on the patches")
    return fig


def _bar_colours(m: PatchMeasurements) -> np.ndarray:
    return np.clip(m.truth_srgb, 0.0, 1.0)


@overload
def plot_delta_e(measurements: PatchMeasurements) -> Figure: ...
@overload
def plot_delta_e(measurements: None) -> None: ...
def plot_delta_e(measurements: PatchMeasurements | None) -> Figure | None:
    """Plot a bar chart of CIEDE2000 per patch (bars in the patch's true colour).

    With the mean and the lecture's bands at 1, 3 and 10. ``None`` without measurements.
    """
    if measurements is None:
        return None
    check_measurements(measurements)
    m = measurements
    fig, ax = _subplots(figsize=(12, 4.2))
    x = np.arange(len(m.names))
    de = np.where(np.isfinite(m.delta_e00), m.delta_e00, 0.0)
    ax.bar(x, de, color=_bar_colours(m), edgecolor="k", lw=0.6)
    top = max(float(np.nanmax(de)) if de.size else 0.0, 4.0) * 1.15
    for level, text in DELTA_E_BANDS:
        if level <= top:
            ax.axhline(level, color="0.4", ls=":", lw=0.8)
            ax.annotate(text, (len(x) - 0.5, level), ha="right", va="bottom", fontsize=7)
    mean = m.delta_e00_mean
    if np.isfinite(mean):
        ax.axhline(mean, color="C3", lw=1.2, label=f"delta_e00_mean = {mean:.2f}")
        ax.legend(loc="upper left", fontsize=8)
    ax.set_xticks(x, m.names, rotation=60, ha="right", fontsize=7)
    ax.set_ylim(0, top)
    ax.set_ylabel("CIEDE2000 ΔE00")
    ax.set_title("Colour error of each ColorChecker patch against the D65 ground truth")
    fig.subplots_adjust(left=0.06, right=0.99, bottom=0.22, top=0.92)
    return fig


@overload
def plot_patch_snr(measurements: PatchMeasurements) -> Figure: ...
@overload
def plot_patch_snr(measurements: None) -> None: ...
def plot_patch_snr(measurements: PatchMeasurements | None) -> Figure | None:
    """Plot a bar chart of ``snr_luminance_db`` of every patch (the SNR of the window's luminance).

    ``None`` without measurements.
    """
    if measurements is None:
        return None
    check_measurements(measurements)
    m = measurements
    fig, ax = _subplots(figsize=(12, 3.8))
    x = np.arange(len(m.names))
    finite = np.isfinite(m.snr_luminance_db)
    ax.bar(
        x[finite], m.snr_luminance_db[finite], color=_bar_colours(m)[finite], edgecolor="k", lw=0.6
    )
    for i in np.flatnonzero(~finite):
        ax.annotate(
            "∞" if m.snr_luminance_db[i] == np.inf else "n/a",
            (x[i], 0.0),
            ha="center",
            va="bottom",
            fontsize=8,
        )
    ax.set_xticks(x, m.names, rotation=60, ha="right", fontsize=7)
    ax.set_ylabel("snr_luminance_db = 20 log10(mean(Y) / std(Y))")
    ax.set_title(f"Luminance signal-to-noise ratio per patch, on stage '{m.snr_stage}'")
    fig.subplots_adjust(left=0.06, right=0.99, bottom=0.24, top=0.91)
    return fig


def photon_transfer_summary(result: SimulationResult) -> dict[str, Any] | None:
    """Return the photon-transfer data as plain numbers plus the EMVA 1288 fit.

    The fit is :func:`imageform.sensor.fit_photon_transfer`'s; ``fit`` is ``None`` with a
    ``fit_error`` when the data cannot be fitted. ``None`` without data.
    """
    check_result(result)
    from imageform.errors import ImageformError
    from imageform.sensor.emva import fit_photon_transfer

    d = result.photon_transfer
    if d is None:
        return None
    out: dict[str, Any] = {
        "exposure_times_s": np.asarray(d.exposure_times),
        "photons": np.asarray(d.photons),
        "mean_dn": np.asarray(d.mean_dn),
        "var_dn2": np.asarray(d.var_dn),
        "dark_mean_dn": np.asarray(d.dark_mean_dn),
        "dark_var_dn2": np.asarray(d.dark_var_dn),
        "fit": None,
    }
    try:
        fit = fit_photon_transfer(d)
    except ImageformError as exc:
        out["fit_error"] = str(exc)
    else:
        out["fit"] = {
            "system_gain_dn_per_e": fit.system_gain,
            "read_noise_e": fit.read_noise,
            "quantum_efficiency": fit.quantum_efficiency,
            "dark_current_e_per_s": fit.dark_current,
            "saturation_dn": fit.saturation_dn,
            "saturation_capacity_e": fit.saturation_capacity,
            "fit_points": fit.fit_points,
        }
    return out


@overload
def plot_photon_transfer(summary: dict[str, Any]) -> Figure: ...
@overload
def plot_photon_transfer(summary: None) -> None: ...
def plot_photon_transfer(summary: dict[str, Any] | None) -> Figure | None:
    """Plot the photon-transfer curve: temporal variance against mean signal, both dark-corrected.

    As in EMVA 1288 4.0, §6.3, eq. 31, with the fitted line ``σ² = K μ`` up to saturation.
    ``summary`` from :func:`photon_transfer_summary`; ``None`` without it.
    """
    if summary is None:
        return None
    sig = summary["mean_dn"] - summary["dark_mean_dn"]
    var = summary["var_dn2"] - summary["dark_var_dn2"]
    fig, ax = _subplots(figsize=(6.8, 4.6))
    ax.plot(sig, var, "o", ms=4, mfc="w", mec="C0", label="measured (flat-field pairs)")
    fit = summary["fit"]
    if fit is not None:
        k = fit["system_gain_dn_per_e"]
        sat = float(sig[int(np.argmax(summary["var_dn2"]))])  # EMVA 1288 §6.5
        xs = np.linspace(0.0, max(sat, 0.0), 50)
        ax.plot(xs, k * xs, "-", color="C3", label=f"fit σ² = K μ, K = {k:.4g} DN/e⁻")
        ax.axvline(sat, color="0.5", ls=":", lw=0.8, label="saturation")
        text = (
            f"read noise {fit['read_noise_e']:.3g} e⁻\n"
            f"saturation capacity {fit['saturation_capacity_e']:.4g} e⁻\n"
            f"QE η {fit['quantum_efficiency']:.3g}"
        )
        ax.text(0.02, 0.97, text, transform=ax.transAxes, va="top", fontsize=8)
    else:
        ax.set_title(f"no fit: {summary.get('fit_error', '')}"[:90], fontsize=8)
    ax.set_xlabel("mean signal μ_y − μ_y.dark (DN)")
    ax.set_ylabel("temporal variance σ²_y − σ²_y.dark (DN²)")
    if fit is not None:
        ax.set_title("Photon-transfer curve (EMVA 1288)")
    ax.legend(loc="lower right", fontsize=8)
    fig.subplots_adjust(left=0.13, right=0.975, bottom=0.13, top=0.92)  # as plot_top_view's
    return fig
