"""Boundary checks of the report functions (issue 16)."""

from __future__ import annotations

from imageform.simulate import SimulationResult

__all__ = ["check_result"]


def check_result(result: object, name: str = "result") -> None:
    """Raise :class:`TypeError` naming ``name`` unless ``result`` is a SimulationResult."""
    if not isinstance(result, SimulationResult):
        raise TypeError(
            f"expected {name} as a SimulationResult (imageform.simulate.simulate), "
            f"got {type(result).__name__}"
        )
