"""Validation sweep cost and noise (issue 8): 14 views × 4 incidences of the woven sample at the
default resolution and samples, timed per material on this machine, and the noise of the summed
values: the relative standard deviation of each view's summed RGB over renders with different seeds.

    python benchmarks/bench_validation.py [--resolution N] [--samples S] [--seeds K] [--tables BAKE]

Without --tables the yarn material uses the newest red-cotton bake in the user cache if there is
one (``python -m precompute bake`` makes it), else only the baseline is timed.
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
from subject_medium import SUBJECT_PRESET

import numpy as np


def cached_subject_bake() -> pathlib.Path | None:
    from precompute.cache.entries import default_cache_dir

    root = pathlib.Path(default_cache_dir())
    bakes = [p.parent for p in root.glob("tables/*/summary.json")
             if json.loads(p.read_text()).get("medium", {}).get("name") == SUBJECT_PRESET]
    return max(bakes, key=lambda p: p.stat().st_mtime) if bakes else None


def main() -> None:
    import bpy

    from clothlight.blender.validation.rig import DEFAULT_RESOLUTION, DEFAULT_SAMPLES, RigSettings
    from clothlight.blender.validation.run import run_validation

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--resolution", type=int, default=DEFAULT_RESOLUTION)
    parser.add_argument("--samples", type=int, default=DEFAULT_SAMPLES)
    parser.add_argument("--seeds", type=int, default=5, help="renders per view for the noise figure")
    parser.add_argument("--tables", type=pathlib.Path, default=None)
    args = parser.parse_args()
    tables = args.tables or cached_subject_bake()
    materials = ("yarn", "baseline") if tables else ("baseline",)
    out = pathlib.Path(tempfile.mkdtemp(prefix="clothlight-bench-validation-"))
    print(f"{os.cpu_count()} CPU cores; {args.resolution}² px, {args.samples} spp; tables: {tables}")

    bpy.ops.wm.read_homefile(use_empty=True)
    settings = RigSettings(resolution=args.resolution, samples=args.samples)
    start = time.perf_counter()
    results = run_validation(None, out / "sweep", materials=materials, tables_dir=tables, settings=settings,
                             swatches=False)
    wall = time.perf_counter() - start
    views = len(settings.incidences_deg) * len(settings.views_deg)
    for kind in materials:
        seconds = results["seconds"][kind]
        print(f"{kind:>8}: {views} views in {seconds:6.1f} s ({seconds / views:.2f} s per view)")
    print(f"   total: {wall:.1f} s wall for {len(materials)} × {views} views, including building the sample and rig")

    # Noise: the same views rendered with different seeds.
    noise_views = (-60.0, 0.0, 30.0, 70.0)
    sums = {kind: [] for kind in materials}
    for seed in range(args.seeds):
        noise_settings = RigSettings(incidences_deg=(30.0,), views_deg=noise_views, resolution=args.resolution,
                                     samples=args.samples, seed=seed)
        run = run_validation(None, out / f"seed{seed}", materials=materials, tables_dir=tables,
                             settings=noise_settings, swatches=False)
        for kind in materials:
            sums[kind].append([v["rgb_sum"] for v in run["materials"][kind]["views"]])
    print(f"relative std of the summed RGB over {args.seeds} seeds, θi = 30°, θv = {noise_views}:")
    for kind in materials:
        s = np.array(sums[kind])  # (seeds, views, 3)
        rel = s.std(axis=0, ddof=1) / s.mean(axis=0)
        for k, theta_v in enumerate(noise_views):
            print(f"  {kind:>8} θv = {theta_v:+5.0f}°: R {rel[k, 0]:.2e}  G {rel[k, 1]:.2e}  B {rel[k, 2]:.2e}")


if __name__ == "__main__":
    main()
