"""What the loop names on a blind walk and why: every residual it acted on with its candidates sorted by the misfit
they leave, next to the errors the simulated sensor really has (issue 12's blind table; the notes of the
2026-11-24 evening stop).

The sensor's errors are read from the same walk simulated with its parameters declared (``gaitsim.loop.blind`` runs
it with ``withhold = true``; the seed and the draws are the same): per axis, the least-squares scale (measured
minus true against true) and offset of the accelerometer and the gyro.

Run from the repository root::

    python3 -m studies.blind_candidates bmi160                    # the untouched walk (~1 min)
    python3 -m studies.blind_candidates bmi160 accel_scale_x      # a case of gaitsim.loop.blind.CASES
"""

from __future__ import annotations

import sys
import warnings

import numpy as np

from gaitsim.loop import blind, settings
from gaitsim.scenario import scenario_from_dict
from gaitsim.simulate import simulate_walk


def sensor_errors(sensor: str) -> dict:
    """Per-axis (scale - 1, offset) of the blind walk's accelerometer (m/s^2) and gyro (deg/s), from measured
    minus true."""
    doc = {"path": {"kind": "straight", "length_m": settings.BLIND_WALK_LENGTH_M},
           "sampling": {"rate_hz": settings.BLIND_RATE_HZ}, "sensor": {"preset": sensor}}
    rec = simulate_walk(scenario_from_dict(doc, f"<blind {sensor}, declared>"), seed=settings.BLIND_SEED)
    out = {}
    for name, measured, true, unit in (("accelerometer", rec.acc, rec.truth.acc, 1.0),
                                       ("gyro", rec.gyr, rec.truth.gyr, np.degrees(1.0))):
        fits = [np.linalg.lstsq(np.c_[true[:, i], np.ones(len(true))], measured[:, i] - true[:, i], rcond=None)[0]
                for i in range(3)]
        out[name] = {"scale_minus_1": [float(f[0]) for f in fits], "offset": [float(f[1] * unit) for f in fits]}
    return out


def main(argv: list[str]) -> None:
    source = argv[0] if argv else "bmi160"
    case = blind.BY_NAME[argv[1]] if len(argv) > 1 else None
    if source in blind.SENSORS:
        for name, errors in sensor_errors(source).items():
            unit = "m/s^2" if name == "accelerometer" else "deg/s"
            print(f"{source} {name}: scale - 1 {np.round(errors['scale_minus_1'], 5).tolist()}, "
                  f"offset {np.round(errors['offset'], 4).tolist()} {unit}")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = blind.run(source, case)
    print(f"\n{source}, {case.name if case else 'untouched'}: residual (z) -> effect, magnitude; candidates by misfit")
    for a in result.attributions:
        print(f"{a['residual']} (z {a['z_before']:.2f}) -> {a['effect']} {a.get('magnitude') or ''}")
        if a["effect"] == "unexplained":
            continue
        for c in sorted(a.get("candidates", []), key=lambda c: c["q_after"]):
            print(f"    {c['effect']:24s} {c['magnitude']:10.4f}  misfit {c['q_after']:9.1f}  "
                  f"explains {c['fraction_explained']:.2f}")


if __name__ == "__main__":
    main(sys.argv[1:])
