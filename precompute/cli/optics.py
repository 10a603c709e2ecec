"""``python -m precompute optics``: print a medium's per-wavelength optics (and optionally plot them).

Prints μs, μa, μt (1/mm), albedo and g per wavelength, as a table or as JSON,
with the cos θ grid of the phase tables (chosen when ``phase_samples`` is "auto"),
together with the Percus–Yevick change factors ``μs_PY / μs`` and
``g_PY / g`` (dependent vs independent scattering), which are always computed
so that the size of the dense-medium correction is in view.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys

import numpy as np

from precompute.cli.arguments import preset_argument
from precompute.optics.medium import DEFAULT_PRESET, MediumParameters, load_preset, preset_names
from precompute.optics.coefficients import MediumOptics, medium_optics
from precompute.outputs import check_writable_file


def add_parser(subparsers) -> argparse.ArgumentParser:
    parser = subparsers.add_parser(
        "optics",
        help="per-wavelength μs, μa, albedo, g of a yarn medium",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    source = parser.add_mutually_exclusive_group()
    source.add_argument(
        "--preset", metavar="NAME", help=f"a shipped preset: {', '.join(preset_names())} (default {DEFAULT_PRESET})"
    )
    source.add_argument("--config", metavar="PATH", help="a preset TOML file")
    parser.add_argument(
        "--percus-yevick", action="store_true", help="report the Percus–Yevick (dependent scattering) optics"
    )
    parser.add_argument("--plot", metavar="PNG", help="also write a plot of the optics to this PNG file")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.set_defaults(func=run)
    return parser


def _with_model(params: MediumParameters, model: str) -> MediumParameters:
    return params if params.dependent_scattering == model else dataclasses.replace(params, dependent_scattering=model)


def _report(params: MediumParameters, optics: MediumOptics, independent: MediumOptics, corrected: MediumOptics) -> dict:
    return {
        "preset": params.name,
        "description": params.description,
        "dependent_scattering": optics.dependent_scattering,
        "boundary_index": optics.boundary_index,
        "yarn_radius_mm": params.yarn.radius_mm,
        "wavelengths_nm": optics.wavelengths_nm.tolist(),
        "mu_s_per_mm": optics.mu_s.tolist(),
        "mu_a_per_mm": optics.mu_a.tolist(),
        "mu_t_per_mm": optics.mu_t.tolist(),
        "albedo": optics.albedo.tolist(),
        "g": optics.g.tolist(),
        "host_index": optics.host_index.tolist(),
        "phase_samples": params.phase_samples,
        "phase_grid": {"kind": optics.phase_grid, "samples": optics.phase_samples},
        "percus_yevick_factor": {
            "mu_s": _ratio(corrected.mu_s, independent.mu_s),
            "g": _ratio(corrected.g, independent.g),
        },
    }


def _ratio(numerator: np.ndarray, denominator: np.ndarray) -> list[float | None]:
    """Element-wise ratio; ``None`` (JSON null) where the denominator is 0."""
    return [float(n / d) if d != 0 else None for n, d in zip(numerator, denominator)]


def _print_table(report: dict) -> None:
    model = report["dependent_scattering"]
    print(f"medium {report['preset']}: {report['description']}")
    print(f"scattering model: {'independent (as in the paper)' if model == 'none' else model}")
    print(f"boundary index {report['boundary_index']:.4f}, yarn radius {report['yarn_radius_mm']:g} mm")
    grid = report["phase_grid"]
    print(f"phase tables: {grid['samples']} cos θ samples, {grid['kind']} "
          f"(phase_samples = {report['phase_samples']!r})")
    header = (
        f"{'λ nm':>7} {'μs 1/mm':>11} {'μa 1/mm':>11} {'μt 1/mm':>11} {'albedo':>8} {'g':>7} {'PY μs×':>7} {'PY g×':>7}"
    )
    print(header)
    print("-" * len(header))
    factors = report["percus_yevick_factor"]
    for row in zip(
        report["wavelengths_nm"],
        report["mu_s_per_mm"],
        report["mu_a_per_mm"],
        report["mu_t_per_mm"],
        report["albedo"],
        report["g"],
        factors["mu_s"],
        factors["g"],
    ):
        wl, mu_s, mu_a, mu_t, albedo, g, f_s, f_g = (np.nan if v is None else v for v in row)
        print(f"{wl:7.1f} {mu_s:11.4g} {mu_a:11.4g} {mu_t:11.4g} {albedo:8.4f} {g:7.4f} {f_s:7.3f} {f_g:7.3f}")
    f_s, f_g = (np.array(factors[key], dtype=float) for key in ("mu_s", "g"))
    if np.all(np.isnan(f_s)):
        print("Percus–Yevick vs independent: nothing scatters")
        return
    print(
        f"Percus–Yevick vs independent: μs × {np.nanmin(f_s):.3f}–{np.nanmax(f_s):.3f}, "
        f"g × {np.nanmin(f_g):.3f}–{np.nanmax(f_g):.3f} over the grid"
    )


def run(args: argparse.Namespace) -> int:
    if args.plot:  # before any work
        check_writable_file(args.plot, "--plot", what="a PNG file")
    params = load_preset(preset_argument(args))
    independent = medium_optics(_with_model(params, "none"))
    corrected = medium_optics(_with_model(params, "percus-yevick"))
    chosen_model = "percus-yevick" if args.percus_yevick else params.dependent_scattering
    optics, other = (corrected, independent) if chosen_model == "percus-yevick" else (independent, corrected)
    report = _report(params, optics, independent, corrected)
    if args.plot:
        from precompute.optics.plots import plot_medium_optics  # matplotlib only when a plot is asked for

        other_label = "independent" if other.dependent_scattering == "none" else other.dependent_scattering
        path = plot_medium_optics(
            optics,
            args.plot,
            title=f"{params.name}: {params.description}",
            comparison=other,
            comparison_label=other_label,
        )
        report["plot"] = str(path)
    if args.json:
        json.dump(report, sys.stdout, indent=1)
        print()
    else:
        _print_table(report)
        if args.plot:
            print(f"plot: {report['plot']}")
    return 0
