"""Every command line maps its endings to the same exit codes (precompute/exit_codes.py): 0 done, 2 bad
input naming the parameter or file and what is allowed, 130 interrupted (Ctrl-C at any moment, the
start-up imports included), 1 an internal error in one line.  Numeric inputs are bounded by one
definition per parameter (precompute/bounds.py, clothlight/render_bounds.py), read alike by the
API, the command lines and the panel.

Bad inputs run the commands in-process (``main(argv)``) with the step that would start work
replaced by a sentinel, so a refusal is proven to come before any work; Ctrl-C runs them as child
processes.  Nothing here bakes or renders, but the one Ctrl-C-during-a-sweep test (blender, render).
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import pathlib
import signal
import subprocess
import sys
import textwrap

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

import clothlight.fit.__main__ as fit_cli
import clothlight.fit.match_colour as match_colour_cli
import clothlight.garment.__main__ as garment_cli
import clothlight.validate as validate_cli
import clothlight.validation.report as report_cli
import precompute.__main__ as precompute_cli
from clothlight import jobs, medium_settings, render_bounds
from clothlight.blender.garment.density import THREADS_PER_CM
from precompute.fit.measured_data import MeasurementFormatError
from clothlight.weave import WeaveParameterError
from precompute import bounds, exit_codes
from precompute.errors import InputError, ParameterError
from precompute.tables.exr import TableError
from tests.helpers import REPO

YARN_BAKE = REPO / "example_blends" / "tables" / "paper_2008"
CLIS = {"precompute": precompute_cli.main, "validate": validate_cli.main, "garment": garment_cli.main,
        "report": report_cli.main, "fit": fit_cli.main, "colour": match_colour_cli.main}
#: A place no process can write into, root included: the permission bits of /sys say yes to root,
#: the file system says no.
UNWRITABLE = "/sys/clothlight-output"
MEASURED = REPO / "clothlight" / "validation" / "data" / "synthetic_red_cotton.csv"


class WorkStarted(BaseException):
    """Raised where a command would start its work (a bake, a render, a simulation): the arguments got
    through every check.  A BaseException, so that no command's handler turns it into an exit code."""

    def __init__(self, **arguments):
        super().__init__(arguments)
        self.arguments = arguments


def _started(**named):
    def start(*args, **kwargs):
        raise WorkStarted(args=args, **named, **kwargs)

    return start


@pytest.fixture
def no_work(monkeypatch):
    """Every command's first step of work replaced by :class:`WorkStarted`: the yarn bake's simulation
    (after its configuration is checked; never a cache hit), the slab's, the validation sweep and the
    cloth measurement (both before Blender is imported)."""
    import precompute.bake
    import precompute.cli.slab

    monkeypatch.setattr(precompute.bake, "lookup", lambda *args, **kwargs: None)
    # no cluster either: the command line's default scheduler would start one before the simulation
    monkeypatch.setattr(precompute.bake, "_transport_executor", lambda *args: contextlib.nullcontext())
    monkeypatch.setattr(precompute.bake, "_simulate", lambda configuration, *args: _started(
        configuration=configuration)())
    monkeypatch.setattr(precompute.cli.slab, "slab_summary", _started(command="slab"))
    monkeypatch.setattr(validate_cli, "_sweep", lambda args, interrupt: _started(**vars(args))())
    monkeypatch.setattr(garment_cli, "_measure", lambda args, interrupt: _started(**vars(args))())
    import clothlight.fit.run

    monkeypatch.setattr(clothlight.fit.run, "run_fit", _started(command="fit"))
    import clothlight.fit.colour_match

    monkeypatch.setattr(clothlight.fit.colour_match, "ShadeModel", _started(command="match_colour"))


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    root = tmp_path_factory.mktemp("inputs")
    made = {"root": root, "a_file": root / "a-file", "binary": root / "binary.toml", "junk_blend": root / "junk.blend",
            "bad_csv": root / "measured.csv", "empty_json": root / "results.json", "folder": root / "folder"}
    made["a_file"].write_text("")
    made["binary"].write_bytes(bytes(range(256)) * 4)
    made["junk_blend"].write_bytes(b"not a blend file at all")
    made["bad_csv"].write_text("theta_i,phi_i,theta_o,phi_o,R,G,B\n0,0,0,0,1,1,1\n0,x,0,0,1,1,1\n")
    made["empty_json"].write_text("{}")
    made["folder"].mkdir()
    made["low_index"] = root / "low_index.toml"
    preset = (REPO / "precompute" / "presets" / "voided_red_cotton.toml").read_text()
    made["low_index"].write_text(preset.replace("refractive_index = 1.557", "refractive_index = 0.5", 1))
    return made


def run(cli: str, argv: list[str], capsys) -> tuple[int, str]:
    code = CLIS[cli](argv)
    return code, capsys.readouterr().err


# ---- the mapping -------------------------------------------------------------------------------


def test_one_hierarchy_of_input_errors():
    assert issubclass(WeaveParameterError, ParameterError) and issubclass(ParameterError, InputError)
    assert issubclass(TableError, InputError) and issubclass(MeasurementFormatError, InputError)
    assert str(WeaveParameterError("warp_count", 0, "≥ 1")) == "warp_count = 0 is invalid: allowed ≥ 1"
    for error, code in ((WeaveParameterError("a", 1, "b"), 2), (TableError("x.exr: truncated"), 2),
                        (MeasurementFormatError(3, "bad", "m.csv"), 2), (KeyboardInterrupt(), 130),
                        (RuntimeError("boom"), 1), (MemoryError(), 1)):
        assert exit_codes.exit_code(error) == code
    # The add-on's bake worker reports its ending in the same codes.
    assert (jobs.PARAMETER_EXIT, jobs.CANCELLED_EXIT) == (exit_codes.BAD_INPUT, exit_codes.INTERRUPTED)


@pytest.mark.parametrize("raised, code, stderr", [
    (None, 0, ""),
    (SystemExit(2), 2, ""),
    (SystemExit(0), 0, ""),
    (ParameterError("--paths", 0, "an integer in [2, 9]"), 2,
     "error: --paths = 0 is invalid: allowed an integer in [2, 9]\n"),
    (KeyboardInterrupt(), 130, "interrupted\n"),
    (RuntimeError("boom"), 1, "error: RuntimeError: boom (an internal error; CLOTHLIGHT_TRACEBACK=1 shows the "
                              "traceback)\n"),
])
def test_run_cli_maps_every_ending(raised, code, stderr, capsys, monkeypatch):
    monkeypatch.delenv(exit_codes.TRACEBACK_ENV, raising=False)

    def main():
        if raised is not None:
            raise raised
        return 0

    assert exit_codes.run_cli(main) == code
    assert capsys.readouterr().err == stderr


def test_an_internal_error_is_one_line_and_its_traceback_is_there_when_asked(monkeypatch, capsys):
    import precompute.cli.slab

    def broken(*args, **kwargs):
        raise RuntimeError("the transport broke")

    monkeypatch.setattr(precompute.cli.slab, "slab_summary", broken)
    argv = ["slab", "--albedo", "0.5", "--g", "0", "--tau", "1", "--paths", "100"]
    monkeypatch.delenv(exit_codes.TRACEBACK_ENV, raising=False)
    code, err = run("precompute", argv, capsys)
    assert code == 1 and err.count("\n") == 1 and "RuntimeError: the transport broke" in err
    assert "Traceback" not in err
    monkeypatch.setenv(exit_codes.TRACEBACK_ENV, "1")
    code, err = run("precompute", argv, capsys)
    assert code == 1 and "Traceback" in err and err.rstrip().endswith("(an internal error)")
    monkeypatch.setattr(validate_cli, "_sweep", broken)
    code, err = run("validate", ["--out", str(REPO / "nonexistent-out")], capsys)
    assert code == 1 and "RuntimeError: the transport broke" in err


# ---- bad input: code 2, the parameter or file named with what is allowed, before any work ----------

BAD_INPUTS = [
    # (command, argv, words the message holds); {name} is a file from the ``files`` fixture
    ("precompute", ["slab", "--albedo", "0.5", "--g", "0", "--tau", "1", "--paths", "1e15"],
     ["--paths", "[2, 1000000000]"]),
    ("precompute", ["slab", "--albedo", "0.5", "--g", "1", "--tau", "1"], ["--g", "(-1, 1)"]),
    ("precompute", ["slab", "--albedo", "0.5", "--g", "0", "--tau", "1e9"], ["--tau", "(0, 10000]"]),
    ("precompute", ["bake", "--paths", "1e15"], ["--paths", "transport.paths_per_cell", "[2, 100000000]"]),
    ("precompute", ["bake", "--paths", "2.5"], ["--paths", "transport.paths_per_cell"]),
    ("precompute", ["bake", "--target-error", "1e-9"], ["transport.target_rel_stderr", "[0.0001, 0.5]"]),
    ("precompute", ["bake", "--target-error", "nan"], ["transport.target_rel_stderr", "[0.0001, 0.5]"]),
    ("precompute", ["bake", "--seed", "1e30"], ["transport.seed"]),
    ("precompute", ["bake", "--set", "transport.angular_resolution=100000"],
     ["transport.angular_resolution", "[2, 64]"]),
    ("precompute", ["bake", "--set", "transport.n_around=100000"], ["transport.n_around", "[3, 256]"]),
    ("precompute", ["bake", "--set", "transport.n_along=0"], ["transport.n_along", "[1, 256]"]),
    ("precompute", ["bake", "--set", "transport.incidence_resolution=1001"], ["transport.incidence_resolution", "63"]),
    ("precompute", ["bake", "--set", "transport.paths_per_cell=1000000000000000"], ["transport.paths_per_cell"]),
    ("precompute", ["bake", "--set", "transport.angular_resolution=64", "--set", "transport.n_around=256"],
     ["transport.angular_resolution", "transport.n_around", "GiB", "half this machine's memory"]),
    ("precompute", ["bake", "--preset", "voided_red_cotton", "--set", "particles.0.diameter_nm=1e9"],
     ["diameter_nm", "[1, 100000] nm"]),
    ("precompute", ["bake", "--set", "yarn.radius_mm=1e6"], ["yarn.radius_mm", "[0.001, 10] mm"]),
    ("precompute", ["bake", "--set", "wavelengths.step_nm=1e-9"], ["wavelengths.step_nm", "1001"]),
    ("precompute", ["bake", "--preset", ""], ["--preset = ''", "voided_red_cotton"]),
    ("precompute", ["optics", "--preset", ""], ["--preset = ''", "voided_red_cotton"]),
    ("precompute", ["bake", "--preset", "no_such_yarn"], ["--preset = 'no_such_yarn'", "voided_red_cotton"]),
    ("precompute", ["bake", "--config", "{binary}"], ["--config", "binary.toml", "UTF-8"]),
    ("precompute", ["optics", "--config", "{folder}"], ["--config", "folder"]),
    ("precompute", ["optics", "--config", "{low_index}"], ["host.refractive_index.n = 0.5", "[1, 10]"]),
    ("precompute", ["bake", "--config", "{low_index}"], ["host.refractive_index.n = 0.5", "[1, 10]"]),
    ("precompute", ["bake", "--cache-dir", "{a_file}"], ["--cache-dir", "a-file"]),
    ("precompute", ["bake", "--cache-dir", "{a_file}/cache"], ["--cache-dir", "is a file"]),
    ("precompute", ["bake", "--out", "{a_file}"], ["--out", "a-file"]),
    ("precompute", ["plot", str(YARN_BAKE), "--out", "{a_file}"], ["--out", "a-file"]),
    ("precompute", ["plot", str(YARN_BAKE), "--out", "{a_file}/plots"], ["--out", "is a file"]),
    ("precompute", ["optics", "--plot", "{folder}"], ["--plot", "folder"]),
    ("validate", ["--out", "{a_file}"], ["--out", "a-file", "is a file"]),
    ("validate", ["--out", "{a_file}/validation"], ["--out", "is a file"]),
    ("validate", ["--out", "{root}/v", "--blend", "{root}/missing.blend"], ["--blend", "missing.blend"]),
    ("validate", ["--out", "{root}/v", "--blend", "{junk_blend}"], ["--blend", "junk.blend"]),
    ("validate", ["--out", "{root}/v", "--blend", "{folder}"], ["--blend", "folder"]),
    ("validate", ["--out", "{root}/v", "--resolution", "100000"], ["--resolution", "[4, 4096]"]),
    ("validate", ["--out", "{root}/v", "--samples", "0"], ["--samples", "[1, 4096]"]),
    ("validate", ["--out", "{root}/v", "--seed", "1e10"], ["--seed", "2147483647"]),
    ("validate", ["--out", "{root}/v", "--patch-mm", "0"], ["--patch-mm", "(0, 1000] mm"]),
    ("validate", ["--out", "{root}/v", "--views", "95"], ["views_deg", "85"]),
    ("validate", ["--out", "{root}/v", "--measured", "{bad_csv}"], ["measured.csv", "row 3", "phi_i"]),
    ("validate", ["--out", "{root}/v", "--measured", "{root}/missing.csv"], ["--measured", "missing.csv"]),
    ("validate", ["--out", "{root}/v", "--tables", "{root}/missing"], ["--tables", "missing"]),
    ("garment", ["bake", "--tables", str(YARN_BAKE), "--out", "{a_file}"], ["--out", "a-file"]),
    ("garment", ["bake", "--tables", "{root}/missing", "--out", "{root}/c"], ["--tables", "missing"]),
    ("garment", ["bake", "--tables", str(YARN_BAKE), "--out", "{root}/c", "--cache-dir", "{a_file}"],
     ["--cache-dir", "a-file"]),
    ("garment", ["bake", "--tables", str(YARN_BAKE), "--out", "{root}/c", "--exit-resolution", "1e3"],
     ["--exit-resolution", "[2, 24]"]),
    ("garment", ["bake", "--tables", str(YARN_BAKE), "--out", "{root}/c", "--incidence-resolution", "8"],
     ["--incidence-resolution", "odd"]),
    ("garment", ["bake", "--tables", str(YARN_BAKE), "--out", "{root}/c", "--pixels-per-patch", "1000"],
     ["--pixels-per-patch", "[4, 64]"]),
    *(("garment", ["bake", "--tables", str(YARN_BAKE), "--out", "{root}/c", f"--threads-per-cm={value}"],
       ["--threads-per-cm", "[10, 24] threads/cm"]) for value in ("0", "-3", "25", "nan", "ten", "12.5")),
    ("report", ["{root}/missing.json"], ["RESULTS_JSON", "missing.json"]),
    ("report", ["{binary}"], ["RESULTS_JSON", "binary.toml"]),
    ("report", ["{empty_json}"], ["RESULTS_JSON", "materials"]),
    ("report", [], ["usage"]),
    # output folders and files in a place that refuses to be written, whatever the permission bits say
    ("precompute", ["bake", "--out", f"{UNWRITABLE}/bake"], ["--out", "not writable"]),
    ("precompute", ["bake", "--cache-dir", f"{UNWRITABLE}/cache"], ["--cache-dir", "not writable"]),
    ("precompute", ["plot", str(YARN_BAKE), "--out", f"{UNWRITABLE}/plots"], ["--out", "not writable"]),
    ("precompute", ["optics", "--plot", f"{UNWRITABLE}/optics.png"], ["--plot", "not writable"]),
    ("validate", ["--out", f"{UNWRITABLE}/validation"], ["--out", "not writable"]),
    ("garment", ["bake", "--tables", str(YARN_BAKE), "--out", f"{UNWRITABLE}/cloth"], ["--out", "not writable"]),
    ("garment", ["bake", "--tables", str(YARN_BAKE), "--out", "{root}/c", "--cache-dir", f"{UNWRITABLE}/cache"],
     ["--cache-dir", "not writable"]),
    ("fit", ["--measured", str(MEASURED), "--free", "dye_weight_percent", "--out", f"{UNWRITABLE}/fit"],
     ["--out", "not writable"]),
    ("fit", ["--measured", str(MEASURED), "--free", "dye_weight_percent", "--out", "{root}/fit", "--cache-dir",
             f"{UNWRITABLE}/cache"], ["--cache-dir", "not writable"]),
    ("fit", ["--measured", "{bad_csv}", "--free", "dye_weight_percent", "--out", "{root}/fit"],
     ["measured.csv", "row 3"]),
    ("fit", ["--measured", str(MEASURED), "--free", "sheen", "--out", "{root}/fit"], ["--free", "sheen"]),
    ("fit", ["--measured", str(MEASURED), "--free", "dye_weight_percent", "--out", "{root}/fit", "--config",
             "{root}/missing.toml"], ["--config", "missing.toml"]),
    ("colour", ["--target", "#8c1c2", "--out", "{root}/red.toml"], ["--target", "#rrggbb"]),
    ("colour", ["--target", "1.2,0,0", "--out", "{root}/red.toml"], ["--target", "[0, 1]"]),
    ("colour", ["--target", "#8c1c24", "--out", "{folder}"], ["--out", "is a folder"]),
    ("colour", ["--target", "#8c1c24", "--out", f"{UNWRITABLE}/red.toml"], ["--out", "not writable"]),
    ("colour", ["--target", "#8c1c24", "--out", "{root}/red.toml", "--cache-dir", f"{UNWRITABLE}/cache"],
     ["--cache-dir", "not writable"]),
    ("colour", ["--target", "#8c1c24", "--out", "{root}/red.toml", "--preset", "nope"], ["--preset = 'nope'"]),
    # values that begin with "-": refused by their option's own check, not taken for options
    ("precompute", ["bake", "--dye-series", "-1,5"], ["--dye-series", "'-1,5'", "0 ≤ LOW < HIGH < 100"]),
    ("precompute", ["bake", "--dye-series", "5"], ["--dye-series", "LOW,HIGH"]),
    ("precompute", ["bake", "--seed", "-3"], ["--seed", "-3", "[0, "]),
    ("precompute", ["slab", "--albedo", "-0.5", "--g", "0", "--tau", "1"], ["--albedo", "[0, 1]"]),
    ("validate", ["--out", "{root}/v", "--seed", "-1"], ["--seed", "2147483647"]),
    ("fit", ["--measured", str(MEASURED), "--free", "dye_weight_percent", "--out", "{root}/fit",
             "--budget-evaluations", "1e15"], ["--budget-evaluations", "[2, 100000]"]),
    ("fit", ["--measured", str(MEASURED), "--free", "dye_weight_percent", "--out", "{root}/fit",
             "--budget-evaluations", "-5"], ["--budget-evaluations", "[2, 100000]"]),
]


@pytest.mark.parametrize("cli, argv, words", BAD_INPUTS, ids=[f"{c}:{' '.join(a)[:60]}" for c, a, _ in BAD_INPUTS])
def test_bad_input_exits_2_naming_it_before_any_work(cli, argv, words, files, no_work, capsys):
    if any(UNWRITABLE in arg for arg in argv) and not pathlib.Path(UNWRITABLE).parent.is_dir():
        pytest.skip("no /sys on this system")
    names = {key: str(value) for key, value in files.items()}
    code, err = run(cli, [arg.format(**names) for arg in argv], capsys)
    assert code == 2, err
    assert "Traceback" not in err
    for word in words:
        assert word in err, (word, err)


def test_a_dash_led_value_goes_to_its_option_and_an_option_stays_an_option():
    import argparse

    from precompute.cli.arguments import values_attached

    parser = argparse.ArgumentParser()
    parser.add_argument("--seed")
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--set", action="append")
    assert values_attached(parser, ["--seed", "-3", "--json"]) == ["--seed=-3", "--json"]
    assert values_attached(parser, ["--seed", "--json"]) == ["--seed", "--json"]  # a missing value stays missing
    assert values_attached(parser, ["--set", "-a=1", "--seed", "4"]) == ["--set=-a=1", "--seed", "4"]
    assert values_attached(parser, ["--json", "-3"]) == ["--json", "-3"]  # a flag takes no value
    assert values_attached(parser, ["--seed", "--"]) == ["--seed", "--"]
    commands = parser.add_subparsers()
    bake = commands.add_parser("bake")
    bake.add_argument("--cache-dir")
    bake.add_argument("--dry", action="store_true")
    assert values_attached(parser, ["bake", "--cache-dir", "-x"]) == ["bake", "--cache-dir=-x"]
    assert values_attached(parser, ["bake", "--cache-dir", "--dry"]) == ["bake", "--cache-dir", "--dry"]


@pytest.mark.slow
def test_the_bake_worker_reports_bad_input_and_internal_errors_in_its_events(files):
    """The add-on's bake child: exit 2 with a ``bad_input`` event naming the parameter, 1 with a
    one-line event for anything else (its traceback goes to the log the add-on keeps)."""
    def worker(request: str) -> subprocess.CompletedProcess:
        # stdin stays open while it runs: the worker takes its closing for a cancel
        child = subprocess.Popen([sys.executable, "-m", "clothlight.bake_worker", "--request", request, "--cache-dir",
                                  str(files["root"] / "cache")], cwd=REPO, stdin=subprocess.PIPE,
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        stdout, stderr = child.stdout.read(), child.stderr.read()
        child.stdin.close()
        return subprocess.CompletedProcess(child.args, child.wait(timeout=600), stdout, stderr)

    request = medium_settings.BakeRequest(preset="paper_2008", paths_per_cell=10**12, target_rel_stderr=None)
    refused = worker(request.to_json())
    events = [json.loads(line) for line in refused.stdout.splitlines()]
    assert refused.returncode == 2 and events[-1]["event"] == "error" and events[-1]["bad_input"]
    assert "transport.paths_per_cell" in events[-1]["message"] and "100000000" in events[-1]["message"]
    broken = worker("{not json")
    events = [json.loads(line) for line in broken.stdout.splitlines()]
    assert broken.returncode == 1 and events[-1]["event"] == "error" and not events[-1].get("bad_input")
    assert "\n" not in events[-1]["message"] and "JSONDecodeError" in events[-1]["message"]


# ---- Ctrl-C --------------------------------------------------------------------------------------

#: Put on the child's path as sitecustomize: a Ctrl-C exactly while the named module is imported
#: (the KeyboardInterrupt raised where Python raises it for a SIGINT: inside the import statement).
INTERRUPTING_IMPORT = textwrap.dedent("""
    import os, sys
    class _InterruptImport:
        def __init__(self, name):
            self.name = name
        def find_spec(self, name, path=None, target=None):
            if name == self.name:
                sys.meta_path.remove(self)
                raise KeyboardInterrupt
            return None
    sys.meta_path.insert(0, _InterruptImport(os.environ["CLOTHLIGHT_TEST_INTERRUPT_IMPORT"]))
""")


@pytest.mark.parametrize("module, argv, interrupted_import", [
    ("precompute", ["bake", "--paths", "100"], "numba"),
    ("precompute", ["slab", "--albedo", "0.5", "--g", "0", "--tau", "1"], "precompute.slab.native"),
    ("precompute", ["optics"], "precompute.exit_codes"),
    ("clothlight.validate", ["--out", "{tmp}/v"], "numpy"),
    ("clothlight.validate", ["--out", "{tmp}/v", "--resolution", "8", "--samples", "1"], "bpy"),
    ("clothlight.garment", ["bake", "--tables", str(YARN_BAKE), "--out", "{tmp}/c"], "bpy"),
    ("clothlight.validation.report", ["{tmp}/results.json"], "numpy"),
    ("clothlight.fit", ["--measured", "{tmp}/m.csv", "--free", "dye_weight_percent", "--out", "{tmp}/f"], "numpy"),
    ("clothlight.bake_worker", ["--request", "{{}}", "--cache-dir", "{tmp}/cache"], "precompute.bake"),
])
def test_ctrl_c_during_the_start_up_imports_exits_130_without_a_traceback(tmp_path, module, argv, interrupted_import):
    hook = tmp_path / "hook"
    hook.mkdir()
    (hook / "sitecustomize.py").write_text(INTERRUPTING_IMPORT)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(hook), os.environ.get("PYTHONPATH", "")]),
           "CLOTHLIGHT_TEST_INTERRUPT_IMPORT": interrupted_import}
    child = subprocess.run([sys.executable, "-m", module, *[arg.format(tmp=tmp_path) for arg in argv]], cwd=REPO,
                           env=env, capture_output=True, text=True, input="", timeout=600)
    assert child.returncode == 130, child.stderr[-2000:]
    assert "Traceback" not in child.stderr and "KeyboardInterrupt" not in child.stderr


def _interrupt_when(command: list[str], marker: str, *, delay: float = 0.0) -> tuple[int, str]:
    """Run ``command``, send it SIGINT once the regular expression ``marker`` matches its stderr; its
    exit code and stderr.  The child starts with SIGINT's default disposition, as from a terminal: a
    test run started in the background of a shell (``make test &``) inherits SIGINT ignored, and
    Python then keeps ignoring it."""
    import re
    import time

    child = subprocess.Popen(command, cwd=REPO, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL,
                             stderr=subprocess.PIPE, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    seen = b""
    while not re.search(marker.encode(), seen):
        chunk = child.stderr.read1(4096)
        if not chunk:
            break
        seen += chunk
    time.sleep(delay)
    child.send_signal(signal.SIGINT)
    rest = child.stderr.read()
    child.wait(timeout=600)
    return child.returncode, (seen + rest).decode(errors="replace")


def test_a_real_ctrl_c_among_the_start_up_imports_exits_130(tmp_path):
    """SIGINT itself, sent as soon as numba's import ends (-X importtime reports each import on
    stderr) while the bake command's other modules are still being imported.  The bake is the
    default one into an empty cache (minutes of transport), so that on a loaded machine, where the
    signal may land later, it still lands before the command ends: interrupted either way."""
    code, err = _interrupt_when([sys.executable, "-X", "importtime", "-m", "precompute", "bake",
                                 "--cache-dir", str(tmp_path / "cache")], r"\|\s+numba\n")
    assert code == 130, err[-2000:]
    lines = [line for line in err.splitlines() if not line.startswith("import time:")]
    assert lines[-1] == "interrupted" and "Traceback" not in err


def test_a_deferred_interrupt_at_once_raises_where_it_lands_and_remembers_a_dropped_one():
    # the handler it restores is the one it found (SIG_IGN where the process was started in the background)
    before = signal.getsignal(signal.SIGINT)
    with pytest.raises(KeyboardInterrupt):
        with exit_codes.DeferredInterrupt(note="", at_once=True) as interrupt:
            with pytest.raises(KeyboardInterrupt):
                os.kill(os.getpid(), signal.SIGINT)
                sum(range(1000))  # the handler runs between bytecodes
            assert interrupt.received  # dropped here, as a library might: leaving the block raises it again
    assert signal.getsignal(signal.SIGINT) is before


def test_a_ctrl_c_a_library_drops_during_the_bake_still_exits_130_and_writes_nothing(tmp_path, monkeypatch, capsys):
    """A KeyboardInterrupt caught and dropped inside the bake (numba compiles and runs its kernels
    there) used to let the command run on to exit 0 and write --out."""
    from precompute.bake import BakeResult
    import precompute.cli.bake as bake_cli

    tables = REPO / "example_blends" / "tables" / "paper_2008"

    def bake_that_drops_a_ctrl_c(*args, progress=None, **kwargs):
        try:
            os.kill(os.getpid(), signal.SIGINT)
            sum(range(1000))
        except KeyboardInterrupt:
            pass
        return BakeResult(tables, True, False, json.loads((tables / "summary.json").read_text()))

    monkeypatch.setattr(bake_cli, "bake", bake_that_drops_a_ctrl_c)
    out = tmp_path / "out"
    assert precompute_cli.main(["bake", "--preset", "paper_2008", "--scheduler", "none", "--out", str(out)]) == 130
    assert capsys.readouterr().err.rstrip().endswith("interrupted")
    assert list(tmp_path.iterdir()) == []  # no --out, no staging folder


@pytest.mark.blender
@pytest.mark.render
@pytest.mark.parametrize("scheduler", ["none", "local"])
def test_ctrl_c_during_a_validation_sweep_stops_it_with_130(tmp_path, scheduler):
    """Blender prints and swallows a KeyboardInterrupt raised inside Cycles' render engine: the sweep
    holds the Ctrl-C and stops after the render under way, removing its rig; on a local cluster,
    after the task under way, its other tasks cancelled."""
    pytest.importorskip("bpy")
    if scheduler == "local":
        pytest.importorskip("distributed")
    code, err = _interrupt_when([sys.executable, "-m", "clothlight.validate", "--out", str(tmp_path / "v"),
                                 "--material", "baseline", "--resolution", "16", "--samples", "4",
                                 "--scheduler", scheduler], r"\[\d+/", delay=0.2)
    assert code == 130, err[-2000:]
    assert err.rstrip().endswith("interrupted") and "Traceback" not in err and "KeyboardInterrupt" not in err
    assert list(tmp_path.iterdir()) == []  # nothing written: no renders, no staging folder



@pytest.mark.blender
@pytest.mark.render
@pytest.mark.parametrize("delay", [0.5, 6.0])
def test_ctrl_c_while_the_colour_match_renders_its_response_exits_130(tmp_path, delay):
    """The colour match renders its swatch response with Blender the first time (bpy imported, then
    renders): a Ctrl-C there used to crash the process (import) or be dropped (render)."""
    pytest.importorskip("bpy")
    code, err = _interrupt_when([sys.executable, "-m", "clothlight.fit.match_colour", "--target", "#8c1c24",
                                 "--cache-dir", str(tmp_path / "cache"), "--out", str(tmp_path / "red.toml")],
                                r"cloth response of the swatches", delay=delay)
    assert code == 130, err[-2000:]
    assert err.rstrip().endswith("interrupted") and "Traceback" not in err and "KeyboardInterrupt" not in err
    assert [p.name for p in tmp_path.iterdir()] in ([], ["cache"])  # no recipe, no staging file

# ---- bounds: one definition, read by the API, every command line and the panel ------------------

PRECOMPUTE_BOUNDS = [value for value in vars(bounds).values() if isinstance(value, bounds.Bound)]
ADDON_BOUNDS = [value for value in vars(render_bounds).values() if isinstance(value, bounds.Bound)] + [THREADS_PER_CM]


def _integers_in(bound):
    return st.integers(int(bound.low), int(bound.high)).filter(lambda v: not bound.odd or v % 2)


def _outside(bound):
    """Numbers ``bound`` refuses: beyond either end (far beyond, too), the open ends, non-finite,
    fractions where integers are asked, even numbers where odd ones are."""
    low, high = bound.low, bound.high
    choices = [st.floats(allow_nan=True, allow_infinity=True).filter(lambda v: not math.isfinite(v))]
    if bound.integer:
        choices += [st.integers(max_value=int(low) - 1), st.integers(min_value=int(high) + 1),
                    st.integers(min_value=int(high) + 1).map(lambda v: v * 10**40)]
        if bound.odd:
            choices.append(st.integers(int(low), int(high)).filter(lambda v: v % 2 == 0))
    else:
        choices += [st.floats(max_value=low, exclude_max=not bound.low_open, allow_nan=False),
                    st.floats(min_value=high, exclude_min=not bound.high_open, allow_nan=False)]
    return st.one_of(*choices)


def _text(value) -> str:
    return repr(value) if isinstance(value, float) else str(value)


@settings(max_examples=300, deadline=None)
@given(data=st.data())
def test_a_bound_accepts_its_range_in_every_notation_and_refuses_the_rest_by_name(data):
    bound = data.draw(st.sampled_from(PRECOMPUTE_BOUNDS + ADDON_BOUNDS))
    if bound.integer:
        value = data.draw(_integers_in(bound))
        assert bound.check(value) == value and bound.parse(str(value)) == value
        digits = str(value).rstrip("0")
        if value > 0 and len(digits) < len(str(value)):  # 20000 is also 2e4, as the help writes it
            assert bound.parse(f"{digits}e{len(str(value)) - len(digits)}") == value
    else:
        value = data.draw(st.floats(bound.low, bound.high, exclude_min=bound.low_open, exclude_max=bound.high_open))
        assert bound.check(value) == value and bound.parse(repr(value)) == value
    refused = data.draw(_outside(bound))
    for attempt in (lambda: bound.check(refused), lambda: bound.parse(_text(refused))):
        with pytest.raises(ParameterError) as error:
            attempt()
        assert error.value.name == bound.name and bound.allowed() in str(error.value)


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=30))
@example("1e999999999")
@example("-0")
@example("1_000")
@example("0x10")
@example("\u0661\u0662")  # Arabic-Indic digits
def test_any_text_is_parsed_or_refused_by_name(text):
    for bound in PRECOMPUTE_BOUNDS + ADDON_BOUNDS:
        try:
            value = bound.parse(text)
        except ParameterError as error:
            assert error.name == bound.name
        else:
            assert bound.check(value) == value


#: (command, argv before the option, option, the bound of its value).  The values the argv leaves
#: fixed are in range.
NUMERIC_OPTIONS = [
    ("precompute", ["bake"], "--paths", bounds.PATHS_PER_CELL),
    ("precompute", ["bake"], "--target-error", bounds.TARGET_REL_STDERR),
    ("precompute", ["bake"], "--seed", bounds.SEED),
    ("precompute", ["slab", "--albedo", "0.5", "--g", "0", "--tau", "1"], "--paths", bounds.SLAB_PATHS),
    ("precompute", ["slab", "--g", "0", "--tau", "1"], "--albedo", bounds.SLAB_ALBEDO),
    ("precompute", ["slab", "--albedo", "0.5", "--tau", "1"], "--g", bounds.SLAB_G),
    ("precompute", ["slab", "--albedo", "0.5", "--g", "0"], "--tau", bounds.SLAB_TAU),
    ("precompute", ["slab", "--albedo", "0.5", "--g", "0", "--tau", "1"], "--n", bounds.SLAB_INDEX),
    ("validate", ["--out", "{root}/v"], "--resolution", render_bounds.VALIDATION_RESOLUTION),
    ("validate", ["--out", "{root}/v"], "--samples", render_bounds.VALIDATION_SAMPLES),
    ("validate", ["--out", "{root}/v"], "--seed", render_bounds.VALIDATION_SEED),
    ("validate", ["--out", "{root}/v"], "--patch-mm", render_bounds.VALIDATION_PATCH_MM),
    ("garment", ["bake", "--tables", str(YARN_BAKE), "--out", "{root}/c"], "--incidence-resolution",
     render_bounds.GONIO_INCIDENCE_RESOLUTION),
    ("garment", ["bake", "--tables", str(YARN_BAKE), "--out", "{root}/c"], "--exit-resolution",
     render_bounds.GONIO_EXIT_RESOLUTION),
    ("garment", ["bake", "--tables", str(YARN_BAKE), "--out", "{root}/c"], "--pixels-per-patch",
     render_bounds.GONIO_PIXELS_PER_PATCH),
    ("garment", ["bake", "--tables", str(YARN_BAKE), "--out", "{root}/c"], "--samples", render_bounds.GONIO_SAMPLES),
    ("garment", ["bake", "--tables", str(YARN_BAKE), "--out", "{root}/c"], "--threads-per-cm", THREADS_PER_CM),
]


def _value_given(arguments: dict, command: str, option: str):
    """The value of ``option`` as the command passed it on to its work (:class:`WorkStarted`)."""
    if command == "precompute bake":  # the yarn bake's checked configuration
        key = {"--paths": "paths_per_cell", "--target-error": "target_rel_stderr", "--seed": "seed"}[option]
        return arguments["configuration"].transport[key]
    if command == "precompute slab":  # slab_summary(albedo, g, tau, n, paths=…, seed=…, …)
        positional = ("--albedo", "--g", "--tau", "--n")
        return arguments["args"][positional.index(option)] if option in positional else arguments[option[2:]]
    return arguments[option[2:].replace("-", "_")]  # validate and garment: their parsed arguments


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_every_numeric_option_takes_exactly_its_range(data, files, no_work, capsys):
    """In range, the command starts its work with the value as typed; out of range, it exits 2 naming
    the option and the range, before any work, never with a traceback."""
    cli, before, option, bound = data.draw(st.sampled_from(NUMERIC_OPTIONS))
    inside = data.draw(st.booleans())
    if inside:
        value = data.draw(_integers_in(bound) if bound.integer else st.floats(
            bound.low, bound.high, exclude_min=bound.low_open, exclude_max=bound.high_open))
    else:
        value = data.draw(_outside(bound))
    argv = [arg.format(root=files["root"]) for arg in before] + [f"{option}={_text(value)}"]
    capsys.readouterr()
    try:
        code = CLIS[cli](argv)
    except WorkStarted as started:
        assert inside, f"{option} {value!r} was accepted"
        assert _value_given(started.arguments, f"{cli} {before[0]}", option) == value
        return
    err = capsys.readouterr().err
    assert not inside and code == 2, (option, value, err)
    assert option in err and bound.allowed() in err and "Traceback" not in err


@settings(max_examples=60, deadline=None)
@given(st.sampled_from([bounds.N_AROUND, bounds.N_ALONG, bounds.ANGULAR_RESOLUTION, bounds.PATHS_PER_CELL,
                        bounds.TARGET_REL_STDERR, bounds.INCIDENCE_RESOLUTION, bounds.SEED]), st.data())
def test_the_bake_api_refuses_out_of_range_transport_settings_by_name(bound, data):
    from precompute.bake import bake_configuration

    value = data.draw(_outside(bound))
    key = bound.name.split(".")[-1]
    with pytest.raises(ParameterError) as error:
        if key in ("paths_per_cell", "target_rel_stderr", "seed"):
            bake_configuration("paper_2008", **{key: value})
        else:
            bake_configuration("paper_2008", {bound.name: value})
    assert error.value.name == bound.name and bound.allowed() in error.value.allowed


@settings(max_examples=60, deadline=None)
@given(st.sampled_from([bounds.PATHS_PER_CELL, bounds.TARGET_REL_STDERR, bounds.SEED]), st.data())
def test_a_wrong_value_an_option_replaces_is_refused_all_the_same(bound, data):
    from precompute.bake import bake_configuration

    wrong = data.draw(_outside(bound))
    given = {"seed": 3} if bound is bounds.SEED else data.draw(st.sampled_from([{"paths_per_cell": 64},
                                                                                 {"target_rel_stderr": 0.05}]))
    with pytest.raises(ParameterError) as error:
        bake_configuration("paper_2008", {bound.name: wrong}, **given)
    assert error.value.name == bound.name and bound.allowed() in error.value.allowed


@settings(max_examples=60, deadline=None)
@given(st.lists(st.sampled_from(["dye.weight_percent", "transport.seed", "host.absorption_per_mm"]), min_size=1,
                max_size=4), st.lists(st.integers(0, 5), min_size=4, max_size=4))
def test_a_key_set_twice_is_refused_naming_it(keys, values):
    from precompute.bake import apply_overrides

    texts = [f"{key}={value}" for key, value in zip(keys, values)]
    repeated = next((key for i, key in enumerate(keys) if key in keys[:i]), None)
    if repeated is None:
        config = apply_overrides({}, texts)
        assert all(config[k.split(".")[0]][k.split(".")[1]] == v for k, v in zip(keys, values))
        return
    with pytest.raises(ParameterError) as error:
        apply_overrides({}, texts)
    assert error.value.name == repeated and "one value per key" in error.value.allowed


def test_the_bake_refuses_grids_beyond_memory_with_the_estimate(monkeypatch):
    from precompute.bake import bake_configuration

    small = {"transport.angular_resolution": 4, "transport.n_around": 8, "transport.n_along": 2,
             "transport.incidence_resolution": 5}
    settings_ = bake_configuration("paper_2008", small).transport
    need = bounds.transport_memory_bytes(8, 2, 4, 5, 35)
    assert need == (4 * 16 * 8 * 4 * 16 * 35 + 4 * 16 * 8 * 16 * 35) + (8 * 25 * 16 * 8 + 4 * 16 * 8 * 16 * 35
                                                                         + 32 * 25 * 16 * 35)
    monkeypatch.setattr(bounds, "memory_limit_bytes", lambda: need - 1)
    with pytest.raises(ParameterError) as error:
        bake_configuration("paper_2008", small)
    assert "transport.angular_resolution" in error.value.name and bounds.gib(need) in error.value.allowed
    assert settings_["angular_resolution"] == 4


@pytest.mark.blender
def test_the_panel_reads_the_same_bounds():
    pytest.importorskip("bpy")
    from clothlight.blender import properties

    def limits(name):  # the annotation as Blender reads it at registration (a string: postponed evaluation)
        annotation = properties.ClothLightMediumSettings.__annotations__[name]
        keywords = (eval(annotation, vars(properties)) if isinstance(annotation, str) else annotation).keywords
        return keywords["min"], keywords["max"]

    for name, bound in (("paths_per_cell", bounds.PATHS_PER_CELL), ("target_error", bounds.TARGET_REL_STDERR),
                        ("n_around", bounds.N_AROUND), ("n_along", bounds.N_ALONG),
                        ("angular_resolution", bounds.ANGULAR_RESOLUTION),
                        ("particle_diameter_nm", bounds.PARTICLE_DIAMETER_NM),
                        ("yarn_radius_mm", bounds.YARN_RADIUS_MM)):
        assert limits(name) == (bound.low, bound.high), name
    assert limits("incidence_resolution") == (0, bounds.INCIDENCE_RESOLUTION.high)  # 0: automatic
    from clothlight.weave.params import COUNT_BOUNDS

    for name, bound in COUNT_BOUNDS.items():
        annotation = properties.ClothLightWeaveSettings.__annotations__[name]
        keywords = (eval(annotation, vars(properties)) if isinstance(annotation, str) else annotation).keywords
        assert (keywords["min"], keywords["max"]) == (bound.low, bound.high), name
    from clothlight.blender.validation.operator import CLOTHLIGHT_OT_validate

    for name, bound in (("resolution", render_bounds.VALIDATION_RESOLUTION),
                        ("samples", render_bounds.VALIDATION_SAMPLES)):
        keywords = CLOTHLIGHT_OT_validate.__annotations__[name]
        keywords = (eval(keywords, vars(sys.modules[CLOTHLIGHT_OT_validate.__module__]))
                    if isinstance(keywords, str) else keywords).keywords
        assert (keywords["min"], keywords["max"]) == (bound.low, bound.high), name
