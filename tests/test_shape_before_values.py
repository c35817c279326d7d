"""Issue 16, "reject a misshaped array before scanning its values": a 16 GB array of the
wrong shape (a broadcast view: no memory) is refused by its shape, in well under a second,
by the image entry points of every package (a pass over its values would take seconds)."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from imageform import analysis, color, geometry, sensor
from imageform.errors import InvalidInputError

BIG = np.broadcast_to(np.float64(0.5), (20000, 20000, 5))  # 16 GB of float64, virtually

CALLS: dict[str, Callable[[], Any]] = {
    "color.convert": lambda: color.convert(BIG, "srgb", "lab"),
    "color.white_balance": lambda: color.white_balance(BIG, "gray_world"),
    "color.estimate_illuminant": lambda: color.estimate_illuminant(BIG),
    "color.delta_e": lambda: color.delta_e(BIG, BIG),
    "geometry.project_points": lambda: geometry.project_points(BIG, np.eye(3)),
    "analysis.macenko_stains": lambda: analysis.macenko_stains(BIG),
    "analysis.reinhard_stats": lambda: analysis.reinhard_stats(BIG),
    "analysis.segment_hsv": lambda: analysis.segment_hsv(BIG),
    "sensor.demosaic": lambda: sensor.demosaic(BIG, "RGGB"),
}


@pytest.mark.parametrize("name", sorted(CALLS))
def test_misshaped_array_refused_before_its_values_are_read(name: str) -> None:
    t0 = time.perf_counter()
    with pytest.raises(InvalidInputError, match=r"20000, 20000, 5"):
        CALLS[name]()
    assert time.perf_counter() - t0 < 0.5, name
