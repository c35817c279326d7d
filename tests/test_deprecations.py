"""Every name renamed by the 1.0 API pass keeps working for one release (CHANGELOG.md).

Each old spelling must (1) emit a DeprecationWarning that names its replacement and the
release that removes it, and (2) give exactly what the new spelling gives. Also: the shim
helpers themselves (:mod:`imageform._deprecate`) and the one ``rng`` helper (SPEC 7).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from imageform import _deprecate, analysis, color, geometry, optics, sensor, simulate, spectral
from imageform._random import as_rng
from imageform.errors import InvalidInputError

_R = spectral.colorchecker_reflectances()
_SKY = _R["blue sky"]
_IMG = np.random.default_rng(0).uniform(0, 1, (9, 11, 3))
_SENSOR = sensor.SensorModel(read_noise=1, dark_current=0, black_level=0)


def _board() -> np.ndarray:
    """A 5 x 4-square checkerboard (4 x 3 inner corners), 20 px squares, slightly blurred."""
    from scipy.ndimage import gaussian_filter

    v, u = np.mgrid[0:120, 0:140]
    sq = ((u - 20) // 20 + (v - 20) // 20) % 2
    inside = (u >= 20) & (u < 120) & (v >= 20) & (v < 100)
    return np.asarray(gaussian_filter(np.where(inside, sq, 1).astype(float), 1.0))


def _corner() -> np.ndarray:
    from scipy.ndimage import gaussian_filter

    v, u = np.mgrid[0:40, 0:40] * 1.0
    a, b = np.clip(u - 20.3 + 0.5, 0, 1), np.clip(v - 19.6 + 0.5, 0, 1)
    return np.asarray(gaussian_filter(a * b + (1 - a) * (1 - b), 1.5))


_BOARD, _CORNER = _board(), _corner()


def _written(name: str, **kw: Any) -> Any:
    import tempfile
    from pathlib import Path

    from imageform.io import write_image

    with tempfile.TemporaryDirectory() as d:
        return write_image(Path(d) / name, np.full((2, 2, 3), 0.5), **kw)


def _workflows_analysis() -> Any:
    from imageform.workflows import analysis as wf

    return wf


def _workflows_color() -> Any:
    from imageform.workflows import color as wf

    return wf


def _get_workflow(name: str) -> Any:
    from imageform.workflows import get_workflow

    return get_workflow(name)


def _batch_options(command: str, options: dict[str, Any]) -> Any:
    from imageform.batch import batch_options

    return batch_options(command, options)


def _segments() -> geometry.LineSegments:
    """Segments towards two vanishing points, (600, 240) and (-200, 260), plus noise lines."""
    rng = np.random.default_rng(5)
    ends = []
    for vp in ((600.0, 240.0), (-200.0, 260.0)):
        for _ in range(12):
            p = rng.uniform((50, 50), (300, 400))
            q = p + 0.3 * (np.asarray(vp) - p)
            ends.append([p, q])
    for _ in range(4):
        ends.append(rng.uniform(0, 400, (2, 2)))
    e = np.asarray(ends)
    return geometry.LineSegments(e, np.ones(len(e)), -np.full(len(e), 10.0))


def _pnp_data() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    X = np.random.default_rng(1).uniform(-1, 1, (40, 3)) + [0, 0, 6]
    K = np.array([[500.0, 0, 320], [0, 500, 240], [0, 0, 1]])
    uv = np.asarray(geometry.project_points(X, K).uv)
    uv[:5] += 40.0  # outliers
    return X, uv, K


def _chart_sample() -> Any:
    photo = analysis.synthetic_chart_photo(rng=0)
    return analysis.sample_chart(photo.image, layout="detect")


def _development() -> Any:
    from imageform import io

    raw = io.RawImage(
        mosaic=np.arange(64, dtype=np.uint16).reshape(8, 8) * 60,
        black_level=np.full((2, 2), 60.0),
        white_level=4095.0,
        cfa_pattern="RGGB",
        white_balance=np.array([1.9, 1.0, 1.6]),
        xyz_to_camera=np.eye(3),
        camera_to_srgb=np.eye(3),
        calibration_illuminant="D65",
    )
    return io.develop(raw)


#: (label, old call, new call, text the warning must contain)
CASES: list[tuple[str, Callable[[], Any], Callable[[], Any], str]] = [
    # spectral: illuminant keyword-only
    (
        "spectrum_to_xyz positional illuminant",
        lambda: spectral.spectrum_to_xyz(_R, "A"),
        lambda: spectral.spectrum_to_xyz(_R, illuminant="A"),
        "illuminant=",
    ),
    (
        "spectrum_to_lms positional illuminant",
        lambda: spectral.spectrum_to_lms(_SKY, "D50"),
        lambda: spectral.spectrum_to_lms(_SKY, illuminant="D50"),
        "illuminant=",
    ),
    (
        "spectrum_to_camera_rgb positional illuminant",
        lambda: spectral.spectrum_to_camera_rgb(_SKY, "A"),
        lambda: spectral.spectrum_to_camera_rgb(_SKY, illuminant="A"),
        "illuminant=",
    ),
    (
        "integration_weights positional illuminant",
        lambda: spectral.integration_weights(spectral.cmfs(2), None),
        lambda: spectral.integration_weights(spectral.cmfs(2), illuminant=None),
        "illuminant=",
    ),
    # color: observer / illuminant keyword-only, signal_range
    (
        "whitepoint_xy positional observer",
        lambda: color.whitepoint_xy("D50", 10),
        lambda: color.whitepoint_xy("D50", observer=10),
        "observer=",
    ),
    (
        "whitepoint_xyz positional observer",
        lambda: color.whitepoint_xyz("A", 10),
        lambda: color.whitepoint_xyz("A", observer=10),
        "observer=",
    ),
    (
        "resolve_white positional observer",
        lambda: color.resolve_white("D65", 10),
        lambda: color.resolve_white("D65", observer=10),
        "observer=",
    ),
    (
        "tristimulus positional observer, illuminant",
        lambda: color.tristimulus(_SKY, 10, "A"),
        lambda: color.tristimulus(_SKY, observer=10, illuminant="A"),
        "observer=, illuminant=",
    ),
    (
        "are_metamers positional observer, illuminant",
        lambda: color.are_metamers(_SKY, color.metamer(_SKY), 2, "A"),
        lambda: color.are_metamers(_SKY, color.metamer(_SKY), observer=2, illuminant="A"),
        "observer=, illuminant=",
    ),
    (
        "metamer positional observer",
        lambda: color.metamer(_SKY, "cones").values,
        lambda: color.metamer(_SKY, observer="cones").values,
        "observer=",
    ),
    (
        "match_with_primaries positional observer",
        lambda: color.match_with_primaries(
            spectral.illuminant("D65"), spectral.cone_fundamentals(), 10
        ),
        lambda: color.match_with_primaries(
            spectral.illuminant("D65"), spectral.cone_fundamentals(), observer=10
        ),
        "observer=",
    ),
    (
        "spectral_locus positional observer, coords",
        lambda: color.spectral_locus(10, "uv"),
        lambda: color.spectral_locus(observer=10, coords="uv"),
        "observer=, coords=",
    ),
    (
        "visible_area positional observer",
        lambda: color.visible_area("uv", 10),
        lambda: color.visible_area("uv", observer=10),
        "observer=",
    ),
    (
        "rgb_to_ycbcr range=",
        lambda: color.rgb_to_ycbcr(_IMG, "bt709", range="limited", bits=10),
        lambda: color.rgb_to_ycbcr(_IMG, "bt709", signal_range="limited", bit_depth=10),
        "signal_range=",
    ),
    (
        "ycbcr_to_rgb range=",
        lambda: color.ycbcr_to_rgb([235.0, 128.0, 128.0], range="limited"),
        lambda: color.ycbcr_to_rgb([235.0, 128.0, 128.0], signal_range="limited"),
        "signal_range=",
    ),
    (
        "srgb_to_ycbcr range=",
        lambda: color.srgb_to_ycbcr(_IMG, range="limited"),
        lambda: color.srgb_to_ycbcr(_IMG, signal_range="limited"),
        "signal_range=",
    ),
    (
        "ycbcr_to_srgb range=",
        lambda: color.ycbcr_to_srgb([16.0, 128.0, 128.0], range="limited"),
        lambda: color.ycbcr_to_srgb([16.0, 128.0, 128.0], signal_range="limited"),
        "signal_range=",
    ),
    (
        "convert range=",
        lambda: color.convert(_IMG, "srgb", "ycbcr", range="limited", bits=8),
        lambda: color.convert(_IMG, "srgb", "ycbcr", signal_range="limited", bit_depth=8),
        "signal_range=",
    ),
    # geometry
    (
        "from_homogeneous(return_mask=True)",
        lambda: geometry.from_homogeneous(
            [[1.0, 2, 0], [2, 4, 2]], at_infinity="nan", return_mask=True
        ),
        lambda: geometry.from_homogeneous_masked([[1.0, 2, 0], [2, 4, 2]]),
        "from_homogeneous_masked",
    ),
    (
        "projected_size positional focal_length",
        lambda: geometry.projected_size(30.0, 100.0, 50.0),
        lambda: geometry.projected_size(30.0, 100.0, focal_length=50.0),
        "focal_length=",
    ),
    (
        "Intrinsics.from_physical positional",
        lambda: geometry.Intrinsics.from_physical(50.0, 5.0, image_size=(6000, 4000)),
        lambda: geometry.Intrinsics.from_physical(
            focal_length_mm=50.0, pixel_pitch_um=5.0, image_size=(6000, 4000)
        ),
        "focal_length_mm=, pixel_pitch_um=",
    ),
    (
        "Intrinsics.from_physical focal_length= (mm: focal_length_mm, issue 30)",
        lambda: geometry.Intrinsics.from_physical(
            focal_length=8.0, pixel_pitch_um=3.45, image_size=(1280, 720)
        ),
        lambda: geometry.Intrinsics.from_physical(
            focal_length_mm=8.0, pixel_pitch_um=3.45, image_size=(1280, 720)
        ),
        "use focal_length_mm=",
    ),
    (
        "Intrinsics.from_sensor positional",
        lambda: geometry.Intrinsics.from_sensor(50.0, (36.0, 24.0), (6000, 4000)),
        lambda: geometry.Intrinsics.from_sensor(
            focal_length_mm=50.0, sensor_size_mm=(36.0, 24.0), image_size=(6000, 4000)
        ),
        "focal_length_mm=, sensor_size_mm=, image_size=",
    ),
    (
        "solve_pnp_ransac seed=",
        lambda: geometry.solve_pnp_ransac(*_pnp_data(), seed=3).tvec,
        lambda: geometry.solve_pnp_ransac(*_pnp_data(), rng=3).tvec,
        "use rng=",
    ),
    (
        "detect_vanishing_points seed=",
        lambda: (
            geometry.detect_vanishing_points(
                segments=_segments(), image_size=(400, 400), seed=2
            ).vanishing_points
        ),
        lambda: (
            geometry.detect_vanishing_points(
                segments=_segments(), image_size=(400, 400), rng=2
            ).vanishing_points
        ),
        "use rng=",
    ),
    # optics
    (
        "thin_lens f=",
        lambda: optics.thin_lens(f=0.05, d_o=2.0),
        lambda: optics.thin_lens(focal_length=0.05, d_o=2.0),
        "use focal_length=",
    ),
    (
        "ThinLensSolution.f",
        lambda: optics.thin_lens(d_o=0.3, d_i=0.15).f,
        lambda: optics.thin_lens(d_o=0.3, d_i=0.15).focal_length,
        "use .focal_length",
    ),
    (
        "magnification positional",
        lambda: optics.magnification(0.05, 0.1),
        lambda: optics.magnification(focal_length=0.05, d_o=0.1),
        "focal_length=, d_o=",
    ),
    (
        "f_number positional",
        lambda: optics.f_number(0.05, 0.025),
        lambda: optics.f_number(focal_length=0.05, aperture_diameter=0.025),
        "focal_length=, aperture_diameter=",
    ),
    (
        "aperture_diameter f=",
        lambda: optics.aperture_diameter(f=0.05, f_number=2.0),
        lambda: optics.aperture_diameter(focal_length=0.05, f_number=2.0),
        "use focal_length=",
    ),
    (
        "hyperfocal_distance positional",
        lambda: optics.hyperfocal_distance(0.05, 8, 0.03e-3),
        lambda: optics.hyperfocal_distance(focal_length=0.05, f_number=8, coc=0.03e-3),
        "focal_length=, f_number=, coc=",
    ),
    (
        "depth_of_field positional",
        lambda: optics.depth_of_field(0.05, 2.8, 2.0, 0.03e-3),
        lambda: optics.depth_of_field(focal_length=0.05, f_number=2.8, focus=2.0, coc=0.03e-3),
        "focal_length=, f_number=, focus=, coc=",
    ),
    (
        "circle_of_confusion f=",
        lambda: optics.circle_of_confusion([1.0, 4.0], f=0.05, f_number=2, focus=2.0),
        lambda: optics.circle_of_confusion([1.0, 4.0], focal_length=0.05, f_number=2, focus=2.0),
        "use focal_length=",
    ),
    (
        "defocus_radius_px f=",
        lambda: optics.defocus_radius_px(4.0, f=0.05, f_number=2, focus=2, pixel_pitch=5e-6),
        lambda: optics.defocus_radius_px(
            4.0, focal_length=0.05, f_number=2, focus=2, pixel_pitch=5e-6
        ),
        "use focal_length=",
    ),
    (
        "defocus_blur f=",
        lambda: optics.defocus_blur(_IMG, 3.0, f=0.05, f_number=2, focus=2, pixel_pitch=5e-6),
        lambda: optics.defocus_blur(
            _IMG, 3.0, focal_length=0.05, f_number=2, focus=2, pixel_pitch=5e-6
        ),
        "use focal_length=",
    ),
    (
        "spherical_blur_radius positional",
        lambda: optics.spherical_blur_radius(0.05, 2.0, 0.5),
        lambda: optics.spherical_blur_radius(focal_length=0.05, f_number=2.0, sa_coefficient=0.5),
        "focal_length=, f_number=, sa_coefficient=",
    ),
    (
        "chromatic_focal_lengths positional",
        lambda: optics.chromatic_focal_lengths(0.05, 64.17),
        lambda: optics.chromatic_focal_lengths(focal_length=0.05, abbe_number=64.17),
        "focal_length=, abbe_number=",
    ),
    (
        "field_angle positional focal length and centre",
        lambda: optics.field_angle((5, 7), 3.0, (1.0, 2.0)),
        lambda: optics.field_angle((5, 7), focal_length_px=3.0, center=(1.0, 2.0)),
        "focal_length_px=, center=",
    ),
    (
        "cos4_falloff focal_length= (pixels: focal_length_px, issue 30), centre=",
        lambda: optics.cos4_falloff((5, 7), focal_length=3.0, centre=(1.0, 2.0)),
        lambda: optics.cos4_falloff((5, 7), focal_length_px=3.0, center=(1.0, 2.0)),
        "use focal_length_px=",
    ),
    (
        "mechanical_vignetting positional focal length, centre=",
        lambda: optics.mechanical_vignetting(
            (5, 7), 3.0, pupil_radius=1, barrel_radius=1, barrel_distance=1, centre=(1.0, 2.0)
        ),
        lambda: optics.mechanical_vignetting(
            (5, 7),
            focal_length_px=3.0,
            pupil_radius=1,
            barrel_radius=1,
            barrel_distance=1,
            center=(1.0, 2.0),
        ),
        "use center=",
    ),
    (
        "lateral_chromatic_aberration centre=",
        lambda: optics.lateral_chromatic_aberration(_IMG, (1.01, 1.0, 0.99), centre=(3.0, 4.0)),
        lambda: optics.lateral_chromatic_aberration(_IMG, (1.01, 1.0, 0.99), center=(3.0, 4.0)),
        "use center=",
    ),
    (
        "spherical_aberration centre=",
        lambda: optics.spherical_aberration(
            _IMG[..., 0],
            focal_length=0.05,
            f_number=2,
            pixel_pitch=1e-5,
            sa_coefficient=0.5,
            field_coefficient=1.0,
            centre=(2.0, 3.0),
        ),
        lambda: optics.spherical_aberration(
            _IMG[..., 0],
            focal_length=0.05,
            f_number=2,
            pixel_pitch=1e-5,
            sa_coefficient=0.5,
            field_coefficient=1.0,
            center=(2.0, 3.0),
        ),
        "use center=",
    ),
    # sensor
    (
        "SensorModel.normalise",
        lambda: _SENSOR.normalise([64, 4095]),
        lambda: _SENSOR.normalize([64, 4095]),
        "SensorModel.normalize",
    ),
    (
        "sensor.QUANTISATION_NOISE_DN",
        lambda: sensor.QUANTISATION_NOISE_DN,
        lambda: sensor.QUANTIZATION_NOISE_DN,
        "QUANTIZATION_NOISE_DN",
    ),
    (
        "sensor.noise.QUANTISATION_NOISE_DN",
        lambda: sensor.noise.QUANTISATION_NOISE_DN,
        lambda: sensor.noise.QUANTIZATION_NOISE_DN,
        "QUANTIZATION_NOISE_DN",
    ),
    (
        "SensorModel.capture input=",
        lambda: _SENSOR.capture(
            np.full((4, 4), 1e-3),
            exposure_time=1e-3,
            rng=0,
            input="irradiance",
            wavelength_nm=550.0,
        ),
        lambda: _SENSOR.capture(
            np.full((4, 4), 1e-3),
            exposure_time=1e-3,
            rng=0,
            quantity="irradiance",
            wavelength_nm=550.0,
        ),
        "use quantity=",
    ),
    (
        "SensorModel.mean_electrons input=",
        lambda: _SENSOR.mean_electrons(
            np.full((2, 2), 50.0), exposure_time=1e-3, input="photons", wavelength_nm=550.0
        ),
        lambda: _SENSOR.mean_electrons(
            np.full((2, 2), 50.0), exposure_time=1e-3, quantity="photons", wavelength_nm=550.0
        ),
        "use quantity=",
    ),
    (
        "fixed_pattern seed=",
        lambda: sensor.fixed_pattern((3, 4, 1), prnu=0.01, dsnu=1, column_fpn=1, seed=7).offset,
        lambda: sensor.fixed_pattern((3, 4, 1), prnu=0.01, dsnu=1, column_fpn=1, rng=7).offset,
        "use rng=",
    ),
    # one spelling per concept (issue 30): tol, max_trials, bit_depth, center
    (
        "refine_corners eps=",
        lambda: geometry.refine_corners(_CORNER, [[19.0, 21.0]], half_window=5, eps=1e-2).corners,
        lambda: geometry.refine_corners(_CORNER, [[19.0, 21.0]], half_window=5, tol=1e-2).corners,
        "use tol=",
    ),
    (
        "find_checkerboard eps=",
        lambda: geometry.find_checkerboard(_BOARD, (4, 3), eps=1e-2).corners,
        lambda: geometry.find_checkerboard(_BOARD, (4, 3), tol=1e-2).corners,
        "use tol=",
    ),
    (
        "solve_pnp_ransac max_hypotheses=",
        lambda: geometry.solve_pnp_ransac(*_pnp_data(), max_hypotheses=300).tvec,
        lambda: geometry.solve_pnp_ransac(*_pnp_data(), max_trials=300).tvec,
        "use max_trials=",
    ),
    (
        "detect_vanishing_points iterations=",
        lambda: (
            geometry.detect_vanishing_points(
                segments=_segments(), image_size=(400, 400), iterations=200
            ).vanishing_points
        ),
        lambda: (
            geometry.detect_vanishing_points(
                segments=_segments(), image_size=(400, 400), max_trials=200
            ).vanishing_points
        ),
        "use max_trials=",
    ),
    (
        "detect_vanishing_points principal_point='centre'",
        lambda: (
            geometry.detect_vanishing_points(
                segments=_segments(), image_size=(400, 400), principal_point="centre"
            ).vanishing_points
        ),
        lambda: (
            geometry.detect_vanishing_points(
                segments=_segments(), image_size=(400, 400), principal_point="center"
            ).vanishing_points
        ),
        "principal_point='center'",
    ),
    (
        "rgb_to_ycbcr bits=",
        lambda: color.rgb_to_ycbcr(_IMG, "bt709", signal_range="limited", bits=10),
        lambda: color.rgb_to_ycbcr(_IMG, "bt709", signal_range="limited", bit_depth=10),
        "use bit_depth=",
    ),
    (
        "ycbcr_to_srgb bits=",
        lambda: color.ycbcr_to_srgb([235.0, 128.0, 128.0], signal_range="limited", bits=8),
        lambda: color.ycbcr_to_srgb([235.0, 128.0, 128.0], signal_range="limited", bit_depth=8),
        "use bit_depth=",
    ),
    (
        "convert bits=",
        lambda: color.convert(_IMG, "srgb", "ycbcr", bits=8),
        lambda: color.convert(_IMG, "srgb", "ycbcr", bit_depth=8),
        "use bit_depth=",
    ),
    (
        "write_image bits= and WrittenImage.bits",
        lambda: _written("old.png", bits=16).bits,
        lambda: _written("new.png", bit_depth=16).bit_depth,
        "bit_depth",
    ),
    # one name, one unit (issue 30)
    (
        "render_slanted_edge angle= (degrees: angle_deg)",
        lambda: analysis.render_slanted_edge((8, 10), angle=4.0, sigma=0.5),
        lambda: analysis.render_slanted_edge((8, 10), angle_deg=4.0, sigma=0.5),
        "use angle_deg=",
    ),
    (
        "render_sfr_chart angle= (degrees: angle_deg)",
        lambda: analysis.render_sfr_chart((60, 80), grid=(1, 1), angle=4.0),
        lambda: analysis.render_sfr_chart((60, 80), grid=(1, 1), angle_deg=4.0),
        "use angle_deg=",
    ),
    (
        "Intrinsics.from_sensor focal_length= (mm: focal_length_mm)",
        lambda: geometry.Intrinsics.from_sensor(
            focal_length=8.0, sensor_size_mm=(6.4, 4.8), image_size=(640, 480)
        ),
        lambda: geometry.Intrinsics.from_sensor(
            focal_length_mm=8.0, sensor_size_mm=(6.4, 4.8), image_size=(640, 480)
        ),
        "use focal_length_mm=",
    ),
    (
        "field_angle focal_length= (pixels: focal_length_px)",
        lambda: optics.field_angle((5, 7), focal_length=3.0),
        lambda: optics.field_angle((5, 7), focal_length_px=3.0),
        "use focal_length_px=",
    ),
    # method registries (issue 30): one read-only registry per concept
    (
        "color.CCT_METHODS",
        lambda: dict(color.CCT_METHODS),
        lambda: dict(color.CCT_TO_XY_METHODS),
        "use imageform.color.CCT_TO_XY_METHODS",
    ),
    (
        "color.cct.CCT_METHODS",
        lambda: dict(color.cct.CCT_METHODS),
        lambda: dict(color.cct.CCT_TO_XY_METHODS),
        "CCT_TO_XY_METHODS",
    ),
    (
        "color.cct_methods.XY_TO_CCT_METHODS",
        lambda: dict(color.cct_methods.XY_TO_CCT_METHODS),
        lambda: dict(color.XY_TO_CCT_METHODS),
        "use imageform.color.XY_TO_CCT_METHODS",
    ),
    (
        "analysis.macenko.STAIN_METHODS",
        lambda: dict(analysis.macenko.STAIN_METHODS),
        lambda: dict(analysis.STAIN_VECTOR_METHODS),
        "STAIN_VECTOR_METHODS",
    ),
    (
        "workflows.analysis.STAIN_METHODS",
        lambda: dict(_workflows_analysis().STAIN_METHODS),
        lambda: dict(analysis.STAIN_NORMALIZATION_METHODS),
        "use imageform.analysis.STAIN_NORMALIZATION_METHODS",
    ),
    # analysis and the simulator's colour correction
    (
        "synthetic_endoscopy_image seed first",
        lambda: analysis.synthetic_endoscopy_image(3, (40, 48)),
        lambda: analysis.synthetic_endoscopy_image((40, 48), rng=3),
        "rng=<seed>",
    ),
    (
        "synthetic_stain_image seed=",
        lambda: analysis.synthetic_stain_image(seed=2, shape=(16, 16)),
        lambda: analysis.synthetic_stain_image((16, 16), rng=2),
        "use rng=",
    ),
    (
        "synthetic_shading_scene seed first",
        lambda: analysis.synthetic_shading_scene(1, (32, 40)),
        lambda: analysis.synthetic_shading_scene((32, 40), rng=1),
        "rng=<seed>",
    ),
    (
        "simulate.fit_color_correction (old orientation, M = matrix.T)",
        lambda: simulate.fit_color_correction(_IMG[0], _IMG[0] @ np.diag([2.0, 1.0, 0.5])),
        lambda: (
            analysis.fit_color_correction(
                _IMG[0], _IMG[0] @ np.diag([2.0, 1.0, 0.5]), transfer="linear", saturation=None
            ).matrix.T
        ),
        "transfer='linear'",
    ),
    # issue 30: one spelling (center, bit_depth, rng)
    (
        "ChartPhoto.centres and ChartPhoto(centres=)",
        lambda: (
            analysis.ChartPhoto(_IMG, np.eye(3), centres=np.ones((24, 2)), patches=_IMG[0]).centres
        ),
        lambda: (
            analysis.ChartPhoto(_IMG, np.eye(3), centers=np.ones((24, 2)), patches=_IMG[0]).centers
        ),
        "use .centers instead",
    ),
    (
        "ChartPhoto(centres=)",
        lambda: analysis.ChartPhoto(_IMG, np.eye(3), centres=np.ones((24, 2)), patches=_IMG[0]),
        lambda: analysis.ChartPhoto(_IMG, np.eye(3), centers=np.ones((24, 2)), patches=_IMG[0]),
        "use centers= instead",
    ),
    (
        "ColorCheckerTruth.centres_uv",
        lambda: (
            simulate.ColorCheckerTruth(("a",), np.zeros((1, 3)), np.ones((1, 2)), 1.0).centres_uv
        ),
        lambda: (
            simulate.ColorCheckerTruth(("a",), np.zeros((1, 3)), np.ones((1, 2)), 1.0).centers_uv
        ),
        "use .centers_uv instead",
    ),
    (
        "ChartDetection.centres and ChartSample.centres",
        lambda: (_chart_sample().centres, _chart_sample().detection.centres),
        lambda: (_chart_sample().centers, _chart_sample().detection.centers),
        "use .centers instead",
    ),
    (
        "Development.to_integer(bits=)",
        lambda: _development().to_integer(bits=8),
        lambda: _development().to_integer(bit_depth=8),
        "use bit_depth= instead",
    ),
    # workflows: an options field renamed with its flag (issue 30: --bits is --bit-depth)
    (
        "ConvertOptions(bits=) and .bits",
        lambda: _workflows_color().ConvertOptions(bits=16).bits,
        lambda: _workflows_color().ConvertOptions(bit_depth=16).bit_depth,
        "use bit_depth= instead",
    ),
    (
        "Workflow.make_options(bits=)",
        lambda: _get_workflow("demosaic").make_options(bits=8).bit_depth,
        lambda: _get_workflow("demosaic").make_options(bit_depth=8).bit_depth,
        "use bit_depth= instead",
    ),
    (
        "batch_options {'--bits': 16}",
        lambda: _batch_options("develop", {"--bits": 16}).bit_depth,
        lambda: _batch_options("develop", {"--bit-depth": 16}).bit_depth,
        "use --bit-depth (bit_depth)",
    ),
    (
        "simulate.apply_color_correction (image @ M)",
        lambda: simulate.apply_color_correction(
            _IMG, np.array([[1.0, 0.1, 0], [0, 1, 0], [0, 0, 1]])
        ),
        lambda: analysis.ColorCorrection(
            "linear", 1, np.array([[1.0, 0.1, 0], [0, 1, 0], [0, 0, 1]]).T, transfer="linear"
        ).apply(_IMG),
        "ColorCorrection",
    ),
]


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(a[k] is b[k] for k in a)
    if isinstance(a, tuple) and isinstance(b, tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if hasattr(a, "__dataclass_fields__"):
        return type(a) is type(b) and all(
            _same(getattr(a, f), getattr(b, f)) for f in a.__dataclass_fields__
        )
    return bool(np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True))


@pytest.mark.parametrize(("label", "old", "new", "advice"), CASES, ids=[c[0] for c in CASES])
def test_old_spelling_warns_and_matches_new(
    label: str, old: Callable[[], Any], new: Callable[[], Any], advice: str
) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        want = new()  # the new spelling never warns
    with pytest.warns(DeprecationWarning) as record:
        got = old()
    messages = [str(w.message) for w in record if issubclass(w.category, DeprecationWarning)]
    assert any(
        advice in m and f"removed in imageform {_deprecate.REMOVED_IN}" in m for m in messages
    ), messages
    assert _same(got, want), label


def test_warning_points_at_the_caller() -> None:
    with pytest.warns(DeprecationWarning) as record:
        optics.thin_lens(f=0.05, d_o=2.0)
        color.whitepoint_xy("D65", 2)
    assert {w.filename for w in record} == {__file__}


def test_shim_call_errors() -> None:
    with pytest.raises(TypeError, match=r"got both f= \(deprecated\) and focal_length="):
        optics.thin_lens(f=0.05, focal_length=0.05, d_o=2.0)
    with pytest.raises(TypeError, match="at most 2 positional arguments"):
        color.whitepoint_xy("D65", 2, 3)
    with pytest.raises(TypeError, match="multiple values for argument 'observer'"):
        color.whitepoint_xy("D65", 2, observer=2)
    with pytest.raises(TypeError, match="seed twice"):
        analysis.synthetic_endoscopy_image(0, rng=1)
    with pytest.raises(AttributeError, match="no attribute 'NOPE'"):
        _ = sensor.NOPE  # type: ignore[attr-defined]


def test_shims_report_the_new_signature() -> None:
    import inspect

    params = inspect.signature(optics.depth_of_field).parameters
    assert list(params) == ["focal_length", "f_number", "focus", "coc"]
    assert all(p.kind is inspect.Parameter.KEYWORD_ONLY for p in params.values())
    assert "signal_range" in inspect.signature(color.srgb_to_ycbcr).parameters


def test_shim_decorator_checks_its_own_spec() -> None:
    with pytest.raises(TypeError, match="no parameter 'nope'"):
        _deprecate.parameters(renamed={"old": "nope"})(lambda x: x)
    with pytest.raises(TypeError, match="'x' is not keyword-only"):
        _deprecate.parameters(positional=("x",))(lambda x: x)


# -- the one rng helper (SPEC 7) --------------------------------------------------------------
def test_as_rng_spec7() -> None:
    a, b = as_rng(5).random(3), np.random.default_rng(5).random(3)
    np.testing.assert_array_equal(a, b)
    g = np.random.default_rng(1)
    assert as_rng(g) is g
    assert isinstance(as_rng(None), np.random.Generator)
    seq = np.random.SeedSequence(3)
    np.testing.assert_array_equal(as_rng(seq).random(2), np.random.default_rng(seq).random(2))
    np.testing.assert_array_equal(as_rng(np.int64(5)).random(3), b)
    mixed = as_rng(5, mix=(2, 3)).random(2)
    np.testing.assert_array_equal(
        mixed, np.random.default_rng(np.random.SeedSequence([5, 2, 3])).random(2)
    )


@pytest.mark.parametrize("bad", [1.5, "0", True, -1, np.random.RandomState(0)])
def test_as_rng_rejects(bad: object) -> None:
    with pytest.raises(InvalidInputError, match="rng"):
        as_rng(bad)


def test_rng_generator_accepted_where_seed_was() -> None:
    """A Generator draws from its stream (SPEC 7); an int gives the old numbers."""
    g1, g2 = np.random.default_rng(4), np.random.default_rng(4)
    a = analysis.synthetic_stain_image((8, 8), rng=g1).image
    np.testing.assert_array_equal(a, analysis.synthetic_stain_image((8, 8), rng=g2).image)
    assert not np.array_equal(a, analysis.synthetic_stain_image((8, 8), rng=g1).image)


# -- renamed file keys (issue 30): still read, one warning naming the new key -------------------
def test_scene_key_centre_m_is_read_with_one_warning(tmp_path: Any) -> None:
    from imageform.errors import ImageformWarning, UnknownOptionError

    new = {"objects": [{"type": "plane", "center_m": [0.0, 0.0, 0.1]}] * 2}
    old = {"objects": [{"type": "plane", "centre_m": [0.0, 0.0, 0.1]}] * 2}
    with pytest.warns(ImageformWarning) as record:
        got = simulate.load_scene(old)
    messages = [str(w.message) for w in record]
    assert len(messages) == 1, messages
    assert "objects[0].centre_m" in messages[0] and "write center_m (2 objects" in messages[0]
    assert f"removed in imageform {_deprecate.REMOVED_IN}" in messages[0]
    assert got.config == simulate.load_scene(new).config
    toml = tmp_path / "old.toml"
    toml.write_text('[[objects]]\ntype = "plane"\ncentre_m = [0.0, 0.0, 0.1]\n')
    with pytest.warns(ImageformWarning, match=r"old\.toml, line 3\) is deprecated"):
        simulate.load_scene(toml)
    both = {"objects": [{"type": "plane", "centre_m": [0.0] * 3, "center_m": [0.0] * 3}]}
    with pytest.raises(InvalidInputError, match="give center_m or its deprecated spelling"):
        simulate.load_scene(both)
    with pytest.raises(UnknownOptionError, match="unknown key"):  # only objects took centre_m
        simulate.load_scene({"render": {"centre_m": [0.0] * 3}})


def test_object_config_centre_m() -> None:
    from imageform.simulate.config import PlaneConfig

    kw = {"type": "plane", "name": "p", "normal": (0.0, -1.0, 0.0), "up": None}
    kw |= {"size_m": (1.0, 1.0), "reflectance": 0.5}
    want = PlaneConfig(center_m=(0.0, 0.0, 1.0), **kw)
    with pytest.warns(DeprecationWarning, match="use center_m= instead"):
        got = PlaneConfig(centre_m=(0.0, 0.0, 1.0), **kw)
    assert got == want
    with pytest.warns(DeprecationWarning, match=r"use \.center_m instead"):
        assert got.centre_m == (0.0, 0.0, 1.0)


def test_lab_key_patch_centres_px_is_read_with_one_warning(tmp_path: Any) -> None:
    from imageform.errors import ImageformWarning
    from imageform.workflows._characterize_inputs import LAB_MANIFEST, _manifest

    head = 'format = "imageform-lab"\n[colorchecker]\n'
    (tmp_path / LAB_MANIFEST).write_text(head + "patch_centres_px = [[1.0, 2.0]]\n")
    with pytest.warns(ImageformWarning, match="patch_centres_px is deprecated.*patch_centers_px"):
        doc = _manifest(tmp_path)
    assert doc["colorchecker"] == {"patch_centers_px": [[1.0, 2.0]]}
    (tmp_path / LAB_MANIFEST).write_text(
        head + "patch_centres_px = [[1.0, 2.0]]\npatch_centers_px = [[1.0, 2.0]]\n"
    )
    with pytest.raises(InvalidInputError, match="not both"):
        _manifest(tmp_path)
