"""``python -m clothlight.garment bake``: measure a cloth BSDF on the woven sample and bake it.

By default the measurement is read off the weave's cloth response (traced once per weave and
gonioreflectometer settings, in seconds, cached; then seconds for any yarn); ``--method render`` renders the
measurement with the yarn itself, the response's check (docs/garment.md).

Example::

    python -m precompute bake --out out/bake                       # the yarn (paper's red cotton)
    python -m clothlight.garment bake --tables out/bake --out out/cloth
    python -m clothlight.validate --tables out/bake --cloth-tables out/cloth \\
        --material yarn garment --out out/garment_validation       # flat patch vs yarn sample

Exit codes (``precompute/exit_codes.py``, the same for every ClothLight command): 0 done, 2 bad
input (the message names the option or file and what is allowed), 130 interrupted, 1 an internal
error (a full disk, a damaged cache entry).  The arguments, the output and cache folders included,
are checked before Blender is imported.
"""

from __future__ import annotations

try:  # a Ctrl-C before the handler in main() is in place still exits with 130, without a traceback
    import json
    import pathlib
    import shutil
    import sys
    import time

except KeyboardInterrupt:
    if __name__ != "__main__":
        raise
    print("interrupted", file=__import__("sys").stderr)
    raise SystemExit(130) from None


def build_parser():
    import argparse

    from ..render_bounds import (
        DEFAULT_GONIO_EXIT_RESOLUTION as n_o,
        DEFAULT_GONIO_INCIDENCE_RESOLUTION as n_i,
        DEFAULT_GONIO_PIXELS_PER_PATCH as pixels,
        DEFAULT_GONIO_SAMPLES as samples,
        GONIO_EXIT_RESOLUTION,
        GONIO_INCIDENCE_RESOLUTION,
        GONIO_PIXELS_PER_PATCH,
        GONIO_SAMPLES,
    )
    from ..blender.garment.density import DEFAULT_THREADS_PER_CM, THREADS_PER_CM
    from .goniometry import MEASUREMENT_METHODS

    parser = argparse.ArgumentParser(prog="python -m clothlight.garment", description=__doc__.split("\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    bake = commands.add_parser("bake", help="measure the cloth BSDF and write its tables (cached)")
    bake.add_argument("--tables", required=True, help="yarn bake folder (python -m precompute bake --out DIR)")
    bake.add_argument("--out", required=True, help="folder for the cloth tables and summary.json, written as a "
                      "whole (a new folder, or an earlier cloth bake's, which it replaces)")
    bake.add_argument("--incidence-resolution", type=GONIO_INCIDENCE_RESOLUTION.argument("--incidence-resolution"),
                      default=n_i, help=f"N_i, {GONIO_INCIDENCE_RESOLUTION.allowed()} (default {n_i}: {n_i ** 2} "
                                        "incidence cells over the sphere)")
    bake.add_argument("--exit-resolution", type=GONIO_EXIT_RESOLUTION.argument("--exit-resolution"), default=n_o,
                      help=f"N_o per side, {GONIO_EXIT_RESOLUTION.allowed()} (default {n_o}): 2·N_o² renders")
    bake.add_argument("--pixels-per-patch", type=GONIO_PIXELS_PER_PATCH.argument("--pixels-per-patch"),
                      default=pixels,
                      help=f"pixels across a patch's foreshortened side, {GONIO_PIXELS_PER_PATCH.allowed()} "
                           f"(default {pixels})")
    bake.add_argument("--samples", type=GONIO_SAMPLES.argument("--samples"), default=samples,
                      help=f"Cycles samples per pixel, {GONIO_SAMPLES.allowed()} (default {samples})")
    bake.add_argument("--threads-per-cm", type=THREADS_PER_CM.argument("--threads-per-cm"),
                      default=DEFAULT_THREADS_PER_CM,
                      help=f"warp and weft threads per cm of the measured weave (the validation weave's yarns at "
                           f"a spacing of 10/N mm), {THREADS_PER_CM.allowed()} (default {DEFAULT_THREADS_PER_CM}, "
                           "the validation weave's: the shipped cloth tables). Each density traces its own "
                           "cloth response once (about 30 s on 2 cores), then seconds per yarn")
    bake.add_argument("--method", choices=MEASUREMENT_METHODS, default=MEASUREMENT_METHODS[0],
                      help="response: read the measurement off the weave's cloth response, traced once per weave "
                           "and these settings (cached), seconds for each yarn; render: render it with this yarn, "
                           "the response's check (default: %(default)s)")
    from precompute import distributed
    default_scheduler = distributed.default_scheduler() or distributed.NO_SCHEDULER
    bake.add_argument("--scheduler", default=default_scheduler, metavar="local|tcp://HOST:PORT|none",
                      help=f"where the renders run: {distributed.LOCAL!r}, a worker per core of this machine; a "
                           "scheduler address, a cluster started with `dask scheduler` / `dask worker` "
                           f"(docs/distributed.md); {distributed.NO_SCHEDULER!r}, this process (default: "
                           f"{default_scheduler}). The tables are the same wherever they rendered")
    bake.add_argument("--cache-dir", help="cache folder (default: the user cache)")
    bake.add_argument("--json", action="store_true", help="print summary.json on stdout")
    return parser


def _measure(args, interrupt):
    """The cloth bake's folder in the cache (measured now, or found), whether it was measured, and
    the summary reader."""
    from ..blender.garment.bake import bake_cloth, read_summary
    from ..blender.garment.density import weave_at_thread_count
    from ..blender.garment.measure import GoniometerSettings
    from ..blender.scene_files import open_empty_file

    interrupt.check()
    settings = GoniometerSettings(incidence_resolution=args.incidence_resolution,
                                  exit_resolution=args.exit_resolution,
                                  pixels_per_patch=args.pixels_per_patch, samples=args.samples,
                                  weave=weave_at_thread_count(args.threads_per_cm))
    open_empty_file()
    interrupt.check()
    start = time.perf_counter()
    progress_shown = []

    def progress(done: int, total: int, what: str) -> None:
        progress_shown.append(True)
        elapsed = time.perf_counter() - start
        print(f"\r[{done}/{total}] {what:<32} {elapsed:6.0f} s, ~{elapsed / done * (total - done):.0f} s left",
              end="", file=sys.stderr, flush=True)
        interrupt.check()  # after a render: the cache keeps nothing of an unfinished measurement

    try:
        folder, measured = bake_cloth(args.tables, settings, cache_dir=args.cache_dir, progress=progress,
                                      scheduler=args.scheduler, method=args.method)
    finally:
        if progress_shown:
            print(file=sys.stderr)  # end the progress line: what follows starts on its own
    return folder, measured, read_summary


def main(argv=None) -> int:
    """Run a command; the exit code (module docstring)."""
    from precompute import exit_codes
    return exit_codes.run_cli(lambda: _main(argv))


def _main(argv) -> int:
    from precompute import distributed
    from precompute import exit_codes
    from precompute.cli.arguments import parse_arguments

    args = parse_arguments(build_parser(), sys.argv[1:] if argv is None else argv)
    from precompute.errors import ParameterError
    from precompute.tables import folder as table_folder
    from precompute import outputs
    from .tables import CLOTH_FOLDER_FILES, check_cloth_table_folder
    from ..blender.garment.density import MM_PER_CM

    # Before Blender and minutes of renders: the output folder, the cache, the yarn bake.
    table_folder.check_output_folder(args.out, CLOTH_FOLDER_FILES)
    if args.cache_dir is not None:
        outputs.check_writable_folder(args.cache_dir, "--cache-dir", what="a cache folder")
    args.scheduler = distributed.check_scheduler(args.scheduler)
    if not pathlib.Path(args.tables).is_dir():
        raise ParameterError("--tables", args.tables, "an existing yarn bake folder (python -m precompute bake --out)")

    # Blender prints and swallows an exception raised in its callbacks (Cycles' render engine): a
    # Ctrl-C is held and raised between renders instead, so it always stops the bake (code 130).
    with exit_codes.DeferredInterrupt("interrupting after the current render…") as interrupt:
        folder, measured, summary_of = _measure(args, interrupt)

    def write(staging: pathlib.Path) -> None:
        for name in CLOTH_FOLDER_FILES:
            if (folder / name).is_file():
                shutil.copy2(folder / name, staging / name)
        check_cloth_table_folder(staging)

    # The folder as a whole: a reader, or a kill at any moment, finds the previous one or this one.
    out = table_folder.replace_folder(args.out, write, CLOTH_FOLDER_FILES)
    summary = summary_of(out)
    if args.json:
        sys.stdout.write(json.dumps(summary, indent=1) + "\n")
        return 0
    how = summary["measurement"]
    # The density as the tables record it: their goniometer's weave spacing.
    print(f"weave: {MM_PER_CM / summary['goniometer']['weave']['spacing_mm']:g} threads/cm")
    if how["method"] == "response":
        made = (f"traced in {how['traced_seconds']:.1f} s" if "traced_seconds" in how
                else f"{how.get('render_seconds', 0.0):.0f} s of renders")
        print(f"cloth tables: {out} (read off the weave's cloth response in {how['seconds']:.1f} s; the response "
              f"{made}, {'now' if measured else 'cached'})")
    else:
        print(f"cloth tables: {out} ({'measured' if measured else 'from the cache'}, "
              f"{summary['seconds']['renders']:.0f} s of renders)")
    print(f"energy: reflected + transmitted + open ≤ {summary['energy']['max_total']:.3f} of the incident flux")
    fit = summary["closure_fit_relative_error_median_rgb"]
    print("closure fit, median relative error (R, G, B): "
          + "; ".join(f"{side} {', '.join(f'{e:.2f}' for e in fit[side])}" for side in fit))
    print(f"coverage at normal view: {summary['coverage_normal']['front']:.3f}")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:  # between main's return and the exit
        sys.exit(130)
