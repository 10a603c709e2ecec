"""Fit a yarn medium to a measured cloth BRDF (issue 19; docs/fitting.md).

``python -m precompute fit`` (:mod:`precompute.cli.fit`) and, from Python::

    from precompute.fit import fit_medium, write_fit_folder
    result = fit_medium(measurement, preset_config, base_dir, free=["void_fraction", "dye_weight_percent"],
                        forward_model=model, seed=0, budget=80, target_ratios="B/R=0.08,G/R=0.011")
    write_fit_folder(result, "out/fit", measured_name="red-fabric2.csv")

The modules: :mod:`.parameters` (the free parameters, their bounds and scales), :mod:`.objective`
(fit and held-out views, the misfit), :mod:`.optimise` (CMA-ES, noise handling, the accuracy
schedule, :func:`fit_medium`), :mod:`.baseline` (the paper's Lambert + Cook–Torrance fitted to the
same views), :mod:`.report` (the output folder) and ``.forward`` (the forward model:
``build_forward_model``).
"""

from __future__ import annotations

from .baseline import BaselineFit, fit_baseline
from .objective import Objective, Views, load_measurement, parse_target_ratios, split_views
from .optimise import (
    AccuracySchedule,
    Budget,
    Evaluation,
    FitCancelled,
    FitProgress,
    FitResult,
    ForwardModel,
    fit_medium,
)
from .parameters import PARAMETERS, FitParameter, parse_free
from .report import FIT_FOLDER_FILES, check_fit_folder, write_fit_folder

__all__ = ["FIT_FOLDER_FILES", "PARAMETERS", "AccuracySchedule", "BaselineFit", "Budget", "Evaluation",
           "FitCancelled", "FitParameter", "FitProgress", "FitResult", "ForwardModel", "Objective", "Views",
           "check_fit_folder", "fit_baseline", "fit_medium", "load_measurement", "parse_free",
           "parse_target_ratios", "split_views", "write_fit_folder"]
