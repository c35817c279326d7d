"""The registry: every workflow by its command name.

The command line and ``imageform batch`` are generated from it.
"""

from __future__ import annotations

from types import MappingProxyType

from imageform.errors import UnknownOptionError
from imageform.workflows import (
    analysis,
    calibration,
    characterize,
    chart,
    color,
    emva,
    flatfield,
    geometry,
    lecture,
    optics,
    raw,
    reconstruct,
    sensor,
    sharpness,
    simulate,
    stereo,
    track,
    vanishing,
)
from imageform.workflows._spec import Workflow, _describe

__all__ = ["WORKFLOWS", "get_workflow"]

#: Workflows by command name, in the order ``imageform --help`` lists them within a group.
WORKFLOWS = MappingProxyType(
    {
        w.name: w
        for w in (
            *simulate.WORKFLOWS,
            *characterize.WORKFLOWS,
            *lecture.WORKFLOWS,
            *color.WORKFLOWS,
            *raw.WORKFLOWS,
            *geometry.WORKFLOWS,
            *calibration.WORKFLOWS,
            *stereo.WORKFLOWS,
            *track.WORKFLOWS,
            *reconstruct.WORKFLOWS,
            *vanishing.WORKFLOWS,
            *optics.WORKFLOWS,
            *sensor.WORKFLOWS,
            *emva.WORKFLOWS,
            *analysis.WORKFLOWS,
            *flatfield.WORKFLOWS,
            *chart.WORKFLOWS,
            *sharpness.WORKFLOWS,
        )
    }
)


def get_workflow(name: str) -> Workflow:
    """Return the workflow ``name`` (``-`` or ``_`` alike); unknown names list the valid ones.

    Examples
    --------
    >>> get_workflow("white_balance").name
    'white-balance'
    """
    describe = _describe
    if not isinstance(name, str):
        raise UnknownOptionError(
            f"expected the workflow (command) name as text, got {describe(name)}"
        )
    key = name.strip().lower().replace("_", "-")
    if key not in WORKFLOWS:
        raise UnknownOptionError(
            f"unknown workflow (command) name {describe(name)}; valid: {_shown(tuple(WORKFLOWS))}"
        )
    return WORKFLOWS[key]


def _shown(names: tuple[str, ...], width: int = 80) -> str:
    """As many names as fit ``width`` characters, then how many more."""
    out = ""
    for i, n in enumerate(names):
        part = (", " if out else "") + n
        if len(out) + len(part) > width:
            return out + f", ... ({len(names) - i} more: imageform --help)"
        out += part
    return out
