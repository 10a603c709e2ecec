"""``python -m clothlight.garment bake``: measure a cloth BSDF on the woven sample and bake it.

Example::

    python -m precompute bake --out out/bake                       # the yarn (paper's red cotton)
    python -m clothlight.garment bake --tables out/bake --out out/cloth
    python -m clothlight.validate --tables out/bake --cloth-tables out/cloth \\
        --material yarn garment --out out/garment_validation       # flat patch vs yarn sample

Exit codes: 0 done, 2 bad input (the message names it), 130 interrupted, 1 a failure writing the output.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import shutil
import sys
import time

from .measure import GoniometerSettings


def build_parser() -> argparse.ArgumentParser:
    defaults = GoniometerSettings()
    parser = argparse.ArgumentParser(prog="python -m clothlight.garment", description=__doc__.split("\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    bake = commands.add_parser("bake", help="measure the cloth BSDF and write its tables (cached)")
    bake.add_argument("--tables", required=True, help="yarn bake folder (python -m precompute bake --out DIR)")
    bake.add_argument("--out", required=True, help="folder for the cloth tables and summary.json, written as a "
                      "whole (a new folder, or an earlier cloth bake's, which it replaces)")
    bake.add_argument("--incidence-resolution", type=int, default=defaults.incidence_resolution,
                      help=f"N_i, odd (default {defaults.incidence_resolution}: {defaults.incidence_resolution ** 2} "
                           "incidence cells over the sphere)")
    bake.add_argument("--exit-resolution", type=int, default=defaults.exit_resolution,
                      help=f"N_o per side (default {defaults.exit_resolution}): 2·N_o² renders")
    bake.add_argument("--pixels-per-patch", type=int, default=defaults.pixels_per_patch,
                      help=f"pixels across a patch's foreshortened side (default {defaults.pixels_per_patch})")
    bake.add_argument("--samples", type=int, default=defaults.samples,
                      help=f"Cycles samples per pixel (default {defaults.samples})")
    bake.add_argument("--cache-dir", help="cache folder (default: the user cache)")
    bake.add_argument("--json", action="store_true", help="print summary.json on stdout")
    return parser


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    import bpy

    from ..addon import import_precompute
    from .bake import bake_cloth, read_summary
    from .tables import CLOTH_FOLDER_FILES, check_cloth_table_folder

    ParameterError = import_precompute("errors").ParameterError
    table_folder = import_precompute("table_folder")
    bpy.ops.wm.read_homefile(use_empty=True)
    start = time.perf_counter()

    def progress(done: int, total: int, what: str) -> None:
        elapsed = time.perf_counter() - start
        print(f"\r[{done}/{total}] {what:<32} {elapsed:6.0f} s, ~{elapsed / done * (total - done):.0f} s left",
              end="", file=sys.stderr, flush=True)

    try:
        table_folder.check_output_folder(args.out, CLOTH_FOLDER_FILES)  # before minutes of renders
        settings = GoniometerSettings(incidence_resolution=args.incidence_resolution,
                                      exit_resolution=args.exit_resolution,
                                      pixels_per_patch=args.pixels_per_patch, samples=args.samples)
        folder, measured = bake_cloth(args.tables, settings, cache_dir=args.cache_dir, progress=progress)
    except (ParameterError, FileNotFoundError, ValueError) as error:
        print(f"\nerror: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("\ninterrupted", file=sys.stderr)
        return 130

    def write(staging: pathlib.Path) -> None:
        for name in CLOTH_FOLDER_FILES:
            if (folder / name).is_file():
                shutil.copy2(folder / name, staging / name)
        check_cloth_table_folder(staging)

    try:  # the folder as a whole: a reader, or a kill at any moment, finds the previous one or this one
        out = table_folder.replace_folder(args.out, write, CLOTH_FOLDER_FILES)
    except ParameterError as error:
        print(f"\nerror: {error}", file=sys.stderr)
        return 2
    except (ValueError, OSError) as error:  # a damaged cache entry, a full disk
        print(f"\nerror: {error}", file=sys.stderr)
        return 1
    summary = read_summary(out)
    if args.json:
        sys.stdout.write(json.dumps(summary, indent=1) + "\n")
        return 0
    print(file=sys.stderr)
    print(f"cloth tables: {out} ({'measured' if measured else 'from the cache'}, "
          f"{summary['seconds']['renders']:.0f} s of renders)")
    print(f"energy: reflected + transmitted + open ≤ {summary['energy']['max_total']:.3f} of the incident flux")
    fit = summary["closure_fit_relative_error_median_rgb"]
    print("closure fit, median relative error (R, G, B): "
          + "; ".join(f"{side} {', '.join(f'{e:.2f}' for e in fit[side])}" for side in fit))
    print(f"coverage at normal view: {summary['coverage_normal']['front']:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
