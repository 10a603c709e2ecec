"""Validation sweep cost: 14 views x 4 incidences at the default resolution and samples (target
<= 5 min on 2 cores), and the noise of the summed values over render seeds."""

import pathlib
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

import bpy  # noqa: E402
import numpy as np  # noqa: E402

from clothlight.materials import build_baseline_material  # noqa: E402
from clothlight.validation.measure import run_sweep  # noqa: E402
from clothlight.validation.rig import DEFAULT_INCIDENCES_DEG, DEFAULT_VIEWS_DEG, RigSettings, build_rig  # noqa: E402

out = pathlib.Path(tempfile.mkdtemp(prefix="clothlight-bench-validation-"))
bpy.ops.wm.read_homefile(use_empty=True)
settings = RigSettings()
scene = bpy.context.scene
sample, sun, camera = build_rig(settings, scene)
material = build_baseline_material()
start = time.perf_counter()
run_sweep(scene, sample, sun, camera, material, settings, DEFAULT_INCIDENCES_DEG, DEFAULT_VIEWS_DEG, out)
seconds = time.perf_counter() - start
views = len(DEFAULT_INCIDENCES_DEG) * len(DEFAULT_VIEWS_DEG)
print(f"{views} views at {settings.resolution}² px, {settings.samples} spp: {seconds:.1f} s "
      f"({seconds / views:.2f} s per view) for one material")

sums = []
for seed in range(5):
    scene.cycles.seed = seed
    sums.append(run_sweep(scene, sample, sun, camera, material, settings, (45.0,), (-30.0, 0.0, 50.0), out))
red = np.array([[v.rgb_sum[0] for v in run] for run in sums])
print("relative std of the summed red value over 5 render seeds at θi = 45°, θv = -30, 0, 50°:",
      np.round(red.std(axis=0, ddof=1) / red.mean(axis=0), 5).tolist())
