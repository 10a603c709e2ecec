"""Shared test set-up: Blender's user folder, the test tiers, and the fixtures several modules use.

Blender keeps user state (preferences, installed extensions) in its user resource folder; tests
point it at a throw-away folder before anything imports bpy, so they never touch a real Blender
installation's settings.

The tiers (markers registered in pyproject.toml) are given here, by module and by fixture, so a
test module rarely names them:

``blender``
    the test needs bpy: its module holds ``bpy`` (``bpy = pytest.importorskip("bpy")``), it uses
    the ``bpy`` fixture, or it is marked by hand (a test that imports bpy in its body);
``render``
    a Blender test of a module in :data:`RENDER_MODULES`, or marked by hand;
``slow``
    a test of a module in :data:`SLOW_MODULES`, one of :data:`SLOW_TESTS` or one using a fixture of
    :data:`SLOW_FIXTURES`.

``make test`` runs every tier; ``make test-fast`` runs ``-m "not blender and not render and not
slow"`` with ``CLOTHLIGHT_TESTS_WITHOUT_BPY=1``, which makes ``import bpy`` fail as where Blender is
not installed: modules that need bpy are skipped at collection (``pytest.importorskip``), so the
pure tier proves it needs none.
"""

import atexit
import importlib.abc
import os
import shutil
import sys
import tempfile

import pytest

from tests.helpers import BLENDER_ONLY, build_extension_zip

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

#: Test modules whose Blender tests render with Cycles.
RENDER_MODULES = {"test_addon_operators", "test_cloth_response_render", "test_cycles_closures", "test_example_blends",
                  "test_fit_job", "test_garment", "test_grids", "test_osl_render", "test_validation_rig",
                  "test_yarn_shader"}
#: Test modules that bake tables, build the extension zip or render for minutes.
SLOW_MODULES = {"test_addon_operators", "test_bake_cli", "test_bake_dye_series", "test_distributed",
                "test_distributed_fit", "test_distributed_garment", "test_distributed_jobs",
                "test_distributed_validation", "test_extension", "test_fit_dye_series"}
#: Fixtures that bake (yarn or cloth) or build the extension zip or the native slab library: a test that
#: uses one is slow.
SLOW_FIXTURES = {"extension_zip", "native_slab_library", "red_cotton_cloth", "transport_runs"}
#: Single tests of otherwise quick modules that bake or fit in a child process, run Monte-Carlo
#: transport or a fit's optimiser for seconds (module::name).
SLOW_TESTS = {"test_cache::test_a_killed_bake_leaves_no_table",
              "test_cli_exit_codes::test_the_bake_worker_reports_bad_input_and_internal_errors_in_its_events",
              "test_fit_job::test_a_fit_in_its_child_shows_progress_and_writes_the_fit_folder",
              "test_fit_job::test_the_childs_fit_is_the_command_lines",
              "test_fit_job::test_cancel_mid_fit_exits_130_and_leaves_no_folder",
              "test_fit_job::test_a_preset_without_the_species_a_parameter_needs_exits_2_from_the_child",
              "test_fit_job::test_the_fit_operator_fits_in_background_mode_and_loads_the_fitted_values",
              "test_fit_job::test_esc_cancels_an_interactive_fit_and_nothing_is_written",
              "test_fit_optimise::test_the_back_lit_constraint_keeps_the_cloth_darker_from_behind",
              "test_fit_optimise::test_the_specular_term_is_profiled_when_the_model_splits_it_off",
              "test_cache::test_two_concurrent_bakes_of_one_key_end_with_one_valid_table",
              "test_transport_brdf::test_discretisation_error_shrinks_with_the_grids",
              "test_transport_cylinder::test_error_target_is_reached_deterministically",
              "test_transport_slab::test_iadpython_totals_include_specular_and_unscattered_light"}


def _needs_blender(item) -> bool:
    module_bpy = getattr(getattr(item, "module", None), "bpy", None)
    return (item.get_closest_marker("blender") is not None or "bpy" in getattr(item, "fixturenames", ())
            or (module_bpy is not None and type(module_bpy).__name__ == "module"))


def pytest_collection_modifyitems(config, items):
    for item in items:
        module = item.module.__name__.rpartition(".")[2] if getattr(item, "module", None) else ""
        if _needs_blender(item):
            if item.get_closest_marker("blender") is None:
                item.add_marker(pytest.mark.blender)
            if module in RENDER_MODULES and item.get_closest_marker("render") is None:
                item.add_marker(pytest.mark.render)
        slow = (module in SLOW_MODULES or f"{module}::{item.originalname}" in SLOW_TESTS
                or SLOW_FIXTURES & set(getattr(item, "fixturenames", ())))
        if slow and item.get_closest_marker("slow") is None:
            item.add_marker(pytest.mark.slow)


@pytest.fixture(scope="session")
def bpy():
    """Blender as a Python module; a test that asks for it is a ``blender`` test, skipped without it."""
    return pytest.importorskip("bpy")


@pytest.fixture(scope="session")
def extension_zip(tmp_path_factory):
    """The linux-x64 extension zip, built once per test session (tests.helpers.build_extension_zip)."""
    return build_extension_zip(tmp_path_factory.getbasetemp() / "clothlight-dist")
