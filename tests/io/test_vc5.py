"""imageform's VC-5 decoder (GoPro GPR raws) against GoPro's reference decoder.

The files in tests/data/vc5 (README there) were encoded and decoded by gopro/gpr's own codec;
the decoder must give the reference's samples exactly. Real GPRs (Hero6, HERO7, Fusion) are
checked the same way by benchmarks/check_gpr.py.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from imageform.errors import UnreadableFileError
from imageform.io import _vc5, read_raw

DATA = Path(__file__).resolve().parents[1] / "data" / "vc5"


def _expected(name: str, shape: tuple[int, int]) -> np.ndarray:
    return np.fromfile(DATA / f"{name}.expected.u16", "<u2").reshape(shape)


def test_rggb14_equals_reference() -> None:
    data = (DATA / "synthetic-rggb14.vc5").read_bytes()
    got = _vc5.decode(data)
    assert got.dtype == np.uint16
    np.testing.assert_array_equal(got, _expected("synthetic-rggb14", (76, 100)))


def test_gbrg12_equals_reference() -> None:
    data = (DATA / "synthetic-gbrg12.vc5").read_bytes()
    got = _vc5.decode(data, rggb=False)
    np.testing.assert_array_equal(got, _expected("synthetic-gbrg12", (74, 100)))
    assert int(got.max()) <= 4095


def test_read_raw_gpr_equals_reference() -> None:
    raw = read_raw(DATA / "synthetic.gpr")
    np.testing.assert_array_equal(raw.mosaic, _expected("synthetic-gpr", (76, 100)))
    assert raw.cfa_pattern == "RGGB"
    assert raw.white_level == 16383.0
    assert raw.metadata["reader"] == "imageform VC-5"
    assert raw.xyz_to_camera is not None and raw.white_balance is not None


def test_log_curve() -> None:
    curve = _vc5.log_curve()
    assert curve.shape == (4096,) and curve[0] == 0 and curve[-1] == 65535
    assert np.all(np.diff(curve.astype(np.int64)) >= 0)
    i = np.array([1, 100, 2048, 4000])
    exact = 65535 * (113.0 ** (i / 4095) - 1) / 112
    np.testing.assert_array_less(np.abs(curve[i] - exact), 1.0)


def _segment(data: bytes, tag: int) -> int:
    """Return the byte offset of the first header segment with ``tag``."""
    words = np.frombuffer(data, ">u4")
    return 4 * int(np.flatnonzero((words >> 16) == tag)[0])


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda d: d[: len(d) // 2], "truncated"),
        (lambda d: b"VC-6" + d[4:], "start marker"),
        (lambda d: b"", "no VC-5 bitstream"),
    ],
)
def test_bad_bitstreams_refused(change: Callable[[bytes], bytes], message: str) -> None:
    data = (DATA / "synthetic-rggb14.vc5").read_bytes()
    with pytest.raises(_vc5.Vc5Error, match=message) as info:
        _vc5.decode(change(data))
    assert "\n" not in str(info.value)


def test_wrong_image_format_refused() -> None:
    data = bytearray((DATA / "synthetic-rggb14.vc5").read_bytes())
    at = _segment(bytes(data), 84)  # ImageFormat 4 (raw) -> 3
    data[at + 3] = 3
    with pytest.raises(_vc5.Vc5Error, match="format 3"):
        _vc5.decode(bytes(data))


def test_scrambled_band_refused() -> None:
    """Bits of another code in a highpass band: the band does not end where it must."""
    data = bytearray((DATA / "synthetic-rggb14.vc5").read_bytes())
    words = np.frombuffer(bytes(data), ">u4")
    blocks = np.flatnonzero((words >> 16) == 0xA000)  # codeblocks (optional tag 0x6000)
    start = 4 * (int(blocks[1]) + 1)  # the first highpass band's payload
    rng = np.random.default_rng(1)
    data[start : start + 64] = rng.integers(0, 256, 64, dtype=np.uint8).tobytes()
    with pytest.raises(_vc5.Vc5Error, match="subband 1 of channel 0") as info:
        _vc5.decode(bytes(data))
    assert "\n" not in str(info.value)


def test_corrupt_gpr_refused_in_one_line(tmp_path: Path) -> None:
    data = bytearray((DATA / "synthetic.gpr").read_bytes())
    marker = bytes(data).index(b"VC-5")
    data[marker : marker + 4] = b"XXXX"
    bad = tmp_path / "bad.gpr"
    bad.write_bytes(bytes(data))
    with pytest.raises(UnreadableFileError, match=r"VC-5 .*Compression 9.*corrupt: .*start marker"):
        read_raw(bad)


def test_cli_info_and_develop_a_gpr(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from imageform.cli import main
    from imageform.io import read_image

    src = str(DATA / "synthetic.gpr")
    assert main(["info", src]) == 0
    assert "100 x 76 photosites, RGGB mosaic" in capsys.readouterr().out
    out = tmp_path / "dev.png"
    assert main(["develop", src, "-o", str(out)]) == 0
    image = np.asarray(read_image(out), np.float64) / 65535.0  # 16-bit PNG
    assert image.shape == (76, 100, 3) and 0.05 < image.mean() < 0.95


def test_unreadable_gpr_refusal_names_our_decoder(tmp_path: Path) -> None:
    """A GPR whose raw IFD our reader cannot use (no ImageWidth) is refused in one line saying
    that LibRaw does not decode VC-5 and imageform's own decoder found nothing it reads, not the
    stale 'neither LibRaw nor tifffile decodes' of before the decoder."""
    import tifffile

    src = DATA / "synthetic.gpr"
    with tifffile.TiffFile(src) as tf:
        entry = tf.pages[0].pages[0].tags[256].offset  # type: ignore[union-attr]
    data = bytearray(src.read_bytes())
    data[entry : entry + 2] = (0x7FFF).to_bytes(2, "little")  # ImageWidth: an unknown tag
    bad = tmp_path / "nowidth.gpr"
    bad.write_bytes(bytes(data))
    with pytest.raises(UnreadableFileError, match=r"Compression 9.*imageform's own VC-5") as e:
        read_raw(bad)
    assert "\n" not in str(e.value) and "tifffile" not in str(e.value)
