"""Speed of the IMU forward model (gaitsim.imu.model.apply_sensor), one core.

Prints IMU samples per second (one sample = one 6-axis reading: 3 accel + 3 gyro) for several presets and
for a configuration with every term on, on a 2,000,000-sample (about 42 min) walking-like record at 800 Hz (best of 9 runs),
with one BLAS thread (the deterministic terms' matrix products) unless OPENBLAS_NUM_THREADS is set. Records of
1 M samples or more take the compiled kernels (gaitsim.imu.kernels); shorter ones the numpy reference path.
Run: PYTHONPATH=$PWD python benchmarks/imu_speed.py [n_samples] [--worker-memory]

``--worker-memory`` first sets glibc's malloc as the runner's workers set it
(:func:`gaitsim.experiments.runner.keep_freed_memory`): the outputs (24 MB per sensor and 1 M samples) then reuse
the memory the previous call freed instead of being mapped afresh and paid again in page faults. That is how the
model runs in a Monte Carlo study's workers; without it, as in a plain script.
"""

from __future__ import annotations

import os
import argparse
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # one core: before numpy loads OpenBLAS

import numpy as np  # noqa: E402

import gaitsim.imu.kernels  # noqa: E402,F401  (numba loaded before the arrays: see samples_per_second)
from gaitsim.experiments.runner import keep_freed_memory  # noqa: E402
from gaitsim.imu.model import apply_sensor  # noqa: E402
from gaitsim.imu.presets import get_preset  # noqa: E402


def truth(n: int, rate_hz: float = 800.0):
    t = np.arange(n) / rate_hz
    phase = 2 * np.pi * 1.4 * t[:, None]
    acc = np.array([0.0, 0.0, 9.81]) + 5.0 * np.sin(phase * [1.0, 2.0, 3.0])
    gyr = 3.0 * np.sin(phase * [1.5, 1.0, 0.5])
    return t, acc, gyr


def everything_on():
    paper = get_preset("paper-vn200")
    return paper.replace(
        name="all terms", gyro_random_walk=1e-5, accel_random_walk=1e-4, gyro_bias_repeatability=1e-3,
        accel_bias_repeatability=1e-2, gyro_g2_sensitivity=np.full((3, 3), 1e-7), gyro_resolution=1e-4,
        accel_resolution=1e-3, gyro_bandwidth=250.0, accel_bandwidth=250.0, accel_temp_bias=1e-4,
        gyro_temp_bias=1e-5, accel_temp_scale=1e-4, gyro_temp_scale=1e-4, temperature=[20.0, 30.0],
        clock_error=50e-6, timestamp_jitter=1e-6, accel_gyro_skew=2e-4, mounting_misalignment=[0.01, -0.02, 0.03])


def samples_per_second(spec, t, acc, gyr, repeats: int = 9) -> float:
    """Samples per second of apply_sensor, best of ``repeats``. numba is imported before the arrays are made, as
    the model imported it before issue 16's IMU work (once, on a loaded machine, importing it in the first call
    instead made the ideal preset's copies take 10-15 ms instead of 6 ms per 1 M samples, repeatably for a
    while; later not: cause not found, no page faults counted)."""
    apply_sensor(spec, t, acc, gyr, np.random.default_rng(0))  # load the compiled kernels
    best = np.inf
    for seed in range(repeats):
        start = time.perf_counter()
        apply_sensor(spec, t, acc, gyr, np.random.default_rng(seed))
        best = min(best, time.perf_counter() - start)
    return t.size / best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("n_samples", nargs="?", type=int, default=2_000_000, help="record length (default 2000000)")
    parser.add_argument("--worker-memory", action="store_true", help="malloc set as the runner's workers set it")
    args = parser.parse_args()
    if args.worker_memory:
        keep_freed_memory()
    n = args.n_samples
    t, acc, gyr = truth(n)
    memory = "the runner's worker memory setting" if args.worker_memory else "glibc's default malloc"
    print(f"apply_sensor on {n} samples at 800 Hz, one core (numpy {np.__version__}), {memory}")
    for spec in (get_preset("ideal"), get_preset("vn200"), get_preset("paper-vn200"), get_preset("bmi160"),
                 everything_on()):
        rate = samples_per_second(spec, t, acc, gyr)
        print(f"  {spec.name:12s} {rate / 1e6:7.2f} M samples/s  ({6 * rate / 1e6:7.1f} M channel values/s)")


if __name__ == "__main__":
    main()
