"""``python -m clothlight.validate``: the virtual gonioreflectometer with Blender as a Python module.

The same arguments run in a real Blender through ``blender -b -P scripts/validate_blender.py -- …``,
and both call :func:`clothlight.blender.validation.run.run_validation`, as the add-on's operator does.

Examples::

    python -m clothlight.validate --out out/validation                        # the paper's baseline
    python -m clothlight.validate --tables out/bake --measured cloth.csv --out out/validation
    python -m clothlight.validate --tables out/bake --sample-azimuths 0 45 90 135 --out out/validation

Exit codes (``precompute/exit_codes.py``, the same for every ClothLight command): 0 done, 2 bad
input (the message names the option or file and what is allowed), 130 interrupted, 1 an internal
error.  The arguments are checked, the output folder and the input files included, before Blender
is imported.
"""

from __future__ import annotations

try:  # a Ctrl-C before the handler in main() is in place still exits with 130, without a traceback
    import contextlib
    import math
    import os
    import pathlib
    import sys

except KeyboardInterrupt:
    if __name__ != "__main__":
        raise
    print("interrupted", file=__import__("sys").stderr)
    raise SystemExit(130) from None

#: How a .blend file starts: uncompressed, gzip- or zstd-compressed.
BLEND_MAGIC = (b"BLENDER", b"\x1f\x8b", b"\x28\xb5\x2f\xfd")


def build_parser():
    """The arguments (shared with ``scripts/validate_blender.py``); no Blender needed."""
    import argparse

    from .render_bounds import (
        DEFAULT_VALIDATION_RESOLUTION as DEFAULT_RESOLUTION,
        DEFAULT_VALIDATION_SAMPLES as DEFAULT_SAMPLES,
        VALIDATION_PATCH_MM,
        VALIDATION_RESOLUTION,
        VALIDATION_SAMPLES,
        VALIDATION_SEED,
    )
    from .validation.framing import MATERIALS

    parser = argparse.ArgumentParser(prog="python -m clothlight.validate", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", required=True,
                        help="output folder: results.json, report.md, sweeps.png, swatches/, renders/")
    parser.add_argument("--blend", help="open this .blend first (with the bpy module; a real Blender takes it "
                                        "before -P)")
    parser.add_argument("--object", metavar="NAME", help="measure this object of the open file (a ClothLight "
                                                          "sample) instead of building the default woven sample "
                                                          "(the --tables' sample weave, [sample], where they name one)")
    parser.add_argument("--material", nargs="+", choices=MATERIALS,
                        help="materials to sweep (default: yarn and baseline with --tables, else baseline); "
                             "yarn_general is the general-lighting mode, compared with yarn when both run; "
                             "yarn_scene is that mode path traced (light between yarns), compared with "
                             "yarn_general when both run")
    parser.add_argument("--tables", help="bake folder of the yarn material (python -m precompute bake --out DIR)")
    parser.add_argument("--cloth-tables",
                        help="cloth bake folder of the garment material (python -m clothlight.garment bake --out DIR)")
    parser.add_argument("--measured", help="measured BRDF CSV (format: precompute/fit/measured_data.py)")
    parser.add_argument("--incidences", type=float, nargs="+", metavar="DEG", help="θi, degrees (default 0 30 45 60)")
    parser.add_argument("--views", type=float, nargs="+", metavar="DEG",
                        help="θv, degrees, negative on the light's side (default -60 … 70 by 10)")
    parser.add_argument("--resolution", type=VALIDATION_RESOLUTION.argument("--resolution"), default=DEFAULT_RESOLUTION,
                        help=f"pixels along the patch side, {VALIDATION_RESOLUTION.allowed()} "
                             f"(default {DEFAULT_RESOLUTION})")
    parser.add_argument("--samples", type=VALIDATION_SAMPLES.argument("--samples"), default=DEFAULT_SAMPLES,
                        help=f"Cycles samples per pixel, {VALIDATION_SAMPLES.allowed()} (default {DEFAULT_SAMPLES})")
    parser.add_argument("--seed", type=VALIDATION_SEED.argument("--seed"), default=0, help="Cycles seed (default 0)")
    parser.add_argument("--scheduler", metavar="local|tcp://HOST:PORT|none",
                        help="where the renders run: 'local', a worker per core of this machine; a scheduler "
                             "address, a cluster started with `dask scheduler` / `dask worker` "
                             "(docs/distributed.md); 'none', this process (default: 'local' where dask is "
                             "installed and the sample is built here, else 'none': a --blend or --object sample "
                             "renders here). The results are the same wherever they rendered")
    parser.add_argument("--patch-mm", type=VALIDATION_PATCH_MM.argument("--patch-mm"),
                        help=f"side of the framed patch, {VALIDATION_PATCH_MM.allowed()} (default: largest that fits)")
    parser.add_argument("--sample-azimuths", type=float, nargs="+", metavar="DEG",
                        help="the warp's azimuths from the plane of incidence, degrees, ascending in [0, 180), as a "
                             "preset's [sample] azimuths_deg: every view is rendered with the sample turned to each "
                             "(the sun and cameras turned about its normal) and averaged (default: the --tables "
                             "bake's, where its summary records them, else one turn at 0)")
    parser.add_argument("--no-swatches", action="store_true", help="skip the front/back-lit colour swatches")
    parser.add_argument("--specular-weight", type=float, metavar="W",
                        help="the yarn materials' SpecularWeight in place of the bake's (a number ≥ 0; 0: the "
                             "cloth without its sheen)")
    parser.add_argument("--json", action="store_true", help="print the results as JSON on stdout")
    return parser


def check_arguments(args) -> None:
    """Every argument that can be checked without Blender, before Blender is imported and any work
    starts: the output folder, the input files and folders, the angles (the numbers are checked as
    they are parsed).  ParameterError (or MeasurementFormatError) naming the option otherwise."""
    from .validation.framing import ParameterError, check_angles, sweep_sample_azimuths
    from precompute.fit.measured_data import read_measurement

    from precompute.tables.folder import check_output_folder
    from .validation.report import VALIDATION_FOLDER_NAMES
    check_output_folder(args.out, VALIDATION_FOLDER_NAMES, "--out", job="validation")
    from precompute import distributed
    if args.scheduler is None:
        args.scheduler = None if (args.blend or args.object) else distributed.default_scheduler()
    else:
        args.scheduler = distributed.check_scheduler(args.scheduler)
        if args.scheduler is not None and (args.blend or args.object):
            raise ParameterError("--scheduler", args.scheduler, "'none' with --blend or --object: a cluster's "
                                 "workers build the sample from a weave")
    if args.blend is not None:
        blend = pathlib.Path(args.blend)
        if not blend.is_file():
            raise ParameterError("--blend", args.blend, "an existing .blend file" + (" (this is a folder)"
                                                                                   if blend.is_dir() else ""))
        try:
            with blend.open("rb") as file:
                head = file.read(8)
        except OSError as error:
            raise ParameterError("--blend", args.blend,
                                 f"a .blend file this user can read ({error.strerror})") from None
        if not head.startswith(BLEND_MAGIC):
            raise ParameterError("--blend", args.blend, "a .blend file (this one does not start as Blender's files do)")
    for option, folder in (("--tables", args.tables), ("--cloth-tables", args.cloth_tables)):
        if folder is not None and not pathlib.Path(folder).is_dir():
            raise ParameterError(option, folder, "an existing bake folder")
    args.sample_azimuths = sweep_sample_azimuths(args.sample_azimuths, args.tables, "--sample-azimuths")
    if args.specular_weight is not None and not (math.isfinite(args.specular_weight) and args.specular_weight >= 0):
        raise ParameterError("--specular-weight", args.specular_weight, "a finite number ≥ 0")
    if args.measured is not None:
        if not pathlib.Path(args.measured).is_file():
            raise ParameterError("--measured", args.measured, "an existing measurement file")
        read_measurement(args.measured)  # MeasurementFormatError naming the file and the row
    from .validation.framing import DEFAULT_INCIDENCES_DEG, DEFAULT_VIEWS_DEG

    check_angles(tuple(args.incidences or DEFAULT_INCIDENCES_DEG), tuple(args.views or DEFAULT_VIEWS_DEG))


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


def _sweep(args, interrupt) -> dict:
    from .blender import scene_files
    from .blender.validation.rig import RigSettings
    from .blender.validation.run import run_validation
    from .validation.framing import DEFAULT_INCIDENCES_DEG, DEFAULT_VIEWS_DEG, ParameterError, tables_sample_weave

    interrupt.check()
    settings = RigSettings(incidences_deg=tuple(args.incidences or DEFAULT_INCIDENCES_DEG),
                           views_deg=tuple(args.views or DEFAULT_VIEWS_DEG), resolution=args.resolution,
                           samples=args.samples, seed=args.seed, patch_mm=args.patch_mm,
                           sample_azimuths_deg=args.sample_azimuths)
    progress_shown = []

    def progress(done: int, total: int, what: str) -> None:
        progress_shown.append(True)
        print(f"\r[{done}/{total}] {what:<48}", end="", file=sys.stderr, flush=True)
        interrupt.check()  # after a render: the sweep removes its rig on the way out

    if args.blend:
        reason = scene_files.open_blend_file(args.blend)
        if reason is not None:
            raise ParameterError("--blend", args.blend, f"a .blend file Blender can open ({reason})")
    elif not args.object:
        scene_files.open_empty_file()
    interrupt.check()
    sample = None
    if args.object:
        sample = scene_files.object_named(args.object)
        if sample is None:
            raise ParameterError("--object", args.object, f"an object of the open file: {scene_files.object_names()}")
    elif args.tables:
        sample = tables_sample_weave(args.tables)
    try:
        with stdout_to_stderr() if args.json else contextlib.nullcontext():
            return run_validation(sample, args.out, scheduler=args.scheduler, materials=args.material,
                                  tables_dir=args.tables, cloth_dir=args.cloth_tables, measured_csv=args.measured,
                                  settings=settings, swatches=not args.no_swatches,
                                  specular_weight=args.specular_weight, progress=progress)
    finally:
        if progress_shown:
            print(file=sys.stderr)  # end the progress line: what follows starts on its own


def main(argv=None) -> int:
    """Run the sweep; the exit code (module docstring)."""
    from precompute import exit_codes
    return exit_codes.run_cli(lambda: _main(argv))


def _main(argv) -> int:
    from precompute import exit_codes
    from precompute.cli.arguments import parse_arguments

    args = parse_arguments(build_parser(), sys.argv[1:] if argv is None else argv)
    check_arguments(args)
    # Blender prints and swallows an exception raised in its callbacks (Cycles' render engine): a
    # Ctrl-C is held and raised between renders instead, so it always stops the sweep (code 130).
    with exit_codes.DeferredInterrupt("interrupting after the current render…") as interrupt:
        results = _sweep(args, interrupt)
    if args.json:
        # The file is the results with NaN written as null: standard JSON.
        sys.stdout.write((pathlib.Path(args.out) / "results.json").read_text(encoding="utf-8"))
        return 0
    print(f"report: {args.out}/report.md")
    if len(results["sample_azimuths_deg"]) > 1:
        print("sample averaged over its azimuth: the warp at "
              + ", ".join(f"{a:g}°" for a in results["sample_azimuths_deg"]) + " from the plane of incidence")
    for kind, entry in results["materials"].items():
        ratios = entry["table1"]
        if ratios:
            print(f"{kind}: B/R {ratios['B/R']:.3g}, G/R {ratios['G/R']:.3g} at normal incidence and view")
    comparison = results.get("general_vs_sun")
    if comparison:
        print(f"general-lighting mode vs sun mode: RMS relative difference {comparison['RGB']['relative_rms']:.1%} "
              f"(red {comparison['R']['relative_rms']:.1%}) over {comparison['views_compared']} views")
    light = results.get("interreflection")
    if light and light["R"]:
        print("light between yarns (yarn_scene / yarn_general): "
              + ", ".join(f"{c} mean {light[c]['mean']:.3g}, max {light[c]['max']:.3g} at θi = "
                          f"{light[c]['max_at']['theta_i_deg']:g}°, θv = {light[c]['max_at']['theta_v_deg']:g}°"
                          for c in ("R", "G", "B") if light[c]))
    for kind, mode in (("garment", "sun mode"), ("garment_general", "general lighting")):
        for sample, what in (("yarn", "yarn sample"), ("yarn_scene", "yarn sample in a scene")):
            comparison = results.get(f"{kind}_vs_{sample}")
            if comparison:
                print(f"garment material ({mode}, flat patch) vs {what}: RMS relative difference "
                      f"{comparison['RGB']['relative_rms']:.1%} (red {comparison['R']['relative_rms']:.1%}) over "
                      f"{comparison['views_compared']} views")
    comparison = results.get("garment_general_vs_garment")
    if comparison:
        print(f"garment material, general lighting vs sun mode (the closure mixture's own error): RMS relative "
              f"difference {comparison['RGB']['relative_rms']:.1%} (red {comparison['R']['relative_rms']:.1%}, "
              f"green {comparison['G']['relative_rms']:.1%}, blue {comparison['B']['relative_rms']:.1%}) over "
              f"{comparison['views_compared']} views")
    print(f"sweep: {results['seconds']['total']:.1f} s")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:  # between main's return and the exit
        sys.exit(130)
