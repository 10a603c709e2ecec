"""Compile every numba kernel of the transport once, ahead of the first real job (issue 24).

numba compiles a kernel at its first call and keeps the machine code in its cache (``cache=True``:
``__pycache__`` beside the source, or ``NUMBA_CACHE_DIR``), keyed by the source file and the
argument types.  Without this step a new machine's first slab or bake spends about a minute of CPU
compiling before any work; ``make setup`` runs it once per checkout (``python -m
precompute.transport.compile``), so that first job only loads the cache.  Each kernel is called
here through the public function that calls it in real use, with the same argument types, on a
problem too small to take time.  It then builds the native slab library (:mod:`.native`), with which
``python -m precompute slab`` runs without importing numba at all.
"""

from __future__ import annotations

import subprocess
import sys
import time

import numpy as np

from precompute.tables.grids import AngularGrid
from precompute.transport.absorption import absorption_steps, interpolate_absorption
from precompute.transport.beam import simulate_parallel_beam
from precompute.transport.cylinder import TransportGrids, YarnGeometry, simulate_yarn
from precompute.transport.media import henyey_greenstein_medium
from precompute.transport.native import build_native_slab
from precompute.transport.slab import simulate_hg_slab, simulate_slab


def compile_kernels() -> list[str]:
    """Call every kernel once (module docstring); the names of what was run, in order."""
    done = []
    tabulated = henyey_greenstein_medium([0.9, 0.8], [0.5, 0.3], mu_t=[20.0, 30.0], tabulated=True, samples=33)
    single = henyey_greenstein_medium([0.9], [0.5], mu_t=[20.0])
    simulate_hg_slab(0.9, 0.5, 1.0, 1.5, paths=64)
    simulate_slab(tabulated, 0.05, 1.5, paths=64)
    done.append("slab")
    geometry = YarnGeometry(0.1, 1.5)
    grids = TransportGrids(4, 2, 2)
    steps = absorption_steps(tabulated.mu_a, tabulated.mu_a + 1.0, ratio=2.0)
    for medium in (tabulated, single):
        simulate_yarn(medium, geometry, grids, paths_per_cell=8, seed=0)
    transport = simulate_yarn(tabulated, geometry, grids, paths_per_cell=8, seed=0, extra_absorption_per_mm=steps)
    done.append("yarn")
    for values in (transport.decayed.exit_fraction, transport.decayed.axial_bssrdf):  # float64 and float32
        interpolate_absorption(values, tabulated.mu_a, steps, tabulated.mu_a + 0.5, tabulated.wavelengths_nm)
    done.append("absorption reweighting")
    simulate_parallel_beam(tabulated, geometry, np.array([0.0, 0.6, 0.8]), n_around=4, angular_resolution=2, paths=64)
    done.append("parallel beam")
    for domain in ("hemisphere", "sphere"):
        grid = AngularGrid(domain, 2)
        grid.cell_of(grid.cell_centers())
    done.append("direction grids")
    return done


def main() -> int:
    start = time.perf_counter()
    compiled = compile_kernels()
    print(f"numba kernels ready ({', '.join(compiled)}) in {time.perf_counter() - start:.1f} s", file=sys.stderr)
    start = time.perf_counter()
    try:
        library = build_native_slab()
    except (RuntimeError, subprocess.CalledProcessError) as exc:  # the slab command falls back to numba
        detail = exc.stderr.decode(errors="replace").strip() if isinstance(exc, subprocess.CalledProcessError) else exc
        print(f"native slab library not built: {detail}", file=sys.stderr)
    else:
        print(f"native slab library ready ({library}) in {time.perf_counter() - start:.1f} s", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
