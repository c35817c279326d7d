"""Macenko with the automatic I0 against torchstain, on H&E tiles with and without glass
(issue 26).

Run::

    OPENBLAS_NUM_THREADS=1 PYTHONPATH=src:. python benchmarks/check_stain_glass.py

Tiles: ``tests/analysis/test_stain_glass.py`` (8-bit H&E by Beer-Lambert with Ruifrok &
Johnston's H and E vectors, smooth stroma and nuclei, sensor noise, optionally JPEG 85; with
a glass region covering 30 % of the tile at I0 = 240/255, or none). The target is a
glass-bearing tile. The peer is torchstain's numpy Macenko (Io = 240, alpha = 1,
beta = 0.15) normalising the same tile to the same target. Per tile: the I0 imageform
estimates (and whether it found glass), and the mean CIEDE2000 between imageform's
``macenko_normalize`` (defaults) and torchstain's output, then the same with the source's
I0 given as 240/255.
"""

from __future__ import annotations

import numpy as np

from benchmarks._common import header, markdown_table
from imageform.analysis import estimate_background, macenko_normalize, macenko_stains
from tests.analysis.test_stain_glass import _de, _tile


def main() -> None:
    from torchstain.numpy.normalizers import NumpyMacenkoNormalizer

    target = _tile(0.3, (1.9, 1.0), 100)
    peer = NumpyMacenkoNormalizer()
    peer.fit(target, Io=240, alpha=1, beta=0.15)
    rows = []
    cases = [(0.0, s) for s in ((0.6, 0.4), (1.0, 0.3), (0.8, 0.5))]
    cases += [(0.3, s) for s in ((1.9, 1.0), (1.2, 0.6))]
    for glass, stain in cases:
        for jpeg in (0, 85):
            src = _tile(glass, stain, 7, jpeg=jpeg)
            ref = np.asarray(peer.normalize(src, Io=240, alpha=1, beta=0.15, stains=False)[0])
            est = estimate_background(src)
            out = macenko_normalize(src, target)
            given = macenko_normalize(src, target, source=macenko_stains(src, i0=240 / 255))
            rows.append(
                [
                    f"{glass:.0%}",
                    str(stain),
                    str(jpeg or "-"),
                    str(np.round(est.i0 * 255).astype(int).tolist()),
                    "glass" if est.found else "default",
                    f"{_de(out, ref / 255):.2f}",
                    f"{_de(given, ref / 255):.2f}",
                ]
            )
    print(header("Macenko I0 with and without glass, against torchstain (issue 26)"))
    cols = ["glass", "stain max", "JPEG", "I0 (of 255)", "I0 from", "dE00 defaults",
            "dE00 I0=240 given"]  # fmt: skip
    print(markdown_table(cols, rows))


if __name__ == "__main__":
    main()
