"""The packaged La Jolla GNSS-A surveys (Xie et al. 2023): the repeatability they should reach.

``oceanloc localize gnssa`` without files processes the five packaged surveys and shows, beside their
spread, the target standard deviation across surveys below.
"""

from __future__ import annotations

import numpy as np

TARGET_STD_ENU_M = np.array([0.025, 0.035, 0.06])
"""Target standard deviation across the La Jolla surveys (E, N, U), metres: what a correct solution over
the five surveys, compared at one epoch, reaches (issue acceptance)."""
