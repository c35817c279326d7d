"""Random numbers of the simulator (SPEC 7).

``rng`` is an int seed, a NumPy Generator or None, and ``seed=`` is kept one release as a deprecated
alias.

Internal to :mod:`imageform.simulate` (used by :func:`~imageform.simulate.simulate` and
:func:`~imageform.simulate.truth.detect_vanishing`).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from imageform.errors import InvalidInputError

RNGLike = int | np.integer | np.random.Generator | None

__all__ = ["RNGLike", "RandomSource", "random_source"]


@dataclass(frozen=True)
class RandomSource:
    """Where each random step of a run draws from.

    An int seed ``s`` gives every step its own ``np.random.default_rng(s)`` (the sensor
    noise, the RANSAC of the vanishing-point detector, the photon-transfer frames), exactly
    as ``seed=s`` did, so a seed reproduces earlier runs pixel for pixel. A Generator is
    shared by the steps, drawn from in turn (the detector gets an int seed drawn from it).
    """

    seed: int | None
    generator: np.random.Generator | None

    def for_step(self) -> np.random.Generator:
        """Return the generator of one random step."""
        if self.seed is not None:
            return np.random.default_rng(self.seed)
        assert self.generator is not None
        return self.generator

    def int_seed(self) -> int:
        """Return an int seed for a function that takes only one."""
        if self.seed is not None:
            return self.seed
        assert self.generator is not None
        return int(self.generator.integers(0, 2**63 - 1))


def random_source(rng: RNGLike, seed: int | None, where: str) -> RandomSource:
    """Check ``rng`` (and the deprecated ``seed``) of function ``where``.

    ``seed`` given: a DeprecationWarning naming ``rng``; both given: an error.

    Examples
    --------
    >>> random_source(3, None, "simulate").seed
    3
    """
    if seed is not None:
        warnings.warn(
            f"{where}(seed=...) is deprecated and will be removed in the next release: "
            "use rng=... (an int seed, a numpy.random.Generator or None)",
            DeprecationWarning,
            stacklevel=3,
        )
        if rng is not None:
            raise InvalidInputError(f"{where}: give rng or the deprecated seed, not both")
        rng = seed
    if isinstance(rng, bool) or not (
        rng is None or isinstance(rng, int | np.integer | np.random.Generator)
    ):
        raise InvalidInputError(
            f"{where}: expected rng to be an int seed, a numpy.random.Generator or None, "
            f"got {type(rng).__name__}"
        )
    if isinstance(rng, np.random.Generator):
        return RandomSource(None, rng)
    if rng is None:
        return RandomSource(None, np.random.default_rng())
    if int(rng) < 0:
        raise InvalidInputError(f"{where}: expected a seed rng >= 0, got {int(rng)}")
    return RandomSource(int(rng), None)
