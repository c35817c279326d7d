"""The shared boundary checks for scalars, counts, sizes and memory (imageform._validate)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from imageform._validate import (
    as_bool,
    as_int,
    as_real,
    as_size,
    check_image_size,
    check_memory,
    check_positive,
    describe,
    memory_limit,
)
from imageform.errors import InvalidInputError

BAD_NUMBERS = [None, "5", b"5", 1 + 2j, np.complex64(1), True, np.bool_(False), [1.0], object()]


@pytest.mark.parametrize("bad", BAD_NUMBERS)
def test_as_real_refuses_what_is_not_a_real_number(bad: object) -> None:
    with pytest.raises(InvalidInputError, match=r"^expected sigma as a (real )?number") as info:
        as_real(bad, "sigma")
    assert "\n" not in str(info.value) and len(str(info.value)) < 200


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf, np.float32("nan")])
def test_as_real_refuses_non_finite(value: float) -> None:
    with pytest.raises(InvalidInputError, match="finite"):
        as_real(value, "x")
    assert as_real(math.inf, "x", allow_inf=True) == math.inf


def test_as_real_bounds_and_numpy_scalars() -> None:
    assert as_real(np.float32(2.5), "a") == 2.5 and as_real(np.int64(3), "a") == 3.0
    assert as_real(np.array(4.0), "a") == 4.0  # a 0-d array
    with pytest.raises(InvalidInputError, match="expected a > 0, got 0"):
        as_real(0, "a", positive=True)
    with pytest.raises(InvalidInputError, match="expected a >= 0"):
        as_real(-1e-300, "a", nonnegative=True)
    with pytest.raises(InvalidInputError, match="expected a <= 100"):
        as_real(101, "a", maximum=100)
    assert check_positive(0.0, "t", allow_zero=True) == 0.0


@given(st.integers(min_value=-(2**70), max_value=2**70))
def test_as_int_takes_every_integer_kind(n: int) -> None:
    assert as_int(n, "n") == n
    if -(2**63) <= n < 2**63:
        assert as_int(np.int64(n), "n") == n


@pytest.mark.parametrize("bad", [2.0, math.inf, "3", None, True, np.float64(1), 1 + 0j])
def test_as_int_refuses_non_integers(bad: object) -> None:
    with pytest.raises(InvalidInputError, match="expected n as an integer"):
        as_int(bad, "n")


def test_as_int_bounds() -> None:
    with pytest.raises(InvalidInputError, match="expected max_iter >= 1, got 0"):
        as_int(0, "max_iter", minimum=1)
    with pytest.raises(InvalidInputError, match="expected n <= 10"):
        as_int(np.uint64(11), "n", maximum=10)


def test_as_bool_and_sizes() -> None:
    assert as_bool(np.True_, "clip") is True
    with pytest.raises(InvalidInputError, match="True or False"):
        as_bool(1, "clip")
    assert as_size((640, np.int64(480)), "size") == (640, 480)
    assert check_image_size([3, 2]) == (3, 2)
    with pytest.raises(InvalidInputError, match=r"expected image_size \(width, height\) as 2"):
        check_image_size((5,))  # not "not enough values to unpack"
    with pytest.raises(InvalidInputError, match=r"size\[1\] as an integer"):
        as_size((5, 2.5), "size")
    with pytest.raises(InvalidInputError, match=r"size\[0\] >= 1"):
        as_size((0, 2), "size")
    with pytest.raises(InvalidInputError, match="as 2 integers"):
        as_size("ab", "size")


def test_memory_bound(monkeypatch: pytest.MonkeyPatch) -> None:
    assert memory_limit() > 2**28
    check_memory(2**20, "shape")
    with pytest.raises(InvalidInputError, match=r"disc: a kernel would need 149\.0 GiB"):
        check_memory(149 * 2**30, "disc", "a kernel")
    monkeypatch.setenv("IMAGEFORM_MAX_MEMORY", "1M")
    assert memory_limit() == 2**20
    with pytest.raises(InvalidInputError, match="IMAGEFORM_MAX_MEMORY"):
        check_memory(2**21, "shape")
    with pytest.raises(InvalidInputError, match="IMAGEFORM_MAX_MEMORY"):
        check_memory(math.nan, "shape")


@pytest.mark.parametrize(
    ("text", "n"),
    [("4GiB", 4 * 2**30), ("4G", 4 * 2**30), ("4 GB", 4 * 2**30), ("512MiB", 2**29),
     ("1.5g", 3 * 2**29), ("123456", 123456), ("1e9", 10**9), ("2T", 2 * 2**40)],
)  # fmt: skip
def test_memory_budget_units(monkeypatch: pytest.MonkeyPatch, text: str, n: int) -> None:
    """Issue 25: the budget reads as written in the docs (``IMAGEFORM_MAX_MEMORY=4GiB``)."""
    monkeypatch.setenv("IMAGEFORM_MAX_MEMORY", text)
    assert memory_limit() == n


def test_memory_budget_default_and_refusals(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("IMAGEFORM_MAX_MEMORY", raising=False)
    assert memory_limit() == 4 * 2**30  # documented: 4 GiB, whatever the machine
    for bad in ("lots", "-1G", "0", "4XB", "nan", "1e400"):
        monkeypatch.setenv("IMAGEFORM_MAX_MEMORY", bad)
        with pytest.raises(InvalidInputError, match="IMAGEFORM_MAX_MEMORY") as err:
            memory_limit()
        assert "\n" not in str(err.value)


def test_describe_never_prints_an_array() -> None:
    text = describe(np.zeros((1000, 1000)))
    assert text == "ndarray of shape (1000, 1000), float64"
    assert len(describe("x" * 10_000)) == 40


def test_points_pass_bounded_says_when_as_points_bounded_returns_the_arrays() -> None:
    """True exactly where as_points_bounded would return each array itself, unrefused."""
    from imageform._validate import MAX_MAGNITUDE, as_points_bounded, points_pass_bounded

    good = [np.zeros((4, 2)), np.full((2, 5, 2), -MAX_MAGNITUDE), np.zeros((0, 2))]
    assert points_pass_bounded(good, 2)
    assert all(as_points_bounded(a, "p", 2) is a for a in good)
    assert points_pass_bounded([], 3)
    nan, big = np.zeros((3, 2)), np.zeros((3, 2))
    nan[1, 0], big[2, 1] = np.nan, 2 * MAX_MAGNITUDE
    for bad in (
        np.zeros((4, 2), np.float32),  # converted: a new array
        np.zeros((4, 2)).tolist(),
        np.zeros((4, 3)),
        np.zeros((4, 2), bool),
        np.float64(1.0),
        nan,
        big,
    ):
        assert not points_pass_bounded([np.zeros((4, 2)), bad], 2)
    with pytest.raises(InvalidInputError, match="NaN or inf"):
        as_points_bounded(nan, "p", 2)
    with pytest.raises(InvalidInputError, match="within"):
        as_points_bounded(big, "p", 2)
