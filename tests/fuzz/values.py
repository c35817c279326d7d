"""Valid argument values for the fuzz table, built lazily in the worker process.

The table (:mod:`tests.fuzz.table`) refers to these by name with :class:`V`; a value is
built the first time a worker needs it (some need imageform objects) and a fresh copy is
handed to every call, so that a callable that writes into its input cannot poison the next.
"""

from __future__ import annotations

import atexit
import copy
import os
import shutil
import tempfile
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["FIXTURES", "V", "resolve"]


@dataclass(frozen=True)
class V:
    """A reference to a named fixture value (``V("rgb")``)."""

    name: str

    def __repr__(self) -> str:
        return f"V({self.name!r})"


def _rng() -> np.random.Generator:
    return np.random.default_rng(20261125)


def _rgb() -> np.ndarray:
    return _rng().uniform(0.05, 0.95, (6, 8, 3))


def _camera() -> Any:
    from imageform.geometry import Camera

    return Camera(_K(), image_size=(8, 6))


def _K() -> np.ndarray:
    return np.array([[500.0, 0.0, 4.0], [0.0, 500.0, 3.0], [0.0, 0.0, 1.0]])


def _spectrum() -> Any:
    from imageform.spectral import Spectrum

    wl = np.arange(380.0, 781.0, 10.0)
    return Spectrum(wl, 0.2 + 0.6 * np.exp(-(((wl - 550.0) / 80.0) ** 2)), name="fuzz")


def _spectrum3() -> Any:
    from imageform.spectral import Spectrum

    wl = np.arange(380.0, 781.0, 10.0)
    cols = [np.exp(-(((wl - c) / 30.0) ** 2)) for c in (450.0, 540.0, 610.0)]
    return Spectrum(wl, np.column_stack(cols), name="primaries")


def _brown() -> Any:
    from imageform.geometry import BrownConrady

    return BrownConrady(k1=-0.1, k2=0.01)


def _sensor() -> Any:
    from imageform.sensor import SensorModel

    return SensorModel()


def _emva_frames() -> Any:
    from imageform.sensor import SensorModel, simulate_emva_frames

    return simulate_emva_frames(
        SensorModel(full_well=2000.0),
        irradiance=0.01,
        wavelength_nm=550.0,
        exposure_times=np.linspace(0.0, 0.014, 8),
        rng=0,
        shape=(6, 8),
    )


def _points3() -> np.ndarray:
    g = _rng()
    return np.column_stack([g.uniform(-1, 1, 6), g.uniform(-1, 1, 6), g.uniform(3, 6, 6)])


def _segments() -> Any:
    from imageform.geometry import LineSegments

    ends = np.array([[0.0, 0.0, 10.0, 1.0], [0.0, 5.0, 10.0, 4.0], [2.0, 0.0, 3.0, 10.0]])
    ends = ends.reshape(3, 2, 2)
    return LineSegments(ends, np.ones(3), -np.ones(3))


def _scene() -> Any:
    from imageform.simulate import default_scene

    return default_scene().resized(64)


def _result() -> Any:
    from imageform.simulate import simulate

    with warnings.catch_warnings():  # a noiseless 64-px scene: infinite patch SNR, expected
        warnings.simplefilter("ignore")
        return simulate(_scene(), rng=0)


#: The folders :func:`_tmpdir` made in this process, removed by :func:`remove_tmpdirs`.
_MADE: list[Path] = []


def _tmpdir() -> Path:
    """A new empty folder, under ``IMAGEFORM_FUZZ_TMP`` (a fuzz worker's scratch) if set.

    Removed by :func:`remove_tmpdirs` (at the latest when the process exits; the runner also
    removes a killed worker's whole scratch folder).
    """
    base = os.environ.get("IMAGEFORM_FUZZ_TMP") or None
    path = Path(tempfile.mkdtemp(prefix="imageform-fuzz-", dir=base))
    _MADE.append(path)
    return path


def remove_tmpdirs() -> None:
    """Remove every folder :func:`_tmpdir` made in this process (and what is in it)."""
    while _MADE:
        shutil.rmtree(_MADE.pop(), ignore_errors=True)


atexit.register(remove_tmpdirs)


def _chart() -> np.ndarray:
    from imageform.analysis import synthetic_chart_image

    return synthetic_chart_image(patch=6, gap=2)


def _rgb_chart() -> np.ndarray:
    from imageform.analysis.synthetic import COLORCHECKER_SRGB8

    return np.asarray(COLORCHECKER_SRGB8, dtype=float) / 255.0


def _correction() -> Any:
    from imageform.analysis import fit_color_correction

    chart = _rgb_chart()
    return fit_color_correction(chart * 0.9 + 0.02, chart)


def _stain() -> np.ndarray:
    from imageform.analysis import synthetic_stain_image

    return synthetic_stain_image((32, 32)).image


def _png_file() -> Path:
    from imageform.io import write_image

    path = _tmpdir() / "in.png"
    write_image(path, _rgb())
    return path


def _dicom_file() -> Path:
    """A 12-bit CT slice (signed, rescaled to HU, with a window), written with pydicom."""
    from pydicom.dataset import Dataset, FileMetaDataset
    from pydicom.uid import ExplicitVRLittleEndian, generate_uid

    ds = Dataset()
    ds.file_meta = FileMetaDataset()
    ds.file_meta.TransferSyntaxUID = ExplicitVRLittleEndian
    ds.file_meta.MediaStorageSOPClassUID = ds.SOPClassUID = "1.2.840.10008.5.1.4.1.1.2"
    ds.file_meta.MediaStorageSOPInstanceUID = ds.SOPInstanceUID = generate_uid()
    ds.Modality, ds.Rows, ds.Columns, ds.SamplesPerPixel = "CT", 6, 8, 1
    ds.PhotometricInterpretation = "MONOCHROME2"
    ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 16, 12, 11, 1
    ds.RescaleSlope, ds.RescaleIntercept, ds.WindowCenter, ds.WindowWidth = 1, -1024, 40, 400
    ds.PixelData = _rng().integers(0, 2048, (6, 8)).astype(np.int16).tobytes()
    path = _tmpdir() / "in.dcm"
    ds.save_as(path, enforce_file_format=True)
    return path


def _tiff_file() -> Path:
    import tifffile

    path = _tmpdir() / "in.tif"
    tifffile.imwrite(
        path, (_rng().uniform(0.05, 0.95, (32, 32, 3)) * 255).astype(np.uint8), tile=(16, 16)
    )
    return path


def _job_result() -> Any:
    from imageform.batch import JobResult

    return JobResult(Path("in.png"), Path("out.png"), "done", metrics={"gains": [1.0, 1.0, 1.0]})


def _batch_report() -> Any:
    from imageform.batch import BatchReport

    return BatchReport("white_balance", (_job_result(),))


def _worked_example() -> Any:
    from imageform.report.lecture import WorkedExample

    return WorkedExample("optics", "f?", "1/f = 1/a + 1/b", lambda: 0.05, 0.05, unit="m")


def _palette_check() -> Any:
    from imageform.color import palette, palette_check

    return palette_check(palette("okabe_ito"))


def _camera_file() -> Path:
    from imageform.io import write_camera

    path = _tmpdir() / "camera.toml"
    write_camera(path, _camera())
    return path


def _two_view() -> tuple[np.ndarray, np.ndarray]:
    """Pixel correspondences of 20 points seen by two cameras ``K`` (second at R, t)."""
    from imageform.geometry.rotations import rvec_to_matrix

    g = _rng()
    X = np.column_stack([g.uniform(-1, 1, 20), g.uniform(-1, 1, 20), g.uniform(4, 8, 20)])
    R = np.asarray(rvec_to_matrix([0.02, -0.1, 0.03]))
    t = np.array([-1.0, 0.05, 0.02])
    K = _K()
    a = X @ K.T
    b = (X @ R.T + t) @ K.T
    return a[:, :2] / a[:, 2:], b[:, :2] / b[:, 2:]


def _P2() -> np.ndarray:
    """The second camera of :func:`_two_view`: ``K [R | t]``."""
    from imageform.geometry.rotations import rvec_to_matrix

    R = np.asarray(rvec_to_matrix([0.02, -0.1, 0.03]))
    return _K() @ np.hstack([R, np.array([[-1.0], [0.05], [0.02]])])


def _essential() -> np.ndarray:
    from imageform.geometry import find_essential_matrix

    p1, p2 = _two_view()
    return np.asarray(find_essential_matrix(p1, p2, _K()).E)


def _stereo_views() -> tuple[list[np.ndarray], list[np.ndarray], list[np.ndarray]]:
    """(object points, left and right pixels) of 5 noiseless views of a 7x5 board."""
    from imageform.geometry import BrownConrady, checkerboard_points, project_points_distorted
    from imageform.geometry.rotations import rvec_to_matrix

    obj = np.asarray(checkerboard_points((7, 5), 25.0))
    K1 = np.array([[810.0, 0, 322], [0, 805, 238], [0, 0, 1]])
    K2 = np.array([[790.0, 0, 315], [0, 792, 245], [0, 0, 1]])
    d = BrownConrady(-0.1, 0.05)
    R = np.asarray(rvec_to_matrix([0.02, -0.08, 0.01]))
    T = np.array([-120.0, 2.0, 3.0])
    objs, left, right = [], [], []
    for rv in (
        [0.2, 0.1, 0.0],
        [-0.2, 0.15, 0.05],
        [0.1, -0.25, -0.05],
        [-0.15, -0.1, 0.1],
        [0.25, 0.2, -0.1],
    ):
        Rk = np.asarray(rvec_to_matrix(rv))
        t = np.array([-60.0, -40.0, 500.0])
        left.append(np.asarray(project_points_distorted(obj, K1, Rk, t, d)[0]))
        right.append(np.asarray(project_points_distorted(obj, K2, R @ Rk, R @ t + T, d)[0]))
        objs.append(obj)
    return objs, left, right


def _stereo_result() -> Any:
    from imageform.geometry import stereo_calibrate

    objs, left, right = _stereo_views()
    with warnings.catch_warnings():  # the small board covers a fifth of the frame: fine here
        warnings.simplefilter("ignore")
        return stereo_calibrate(objs, left, right, (640, 480))


def _stereo_file_obj() -> Any:
    from imageform.io import StereoCameraFile

    return StereoCameraFile.from_calibration(_stereo_result())


def _stereo_file() -> Path:
    from imageform.io import write_stereo_camera

    path = _tmpdir() / "stereo.toml"
    write_stereo_camera(path, _stereo_file_obj())
    return path


def _psf() -> np.ndarray:
    from imageform.optics import diffraction_psf

    return diffraction_psf(wavelength=550e-9, f_number=4.0, pixel_pitch=2e-6, size=16, n_pupil=64)


def _json_of(fixture: str) -> Callable[[], Path]:
    def build() -> Path:
        path = _tmpdir() / f"{fixture}.json"
        FIXTURES[fixture]().to_json(path)
        return path

    return build


def _reinhard() -> Any:
    from imageform.analysis import ReinhardStats

    return ReinhardStats((50.0, 5.0, -5.0), (10.0, 4.0, 4.0), 100)


def _macenko() -> Any:
    from imageform.analysis import MacenkoStains

    return MacenkoStains(np.array([[0.65, 0.70, 0.29], [0.07, 0.99, 0.11]]), np.array([1.5, 1.2]))


def _of(name: str, path: str) -> Callable[[], Any]:
    """A fixture that is an attribute (dotted ``path``; ``[i]`` indexes) of another."""

    def build() -> Any:
        obj = resolve(V(name))
        for part in path.split("."):
            obj = obj[int(part[1:-1])] if part.startswith("[") else getattr(obj, part)
        return obj

    return build


def _scene_object(kind: str) -> Callable[[], Any]:
    def build() -> Any:
        return next(o for o in resolve(V("scene")).objects if o.kind == kind)

    return build


def _render_output() -> Any:
    from imageform.simulate.render import render_scene

    return render_scene(resolve(V("scene")))


def _calibration() -> Any:
    return _stereo_result().left


def _calibration_toml() -> Path:
    path = _tmpdir() / "calibration.toml"
    resolve(V("calibration")).to_toml(path)
    return path


def _chart_photo() -> np.ndarray:
    from imageform.analysis import synthetic_chart_photo

    return synthetic_chart_photo(shape=(128, 192), width=0.6, tilt=0.0, rotation=10.0).image


def _chart_detection() -> Any:
    from imageform.analysis import detect_colorchecker

    return detect_colorchecker(_chart_photo())


FIXTURES: dict[str, Callable[[], Any]] = {
    "chart_photo": _chart_photo,
    "chart_detection": _chart_detection,
    "rgb": _rgb,
    "rgb_u8": lambda: (_rgb() * 255).astype(np.uint8),
    "rgb_big": lambda: _rng().uniform(0.05, 0.95, (32, 40, 3)),
    # straight edges: a 48 x 64 checkerboard of 12 px squares (estimate_distortion_from_lines)
    "board_grey": lambda: ((np.mgrid[0:48, 0:64] // 12).sum(0) % 2) * 0.6 + 0.2,
    "gray": lambda: _rgb()[..., 1],
    "rgb4": lambda: _rng().uniform(0.05, 0.95, (4, 3)),
    "rgb1": lambda: np.array([0.2, 0.5, 0.7]),
    "xyz": lambda: _rng().uniform(0.1, 0.8, (4, 3)),
    "lab": lambda: np.array([[50.0, 10.0, -10.0], [60.0, -20.0, 15.0], [30.0, 5.0, 5.0]]),
    "xy": lambda: np.array([[0.3127, 0.329], [0.40, 0.38]]),
    "uv": lambda: np.array([[1.0, 2.0], [3.0, 4.0], [6.0, 1.0], [7.5, 5.0]]),
    "K": _K,
    "R": lambda: np.eye(3),
    "t": lambda: np.array([0.0, 0.0, 0.5]),
    "rvec": lambda: np.array([0.1, -0.2, 0.05]),
    "H": lambda: np.array([[1.0, 0.1, 2.0], [0.0, 1.1, -1.0], [0.001, 0.0, 1.0]]),
    "P": lambda: np.hstack([_K(), np.zeros((3, 1))]),
    "points3": _points3,
    "points2": lambda: _points3()[:, :2],
    "depth": lambda: np.array([2.0, 3.0, 4.0, 5.0]),
    "lines": lambda: np.array([[1.0, 0.0, -2.0], [0.0, 1.0, -3.0], [1.0, 1.0, -6.0]]),
    "wavelengths": lambda: np.arange(400.0, 701.0, 10.0),
    "spectrum": _spectrum,
    "camera": _camera,
    "sensor": _sensor,
    "segments": _segments,
    "spectrum3": _spectrum3,
    "brown": _brown,
    "scene": _scene,
    "result": _result,
    "tmpdir": _tmpdir,
    "chart": _chart,
    "rgb_chart": _rgb_chart,
    "correction": _correction,
    "stain": _stain,
    "png_file": _png_file,
    "dicom_file": _dicom_file,
    "camera_file": _camera_file,
    "tmpfile_png": lambda: _tmpdir() / "out.png",
    "tmpfile_json": lambda: _tmpdir() / "out.json",
    "tmpfile_toml": lambda: _tmpdir() / "out.toml",
    "pts1": lambda: _two_view()[0],
    "pts2": lambda: _two_view()[1],
    "pts1_5": lambda: (_two_view()[0][:5] - [4.0, 3.0]) / 500.0,
    "pts2_5": lambda: (_two_view()[1][:5] - [4.0, 3.0]) / 500.0,
    "pts1_7": lambda: _two_view()[0][:7],
    "pts2_7": lambda: _two_view()[1][:7],
    "points3_uv": lambda: _points3()[:, :2] / _points3()[:, 2:] * 500.0 + [4.0, 3.0],
    "P2": _P2,
    "E": _essential,
    "stereo_objs": lambda: _stereo_views()[0],
    "stereo_left": lambda: _stereo_views()[1],
    "stereo_right": lambda: _stereo_views()[2],
    "stereo_result": _stereo_result,
    "stereo_file_obj": _stereo_file_obj,
    "stereo_file": _stereo_file,
    "psf": _psf,
    "reinhard": _reinhard,
    "macenko": _macenko,
    "correction_json": _json_of("correction"),
    "scene_config": _of("scene", "config"),
    "P_stack": lambda: np.stack([_K() @ np.eye(3, 4), _P2()]),
    "pts_stack": lambda: np.stack(_two_view()),
    "png_dir": lambda: _png_file().parent,
    "job_result": _job_result,
    "batch_report": _batch_report,
    "worked_example": _worked_example,
    "tiff_file": _tiff_file,
    "tmpfile_tif": lambda: _tmpdir() / "out.tif",
    "png_glob": lambda: str(_png_file().parent / "*.png"),
    "png_file_str": lambda: str(_png_file()),
    "palette_check": _palette_check,
    "workflow": lambda: __import__("imageform.workflows", fromlist=["x"]).get_workflow(
        "white_balance"
    ),
    "encoded": lambda: __import__("imageform.simulate.stages", fromlist=["x"]).Encoded(
        image=_rgb(), transfer="srgb"
    ),
    "lens_config": _of("scene", "config.lens"),
    "sensor_config": _of("scene", "config.sensor"),
    "camera_config": _of("scene", "config.camera"),
    "colorchecker_obj": _scene_object("colorchecker"),
    "ground_obj": _scene_object("ground"),
    "render_output": _render_output,
    "photon_data": _of("result", "photon_transfer"),
    "emva_frames": _emva_frames,
    "emva_flats": _of("emva_frames", "flats"),
    "emva_darks": _of("emva_frames", "darks"),
    "emva_times": _of("emva_frames", "exposure_times"),
    "emva_photons": _of("emva_frames", "photons"),
    "patch_measurements": _of("result", "patches"),
    "cc_truth": _of("result", "colorchecker"),
    "vanishing_truth": _of("result", "vanishing"),
    "stage": _of("result", "stages.[0]"),
    "calibration": _calibration,
    "calibration_toml": _calibration_toml,
    "reinhard_json": _json_of("reinhard"),
    "macenko_json": _json_of("macenko"),
}

_CACHE: dict[str, Any] = {}
_FRESH = {
    "tmpdir",
    "dicom_file",
    "tmpfile_png",
    "tmpfile_json",
    "tmpfile_toml",
    "png_file",
    "camera_file",
    "stereo_file",
    "stereo_file_obj",
    "png_dir",
    "tiff_file",
    "tmpfile_tif",
    "png_glob",
    "png_file_str",
    "calibration_toml",
    "correction_json",
    "reinhard_json",
    "macenko_json",
}


def resolve(value: Any) -> Any:
    """``value`` with every :class:`V` (also inside tuples, lists and dicts) replaced by a
    fresh copy of its fixture."""
    if isinstance(value, V):
        if value.name in _FRESH:
            return FIXTURES[value.name]()
        if value.name not in _CACHE:
            _CACHE[value.name] = FIXTURES[value.name]()
        return copy.deepcopy(_CACHE[value.name])
    if isinstance(value, tuple) and not hasattr(value, "_fields"):
        return tuple(resolve(v) for v in value)
    if isinstance(value, list):
        return [resolve(v) for v in value]
    if isinstance(value, dict):
        return {k: resolve(v) for k, v in value.items()}
    return value
