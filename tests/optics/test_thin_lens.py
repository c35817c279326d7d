"""Thin lens and depth of field against textbook values; impossible settings raise clearly."""

from __future__ import annotations

import math

import numpy as np
import pytest

from imageform.errors import InvalidInputError
from imageform.optics import (
    aperture_diameter,
    circle_of_confusion,
    depth_of_field,
    f_number,
    hyperfocal_distance,
    magnification,
    thin_lens,
)
from tests.helpers import to_backend, to_np


# -- thin lens --------------------------------------------------------------------------------
def test_thin_lens_textbook() -> None:
    # Hecht, Optics 5th ed., eq. 5.17: f = 50 mm, object 2 m → d_i = 1/(1/0.05 - 1/2) = 51.282 mm
    s = thin_lens(focal_length=0.05, d_o=2.0)
    assert s.d_i == pytest.approx(0.05128205128, rel=1e-10)
    assert s.magnification == pytest.approx(-1 / 39, rel=1e-12)  # m = -d_i/d_o = f/(f - d_o)
    assert not s.virtual


@pytest.mark.parametrize(
    ("given", "missing", "want"),
    [
        ({"focal_length": 0.1, "d_o": 0.2}, "d_i", 0.2),  # object at 2f images at 2f (life size)
        ({"focal_length": 0.1, "d_i": 0.2}, "d_o", 0.2),
        ({"d_o": 0.3, "d_i": 0.15}, "focal_length", 0.1),  # 1/0.3 + 1/0.15 = 10
    ],
)
def test_thin_lens_solves_for_missing(given: dict, missing: str, want: float) -> None:
    assert getattr(thin_lens(**given), missing) == pytest.approx(want, rel=1e-12)


def test_magnification_and_f_number() -> None:
    assert magnification(focal_length=0.05, d_o=0.1) == pytest.approx(-1.0)
    assert f_number(focal_length=0.05, aperture_diameter=0.025) == pytest.approx(2.0)
    assert aperture_diameter(focal_length=0.05, f_number=2.8) == pytest.approx(0.017857142857)


def test_object_inside_focal_length_explains_virtual_image() -> None:
    with pytest.raises(InvalidInputError, match=r"inside the focal length.*virtual"):
        thin_lens(focal_length=0.05, d_o=0.03)
    s = thin_lens(focal_length=0.05, d_o=0.03, allow_virtual=True)  # magnifying glass: Hecht §5.2.3
    assert s.virtual and s.d_i == pytest.approx(-0.075) and s.magnification == pytest.approx(2.5)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"focal_length": 0.05, "d_o": 0.05}, "at infinity"),
        ({"focal_length": -0.05, "d_o": 1.0}, "converging lens"),
        ({"focal_length": 0.05, "d_o": -1.0}, "in front of the lens"),
        ({"focal_length": 0.05}, "exactly two"),
        ({"focal_length": 0.05, "d_o": 1.0, "d_i": 0.1}, "exactly two"),
        ({"focal_length": 0.05, "d_i": 0.03}, "not beyond f"),
        ({"focal_length": 0.05, "d_i": -0.1}, "virtual image"),
        ({"focal_length": "fifty", "d_o": 1.0}, "as a number"),
        ({"focal_length": math.nan, "d_o": 1.0}, "finite"),
    ],
)
def test_thin_lens_bad_input(kwargs: dict, match: str) -> None:
    with pytest.raises(InvalidInputError, match=match):
        thin_lens(**kwargs)


# -- depth of field ---------------------------------------------------------------------------
def test_hyperfocal_textbook() -> None:
    # H = f²/(N c) + f: 50 mm f/8 c = 0.03 mm → 10.47 m (issue 5; Ray, Applied Photographic Optics)
    assert hyperfocal_distance(focal_length=0.05, f_number=8, coc=0.03e-3) == pytest.approx(
        10.47, abs=0.005
    )


def test_depth_of_field_dofmaster() -> None:
    # DOFMaster online calculator, 50 mm f/2.8 at 2 m, c = 0.03 mm:
    # near 1.88 m, far 2.14 m, total 0.26 m
    d = depth_of_field(focal_length=0.05, f_number=2.8, focus=2.0, coc=0.03e-3)
    assert d.near == pytest.approx(1.88, abs=0.005)
    assert d.far == pytest.approx(2.14, abs=0.005)
    assert d.total == pytest.approx(0.26, abs=0.005)
    assert d.in_front < d.behind  # more depth of field behind than in front


def test_focus_at_hyperfocal_gives_half_to_infinity() -> None:
    h = hyperfocal_distance(focal_length=0.05, f_number=8, coc=0.03e-3)
    d = depth_of_field(focal_length=0.05, f_number=8, focus=h, coc=0.03e-3)
    assert math.isinf(d.far) and math.isinf(d.total)
    assert d.near == pytest.approx(h / 2, rel=1e-12)


@pytest.mark.parametrize("n", [1.4, 2.8, 8, 22])
def test_coc_at_dof_limits_equals_c(n: float) -> None:
    c = 0.03e-3
    d = depth_of_field(focal_length=0.085, f_number=n, focus=3.0, coc=c)
    far = d.far if math.isfinite(d.far) else np.inf
    got = circle_of_confusion(np.array([d.near, far]), focal_length=0.085, f_number=n, focus=3.0)
    assert got[0] == pytest.approx(c, rel=1e-10)
    if math.isfinite(d.far):
        assert got[1] == pytest.approx(c, rel=1e-10)


def test_coc_values_and_backends(xp_name: str) -> None:
    depth = np.array([1.0, 2.0, 4.0, np.inf])
    # c(d) = (f/N)|d - s|/d · f/(s - f), f = 50 mm, N = 2, s = 2 m (Wikipedia "Circle of confusion")
    k = 0.05**2 / (2 * 1.95)
    want = [k * 1.0, 0.0, k * 0.5, k]
    got = circle_of_confusion(to_backend(depth, xp_name), focal_length=0.05, f_number=2, focus=2.0)
    np.testing.assert_allclose(to_np(got), want, rtol=1e-12)
    assert isinstance(circle_of_confusion(1.0, focal_length=0.05, f_number=2, focus=2.0), float)


def test_dof_bad_input() -> None:
    with pytest.raises(InvalidInputError, match="focal length"):
        depth_of_field(focal_length=0.05, f_number=2.8, focus=0.04, coc=0.03e-3)
    with pytest.raises(InvalidInputError, match="f_number > 0"):
        depth_of_field(focal_length=0.05, f_number=-2.8, focus=2.0, coc=0.03e-3)
    with pytest.raises(InvalidInputError, match="coc"):
        hyperfocal_distance(focal_length=0.05, f_number=2.8, coc=0.0)
    with pytest.raises(InvalidInputError, match="depth > 0"):
        circle_of_confusion([-1.0], focal_length=0.05, f_number=2, focus=2)
