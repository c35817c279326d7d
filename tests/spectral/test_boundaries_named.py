"""Issue 16, second pass on imageform.spectral: unknown or malformed names are refused in one
line under 200 characters that names the parameter (``name``, ``kind``, ``illuminant`` or the
caller's own, e.g. ``test``), never echoing a 100,000-character value."""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from imageform.errors import ImageformError, InvalidInputError, UnknownOptionError
from imageform.spectral import (
    Spectrum,
    colorchecker_reflectances,
    illuminant,
    illuminant_table,
    led_spectrum,
    load_table,
    luminous_efficiency,
    resolve_illuminant,
    spectrum_to_camera_rgb,
    spectrum_to_lms,
    spectrum_to_xyz,
)

HUGE = "x" * 100_000


@pytest.fixture(autouse=True)
def _no_warnings():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        yield


def _refused(call: Callable[[], Any], name: str) -> str:
    with pytest.raises((ImageformError, TypeError)) as exc:
        call()
    msg = str(exc.value)
    assert "\n" not in msg and len(msg) <= 200, msg
    assert name in msg, (name, msg)
    return msg


def _r() -> Spectrum:
    return colorchecker_reflectances()["dark skin"]


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (illuminant, "name"),
        (illuminant_table, "name"),
        (led_spectrum, "name"),
        (luminous_efficiency, "kind"),
        (resolve_illuminant, "illuminant"),
        (lambda v: resolve_illuminant(v, name="test"), "test"),
        (lambda v: spectrum_to_xyz(_r(), illuminant=v), "illuminant"),
        (lambda v: spectrum_to_lms(_r(), illuminant=v), "illuminant"),
        (lambda v: spectrum_to_camera_rgb(_r(), illuminant=v), "illuminant"),
    ],
)
@pytest.mark.parametrize("bad", ["", HUGE, "tungsten", ["D65", "D65"], 0, True, object()])
def test_names_are_named_and_short(call: Callable[[Any], Any], name: str, bad: object) -> None:
    msg = _refused(lambda: call(bad), name)
    assert "xxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxxx" not in msg  # the value is cut


def test_unknown_names_keep_their_classes_and_list_the_valid_ones() -> None:
    with pytest.raises(
        InvalidInputError, match=r"unknown illuminant 'tungsten' for name; valid: A"
    ):
        illuminant("tungsten")
    msg = _refused(lambda: illuminant("tungsten"), "LED-B1 ... LED-V2")
    assert "D<cct/100>" in msg and "bb<T>" in msg
    with pytest.raises(UnknownOptionError, match="photopic"):
        luminous_efficiency("mesopic")
    with pytest.raises(InvalidInputError, match="'LED-B1'"):
        led_spectrum("LED-X")


def test_load_table_display_name_is_a_string() -> None:
    """A list used to reach the table cache (TypeError: unhashable type: 'list')."""
    _refused(lambda: load_table("cmf_2", ["a", "b"]), "name")  # type: ignore[arg-type]
    assert load_table("cmf_2", "mine").name == "mine"


def test_resolve_illuminant_names_the_callers_parameter() -> None:
    multi = Spectrum(np.linspace(400, 700, 7), np.ones((7, 2)))
    _refused(lambda: resolve_illuminant(multi, name="reference"), "reference")
    assert resolve_illuminant("D65", name="test").name == "CIE D65"
    assert resolve_illuminant(None, name="test") is None


@pytest.mark.parametrize("bad", [None, object(), True, 0, "ab"])
def test_from_columns_labels_is_a_sequence_of_str(bad: object) -> None:
    wl = np.linspace(400, 700, 7)
    _refused(lambda: Spectrum.from_columns(wl, [wl, wl], labels=bad), "labels")
    assert Spectrum.from_columns(wl, [wl, wl], labels=["a", "b"]).labels == ("a", "b")
