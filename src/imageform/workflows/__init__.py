"""imageform.workflows: the file-level operations behind every command.

Each workflow reads files, calls the library and writes its outputs all or nothing, with its
options as a typed dataclass. The command line (``imageform``) and ``imageform batch`` are
generated from :data:`WORKFLOWS`; from Python, :func:`execute` runs one by name::

    from imageform.workflows import execute, get_workflow
    wf = get_workflow("white-balance")
    opts = wf.make_options(method="gray-world")
    result = execute(wf, image="in.png", out="out.png", options=opts)
    result.summary["gains"]
"""

from imageform.workflows._execute import execute, run_file
from imageform.workflows._spec import (
    Input,
    Options,
    Output,
    Result,
    Run,
    Workflow,
    choice_names,
    flag_of,
    normalize_choice,
)
from imageform.workflows.characterize import (
    CameraCharacterization,
    ColorMeasurement,
    GeometryMeasurement,
    NoiseMeasurement,
    SharpnessMeasurement,
    characterize_camera,
)
from imageform.workflows.registry import WORKFLOWS, get_workflow

__all__ = [
    "WORKFLOWS",
    "CameraCharacterization",
    "ColorMeasurement",
    "GeometryMeasurement",
    "Input",
    "NoiseMeasurement",
    "Options",
    "Output",
    "Result",
    "Run",
    "SharpnessMeasurement",
    "Workflow",
    "characterize_camera",
    "choice_names",
    "execute",
    "flag_of",
    "get_workflow",
    "normalize_choice",
    "run_file",
]
