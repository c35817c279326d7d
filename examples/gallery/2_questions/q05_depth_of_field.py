"""
Practice question 5: depth of field and the aperture
====================================================

Depth of field is the range of distances that look sharp: their blur circle stays under what
the sensor and the viewer can resolve. A smaller aperture (a larger f-number) narrows the cone
of rays from each point, so blur grows more slowly away from the focus and the range widens, at
the cost of light (and, eventually, diffraction).
"""

import matplotlib.pyplot as plt
import numpy as np

from imageform.optics import depth_of_field, hyperfocal_distance

stops = np.array([1.4, 2, 2.8, 4, 5.6, 8, 11, 16])
near, far = [], []
for n in stops:
    dof = depth_of_field(focal_length=50.0, f_number=float(n), focus=5000.0, coc=0.03)
    near.append(dof.near / 1000)
    far.append(min(dof.far, 1e9) / 1000)
    print(f"f/{n:g}: {dof.near / 1000:.2f} m to {dof.far / 1000:.2f} m")
print(
    "hyperfocal distance at f/8:",
    round(hyperfocal_distance(focal_length=50.0, f_number=8.0, coc=0.03) / 1000, 2),
    "m",
)

fig, ax = plt.subplots(figsize=(6, 3.5))
ax.fill_between(range(len(stops)), near, np.minimum(far, 60), alpha=0.4)
ax.axhline(5, color="k", lw=1, label="focus (5 m)")
ax.set_xticks(range(len(stops)), [f"f/{n:g}" for n in stops])
ax.set_ylabel("sharp range (m)")
ax.set_ylim(0, 60)
ax.legend()
fig.tight_layout()
plt.show()
