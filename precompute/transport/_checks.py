"""Checks of user input shared by the transport modules; each raises ParameterError naming the input."""

from __future__ import annotations

import math

import numba
import numpy as np

from precompute.errors import ParameterError


def integer_at_least(name: str, value, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ParameterError(name, value, f"an integer ≥ {minimum}")
    return int(value)


def positive_length(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) or not (
        math.isfinite(value) and value > 0
    ):
        raise ParameterError(name, value, "a finite length > 0 (mm)")
    return float(value)


def refractive_index(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) or not (
        math.isfinite(value) and value >= 1.0
    ):
        raise ParameterError(name, value, "a real refractive index ≥ 1")
    return float(value)


def seed_value(value) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 0 <= value < 2**63:
        raise ParameterError("seed", value, "an integer in [0, 2^63)")
    return int(value)


def thread_count(value) -> int:
    """Threads for a numba kernel: ``None`` means all that numba was started with."""
    limit = numba.config.NUMBA_NUM_THREADS
    if value is None:
        return limit
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 1 <= value <= limit:
        raise ParameterError("threads", value, f"an integer in 1 … {limit}")
    return int(value)
