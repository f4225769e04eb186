"""The compiled first-order recursion of the bias-instability nodes is scipy's lfilter, bit for bit."""

import numpy as np
import pytest
from scipy.signal import lfilter

from gaitsim.imu.model import _first_order_recursion


@pytest.mark.parametrize("decay", [0.0, 0.5, 0.999, 0.99999])
def test_recursion_equals_lfilter(decay):
    rng = np.random.default_rng(7)
    first, steps = rng.normal(size=3), rng.normal(size=(4000, 3))
    expected = np.concatenate([first[None, :], lfilter([1.0], [1.0, -decay], steps, axis=0,
                                                       zi=(decay * first)[None, :])[0]])
    np.testing.assert_array_equal(_first_order_recursion(first, steps, decay), expected)
