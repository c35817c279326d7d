"""Raw files as LibRaw reads them: DNG variants written from a real photograph (issue 26).

A mosaic sampled from a Kodak photograph (or, without the reference data, the simulator's
default scene) is written as DNG, then varied as cameras and converters write them: an
orientation tag (a portrait shot), per-photosite black levels, a linear (already demosaiced,
LinearRaw) DNG, no colour matrix at all, an X-Trans CFA, a black frame. Each develops to
within a mean CIEDE2000 of 1 of LibRaw's own rendering at matched settings, with the same
orientation and size, or is refused in one line.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from imageform.errors import InvalidInputError, UnreadableFileError
from imageform.io import develop, read_image, read_raw, write_dng

rawpy = pytest.importorskip("rawpy")

ROOT = Path(__file__).resolve().parents[2]
KODAK = ROOT.parent / "shared" / "data" / "kodak" / "kodim23.png"

#: XYZ (D65) to camera RGB of a made-up camera (rows: R, G, B).
CM = np.array([[1.20, -0.30, -0.10], [-0.40, 1.30, 0.10], [-0.05, 0.20, 0.60]])
NEUTRAL = (0.55, 1.0, 0.42)


def _camera_rgb() -> np.ndarray:
    """Linear camera RGB in [0, 1] of a real photograph (what the made-up camera recorded)."""
    from imageform.color import decode, linear_srgb_to_xyz

    if KODAK.is_file():
        srgb = np.asarray(read_image(KODAK), np.float64)[:256, :384] / 255.0
    else:  # pragma: no cover - without the reference data
        from imageform.simulate import default_scene, simulate

        srgb = np.asarray(simulate(default_scene().resized(384), rng=0).image)[:216]
    xyz = linear_srgb_to_xyz(decode(srgb, "srgb"))
    cam = xyz @ CM.T / np.asarray(NEUTRAL)  # white-balanced by the neutral as shot
    return np.clip(cam * np.asarray(NEUTRAL) * 0.9, 0, 1)


@pytest.fixture(scope="module")
def base(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[tuple], np.ndarray]:
    import tifffile

    from imageform.sensor import mosaic as make_mosaic

    cam = _camera_rgb()
    dn = np.round(64 + make_mosaic(cam, "RGGB") * (4095 - 64)).astype(np.uint16)
    path = write_dng(
        tmp_path_factory.mktemp("raw") / "base.dng",
        dn,
        black_level=64,
        white_level=4095,
        color_matrix=CM,
        as_shot_neutral=NEUTRAL,
    )
    with tifffile.TiffFile(path) as tf:
        tags = [(t.code, t.dtype, t.count, t.value, True) for t in tf.pages[0].tags]
    tags = [t for t in tags if t[0] >= 33421]
    lin = np.round(64 + cam * (4095 - 64)).astype(np.uint16)
    return path, tags, lin


def _variant(base: tuple[Path, list[tuple], np.ndarray], name: str, **change: object) -> Path:
    import tifffile

    path, tags, _ = base
    drop = set(change.get("drop", ()))  # type: ignore[call-overload]
    extra = list(change.get("extra", ()))  # type: ignore[call-overload]
    data = change.get("data")
    if data is None:
        with tifffile.TiffFile(path) as tf:
            data = tf.pages[0].asarray()
    out = path.with_name(f"{name}.dng")
    tifffile.imwrite(
        out,
        data,
        photometric=change.get("photometric", 32803),
        extratags=[t for t in tags if t[0] not in drop] + extra,
    )
    return out


def _libraw(path: Path, **kw: object) -> np.ndarray:
    settings = {
        "use_camera_wb": True,
        "no_auto_bright": True,
        "output_bps": 16,
        "gamma": (2.4, 12.92),
        "demosaic_algorithm": rawpy.DemosaicAlgorithm.LINEAR,
        "adjust_maximum_thr": 0.0,
    } | kw
    with rawpy.imread(str(path)) as r:
        return r.postprocess(**settings) / 65535.0


def _mean_de00(a: np.ndarray, b: np.ndarray) -> float:
    from imageform.color import decode, delta_e, linear_srgb_to_xyz, xyz_to_lab

    lab1 = xyz_to_lab(linear_srgb_to_xyz(decode(np.asarray(a, np.float64), "srgb")))
    lab2 = xyz_to_lab(linear_srgb_to_xyz(decode(b, "srgb")))
    return float(np.mean(delta_e(lab1, lab2)[2:-2, 2:-2]))


def test_base_matches_libraw(base: tuple[Path, list[tuple], np.ndarray]) -> None:
    ours = develop(base[0]).image
    assert _mean_de00(ours, _libraw(base[0])) < 1.0


@pytest.mark.parametrize(("exif", "flip"), [(3, 3), (6, 6), (8, 5)])
def test_orientation_as_libraw(
    base: tuple[Path, list[tuple], np.ndarray], exif: int, flip: int
) -> None:
    """A portrait shot comes out as LibRaw turns it (issue 26: it came out sideways)."""
    path = _variant(base, f"orient{exif}", extra=[(274, 3, 1, exif, True)])
    raw = read_raw(path)
    assert raw.orientation == flip
    dev = develop(raw)
    ref = _libraw(path)
    assert dev.image.shape == ref.shape
    assert _mean_de00(dev.image, ref) < 1.0
    assert develop(raw, orient=False).image.shape == raw.mosaic.shape + (3,)


def test_per_photosite_black_levels(base: tuple[Path, list[tuple], np.ndarray]) -> None:
    import tifffile

    with tifffile.TiffFile(base[0]) as tf:
        data = tf.pages[0].asarray().astype(np.int32)
    offsets = np.array([[0, 8], [16, 24]])
    data = np.clip(data + np.tile(offsets, (data.shape[0] // 2, data.shape[1] // 2)), 0, 4095)
    path = _variant(
        base,
        "black4",
        data=data.astype(np.uint16),
        drop={50713, 50714},
        extra=[(50713, 3, 2, (2, 2), True), (50714, 4, 4, tuple(64 + offsets.ravel()), True)],
    )
    raw = read_raw(path)
    np.testing.assert_array_equal(raw.black_level, 64 + offsets)
    assert _mean_de00(develop(raw).image, _libraw(path)) < 1.0


def test_linear_dng_develops(base: tuple[Path, list[tuple], np.ndarray]) -> None:
    """A LinearRaw DNG (three colours a pixel) crashed with IndexError; now it develops."""
    path = _variant(
        base,
        "linear",
        data=base[2],
        photometric=34892,
        drop={33421, 33422, 50710, 50711},
    )
    raw = read_raw(path)
    assert raw.cfa_pattern is None and raw.mosaic.shape == base[2].shape
    dev = develop(raw)
    assert dev.demosaic == "none"
    ref = _libraw(path)
    assert dev.image.shape == ref.shape
    assert _mean_de00(dev.image, ref) < 1.0


def test_no_colour_matrix_is_not_black(
    base: tuple[Path, list[tuple], np.ndarray], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """No matrix in the file and none known to LibRaw (rgb_cam all zeros): camera RGB, a note."""
    from imageform.cli import main

    path = _variant(base, "nomatrix", drop={50721})
    raw = read_raw(path)
    assert raw.xyz_to_camera is None and not np.any(raw.camera_to_srgb)
    dev = develop(raw)
    assert dev.image.mean() > 0.1 and dev.notes
    assert main(["develop", str(path), "-o", str(tmp_path / "x.png")]) == 0
    err = capsys.readouterr().err
    assert "no colour matrix" in err and err.count("\n") == 1


def test_a_black_frame_is_refused(
    base: tuple[Path, list[tuple], np.ndarray], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from imageform.cli import main

    path = _variant(base, "black", data=np.full((64, 96), 60, np.uint16))
    with pytest.raises(InvalidInputError, match="black level"):
        develop(path)
    assert main(["develop", str(path), "-o", str(tmp_path / "x.png")]) == 1
    assert capsys.readouterr().err.count("\n") == 1
    assert not (tmp_path / "x.png").exists()


def test_xtrans_develops_through_libraw_linear_interpolation(
    base: tuple[Path, list[tuple], np.ndarray], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A 6x6 X-Trans CFA (Fujifilm) was refused; it is demosaiced by LibRaw's own linear
    interpolation (what its LINEAR mode does for X-Trans) and developed by imageform's
    pipeline, to LibRaw's rendering. Without LibRaw it is refused in one line, named."""
    import sys

    import tifffile

    xt = np.array([[1, 1, 0, 1, 1, 2], [1, 1, 2, 1, 1, 0], [2, 0, 1, 0, 2, 1],
                   [1, 1, 2, 1, 1, 0], [1, 1, 0, 1, 1, 2], [0, 2, 1, 2, 0, 1]])  # fmt: skip
    cam = _camera_rgb()
    h, w = cam.shape[:2]
    which = np.tile(xt, (h // 6 + 1, w // 6 + 1))[:h, :w]
    mos = np.take_along_axis(cam, which[..., None], axis=2)[..., 0]
    path = _variant(
        base,
        "xtrans",
        data=np.round(64 + mos * (4095 - 64)).astype(np.uint16),
        drop={33421, 33422},
        extra=[(33421, 3, 2, (6, 6), True), (33422, 1, 36, tuple(xt.ravel().tolist()), True)],
    )
    raw = read_raw(path)
    assert raw.metadata["xtrans"] == "GGRGGB" and raw.metadata["raw_type"] == "xtrans"
    assert raw.cfa_pattern is None and raw.mosaic.shape == (h, w, 3)
    dev = develop(raw)
    assert dev.demosaic == "libraw_linear" and not dev.notes
    assert _mean_de00(dev.image, _libraw(path)) < 0.1
    assert "X-Trans" in develop(raw, demosaic="malvar").notes[0]
    with tifffile.TiffFile(path) as tf:
        assert tf.pages[0].tags[33421].value == (6, 6)

    def broken(r: object) -> np.ndarray:
        raise MemoryError

    with monkeypatch.context() as m:  # LibRaw's own failure: one line, named
        m.setattr("imageform.io.raw._libraw_linear_demosaic", broken)
        with pytest.raises(InvalidInputError, match="could not demosaic its X-Trans"):
            read_raw(path)
    monkeypatch.setitem(sys.modules, "rawpy", None)
    with pytest.raises(InvalidInputError, match=r"6x6 CFA \(first row GGRGGB\)") as e:
        read_raw(path)
    assert "\n" not in str(e.value)


def test_develop_writes_16_bit_png(
    base: tuple[Path, list[tuple], np.ndarray], tmp_path: Path
) -> None:
    import imagecodecs

    from imageform.cli import main

    for name, path in (
        ("bayer", base[0]),
        (
            "linear",
            _variant(
                base, "lin2", data=base[2], photometric=34892, drop={33421, 33422, 50710, 50711}
            ),
        ),
    ):
        out = tmp_path / f"{name}.png"
        assert main(["develop", str(path), "-o", str(out)]) == 0
        assert imagecodecs.imread(out).dtype == np.uint16, name
    assert main(["develop", str(base[0]), "-o", str(tmp_path / "8.png"), "--bit-depth", "8"]) == 0
    assert imagecodecs.imread(tmp_path / "8.png").dtype == np.uint8


def test_json_reports_the_orientation(
    base: tuple[Path, list[tuple], np.ndarray], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import json

    from imageform.cli import main

    path = _variant(base, "orient6j", extra=[(274, 3, 1, 6, True)])
    assert main(["develop", str(path), "-o", str(tmp_path / "x.png"), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["orientation"] == {"flip": 6, "applied": True}
    h, w = read_raw(path).mosaic.shape
    assert doc["output_size"] == [h, w]


def _rational(values: object) -> tuple[int, ...]:
    """TIFF (S)RATIONAL values as tifffile writes them: numerator, denominator pairs."""
    out: list[int] = []
    for v in np.ravel(np.asarray(values, np.float64)):
        out += [round(float(v) * 10000), 10000]
    return tuple(out)


#: XYZ to camera RGB of the made-up camera under CIE A (its second matrix in two-matrix files).
CM_A = np.array([[0.90, -0.20, -0.05], [-0.50, 1.40, 0.15], [-0.10, 0.30, 0.80]])


def _two_matrices(
    base: tuple[Path, list[tuple], np.ndarray], name: str, ill: tuple[int, int], **more: object
) -> Path:
    """The base DNG with CM_A as ColorMatrix1 and CM as ColorMatrix2 under illuminants ``ill``."""
    extra = [
        (50721, 10, 9, _rational(CM_A), True),
        (50722, 10, 9, _rational(CM), True),
        (50778, 3, 1, ill[0], True),
        (50779, 3, 1, ill[1], True),
    ]
    return _variant(base, name, drop={50721, 50778}, extra=extra + list(more.get("extra", ())))  # type: ignore[call-overload]


def _assert_libraw_matrix(raw: object, path: Path) -> None:
    """LibRaw's rgb_cam for the file is the one of imageform's matrix (the same matrix picked)."""
    from imageform.io.raw import _libraw_rgb_cam

    with rawpy.imread(str(path)) as r:
        theirs = np.asarray(r.color_matrix, np.float64)[:3, :3]
    ours = _libraw_rgb_cam(np.asarray(raw.xyz_to_camera))[0]  # type: ignore[attr-defined]
    np.testing.assert_allclose(ours, theirs, atol=2e-3)


@pytest.mark.parametrize(
    ("ill", "picked", "name"),
    [
        ((17, 21), CM, "D65"),  # Adobe's converter: StdA first, D65 second
        ((21, 17), CM_A, "D65"),  # D65 first: its matrix (here CM_A's slot)
        ((17, 23), CM, "D50"),  # no D65: the first daylight kind (D50)
        ((20, 23), CM_A, "D55"),  # two daylight kinds: the first
        ((17, 24), CM, "D65"),  # no daylight kind at all: the last matrix (unknown code: D65)
    ],
)
def test_two_colour_matrices_picked_as_libraw(
    base: tuple[Path, list[tuple], np.ndarray],
    ill: tuple[int, int],
    picked: np.ndarray,
    name: str,
) -> None:
    """Which of two ColorMatrix tags a DNG is developed with: LibRaw's rule (its identify)."""
    path = _two_matrices(base, f"two{ill[0]}_{ill[1]}", ill)
    raw = read_raw(path)
    if ill == (21, 17):  # D65 is ColorMatrix1 here, which holds CM_A
        picked = CM_A
    np.testing.assert_allclose(raw.xyz_to_camera, picked, atol=1e-4)
    assert raw.calibration_illuminant == name
    _assert_libraw_matrix(raw, path)
    assert _mean_de00(develop(raw).image, _libraw(path)) < 0.05


def test_camera_calibration_and_analog_balance_as_libraw(
    base: tuple[Path, list[tuple], np.ndarray],
) -> None:
    """The matrix is diag(AnalogBalance) CameraCalibration ColorMatrix (DNG 1.4, ch. 6)."""
    cc = np.array([[1.05, 0.03, -0.02], [0.01, 0.98, 0.02], [-0.03, 0.04, 1.10]])
    ab = np.array([1.2, 1.0, 0.8])
    path = _variant(
        base,
        "calibrated",
        extra=[(50723, 10, 9, _rational(cc), True), (50727, 5, 3, _rational(ab), True)],
    )
    raw = read_raw(path)
    np.testing.assert_allclose(raw.xyz_to_camera, np.diag(ab) @ cc @ CM, atol=1e-4)
    _assert_libraw_matrix(raw, path)
    assert _mean_de00(develop(raw).image, _libraw(path)) < 0.05
    # with two matrices, the calibration of the picked one (CameraCalibration2 for D65)
    path2 = _two_matrices(
        base,
        "calibrated2",
        (17, 21),
        extra=[
            (50723, 10, 9, _rational(np.eye(3) * 0.9), True),
            (50724, 10, 9, _rational(cc), True),
        ],
    )
    raw2 = read_raw(path2)
    np.testing.assert_allclose(raw2.xyz_to_camera, cc @ CM, atol=1e-4)
    _assert_libraw_matrix(raw2, path2)


def test_a_single_matrix_is_not_adapted_from_its_illuminant(
    base: tuple[Path, list[tuple], np.ndarray],
) -> None:
    """One matrix labelled CIE A (or D50): LibRaw, like Adobe's DNG SDK for one matrix, takes a
    white-balanced white as D65's; so does develop (it adapted from A before, 2.6 ΔE00 off)."""
    for code, label in ((17, "A"), (23, "D50")):
        path = _variant(base, f"single{code}", drop={50778}, extra=[(50778, 3, 1, code, True)])
        raw = read_raw(path)
        assert raw.calibration_illuminant == label
        dev = develop(raw)
        np.testing.assert_allclose(dev.adaptation, np.eye(3))
        assert _mean_de00(dev.image, _libraw(path)) < 0.05


@pytest.mark.parametrize("how", ["none", "white_xy"])
def test_no_as_shot_white_balance_falls_back_as_libraw(
    base: tuple[Path, list[tuple], np.ndarray],
    how: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """No AsShotNeutral (and LibRaw does not read AsShotWhiteXY for the gains): LibRaw's
    use_camera_wb falls back to its automatic white balance; develop did refuse 'camera'."""
    from imageform.cli import main

    extra = [(50729, 5, 2, _rational([0.3127, 0.3290]), True)] if how == "white_xy" else []
    path = _variant(base, f"nowb_{how}", drop={50728}, extra=extra)
    raw = read_raw(path)
    assert raw.white_balance is None
    dev = develop(raw)
    assert any("no as-shot white balance" in n for n in dev.notes)
    np.testing.assert_allclose(dev.gains, develop(raw, white_balance="auto").gains)
    assert _mean_de00(dev.image, _libraw(path)) < 0.2
    assert main(["develop", str(path), "-o", str(tmp_path / "x.png")]) == 0
    err = capsys.readouterr().err
    assert "no as-shot white balance" in err and err.count("\n") == 1


def test_automatic_white_balance_as_libraw(base: tuple[Path, list[tuple], np.ndarray]) -> None:
    """white_balance='auto': dcraw's -a (LibRaw's use_auto_wb), unsaturated 8x8 blocks."""
    from imageform.io.raw import _auto_gains

    raw = read_raw(base[0])
    auto = develop(raw, white_balance="auto")
    ref = _libraw(base[0], use_camera_wb=False, use_auto_wb=True)
    assert _mean_de00(auto.image, ref) < 0.2
    # a saturated block is left out: saturating one 8x8 block's red changes nothing
    sat = replace(raw, mosaic=raw.mosaic.copy())
    sat.mosaic[8:16, 8:16] = 4095
    np.testing.assert_allclose(_auto_gains(sat), _auto_gains(raw), rtol=2e-3)
    # an odd-sized frame: the last blocks are partial
    odd = replace(raw, mosaic=raw.mosaic[:251, :379])
    assert np.all(np.isfinite(_auto_gains(odd)))


def test_automatic_white_balance_scales_the_two_greens_apart(
    base: tuple[Path, list[tuple], np.ndarray],
) -> None:
    """LibRaw's automatic white balance (and use_camera_wb's fallback) gives the second
    green of the tile its own multiplier; pooled, a real Canon CRW (no as-shot balance, a
    1.3 % green imbalance) developed 0.18 ΔE00 from LibRaw (benchmarks/check_raw_fresh.py)."""
    from imageform.io.raw import _auto_gains

    with __import__("tifffile").TiffFile(base[0]) as tf:
        data = tf.pages[0].asarray().astype(np.float64)
    data[1::2, 0::2] = 64 + (data[1::2, 0::2] - 64) * 0.96  # the second green 4 % darker
    path = _variant(base, "green_split", drop={50728}, data=np.round(data).astype(np.uint16))
    raw = read_raw(path)
    mul = _auto_gains(raw)
    assert mul.shape == (2, 2)
    assert mul[1, 0] / mul[0, 1] == pytest.approx(1 / 0.96, rel=0.01)
    for wb, theirs in (("camera", {}), ("auto", {"use_camera_wb": False, "use_auto_wb": True})):
        dev = develop(raw, white_balance=wb)
        assert dev.gains.min() == pytest.approx(1.0)
        assert _mean_de00(dev.image, _libraw(path, **theirs)) < 0.03
        # the other demosaicing methods take the same gains (the white-balanced mosaic)
        balanced = dev.white_balanced
        assert np.median(balanced[1::2, 0::2]) == pytest.approx(
            np.median(balanced[0::2, 1::2]), rel=0.01
        )


def _monochrome(base: tuple[Path, list[tuple], np.ndarray], name: str, grey: np.ndarray) -> Path:
    """A monochrome DNG (LinearRaw, one sample a pixel, no colour tags), as a Leica Monochrom
    writes it. tifffile writes LinearRaw with three samples only: the tag is set afterwards."""
    import tifffile

    colour = {33421, 33422, 50710, 50711, 50721, 50728, 50778}
    path = _variant(base, name, data=grey, photometric=1, drop=colour)
    with tifffile.TiffFile(path) as tf:
        at = tf.pages[0].tags[262].valueoffset  # type: ignore[union-attr]
    with path.open("r+b") as fh:
        fh.seek(at)
        fh.write(np.uint16(34892).tobytes())  # little-endian, as tifffile wrote the file
    return path


def test_monochrome_raw_develops_grey(
    base: tuple[Path, list[tuple], np.ndarray], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A sensor without colour filters was refused ("a 1x1 1-colour CFA"); LibRaw develops it
    to one grey channel, and so does develop, to LibRaw's values."""
    import json

    import imagecodecs

    from imageform.cli import main

    grey = base[2][..., 1].copy()
    path = _monochrome(base, "mono", grey)
    raw = read_raw(path)
    assert raw.monochrome and raw.cfa_pattern is None and raw.mosaic.shape == grey.shape
    np.testing.assert_array_equal(raw.mosaic, grey)
    assert raw.white_balance is None and raw.xyz_to_camera is None
    for linear, gamma in ((False, (2.4, 12.92)), (True, (1, 1))):
        dev = develop(raw, linear=linear)
        ref = _libraw(path, gamma=gamma)
        assert ref.shape == grey.shape + (1,)
        assert dev.image.shape == grey.shape and dev.demosaic == "none" and not dev.notes
        assert np.abs(dev.image - ref[..., 0]).max() < 2e-4
    assert develop(raw).to_integer(16).shape == grey.shape
    assert develop(raw, space="prophoto").image.shape == grey.shape  # grey in any space
    out = tmp_path / "mono.png"
    assert main(["develop", str(path), "-o", str(out), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["monochrome"] is True and doc["cfa_pattern"] is None
    written = imagecodecs.imread(out)
    assert written.shape == grey.shape and written.dtype == np.uint16


@pytest.mark.parametrize("layout", ["BGGR", "GRBG", "GBRG", "odd", "active_area", "crop",
                                    "linearization", "black_delta"])  # fmt: skip
def test_more_dng_layouts_match_libraw(
    base: tuple[Path, list[tuple], np.ndarray], layout: str
) -> None:
    """The other Bayer phases, odd sizes, ActiveArea (margins cut), DefaultCrop (LibRaw does not
    crop), a LinearizationTable and BlackLevelDeltaH/V: each as LibRaw develops it."""
    import tifffile

    from imageform.sensor import mosaic as make_mosaic

    with tifffile.TiffFile(base[0]) as tf:
        data = tf.pages[0].asarray()
    cam = _camera_rgb()
    change: dict[str, object] = {}
    if layout in ("BGGR", "GRBG", "GBRG"):
        codes = {"BGGR": (2, 1, 1, 0), "GRBG": (1, 0, 2, 1), "GBRG": (1, 2, 0, 1)}[layout]
        change = {
            "data": np.round(64 + make_mosaic(cam, layout) * (4095 - 64)).astype(np.uint16),
            "drop": {33422},
            "extra": [(33422, 1, 4, codes, True)],
        }
    elif layout == "odd":
        change = {"data": data[:255, :383].copy()}
    elif layout == "active_area":
        change = {"extra": [(50829, 4, 4, (2, 4, 250, 380), True)]}
    elif layout == "crop":
        change = {"extra": [(50719, 4, 2, (4, 4), True), (50720, 4, 2, (370, 240), True)]}
    elif layout == "linearization":  # stored as indices of a quadratic table to 12 bits
        table = np.round((np.arange(1024) / 1023.0) ** 2 * 4095).astype(np.uint16)
        change = {
            "data": np.searchsorted(table, data).clip(0, 1023).astype(np.uint16),
            "extra": [(50712, 3, 1024, tuple(table.tolist()), True)],
        }
    else:  # black_delta: a black level drifting across rows and columns
        dh, dv = np.linspace(0, 10, data.shape[1]), np.linspace(0, 6, data.shape[0])
        drift = np.clip(data + dh[None, :] + dv[:, None], 0, 4095).round().astype(np.uint16)
        change = {
            "data": drift,
            "extra": [
                (50715, 10, data.shape[1], _rational(dh), True),
                (50716, 10, data.shape[0], _rational(dv), True),
            ],
        }
    path = _variant(base, f"layout_{layout}", **change)
    ours = develop(path).image
    ref = _libraw(path)
    assert ours.shape == ref.shape
    assert _mean_de00(ours, ref) < 0.05


@pytest.mark.parametrize("kind", ["cfa", "linear", "cfa_black"])
def test_floating_point_dng_develops(base: tuple[Path, list[tuple], np.ndarray], kind: str) -> None:
    """A DNG of 32-bit floats with WhiteLevel 1.0 (an HDR merge, some converters): LibRaw opens
    it but leaves every sample 0 (a black image); read_raw reads the samples with tifffile,
    and the development equals the integer file's."""
    import tifffile

    with tifffile.TiffFile(base[0]) as tf:
        data = tf.pages[0].asarray()
    levels = [(50717, 11, 1, 1.0, True)]
    if kind == "linear":
        floats = (base[2].astype(np.float64) - 64) / (4095 - 64)
        path = _variant(base, "float_lin", data=floats.astype(np.float32), photometric=34892,
                        drop={33421, 33422, 50710, 50711, 50713, 50714, 50717},
                        extra=levels + [(50714, 11, 1, 0.0, True)])  # fmt: skip
        reference = _variant(base, "int_lin", data=base[2], photometric=34892,
                             drop={33421, 33422, 50710, 50711})  # fmt: skip
    else:
        black = 0.02 if kind == "cfa_black" else 0.0
        floats = black + (1 - black) * (data.astype(np.float64) - 64) / (4095 - 64)
        path = _variant(base, f"float_{kind}", data=floats.astype(np.float32),
                        drop={50713, 50714, 50717},
                        extra=levels + [(50714, 11, 1, black, True)])  # fmt: skip
        reference = base[0]
    with rawpy.imread(str(path)) as r:
        assert not np.any(r.raw_image_visible)  # what LibRaw gives: nothing
    raw = read_raw(path)
    assert raw.metadata["raw_type"] == "float" and raw.white_level == 65535.0
    dev = develop(raw)
    assert _mean_de00(dev.image, develop(reference).image) < 0.02


def test_raw_pixel_limit(
    base: tuple[Path, list[tuple], np.ndarray], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Raws default to 200 Mpx (a 102 Mpx GFX100 or 151 Mpx IQ4 file was over the images' 100
    Mpx); IMAGEFORM_MAX_PIXELS and max_pixels still rule when given."""
    from imageform.io import RAW_MAX_PIXELS, max_pixels

    assert RAW_MAX_PIXELS >= 151_000_000 + 10_000_000 > max_pixels()
    with pytest.raises(InvalidInputError, match="pixels"):
        read_raw(base[0], max_pixels=1000)
    monkeypatch.setenv("IMAGEFORM_MAX_PIXELS", "1000")
    with pytest.raises(InvalidInputError, match="pixels"):
        read_raw(base[0])
    monkeypatch.setenv("IMAGEFORM_MAX_PIXELS", "")
    assert read_raw(base[0]).mosaic.size == base[2][..., 0].size


def test_characterize_frames_refuse_a_linear_raw(
    base: tuple[Path, list[tuple], np.ndarray],
) -> None:
    """characterize's EMVA frames need photosite values: a linear raw is refused in one line,
    a monochrome raw is one grey frame."""
    from imageform.workflows._characterize_inputs import _frame

    path = _variant(base, "lin_frame", data=base[2], photometric=34892,
                    drop={33421, 33422, 50710, 50711})  # fmt: skip
    with pytest.raises(InvalidInputError, match="linear") as e:
        _frame(path, {}, None)
    assert "\n" not in str(e.value)
    grey, cfa = _frame(_monochrome(base, "mono_frame", base[2][..., 0].copy()), {}, None)
    assert cfa is None and grey.shape == base[2].shape[:2]


def test_floating_point_dng_in_a_tiled_subifd(
    base: tuple[Path, list[tuple], np.ndarray], tmp_path: Path
) -> None:
    """As converters lay a DNG out: IFD 0 a preview with the colour tags, the raw image (tiled
    floats here) in a SubIFD with its CFA and level tags."""
    import tifffile

    path0, tags, _ = base
    with tifffile.TiffFile(path0) as tf:
        data = tf.pages[0].asarray()
    raw_codes = {33421, 33422, 50710, 50711}
    ifd0 = [t for t in tags if t[0] not in raw_codes | {50713, 50714, 50717}]
    in_raw = [t for t in tags if t[0] in raw_codes]
    in_raw += [(50714, 11, 1, 0.0, True), (50717, 11, 1, 1.0, True)]
    floats = ((data.astype(np.float64) - 64) / (4095 - 64)).astype(np.float32)
    path = tmp_path / "subifd.dng"
    with tifffile.TiffWriter(path) as tw:
        tw.write(np.zeros((32, 48, 3), np.uint8), photometric="rgb", subifds=1, subfiletype=1,
                 extratags=ifd0)  # fmt: skip
        tw.write(floats, photometric=32803, subfiletype=0, tile=(64, 64), extratags=in_raw)
    raw = read_raw(path)
    assert raw.metadata["raw_type"] == "float" and raw.cfa_pattern == "RGGB"
    assert _mean_de00(develop(raw).image, develop(path0).image) < 0.02


def _variants_libraw_reads(base: tuple[Path, list[tuple], np.ndarray]) -> dict[str, Path]:
    """DNG variants LibRaw reads, to hold imageform's own DNG reader against."""
    import tifffile

    with tifffile.TiffFile(base[0]) as tf:
        data = tf.pages[0].asarray()
    table = np.round((np.arange(1024) / 1023.0) ** 2 * 4095).astype(np.uint16)
    offsets = np.array([[0, 8], [16, 24]])
    black4 = np.clip(data + np.tile(offsets, (data.shape[0] // 2, data.shape[1] // 2)), 0, 4095)
    return {
        "base": base[0],
        "black4": _variant(base, "own_black4", data=black4.astype(np.uint16),
                           drop={50713, 50714},
                           extra=[(50713, 3, 2, (2, 2), True),
                                  (50714, 4, 4, tuple(64 + offsets.ravel()), True)]),
        "two_matrices": _two_matrices(base, "own_two", (17, 21)),
        "calibrated": _variant(base, "own_cal", extra=[
            (50723, 10, 9, _rational(np.diag([1.1, 1.0, 0.9]) + 0.02), True),
            (50727, 5, 3, _rational([1.2, 1.0, 0.8]), True)]),
        "linear": _variant(base, "own_linear", data=base[2], photometric=34892,
                           drop={33421, 33422, 50710, 50711}),
        "mono": _monochrome(base, "own_mono", base[2][..., 1].copy()),
        "active_area_odd": _variant(base, "own_area", extra=[(50829, 4, 4, (3, 5, 251, 381),
                                                              True)]),
        "linearization": _variant(base, "own_lin_table",
                                  data=np.searchsorted(table, data).clip(0, 1023).astype(np.uint16),
                                  extra=[(50712, 3, 1024, tuple(table.tolist()), True)]),
        "orientation": _variant(base, "own_orient", extra=[(274, 3, 1, 6, True)]),
        "bggr": _variant(base, "own_bggr", drop={33422}, extra=[(33422, 1, 4, (2, 1, 1, 0),
                                                                 True)]),
    }  # fmt: skip


def test_own_dng_reader_agrees_with_libraw(
    base: tuple[Path, list[tuple], np.ndarray], monkeypatch: pytest.MonkeyPatch
) -> None:
    """imageform's DNG reader (tifffile: for DNGs LibRaw cannot decode, or without rawpy)
    gives LibRaw's RawImage on every variant LibRaw reads: the same samples, levels, pattern,
    gains, matrix and orientation, and a development within 0.05 ΔE00."""
    import sys

    from imageform.io.raw import _read_dng

    for name, path in _variants_libraw_reads(base).items():
        theirs = read_raw(path)
        ours = _read_dng(path, 10**9)
        assert ours is not None, name
        assert ours.metadata["reader"] == "tifffile"
        np.testing.assert_array_equal(ours.mosaic, theirs.mosaic, err_msg=name)
        np.testing.assert_allclose(ours.black_level, theirs.black_level, err_msg=name)
        assert ours.white_level == theirs.white_level, name
        assert ours.cfa_pattern == theirs.cfa_pattern and ours.monochrome == theirs.monochrome
        assert ours.orientation == theirs.orientation, name
        if theirs.white_balance is None:
            assert ours.white_balance is None, name
        else:
            np.testing.assert_allclose(ours.white_balance, theirs.white_balance, rtol=1e-4)
        if theirs.xyz_to_camera is None:
            assert ours.xyz_to_camera is None, name
        else:
            np.testing.assert_allclose(ours.xyz_to_camera, theirs.xyz_to_camera, atol=1e-6)
            np.testing.assert_allclose(ours.camera_to_srgb, theirs.camera_to_srgb, atol=1e-3)
        a, b = develop(ours).image, develop(theirs).image
        assert a.shape == b.shape, name
        if a.ndim == 3:
            assert _mean_de00(a, b) < 0.05, name
        else:
            assert np.abs(a - b).max() < 1e-5, name
    # and read_raw itself takes that reader when rawpy is not installed
    monkeypatch.setitem(sys.modules, "rawpy", None)
    assert read_raw(base[0]).metadata["reader"] == "tifffile"


@pytest.mark.parametrize("kind", ["cfa", "linear"])
def test_jpeg_xl_dng_that_libraw_cannot_read(
    base: tuple[Path, list[tuple], np.ndarray], kind: str
) -> None:
    """DNG 1.7's JPEG XL compression (52546), as recent phones write their raws: LibRaw (as
    rawpy builds it) refuses the file; read_raw reads it with tifffile and develops it as the
    uncompressed file."""
    import tifffile

    imagecodecs = pytest.importorskip("imagecodecs")
    if not imagecodecs.JPEGXL.available:  # pragma: no cover - depends on the wheel
        pytest.skip("imagecodecs without JPEG XL")
    path0, tags, lin = base
    with tifffile.TiffFile(path0) as tf:
        data = tf.pages[0].asarray()
    if kind == "linear":
        keep = [t for t in tags if t[0] not in (33421, 33422, 50710, 50711)]
        plain = _variant(base, "plain_linear", data=lin, photometric=34892,
                         drop={33421, 33422, 50710, 50711})  # fmt: skip
        pixels, photometric = lin, 34892
    else:
        keep, plain, pixels, photometric = tags, path0, data, 32803
    path = path0.with_name(f"jxl_{kind}.dng")
    tifffile.imwrite(path, pixels, photometric=photometric, extratags=keep, tile=(128, 128),
                     compression=52546, compressionargs={"lossless": True})  # fmt: skip
    with pytest.raises(rawpy.LibRawFileUnsupportedError):
        rawpy.imread(str(path)).raw_type  # noqa: B018 - rawpy opens the file lazily
    raw = read_raw(path)
    assert raw.metadata["reader"] == "tifffile" and raw.metadata["libraw"]
    np.testing.assert_array_equal(raw.mosaic, read_raw(plain).mosaic)
    assert _mean_de00(develop(raw).image, develop(plain).image) < 0.01


def test_own_dng_reader_edges(base: tuple[Path, list[tuple], np.ndarray], tmp_path: Path) -> None:
    """Black level deltas subtracted from each sample, as the DNG specification defines them
    (LibRaw adds their means to its black level instead: 0.28 ΔE00 apart here); automatic
    white balance of a linear raw as LibRaw's; a TIFF that is no DNG, or a DNG with only a
    preview, is not read (None: LibRaw's business)."""
    import tifffile

    from imageform.io.raw import _read_dng

    with tifffile.TiffFile(base[0]) as tf:
        data = tf.pages[0].asarray()
    dh, dv = np.linspace(0, 10, data.shape[1]), np.linspace(0, 6, data.shape[0])
    drift = np.clip(data + dh[None, :] + dv[:, None], 0, 4095).round().astype(np.uint16)
    delta = _variant(base, "own_delta", data=drift, extra=[
        (50715, 10, data.shape[1], _rational(dh), True),
        (50716, 10, data.shape[0], _rational(dv), True)])  # fmt: skip
    ours = _read_dng(delta, 10**9)
    assert ours is not None
    assert _mean_de00(develop(ours).image, develop(base[0]).image) < 0.01  # the drift undone
    assert _mean_de00(develop(ours).image, _libraw(delta)) < 0.5
    linear = _variant(base, "own_auto_lin", data=base[2], photometric=34892,
                      drop={33421, 33422, 50710, 50711})  # fmt: skip
    own_lin = _read_dng(linear, 10**9)
    assert own_lin is not None
    auto = develop(own_lin, white_balance="auto").image
    assert _mean_de00(auto, _libraw(linear, use_camera_wb=False, use_auto_wb=True)) < 0.05
    plain = tmp_path / "plain.tif"
    tifffile.imwrite(plain, data)
    assert _read_dng(plain, 10**9) is None
    preview = tmp_path / "preview.dng"
    tifffile.imwrite(preview, np.zeros((8, 8, 3), np.uint8), photometric="rgb", subfiletype=1,
                     extratags=[t for t in base[1] if t[0] == 50706])  # fmt: skip
    assert _read_dng(preview, 10**9) is None
    with pytest.raises(InvalidInputError, match="pixels"):
        _read_dng(base[0], 100)


def test_libraw_default_look(
    base: tuple[Path, list[tuple], np.ndarray], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """LibRaw's own defaults brighten (1 % of the brightest channel at white) and encode with
    BT.709's curve: auto_bright=True and transfer="rec709" give that rendering; an
    underexposed file (a third of the light) shows the difference (7 ΔE00 without)."""
    import json

    import tifffile

    from imageform.cli import main

    with tifffile.TiffFile(base[0]) as tf:
        data = tf.pages[0].asarray()
    dark = _variant(base, "dark", data=np.round(64 + (data - 64.0) * 0.35).astype(np.uint16))
    for transfer, gamma in (("srgb", (2.4, 12.92)), ("rec709", (2.222, 4.5))):
        ref = _libraw(dark, gamma=gamma, no_auto_bright=False)
        dev = develop(dark, transfer=transfer, auto_bright=True)
        assert 1.5 < dev.brightness < 1.8
        assert float(dev.linear_rgb.max()) == 1.0
        assert _mean_de00(dev.image, ref) < 0.1
        assert _mean_de00(develop(dark, transfer=transfer).image, ref) > 5.0
    mono = _monochrome(base, "mono_bright", base[2][..., 1].copy())
    ref = _libraw(mono, no_auto_bright=False)[..., 0]
    assert np.abs(develop(mono, auto_bright=True).image - ref).max() < 5e-4
    with pytest.raises(InvalidInputError, match="unknown transfer 'gamma'"):
        develop(dark, transfer="gamma")
    with pytest.raises(InvalidInputError, match="disagree"):
        develop(dark, linear=True, transfer="srgb")
    out = tmp_path / "look.png"
    assert main(["develop", str(dark), "-o", str(out), "--auto-bright", "--transfer", "rec709",
                 "--json"]) == 0  # fmt: skip
    doc = json.loads(capsys.readouterr().out)
    assert doc["transfer"] == "rec709" and doc["brightness"] > 1.5


def test_develop_transfer_choices_are_the_transfer_functions() -> None:
    """``imageform develop --transfer`` offers what ``develop(transfer=)`` takes: every
    transfer function but ``gamma`` (it needs an exponent)."""
    from typing import get_args

    from imageform.color import TRANSFER_FUNCTIONS
    from imageform.workflows.raw import _RawTransfer

    assert set(get_args(_RawTransfer)) == set(TRANSFER_FUNCTIONS) - {"gamma"}


def test_truncated_dng_is_refused_not_read_black(tmp_path: Path) -> None:
    """A DNG cut short inside its raw data (as metadata test suites prune them, e.g. Exiv2's
    iPhone 12 Pro ProRAW ``IMG_1361.dng``: 64 kB of a 29 MB file): LibRaw decodes its
    lossless-JPEG tiles as zeros without an error; read_raw says the file is truncated
    instead of giving a black image."""
    import tifffile

    imagecodecs = pytest.importorskip("imagecodecs")
    not_copied = (33421, 33422, 50713, 50714, 50717)  # the CFA's tags and the levels
    h, w, t = 64, 96, 32
    base = write_dng(tmp_path / "base.dng", np.full((h, w), 100, np.uint16), black_level=0,
                     white_level=65535, color_matrix=CM)  # fmt: skip
    with tifffile.TiffFile(base) as tf:
        tags = [(g.code, g.dtype, g.count, g.value, True) for g in tf.pages[0].tags
                if g.code >= 33421 and g.code not in not_copied]  # fmt: skip
    rgb = np.random.default_rng(0).integers(1000, 60000, (h, w, 3)).astype(np.uint16)
    tiles = [imagecodecs.ljpeg_encode(np.ascontiguousarray(rgb[r : r + t, c : c + t])
                                      .reshape(t, 3 * t), bitspersample=16)
             for r in range(0, h, t) for c in range(0, w, t)]  # fmt: skip
    path = tmp_path / "linear.dng"
    tifffile.imwrite(path, iter(tiles), shape=rgb.shape, dtype=np.uint16, photometric="rgb",
                     compression=7, tile=(t, t), extratags=tags)  # fmt: skip
    with tifffile.TiffFile(path, mode="r+") as tf:
        tf.pages[0].tags[262].overwrite(34892)  # LinearRaw, as a ProRAW file
        start = min(tf.pages[0].dataoffsets)
    assert np.any(read_raw(path).mosaic)  # whole, it reads
    cut = tmp_path / "cut.dng"
    cut.write_bytes(path.read_bytes()[:start])
    end = path.stat().st_size
    message = (
        rf"cannot read \S*cut\.dng: the file is truncated \(its raw image's data ends at byte "
        rf"{end}, the file has"
    )
    with pytest.raises(InvalidInputError, match=rf"{message} {start} bytes"):
        read_raw(cut)


def test_raw_read_as_zeros_from_under_a_bit_a_photosite_is_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Any raw (not only a DNG, whose strips say where its data ends): a file of fewer bits
    than photosites that LibRaw decodes to (nearly) all zeros has lost its data, as
    ExifTool's pruned Panasonic.rw2 (12 kB for 10 Mpx) is read; refused in one line."""
    import imageform.io.raw as raw_module

    test_truncated_dng_is_refused_not_read_black(tmp_path)
    monkeypatch.setattr(raw_module, "_page_data_end", lambda tf: 0)  # as for a non-DNG file
    cut = tmp_path / "cut.dng"
    message = rf"is truncated \({cut.stat().st_size} bytes for 6144 photosites, under one bit"
    with pytest.raises(InvalidInputError, match=message):
        read_raw(cut)


def test_uncompressed_dng_cut_in_transfer_is_refused_as_truncated(tmp_path: Path) -> None:
    """An uncompressed DNG cut inside its strips (an interrupted copy): LibRaw stops with an
    I/O error, and the one-line refusal says the file is truncated (where its data should
    end), not that it is no raw file."""
    h, w = 64, 96
    mosaic = np.random.default_rng(0).integers(0, 4096, (h, w)).astype(np.uint16)
    whole = write_dng(tmp_path / "whole.dng", mosaic, black_level=64, white_level=4095,
                      color_matrix=CM)  # fmt: skip
    assert read_raw(whole).mosaic.shape == (h, w)
    data = whole.read_bytes()
    cut = tmp_path / "cut.dng"
    cut.write_bytes(data[: len(data) // 2])
    before = cut.read_bytes()
    with pytest.raises(
        InvalidInputError, match=r"cut\.dng: the file is truncated \(its raw image.s data"
    ):
        read_raw(cut)
    assert cut.read_bytes() == before  # the input is untouched


def test_a_raw_cut_well_short_is_refused_before_libraw_speaks(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    """A DNG cut by an interrupted copy (hundreds of kB of its data missing) is refused from
    its header, before LibRaw is asked: LibRaw's own "Unexpected end of file" line no longer
    precedes the one-line refusal on stderr; the file is untouched."""
    pytest.importorskip("rawpy")
    mosaic = np.random.default_rng(0).integers(0, 4096, (512, 768)).astype(np.uint16)
    whole = write_dng(tmp_path / "whole.dng", mosaic, black_level=64, white_level=4095,
                      color_matrix=CM)  # fmt: skip
    cut = tmp_path / "cut.dng"
    cut.write_bytes(whole.read_bytes()[: whole.stat().st_size // 2])
    before = cut.read_bytes()
    capfd.readouterr()
    with pytest.raises(UnreadableFileError, match=r"cut\.dng: the file is truncated \(its raw"):
        read_raw(cut)
    assert capfd.readouterr().err == ""
    assert cut.read_bytes() == before


def test_white_level_below_most_samples(base: tuple[Path, list[tuple], np.ndarray]) -> None:
    """A white level most samples lie above (LibRaw's 255 for a Nikon Coolscan's 16-bit NEF)
    is the file's error, not the scene's: the samples' bit depth, with a note, instead of an
    all-white development; a few samples above white (clipped highlights) change nothing."""
    tags = [t for t in base[1] if t[0] != 50717] + [(50717, 3, 1, (255,), True)]
    path = _variant((base[0], tags, base[2]), "white_low")
    raw = read_raw(path)
    assert raw.white_level == 4095 and raw.metadata["white_level_libraw"] == 255
    dev = develop(raw)
    assert any("below most of its samples" in n for n in dev.notes)
    assert 0.05 < float(np.median(dev.image)) < 0.95
    ok = read_raw(base[0])
    assert ok.white_level == 4095 and "white_level_libraw" not in ok.metadata


def test_gpr_vc5_refused_naming_the_compression(
    base: tuple[Path, list[tuple], np.ndarray], tmp_path: Path
) -> None:
    """A DNG that says Compression 9 (GoPro's VC-5, which rawpy's LibRaw is built without and
    imageform decodes: tests/io/test_vc5.py) but whose tile is no VC-5 bitstream is refused in
    one line naming the compression and what is wrong, not as 'not a raw file'."""
    import tifffile

    data = bytearray(base[0].read_bytes())
    with tifffile.TiffFile(base[0]) as tf:
        entry = tf.pages[0].tags[259].offset  # the IFD entry: tag, type, count, value
    data[entry + 8 : entry + 10] = (9).to_bytes(2, "little")
    gpr = tmp_path / "hero.gpr"
    gpr.write_bytes(bytes(data))
    with pytest.raises(UnreadableFileError, match=r"VC-5.*Compression 9.*start marker") as err:
        read_raw(gpr)
    assert "\n" not in str(err.value)
