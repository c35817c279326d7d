"""Exceptions and warnings raised by imageform.

Every error imageform raises on purpose is an :class:`ImageformError`. Errors about the
*value* of an argument are also :class:`ValueError` so that ``except ValueError`` keeps
working for callers who do not know about imageform.

- :class:`InvalidInputError` — an argument has the wrong shape, dtype, range or is not finite.
- :class:`UnknownOptionError` — an option name is not one of the valid ones (they are listed).
- :class:`UnreadableFileError` — a file cannot be read as what it was asked to be: empty,
  truncated, not of its format, or a kind imageform does not read (its ``reason`` says which).
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

import os

__all__ = [
    "ConvergenceError",
    "ConvergenceWarning",
    "DegenerateConfigurationError",
    "IllConditionedWarning",
    "ImageformError",
    "ImageformWarning",
    "InvalidInputError",
    "UnknownOptionError",
    "UnreadableFileError",
]


class ImageformError(Exception):
    """Base class of every exception imageform raises deliberately."""


class InvalidInputError(ImageformError, ValueError):
    """An argument has the wrong shape, dtype, range, or contains NaN/inf."""


class UnknownOptionError(InvalidInputError):
    """An option name (space, method, pattern, order ...) is not one of the valid names."""


class UnreadableFileError(InvalidInputError):
    """A file cannot be read as what it was asked to be.

    The file exists but is empty, truncated, not of the format it was read as, or holds a
    kind of image imageform does not read (an animated GIF, a CMYK TIFF, a JPEG 2000 DICOM
    without its decoder). The message is ``cannot read PATH: REASON``; ``path`` and
    ``reason`` keep its two parts, so that a caller reading a folder can skip such a file
    and say why (``imageform calibrate`` on a folder does).

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    reason : str
        Why it cannot be read, in a few words ("an empty file (0 bytes)").

    Attributes
    ----------
    path, reason : str
        As given.
    brief : str
        ``reason`` for a note that names the file already: without the file's name (a
        decoder's own words may repeat it) and without an empty file's byte count
        ("an empty file").
    """

    def __init__(self, path: str | os.PathLike[str], reason: str) -> None:
        self.path = os.fspath(path)
        self.reason = reason
        brief = reason.removesuffix(" (0 bytes)")
        self.brief = brief.replace(f" '{self.path}'", "").replace(f" {self.path}", "")
        super().__init__(f"cannot read {self.path}: {reason}")

    def __reduce__(self) -> tuple[type[UnreadableFileError], tuple[str, str]]:
        """Pickle by ``path`` and ``reason`` (the default would pass the message alone)."""
        return (type(self), (self.path, self.reason))


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
