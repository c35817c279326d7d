"""Reinhard colour transfer as stain normalisation, in CIELAB (D65, sRGB's white).

Reinhard et al. (2001) matched per-channel means and standard deviations in Ruderman's
lαβ space (log LMS, decorrelated). The lecture, and most pathology pipelines, do the same
in CIE 1976 L*a*b*; imageform uses CIELAB computed from encoded sRGB with the D65 white of
sRGB (``convert(image, "srgb", "lab")``), so the sRGB white maps to L* = 100, a* = b* = 0.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from imageform._typing import Array, ArrayLike
from imageform._validate import as_bool, as_int, as_reals, describe, format_shape
from imageform.analysis._arrays import image_in, is_dask, read_json, target_source, write_json
from imageform.color.convert import convert
from imageform.errors import DegenerateConfigurationError, InvalidInputError

__all__ = ["REINHARD_SPACE", "ReinhardStats", "reinhard_normalize", "reinhard_stats"]

#: The space the statistics live in (named in the JSON so a file cannot be misread).
REINHARD_SPACE = "cielab_d65_from_srgb"


@dataclass(frozen=True)
class ReinhardStats:
    """Per-channel mean and (population) standard deviation of L*, a*, b*.

    ``n_pixels`` counts the pixels the statistics were taken over.
    """

    mean: tuple[float, float, float]
    std: tuple[float, float, float]
    n_pixels: int
    space: str = REINHARD_SPACE

    def __post_init__(self) -> None:
        """Three finite means, three finite stds >= 0, a pixel count >= 0, the one space."""
        object.__setattr__(self, "mean", as_reals(self.mean, "mean", 3))
        object.__setattr__(self, "std", as_reals(self.std, "std", 3, nonnegative=True))
        object.__setattr__(self, "n_pixels", as_int(self.n_pixels, "n_pixels", minimum=0))
        if self.space != REINHARD_SPACE:
            raise InvalidInputError(
                f"expected space {REINHARD_SPACE!r}, got {describe(self.space)}"
            )

    def to_json(self, path: str | Path) -> None:
        """Save as JSON (``kind: "reinhard_stats"``)."""
        write_json(
            path,
            {
                "kind": "reinhard_stats",
                "space": self.space,
                "mean": list(self.mean),
                "std": list(self.std),
                "n_pixels": self.n_pixels,
            },
        )

    @classmethod
    def from_json(cls, path: str | Path) -> ReinhardStats:
        """Load statistics saved by :meth:`to_json`."""
        d = read_json(path, "reinhard_stats")
        if d.get("space") != REINHARD_SPACE:
            raise InvalidInputError(
                f"expected statistics in {REINHARD_SPACE!r} in {path}, got "
                f"{describe(d.get('space'))}"
            )
        try:
            mean = tuple(float(v) for v in d["mean"])
            std = tuple(float(v) for v in d["std"])
            n = int(d["n_pixels"])
        except (KeyError, TypeError, ValueError) as exc:
            raise InvalidInputError(f"malformed Reinhard statistics in {path}: {exc}") from exc
        if len(mean) != 3 or len(std) != 3:
            raise InvalidInputError(f"expected 3 means and 3 stds in {path}")
        return cls(mean, std, n)


def _lab(rgb: Any) -> Any:
    if is_dask(rgb):
        return rgb.map_blocks(lambda b: np.asarray(convert(b, "srgb", "lab")), dtype=rgb.dtype)
    return np.asarray(convert(rgb, "srgb", "lab"))


def reinhard_stats(image: ArrayLike, mask: ArrayLike | None = None) -> ReinhardStats:
    r"""Mean and standard deviation of L*, a*, b* over the image (or its ``mask``).

    .. math:: \mu_k = \frac{1}{N}\sum_{i \in M} c_{ik}, \quad
        \sigma_k = \sqrt{\frac{1}{N}\sum_{i \in M} (c_{ik} - \mu_k)^2},
        \quad c = (L^*, a^*, b^*)

    Parameters
    ----------
    image : array_like, shape (..., 3)
        Encoded sRGB (floats in [0, 1], uint8, uint16) or a Dask array (statistics are
        Dask reductions, two passes: means, then squared deviations).
    mask : array_like of bool, shape (...), optional
        Pixels to use (e.g. tissue only). An empty mask raises.

    Returns
    -------
    ReinhardStats

    Notes
    -----
    Source: E. Reinhard, M. Ashikhmin, B. Gooch, P. Shirley, "Color transfer between
    images", IEEE CG&A 21(5), 2001, sec. 3 (statistics in lαβ; here CIELAB D65).

    Examples
    --------
    >>> s = reinhard_stats(np.array([[[1.0, 1.0, 1.0], [0.0, 0.0, 0.0]]]))
    >>> [round(v, 6) for v in s.mean], [round(v, 6) for v in s.std]
    ([50.0, 0.0, 0.0], [50.0, 0.0, 0.0])
    """
    rgb = image_in(image)
    lab = _lab(rgb)
    w: Any
    if mask is None:
        w = None
    else:
        w = mask if is_dask(mask) else np.asarray(mask)
        if np.dtype(w.dtype) != np.bool_ or tuple(w.shape) != tuple(rgb.shape[:-1]):
            raise InvalidInputError(
                f"expected mask as booleans of shape {format_shape(rgb.shape[:-1])}, "
                f"got {w.dtype} {format_shape(w.shape)}"
            )
    flat = lab.reshape((-1, 3)).astype(np.float64)
    if w is not None:
        wf = w.reshape((-1,)).astype(np.float64)[:, None]
        n = wf.sum()
    else:
        wf = None
        n = flat.shape[0]
    if is_dask(flat):
        import dask

        n = int(dask.compute(n)[0]) if is_dask(n) else int(n)
    n = int(n)
    if n == 0:
        raise InvalidInputError("reinhard_stats: the mask is empty (no pixel to take statistics)")
    s1 = flat.sum(axis=0) if wf is None else (flat * wf).sum(axis=0)
    mean = s1 / n
    if is_dask(mean):
        import dask

        mean = np.asarray(dask.compute(mean)[0])
    dev = (flat - mean) ** 2
    var = (dev.sum(axis=0) if wf is None else (dev * wf).sum(axis=0)) / n
    if is_dask(var):
        import dask

        var = np.asarray(dask.compute(var)[0])
    std = np.sqrt(np.asarray(var))
    return ReinhardStats(
        tuple(float(v) for v in mean),  # type: ignore[arg-type]
        tuple(float(v) for v in std),  # type: ignore[arg-type]
        n,
    )


def _target_stats(target: object) -> ReinhardStats:
    if isinstance(target, ReinhardStats):
        return target
    src = target_source(target, "target", "ReinhardStats")
    if isinstance(src, Path):
        return ReinhardStats.from_json(src)
    return reinhard_stats(src)


def _transfer(
    rgb: np.ndarray, mu_s: np.ndarray, gain: np.ndarray, mu_t: np.ndarray, clip: bool
) -> np.ndarray:
    lab = np.asarray(convert(rgb, "srgb", "lab"))
    out = (lab - mu_s.astype(lab.dtype)) * gain.astype(lab.dtype) + mu_t.astype(lab.dtype)
    res = np.asarray(convert(out, "lab", "srgb"))
    return np.clip(res, 0.0, 1.0) if clip else res


def reinhard_normalize(
    image: ArrayLike,
    target: ArrayLike,
    *,
    mask: ArrayLike | None = None,
    source_stats: ReinhardStats | None = None,
    clip: bool = False,
) -> Array:
    r"""Match the L*a*b* mean and standard deviation of ``image`` to ``target``'s.

    .. math:: c'_k = \frac{\sigma^t_k}{\sigma^s_k}(c_k - \mu^s_k) + \mu^t_k,
        \quad c = (L^*, a^*, b^*) \text{ (CIELAB, D65)}

    Parameters
    ----------
    image : array_like, shape (..., 3)
        Encoded sRGB, uint8/uint16, or Dask (statistics are reductions; the transfer runs
        chunk-wise).
    target : array_like or ReinhardStats or path
        A target image, its statistics, or a JSON file saved by :meth:`ReinhardStats.to_json`.
    mask : array_like of bool, optional
        Pixels of ``image`` to take its statistics over (the whole image is transformed).
    source_stats : ReinhardStats, optional
        Precomputed statistics of ``image`` (skips the pass over it).
    clip : bool
        Clip the result to [0, 1]. By default out-of-gamut values are returned as they are.

    Returns
    -------
    array, shape (..., 3)
        Encoded sRGB; float32 for float32/integer input.

    Raises
    ------
    DegenerateConfigurationError
        A channel of the source has zero standard deviation (a flat image).

    Notes
    -----
    Source: Reinhard et al. 2001, eq. (10)-(11) (there in lαβ; CIELAB here, as the lecture).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> a, b = rng.uniform(0.2, 0.6, (8, 8, 3)), rng.uniform(0.4, 0.9, (8, 8, 3))
    >>> out = reinhard_normalize(a, b)
    >>> np.allclose(reinhard_stats(out).mean, reinhard_stats(b).mean)
    True
    """
    rgb = image_in(image)
    tgt = _target_stats(target)
    if source_stats is not None and not isinstance(source_stats, ReinhardStats):
        raise TypeError(
            f"expected source_stats as ReinhardStats or None, got {type(source_stats).__name__}"
        )
    src = reinhard_stats(rgb, mask) if source_stats is None else source_stats
    sd_s = np.asarray(src.std)
    if np.any(sd_s == 0):
        raise DegenerateConfigurationError(
            f"reinhard_normalize: source channel std is zero (L*, a*, b* std = {src.std}); "
            "a flat image cannot be rescaled"
        )
    gain = np.asarray(tgt.std) / sd_s
    args = (np.asarray(src.mean), gain, np.asarray(tgt.mean), as_bool(clip, "clip"))
    if is_dask(rgb):
        return rgb.map_blocks(_transfer, *args, dtype=rgb.dtype)
    return _transfer(rgb, *args)
