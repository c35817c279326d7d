"""What ``imageform track`` and ``imageform reconstruct`` say about an interlaced video."""

from __future__ import annotations

import math
from dataclasses import asdict
from typing import TYPE_CHECKING, Any, Literal, get_args

from imageform.workflows._spec import option

if TYPE_CHECKING:
    from imageform.io import VideoReader

__all__ = [
    "DEINTERLACE_CHOICES",
    "FIELD_ORDER_CHOICES",
    "DeinterlaceChoice",
    "FieldOrderChoice",
    "deinterlace_note",
    "deinterlace_summary",
    "field_order_option",
]

#: ``--deinterlace``: the reader's methods (:data:`imageform.io.DEINTERLACE_METHODS`, a test
#: keeps the two equal; spelt out here so that ``--help`` imports no NumPy).
DeinterlaceChoice = Literal["auto", "off", "fields", "linear", "blend"]
DEINTERLACE_CHOICES: tuple[str, ...] = get_args(DeinterlaceChoice)
#: ``--field-order``: the field first in time (:data:`imageform.io.FIELD_ORDERS`).
FieldOrderChoice = Literal["top", "bottom"]
FIELD_ORDER_CHOICES: tuple[str, ...] = get_args(FieldOrderChoice)


def field_order_option() -> Any:
    """Return the ``--field-order`` option of every command that reads an interlaced video.

    Declared once here (``track`` and ``reconstruct``: ``field_order: FieldOrderChoice | None
    = field_order_option()``), so that its help, choices and default are one; a field, not a
    base class as :class:`~imageform.workflows._images.OnDevice` is, so that ``--help`` lists
    it beside each command's own ``--deinterlace``.
    """
    return option(
        None,
        help="The field first in time, top or bottom (default: the frames', else the "
        "stream's, else top).",
        choices=FIELD_ORDER_CHOICES,
    )


def deinterlace_summary(reader: VideoReader) -> dict[str, Any]:
    """Return what the reader found and did about interlacing, for a summary (JSON-safe)."""
    interlacing = getattr(reader, "interlacing", None)  # a stand-in reader may not say
    found = None
    if interlacing is not None:
        found = {
            k: (None if isinstance(v, float) and not math.isfinite(v) else v)
            for k, v in asdict(interlacing).items()
        }
    return {
        "method": getattr(reader, "deinterlaced", "off"),
        "field_order": getattr(reader, "field_order", None),
        "found": found,
    }


def deinterlace_note(reader: VideoReader, fps: float, what_is_done: str = "tracking") -> str:
    """Say what the reader found and did about interlacing.

    "" when it did not look, and when it looked and found a progressive clip the stream
    does not flag as interlaced (the ordinary clip: nothing to say; the summary keeps it).
    """
    found = getattr(reader, "interlacing", None)
    if found is None:
        return ""
    flagged = found.stream is not None and found.stream != "progressive"
    if reader.deinterlaced == "off" and not found.interlaced and not flagged:
        return ""
    what = found.describe()
    method = reader.deinterlaced
    if method == "fields":
        if what_is_done == "tracking":
            return f"{what}: tracking fields at {2 * fps:g} per second"
        return f"{what}: {what_is_done} the {reader.field_order} field of each frame"
    if method == "linear":
        return f"{what}: frames deinterlaced (linear, the {reader.field_order} field kept)"
    if method == "blend":
        return f"{what}: frames deinterlaced (blend of the two fields)"
    return f"{what}: frames as decoded"
