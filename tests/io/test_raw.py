"""Raw files in and out (docs/raw.md): the simulator's DNG read back by LibRaw bit for bit,
read_raw's fields, and imageform's development against LibRaw's own (rawpy.postprocess)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from imageform.errors import ImageformError, InvalidInputError
from imageform.io import Development, RawImage, develop, read_raw, write_dng

rawpy = pytest.importorskip("rawpy")

ROOT = Path(__file__).resolve().parents[2]

#: XYZ (D65) to camera RGB of a made-up camera (rows: R, G, B).
CM = np.array([[1.20, -0.30, -0.10], [-0.40, 1.30, 0.10], [-0.05, 0.20, 0.60]])


@pytest.fixture(scope="module")
def simulated(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, object, object]:
    """The default scene at 160 x 90 through the simulator, its raw stage as a DNG."""
    from imageform.simulate import default_scene, simulate, write_simulated_dng

    scene = default_scene().resized(160)
    res = simulate(scene, rng=0)
    path = write_simulated_dng(res, scene, tmp_path_factory.mktemp("dng") / "sim.dng")
    return path, res, scene


def _rgb_cam_libraw(cm: np.ndarray) -> np.ndarray:
    """LibRaw's rgb_cam from a DNG ColorMatrix (dcraw's cam_xyz_coeff): rows of
    cam_rgb = cm @ xyz_rgb normalised to sum 1, then inverted."""
    xyz_rgb = np.array(  # dcraw's sRGB (D65) matrix
        [
            [0.412453, 0.357580, 0.180423],
            [0.212671, 0.715160, 0.072169],
            [0.019334, 0.119193, 0.950227],
        ]
    )
    cam_rgb = cm @ xyz_rgb
    cam_rgb /= cam_rgb.sum(axis=1, keepdims=True)
    return np.linalg.inv(cam_rgb)


@pytest.mark.parametrize("pattern", ["RGGB", "BGGR", "GRBG", "GBRG"])
def test_libraw_reads_write_dng_bit_for_bit(tmp_path: Path, pattern: str) -> None:
    rng = np.random.default_rng(1)
    mosaic = rng.integers(0, 4096, size=(24, 36)).astype(np.uint16)
    path = write_dng(
        tmp_path / "a.dng",
        mosaic,
        cfa_pattern=pattern,
        black_level=64,
        white_level=4095,
        color_matrix=CM,
        as_shot_neutral=(0.5, 1.0, 0.8),
    )
    with rawpy.imread(str(path)) as r:
        np.testing.assert_array_equal(r.raw_image, mosaic)
        assert r.raw_image.dtype == np.uint16
        assert list(r.black_level_per_channel) == [64, 64, 64, 64]
        assert r.white_level == 4095
        desc = r.color_desc.decode()
        got = "".join(desc[i] for i in np.asarray(r.raw_pattern).ravel())
        assert got == pattern  # color_desc "RGBG": the second green is also "G"
        wb = np.asarray(r.camera_whitebalance)
        np.testing.assert_allclose(wb[:3] / wb[1], [2.0, 1.0, 1.25], rtol=1e-6)
        np.testing.assert_allclose(
            np.asarray(r.color_matrix)[:3, :3], _rgb_cam_libraw(CM), atol=2e-4
        )
    raw = read_raw(path)
    assert raw.cfa_pattern == pattern
    np.testing.assert_array_equal(raw.mosaic, mosaic)
    np.testing.assert_allclose(raw.xyz_to_camera, CM, atol=1e-6)


def test_simulated_dng_read_back_bit_for_bit(simulated: tuple[Path, object, object]) -> None:
    path, res, scene = simulated
    raw = np.asarray(res.stage("raw").image)  # type: ignore[attr-defined]
    sensor = scene.sensor  # type: ignore[attr-defined]
    with rawpy.imread(str(path)) as r:
        np.testing.assert_array_equal(r.raw_image, raw)
        assert set(r.black_level_per_channel) == {int(sensor.black_level)}
        assert r.white_level == sensor.max_dn
        wb = np.asarray(r.camera_whitebalance)[:3]
        gains = np.asarray(res.metrics["white_balance_gains"])  # type: ignore[attr-defined]
        np.testing.assert_allclose(wb / wb[1], gains / gains[1], rtol=1e-4)
        from imageform.simulate import simulated_color_matrix

        cm, _ = simulated_color_matrix(res)  # type: ignore[arg-type]
        np.testing.assert_allclose(
            np.asarray(r.color_matrix)[:3, :3], _rgb_cam_libraw(cm), atol=5e-4
        )


def test_read_raw_fields(simulated: tuple[Path, object, object]) -> None:
    path, res, scene = simulated
    raw = read_raw(path)
    assert isinstance(raw, RawImage)
    assert raw.cfa_pattern == scene.config.sensor.cfa  # type: ignore[attr-defined]
    assert raw.mosaic.dtype == np.uint16 and raw.mosaic.shape == (90, 160)
    np.testing.assert_array_equal(raw.black_level, np.full((2, 2), 64.0))
    assert raw.white_level == 4095.0
    gains = np.asarray(res.metrics["white_balance_gains"])  # type: ignore[attr-defined]
    np.testing.assert_allclose(raw.white_balance, gains / gains[1], rtol=1e-5)
    from imageform.simulate import simulated_color_matrix

    cm, _ = simulated_color_matrix(res)  # type: ignore[arg-type]
    np.testing.assert_allclose(raw.xyz_to_camera, cm, atol=1e-6)
    assert raw.calibration_illuminant == "D65"
    assert raw.metadata["camera_model"] == "imageform simulated camera"
    assert raw.camera_to_srgb.shape == (3, 3)


def _delta_e00_vs_libraw(path: Path, *, linear: bool) -> float:
    from imageform.color import decode, delta_e, linear_srgb_to_xyz, xyz_to_lab

    # LibRaw skips the DNG's opcodes (the simulator's FixVignetteRadial): so does this side
    dev = develop(read_raw(path, opcodes=False), demosaic="bilinear", linear=linear)
    with rawpy.imread(str(path)) as r:
        ref = r.postprocess(
            use_camera_wb=True,
            no_auto_bright=True,
            output_bps=16,
            gamma=(1, 1) if linear else (2.4, 12.92),
            demosaic_algorithm=rawpy.DemosaicAlgorithm.LINEAR,
            adjust_maximum_thr=0.0,
            user_flip=0,
        )
    ours = dev.image
    ref = ref / 65535.0
    if not linear:
        ours, ref = decode(ours, "srgb"), decode(ref, "srgb")
    lab1 = xyz_to_lab(linear_srgb_to_xyz(ours))
    lab2 = xyz_to_lab(linear_srgb_to_xyz(ref))
    return float(np.mean(delta_e(lab1, lab2)))


@pytest.mark.parametrize("linear", [True, False], ids=["linear", "srgb"])
def test_develop_matches_libraw(simulated: tuple[Path, object, object], linear: bool) -> None:
    """Same white balance, bilinear (LibRaw LINEAR), no auto-brightening: measured mean
    CIEDE2000 0.02 (docs/raw.md); asserted < 1."""
    path, _, _ = simulated
    de = _delta_e00_vs_libraw(path, linear=linear)
    assert de < 1.0, de


def test_develop_stages(simulated: tuple[Path, object, object]) -> None:
    path, _, _ = simulated
    raw = read_raw(path, opcodes=False)  # the stages before any opcode
    dev = develop(raw, demosaic="menon")
    assert isinstance(dev, Development)
    h, w = raw.mosaic.shape
    # 1. linearise
    # float32 stages (the development's precision): within 1e-6 relative
    assert dev.linear.dtype == dev.image.dtype == np.float32
    np.testing.assert_allclose(dev.linear, (raw.mosaic - 64.0) / (4095.0 - 64.0), rtol=1e-6)
    # 2. white balance: the gains, smallest 1, per photosite colour, clipped
    assert dev.gains.min() == pytest.approx(1.0)
    g = raw.white_balance / raw.white_balance.min()
    np.testing.assert_allclose(dev.gains, g)
    r0 = "RGB".index(raw.cfa_pattern[0])
    np.testing.assert_allclose(
        dev.white_balanced[0::2, 0::2], np.clip(dev.linear[0::2, 0::2] * g[r0], 0, 1), rtol=1e-6
    )
    # 3. demosaic keeps the measured samples
    assert dev.camera_rgb.shape == (h, w, 3)
    np.testing.assert_allclose(
        dev.camera_rgb[0::2, 0::2, r0], dev.white_balanced[0::2, 0::2], rtol=1e-6
    )
    # 4. white-balanced white maps to the illuminant's white (D65, Y = 1)
    from imageform.color import linear_srgb_to_xyz, whitepoint_xy, xy_to_xyz_white

    np.testing.assert_allclose(
        dev.camera_to_xyz @ np.ones(3), xy_to_xyz_white(whitepoint_xy("D65")), atol=1e-12
    )
    np.testing.assert_allclose(dev.adaptation, np.eye(3))
    np.testing.assert_allclose(dev.xyz, dev.camera_rgb @ dev.camera_to_xyz.T, rtol=1e-5, atol=1e-7)
    # 5-6. output
    np.testing.assert_allclose(
        linear_srgb_to_xyz(dev.linear_rgb)[dev.linear_rgb.max(-1) < 0.99].mean(0),
        dev.xyz[dev.linear_rgb.max(-1) < 0.99].mean(0),
        atol=0.02,
    )
    assert dev.image.min() >= 0 and dev.image.max() <= 1 and dev.transfer == "srgb"
    assert dev.to_integer(8).dtype == np.uint8 and dev.to_integer(16).dtype == np.uint16


def test_develop_adapts_to_a_d50_space(simulated: tuple[Path, object, object]) -> None:
    """ProPhoto RGB has a D50 white: Bradford from D65, so white stays white."""
    from imageform.color import chromatic_adaptation_matrix, whitepoint_xy, xy_to_xyz_white

    path, _, _ = simulated
    dev = develop(path, space="prophoto", linear=True)
    d65 = xy_to_xyz_white(whitepoint_xy("D65"))
    d50 = xy_to_xyz_white((0.3457, 0.3585))
    np.testing.assert_allclose(dev.adaptation, chromatic_adaptation_matrix(d65, d50, "bradford"))
    from imageform.color import xyz_to_linear_rgb

    white = xyz_to_linear_rgb(dev.adaptation @ dev.camera_to_xyz @ np.ones(3), "prophoto")
    np.testing.assert_allclose(white, np.ones(3), atol=2e-3)


def test_not_a_raw_file(tmp_path: Path) -> None:
    bad = tmp_path / "notes.dng"
    bad.write_text("hello")
    with pytest.raises(InvalidInputError, match="not a raw file") as e:
        read_raw(bad)
    assert "\n" not in str(e.value) and "notes.dng" in str(e.value)
    with pytest.raises(InvalidInputError, match="does not exist"):
        read_raw(tmp_path / "missing.dng")


def test_missing_extra(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "rawpy", None)
    f = tmp_path / "x.dng"
    f.write_bytes(b"II*\x00")
    with pytest.raises(ImageformError, match=r'pip install "imageform\[raw\]"') as e:
        read_raw(f)
    assert "\n" not in str(e.value)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"mosaic": np.zeros((3, 4), np.uint16)}, "H and W even"),
        ({"mosaic": np.full((4, 4), -1.0)}, r"\[0, 65535\]"),
        ({"color_matrix": np.zeros((3, 3))}, "invertible"),
        ({"as_shot_neutral": (1, 0, 1)}, "positive"),
        ({"calibration_illuminant": "F2"}, "calibration_illuminant"),
        ({"cfa_pattern": "RGBG"}, "RGBG"),
        ({"black_level": 5000}, "black_level"),
        ({"baseline_exposure_ev": float("nan")}, "baseline_exposure_ev"),
        ({"baseline_exposure_ev": 40}, "baseline_exposure_ev"),
        ({"baseline_exposure_ev": True}, "baseline_exposure_ev"),
        ({"fix_vignette_radial": (1, 2, 3)}, "fix_vignette_radial"),
        ({"fix_vignette_radial": (0, 0, 0, 0, 0, 1.5, 0.5)}, "fix_vignette_radial"),
        ({"fix_vignette_radial": (np.nan, 0, 0, 0, 0, 0.5, 0.5)}, "fix_vignette_radial"),
    ],
)
def test_write_dng_bad_inputs(tmp_path: Path, kwargs: dict[str, object], match: str) -> None:
    args: dict[str, object] = {
        "mosaic": np.zeros((4, 4), np.uint16),
        "color_matrix": CM,
        "white_level": 4095,
    } | kwargs
    mosaic = args.pop("mosaic")
    with pytest.raises(InvalidInputError, match=match) as e:
        write_dng(tmp_path / "x.dng", mosaic, **args)  # type: ignore[arg-type]
    assert "\n" not in str(e.value)


def test_develop_bad_inputs(simulated: tuple[Path, object, object]) -> None:
    path, _, _ = simulated
    raw = read_raw(path)
    with pytest.raises(InvalidInputError, match="demosaic"):
        develop(raw, demosaic="magic")
    with pytest.raises(InvalidInputError, match="space"):
        develop(raw, space="cmyk")
    with pytest.raises(InvalidInputError, match="white_balance"):
        develop(raw, white_balance=(1, -1, 1))
    with pytest.raises(InvalidInputError, match="RawImage"):
        develop(np.zeros((4, 4)))  # type: ignore[arg-type]


def test_cli_simulate_raw_then_develop(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``imageform simulate --raw`` writes the DNG; ``imageform develop`` develops it."""
    from imageform.cli import main
    from imageform.io import read_image

    pytest.importorskip("matplotlib")
    text = (ROOT / "examples" / "scenes" / "default.toml").read_text()
    text = text.replace("width = 1280", "width = 320").replace("height = 720", "height = 180")
    text = text.replace("supersampling = 2", "supersampling = 1")
    scene = tmp_path / "small.toml"
    scene.write_text(text)
    dng, png = tmp_path / "sim.dng", tmp_path / "dev.png"
    args = ["simulate", "--scene", str(scene), "-o", str(tmp_path / "sim"), "--raw", str(dng)]
    assert main(args) == 0
    assert "raw DNG" in capsys.readouterr().out
    with rawpy.imread(str(dng)) as r:
        assert r.raw_image.shape == (180, 320)
    assert main(["develop", str(dng), "-o", str(png)]) == 0
    img = read_image(png)
    assert img.shape == (180, 320, 3)
    # the 16-bit PNG is the developer's own rounding of its float image (the fused pass)
    cv2 = pytest.importorskip("cv2")
    from imageform.io import develop, read_raw

    dev = develop(read_raw(dng))
    written = cv2.imread(str(png), cv2.IMREAD_UNCHANGED)[..., ::-1]
    assert written.dtype == np.uint16
    expect = np.floor(np.clip(dev.image, 0, 1) * 65535 + 0.5).astype(np.uint16)
    np.testing.assert_array_equal(written, expect)
    assert main(["develop", str(dng), "-o", str(tmp_path / "dev.tif")]) == 0
    np.testing.assert_allclose(read_image(tmp_path / "dev.tif"), dev.image, atol=1e-7)
    bad = tmp_path / "x.txt"
    bad.write_text("no")
    capsys.readouterr()  # the developments' notes (the DNG's FixVignetteRadial applied)
    assert main(["develop", str(bad), "-o", str(tmp_path / "y.png")]) == 1
    err = capsys.readouterr().err
    assert "not a raw file" in err and err.count("\n") == 1
    both = ["develop", str(dng), "-o", str(tmp_path / "b.png"), "--auto-bright"]
    assert main([*both, "--baseline-exposure"]) == 2
    err = capsys.readouterr().err
    assert "give one of them" in err and err.count("\n") == 1
    assert not (tmp_path / "b.png").exists()
    assert main(["simulate", "--raw", str(tmp_path / "x.tif"), "-o", str(tmp_path / "z")]) == 2
    assert "expected --raw as a .dng file" in capsys.readouterr().err


def test_write_dng_baseline_exposure_and_vignette_round_trip(tmp_path: Path) -> None:
    """BaselineExposure (SRATIONAL, tag 50730) and an OpcodeList3 FixVignetteRadial (tag
    51022) come back as written: tifffile reads the tag, read_raw parses both, develop applies
    the opcode's gain on demosaiced camera RGB and 2^EV with baseline_exposure=True."""
    import tifffile

    from imageform.io._dng_opcodes import FixVignetteRadial

    mosaic = np.full((32, 48), 1000, np.uint16)
    vig = (0.5, 0.25, 0.0, 0.0, 0.0, 0.5, 0.5)
    path = write_dng(
        tmp_path / "v.dng",
        mosaic,
        color_matrix=CM,
        white_level=4095,
        baseline_exposure_ev=-0.75,
        fix_vignette_radial=vig,
    )
    with tifffile.TiffFile(path) as tf:
        num, den = tf.pages[0].tags[50730].value
        assert num / den == -0.75
    raw = read_raw(path)
    assert raw.metadata["baseline_exposure_ev"] == -0.75
    (op,) = raw.metadata["opcodes_stage3"]
    assert op == FixVignetteRadial((0.5, 0.25, 0.0, 0.0, 0.0), (0.5, 0.5))
    plain = develop(read_raw(path, opcodes=False), linear=True)
    shaded = develop(raw, linear=True)
    # the farthest corner has r = 1 less half a pixel: the gain there is nearly 1.75
    for y, x in ((0, 0), (16, 24), (5, 7)):
        r2 = ((y + 0.5 - 16) ** 2 + (x + 0.5 - 24) ** 2) / (16**2 + 24**2)
        ratio = shaded.image[y, x] / plain.image[y, x]
        np.testing.assert_allclose(ratio, 1 + 0.5 * r2 + 0.25 * r2**2, rtol=1e-5)
    bright = develop(raw, linear=True, baseline_exposure=True)
    assert bright.brightness == pytest.approx(2**-0.75)
    np.testing.assert_allclose(bright.image, shaded.image * 2**-0.75, rtol=1e-5, atol=1e-7)
    # no tag: a note and no brightening; both brightenings at once are refused
    none = write_dng(tmp_path / "n.dng", mosaic, color_matrix=CM, white_level=4095)
    dev = develop(none, baseline_exposure=True)
    assert dev.brightness == 1.0 and any("BaselineExposure" in n for n in dev.notes)
    with pytest.raises(InvalidInputError, match="give one"):
        develop(raw, auto_bright=True, baseline_exposure=True)


def test_simulated_vignette_opcode_is_the_cos4_law() -> None:
    """Without distortion the simulator's correction 1/cos^4 = (1 + rho^2)^2 is DNG's
    polynomial exactly: k0 = 2a, k1 = a^2 with a = (R/f)^2 (R the distance to the farthest
    corner, pixel centres at half-integers); no vignetting, no opcode."""
    from dataclasses import replace

    from imageform.simulate import default_scene, simulated_vignette_opcode

    scene = default_scene().resized(160)
    scene = replace(scene, camera=replace(scene.camera, distortion=None))
    p = simulated_vignette_opcode(scene, (90, 160))
    assert p is not None
    K = scene.camera.K
    cx, cy = (K[0, 2] + 0.5) / 160, (K[1, 2] + 0.5) / 90
    np.testing.assert_allclose(p[5:], [cx, cy])
    R = np.hypot(max(cy * 90, 90 - cy * 90), max(cx * 160, 160 - cx * 160))
    a = (R / K[0, 0]) ** 2
    np.testing.assert_allclose(p[:5], [2 * a, a * a, 0, 0, 0], atol=1e-7)


def test_simulated_dng_develops_as_the_simulation(simulated: tuple[Path, object, object]) -> None:
    """With the DNG's FixVignetteRadial and BaselineExposure applied, the developed linear
    RGB is the simulator's colour-corrected image: medians over mid-tone pixels within 3 %
    (measured 0.5-3 %, the demosaicing and the highlight clip apart); without the
    brightening, 2^-EV darker."""
    from imageform.simulate import simulated_baseline_exposure

    path, res, _ = simulated
    raw = read_raw(path)
    ev = simulated_baseline_exposure(res)  # type: ignore[arg-type]
    assert raw.metadata["baseline_exposure_ev"] == pytest.approx(ev, abs=1e-6)
    assert 0.2 < ev < 1.0
    h, w = raw.mosaic.shape
    cc = np.asarray(res.stage("color_corrected").image, np.float64)[:h, :w]  # type: ignore[attr-defined]
    dev = develop(raw, demosaic="menon", linear=True, baseline_exposure=True)
    im = np.asarray(dev.image, np.float64)
    ok = (cc.min(-1) > 0.03) & (cc.max(-1) < 0.9)
    assert ok.sum() > 1000
    ok &= im.min(-1) > 0.01
    np.testing.assert_allclose(np.median(cc[ok] / im[ok], axis=0), 1.0, atol=0.03)
    dark = develop(raw, demosaic="menon", linear=True)
    ratio = np.median(im[ok] / np.maximum(np.asarray(dark.image, np.float64)[ok], 1e-6))
    assert ratio == pytest.approx(2**ev, rel=1e-3)
    # the highlights rolled off: the same under the knee (0.8), nothing clipped the sensor kept
    rolled = develop(raw, demosaic="menon", linear=True, baseline_exposure=True,
                     highlight_rolloff=True).image  # fmt: skip
    low = im < 0.79
    np.testing.assert_allclose(rolled[low], im[low], atol=3e-5)
    assert np.mean(rolled >= 1.0) <= np.mean(im >= 1.0)
    assert np.all(rolled[~low] >= 0.79)


def test_nearly_black_frame_is_noted(tmp_path: Path) -> None:
    """A dark frame (a Pixel 7 DNG of pigallery2's test data: its brightest photosite 0.84 %
    of the way from black to white) develops black, as LibRaw's does, with a note saying
    so and how to brighten it; a frame that reaches 2 % has no such note."""
    rng = np.random.default_rng(3)
    noise = rng.normal(1024, 8, (32, 48)).clip(973, 1153).astype(np.uint16)
    noise[7, 9] = 1153  # the Pixel 7 frame's brightest photosite
    dark = write_dng(tmp_path / "dark.dng", noise, black_level=1024, white_level=16368,
                     color_matrix=np.eye(3))  # fmt: skip
    dev = develop(read_raw(dark))
    assert float(np.median(dev.image)) < 0.01
    note = [n for n in dev.notes if "nearly black" in n]
    assert len(note) == 1 and "0.84 %" in note[0] and "--auto-bright" in note[0]
    assert not [n for n in develop(read_raw(dark), auto_bright=True).notes if "nearly" in n]
    lit = noise.copy()
    lit[5, 5] = 1024 + 0.021 * (16368 - 1024)
    ok = write_dng(tmp_path / "lit.dng", lit, black_level=1024, white_level=16368,
                   color_matrix=np.eye(3))  # fmt: skip
    assert not [n for n in develop(read_raw(ok)).notes if "nearly black" in n]
