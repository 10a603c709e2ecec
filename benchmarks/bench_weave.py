"""Woven geometry: 100 x 100 crossings at default tessellation (target <= 5 s), with memory."""

import pathlib
import resource
import sys
import time
import tracemalloc

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from clothlight.weave import WeaveParameters, build_woven_mesh  # noqa: E402

params = WeaveParameters(warp_count=100, weft_count=100)
tracemalloc.start()
start = time.perf_counter()
mesh = build_woven_mesh(params)
core_seconds = time.perf_counter() - start
_, peak = tracemalloc.get_traced_memory()
tracemalloc.stop()
print(f"core mesh: {len(mesh.vertices):,} vertices, {len(mesh.faces):,} triangles in {core_seconds:.2f} s, "
      f"peak Python allocations {peak / 2**20:.0f} MiB")
try:
    import bpy

    from clothlight.sample_object import build_sample_object

    bpy.ops.wm.read_homefile(use_empty=True)
    start = time.perf_counter()
    build_sample_object(params)
    print(f"Blender object (core + mesh data): {time.perf_counter() - start:.2f} s")
except ImportError:
    print("bpy not importable: Blender object not timed")
print(f"process peak RSS {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MiB")
