"""Compiled (numba) inner loops of the strapdown and the error-state EKF; private: use nav.strapdown and nav.ekf.

Everything here works on plain float64 arrays, allocates its work buffers once per run and is compiled with
``cache=True`` so a new process does not recompile. Frames and units are those of the package: world ENU (m,
m/s), body frame of the sensor, quaternions (w, x, y, z) body->world, specific force in m/s^2, rates in rad/s.

- :mod:`.quat`: quaternion product, rotation, exponential map and matrix on scalars (the compiled twins of
  nav.quaternion, tested against it).
- :mod:`.strapdown`: RK4 and exact-increment mechanisation of the nominal state.
- :mod:`.linalg`: Cholesky factor and solve of small symmetric positive definite matrices.
- :mod:`.covariance`: error-state transition, covariance propagation and the Joseph-form update.
- :mod:`.ekf`: the forward filter, the RTS pass and the batch over runs.
"""
