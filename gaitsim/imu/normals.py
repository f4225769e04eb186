"""White noise from float32 standard normals, compiled: the draws of ``Generator.standard_normal(dtype=float32)``.

numpy draws a float32 standard normal with a 256-layer ziggurat (Marsaglia and Tsang, J. Stat. Softw. 5(8),
2000) on the 32-bit words of its bit generator. Called through ``Generator.standard_normal``, that costs
about 10 ns per normal here, most of it outside the bit generator and the ziggurat. :func:`add_white_noise`
runs the same ziggurat, with the same tables and the same float32 arithmetic, in compiled code (the IMU
model's stochastic pass, :mod:`gaitsim.imu.kernels`) that takes the words from the bit generator's own C
function (``BitGenerator.ctypes.next_uint32``): the normals are the ones numpy gives, bit for bit, and the
Generator is left in the state numpy leaves it in (``tests/test_imu_normals.py``), so a seeded run gives the
sensor output it gave before.

The ziggurat: a 23-bit magnitude ``m``, a sign bit and an 8-bit layer ``i`` are read from one 32-bit word;
``m * w[i]`` is returned when ``m < k[i]`` (about 99 % of draws); else the wedge of layer ``i`` is tested
against the density with one more uniform, or, in the base layer, the tail beyond ``r`` is drawn by
Marsaglia's exponential method. The tables follow Marsaglia and Tsang's recursion for 256 layers with the
tail start ``r`` and layer area ``v`` numpy uses.
"""

from __future__ import annotations

import math
from contextlib import contextmanager

import numpy as np
from numba import njit

LAYERS = 256
TAIL_START = 3.6541528853610088  # r: start of the tail of the base layer
LAYER_AREA = 0.00492867323399  # v: area of each layer (the base layer: rectangle plus tail)
MAGNITUDE_SCALE = 2.0**23  # a 23-bit magnitude


def ziggurat_tables() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(k, w, f): the acceptance bounds (uint32, in units of the 23-bit magnitude), the layer widths per unit
    magnitude (float32) and the density at each layer's edge (float32), computed in float64 by Marsaglia and
    Tsang's recursion and rounded once (bounds to the nearest integer)."""
    bound, width, density = np.zeros(LAYERS), np.zeros(LAYERS), np.zeros(LAYERS)
    x = TAIL_START
    base_width = LAYER_AREA / math.exp(-0.5 * x * x)
    bound[0] = x / base_width * MAGNITUDE_SCALE
    width[0], width[-1] = base_width / MAGNITUDE_SCALE, x / MAGNITUDE_SCALE
    density[0], density[-1] = 1.0, math.exp(-0.5 * x * x)
    for i in range(LAYERS - 2, 0, -1):
        inner = math.sqrt(-2.0 * math.log(LAYER_AREA / x + math.exp(-0.5 * x * x)))
        bound[i + 1] = inner / x * MAGNITUDE_SCALE
        x = inner
        density[i], width[i] = math.exp(-0.5 * x * x), x / MAGNITUDE_SCALE
    return np.round(bound).astype(np.uint32), width.astype(np.float32), density.astype(np.float32)


_BOUND, _WIDTH, _DENSITY = ziggurat_tables()  # compiled in as constants
_TAIL_START = np.float32(TAIL_START)
_INVERSE_TAIL_START = np.float32(1.0 / TAIL_START)
_UNIFORM_STEP = np.float32(1.0 / 16777216.0)  # 2**-24: a float32 uniform from the top 24 bits of a word


@njit(cache=True, inline="always")
def _layer_draw(word):
    """(layer, magnitude, x) of one 32-bit word: x = +-magnitude * width[layer] in float32."""
    layer = word & np.uint32(0xFF)
    magnitude = word >> np.uint32(9)
    # the sign as a factor of +-1 (exact): a branch on a random bit costs more than the whole draw
    sign = np.float32(1.0) - np.float32(2.0) * np.float32((word >> np.uint32(8)) & np.uint32(1))
    return layer, magnitude, np.float32(magnitude) * _WIDTH[layer] * sign


@njit(cache=True, inline="always")
def _uniform(next_uint32, state):
    """A float32 uniform in [0, 1) from the top 24 bits of the next 32-bit word."""
    return np.float32(next_uint32(state) >> np.uint32(8)) * _UNIFORM_STEP


@njit(cache=True)
def _rejected(next_uint32, state, layer, magnitude, x):
    """The normal whose first draw (layer, magnitude, x) fell outside its layer's rectangle: the wedge or
    tail test, then new draws until one is accepted."""
    while True:
        if layer == 0:  # the tail beyond r, by Marsaglia's exponential method (with this draw's sign)
            sign = np.float32(1.0) - np.float32(2.0) * np.float32((magnitude >> np.uint32(8)) & np.uint32(1))
            while True:
                excess = -_INVERSE_TAIL_START * np.float32(math.log1p(-_uniform(next_uint32, state)))
                exponential = -np.float32(math.log1p(-_uniform(next_uint32, state)))
                if exponential + exponential > excess * excess:
                    return (_TAIL_START + excess) * sign
        u = _uniform(next_uint32, state)  # the wedge of the layer
        if (_DENSITY[layer - 1] - _DENSITY[layer]) * u + _DENSITY[layer] < math.exp(-0.5 * float(x) * float(x)):
            return x
        layer, magnitude, x = _layer_draw(next_uint32(state))
        if magnitude < _BOUND[layer]:
            return x


@njit(cache=True, inline="always")
def standard_normal(next_uint32, state):
    """One float32 standard normal from the 32-bit words ``next_uint32(state)`` of a numpy bit generator
    (compiled code only; see :func:`bit_words`)."""
    layer, magnitude, x = _layer_draw(next_uint32(state))
    if magnitude >= _BOUND[layer]:  # about 1 % of draws
        x = _rejected(next_uint32, state, layer, magnitude, x)
    return x


@contextmanager
def bit_words(rng: np.random.Generator):
    """(next_uint32, state address) of the Generator's bit generator for :func:`standard_normal`, its lock
    held (as numpy holds it while it draws)."""
    bit_generator = rng.bit_generator
    interface = bit_generator.ctypes
    with bit_generator.lock:
        yield interface.next_uint32, interface.state_address

