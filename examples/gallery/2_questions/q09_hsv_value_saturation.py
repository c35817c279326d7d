"""
Practice question 9: V and S of an RGB pixel
============================================

For RGB (200, 50, 50): ``V = max = 200/255 = 0.784`` and ``S = (max - min) / max = 150/200 =
0.75``; the hue is 0 degrees (red). Integers in a tuple are 8-bit codes.
"""

from imageform.color import convert

h, s, v = convert((200, 50, 50), "srgb", "hsv")
print(f"H = {h:.1f} deg, S = {s:.3f}, V = {v:.3f}")
