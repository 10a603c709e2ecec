"""Absorption without new transport (issue 19): a dye range from one simulation, against fresh ones.

The default red cotton's dye from 0.5 % to 5 %: one simulation at 0.5 % that also tallies its exits
at the steps up to 5 % (precompute/transport/absorption.py), then, per dye amount, the reweighted
BSSRDF → eq. (5) on the fit's incidence grid, against a fresh simulation at that dye with the same
budget (another seed) → eq. (5); by default both at the bake's error target.  Printed per dye
amount: the time of each, and the deviation of ρ summed over the incidence and exit cells, in
linear Rec.709 RGB, in percent and in units of the two estimates' combined standard error (exact
over the paths, an upper bound over the wavelengths, which share paths).

    python benchmarks/bench_absorption_reweighting.py [--target 0.01 | --paths N] [--dyes 0.5,1,2,3.5,5]
"""

from __future__ import annotations

import argparse
import os
import pathlib
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
from subject_medium import SUBJECT_PRESET

import numpy as np


def total_rho_rgb(transport, resolution: int):
    """ρ summed over the incidence cells of eq. (5) on ``resolution``² and over the exit cells, RGB (3,),
    and its standard error (3,): exact over the paths (each adds to one bin of the axial sum), an
    upper bound over the wavelengths (which share paths)."""
    from precompute.tables.color import spectral_stderr_to_rgb, spectral_to_rgb
    from precompute.tables.grids import AngularGrid
    from precompute.transport.brdf import source_weights

    weights = source_weights(transport, AngularGrid("sphere", resolution).cell_centers()).sum(axis=0)
    axial = transport.axial_bssrdf()  # (n_in, n_around, n_out, L)
    second = transport.bssrdf_axial_second_moment.astype(np.float64)
    total = np.einsum("cd,cdol->l", weights, axial)
    per_cell = np.einsum("cd,cdol->cl", weights, axial)
    per_path_square = np.einsum("cd,cdol->cl", weights**2, second)
    n = transport.paths_per_cell[:, None].astype(float)
    variance = (np.maximum(per_path_square - per_cell**2, 0.0) / (n - 1)).sum(axis=0)
    wavelengths = transport.wavelengths_nm
    return spectral_to_rgb(total, wavelengths), spectral_stderr_to_rgb(np.sqrt(variance), wavelengths)


def main() -> None:
    from precompute.bake import transport_settings
    from clothlight.fit.forward import FIT_INCIDENCE_RESOLUTION
    from precompute.optics.medium import load_preset_config, medium_from_dict
    from precompute.optics.coefficients import medium_optics
    from precompute.transport import TransportGrids, YarnGeometry, simulate_yarn, yarn_brdf
    from precompute.transport.absorption import absorption_steps, reweighted_transport

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    budget = parser.add_mutually_exclusive_group()
    budget.add_argument("--target", type=float, default=0.01,
                        help="every simulation's error target, as a bake's (default 0.01, the bake's default)")
    budget.add_argument("--paths", type=int, help="a fixed number of paths per incidence cell instead")
    parser.add_argument("--dyes", default="0.5,1,2,3.5,5", help="dye weight percents, the first the reference")
    args = parser.parse_args()
    dyes = [float(d) for d in args.dyes.split(",")]
    run_budget = {"paths_per_cell": args.paths} if args.paths else {"target_rel_stderr": args.target}

    config, base_dir = load_preset_config(SUBJECT_PRESET)

    def optics_at(dye: float):
        config["dye"]["weight_percent"] = dye
        return medium_optics(medium_from_dict(config, base_dir))

    settings = transport_settings(config)
    reference, largest = optics_at(dyes[0]), optics_at(max(dyes))
    geometry = YarnGeometry(medium_from_dict(config, base_dir).yarn.radius_mm, reference.boundary_index)
    grids = TransportGrids(settings["n_around"], settings["n_along"], settings["angular_resolution"])
    steps = absorption_steps(reference.mu_a, largest.mu_a)
    budget_text = f"{args.paths} paths per incidence cell" if args.paths else f"error target {args.target:g}"
    print(f"{os.cpu_count()} CPU cores; voided_red_cotton, Congo red {dyes[0]:g}–{max(dyes):g} %, {budget_text}, "
          f"{len(steps)} absorption steps; eq. (5) on {FIT_INCIDENCE_RESOLUTION}² incidence cells")
    simulate_yarn(reference, geometry, TransportGrids(4, 1, 2), paths_per_cell=64, seed=0,
                  extra_absorption_per_mm=steps[:3])  # compile outside the timings

    start = time.perf_counter()
    series = simulate_yarn(reference, geometry, grids, seed=1, extra_absorption_per_mm=steps, **run_budget)
    print(f"the series' simulation: {time.perf_counter() - start:.1f} s, {series.traced_paths} paths traced")
    print("dye %  reweight+eq5 s  fresh sim+eq5 s  speed-up   Σρ: reweighted / fresh − 1 (R, G, B)   in combined σ")
    for dye in dyes:
        optics = optics_at(dye)
        start = time.perf_counter()
        reweighted = reweighted_transport(series, optics.mu_a)
        yarn_brdf(reweighted, FIT_INCIDENCE_RESOLUTION)
        reweight_seconds = time.perf_counter() - start
        start = time.perf_counter()
        fresh = simulate_yarn(optics, geometry, grids, seed=2, **run_budget)
        yarn_brdf(fresh, FIT_INCIDENCE_RESOLUTION)
        fresh_seconds = time.perf_counter() - start
        (total_a, sigma_a), (total_b, sigma_b) = (total_rho_rgb(t, FIT_INCIDENCE_RESOLUTION)
                                                  for t in (reweighted, fresh))
        deviation = total_a / total_b - 1
        in_sigma = np.abs(total_a - total_b) / np.hypot(sigma_a, sigma_b)
        speed_up = fresh_seconds / reweight_seconds
        print(f"{dye:5.2f}  {reweight_seconds:14.2f}  {fresh_seconds:15.1f}  {speed_up:7.0f}×   "
              + "  ".join(f"{d:+7.2%}" for d in deviation) + "          "
              + "  ".join(f"{x:4.1f}" for x in in_sigma))


if __name__ == "__main__":
    main()
