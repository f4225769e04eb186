"""Compiled kernels of the IMU model (numba): the deterministic terms' sums, the stochastic terms, quantisation and
clipping in one pass, and the nodes of the bias-instability recursion.

:mod:`gaitsim.imu.model` uses them for long records, or when numba is already loaded; its numpy path is the
reference, and both give the same bits (``tests/test_imu_model.py``). This module is imported only then:
numba's first use in a process costs about half a second (its import and the loading of its registries),
more than a short record's whole sensor stage.
"""

from __future__ import annotations

import sys

import numpy as np
from numba import njit

from nav.compiled import kernel_array, key_cache_to_sources

from gaitsim.imu import normals, pcg64
from gaitsim.imu.normals import standard_normal, with_bit_words


@njit(cache=True, inline="always")
def _quantised(value, resolution, limit):
    """``value`` rounded to a multiple of ``resolution`` (0: off; halves to even, like np.round), then
    clipped at +-``limit`` (inf: off)."""
    if resolution > 0:
        value = np.round(value / resolution) * resolution
    return min(max(value, -limit), limit)


STOCHASTIC_BLOCK = 4096  # samples summed at a time (96 kB: the block stays in the core's cache)


@njit(cache=True)
def _fractions(node_step):
    """(node_step,) the interpolation fractions ``i / node_step``, divided as the numpy reference divides."""
    return np.arange(node_step) / node_step


@njit(cache=True)
def _add_interpolated(block, nodes, fractions, node, offset):
    """block[k] += linear interpolation of ``nodes`` (J, 3), spaced ``node_step`` samples, at the samples of
    the block, the first of which lies ``offset`` samples after node ``node``; returns (node, offset) of the
    sample after the block. ``fractions`` (node_step,) holds ``i / node_step`` (:func:`_fractions`). The
    reference's arithmetic per sample, ``before + (i / node_step) (after - before)`` with ``i`` the sample's offset
    from its node, taken one node interval at a time: the interval's differences once, then a loop over its
    samples without a division or a branch."""
    node_step = fractions.shape[0]
    k = 0
    while k < block.shape[0]:
        run = min(block.shape[0] - k, node_step - offset)
        before_x, before_y, before_z = nodes[node, 0], nodes[node, 1], nodes[node, 2]
        change_x = nodes[node + 1, 0] - before_x
        change_y = nodes[node + 1, 1] - before_y
        change_z = nodes[node + 1, 2] - before_z
        for i in range(run):
            fraction = fractions[offset + i]
            block[k + i, 0] += before_x + fraction * change_x
            block[k + i, 1] += before_y + fraction * change_y
            block[k + i, 2] += before_z + fraction * change_z
        k += run
        offset += run
        if offset == node_step:
            node, offset = node + 1, 0
    return node, offset


@njit(cache=True)
def _add_stochastic_terms(out, signal, summand, offsets, instability_nodes, instability_step, walk_nodes,
                          walk_step, white_std, resolution, limit, generator, state):
    """``out`` (n, 3) = ``signal`` (n, 3; none when it has no rows: ``out`` holds it already) + ``summand`` (n, 3;
    none when it has no rows) + each row of ``offsets`` (K, 3) per axis in turn (the deterministic terms' sums) +
    bias instability + random walk (each linearly interpolated between its nodes, spaced ``*_step`` samples; none
    when it has no nodes) + white noise of std ``white_std`` (3,) (none when all zero), then quantisation and
    clipping (``resolution`` 0 and ``limit`` inf: none). Each sum is rounded in this order, as separate passes
    over the arrays would round it; the terms are added to ``out`` a cache-sized block at a time, each in its own
    simple loop. The normals are drawn from the bit generator (``generator``, ``state``: see
    :func:`gaitsim.imu.normals.with_bit_words`); returns its state after them."""
    white = white_std[0] != 0.0 or white_std[1] != 0.0 or white_std[2] != 0.0
    finish = resolution > 0.0 or limit < np.inf
    instability_at = walk_at = (0, 0)  # (node before the block's first sample, its offset from that node)
    instability_fractions, walk_fractions = _fractions(instability_step), _fractions(walk_step)
    for start in range(0, out.shape[0], STOCHASTIC_BLOCK):
        stop = min(out.shape[0], start + STOCHASTIC_BLOCK)
        block = out[start:stop]  # the terms are summed where they end, a cache-sized block at a time
        if signal.shape[0]:
            block[:] = signal[start:stop]
        if summand.shape[0]:
            block += summand[start:stop]
        for offset in offsets:
            for k in range(block.shape[0]):
                for c in range(3):
                    block[k, c] += offset[c]
        if instability_nodes.shape[0]:
            instability_at = _add_interpolated(block, instability_nodes, instability_fractions, *instability_at)
        if walk_nodes.shape[0]:
            walk_at = _add_interpolated(block, walk_nodes, walk_fractions, *walk_at)
        if white:
            for k in range(block.shape[0]):
                for c in range(3):
                    normal, state = standard_normal(generator, state)
                    block[k, c] += float(normal) * white_std[c]
        if finish:
            for k in range(block.shape[0]):
                for c in range(3):
                    block[k, c] = _quantised(block[k, c], resolution, limit)
    return state


@njit(cache=True)
def quantise_and_clip(x, resolution, limit):
    """Round ``x`` (n, 3) to multiples of ``resolution`` (0: off), then clip at +-``limit`` (inf: off); in place."""
    for k in range(x.shape[0]):
        for c in range(3):
            x[k, c] = _quantised(x[k, c], resolution, limit)


@njit(cache=True)
def first_order_recursion(first: np.ndarray, steps: np.ndarray, decay: float) -> np.ndarray:
    """(J+1, 3) nodes of the recursion nodes[0] = first, nodes[j+1] = decay nodes[j] + steps[j] (``steps`` (J, 3)):
    the arithmetic of scipy's ``lfilter([1], [1, -decay], steps, zi=decay * first)`` after ``first``."""
    nodes = np.empty((steps.shape[0] + 1, 3))
    nodes[0] = first
    for j in range(steps.shape[0]):
        for c in range(3):
            nodes[j + 1, c] = decay * nodes[j, c] + steps[j, c]
    return nodes


_NO_ROWS = np.zeros((0, 3))  # an (n, 3) input left out: no summand, or no signal (``out`` holds it)


def add_stochastic_terms(out, signal, addends, instability, walk, white_std, rng, resolution, limit) -> None:
    """``out`` = ``signal`` + each of ``addends`` in turn (:func:`nav.calibration.add_in_order`: an (n, 3) array
    first, then numbers or (3,) vectors) + bias instability + random walk (each ``(nodes, node_step)``; no nodes:
    off) + white noise of per-axis std ``white_std`` drawn from ``rng``, then quantised and clipped (see
    :func:`_add_stochastic_terms`); ``out`` may be ``signal``."""
    summand = _NO_ROWS
    if addends and np.ndim(addends[0]) == 2:
        summand, addends = addends[0], addends[1:]
    if any(np.ndim(addend) == 2 for addend in addends):
        raise ValueError("an (n, 3) addend must come first")
    offsets = np.array([np.broadcast_to(np.asarray(addend, float), 3) for addend in addends]).reshape(-1, 3)
    signal = _NO_ROWS if signal is out else kernel_array(signal, float)  # one compiled type
    summand = kernel_array(summand, float)
    with_bit_words(rng, _add_stochastic_terms, out, signal, summand, offsets, *instability, *walk,
                   np.asarray(white_std, float), resolution, limit)


key_cache_to_sources([pcg64, normals, sys.modules[__name__]])  # this pass inlines the other two modules' code
