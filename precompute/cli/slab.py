"""``python -m precompute slab``: the transport core on a slab, to check it against exact solutions.

A collimated beam falls normally on a plane-parallel slab of Henyey–Greenstein
medium (optical thickness τ, μt = 1/mm) of refractive index n between two media
of index 1.  Prints the total reflectance and transmittance (specular and
unscattered parts included, as iadpython's ``Sample(...).rt()`` gives them) with
their Monte-Carlo standard errors, then the parts.

The paths run in the native slab library where ``make setup`` built it for these sources
(:mod:`precompute.slab.native`: no numba, no NumPy, the same numbers bit for bit), else in numba's
kernel; ``--engine`` chooses.
"""

from __future__ import annotations

import argparse
import json

from precompute.bounds import SLAB_ALBEDO, SLAB_G, SLAB_INDEX, SLAB_PATHS, SLAB_SEED, SLAB_TAU
from precompute.errors import ParameterError

ENGINES = ("auto", "native", "numba")
KEYS = ("R_total", "R_total_stderr", "T_total", "T_total_stderr", "R_specular", "R_unscattered", "R_diffuse",
        "T_unscattered", "T_diffuse", "absorbed", "lost", "paths", "events")


def add_parser(subparsers) -> argparse.ArgumentParser:
    parser = subparsers.add_parser(
        "slab",
        help="Monte-Carlo R and T of a Henyey-Greenstein slab (collimated normal incidence)",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--albedo", type=SLAB_ALBEDO.argument("--albedo"), required=True,
                        help=f"single-scattering albedo, {SLAB_ALBEDO.allowed()}")
    parser.add_argument("--g", type=SLAB_G.argument("--g"), required=True,
                        help=f"Henyey-Greenstein asymmetry, {SLAB_G.allowed()}")
    parser.add_argument("--tau", type=SLAB_TAU.argument("--tau"), required=True,
                        help=f"optical thickness, {SLAB_TAU.allowed()}")
    parser.add_argument("--n", type=SLAB_INDEX.argument("--n"), default=1.0,
                        help=f"refractive index of the slab, {SLAB_INDEX.allowed()} (default 1)")
    parser.add_argument("--paths", type=SLAB_PATHS.argument("--paths"), default=1_000_000,
                        help=f"number of paths, {SLAB_PATHS.allowed()} (default 1e6; 1e6 notation allowed)")
    parser.add_argument("--seed", type=SLAB_SEED.argument("--seed"), default=0, help="random seed (default 0)")
    parser.add_argument("--threads", type=int, default=None, help="threads (default: all)")
    parser.add_argument("--engine", choices=ENGINES, default="auto",
                        help="native: the native slab library; numba: numba's kernel; auto (default): native where "
                             "it is built for these sources, else numba")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.set_defaults(func=run)
    return parser


def run(args) -> int:
    summary = slab_summary(args.albedo, args.g, args.tau, args.n, paths=args.paths, seed=args.seed,
                           threads=args.threads, engine=args.engine)
    summary = {key: summary[key] for key in KEYS}
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        for key in KEYS:
            print(f"{key:15s} {summary[key]}")
    return 0


def slab_summary(albedo: float, g: float, tau: float, index: float, *, paths: int, seed: int,
                 threads: int | None, engine: str) -> dict:
    """``simulate_hg_slab(...).summary()`` from ``engine`` (:data:`ENGINES`; the module docstring)."""
    if engine != "numba":
        from precompute.slab import native as native_slab  # neither numba nor NumPy

        library = native_slab.load_library()
        if library is not None:
            return native_slab.simulate_hg_slab_native(library, albedo, g, tau, index, paths=paths, seed=seed,
                                                       threads=threads)
        if engine == "native":
            raise ParameterError("--engine", "native", "an engine that is built: the native slab library is not "
                                 f"built for these sources ({native_slab.library_path()}); run make setup")
    from precompute.transport import simulate_hg_slab

    return simulate_hg_slab(albedo, g, tau, index, paths=paths, seed=seed, threads=threads).summary()
