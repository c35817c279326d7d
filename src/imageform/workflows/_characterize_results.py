"""The results of ``imageform characterize`` (:func:`imageform.workflows.characterize_camera`).

Re-exported by :mod:`imageform.workflows.characterize`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from imageform.errors import InvalidInputError

if TYPE_CHECKING:
    from imageform.io.camera_file import CameraFile

Progress = Callable[[str, float], None]


# ---------------------------------------------------------------- results


@dataclass(frozen=True)
class GeometryMeasurement:
    """The checkerboard calibration.

    ``calibration`` (a :class:`~imageform.geometry.CalibrationResult`), the ``views`` used, the
    ``board`` description and the views where no board was found (``missed``).
    """

    calibration: Any
    views: tuple[str, ...]
    board: str
    missed: tuple[str, ...] = ()


@dataclass(frozen=True)
class SharpnessMeasurement:
    """The slanted-edge e-SFR of the image ``image``.

    Per channel MTF50 and MTF10 (cycles/pixel, median over the edges, ``*_std`` their spread),
    the fitted Gaussian PSF ``gaussian_sigma_px`` (the optics' blur, the pixel aperture divided
    out) and the curves (``frequency``, ``sfr`` (n, channels), the median over the edges);
    ``raw`` when it was measured on a raw mosaic (the CFA balanced on the neutral edge: one
    channel ``"raw"``).
    """

    image: str
    channels: tuple[str, ...]
    mtf50: tuple[float, ...]
    mtf50_std: tuple[float, ...]
    mtf10: tuple[float, ...]
    gaussian_sigma_px: float
    gaussian_sigma_std: float
    frequency: Any
    sfr: Any
    angles_deg: tuple[float, ...]
    edges: int
    raw: bool
    cfa: str | None = None
    image_size: tuple[int, int] | None = None

    @property
    def mtf50_main(self) -> float:
        """MTF50 of the green channel (or the only one)."""
        return self.mtf50[self.channels.index("G")] if "G" in self.channels else self.mtf50[0]


@dataclass(frozen=True)
class NoiseMeasurement:
    """EMVA 1288 from the flats and darks.

    ``emva`` (an :class:`~imageform.sensor.EmvaMeasurement`), the standard errors of the gain
    and the read noise, the black level (mean dark at the shortest exposure, DN), the frame
    ``shape``, the ``plane`` measured (``"all"`` or a CFA photosite) and how many exposures.
    """

    emva: Any
    system_gain_std: float
    read_noise_std: float
    black_level_dn: float
    shape: tuple[int, int]
    plane: str
    exposures: int


@dataclass(frozen=True)
class ColorMeasurement:
    """The ColorChecker: patch means, white balance, CCM, colour errors and sensitivities.

    Where it came from (``raw``, ``developed`` file names), the patch means (``camera_rgb``:
    linear raw, black subtracted, scaled to the white level; ``output_rgb``: the developed
    photograph, linear), the ``white_balance`` gains (green 1) and ``ccm`` (3, 3) with linear
    output = (camera RGB x gains) @ ccm, what it maps to (``ccm_to``: ``"camera_output"`` when
    fitted to the camera's own developed photograph, else ``"srgb"``, the chart's D65
    reference), per-patch CIEDE2000 of the camera's rendering against the reference
    (``delta_e00``) and of the fitted model against its target (``fit_delta_e00``), the
    estimated ``sensitivities`` (a :class:`~imageform.spectral.Spectrum`, or None without a raw
    photograph) and their misfit (``sensitivity_rms``), and ``detection`` (the chart found).
    """

    raw: str | None
    developed: str | None
    camera_rgb: Any
    output_rgb: Any
    white_balance: tuple[float, float, float]
    ccm: Any
    ccm_to: str
    illuminant: str
    delta_e00: Any
    fit_delta_e00: Any
    sensitivities: Any
    sensitivity_rms: tuple[float, ...]
    reference_rgb: Any
    detection: Any
    photo: Any = field(default=None, repr=False)
    half_size: bool = False
    cfa: str | None = None


@dataclass(frozen=True)
class CameraCharacterization:
    """What :func:`characterize_camera` measured.

    Attributes
    ----------
    folder : Path
        The lab set.
    image_size : (int, int) or None
        ``(width, height)`` of the checkerboard views (or the other photographs).
    geometry, sharpness, noise, color : measurement or None
        Each part, None when not measured.
    missing : dict
        Why each part that was not measured was not (``{"noise": "no flats/ folder"}``).
    notes : tuple of str
        Warnings met on the way (a view without a board, ...).
    manifest : dict
        The parsed ``lab.toml`` (empty without one).
    tables : dict
        The camera file's measured tables: ``sensor``, ``optics``, ``color`` (plain data).
    """

    folder: Path
    image_size: tuple[int, int] | None
    geometry: GeometryMeasurement | None
    sharpness: SharpnessMeasurement | None
    noise: NoiseMeasurement | None
    color: ColorMeasurement | None
    missing: dict[str, str]
    notes: tuple[str, ...]
    manifest: dict[str, Any]
    tables: dict[str, dict[str, Any]]

    @property
    def raw_cfa(self) -> str | None:
        """The CFA pattern of a raw photograph measured (None: none was raw)."""
        for part in (self.color, self.sharpness):
            cfa = getattr(part, "cfa", None) if part is not None else None
            if cfa:
                return str(cfa)
        return None

    @property
    def measured(self) -> tuple[str, ...]:
        """The parts measured, in the order geometry, sharpness, noise, color."""
        return tuple(
            p for p in ("geometry", "sharpness", "noise", "color") if getattr(self, p) is not None
        )

    def camera_file(self) -> CameraFile:
        """Return the :class:`~imageform.io.CameraFile` of the geometry.

        A camera with the default intrinsics of the image size when no checkerboard was
        measured.
        """
        from imageform.io import CameraFile, Provenance

        cmd = f"imageform characterize {self.folder}"
        if self.geometry is not None:
            cf = CameraFile.from_calibration(
                self.geometry.calibration, images=list(self.geometry.views), command=cmd
            )
            return cf
        from imageform.geometry import Camera

        if self.image_size is None:
            raise InvalidInputError(
                "no image size is known (no checkerboard, edge or chart photograph) for the "
                "camera file"
            )
        w, h = self.image_size
        f = float(max(w, h))
        cam = Camera([[f, 0.0, (w - 1) / 2], [0.0, f, (h - 1) / 2], [0, 0, 1]], image_size=(w, h))
        return CameraFile(cam, provenance=Provenance(command=cmd))

    def summary(self) -> dict[str, Any]:
        """Return the headline numbers (plain data), as ``metrics.json``'s ``summary``."""
        out: dict[str, Any] = {"measured": list(self.measured), "missing": dict(self.missing)}
        g = self.geometry
        if g is not None:
            c = g.calibration
            K, d = c.K, c.distortion
            out["geometry"] = {
                "fx": float(K[0, 0]),
                "fy": float(K[1, 1]),
                "cx": float(K[0, 2]),
                "cy": float(K[1, 2]),
                "k1": float(d.k1),
                "k2": float(d.k2),
                "p1": float(d.p1),
                "p2": float(d.p2),
                "k3": float(d.k3),
                "std": {k: float(v) for k, v in c.std.items()},
                "rms_px": float(c.rms),
                "views_used": len(g.views),
                "views_missed": list(g.missed),
                "board": g.board,
            }
        s = self.sharpness
        if s is not None:
            out["sharpness"] = {
                "image": s.image,
                "raw": s.raw,
                "edges": s.edges,
                "angles_deg": list(s.angles_deg),
                "mtf50_cy_per_px": dict(zip(s.channels, s.mtf50, strict=True)),
                "mtf50_std": dict(zip(s.channels, s.mtf50_std, strict=True)),
                "mtf10_cy_per_px": dict(zip(s.channels, s.mtf10, strict=True)),
                "gaussian_sigma_px": s.gaussian_sigma_px,
                "gaussian_sigma_std": s.gaussian_sigma_std,
            }
        n = self.noise
        if n is not None:
            m = n.emva
            out["noise"] = {
                "system_gain_dn_per_e": m.system_gain,
                "system_gain_std": n.system_gain_std,
                "read_noise_e": m.dark_noise,
                "read_noise_std": n.read_noise_std,
                "read_noise_upper_limit": bool(m.dark_noise_upper_limit),
                "dark_current_e_per_s": m.dark_current,
                "dsnu_e": m.dsnu,
                "prnu_percent": m.prnu,
                "saturation_capacity_e": m.saturation_capacity,
                "saturated": bool(m.saturated),
                "quantum_efficiency": m.quantum_efficiency,
                "snr_max_db": m.snr_max_db,
                "dynamic_range_db": m.dynamic_range_db,
                "black_level_dn": n.black_level_dn,
                "plane": n.plane,
                "exposures": n.exposures,
                "frame_shape": list(n.shape),
            }
        c2 = self.color
        if c2 is not None:
            import numpy as np

            out["color"] = {
                "raw": c2.raw,
                "developed": c2.developed,
                "white_balance": list(c2.white_balance),
                "ccm": np.asarray(c2.ccm).tolist(),
                "ccm_to": c2.ccm_to,
                "illuminant": c2.illuminant,
                "delta_e00_mean": _nanmean(c2.delta_e00),
                "delta_e00_max": _nanmax(c2.delta_e00),
                "delta_e00_per_patch": [float(x) for x in np.asarray(c2.delta_e00)],
                "fit_delta_e00_mean": _nanmean(c2.fit_delta_e00),
                "sensitivities_estimated": c2.sensitivities is not None,
                "sensitivity_relative_rms": list(c2.sensitivity_rms),
            }
        return out


def _nanmean(x: Any) -> float | None:
    import numpy as np

    a = np.asarray(x, dtype=float)
    return float(np.nanmean(a)) if a.size and np.isfinite(a).any() else None


def _nanmax(x: Any) -> float | None:
    import numpy as np

    a = np.asarray(x, dtype=float)
    return float(np.nanmax(a)) if a.size and np.isfinite(a).any() else None
