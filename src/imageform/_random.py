"""The one way imageform turns an ``rng`` argument into a NumPy Generator (SPEC 7).

Every public function that draws random numbers takes ``rng`` (keyword-only), following
Scientific Python SPEC 7 ("Seeding pseudo-random number generation"):

- an ``int`` (or a :class:`numpy.random.SeedSequence`) seeds a new Generator, so the same
  seed gives the same numbers;
- a :class:`numpy.random.Generator` is used as is (and advanced);
- ``None`` draws fresh entropy from the operating system.

Internal module: imageform's packages share it.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from typing import TypeAlias

import numpy as np

from imageform.errors import InvalidInputError

__all__ = ["RNGLike", "as_rng"]

#: What an ``rng`` parameter accepts.
RNGLike: TypeAlias = "int | np.integer | np.random.SeedSequence | np.random.Generator | None"


def as_rng(rng: object, name: str = "rng", *, mix: Sequence[int] = ()) -> np.random.Generator:
    """Return a :class:`numpy.random.Generator` from ``rng`` (SPEC 7).

    ``mix`` adds integers to an integer seed's entropy (``SeedSequence([seed, *mix])``), for
    a draw that must depend on, e.g., the shape as well as the seed. A Generator is returned
    unchanged whatever ``mix`` holds.

    Examples
    --------
    >>> float(as_rng(0).random()) == float(np.random.default_rng(0).random())
    True
    >>> g = np.random.default_rng(1)
    >>> as_rng(g) is g
    True
    """
    if isinstance(rng, np.random.Generator):
        return rng
    if rng is None:
        return np.random.default_rng()
    if isinstance(rng, np.random.SeedSequence):
        return np.random.default_rng(rng)
    if isinstance(rng, numbers.Integral) and not isinstance(rng, bool):
        seed = int(rng)
        if seed < 0:
            raise InvalidInputError(f"expected {name} as a non-negative int seed, got {seed}")
        if mix:
            return np.random.default_rng(np.random.SeedSequence([seed, *(int(m) for m in mix)]))
        return np.random.default_rng(seed)
    from imageform._validate import describe

    raise InvalidInputError(
        f"expected {name} as an int seed, a numpy.random.Generator or None, got {describe(rng)}"
    )
