"""Shared test set-up: Blender's user folder, the tiers that follow from what a test uses, and shared fixtures.

Blender keeps user state (preferences, installed extensions) in its user resource folder; tests
point it at a throw-away folder before anything imports bpy, so they never touch a real Blender
installation's settings.

The tiers (markers registered in pyproject.toml) are marked where the tests are: a module that is
all of one tier says so in its ``pytestmark``, a single test by its decorator.  Two follow from what
a test uses, and are added here:

``blender``
    the test needs bpy: its module holds ``bpy`` (``bpy = pytest.importorskip("bpy")``), or it uses
    the ``bpy`` fixture (directly or through another fixture);
``slow``
    the test uses a fixture that bakes, builds the extension zip or the native slab library: such a
    fixture says so itself (``@slow_fixture``, tests/helpers.py).

``render`` (Cycles renders) and ``slow`` (bakes, the extension zip, minutes of rendering) are
otherwise marked by hand.  ``make test`` runs every tier; ``make test-fast`` runs ``-m "not blender
and not render and not slow"`` with ``CLOTHLIGHT_TESTS_WITHOUT_BPY=1``, which makes ``import bpy``
fail as where Blender is not installed: modules that need bpy are skipped at collection
(``pytest.importorskip``), so the pure tier proves it needs none.
"""

import atexit
import importlib.abc
import os
import shutil
import sys
import tempfile

import pytest

from tests.helpers import BLENDER_ONLY, SLOW_FIXTURE, build_extension_zip, slow_fixture

# Blender's user folder (installed extensions, their wheels and caches) in a temporary folder, one
# per process: pytest-xdist's workers inherit the controller's environment, and two workers
# installing the extension into one folder would race.  A folder the user set is kept.
if os.environ.get("BLENDER_USER_RESOURCES", "") == os.environ.get("CLOTHLIGHT_TEST_USER_RESOURCES", ""):
    _user_resources = tempfile.mkdtemp(prefix="clothlight-blender-user-")
    os.environ["BLENDER_USER_RESOURCES"] = os.environ["CLOTHLIGHT_TEST_USER_RESOURCES"] = _user_resources
    atexit.register(shutil.rmtree, _user_resources, ignore_errors=True)


class _WithoutBlender(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.partition(".")[0] in BLENDER_ONLY:
            raise ModuleNotFoundError(f"No module named {name!r} (CLOTHLIGHT_TESTS_WITHOUT_BPY is set)", name=name)
        return None


if os.environ.get("CLOTHLIGHT_TESTS_WITHOUT_BPY"):
    sys.meta_path.insert(0, _WithoutBlender())

def _needs_blender(item) -> bool:
    module_bpy = getattr(getattr(item, "module", None), "bpy", None)
    return (item.get_closest_marker("blender") is not None or "bpy" in getattr(item, "fixturenames", ())
            or (module_bpy is not None and type(module_bpy).__name__ == "module"))


def _uses_a_slow_fixture(item) -> bool:
    definitions = getattr(item, "_fixtureinfo", None)
    return definitions is not None and any(getattr(definition.func, SLOW_FIXTURE, False)
                                           for defs in definitions.name2fixturedefs.values() for definition in defs)


def pytest_collection_modifyitems(config, items):
    for item in items:
        if _needs_blender(item) and item.get_closest_marker("blender") is None:
            item.add_marker(pytest.mark.blender)
        if _uses_a_slow_fixture(item) and item.get_closest_marker("slow") is None:
            item.add_marker(pytest.mark.slow)


@pytest.fixture(scope="session")
def bpy():
    """Blender as a Python module; a test that asks for it is a ``blender`` test, skipped without it."""
    return pytest.importorskip("bpy")


@pytest.fixture(scope="session")
@slow_fixture
def extension_zip(tmp_path_factory):
    """The linux-x64 extension zip, built once per test session (tests.helpers.build_extension_zip)."""
    return build_extension_zip(tmp_path_factory.getbasetemp() / "clothlight-dist")
