"""The extension zip as Blender's tool builds it: the add-on, its pre-baked tables and the wheels an
in-Blender bake and fit need for linux-x64, at the versions requirements.txt pins, never numpy, and a manifest
that Blender's validator accepts.  The installed zip is driven in tests/test_addon_operators.py."""

import importlib.util
import json
import pathlib
import re
import subprocess
import sys
import tomllib
import zipfile

import pytest

from clothlight.jobs import BUNDLED_DEPENDENCIES, CLOTH_TRACE_DEPENDENCIES
from clothlight.medium_settings import BakeRequest, preset_request
from tests.helpers import PREBAKED_PRESET, PREBAKED_TRANSPORT

pytestmark = pytest.mark.slow

REPO_ROOT = pathlib.Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("build_extension", REPO_ROOT / "scripts" / "build_extension.py")
build_extension = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(build_extension)


def _wheel_name_version(filename: str) -> tuple[str, str]:
    name, version = filename.split("-")[:2]
    return re.sub(r"[-_.]+", "-", name).lower(), version


def test_zip_holds_the_add_on_shaders_presets_and_prebaked_tables_but_no_dev_files_or_numpy(extension_zip):
    names = zipfile.ZipFile(extension_zip).namelist()
    assert "blender_manifest.toml" in names and "__init__.py" in names
    assert {"clothlight/__init__.py", "osl/clothlight.h", "precompute/presets/voided_red_cotton.toml"} <= set(names)
    assert any(n.startswith("clothlight/blender/presets/clothlight_weave/") for n in names)
    assert not [n for n in names if n.startswith(("tests/", "benchmarks/", "scripts/", "example_blends/", ".git"))]
    assert not [n for n in names if "numpy" in n.lower() or n.endswith((".oso", ".nbi", ".nbc")) or "__pycache__" in n]
    prebaked = {n.rsplit("/", 1)[-1] for n in names if n.startswith(f"prebaked/{PREBAKED_PRESET}/")}
    assert {"brdf.exr", "lobes.exr", "summary.json", "request.json"} <= prebaked
    assert "spectral.npz" not in prebaked


def test_prebaked_tables_record_the_request_they_were_baked_from(extension_zip):
    with zipfile.ZipFile(extension_zip) as archive:
        request = BakeRequest.from_json(archive.read(f"prebaked/{PREBAKED_PRESET}/request.json").decode())
        summary = json.loads(archive.read(f"prebaked/{PREBAKED_PRESET}/summary.json"))
    untouched = preset_request(PREBAKED_PRESET)
    assert request.preset == PREBAKED_PRESET and not request.overrides and request.seed == untouched.seed
    assert summary["schema"].startswith("clothlight-table/")
    assert summary["medium"]["name"] == PREBAKED_PRESET
    for key, value in PREBAKED_TRANSPORT.items():
        assert getattr(request, key) == value and summary["transport"][key] == value, key
    assert request.target_rel_stderr is None and summary["transport"]["target_rel_stderr"] is None


def test_manifest_lists_linux_wheels_of_every_bake_and_fit_dependency_at_the_pinned_versions(extension_zip):
    with zipfile.ZipFile(extension_zip) as archive:
        manifest = tomllib.loads(archive.read("blender_manifest.toml").decode())
        names = set(archive.namelist())
    assert manifest["platforms"] == ["linux-x64"]
    assert manifest["blender_version_max"] == build_extension.BLENDER_VERSION_MAX
    wheels = [pathlib.PurePosixPath(w).name for w in manifest["wheels"]]
    assert all(f"wheels/{w}" in names for w in wheels)
    bundled = dict(_wheel_name_version(w) for w in wheels)
    assert set(bundled) == {re.sub(r"[-_.]+", "-", d).lower()
                            for d in (*BUNDLED_DEPENDENCIES.values(), *CLOTH_TRACE_DEPENDENCIES.values())}
    assert "numpy" not in bundled and "cma" in bundled  # the fit's optimiser, a pure-Python wheel
    pins = build_extension.requirement_pins()
    for name, version in bundled.items():
        if name in pins:
            assert version == pins[name], name
    for wheel in wheels:
        platform_tag = wheel[:-4].split("-")[-1]
        assert platform_tag == "any" or "manylinux" in platform_tag and "x86_64" in platform_tag, wheel
        assert wheel.split("-")[2] in ("py3", "cp311"), wheel


def test_blender_validator_accepts_the_zip(extension_zip):
    tool = build_extension.blender_extension_tool()
    result = subprocess.run([sys.executable, str(tool), "validate", str(extension_zip)], capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr


def test_staged_manifest_adds_top_level_keys_before_the_first_table():
    source = (REPO_ROOT / "blender_manifest.toml").read_text()
    staged = tomllib.loads(build_extension.staged_manifest(source, ["windows-x64"], ["a-1-py3-none-any.whl"], False))
    original = tomllib.loads(source)
    assert staged["platforms"] == ["windows-x64"] and staged["wheels"] == ["./wheels/a-1-py3-none-any.whl"]
    assert "blender_version_max" not in staged
    assert staged["build"] == original["build"] and staged["permissions"] == original["permissions"]
    with pytest.raises(SystemExit, match="wheels"):
        build_extension.staged_manifest(source + '\nwheels = []\n', ["linux-x64"], [], False)


def test_requirement_pins_read_names_case_and_separator_insensitively(tmp_path):
    path = tmp_path / "requirements.txt"
    path.write_text("# comment\nColour_Science==0.4.6  # why\nnumpy==1.26.4\nscipy>=1\n\nOpenEXR == 3.5.3\n")
    assert build_extension.requirement_pins(path) == {"colour-science": "0.4.6", "numpy": "1.26.4", "openexr": "3.5.3"}


def test_every_bundled_distribution_is_pinned_or_resolved_from_requirements():
    versions, notes = build_extension.bundled_versions()
    pins = build_extension.requirement_pins()
    assert set(versions) == set(BUNDLED_DEPENDENCIES.values()) and versions["cma"] == pins["cma"]
    for dist, version in versions.items():
        pinned = pins.get(re.sub(r"[-_.]+", "-", dist).lower())
        assert version == pinned if pinned else any(dist in note for note in notes)
