"""Boundary checks of the report functions (issue 16).

Only the checks of imageform.simulate's types live here; the generic ones (``check_path``)
are in :mod:`imageform._validate` (issue 30).
"""

from __future__ import annotations

from imageform.simulate import SimulationResult

__all__ = ["check_measurements", "check_result"]


def check_result(result: object, name: str = "result") -> None:
    """Raise :class:`TypeError` naming ``name`` unless ``result`` is a SimulationResult."""
    if not isinstance(result, SimulationResult):
        raise TypeError(
            f"expected {name} as a SimulationResult (imageform.simulate.simulate), "
            f"got {type(result).__name__}"
        )


def check_measurements(measurements: object, name: str = "measurements") -> None:
    """Raise :class:`TypeError` naming ``name`` unless ``measurements`` is PatchMeasurements."""
    from imageform.simulate.result import PatchMeasurements

    if not isinstance(measurements, PatchMeasurements):
        raise TypeError(
            f"expected {name} as PatchMeasurements (imageform.report.measure_patches), "
            f"got {type(measurements).__name__}"
        )
