"""The chromaticity diagram renders with the Agg backend; the Planckian locus is right."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imageform.errors import InvalidInputError, UnknownOptionError

mpl = pytest.importorskip("matplotlib")
mpl.use("Agg")

from imageform.report.chromaticity_plot import (  # noqa: E402
    planckian_locus,
    plot_chromaticity_diagram,
)


def test_planckian_locus_matches_illuminant_a() -> None:
    """CIE 015:2018 Table T.3: A (2856 K black body) x, y = 0.44757, 0.40745."""
    xy = planckian_locus([2848.0 * 1.4388 / 1.435])
    assert xy[0] == pytest.approx([0.44757, 0.40745], abs=5e-5)
    assert planckian_locus([2856.0, 6500.0], "uv").shape == (2, 2)


def test_plot_writes_png(tmp_path: Path) -> None:
    out = tmp_path / "d.png"
    fig = plot_chromaticity_diagram(
        ["srgb", "display-p3", "rec2020", "adobe_rgb"],
        points=[[0.3127, 0.329]],
        point_labels=["D65"],
        resolution=60,
        path=out,
    )
    assert out.stat().st_size > 10_000
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert labels[:3] == ["sRGB", "Display P3", "Rec. 2020"] and "Planckian locus" in labels
    import matplotlib.pyplot as plt

    fig2, ax = plt.subplots()
    assert plot_chromaticity_diagram(coords="uv", ax=ax, planckian=False, resolution=40) is fig2
    plt.close("all")


def test_plot_bad_input() -> None:
    with pytest.raises(UnknownOptionError, match="chromaticity diagram"):
        plot_chromaticity_diagram(coords="lab")
    with pytest.raises(UnknownOptionError, match="RGB space"):
        plot_chromaticity_diagram(["srgb", "cmyk"])
    with pytest.raises(InvalidInputError, match="NaN"):
        plot_chromaticity_diagram(points=np.array([[np.nan, 0.3]]))
