"""Issue 16: the report's building blocks refuse malformed input in one line naming the
parameter (the fuzz findings of imageform.report, each as a test)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from imageform.errors import ImageformError, InvalidInputError, UnknownOptionError
from imageform.report import html_parts as hp
from imageform.report.chromaticity_plot import planckian_locus, plot_chromaticity_diagram
from imageform.report.display import stage_display_image
from imageform.report.figures_color import plot_delta_e, plot_patch_snr, truth_xy
from imageform.report.figures_geometry import top_view_axes, vanishing_overlay
from imageform.report.metrics import to_json_value
from imageform.report.overlays import draw_vanishing_truth_overlay

RGB = np.full((6, 8, 3), 0.5)
R = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])


def _one_line(info: pytest.ExceptionInfo[BaseException]) -> str:
    msg = str(info.value)
    assert "\n" not in msg and len(msg) <= 200, msg
    return msg


CASES: list[tuple[Callable[[], Any], str]] = [
    (lambda: planckian_locus([2856.0], coords=""), "coords"),
    (lambda: planckian_locus([2856.0], coords=None), "coords"),  # type: ignore[arg-type]
    (lambda: planckian_locus(True), "temperatures"),  # type: ignore[arg-type]
    (lambda: planckian_locus([1.0]), "temperatures"),  # underflowed to 0 before
    (lambda: planckian_locus([1j]), "temperatures"),
    (lambda: plot_chromaticity_diagram(coords=0), "coords"),  # type: ignore[arg-type]
    (lambda: plot_chromaticity_diagram(resolution=float("inf")), "resolution"),
    (lambda: plot_chromaticity_diagram(resolution=0), "resolution"),
    (lambda: plot_chromaticity_diagram(resolution=10**30), "resolution"),
    (lambda: plot_chromaticity_diagram(points="abc"), "points"),
    (lambda: stage_display_image(np.float64(0.0), "linear"), "image"),  # type: ignore[arg-type]
    (lambda: stage_display_image(RGB, "linear", percentile=None), "percentile"),  # type: ignore[arg-type]
    (lambda: stage_display_image(RGB, "linear", percentile=1j), "percentile"),  # type: ignore[arg-type]
    (lambda: stage_display_image(RGB[..., 0], "raw", white_level=np.nan), "white_level"),
    (lambda: truth_xy(None), "measurements"),  # type: ignore[arg-type]
    (lambda: plot_delta_e("abc"), "measurements"),  # type: ignore[arg-type]
    (lambda: plot_patch_snr(0), "measurements"),  # type: ignore[arg-type]
    (lambda: top_view_axes(None, (0, 0, 1)), "R"),
    (lambda: top_view_axes("abc", (0, 0, 1)), "R"),
    (lambda: top_view_axes(R, "abc"), "world_up"),
    (lambda: top_view_axes(R, (1j, 0, 1)), "world_up"),
    (lambda: hp.img_tag("abc", "alt"), "png"),  # type: ignore[arg-type]
    (lambda: hp.figure(None, "alt", "caption"), "png"),  # type: ignore[arg-type]
    (lambda: hp.json_block(object(), "summary"), "value"),
    (lambda: hp.page("t", "s", None, "<p>x</p>"), "nav"),  # type: ignore[arg-type]
    (lambda: hp.page("t", "s", "abc", "<p>x</p>"), "nav"),  # type: ignore[arg-type]
    (lambda: hp.table(None, [[1]]), "header"),  # type: ignore[arg-type]
    (lambda: hp.table(["a"], 0), "rows"),  # type: ignore[arg-type]
    (lambda: hp.page_jpeg(None), "rgb"),
    (lambda: hp.page_jpeg(np.zeros((0, 4, 3), np.uint8)), "rgb"),
    (lambda: hp.page_jpeg(RGB), "rgb"),  # floats: not an 8-bit picture
    (lambda: hp.page_jpeg(np.zeros((4, 4, 3), np.uint8), max_width=0), "max_width"),
    (lambda: hp.page_jpeg(np.zeros((4, 4, 3), np.uint8), quality=None), "quality"),  # type: ignore[arg-type]
    (lambda: hp.page_jpeg(np.zeros((4, 4, 3), np.uint8), quality=10**30), "quality"),
    (lambda: to_json_value(1j), "value"),
    (lambda: to_json_value(object()), "value"),
    (lambda: draw_vanishing_truth_overlay(None, [1.0, 2.0]), "image"),  # type: ignore[arg-type]
    (lambda: draw_vanishing_truth_overlay("abc", [1.0, 2.0]), "image"),  # type: ignore[arg-type]
    (lambda: draw_vanishing_truth_overlay(RGB, []), "vanishing_point"),
    (lambda: draw_vanishing_truth_overlay(RGB, [1 + 1j, 2.0]), "vanishing_point"),
    (lambda: draw_vanishing_truth_overlay(RGB, "abc"), "vanishing_point"),
    (lambda: draw_vanishing_truth_overlay(RGB, [1.0, 2.0], [0, 1]), "horizon"),
    (lambda: draw_vanishing_truth_overlay(RGB, [1.0, 2.0], max_margin=None), "max_margin"),  # type: ignore[arg-type]
    (lambda: draw_vanishing_truth_overlay(RGB, [1.0, 2.0], max_margin=1e308), "max_margin"),
]


@pytest.mark.parametrize(("call", "name"), CASES)
def test_report_boundaries_name_the_parameter(call: Callable[[], Any], name: str) -> None:
    with pytest.raises((ImageformError, TypeError), match=rf"\b{name}\b") as info:
        call()
    _one_line(info)


def test_torch_scalar_is_a_json_number() -> None:
    torch = pytest.importorskip("torch")
    assert to_json_value(torch.tensor(1.5)) == 1.5
    with pytest.raises(InvalidInputError, match="value"):
        to_json_value(torch.tensor(1 + 1j))


def test_coords_unknown_is_an_option_error_naming_coords() -> None:
    with pytest.raises(UnknownOptionError, match=r"coords.*valid: 'uv', 'xy'"):
        planckian_locus([2856.0], coords="lab")


def test_valid_calls_still_work() -> None:
    """Numpy scalars and tensors of a real dtype are numbers; the valid paths are unchanged."""
    assert planckian_locus(np.float64(2856.0)).shape == (1, 2)
    jpeg = hp.page_jpeg(np.zeros((4, 4, 3), np.uint8), max_width=np.int64(2), quality=np.int64(80))
    assert jpeg[:2] == b"\xff\xd8"
    assert 'alt="a"' in hp.img_tag(bytearray(b"\x89PNG"), "a")
    assert "<td>1</td>" in hp.table(("a",), ((1,),))
    assert stage_display_image(RGB, "linear", percentile=np.float32(50)).dtype == np.uint8
    right, ahead = top_view_axes(R.tolist(), np.array([0, 0, 1]))
    assert right.tolist() == [1.0, 0.0, 0.0] and ahead.tolist() == [0.0, 1.0, 0.0]
    im = draw_vanishing_truth_overlay(np.zeros((40, 60, 3)), [30.0, 20.0, np.inf], [0, 1, -20])
    assert im.info["offset"] == (0, 0)  # a point not finite is not drawn, as before


def test_vanishing_overlay_names_display(sim_result: Any) -> None:
    with pytest.raises(InvalidInputError, match="display") as info:
        vanishing_overlay(sim_result, None)  # type: ignore[arg-type]
    _one_line(info)


@pytest.mark.parametrize("out_dir", [None, 0, ""])
def test_write_report_names_out_dir(sim_result: Any, out_dir: object) -> None:
    from imageform.report import write_report

    with pytest.raises(TypeError, match="out_dir") as info:
        write_report(sim_result, out_dir)  # type: ignore[arg-type]
    _one_line(info)


def test_chromaticity_checks_come_before_matplotlib(monkeypatch: pytest.MonkeyPatch) -> None:
    """Malformed arguments are refused before pyplot is imported (the fuzz's timeouts were a
    cold pyplot import in front of a refusal)."""
    import builtins

    real_import = builtins.__import__

    def guard(name: str, *args: Any, **kwargs: Any) -> Any:
        if name.startswith("matplotlib.pyplot"):
            raise AssertionError("pyplot imported before the arguments were checked")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", guard)
    with pytest.raises(TypeError, match="coords"):
        plot_chromaticity_diagram(coords=None)  # type: ignore[arg-type]
