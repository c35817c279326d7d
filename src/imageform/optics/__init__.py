"""imageform.optics — thin lens, depth of field, defocus, vignetting and aberrations (SI units).

The focal length is always the keyword-only ``focal_length``: in metres, except where a
function works on pixels (the vignetting maps take it in pixels, as ``fx`` of K).
"""

from __future__ import annotations

from imageform.optics.aberrations import (
    ChromaticFocalLengths,
    axial_chromatic_aberration,
    axial_chromatic_blur_diameters,
    chromatic_focal_lengths,
    lateral_chromatic_aberration,
    spherical_aberration,
    spherical_blur_radius,
)
from imageform.optics.defocus import blur_by_radius, defocus_blur, defocus_radius_px, disc_kernel
from imageform.optics.depth_of_field import (
    DepthOfField,
    circle_of_confusion,
    depth_of_field,
    hyperfocal_distance,
)
from imageform.optics.thin_lens import (
    ThinLensSolution,
    aperture_diameter,
    f_number,
    magnification,
    thin_lens,
)
from imageform.optics.vignetting import (
    apply_vignetting,
    cos4_falloff,
    field_angle,
    mechanical_vignetting,
    pupil_overlap_fraction,
)

__all__ = [
    "ChromaticFocalLengths",
    "DepthOfField",
    "ThinLensSolution",
    "aperture_diameter",
    "apply_vignetting",
    "axial_chromatic_aberration",
    "axial_chromatic_blur_diameters",
    "blur_by_radius",
    "chromatic_focal_lengths",
    "circle_of_confusion",
    "cos4_falloff",
    "defocus_blur",
    "defocus_radius_px",
    "depth_of_field",
    "disc_kernel",
    "f_number",
    "field_angle",
    "hyperfocal_distance",
    "lateral_chromatic_aberration",
    "magnification",
    "mechanical_vignetting",
    "pupil_overlap_fraction",
    "spherical_aberration",
    "spherical_blur_radius",
    "thin_lens",
]
