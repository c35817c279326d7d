"""The simulation report's figures and measurements, with values known from the fixture
(tests/report/conftest.py)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imageform.simulate.result import ColorCheckerTruth, SceneQuad, SimulationResult, Stage
from imageform.simulate.scene import Scene

mpl = pytest.importorskip("matplotlib")
mpl.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from imageform.report.figures_color import (  # noqa: E402
    photon_transfer_summary,
    plot_delta_e,
    plot_patch_chromaticity,
    plot_patch_snr,
    plot_photon_transfer,
    truth_xy,
)
from imageform.report.figures_geometry import (  # noqa: E402
    image_corner_pixels,
    plot_top_view,
    top_view_axes,
    top_view_data,
    top_view_project,
    vanishing_overlay,
    vanishing_summary,
)
from imageform.report.overlays import (  # noqa: E402
    DETECTED_COLOUR,
    TRUE_COLOUR,
    draw_vanishing_truth_overlay,
)
from imageform.report.patches import measure_patches, patch_windows  # noqa: E402

from .conftest import GAIN, SNR_DELTA, SNR_MU, TRUE_VP  # noqa: E402


@pytest.fixture(autouse=True)
def _close_figures() -> Iterator[None]:
    yield
    plt.close("all")


def test_delta_e_gold_and_readings(sim_result: SimulationResult) -> None:
    m = measure_patches(sim_result)
    assert m is not None
    # Sharma et al. (2005) eq. 10-16: pure ΔL' = 2 at L̄ = 50 gives S_L = 1, ΔE00 = 2
    assert m.delta_e00[0] == pytest.approx(2.0, abs=1e-6)
    assert np.allclose(m.delta_e00[1:], 0.0, atol=1e-6)
    assert m.readings[0] == "just noticeable" and set(m.readings[1:]) == {"imperceptible"}
    assert m.delta_e00_mean == pytest.approx(2.0 / 24, abs=1e-6)
    assert m.delta_e00_max == pytest.approx(2.0, abs=1e-6)


def test_snr_per_patch(sim_result: SimulationResult) -> None:
    m = measure_patches(sim_result)
    assert m is not None and m.snr_stage == "white_balanced"
    # a ±δ checker on μ: std = δ (population), SNR = 20 log10(μ/δ)
    # (the weights of the luminance sum to 1: Y of a grey μ ± δ is μ ± δ)
    assert np.allclose(m.snr_luminance_db, 20 * math.log10(SNR_MU / SNR_DELTA), atol=0.05)


def test_measurements_absent_without_colorchecker(bare_result: SimulationResult) -> None:
    assert measure_patches(bare_result) is None
    assert plot_delta_e(None) is None and plot_patch_snr(None) is None
    assert plot_patch_chromaticity(bare_result) is None


def test_patch_windows_cut_at_the_border() -> None:
    t = ColorCheckerTruth(
        ("a", "b", "c"), np.zeros((3, 3)), np.array([[1.0, 1], [50, 50], [np.nan, 0]]), 3
    )
    w = patch_windows(t, 20, 30)
    assert w[0] == (slice(0, 5), slice(0, 5)) and w[1] is None and w[2] is None


def test_patch_outside_image_is_not_measured(sim_result: SimulationResult) -> None:
    cc = sim_result.colorchecker
    assert cc is not None
    centres = cc.centers_uv.copy()
    centres[3] = [-100.0, -100.0]
    r = dataclasses.replace(sim_result, colorchecker=dataclasses.replace(cc, centers_uv=centres))
    m = measure_patches(r)
    assert m is not None and np.isnan(m.delta_e00[3]) and m.readings[3] == "not measured"
    assert np.isnan(m.snr_luminance_db[3]) and np.isfinite(m.delta_e00_mean)
    assert plot_delta_e(m) is not None and plot_patch_snr(m) is not None


def test_chromaticity_figure_plots_every_stage_and_truth(sim_result: SimulationResult) -> None:
    m = measure_patches(sim_result)
    fig = plot_patch_chromaticity(sim_result, m)
    ax = fig.axes[0]
    by_label = {ln.get_label(): ln for ln in ax.lines}
    for key, xy in sim_result.patch_xy.items():
        line = by_label[key.replace("_", " ")]
        assert np.allclose(line.get_xydata(), xy)
    assert m is not None
    assert np.allclose(by_label["ground truth (D65)"].get_xydata(), truth_xy(m))
    # the zoomed panel frames the patches
    x0, x1 = fig.axes[1].get_xlim()
    assert x0 < 0.24 and x1 > 0.53 and x1 - x0 < 0.5


def test_delta_e_bars_hold_the_values(sim_result: SimulationResult) -> None:
    m = measure_patches(sim_result)
    fig = plot_delta_e(m)
    heights = [p.get_height() for p in fig.axes[0].patches]
    assert m is not None and heights == pytest.approx(list(m.delta_e00), abs=1e-9)


def test_top_view_places_camera_centre_and_frustum(sim_result: SimulationResult) -> None:
    data = top_view_data(sim_result)
    assert np.allclose(data["camera_center_m"], [0.5, -1.0, -1.0])
    fig = plot_top_view(data)
    centre = next(ln for ln in fig.axes[0].lines if ln.get_label() == "camera centre")
    assert centre.get_xdata()[0] == 0.0 and centre.get_ydata()[0] == 0.0
    # the far corners re-project onto the image corners at the frustum depth
    cam = sim_result.camera
    far = data["frustum_far_corners_m"]
    uv = np.asarray(cam.project(far).uv)
    w, h = sim_result.image_size
    assert np.allclose(uv, image_corner_pixels(w, h), atol=1e-6)
    z = np.asarray(cam.world_to_camera(far))[:, 2]
    assert np.allclose(z, data["frustum_depth_m"])
    # the depth reaches the farthest scene corner
    corners = np.concatenate([q.corners for q in sim_result.quads])
    assert data["frustum_depth_m"] == pytest.approx(
        np.asarray(cam.world_to_camera(corners))[:, 2].max()
    )
    assert set(data["quads_m"]) == {"colorchecker", "ground"}
    # this synthetic world is y-down: seen from above (along -y), the camera looks along +z
    assert np.allclose(data["view_ahead"], [0.0, 0.0, 1.0])
    assert np.allclose(data["view_right"], [1.0, 0.0, 0.0])


def test_top_view_figure_draws_the_projection(sim_result: SimulationResult) -> None:
    data = top_view_data(sim_result)
    fig = plot_top_view(data)
    lines = {ln.get_label(): ln for ln in fig.axes[0].lines}
    for name, corners in data["quads_m"].items():
        ring = top_view_project(np.vstack([corners, corners[:1]]), data)
        assert np.allclose(lines[name].get_xydata(), ring)
    axis = lines["optical axis"].get_xydata()
    assert np.allclose(axis[1], top_view_project(data["optical_axis_end_m"], data)[0])
    assert fig.axes[0].get_title().startswith("Scene and camera frustum from above")


def _top_view_of_scene(scene: Scene) -> dict:
    """The top view of a scene's objects seen by its camera (no simulation needed)."""
    w, h = scene.image_size
    result = SimulationResult(
        stages=(Stage("o", "o", "o", np.zeros((h, w, 3)), "srgb"),),
        camera=scene.camera,
        image_size=(w, h),
        quads=tuple(SceneQuad(o.name, o.corners) for o in scene.objects),
    )
    return top_view_data(result)


def test_top_view_of_the_default_scene_is_seen_from_above() -> None:
    from imageform.simulate import default_scene

    scene = default_scene().resized(64)
    data = _top_view_of_scene(scene)
    assert np.allclose(data["world_up"], [0.0, 0.0, 1.0])  # the simulator's z-up world
    centre = {n: top_view_project(c, data).mean(axis=0) for n, c in data["quads_m"].items()}
    # the ColorChecker (x = -5 cm) stands left of the camera, the checkerboard (+5 cm) right
    assert centre["ColorChecker"][0] < 0 < centre["checkerboard"][0]
    # both stand nearer than the middle of the 60 cm ground: drawn lower
    assert centre["ColorChecker"][1] < centre["ground with rails"][1]
    # the ground is a 0.2 x 0.6 m rectangle seen from above, not a line (a front view)
    g = top_view_project(data["quads_m"]["ground with rails"], data)
    x, y = g[:, 0], g[:, 1]
    area = 0.5 * abs(np.dot(x, np.roll(y, 1)) - np.dot(y, np.roll(x, 1)))
    assert area == pytest.approx(0.2 * 0.6, rel=1e-9)


@given(
    yaw=st.floats(-math.pi, math.pi),
    pitch=st.floats(-1.2, 1.2),
    pts=st.lists(st.tuples(st.floats(-2.0, 2.0), st.floats(-2.0, 2.0)), min_size=2, max_size=6),
)
@settings(max_examples=60, deadline=None)
def test_top_view_left_is_left_and_nearer_is_lower(
    yaw: float, pitch: float, pts: list[tuple[float, float]]
) -> None:
    # a level (unrolled) camera at any heading and tilt over the z = 0 ground: a ground point
    # left of the camera (camera x < 0) is drawn left (x < 0); of two ground points in front,
    # the nearer (smaller camera depth) is drawn lower
    from imageform.geometry import Camera

    eye = np.array([0.3, -0.2, 1.0])
    d = np.array([np.cos(pitch) * np.cos(yaw), np.cos(pitch) * np.sin(yaw), np.sin(pitch)])
    cam = Camera.look_at(np.diag([100.0, 100.0, 1.0]), eye, eye + d, up=(0.0, 0.0, 1.0))
    data = {
        "camera_center_m": np.asarray(cam.center),
        **dict(zip(("view_right", "view_ahead"), top_view_axes(cam.R, (0, 0, 1)), strict=True)),
    }
    X = np.array([[x, y, 0.0] for x, y in pts])
    xy = top_view_project(X, data)
    Xc = np.asarray(cam.world_to_camera(X))
    ok = np.abs(Xc[:, 0]) > 1e-9
    assert np.array_equal(np.sign(xy[ok, 0]), np.sign(Xc[ok, 0]))
    front = np.flatnonzero(Xc[:, 2] > 1e-6)
    for i in front:
        for j in front:
            if Xc[i, 2] < Xc[j, 2] - 1e-9:
                assert xy[i, 1] < xy[j, 1]


def test_top_view_without_quads(bare_result: SimulationResult) -> None:
    data = top_view_data(bare_result)
    assert data["frustum_depth_m"] == 1.0 and data["quads_m"] == {}
    assert plot_top_view(data) is not None


def test_overlay_puts_the_vanishing_point_where_given() -> None:
    img = np.full((60, 80, 3), 0.5)
    im = draw_vanishing_truth_overlay(img, [40.0, 30.0, 1.0], [0.0, 1.0, -30.0])
    assert im.info["offset"] == (0, 0) and im.size == (80, 60)
    assert im.getpixel((40, 30)) == TRUE_COLOUR  # the cross at the VP
    assert im.getpixel((2, 30)) == TRUE_COLOUR  # the horizon v = 30 at the left edge
    assert im.getpixel((2, 10)) != TRUE_COLOUR


def test_overlay_grows_a_margin_for_an_outside_point_and_marks_detection() -> None:
    img = np.zeros((40, 60, 3))
    im = draw_vanishing_truth_overlay(
        img,
        [30.0, -15.0, 1.0],
        None,
        detected_vanishing_point=[45.0, 20.0, 1.0],
        detected_horizon=[0.0, 1.0, -20.0],
    )
    ox, oy = im.info["offset"]
    assert ox == 0 and oy >= 27  # 15 px above plus the ring
    assert im.getpixel((30, -15 + oy)) == TRUE_COLOUR
    ring = [im.getpixel((45 + dx + ox, 20 + oy)) for dx in range(-9, 10)]
    assert DETECTED_COLOUR in ring
    far = draw_vanishing_truth_overlay(img, [1e5, 0.0, 1.0], None)
    assert far.size == (60, 40)  # too far (and points at infinity): not drawn, no margin
    inf = draw_vanishing_truth_overlay(img, [1.0, 0.0, 0.0], None)
    assert inf.size == (60, 40)


def test_vanishing_summary_and_overlay(
    sim_result: SimulationResult, bare_result: SimulationResult
) -> None:
    s = vanishing_summary(sim_result)
    assert s is not None and s["vanishing_point_error_px"] == pytest.approx(5.0)
    assert s["horizon_angle_error_deg"] == pytest.approx(0.0)
    assert np.allclose(s["vanishing_point_px"], TRUE_VP)
    shown = (np.asarray(sim_result.stages[-1].image) * 255).astype(np.uint8)
    im = vanishing_overlay(sim_result, shown)
    assert im.getpixel((int(TRUE_VP[0]), int(TRUE_VP[1]))) == TRUE_COLOUR
    assert vanishing_summary(bare_result) is None and vanishing_overlay(bare_result, shown) is None
    assert sim_result.vanishing is not None
    no_det = dataclasses.replace(
        sim_result,
        vanishing=dataclasses.replace(sim_result.vanishing, detected_vanishing_point=None),
    )
    summary = vanishing_summary(no_det)
    assert summary is not None and summary["vanishing_point_error_px"] is None


def test_photon_transfer_fit_and_plot(
    sim_result: SimulationResult, bare_result: SimulationResult
) -> None:
    s = photon_transfer_summary(sim_result)
    assert s is not None and s["fit"]["system_gain_dn_per_e"] == pytest.approx(GAIN, rel=1e-9)
    fig = plot_photon_transfer(s)
    fit_line = next(ln for ln in fig.axes[0].lines if ln.get_label().startswith("fit"))
    x, y = fit_line.get_xdata(), fit_line.get_ydata()
    assert np.allclose(y, GAIN * x)
    assert photon_transfer_summary(bare_result) is None and plot_photon_transfer(None) is None


def test_photon_transfer_unfittable_keeps_the_points(sim_result: SimulationResult) -> None:
    d = sim_result.photon_transfer
    assert d is not None
    one = dataclasses.replace(d, exposure_times=np.full(12, 1e-3))
    s = photon_transfer_summary(dataclasses.replace(sim_result, photon_transfer=one))
    assert s is not None and s["fit"] is None and "two different exposure times" in s["fit_error"]
    assert plot_photon_transfer(s) is not None


# --- what the report's figures cost (issue 25: the report at most 20 % of the simulation) ---


def test_report_figures_skip_layout_passes(
    sim_result: SimulationResult, monkeypatch: pytest.MonkeyPatch
) -> None:
    """No figure of the report runs tight_layout or moves its title at draw time.

    Both measure every text of the figure again (a fifth of the figures' drawing time);
    the margins are fixed and the titles sit at the top of their axes.
    """
    from matplotlib.figure import Figure

    from imageform.report import html_parts as hp

    def refuse(*args: object, **kwargs: object) -> None:
        raise AssertionError("tight_layout ran")

    monkeypatch.setattr(Figure, "tight_layout", refuse)
    m = measure_patches(sim_result)
    figs = [
        plot_patch_chromaticity(sim_result, m),
        plot_delta_e(m),
        plot_patch_snr(m),
        plot_top_view(top_view_data(sim_result)),
        plot_photon_transfer(photon_transfer_summary(sim_result)),
    ]
    for fig in figs:
        assert fig is not None
        assert all(not ax._autotitlepos for ax in fig.axes)  # titles placed once
        assert hp.figure_png(fig)[:8] == b"\x89PNG\r\n\x1a\n"


def test_chromaticity_background_and_planckian_locus_are_cached(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The horseshoe picture and the black bodies' chromaticities are computed once."""
    import imageform.spectral.integrate as integrate
    from imageform.report import chromaticity_plot as cp

    img, _ = cp._horseshoe_image("xy", 48)
    again, _ = cp._horseshoe_image("xy", 48)
    assert again is img and not img.flags.writeable
    calls = []
    real = integrate.spectrum_to_xyz

    def counting(*args: Any, **kwargs: Any) -> Any:
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(integrate, "spectrum_to_xyz", counting)
    temps = [1234.5, 4321.0, 9876.5]  # temperatures no other test asks for
    first = cp.planckian_locus(temps)
    n = len(calls)
    assert n <= len(temps)
    np.testing.assert_array_equal(cp.planckian_locus(temps), first)
    np.testing.assert_array_equal(cp.planckian_locus(temps, "uv")[0].shape, (2,))
    assert len(calls) == n  # no integral again
    # the standard observers only; another value is checked (and refused) as before
    with pytest.raises(Exception, match="observer"):
        cp.planckian_locus(temps, observer=5)
