"""The project's own bookkeeping: one version everywhere, the test tiers registered."""

import pathlib
import tomllib

import precompute

REPO = pathlib.Path(__file__).resolve().parents[1]


def test_pyproject_the_extension_manifest_and_precompute_carry_one_version():
    pyproject = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["version"]
    manifest = tomllib.loads((REPO / "blender_manifest.toml").read_text())["version"]
    assert pyproject == manifest == precompute.__version__


def test_the_test_tiers_are_registered_markers():
    options = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["pytest"]["ini_options"]
    registered = {marker.split(":")[0] for marker in options["markers"]}
    assert {"blender", "render", "slow"} <= registered and "--strict-markers" in options["addopts"]
