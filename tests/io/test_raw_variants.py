"""Raw files as LibRaw reads them: DNG variants written from a real photograph (issue 26).

A mosaic sampled from a Kodak photograph (or, without the reference data, the simulator's
default scene) is written as DNG, then varied as cameras and converters write them: an
orientation tag (a portrait shot), per-photosite black levels, a linear (already demosaiced,
LinearRaw) DNG, no colour matrix at all, an X-Trans CFA, a black frame. Each develops to
within a mean CIEDE2000 of 1 of LibRaw's own rendering at matched settings, with the same
orientation and size, or is refused in one line.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imageform.errors import InvalidInputError
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


def test_xtrans_is_refused_naming_the_pattern(base: tuple[Path, list[tuple], np.ndarray]) -> None:
    xt = [[1, 1, 0, 1, 1, 2], [1, 1, 2, 1, 1, 0], [2, 0, 1, 0, 2, 1]]
    xt += [[1, 1, 2, 1, 1, 0], [1, 1, 0, 1, 1, 2], [0, 2, 1, 2, 0, 1]]
    path = _variant(
        base,
        "xtrans",
        drop={33421, 33422},
        extra=[(33421, 3, 2, (6, 6), True), (33422, 1, 36, tuple(np.ravel(xt).tolist()), True)],
    )
    with pytest.raises(InvalidInputError, match=r"6x6 X-Trans CFA \(first row GGRGGB\)") as e:
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
