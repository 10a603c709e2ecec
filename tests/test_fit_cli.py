"""``python -m clothlight.fit``: exit codes (0 done, 2 bad input, 130 interrupted, 1 internal) and an
--out folder written as a whole.  In-process (``--scheduler none``), with the synthetic forward model
standing in for ``clothlight.fit.forward`` (put in sys.modules, where the command's lazy import finds it)."""

from __future__ import annotations

import json
import os
import signal
import sys
import time
import tomllib
import types

import pytest

import clothlight.fit.__main__ as fit_cli
from precompute.fit import report as fit_report
from precompute.fit.parameters import PARAMETERS
from precompute.fit.report import FIT_FOLDER_FILES, PLOT_FILES
from precompute.optics.medium import load_preset
from tests.test_fit_optimise import SyntheticForward, preset_with_voids, write_measurement


@pytest.fixture
def fake_forward(monkeypatch):
    """A ``clothlight.fit.forward`` module whose build_forward_model returns the synthetic model;
    records its calls."""
    module = types.ModuleType("clothlight.fit.forward")
    module.calls = []

    def build_forward_model(measured_views, preset_config, base_dir, *, seed=0, progress=None, **kwargs):
        module.calls.append({"views": list(measured_views), "config": preset_config, "base_dir": base_dir,
                             "seed": seed, "kwargs": kwargs})
        if progress is not None:
            progress(1, 1)
        return SyntheticForward(measured_views)

    module.build_forward_model = build_forward_model
    monkeypatch.setitem(sys.modules, "clothlight.fit.forward", module)
    return module


@pytest.fixture
def plots_as_text(monkeypatch):
    """The report's figures stood in for by text files, for tests of the folder rather than of the
    figures (the first test below draws them): matplotlib takes seconds a fit."""
    def write_plots(result, folder):
        for file in PLOT_FILES.values():
            (folder / file).write_text(file)

    monkeypatch.setattr(fit_report, "write_plots", write_plots)


@pytest.fixture
def inputs(tmp_path):
    config, _ = preset_with_voids(specular_weight=0.6)
    preset = tmp_path / "with_voids.toml"
    preset.write_text(fit_report.to_toml(config))
    return {"measured": write_measurement(tmp_path / "synthetic.csv"), "config": preset}


def fit(inputs, out, *extra):
    return fit_cli.main(["--measured", str(inputs["measured"]), "--config", str(inputs["config"]),
                                "--free", "void_fraction,dye_weight_percent", "--budget-evaluations", "30",
                                "--scheduler", "none", "--out", str(out), *extra])


def test_a_fit_writes_its_folder_and_a_preset_the_bake_accepts(inputs, tmp_path, fake_forward, capsys):
    out = tmp_path / "fit"
    assert fit(inputs, out, "--json", "--target-ratios", "B/R=0.2") == 0
    assert sorted(p.name for p in out.iterdir()) == sorted(FIT_FOLDER_FILES)
    summary = json.loads(capsys.readouterr().out)
    assert set(summary["parameters"]) == {"void_fraction", "dye_weight_percent"}
    assert summary["target_ratios"] == {"B/R": 0.2}
    medium = load_preset(out / "preset.toml")
    fitted = json.loads((out / "fit.json").read_text())
    assert medium.dye.weight_percent == pytest.approx(fitted["parameters"]["dye_weight_percent"]["value"])
    assert medium.dye.source == "red_dye_band_model.csv"  # the shipped spectrum still resolves
    assert len(fitted["history"]) >= 10 and len(fitted["views"]) == 84
    report = (out / "report.md").read_text()
    assert "held out" in report and "fit.png" in report
    # the forward model was built once, for every view, in the light-at-180° frame, without [fit]
    (call,) = fake_forward.calls
    assert len(call["views"]) == 84 and all(view[1] == 180.0 for view in call["views"])
    assert "fit" not in call["config"]


def test_the_search_asks_the_forward_model_for_the_errors_given(inputs, tmp_path, fake_forward):
    assert fit(inputs, tmp_path / "fit", "--search-error", "0.03,0.015") == 0
    fitted = json.loads((tmp_path / "fit" / "fit.json").read_text())
    assert fitted["schedule"] == {"loose": 0.03, "tight": 0.015, "final": 0.01}
    searched = [e["relative_error"] for e in fitted["history"] if e["kind"] != "final"]
    assert searched[0] == pytest.approx(0.03) and all(0.015 <= error <= 0.03 for error in searched)
    assert all(e["relative_error"] == pytest.approx(0.01) for e in fitted["history"] if e["kind"] == "final")
    assert fit(inputs, tmp_path / "fine", "--search-error", "0.005,0.005") == 0
    fine = json.loads((tmp_path / "fine" / "fit.json").read_text())
    assert fine["schedule"]["final"] == 0.005  # never looser than the search


def test_unknown_parameter_is_bad_input(inputs, tmp_path, fake_forward, capsys):
    code = fit_cli.main(["--measured", str(inputs["measured"]), "--free", "void_fraction,sheen",
                                "--out", str(tmp_path / "fit")])
    assert code == 2
    error = capsys.readouterr().err
    assert "sheen" in error and "dye_weight_percent" in error
    assert not fake_forward.calls and not (tmp_path / "fit").exists()


@pytest.mark.parametrize("args, words", [
    (["--measured", "{tmp}/missing.csv"], ["--measured", "missing.csv"]),
    (["--config", "{tmp}/missing.toml"], ["--config", "missing.toml"]),
    (["--preset", "paper_2008"], ["voids", "[[particles]]"]),  # no voids species in the paper's preset
    (["--target-ratios", "B/R=-1"], ["--target-ratios"]),
    (["--budget-evaluations", "4"], ["--budget-evaluations"]),
    (["--hold-bands", "1.15,0.85"], ["--hold-bands", "0 < LOW < 1 < HIGH"]),
    (["--search-error", "0.01,0.05"], ["--search-error", "TIGHT ≤ LOOSE"]),
    (["--search-error", "0.05"], ["--search-error"]),
    (["--out", "{tmp}/synthetic.csv"], ["--out", "is a file"]),
])
def test_bad_inputs_exit_with_2_before_any_work(inputs, tmp_path, fake_forward, capsys, args, words):
    argv = {"--measured": str(inputs["measured"]), "--config": str(inputs["config"]), "--out": str(tmp_path / "fit")}
    given = dict(zip(args[::2], (a.replace("{tmp}", str(tmp_path)) for a in args[1::2])))
    if "--preset" in given:
        argv.pop("--config")
    argv.update(given)
    flat = ["--free", "void_fraction,dye_weight_percent"] + [x for kv in argv.items() for x in kv]
    assert fit_cli.main(flat) == 2
    error = capsys.readouterr().err
    for word in words:
        assert word in error
    assert not fake_forward.calls
    assert not (tmp_path / "fit").exists()


def test_dye_series_is_for_a_fit_of_the_dye_alone(inputs, tmp_path, fake_forward, plots_as_text, capsys):
    assert fit(inputs, tmp_path / "refused", "--dye-series") == 2  # void_fraction is free too
    assert "--dye-series" in capsys.readouterr().err and not fake_forward.calls
    code = fit_cli.main(["--measured", str(inputs["measured"]), "--config", str(inputs["config"]),
                                "--free", "dye_weight_percent,specular_weight", "--budget-evaluations", "12",
                                "--dye-series", "--out", str(tmp_path / "fit")])
    assert code == 0
    dye = PARAMETERS["dye_weight_percent"]
    assert fake_forward.calls[0]["kwargs"]["dye_range"] == (dye.low, dye.high)


def test_a_failure_while_writing_leaves_no_partial_folder(inputs, tmp_path, fake_forward, monkeypatch, capsys):
    out = tmp_path / "fit"

    def broken(result, folder):
        (folder / "fit.png").write_bytes(b"half a plot")
        raise RuntimeError("disk full")

    monkeypatch.setattr(fit_report, "write_plots", broken)
    assert fit(inputs, out) == 1
    assert "disk full" in capsys.readouterr().err
    assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["synthetic.csv", "with_voids.toml"]  # no staging left


def test_a_failed_fit_keeps_the_previous_one(inputs, tmp_path, fake_forward, plots_as_text, monkeypatch):
    out = tmp_path / "fit"
    assert fit(inputs, out) == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    monkeypatch.setattr(fit_report, "write_plots", lambda result, folder: (_ for _ in ()).throw(OSError("no")))
    assert fit(inputs, out, "--seed", "5") == 1
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


def test_interrupt_exits_130_and_writes_nothing(inputs, tmp_path, fake_forward, monkeypatch, capsys):
    out = tmp_path / "fit"
    calls = []

    def interrupting(self, config, **kwargs):
        calls.append(1)
        if len(calls) == 12:
            raise KeyboardInterrupt
        return original(self, config, **kwargs)

    original = SyntheticForward.__call__
    monkeypatch.setattr(SyntheticForward, "__call__", interrupting)
    assert fit(inputs, out) == 130
    assert "interrupted" in capsys.readouterr().err
    assert not out.exists()


def test_a_ctrl_c_that_blender_would_swallow_during_the_renders_still_stops_the_fit(inputs, tmp_path, fake_forward,
                                                                                   monkeypatch, capsys):
    """Blender prints and swallows an exception raised in a render callback: a Ctrl-C while the cloth
    response renders must still end the fit with 130 and write nothing."""
    out = tmp_path / "fit"
    build = fake_forward.build_forward_model

    def rendering(measured_views, preset_config, base_dir, *, progress=None, **kwargs):
        try:
            os.kill(os.getpid(), signal.SIGINT)  # during a render …
            time.sleep(0.01)
        except KeyboardInterrupt:
            pass  # … where Blender would print it and render on
        return build(measured_views, preset_config, base_dir, progress=progress, **kwargs)

    monkeypatch.setattr(fake_forward, "build_forward_model", rendering)
    assert fit(inputs, out) == 130
    assert "interrupted" in capsys.readouterr().err
    assert not out.exists()


def test_without_the_forward_model_module_it_is_an_internal_error(inputs, tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "clothlight.fit.forward", None)  # import fails as if the file were absent
    assert fit(inputs, tmp_path / "fit") == 1
    assert not (tmp_path / "fit").exists()


def test_a_sample_weave_the_fit_cannot_render_exits_2_before_any_work_and_a_known_one_reaches_the_preset(
        inputs, tmp_path, fake_forward, plots_as_text, capsys):
    config = tomllib.loads(inputs["config"].read_text())
    inputs["config"].write_text(fit_report.to_toml({**config, "sample": {"weave": "satin"}}))
    assert fit(inputs, tmp_path / "refused") == 2
    error = capsys.readouterr().err
    assert "sample.weave" in error and "satin" in error and "sheeting" in error
    assert not fake_forward.calls and not (tmp_path / "refused").exists()

    inputs["config"].write_text(fit_report.to_toml({**config, "sample": {"weave": "sheeting"}}))
    assert fit(inputs, tmp_path / "fit") == 0
    assert tomllib.loads((tmp_path / "fit" / "preset.toml").read_text())["sample"] == {"weave": "sheeting"}
    assert "sample weave (the cloth the forward model renders, `[sample]`): sheeting, averaged over the warp at " \
           "0°, 90° from the plane of incidence" in (tmp_path / "fit" / "report.md").read_text()

    unsorted = {"weave": "sheeting", "azimuths_deg": [90, 0]}
    inputs["config"].write_text(fit_report.to_toml({**config, "sample": unsorted}))
    calls = len(fake_forward.calls)
    assert fit(inputs, tmp_path / "refused azimuths") == 2
    assert "sample.azimuths_deg" in capsys.readouterr().err and len(fake_forward.calls) == calls
    turned = {"weave": "sheeting", "azimuths_deg": [0.0, 45.0, 90.0, 135.0]}
    inputs["config"].write_text(fit_report.to_toml({**config, "sample": turned}))
    assert fit(inputs, tmp_path / "turned") == 0
    assert tomllib.loads((tmp_path / "turned" / "preset.toml").read_text())["sample"] == turned
    assert "averaged over the warp at 0°, 45°, 90°, 135° from the plane of incidence" in (
        tmp_path / "turned" / "report.md").read_text()
