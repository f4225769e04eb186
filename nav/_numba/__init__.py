"""Compiled (numba) inner loops of the strapdown, the error-state EKF and the SHOE detector; private: use
nav.strapdown, nav.ekf and nav.detectors.

Everything here works on plain float64 arrays, allocates its work buffers once per run and is compiled with
``cache=True`` so a new process does not recompile. The helpers the filter calls every sample (the increments, the
nominal state's advance, the propagation, the store, the update and its injection) are inlined into it
(``inline="always"``): a call hands each array over as its separate fields (pointer, shape, strides, ...), which cost
about 110 ns per 15-state sample, a seventh of the filter. numba's cache keys a function on its own file
alone; importing this package keys it on all of the package's modules (:func:`nav.compiled.key_cache_to_sources`),
so an edit of a callee reaches the filter.
Frames and units are those of the package: world ENU (m, m/s), body frame of the sensor, quaternions (w, x, y, z)
body->world, specific force in m/s^2, rates in rad/s.

- :mod:`.quat`: quaternion product, rotation, exponential map and matrix on scalars (the compiled twins of
  nav.quaternion, tested against it).
- :mod:`.strapdown`: RK4 and exact-increment mechanisation of the nominal state.
- :mod:`.linalg`: the inverse of a small (at most 3 x 3) symmetric positive definite matrix by Cholesky.
- :mod:`.covariance`: error-state transition, covariance propagation and the Joseph-form update.
- :mod:`.ekf`: the forward filter, the RTS pass and the batch over runs.
- :mod:`.detector`: the SHOE statistic of the zero-velocity detector.

Callers hand the kernels their arrays through :func:`nav.compiled.kernel_array`.
"""

from ..compiled import key_cache_to_sources
from . import covariance, detector, ekf, linalg, quat, strapdown

key_cache_to_sources([quat, linalg, strapdown, covariance, ekf, detector])
