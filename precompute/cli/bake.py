"""``python -m precompute bake``: bake a yarn's tables (cached) and report B/R and G/R.

Progress goes to stderr as a bar with the time left; the result to stdout, as
text or with ``--json`` as the bake's summary.  Exit codes: precompute/exit_codes.py.
"""

from __future__ import annotations

import json
import pathlib
import sys

from precompute import bounds
from precompute.bake import bake, export_bake
from precompute.cli.arguments import preset_argument
from precompute.distributed import LOCAL, NO_SCHEDULER, check_scheduler, default_scheduler
from precompute.errors import ParameterError
from precompute.exit_codes import DeferredInterrupt
from precompute.optics.medium import DEFAULT_PRESET, preset_names
from precompute.outputs import check_writable_folder
from precompute.tables.folder import YARN_FOLDER_FILES, check_output_folder


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "bake",
        help="Monte-Carlo bake of a yarn's BRDF tables (OpenEXR), cached by content",
        description="Medium optics -> Monte-Carlo transport -> yarn BRDF -> RGB OpenEXR tables "
        "(docs/table-spec.md). A second bake of the same inputs is a cache hit; another illuminant "
        "(--set bake.illuminant=A) recomputes colour without simulating again.",
    )
    source = parser.add_mutually_exclusive_group()
    source.add_argument("--preset", default=DEFAULT_PRESET,
                        help=f"a shipped preset: {', '.join(preset_names())} (default {DEFAULT_PRESET})")
    source.add_argument("--config", type=pathlib.Path, help="a preset TOML file")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                        help="override a preset value (a TOML literal), e.g. dye.weight_percent=2, "
                        "transport.angular_resolution=8, bake.illuminant=A; repeatable")
    parser.add_argument("--out", type=pathlib.Path,
                        help="also copy the tables, spectral.npz and summary.json into this folder, as a whole "
                        "(a new folder, or an earlier bake's, which it replaces)")
    parser.add_argument("--seed", type=bounds.SEED.argument("--seed"),
                        help="random seed (default: the preset's [transport] seed, 0)")
    budget = parser.add_mutually_exclusive_group()
    budget.add_argument("--paths", type=bounds.PATHS_PER_CELL.argument("--paths"),
                        help=f"paths per incidence cell, {bounds.PATHS_PER_CELL.allowed()} (2e4 notation allowed)")
    budget.add_argument("--target-error", type=bounds.TARGET_REL_STDERR.argument("--target-error"),
                        help="relative standard error of every incidence cell's albedo to reach "
                             f"(default 0.01), {bounds.TARGET_REL_STDERR.allowed()}")
    parser.add_argument("--dye-series", type=_dye_range, metavar="LOW,HIGH",
                        help="simulate once for this dye range (%% of fibre weight, holding the preset's amount; "
                        "cached) and read the tables at any amount in it in seconds: a later bake with another "
                        "dye.weight_percent in the range and the same --dye-series simulates nothing")
    parser.add_argument("--threads", type=int, help="CPU threads, with --scheduler local its worker processes "
                        "(default: all); results do not depend on it")
    parser.add_argument("--scheduler", default=default_scheduler() or NO_SCHEDULER, metavar="local|tcp://HOST:PORT|none",
                        help=f"where the transport runs: {LOCAL!r}, a cluster of this machine's cores; a scheduler "
                        "address, a cluster started with `dask scheduler` / `dask worker` (docs/distributed.md); "
                        f"{NO_SCHEDULER!r}, this process (default: {default_scheduler() or NO_SCHEDULER}). The tables "
                        "are the same wherever it ran")
    parser.add_argument("--cache-dir", type=pathlib.Path, help="cache folder (default: the user cache folder)")
    parser.add_argument("--json", action="store_true", help="print the summary as JSON on stdout")
    parser.set_defaults(func=run)


def run(args) -> int:
    from tqdm import tqdm

    preset = preset_argument(args)
    if args.out:
        check_output_folder(args.out, YARN_FOLDER_FILES)  # before the bake, not after it
    if args.cache_dir is not None:
        check_writable_folder(args.cache_dir, "--cache-dir", what="a cache folder")
    scheduler = check_scheduler(args.scheduler)
    bars = []  # opened at the first progress report, so input errors print no bar

    # A Ctrl-C is raised where it lands and also remembered, so that one dropped on the way ends the
    # bake all the same, at the next progress report or before --out is written (exit 130).
    interrupt = DeferredInterrupt(note="", at_once=True)

    def progress(fraction: float) -> None:
        interrupt.check()
        if not bars:
            bars.append(tqdm(total=100, desc="bake", unit="%", file=sys.stderr, dynamic_ncols=True,
                             bar_format="{desc}: {percentage:3.0f}%|{bar}| {elapsed} elapsed, {remaining} left"))
        bars[0].update(max(0.0, round(100 * fraction, 1) - bars[0].n))

    try:
        with interrupt:
            result = bake(preset, args.overrides, seed=args.seed, paths_per_cell=args.paths,
                          target_rel_stderr=args.target_error, threads=args.threads, cache_dir=args.cache_dir,
                          progress=progress, dye_series=args.dye_series, scheduler=scheduler)
    finally:
        for bar in bars:
            bar.close()
    summary = export_bake(result, args.out) if args.out else result.summary
    if args.json:
        print(json.dumps(summary, indent=1))
        return 0
    ratios, paper = summary["table1_ratios_normal"], summary["table1_ratios_paper_real_red_cotton"]
    seconds = summary["seconds"]
    origin = "cache hit" if result.cache_hit else ("simulated" if result.simulated else "colour recomputed")
    if "dye_series" in summary and not result.cache_hit:
        low, high = summary["dye_series"]["dye_range_percent"]
        origin += f"; read from the dye series {low:g}–{high:g} %"
    print(f"tables:  {summary['folder']}  ({origin})")
    paths = summary["paths"]
    print(f"paths:   {paths['total']:,} traced on {paths['incidence_cells_traced']} of "
          f"{len(paths['per_incidence_cell'])} incidence cells (the others their mirror images; "
          f"{paths['min']:,} per cell at least), albedo rel. stderr <= {paths['albedo_rel_stderr_max']:.3g}")
    took = f"transport {seconds['transport']:.1f} s, BRDF {seconds['brdf']:.1f} s, tables {seconds['tables']:.1f} s"
    if "reweighting" in seconds:
        took = f"read from the dye series {seconds['reweighting']:.1f} s, tables {seconds['tables']:.1f} s"
    print(f"time:    {summary['call_seconds']:.2f} s; when baked: {took}")
    print(f"B/R = {_ratio(ratios['B/R'])}, G/R = {_ratio(ratios['G/R'])} at normal incidence and view "
          f"(paper, Table 1, real red cotton: {paper['B/R']} and {paper['G/R']})")
    unclipped = summary["table1_ratios_normal_unclipped"]
    if unclipped != ratios:
        print(f"         before clipping to the Rec.709 gamut: B/R = {_ratio(unclipped['B/R'])}, "
              f"G/R = {_ratio(unclipped['G/R'])}")
    return 0


def _dye_range(text: str) -> tuple[float, float]:
    import argparse

    try:
        return bounds.check_dye_range(text, "--dye-series")
    except ParameterError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def _ratio(value) -> str:
    return "undefined (R = 0)" if value is None else f"{value:.4g}"
