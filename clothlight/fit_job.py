"""Medium fits in a separate process, so Blender's interface never waits on the fit (issue 19).

The Yarn Medium panel's Fit runs the fit of ``python -m clothlight.fit`` (docs/fitting.md): the
same checks, forward model, optimiser and folder (:mod:`clothlight.fit.run`), in the child
:mod:`clothlight.fit.worker`, driven as the bake is (:class:`clothlight.jobs.ChildJob`: JSON-line
progress, ``cancel`` on stdin, exit codes 0/2/130/1).  The fit's forward model renders the cloth
response with bpy, so inside Blender the child is Blender itself in background mode
(:func:`clothlight.jobs.child_command`).  A cancelled fit writes nothing: the folder is written
into a staging folder and swapped in at the end (``precompute.tables.folder.replace_folder``).

A :class:`FitRequest` says what to fit; :meth:`FitRequest.check` refuses bad input before a child
starts, with precompute's messages (the parameter named as the request names it).  No Blender
here: the operators use it, and the tests drive it from a plain Python.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import pathlib
from collections.abc import Iterator

from .jobs import FIT_DEPENDENCIES, ChildJob, JobCancelled, JobFailed, missing_dependencies
from .medium_settings import BakeRequest, typed_number

FIT_WORKER_MODULE = "clothlight.fit.worker"

#: The parameters a fit may free, as the panel lists them: name, label, unit, fit range (low, high)
#: and what it sets.  The same as :data:`precompute.fit.parameters.PARAMETERS` (held together by
#: tests/test_fit_job.py), written here so that enabling the add-on imports none of the fit
#: (its package imports SciPy).
FREE_PARAMETERS = (
    ("void_fraction", "Void Fraction", "", 0.001, 0.55, "the volume fraction of the particle species named voids"),
    ("void_diameter_um", "Void Diameter", "µm", 0.2, 40.0, "the diameter of the particle species named voids"),
    ("scatterer_fraction", "Scatterer Fraction", "", 0.005, 0.4,
     "the volume fraction of the particle species named scatterers"),
    ("scatterer_diameter_nm", "Scatterer Diameter", "nm", 30.0, 3000.0,
     "the diameter of the particle species named scatterers"),
    ("dye_weight_percent", "Dye", "%", 0.1, 10.0, "the dye content, % of the fibre's weight"),
    ("dye_share", "Second Dye Share", "", 0.0, 1.0,
     "the second dye's share of the dye weight, in a preset that mixes two dyes"),
    ("host_absorption_per_mm", "Fibre Absorption", "1/mm", 0.01, 30.0,
     "the fibre's own grey absorption coefficient, beside the dye's spectrum"),
    ("fibre_fraction", "Fibre Fraction", "", 0.2, 0.8, "the share of the yarn's volume its fibres fill"),
    ("fibre_diameter_um", "Fibre Diameter", "µm", 5.0, 40.0, "the diameter of the yarn's fibres"),
    ("fibre_absorption_per_mm", "Fibre Grey Absorption", "1/mm", 0.01, 100.0,
     "the fibre material's grey absorption coefficient, beside its dye"),
    ("fibre_spread_deg", "Fibre Spread", "°", 0.0, 60.0,
     "the spread of fibres along the yarn axis about the twist's helix (σ)"),
    ("fibre_roughness_deg", "Fibre Roughness", "°", 0.0, 60.0,
     "the blur of the light a fibre along the yarn axis sends on (σ)"),
    ("twist_angle_deg", "Twist Angle", "°", 0.0, 45.0, "the surface fibres' helix angle about the yarn axis"),
    ("yarn_radius_mm", "Yarn Radius", "mm", 0.03, 0.5, "the yarn's radius"),
    ("specular_weight", "Sheen Weight", "", 0.0, 3.0, "the Cook–Torrance sheen's weight (the shader's SpecularWeight)"),
    ("specular_slope", "Sheen Slope", "", 0.05, 1.0,
     "the Cook–Torrance sheen's Beckmann rms slope m (the shader's Slope; the paper's 0.8)"),
    ("fuzz_albedo", "Fuzz Albedo", "", 0.0, 1.0,
     "the single-scattering albedo of the cloth's surface fibres (the shader's FuzzAlbedo)"),
    ("fuzz_depth", "Fuzz Depth", "", 0.0, 2.0,
     "the optical depth of the surface fibres, which shade the yarn beneath them (the shader's FuzzDepth; 0: none)"),
    ("fuzz_asymmetry", "Fuzz Asymmetry", "", -0.5, 0.9,
     "the Henyey–Greenstein g of the surface fibres' scattering (the shader's FuzzAsymmetry; 0: isotropic)"),
    ("fuzz_tint_red", "Fuzz Red Tint", "", 0.1, 10.0,
     "the fuzz's red albedo over its green (the shader's FuzzTint)"),
    ("fuzz_tint_blue", "Fuzz Blue Tint", "", 0.1, 10.0,
     "the fuzz's blue albedo over its green (the shader's FuzzTint)"),
    ("fuzz_flatness", "Fuzz Flatness", "", 0.0, 1.0,
     "the share of the surface fibres lying in the cloth's plane (the shader's FuzzFlatness; 0: every direction)"),
)

#: precompute's command-line names of a fit's inputs → the request's (messages name what the user set).
_REQUEST_NAMES = {
    "--measured": "measured", "--free": "free", "--target-ratios": "target_ratios",
    "--max-back-front": "max_back_front", "--budget-evaluations": "budget", "--budget-seconds": "budget_seconds",
    "--seed": "seed", "--out": "out", "--dye-series": "dye_series", "--cache-dir": "cache_dir",
    "--scheduler": "scheduler",
}


def missing_fit_dependencies() -> list[str]:
    """Distributions the fit needs that this Python cannot import (without importing them)."""
    return missing_dependencies(FIT_DEPENDENCIES)


def fit_unavailable_reason(missing: list[str] | None = None) -> str | None:
    """Why Fit cannot run in this Python, or None: the ``missing`` distributions (by default
    :func:`missing_fit_dependencies`) in one sentence the panel shows."""
    missing = missing_fit_dependencies() if missing is None else missing
    if not missing:
        return None
    return (f"Fit unavailable: {', '.join(missing)} not installed (this build of the extension does not bundle "
            "them for this platform)")


@contextlib.contextmanager
def request_names() -> Iterator[None]:
    """Re-raise precompute's ParameterError naming a command-line option (``--free``) with the
    request's name for it (``free``); same type, value and allowed values."""
    from precompute.errors import ParameterError
    try:
        yield
    except ParameterError as error:
        name = _REQUEST_NAMES.get(error.name)
        if name is None:
            raise
        raise type(error)(name, error.value, error.allowed) from None


@dataclasses.dataclass(frozen=True)
class FitRequest:
    """Everything a fit is made from (docs/fitting.md, ``python -m clothlight.fit``).

    Attributes
    ----------
    measured
        The measured-data CSV (``theta_i,phi_i,theta_o,phi_o,R,G,B``, docs/validation.md).
    out
        The folder to write the fit into, as a whole (new, or an earlier fit's, which it replaces).
    free
        The free parameters, names of :data:`FREE_PARAMETERS` (``--free``).
    medium
        The starting medium as the bake describes it (:class:`clothlight.medium_settings.BakeRequest`: a shipped
        preset and overrides of its values; its grids become the fit's ``[transport]`` table, its
        seed, budget and dye range are not used).
    target_ratios
        Colour ratios to meet at normal incidence and view, ``"B/R=0.08,G/R=0.011"``; "" for none.
    max_back_front
        The largest luminance ratio lit from behind over lit from the front; None: unconstrained.
    budget, budget_seconds
        Forward-model evaluations at most (the final one included), and wall seconds (None: no limit).
    seed
        Seeds the optimiser and every forward evaluation.
    dye_series
        Read every candidate from one transport of the dye's range (``--dye-series``): only for a fit
        whose one free medium parameter is the dye.
    """

    measured: str = ""
    out: str = ""
    free: tuple[str, ...] = ()
    medium: BakeRequest = BakeRequest()
    target_ratios: str = ""
    max_back_front: float | None = None
    budget: int = 150
    budget_seconds: float | None = None
    seed: int = 0
    dye_series: bool = False

    def __post_init__(self):
        free = (self.free,) if isinstance(self.free, str) else self.free
        object.__setattr__(self, "free", tuple(str(name) for name in free))
        object.__setattr__(self, "target_ratios", str(self.target_ratios or "").strip())
        for name in ("max_back_front", "budget_seconds"):
            value = getattr(self, name)
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                object.__setattr__(self, name, typed_number(value))

    def to_json(self) -> str:
        """Canonical JSON: equal requests give equal text."""
        fields = dataclasses.asdict(self)
        fields["medium"] = json.loads(self.medium.to_json())
        return json.dumps(fields, sort_keys=True, separators=(",", ":"))

    @classmethod
    def from_json(cls, text: str) -> "FitRequest":
        fields = json.loads(text)
        if not isinstance(fields, dict):
            raise ValueError("a FitRequest is a JSON object")
        if "medium" in fields:
            fields["medium"] = BakeRequest.from_json(json.dumps(fields["medium"]))
        fields["free"] = tuple(fields.get("free", ()))
        return cls(**fields)

    def fit_arguments(self) -> dict:
        """Keyword arguments of :func:`clothlight.fit.run.check_fit_inputs` (but ``cache_dir``)."""
        medium = self.medium.bake_arguments()
        return {"measured": self.measured, "preset": medium["preset_or_params"], "free": ",".join(self.free),
                "out": self.out, "overrides": medium["overrides"], "target_ratios": self.target_ratios or None,
                "max_back_front": self.max_back_front, "budget_evaluations": self.budget,
                "budget_seconds": self.budget_seconds, "dye_series": self.dye_series}

    def check(self) -> "FitRequest":
        """This request, if a fit can start from it; ParameterError naming the first bad field otherwise.

        What can be checked without reading the medium: the measurement is a file, the free
        parameters exist (precompute's ``parse_free``), a dye series frees the dye alone, the colour
        targets parse (``parse_target_ratios``), the budget holds a generation (``check_budget``),
        the seed and the back-lit ratio, the output folder (an earlier fit's or new).  The child
        checks the rest before any work (the measurement's format, the preset's species; exit 2)."""
        import math

        from precompute.errors import ParameterError
        from precompute.fit import parameters
        from precompute.fit import objective
        from precompute.fit import optimise
        from precompute.fit import report
        from precompute import bounds
        with request_names():
            if not self.measured or not pathlib.Path(self.measured).is_file():
                raise ParameterError("--measured", self.measured,
                                     "an existing measured-data CSV file (theta_i,phi_i,theta_o,phi_o,R,G,B)")
            free = parameters.parse_free(list(self.free))
            medium_free = [p.name for p in free if not p.is_specular]
            if self.dye_series and medium_free != ["dye_weight_percent"]:
                raise ParameterError("--dye-series", ",".join(self.free), "a fit whose only free medium parameter is "
                                     "dye_weight_percent (the specular term may be free too)")
            objective.parse_target_ratios(self.target_ratios or None)
            optimise.check_budget(optimise.Budget(evaluations=self.budget, seconds=self.budget_seconds), len(free))
            bounds.SEED.check(self.seed, "seed")
            if self.max_back_front is not None and not (
                    isinstance(self.max_back_front, (int, float)) and math.isfinite(self.max_back_front)
                    and self.max_back_front > 0):
                raise ParameterError("--max-back-front", self.max_back_front, "a ratio > 0")
            if not self.out:
                raise ParameterError("--out", self.out, "a folder to write the fit into")
            report.check_fit_folder(self.out)
        return self


class FitFailed(JobFailed):
    """The child fit stopped with an error; ``message`` is meant for the user, ``log`` for the console."""


class FitJobCancelled(JobCancelled):
    """The fit was cancelled before it finished: nothing was written."""


@dataclasses.dataclass
class FitOutcome:
    """A finished fit: its folder, the fitted preset and the figures of its summary.

    ``relative_rms`` is the fitted medium's relative RMS error on the fit views (the plane of
    incidence), ``held_out_rms`` on the held-out views (None without any); ``overrides`` the fitted
    values as the bake's overrides (:func:`clothlight.medium_settings.fitted_overrides`); ``figures``
    whether the folder has its plots (Blender's Python has no matplotlib)."""

    folder: pathlib.Path
    preset: pathlib.Path
    relative_rms: float
    held_out_rms: float | None
    seconds: float
    parameters: dict
    overrides: tuple[tuple[str, float], ...]
    figures: bool
    stop_reason: str = ""
    bound_hits: tuple[str, ...] = ()


class FitJob(ChildJob):
    """One medium fit in a child process.  ``start()``, then ``poll()`` until ``done``; or ``wait()``.

    Parameters
    ----------
    request
        What to fit (checked by :meth:`FitRequest.check` first, by the caller).
    cache_dir
        The cache folder of the forward model's cloth response (the bake cache's).
    threads
        CPU threads of the transport; None: all.
    scheduler
        A dask cluster's address for the candidates (docs/distributed.md); None: the child itself.
    blender
        ``bpy.app.binary_path``: inside Blender, the child is Blender (:func:`clothlight.jobs.child_command`).
    numba_cache_dir, bytecode_cache_dir
        As :class:`clothlight.jobs.ChildJob`.
    """

    module = FIT_WORKER_MODULE
    what = "fit"
    imports_bpy = True
    failure = FitFailed
    cancellation = FitJobCancelled
    cancelled_note = "nothing was written"
    killed_note = "a later fit into the same folder removes its staging folder"

    def __init__(self, request: FitRequest, *, cache_dir, threads: int | None = None, scheduler: str | None = None,
                 blender: str | None = None, numba_cache_dir=None, bytecode_cache_dir=None):
        super().__init__(numba_cache_dir=numba_cache_dir, bytecode_cache_dir=bytecode_cache_dir, blender=blender)
        self.request = request
        self.cache_dir = pathlib.Path(cache_dir)
        self.threads = threads
        self.scheduler = scheduler or None
        self.outcome: FitOutcome | None = None

    def arguments(self) -> list[str]:
        arguments = ["--request", self.request.to_json(), "--cache-dir", str(self.cache_dir)]
        if self.scheduler:
            arguments += ["--scheduler", self.scheduler]
        if self.threads:
            arguments += ["--threads", str(int(self.threads))]
        return arguments

    def outcome_from(self, event: dict) -> FitOutcome:
        held_out = event.get("held_out_rms")
        return FitOutcome(folder=pathlib.Path(event["folder"]), preset=pathlib.Path(event["preset"]),
                          relative_rms=float(event["relative_rms"]),
                          held_out_rms=None if held_out is None else float(held_out),
                          seconds=float(event.get("seconds", 0.0)), parameters=dict(event.get("parameters", {})),
                          overrides=tuple((str(k), float(v)) for k, v in event.get("overrides", ())),
                          figures=bool(event.get("figures", True)), stop_reason=str(event.get("stop_reason", "")),
                          bound_hits=tuple(event.get("bound_hits", ())))


__all__ = ["FIT_WORKER_MODULE", "FREE_PARAMETERS", "FitFailed", "FitJob", "FitJobCancelled", "FitOutcome",
           "FitRequest", "fit_unavailable_reason", "missing_fit_dependencies", "request_names"]
