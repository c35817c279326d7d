"""Global versus rolling shutter; CCD/CMOS presets reflect the comparison table."""

from __future__ import annotations

import numpy as np
import pytest

from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.sensor import (
    CCD_VS_CMOS,
    ccd_preset,
    cmos_preset,
    comparison_table,
    rolling_shutter_points,
    rolling_shutter_skew,
    shutter_capture,
)


def _bar_scene(velocity: float, x0: float = 10.0, h: int = 48, w: int = 96):
    u = np.arange(w)

    def render(t: float) -> np.ndarray:
        row = np.clip(1.5 - np.abs(u - (x0 + velocity * t)), 0, 1)  # a 3-px bar moving right
        return np.repeat(row[None], h, axis=0)

    return render


def _centres(img: np.ndarray) -> np.ndarray:
    u = np.arange(img.shape[1])
    return (img * u).sum(axis=1) / img.sum(axis=1)


def test_rolling_shutter_skews_by_velocity_times_line_time() -> None:
    v, tl = 2000.0, 250e-6  # px/s, s per line → 0.5 px per row
    img = shutter_capture(_bar_scene(v), exposure_time=1e-4, mode="rolling", line_time=tl)
    slope = np.polyfit(np.arange(img.shape[0]), _centres(img), 1)[0]
    assert slope == pytest.approx(rolling_shutter_skew(v, tl), rel=1e-6)
    assert rolling_shutter_skew(v, tl) == 0.5


def test_global_shutter_keeps_the_bar_upright() -> None:
    img = shutter_capture(_bar_scene(2000.0), exposure_time=1e-4, mode="global", line_time=250e-6)
    c = _centres(img)
    np.testing.assert_allclose(c, c[0], atol=1e-9)
    assert c[0] == pytest.approx(10.0 + 2000.0 * 0.5e-4, abs=1e-6)  # motion during exposure


def test_rolling_shutter_points_analytic() -> None:
    # a point moving down at v_y meets row r = y0 / (1 - v_y t_line)
    out = rolling_shutter_points([[5.0, 50.0]], [100.0, 1000.0], line_time=1e-4)
    r = 50.0 / (1 - 0.1)
    np.testing.assert_allclose(out, [[5.0 + 100 * r * 1e-4, r]])
    with pytest.raises(InvalidInputError, match="outruns"):
        rolling_shutter_points([[0.0, 1.0]], [0.0, 2e4], line_time=1e-4)


def test_shutter_bad_input() -> None:
    with pytest.raises(UnknownOptionError, match="valid: 'global', 'rolling'"):
        shutter_capture(_bar_scene(1.0), exposure_time=1e-3, mode="leaf", line_time=1e-5)
    with pytest.raises(InvalidInputError, match="exposure_time"):
        shutter_capture(_bar_scene(1.0), exposure_time=-1e-3, mode="global", line_time=1e-5)


def test_presets_reflect_comparison_table() -> None:
    ccd, cmos = ccd_preset(), cmos_preset()
    assert ccd.shutter == "global" and cmos.shutter == "rolling"  # shutter row
    assert ccd.read_noise < cmos.read_noise  # noise row: CCD low
    assert ccd.prnu < cmos.prnu and ccd.dsnu < cmos.dsnu  # uniformity row
    assert ccd.column_fpn == 0 < cmos.column_fpn  # column ADCs only on CMOS
    assert ccd.power > cmos.power  # power row
    assert ccd.frame_readout_time(1000) > cmos.frame_readout_time(1000)  # speed row
    assert ccd.fill_factor > cmos.fill_factor  # fill-factor row
    aspects = [r.aspect for r in CCD_VS_CMOS]
    assert {"readout", "speed", "noise", "power", "shutter"} <= set(aspects)
    table = comparison_table(1000)
    assert "frames/s" in table[1]["ccd"] and "W" in table[4]["cmos"]


def test_preset_overrides_and_color() -> None:
    s = cmos_preset(color=True, analog_gain=4.0)
    assert s.n_channels == 3 and s.analog_gain == 4.0
    assert s.system_gain == pytest.approx(4 * cmos_preset().system_gain)
