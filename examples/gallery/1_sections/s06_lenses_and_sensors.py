"""
Section 6: lenses, sensors and the imaging pipeline
===================================================

A lens gathers far more light than a pinhole but focuses only one distance exactly: the thin
lens equation ``1/f = 1/d_o + 1/d_i``. Objects nearer or farther blur into a circle of
confusion, and the range that stays sharp enough is the depth of field, which grows as the
aperture closes (larger f-number). On the sensor, a colour filter array gives each pixel one
of red, green or blue; demosaicing interpolates the other two.
"""

import matplotlib.pyplot as plt
import numpy as np

from imageform.optics import circle_of_confusion, depth_of_field, thin_lens

print(
    "image distance for f = 50 mm, object at 2 m:",
    round(thin_lens(focal_length=50.0, d_o=2000.0).d_i, 3),
    "mm",
)
for n in (1.8, 4.0, 11.0):
    dof = depth_of_field(focal_length=50.0, f_number=n, focus=3000.0, coc=0.03)
    print(f"f/{n:g}: sharp from {dof.near / 1000:.2f} m to {dof.far / 1000:.2f} m")

# %%
# The blur circle's diameter against the object distance, focused at 3 m.

depth = np.linspace(1000.0, 10000.0, 300)
fig, ax = plt.subplots(figsize=(6, 3.5))
for n in (1.8, 4.0, 11.0):
    ax.plot(
        depth / 1000,
        circle_of_confusion(depth, focal_length=50.0, f_number=n, focus=3000.0),
        label=f"f/{n:g}",
    )
ax.axhline(0.03, color="k", ls="--", lw=1, label="acceptable blur (0.03 mm)")
ax.set_xlabel("object distance (m)")
ax.set_ylabel("circle of confusion (mm)")
ax.set_ylim(0, 0.4)
ax.legend()
fig.tight_layout()
plt.show()

# %%
# A Bayer mosaic (RGGB) of a small synthetic image, and the image demosaiced back.

from imageform.sensor import demosaic, mosaic

yy, xx = np.mgrid[0:64, 0:64] / 63.0
rgb = np.stack([xx, yy, 1 - xx * yy], axis=-1)
raw = mosaic(rgb, "RGGB")
back = demosaic(raw, "RGGB", method="malvar", clip=True)
print("mean abs error after demosaicing:", float(np.abs(back - rgb).mean().round(4)))
fig, axes = plt.subplots(1, 3, figsize=(9, 3))
for ax, img, title in (
    (axes[0], rgb, "scene"),
    (axes[1], raw[..., 0] if raw.ndim == 3 else raw, "raw mosaic"),
    (axes[2], back, "demosaiced"),
):
    ax.imshow(img, cmap="gray" if img.ndim == 2 else None, interpolation="nearest")
    ax.set_title(title)
    ax.axis("off")
fig.tight_layout()
plt.show()
