"""The compiled white noise (gaitsim.imu.normals, in the stochastic pass of gaitsim.imu.kernels) draws numpy's
float32 normals bit for bit and leaves the Generator where numpy leaves it: on random words of every numpy bit
generator, and on crafted words at every edge of the ziggurat (each layer's bound, the wedge tests next to
their decision, the tail)."""

import math

import numpy as np
import pytest

from gaitsim.imu.kernels import add_stochastic_terms
from gaitsim.imu.normals import ziggurat_tables

BIT_GENERATORS = (np.random.PCG64, np.random.PCG64DXSM, np.random.SFC64, np.random.Philox, np.random.MT19937)
BOUND, WIDTH, DENSITY = ziggurat_tables()


NO_NODES = (np.zeros((0, 3)), 1)


def add_white_noise(out, sample_std, rng):
    """The compiled pass with white noise alone."""
    add_stochastic_terms(out, out, NO_NODES, NO_NODES, np.asarray(sample_std, float), rng, 0.0, np.inf)


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
