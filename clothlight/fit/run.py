"""A whole medium fit as one job: every input checked before any work, then the forward model and the search.

``python -m clothlight.fit`` (:mod:`clothlight.fit.__main__`) and the add-on's fit worker
(``clothlight.fit.worker``, the Yarn Medium panel's Fit) both run a fit through here, so they check
the same inputs in the same order with the same messages, build the same forward model and write
the same folder (:func:`precompute.fit.report.write_fit_folder`)::

    inputs = check_fit_inputs("red-fabric2.csv", "voided_red_cotton", "dye_weight_percent,specular_slope",
                              out="out/fit", budget_evaluations=40)
    result = run_fit(inputs, seed=0)
    write_fit_folder(result, inputs.out, measured_name=inputs.measured_name)

The messages name the command line's options (``--free``, ``--budget-evaluations``, …); the
add-on maps them to its own names.  Not imported by :mod:`precompute.fit` itself.
"""

from __future__ import annotations

import contextlib
import math
import pathlib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

from precompute.errors import ParameterError
from precompute.optics.medium import load_preset_config, medium_from_dict
from precompute.outputs import check_writable_folder
from precompute.fit.figures import parse_band
from precompute.fit.objective import Objective, Views, load_measurement, parse_target_ratios, split_views
from precompute.fit.optimise import (FIT_CODE, AccuracySchedule, Budget, FitProgress, FitResult, check_budget,
                                     fit_medium, parse_search_error)
from precompute.fit.parameters import FitParameter, initial_values, parse_free
from precompute.optics.measured_sample import sample_azimuths_deg, sample_weave_name
from precompute.optics.cook_torrance import FIT_TABLE, specular_from_config
from precompute.fit.report import check_fit_folder


@dataclass(frozen=True)
class FitInputs:
    """The checked inputs of a fit (:func:`check_fit_inputs`).

    ``config`` is the starting preset's content with its ``[fit]`` table (the specular term) and
    ``medium_config`` the same without it, as the medium and the forward model take it; ``dye_range``
    is the free dye's range when the fit reads every candidate from one dye series, else None."""

    measurement: object
    measured_name: str
    config: dict
    medium_config: dict
    base_dir: pathlib.Path
    free: tuple[FitParameter, ...]
    target_ratios: dict
    views: Views
    budget: Budget
    max_back_front: float | None
    hold_bands: tuple[float, float] | None
    schedule: AccuracySchedule
    dye_range: tuple[float, float] | None
    out: pathlib.Path
    cache_dir: pathlib.Path | None


def check_fit_inputs(measured: str | pathlib.Path, preset: str | pathlib.Path, free: str | Sequence[str], *,
                     out: str | pathlib.Path, overrides: Mapping[str, object] | Sequence[str] = (),
                     target_ratios: str | Mapping[str, float] | None = None, max_back_front: float | None = None,
                     hold_bands: str | Sequence[float] | None = None, budget_evaluations: int = 150,
                     budget_seconds: float | None = None, search_error: str | Sequence[float] | None = None,
                     dye_series: bool = False, cache_dir: str | pathlib.Path | None = None) -> FitInputs:
    """Every input of a fit, checked before any work: the free parameters (and whether a dye series
    can serve them), the measurement, the starting medium (a shipped preset's name or a preset TOML
    file, with ``overrides`` as ``precompute.bake.apply_overrides`` takes them: ``{"dye.weight_percent":
    2.0}``), its sample weave (``[sample]``, :mod:`precompute.optics.measured_sample`) and the species
    the free parameters need, the colour targets, the budget, the back-lit limit, the band held, the search's
    relative errors (:func:`precompute.fit.optimise.parse_search_error`), the output folder and the cache
    folder.  ParameterError (an InputError) naming the first bad one."""
    free_parameters = parse_free(free)
    dye_range = None
    if dye_series:
        medium_free = [p for p in free_parameters if not p.is_specular]
        if [p.name for p in medium_free] != ["dye_weight_percent"]:
            raise ParameterError("--dye-series", ",".join(p.name for p in free_parameters),
                                 "a fit whose only free medium parameter is dye_weight_percent (the specular term "
                                 "may be free too)")
        dye_range = (medium_free[0].low, medium_free[0].high)
    measurement = load_measurement(measured)
    config, base_dir = load_preset_config(preset)
    if overrides:
        from precompute.bake import apply_overrides

        config = apply_overrides(config, overrides)
    medium_config = {key: value for key, value in config.items() if key != FIT_TABLE}
    medium_from_dict(medium_config, base_dir)
    sample_weave_name(config)
    sample_azimuths_deg(config)
    initial_values(free_parameters, config, specular_from_config(config))  # the species the free parameters need
    ratios = parse_target_ratios(target_ratios)
    views = split_views(measurement)
    Objective(measurement, views, ratios)
    budget = Budget(evaluations=budget_evaluations, seconds=budget_seconds)
    check_budget(budget, len(free_parameters))
    if max_back_front is not None and not (isinstance(max_back_front, (int, float)) and math.isfinite(max_back_front)
                                           and max_back_front > 0):
        raise ParameterError("--max-back-front", max_back_front, "a ratio > 0")
    bands = None if hold_bands is None else parse_band(hold_bands)
    schedule = AccuracySchedule() if search_error is None else parse_search_error(search_error)
    out = check_fit_folder(out)
    if cache_dir is not None:
        check_writable_folder(cache_dir, "--cache-dir", what="a cache folder")
    return FitInputs(measurement, pathlib.Path(measured).name, config, medium_config, base_dir, free_parameters,
                     ratios, views, budget, max_back_front, bands, schedule, dye_range, out,
                     None if cache_dir is None else pathlib.Path(cache_dir))


def build_forward(inputs: FitInputs, *, seed: int, threads: int | None = None,
                  progress: Callable[[int, int], None] | None = None):
    """The real forward model of ``inputs`` (``clothlight.fit.forward``, imported here so the rest
    of a fit runs and is tested without it): the cloth response rendered with Blender (``bpy``) or
    read from the cache, ``progress(done, total)`` following its renders."""
    from .forward import build_forward_model

    kwargs = {"cache_dir": inputs.cache_dir} if inputs.cache_dir is not None else {}
    if threads is not None:
        kwargs["threads"] = threads
    return build_forward_model(inputs.views.forward_views, inputs.medium_config, inputs.base_dir, seed=seed,
                               progress=progress, dye_range=inputs.dye_range, **kwargs)


def run_fit(inputs: FitInputs, *, seed: int, scheduler: str | None = None, threads: int | None = None,
            building: Callable[[int, int], None] | None = None,
            searching: Callable[[FitProgress], None] | None = None,
            cancel: Callable[[], bool] | None = None,
            while_building: Callable[[], contextlib.AbstractContextManager] = contextlib.nullcontext) -> FitResult:
    """Build the forward model and fit (:func:`precompute.fit.fit_medium`); nothing is written.

    ``scheduler``: a checked scheduler (``precompute.distributed.check_scheduler``) or None; its
    cluster is opened first, so that an address that does not answer is refused before the cloth
    response.  A dye-series fit always runs here.  ``building(done, total)`` follows the cloth
    response's renders, ``searching(FitProgress)`` every evaluation, ``cancel()`` is asked before
    each evaluation (True: FitCancelled, a KeyboardInterrupt).  The forward model is built inside
    ``while_building()`` (the add-on's worker holds a cancel there until a render ends:
    :class:`precompute.exit_codes.DeferredInterrupt`)."""
    from precompute.distributed import open_executor

    scheduler = None if inputs.dye_range is not None else scheduler
    with contextlib.ExitStack() as stack:
        executor = None if scheduler is None else stack.enter_context(open_executor(scheduler, code=FIT_CODE))
        with while_building():
            forward_model = build_forward(inputs, seed=seed, threads=threads, progress=building)
        return fit_medium(inputs.measurement, inputs.config, inputs.base_dir, free=[p.name for p in inputs.free],
                          forward_model=forward_model, seed=seed, budget=inputs.budget,
                          target_ratios=inputs.target_ratios, progress=searching, cancel=cancel,
                          max_back_front=inputs.max_back_front, hold_bands=inputs.hold_bands,
                          schedule=inputs.schedule, scheduler=executor)


__all__ = ["FitInputs", "build_forward", "check_fit_inputs", "run_fit"]
