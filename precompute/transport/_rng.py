"""Random numbers for the transport kernels: one independent xoroshiro128+ stream per task.

A stream is named by ``(seed, a, b)`` (e.g. run seed, incidence cell, task);
its 128-bit state is derived from the name with splitmix64, so the numbers a
task draws depend on nothing else — not on the thread that runs it nor on the
order in which tasks run.  With a 2^128 period, streams that start at random
points overlap with negligible probability.

Free paths are drawn from the unit exponential by the ziggurat method (Marsaglia & Tsang 2000,
"The ziggurat method for generating random variables", J. Stat. Softw. 5(8)): 256 layers of equal
area under e^{−x}; a draw picks a layer and a point in it from one 64-bit number and is accepted
at once, without a logarithm, 98.9 % of the time.  The rest is the exact rejection step, so the
numbers are exactly exponential.
"""

from __future__ import annotations

import math

import numba
import numpy as np

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_MIX1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX2 = np.uint64(0x94D049BB133111EB)
_SALT = np.uint64(0xD1B54A32D192ED03)
_UNIT = 1.0 / 9007199254740992.0  # 2^-53


@numba.njit(cache=True)
def splitmix64(x):
    """The splitmix64 finaliser of ``x + golden``: a bijective hash of a 64-bit word."""
    z = np.uint64(x) + _GOLDEN
    z = (z ^ (z >> np.uint64(30))) * _MIX1
    z = (z ^ (z >> np.uint64(27))) * _MIX2
    return z ^ (z >> np.uint64(31))


@numba.njit(cache=True)
def seed_stream(state, seed, a, b):
    """Set the 2-word ``state`` to the start of stream ``(seed, a, b)`` (all non-negative integers)."""
    h = splitmix64(np.uint64(seed))
    h = splitmix64(h ^ (np.uint64(a) * _SALT))
    h = splitmix64(h ^ (np.uint64(b) * _GOLDEN))
    state[0] = splitmix64(h)
    state[1] = splitmix64(state[0] ^ _SALT)
    if state[0] == np.uint64(0) and state[1] == np.uint64(0):
        state[1] = _GOLDEN


@numba.njit(cache=True, inline="always")
def _next_bits(state):
    """The stream's next 53 random bits, as an integer below 2^53 (xoroshiro128+; its low bits, the
    weakest, are dropped)."""
    s0 = state[0]
    s1 = state[1]
    result = s0 + s1
    s1 ^= s0
    state[0] = ((s0 << np.uint64(24)) | (s0 >> np.uint64(40))) ^ s1 ^ (s1 << np.uint64(16))
    state[1] = (s1 << np.uint64(37)) | (s1 >> np.uint64(27))
    return result >> np.uint64(11)


@numba.njit(cache=True, inline="always")
def uniform(state):
    """Next number of the stream, uniform on [0, 1) with 53 random bits."""
    return float(_next_bits(state)) * _UNIT


#: The exponential ziggurat: the right edge of its base layer (whose tail goes on to infinity) and the
#: common area of the layers (Marsaglia & Tsang 2000, 256 layers).
_ZIGGURAT_R = 7.69711747013104972
_ZIGGURAT_AREA = 3.949659822581572e-3
#: A draw's 53 bits: the low 8 pick one of the 256 layers, the 45 above them the point in it.
_LAYER_BITS = 8
_LAYERS = 2**_LAYER_BITS
_POINT_SCALE = float(2 ** (53 - _LAYER_BITS))


def _exponential_ziggurat():
    """Per layer i: ``threshold[i]`` (below it a point lies under e^{−x} for sure), ``width[i]`` (the
    layer's right edge per unit of the point's integer) and ``height[i]`` = e^{−x_i}.  Layer 0 is the
    base, with the tail; layer 1 the top one (its inner edge is x = 0)."""
    threshold = np.zeros(_LAYERS, dtype=np.uint64)
    width = np.zeros(_LAYERS)
    height = np.zeros(_LAYERS)
    edge = _ZIGGURAT_R
    base = _ZIGGURAT_AREA / math.exp(-edge)  # the base layer's width as a rectangle of the common area
    threshold[0] = np.uint64(edge / base * _POINT_SCALE)
    width[0] = base / _POINT_SCALE
    width[-1] = edge / _POINT_SCALE
    height[0] = 1.0
    height[-1] = math.exp(-edge)
    outer = edge
    for i in range(_LAYERS - 2, 0, -1):
        edge = -math.log(_ZIGGURAT_AREA / edge + math.exp(-edge))
        threshold[i + 1] = np.uint64(edge / outer * _POINT_SCALE)
        outer = edge
        height[i] = math.exp(-edge)
        width[i] = edge / _POINT_SCALE
    return threshold, width, height


_ZIGGURAT_THRESHOLD, _ZIGGURAT_WIDTH, _ZIGGURAT_HEIGHT = _exponential_ziggurat()


@numba.njit(cache=True, inline="always")
def exponential(state):
    """Next number of the stream drawn from the unit exponential density e^{−x}, x ≥ 0."""
    while True:
        bits = _next_bits(state)
        layer = bits & np.uint64(_LAYERS - 1)
        point = bits >> np.uint64(_LAYER_BITS)
        x = float(point) * _ZIGGURAT_WIDTH[layer]
        if point < _ZIGGURAT_THRESHOLD[layer]:
            return x
        if layer == 0:  # the tail beyond R is R plus an exponential
            return _ZIGGURAT_R - math.log(1.0 - uniform(state))
        top = _ZIGGURAT_HEIGHT[layer - 1]
        bottom = _ZIGGURAT_HEIGHT[layer]
        if bottom + (top - bottom) * uniform(state) < math.exp(-x):
            return x
