"""Random numbers for the transport kernels: one independent xoroshiro128+ stream per task.

A stream is named by ``(seed, a, b)`` (e.g. run seed, incidence cell, task);
its 128-bit state is derived from the name with splitmix64, so the numbers a
task draws depend on nothing else — not on the thread that runs it nor on the
order in which tasks run.  With a 2^128 period, streams that start at random
points overlap with negligible probability.
"""

from __future__ import annotations

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
def uniform(state):
    """Next number of the stream, uniform on [0, 1) with 53 random bits (xoroshiro128+)."""
    s0 = state[0]
    s1 = state[1]
    result = s0 + s1
    s1 ^= s0
    state[0] = ((s0 << np.uint64(24)) | (s0 >> np.uint64(40))) ^ s1 ^ (s1 << np.uint64(16))
    state[1] = (s1 << np.uint64(37)) | (s1 >> np.uint64(27))
    return float(result >> np.uint64(11)) * _UNIT
