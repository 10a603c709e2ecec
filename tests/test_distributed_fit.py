"""The medium fit with each generation's candidates evaluated on a dask cluster: the same fit as
one evaluated in this process (the synthetic forward model of tests/test_fit_optimise.py)."""

from __future__ import annotations

import sys

import pytest

pytest.importorskip("distributed")

from precompute.fit.optimise import FitCancelled
from tests.test_fit_optimise import measured, preset_with_voids, run_fit  # noqa: F401 - the fixture

pytestmark = pytest.mark.slow


def test_a_fit_on_two_local_workers_is_the_fit_made_here(measured):  # noqa: F811
    here, _ = run_fit(measured, budget=40, seed=7)
    spread, model = run_fit(measured, budget=40, seed=7, scheduler="local")
    assert spread.parameters == here.parameters
    assert [(e.kind, e.parameters, e.objective, e.relative_error, e.seed) for e in spread.history] == \
        [(e.kind, e.parameters, e.objective, e.relative_error, e.seed) for e in here.history]
    # the candidates ran on the workers: this process's copy of the model made only the final evaluations
    finals = [e for e in here.history if e.kind == "final"]
    assert len(model.calls) == len(finals) >= 1
    assert all(call["relative_error"] == pytest.approx(0.01) for call in model.calls)


def test_cancel_stops_a_fit_on_a_cluster(measured):  # noqa: F811
    asked = []

    def cancel() -> bool:
        asked.append(True)
        return len(asked) > 3

    with pytest.raises(FitCancelled):
        run_fit(measured, budget=40, seed=7, scheduler="local", cancel=cancel)


def test_an_unreachable_scheduler_is_bad_input_before_any_work(tmp_path, capsys, monkeypatch):
    import clothlight.fit.__main__ as fit_cli
    from precompute.fit import report as fit_report
    from tests.test_fit_optimise import write_measurement

    # importing the forward model is the first work: a stand-in that cannot be imported says if it began
    monkeypatch.setitem(sys.modules, "clothlight.fit.forward", None)
    config, _ = preset_with_voids(specular_weight=0.6)
    preset = tmp_path / "with_voids.toml"
    preset.write_text(fit_report.to_toml(config))
    code = fit_cli.main(["--measured", str(write_measurement(tmp_path / "synthetic.csv")),
                                "--config", str(preset), "--free", "dye_weight_percent", "--budget-evaluations", "12",
                                "--scheduler", "tcp://127.0.0.1:9", "--out", str(tmp_path / "fit")])
    assert code == 2
    assert "tcp://127.0.0.1:9" in capsys.readouterr().err
    assert not (tmp_path / "fit").exists()
