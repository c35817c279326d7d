"""The registry: every workflow by its command name (the command line and ``imageform
batch`` are generated from it)."""

from __future__ import annotations

from types import MappingProxyType

from imageform.errors import UnknownOptionError
from imageform.workflows import (
    analysis,
    calibration,
    chart,
    color,
    geometry,
    lecture,
    optics,
    raw,
    sensor,
    sharpness,
    simulate,
    stereo,
    vanishing,
)
from imageform.workflows._spec import Workflow

__all__ = ["WORKFLOWS", "get_workflow"]

#: Workflows by command name, in the order ``imageform --help`` lists them within a group.
WORKFLOWS = MappingProxyType(
    {
        w.name: w
        for w in (
            *simulate.WORKFLOWS,
            *lecture.WORKFLOWS,
            *color.WORKFLOWS,
            *raw.WORKFLOWS,
            *geometry.WORKFLOWS,
            *calibration.WORKFLOWS,
            *stereo.WORKFLOWS,
            *vanishing.WORKFLOWS,
            *optics.WORKFLOWS,
            *sensor.WORKFLOWS,
            *analysis.WORKFLOWS,
            *chart.WORKFLOWS,
            *sharpness.WORKFLOWS,
        )
    }
)


def get_workflow(name: str) -> Workflow:
    """The workflow called ``name`` (``-`` or ``_`` alike); unknown names list the valid ones.

    Examples
    --------
    >>> get_workflow("white_balance").name
    'white-balance'
    """
    key = str(name).strip().lower().replace("_", "-")
    if key not in WORKFLOWS:
        raise UnknownOptionError(f"unknown command {name!r}; valid: {', '.join(WORKFLOWS)}")
    return WORKFLOWS[key]
