"""Bakes in a separate Python process, so Blender's interface never waits on the Monte-Carlo transport.

Blender's own Python runs :mod:`clothlight.bake_worker` as a child process with the same import
path as Blender (so it finds the wheels the extension bundles and Blender's numpy) and talks to it
in JSON lines: the child writes ``progress``, then ``done``, ``error`` or ``cancelled`` on stdout;
the parent writes ``cancel`` on the child's stdin.  The child turns ``cancel`` (or its stdin
closing, when Blender dies) into a KeyboardInterrupt in its main thread: the bake's cache stages
every entry in a private temporary folder and removes it on the way out
(:func:`precompute.cache.store`), so a cancelled bake leaves no partial table.  A child that does
not stop within :data:`CANCEL_GRACE_SECONDS` (one transport block still running) is killed; its
temporary folder is hidden from every lookup and removed by a later bake.

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

from .addon import import_precompute

#: The ``[transport]`` defaults (standard library only, as the add-on's start needs).
_TRANSPORT_DEFAULTS = import_precompute("bounds").TRANSPORT_DEFAULTS
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


def missing_bake_dependencies() -> list[str]:
    """Distributions the bake needs that this Python cannot import (without importing them)."""
    import importlib.util

    return [dist for module, dist in BAKE_DEPENDENCIES.items() if importlib.util.find_spec(module) is None]


def bake_unavailable_reason(missing: list[str] | None = None) -> str | None:
    """Why Bake Tables cannot run in this Python, or None: the ``missing`` distributions (by
    default :func:`missing_bake_dependencies`) in one sentence the panel shows."""
    missing = missing_bake_dependencies() if missing is None else missing
    if not missing:
        return None
    return (f"Bake unavailable: {', '.join(missing)} not installed (this build of the extension bundles no "
            "wheels for this platform). Pre-baked tables of the shipped presets still work")


def typed_number(value: float) -> float:
    """A float as typed: Blender stores float properties in single precision (0.14 → 0.14000000059604645),
    and a bake's cache key hashes its inputs, so the digits beyond single precision are dropped."""
    return float(f"{float(value):.6g}")


@dataclasses.dataclass(frozen=True)
class BakeRequest:
    """Everything a bake is made from: a shipped preset, overrides of its medium, seed, budget, grids.

    Two equal requests bake the same tables (the bake's cache key hashes the same inputs), which is
    how the add-on recognises tables it shipped or baked before.

    Attributes
    ----------
    preset
        Name of a shipped medium preset (``precompute/presets/<name>.toml``).
    overrides
        ``(dotted key, value)`` pairs applied to the preset's TOML, e.g. ``("dye.weight_percent", 2.0)``.
    seed
        Seed of the transport's random streams.
    paths_per_cell, target_rel_stderr
        The path budget: paths per incidence cell, or the relative standard error of every cell's
        albedo to reach.  Exactly one is set.
    n_around, n_along, angular_resolution, incidence_resolution
        Transport and table grids (``[transport]`` of a preset, see :mod:`precompute.bake`); the
        defaults are the bake's.  ``incidence_resolution`` is an odd integer or ``AUTO_RESOLUTION``
        (the bake chooses it by its accuracy checks).
    dye_series
        A dye range (low, high), % of fibre weight: the bake simulates once for the range and reads
        any dye amount in it in seconds (``precompute.bake.bake(dye_series=...)``); None: one
        simulation per medium.
    """

    preset: str = "red_cotton"
    overrides: tuple[tuple[str, float], ...] = ()
    seed: int = _TRANSPORT_DEFAULTS["seed"]
    paths_per_cell: int | None = _TRANSPORT_DEFAULTS["paths_per_cell"]
    target_rel_stderr: float | None = _TRANSPORT_DEFAULTS["target_rel_stderr"]
    n_around: int = _TRANSPORT_DEFAULTS["n_around"]
    n_along: int = _TRANSPORT_DEFAULTS["n_along"]
    angular_resolution: int = _TRANSPORT_DEFAULTS["angular_resolution"]
    incidence_resolution: int | str = _TRANSPORT_DEFAULTS["incidence_resolution"]
    dye_series: tuple[float, float] | None = None

    def __post_init__(self):
        object.__setattr__(self, "overrides", tuple(sorted((str(k), typed_number(v)) for k, v in self.overrides)))
        if self.dye_series is not None:
            object.__setattr__(self, "dye_series", tuple(typed_number(v) for v in self.dye_series))
        if self.target_rel_stderr is not None:
            object.__setattr__(self, "target_rel_stderr", typed_number(self.target_rel_stderr))

    def to_json(self) -> str:
        """Canonical JSON: equal requests give equal text."""
        return json.dumps(dataclasses.asdict(self), sort_keys=True, separators=(",", ":"))

    @classmethod
    def from_json(cls, text: str) -> "BakeRequest":
        fields = json.loads(text)
        fields["overrides"] = tuple(tuple(pair) for pair in fields.get("overrides", ()))
        if fields.get("dye_series") is not None:
            fields["dye_series"] = tuple(fields["dye_series"])
        return cls(**fields)

    def same_but_dye(self, other: "BakeRequest") -> bool:
        """Whether ``other`` asks for the same bake but another dye amount."""

        def without_dye(request):
            return dataclasses.replace(request, overrides=tuple(pair for pair in request.overrides
                                                                if pair[0] != "dye.weight_percent"))

        return without_dye(self) == without_dye(other)

    def bake_arguments(self) -> dict:
        """Keyword arguments of :func:`precompute.bake.bake`."""
        grids = {f"transport.{name}": getattr(self, name) for name in import_precompute("bounds").GRID_SETTINGS}
        return {
            "preset_or_params": self.preset,
            "overrides": {**dict(self.overrides), **grids},
            "seed": self.seed,
            "paths_per_cell": self.paths_per_cell,
            "target_rel_stderr": None if self.paths_per_cell is not None else self.target_rel_stderr,
            "dye_series": self.dye_series,
        }


def preset_request(name: str) -> BakeRequest:
    """The request of the shipped preset ``name`` untouched: its own [transport] table over the defaults."""
    config = import_precompute("medium").load_preset_config(name)[0]
    given = config.get("transport", {})
    defaults = BakeRequest(preset=name)
    fields = {key: given.get(key, getattr(defaults, key))
              for key in ("seed", *import_precompute("bounds").GRID_SETTINGS)}
    if given.get("paths_per_cell") is not None and "target_rel_stderr" not in given:
        fields.update(paths_per_cell=int(given["paths_per_cell"]), target_rel_stderr=None)
    else:
        fields.update(target_rel_stderr=float(given.get("target_rel_stderr", defaults.target_rel_stderr)))
    return BakeRequest(preset=name, **fields)


class BakeFailed(RuntimeError):
    """The child bake stopped with an error; ``message`` is meant for the user, ``log`` for the console."""

    def __init__(self, message: str, log: str = "", bad_input: bool = False):
        super().__init__(message)
        self.log = log
        self.bad_input = bad_input


class BakeCancelled(RuntimeError):
    """The bake was cancelled before it finished."""


@dataclasses.dataclass
class BakeOutcome:
    """A finished bake: its table folder and the bake's summary figures."""

    folder: pathlib.Path
    cache_hit: bool
    seconds: float
    table1_ratios: dict


class BakeJob:
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
    numba_cache_dir
        Where numba keeps compiled kernels: numba writes next to a module by default, and an
        extension must not write into its own folder.
    bytecode_cache_dir
        Where the child keeps Python bytecode (``PYTHONPYCACHEPREFIX``), for the same reason: the
        child imports the add-on's modules from the extension's folder, and Python would write
        their ``__pycache__`` there.  A prefix rather than no bytecode at all, so that the child's
        imports of numba and SciPy stay quick from the second bake on.  None: Python's default.
    """

    def __init__(self, request: BakeRequest, *, cache_dir, threads: int | None = None, scheduler: str | None = None,
                 numba_cache_dir=None, bytecode_cache_dir=None):
        self.request = request
        self.cache_dir = pathlib.Path(cache_dir)
        self.threads = threads
        self.scheduler = scheduler or None
        self.numba_cache_dir = numba_cache_dir
        self.bytecode_cache_dir = bytecode_cache_dir
        self.progress = 0.0
        self.outcome: BakeOutcome | None = None
        self.error: BakeFailed | BakeCancelled | None = None
        self._process: subprocess.Popen | None = None
        self._events: queue.Queue = queue.Queue()
        self._stderr: list[str] = []
        self._cancel_sent: float | None = None
        self._started = 0.0

    # -- the child process ----------------------------------------------------------------

    def command(self) -> list[str]:
        command = [sys.executable, "-m", WORKER_MODULE, "--request", self.request.to_json(),
                   "--cache-dir", str(self.cache_dir)]
        if self.scheduler:
            command += ["--scheduler", self.scheduler]
        elif self.threads:
            command += ["--threads", str(int(self.threads))]
        return command

    def environment(self) -> dict:
        """The child's environment: Blender's import path (bundled wheels, numpy), numba's cache and
        Python's bytecode folder."""
        env = dict(os.environ)
        paths = [str(PACKAGE_ROOT)] + [p for p in sys.path if p and os.path.isdir(p)]
        env["PYTHONPATH"] = os.pathsep.join(dict.fromkeys(paths))
        env["PYTHONUNBUFFERED"] = "1"
        env["PYTHONIOENCODING"] = "utf-8"
        if self.numba_cache_dir is not None:
            env["NUMBA_CACHE_DIR"] = str(self.numba_cache_dir)
        if self.bytecode_cache_dir is not None:
            env["PYTHONPYCACHEPREFIX"] = str(self.bytecode_cache_dir)
        return env

    def start(self) -> "BakeJob":
        if not sys.executable or not os.path.isfile(sys.executable):
            raise BakeFailed(f"Blender's Python executable is missing ({sys.executable!r}): cannot bake")
        self._started = time.monotonic()
        self._process = subprocess.Popen(
            self.command(), cwd=PACKAGE_ROOT, env=self.environment(),
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
            text=True, encoding="utf-8", errors="replace", bufsize=1,
        )
        threading.Thread(target=self._read_events, args=(self._process.stdout,), daemon=True).start()
        threading.Thread(target=self._read_log, args=(self._process.stderr,), daemon=True).start()
        return self

    def _read_events(self, stream) -> None:
        for line in stream:
            try:
                self._events.put(json.loads(line))
            except ValueError:
                self._stderr.append(line)  # a stray print of a library: keep it for the console
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
            self.error = BakeCancelled("bake cancelled (the child was killed after "
                                       f"{CANCEL_GRACE_SECONDS:g} s; a later bake removes its temporary folder)")
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
            self.progress = max(self.progress, float(event["fraction"]))
        elif kind == "done":
            self.progress = 1.0
            self.outcome = BakeOutcome(
                folder=pathlib.Path(event["folder"]), cache_hit=bool(event["cache_hit"]),
                seconds=float(event["seconds"]), table1_ratios=event.get("table1_ratios", {}))
        elif kind == "error":
            self.error = BakeFailed(event["message"], self.log, bad_input=bool(event.get("bad_input")))
        elif kind == "cancelled":
            self.error = BakeCancelled("bake cancelled: no table was written")

    def _conclude(self) -> None:
        if self.done:
            return
        code = self._process.returncode
        if code == CANCELLED_EXIT or self._cancel_sent is not None:
            self.error = BakeCancelled("bake cancelled: no table was written")
        else:
            tail = self.log.strip().splitlines()[-1:] or [f"exit status {code}"]
            self.error = BakeFailed(f"bake process stopped unexpectedly: {tail[0]}", self.log)

    @property
    def cancelling(self) -> bool:
        return self._cancel_sent is not None and not self.done

    def cancel(self) -> None:
        """Ask the child to stop; ``poll()`` reports the end (``BakeCancelled``)."""
        if self._process is None or self.done or self._cancel_sent is not None:
            return
        self._cancel_sent = time.monotonic()
        try:
            self._process.stdin.write("cancel\n")
            self._process.stdin.flush()
            self._process.stdin.close()
        except OSError:
            pass  # the child already exited: poll() picks up how

    def wait(self, on_progress: Callable[[float], None] | None = None, interval: float = 0.1) -> BakeOutcome:
        """Run to the end (background mode); Ctrl-C cancels the child too.  Raises BakeFailed/BakeCancelled."""
        if self._process is None:
            self.start()
        reported = -1.0
        try:
            while not self.poll():
                if on_progress is not None and self.progress != reported:
                    reported = self.progress
                    on_progress(reported)
                time.sleep(interval)
        except KeyboardInterrupt:
            self.cancel()
            while not self.poll():
                time.sleep(interval)
            raise
        if self.error is not None:
            raise self.error
        return self.outcome
