"""``python -m clothlight.fit``: fit a yarn medium to a measured cloth BRDF (docs/fitting.md).

Checks every input first (the measurement, the preset, the free parameters, the colour targets, the
output folder), then builds the forward model (``clothlight.fit.forward.build_forward_model``, a
cached cloth response), runs CMA-ES with progress on stderr, and writes ``--out`` as a whole; the
checks and the run are :mod:`clothlight.fit.run`'s, which the add-on's fit worker runs too.
Exit codes: precompute/exit_codes.py (0 done, 2 bad input, 130 interrupted: nothing written).
"""

from __future__ import annotations

try:  # a Ctrl-C before the handler in main() is in place still exits with 130, without a traceback
    import argparse
    import json
    import pathlib
    import sys

    from precompute import bounds
    from precompute.cli.arguments import parse_arguments
    from precompute.distributed import LOCAL, NO_SCHEDULER, check_scheduler, default_scheduler
    from precompute.exit_codes import INTERRUPTED, DeferredInterrupt, run_cli
    from precompute.fit.parameters import PARAMETERS
    from precompute.optics.medium import DEFAULT_PRESET, preset_names
except KeyboardInterrupt:
    if __name__ != "__main__":
        raise
    print("interrupted", file=__import__("sys").stderr)
    raise SystemExit(130) from None


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="python -m clothlight.fit",
        description="CMA-ES over the free parameters of a medium against a measured-data CSV: fitted on the "
        "plane of incidence, checked on the measurement's other azimuths (held out), compared with the paper's "
        "Lambert + Cook-Torrance baseline fitted to the same views. Writes preset.toml, fit.json, report.md "
        "and plots into --out. docs/fitting.md.",
    )
    parser.add_argument("--measured", type=pathlib.Path, required=True,
                        help="measured-data CSV (theta_i,phi_i,theta_o,phi_o,R,G,B; docs/validation.md)")
    source = parser.add_mutually_exclusive_group()
    source.add_argument("--preset", default=DEFAULT_PRESET,
                        help=f"the starting medium: a shipped preset, {', '.join(preset_names())} "
                        f"(default {DEFAULT_PRESET})")
    source.add_argument("--config", type=pathlib.Path, help="the starting medium as a preset TOML file")
    parser.add_argument("--free", required=True,
                        help=f"comma-separated free parameters: {', '.join(PARAMETERS)}")
    parser.add_argument("--target-ratios", metavar="B/R=0.08,G/R=0.011",
                        help="colour ratios to meet at normal incidence and view (θi = 0, θo ≤ 10°)")
    parser.add_argument("--max-back-front", type=float, metavar="RATIO",
                        help="the largest luminance ratio of the cloth lit from straight behind over lit from the "
                             "front, at normal view (real cloth is darker from behind: e.g. 0.5)")
    parser.add_argument("--hold-bands", metavar="LOW,HIGH",
                        help="hold the backscatter (θi 60° θv −60°, −40°; θi 45° θv −60°, the fabric's main channel) "
                             "and the off-specular B/R and G/R medians, model / measured, within LOW–HIGH: their "
                             "log distance outside it joins the objective (issue 43's band: 0.85,1.15)")
    parser.add_argument("--search-error", metavar="LOOSE,TIGHT",
                        help="the relative error asked of the forward model while the search is wide and once it "
                             "has narrowed (default 0.08,0.02; the final evaluations 0.01). A yarn of fibres' "
                             "evaluation costs mostly its optics, not its paths: 0.02,0.01 costs little more and "
                             "ranks candidates that differ by less than the default's noise")
    parser.add_argument("--seed", type=bounds.SEED.argument("--seed"), default=0,
                        help="seed of the optimiser and of every forward evaluation (default 0)")
    parser.add_argument("--budget-evaluations", type=bounds.FIT_EVALUATIONS.argument("--budget-evaluations"),
                        default=150, help="forward-model evaluations at most, the final accurate one included: "
                        f"{bounds.FIT_EVALUATIONS.allowed()} (default 150)")
    parser.add_argument("--budget-seconds", type=float,
                        help="wall seconds at most for the search (default: no limit)")
    parser.add_argument("--out", type=pathlib.Path, required=True,
                        help="folder to write the fit into, as a whole (new, or an earlier fit's, which it replaces)")
    parser.add_argument("--dye-series", action="store_true",
                        help="for a fit whose only free medium parameter is dye_weight_percent: one transport for "
                             "its whole range, every candidate read from it in about a second and without "
                             "Monte-Carlo noise between candidates (docs/fitting.md)")
    parser.add_argument("--scheduler", default=default_scheduler() or NO_SCHEDULER, metavar="local|tcp://HOST:PORT|none",
                        help=f"where each generation's candidates are evaluated: {LOCAL!r}, a worker per core of "
                        "this machine; a scheduler address, a cluster started with `dask scheduler` / `dask worker` "
                        f"(docs/distributed.md); {NO_SCHEDULER!r}, this process, one after the other (default: "
                        f"{default_scheduler() or NO_SCHEDULER}; with --dye-series always this process, where "
                        "a candidate is a read of one series). The fit is the same wherever it ran")
    parser.add_argument("--cache-dir", type=pathlib.Path, help="cache folder of the forward model's cloth response")
    parser.add_argument("--json", action="store_true", help="print fit.json's summary on stdout")
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the fit; its exit code (module docstring)."""
    return run_cli(lambda: run(parse_arguments(build_parser(), sys.argv[1:] if argv is None else argv)))


def run(args) -> int:
    from tqdm import tqdm

    from .run import check_fit_inputs, run_fit
    from precompute.cli.arguments import preset_argument
    from precompute.fit.report import fit_summary, write_fit_folder

    # every input checked before any work (clothlight.fit.run, shared with the add-on's fit worker)
    inputs = check_fit_inputs(args.measured, preset_argument(args), args.free, out=args.out,
                              target_ratios=args.target_ratios, max_back_front=args.max_back_front,
                              hold_bands=args.hold_bands,
                              budget_evaluations=args.budget_evaluations, budget_seconds=args.budget_seconds,
                              search_error=args.search_error, dye_series=args.dye_series, cache_dir=args.cache_dir)
    scheduler = None if args.dye_series else check_scheduler(args.scheduler)

    bars: dict = {}

    def bar(name: str, total: int, unit: str):
        if name not in bars:
            bars[name] = tqdm(total=total, desc=name, unit=unit, file=sys.stderr, dynamic_ncols=True)
        return bars[name]

    # Blender prints and swallows an exception raised in its callbacks (Cycles' render engine): a
    # Ctrl-C while the cloth response renders is held and raised between renders instead.
    held = DeferredInterrupt("interrupting after the current render…")

    def building(done: int, total: int) -> None:
        held.check()
        b = bar("cloth response", total, "render")
        b.update(max(0, done - b.n))

    def searching(state) -> None:
        b = bar("fit", state.total, "eval")
        b.set_postfix_str(f"best {state.best_objective:.4g}, rel. error {state.relative_error or 0:.3g}")
        b.update(max(0, state.evaluations - b.n))

    try:
        result = run_fit(inputs, seed=args.seed, scheduler=scheduler, building=building, searching=searching,
                         while_building=lambda: held)
    finally:
        for b in bars.values():
            b.close()
    out = write_fit_folder(result, inputs.out, measured_name=inputs.measured_name)
    if args.json:
        summary = fit_summary(result, inputs.measured_name)
        summary.pop("views")
        summary.pop("history")
        print(json.dumps({"out": str(out), **summary}, indent=1))
        return 0
    model, base = result.metrics["model"], result.metrics["baseline"]
    print(f"fit:      {out}")
    print("fitted:   " + ", ".join(f"{p.name} = {result.parameters[p.name]:.4g}" + (f" {p.unit}" if p.unit else "")
                                   for p in result.free))
    print(f"error:    relative RMS {model['fit_views']['relative_rms']:.3g} on the plane of incidence, "
          f"{_show(model['held_out_views']['relative_rms'])} held out "
          f"(baseline {base['fit_views']['relative_rms']:.3g} / {_show(base['held_out_views']['relative_rms'])})")
    print(f"search:   {result.forward_evaluations} evaluations, {result.seconds:.1f} s; "
          f"stopped by {result.stop_reason}")
    for hit in result.bound_hits:
        print(f"note:     {hit}")
    return 0


def _show(value) -> str:
    return "–" if value is None else f"{value:.3g}"


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:  # between main's return and the exit
        sys.exit(INTERRUPTED)
