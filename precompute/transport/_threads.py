"""Run numba's parallel kernels on a chosen number of threads, restoring the previous setting after."""

from __future__ import annotations

import contextlib

import numba


@contextlib.contextmanager
def numba_threads(count: int):
    previous = numba.get_num_threads()
    numba.set_num_threads(count)
    try:
        yield
    finally:
        numba.set_num_threads(previous)
