"""The compiled white noise (gaitsim.imu.normals, in the stochastic pass of gaitsim.imu.kernels) draws numpy's
float32 normals bit for bit and leaves the Generator where numpy leaves it: on random words of every numpy bit
generator (PCG64's drawn by the compiled twin of gaitsim.imu.pcg64, whose words and state are also checked
against numpy's own), and on crafted words at every edge of the ziggurat (each layer's bound, the wedge tests
next to their decision, the tail)."""

import math

import numpy as np
import pytest
from numba import njit

from gaitsim.imu import pcg64
from gaitsim.imu.kernels import add_stochastic_terms
from gaitsim.imu.normals import next_uint32, with_bit_words, ziggurat_tables

BIT_GENERATORS = (np.random.PCG64, np.random.PCG64DXSM, np.random.SFC64, np.random.Philox, np.random.MT19937)
BOUND, WIDTH, DENSITY = ziggurat_tables()


NO_NODES = (np.zeros((0, 3)), 1)


def add_white_noise(out, sample_std, rng):
    """The compiled pass with white noise alone."""
    add_stochastic_terms(out, out, (), NO_NODES, NO_NODES, np.asarray(sample_std, float), rng, 0.0, np.inf)


def numpy_noise(n, sample_std, rng):
    return rng.standard_normal((n, 3), dtype=np.float32) * np.asarray(sample_std)


@pytest.mark.parametrize("bit_generator", BIT_GENERATORS, ids=lambda b: b.__name__)
@pytest.mark.parametrize("n", [1, 2, 7, 40_000])
@pytest.mark.parametrize("half_word_left", [False, True])
def test_equals_numpy_draws_and_state(bit_generator, n, half_word_left):
    sample_std = np.array([0.5, 1.0, 3.0e-3])
    ours, theirs = np.random.Generator(bit_generator(n)), np.random.Generator(bit_generator(n))
    if half_word_left:  # an odd number of 32-bit words drawn before: half a 64-bit output is buffered
        ours.random(dtype=np.float32), theirs.random(dtype=np.float32)
    out = np.full((n, 3), 2.0)
    add_white_noise(out, sample_std, ours)
    assert np.array_equal(out, 2.0 + numpy_noise(n, sample_std, theirs))
    assert str(ours.bit_generator.state) == str(theirs.bit_generator.state)
    assert ours.random() == theirs.random()


@njit  # not cached: it inlines the package's generator, and a test must run the code as it is now
def _compiled_words(count, generator, state):
    """(count 32-bit words, state after them) from ``next_uint32``."""
    words = np.empty(count, np.uint32)
    for i in range(count):
        words[i], state = next_uint32(generator, state)
    return words, state


@njit  # not cached (as _compiled_words)
def _compiled_raw(count, increment, state):
    """``count`` 64-bit outputs of the compiled PCG64 and its (high, low) state after them."""
    high, low = state[0], state[1]
    outputs = np.empty(count, np.uint64)
    for i in range(count):
        outputs[i], high, low = pcg64.next_uint64(increment, high, low)
    return outputs, (high, low, state[2], state[3])


@pytest.mark.parametrize("seed", [0, 1, 2, 12345, 2**63 + 7, 2**127 + 3])
def test_compiled_pcg64_outputs_equal_random_raw_and_leave_its_state(seed):
    ours, theirs = np.random.PCG64(seed), np.random.PCG64(seed)
    increment, state = pcg64.words_of(ours)
    outputs, state = _compiled_raw(1001, increment, state)
    pcg64.store_words(ours, increment, state)
    assert np.array_equal(outputs, theirs.random_raw(1001))
    assert ours.state == theirs.state


@pytest.mark.parametrize("count", [1, 2, 7, 1000, 1001])
@pytest.mark.parametrize("seed", range(8))
def test_compiled_pcg64_words_equal_numpys_c_function_and_leave_its_state(seed, count):
    """The 32-bit words, buffered high halves included, against numpy's own ``next_uint32``, from a state
    with and without a buffered half."""
    ours, theirs = np.random.PCG64(seed), np.random.PCG64(seed)
    theirs_next = theirs.ctypes.next_uint32
    for start in range(2):  # with a buffered half word at the second pass
        increment, state = pcg64.words_of(ours)
        words, state = _compiled_words(count + start, increment, state)
        pcg64.store_words(ours, increment, state)
        expected = [theirs_next(theirs.ctypes.state_address) for _ in range(count + start)]
        assert words.tolist() == expected
        assert ours.state == theirs.state


def test_only_plain_pcg64_takes_the_compiled_generator():
    """PCG64DXSM and a subclass of PCG64 keep their C function (their words may differ from PCG64's)."""

    class Sub(np.random.PCG64):
        pass

    seen = []
    for bit_generator in (np.random.PCG64(1), np.random.PCG64DXSM(1), Sub(1)):
        with_bit_words(np.random.Generator(bit_generator), lambda generator, state: seen.append(generator) or state)
    assert isinstance(seen[0], tuple) and not isinstance(seen[1], tuple) and not isinstance(seen[2], tuple)


def test_equals_numpy_on_a_long_stream_with_thousands_of_tail_draws():
    n = 3_000_000  # 9 M normals: ~2,000 from the tail, ~90,000 wedge tests
    out = np.zeros((n, 3))
    add_white_noise(out, np.ones(3), np.random.default_rng(2026))
    reference = np.random.default_rng(2026).standard_normal((n, 3), dtype=np.float32)
    assert np.array_equal(out, reference)
    assert np.abs(reference).max() > 3.6541528853610088  # the tail was reached


def _untemper(y: int) -> int:
    """MT19937's state word whose tempered output is ``y``."""
    y ^= y >> 18
    y ^= (y << 15) & 0xEFC60000
    x = y
    for _ in range(5):
        x = y ^ ((x << 7) & 0x9D2C5680)
    y = x & 0xFFFFFFFF
    x = y
    for _ in range(3):
        x = y ^ (x >> 11)
    return x & 0xFFFFFFFF


def _fed(words) -> np.random.Generator:
    """A Generator whose next 32-bit words are ``words`` (at most 624): MT19937 with a crafted state."""
    bit_generator = np.random.MT19937(0)
    key = np.zeros(624, np.uint32)
    key[: len(words)] = [_untemper(int(w)) for w in words]
    state = bit_generator.state
    state["state"] = {"key": key, "pos": 0}
    bit_generator.state = state
    return np.random.Generator(bit_generator)


def _word(layer: int, magnitude: int, negative: bool = False) -> int:
    return (int(magnitude) << 9) | (int(negative) << 8) | layer


def _uniform_word(u: float) -> int:
    return min(int(u * 2**24), 2**24 - 1) << 8


def _crafted_cases():
    """Word sequences, each starting one normal: the rectangle bounds of every layer, wedge tests at both
    sides of their decision, tail draws; a filler word (accepted at once) ends each."""
    filler = _word(7, 1)
    cases = []
    for layer in range(256):
        for magnitude in {0, 1, int(BOUND[layer]) - 1, int(BOUND[layer]), int(BOUND[layer]) + 1, 2**23 - 1}:
            if 0 <= magnitude < 2**23:
                for negative in (False, True):
                    cases.append([_word(layer, magnitude, negative), filler, filler, filler])
        if layer == 0:
            continue
        for magnitude in (int(BOUND[layer]), (int(BOUND[layer]) + 2**23) // 2, 2**23 - 1):
            if magnitude < int(BOUND[layer]) or magnitude >= 2**23:
                continue
            x = float(np.float32(magnitude) * WIDTH[layer])
            gap = float(DENSITY[layer - 1] - DENSITY[layer])
            u_decision = (math.exp(-0.5 * x * x) - float(DENSITY[layer])) / gap if gap else 0.5
            for step in range(-3, 4):  # the 24-bit uniforms next to the decision of the wedge test
                u_word = (int(np.clip(u_decision, 0.0, 1.0) * 2**24) + step) % 2**24 << 8
                cases.append([_word(layer, magnitude), u_word, filler, filler])
    for magnitude in (int(BOUND[0]), 2**23 - 1):  # the tail: accepted, rejected then accepted
        for u1, u2 in ((0.5, 0.5), (0.9, 0.001), (1e-7, 0.999), (0.999999, 0.2)):
            cases.append([_word(0, magnitude), _uniform_word(u1), _uniform_word(u2), _uniform_word(0.3),
                          _uniform_word(0.9), filler, filler])
    return cases


def test_equals_numpy_at_every_edge_of_the_ziggurat():
    cases = _crafted_cases()
    assert len(cases) > 3000
    for words in cases:
        out = np.zeros((1, 3))
        ours, theirs = _fed(words), _fed(words)
        add_white_noise(out, np.ones(3), ours)
        assert np.array_equal(out, numpy_noise(1, np.ones(3), theirs)), words
        assert ours.bit_generator.state["state"]["pos"] == theirs.bit_generator.state["state"]["pos"], words


def test_tables_follow_the_ziggurat_laws():
    bound, width, density = (t.astype(float) for t in ziggurat_tables())
    edges = width * 2**23  # layer edges x_i (the base layer: v / f(r))
    assert edges[-1] == pytest.approx(3.6541528853610088) and np.all(np.diff(edges[1:]) > 0)
    np.testing.assert_allclose(density[1:], np.exp(-0.5 * edges[1:] ** 2), rtol=1e-6)
    # every layer has the same area v: x_i (f(x_{i-1}) - f(x_i)), the base x_0 f(r)
    areas = edges[1:] * (density[:-1] - density[1:])
    np.testing.assert_allclose(areas, 0.00492867323399, rtol=3e-5)  # float32 densities
    np.testing.assert_allclose(bound[2:], np.round(edges[1:-1] / edges[2:] * 2**23), atol=1)
