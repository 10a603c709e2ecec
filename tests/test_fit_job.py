"""The Yarn Medium panel's Fit: the request (clothlight/fit_job.py), its child process
(clothlight/fit/worker.py, the fit of ``python -m clothlight.fit`` with JSON-line progress, cancel and
exit codes), which child runs it (Blender itself inside Blender, ``python -m`` under the bpy module),
and the operator through bpy, in background mode and interactively (Esc).

The real fits are as small as a fit gets: ten views of a synthetic cloth (24 renders of the cloth
response, rendered once for the session into a shared cache), red cotton on 4 × 2 cells and 4 × 4
angular grids, the dye read from one dye series (``--dye-series``) with the sheen's weight profiled,
8 evaluations."""

from __future__ import annotations

import dataclasses
import json
import pathlib
import stat
import sys
import time
from types import SimpleNamespace

import pytest

from clothlight.fit_job import FREE_PARAMETERS, FitFailed, FitJob, FitJobCancelled, FitRequest
from clothlight.jobs import BLENDER_BOOTSTRAP, child_command, is_blender_executable
from clothlight.medium_settings import BakeRequest
from precompute.errors import ParameterError
from precompute.fit.parameters import PARAMETERS
from tests.test_fit_optimise import TRUTH, synthetic_brdf

#: Red cotton on the smallest grids (the transport of a candidate or a dye series in well under a second).
TINY_MEDIUM = BakeRequest(preset="voided_red_cotton", n_around=4, n_along=2, angular_resolution=4)
#: Ten views: θi 0 and 30°, in the plane of incidence on both sides and the normal, one held out (90°).
VIEWS = [(theta_i, 180, theta_o, phi_o) for theta_i in (0, 30)
         for theta_o, phi_o in ((20, 180), (0, 0), (20, 0), (40, 0), (30, 90))]


def write_small_measurement(path: pathlib.Path) -> pathlib.Path:
    rgb = synthetic_brdf(VIEWS, **TRUTH)
    rows = [",".join(f"{v:g}" for v in view) + "," + ",".join(f"{c:.8g}" for c in values)
            for view, values in zip(VIEWS, rgb)]
    path.write_text("theta_i,phi_i,theta_o,phi_o,R,G,B\n" + "\n".join(rows) + "\n")
    return path


@pytest.fixture(scope="module")
def measured(tmp_path_factory) -> pathlib.Path:
    return write_small_measurement(tmp_path_factory.mktemp("measured") / "small.csv")


@pytest.fixture(scope="session")
def response_cache(tmp_path_factory) -> pathlib.Path:
    """One cache for every fit of the session: the cloth response of :data:`VIEWS` is rendered once."""
    return tmp_path_factory.mktemp("fit-cache")


def small_request(measured, out, **changes) -> FitRequest:
    fields = dict(measured=str(measured), out=str(out), free=("dye_weight_percent", "specular_weight"),
                  medium=TINY_MEDIUM, budget=9, dye_series=True)
    return FitRequest(**{**fields, **changes})


def refused(request: FitRequest) -> ParameterError:
    with pytest.raises(ParameterError) as refusal:
        request.check()
    return refusal.value


# -- the request ----------------------------------------------------------------------------------


def test_the_panels_free_parameters_are_the_fits_own():
    assert [(name, unit, low, high) for name, _label, unit, low, high, _what in FREE_PARAMETERS] == \
        [(p.name, p.unit, p.low, p.high) for p in PARAMETERS.values()]


def test_a_fit_request_round_trips_through_json(tmp_path):
    request = FitRequest(measured="/data/red.csv", out=str(tmp_path / "fit"), free=["void_fraction", "specular_slope"],
                         medium=BakeRequest(preset="voided_red_cotton", overrides=(("dye.weight_percent", 0.5),
                                                                            ("fit.specular_weight", 0.02)),
                                            n_around=8, dye_series=(0.1, 3.0)),
                         target_ratios=" B/R=0.08,G/R=0.011 ", max_back_front=0.5, budget=40, budget_seconds=600,
                         seed=7, dye_series=False)
    text = request.to_json()
    again = FitRequest.from_json(text)
    assert again == request and again.to_json() == text
    assert again.free == ("void_fraction", "specular_slope") and again.target_ratios == "B/R=0.08,G/R=0.011"
    assert isinstance(again.medium, BakeRequest) and again.medium.overrides == request.medium.overrides
    assert json.loads(text)["medium"]["preset"] == "voided_red_cotton"
    # what the fit gets: the medium as the bake describes it, its grids as the [transport] table
    arguments = request.fit_arguments()
    assert arguments["preset"] == "voided_red_cotton" and arguments["free"] == "void_fraction,specular_slope"
    assert arguments["overrides"]["dye.weight_percent"] == 0.5 and arguments["overrides"]["transport.n_around"] == 8
    assert arguments["budget_evaluations"] == 40 and arguments["target_ratios"] == "B/R=0.08,G/R=0.011"
    assert FitRequest.from_json(FitRequest().to_json()) == FitRequest()


@pytest.mark.parametrize("changes, words", [
    ({"measured": "{tmp}/missing.csv"}, ["measured", "missing.csv"]),
    ({"free": ("void_fraction", "sheen")}, ["free", "'sheen'", "dye_weight_percent"]),
    ({"free": ()}, ["free", "one or more of"]),
    ({"free": ("void_fraction",), "dye_series": True}, ["dye_series", "dye_weight_percent"]),
    ({"target_ratios": "B/R=-1"}, ["target_ratios", "B/R=-1"]),
    ({"budget": 5}, ["budget", "at least 9"]),
    ({"budget": 2}, ["budget", "≥ 3"]),
    ({"budget_seconds": -1.0}, ["budget_seconds"]),
    ({"seed": -1}, ["seed"]),
    ({"max_back_front": 0.0}, ["max_back_front", "> 0"]),
    ({"out": ""}, ["out"]),
    ({"out": "{tmp}/small.csv"}, ["out", "is a file"]),
])
def test_a_bad_request_is_refused_before_a_child_starts_naming_the_field(tmp_path, changes, words):
    measured = write_small_measurement(tmp_path / "small.csv")
    changes = {key: value.replace("{tmp}", str(tmp_path)) if isinstance(value, str) else value
               for key, value in changes.items()}
    request = small_request(measured, tmp_path / "fit")
    assert request.check() == request
    error = refused(dataclasses.replace(request, **changes))
    assert error.name == words[0]
    for word in words:
        assert word in str(error), (word, str(error))


# -- which child ----------------------------------------------------------------------------------


def _fake_blender(folder: pathlib.Path) -> pathlib.Path:
    """An executable named blender that does what Blender does with ``--background --factory-startup
    --python-expr EXPR -- ARGS``: runs EXPR with ARGS after ``--`` in its own Python, which ignores
    PYTHONPATH and PYTHONPYCACHEPREFIX (``-E``, as Blender without --python-use-system-env)."""
    script = folder / "blender"
    script.write_text(f"""#!/bin/sh
cd /  # nothing of the add-on on the path but what the bootstrap puts there
while [ "$1" != "--python-expr" ]; do
    case "$1" in --background|--factory-startup) shift ;; *) echo "unexpected $1" >&2; exit 9 ;; esac
done
expr="$2"
shift 2
exec {sys.executable} -E -c "$expr" "$@"
""")
    script.chmod(script.stat().st_mode | stat.S_IXUSR)
    return script


def test_the_child_is_blender_in_background_mode_only_when_the_binary_is_blender(tmp_path):
    arguments = ["--request", "{}", "--cache-dir", "c"]
    python = [sys.executable, "-m", "clothlight.fit.worker", *arguments]
    not_executable = tmp_path / "blender.txt"
    not_executable.write_text("")
    # the bpy module reports "" (or a Python); no binary, a missing or non-executable file: this Python
    for binary in ("", None, sys.executable, str(tmp_path / "missing"), str(not_executable)):
        assert child_command("clothlight.fit.worker", arguments, blender=binary) == python, binary
        assert not is_blender_executable(binary, sys.executable)
    blender = str(_fake_blender(tmp_path))
    command = child_command("clothlight.fit.worker", arguments, blender=blender)
    assert command[:5] == [blender, "--background", "--factory-startup", "--python-expr",
                           BLENDER_BOOTSTRAP.format(module="clothlight.fit.worker")]
    assert command[5:] == ["--", *arguments]
    compile(command[4], "<python-expr>", "exec")
    assert "'clothlight.fit.worker'" in command[4]
    # a job that needs no bpy (the bake) runs in this Python whatever Blender is
    assert child_command("clothlight.bake_worker", arguments) == [sys.executable, "-m", "clothlight.bake_worker",
                                                                   *arguments]


@pytest.mark.render
def test_under_the_bpy_module_the_fit_child_is_this_python(bpy, tmp_path):
    assert not is_blender_executable(bpy.app.binary_path, sys.executable), repr(bpy.app.binary_path)
    job = FitJob(FitRequest(), cache_dir=tmp_path, blender=bpy.app.binary_path)
    assert job.command()[:3] == [sys.executable, "-m", "clothlight.fit.worker"]


def test_a_child_started_as_blender_finds_the_add_on_and_exits_2_naming_the_bad_field(measured, tmp_path):
    """The bootstrap Blender runs: the import path and bytecode folder from the environment (Blender
    ignores PYTHONPATH), the worker's exit status through os._exit; the request is refused by the
    child (the check the operator makes first is skipped here)."""
    request = small_request(measured, tmp_path / "fit", free=("void_fraction", "sheen"))
    job = FitJob(request, cache_dir=tmp_path / "cache", blender=str(_fake_blender(tmp_path)),
                 bytecode_cache_dir=tmp_path / "pycache")
    assert job.command()[0].endswith("blender")
    with pytest.raises(FitFailed) as failure:
        job.wait()
    assert job.returncode == 2 and failure.value.bad_input, job.log[-3000:]
    assert "free" in str(failure.value) and "'sheen'" in str(failure.value)
    assert (tmp_path / "pycache").is_dir() and not (tmp_path / "fit").exists()


# -- the child: a real fit ------------------------------------------------------------------------


def run_to_the_end(job: FitJob) -> list[tuple[float, str]]:
    """Start ``job`` and poll it to the end; every (progress, stage) it went through."""
    seen = []
    job.start()
    while not job.poll():
        if not seen or seen[-1] != (job.progress, job.stage):
            seen.append((job.progress, job.stage))
        time.sleep(0.02)
    seen.append((job.progress, job.stage))
    return seen


@pytest.fixture(scope="module")
def fitted(measured, response_cache, tmp_path_factory):
    """A real fit in its child (``python -m clothlight.fit.worker``): the job and the progress it showed."""
    pytest.importorskip("bpy")  # the child renders the cloth response
    request = small_request(measured, tmp_path_factory.mktemp("fitted") / "fit").check()
    job = FitJob(request, cache_dir=response_cache)
    seen = run_to_the_end(job)
    assert job.error is None and job.returncode == 0, job.log[-3000:]
    return job, seen


@pytest.mark.render
@pytest.mark.slow
@pytest.mark.blender
def test_a_fit_in_its_child_shows_progress_and_writes_the_fit_folder(fitted):
    from precompute.fit.report import FIT_FOLDER_FILES
    from precompute.optics.medium import load_preset, load_preset_config

    job, seen = fitted
    fractions = [fraction for fraction, _ in seen]
    assert fractions == sorted(fractions) and fractions[-1] == 1.0 and 0.0 <= fractions[0] < 0.2
    stages = [stage for _, stage in seen]
    assert any(stage.startswith("cloth response: ") for stage in stages)  # the session's first fit renders it
    assert any(stage.startswith("evaluation 7/9") for stage in stages) and "writing the report" in stages
    outcome = job.outcome
    assert sorted(p.name for p in outcome.folder.iterdir()) == sorted(FIT_FOLDER_FILES) and outcome.figures
    assert outcome.preset == outcome.folder / "preset.toml" and outcome.folder == pathlib.Path(job.request.out)
    summary = json.loads((outcome.folder / "fit.json").read_text())
    assert outcome.relative_rms == pytest.approx(summary["metrics"]["model"]["fit_views"]["relative_rms"])
    assert outcome.held_out_rms == pytest.approx(summary["metrics"]["model"]["held_out_views"]["relative_rms"])
    assert set(outcome.parameters) == {"dye_weight_percent", "specular_weight"}
    # the fitted preset: loadable, with the fitted values, which the done event gives as bake overrides
    config, _ = load_preset_config(outcome.preset)
    medium = load_preset(outcome.preset)
    assert medium.dye.weight_percent == pytest.approx(outcome.parameters["dye_weight_percent"])
    assert config["fit"]["specular_weight"] == pytest.approx(outcome.parameters["specular_weight"])
    assert config["transport"]["n_around"] == 4  # the panel's grids, the forward model's transport
    assert dict(outcome.overrides) == pytest.approx({"dye.weight_percent": outcome.parameters["dye_weight_percent"],
                                                     "fit.specular_weight": outcome.parameters["specular_weight"]})


@pytest.mark.render
@pytest.mark.slow
@pytest.mark.blender
def test_the_childs_fit_is_the_command_lines(fitted, measured, response_cache, tmp_path, capsys):
    """``python -m clothlight.fit`` on the same medium (written as a preset TOML), measurement, seed
    and budget writes the same preset."""
    import clothlight.fit.__main__ as fit_cli
    from precompute.bake import apply_overrides
    from precompute.fit.report import to_toml
    from precompute.optics.medium import load_preset_config

    job, _ = fitted
    config, _ = load_preset_config("voided_red_cotton")
    config = apply_overrides(config, job.request.medium.bake_arguments()["overrides"])
    preset = tmp_path / "start.toml"  # its dye spectrum resolves in precompute/data
    preset.write_text(to_toml(config))
    code = fit_cli.main(["--measured", str(measured), "--config", str(preset), "--free",
                         "dye_weight_percent,specular_weight", "--dye-series", "--budget-evaluations", "9",
                         "--seed", "0", "--cache-dir", str(response_cache), "--out", str(tmp_path / "cli"), "--json"])
    assert code == 0, capsys.readouterr().err[-2000:]
    mine, theirs = (json.loads((folder / "fit.json").read_text()) for folder in (job.outcome.folder, tmp_path / "cli"))
    assert mine["parameters"] == theirs["parameters"] and mine["objective"] == theirs["objective"]
    assert [e["objective"] for e in mine["history"]] == [e["objective"] for e in theirs["history"]]


@pytest.mark.render
@pytest.mark.slow
@pytest.mark.blender
def test_cancel_mid_fit_exits_130_and_leaves_no_folder(measured, response_cache, tmp_path):
    pytest.importorskip("bpy")
    out = tmp_path / "fits" / "fit"
    out.parent.mkdir()  # where a staging folder would be left
    job = FitJob(small_request(measured, out, budget=400).check(), cache_dir=response_cache)
    job.start()
    while not job.poll() and not job.stage.startswith("evaluation"):
        time.sleep(0.02)
    assert not job.done, job.log[-3000:]
    job.cancel()
    while not job.poll():
        time.sleep(0.05)
    assert isinstance(job.error, FitJobCancelled) and job.returncode == 130, job.log[-3000:]
    assert "nothing was written" in str(job.error)
    assert not out.exists() and not list(out.parent.iterdir())  # no folder, no staging folder either


@pytest.mark.slow
def test_a_preset_without_the_species_a_parameter_needs_exits_2_from_the_child(measured, tmp_path):
    """What only the child can check (it reads the preset): paper_2008 has no voids species."""
    request = small_request(measured, tmp_path / "fit", free=("void_fraction",), dye_series=False,
                            medium=dataclasses.replace(TINY_MEDIUM, preset="paper_2008")).check()
    job = FitJob(request, cache_dir=tmp_path / "cache")
    with pytest.raises(FitFailed) as failure:
        job.wait()
    assert job.returncode == 2 and failure.value.bad_input
    assert "voids" in str(failure.value) and "[[particles]]" in str(failure.value)
    assert not (tmp_path / "fit").exists() and not (tmp_path / "cache").exists()


# -- the operator ---------------------------------------------------------------------------------


@pytest.fixture
def addon(bpy, response_cache, tmp_path, monkeypatch):
    """The development checkout registered as an add-on, its caches in the session's fit cache."""
    from clothlight.blender import registration
    from clothlight.blender import preferences

    monkeypatch.setattr(preferences, "cache_directory", lambda context=None: str(response_cache))
    monkeypatch.setattr(preferences, "fit_directory", lambda: str(tmp_path / "fits"))
    registration.register()
    try:
        bpy.ops.wm.read_homefile(use_empty=True)
        yield bpy.context.scene
    finally:
        registration.unregister()
        assert not hasattr(bpy.types, "CLOTHLIGHT_OT_fit_medium") and not hasattr(bpy.types, "CLOTHLIGHT_PT_medium_fit")
        bpy.ops.wm.read_homefile(use_empty=True)


def set_up_small_fit(scene, measured) -> None:
    medium, fit = scene.clothlight.medium, scene.clothlight.fit
    medium.base = "voided_red_cotton"  # Congo red in a host: the dye series of one simulation
    medium.n_around, medium.n_along, medium.angular_resolution = 4, 2, 4
    fit.measured_path = str(measured)
    fit.free = {"dye_weight_percent", "specular_weight"}
    fit.dye_series = True
    fit.budget = 9


@pytest.mark.render
@pytest.mark.slow
@pytest.mark.blender
def test_the_fit_operator_fits_in_background_mode_and_loads_the_fitted_values(addon, bpy, measured, tmp_path):
    from clothlight.blender import running_jobs
    from tests.test_addon_operators import _Layout

    scene = addon
    medium, fit = scene.clothlight.medium, scene.clothlight.fit
    set_up_small_fit(scene, measured)
    assert fit.request(medium, tmp_path / "fits").out == str(tmp_path / "fits" / "small")
    fit.free = set()
    with pytest.raises(RuntimeError, match="free"):  # refused before a child starts
        bpy.ops.clothlight.fit_medium("INVOKE_DEFAULT")
    fit.free = {"void_fraction", "dye_weight_percent"}  # Dye Series, not offered for this fit, asks for nothing
    assert fit.dye_series and not fit.request(medium, tmp_path).dye_series
    fit.free = {"dye_weight_percent", "specular_weight"}
    start = medium.request()
    assert not bpy.ops.clothlight.load_fit.poll()
    # In background mode INVOKE_DEFAULT runs execute(): the fit in its child, to the end.
    assert bpy.ops.clothlight.fit_medium("INVOKE_DEFAULT") == {"FINISHED"}
    last = fit.last()
    folder = pathlib.Path(last["folder"])
    assert folder == tmp_path / "fits" / "small" and (folder / "preset.toml").is_file()
    fitted = json.loads((folder / "fit.json").read_text())["parameters"]
    dye, sheen = fitted["dye_weight_percent"]["value"], fitted["specular_weight"]["value"]
    # Load Result: the dye in its field, the sheen (not in the panel) among the fitted values, all baked
    assert medium.dye_weight_percent == pytest.approx(dye, rel=1e-5)
    assert "fit.specular_weight" in medium.extra_overrides_text()
    overrides = dict(medium.request().overrides)
    assert overrides["dye.weight_percent"] == pytest.approx(dye, rel=1e-5)
    assert overrides["fit.specular_weight"] == pytest.approx(sheen, rel=1e-5)
    assert medium.request().n_around == 4  # the bake settings stay
    # another base medium forgets them; Load Fitted Values brings the fit back
    medium.base = "paper_2008"
    assert medium.fitted_overrides == "" and medium.request() != start
    assert bpy.ops.clothlight.load_fit() == {"FINISHED"}
    assert medium.base == "voided_red_cotton" and dict(medium.request().overrides) == overrides
    assert bpy.ops.clothlight.clear_fitted_values() == {"FINISHED"}
    assert "fit.specular_weight" not in dict(medium.request().overrides)
    # the panel draws existing properties and operators, and the last fit
    labels = []
    context = SimpleNamespace(scene=scene)
    for name in ("CLOTHLIGHT_PT_medium", "CLOTHLIGHT_PT_medium_fit"):
        getattr(bpy.types, name).draw(SimpleNamespace(layout=_Layout(labels)), context)
    assert any(label.startswith("Last fit: relative RMS") for label in labels)
    assert running_jobs.running_fit() is None


@pytest.mark.render
@pytest.mark.slow
@pytest.mark.blender
def test_esc_cancels_an_interactive_fit_and_nothing_is_written(addon, bpy, measured, tmp_path):
    from clothlight.blender import operators, running_jobs
    from tests.test_addon_operators import _tick, interactive_operator

    scene = addon
    set_up_small_fit(scene, measured)
    scene.clothlight.fit.budget = 400
    scene.clothlight.fit.out_dir = str(tmp_path / "interactive")
    operator, context = interactive_operator(operators.CLOTHLIGHT_OT_fit_medium, scene)
    assert operator._start_modal(context) == {"RUNNING_MODAL"}
    job = running_jobs.running_fit()
    assert job is not None and not bpy.ops.clothlight.fit_medium.poll()
    assert operator.modal(context, SimpleNamespace(type="MOUSEMOVE", value="NOTHING")) == {"PASS_THROUGH"}
    _tick(operator, context, lambda result: job.stage.startswith("evaluation") or result != {"PASS_THROUGH"})
    assert not job.done, job.log[-3000:]
    assert operator.modal(context, SimpleNamespace(type="ESC", value="PRESS")) == {"RUNNING_MODAL"}
    assert _tick(operator, context, lambda result: result != {"PASS_THROUGH"}) == {"CANCELLED"}
    assert isinstance(job.error, FitJobCancelled) and job.returncode == 130
    assert operator.reports[-1][0] == "WARNING" and "nothing was written" in operator.reports[-1][1]
    assert callable(context.workspace.status[0]) and context.workspace.status[-1] is None
    assert running_jobs.running_fit() is None and scene.clothlight.fit.last() is None
    assert not (tmp_path / "interactive").exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".interactive")]


def test_the_response_renders_with_the_example_tables_or_in_the_extension_a_prebaked_presets(tmp_path):
    from clothlight.fit.forward import PROJECT_ROOT, lookup_tables_folder

    assert lookup_tables_folder() == PROJECT_ROOT / "example_blends" / "tables" / "paper_2008"
    with pytest.raises(FileNotFoundError, match="no yarn tables"):
        lookup_tables_folder(tmp_path)
    for name in ("voided_red_cotton", "paper_2008"):
        (tmp_path / "prebaked" / name).mkdir(parents=True)
        (tmp_path / "prebaked" / name / "summary.json").write_text("{}")
    assert lookup_tables_folder(tmp_path) == tmp_path / "prebaked" / "paper_2008"


def test_the_fit_needs_cma_and_says_so(monkeypatch):
    from clothlight import fit_job, jobs

    assert "cma" in jobs.FIT_DEPENDENCIES and "cma" in jobs.BUNDLED_DEPENDENCIES.values()
    assert fit_job.fit_unavailable_reason() is None  # this environment has all
    monkeypatch.setattr(fit_job, "missing_fit_dependencies", lambda: ["cma"])
    assert fit_job.fit_unavailable_reason().startswith("Fit unavailable: cma not installed")
