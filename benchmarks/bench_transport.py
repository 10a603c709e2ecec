"""Transport speed: paths/s and scattering events/s per core, and the default bake's wall time.

Figures are printed, never asserted.  Targets (issue 4): >= 10 M events/s per core on the slab;
the default red-cotton tables (16 x 8 spatial, 144 x 144 angular, 35 wavelengths) to <= 1 %
relative standard error on every incidence cell's albedo in <= 60 s on 2 cores.
"""

import pathlib
import resource
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

import numba  # noqa: E402

from precompute.medium import load_preset  # noqa: E402
from precompute.optics import medium_optics  # noqa: E402
from precompute.transport import (  # noqa: E402
    TransportGrids,
    YarnGeometry,
    simulate_hg_slab,
    simulate_yarn,
    yarn_brdf,
)


def slab(threads: int) -> None:
    numba.set_num_threads(threads)
    simulate_hg_slab(0.9, 0.75, 2.0, 1.0, paths=10_000)  # compile
    start = time.perf_counter()
    result = simulate_hg_slab(0.9, 0.75, 2.0, 1.0, paths=2_000_000, seed=1)
    seconds = time.perf_counter() - start
    print(f"van de Hulst slab, {threads} thread(s): {result.paths / seconds / threads / 1e6:.2f} M paths/s/core, "
          f"{result.events / seconds / threads / 1e6:.2f} M events/s/core  "
          f"(R = {result.R_total[0]:.5f} ± {result.R_total_stderr[0]:.5f}, T = {result.T_total[0]:.5f} ± {result.T_total_stderr[0]:.5f})")


def yarn(threads: int) -> None:
    numba.set_num_threads(threads)
    optics = medium_optics(load_preset("red_cotton"))
    geometry = YarnGeometry(0.1, optics.boundary_index)
    simulate_yarn(optics, geometry, TransportGrids(16, 8, 4), paths_per_cell=50)  # compile
    start = time.perf_counter()
    transport = simulate_yarn(optics, geometry, TransportGrids(16, 8, 12), paths_per_cell=4000, seed=2)
    seconds = time.perf_counter() - start
    paths = transport.paths_per_cell.sum()
    print(f"red-cotton yarn (35 wavelengths), {threads} thread(s): {paths / seconds / threads / 1e3:.0f} k paths/s/core, "
          f"{transport.events / seconds / threads / 1e6:.2f} M events/s/core")


def default_bake() -> None:
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    optics = medium_optics(load_preset("red_cotton"))
    geometry = YarnGeometry(0.1, optics.boundary_index)
    start = time.perf_counter()
    transport = simulate_yarn(optics, geometry, TransportGrids(16, 8, 12), target_rel_stderr=0.01, seed=0)
    simulated = time.perf_counter() - start
    brdf = yarn_brdf(transport, 12)
    total = time.perf_counter() - start
    print(f"default red-cotton tables to 1 % albedo error on {numba.get_num_threads()} threads: transport {simulated:.1f} s, "
          f"with the BRDF integration {total:.1f} s; {transport.paths_per_cell.sum():,} paths, "
          f"{transport.events:,} scattering events; worst counted albedo rel. error "
          f"{transport.counted_albedo_rel_stderr().max():.4f}; BRDF {brdf.rho.shape}")
    print(f"peak RSS {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MiB")


if __name__ == "__main__":
    for threads in (1, numba.config.NUMBA_NUM_THREADS):
        slab(threads)
    for threads in (1, numba.config.NUMBA_NUM_THREADS):
        yarn(threads)
    default_bake()
