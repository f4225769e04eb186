"""What the loop sends to its worker processes comes back as itself: library effects by name, sensor specs
validated and read-only (the result's independence of the worker count: tests/test_loop_reproducible.py)."""

import pickle

import numpy as np
import pytest

from gaitsim.imu.presets import get_preset
from gaitsim.loop import attribution
from gaitsim.loop import effects as fx


@pytest.mark.parametrize("name", sorted(fx.BY_NAME))
def test_a_library_effect_is_pickled_as_the_library_entry(name):
    assert pickle.loads(pickle.dumps(fx.BY_NAME[name])) is fx.BY_NAME[name]


def test_a_sensor_spec_comes_back_equal_and_read_only():
    spec = get_preset("bmi160").replace(filter_order=1, filter_kind="analogue", accel_bandwidth=30.0)
    back = pickle.loads(pickle.dumps(spec))
    assert (back.name, back.source, back.filter_order, back.filter_kind, back.withheld) == (
        spec.name, spec.source, spec.filter_order, "analogue", spec.withheld)
    for key, value in spec.parameters.items():
        np.testing.assert_array_equal(back[key], value)
        assert not back[key].flags.writeable
    with pytest.raises(TypeError, match="immutable"):
        back.parameters["accel_bias"] = np.zeros(3)


def test_worker_count_must_be_positive():
    with pytest.raises(ValueError, match="workers = 0"):
        with attribution.Workers.started(0):
            pass
