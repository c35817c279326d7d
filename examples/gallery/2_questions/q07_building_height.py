"""
Practice question 7: how tall is the building's image?
======================================================

A 20 m building stands 80 m from a pinhole camera with f = 35 mm. Its image is
``h = f H / Z = 35 * 20 / 80 = 8.75 mm`` tall.
"""

from imageform.geometry import projected_size

print("image height:", projected_size(20.0, 80.0, focal_length=35.0), "mm")
