"""``python -m precompute slab``: the transport core on a slab, to check it against exact solutions."""

from __future__ import annotations

import json

from ..transport import simulate_hg_slab


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "slab",
        help="Monte-Carlo R and T of a Henyey-Greenstein slab (collimated normal incidence)",
        description="Total reflectance and transmittance, specular and unscattered parts included, "
        "of a slab of optical thickness tau (mu_t = 1/mm) between two media of index 1.",
    )
    parser.add_argument("--albedo", type=float, required=True, help="single-scattering albedo, [0, 1]")
    parser.add_argument("--g", type=float, required=True, help="Henyey-Greenstein asymmetry, (-1, 1)")
    parser.add_argument("--tau", type=float, required=True, help="optical thickness, > 0")
    parser.add_argument("--n", type=float, default=1.0, help="refractive index of the slab, >= 1 (default 1)")
    parser.add_argument("--paths", type=int, default=1_000_000, help="number of paths (default 1e6)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.set_defaults(func=run)


def run(args) -> int:
    result = simulate_hg_slab(args.albedo, args.g, args.tau, args.n, paths=args.paths, seed=args.seed)
    summary = result.as_dict()
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        for key in ("R_total", "R_total_stderr", "T_total", "T_total_stderr", "R_specular", "R_unscattered",
                    "R_diffuse", "T_unscattered", "T_diffuse", "absorbed", "paths", "events"):
            print(f"{key:15s} {summary[key]}")
    return 0
