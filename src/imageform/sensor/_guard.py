"""Boundary checks private to :mod:`imageform.sensor` (issue 16)."""

from __future__ import annotations

import numbers

import numpy as np

from imageform._validate import describe
from imageform.errors import InvalidInputError

__all__ = ["MAX_MEAN_ELECTRONS", "check_electrons", "check_rng"]

#: The largest mean number of electrons per pixel a capture draws: far beyond any full well
#: (1e5-1e6 e⁻), and below NumPy's Poisson limit (about 9.2e18), which raises a bare
#: ``ValueError: lam value too large`` naming nothing.
MAX_MEAN_ELECTRONS = 1e15


def check_rng(rng: object, name: str = "rng") -> object:
    """Return ``rng`` unchanged when :func:`imageform._random.as_rng` takes it.

    Otherwise raise a one-line error that never prints an array.
    """
    if (
        rng is None
        or isinstance(rng, np.random.Generator | np.random.SeedSequence)
        or (isinstance(rng, numbers.Integral) and not isinstance(rng, bool | np.bool_))
    ):
        return rng
    raise InvalidInputError(
        f"expected {name} an int seed, a numpy.random.Generator or None, got {describe(rng)}"
    )


def check_electrons(mean: float, names: str) -> None:
    """Refuse a mean signal above :data:`MAX_MEAN_ELECTRONS` electrons per pixel."""
    if not mean <= MAX_MEAN_ELECTRONS:
        raise InvalidInputError(
            f"expected {names} giving at most {MAX_MEAN_ELECTRONS:g} mean electrons per pixel, "
            f"got {mean:.3g}"
        )
