"""The content-addressed cache: hits without simulating, atomic entries, concurrent and interrupted bakes."""

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from precompute import bake as bake_module
from precompute.cache import entries as cache
from precompute.bake import bake
from precompute.tables.exr import read_table

from tests.helpers import slow_fixture

SMALL = ["transport.angular_resolution=4", "transport.incidence_resolution=5",
         "transport.n_around=8", "transport.n_along=4"]
SMALL_CLI = [arg for setting in SMALL for arg in ("--set", setting)]


def entries(cache_dir, namespace):
    """Complete and partial entries of a namespace, by name."""
    folder = cache_dir / namespace
    return sorted(p.name for p in folder.iterdir()) if folder.is_dir() else []


# ---- the cache module ---------------------------------------------------------------------------


def test_key_is_canonical_and_sensitive_to_every_input():
    inputs = {"medium": {"radius_mm": 0.1, "n": [1.5, 1.6]}, "seed": 0, "schema": "s/1"}
    assert cache.cache_key(inputs) == cache.cache_key(dict(reversed(list(inputs.items()))))
    variants = [{**inputs, "seed": 1}, {**inputs, "schema": "s/2"},
                {**inputs, "medium": {"radius_mm": 0.1, "n": [1.5, 1.61]}}]
    keys = {cache.cache_key(v) for v in variants} | {cache.cache_key(inputs)}
    assert len(keys) == 4


def test_store_renames_a_complete_entry_into_place(tmp_path):
    assert cache.lookup(tmp_path, "ns", "k1") is None
    folder, kept = cache.store(tmp_path, "ns", "k1", {"x": 1}, lambda f: (f / "data.txt").write_text("42"))
    assert kept and folder == cache.lookup(tmp_path, "ns", "k1")
    assert (folder / "data.txt").read_text() == "42"
    assert json.loads((folder / cache.ENTRY_FILE).read_text()) == {"key": "k1", "inputs": {"x": 1}}
    assert entries(tmp_path, "ns") == ["k1"]


def test_a_failing_writer_leaves_nothing(tmp_path):
    def write_then_fail(folder):
        (folder / "brdf.exr").write_bytes(b"half a table")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        cache.store(tmp_path, "ns", "k1", {}, write_then_fail)
    assert entries(tmp_path, "ns") == [] and cache.lookup(tmp_path, "ns", "k1") is None


def test_the_first_of_two_stores_of_one_key_wins(tmp_path):
    first, kept_first = cache.store(tmp_path, "ns", "k", {}, lambda f: (f / "v").write_text("first"))

    def late_writer(folder):
        (folder / "v").write_text("second")

    second, kept_second = cache.store(tmp_path, "ns", "k", {}, late_writer)
    assert kept_first and not kept_second and first == second
    assert (first / "v").read_text() == "first" and entries(tmp_path, "ns") == ["k"]


def test_a_damaged_entry_is_replaced(tmp_path):
    (tmp_path / "ns" / "k").mkdir(parents=True)
    (tmp_path / "ns" / "k" / "brdf.exr").write_bytes(b"junk")  # no entry.json: not made by store
    assert cache.lookup(tmp_path, "ns", "k") is None
    folder, kept = cache.store(tmp_path, "ns", "k", {}, lambda f: (f / "v").write_text("new"))
    assert kept and (folder / "v").read_text() == "new" and not (folder / "brdf.exr").exists()


def test_stale_partials_of_dead_bakes_are_removed_fresh_ones_kept(tmp_path):
    space = tmp_path / "ns"
    stale, fresh = space / ".aaaa.1.ff.partial", space / ".bbbb.2.ee.partial"
    for folder in (stale, fresh):
        folder.mkdir(parents=True)
    old = time.time() - cache.STALE_PARTIAL_SECONDS - 60
    os.utime(stale, (old, old))
    cache.store(tmp_path, "ns", "k", {}, lambda f: None)
    assert not stale.exists() and fresh.exists()


# ---- bakes --------------------------------------------------------------------------------------


@pytest.fixture
@slow_fixture
def transport_runs(monkeypatch):
    """Counts the Monte-Carlo transport runs of in-process bakes."""
    runs = []
    real = bake_module.simulate_yarn

    def counted(*args, **kwargs):
        runs.append(kwargs.get("seed"))
        return real(*args, **kwargs)

    monkeypatch.setattr(bake_module, "simulate_yarn", counted)
    return runs


def test_a_second_bake_is_a_cache_hit_that_simulates_nothing(tmp_path, transport_runs):
    first = bake("paper_2008", SMALL, paths_per_cell=100, cache_dir=tmp_path)
    assert first.simulated and not first.cache_hit and len(transport_runs) == 1
    files = {p: p.stat().st_mtime_ns for p in first.folder.iterdir()}
    second = bake("paper_2008", SMALL, paths_per_cell=100, cache_dir=tmp_path)
    assert second.cache_hit and not second.simulated and len(transport_runs) == 1
    assert second.folder == first.folder and {p: p.stat().st_mtime_ns for p in first.folder.iterdir()} == files
    assert second.summary["table1_ratios_normal"] == first.summary["table1_ratios_normal"]
    # The thread count does not change the result, so it is not part of the key.
    assert bake("paper_2008", SMALL, paths_per_cell=100, threads=1, cache_dir=tmp_path).cache_hit
    # Any input that changes the result is: the seed, the medium.
    bake("paper_2008", SMALL, paths_per_cell=100, seed=5, cache_dir=tmp_path)
    bake("paper_2008", [*SMALL, "dye.weight_percent=1"], paths_per_cell=100, cache_dir=tmp_path)
    assert transport_runs == [0, 5, 0] and len(entries(tmp_path, "tables")) == 3


def test_another_illuminant_recomputes_colour_without_simulating(tmp_path, transport_runs):
    # 400 paths per cell: at 100 the yarn's spectrum at normal incidence is noise (B/R 0.06–0.38 by seed)
    daylight = bake("paper_2008", SMALL, paths_per_cell=400, cache_dir=tmp_path)
    tungsten = bake("paper_2008", [*SMALL, "bake.illuminant=A"], paths_per_cell=400, cache_dir=tmp_path)
    assert len(transport_runs) == 1 and not tungsten.simulated and not tungsten.cache_hit
    assert tungsten.folder != daylight.folder
    assert tungsten.summary["spectral_key"] == daylight.summary["spectral_key"]
    assert read_table(tungsten.brdf_table).metadata["colour"]["illuminant"] == "A"
    # A white-balanced red under tungsten light loses blue relative to red.
    assert tungsten.summary["table1_ratios_normal"]["B/R"] < daylight.summary["table1_ratios_normal"]["B/R"]


def test_a_bake_interrupted_while_writing_tables_leaves_no_table(tmp_path, monkeypatch, transport_runs):
    real_write = bake_module.write_table

    def write_then_crash(path, pixels, metadata):
        if metadata["table"] == "albedo":  # brdf.exr and brdf_stderr.exr are already written
            path.write_bytes(b"\x76\x2f\x31\x01 half-written")
            raise KeyboardInterrupt
        return real_write(path, pixels, metadata)

    monkeypatch.setattr(bake_module, "write_table", write_then_crash)
    with pytest.raises(KeyboardInterrupt):
        bake("paper_2008", SMALL, paths_per_cell=100, cache_dir=tmp_path)
    assert entries(tmp_path, "tables") == []  # neither an entry nor its temporary folder
    # The finished simulation stage is kept and valid: the next bake only writes the tables.
    monkeypatch.setattr(bake_module, "write_table", real_write)
    result = bake("paper_2008", SMALL, paths_per_cell=100, cache_dir=tmp_path)
    assert not result.simulated and len(transport_runs) == 1
    read_table(result.table("albedo"), kind="albedo")


@pytest.mark.slow
def test_a_killed_bake_leaves_no_table(tmp_path):
    command = [sys.executable, "-m", "precompute", "bake", *SMALL_CLI, "--paths", "400000",
               "--threads", "1", "--cache-dir", str(tmp_path)]
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        while not any(name.endswith(".partial") for name in entries(tmp_path, "spectral")):
            assert process.poll() is None, "the bake ended before it could be killed"
            time.sleep(0.05)
        time.sleep(0.5)  # well inside the transport
        process.send_signal(signal.SIGKILL)
    finally:
        process.wait()
    assert process.returncode == -signal.SIGKILL
    assert entries(tmp_path, "tables") == []
    assert all(name.endswith(".partial") for name in entries(tmp_path, "spectral"))
    configuration = bake_module.bake_configuration("paper_2008", SMALL, paths_per_cell=400000)
    key = cache.cache_key(bake_module.spectral_inputs(configuration))
    assert cache.lookup(tmp_path, "spectral", key) is None  # a later bake of these inputs starts afresh


@pytest.mark.slow
def test_two_concurrent_bakes_of_one_key_end_with_one_valid_table(tmp_path):
    command = [sys.executable, "-m", "precompute", "bake", *SMALL_CLI, "--paths", "40000", "--threads", "1",
               "--cache-dir", str(tmp_path), "--json"]
    runs = [subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for _ in range(2)]
    outputs = [run.communicate() for run in runs]
    assert [run.returncode for run in runs] == [0, 0], [err[-2000:] for _, err in outputs]
    summaries = [json.loads(out) for out, _ in outputs]
    # Each simulation takes seconds, far longer than the two start-ups differ: both really raced.
    assert [s["simulated"] for s in summaries] == [True, True]
    assert entries(tmp_path, "tables") == [summaries[0]["cache_key"]]
    assert summaries[0]["folder"] == summaries[1]["folder"]
    assert len(entries(tmp_path, "spectral")) == 1
    folder = tmp_path / "tables" / entries(tmp_path, "tables")[0]
    for name in ("brdf.exr", "brdf_stderr.exr", "albedo.exr", "lobes.exr"):
        read_table(folder / name)
