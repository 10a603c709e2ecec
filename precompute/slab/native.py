"""A Henyey–Greenstein slab through the native slab library: the slab command without numba or NumPy.

The library (:mod:`precompute.transport.native`, built by ``make setup``) holds the numba kernel's own
slab task and result, compiled ahead of time.  Its tasks draw from the same random streams and tally
as :func:`precompute.transport.simulate_hg_slab` does, so it gives the same answer bit for bit
(``tests/test_native_slab.py``); a process that runs it imports neither numba nor NumPy, which is most
of a short slab run's time (docs/transport.md, "Beside MCML").  Its functions release the GIL (ctypes),
so the tasks run on as many Python threads as asked.

The library is named by the digest of the transport's sources (:mod:`precompute.cache.kernel_sources`): after
a change of them :func:`load_library` finds none until it is built again, and the slab command falls
back to numba.
"""

from __future__ import annotations

import ctypes
import os
import pathlib
import sys
import threading

from precompute.errors import ParameterError
from precompute.cache.kernel_sources import PACKAGE_ROOT, sources_digest
from precompute.slab.layout import SLAB_RESULTS, SLAB_TALLY_ROWS, SLAB_TASKS, task_paths

#: The library's functions (:mod:`precompute.transport.native`).
TASKS_FUNCTION = "clothlight_hg_slab_tasks"
RESULTS_FUNCTION = "clothlight_slab_results"
#: Doubles of scratch that a thread hands to the tasks function.
WORK_DOUBLES = 64
#: The library's file names, one per digest of the sources.
LIBRARY_PATTERN = "clothlight_slab-*.so"

_DOUBLES, _INT64S = ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_int64)
# numba's calling convention: a status, then pointers to the return value and to an exception's record
_CALL = [ctypes.c_void_p, ctypes.c_void_p]
_ARGUMENTS = {
    TASKS_FUNCTION: _CALL + [ctypes.c_int64, ctypes.c_int64, _INT64S, ctypes.c_uint64, ctypes.c_double, ctypes.c_double,
                             ctypes.c_double, ctypes.c_double, _DOUBLES, _INT64S, _DOUBLES,
                             ctypes.POINTER(ctypes.c_uint64), ctypes.POINTER(ctypes.c_int32)],
    RESULTS_FUNCTION: _CALL + [_DOUBLES, ctypes.c_int64, ctypes.c_double, _DOUBLES],
}


def library_folder() -> pathlib.Path:
    """Where the library is kept: beside numba's cache of the transport kernels (``NUMBA_CACHE_DIR`` where
    it is set, else the transport's ``__pycache__``)."""
    cache = os.environ.get("NUMBA_CACHE_DIR")
    return pathlib.Path(cache) if cache else PACKAGE_ROOT / "transport" / "__pycache__"


def library_path(digest: str | None = None, folder: str | os.PathLike | None = None) -> pathlib.Path:
    """The library built from the sources of ``digest`` (default: the sources as they are), in ``folder``
    (default :func:`library_folder`)."""
    folder = pathlib.Path(folder) if folder is not None else library_folder()
    return folder / LIBRARY_PATTERN.replace("*", (digest or sources_digest())[:16])


def load_library(path: str | os.PathLike | None = None) -> ctypes.CDLL | None:
    """The library at ``path`` (default :func:`library_path`), its functions typed; None where there is none."""
    path = pathlib.Path(path) if path is not None else library_path()
    if not path.is_file():
        return None
    library = ctypes.CDLL(str(path))
    for name, arguments in _ARGUMENTS.items():
        function = getattr(library, name)
        function.argtypes, function.restype = arguments, ctypes.c_int32
    return library


def available_threads() -> int:
    """The threads numba starts with, without importing it: ``NUMBA_NUM_THREADS``, else the CPUs this
    process may run on (numba's own default)."""
    if os.environ.get("NUMBA_NUM_THREADS"):
        return int(os.environ["NUMBA_NUM_THREADS"])
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def simulate_hg_slab_native(library: ctypes.CDLL, albedo: float, g: float, tau: float, index: float, *,
                            paths: int, seed: int, threads: int | None = None) -> dict:
    """:func:`precompute.transport.simulate_hg_slab` (one wavelength, μt = 1/mm) through ``library``
    (:func:`load_library`): its ``SlabResult.summary()``, the same numbers bit for bit.

    The optical inputs are taken as the slab command's argument types checked them
    (:mod:`precompute.bounds`); ``threads`` (default all: :func:`available_threads`) run the
    :data:`SLAB_TASKS` tasks in contiguous shares.
    """
    limit = available_threads()
    threads = limit if threads is None else threads
    if isinstance(threads, bool) or not isinstance(threads, int) or not 1 <= threads <= limit:
        raise ParameterError("threads", threads, f"an integer in 1 … {limit}")
    counts = (ctypes.c_int64 * SLAB_TASKS)(*task_paths(paths))
    sums = (ctypes.c_double * (SLAB_TASKS * SLAB_TALLY_ROWS))()
    events = (ctypes.c_int64 * SLAB_TASKS)()
    statuses = []
    stop = threading.Event()

    def run_tasks(first: int, count: int) -> None:
        # One task a call: between calls the main thread takes a Ctrl-C and the others see `stop`.
        work, state, alias = (ctypes.c_double * WORK_DOUBLES)(), (ctypes.c_uint64 * 2)(), (ctypes.c_int32 * 1)()
        status = 0
        for task in range(first, first + count):
            if stop.is_set() or status:
                break
            status = _call(library, TASKS_FUNCTION, task, 1, counts, seed, float(tau), float(index),
                           float(albedo), float(g), sums, events, work, state, alias)
        statuses.append(status)

    shares = [(SLAB_TASKS * t // threads, SLAB_TASKS * (t + 1) // threads) for t in range(threads)]
    workers = [threading.Thread(target=run_tasks, args=(first, end - first)) for first, end in shares[1:]]
    for worker in workers:
        worker.start()
    try:
        run_tasks(shares[0][0], shares[0][1] - shares[0][0])
    finally:
        if sys.exc_info()[0] is not None:
            stop.set()
        for worker in workers:
            worker.join()
    if len(statuses) != threads:  # a thread that raised reported no status: its tasks' tallies are missing
        raise RuntimeError(f"{threads - len(statuses)} of {threads} threads of the native slab library failed")
    results = (ctypes.c_double * len(SLAB_RESULTS))()
    statuses.append(_call(library, RESULTS_FUNCTION, sums, paths, float(index), results))
    if any(statuses):
        raise RuntimeError(f"the native slab library returned status {max(statuses, key=abs)}")
    return dict(zip(SLAB_RESULTS, results)) | {"paths": paths, "events": sum(events)}


def _call(library: ctypes.CDLL, name: str, *arguments) -> int:
    """``name``'s status, called by numba's convention."""
    return_value, exception = ctypes.c_int64(), ctypes.c_void_p()
    return getattr(library, name)(ctypes.byref(return_value), ctypes.byref(exception), *arguments)
