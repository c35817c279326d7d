"""imageform.batch: scale out over many files (a dask cluster) and over images larger than memory.

- :func:`run_batch` runs a workflow of :mod:`imageform.workflows` that works file by file
  (convert, white-balance, cvd, mosaic, demosaic, stain-normalize, harmonize ...) over the
  files matching a glob on a ``dask.distributed`` cluster, with the single command's options
  and defaults: resumable (a manifest records what produced each output), atomic outputs,
  inputs never modified, failures collected.
- :func:`process_chunked` applies a pointwise colour operation to one TIFF or Zarr array
  chunk by chunk with bounded memory (global statistics as real reductions).

``dask``/``distributed``/``zarr`` (the ``scale`` extra) are imported only when these
functions run; a missing one is one line naming ``pip install "imageform[scale]"``.
"""

from imageform.batch.chunked import CHUNKED_COMMANDS, ChunkedResult, process_chunked
from imageform.batch.runner import (
    MANIFEST,
    BatchInterrupted,
    BatchReport,
    Job,
    JobResult,
    NoWorkersError,
    batch_options,
    batch_workflow,
    plan_jobs,
    print_summary,
    run_batch,
    run_job,
)

__all__ = [
    "CHUNKED_COMMANDS",
    "MANIFEST",
    "BatchInterrupted",
    "BatchReport",
    "ChunkedResult",
    "Job",
    "JobResult",
    "NoWorkersError",
    "batch_options",
    "batch_workflow",
    "plan_jobs",
    "print_summary",
    "process_chunked",
    "run_batch",
    "run_job",
]
