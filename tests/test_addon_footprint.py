"""What the add-on costs a Blender that enables it.

Enabling it imports only its own light modules: numba, llvmlite, SciPy, OpenEXR, colour-science and
matplotlib wait for a job that needs them (issue 22: 657 modules, 10.5 s at every Blender start).
Blender runs in a child process with a clean interpreter (nothing imported yet) and its own user
folder and home.  The time is printed, never asserted.
"""

import json
import os
import pathlib
import subprocess
import sys
import textwrap

import pytest

bpy = pytest.importorskip("bpy")  # the Blenders below run in child processes; this one only says bpy is here

REPO = pathlib.Path(__file__).resolve().parents[1]
#: What a job may import, never the add-on's registration.
HEAVY = ("numba", "llvmlite", "scipy", "OpenEXR", "colour", "matplotlib")
EXTENSION = "bl_ext.user_default.clothlight"
#: Environment that would hide a write (bytecode off, another bytecode or numba folder).
HIDING = ("PYTHONDONTWRITEBYTECODE", "PYTHONPYCACHEPREFIX", "NUMBA_CACHE_DIR")


def blender_env(tmp_path: pathlib.Path) -> dict:
    env = {key: value for key, value in os.environ.items() if key not in HIDING}
    env["HOME"] = str(tmp_path / "home")
    env["BLENDER_USER_RESOURCES"] = str(tmp_path / "blender")
    for key in ("HOME", "BLENDER_USER_RESOURCES"):
        pathlib.Path(env[key]).mkdir(exist_ok=True)
    return env


def run_blender(code: str, env: dict, cwd: pathlib.Path) -> dict:
    """Run ``code`` in a fresh Python with Blender as a module; it prints one JSON object last."""
    preamble = textwrap.dedent(f"""
        import json, pathlib, sys, time
        HEAVY = {HEAVY!r}
        EXTENSION = {EXTENSION!r}
        def heavy_imported():
            return sorted(name for name in HEAVY if name in sys.modules)
        import bpy
    """)
    result = subprocess.run([sys.executable, "-c", preamble + textwrap.dedent(code)], cwd=cwd, env=env,
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-5000:]
    return json.loads(result.stdout.strip().splitlines()[-1])


def test_registering_the_add_on_imports_none_of_the_heavy_modules(tmp_path):
    """The development checkout registered as tests/test_table_folder.py does it."""
    outcome = run_blender("""
        before = len(sys.modules)
        started = time.perf_counter()
        import clothlight
        clothlight.register()
        seconds = time.perf_counter() - started
        print(json.dumps({"seconds": seconds, "modules": len(sys.modules) - before, "heavy": heavy_imported()}))
    """, blender_env(tmp_path), cwd=REPO)
    print(f"\nimport clothlight + register(): {outcome['seconds']:.2f} s, {outcome['modules']} modules imported")
    assert outcome["heavy"] == []
