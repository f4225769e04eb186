"""White noise from float32 standard normals, compiled: the draws of ``Generator.standard_normal(dtype=float32)``.

numpy draws a float32 standard normal with a 256-layer ziggurat (Marsaglia and Tsang, J. Stat. Softw. 5(8),
2000) on the 32-bit words of its bit generator. Called through ``Generator.standard_normal``, that costs
about 10 ns per normal here, most of it outside the bit generator and the ziggurat. :func:`standard_normal`
runs the same ziggurat, with the same tables and the same float32 arithmetic, in compiled code (the IMU
model's stochastic pass, :mod:`gaitsim.imu.kernels`) on the same 32-bit words: a PCG64's (numpy's default)
from its compiled twin (:mod:`gaitsim.imu.pcg64`), any other bit generator's from its own C function
(``BitGenerator.ctypes.next_uint32``). The normals are the ones numpy gives, bit for bit, and the Generator is
left in the state numpy leaves it in (``tests/test_imu_normals.py``), so a seeded run gives the sensor output
it gave before.

The ziggurat: a 23-bit magnitude ``m``, a sign bit and an 8-bit layer ``i`` are read from one 32-bit word;
``m * w[i]`` is returned when ``m < k[i]`` (about 99 % of draws); else the wedge of layer ``i`` is tested
against the density with one more uniform, or, in the base layer, the tail beyond ``r`` is drawn by
Marsaglia's exponential method. The tables follow Marsaglia and Tsang's recursion for 256 layers with the
tail start ``r`` and layer area ``v`` numpy uses.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, types
from numba.extending import overload

from gaitsim.imu import pcg64

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


def next_uint32(generator, state):
    """(word, state): the next 32-bit word of a bit generator and its state after it, in compiled code:
    ``generator`` is the bit generator's C function ``next_uint32`` and ``state`` its state address (which does
    not change), or a PCG64's increment and state (:mod:`gaitsim.imu.pcg64`); see :func:`with_bit_words`."""
    raise NotImplementedError("compiled code only")


@overload(next_uint32)
def _next_uint32(generator, state):
    if isinstance(generator, types.ExternalFunctionPointer):
        def from_c_function(generator, state):
            return generator(state), state

        return from_c_function

    def from_pcg64(generator, state):
        return pcg64.next_uint32(generator, state)

    return from_pcg64


@njit(cache=True, inline="always")
def _uniform(generator, state):
    """(u, state): a float32 uniform in [0, 1) from the top 24 bits of the next 32-bit word."""
    word, state = next_uint32(generator, state)
    return np.float32(word >> np.uint32(8)) * _UNIFORM_STEP, state


@njit(cache=True)
def _rejected(generator, state, layer, magnitude, x):
    """(normal, state): the normal whose first draw (layer, magnitude, x) fell outside its layer's rectangle:
    the wedge or tail test, then new draws until one is accepted."""
    while True:
        if layer == 0:  # the tail beyond r, by Marsaglia's exponential method (with this draw's sign)
            sign = np.float32(1.0) - np.float32(2.0) * np.float32((magnitude >> np.uint32(8)) & np.uint32(1))
            while True:
                u, state = _uniform(generator, state)
                excess = -_INVERSE_TAIL_START * np.float32(math.log1p(-u))
                u, state = _uniform(generator, state)
                exponential = -np.float32(math.log1p(-u))
                if exponential + exponential > excess * excess:
                    return (_TAIL_START + excess) * sign, state
        u, state = _uniform(generator, state)  # the wedge of the layer
        if (_DENSITY[layer - 1] - _DENSITY[layer]) * u + _DENSITY[layer] < math.exp(-0.5 * float(x) * float(x)):
            return x, state
        word, state = next_uint32(generator, state)
        layer, magnitude, x = _layer_draw(word)
        if magnitude < _BOUND[layer]:
            return x, state


@njit(cache=True, inline="always")
def standard_normal(generator, state):
    """(normal, state): one float32 standard normal from the 32-bit words of a numpy bit generator and the
    generator's state after it (compiled code only; see :func:`with_bit_words`)."""
    word, state = next_uint32(generator, state)
    layer, magnitude, x = _layer_draw(word)
    if magnitude >= _BOUND[layer]:  # about 1 % of draws
        x, state = _rejected(generator, state, layer, magnitude, x)
    return x, state


def with_bit_words(rng: np.random.Generator, kernel, *arguments):
    """``kernel(*arguments, generator, state)`` (compiled; it draws with :func:`standard_normal` and returns the
    state after its last draw) run on the Generator's bit generator, its lock held (as numpy holds it while it
    draws): a PCG64 (numpy's default) as compiled code on a copy of its state, stored back afterwards, any other
    through its C function ``next_uint32``."""
    bit_generator = rng.bit_generator
    with bit_generator.lock:
        if type(bit_generator) is np.random.PCG64:
            increment, state = pcg64.words_of(bit_generator)
            pcg64.store_words(bit_generator, increment, kernel(*arguments, increment, state))
        else:
            interface = bit_generator.ctypes
            kernel(*arguments, interface.next_uint32, interface.state_address)
