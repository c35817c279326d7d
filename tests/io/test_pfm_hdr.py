"""PFM (read and written) and Radiance HDR (read): float32, cross-checked against OpenCV.

PFM: files written here by OpenCV (``cv2.imwrite`` of ``.pfm``), by hand (big-endian, a
scale other than 1) and by imageform, read back by imageform, OpenCV and Pillow (grey
``Pf``). The format (pauldebevec.com/Research/HDR/PFM): rows bottom to top, the scale's sign
the byte order; its magnitude is left to the reader: imageform and Pillow keep the stored
numbers, OpenCV divides by it.

Radiance HDR: files written by OpenCV (new-style RLE scanlines), and by hand (flat pixels,
Radiance's old runs, the 8 scanline orders); the values against Radiance's ``colr_color``,
``(m + 0.5) * 2**(E - 136)``, and OpenCV's reader, which leaves out the ``+ 0.5``: the two
differ by exactly ``0.5 * 2**(E - 136)``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from imageform.cli import main
from imageform.errors import InvalidInputError
from imageform.io import image_color_space, image_info, read_image, write_image

cv2 = pytest.importorskip("cv2")
RNG = np.random.default_rng(20261130)
HDR_RGB = (RNG.random((9, 13, 3)) * np.array([0.01, 1.0, 40.0])).astype(np.float32)


# ---------------------------------------------------------------- PFM


@pytest.mark.parametrize("channels", [1, 3])
def test_pfm_written_by_opencv_reads_as_opencv_and_pillow_read_it(
    tmp_path: Path, channels: int
) -> None:
    a = (RNG.standard_normal((7, 11, channels)) * 50).astype(np.float32)
    a[0, 0, 0] = np.inf  # Middlebury's unknown disparity
    p = tmp_path / "cv.pfm"
    assert cv2.imwrite(str(p), a[..., ::-1].copy() if channels == 3 else a[..., 0])
    got = read_image(p)
    assert got.dtype == np.float32 and got.shape == a.shape
    np.testing.assert_array_equal(got, a)
    assert image_info(p) == (11, 7, channels, "float32", "pfm")
    assert image_color_space(p).name is None
    if channels == 1:
        from PIL import Image

        with Image.open(p) as im:
            np.testing.assert_array_equal(np.asarray(im), a[..., 0])


@pytest.mark.parametrize(("channels", "order", "scale"), [(3, ">", 1.0), (1, ">", 2.5),
                                                          (1, "<", -4.0)])  # fmt: skip
def test_pfm_byte_order_follows_the_sign_and_rows_run_bottom_up(
    tmp_path: Path, channels: int, order: str, scale: float
) -> None:
    a = RNG.random((4, 6, channels)).astype(np.float32) * 9
    kind = b"PF" if channels == 3 else b"Pf"
    raster = np.ascontiguousarray(a[::-1], dtype=f"{order}f4").tobytes()
    p = tmp_path / "hand.pfm"
    p.write_bytes(kind + b"\n6 4\n%r\n" % scale + raster)
    np.testing.assert_array_equal(read_image(p), a)  # the stored numbers, whatever |scale|
    cv = cv2.imread(str(p), cv2.IMREAD_UNCHANGED).reshape(a.shape[0], a.shape[1], channels)
    cv = cv[..., ::-1] if channels == 3 else cv
    np.testing.assert_allclose(cv * abs(scale), a, rtol=1e-6)  # OpenCV divides by |scale|


@pytest.mark.parametrize("channels", [1, 3])
def test_pfm_written_by_imageform_reads_back_in_opencv(tmp_path: Path, channels: int) -> None:
    a = (RNG.random((5, 8, channels)) * 3 - 1).astype(np.float32)  # HDR: outside [0, 1]
    p = tmp_path / "out.pfm"
    assert write_image(p, a) == (None, 0)
    assert p.read_bytes()[:2] == (b"PF" if channels == 3 else b"Pf")
    np.testing.assert_array_equal(read_image(p), a)
    cv = cv2.imread(str(p), cv2.IMREAD_UNCHANGED)
    np.testing.assert_array_equal(cv[..., ::-1] if channels == 3 else cv[..., None], a)
    u8 = np.array([[[0, 51, 255]]], np.uint8)  # integers as the encoded values they mean
    write_image(p, u8)
    np.testing.assert_allclose(read_image(p), [[[0.0, 0.2, 1.0]]], rtol=1e-7)


def test_pfm_writer_refuses_what_it_cannot_hold_and_leaves_nothing(tmp_path: Path) -> None:
    p = tmp_path / "x.pfm"
    for kwargs, image, words in (
        ({}, np.zeros((2, 2, 4), np.float32), "PFM holds grey or RGB images"),
        ({"bit_depth": 16}, np.zeros((2, 2), np.float32), "PFM stores float32 samples"),
        ({"color_space": "display_p3"}, np.zeros((2, 2, 3)), "PFM has no colour profile"),
    ):
        with pytest.raises(InvalidInputError, match=words):
            write_image(p, image, **kwargs)
        assert not p.exists() and not list(tmp_path.iterdir())


@pytest.mark.parametrize(
    ("data", "words"),
    [
        (b"PF\n4 2\n-1.0\n" + b"\0" * 40, "the file is truncated (52 bytes, its header promi"),
        (b"PF\n4 2\n0\n" + b"\0" * 96, "a PFM scale of '0'"),
        (b"PF\nfour 2\n-1\n" + b"\0" * 96, "corrupt PFM header"),
        (b"Pf\n0 2\n-1\n", "holds no image"),
    ],
)
def test_a_bad_pfm_is_one_line_in_python_and_on_the_command_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], data: bytes, words: str
) -> None:
    p = tmp_path / "bad.pfm"
    p.write_bytes(data)
    with pytest.raises(InvalidInputError, match=words.replace("(", r"\(")) as err:
        read_image(p)
    assert "\n" not in str(err.value)
    out = tmp_path / "o.tif"
    assert main(["convert", str(p), "-o", str(out), "--to", "xyz"]) == 1
    text = capsys.readouterr().err
    assert text.count("\n") == 1 and "Traceback" not in text and not out.exists()
    assert main(["info", str(p)]) == 1


def test_cli_convert_writes_and_reads_pfm(tmp_path: Path) -> None:
    src = tmp_path / "in.pfm"
    write_image(src, HDR_RGB / 40)
    out = tmp_path / "out.pfm"
    assert main(["convert", str(src), "-o", str(out), "--from", "linear_srgb", "--to",
                 "linear_rec2020"]) == 0  # fmt: skip
    from imageform.color import convert

    want = convert(HDR_RGB / 40, "linear_srgb", "linear_rec2020")
    np.testing.assert_allclose(read_image(out), want, rtol=1e-5, atol=1e-7)


# ---------------------------------------------------------------- Radiance HDR


def _rgbe(rgb: np.ndarray) -> np.ndarray:
    """Ward's float -> RGBE (Graphics Gems II): the shared exponent of the largest value."""
    top = rgb.max(axis=-1)
    mant, exp = np.frexp(top)
    scale = np.where(top > 1e-32, mant * 256.0 / np.where(top > 0, top, 1), 0.0)
    out = np.zeros((*rgb.shape[:-1], 4), np.uint8)
    out[..., :3] = np.floor(rgb * scale[..., None])
    out[..., 3] = np.where(top > 1e-32, exp + 128, 0)
    return out


def _radiance(rgbe: np.ndarray) -> np.ndarray:
    e = rgbe[..., 3].astype(np.int32)
    f = np.where(e > 0, np.ldexp(1.0, e - 136), 0.0)
    return ((rgbe[..., :3] + 0.5) * f[..., None]).astype(np.float32)


def test_hdr_written_by_opencv_is_radiance_s_values_and_half_a_step_from_opencv(
    tmp_path: Path,
) -> None:
    p = tmp_path / "cv.hdr"
    big = np.tile(HDR_RGB, (1, 4, 1))  # 52 px wide: OpenCV writes new-style RLE scanlines
    assert cv2.imwrite(str(p), big[..., ::-1].copy())
    got = read_image(p)
    assert got.dtype == np.float32 and got.shape == big.shape
    assert image_info(p) == (52, 9, 3, "float32", "hdr")
    cv = cv2.imread(str(p), cv2.IMREAD_UNCHANGED)[..., ::-1]
    e = _rgbe(big)[..., 3].astype(np.int32)  # the exponents OpenCV stored
    half = np.where(e > 0, np.ldexp(0.5, e - 136), 0.0)[..., None]
    np.testing.assert_allclose(got - cv, np.broadcast_to(half, got.shape), rtol=1e-5, atol=0)
    step = np.where(e > 0, np.ldexp(1.0, e - 136), 0.0)[..., None]  # RGBE's precision
    assert np.all(np.abs(got - big) <= step)
    assert image_color_space(p)[:2] == ("linear_srgb", "radiance")


@pytest.mark.parametrize(
    ("resolution", "turn"),
    [
        (b"-Y 3 +X 5", lambda a: a),
        (b"+Y 3 +X 5", lambda a: a[::-1]),
        (b"-Y 3 -X 5", lambda a: a[:, ::-1]),
        (b"+X 5 -Y 3", lambda a: np.swapaxes(a, 0, 1)),
    ],
)
def test_hdr_flat_and_old_runs_in_any_scanline_order(
    tmp_path: Path, resolution: bytes, turn: object
) -> None:
    rgbe = RNG.integers(1, 255, (3, 5, 4)).astype(np.uint8)
    rgbe[1, 2:] = rgbe[1, 1]  # a run of 3 in Radiance's old form: (1, 1, 1, 3)
    stored = turn(rgbe)  # type: ignore[operator]
    body = np.ascontiguousarray(stored).tobytes()  # flat: 4 bytes a pixel, scanline order
    p = tmp_path / "flat.hdr"
    head = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=2.0\n\n" + resolution + b"\n"
    p.write_bytes(head + bytes(body))
    np.testing.assert_array_equal(read_image(p), _radiance(rgbe))
    if resolution.startswith(b"-Y 3 +X"):  # the old run form, in the usual order
        runs = b"".join(bytes(px) for px in rgbe[0]) + bytes(rgbe[1, 0]) + bytes(rgbe[1, 1])
        runs += b"\1\1\1\3" + b"".join(bytes(px) for px in rgbe[2])
        p.write_bytes(head + runs)
        np.testing.assert_array_equal(read_image(p), _radiance(rgbe))


@pytest.mark.parametrize(
    ("cut", "words"),
    [
        (lambda d: d[: len(d) - 30], "the file is truncated (scanline"),
        (lambda d: d.replace(b"-Y 9 +X 52", b"-Y 9 +Z 52"), "corrupt Radiance resolution line"),
        (lambda d: d.replace(b"32-bit_rle_rgbe", b"32-bit_rle_xyze"), "FORMAT=32-bit_rle_xyze"),
        (lambda d: d.replace(b"\n\n", b"\n"), "corrupt Radiance"),
        (lambda d: d.replace(b"-Y 9 +X 52", b"-Y 9 +X 51"), "corrupt scanline 0"),
    ],
)
def test_a_bad_hdr_is_one_line_and_nothing_is_written(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], cut: object, words: str
) -> None:
    good = tmp_path / "good.hdr"
    cv2.imwrite(str(good), np.tile(HDR_RGB, (1, 4, 1))[..., ::-1].copy())
    p = tmp_path / "bad.hdr"
    p.write_bytes(cut(good.read_bytes()))  # type: ignore[operator]
    with pytest.raises(InvalidInputError, match=words.replace("(", r"\(")) as err:
        read_image(p)
    assert "\n" not in str(err.value)
    out = tmp_path / "o.pfm"
    assert main(["convert", str(p), "-o", str(out), "--from", "linear_srgb", "--to", "xyz"]) == 1
    text = capsys.readouterr().err
    assert text.count("\n") == 1 and "Traceback" not in text and not out.exists()


def test_hdr_is_read_not_written(tmp_path: Path) -> None:
    with pytest.raises(InvalidInputError, match="reads Radiance HDR but does not write it"):
        write_image(tmp_path / "a.hdr", HDR_RGB)


def test_hdr_declares_linear_srgb_unless_its_primaries_differ(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rgbe = np.full((2, 3, 4), 128, np.uint8)
    p = tmp_path / "p.hdr"
    head = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n%s\n-Y 2 +X 3\n"
    p.write_bytes(head % b"" + rgbe.tobytes())
    assert image_color_space(p)[:2] == ("linear_srgb", "radiance")
    out = tmp_path / "o.png"
    assert main(["convert", str(p), "-o", str(out)]) == 0  # --from auto: linear -> sRGB codes
    assert "declares linear_srgb in its Radiance HDR header" in capsys.readouterr().err
    np.testing.assert_array_equal(read_image(out), np.full((2, 3, 3), 188, np.uint8))  # 0.50196
    p.write_bytes(head % b"PRIMARIES=0.708 0.292 0.170 0.797 0.131 0.046 0.3127 0.329\n"
                  + rgbe.tobytes())  # fmt: skip
    declared = image_color_space(p)
    assert declared.name is None and "PRIMARIES=0.708" in declared.description
    for stated in (
        b"0.64 0.33 0.30 0.60 0.15 0.06 0.3127 0.329",  # Rec. 709 / sRGB
        b"0.6400 0.3300 0.2900 0.6000 0.1500 0.0600 0.3333 0.3333",
    ):  # Radiance's
        p.write_bytes(head % (b"PRIMARIES= " + stated + b"\n") + rgbe.tobytes())  # fmt: skip
        assert image_color_space(p).name == "linear_srgb"


def test_info_of_a_truncated_hdr_says_where_its_scanlines_end_as_read_does(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``imageform info`` read the header alone and passed a file cut short: it now steps over
    the scanlines (new-style runs, flat pixels, old runs) and names the one it ends in, the
    scanline ``read_image`` names, at every cut."""
    rle = tmp_path / "rle.hdr"
    cv2.imwrite(str(rle), np.tile(HDR_RGB, (1, 4, 1))[..., ::-1].copy())
    rgbe = RNG.integers(1, 255, (3, 5, 4)).astype(np.uint8)
    rgbe[1, 2:] = rgbe[1, 1]
    runs = b"".join(bytes(px) for px in rgbe[0]) + bytes(rgbe[1, 0]) + bytes(rgbe[1, 1])
    runs += b"\1\1\1\3" + b"".join(bytes(px) for px in rgbe[2])
    old = tmp_path / "old.hdr"
    old.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 3 +X 5\n" + runs)
    assert image_info(old) == (5, 3, 3, "float32", "hdr")
    cut = tmp_path / "cut.hdr"
    for good in (rle, old):
        data = good.read_bytes()
        start = data.index(b"\n", data.index(b"\n\n") + 2) + 1  # the first scanline
        for n in range(start, len(data), 7):
            cut.write_bytes(data[:n])
            with pytest.raises(InvalidInputError) as said:
                image_info(cut)
            with pytest.raises(InvalidInputError) as read:
                read_image(cut)
            assert "the file is truncated (scanline" in str(said.value)
            assert str(said.value) == str(read.value)
    data = rle.read_bytes()
    cut.write_bytes(data[: data.index(b"\n", data.index(b"\n\n") + 2) + 12])
    assert main(["info", str(cut)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "truncated (scanline 0 of 9)" in err


def test_info_and_read_refuse_a_corrupt_run_alike(tmp_path: Path) -> None:
    """One scanline walker serves ``read_image`` and ``image_info``: a run past the line's end
    or a zero-length run is the same one line from both (``info`` once stepped over them)."""
    good = tmp_path / "good.hdr"
    cv2.imwrite(str(good), np.tile(HDR_RGB, (1, 4, 1))[..., ::-1].copy())
    data = good.read_bytes()
    first = data.index(b"\n", data.index(b"\n\n") + 2) + 1 + 4  # the first run of scanline 0
    for count in (0, 255):  # a zero-length run; a repeat of 127, past the 52-pixel line
        bad = tmp_path / f"bad{count}.hdr"
        bad.write_bytes(data[:first] + bytes([count]) + data[first + 1 :])
        with pytest.raises(InvalidInputError) as said:
            image_info(bad)
        with pytest.raises(InvalidInputError) as read:
            read_image(bad)
        assert "corrupt run in scanline 0" in str(said.value)
        assert str(said.value) == str(read.value)
