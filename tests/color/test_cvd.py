"""CVD simulation: Machado 2009 matrices exactly, Brettel 1997 and Viénot 1999 properties."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from imageform.color import brettel_planes, cvd_matrix, machado_matrix, simulate_cvd
from imageform.errors import InvalidInputError, UnknownOptionError
from tests.helpers import to_backend, to_np

# Machado, Oliveira & Fernandes (2009), supplementary table (severity 1.0), 6 decimals.
MACHADO_1 = {
    "protan": [
        [0.152286, 1.052583, -0.204868],
        [0.114503, 0.786281, 0.099216],
        [-0.003882, -0.048116, 1.051998],
    ],
    "deutan": [
        [0.367322, 0.860646, -0.227968],
        [0.280085, 0.672501, 0.047413],
        [-0.011820, 0.042940, 0.968881],
    ],
    "tritan": [
        [1.255528, -0.076749, -0.178779],
        [-0.078411, 0.930809, 0.147602],
        [0.004733, 0.691367, 0.303900],
    ],
}
# Same table, severity 0.5 (protanomaly).
MACHADO_PROTAN_05 = [
    [0.458064, 0.679578, -0.137642],
    [0.092785, 0.846313, 0.060902],
    [-0.007494, -0.016807, 1.024301],
]


@pytest.mark.parametrize("d", ["protan", "deutan", "tritan"])
def test_machado_matrices_exact(d: str) -> None:
    assert np.array_equal(machado_matrix(d, 1.0), np.array(MACHADO_1[d]))
    assert np.array_equal(machado_matrix(d, 0.0), np.eye(3))


def test_machado_protan_half_and_interpolation() -> None:
    assert np.array_equal(machado_matrix("protanomaly", 0.5), np.array(MACHADO_PROTAN_05))
    m = machado_matrix("protan", 0.55)
    mid = 0.5 * (machado_matrix("protan", 0.5) + machado_matrix("protan", 0.6))
    assert np.allclose(m, mid, atol=1e-15)


def test_machado_all_tenths_match_colour_science() -> None:
    """Cross-check: every pre-computed matrix equals colour-science's transcription."""
    colour = pytest.importorskip("colour")
    table = colour.blindness.CVD_MATRICES_MACHADO2010
    for ours, theirs in (
        ("protan", "Protanomaly"),
        ("deutan", "Deuteranomaly"),
        ("tritan", "Tritanomaly"),
    ):
        for s, mat in table[theirs].items():
            assert np.array_equal(machado_matrix(ours, s), np.asarray(mat) + 0.0), (ours, s)


@pytest.mark.parametrize("method", ["machado2009", "brettel1997", "vienot1999"])
@pytest.mark.parametrize("d", ["protan", "deutan", "tritan"])
def test_greys_stay_grey_and_severity_zero_is_identity(method: str, d: str) -> None:
    """Neutral colours are seen the same by dichromats (all three models keep greys
    within 1e-3; Machado's rows sum to 1 within the table's rounding)."""
    g = np.linspace(0, 1, 5)[:, None] * np.ones(3)
    out = simulate_cvd(g, d, 1.0, method)
    assert np.allclose(out, g, atol=2e-3)
    rgb = np.random.default_rng(1).random((4, 5, 3))
    assert np.allclose(simulate_cvd(rgb, d, 0.0, method), rgb, atol=1e-12)


def test_red_green_confusion() -> None:
    """Deutan and protan: red and green collapse onto yellow-blue axis (R ≈ G after
    simulation for Brettel/Viénot's dichromat projection of pure red and green)."""
    red_green = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    for method in ("brettel1997", "vienot1999"):
        out = simulate_cvd(red_green, "deutan", 1.0, method, linear=True)
        lms_out = out @ np.array([[0.2, 0.7, 0.1]]).T  # rough luminance, not needed equal
        assert lms_out.shape == (2, 1)
        # both come out yellowish: blue channel well below red and green
        assert np.all(out[:, 2] < 0.1 * out[:, :2].max(axis=1) + 0.05)


def test_vienot_is_one_brettel_plane_for_protan() -> None:
    """For protan/deutan the two Brettel half-planes nearly coincide (Viénot 1999): on random
    colours the two models agree to a few hundredths in linear RGB."""
    rgb = np.random.default_rng(0).random((500, 3))
    for d in ("protan", "deutan"):
        b = simulate_cvd(rgb, d, method="brettel1997", linear=True)
        v = simulate_cvd(rgb, d, method="vienot1999", linear=True)
        assert np.mean(np.abs(b - v)) < 0.05


def test_dichromat_projection_is_idempotent() -> None:
    rgb = np.random.default_rng(2).random((100, 3))
    for d in ("protan", "deutan", "tritan"):
        m = cvd_matrix(d, 1.0, "vienot1999")
        assert np.allclose(m @ m, m, atol=1e-12)
        h1, h2, _ = brettel_planes(d)
        assert np.allclose(h1 @ h1, h1, atol=1e-12) and np.allclose(h2 @ h2, h2, atol=1e-12)
        once = simulate_cvd(rgb, d, method="brettel1997", linear=True)
        assert np.allclose(
            simulate_cvd(once, d, method="brettel1997", linear=True), once, atol=1e-9
        )


@settings(max_examples=25, deadline=None)
@given(st.floats(0, 1), st.sampled_from(["protan", "deutan", "tritan"]))
def test_severity_is_continuous(s: float, d: str) -> None:
    """Property: the simulation moves continuously with severity (no jump at tenths)."""
    rgb = np.array([[0.8, 0.3, 0.1]])
    a = simulate_cvd(rgb, d, s, linear=True)
    b = simulate_cvd(rgb, d, min(1.0, s + 1e-6), linear=True)
    assert np.max(np.abs(a - b)) < 1e-4


def test_encoded_path_and_clip() -> None:
    rgb = np.array([[1.0, 0.0, 0.0]], dtype=np.float32)
    out = simulate_cvd(rgb, "tritan")
    assert out.dtype == np.float32
    lin = simulate_cvd(rgb, "tritan", linear=True)
    assert np.any(lin < 0)  # Machado's tritan matrix leaves the gamut: reported, not clipped
    assert simulate_cvd(rgb, "tritan", linear=True, clip=True).min() >= 0
    u8 = simulate_cvd(np.full((2, 2, 3), 128, np.uint8), "deutan")
    assert u8.dtype == np.float32 and np.allclose(u8, 128 / 255, atol=2e-3)


def test_backends(xp_name: str) -> None:
    rgb = np.random.default_rng(3).random((3, 4, 3))
    for method in ("machado2009", "brettel1997"):
        want = simulate_cvd(rgb, "deutan", 0.7, method)
        got = simulate_cvd(to_backend(rgb, xp_name), "deutan", 0.7, method)
        assert (
            type(got).__module__.split(".")[0]
            == type(to_backend(rgb, xp_name)).__module__.split(".")[0]
        )
        assert np.allclose(to_np(got), want, atol=1e-12)


def test_bad_input() -> None:
    rgb = np.zeros((2, 3))
    with pytest.raises(InvalidInputError, match=r"severity in \[0, 1\], got 1.5"):
        simulate_cvd(rgb, "deutan", 1.5)
    with pytest.raises(InvalidInputError, match="severity"):
        simulate_cvd(rgb, "deutan", -0.1)
    with pytest.raises(InvalidInputError, match="severity"):
        simulate_cvd(rgb, "deutan", "high")  # type: ignore[arg-type]
    with pytest.raises(UnknownOptionError, match="colour-vision deficiency"):
        simulate_cvd(rgb, "achromat")
    with pytest.raises(UnknownOptionError, match="valid: 'brettel1997', 'machado2009'"):
        simulate_cvd(rgb, "deutan", method="daltonize")
    with pytest.raises(InvalidInputError, match="3 channels"):
        simulate_cvd(np.zeros((2, 4)), "deutan")
    with pytest.raises(InvalidInputError, match="piecewise"):
        cvd_matrix("deutan", 1.0, "brettel1997")


# --------------------------------------------------------------------------- cached arrays


def test_cached_matrices_are_read_only_and_shared() -> None:
    """The cached LMS, Viénot and Brettel arrays are one read-only object per key."""
    from imageform.color import cvd

    t, t_inv = cvd._rgb_lms()
    assert cvd._rgb_lms()[0] is t and cvd._rgb_lms()[1] is t_inv
    np.testing.assert_allclose(t @ t_inv, np.eye(3), atol=1e-12)
    for d in ("protan", "deutan", "tritan"):
        v = cvd._vienot_matrix(d)
        assert cvd._vienot_matrix(d) is v
        planes = cvd._brettel_planes(d)
        assert all(a is b for a, b in zip(cvd._brettel_planes(d), planes, strict=True))
        for a in (t, t_inv, v, *planes):
            assert not a.flags.writeable
            with pytest.raises(ValueError, match="read-only"):
                a[0] = 0.0
    # Viénot et al. (1999): the projection keeps white; the doctest's protan value
    np.testing.assert_allclose(cvd._vienot_matrix("protan") @ np.ones(3), np.ones(3), atol=1e-12)
    np.testing.assert_allclose(
        cvd_matrix("protan", 1.0, "vienot1999") @ [1.0, 0.0, 0.0],
        [0.1089, 0.1089, 0.0045],
        atol=5e-5,
    )


def test_brettel_planes_are_writable_copies_of_the_cache() -> None:
    """The public result is the caller's (writable, equal bits); simulate_cvd reads the cache."""
    from imageform.color import cvd

    for d in ("protan", "deutan", "tritan"):
        out = brettel_planes(d)
        for a, c in zip(out, cvd._brettel_planes(d), strict=True):
            assert a.flags.writeable and a is not c
            np.testing.assert_array_equal(a, c)
    rgb = np.random.default_rng(5).random((4, 5, 3))
    h1, h2, n = brettel_planes("deutan")
    want = np.where(((rgb @ n) >= 0)[..., None], rgb @ h1.T, rgb @ h2.T)
    got = simulate_cvd(rgb, "deutan", method="brettel1997", linear=True)
    np.testing.assert_array_equal(got, want)


def test_brettel_on_torch_gets_writable_copies(monkeypatch: pytest.MonkeyPatch) -> None:
    """torch.asarray shares a float64 array and warns (once a process) on a read-only one:
    NumPy reads the cached planes, torch gets brettel_planes' writable copies."""
    from imageform.color import cvd

    torch = pytest.importorskip("torch")
    calls: list[str] = []
    real = cvd.brettel_planes
    monkeypatch.setattr(cvd, "brettel_planes", lambda d: calls.append(d) or real(d))
    rgb = np.random.default_rng(6).random((3, 4, 3))
    want = simulate_cvd(rgb, "protan", method="brettel1997", linear=True)
    assert calls == []
    out = simulate_cvd(torch.asarray(rgb), "protan", method="brettel1997", linear=True)
    assert calls == ["protan"]
    np.testing.assert_allclose(out.numpy(), want, rtol=0, atol=1e-12)  # torch sums its own way
