"""What the add-on's child processes share: JSON-line events on stdout, ``cancel`` on stdin, the exit codes.

The bake (:mod:`clothlight.bake_worker`) and the medium fit (:mod:`clothlight.fit.worker`) run in a
child process of Blender (:mod:`clothlight.jobs`, :mod:`clothlight.fit_job`).  Each writes JSON
lines on stdout — ``{"event": "progress", "fraction": f}`` (the fit adds a ``stage``), then one of
``done``, ``error`` or ``cancelled`` — and stops when its stdin says ``cancel`` or closes (Blender
went away).  A worker's ``main(argv)`` is ``run_worker(parse, work)``: ``parse()`` reads its
arguments, ``work(args, cancelled)`` does the job and returns the ``done`` event's fields.

The stdin watch turns ``cancel`` into a KeyboardInterrupt in the main thread (``_thread.interrupt_main``)
and sets ``cancelled``, a :class:`threading.Event` for jobs that look at it between steps (the fit's
``cancel()``, asked before each evaluation) or that hold the interrupt while Blender renders
(:class:`precompute.exit_codes.DeferredInterrupt`: Blender swallows an exception raised inside a
render).  Exit status as every ClothLight command (``precompute/exit_codes.py``): 0 done, 2 bad
input (an InputError, named; its event says ``bad_input``), 130 cancelled (also a Ctrl-C), 1 any other
failure (a one-line message in the event for the report; the traceback on stderr, the log that the
add-on keeps for the console).

A worker started as Blender itself (a job that renders, inside Blender, where the bundled Python
cannot import bpy: :func:`clothlight.jobs.child_command`) runs its ``main`` through
:func:`exec_in_blender`.
"""

from __future__ import annotations

import _thread
import importlib
import json
import os
import signal
import sys
import threading
import traceback
import warnings
from collections.abc import Callable


from precompute import exit_codes as _exit_codes


def emit(**event) -> None:
    """One event, one JSON line on stdout."""
    print(json.dumps(event), flush=True)


def watch_stdin() -> threading.Event:
    """Start watching stdin: when the parent says ``cancel`` or goes away (its end of the pipe closes),
    set the returned event and interrupt the main thread."""
    cancelled = threading.Event()

    def watch() -> None:
        for line in sys.stdin:
            if line.strip() == "cancel":
                break
        cancelled.set()
        _thread.interrupt_main()

    threading.Thread(target=watch, daemon=True).start()
    return cancelled


class ProgressEvents:
    """``progress(fraction, stage=None)``: a ``progress`` event when the fraction has moved by ``step``
    since the last one, the stage changed, or the job reached 1."""

    def __init__(self, step: float = 0.005):
        self.step = step
        self.last = -1.0
        self.stage: str | None = None

    def __call__(self, fraction: float, stage: str | None = None) -> None:
        fraction = float(fraction)
        if fraction - self.last >= self.step or fraction >= 1.0 or stage != self.stage:
            self.last, self.stage = fraction, stage
            emit(event="progress", fraction=fraction, **({"stage": stage} if stage is not None else {}))


def run_worker(parse: Callable[[], object], work: Callable[[object, threading.Event], dict]) -> int:
    """A worker's ``main``: its exit status (module docstring).  ``parse()`` reads the arguments
    (argparse's SystemExit passes through); ``work(args, cancelled)`` runs with the stdin watch on
    and returns the ``done`` event's fields."""
    try:
        args = parse()
        # A process started in the background of a shell inherits SIGINT ignored, and then
        # interrupt_main() raises nothing: the cancel would be lost.
        signal.signal(signal.SIGINT, signal.default_int_handler)
        cancelled = watch_stdin()
        try:
            # colour-science probes for matplotlib and warns when it is absent: its plots are not used here.
            warnings.filterwarnings("ignore", message=".*Matplotlib.*")
            from precompute.errors import InputError
            try:
                done = work(args, cancelled)
            except InputError as error:
                emit(event="error", message=str(error), bad_input=True)
                return _exit_codes.BAD_INPUT
        except KeyboardInterrupt:
            emit(event="cancelled")
            return _exit_codes.INTERRUPTED
        except Exception as error:  # noqa: BLE001 - reported to the user; the traceback goes to the console
            traceback.print_exc()
            emit(event="error", message=f"{type(error).__name__}: {error}".replace("\n", " "))
            return _exit_codes.INTERNAL_ERROR
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # done: a cancel arriving now changes nothing
        emit(event="done", **done)
        return _exit_codes.OK
    except KeyboardInterrupt:  # before the work started (the arguments, the thread)
        emit(event="cancelled")
        return _exit_codes.INTERRUPTED


def exec_in_blender(module: str) -> None:
    """Run ``module``'s ``main`` in Blender started in background mode with ``--python-expr``
    (:func:`clothlight.jobs.child_command`), with the arguments after ``--``, and leave Blender with
    its exit status at once (``os._exit``: Blender's own shutdown neither runs nor changes it)."""
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    try:
        code = importlib.import_module(module).main(argv)
    except SystemExit as exit_:
        code = exit_.code if isinstance(exit_.code, int) else (0 if exit_.code is None else 1)
        if not isinstance(exit_.code, (int, type(None))):
            print(exit_.code, file=sys.stderr)
    except KeyboardInterrupt:
        code = _exit_codes.INTERRUPTED
    except BaseException:  # noqa: BLE001 - the status must come out whatever happened
        traceback.print_exc()
        code = _exit_codes.INTERNAL_ERROR
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(int(code or 0))


__all__ = ["ProgressEvents", "emit", "exec_in_blender", "run_worker", "watch_stdin"]
