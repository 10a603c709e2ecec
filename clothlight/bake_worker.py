"""``python -m clothlight.bake_worker``: one bake in a child process of Blender (see :mod:`clothlight.jobs`).

Writes JSON lines on stdout — ``{"event": "progress", "fraction": f}``, then one of ``done``,
``error`` or ``cancelled`` — and stops when its stdin says ``cancel`` or closes.  Exit status as
every ClothLight command (``precompute/exit_codes.py``): 0 done, 2 bad input (an InputError, named;
its event says ``bad_input``), 130 cancelled (also a Ctrl-C), 1 any other failure (a one-line message
in the event for the report; the traceback on stderr, the bake's log that the add-on keeps for the
console).
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
from .jobs import BakeRequest

_exit_codes = import_precompute("exit_codes")


def _emit(**event) -> None:
    print(json.dumps(event), flush=True)


def _watch_stdin() -> None:
    """Interrupt the bake when the parent says ``cancel`` or goes away (its end of the pipe closes)."""
    for line in sys.stdin:
        if line.strip() == "cancel":
            break
    _thread.interrupt_main()


def main(argv=None) -> int:
    try:
        return _main(argv)
    except KeyboardInterrupt:  # before the bake started (the arguments, the thread)
        _emit(event="cancelled")
        return _exit_codes.INTERRUPTED


def _main(argv) -> int:
    parser = argparse.ArgumentParser(prog="python -m clothlight.bake_worker", description=__doc__)
    parser.add_argument("--request", required=True, help="a BakeRequest as JSON")
    parser.add_argument("--cache-dir", required=True)
    parser.add_argument("--threads", type=int)
    parser.add_argument("--scheduler", help="a dask scheduler's address (default: this process's threads)")
    args = parser.parse_args(argv)
    # A process started in the background of a shell inherits SIGINT ignored, and then
    # interrupt_main() raises nothing: the cancel would be lost.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    threading.Thread(target=_watch_stdin, daemon=True).start()
    try:
        # colour-science probes for matplotlib and warns when it is absent: its plots are not used here.
        warnings.filterwarnings("ignore", message=".*Matplotlib.*")
        bake_module = import_precompute("bake")
        InputError = import_precompute("errors").InputError
        request = BakeRequest.from_json(args.request)
        last = [-1.0]

        def progress(fraction: float) -> None:
            if fraction - last[0] >= 0.005 or fraction >= 1.0:
                last[0] = fraction
                _emit(event="progress", fraction=float(fraction))

        try:
            result = bake_module.bake(**request.bake_arguments(), threads=args.threads, cache_dir=args.cache_dir,
                                      progress=progress, scheduler=args.scheduler)
        except InputError as error:
            _emit(event="error", message=str(error), bad_input=True)
            return _exit_codes.BAD_INPUT
    except KeyboardInterrupt:
        _emit(event="cancelled")
        return _exit_codes.INTERRUPTED
    except Exception as error:  # noqa: BLE001 - reported to the user; the traceback goes to the console
        traceback.print_exc()
        _emit(event="error", message=f"{type(error).__name__}: {error}")
        return _exit_codes.INTERNAL_ERROR
    _emit(event="done", folder=str(result.folder), cache_hit=result.cache_hit,
          seconds=float(result.summary.get("call_seconds", 0.0)),
          table1_ratios=result.summary.get("table1_ratios_normal", {}))
    return _exit_codes.OK


if __name__ == "__main__":
    sys.exit(main())
