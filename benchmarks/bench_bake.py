"""The default bake (the paper's red cotton): wall time, cache hit, recolouring, and the Table 1 ratios.

Bakes into a throw-away cache: the default settings (32 × 3 spatial cells, 12 × 12 angular grids,
1 % target error of every cell's albedo) with seeds 0, 1, 2 for the spread of B/R and G/R, then
the same inputs again (a cache hit) and under illuminant A (colour only).  Also prints the error
half floats would add to the ρ table, which is why tables are float32.

    python benchmarks/bench_bake.py
"""

from __future__ import annotations

import pathlib
import sys
import tempfile
import time

import numba
import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from precompute.bake import bake
from precompute.tables.exr import read_table

cache_dir = pathlib.Path(tempfile.mkdtemp(prefix="clothlight-bench-bake-"))
print(f"{numba.config.NUMBA_NUM_THREADS} threads; cache {cache_dir}")
ratios = []
for seed in (0, 1, 2):
    start = time.perf_counter()
    result = bake("paper_2008", seed=seed, cache_dir=cache_dir)
    wall = time.perf_counter() - start
    s = result.summary
    ratios.append((s["table1_ratios_normal"]["B/R"], s["table1_ratios_normal"]["G/R"],
                   s["table1_ratios_normal_unclipped"]["G/R"]))
    print(f"seed {seed}: {wall:.1f} s wall (transport {s['seconds']['transport']:.1f} s, "
          f"BRDF {s['seconds']['brdf']:.1f} s, tables {s['seconds']['tables']:.2f} s); {s['paths']['total']:,} paths; "
          f"B/R = {ratios[-1][0]:.4f}, G/R = {ratios[-1][1]:.4f} (before gamut clipping {ratios[-1][2]:.4f}); "
          f"gamut clipping up to {s['colour']['gamut_clipping_max_relative']:.1%} of a cell's largest channel")
mean, spread = np.mean(ratios, axis=0), np.std(ratios, axis=0, ddof=1)
print(f"over 3 seeds: B/R = {mean[0]:.4f} ± {spread[0]:.4f}, G/R = {mean[1]:.4f} ± {spread[1]:.4f} "
      f"(unclipped {mean[2]:.4f} ± {spread[2]:.4f}); paper Table 1, real red cotton: 0.08 and 0.011")

start = time.perf_counter()
hit = bake("paper_2008", seed=0, cache_dir=cache_dir)
print(f"same inputs again: cache hit = {hit.cache_hit}, {time.perf_counter() - start:.3f} s")
start = time.perf_counter()
tungsten = bake("paper_2008", ["bake.illuminant=A"], seed=0, cache_dir=cache_dir)
print(f"illuminant A: simulated = {tungsten.simulated}, {time.perf_counter() - start:.2f} s, "
      f"B/R = {tungsten.blue_red:.4f}, G/R = {tungsten.green_red:.4f}")

rho = read_table(hit.brdf_table).pixels
stored = rho[rho > 0]
half = stored.astype(np.float16).astype(np.float32)
print(f"rho table {rho.shape}: values {stored.min():.3g} … {stored.max():.3g} 1/sr; as half floats the largest "
      f"relative error would be {np.max(np.abs(half - stored) / stored):.2e} "
      f"({np.mean(stored < 6.1e-5):.1%} of the values below half's normal range)")
