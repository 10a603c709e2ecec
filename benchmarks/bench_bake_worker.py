"""The add-on's Bake Tables as Blender runs it: a child process (clothlight.bake_worker) from start to
tables, wall time, for the tiny settings the test suite bakes with (4 × 4 angular grids, 64 paths per
incidence cell; tests/helpers.py PREBAKED_TRANSPORT) — what a user waits for beyond the transport
itself: the child's start-up, its imports and numba's kernels.  First with an empty numba cache (the
first bake after installing the extension compiles every kernel: what the add-on test's first bake
costs), then with the kernels cached, then the same request again (a cache hit: start-up only).
No test asserts these times (a loaded machine takes longer).

    python benchmarks/bench_bake_worker.py
"""

from __future__ import annotations

import pathlib
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from clothlight.jobs import BakeJob
from clothlight.medium_settings import BakeRequest
from tests.helpers import PREBAKED_TRANSPORT

request = BakeRequest(overrides=(("dye.weight_percent", 2.0),), target_rel_stderr=None, **PREBAKED_TRANSPORT)
root = pathlib.Path(tempfile.mkdtemp(prefix="clothlight-bench-worker-"))
print(f"request {request.to_json()}; caches in {root}")
runs = [("empty numba cache, empty bake cache", "bake-1"), ("numba kernels cached, empty bake cache", "bake-2"),
        ("the same request again (bake cache hit)", "bake-2")]
for label, bake_cache in runs:
    start = time.perf_counter()
    outcome = BakeJob(request, cache_dir=root / bake_cache, numba_cache_dir=root / "numba").wait()
    print(f"{label}: {time.perf_counter() - start:.1f} s wall (child process start to tables), "
          f"cache hit = {outcome.cache_hit}, the bake itself {outcome.seconds:.1f} s")
