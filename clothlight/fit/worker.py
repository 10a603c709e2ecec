"""``python -m clothlight.fit.worker``: one medium fit in a child process of Blender (see :mod:`clothlight.fit_job`).

The fit of ``python -m clothlight.fit`` (the same checks, forward model, optimiser and folder:
:mod:`clothlight.fit.run`) for a :class:`~clothlight.fit_job.FitRequest`.  Writes JSON lines on
stdout — ``{"event": "progress", "fraction": f, "stage": "…"}`` (the cloth response's renders, when
not cached, then every evaluation, then the report), then one of ``done`` (the folder, the fitted
preset, the fitted relative RMS and the fitted values as bake overrides), ``error`` or ``cancelled``
— and stops when its stdin says ``cancel`` or closes (:mod:`clothlight.worker_io`).  Exit status
as every ClothLight command: 0 done, 2 bad input (named as the request names it), 130 cancelled
(nothing written: the folder is swapped in whole at the end), 1 any other failure.

The forward model renders with bpy: inside Blender this runs in Blender itself (background mode,
:func:`clothlight.jobs.child_command`), elsewhere in a Python that has the ``bpy`` module.  A cancel
that comes while Blender renders is held until the render ends (Blender swallows an exception
raised inside one); the optimiser looks for it before every evaluation.
"""

from __future__ import annotations

import argparse
import importlib.util
import sys

from ..fit_job import FitRequest, request_names
from ..medium_settings import fitted_overrides
from ..worker_io import ProgressEvents, run_worker

#: Shares of the progress bar: the cloth response's renders (when not cached), the search, the report.
RESPONSE_SHARE = 0.2
REPORT_AT = 0.97


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m clothlight.fit.worker", description=__doc__)
    parser.add_argument("--request", required=True, help="a FitRequest as JSON")
    parser.add_argument("--cache-dir", required=True, help="cache folder of the forward model's cloth response")
    parser.add_argument("--threads", type=int)
    parser.add_argument("--scheduler", help="a dask scheduler's address for the candidates (default: this process)")
    return run_worker(lambda: parser.parse_args(argv), _fit)


def _fit(args, cancelled) -> dict:
    from precompute import distributed
    from precompute import exit_codes
    from . import run as job
    from precompute.fit import report
    request = FitRequest.from_json(args.request)
    with request_names():
        inputs = job.check_fit_inputs(**request.fit_arguments(), cache_dir=args.cache_dir)
        scheduler = distributed.check_scheduler(args.scheduler) if args.scheduler else None
    progress = ProgressEvents()
    held = exit_codes.DeferredInterrupt(note="")

    def building(done: int, total: int) -> None:
        held.check()  # a cancel during the renders, held until one ended
        progress(RESPONSE_SHARE * done / max(total, 1), stage=f"cloth response: {done}/{total} renders")

    def searching(state) -> None:
        fraction = RESPONSE_SHARE + (REPORT_AT - RESPONSE_SHARE) * min(state.evaluations / max(state.total, 1), 1.0)
        progress(fraction, stage=f"evaluation {state.evaluations}/{state.total}, "
                                 f"relative RMS {state.best_objective:.3g}")

    progress(0.0, stage="starting")
    result = job.run_fit(inputs, seed=request.seed, scheduler=scheduler, threads=args.threads, building=building,
                         searching=searching, cancel=cancelled.is_set, while_building=lambda: held)
    progress(REPORT_AT, stage="writing the report")
    figures = importlib.util.find_spec("matplotlib") is not None  # Blender's Python has none
    out = report.write_fit_folder(result, inputs.out, measured_name=inputs.measured_name, figures=figures)
    model = result.metrics["model"]
    return {"folder": str(out), "preset": str(out / report.PRESET_FILE),
            "relative_rms": float(model["fit_views"]["relative_rms"]),
            "held_out_rms": _number_or_none(model["held_out_views"]["relative_rms"]), "seconds": float(result.seconds),
            "parameters": {p.name: float(result.parameters[p.name]) for p in result.free},
            "overrides": [list(pair) for pair in fitted_overrides(result)], "figures": figures,
            "stop_reason": result.stop_reason, "bound_hits": list(result.bound_hits)}


def _number_or_none(value) -> float | None:
    """A figure for JSON: None where there is none (no held-out views)."""
    import math

    return None if value is None or not math.isfinite(float(value)) else float(value)


if __name__ == "__main__":
    sys.exit(main())
