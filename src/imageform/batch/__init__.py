"""imageform.batch: scale out over many files (a dask cluster) and over images larger than memory.

- :func:`run_batch` runs a command of :data:`COMMANDS` (convert, white-balance, demosaic,
  stain-normalize, harmonize) over the files matching a glob on a ``dask.distributed``
  cluster: resumable, atomic outputs, inputs never modified, failures collected.
- :func:`process_chunked` applies a pointwise colour operation to one tiled TIFF or Zarr array
  chunk by chunk with bounded memory (global statistics as real reductions).

``dask``/``distributed``/``zarr`` are imported only when these functions run.
"""

from imageform.batch.chunked import CHUNKED_COMMANDS, ChunkedResult, process_chunked
from imageform.batch.commands import COMMANDS, BatchCommand, get_command
from imageform.batch.runner import (
    BatchReport,
    Job,
    JobResult,
    plan_jobs,
    print_summary,
    run_batch,
    run_job,
)

__all__ = [
    "CHUNKED_COMMANDS",
    "COMMANDS",
    "BatchCommand",
    "BatchReport",
    "ChunkedResult",
    "Job",
    "JobResult",
    "get_command",
    "plan_jobs",
    "print_summary",
    "process_chunked",
    "run_batch",
    "run_job",
]
