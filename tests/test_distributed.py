"""The bake's transport on a real dask.distributed cluster (precompute/distributed.py, docs/distributed.md).

A ``dask scheduler`` and ``dask worker`` processes on 127.0.0.1 (random free ports), started and torn
down here: a small bake through two workers is bitwise the single-process bake; a worker killed
mid-job by its PID changes nothing; Ctrl-C leaves nothing behind, on the cluster or in the cache; an
unreachable scheduler and a worker with other code are clear errors before anything is written.
"""

import contextlib
import json
import os
import pathlib
import shutil
import signal
import socket
import subprocess
import sys
import time

import numpy as np
import pytest

from precompute import distributed as layer
from precompute.bake import SPECTRAL_FILE, bake, load_spectral
from precompute.errors import SchedulerUnreachable, WorkerCodeMismatch
from precompute.tables.folder import FILE_HASHES_KEY
from tests.helpers import REPO

pytestmark = pytest.mark.slow

pytest.importorskip("distributed")

#: A small bake with an error target, so that the transport runs rounds (the large tallies of a
#: block of cells stay on a worker between them): a few seconds of transport on 2 cores.
SMALL = ["transport.incidence_resolution=5", "transport.angular_resolution=3", "transport.n_around=8",
         "transport.n_along=2"]
TARGET, SEED, PRESET = 0.05, 5, "paper_2008"
#: Looks at the cluster, 0.1 s apart, for a change it makes in the background.
ATTEMPTS = 600
DASK = pathlib.Path(sys.executable).with_name("dask")
#: Seconds a cluster gets to start (a generous bound on waiting, never asserted as a speed).
START_S = 120


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def wait_for_workers(address: str, count: int) -> None:
    from distributed import Client

    with Client(address, timeout=START_S) as client:
        client.wait_for_workers(count, timeout=START_S)


@contextlib.contextmanager
def dask_cluster(tmp_path, checkouts):
    """A scheduler and one ``dask worker --no-nanny`` per checkout folder (the worker's PYTHONPATH), on
    127.0.0.1; yields the address and the worker processes, and ends every process it started."""
    address = f"tcp://127.0.0.1:{free_port()}"
    processes = []
    log = open(tmp_path / "cluster.log", "w")
    try:
        # the scheduler unpickles the tasks: it imports this checkout's code too
        processes.append(subprocess.Popen([str(DASK), "scheduler", "--host", "127.0.0.1", "--port",
                                           address.rpartition(":")[2], "--no-dashboard"], cwd=REPO,
                                          env={**os.environ, "PYTHONPATH": str(REPO)}, stdout=log, stderr=log))
        workers = []
        for checkout in checkouts:
            env = {**os.environ, "PYTHONPATH": str(checkout), "NUMBA_NUM_THREADS": "1"}
            workers.append(subprocess.Popen([str(DASK), "worker", address, "--host", "127.0.0.1", "--nthreads", "1",
                                             "--no-nanny", "--no-dashboard"], cwd=checkout, env=env, stdout=log,
                                            stderr=log))
        processes.extend(workers)
        wait_for_workers(address, len(workers))
        yield address, workers
    finally:
        for process in reversed(processes):
            if process.poll() is None:
                process.terminate()
        for process in processes:
            try:
                process.wait(timeout=30)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
        log.close()


def small_bake(cache_dir, **options):
    return bake(PRESET, SMALL, seed=SEED, target_rel_stderr=TARGET, cache_dir=cache_dir, **options)


def files_under(folder: pathlib.Path) -> list[pathlib.Path]:
    return sorted(path for path in folder.rglob("*") if path.is_file()) if folder.exists() else []


@pytest.fixture(scope="module")
def single_process(tmp_path_factory):
    """The small bake in this process (no scheduler): the reference every cluster bake must equal."""
    return small_bake(tmp_path_factory.mktemp("single") / "cache")


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """A scheduler and two workers from this checkout."""
    with dask_cluster(tmp_path_factory.mktemp("cluster"), [REPO, REPO]) as (address, _):
        yield address


def assert_same_bake(result, reference) -> None:
    """Same tables (key and every file's content hash) and the same spectral arrays, bit for bit."""
    assert result.simulated and reference.simulated
    assert result.folder.name == reference.folder.name  # the tables' cache key
    assert result.summary["spectral_key"] == reference.summary["spectral_key"]
    for name in ("brdf.exr", "brdf_stderr.exr", "albedo.exr", "lobes.exr", "unscattered.exr"):
        assert (result.folder / name).read_bytes() == (reference.folder / name).read_bytes(), name
    arrays, _ = load_spectral(result.folder / SPECTRAL_FILE)
    expected, _ = load_spectral(reference.folder / SPECTRAL_FILE)
    assert sorted(arrays) == sorted(expected)
    for name in arrays:
        np.testing.assert_array_equal(arrays[name], expected[name], err_msg=name)


def test_a_bake_on_two_workers_is_bitwise_the_single_process_bake(cluster, single_process, tmp_path):
    result = small_bake(tmp_path / "cache", scheduler=cluster)
    assert_same_bake(result, single_process)
    # rounds after the first ran: tallies travelled on
    assert result.summary["paths"]["total"] > result.summary["paths"]["incidence_cells_traced"] * 65536


def test_the_command_line_on_a_local_cluster_of_one_worker_is_bitwise_the_same(single_process, tmp_path):
    command = [sys.executable, "-m", "precompute", "bake", "--preset", PRESET, "--seed", str(SEED),
               "--target-error", str(TARGET), "--scheduler", "local", "--threads", "1",
               "--cache-dir", str(tmp_path / "cache"), "--json"]
    for setting in SMALL:
        command += ["--set", setting]
    run = subprocess.run(command, capture_output=True, text=True, cwd=REPO)
    assert run.returncode == 0, run.stderr[-3000:]
    summary = json.loads(run.stdout)
    assert summary["simulated"]
    assert "bake:" in run.stderr and "100%" in run.stderr  # the progress bar, fed from the tasks
    assert pathlib.Path(summary["folder"]).name == single_process.folder.name
    hashes, expected = summary[FILE_HASHES_KEY], single_process.summary[FILE_HASHES_KEY]
    tables = [name for name in expected if name.endswith(".exr")]  # spectral.npz records its seconds
    assert tables and all(hashes[name] == expected[name] for name in tables)


def test_a_worker_killed_mid_job_changes_nothing(single_process, tmp_path):
    with dask_cluster(tmp_path, [REPO, REPO]) as (address, workers):
        killed = []

        def kill_one_worker(fraction: float) -> None:
            if 0 < fraction < 0.9 and not killed:  # some tasks done, others running or queued
                os.kill(workers[0].pid, signal.SIGKILL)
                killed.append(fraction)

        result = small_bake(tmp_path / "cache", scheduler=address, progress=kill_one_worker)
        assert killed and workers[0].wait(timeout=30) == -signal.SIGKILL
        assert_same_bake(result, single_process)
        assert len([p for p in (tmp_path / "cache" / "spectral").iterdir() if p.name.endswith(".partial")]) == 0


def _losing_results(monkeypatch, times: int) -> list:
    """Make the first ``times`` results the client reads raise FutureCancelledError, as dask's gather
    does when the worker holding a finished task's result dies before handing it over (a worker
    killed at that moment makes it happen only by chance); returns the list of the keys lost."""
    from distributed import Future
    from distributed.client import FutureCancelledError

    original, lost = Future.result, []

    def result(self, *args, **kwargs):
        if len(lost) < times:
            lost.append(self.key)
            raise FutureCancelledError(self.key, "lost with its worker")
        return original(self, *args, **kwargs)

    monkeypatch.setattr(Future, "result", result)
    return lost


def test_a_result_lost_with_its_worker_after_the_task_finished_is_computed_again(cluster, single_process, tmp_path,
                                                                                 monkeypatch):
    lost = _losing_results(monkeypatch, times=1)
    assert_same_bake(small_bake(tmp_path / "cache", scheduler=cluster), single_process)
    assert len(lost) == 1


def test_a_result_lost_again_and_again_is_a_cluster_error_and_writes_nothing(cluster, tmp_path, monkeypatch):
    from precompute.errors import ClusterError

    lost = _losing_results(monkeypatch, times=10 ** 6)
    with pytest.raises(ClusterError, match="cancelled"):
        small_bake(tmp_path / "cache", scheduler=cluster)
    # Each task is run again up to MAX_RESUBMITS times (new futures, new keys), then the job ends.
    assert len(lost) >= layer.MAX_RESUBMITS + 1
    assert not [path for path in files_under(tmp_path / "cache") if path.suffix == ".exr"]


def test_ctrl_c_cancels_the_tasks_and_leaves_nothing(cluster, tmp_path):
    from distributed import Client

    def interrupt(fraction: float) -> None:
        if fraction > 0:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        small_bake(tmp_path / "cache", scheduler=cluster, progress=interrupt)
    assert files_under(tmp_path / "cache") == []
    with Client(cluster, timeout=START_S) as client:
        deadline = time.monotonic() + START_S  # the scheduler forgets cancelled tasks soon after
        while client.run_on_scheduler(lambda dask_scheduler: len(dask_scheduler.tasks)) and time.monotonic() < deadline:
            time.sleep(0.2)
        assert client.run_on_scheduler(lambda dask_scheduler: len(dask_scheduler.tasks)) == 0


def test_an_unreachable_scheduler_is_a_clear_error_and_writes_nothing(tmp_path, monkeypatch):
    address = f"tcp://127.0.0.1:{free_port()}"  # nothing listens there
    monkeypatch.setattr(layer, "CONNECT_TIMEOUT_S", 2.0)
    with pytest.raises(SchedulerUnreachable, match=address):
        small_bake(tmp_path / "cache", scheduler=address)
    assert files_under(tmp_path / "cache") == []


def test_the_command_line_names_an_unreachable_scheduler_and_exits_2(tmp_path):
    address = f"tcp://127.0.0.1:{free_port()}"
    run = subprocess.run([sys.executable, "-m", "precompute", "bake", "--scheduler", address,
                          "--cache-dir", str(tmp_path / "cache")], capture_output=True, text=True, cwd=REPO)
    assert run.returncode == 2, run.stderr[-3000:]
    assert address in run.stderr and run.stderr.startswith("error: --scheduler")
    assert files_under(tmp_path / "cache") == []


def test_a_malformed_scheduler_is_bad_input():
    run = subprocess.run([sys.executable, "-m", "precompute", "bake", "--scheduler", "localhost"],
                         capture_output=True, text=True, cwd=REPO)
    assert run.returncode == 2 and "--scheduler = 'localhost' is invalid" in run.stderr


def other_version(folder: pathlib.Path) -> pathlib.Path:
    """A checkout whose transport differs from this one by a comment."""
    shutil.copytree(REPO / "precompute", folder / "precompute", ignore=shutil.ignore_patterns("__pycache__"))
    with open(folder / "precompute" / "transport" / "cylinder.py", "a") as source:
        source.write("# another version\n")
    return folder


def without_the_project(folder: pathlib.Path) -> pathlib.Path:
    folder.mkdir()
    return folder


@pytest.mark.parametrize("checkout, says", [(other_version, "has code digest"),
                                            (without_the_project, "cannot run the job's code")])
def test_a_worker_with_other_code_is_refused_before_any_work(tmp_path, checkout, says):
    with dask_cluster(tmp_path, [checkout(tmp_path / "worker")]) as (address, _):
        with pytest.raises(WorkerCodeMismatch, match=says) as refused:
            small_bake(tmp_path / "cache", scheduler=address)
    assert address in str(refused.value) and refused.value.process.startswith("worker tcp://127.0.0.1:")
    assert files_under(tmp_path / "cache") == []


def test_map_tasks_keeps_the_order_of_its_items_wherever_it_runs(cluster):
    code = {"entries": ("precompute.distributed",)}
    items = [(value,) for value in range(7)]
    assert layer.map_tasks(abs, [(-v,) for (v,) in items], scheduler=None, code=code) == list(range(7))
    done = []
    assert layer.map_tasks(np.square, items, scheduler=cluster, code=code, progress=done.append) == [
        v * v for (v,) in items]
    assert sorted(done) == list(range(7))


def test_a_dye_series_transport_on_the_cluster_is_bitwise_the_single_process_one(cluster):
    """The exits tallied again at absorption steps (precompute/transport/absorption.py) travel too."""
    from precompute.bake import SPECTRAL_SOURCES, bake_configuration
    from precompute.optics.coefficients import medium_optics
    from precompute.transport import TransportGrids, YarnGeometry, simulate_yarn

    medium = bake_configuration(PRESET, SMALL).medium
    optics = medium_optics(medium)
    geometry, grids = YarnGeometry(medium.yarn.radius_mm, optics.boundary_index), TransportGrids(8, 2, 3)
    steps = np.outer([0.5, 2.0], np.ones(len(optics.wavelengths_nm)))  # Δμa, 1/mm

    def transport(executor=None):
        return simulate_yarn(optics, geometry, grids, paths_per_cell=3000, seed=SEED, extra_absorption_per_mm=steps,
                             executor=executor)

    with layer.open_executor(cluster, code=SPECTRAL_SOURCES) as executor:
        spread = transport(executor)
    here = transport()
    np.testing.assert_array_equal(spread.axial_bssrdf(), here.axial_bssrdf())
    np.testing.assert_array_equal(spread.bssrdf_axial_second_moment, here.bssrdf_axial_second_moment)
    for name in ("axial_bssrdf", "exit_fraction", "exit_second_moment", "unscattered_fraction"):
        np.testing.assert_array_equal(getattr(spread.decayed, name), getattr(here.decayed, name), err_msg=name)
    for name in ("specular", "exit_fraction", "absorbed_fraction", "lost_fraction", "paths_per_cell"):
        np.testing.assert_array_equal(getattr(spread, name), getattr(here, name), err_msg=name)
    assert spread.events == here.events


def test_a_shared_value_outlives_the_worker_that_holds_its_only_copy(tmp_path):
    """dask's memory manager keeps one copy of data nobody waits on (every 2 s): a value shared
    with the workers must come back from the job's graph when its last holder dies (a fresh-clone
    CI run lost a bake's medium so: every task reading it was cancelled, again and again)."""
    with dask_cluster(tmp_path, [REPO, REPO]) as (address, workers):
        with layer.open_executor(address, code={"entries": ("precompute.distributed",)}) as executor:
            client = executor.client
            handle = executor.share(np.arange(5.0))
            assert executor.map(np.sum, [(handle,)] * 2) == [10.0, 10.0]
            pid_of = client.run(os.getpid)
            for _ in range(ATTEMPTS):  # the memory manager's drops are asynchronous
                holders = client.who_has([handle])[handle.key]
                if len(holders) == 1:
                    break
                client.amm.run_once()
                time.sleep(0.1)
            (holder,) = holders
            os.kill(pid_of[holder], signal.SIGKILL)
            for _ in range(ATTEMPTS):
                if len(client.scheduler_info()["workers"]) == 1:
                    break
                time.sleep(0.1)
            assert executor.map(np.sum, [(handle,)] * 2) == [10.0, 10.0]
