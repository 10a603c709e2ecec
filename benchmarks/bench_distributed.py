"""The default bake on a LocalCluster of 1 and of 2 workers, side by side: speed-up, task sizes, the
scheduler's overhead per task and the bytes moved (docs/distributed.md); and a draft cloth BSDF
measurement (18 views of the paper's red cotton) the same way; and what an idle local cluster costs in CPU.

Each bake runs into a throw-away cache, so both simulate.  The transport's tasks are timed from
dask's task stream (compute time of every task on its worker); the scheduler's overhead per task
is measured on the same cluster right after the bake, as the wall time per task of trivial tasks
submitted as the bake submits its own (a task and its two getters, ``map(..., keep=True)``) times
the workers; the bytes are the NumPy arrays sent in tasks' arguments and shared values, and
received as results (:class:`precompute.distributed.ClusterExecutor`).

    python benchmarks/bench_distributed.py [--workers 1 2] [--job bake cloth idle] [--preset voided_red_cotton]
        [--set KEY=VALUE ...] [--paths N] [--single-process]

``--paths N``: N paths per incidence cell instead of the error target (one round);
``--single-process``: also the single-process bake on as many numba threads, for the machine's own
scaling beside the cluster's.  ``--job idle``: the CPU time of this process and of its workers and
nannies while a local cluster of the largest ``--workers`` idles IDLE_SECONDS, with dask's own
monitoring switched off as ClothLight's local cluster has it
(``precompute.distributed._LOCAL_CLUSTER_CONFIG``) and with dask's defaults, alternately: the CPU a
bake's transport shares with the cluster itself on a small machine.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import pathlib
import statistics
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from precompute import bake as bake_module
from precompute.transport.cylinder import BLOCKS_PER_WORKER
from subject_medium import SUBJECT_PRESET

#: Trivial tasks timed for the scheduler's overhead.
OVERHEAD_TASKS = 400
#: Seconds a local cluster idles in ``--job idle``; and how many times each configuration is timed.
IDLE_SECONDS = 20.0
IDLE_REPEATS = 2
#: Cluster sizes the scaling model predicts.
PREDICTED_WORKERS = (8, 32, 128)


def instrumented(record: dict, opened=bake_module.open_executor):
    """``open_executor`` as the bake calls it, also recording the task stream, the bytes moved and
    the overhead of trivial tasks on the same cluster."""

    @contextlib.contextmanager
    def open_executor(*args, **kwargs):
        from distributed import get_task_stream

        started = time.perf_counter()
        with opened(*args, **kwargs) as executor:
            record["cluster_start_s"] = time.perf_counter() - started
            with get_task_stream(executor.client) as stream:
                yield executor
            record["task_seconds"] = [
                sum(s["stop"] - s["start"] for s in task["startstops"] if s["action"] == "compute")
                for task in stream.data if task["key"].startswith("_run_task-")]
            record["bytes_sent"], record["bytes_received"] = executor.bytes_sent, executor.bytes_received
            started = time.perf_counter()
            executor.map(divmod, [(i, 1) for i in range(OVERHEAD_TASKS)], keep=True)
            record["overhead_wall_s"] = time.perf_counter() - started
            record["overhead_per_task_s"] = record["overhead_wall_s"] * executor.workers / OVERHEAD_TASKS

    return open_executor


#: The draft cloth measurement timed (N_o = 3: 18 views; a smaller incidence grid than the default's 11).
DRAFT_CLOTH = {"incidence_resolution": 11, "exit_resolution": 4, "pixels_per_patch": 12, "samples": 4}


def bench_cloth(worker_counts) -> None:
    """The draft cloth measurement of the paper's red cotton on LocalClusters of ``worker_counts``."""
    from distributed import get_task_stream

    from clothlight.blender.garment.measure import CLUSTER_CODE, GoniometerSettings, measure_cloth
    from clothlight.yarn_tables import yarn_tables_from_bake
    from precompute.distributed import open_executor

    yarn = pathlib.Path(__file__).resolve().parents[1] / "example_blends" / "tables" / "paper_2008"
    settings = GoniometerSettings(**DRAFT_CLOTH)
    walls = {}
    for workers in worker_counts:
        with tempfile.TemporaryDirectory() as renders:
            started = time.perf_counter()
            with open_executor("local", code=CLUSTER_CODE, workers=workers) as executor:
                cluster_start = time.perf_counter() - started
                with get_task_stream(executor.client) as stream:
                    measure_cloth(yarn_tables_from_bake(yarn), settings, render_dir=renders, scheduler=executor,
                                  table_folder=yarn)
                walls[workers] = time.perf_counter() - started
                tasks = sorted(sum(s["stop"] - s["start"] for s in task["startstops"] if s["action"] == "compute")
                               for task in stream.data if task["key"].startswith("_run_task-"))
                overhead = _overhead_per_task(executor)
                moved = (executor.bytes_sent, executor.bytes_received)
        print(f"cloth, {workers} worker(s): {walls[workers]:.1f} s wall (cluster start {cluster_start:.1f} s); "
              f"{len(tasks)} tasks (one view each; a worker's first builds its scene): median "
              f"{statistics.median(tasks):.2f} s, longest {tasks[-1]:.2f} s; scheduler overhead "
              f"{1e3 * overhead:.1f} ms per task = {overhead / statistics.median(tasks):.2%} of the median task; "
              f"moved {moved[0] / 1e6:.2f} MB to the workers, {moved[1] / 1e6:.2f} MB back", flush=True)
    base = min(walls)
    for workers, wall in walls.items():
        if workers != base:
            print(f"cloth speed-up {workers} workers against {base}: {walls[base] / wall:.2f}×")


def _overhead_per_task(executor) -> float:
    """The scheduler's wall time per trivial task on ``executor``'s cluster, times its workers."""
    started = time.perf_counter()
    executor.map(divmod, [(i, 1) for i in range(OVERHEAD_TASKS)])
    return (time.perf_counter() - started) * executor.workers / OVERHEAD_TASKS


def _cpu_seconds() -> tuple[float, float]:
    """User + system CPU seconds so far of this process and of its live descendants (workers, nannies)."""
    import psutil

    def used(process):
        times = process.cpu_times()
        return times.user + times.system

    me = psutil.Process()
    return used(me), sum(used(child) for child in me.children(recursive=True))


def bench_idle(workers: int) -> None:
    from precompute import distributed

    quiet = distributed._LOCAL_CLUSTER_CONFIG
    print(f"a local cluster of {workers} worker(s), idle for {IDLE_SECONDS:g} s after it opened: CPU used meanwhile",
          flush=True)
    try:
        for _ in range(IDLE_REPEATS):
            for name, config in (("monitoring off (ClothLight's)", quiet), ("dask's defaults", {})):
                distributed._LOCAL_CLUSTER_CONFIG = config
                with distributed.open_executor("local", code=bake_module.SPECTRAL_SOURCES, workers=workers):
                    own, children = _cpu_seconds()
                    time.sleep(IDLE_SECONDS)
                    own_after, children_after = _cpu_seconds()
                print(f"  {name}: this process {own_after - own:.2f} s, workers and nannies "
                      f"{children_after - children:.2f} s: "
                      f"{(own_after - own + children_after - children) / IDLE_SECONDS:.3f} of a core", flush=True)
    finally:
        distributed._LOCAL_CLUSTER_CONFIG = quiet


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--preset", default=SUBJECT_PRESET)
    parser.add_argument("--set", dest="overrides", action="append", default=[])
    parser.add_argument("--paths", type=int)
    parser.add_argument("--single-process", action="store_true")
    parser.add_argument("--job", nargs="+", choices=("bake", "cloth", "idle"), default=["bake", "cloth"],
                        help="what to time: the default bake, a draft cloth measurement (default: both), an idle "
                        "local cluster's CPU")
    args = parser.parse_args()
    if "idle" in args.job:
        bench_idle(max(args.workers))
    if "cloth" in args.job:
        bench_cloth(args.workers)
    if "bake" not in args.job:
        return
    print(f"{args.preset} {' '.join(args.overrides)}; load average before: "
          f"{' '.join(f'{x:.2f}' for x in os.getloadavg())}", flush=True)
    rows = []
    for threads in args.workers if args.single_process else ():
        started = time.perf_counter()
        result = bake_module.bake(args.preset, args.overrides, threads=threads, paths_per_cell=args.paths,
                                  cache_dir=tempfile.mkdtemp(prefix="clothlight-bench-distributed-"))
        print(f"single process, {threads} thread(s): bake {time.perf_counter() - started:.1f} s wall (transport "
              f"{result.summary['seconds']['transport']:.1f} s)", flush=True)
    for workers in args.workers:
        record: dict = {}
        bake_module.open_executor = instrumented(record)
        cache = pathlib.Path(tempfile.mkdtemp(prefix="clothlight-bench-distributed-"))
        started = time.perf_counter()
        result = bake_module.bake(args.preset, args.overrides, scheduler="local", threads=workers, cache_dir=cache,
                                  paths_per_cell=args.paths)
        wall = time.perf_counter() - started - record["overhead_wall_s"]  # the bake's own time
        seconds = result.summary["seconds"]
        tasks = sorted(record["task_seconds"])
        rows.append((workers, wall, record))
        print(f"{workers} worker(s): bake {wall:.1f} s wall (cluster start {record['cluster_start_s']:.1f} s, "
              f"optics {seconds['optics']:.1f} s, transport {seconds['transport']:.1f} s, eq. (5) "
              f"{seconds['brdf']:.1f} s, tables {seconds['tables']:.1f} s); {result.summary['paths']['total']:,} paths",
              flush=True)
        print(f"   {len(tasks)} tasks: median {statistics.median(tasks):.3f} s, shortest {tasks[0]:.3f} s, longest "
              f"{tasks[-1]:.2f} s, {sum(tasks):.1f} s in all; scheduler overhead "
              f"{1e3 * record['overhead_per_task_s']:.1f} ms per task = "
              f"{record['overhead_per_task_s'] / statistics.median(tasks):.2%} of the median task", flush=True)
        print(f"   moved: {record['bytes_sent'] / 1e6:.1f} MB to the workers, {record['bytes_received'] / 1e6:.1f} MB "
              f"back; load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}", flush=True)
    base = rows[0]
    for workers, wall, _ in rows[1:]:
        print(f"speed-up {workers} workers against {base[0]}: {base[1] / wall:.2f}×")
    scaling_model(*base, result.summary["paths"])


def scaling_model(workers: int, wall: float, record: dict, paths: dict) -> None:
    """Predicted bake time on W workers from the run on ``workers`` (docs/distributed.md, "Scaling").

    The run splits into the transport's compute C (its tasks' compute time: the same work on any
    cluster), the scheduler's overhead o per task and the serial rest S = wall − C/workers − o·tasks/workers
    (the cluster's start, the optics, eq. (5), the tables, the gather of the tallies).  On W workers
    each of the R rounds runs B = min(cells, BLOCKS_PER_WORKER·W) blocks, the busiest worker ⌈B/W⌉
    of them: T(W) = S + C/W_eff + R·⌈B/W⌉·o with W_eff = B/⌈B/W⌉ (blocks of equal cost).  The
    costliest cell bounds a round below: C · max/Σ of its paths.  Cells: the traced ones (``paths``, the
    bake summary's record; an image cell's paths are its source's).
    """
    cells = paths["incidence_cells_traced"]
    compute, overhead = sum(record["task_seconds"]), record["overhead_per_task_s"]
    blocks = min(cells, BLOCKS_PER_WORKER * workers)
    rounds = len(record["task_seconds"]) / blocks
    serial = wall - compute / workers - overhead * len(record["task_seconds"]) / workers
    floor = compute * max(paths["per_incidence_cell"]) / paths["total"]
    print(f"scaling model from {workers} worker(s): compute C = {compute:.1f} s in {rounds:.0f} rounds of tasks, "
          f"serial S = {serial:.1f} s ({serial / wall:.1%} of the bake: the serial fraction), overhead "
          f"{1e3 * overhead:.1f} ms per task; the costliest of {cells} cells takes {floor:.2f} s")
    for target in PREDICTED_WORKERS:
        blocks = min(cells, BLOCKS_PER_WORKER * target)
        busiest = -(-blocks // target)
        effective = blocks / busiest
        predicted = serial + max(compute / effective, floor) + rounds * busiest * overhead
        print(f"   {target:4d} workers: {blocks} blocks, effective parallelism {effective:.0f}: "
              f"{predicted:.1f} s predicted ({wall / predicted:.1f}× the {workers}-worker bake)")


if __name__ == "__main__":
    main()
