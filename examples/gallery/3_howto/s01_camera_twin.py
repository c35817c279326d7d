"""
A camera's digital twin: photograph, characterise, simulate
===========================================================

A lab characterises a camera from photographs of standard targets: checkerboard views for the
geometry, a slanted edge for sharpness (ISO 12233 e-SFR), flat and dark frame stacks for the
noise (EMVA 1288) and a ColorChecker for colour. Here the "real" camera X is a camera file, and
the lab's photographs are rendered through it by ``render_lab_set``; ``characterize_camera``
measures them back into a camera file, the twin. How-to guide: docs/characterize.md.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from imageform.geometry import BrownConrady, Camera
from imageform.io import CameraFile, write_camera
from imageform.simulate import render_lab_set
from imageform.workflows import characterize_camera

x = CameraFile(
    Camera(
        [[560.0, 0.0, 322.0], [0.0, 555.0, 236.0], [0.0, 0.0, 1.0]],
        image_size=(640, 480),
        distortion=BrownConrady(k1=-0.18, k2=0.03),
    ),
    sensor={
        "system_gain_dn_per_e": 0.4,
        "read_noise_e": 4.0,
        "bit_depth": 12,
        "black_level_dn": 64.0,
        "full_well_e": 9000.0,
    },
    optics={"model": "gaussian", "gaussian_sigma_px": 0.8},
    color={
        "white_balance": [1.45, 1.0, 1.3],
        "ccm": [[1.7, -0.5, -0.2], [-0.3, 1.6, -0.3], [0.0, -0.6, 1.6]],
        "spectral_sensitivity": "nikon_d5100",
    },
)
work = Path(tempfile.mkdtemp())
write_camera(work / "x.toml", x)
lab = render_lab_set(work / "x.toml", work / "lab", views=8)
twin = characterize_camera(lab.folder)

K = twin.geometry.calibration.K
print(
    f"fx {K[0, 0]:.2f} (560), fy {K[1, 1]:.2f} (555), cx {K[0, 2]:.2f} (322), "
    f"cy {K[1, 2]:.2f} (236)"
)
print(f"k1 {twin.geometry.calibration.distortion.k1:.4f} (-0.18)")
print(
    f"system gain {twin.noise.emva.system_gain:.4f} DN/e- (0.4), "
    f"read noise {twin.noise.emva.dark_noise:.2f} e- (4.0)"
)
print(f"Gaussian PSF sigma {twin.sharpness.gaussian_sigma_px:.3f} px (0.8)")

# %%
# The lab's photographs: one checkerboard view, the slanted edge (a raw DNG mosaic: its
# sharpness is measured without demosaicing) and the chart as the camera develops it.

from imageform.io import read_image, read_raw

edge = read_raw(lab.edge)
fig, axes = plt.subplots(1, 3, figsize=(10, 3))
for ax, image, title in zip(
    axes,
    (
        read_image(lab.checkerboard[0]) / 65535.0,  # 16-bit PNGs
        edge.mosaic / edge.white_level,
        read_image(lab.folder / "colorchecker" / "developed.png") / 65535.0,
    ),
    ("checkerboard view", "slanted edge (raw mosaic)", "ColorChecker (developed)"),
    strict=True,
):
    ax.imshow(image, cmap="gray")
    ax.set_title(title)
    ax.axis("off")
fig.tight_layout()
plt.show()

# %%
# What was measured: the MTF from the slanted edge with the fitted Gaussian model, and the
# EMVA 1288 photon-transfer curve (temporal variance against the mean, both in DN) whose
# slope is the system gain K.

s, e = twin.sharpness, twin.noise.emva
f = np.asarray(s.frequency)
fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 3.5))
for i, ch in enumerate(s.channels):
    a1.plot(f, np.asarray(s.sfr)[:, i], label=f"{ch}: MTF50 {s.mtf50[i]:.3f} cy/px")
a1.axhline(0.5, color="k", lw=0.8, ls=":")
a1.set_xlim(0, 0.5)
a1.set_xlabel("frequency (cycles/pixel)")
a1.set_ylabel("MTF")
a1.legend(fontsize=8)
a1.set_title("sharpness (e-SFR)")
mean = np.asarray(e.mean_dn) - np.asarray(e.dark_mean_dn)
var = np.asarray(e.var_dn) - np.asarray(e.dark_var_dn)
keep = np.arange(len(mean)) < e.fit_points
a2.plot(mean, var, "o", ms=3, label="flats, dark subtracted")
a2.plot(mean[keep], e.system_gain * mean[keep], "-", label=f"slope K = {e.system_gain:.3f} DN/e-")
a2.set_xlabel("mean - dark (DN)")
a2.set_ylabel("temporal variance (DN²)")
a2.legend(fontsize=8)
a2.set_title("photon transfer (EMVA 1288)")
fig.tight_layout()
plt.show()

# %%
# The twin as a camera file (geometry, ``[optics]``, ``[sensor]``, ``[color]``: the white
# balance and matrix fitted to X's developed chart, and the spectral sensitivities estimated
# from its raw one), and a scene simulated through X and through the twin: the same
# ColorChecker, the same noise seed, compared patch by patch in CIEDE2000.

from imageform.io import read_camera
from imageform.simulate import apply_camera_file, load_scene, simulate

write_camera(work / "twin.toml", twin.camera_file(), **twin.tables)
scene = load_scene(
    {
        "name": "chart",
        "render": {"width": 640, "height": 480, "supersampling": 2},
        "illuminant": {"type": "cie", "name": "D65", "illuminance_lux": 1000.0},
        "camera": {"eye_m": [0.0, -0.2, 0.0], "target_m": [0.0, 0.0, 0.0]},
        "lens": {"defocus": False, "vignetting": "none"},
        "objects": [{"type": "colorchecker", "center_m": [0.0, 0.0, 0.0], "width_m": 0.12}],
    }
)
from imageform.color import delta_e_ciede2000

fig, axes = plt.subplots(1, 2, figsize=(10, 3.8))
patches = []
for ax, name in zip(axes, ("x.toml", "twin.toml"), strict=True):
    out = simulate(apply_camera_file(scene, read_camera(work / name)), rng=1)
    img = np.clip(next(s.image for s in out.stages if s.name == "output"), 0, 1)
    patches.append(out.patches.lab_measured)  # the simulator's patch means, CIELAB
    ax.imshow(img)
    ax.set_title(f"through {name}")
    ax.axis("off")
fig.tight_layout()
plt.show()
de = delta_e_ciede2000(patches[0], patches[1])
print(
    f"ColorChecker through the twin vs through X: mean CIEDE2000 {de.mean():.2f}, "
    f"max {de.max():.2f}"
)
