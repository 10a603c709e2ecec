"""``python -m clothlight.validate``: the validation sweep with Blender as a Python module.

The same code runs in a real Blender through ``blender -b -P scripts/validate_blender.py -- <args>``.
"""

from __future__ import annotations

import argparse
import json
import sys


def parse_args(argv=None):
    parser = argparse.ArgumentParser(prog="python -m clothlight.validate", description=__doc__)
    parser.add_argument("--out", required=True, help="output folder (results.json, sweeps.png, report.md)")
    parser.add_argument("--tables", help="a bake folder (python -m precompute bake --out DIR); omitted: baseline only")
    parser.add_argument("--measured", help="measured BRDF CSV (clothlight/validation/measured_data.py format)")
    parser.add_argument("--incidences", type=float, nargs="+", help="θi in degrees (default 0 30 45 60)")
    parser.add_argument("--views", type=float, nargs="+", help="θv in degrees (default -60 … 70 by 10)")
    parser.add_argument("--resolution", type=int, help="pixels per side (default 48)")
    parser.add_argument("--samples", type=int, help="samples per pixel (default 4)")
    parser.add_argument("--json", action="store_true", help="print the results as JSON")
    return parser.parse_args(argv)


def main(argv=None) -> int:
    args = parse_args(argv)
    import bpy

    from .validation.rig import DEFAULT_INCIDENCES_DEG, DEFAULT_VIEWS_DEG, RigSettings
    from .validation.run import run_validation

    bpy.ops.wm.read_homefile(use_empty=True)
    settings = RigSettings(**{k: v for k, v in (("resolution", args.resolution), ("samples", args.samples)) if v})
    results = run_validation(
        args.out, tables_dir=args.tables, settings=settings,
        incidences=tuple(args.incidences or DEFAULT_INCIDENCES_DEG), views=tuple(args.views or DEFAULT_VIEWS_DEG),
        measurement_csv=args.measured,
        progress=lambda f: print(f"\rvalidation {100 * f:5.1f} %", end="", file=sys.stderr, flush=True),
    )
    print(file=sys.stderr)
    if args.json:
        print(json.dumps(results, indent=2))
    else:
        print(f"report: {args.out}/report.md")
        for label, ratios in results["table1_ratios"].items():
            print(f"{label}: B/R {ratios['B/R']:.4g}, G/R {ratios['G/R']:.4g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
