"""A measured camera's tables in the simulator's sensor model.

Internal to :mod:`imageform.simulate` (:func:`imageform.simulate.apply_camera_file` is the
entry point): :class:`MeasuredCamera` holds a camera file's ``[sensor]``, ``[optics]`` and
``[color]``, :func:`measured_sensor` puts them into a :class:`~imageform.sensor.SensorModel`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from imageform._validate import describe
from imageform.errors import InvalidInputError
from imageform.io import CameraColor, CameraOptics, CameraSensor
from imageform.sensor.model import SensorModel

__all__ = ["MeasuredCamera", "measured_sensor"]


@dataclass(frozen=True)
class MeasuredCamera:
    """The measured-camera tables a scene renders through (each None when absent)."""

    sensor: CameraSensor | None = None
    optics: CameraOptics | None = None
    color: CameraColor | None = None

    def __post_init__(self) -> None:
        """Each field None or its camera-file dataclass."""
        tables = (("sensor", CameraSensor), ("optics", CameraOptics), ("color", CameraColor))
        for name, cls in tables:
            v = getattr(self, name)
            if v is not None and not isinstance(v, cls):
                raise TypeError(f"expected {name} as a {cls.__name__} or None, got {describe(v)}")

    @property
    def empty(self) -> bool:
        """No table at all."""
        return self.sensor is None and self.optics is None and self.color is None


def measured_sensor(sensor: SensorModel, measured: MeasuredCamera | None) -> SensorModel:
    r"""Return the scene's sensor model with the camera file's values in place of its own.

    The values are the ``[sensor]`` table's (and the ``[color]`` spectral sensitivities).

    The EMVA 1288 system gain ``K`` is set through the analog gain, the preset's conversion
    gain and ADC range kept: :math:`G_{analog} = K\, V_{ADC} / (G_{conv} (2^b - 1))`. The
    file's ``dsnu_e`` is the whole dark non-uniformity, so the preset's column offsets are
    removed. ``quantum_efficiency`` (the effective QE EMVA 1288 measures, fill factor
    included) scales the QE curves to that peak and sets the fill factor to 1; sensitivities
    given in ``[color]`` replace the curves' shape. ``exposure_time_s`` is not applied (the scene's
    exposure is a shooting setting).

    Raises
    ------
    InvalidInputError
        ``bit_depth`` above 16 (the simulator's ADC), or values the sensor model refuses
        (a black level above the ADC's range).
    """
    if not isinstance(sensor, SensorModel):
        raise TypeError(f"expected sensor as a SensorModel, got {describe(sensor)}")
    if measured is None:
        return sensor
    if not isinstance(measured, MeasuredCamera):
        raise TypeError(f"expected measured as a MeasuredCamera or None, got {describe(measured)}")
    s, color = measured.sensor, measured.color
    changes: dict[str, Any] = {}
    if s is not None:
        table = {
            "read_noise_e": "read_noise",
            "dark_current_e_per_s": "dark_current",
            "dsnu_e": "dsnu",
            "prnu": "prnu",
            "full_well_e": "full_well",
            "black_level_dn": "black_level",
        }
        for key, name in table.items():
            if getattr(s, key) is not None:
                changes[name] = float(getattr(s, key))
        if s.pixel_pitch_um is not None:
            changes["pixel_pitch"] = s.pixel_pitch_um * 1e-6
        changes["column_fpn"] = 0.0
        bits = sensor.bit_depth
        if s.bit_depth is not None:
            if s.bit_depth > 16:
                raise InvalidInputError(
                    f"sensor.bit_depth: the simulator's ADC has at most 16 bits, got {s.bit_depth}"
                )
            bits = changes["bit_depth"] = int(s.bit_depth)
        if s.system_gain_dn_per_e is not None:
            changes["analog_gain"] = (
                s.system_gain_dn_per_e * sensor.adc_range / (sensor.conversion_gain * (2**bits - 1))
            )
    wl = np.asarray(sensor.qe_wavelengths, dtype=np.float64)
    curves = np.asarray(sensor.qe_curves, dtype=np.float64)
    peak = float(curves.max())
    qe_changed = False
    if color is not None and color.sensitivity is not None:
        w, v = color.sensitivity.to_array()
        step = float(np.min(np.diff(w)))
        wl = np.concatenate([[max(w[0] - step, 1.0)], w, [w[-1] + step]])
        curves = np.vstack([np.zeros(3), v, np.zeros(3)]).T
        curves = curves / curves.max() * peak
        qe_changed = True
    if color is not None and color.spectral_sensitivity is not None:
        from imageform.spectral import camera_sensitivities

        sens = camera_sensitivities(color.spectral_sensitivity)
        wl = np.asarray(sens.wavelengths, dtype=np.float64)
        curves = np.asarray(sens.values, dtype=np.float64).T
        curves = curves / curves.max() * peak
        qe_changed = True
    if s is not None and s.quantum_efficiency is not None:
        # the file's QE is EMVA 1288's effective one (fill factor included, as measured):
        # the model's fill factor must not scale it a second time
        curves = curves / curves.max() * s.quantum_efficiency
        changes["fill_factor"] = 1.0
        qe_changed = True
    if qe_changed:
        changes["qe_wavelengths"] = tuple(float(x) for x in wl)
        changes["qe_curves"] = tuple(tuple(float(x) for x in c) for c in curves)
    if not changes:
        return sensor
    try:
        return dataclasses.replace(sensor, **changes)
    except InvalidInputError as exc:
        raise InvalidInputError(f"camera file [sensor]: {exc}") from None
