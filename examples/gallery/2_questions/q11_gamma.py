"""
Practice question 11: gamma, and decoding before linear operations
==================================================================

Encoded values are roughly linear light raised to 1/2.2. Averaging, blurring or mixing must
happen on light, so decode first: the average of black and white encoded values (0.5) is far
darker than the average of their light (0.735 once encoded back).
"""

import numpy as np

from imageform.color import linear_to_srgb, mean_linear_light, srgb_to_linear

pair = np.array([0.0, 1.0])
print("naive mean of encoded values:", pair.mean())
print("mean in linear light, encoded back:", round(float(mean_linear_light(pair)), 4))
print(
    "sRGB 0.5 is",
    round(float(srgb_to_linear(0.5)), 4),
    "of full light; 0.5 light encodes to",
    round(float(linear_to_srgb(0.5)), 4),
)
