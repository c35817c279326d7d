"""The stain-normalisation methods of :mod:`imageform.analysis`: one registry.

Not the stain-*vector* estimators (:data:`imageform.analysis.STAIN_VECTOR_METHODS`).
"""

from __future__ import annotations

from collections.abc import Callable
from types import MappingProxyType
from typing import Any

from imageform.analysis.macenko import macenko_normalize
from imageform.analysis.reinhard import reinhard_normalize

__all__ = ["STAIN_NORMALIZATION_METHODS"]

#: Stain-normalisation methods, each name mapped to its function ``f(image, target, ...)``
#: (read-only); the first is the default of ``imageform stain-normalize``:
#: ``"macenko"`` (optical-density stain vectors, :func:`macenko_normalize`) and
#: ``"reinhard"`` (CIELAB statistics, :func:`reinhard_normalize`).
STAIN_NORMALIZATION_METHODS: MappingProxyType[str, Callable[..., Any]] = MappingProxyType(
    {"macenko": macenko_normalize, "reinhard": reinhard_normalize}
)
