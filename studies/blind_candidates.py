"""What the loop names on a blind walk and why: the default twin's residuals, and every residual the loop acted on
with its candidates sorted by the misfit they leave, next to the errors the simulated sensor really has (issue 12's
blind table; the notes of the 2026-11-24 evening stop).

The sensor's errors are read from the same walk simulated with its parameters declared (``gaitsim.loop.blind`` runs
it with ``withhold = true``; the seed and the draws are the same): per axis, the least-squares fit of measured minus
true on the true specific force (and, for the gyro, the true rate) and a constant: the scale error (the diagonal),
the offset and, for the gyro, the g-sensitivity's diagonal. The cross-axis terms are fitted but not printed.

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
    """Per axis, the scale error (1), offset (m/s^2 or deg/s) and, for the gyro, g-sensitivity (deg/s per m/s^2) of
    the blind walk's sensor, from measured minus true (module docstring)."""
    doc = {"path": {"kind": "straight", "length_m": settings.BLIND_WALK_LENGTH_M},
           "sampling": {"rate_hz": settings.BLIND_RATE_HZ}, "sensor": {"preset": sensor}}
    rec = simulate_walk(scenario_from_dict(doc, f"<blind {sensor}, declared>"), seed=settings.BLIND_SEED)
    ones = np.ones((len(rec.t), 1))
    acc = np.linalg.lstsq(np.hstack([rec.truth.acc, ones]), rec.acc - rec.truth.acc, rcond=None)[0]
    gyr = np.linalg.lstsq(np.hstack([rec.truth.gyr, rec.truth.acc, ones]), rec.gyr - rec.truth.gyr, rcond=None)[0]
    return {"accelerometer": {"scale_minus_1": np.diag(acc[:3]).tolist(), "offset": acc[3].tolist()},
            "gyro": {"scale_minus_1": np.diag(gyr[:3]).tolist(), "offset": np.degrees(gyr[6]).tolist(),
                     "g_sensitivity": np.degrees(np.diag(gyr[3:6])).tolist()}}


def main(argv: list[str]) -> None:
    source = argv[0] if argv else "bmi160"
    case = blind.BY_NAME[argv[1]] if len(argv) > 1 else None
    if source in blind.SENSORS:
        for name, errors in sensor_errors(source).items():
            unit = "m/s^2" if name == "accelerometer" else "deg/s"
            extra = (f", g-sensitivity {np.round(errors['g_sensitivity'], 5).tolist()} deg/s/(m/s^2)"
                     if "g_sensitivity" in errors else "")
            print(f"{source} {name}: scale - 1 {np.round(errors['scale_minus_1'], 5).tolist()}, "
                  f"offset {np.round(errors['offset'], 4).tolist()} {unit}{extra}")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = blind.run(source, case)
    label = case.name if case else "untouched"
    print(f"\n{source}, {label}: every residual of the default twin, recording minus twin +- uncertainty (z)")
    for r in result.residuals_before.values():
        z = r.value / r.uncertainty
        print(f"    {r.name:32s} {r.value:+11.4g} +- {r.uncertainty:<10.3g} {r.unit:8s} (z {z:+.2f})")
    print(f"\n{source}, {label}: residual (z) -> effect, magnitude; candidates by misfit")
    for a in result.attributions:
        print(f"{a['residual']} (z {a['z_before']:.2f}) -> {a['effect']} {a.get('magnitude') or ''}")
        if a["effect"] == "unexplained":
            continue
        for c in sorted(a.get("candidates", []), key=lambda c: c["q_after"]):
            print(f"    {c['effect']:24s} {c['magnitude']:10.4f}  misfit {c['q_after']:9.1f}  "
                  f"explains {c['fraction_explained']:.2f}")


if __name__ == "__main__":
    main(sys.argv[1:])
