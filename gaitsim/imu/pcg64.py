"""numpy's PCG64 bit generator in compiled code: the 32-bit words ``np.random.PCG64`` hands out, without a call
into numpy per word.

PCG64 (O'Neill, "PCG: A family of simple fast space-efficient statistically good algorithms for random number
generation", HMC-CS-2014-0905, 2014; numpy's default bit generator) is a 128-bit linear congruential generator,
``state <- state * a + increment (mod 2**128)`` with the multiplier ``a`` below, whose 64-bit output is the XSL-RR
function of the new state: its high and low halves xor-ed, rotated right by the top 6 bits of the state. numpy
hands out a 32-bit word as the low half of a 64-bit output and keeps the high half for the next word
(``has_uint32``, ``uinteger`` of the state dict). :func:`next_uint32` does the same on a copy of that state
held in a tuple of uint64 (:func:`words_of`, written back by :func:`store_words`), passed along from word to
word so that compiled code keeps it in registers, the 128-bit arithmetic in 64-bit halves:
``tests/test_imu_normals.py`` checks its words against ``BitGenerator.random_raw``, numpy's own ``next_uint32``
and numpy's normals, and the state it leaves against numpy's.

PCG64DXSM (another output function and multiplier) and the other bit generators are not covered: their words
come from their C functions (:func:`gaitsim.imu.normals.with_bit_words`).
"""

from __future__ import annotations

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

MULTIPLIER = 0x2360ED051FC65DA44385DF649FCCF645  # PCG's default 128-bit multiplier, numpy's for PCG64
_MASK64 = 2**64 - 1
_MULTIPLIER_HIGH = np.uint64(MULTIPLIER >> 64)
_MULTIPLIER_LOW = np.uint64(MULTIPLIER & _MASK64)


@intrinsic
def _multiply_high(typingctx, a, b):
    """The high 64 bits of the 128-bit product of two uint64 (one machine multiply)."""

    def codegen(context, builder, signature, args):
        wide = ir.IntType(128)
        product = builder.mul(builder.zext(args[0], wide), builder.zext(args[1], wide))
        return builder.trunc(builder.lshr(product, ir.Constant(wide, 64)), ir.IntType(64))

    return types.uint64(types.uint64, types.uint64), codegen


@njit(cache=True, inline="always")
def next_uint64(increment, high, low):
    """(64-bit output, high, low): the 128-bit state (``high``, ``low`` halves) advanced one step with the
    ``increment`` (high, low), and the XSL-RR output of the new state."""
    product_low = low * _MULTIPLIER_LOW
    product_high = _multiply_high(low, _MULTIPLIER_LOW) + low * _MULTIPLIER_HIGH + high * _MULTIPLIER_LOW
    low = product_low + increment[1]
    high = product_high + increment[0] + np.uint64(low < product_low)  # the carry of the low half
    rotation = high >> np.uint64(58)
    folded = high ^ low
    return (folded >> rotation) | (folded << ((np.uint64(64) - rotation) & np.uint64(63))), high, low


@njit(cache=True, inline="always")
def next_uint32(increment, state):
    """(word, state): numpy's next 32-bit word of PCG64 and the state after it; ``state`` is (high, low,
    has_uint32, uinteger) (:func:`words_of`). The word is the buffered high half of the last 64-bit output if
    there is one, else the low half of a new output, whose high half is buffered."""
    high, low, has_uint32, uinteger = state
    if has_uint32:
        return np.uint32(uinteger), (high, low, np.uint64(0), uinteger)
    output, high, low = next_uint64(increment, high, low)
    return np.uint32(output & np.uint64(0xFFFFFFFF)), (high, low, np.uint64(1), output >> np.uint64(32))


def words_of(bit_generator: np.random.PCG64) -> tuple[tuple, tuple]:
    """(increment, state) of a PCG64 for :func:`next_uint32`: the increment as uint64 (high, low) halves, the
    state as uint64 (high, low, has_uint32, uinteger)."""
    state = bit_generator.state
    value, increment = state["state"]["state"], state["state"]["inc"]
    halves = (np.uint64(increment >> 64), np.uint64(increment & _MASK64))
    return halves, (np.uint64(value >> 64), np.uint64(value & _MASK64), np.uint64(state["has_uint32"]),
                    np.uint64(state["uinteger"]))


def store_words(bit_generator: np.random.PCG64, increment: tuple, state: tuple) -> None:
    """Set the PCG64's state to ``state`` (see :func:`words_of`)."""
    high, low, has_uint32, uinteger = (int(v) for v in state)
    bit_generator.state = {"bit_generator": "PCG64",
                           "state": {"state": (high << 64) | low, "inc": (int(increment[0]) << 64) | int(increment[1])},
                           "has_uint32": has_uint32, "uinteger": uinteger}
