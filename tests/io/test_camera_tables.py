"""The camera file's measured-camera tables [sensor], [optics], [color] (issue 18)."""

from __future__ import annotations

from pathlib import Path

import pytest

from imageform.errors import InvalidInputError, UnknownOptionError
from imageform.geometry import BrownConrady, Camera
from imageform.io import (
    CameraColor,
    CameraFile,
    CameraOptics,
    CameraSensor,
    read_camera,
    write_camera,
)

BASE = (
    'format = "imageform-camera"\nversion = 1\n[intrinsics]\nfx = 500\nfy = 500\ncx = 1\ncy = 1\n'
)

SENSOR = CameraSensor(
    system_gain_dn_per_e=0.2512345678901,
    read_noise_e=2.1,
    dark_current_e_per_s=5.0,
    dsnu_e=1.0,
    prnu=0.01,
    full_well_e=10000.0,
    bit_depth=12,
    black_level_dn=64.0,
    quantum_efficiency=0.6,
    pixel_pitch_um=3.45,
    cfa="RGGB",
    exposure_time_s=0.01,
)
OPTICS = {
    "model": "zernike",
    "f_number": 4,
    "focal_length_mm": 8.0,
    "zernike": [0.0, 0.0, 0.0, 0.1, 0.02],
    "wavelength_nm": 550,
    "mtf50_cy_per_px": [0.3, 0.31, 0.29],
}
COLOR = {
    "ccm": [[1.6, -0.4, -0.2], [-0.3, 1.5, -0.2], [0.0, -0.5, 1.5]],
    "white_balance": [2.0, 1.0, 1.5],
    "illuminant": "D65",
    "sensitivity": {
        "wavelengths_nm": [400, 500, 600, 700],
        "r": [0.0, 0.1, 0.9, 0.3],
        "g": [0.1, 0.9, 0.3, 0.0],
        "b": [0.9, 0.2, 0.0, 1 / 3],
    },
}


def _camera() -> Camera:
    return Camera(
        [[500.0, 0, 320], [0, 500, 240], [0, 0, 1]],
        image_size=(640, 480),
        distortion=BrownConrady(k1=-0.1),
    )


def test_round_trip_exact(tmp_path: Path) -> None:
    p = write_camera(tmp_path / "c.toml", _camera(), sensor=SENSOR, optics=OPTICS, color=COLOR)
    back = read_camera(p)
    assert back.sensor == SENSOR
    assert back.optics == CameraOptics(**{**OPTICS, "zernike": tuple(OPTICS["zernike"])})
    assert back.optics is not None and back.optics.mtf50_rgb() == (0.3, 0.31, 0.29)
    assert isinstance(back.color, CameraColor)
    assert back.color.ccm_to == "linear_srgb"
    assert back.color.sensitivity is not None
    assert back.color.sensitivity.b[-1] == 1 / 3
    again = write_camera(tmp_path / "d.toml", back)
    head = p.read_text().split("[provenance]")[0]
    assert head == again.read_text().split("[provenance]")[0]
    assert "[color.sensitivity]" in head and "[sensor]" in head


def test_tables_absent_read_as_none_and_old_text_unchanged(tmp_path: Path) -> None:
    p = write_camera(tmp_path / "c.toml", _camera())
    cf = read_camera(p)
    assert cf.sensor is None and cf.optics is None and cf.color is None
    text = p.read_text()
    for t in ("[sensor]", "[optics]", "[color]"):
        assert t not in text
    assert "version = 1" in text


def test_camera_file_takes_mappings() -> None:
    cf = CameraFile(
        _camera(), sensor={"read_noise_e": 3}, optics={"model": "diffraction", "f_number": 2.8}
    )
    assert cf.sensor == CameraSensor(read_noise_e=3.0)
    assert cf.optics is not None and cf.optics.f_number == 2.8
    with pytest.raises(TypeError, match="sensor as a CameraSensor"):
        CameraFile(_camera(), sensor=3)  # type: ignore[arg-type]


def test_cfa_list_matches_sensor() -> None:
    from imageform.io._camera_tables import _CFA
    from imageform.sensor import CFA_PATTERNS

    assert tuple(_CFA) == tuple(CFA_PATTERNS)


@pytest.mark.parametrize(
    ("extra", "exc", "where"),
    [
        ("[sensor]\nfoo = 1", UnknownOptionError, "sensor.foo; valid in [sensor]: system_gain"),
        ("[sensor]\nread_noise_e = -1", InvalidInputError, "sensor.read_noise_e: expected"),
        ("[sensor]\nsystem_gain_dn_per_e = 0", InvalidInputError, "sensor.system_gain_dn_per_e"),
        ("[sensor]\nbit_depth = 12.5", InvalidInputError, "sensor.bit_depth: expected an integer"),
        ("[sensor]\ncfa = 'XX'", UnknownOptionError, "sensor.cfa: unknown CFA"),
        ("[sensor]\nprnu = 2", InvalidInputError, "sensor.prnu: expected a fraction"),
        ("[sensor]\nquantum_efficiency = 0", InvalidInputError, "sensor.quantum_efficiency"),
        ("[sensor]\nfull_well_e = true", InvalidInputError, "sensor.full_well_e: expected a num"),
        ("[optics]\nf_number = 2", InvalidInputError, "optics.model: missing"),
        ("[optics]\nmodel = 'blur'", UnknownOptionError, "optics.model: unknown optics model"),
        ("[optics]\nmodel = 'zernike'\nf_number = 2", InvalidInputError, "optics.zernike: miss"),
        ("[optics]\nmodel = 'diffraction'", InvalidInputError, "optics.f_number: missing"),
        ("[optics]\nmodel = 'gaussian'\ngaussian_sigma_px = -1", InvalidInputError, "sigma_px"),
        ("[optics]\nmodel = 'mtf50'\nmtf50_cy_per_px = [1, 2]", InvalidInputError, "mtf50_cy"),
        ("[optics]\nmodel = 'mtf50'\nmtf50_cy_per_px = 0", InvalidInputError, "mtf50_cy_per_px"),
        ("[optics]\nmodel='diffraction'\nf_number=2\nx=1", UnknownOptionError, "optics.x"),
        ("[color]\nccm = [[1, 2], [3, 4]]", InvalidInputError, "color.ccm: expected 3 rows"),
        ("[color]\nwhite_balance = [1, 0, 1]", InvalidInputError, "color.white_balance"),
        ("[color]\nilluminant = 'Q99'", InvalidInputError, "color.illuminant: unknown"),
        ("[color]\nspectral_sensitivity = 'canon'", UnknownOptionError, "nikon_d5100"),
        ("[color]\nccm_to = 'xyz'", InvalidInputError, "color.ccm_to: given without a ccm"),
        ("[color]\nccm=[[1,0,0],[0,1,0],[0,0,1]]\nccm_to='lab'", UnknownOptionError, "ccm_to"),
        (
            "[color.sensitivity]\nwavelengths_nm = [1, 2]\nr = [1]\ng = [1, 1]\nb = [1, 1]",
            InvalidInputError,
            "color.sensitivity.r",
        ),
        (
            "[color.sensitivity]\nwavelengths_nm = [2, 1]\nr = [1, 1]\ng = [1, 1]\nb = [1, 1]",
            InvalidInputError,
            "color.sensitivity.wavelengths_nm: expected strictly increasing",
        ),
        (
            "[color]\nspectral_sensitivity = 'nikon_d5100'\n[color.sensitivity]\n"
            "wavelengths_nm = [1, 2]\nr = [1, 1]\ng = [1, 1]\nb = [1, 1]",
            InvalidInputError,
            "not both",
        ),
    ],
)
def test_bad_values_one_line(tmp_path: Path, extra: str, exc: type, where: str) -> None:
    p = tmp_path / "cam.toml"
    p.write_text(BASE + extra + "\n")
    with pytest.raises(exc) as info:
        read_camera(p)
    msg = str(info.value)
    assert "\n" not in msg and len(msg) <= 240, msg
    assert str(p) in msg and where in msg, msg


def test_python_errors_name_the_table_key() -> None:
    with pytest.raises(InvalidInputError, match=r"sensor\.read_noise_e"):
        CameraSensor(read_noise_e=-2)
    with pytest.raises(InvalidInputError, match=r"optics\.gaussian_sigma_px: missing"):
        CameraOptics(model="gaussian")
    with pytest.raises(UnknownOptionError, match=r"valid in \[color\]"):
        write_camera("unused.toml", _camera(), color={"wb": [1, 1, 1]})


def test_stereo_file_keeps_the_tables(tmp_path: Path) -> None:
    import numpy as np

    from imageform.io import StereoCameraFile, read_stereo_camera, write_stereo_camera

    left = CameraFile(_camera(), sensor=SENSOR, color=COLOR)
    right = CameraFile(_camera(), optics=OPTICS).with_pose(np.eye(3), [-0.1, 0.0, 0.0])
    right = CameraFile(right.camera, True, optics=OPTICS)
    p = write_stereo_camera(tmp_path / "rig.toml", StereoCameraFile(left, right))
    assert "[left.color.sensitivity]" in p.read_text()
    back = read_stereo_camera(p)
    assert back.left.sensor == SENSOR and back.left.color == left.color
    assert back.right.optics == right.optics and back.right.sensor is None


def test_zernike_zones_round_trip(tmp_path: Path) -> None:
    zones = [[[0.0, 0.0, 0.0, 0.1], [0.0, 0.0, 0.0, 0.1, 0.0, 0.0, 0.0, 0.5]]] * 2
    optics = CameraOptics(model="zernike", f_number=2.8, wavelength_nm=550.0, zernike_zones=zones)
    write_camera(tmp_path / "z.toml", _camera(), optics=optics)
    back = read_camera(tmp_path / "z.toml").optics
    assert back == optics and back.zernike is None
    assert len(back.zernike_zones) == 2 and len(back.zernike_zones[0][1]) == 8
