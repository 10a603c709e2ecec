"""``python -m clothlight.validate``: the virtual gonioreflectometer with Blender as a Python module.

The same arguments run in a real Blender through ``blender -b -P scripts/validate_blender.py -- …``,
and both call :func:`clothlight.validation.run.run_validation`, as the add-on's operator does.

Examples::

    python -m clothlight.validate --out out/validation                        # the paper's baseline
    python -m clothlight.validate --tables out/bake --measured cloth.csv --out out/validation

Exit codes: 0 done, 2 bad input (the message names it), 130 interrupted.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import pathlib
import sys


def build_parser() -> argparse.ArgumentParser:
    from .validation.rig import DEFAULT_RESOLUTION, DEFAULT_SAMPLES
    from .validation.run import MATERIALS

    parser = argparse.ArgumentParser(prog="python -m clothlight.validate", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", required=True,
                        help="output folder: results.json, report.md, sweeps.png, swatches/, renders/")
    parser.add_argument("--blend", help="open this .blend first (with the bpy module; a real Blender takes it "
                                        "before -P)")
    parser.add_argument("--object", metavar="NAME", help="measure this object of the open file (a ClothLight "
                                                          "sample) instead of building the default woven sample")
    parser.add_argument("--material", nargs="+", choices=MATERIALS,
                        help="materials to sweep (default: yarn and baseline with --tables, else baseline); "
                             "yarn_general is the general-lighting mode, compared with yarn when both run")
    parser.add_argument("--tables", help="bake folder of the yarn material (python -m precompute bake --out DIR)")
    parser.add_argument("--cloth-tables",
                        help="cloth bake folder of the garment material (python -m clothlight.garment bake --out DIR)")
    parser.add_argument("--measured", help="measured BRDF CSV (format: clothlight/validation/measured_data.py)")
    parser.add_argument("--incidences", type=float, nargs="+", metavar="DEG", help="θi, degrees (default 0 30 45 60)")
    parser.add_argument("--views", type=float, nargs="+", metavar="DEG",
                        help="θv, degrees, negative on the light's side (default -60 … 70 by 10)")
    parser.add_argument("--resolution", type=int, default=DEFAULT_RESOLUTION,
                        help=f"pixels along the patch side (default {DEFAULT_RESOLUTION})")
    parser.add_argument("--samples", type=int, default=DEFAULT_SAMPLES,
                        help=f"Cycles samples per pixel (default {DEFAULT_SAMPLES})")
    parser.add_argument("--seed", type=int, default=0, help="Cycles seed (default 0)")
    parser.add_argument("--patch-mm", type=float, help="side of the framed patch, mm (default: largest that fits)")
    parser.add_argument("--no-swatches", action="store_true", help="skip the front/back-lit colour swatches")
    parser.add_argument("--json", action="store_true", help="print the results as JSON on stdout")
    return parser


@contextlib.contextmanager
def stdout_to_stderr():
    """Send everything written to file descriptor 1 (Blender's render log included) to 2 meanwhile,
    so that stdout carries only the JSON."""
    sys.stdout.flush()
    saved = os.dup(1)
    os.dup2(2, 1)
    try:
        yield
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    import bpy

    from .addon import import_precompute
    from .validation.framing import DEFAULT_INCIDENCES_DEG, DEFAULT_VIEWS_DEG
    from .validation.measured_data import MeasurementFormatError
    from .validation.rig import RigSettings
    from .validation.run import run_validation
    from .weave import WeaveParameterError

    ParameterError = import_precompute("errors").ParameterError

    def progress(done: int, total: int, what: str) -> None:
        print(f"\r[{done}/{total}] {what:<48}", end="", file=sys.stderr, flush=True)

    if args.blend:
        bpy.ops.wm.open_mainfile(filepath=str(pathlib.Path(args.blend).resolve()))
    elif not args.object:
        bpy.ops.wm.read_homefile(use_empty=True)
    try:
        sample = None
        if args.object:
            sample = bpy.data.objects.get(args.object)
            if sample is None:
                raise ParameterError("object", args.object,
                                     f"an object of the open file: {sorted(bpy.data.objects.keys())}")
        settings = RigSettings(incidences_deg=tuple(args.incidences or DEFAULT_INCIDENCES_DEG),
                               views_deg=tuple(args.views or DEFAULT_VIEWS_DEG), resolution=args.resolution,
                               samples=args.samples, seed=args.seed, patch_mm=args.patch_mm)
        with stdout_to_stderr() if args.json else contextlib.nullcontext():
            results = run_validation(sample, args.out, materials=args.material, tables_dir=args.tables,
                                     cloth_dir=args.cloth_tables,
                                     measured_csv=args.measured, settings=settings, swatches=not args.no_swatches,
                                     progress=progress)
    except (ParameterError, WeaveParameterError, MeasurementFormatError) as error:
        print(f"\nerror: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("\ninterrupted", file=sys.stderr)
        return 130
    print(file=sys.stderr)
    if args.json:
        # The file is the results with NaN written as null: standard JSON.
        sys.stdout.write((pathlib.Path(args.out) / "results.json").read_text(encoding="utf-8"))
        return 0
    print(f"report: {args.out}/report.md")
    for kind, entry in results["materials"].items():
        ratios = entry["table1"]
        if ratios:
            print(f"{kind}: B/R {ratios['B/R']:.3g}, G/R {ratios['G/R']:.3g} at normal incidence and view")
    comparison = results.get("general_vs_sun")
    if comparison:
        print(f"general-lighting mode vs sun mode: RMS relative difference {comparison['RGB']['relative_rms']:.1%} "
              f"(red {comparison['R']['relative_rms']:.1%}) over {comparison['views_compared']} views")
    for kind, mode in (("garment", "sun mode"), ("garment_general", "general lighting")):
        comparison = results.get(f"{kind}_vs_yarn")
        if comparison:
            print(f"garment material ({mode}, flat patch) vs yarn sample: RMS relative difference "
                  f"{comparison['RGB']['relative_rms']:.1%} (red {comparison['R']['relative_rms']:.1%}) over "
                  f"{comparison['views_compared']} views")
    print(f"sweep: {results['seconds']['total']:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
