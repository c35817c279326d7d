"""Exceptions and warnings raised by imageform.

Every error imageform raises on purpose is an :class:`ImageformError`. Errors about the
*value* of an argument are also :class:`ValueError` so that ``except ValueError`` keeps
working for callers who do not know about imageform.

- :class:`InvalidInputError` — an argument has the wrong shape, dtype, range or is not finite.
- :class:`UnknownOptionError` — an option name is not one of the valid ones (they are listed).
- :class:`DegenerateConfigurationError` — the input is valid but the geometry cannot determine
  the answer (coplanar points for a 3-D DLT, collinear points for a homography, too few views,
  a singular matrix); the message names the cause.
- :class:`ConvergenceError` — an iterative solver did not reach its tolerance in ``max_iter``.

An image that simply lacks what a detector looks for is not an error: the detector returns
its result with ``found`` False (one object) or an empty collection (any number of objects);
see docs/conventions.md, "Not found".

Every warning imageform issues is an :class:`ImageformWarning` (a ``UserWarning``), so that
``warnings.filterwarnings("ignore", category=ImageformWarning)`` silences them all and the
command line turns each into one ``imageform: warning: ...`` line.
"""

from __future__ import annotations

__all__ = [
    "ConvergenceError",
    "ConvergenceWarning",
    "DegenerateConfigurationError",
    "IllConditionedWarning",
    "ImageformError",
    "ImageformWarning",
    "InvalidInputError",
    "UnknownOptionError",
]


class ImageformError(Exception):
    """Base class of every exception imageform raises deliberately."""


class InvalidInputError(ImageformError, ValueError):
    """An argument has the wrong shape, dtype, range, or contains NaN/inf."""


class UnknownOptionError(InvalidInputError):
    """An option name (space, method, pattern, order ...) is not one of the valid names."""


class DegenerateConfigurationError(ImageformError, ValueError):
    """The input is well-formed but does not determine a unique answer."""


class ConvergenceError(ImageformError, RuntimeError):
    """An iterative solver did not converge within ``max_iter`` iterations."""


class ImageformWarning(UserWarning):
    """Base class of every warning imageform issues."""


class ConvergenceWarning(ImageformWarning):
    """Some elements of a batched iterative solve did not converge (see the returned mask)."""


class IllConditionedWarning(ImageformWarning):
    """The input is valid but poorly conditioned: results will be uncertain."""
