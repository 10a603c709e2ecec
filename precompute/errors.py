"""Errors raised for bad input anywhere in ClothLight.

One hierarchy: :class:`InputError` is bad input from the user (a parameter, a file), and every
command line maps it to exit code 2 (:mod:`precompute.exit_codes`).  Its kinds:

- :class:`ParameterError`: a parameter outside its allowed range or malformed; the message names
  the parameter, the value it got and the range it allows (the ranges of numeric inputs are data:
  :mod:`precompute.bounds`).  ``clothlight.weave.WeaveParameterError`` is one.
- :class:`precompute.tables.exr.TableError`: a file that is not a valid ClothLight table, named.
- ``precompute.fit.measured_data.MeasurementFormatError``: a measurement file breaking
  its format, the file and the row named.
- :class:`ClusterError`: a dask.distributed cluster a job was pointed at cannot run it
  (:mod:`precompute.distributed`): :class:`SchedulerUnreachable` (the address named) or
  :class:`WorkerCodeMismatch` (the worker and both code digests named).

Nothing is ever clamped silently.  No imports beyond the standard library: the add-on's panel
and every command line import this before anything heavy.
"""

from __future__ import annotations


class InputError(ValueError):
    """Bad input from the user: a parameter or a file.  Command lines exit with code 2 on it."""


class ParameterError(InputError):
    """A parameter is outside its allowed range or malformed.

    Parameters
    ----------
    name
        Dotted name of the parameter, as the user would write it
        (``"particles[0].diameter_nm"``), or the command-line option (``"--out"``).
    value
        The offending value.
    allowed
        Human-readable description of what is allowed (``"> 0"``,
        ``"(0, 0.74)"``, ``"monotonically increasing"``).
    """

    def __init__(self, name: str, value: object, allowed: str):
        self.name = name
        self.value = value
        self.allowed = allowed
        super().__init__(f"{name} = {value!r} is invalid: allowed {allowed}")


class ClusterError(InputError):
    """The cluster a job was pointed at (``--scheduler``) cannot run it; nothing was written."""


class SchedulerUnreachable(ClusterError):
    """No dask scheduler answers at ``address``, or it was lost during the job (``detail`` says which)."""

    def __init__(self, address: str, detail: str):
        self.address = address
        super().__init__(f"--scheduler {address}: {detail}")


class WorkerCodeMismatch(ClusterError):
    """A worker or the scheduler (``process``: ``"worker tcp://…"`` or ``"the scheduler"``; the
    scheduler unpickles the tasks, so it imports their code too) runs other code than this process:
    another version, or none of the project.  The digests of the job's source files
    (:func:`precompute.cache.sources.stage_digest`) differ, or it cannot import them."""

    def __init__(self, address: str, process: str, detail: str):
        self.address = address
        self.process = process
        super().__init__(f"--scheduler {address}: {process} {detail}; start the scheduler and every worker "
                         "from this checkout (docs/distributed.md)")
