"""One execution layer for ClothLight's long jobs: independent tasks on a dask.distributed cluster.

A job picks where its tasks run with a *scheduler* (``--scheduler`` on the command lines):

``"local"``
    a :class:`distributed.LocalCluster` started in this process for the job: one worker process
    per core (or per ``workers``), one thread each, closed when the job ends.  The command
    lines' default wherever dask is installed (:func:`default_scheduler`).
``"tcp://HOST:PORT"``
    an existing cluster, started with ``dask scheduler`` and ``dask worker`` (docs/distributed.md).
``None`` (``"none"`` on a command line)
    no cluster: the job's own single-process path, today's, and the only one where dask is absent
    (Blender's own Python).  The :func:`precompute.bake.bake` default.

Where tasks ran never changes a result: a job splits its work into tasks whose random streams
and sums do not depend on the split (the yarn transport: docs/transport.md, "Random numbers and
determinism"), so N workers give the single-process result bit for bit.

A task function is a module-level function of the project, pickled by reference: every worker
imports it from its own checkout.  So that a worker with other code cannot change a result,
:func:`open_executor` compares the digest of the job's source files
(:func:`precompute.cache.sources.stage_digest`, what the cache keys hold) on every worker with this
process's before any work (:class:`~precompute.errors.WorkerCodeMismatch`), and every task checks
it again on its worker, once per process, for workers that join later.  A worker process runs one
task at a time (ClothLight's numba kernels and bpy are not for concurrent calls), with the worker's
threads as the kernels' threads.

Faults: a worker that dies mid-task has its tasks, and the results it held, recomputed elsewhere
from their inputs (dask keeps the lineage of every result a job still holds, and shared values
are inputs in that graph), with the same result;
a finished result that dask gives up fetching from a dead worker (its future left cancelled) is
submitted again, up to MAX_RESUBMITS times, each after a longer wait (RESUBMIT_BACKOFF_S);
a scheduler that does not answer within ``connect_timeout_s`` or is lost during the job raises
:class:`~precompute.errors.SchedulerUnreachable` naming its address; an exception in a task, or a
KeyboardInterrupt (Ctrl-C) or ``cancel()`` while waiting, cancels every future of the map before it
propagates, so the cluster keeps nothing of the job.  Jobs write their results only after the
map has returned (the bake: into a cache entry renamed into place at the end, precompute/cache/entries.py).
"""

from __future__ import annotations

import contextlib
import functools
import importlib.util
import logging
import operator
import os
import pathlib
import re
import signal
import sys
import threading
import time
import warnings
from collections.abc import Callable, Iterable, Iterator, Sequence

from precompute.errors import ClusterError, ParameterError, SchedulerUnreachable, WorkerCodeMismatch
from precompute.cache.sources import stage_digest

#: ``--scheduler`` values besides an address.
LOCAL = "local"
NO_SCHEDULER = "none"
#: Seconds to wait for a scheduler to answer, and for a cluster to have a worker.
CONNECT_TIMEOUT_S = 10.0
#: Seconds between looks at ``cancel()`` while waiting for tasks.
POLL_S = 0.25
#: Times a task whose finished result was lost with its worker is run again before the job fails.
MAX_RESUBMITS = 3
#: Seconds to wait before running a task again, times its resubmissions so far: gives the scheduler
#: time to remove a dead worker before the task is placed again.
RESUBMIT_BACKOFF_S = 1.0
#: A scheduler address: protocol, host (a name, IPv4, or IPv6 in brackets) and port.
_ADDRESS = re.compile(r"^(tcp|tls)://(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_.-]+):\d{1,5}$")
PROJECT_ROOT = pathlib.Path(__file__).resolve().parents[1]
#: This module, digested with every job's code: it runs the tasks on the workers.
_LAYER_ENTRY = "precompute.distributed"
#: dask's self-monitoring, switched off on the local cluster, whose dashboard is off so that nothing reads
#: it: each worker's statistical profiler samples its threads' stacks every 10 ms, and every process times its
#: event loop every 20 ms.  On an idle two-worker cluster that was ~0.1 of a core, CPU the bake's transport
#: shares on a small machine (docs/distributed.md, "The local cluster's own cost").
_LOCAL_CLUSTER_CONFIG = {"distributed.worker.profile.enabled": False, "distributed.admin.tick.interval": "1s"}


def dask_available() -> bool:
    """Whether dask.distributed can be imported here (not in Blender's own Python)."""
    return importlib.util.find_spec("distributed") is not None


def default_scheduler() -> str | None:
    """The command lines' scheduler when none is given: ``"local"`` where dask is installed, else None."""
    return LOCAL if dask_available() else None


def check_scheduler(value: str | None, option: str = "--scheduler") -> str | None:
    """``value`` as a scheduler (None, ``"local"`` or an address; ``"none"`` is None), or ParameterError."""
    if value is None or value == NO_SCHEDULER:
        return None
    allowed = f"{LOCAL!r}, {NO_SCHEDULER!r} or a scheduler address tcp://HOST:PORT"
    if not isinstance(value, str) or not (value == LOCAL or _ADDRESS.match(value)):
        raise ParameterError(option, value, allowed)
    if not dask_available():
        raise ParameterError(option, value, f"{NO_SCHEDULER!r} here: dask.distributed is not installed")
    return value


def code_digest(entries: Sequence[str], files: Sequence[str] = ()) -> str:
    """Digest of a job's source files, with this layer's, in the checkout this process imported."""
    return stage_digest(PROJECT_ROOT, (*entries, _LAYER_ENTRY), files)


@functools.lru_cache(maxsize=16)
def _own_code_digest(entries: tuple[str, ...], files: tuple[str, ...]) -> str:
    """:func:`code_digest` once per worker process: the code it imported (a client computes its own
    afresh for every job, as the cache keys are, from the files as they are then)."""
    return code_digest(entries, files)


_TASK_LOCK = threading.Lock()


def _run_task(expected_digest: str, code: tuple, function: Callable, args: tuple):
    """Run ``function(*args)`` on a worker: its code checked, one task per process at a time, with
    the worker's threads as numba's."""
    from distributed import get_worker

    worker = get_worker()
    digest = _own_code_digest(*code)
    if digest != expected_digest:
        raise WorkerCodeMismatch(worker.scheduler.address, f"worker {worker.address}",
                                 f"has code digest {digest[:12]}, the job {expected_digest[:12]}")
    with _TASK_LOCK:
        import numba

        previous = numba.get_num_threads()
        numba.set_num_threads(max(1, min(worker.state.nthreads, numba.config.NUMBA_NUM_THREADS)))
        try:
            return function(*args)
        finally:
            numba.set_num_threads(previous)


class ClusterExecutor:
    """Tasks on a dask.distributed cluster (made by :func:`open_executor`).

    ``workers`` is the number of tasks the cluster runs at once (its worker threads), for sizing
    a job's tasks.  Handles (what :meth:`share` and ``map(..., keep=True)`` return) are opaque:
    pass them in later tasks' arguments, where each arrives as its value.
    """

    def __init__(self, client, address: str, code: tuple[tuple[str, ...], tuple[str, ...]], digest: str):
        self.client = client
        self.address = address
        self._code = code
        self._digest = digest
        self.workers = sum(info["nthreads"] for info in client.scheduler_info()["workers"].values())
        #: NumPy bytes sent in task arguments and shared values (counted once per worker), and
        #: received as tasks' results: what the job moved, beside pickling's few hundred bytes a task.
        self.bytes_sent = 0
        self.bytes_received = 0

    def share(self, value):
        """A handle of ``value`` (data that many tasks read), fetched by each worker once.

        The value is held in the job's graph, as a task's input, not scattered: dask's memory
        manager keeps a single copy of scattered data, which dies with its worker, and every task
        reading it is then cancelled; a task's result is made again from its input.
        """
        self.bytes_sent += _nbytes(value) * self.workers
        with warnings.catch_warnings():
            # the value travels once, to the scheduler, as dask's large-graph warning advises against
            warnings.filterwarnings("ignore", message="Sending large graph", category=UserWarning)
            return self.client.submit(_shared_value, value, pure=False)

    def map(self, function: Callable, items: Iterable[Sequence], *, keep: bool = False,
            progress: Callable[[int], None] | None = None, cancel: Callable[[], bool] | None = None) -> list:
        """``function(*item)`` for every item, as tasks; the results in the order of ``items``.

        ``keep``: ``function`` returns ``(kept, returned)``; ``kept`` stays on the worker that made
        it (a handle for later tasks, recomputed from its inputs if that worker dies) and only
        ``returned`` comes back: the result is ``[(handle, returned), ...]``.  ``progress(i)`` is
        called as item i completes (in any order); ``cancel()``, polled every POLL_S, ends the map
        with KeyboardInterrupt.  Every future of the map is cancelled before an exception leaves.
        """
        from distributed import wait
        from distributed.client import FutureCancelledError, FuturesCancelledError

        client = self.client
        items = [tuple(item) for item in items]
        self.bytes_sent += sum(_nbytes(item) for item in items)
        tasks, kept, returned = [None] * len(items), [None] * len(items), [None] * len(items)
        position, resubmitted = {}, [0] * len(items)

        def submit(i: int) -> None:
            tasks[i] = client.submit(_run_task, self._digest, self._code, function, items[i], pure=False)
            if keep:
                kept[i] = client.submit(operator.itemgetter(0), tasks[i], pure=False)
                returned[i] = client.submit(operator.itemgetter(1), tasks[i], pure=False)
            else:
                returned[i] = tasks[i]
            position[returned[i].key] = i

        for i in range(len(items)):
            submit(i)
        results = [None] * len(items)
        try:
            pending = set(returned)
            while pending:
                if cancel is not None and cancel():
                    raise KeyboardInterrupt
                try:
                    done, pending = wait(pending, timeout=POLL_S, return_when="FIRST_COMPLETED")
                except TimeoutError:
                    continue
                except FuturesCancelledError as error:
                    # dask's wait raises as soon as a future it waits on is cancelled: those are
                    # run again below, as the cancelled futures it returns.
                    done = {future for future in pending if future.status == "cancelled"}
                    if not done:
                        self._raise_cancelled(error)
                    pending = pending - done
                for future in done:
                    i = position[future.key]
                    try:
                        if future.status == "cancelled":
                            raise FutureCancelledError(future.key, "cancelled before its result was read")
                        results[i] = future.result()
                    except FutureCancelledError as error:
                        # A worker that dies between finishing a task and handing over its result
                        # can leave the finished future cancelled (dask's gather gives up on it):
                        # the task is run again from its inputs, with the same result.
                        if self.client.status not in ("running", "connecting") or \
                                resubmitted[i] >= MAX_RESUBMITS:
                            self._raise_cancelled(error)
                        resubmitted[i] += 1
                        time.sleep(RESUBMIT_BACKOFF_S * resubmitted[i])
                        submit(i)
                        pending.add(returned[i])
                        continue
                    self.bytes_received += _nbytes(results[i])
                    if progress is not None:
                        progress(i)
        except BaseException:
            client.cancel([future for future in (*tasks, *kept, *returned) if future is not None], force=True)
            raise
        return list(zip(kept, results)) if keep else results

    def _raise_cancelled(self, error: Exception | None) -> None:
        """The job's futures were cancelled by the cluster: the scheduler lost, or it refused them."""
        if self.client.status not in ("running", "connecting"):
            raise SchedulerUnreachable(self.address, "the scheduler was lost during the job")
        why = f" ({error})" if error is not None else ""
        raise ClusterError(f"--scheduler {self.address}: the scheduler cancelled the job's tasks{why}")


def _shared_value(value):
    """The task of :meth:`ClusterExecutor.share`: its value, as a result the scheduler can remake."""
    return value


def folder_payload(folder) -> dict:
    """{name: the file's bytes as a uint8 array} of the files of ``folder`` (a bake's tables): what
    a job shares with its workers, which may not see this machine's disk (arrays, so that the bytes
    moved count them)."""
    import numpy as np

    return {path.name: np.frombuffer(path.read_bytes(), np.uint8)
            for path in sorted(pathlib.Path(folder).iterdir()) if path.is_file()}


def write_payload(payload: dict, folder) -> pathlib.Path:
    """Write the files of a :func:`folder_payload` into ``folder`` (created); the folder."""
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for name, data in payload.items():
        (folder / name).write_bytes(data.tobytes())
    return folder


def _nbytes(value) -> int:
    """Bytes of the NumPy arrays in ``value`` (nested in tuples, lists, dicts, named tuples)."""
    if hasattr(value, "nbytes"):
        return int(value.nbytes)
    if isinstance(value, dict):
        return sum(_nbytes(v) for v in value.values())
    if isinstance(value, (tuple, list)):
        return sum(_nbytes(v) for v in value)
    return 0


def _remote_code_digest(entries: tuple[str, ...], files: tuple[str, ...]) -> str:
    """Run on each worker by :func:`open_executor`: the digest of the code it imported."""
    return _own_code_digest(entries, files)


def _check_code(client, address: str, code: tuple, digest: str) -> None:
    """WorkerCodeMismatch unless the scheduler's and every worker's code digest is ``digest``."""
    answers = {f"worker {worker}": answer
               for worker, answer in client.run(_remote_code_digest, *code, on_error="return").items()}
    try:
        # as the files are now: a local cluster's scheduler is this process, which may have run jobs before
        answers["the scheduler"] = client.run_on_scheduler(code_digest, *code)
    except Exception as error:  # noqa: BLE001 - whatever it could not import or run, named below
        answers["the scheduler"] = error
    for process, answer in sorted(answers.items()):
        if isinstance(answer, BaseException):
            raise WorkerCodeMismatch(address, process, f"cannot run the job's code ({type(answer).__name__}: "
                                     f"{answer})")
        if answer != digest:
            raise WorkerCodeMismatch(address, process, f"has code digest {answer[:12]}, this checkout {digest[:12]}")


@contextlib.contextmanager
def _sys_path_without_blender_scripts() -> Iterator[None]:
    """``sys.path`` without the script folders an imported bpy put first on it, meanwhile.

    Local workers are spawned with this process's ``sys.path``: after ``import bpy`` it starts with
    Blender's ``scripts/modules``, whose ``bpy`` package (the Python half, without ``_bpy``) would
    then shadow the wheel's module in a worker, and a task that renders could not import bpy.
    """
    bpy = sys.modules.get("bpy")
    scripts = pathlib.Path(bpy.__file__).resolve().parents[2] if getattr(bpy, "__file__", None) else None
    saved = list(sys.path)
    if scripts is not None and scripts.name == "scripts":
        sys.path[:] = [entry for entry in saved if not pathlib.Path(entry or ".").resolve().is_relative_to(scripts)]
    try:
        yield
    finally:
        sys.path[:] = saved


@contextlib.contextmanager
def _children_ignore_ctrl_c() -> Iterator[None]:
    """SIGINT ignored meanwhile (in the main thread), so that the local workers started now inherit
    that: a terminal's Ctrl-C reaches its whole process group, and only this process is to handle
    it (cancel the job, close the cluster), without a traceback from every worker."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


@contextlib.contextmanager
def open_executor(scheduler: str, *, code: dict, workers: int | None = None,
                  connect_timeout_s: float | None = None) -> Iterator[ClusterExecutor]:
    """A :class:`ClusterExecutor` on ``scheduler`` (``"local"`` or an address), checked, for a ``with``.

    ``code``: the job's sources as :func:`precompute.cache.sources.stage_digest` takes them (``entries``,
    optionally ``files``); every worker must have the same (WorkerCodeMismatch otherwise, before
    any work).  ``workers``: the local cluster's worker processes (default: this machine's cores);
    only with ``"local"``.  An address that does not answer within ``connect_timeout_s`` (default
    CONNECT_TIMEOUT_S): SchedulerUnreachable.  The local cluster is closed at the end, whatever happened.
    """
    import dask
    from distributed import Client, LocalCluster

    connect_timeout_s = CONNECT_TIMEOUT_S if connect_timeout_s is None else connect_timeout_s

    scheduler = check_scheduler(scheduler)
    if scheduler is None:
        raise ParameterError("scheduler", scheduler, f"{LOCAL!r} or an address (None runs in this process)")
    if workers is not None and scheduler != LOCAL:
        raise ParameterError("workers", workers, f"unset with --scheduler {scheduler}: the cluster's workers count")
    spec = (tuple(code["entries"]), tuple(code.get("files", ())))
    with contextlib.ExitStack() as stack:
        if scheduler == LOCAL:
            stack.enter_context(_sys_path_without_blender_scripts())
            # the nannies hand the configuration of their creation to their workers
            with _children_ignore_ctrl_c(), dask.config.set(_LOCAL_CLUSTER_CONFIG):
                cluster = LocalCluster(
                    n_workers=workers or len(os.sched_getaffinity(0)), threads_per_worker=1, processes=True,
                    # CRITICAL: a worker's heartbeat racing the close logs an ERROR; a task's error reaches the client
                    dashboard_address=None, silence_logs=logging.CRITICAL)
            stack.enter_context(cluster)
            client = stack.enter_context(Client(cluster))
            address = cluster.scheduler_address
        else:
            try:
                client = stack.enter_context(Client(scheduler, timeout=connect_timeout_s))
                client.wait_for_workers(1, timeout=connect_timeout_s)
            except (OSError, TimeoutError) as error:
                raise SchedulerUnreachable(
                    scheduler, f"no scheduler with a worker answered within {connect_timeout_s:g} s ({error})"
                ) from None
            address = scheduler
        digest = code_digest(*spec)
        _check_code(client, address, spec, digest)
        yield ClusterExecutor(client, address, spec, digest)


def map_tasks(function: Callable, items: Iterable[Sequence], *, scheduler: str | None, code: dict,
              progress: Callable[[int], None] | None = None, cancel: Callable[[], bool] | None = None,
              workers: int | None = None) -> list:
    """``[function(*item) for item in items]``, in this process (``scheduler`` None) or as tasks on a
    cluster (:func:`open_executor`, :meth:`ClusterExecutor.map`): results in the order of ``items``."""
    items = list(items)
    if check_scheduler(scheduler) is None:
        results = []
        for i, item in enumerate(items):
            if cancel is not None and cancel():
                raise KeyboardInterrupt
            results.append(function(*item))
            if progress is not None:
                progress(i)
        return results
    with open_executor(scheduler, code=code, workers=workers) as executor:
        return executor.map(function, items, progress=progress, cancel=cancel)
