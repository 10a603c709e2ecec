"""``python -m clothlight.bake_worker``: one bake in a child process of Blender (see :mod:`clothlight.jobs`).

Writes JSON lines on stdout — ``{"event": "progress", "fraction": f}``, then one of ``done``,
``error`` or ``cancelled`` — and stops when its stdin says ``cancel`` or closes.  Exit status:
0 done, 2 bad input (a ParameterError, named), 130 cancelled, 1 any other failure (traceback on
stderr for the console, a one-line message on stdout for the report).
"""

from __future__ import annotations

import _thread
import argparse
import json
import signal
import sys
import threading
import traceback
import warnings

from .addon import import_precompute
from .jobs import CANCELLED_EXIT, PARAMETER_EXIT, BakeRequest


def _emit(**event) -> None:
    print(json.dumps(event), flush=True)


def _watch_stdin() -> None:
    """Interrupt the bake when the parent says ``cancel`` or goes away (its end of the pipe closes)."""
    for line in sys.stdin:
        if line.strip() == "cancel":
            break
    _thread.interrupt_main()


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m clothlight.bake_worker", description=__doc__)
    parser.add_argument("--request", required=True, help="a BakeRequest as JSON")
    parser.add_argument("--cache-dir", required=True)
    parser.add_argument("--threads", type=int)
    args = parser.parse_args(argv)
    # A process started in the background of a shell inherits SIGINT ignored, and then
    # interrupt_main() raises nothing: the cancel would be lost.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    threading.Thread(target=_watch_stdin, daemon=True).start()
    try:
        # colour-science probes for matplotlib and warns when it is absent: its plots are not used here.
        warnings.filterwarnings("ignore", message=".*Matplotlib.*")
        bake_module = import_precompute("bake")
        ParameterError = import_precompute("errors").ParameterError
        request = BakeRequest.from_json(args.request)
        last = [-1.0]

        def progress(fraction: float) -> None:
            if fraction - last[0] >= 0.005 or fraction >= 1.0:
                last[0] = fraction
                _emit(event="progress", fraction=float(fraction))

        try:
            result = bake_module.bake(**request.bake_arguments(), threads=args.threads, cache_dir=args.cache_dir,
                                      progress=progress)
        except ParameterError as error:
            _emit(event="error", message=str(error), bad_input=True)
            return PARAMETER_EXIT
    except KeyboardInterrupt:
        _emit(event="cancelled")
        return CANCELLED_EXIT
    except Exception as error:  # noqa: BLE001 - reported to the user; the traceback goes to the console
        traceback.print_exc()
        _emit(event="error", message=f"{type(error).__name__}: {error}")
        return 1
    _emit(event="done", folder=str(result.folder), cache_hit=result.cache_hit,
          seconds=float(result.summary.get("call_seconds", 0.0)),
          table1_ratios=result.summary.get("table1_ratios_normal", {}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
