"""Realistic chart photographs for the ColorChecker detector's tests and benchmark.

A rendered ColorChecker (:func:`imageform.analysis.synthetic_chart_photo`: random
perspective up to 40 degrees of tilt, any rotation, 10-60 % of the frame width, an
illuminant cast, vignetting and a light ramp, blur, noise) composited into a REAL photograph
of clutter from ``../shared/data/kodak`` (read at run time, never copied), then JPEG
compressed; some cases have a few patches occluded by a textured crop of another photograph.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from imageform.analysis import synthetic_chart_photo


@dataclass(frozen=True)
class ChartCase:
    """One test photograph and its truth."""

    image: np.ndarray  # uint8 (H, W, 3), JPEG-decoded
    centres: np.ndarray  # (24, 2) true patch centres
    pitch: float  # smallest distance between neighbouring true centres (pixels)
    occluded: np.ndarray  # (24,) bool: patch covered by clutter
    patches: np.ndarray  # (24, 3) true encoded sRGB of the patches as lit (before blur, noise)
    params: dict[str, float]


def kodak_images(data: Path) -> list[np.ndarray]:
    """The 24 Kodak photographs as float sRGB in [0, 1]."""
    from PIL import Image

    files = sorted((data / "kodak").glob("kodim*.png"))
    return [np.asarray(Image.open(f).convert("RGB"), dtype=np.float64) / 255.0 for f in files]


def _jpeg(img: np.ndarray, quality: int) -> np.ndarray:
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.round(np.clip(img, 0, 1) * 255).astype(np.uint8)).save(
        buf, "JPEG", quality=quality
    )
    buf.seek(0)
    return np.asarray(Image.open(buf).convert("RGB"))


def _pitch(centres: np.ndarray) -> float:
    g = centres.reshape(4, 6, 2)
    du = np.linalg.norm(np.diff(g, axis=1), axis=2)
    dv = np.linalg.norm(np.diff(g, axis=0), axis=2)
    return float(min(du.min(), dv.min()))


def chart_case(
    backgrounds: list[np.ndarray],
    seed: int,
    *,
    occlude: int | None = None,
    width: tuple[float, float] = (0.1, 0.6),
) -> ChartCase:
    """Case number ``seed``: a random background, chart pose, light, blur, noise, JPEG, and
    ``occlude`` patches covered (default: 0 in 4 cases out of 5, else 1 to 3); the chart's
    lattice spans ``width`` (a range) of the frame width."""
    rng = np.random.default_rng([17, seed])
    bg = backgrounds[int(rng.integers(len(backgrounds)))]
    if rng.uniform() < 0.5:  # a horizontal flip of the background: more clutter variety
        bg = bg[:, ::-1]
    params = {
        "width": float(rng.uniform(*width)),
        "tilt": float(rng.uniform(0.0, 40.0)),
        "rotation": float(rng.uniform(-180.0, 180.0)),
        "shading": float(rng.uniform(0.0, 0.5)),
        "blur": float(rng.uniform(0.3, 1.5)),
        "noise": float(rng.uniform(0.0, 0.02)),
    }
    cast = rng.uniform(0.55, 1.1, 3)
    photo = synthetic_chart_photo(bg, cast=cast, rng=rng, **params)
    img = photo.image.copy()
    n_occ = (0 if rng.uniform() < 0.8 else int(rng.integers(1, 4))) if occlude is None else occlude
    occluded = np.zeros(24, dtype=bool)
    pitch = _pitch(photo.centers)
    if n_occ:
        # textured crops of another photograph over a few patches (not the whole chart)
        other = backgrounds[int(rng.integers(len(backgrounds)))]
        for k in rng.choice(24, n_occ, replace=False):
            cu, cv = photo.centers[k]
            half = int(np.ceil(0.45 * pitch))
            v0, v1 = max(int(cv) - half, 0), min(int(cv) + half + 1, img.shape[0])
            u0, u1 = max(int(cu) - half, 0), min(int(cu) + half + 1, img.shape[1])
            if v1 <= v0 or u1 <= u0:
                continue
            oy = int(rng.integers(0, other.shape[0] - (v1 - v0)))
            ox = int(rng.integers(0, other.shape[1] - (u1 - u0)))
            img[v0:v1, u0:u1] = other[oy : oy + v1 - v0, ox : ox + u1 - u0]
            occluded[k] = True
    quality = int(rng.integers(70, 96))
    params["jpeg_quality"] = quality
    params["occluded"] = float(occluded.sum())
    return ChartCase(_jpeg(img, quality), photo.centers, pitch, occluded, photo.patches, params)
