"""The medium fit: CMA-ES over the free parameters, noise-aware, cheap candidates and an accurate winner.

Optimiser
---------
CMA-ES (the ``cma`` package, Hansen's pycma) on every free parameter mapped to [0, 1]
(:meth:`~precompute.fit.parameters.FitParameter.to_unit`, log where the parameter says), with the
box [0, 1]ⁿ as its bounds (pycma's BoundTransform: every candidate it asks for lies in the box),
started at the preset's values with step size σ₀ = 0.2 and a population of max(6, 4 + ⌊3 ln n⌋)
(8 for four parameters).  Its random numbers come from ``seed``: the same seed, measurement, preset
and forward model give the same evaluations, the same history and the same fitted preset (unless a
budget in seconds stops it at a different point).

Noise
-----
The forward model is a Monte-Carlo estimate: its objective is noisy.  Three things keep the fit
honest about it.

* **Common random numbers**: every candidate of one generation is evaluated with the same forward
  seed, so their ranking, which is all CMA-ES uses, is not scrambled by independent noise.
* **The start is a candidate**: the first generation evaluates the start itself beside CMA-ES's
  samples about it, so a fit started from a fitted preset returns that preset unless it finds a
  better point (CMA-ES's samples need not come near a narrow well the start sits in).
* **Re-evaluation of the incumbent**: each generation the best point so far is evaluated again (at
  the generation's seed and accuracy), and a point's estimate is the inverse-variance weighted mean
  of all its evaluations (variance ∝ relative_error²).  A candidate that looked best by a lucky draw
  is pulled back to its mean before it can be returned.
* **Cheap candidates, accurate winner**: the accuracy asked of the forward model follows CMA-ES's
  step size σ: ``relative_error = loose · (tight/loose)^t``, t = log₁₀(σ₀/σ) clipped to [0, 1], from
  ``loose`` (0.08) while the search is wide to ``tight`` (0.02) once σ has shrunk tenfold (both set by
  ``--search-error``, :func:`parse_search_error`); the
  winner is evaluated once more at ``final`` (0.01), and so is the start, with the same seed: the
  closer of the two is the fit, and its evaluation is what the report shows (the lowest of many
  noisy estimates is low by luck, so a winner may be further than the start it was found from).
  (A forward evaluation's paths cost ∝ 1/relative_error²; its optics and tables, the same at every
  accuracy, can cost more.)

Budget
------
``Budget(evaluations=80, seconds=None)``: forward-model calls (candidates, the start, incumbent
re-evaluations and the two final ones; a candidate the medium refuses costs none) and, optionally, wall
seconds (a generation is not started when it and the final evaluations would not fit).  CMA-ES's own
stopping rules (``tolx`` = 1e-3 of the range) end it earlier.

Progress and cancel
-------------------
``progress(FitProgress)`` after every evaluation; ``cancel()`` (returns True to stop) is asked
before each.  Cancelling raises :class:`FitCancelled`, a KeyboardInterrupt: the command line exits
with 130 and writes nothing.
"""

from __future__ import annotations

import contextlib
import functools
import math
import pathlib
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from precompute import bounds
from precompute.distributed import ClusterExecutor, open_executor
from precompute.errors import InputError, ParameterError
from precompute.optics.medium import MAX_VOLUME_FRACTION, medium_from_dict
from precompute.fit.baseline import BaselineFit, fit_baseline
from precompute.fit.figures import band_penalty, band_ratios
from precompute.fit.objective import Objective, Views, load_measurement, parse_target_ratios, split_views
from precompute.fit.parameters import FitParameter, apply, initial_values, parse_free, total_volume_fraction
from precompute.optics.cook_torrance import FIT_TABLE, fuzz_tint, specular_from_config

#: The objective of a candidate the medium refuses (volume fractions summing to 0.74 or more), plus
#: 100 × how far over it is: far above any misfit (a zero model scores 1).
INFEASIBLE_OBJECTIVE = 10.0
#: CMA-ES's initial step size in the [0, 1] box.
SIGMA0 = 0.2
#: CMA-ES stops when its steps are below this (in the [0, 1] box).
TOLX = 1e-3


class ForwardModel(Protocol):
    """A forward model: the cloth's (n_views, 3) BRDF, 1/sr, at the views it was built for."""

    def __call__(self, config: dict, *, specular_weight: float, specular_slope: float, relative_error: float,
                 seed: int, **fuzz) -> np.ndarray: ...


class FitCancelled(KeyboardInterrupt):
    """``cancel()`` asked the fit to stop (a KeyboardInterrupt: exit code 130, nothing written)."""


@dataclass(frozen=True)
class Budget:
    """What a fit may spend: forward-model calls, and optionally wall seconds."""

    evaluations: int = 80
    seconds: float | None = None

    def __post_init__(self):
        if isinstance(self.evaluations, bool) or not isinstance(self.evaluations, int) or self.evaluations < 3:
            raise ParameterError("--budget-evaluations", self.evaluations, "an integer ≥ 3")
        if self.seconds is not None and (not math.isfinite(self.seconds) or self.seconds <= 0):
            raise ParameterError("--budget-seconds", self.seconds, "a number of seconds > 0")


@dataclass(frozen=True)
class AccuracySchedule:
    """The relative error asked of the forward model as the search narrows (module docstring)."""

    loose: float = 0.08
    tight: float = 0.02
    final: float = 0.01

    def __post_init__(self):
        if not 0 < self.final <= self.tight <= self.loose < 1:
            raise ParameterError("schedule", (self.loose, self.tight, self.final), "0 < final ≤ tight ≤ loose < 1")

    def relative_error(self, sigma: float, sigma0: float = SIGMA0) -> float:
        t = min(max(math.log10(sigma0 / sigma) if sigma > 0 else 1.0, 0.0), 1.0)
        return float(self.loose * (self.tight / self.loose) ** t)

    def to_dict(self) -> dict:
        return {"loose": self.loose, "tight": self.tight, "final": self.final}


def parse_search_error(text: str | Sequence[float]) -> AccuracySchedule:
    """``"0.08,0.02"`` (or a pair) → the :class:`AccuracySchedule` whose search asks the forward model for
    that relative error while it is wide and once it has narrowed (``--search-error``); the final
    evaluations ask for 0.01, or the tight error where that is smaller.  ParameterError otherwise."""
    allowed = "LOOSE,TIGHT relative errors with 0 < TIGHT ≤ LOOSE < 1, e.g. 0.08,0.02 (the default)"
    loose, tight = bounds.parse_pair(text, "--search-error", allowed)
    if not 0.0 < tight <= loose < 1.0:
        raise ParameterError("--search-error", text, allowed)
    return AccuracySchedule(loose, tight, min(AccuracySchedule.final, tight))


@dataclass(frozen=True)
class Evaluation:
    """One entry of a fit's history.  ``kind``: ``"candidate"`` (asked by CMA-ES), ``"start"`` (the
    start, evaluated in the first generation), ``"incumbent"`` (the best so far, evaluated again),
    ``"final"`` (the winner, then the start, at the final accuracy) or ``"refused"`` (a medium the loader refuses: no
    forward call, :data:`INFEASIBLE_OBJECTIVE`)."""

    index: int
    generation: int
    kind: str
    parameters: dict
    objective: float
    relative_error: float | None
    seed: int | None
    seconds: float

    def to_dict(self) -> dict:
        return {"index": self.index, "generation": self.generation, "kind": self.kind,
                "parameters": dict(self.parameters), "objective": self.objective,
                "relative_error": self.relative_error, "seed": self.seed, "seconds": round(self.seconds, 6)}


@dataclass(frozen=True)
class FitProgress:
    """What ``progress`` gets after every evaluation."""

    evaluations: int
    total: int
    best_objective: float
    best_parameters: dict
    relative_error: float | None
    sigma: float
    generation: int


@dataclass
class FitResult:
    """Everything a fit found; :mod:`precompute.fit.report` writes it out.

    ``parameters`` holds the free parameters' fitted values, ``specular`` the forward model's
    specular keywords (fitted where free), ``config`` the fitted preset's content (relative file
    paths resolve in ``base_dir``), ``model_rgb`` and ``baseline_rgb`` the (M, 3) BRDFs at every
    measured view (the model's from the final, accurate evaluation), ``metrics`` the objective's
    terms for each, ``bound_hits`` a sentence per parameter that ends at a bound."""

    free: tuple[FitParameter, ...]
    parameters: dict
    initial: dict
    specular: dict
    config: dict
    base_dir: pathlib.Path
    objective: float
    estimate: float
    history: list[Evaluation]
    stop_reason: str
    seed: int
    budget: Budget
    schedule: AccuracySchedule
    measurement: object
    views: Views
    model_rgb: np.ndarray
    baseline: BaselineFit
    baseline_rgb: np.ndarray
    metrics: dict
    target_ratios: dict
    bound_hits: list[str] = field(default_factory=list)
    seconds: float = 0.0
    generations: int = 0
    #: The §6.1 swatches of the final evaluation, when the forward model gives them: ``front_rgb``,
    #: ``back_rgb`` (1/sr at normal view), ``back_front_luminance`` and the ``max_back_front`` asked for.
    swatches: dict | None = None
    #: The bands held (``hold_bands``), when asked: ``band`` (low, high), the final evaluation's
    #: ``ratios`` (:func:`precompute.fit.figures.band_ratios`) and its ``penalty``.
    bands: dict | None = None

    @property
    def forward_evaluations(self) -> int:
        return sum(1 for e in self.history if e.kind != "refused")

    def to_dict(self) -> dict:
        """Everything, JSON-ready (``fit.json``)."""
        views = self.views
        return {
            "parameters": {p.name: {"value": self.parameters[p.name], "initial": self.initial[p.name],
                                    "unit": p.unit, "sets": p.path, "bounds": [p.low, p.high],
                                    "scale": "log" if p.log else "linear",
                                    "at_bound": p.at_bound(self.parameters[p.name])}
                           for p in self.free},
            "specular": dict(self.specular),
            "objective": self.objective,
            "objective_estimate_during_search": self.estimate,
            "metrics": self.metrics,
            "bound_hits": list(self.bound_hits),
            "target_ratios": dict(self.target_ratios),
            "baseline": self.baseline.to_dict(),
            "stop_reason": self.stop_reason,
            "seed": self.seed,
            "budget": {"evaluations": self.budget.evaluations, "seconds": self.budget.seconds},
            "schedule": self.schedule.to_dict(),
            "forward_evaluations": self.forward_evaluations,
            "generations": self.generations,
            "seconds": round(self.seconds, 3),
            "swatches": self.swatches,
            "bands": self.bands,
            "views": [{"theta_i": float(a[0]), "phi_i": float(a[1]), "theta_o": float(a[2]), "phi_o": float(a[3]),
                       "set": "fit" if fit else ("held_out" if held else "other"),
                       "measured": [float(v) for v in measured], "model": [float(v) for v in model],
                       "baseline": [float(v) for v in base]}
                      for a, fit, held, measured, model, base in zip(views.angles_deg, views.fit, views.held_out,
                                                                      self.measurement.rgb, self.model_rgb,
                                                                      self.baseline_rgb)],
            "history": [e.to_dict() for e in self.history],
        }


# ---- CMA-ES -------------------------------------------------------------------------------------


def _derived_seed(*words: int) -> int:
    return int(np.random.SeedSequence([int(w) % 2**63 for w in words]).generate_state(1, np.uint64)[0] % 2**63)


_FINAL_TAG, _CMA_TAG = 0xF17A1, 0xC3A


@dataclass
class _Point:
    unit: tuple
    parameters: dict
    evaluations: list = field(default_factory=list)  # (objective, relative_error)
    profiled: dict = field(default_factory=dict)  # the inner fit's values at the latest evaluation

    @property
    def estimate(self) -> float:
        if not self.evaluations:
            return math.inf
        values = np.array([o for o, _ in self.evaluations])
        weights = np.array([1.0 / (e * e) if e else 1.0 for _, e in self.evaluations])
        return float(np.sum(values * weights) / np.sum(weights))


@dataclass(frozen=True)
class Refused:
    """What ``evaluate`` returns for a candidate the medium refuses: no forward call, and the objective
    :data:`INFEASIBLE_OBJECTIVE` plus 100 × ``excess`` (how far the volume fractions' sum is over
    0.74), a slope that leads CMA-ES back to media that exist."""

    reason: str
    excess: float = 0.0

    @property
    def objective(self) -> float:
        return INFEASIBLE_OBJECTIVE + 100.0 * max(0.0, self.excess)


#: Accurate evaluations after the search: the winner's and the start's (:func:`fit_medium`).
FINAL_EVALUATIONS = 2


def population_size(n: int) -> int:
    """CMA-ES's population for ``n`` free parameters: max(6, 4 + ⌊3 ln n⌋)."""
    return max(6, 4 + int(3 * math.log(n)))


def check_budget(budget: Budget, n_free: int, popsize: int | None = None) -> int:
    """The population size; ParameterError naming ``--budget-evaluations`` when the budget does not
    hold one generation and the final evaluations."""
    population = popsize or population_size(n_free)
    bounds.FIT_EVALUATIONS.check(budget.evaluations)
    least = population + 1 + FINAL_EVALUATIONS
    if budget.evaluations < least:
        raise ParameterError("--budget-evaluations", budget.evaluations,
                             f"at least {least} for {n_free} free parameters (one generation of {population} "
                             f"candidates and the start, and the final evaluations of the winner and the start)")
    return population


def evaluate_in_turn(evaluate: Callable, requests: Sequence[tuple], cancel: Callable[[], bool] | None = None):
    """``(evaluate(*request), seconds)`` for each request, one after the other, as each is done;
    ``cancel()`` is asked before each (FitCancelled)."""
    for request in requests:
        if cancel is not None and cancel():
            raise FitCancelled("fit cancelled")
        t0 = time.perf_counter()
        value = evaluate(*request)
        yield value, time.perf_counter() - t0


def minimise(evaluate: Callable[[dict, float, int], float | tuple | Refused], free: Sequence[FitParameter],
             start: Mapping,
             *, seed: int = 0, budget: Budget = Budget(), schedule: AccuracySchedule = AccuracySchedule(),
             popsize: int | None = None, progress: Callable[[FitProgress], None] | None = None,
             cancel: Callable[[], bool] | None = None, evaluate_many: Callable = evaluate_in_turn) -> dict:
    """Minimise ``evaluate(parameters, relative_error, seed)`` over ``free`` from ``start`` (module
    docstring).  ``evaluate`` returns the objective, ``(objective, values)`` when it also fitted
    parameters of its own (the profiled specular term: ``values`` are recorded with the point), or
    :class:`Refused` for a medium the loader refuses (CMA-ES gets its penalty; no forward evaluation
    is counted).

    A generation's evaluations (its candidates and the incumbent's re-evaluation) are independent:
    ``evaluate_many(evaluate, requests, cancel)`` yields ``(value, seconds)`` for each request in
    order (:func:`evaluate_in_turn`, or on a cluster :func:`evaluate_on_cluster`); the history is
    the same either way.

    Returns ``{"best": parameters, "estimate": objective, "history": [Evaluation], "stop_reason",
    "generations", "seconds", "sigma"}``; the final, accurate evaluations are left to the caller (it
    reserves :data:`FINAL_EVALUATIONS` of the budget for them)."""
    import cma

    n = len(free)
    x0 = [min(max(p.to_unit(start[p.name]), 0.02), 0.98) for p in free]
    population = popsize or population_size(n)
    options = {"bounds": [[0.0] * n, [1.0] * n], "seed": _derived_seed(seed, _CMA_TAG) % (2**31 - 2) + 1,
               "popsize": population, "tolx": TOLX, "tolfun": 0.0, "tolfunhist": 0.0, "tolflatfitness": 10,
               "verbose": -9, "verb_disp": 0, "verb_log": 0, "verb_time": False, "maxiter": 10**6}
    es = cma.CMAEvolutionStrategy(x0, SIGMA0, options)
    began = time.perf_counter()
    history: list[Evaluation] = []
    points: dict[tuple, _Point] = {}
    spent = 0  # forward evaluations
    reserve = FINAL_EVALUATIONS
    generation = 0

    def to_parameters(u) -> tuple[tuple, dict]:
        key = tuple(round(float(v), 12) for v in u)
        return key, {p.name: p.from_unit(v) for p, v in zip(free, key)}

    # The start is evaluated beside the first generation's candidates, in the incumbent's place: CMA-ES
    # samples about it and may never land on it, and a fit started from a fitted preset must not end
    # further from the measurement than that preset.
    start_key, start_parameters = to_parameters([p.to_unit(start[p.name]) for p in free])
    start_point = _Point(start_key, start_parameters)
    incumbent: _Point | None = None
    stop_reason = ""
    generation_seconds = 0.0

    def record(point: _Point, kind: str, accuracy: float, forward_seed: int, value, seconds: float) -> float:
        nonlocal spent
        if isinstance(value, tuple):  # (objective, the profiled parameters' values for this point)
            value, point.profiled = value[0], dict(value[1])
        if isinstance(value, Refused):
            history.append(Evaluation(len(history), generation, "refused", dict(point.parameters), value.objective,
                                      None, None, seconds))
            return value.objective
        spent += 1
        point.evaluations.append((float(value), accuracy))
        history.append(Evaluation(len(history), generation, kind, {**point.parameters, **point.profiled},
                                  float(value), accuracy, forward_seed, seconds))
        if progress is not None:
            best = min((p for p in points.values() if p.evaluations), key=lambda p: p.estimate)
            progress(FitProgress(spent, budget.evaluations, best.estimate, dict(best.parameters), accuracy,
                                 float(es.sigma), generation))
        return float(value)

    while True:
        accuracy = schedule.relative_error(float(es.sigma))
        needed = population + 1  # the candidates and the incumbent's re-evaluation (the start's, at first)
        if spent + needed + reserve > budget.evaluations:
            stop_reason = f"budget: {budget.evaluations} forward evaluations"
            break
        if budget.seconds is not None and history:
            per_evaluation = generation_seconds / max(needed, 1)
            final_cost = FINAL_EVALUATIONS * per_evaluation * (accuracy / schedule.final) ** 2
            if time.perf_counter() - began + generation_seconds + final_cost > budget.seconds:
                stop_reason = f"budget: {budget.seconds:g} s"
                break
        if es.stop():
            stop_reason = "converged: " + ", ".join(f"{k} = {v}" for k, v in es.stop().items())
            break
        if generation > 100 * budget.evaluations:  # every candidate refused: no progress is possible
            stop_reason = "every candidate was refused by the medium"
            break
        t_generation = time.perf_counter()
        forward_seed = _derived_seed(seed, generation)
        solutions = es.ask()
        # The budget check above leaves room for every candidate and the incumbent's re-evaluation.
        batch = [(points.setdefault(key, _Point(key, parameters)), "candidate")
                 for key, parameters in map(to_parameters, solutions)]
        if incumbent is not None:
            batch.append((incumbent, "incumbent"))
        else:
            batch.append((points.setdefault(start_key, start_point), "start"))
        requests = [(dict(point.parameters), accuracy, forward_seed) for point, _ in batch]
        values = [record(point, kind, accuracy, forward_seed, value, seconds)
                  for (point, kind), (value, seconds) in zip(batch, evaluate_many(evaluate, requests, cancel))]
        es.tell(solutions, values[:len(solutions)])
        evaluated = [p for p in points.values() if p.evaluations]
        if evaluated:
            incumbent = min(evaluated, key=lambda p: (p.estimate, p.unit))
        generation += 1
        generation_seconds = time.perf_counter() - t_generation
    if incumbent is None:
        raise InputError("the fit evaluated no medium the loader accepts (every candidate was refused); "
                         "check the preset's volume fractions")
    return {"best": {**incumbent.parameters, **incumbent.profiled}, "estimate": incumbent.estimate, "history": history,
            "stop_reason": stop_reason, "generations": generation, "seconds": time.perf_counter() - began,
            "sigma": float(es.sigma), "spent": spent}


# ---- the fit ------------------------------------------------------------------------------------


def fit_medium(measurement, preset_config: Mapping, base_dir: str | pathlib.Path, *, free: str | Sequence[str],
               forward_model: ForwardModel, seed: int = 0, budget: Budget | int = 80,
               target_ratios: str | Mapping[str, float] | None = None,
               progress: Callable[[FitProgress], None] | None = None, cancel: Callable[[], bool] | None = None,
               specular: Mapping[str, float] | None = None, schedule: AccuracySchedule | None = None,
               popsize: int | None = None, max_back_front: float | None = None,
               hold_bands: tuple[float, float] | None = None,
               scheduler: str | ClusterExecutor | None = None) -> FitResult:
    """Fit the free parameters of a medium to a measurement (module docstring).

    Parameters
    ----------
    measurement
        A ``precompute.fit.measured_data.Measurement``, or the path of a measured-data CSV.
    preset_config, base_dir
        The preset's content and the folder its relative paths resolve in
        (:func:`precompute.optics.medium.load_preset_config`); the values of the parameters that are not
        free stay as they are.
    free
        Names of :data:`precompute.fit.parameters.PARAMETERS` (a sequence or ``"a,b,c"``).
    forward_model
        :class:`ForwardModel`, built for the measurement's views in the order of ``measurement.rgb``
        (``split_views(measurement).forward_views``).
    seed
        Seeds CMA-ES and every forward evaluation: the same seed gives the same result.
    budget
        :class:`Budget`, or a number of forward evaluations.
    target_ratios
        Colour targets at normal incidence and view (``"B/R=0.08,G/R=0.011"`` or a mapping).
    progress, cancel
        After every evaluation / before each (module docstring).
    specular
        The specular keywords where not free (default: the preset's ``[fit]`` table, else the
        shader's defaults, weight 1 and m = 0.8).
    max_back_front
        The largest luminance ratio of the §6.1 swatches, lit from behind over lit from the front
        (real cloth is darker lit from behind, the paper's Fig. 9): a forward model that gives the
        swatches (``swatch_count`` rows after the measured views) adds ``max(0, ln(ratio / max))``
        to the objective.  None: no constraint.
    hold_bands
        (low, high): adds :func:`precompute.fit.figures.band_penalty`, how far the candidate's
        backscatter and off-specular colour, model over measured, lie outside that band (issue 43's is
        0.85–1.15).  None: no constraint.
    scheduler
        Where each generation's evaluations run (:mod:`precompute.distributed`: ``"local"`` or a
        cluster's address, or a cluster already open with ``open_executor(..., code=FIT_CODE)``;
        None: here, one after the other); the fit is the same either way.
    """
    began = time.perf_counter()
    if isinstance(measurement, (str, pathlib.Path)):
        measurement = load_measurement(measurement)
    budget = budget if isinstance(budget, Budget) else Budget(evaluations=budget)
    schedule = schedule or AccuracySchedule()
    free = parse_free(free)
    base_dir = pathlib.Path(base_dir)
    # the medium and the forward model get the preset without its [fit] table (the specular term)
    config = {key: value for key, value in preset_config.items() if key != FIT_TABLE}
    medium_from_dict(config, base_dir)  # the preset itself must be valid: bad input, before any work
    specular = {**specular_from_config(preset_config), **dict(specular or {})}
    start = initial_values(free, config, specular)
    views = split_views(measurement)
    objective = Objective(measurement, views, parse_target_ratios(target_ratios))
    profiled = [p for p in free if p.is_specular] if hasattr(forward_model, "parts") else []
    if len(profiled) == len(free):
        profiled = []
    searched = [p for p in free if p not in profiled]

    population = check_budget(budget, len(searched), popsize)

    swatches = int(getattr(forward_model, "swatch_count", 0))
    if max_back_front is not None and not swatches:
        raise ParameterError("max_back_front", max_back_front, "a forward model that gives the §6.1 swatches")

    evaluate = CandidateEvaluator(config, specular, base_dir, forward_model, objective, tuple(profiled), swatches,
                                  max_back_front, None if hold_bands is None else tuple(hold_bands))
    with contextlib.ExitStack() as stack:
        evaluate_many = evaluate_in_turn
        if scheduler is not None:
            executor = (scheduler if isinstance(scheduler, ClusterExecutor)
                        else stack.enter_context(open_executor(scheduler, code=FIT_CODE)))
            evaluate_many = functools.partial(evaluate_on_cluster, executor, executor.share(evaluate))
        search = minimise(evaluate, searched, {p.name: start[p.name] for p in searched}, seed=seed, budget=budget,
                          schedule=schedule, popsize=population, progress=progress, cancel=cancel,
                          evaluate_many=evaluate_many)
    history = search["history"]
    # The winner's estimate comes from loose evaluations, and the lowest of many noisy estimates is low by
    # luck: the start is evaluated again beside it at the final accuracy, with the same seed, and the closer
    # of the two is the fit (a fit from a fitted preset never returns a medium further than the preset).
    finalists = [search["best"]]
    if any(abs(p.to_unit(search["best"][p.name]) - p.to_unit(start[p.name])) > 1e-9 for p in searched):
        finalists.append(dict(start))
    final_seed = _derived_seed(seed, _FINAL_TAG)
    finals = []
    for parameters in finalists:
        if cancel is not None and cancel():
            raise FitCancelled("fit cancelled")
        if evaluate.refusal(parameters) is not None:
            continue
        t0 = time.perf_counter()
        all_rgb, values = evaluate.model_and_values(*apply(config, specular, parameters), schedule.final, final_seed)
        parameters = {**parameters, **values}  # the specular term refitted to the accurate evaluation
        finals.append((evaluate.score(all_rgb), parameters, all_rgb))
        history.append(Evaluation(len(history), search["generations"], "final", dict(parameters), finals[-1][0],
                                  schedule.final, final_seed, time.perf_counter() - t0))
        if progress is not None:
            progress(FitProgress(search["spent"] + len(finals), budget.evaluations, min(f[0] for f in finals),
                                 dict(parameters), schedule.final, search["sigma"], search["generations"]))
    final_objective, best, all_rgb = min(finals, key=lambda final: final[0])
    fitted_config, keywords = apply(config, specular, best)
    model_rgb = objective.check(all_rgb[:len(all_rgb) - swatches])
    swatch_rgb = all_rgb[len(all_rgb) - swatches:] if swatches else None
    baseline = fit_baseline(objective)
    baseline_rgb = baseline.brdf(views.angles_deg)
    metrics = {"model": objective.terms(model_rgb), "baseline": objective.terms(baseline_rgb)}
    return FitResult(
        free=free, parameters=best, initial=start, specular=keywords, config=fitted_config, base_dir=base_dir,
        objective=final_objective, estimate=search["estimate"], history=history, stop_reason=search["stop_reason"],
        seed=seed, budget=budget, schedule=schedule, measurement=measurement, views=views, model_rgb=model_rgb,
        baseline=baseline, baseline_rgb=baseline_rgb, metrics=metrics, target_ratios=objective.target_ratios,
        bound_hits=bound_hits(free, best), seconds=time.perf_counter() - began, generations=search["generations"],
        swatches=None if swatch_rgb is None else {
            "front_rgb": swatch_rgb[0].tolist(), "back_rgb": swatch_rgb[1].tolist(),
            "back_front_luminance": float(LUMINANCE @ swatch_rgb[1]) / float(LUMINANCE @ swatch_rgb[0]),
            "max_back_front": max_back_front},
        bands=None if hold_bands is None else {
            "band": list(hold_bands), "ratios": band_ratios(model_rgb, objective.measured, views),
            "penalty": band_penalty(model_rgb, objective.measured, views, hold_bands)})


@dataclass
class CandidateEvaluator:
    """A candidate's objective: ``evaluator(parameters, relative_error, forward_seed)`` applies the
    free parameters to the preset, refuses a medium the loader refuses (:class:`Refused`), runs the
    forward model and scores it — with the specular term fitted per candidate where it is profiled
    (``(objective, its values)``).  Picklable, so that a cluster's workers evaluate candidates."""

    config: dict
    specular: dict
    base_dir: pathlib.Path
    forward_model: ForwardModel
    objective: Objective
    profiled: tuple
    swatches: int
    max_back_front: float | None
    hold_bands: tuple[float, float] | None = None

    def score(self, rgb: np.ndarray) -> float:
        measured_views = rgb[:len(rgb) - self.swatches]
        score = self.objective(measured_views)
        if self.max_back_front is not None:
            score += back_front_penalty(rgb[len(rgb) - self.swatches:], self.max_back_front)
        if self.hold_bands is not None:
            score += band_penalty(measured_views, self.objective.measured, self.objective.views, self.hold_bands)
        return score

    def model_and_values(self, candidate: dict, keywords: dict, relative_error: float, forward_seed: int):
        if not self.profiled:
            return self.forward_model(candidate, **keywords, relative_error=relative_error, seed=forward_seed), {}
        medium_part, specular_part = self.forward_model.parts(candidate, relative_error=relative_error,
                                                              seed=forward_seed)
        values = fit_profiled_specular(self.score, medium_part, specular_part, self.profiled, keywords)
        keywords = {**keywords, **{p.path: values[p.name] for p in self.profiled}}
        return cloth_from_parts(medium_part, specular_part, keywords), values

    def refusal(self, parameters: dict) -> Refused | None:
        """:class:`Refused` where the medium at ``parameters`` is one the loader refuses, else None."""
        candidate, _ = apply(self.config, self.specular, parameters)
        total = total_volume_fraction(candidate)
        if total >= MAX_VOLUME_FRACTION:
            return Refused(f"particle volume fractions sum to {total:.3g} (≥ {MAX_VOLUME_FRACTION})",
                           total - MAX_VOLUME_FRACTION)
        try:
            medium_from_dict(candidate, self.base_dir)
        except ParameterError as error:
            return Refused(str(error))
        return None

    def __call__(self, parameters: dict, relative_error: float, forward_seed: int) -> float | tuple | Refused:
        refused = self.refusal(parameters)
        if refused is not None:
            return refused
        candidate, keywords = apply(self.config, self.specular, parameters)
        rgb, values = self.model_and_values(candidate, keywords, relative_error, forward_seed)
        return (self.score(rgb), values) if self.profiled else self.score(rgb)


#: The code a fit's workers run, checked against this checkout's (precompute.distributed).
FIT_CODE = {"entries": ("precompute.fit.optimise",)}


def evaluate_timed(evaluate: CandidateEvaluator, parameters: dict, relative_error: float,
                   forward_seed: int) -> tuple:
    """A cluster task: ``(evaluate(parameters, relative_error, forward_seed), seconds)``."""
    t0 = time.perf_counter()
    value = evaluate(parameters, relative_error, forward_seed)
    return value, time.perf_counter() - t0


def evaluate_on_cluster(executor, shared_evaluate, evaluate: CandidateEvaluator, requests: Sequence[tuple],
                        cancel: Callable[[], bool] | None = None) -> list:
    """A generation's evaluations as tasks of ``executor`` (:func:`precompute.distributed.open_executor`),
    with the evaluator copied to each worker once (``shared_evaluate``); ``cancel()`` stops them all
    (FitCancelled).  ``evaluate`` is what they run, here for :func:`minimise`'s signature."""
    try:
        return executor.map(evaluate_timed, [(shared_evaluate, *request) for request in requests], cancel=cancel)
    except KeyboardInterrupt:
        if cancel is not None and cancel():
            raise FitCancelled("fit cancelled") from None
        raise


#: The points in all of the grid the profiled specular fit scans before it polishes (19 per parameter
#: for two, the sheen; 7 for three, with the fuzz): the misfit over (weight, slope) has more than one
#: basin (a broad faint lobe and a narrow bright one can both explain a grazing rise), and a local
#: search from fixed starts ended in the worse one (fibre_red_cotton's sheen 0.84, m 0.58: relative
#: RMS 0.349, against 0.231 at 0.11, m 0.23),
PROFILE_GRID_SIZE = 343
#: and never fewer than this per parameter.
PROFILE_MIN_POINTS = 7
#: How many of the grid's best points the bounded local search starts from.
PROFILE_POLISHED = 3
#: The most points the scan takes (7 per parameter for four: the sheen and the fuzz's albedo and
#: depth); beyond, the fuzz's shape freed too, it scans a Sobol' set of 2048 instead of the grid.
PROFILE_MAX_SCANNED = 2401


#: Rec. 709 luminance of linear R, G, B.
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


def back_front_penalty(swatch_rgb: np.ndarray, max_back_front: float) -> float:
    """``max(0, ln(r / max_back_front))`` with r the luminance ratio of the swatch lit from behind
    over the one lit from the front (rows 1 and 0 of ``swatch_rgb``)."""
    front, back = (float(LUMINANCE @ row) for row in swatch_rgb[:2])
    if front <= 0.0:
        return INFEASIBLE_OBJECTIVE
    return max(0.0, math.log(max(back, 1e-300) / front / max_back_front))


def cloth_from_parts(medium_part: np.ndarray, specular_part: Callable, keywords: Mapping[str, float]) -> np.ndarray:
    """The cloth BRDF (n, 3), 1/sr, of a forward model's ``parts``: the medium's part, shaded by a fuzz
    of depth where ``keywords`` holds one (``specular_part.transmittance``), plus what the sheen and
    the fuzz add (n, 3), ``specular_part`` at the sheen's weight and slope of ``keywords`` and at its
    fuzz albedo, depth, asymmetry, flatness and tint where it holds them
    (:func:`precompute.optics.cook_torrance.fuzz_tint`)."""
    fuzz = {key: keywords[key] for key in ("fuzz_albedo", "fuzz_depth", "fuzz_asymmetry", "fuzz_flatness")
            if keywords.get(key)}
    if fuzz.get("fuzz_albedo"):
        fuzz["fuzz_tint"] = fuzz_tint(keywords)
    terms = specular_part(keywords["specular_weight"], keywords["specular_slope"], **fuzz)
    if fuzz.get("fuzz_depth"):
        flatness = {"fuzz_flatness": fuzz["fuzz_flatness"]} if "fuzz_flatness" in fuzz else {}
        medium_part = medium_part * specular_part.transmittance(fuzz["fuzz_depth"], **flatness)[:, None]
    return medium_part + terms


def fit_profiled_specular(objective: Callable[[np.ndarray], float], medium_part: np.ndarray, specular_part: Callable,
                          profiled: Sequence[FitParameter], keywords: Mapping[str, float]) -> dict[str, float]:
    """The values of the specular parameters ``profiled`` that minimise ``objective`` for one medium:
    its cloth BRDF without the specular term ``medium_part`` (n, 3) plus ``specular_part(weight,
    slope, **fuzz)`` (n, 3) (:func:`cloth_from_parts`).  A grid of about
    :data:`PROFILE_GRID_SIZE` points over their [0, 1] box (a Sobol' set beyond
    :data:`PROFILE_MAX_SCANNED`; log where they say; the fuzz's albedo at most 1 in every channel,
    :func:`fuzz_within_unit_albedo`), then bounded L-BFGS-B from its :data:`PROFILE_POLISHED` best points
    and from ``keywords``' own values (where it holds them all), so that the profile never ends worse
    than where it was started; no forward evaluation.  Variable projection: the optimiser outside
    searches only the medium, whose every candidate gets its best sheen."""
    from scipy.optimize import minimize

    def values_at(u) -> dict:
        return fuzz_within_unit_albedo({**keywords, **{p.path: p.from_unit(float(x)) for p, x in zip(profiled, u)}})

    def misfit(u) -> float:
        return objective(cloth_from_parts(medium_part, specular_part, values_at(u)))

    points = max(PROFILE_MIN_POINTS, round(PROFILE_GRID_SIZE ** (1.0 / len(profiled))))
    if points ** len(profiled) <= PROFILE_MAX_SCANNED:
        axes = [np.linspace(0.0, 1.0, points)] * len(profiled)
        grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(profiled))
    else:  # a full grid would be too many: a scrambled Sobol' set of as many points fills the box as evenly
        from scipy.stats import qmc

        grid = qmc.Sobol(len(profiled), seed=0).random_base2(int(math.log2(PROFILE_MAX_SCANNED)))
    scanned = np.array([misfit(u) for u in grid])
    starts = list(grid[np.argsort(scanned, kind="stable")[:PROFILE_POLISHED]])
    if all(p.path in keywords for p in profiled):  # a narrow well between the grid's points is not lost
        starts.append(np.array([p.to_unit(float(keywords[p.path])) for p in profiled]))
    best = None
    for start in starts:
        result = minimize(misfit, start, method="L-BFGS-B", bounds=[(0.0, 1.0)] * len(profiled))
        if best is None or result.fun < best.fun:
            best = result
    values = values_at(best.x)
    return {p.name: values[p.path] for p in profiled}


def fuzz_within_unit_albedo(keywords: Mapping[str, float]) -> dict:
    """``keywords`` with each fuzz tint cut to 1 / ``fuzz_albedo`` where it is more: a fuzz cannot
    return more light than it meets in any channel (an albedo of at most 1, what the bake checks).
    The profile searches a box (:func:`fit_profiled_specular`), where that bound is not a face:
    beyond it the channel's albedo stays 1, a misfit that is flat there rather than a wall."""
    keywords = dict(keywords)
    albedo = float(keywords.get("fuzz_albedo", 0.0))
    for key in ("fuzz_tint_red", "fuzz_tint_blue"):
        if albedo > 0.0 and key in keywords:
            keywords[key] = min(float(keywords[key]), 1.0 / albedo)
    return keywords


def bound_hits(free: Sequence[FitParameter], values: Mapping[str, float]) -> list[str]:
    """A sentence for each parameter whose value ends at a bound (within 5 % of its [0, 1] range)."""
    hits = []
    for p in free:
        side = p.at_bound(values[p.name])
        if side:
            bound = p.low if side == "lower" else p.high
            unit = f" {p.unit}" if p.unit else ""
            hits.append(f"ends at the {side} bound of {p.name} ({bound:g}{unit}): the best medium may lie beyond "
                        "the fit range, or the parameter compensates for something the model lacks")
    return hits


__all__ = ["INFEASIBLE_OBJECTIVE", "AccuracySchedule", "Budget", "Evaluation", "FitCancelled", "FitProgress",
           "FitResult", "ForwardModel", "Refused", "bound_hits", "check_budget", "fit_medium",
           "fuzz_within_unit_albedo", "minimise", "population_size"]
