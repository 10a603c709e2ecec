"""The exit codes every ClothLight command line returns, and the one wrapper that maps to them.

====  =====================================================================================
code  meaning
====  =====================================================================================
0     done
1     an internal error: one line on stderr (the traceback with ``CLOTHLIGHT_TRACEBACK=1``)
2     bad input: the message names the parameter or the file and what is allowed
130   interrupted (Ctrl-C, at any moment, start-up imports included; or a cancelled bake)
====  =====================================================================================

Used by ``python -m precompute``, ``python -m clothlight.validate``, ``python -m
clothlight.garment``, ``python -m clothlight.validation.report`` and the add-on's bake worker
(``clothlight.bake_worker``, whose status follows the same codes).  A command's ``main(argv)``
returns ``run_cli(lambda: _main(argv))``; everything that may take time, imports included, runs
inside ``_main`` so that a Ctrl-C there ends in code 130 and one line, never a traceback.

Standard library only, like :mod:`precompute.errors`: importing it costs nothing.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
import traceback
from collections.abc import Callable

from precompute.errors import InputError

OK = 0
INTERNAL_ERROR = 1
BAD_INPUT = 2
INTERRUPTED = 130
#: Set (to anything but "" or "0") to print the traceback of an internal error.
TRACEBACK_ENV = "CLOTHLIGHT_TRACEBACK"


def _say(text: str) -> None:
    try:
        print(text, file=sys.stderr, flush=True)
    except (OSError, ValueError, KeyboardInterrupt):  # stderr closed, or a second Ctrl-C: the code still says it
        pass


def traceback_asked() -> bool:
    return os.environ.get(TRACEBACK_ENV, "") not in ("", "0")


def internal_error_line(error: BaseException) -> str:
    """The one line an internal error prints (the exception's type and message)."""
    hint = "" if traceback_asked() else f"; {TRACEBACK_ENV}=1 shows the traceback"
    return f"error: {type(error).__name__}: {error} (an internal error{hint})"


def exit_code(error: BaseException) -> int:
    """The exit code of a command that stopped on ``error``."""
    if isinstance(error, KeyboardInterrupt):
        return INTERRUPTED
    if isinstance(error, InputError):
        return BAD_INPUT
    return INTERNAL_ERROR


def _silence_stdout() -> None:
    """After a broken pipe (``… | head``): send what is left of stdout nowhere, so that Python's own
    flush at exit raises nothing more."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):
        pass


class DeferredInterrupt:
    """A Ctrl-C held while the block runs, raised as KeyboardInterrupt at a safe point.

    Blender calls into Python (Cycles' render engine, add-on registration) and prints and swallows
    any exception raised there: a KeyboardInterrupt arriving during a render or ``import bpy`` would
    be lost, and the command would run on to exit code 0.  Inside this block SIGINT only records
    itself; :meth:`check` (called between renders, e.g. from a progress callback) raises
    KeyboardInterrupt, and so does leaving the block after one came.  Outside the main thread (where
    signals cannot be handled) it does nothing.

    With ``at_once`` the Ctrl-C is also raised where it lands, as Python's own handler does, and the
    block only remembers it: a KeyboardInterrupt that a library catches and drops on the way (a
    bake's kernels compile and run in numba) still ends the block with one.
    """

    def __init__(self, note: str = "interrupting after the current step…", *, at_once: bool = False):
        self.note = note
        self.at_once = at_once
        self.received = False
        self._previous = None

    def _record(self, _signum, _frame) -> None:
        if not self.received and self.note:
            _say(f"\n{self.note}")
        self.received = True
        if self.at_once:
            raise KeyboardInterrupt

    def check(self) -> None:
        """Raise KeyboardInterrupt if a Ctrl-C came."""
        if self.received:
            raise KeyboardInterrupt

    def __enter__(self) -> DeferredInterrupt:
        if threading.current_thread() is threading.main_thread():
            self._previous = signal.signal(signal.SIGINT, self._record)
        return self

    def __exit__(self, exc_type, exc, tb) -> bool:
        if threading.current_thread() is threading.main_thread():
            previous = self._previous if callable(self._previous) or self._previous in (
                signal.SIG_DFL, signal.SIG_IGN) else signal.default_int_handler
            signal.signal(signal.SIGINT, previous)
        if self.received and exc_type is not KeyboardInterrupt:
            raise KeyboardInterrupt
        return False


def run_cli(main: Callable[[], int | None]) -> int:
    """Run a command's ``main()`` and return its exit code (module docstring).

    ``SystemExit`` (argparse's 2 for a bad argument, 0 for ``--help``) becomes its code; an
    :class:`~precompute.errors.InputError` prints ``error: <message>`` and gives 2; a
    KeyboardInterrupt prints ``interrupted`` and gives 130; a closed stdout (``… | head``) gives 1
    silently; any other exception prints one line and gives 1.
    """
    try:
        code = main()
        return OK if code is None else int(code)
    except SystemExit as exit_:
        if exit_.code is None or isinstance(exit_.code, int):
            return exit_.code or OK
        _say(str(exit_.code))
        return INTERNAL_ERROR
    except KeyboardInterrupt:
        _say("interrupted")
        return INTERRUPTED
    except InputError as error:
        _say(f"error: {error}")
        return BAD_INPUT
    except BrokenPipeError:  # the reader went away (``… | head``): nothing to tell it, as other tools
        _silence_stdout()
        return INTERNAL_ERROR
    except Exception as error:  # noqa: BLE001 - the commands' last line of defence: one line, exit code 1
        if traceback_asked():
            traceback.print_exc()
        _say(f"{internal_error_line(error)}")
        return INTERNAL_ERROR


__all__ = ["BAD_INPUT", "INTERNAL_ERROR", "INTERRUPTED", "OK", "TRACEBACK_ENV", "DeferredInterrupt", "exit_code",
           "internal_error_line", "run_cli", "traceback_asked"]
