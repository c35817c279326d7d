"""Method names: one read-only registry per concept, and every name in it works (issue 30).

Every public ``*_METHODS`` constant of every public module is a read-only collection (a
``MappingProxyType`` mapping a name to the function that implements it, or a tuple of names
where the implementations are imported lazily), each concept has one such list (no two
public constants of the same name that differ), and each name of it is called here through
the public function that takes ``method=``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import Any

import numpy as np
import pytest

from imageform import analysis, color, io, sensor, spectral
from tests.regen_api_snapshot import public_modules

_RGB = np.random.default_rng(0).uniform(0.05, 0.95, (12, 14, 3))
_LAB1 = np.array([[50.0, 2.0, -3.0], [60.0, -10.0, 20.0]])
_LAB2 = np.array([[52.0, 0.0, -1.0], [58.0, -12.0, 25.0]])
_XY_D65 = np.array([0.31271, 0.32902])


def _stain_image() -> np.ndarray:
    img, _, _ = analysis.synthetic_stain_image((48, 48), rng=1)
    return np.asarray(img)


def _white_balance(name: str) -> Any:
    kw: dict[str, Any] = {"cct": 5000.0} if name == "manual" else {}
    return color.white_balance(_RGB, name, transfer="linear", **kw).gains


def _read_video(name: str) -> Any:
    """The frames of a small interlaced image sequence read with ``deinterlace=name``."""
    import tempfile
    from pathlib import Path

    from imageform.io import open_video, write_image

    # removed afterwards: a folder per call was once left in the temporary folder
    with tempfile.TemporaryDirectory(prefix="imageform-registry-") as tmp:
        folder = Path(tmp)
        rows = np.arange(24.0)[:, None]
        for k in range(10):  # a bright bar moving down 3 rows a field: the fields comb
            frame = np.zeros((24, 32))
            frame[0::2] = (np.abs(rows[0::2] - 3.0 * (2 * k) % 24) < 3) * 0.9
            frame[1::2] = (np.abs(rows[1::2] - 3.0 * (2 * k + 1) % 24) < 3) * 0.9
            write_image(folder / f"f{k:02d}.png", np.repeat(frame[..., None], 3, axis=-1))
        with open_video(folder, fps=25, deinterlace=name) as reader:
            return [f.image.shape for f in reader]


def _stain_normalize(name: str) -> Any:
    img = _stain_image()
    fn = analysis.STAIN_NORMALIZATION_METHODS[name]
    return fn(img, img)


#: registry name -> (the registry, how one of its names is used through the public API)
CALLS: dict[str, tuple[Any, Callable[[str], Any]]] = {
    "XY_TO_CCT_METHODS": (
        color.XY_TO_CCT_METHODS,
        lambda m: color.xy_to_cct(_XY_D65, method=m),
    ),
    "CCT_TO_XY_METHODS": (
        color.CCT_TO_XY_METHODS,
        lambda m: color.cct_to_xy(6504.0, method=m),
    ),
    "WHITE_BALANCE_METHODS": (color.WHITE_BALANCE_METHODS, _white_balance),
    "WHITE_BALANCE_ALIASES": (color.WHITE_BALANCE_ALIASES, _white_balance),
    "DELTA_E_METHODS": (color.DELTA_E_METHODS, lambda m: color.delta_e(_LAB1, _LAB2, m)),
    "GRAY_METHODS": (color.GRAY_METHODS, lambda m: color.srgb_to_gray(_RGB, m)),
    "GAMUT_MAPPING_METHODS": (
        color.GAMUT_MAPPING_METHODS,
        lambda m: color.gamut_map(np.array([0.3, 0.2, 0.9]), "srgb", method=m),
    ),
    "CVD_METHODS": (color.CVD_METHODS, lambda m: color.simulate_cvd(_RGB, "deutan", 1.0, m)),
    "STAIN_VECTOR_METHODS": (
        analysis.STAIN_VECTOR_METHODS,
        lambda m: analysis.macenko_stains(_stain_image(), method=m).stain_matrix,
    ),
    "STAIN_NORMALIZATION_METHODS": (analysis.STAIN_NORMALIZATION_METHODS, _stain_normalize),
    "CORRECTION_METHODS": (
        analysis.CORRECTION_METHODS,
        lambda m: analysis.fit_color_correction(_RGB[0], _RGB[0] ** 1.1, method=m).matrix,
    ),
    "DEINTERLACE_METHODS": (io.DEINTERLACE_METHODS, _read_video),
    "DEMOSAIC_METHODS": (
        sensor.DEMOSAIC_METHODS,
        lambda m: sensor.demosaic(np.full((8, 8), 0.25), "RGGB", m),
    ),
    "INTEGRATION_METHODS": (
        spectral.INTEGRATION_METHODS,
        lambda m: spectral.spectrum_to_xyz(
            spectral.colorchecker_reflectances()["blue sky"], method=m
        ),
    ),
    "INTERPOLATION_METHODS": (
        spectral.INTERPOLATION_METHODS,
        lambda m: (
            spectral.colorchecker_reflectances()["blue sky"]
            .interpolate([455.0, 505.0], method=m)
            .values
        ),
    ),
    "EXTRAPOLATION_METHODS": (
        spectral.EXTRAPOLATION_METHODS,
        lambda m: (
            spectral.colorchecker_reflectances()["blue sky"]
            .interpolate([500.0], extrapolate=m)
            .values
        ),
    ),
}


def _public_registries() -> dict[str, list[tuple[str, Any]]]:
    """``NAME -> [(module, value)]`` for every public ``*_METHODS`` / ``*_ALIASES`` constant."""
    out: dict[str, list[tuple[str, Any]]] = {}
    for mod in public_modules():
        for name in mod.__all__:
            if name.endswith(("_METHODS", "_ALIASES")):
                out.setdefault(name, []).append((mod.__name__, getattr(mod, name)))
    return out


def test_every_public_registry_is_known_here() -> None:
    """A new ``*_METHODS`` constant needs a line in CALLS (so its names get called)."""
    assert set(_public_registries()) == set(CALLS)


@pytest.mark.parametrize("name", sorted(_public_registries()))
def test_registry_is_read_only_and_one_per_concept(name: str) -> None:
    found = _public_registries()[name]
    first = found[0][1]
    for module, value in found:
        # one concept, one list: every module exporting the name exports the same object
        assert value is first, f"{module}.{name} differs from {found[0][0]}.{name}"
    assert isinstance(first, (tuple, MappingProxyType)), f"{name}: {type(first).__name__}"
    assert len(first) > 0
    assert all(isinstance(k, str) and k == k.lower() for k in first)
    if isinstance(first, MappingProxyType):
        with pytest.raises(TypeError):
            first["new"] = first[next(iter(first))]  # type: ignore[index]
        if not name.endswith("_ALIASES") and name != "CORRECTION_METHODS":
            # a dispatching registry: each name maps to the function that implements it
            assert all(callable(v) for v in first.values()), name


@pytest.mark.parametrize(
    ("registry", "method"),
    [(r, m) for r, (reg, _) in CALLS.items() for m in reg],
    ids=[f"{r}-{m}" for r, (reg, _) in CALLS.items() for m in reg],
)
def test_every_name_works(registry: str, method: str) -> None:
    import glob
    import os
    import tempfile

    pattern = os.path.join(tempfile.gettempdir(), "imageform-registry-*")
    before = set(glob.glob(pattern))
    _, call = CALLS[registry]
    out = call(method)
    assert set(glob.glob(pattern)) <= before, "a temporary folder left behind"
    values = out if isinstance(out, tuple) else (out,)
    for v in values:
        assert np.all(np.isfinite(np.asarray(v, dtype=np.float64))), (registry, method)


def test_unknown_name_lists_the_registry_keys() -> None:
    """The error message lists the same keys as the registry."""
    with pytest.raises(ValueError, match="valid: ") as info:
        color.xy_to_cct(_XY_D65, method="nope")
    for key in color.XY_TO_CCT_METHODS:
        assert repr(key) in str(info.value)
    with pytest.raises(ValueError, match="valid: ") as info:
        color.cct_to_xy(6504.0, method="mccamy1992")  # a one-way method
    for key in color.CCT_TO_XY_METHODS:
        assert repr(key) in str(info.value)


def test_white_balance_lists_derive_from_the_registry() -> None:
    """The CLI's --method (spelled out: --help imports no NumPy) and chunked processing's
    streamed subset are the registry's names."""
    from imageform.batch import chunked
    from imageform.workflows import color as wf_color
    from imageform.workflows._spec import choice_names

    cli = set(choice_names(wf_color._WB_METHODS)) - {"chart"}
    assert set(color.WHITE_BALANCE_METHODS) <= cli
    assert cli <= set(color.WHITE_BALANCE_METHODS) | set(color.WHITE_BALANCE_ALIASES)
    assert set(chunked._WB_METHODS) <= set(color.WHITE_BALANCE_METHODS)
    assert set(color.WHITE_BALANCE_ALIASES.values()) <= set(color.WHITE_BALANCE_METHODS)


@pytest.mark.parametrize(
    ("ref", "registry"),
    [
        ("imageform.workflows.analysis:_STAIN_METHODS", analysis.STAIN_NORMALIZATION_METHODS),
        ("imageform.workflows.analysis:_CORRECTION_METHODS", analysis.CORRECTION_METHODS),
        ("imageform.workflows.sensor:_DEMOSAIC_METHODS", sensor.DEMOSAIC_METHODS),
    ],
)
def test_cli_choices_are_the_registry(
    ref: str, registry: Mapping[str, Any] | tuple[str, ...]
) -> None:
    """The CLI spells the names out (--help imports no NumPy); they are the registry's."""
    from imageform.workflows._spec import choice_names, resolve

    assert choice_names(resolve(ref)) == tuple(registry)


def test_cli_deinterlace_choices_are_the_readers() -> None:
    """``--deinterlace`` / ``--field-order`` spell out the reader's names (no NumPy at --help)."""
    from imageform.workflows._video import DEINTERLACE_CHOICES, FIELD_ORDER_CHOICES

    assert DEINTERLACE_CHOICES == io.DEINTERLACE_METHODS
    assert FIELD_ORDER_CHOICES == io.FIELD_ORDERS
