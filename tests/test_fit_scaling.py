"""The fit's scaling model (scripts/fit_scaling.py): a generation's tasks dealt out to W workers."""

import importlib.util
import pathlib

import pytest

_PATH = pathlib.Path(__file__).resolve().parents[1] / "scripts" / "fit_scaling.py"
_SPEC = importlib.util.spec_from_file_location("fit_scaling", _PATH)
fit_scaling = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(fit_scaling)


def test_a_generation_takes_its_busiest_worker():
    tasks = [5.0, 3.0, 3.0, 2.0]
    assert fit_scaling.generation_wall(tasks, 1) == sum(tasks)
    assert fit_scaling.generation_wall(tasks, 2) == 7.0  # 5 + 2 against 3 + 3
    assert fit_scaling.generation_wall(tasks, 8) == max(tasks)


def test_the_search_is_its_generations_one_after_the_other_then_the_final_evaluation():
    history = [{"generation": 0, "kind": "candidate", "seconds": 4.0},
               {"generation": 0, "kind": "candidate", "seconds": 2.0},
               {"generation": 1, "kind": "candidate", "seconds": 3.0},
               {"generation": 1, "kind": "incumbent", "seconds": 1.0},
               {"generation": 1, "kind": "refused", "seconds": None},
               {"generation": 2, "kind": "final", "seconds": 10.0}]
    assert fit_scaling.predicted_search_seconds(history, 1) == pytest.approx(20.0)
    assert fit_scaling.predicted_search_seconds(history, 2) == pytest.approx(4.0 + 3.0 + 10.0)
