"""The public API's boundary findings of issue 25's fuzz run, one test each.

Each call below raised a raw Python error (IndexError, KeyError, AttributeError,
ZeroDivisionError, OverflowError ...) or returned garbage before the fix; now each is the
library's own error, in one line naming the parameter the user gave.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from imageform.errors import InvalidInputError, UnknownOptionError
from tests.fuzz.values import V, resolve


def _one_line(exc: BaseException, name: str) -> str:
    msg = str(exc)
    assert "\n" not in msg and len(msg) <= 200, msg
    assert name in msg, msg
    return msg


@pytest.mark.parametrize(
    "cls", ["CameraColor", "CameraOptics", "CameraSensor", "CameraSensitivity"]
)
def test_from_table_refuses_a_non_reader(cls: str) -> None:
    import imageform.io as io

    with pytest.raises(TypeError) as info:
        getattr(io, cls).from_table({}, object())
    _one_line(info.value, "r")
    assert "Reader" in str(info.value)


def _stain_calls() -> dict:
    from imageform.analysis import (
        background_intensity,
        macenko_normalize,
        macenko_stains,
        vahadane_stains,
    )

    ok = resolve(V("stain"))
    e = np.empty((0, 0, 3))
    return {
        "macenko_stains": (lambda: macenko_stains(e), "image"),
        "macenko_normalize": (lambda: macenko_normalize(e, ok), "image"),
        "macenko_normalize(target)": (lambda: macenko_normalize(ok, e), "target"),
        "vahadane_stains": (lambda: vahadane_stains(e), "image"),
        "background_intensity": (lambda: background_intensity(e), "image"),
        "background_intensity(0 rows)": (
            lambda: background_intensity(np.empty((0, 4, 3))),
            "image",
        ),
    }


@pytest.mark.parametrize(
    "which",
    [
        "macenko_stains",
        "macenko_normalize",
        "macenko_normalize(target)",
        "vahadane_stains",
        "background_intensity",
        "background_intensity(0 rows)",
    ],
)
def test_stain_functions_refuse_an_empty_image(which: str) -> None:
    call, name = _stain_calls()[which]
    with pytest.raises(InvalidInputError, match="empty image") as info:
        call()
    _one_line(info.value, name)


def test_simulation_result_stage_lists_the_valid_names() -> None:
    res = resolve(V("result"))
    with pytest.raises(UnknownOptionError, match=r"unknown stage 'nope'.*'raw'") as info:
        res.stage("nope")
    _one_line(info.value, "name")
    assert res.stage("raw").name == "raw"


def test_print_summary_refuses_a_console_without_print() -> None:
    from imageform.batch import print_summary

    with pytest.raises(TypeError, match="console") as info:
        print_summary(resolve(V("batch_report")), console=object())
    _one_line(info.value, "console")


def test_plot_chromaticity_diagram_refuses_an_ax_that_is_not_axes() -> None:
    pytest.importorskip("matplotlib")
    from imageform.report.chromaticity_plot import plot_chromaticity_diagram

    with pytest.raises(TypeError, match="ax") as info:
        plot_chromaticity_diagram(ax=object())
    _one_line(info.value, "ax")


@pytest.mark.parametrize("size", [(), (64,), "ab", (0, 36), (64.5, 36)])
def test_to_camera_refuses_a_bad_image_size(size: object) -> None:
    cfg = resolve(V("camera_config"))
    with pytest.raises(InvalidInputError) as info:
        cfg.to_camera(size, 2e-6)
    _one_line(info.value, "image_size")


@pytest.mark.parametrize("pitch", [2e-6 + 1j, 5e-324, 0.0, -1e-6, float("nan"), "2e-6"])
def test_to_camera_refuses_a_bad_sensor_pixel_pitch(pitch: object) -> None:
    cfg = resolve(V("camera_config"))
    with pytest.raises(InvalidInputError) as info:
        cfg.to_camera((64, 36), pitch)  # type: ignore[arg-type]
    _one_line(info.value, "sensor_pixel_pitch_m")


@pytest.mark.parametrize("width", [0, -3, float("inf"), float("nan"), 2.5, 10**30])
def test_scene_resized_refuses_a_bad_width(width: object) -> None:
    scene = resolve(V("scene"))
    with pytest.raises(InvalidInputError) as info:
        scene.resized(width)  # type: ignore[arg-type]
    _one_line(info.value, "width")


def test_scene_resized_refuses_a_bad_height() -> None:
    scene = resolve(V("scene"))
    with pytest.raises(InvalidInputError) as info:
        scene.resized(32, 0)
    _one_line(info.value, "height")


def test_a_subnormal_positive_number_is_refused() -> None:
    """5e-324 passes ``> 0`` but its reciprocal overflows: as_real(positive=True) refuses it."""
    from imageform._validate import as_real
    from imageform.optics import mtf

    with pytest.raises(InvalidInputError, match="pixel_pitch"):
        as_real(5e-324, "pixel_pitch", positive=True)
    assert as_real(1e-300, "x", positive=True) == 1e-300
    with pytest.raises(InvalidInputError, match="pixel_pitch"):
        mtf(resolve(V("psf")), pixel_pitch=5e-324)


def test_check_memory_message_stays_short_for_a_huge_request() -> None:
    from imageform._validate import check_memory

    with pytest.raises(InvalidInputError) as info:
        check_memory(1e300, "pixel_pitch", "the padded pupil")
    _one_line(info.value, "pixel_pitch")


def test_checkerboard_candidates_take_float16() -> None:
    from imageform.geometry.checkerboard_candidates import find_candidates

    gray = resolve(V("gray"))
    a = find_candidates(gray.astype(np.float16), sigma=1.0)
    b = find_candidates(gray.astype(np.float16).astype(np.float32), sigma=1.0)
    np.testing.assert_array_equal(a.xy, b.xy)


def test_characterize_camera_does_not_echo_a_huge_folder_name() -> None:
    from imageform.workflows import characterize_camera

    with pytest.raises(InvalidInputError) as info:
        characterize_camera("x" * 100_000)
    _one_line(info.value, "folder")


# --- silent garbage ---------------------------------------------------------------------


@pytest.mark.parametrize("method", ["capture", "mean_electrons"])
@pytest.mark.parametrize("wavelength", [550 + 1j, "550", 0.0, float("nan")])
def test_sensor_refuses_a_bad_wavelength_even_when_unused(method: str, wavelength: object) -> None:
    from imageform.sensor import SensorModel

    s = SensorModel()
    kwargs = {"rng": 0} if method == "capture" else {}
    with pytest.raises(InvalidInputError) as info:
        getattr(s, method)(
            np.full((6, 8, 1), 100.0), exposure_time=0.01, wavelength_nm=wavelength, **kwargs
        )
    _one_line(info.value, "wavelength_nm")


@pytest.mark.parametrize("white_level", [1 + 1j, "1", 0.0])
def test_stage_display_image_refuses_a_bad_white_level_for_any_kind(white_level: object) -> None:
    from imageform.report.display import stage_display_image

    with pytest.raises(InvalidInputError) as info:
        stage_display_image(resolve(V("rgb")), "linear", white_level=white_level)  # type: ignore[arg-type]
    _one_line(info.value, "white_level")


@pytest.mark.parametrize(
    "E",
    [
        np.zeros((3, 3)),  # rank 0
        np.diag([1.0, 0.0, 0.0]),  # rank 1
        np.eye(3),  # rank 3
    ],
)
def test_recover_pose_refuses_an_E_that_is_not_rank_2(E: np.ndarray) -> None:
    from imageform.errors import DegenerateConfigurationError
    from imageform.geometry import recover_pose

    with pytest.raises((InvalidInputError, DegenerateConfigurationError)) as info:
        recover_pose(E, resolve(V("pts1")), resolve(V("pts2")), resolve(V("K")))
    _one_line(info.value, "E")
    assert "rank" in str(info.value)


def test_recover_pose_still_takes_a_valid_E() -> None:
    from imageform.geometry import recover_pose

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        pose = recover_pose(
            resolve(V("E")), resolve(V("pts1")), resolve(V("pts2")), resolve(V("K"))
        )
    assert np.allclose(pose.R @ pose.R.T, np.eye(3))


@pytest.mark.parametrize("value", [1e308, 1.0, [0.3, 0.3, 1.2]])
def test_camera_optics_refuses_an_mtf50_beyond_the_sampling_frequency(value: object) -> None:
    from imageform.io import CameraOptics

    with pytest.raises(InvalidInputError, match="sampling frequency") as info:
        CameraOptics(model="mtf50", mtf50_cy_per_px=value)  # type: ignore[arg-type]
    _one_line(info.value, "mtf50_cy_per_px")
    assert CameraOptics(model="mtf50", mtf50_cy_per_px=0.5).mtf50_cy_per_px == 0.5
    # a sharp sensor without an anti-aliasing filter: the pixel aperture alone gives 0.60
    assert CameraOptics(model="mtf50", mtf50_cy_per_px=0.6).mtf50_cy_per_px == 0.6


# --- found by the fuzz harness on parameters left to a None/non-simple default -----------


def _default_param_calls() -> dict:
    import imageform.io as io
    from imageform.analysis import chart_white_balance, render_slanted_edge
    from imageform.color import rgb_to_ycbcr
    from imageform.geometry import stereo_calibrate
    from imageform.io import write_image
    from imageform.report.html_parts import table
    from imageform.simulate import SimulationResult, simulate
    from imageform.simulate.schema import Field
    from imageform.workflows import Input, Output, Run

    res = resolve(V("result"))
    objs, left, right = (resolve(V(n)) for n in ("stereo_objs", "stereo_left", "stereo_right"))
    return {
        "chart_white_balance(chart='abc')": (
            lambda: chart_white_balance(resolve(V("chart")), chart="abc"),
            "chart",
        ),
        "render_slanted_edge(center=0)": (
            lambda: render_slanted_edge((16, 16), center=0),
            "center",
        ),
        "render_slanted_edge(esf=1.0)": (lambda: render_slanted_edge((16, 16), esf=1.0), "esf"),
        "rgb_to_ycbcr(bit_depth='x' * 100000)": (
            lambda: rgb_to_ycbcr(resolve(V("rgb")), bit_depth="x" * 100_000),
            "bit_depth",
        ),
        "write_image(bit_depth='x' * 100000)": (
            lambda: write_image(
                resolve(V("tmpfile_png")), resolve(V("rgb")), bit_depth="x" * 100_000
            ),
            "bit_depth",
        ),
        "stereo_calibrate(fix=0)": (
            lambda: stereo_calibrate(objs, left, right, (640, 480), fix=0),
            "fix",
        ),
        "table(left=None)": (lambda: table(["a"], [["b"]], left=None), "left"),
        "simulate(progress=0)": (lambda: simulate(resolve(V("scene")), progress=0), "progress"),
        "Provenance(rms_px=nan)": (lambda: io.Provenance(rms_px=float("nan")), "rms_px"),
        "Provenance(command=nan)": (lambda: io.Provenance(command=float("nan")), "command"),
        "Provenance(views_used=1.5)": (lambda: io.Provenance(views_used=1.5), "views_used"),
        "CameraFile(path=nan)": (
            lambda: io.CameraFile(resolve(V("camera")), path=float("nan")),
            "path",
        ),
        "SimulationResult(patches=nan)": (
            lambda: SimulationResult(
                res.camera, res.image_size, res.world_up, res.stages, patches=float("nan")
            ),
            "patches",
        ),
        "Field(minimum=nan)": (lambda: Field("float", None, "x", minimum=float("nan")), "minimum"),
        "Field(dimension=1j)": (lambda: Field("float", None, "x", dimension=1j), "dimension"),
        "Input(metavar=nan)": (lambda: Input("x", "help", metavar=float("nan")), "metavar"),
        "Output(default=nan)": (lambda: Output("help", default=float("nan")), "default"),
        "Run(progress=nan)": (lambda: Run(None, progress=float("nan")), "progress"),
    }


@pytest.mark.parametrize(
    "which",
    [
        "chart_white_balance(chart='abc')",
        "render_slanted_edge(center=0)",
        "render_slanted_edge(esf=1.0)",
        "rgb_to_ycbcr(bit_depth='x' * 100000)",
        "write_image(bit_depth='x' * 100000)",
        "stereo_calibrate(fix=0)",
        "table(left=None)",
        "simulate(progress=0)",
        "Provenance(rms_px=nan)",
        "Provenance(command=nan)",
        "Provenance(views_used=1.5)",
        "CameraFile(path=nan)",
        "SimulationResult(patches=nan)",
        "Field(minimum=nan)",
        "Field(dimension=1j)",
        "Input(metavar=nan)",
        "Output(default=nan)",
        "Run(progress=nan)",
    ],
)
def test_a_parameter_left_to_its_default_is_checked_when_given(which: str) -> None:
    call, name = _default_param_calls()[which]
    with pytest.raises((InvalidInputError, TypeError)) as info:
        call()
    _one_line(info.value, name)


def test_messages_name_the_argument_not_an_internal_name() -> None:
    """0-255 codes in an int64 array: the message names ``normalized``/``measured``, not
    "raw" or "srgb image" (the internal names of the functions they are handed to)."""
    from imageform.analysis import correction_report, fit_color_correction
    from imageform.simulate.stages import demosaic_raw

    codes = (np.random.default_rng(0).uniform(0, 0.3, (6, 8)) * 255).round().astype(np.int64)
    with pytest.raises(InvalidInputError) as info:
        demosaic_raw(codes, "RGGB", "bilinear")
    msg = _one_line(info.value, "normalized")
    assert "raw looks like" not in msg
    chart = resolve(V("rgb_chart"))
    corr = fit_color_correction(chart, chart)
    for name in ("measured", "reference"):
        args = {"measured": chart, "reference": chart}
        args[name] = (chart * 255).round().astype(np.int64)
        with pytest.raises(InvalidInputError) as info:
            correction_report(args["measured"], args["reference"], corr)
        msg = _one_line(info.value, name)
        assert "srgb image" not in msg


@pytest.mark.parametrize("q", [None, "abc", [1.0, 0.0, 0.0, 0.0, 0.0], [float("nan"), 0, 0, 1]])
def test_quaternion_to_matrix_names_q(q: object) -> None:
    """Found by the fuzz harness once a name counts only as a word: "quaternion" is not q."""
    from imageform.geometry import quaternion_to_matrix
    from tests.fuzz.runner import _names_param

    with pytest.raises(InvalidInputError) as info:
        quaternion_to_matrix(q)  # type: ignore[arg-type]
    assert _names_param(_one_line(info.value, "q"), "q")


@pytest.mark.parametrize("n", [None, "1", [1, 2], float("nan"), -1.0])
def test_format_bytes_names_n(n: object) -> None:
    from imageform.simulate.budget import format_bytes
    from tests.fuzz.runner import _names_param

    with pytest.raises(InvalidInputError) as info:
        format_bytes(n)  # type: ignore[arg-type]
    assert _names_param(_one_line(info.value, "n"), "n")


def _word_named_calls() -> dict:
    import imageform.io as io
    from imageform.analysis import MacenkoStains
    from imageform.io.camera_file import distortion_name
    from imageform.simulate.config import DistortionConfig

    return {
        "read_camera(None)": (lambda: io.read_camera(None), "path"),
        "read_stereo_camera(0)": (lambda: io.read_stereo_camera(0), "path"),
        "image_format(None)": (lambda: io.image_format(None), "path"),
        "read_png(0)": (lambda: io.read_png(0), "path"),
        "write_png(None)": (lambda: io.write_png(None, np.zeros((2, 2), np.uint8)), "path"),
        "MacenkoStains.from_json(None)": (lambda: MacenkoStains.from_json(None), "path"),
        "distortion_name(1)": (lambda: distortion_name(1), "model"),
        "DistortionConfig.from_model('x')": (lambda: DistortionConfig.from_model("x"), "model"),
    }


@pytest.mark.parametrize(
    "which",
    [
        "read_camera(None)",
        "read_stereo_camera(0)",
        "image_format(None)",
        "read_png(0)",
        "write_png(None)",
        "MacenkoStains.from_json(None)",
        "distortion_name(1)",
        "DistortionConfig.from_model('x')",
    ],
)
def test_the_parameter_is_named_as_a_word(which: str) -> None:
    """'PathLike' or 'DivisionModel' in a message do not name ``path`` or ``model``."""
    from tests.fuzz.runner import _names_param

    call, name = _word_named_calls()[which]
    with pytest.raises((InvalidInputError, TypeError)) as info:
        call()
    assert _names_param(_one_line(info.value, name), name), str(info.value)


def test_shorten_never_echoes_a_huge_or_multiline_text() -> None:
    from imageform._validate import shorten

    assert len(shorten("x" * 100_000)) == 80
    assert "\n" not in shorten(str(np.arange(1000.0).reshape(100, 10)))
