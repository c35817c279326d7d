"""ColorChecker patches measured on a simulation's images: CIEDE2000 against the ground truth,
the lecture's reading of each difference, and the signal-to-noise ratio of each patch.

The report measures what it shows, from the stage images and the patch positions of
:class:`~imageform.simulate.ColorCheckerTruth`, so every number in a figure can be traced to
pixels.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from imageform.errors import InvalidInputError
from imageform.simulate.result import ColorCheckerTruth, SimulationResult, Stage

__all__ = ["PatchMeasurements", "measure_patches", "patch_windows", "snr_stage"]


@dataclass(frozen=True)
class PatchMeasurements:
    """Per patch (24 rows): ``names``; ``lab_truth`` and ``lab_measured`` (CIELAB, D65 white);
    ``delta_e00`` (CIEDE2000); ``readings`` (the lecture's words for each ΔE00, NaN-free
    patches only, else ``"not measured"``); ``snr_db`` (``20 log10(mean / std)`` in the
    window, ``inf`` for a noise-free window, NaN outside the image); ``snr_stage`` the stage
    the SNR was measured on; ``truth_srgb`` the encoded sRGB of the ground truth (for bar
    colours; clipped to [0, 1] for display)."""

    names: tuple[str, ...]
    lab_truth: np.ndarray
    lab_measured: np.ndarray
    delta_e00: np.ndarray
    readings: tuple[str, ...]
    snr_db: np.ndarray
    snr_stage: str
    truth_srgb: np.ndarray

    @property
    def mean_delta_e00(self) -> float:
        """Mean ΔE00 over the measured patches (NaN if none was measured)."""
        d = self.delta_e00[np.isfinite(self.delta_e00)]
        return float(d.mean()) if d.size else float("nan")

    @property
    def max_delta_e00(self) -> float:
        """Largest ΔE00 over the measured patches (NaN if none was measured)."""
        d = self.delta_e00[np.isfinite(self.delta_e00)]
        return float(d.max()) if d.size else float("nan")


def patch_windows(
    truth: ColorCheckerTruth, height: int, width: int
) -> list[tuple[slice, slice] | None]:
    """The square window ``(rows, cols)`` sampled around each patch centre: pixels whose
    centres lie within ``sample_radius_px`` of the centre along both axes, cut to the image
    (``None`` where nothing of the window is inside).

    >>> t = ColorCheckerTruth(("a",), np.zeros((1, 3)), np.array([[10.0, 5.0]]), 2.0)
    >>> patch_windows(t, 20, 20)
    [(slice(3, 8, None), slice(8, 13, None))]
    """
    c = np.asarray(truth.centres_uv, dtype=np.float64)
    r = float(truth.sample_radius_px)
    if c.ndim != 2 or c.shape[1] != 2 or not np.isfinite(r) or r < 0:
        raise InvalidInputError(
            f"expected centres_uv of shape (n, 2) and sample_radius_px >= 0, "
            f"got {c.shape} and {truth.sample_radius_px!r}"
        )
    out: list[tuple[slice, slice] | None] = []
    for u, v in c:
        if not (np.isfinite(u) and np.isfinite(v)):
            out.append(None)
            continue
        r0, r1 = max(int(np.ceil(v - r)), 0), min(int(np.floor(v + r)) + 1, height)
        c0, c1 = max(int(np.ceil(u - r)), 0), min(int(np.floor(u + r)) + 1, width)
        out.append((slice(r0, r1), slice(c0, c1)) if r0 < r1 and c0 < c1 else None)
    return out


def snr_stage(result: SimulationResult) -> Stage:
    """The stage the patch SNR is measured on: the last three-channel ``"linear"`` stage
    (the camera's linear RGB after demosaicing and white balance, before encoding), else the
    final stage."""
    for s in reversed(result.stages):
        if s.kind == "linear" and s.image.ndim == 3 and s.image.shape[-1] == 3:
            return s
    return result.stages[-1]


def _stage_linear(stage: Stage) -> np.ndarray:
    from imageform.color.transfer import srgb_to_linear

    a = np.asarray(stage.image, dtype=np.float64)
    if stage.kind == "srgb":
        a = np.asarray(srgb_to_linear(np.clip(a, 0.0, 1.0)))
    return a if a.ndim == 3 else a[..., None]


def measure_patches(result: SimulationResult) -> PatchMeasurements | None:
    """Measure every ColorChecker patch on the result's images (``None`` without a
    ColorChecker).

    Colour: the final (``"srgb"``) stage is decoded to linear sRGB, averaged over each
    patch window, converted to XYZ and CIELAB (white: CIE D65, the ground truth's) and
    compared with ``lab_d65`` by CIEDE2000:

    .. math:: \\Delta E_{00}\\big(\\mathrm{Lab}(\\overline{\\mathrm{sRGB}^{-1}(V)}),
              \\mathrm{Lab}_{truth}\\big)

    Noise: on :func:`snr_stage`, the channel mean ``s`` of each pixel in the window gives
    ``SNR = 20 log10(mean(s) / std(s))`` dB.

    Source: CIE 142-2001 / Sharma et al. (2005) for ΔE00; IEC 61966-2-1:1999 for sRGB;
    ISO 15739:2013 §6 (SNR of a uniform patch as mean over standard deviation).
    """
    from imageform.color.cielab import lab_to_xyz, xyz_to_lab
    from imageform.color.delta_e import delta_e_ciede2000, describe_delta_e
    from imageform.color.rgb_spaces import linear_srgb_to_xyz, xyz_to_linear_srgb
    from imageform.color.transfer import linear_to_srgb

    cc = result.colorchecker
    if cc is None:
        return None
    lab_truth = np.asarray(cc.lab_d65, dtype=np.float64)
    n = len(cc.names)
    if lab_truth.shape != (n, 3) or np.asarray(cc.centres_uv).shape != (n, 2):
        raise InvalidInputError(
            f"expected lab_d65 ({n}, 3) and centres_uv ({n}, 2) for {n} patch names, got "
            f"{lab_truth.shape} and {np.asarray(cc.centres_uv).shape}"
        )
    final = _stage_linear(result.stages[-1])
    h, w = final.shape[:2]
    wins = patch_windows(cc, h, w)
    rgb = np.full((n, 3), np.nan)
    for i, win in enumerate(wins):
        if win is not None:
            rgb[i] = final[win].reshape(-1, final.shape[-1]).mean(axis=0)[:3]
    ok = np.all(np.isfinite(rgb), axis=1)
    lab = np.full((n, 3), np.nan)
    de = np.full(n, np.nan)
    if ok.any():
        lab[ok] = np.asarray(xyz_to_lab(linear_srgb_to_xyz(rgb[ok]), white="D65"))
        de[ok] = np.asarray(delta_e_ciede2000(lab[ok], lab_truth[ok]))
    readings = tuple(describe_delta_e(d) if np.isfinite(d) else "not measured" for d in de)

    s_stage = snr_stage(result)
    lin = _stage_linear(s_stage)
    wins_s = patch_windows(cc, lin.shape[0], lin.shape[1])
    snr = np.full(n, np.nan)
    for i, win in enumerate(wins_s):
        if win is None:
            continue
        s = lin[win].mean(axis=-1).ravel()
        mu, sd = float(s.mean()), float(s.std())
        if sd > 0 and mu > 0:
            snr[i] = 20.0 * np.log10(mu / sd)
        elif sd == 0 and mu > 0:
            snr[i] = np.inf
    truth_lin = np.asarray(xyz_to_linear_srgb(lab_to_xyz(lab_truth, white="D65")))
    truth_srgb = np.asarray(linear_to_srgb(np.clip(truth_lin, 0.0, 1.0)))
    return PatchMeasurements(
        names=tuple(cc.names),
        lab_truth=lab_truth,
        lab_measured=lab,
        delta_e00=de,
        readings=readings,
        snr_db=snr,
        snr_stage=s_stage.name,
        truth_srgb=truth_srgb,
    )
