"""Public names of imageform.spectral and the vision part of imageform.color (issue 4)."""

from __future__ import annotations

import imageform.color as color
import imageform.spectral as spectral

SPECTRAL = {
    "Spectrum",
    "blackbody_spectrum",
    "camera_sensitivities",
    "cmfs",
    "colorchecker_reflectances",
    "cone_fundamentals",
    "daylight_spectrum",
    "illuminant",
    "led_spectrum",
    "luminance",
    "luminous_efficiency",
    "planck",
    "planckian_cct",
    "spectrum_to_camera_rgb",
    "spectrum_to_lms",
    "spectrum_to_xyz",
    "table_source",
}
VISION = {
    "are_metamers",
    "metamer",
    "metamerism_index",
    "match_with_primaries",
    "simulate_cvd",
    "machado_matrix",
    "palette_check",
    "palette",
    "viridis",
    "OKABE_ITO",
    "spectral_locus",
    "xy_to_uv_prime",
    "xy_to_xyz",
    "in_locus",
    "gamut_area",
    "gamut_coverage",
    "gamut_map",
    "in_gamut",
    "gamut_triangle",
}


def test_public_names() -> None:
    for mod, names in ((spectral, SPECTRAL), (color, VISION)):
        missing = names - set(mod.__all__)
        assert not missing, f"{mod.__name__} lost {sorted(missing)}"
        for n in mod.__all__:
            assert hasattr(mod, n), n


def test_library_never_imports_colour_science() -> None:
    import re
    from pathlib import Path

    root = Path(spectral.__file__).parents[1]
    pattern = re.compile(r"^\s*(import colour\b|from colour(\.\w+)* import)", re.MULTILINE)
    for f in root.rglob("*.py"):
        assert not pattern.search(f.read_text()), f
