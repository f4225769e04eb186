"""Constants shared across nav (and by gaitsim through it): the one place for each of them. SI units.

Gravity comes in two meanings that must not be mixed:

- ``DEFAULT_GRAVITY``: the magnitude of the world's gravity, (0, 0, -DEFAULT_GRAVITY) in ENU, when a recording
  does not state its own (``meta.json`` ``sampling.gravity_mps2``, read by ``Recording.gravity``). The
  simulator's world uses it.
- ``STANDARD_GRAVITY``: the "g" of datasheet units (ranges and noise in g, mg, ug), a fixed conversion factor.

Detector defaults are OpenShoe's (anchors §2): the SHOE statistic's noise parameters, window and threshold.
"""

from __future__ import annotations

import math

DEFAULT_GRAVITY = 9.81  # m/s^2
STANDARD_GRAVITY = 9.80665  # m/s^2 per g

DEFAULT_SIGMA_A = 0.01  # m/s^2, detector accelerometer noise std
DEFAULT_SIGMA_G = math.radians(0.1)  # rad/s, detector gyro noise std
DEFAULT_WINDOW = 3  # samples, detector window
DEFAULT_THRESHOLD = 3e4  # detector threshold gamma (dimensionless)
