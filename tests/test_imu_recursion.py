"""The first-order recursion of the bias-instability nodes, compiled and reference, is scipy's lfilter, bit for bit."""

import numpy as np
import pytest
from scipy.signal import lfilter

from gaitsim.imu import kernels, model


@pytest.mark.parametrize("recursion", [kernels.first_order_recursion, model.first_order_recursion],
                         ids=["compiled", "reference"])
@pytest.mark.parametrize("decay", [0.0, 0.5, 0.999, 0.99999])
def test_recursion_equals_lfilter(decay, recursion):
    rng = np.random.default_rng(7)
    first, steps = rng.normal(size=3), rng.normal(size=(4000, 3))
    expected = np.concatenate([first[None, :], lfilter([1.0], [1.0, -decay], steps, axis=0,
                                                       zi=(decay * first)[None, :])[0]])
    np.testing.assert_array_equal(recursion(first, steps, decay), expected)
