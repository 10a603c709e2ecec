"""Bakes in a separate Python process, so Blender's interface never waits on the Monte-Carlo transport.

Blender's own Python runs :mod:`clothlight.bake_worker` as a child process with the same import
path as Blender (so it finds the wheels the extension bundles and Blender's numpy) and talks to it
in JSON lines: the child writes ``progress``, then ``done``, ``error`` or ``cancelled`` on stdout;
the parent writes ``cancel`` on the child's stdin.  The child turns ``cancel`` (or its stdin
closing, when Blender dies) into a KeyboardInterrupt in its main thread: the bake's cache stages
every entry in a private temporary folder and removes it on the way out
(:func:`precompute.cache.entries.store`), so a cancelled bake leaves no partial table.  A child that does
not stop within :data:`CANCEL_GRACE_SECONDS` (one transport block still running) is killed; its
temporary folder is hidden from every lookup and removed by a later bake.

What runs a child and talks to it is :class:`ChildJob`, which the medium fit's job
(:class:`clothlight.fit_job.FitJob`) shares; :func:`child_command` says what the child is: this
Python (``-m``), or for a job that renders with bpy inside Blender, Blender itself in background mode.

No Blender here: the operators (UI, modal timer) and the build script (pre-baked tables) use it.
"""

from __future__ import annotations

import dataclasses
import json
import os
import pathlib
import queue
import subprocess
import sys
import threading
import time
from collections.abc import Callable

from .medium_settings import BakeRequest


#: The folder holding the ``clothlight`` and ``precompute`` packages (the extension's root).
PACKAGE_ROOT = pathlib.Path(__file__).resolve().parents[1]
WORKER_MODULE = "clothlight.bake_worker"
#: Seconds a cancelled child may take to clean up before it is killed.
CANCEL_GRACE_SECONDS = 30.0
#: Exit status of a child stopped by ``cancel``, as for SIGINT.
CANCELLED_EXIT = 130
#: Exit status of a child refused by bad input (precompute's ParameterError), as the CLI.
PARAMETER_EXIT = 2

#: What the bake needs beyond Blender's own Python and numpy, by import name → distribution name.
BAKE_DEPENDENCIES = {
    "numba": "numba",
    "llvmlite": "llvmlite",
    "scipy": "scipy",
    "colour": "colour-science",
    "typing_extensions": "typing-extensions",
    "miepython": "miepython",
    "OpenEXR": "OpenEXR",
    "platformdirs": "platformdirs",
}


#: What the medium fit needs beyond the bake's: its optimiser, CMA-ES (pure Python).  Its report's
#: figures need matplotlib, which is not bundled: without it the fit folder holds no plots.
FIT_DEPENDENCIES = {**BAKE_DEPENDENCIES, "cma": "cma"}
#: Every distribution the extension bundles as a wheel (scripts/build_extension.py), all or none.
BUNDLED_DEPENDENCIES = {**BAKE_DEPENDENCIES, **FIT_DEPENDENCIES}
#: What Bake Cloth traces a new weave's cloth response with (clothlight/garment/traced_response.py, seconds):
#: bundled on its own wherever its platform has a wheel; without it the response is rendered (about an hour).
CLOTH_TRACE_DEPENDENCIES = {"embreex": "embreex"}


def missing_dependencies(dependencies: dict[str, str]) -> list[str]:
    """Distributions of ``dependencies`` (import name → distribution name) that this Python cannot
    import (without importing them)."""
    import importlib.util

    return [dist for module, dist in dependencies.items() if importlib.util.find_spec(module) is None]


def missing_bake_dependencies() -> list[str]:
    """Distributions the bake needs that this Python cannot import (without importing them)."""
    return missing_dependencies(BAKE_DEPENDENCIES)


def bake_unavailable_reason(missing: list[str] | None = None) -> str | None:
    """Why Bake Tables cannot run in this Python, or None: the ``missing`` distributions (by
    default :func:`missing_bake_dependencies`) in one sentence the panel shows."""
    missing = missing_bake_dependencies() if missing is None else missing
    if not missing:
        return None
    return (f"Bake unavailable: {', '.join(missing)} not installed (this build of the extension bundles no "
            "wheels for this platform). Pre-baked tables of the shipped presets still work")


class JobFailed(RuntimeError):
    """A child job stopped with an error; ``message`` is meant for the user, ``log`` for the console,
    ``bad_input`` says it refused its input (exit code 2: the message names the parameter)."""

    def __init__(self, message: str, log: str = "", bad_input: bool = False):
        super().__init__(message)
        self.log = log
        self.bad_input = bad_input


class JobCancelled(RuntimeError):
    """A child job was cancelled before it finished."""


class BakeFailed(JobFailed):
    """The child bake stopped with an error; ``message`` is meant for the user, ``log`` for the console."""


class BakeCancelled(JobCancelled):
    """The bake was cancelled before it finished."""


class ClothBakeFailed(JobFailed):
    """The child cloth bake stopped with an error; ``message`` is meant for the user, ``log`` for the console."""


class ClothBakeCancelled(JobCancelled):
    """The cloth bake was cancelled before it finished."""


@dataclasses.dataclass
class ClothBakeOutcome:
    """A finished cloth bake: its cloth table folder (in the cache) and whether it rendered (False:
    the measurement was in the cache)."""

    folder: pathlib.Path
    rendered: bool


@dataclasses.dataclass
class BakeOutcome:
    """A finished bake: its table folder and the bake's summary figures."""

    folder: pathlib.Path
    cache_hit: bool
    seconds: float
    table1_ratios: dict


#: What Blender runs (``--python-expr``) to start a worker module: Blender ignores PYTHONPATH and
#: PYTHONPYCACHEPREFIX (unless ``--python-use-system-env``), so the expression takes both from the
#: environment (:meth:`ChildJob.environment`), the bytecode folder first so that nothing is written
#: into the extension's folder, then hands over to :func:`clothlight.worker_io.exec_in_blender`.
BLENDER_BOOTSTRAP = (
    "import os, sys; "
    "sys.pycache_prefix = os.environ.get('PYTHONPYCACHEPREFIX') or sys.pycache_prefix; "
    "sys.path[:0] = [p for p in os.environ.get('CLOTHLIGHT_CHILD_PATH', '').split(os.pathsep) if p]; "
    "import clothlight.worker_io; clothlight.worker_io.exec_in_blender({module!r})"
)


def is_blender_executable(binary_path: str | None, python: str | None = None) -> bool:
    """Whether ``binary_path`` (``bpy.app.binary_path``) is a Blender executable to start a child with:
    an executable file that is not a Python (the ``bpy`` module, as in the tests, reports "" there)."""
    if not binary_path:
        return False
    path = pathlib.Path(binary_path)
    if not path.is_file() or not os.access(path, os.X_OK) or path.name.lower().startswith("python"):
        return False
    try:
        return not (python and path.samefile(python))
    except OSError:
        return True


def blender_scripts_folder() -> pathlib.Path | None:
    """The ``scripts`` folder of the Blender this process has imported (``…/scripts/modules/bpy``), or
    None when bpy is not imported.  ``import bpy`` puts its folders on sys.path, the first of them
    ``scripts/modules`` with Blender's own ``bpy`` package in it, which needs Blender's ``_bpy``."""
    file = getattr(sys.modules.get("bpy"), "__file__", None)
    if not file:
        return None
    path = pathlib.Path(file).resolve()
    if path.parent.name != "bpy" or path.parents[1].name != "modules":
        return None
    return path.parents[2]


def child_command(module: str, arguments: list[str], *, blender: str | None = None,
                  python: str | None = None) -> list[str]:
    """The command line of the worker ``module`` with ``arguments``.

    A worker that imports bpy (the fit renders its cloth response) cannot run in Blender's bundled
    Python, which has no bpy: inside Blender (``blender`` is ``bpy.app.binary_path``, a Blender
    executable) the child is Blender itself in background mode, without the user's settings and
    add-ons (``--factory-startup``), running :data:`BLENDER_BOOTSTRAP`.  Otherwise — Blender as the
    ``bpy`` module (tests, command lines), whose ``binary_path`` is not a Blender executable, or a
    worker that needs no bpy (``blender=None``) — it is ``python -m module`` (``python``: this
    Python by default)."""
    python = python or sys.executable
    if is_blender_executable(blender, python):
        return [str(blender), "--background", "--factory-startup", "--python-expr",
                BLENDER_BOOTSTRAP.format(module=module), "--", *arguments]
    return [python, "-m", module, *arguments]


class ChildJob:
    """One job in a child process talking JSON lines (:mod:`clothlight.worker_io`): ``start()``, then
    ``poll()`` until ``done``; or ``wait()``.  Subclasses name the worker module and its arguments
    (:meth:`arguments`) and turn the ``done`` event into their outcome (:meth:`outcome_from`).

    Parameters
    ----------
    numba_cache_dir
        Where numba keeps compiled kernels: numba writes next to a module by default, and an
        extension must not write into its own folder.
    bytecode_cache_dir
        Where the child keeps Python bytecode (``PYTHONPYCACHEPREFIX``), for the same reason: the
        child imports the add-on's modules from the extension's folder, and Python would write
        their ``__pycache__`` there.  A prefix rather than no bytecode at all, so that the child's
        imports of numba and SciPy stay quick from the second job on.  None: Python's default.
    blender
        ``bpy.app.binary_path``, for a worker that imports bpy (:func:`child_command`); None: this Python.
    """

    #: The worker module, run as ``python -m`` (or by Blender, :func:`child_command`).
    module = ""
    #: Whether the worker imports bpy: then Blender's script folders stay off its import path, where
    #: ``import bpy`` in this process put them and where a ``python -m`` child would find Blender's
    #: inner ``bpy`` package before the ``bpy`` module (in Blender, the child adds its own).
    imports_bpy = False
    #: What the job is, for its messages ("bake", "fit").
    what = "job"
    failure = JobFailed
    cancellation = JobCancelled

    def __init__(self, *, numba_cache_dir=None, bytecode_cache_dir=None, blender: str | None = None):
        self.numba_cache_dir = numba_cache_dir
        self.bytecode_cache_dir = bytecode_cache_dir
        self.blender = blender
        self.progress = 0.0
        # each rise of the progress, for wait() to report every one whenever it looks
        self._progress_news: list[float] = []
        #: What the child is doing, as its last progress event said ("" when it does not say).
        self.stage = ""
        self.outcome = None
        self.error: JobFailed | JobCancelled | None = None
        self._process: subprocess.Popen | None = None
        self._events: queue.Queue = queue.Queue()
        self._stderr: list[str] = []
        self._cancel_sent: float | None = None
        self._started = 0.0

    # -- what a subclass says ---------------------------------------------------------------

    def arguments(self) -> list[str]:
        """The worker's command-line arguments."""
        raise NotImplementedError

    def outcome_from(self, event: dict):
        """The job's outcome from its ``done`` event."""
        raise NotImplementedError

    #: What the cancelled job left, for the user ("no table was written").
    cancelled_note = "nothing was written"
    #: What a child killed after a cancel leaves, for the user.
    killed_note = "a later job removes what it left"

    # -- the child process ----------------------------------------------------------------

    def command(self) -> list[str]:
        return child_command(self.module, self.arguments(), blender=self.blender)

    def environment(self) -> dict:
        """The child's environment: Blender's import path (bundled wheels, numpy), numba's cache and
        Python's bytecode folder (both also for a child that is Blender: :data:`BLENDER_BOOTSTRAP`)."""
        env = dict(os.environ)
        entries = [str(PACKAGE_ROOT)] + [p for p in sys.path if p and os.path.isdir(p)]
        scripts = blender_scripts_folder() if self.imports_bpy else None
        if scripts is not None:
            entries = [p for p in entries if not pathlib.Path(p).resolve().is_relative_to(scripts)]
        paths = os.pathsep.join(dict.fromkeys(entries))
        env["PYTHONPATH"] = paths
        env["CLOTHLIGHT_CHILD_PATH"] = paths
        env["PYTHONUNBUFFERED"] = "1"
        env["PYTHONIOENCODING"] = "utf-8"
        if self.numba_cache_dir is not None:
            env["NUMBA_CACHE_DIR"] = str(self.numba_cache_dir)
        if self.bytecode_cache_dir is not None:
            env["PYTHONPYCACHEPREFIX"] = str(self.bytecode_cache_dir)
        return env

    def start(self):
        command = self.command()
        if not command[0] or not os.path.isfile(command[0]):
            raise self.failure(f"the executable to run the {self.what} with is missing ({command[0]!r}): cannot "
                              f"{self.what}")
        self._started = time.monotonic()
        self._process = subprocess.Popen(
            command, cwd=PACKAGE_ROOT, env=self.environment(),
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
            text=True, encoding="utf-8", errors="replace", bufsize=1,
        )
        threading.Thread(target=self._read_events, args=(self._process.stdout,), daemon=True).start()
        threading.Thread(target=self._read_log, args=(self._process.stderr,), daemon=True).start()
        return self

    def _read_events(self, stream) -> None:
        for line in stream:
            try:
                event = json.loads(line)
            except ValueError:
                event = None
            if isinstance(event, dict):
                self._events.put(event)
            else:
                self._stderr.append(line)  # a stray print of a library, Blender's banner: kept for the console
        self._events.put(None)

    def _read_log(self, stream) -> None:
        for line in stream:
            self._stderr.append(line)
            del self._stderr[:-200]

    @property
    def log(self) -> str:
        return "".join(self._stderr)

    @property
    def elapsed(self) -> float:
        return time.monotonic() - self._started if self._started else 0.0

    # -- driving it -----------------------------------------------------------------------

    @property
    def done(self) -> bool:
        return self.outcome is not None or self.error is not None

    def poll(self) -> bool:
        """Take the child's news without waiting; True once the job is over (``outcome`` or ``error`` set)."""
        if self.done:
            return True
        finished = False
        while True:
            try:
                event = self._events.get_nowait()
            except queue.Empty:
                break
            if event is None:
                finished = True
                break
            self._handle(event)
        if finished:  # stdout closed: the child has exited or is exiting
            self._process.wait()
            self._conclude()
        elif self._cancel_sent is not None and time.monotonic() - self._cancel_sent > CANCEL_GRACE_SECONDS:
            self._process.kill()
            self._process.wait()
            self.error = self.cancellation(f"{self.what} cancelled (the child was killed after "
                                        f"{CANCEL_GRACE_SECONDS:g} s; {self.killed_note})")
        if self.done:
            try:
                self._process.wait(timeout=10)  # it exits right after its last message
            except subprocess.TimeoutExpired:
                self._process.kill()
                self._process.wait()
        return self.done

    def _handle(self, event: dict) -> None:
        kind = event.get("event")
        if kind == "progress":
            self._rise_to(float(event["fraction"]))
            self.stage = str(event.get("stage", self.stage))
        elif kind == "done":
            self._rise_to(1.0)
            self.outcome = self.outcome_from(event)
        elif kind == "error":
            self.error = self.failure(event["message"], self.log, bad_input=bool(event.get("bad_input")))
        elif kind == "cancelled":
            self.error = self.cancellation(f"{self.what} cancelled: {self.cancelled_note}")

    def _rise_to(self, fraction: float) -> None:
        if fraction > self.progress:
            self.progress = fraction
            self._progress_news.append(fraction)

    def _conclude(self) -> None:
        if self.done:
            return
        code = self._process.returncode
        if code == CANCELLED_EXIT or self._cancel_sent is not None:
            self.error = self.cancellation(f"{self.what} cancelled: {self.cancelled_note}")
        else:
            tail = self.log.strip().splitlines()[-1:] or [f"exit status {code}"]
            self.error = self.failure(f"{self.what} process stopped unexpectedly: {tail[0]}", self.log)

    @property
    def returncode(self) -> int | None:
        """The child's exit status once it has exited (0, 2, 130, 1: precompute/exit_codes.py)."""
        return None if self._process is None else self._process.returncode

    @property
    def cancelling(self) -> bool:
        return self._cancel_sent is not None and not self.done

    def cancel(self) -> None:
        """Ask the child to stop; ``poll()`` reports the end (:attr:`cancellation`)."""
        if self._process is None or self.done or self._cancel_sent is not None:
            return
        self._cancel_sent = time.monotonic()
        try:
            self._process.stdin.write("cancel\n")
            self._process.stdin.flush()
            self._process.stdin.close()
        except OSError:
            pass  # the child already exited: poll() picks up how

    def wait(self, on_progress: Callable[[float], None] | None = None, interval: float = 0.1):
        """Run to the end (background mode); Ctrl-C cancels the child too.  Returns the outcome;
        raises :attr:`failure` / :attr:`cancellation`."""
        if self._process is None:
            self.start()

        def report() -> None:
            # every rise the child sent, not the progress when looked at: a fast child's views all
            # arrive between two looks
            news, self._progress_news = self._progress_news, []
            if on_progress is not None:
                for fraction in news:
                    on_progress(fraction)

        if on_progress is not None:
            on_progress(self.progress)
        try:
            while not self.poll():
                report()
                time.sleep(interval)
            report()
        except KeyboardInterrupt:
            self.cancel()
            while not self.poll():
                time.sleep(interval)
            raise
        if self.error is not None:
            raise self.error
        return self.outcome


class BakeJob(ChildJob):
    """One bake in a child process.  ``start()``, then ``poll()`` until ``done``; or ``wait()``.

    Parameters
    ----------
    request
        What to bake.
    cache_dir
        The bake cache's folder (the add-on's preference, by default its extension user folder).
    threads
        CPU threads of the transport; None: all.
    scheduler
        The address of a dask cluster (``tcp://HOST:PORT``, docs/distributed.md) whose workers run
        the transport; None: the child's own threads (Blender's Python has no dask, and on one
        machine the threads use every core already).
    numba_cache_dir, bytecode_cache_dir
        As :class:`ChildJob`.
    """

    module = WORKER_MODULE
    what = "bake"
    failure = BakeFailed
    cancellation = BakeCancelled
    cancelled_note = "no table was written"
    killed_note = "a later bake removes its temporary folder"

    def __init__(self, request: BakeRequest, *, cache_dir, threads: int | None = None, scheduler: str | None = None,
                 numba_cache_dir=None, bytecode_cache_dir=None):
        super().__init__(numba_cache_dir=numba_cache_dir, bytecode_cache_dir=bytecode_cache_dir)
        self.request = request
        self.cache_dir = pathlib.Path(cache_dir)
        self.threads = threads
        self.scheduler = scheduler or None
        self.outcome: BakeOutcome | None = None

    def arguments(self) -> list[str]:
        arguments = ["--request", self.request.to_json(), "--cache-dir", str(self.cache_dir)]
        if self.scheduler:
            arguments += ["--scheduler", self.scheduler]
        elif self.threads:
            arguments += ["--threads", str(int(self.threads))]
        return arguments

    def outcome_from(self, event: dict) -> BakeOutcome:
        return BakeOutcome(folder=pathlib.Path(event["folder"]), cache_hit=bool(event["cache_hit"]),
                           seconds=float(event["seconds"]), table1_ratios=event.get("table1_ratios", {}))

    def start(self) -> "BakeJob":
        if not sys.executable or not os.path.isfile(sys.executable):
            raise BakeFailed(f"Blender's Python executable is missing ({sys.executable!r}): cannot bake")
        return super().start()


class ClothBakeJob(ChildJob):
    """The cloth tables of a yarn bake (the garment's BSDF, :mod:`clothlight.cloth_bake_worker`) in a
    child process.  ``start()``, then ``poll()`` until ``done``; or ``wait()``.

    Parameters
    ----------
    yarn_tables
        The yarn bake folder the cloth is measured with.
    cache_dir
        The cache folder (the bake's): the cloth tables are stored there.
    settings
        Goniometer settings by name (``incidence_resolution``, ``exit_resolution``,
        ``pixels_per_patch``, ``samples``); absent: the command's defaults.
    blender
        ``bpy.app.binary_path``: inside Blender, the child is Blender (:func:`child_command`).
    numba_cache_dir, bytecode_cache_dir
        As :class:`ChildJob`.
    """

    module = "clothlight.cloth_bake_worker"
    what = "cloth bake"
    imports_bpy = True
    failure = ClothBakeFailed
    cancellation = ClothBakeCancelled
    cancelled_note = "no cloth table was written"
    killed_note = "a later bake removes its temporary folder"

    def __init__(self, yarn_tables, *, cache_dir, settings: dict | None = None, blender: str | None = None,
                 numba_cache_dir=None, bytecode_cache_dir=None):
        super().__init__(numba_cache_dir=numba_cache_dir, bytecode_cache_dir=bytecode_cache_dir, blender=blender)
        self.yarn_tables = pathlib.Path(yarn_tables)
        self.cache_dir = pathlib.Path(cache_dir)
        self.settings = dict(settings or {})
        self.outcome: ClothBakeOutcome | None = None

    def arguments(self) -> list[str]:
        arguments = ["--tables", str(self.yarn_tables), "--cache-dir", str(self.cache_dir)]
        for name, value in sorted(self.settings.items()):
            arguments += [f"--{name.replace('_', '-')}", str(int(value))]
        return arguments

    def outcome_from(self, event: dict) -> ClothBakeOutcome:
        return ClothBakeOutcome(folder=pathlib.Path(event["folder"]), rendered=bool(event["rendered"]))
