"""Does the twin respond to a sensor error as the recording does? Issue 12's blind misses on the stride closure.

The loop fits a sensor effect's magnitude by adding it to the twin and matching the residuals (recording minus
twin). That reads the magnitude right only if the twin's residuals move with the effect as the recording's would:
the closure a scale or g-sensitivity error leaves depends on the specific force and rate history of the stride,
which the twin reproduces only as well as its gait-shape fit does.

For one blind walk (:mod:`gaitsim.loop.blind`) this prints, per error of :data:`ERRORS` and per stride-closure
residual, how much the error moves it

- on the recording: the error put into its IMU samples by the blind test's own numpy lines
  (:data:`gaitsim.loop.blind.CASES`), signature of the changed recording minus that of the untouched one;
- on its default twin: the library's effect at the same magnitude (the g-sensitivity without the gyro-bias
  re-balance the effect applies at rest, since the injection has none), simulated, minus the twin;

and their ratio. A ratio of r makes the loop's fit r times the injected magnitude (on top of what the untouched
recording's own errors already leave below the noise level: the untouched recording's residuals are printed
first, with their z).

Run from the repository root::

    python3 -m studies.effect_response paper-vn200      # ~1 min
    python3 -m studies.effect_response bmi160
"""

from __future__ import annotations

import dataclasses
import sys
import warnings

import numpy as np

from gaitsim.loop import attribution as att
from gaitsim.loop import blind
from gaitsim.loop import effects as fx
from gaitsim.loop import twin as tw

ERRORS = ("g_sensitivity", "accel_scale_x", "gyro_scale_y")  # blind cases whose library effect has the same form
CLOSURE = ("closure_forward", "closure_left", "closure_up", "closure_roll", "closure_pitch")


def twin_changes(name: str, magnitude: float, ctx: dict) -> dict:
    """The library effect ``name`` at ``magnitude`` as a change of the twin's scenario; the g-sensitivity without
    its rest re-balance of the gyro bias (the numpy injection adds k f at rest as well)."""
    if name == "g_sensitivity":
        matrix = np.asarray(ctx["gyro_g_sensitivity"]) + magnitude * np.eye(3)
        return {"sensor": {"gyro_g_sensitivity": [matrix.tolist(), "deg/s/(m/s^2)"]}}
    return fx.BY_NAME[name].changes(magnitude, ctx)


def main(argv: list[str]) -> None:
    sensor = argv[0] if argv else "paper-vn200"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rec, _, ref = att.prepare(blind.blind_recording(sensor, None))
        simulate = tw.TwinSimulator()
        measured = att.measure(rec, ref)
        twin = tw.fit_twin(rec, measured.signature, measured.solution, simulate)
        twin_side = att.simulate_side(simulate, twin, measured, False)
        ctx = fx.context(rec, twin.scenario, measured.signature, twin_side.signature)
        print(f"{sensor}, untouched walk: recording - default twin (residual / its stride standard error)")
        for name in CLOSURE:
            m, w = measured.signature.scalars[name], twin_side.signature.scalars[name]
            print(f"    {name:16s} {m.value - w.value:+.4g} ({(m.value - w.value) / np.hypot(m.se, w.se):+.2f})")
        for name in ERRORS:
            case = blind.BY_NAME[name]
            acc, gyr = case.inject(rec.t, rec.acc.copy(), rec.gyr.copy(), case.magnitude)
            changed = dataclasses.replace(rec, acc=np.asarray(acc, float), gyr=np.asarray(gyr, float))
            on_recording = att.measure(changed, ref, with_nav=False).signature.scalars
            effect_twin = tw.match_noise(twin.with_changes(twin_changes(name, case.expected, ctx)), simulate)
            on_twin = att.simulate_side(simulate, effect_twin, measured, False).signature.scalars
            print(f"\n{sensor}, {name} {case.magnitude} {case.unit}: change of each residual, recording | twin | ratio")
            for res in CLOSURE:
                d_rec = on_recording[res].value - measured.signature.scalars[res].value
                d_twin = on_twin[res].value - twin_side.signature.scalars[res].value
                print(f"    {res:16s} {d_rec:+.4g} | {d_twin:+.4g} | {d_rec / d_twin if d_twin else np.nan:.2f}")


if __name__ == "__main__":
    main(sys.argv[1:])
