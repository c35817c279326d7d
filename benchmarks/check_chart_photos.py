"""ColorCheckers in real photographs: occluders on neutral patches, the out-of-sRGB cyan,
and the correction against no correction (issue 26).

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_chart_photos.py

Cases: ``tests/analysis/test_chart_photos.py`` (a ColorChecker rendered into scikit-image's
real photographs with perspective, rotation, illuminant cast, uneven light, blur, noise,
JPEG). Occluders: a flat rectangle (beige, dark grey, brick) over the white, neutral 8 or
neutral 5 patch, seeds 1 and 2, and a beige card over the white patch of a chart lit by the
reference light (no cast: the chart is nearly right as it is), seeds 0-5. Per case: whether
the occluded patch is flagged (missing) and which patches are, and the mean CIEDE2000 of
the usable patches to the published values before and after the 3 x 3 correction.
Then ten clean charts whose patches are rendered from the ColorChecker's reflectances
(the cyan outside sRGB): in how many the cyan is kept.
"""

from __future__ import annotations

import warnings

import numpy as np

import imageform.analysis.synthetic as synthetic
from benchmarks._common import header, markdown_table
from imageform.analysis import (
    ChartWarning,
    correction_report,
    fit_color_correction,
    synthetic_chart_photo,
)
from tests.analysis.chart_cases import _jpeg
from tests.analysis.test_chart_photos import (
    _PHOTOS,
    CYAN,
    REF,
    WHITE,
    _measure,
    _photo,
    _spectral_chart_srgb8,
)


def _row(name: str, img: np.ndarray, patch: int) -> list[str]:
    pat = _measure(img)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ChartWarning)
        s = correction_report(pat, REF, fit_color_correction(pat, REF)).summary()
    return [
        name,
        str(bool(pat.missing[patch])),
        str(np.flatnonzero(pat.missing).tolist()),
        f"{s['mean_before']:.2f} -> {s['mean_after']:.2f}",
    ]


def main() -> None:
    from skimage import data

    photos = [np.asarray(getattr(data, n)(), dtype=np.float64) / 255.0 for n in _PHOTOS]
    rows = []
    for patch in (18, 19, 21):
        for occ in ((0.8, 0.75, 0.7), (0.3, 0.3, 0.32), (0.55, 0.35, 0.3)):
            for seed in (1, 2):
                img = _photo(photos, seed, occlude=patch, occluder=occ)
                rows.append(_row(f"patch {patch}, {occ}, seed {seed}", img, patch))
    for seed in range(6):
        rng = np.random.default_rng([27, seed])
        p = synthetic_chart_photo(
            photos[seed],
            width=rng.uniform(0.3, 0.6),
            tilt=rng.uniform(0.0, 35.0),
            rotation=rng.uniform(-180.0, 180.0),
            shading=0.0,
            blur=0.7,
            noise=0.005,
            cast=(1.0, 1.0, 1.0),
            rng=rng,
        )
        img = p.image.copy()
        cu, cv = p.centers[WHITE]
        half = int(0.5 * np.linalg.norm(p.centers[1] - p.centers[0]))
        img[int(cv) - half : int(cv) + half + 1, int(cu) - half : int(cu) + half + 1] = (
            0.8,
            0.75,
            0.7,
        )
        rows.append(_row(f"no cast, beige on white, seed {seed}", _jpeg(img, 90), WHITE))
    print(header("ColorChecker occluders and corrections in real photographs (issue 26)"))
    cols = ["case", "occluded patch flagged", "missing", "mean dE00 before -> after (3x3)"]
    print(markdown_table(cols, rows))
    orig = synthetic.COLORCHECKER_SRGB8
    setattr(synthetic, "COLORCHECKER_SRGB8", _spectral_chart_srgb8())  # noqa: B010
    try:
        imgs = [_photo(photos, seed) for seed in range(10)]
    finally:
        setattr(synthetic, "COLORCHECKER_SRGB8", orig)  # noqa: B010
    kept = [not _measure(img).missing[CYAN] for img in imgs]
    print(f"out-of-sRGB cyan kept in {sum(kept)} of {len(kept)} clean charts")


if __name__ == "__main__":
    main()
