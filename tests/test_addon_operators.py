"""The add-on as a Blender user gets it: the built zip installed into a fresh Blender user folder
(tests/conftest.py), enabled, and driven headless — Build Sample, Bake Tables (tiny budget, in a child
process, and cancelled), Fit to Measurement (tiny), Apply Material (pre-baked and freshly baked
tables), Validate (tiny), presets, register/unregister twice, and a .blend saved and reloaded with its
settings intact."""

import json
import os
import pathlib
import subprocess
import sys
import time
from types import SimpleNamespace

import pytest

bpy = pytest.importorskip("bpy")

from tests.helpers import PREBAKED_PRESET, PREBAKED_TRANSPORT  # noqa: E402

EXTENSION_MODULE = "bl_ext.user_default.clothlight"
ADDON = f"{EXTENSION_MODULE}.clothlight"
#: A bake small enough for a test: 4 × 4 angular grids, 64 paths per incidence cell; the test build
#: ships the red-cotton tables baked with exactly these settings.
TINY = {"budget": "PATHS", **PREBAKED_TRANSPORT}


def tiny(medium) -> None:
    for key, value in TINY.items():
        setattr(medium, key, value)

pytestmark = [pytest.mark.blender, pytest.mark.render, pytest.mark.slow]


@pytest.fixture(scope="module")
def addon(extension_zip):
    bpy.ops.wm.read_homefile(use_empty=True)
    result = bpy.ops.extensions.package_install_files(filepath=str(extension_zip), repo="user_default",
                                                      enable_on_install=True)
    assert result == {"FINISHED"}
    # The installer reports FINISHED even on a platform mismatch: check the module really loaded.
    assert EXTENSION_MODULE in sys.modules and EXTENSION_MODULE in bpy.context.preferences.addons
    import importlib

    yield {name: importlib.import_module(f"{ADDON}.{module}")
           for name, module in (("operators", "blender.operators"), ("jobs", "jobs"), ("prebaked", "prebaked"),
                                ("properties", "blender.properties"), ("preferences", "blender.preferences"),
                                ("materials", "blender.materials"),
                                ("running_jobs", "blender.running_jobs"),
                                ("medium_settings", "medium_settings"))}
    import addon_utils

    addon_utils.disable(EXTENSION_MODULE)
    bpy.ops.wm.read_homefile(use_empty=True)


@pytest.fixture
def scene(addon):
    bpy.ops.wm.read_homefile(use_empty=True)
    return bpy.context.scene


def unused_blocks() -> set:
    collections = (bpy.data.meshes, bpy.data.materials, bpy.data.objects, bpy.data.lights, bpy.data.cameras,
                   bpy.data.images, bpy.data.node_groups, bpy.data.scenes, bpy.data.worlds)
    return {(type(block).__name__, block.name) for collection in collections for block in collection
            if block.users == 0 and not block.use_fake_user}


def shader_inputs(material):
    node = next(n for n in material.node_tree.nodes if n.type == "SCRIPT")
    return node.inputs


def brdf_table(addon, material) -> pathlib.Path:
    """The BRDF table a yarn material reads (an OSL shader or the general mode's plain nodes)."""
    return pathlib.Path(addon["materials"].yarn_tables_folder(material)) / "brdf.exr"


# -- registration, preferences ---------------------------------------------------------------------


def test_installed_extension_registers_its_classes_and_user_folders(addon, scene):
    for name in ("CLOTHLIGHT_OT_build_sample", "CLOTHLIGHT_OT_bake_tables", "CLOTHLIGHT_OT_apply_material",
                 "CLOTHLIGHT_OT_validate", "CLOTHLIGHT_OT_setup_render", "CLOTHLIGHT_PT_main",
                 "CLOTHLIGHT_PT_material_properties", "CLOTHLIGHT_OT_weave_preset_add",
                 "CLOTHLIGHT_OT_apply_garment_material", "CLOTHLIGHT_PT_garment", "CLOTHLIGHT_OT_fit_medium",
                 "CLOTHLIGHT_PT_medium_fit"):
        assert hasattr(bpy.types, name), name
    prefs = bpy.context.preferences.addons[EXTENSION_MODULE].preferences
    assert prefs.threads == 0 and prefs.cache_dir == ""
    package = pathlib.Path(sys.modules[EXTENSION_MODULE].__file__).parent
    for folder in (addon["preferences"].cache_directory(), addon["preferences"].numba_cache_directory()):
        assert pathlib.Path(folder).is_dir() and not pathlib.Path(folder).is_relative_to(package)


def test_bake_request_defaults_are_the_bakes_own():
    from precompute.bake import TRANSPORT_DEFAULTS
    from precompute.bounds import GRID_SETTINGS
    from clothlight.medium_settings import BakeRequest

    request = BakeRequest()
    for key, value in TRANSPORT_DEFAULTS.items():
        assert getattr(request, key) == value, key
    assert set(GRID_SETTINGS) <= set(TRANSPORT_DEFAULTS)
    overrides = dict(BakeRequest(n_around=24).bake_arguments()["overrides"])
    assert overrides == {f"transport.{key}": getattr(BakeRequest(n_around=24), key) for key in GRID_SETTINGS}


# -- settings ------------------------------------------------------------------------------------


def test_medium_settings_load_the_preset_and_send_only_changed_values(addon, scene):
    medium = scene.clothlight.medium
    medium_settings = addon["medium_settings"]
    assert medium.request() == medium_settings.preset_request("red_cotton")  # the default
    medium.base = "voided_red_cotton"
    medium.dye_weight_percent = 2.5
    medium.particle_volume_fraction = 0.14  # the preset's own value, stored in single precision
    assert medium.request().overrides == (("dye.weight_percent", 2.5),)
    medium.base = "delustred_polyester"
    assert "dye_weight_percent" not in medium.exposed_keys()
    assert medium.particle_diameter_nm == pytest.approx(250.0)
    assert medium.request() == medium_settings.preset_request("delustred_polyester")
    medium.particle_diameter_nm = 300.0
    assert medium.request().overrides == (("particles.0.median_diameter_nm", 300.0),)


def test_weave_settings_with_bad_values_are_refused_by_name_and_build_nothing(addon, scene):
    weave = scene.clothlight.weave
    weave.cross_section = "ROUND"
    weave.yarn_radius_mm = 0.3  # wider than half the spacing (0.4 mm): neighbouring yarns would intersect
    with pytest.raises(RuntimeError, match="yarn_radius_mm"):
        bpy.ops.clothlight.build_sample()
    weave.yarn_radius_mm = 0.1
    weave.pattern = "CUSTOM"
    weave.custom_draft = "12/01"
    with pytest.raises(RuntimeError, match="custom draft"):
        bpy.ops.clothlight.build_sample()
    assert not bpy.data.objects and not bpy.data.meshes


# -- Build Sample ---------------------------------------------------------------------------------


def test_build_sample_makes_a_real_size_sample_and_rebuilds_it_in_place(addon, scene):
    weave = scene.clothlight.weave
    weave.warp_count, weave.weft_count = 4, 6
    assert bpy.ops.clothlight.build_sample() == {"FINISHED"}
    obj = bpy.context.active_object
    assert obj["clothlight_weave"]["warp_count"] == 4
    # Modelled in mm, shown at its physical size in a metre scene: 6 picks × 0.4 mm = 2.4 mm = 0.0024 m
    # (the default: cotton sheeting, clothlight.weave.closeup.sheeting_weave).
    assert weave.spacing_mm == pytest.approx(0.4) and weave.cross_section == "ELLIPTICAL" and weave.use_plies
    assert obj.dimensions.x == pytest.approx(6 * 0.4e-3, rel=0.02)
    weave.pattern = "twill_2_1"
    weave.warp_count = 3
    assert bpy.ops.clothlight.build_sample() == {"FINISHED"}
    assert bpy.context.active_object == obj and len(bpy.data.objects) == len(bpy.data.meshes) == 1
    assert obj["clothlight_weave"]["warp_count"] == 3 and len(obj["clothlight_weave"]["interlacing"]) == 3
    bpy.ops.object.select_all(action="DESELECT")
    bpy.context.view_layer.objects.active = None
    assert bpy.ops.clothlight.build_sample() == {"FINISHED"}  # nothing active: a second sample
    assert len(bpy.data.objects) == 2 and not unused_blocks()


# -- Apply Material -------------------------------------------------------------------------------


def test_apply_material_uses_the_prebaked_tables_follows_the_sun_and_leaves_no_orphans(addon, scene):
    tiny(scene.clothlight.medium)  # the settings the shipped tables were baked with
    bpy.ops.clothlight.build_sample()
    sample = bpy.context.active_object
    assert bpy.ops.clothlight.apply_material() == {"FINISHED"}
    general = sample.active_material
    general_name = general.name
    prebaked = addon["prebaked"].PREBAKED_DIR / PREBAKED_PRESET
    table = brdf_table(addon, general)
    # The shipped tables' copy in the user cache (an update replaces the extension's folder):
    # tests/test_addon_footprint.py follows it through a saved file.
    assert table.name == "brdf.exr" and not table.is_relative_to(prebaked.parents[1])
    assert table.read_bytes() == (prebaked / "brdf.exr").read_bytes()
    # The default medium scatters: its general mode is plain nodes, which need no OSL.
    assert addon["materials"].material_mode(general) == "GENERAL"
    assert not [node for node in general.node_tree.nodes if node.type == "SCRIPT"]
    assert scene.render.engine == "CYCLES" and not scene.cycles.shading_system

    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    scene.collection.objects.link(sun)
    sun.data.energy = 3.0
    scene.clothlight.material_mode = "SUN"
    sample.select_set(True)
    bpy.context.view_layer.objects.active = sample
    assert bpy.ops.clothlight.apply_material() == {"FINISHED"}
    sun_material = sample.active_material
    assert sun_material.name != general_name and "ClothLight" in sun_material.name
    assert general_name not in bpy.data.materials  # replaced and unused: removed, not orphaned
    inputs = shader_inputs(sun_material)
    assert inputs["SunMode"].default_value == 1 and tuple(inputs["SunIrradiance"].default_value)[:3] == (3.0, 3.0, 3.0)
    sun.rotation_euler = (0.0, 1.0, 0.0)  # the sun tilts 1 rad toward +x
    bpy.context.view_layer.update()
    direction = tuple(shader_inputs(sun_material)["SunDirection"].default_value)
    assert direction == pytest.approx((0.8414710, 0.0, 0.5403023), abs=1e-5)
    assert not unused_blocks()


@pytest.fixture(scope="module")
def small_cloth_bake(addon, tmp_path_factory):
    """A small cloth bake of the paper's yarn tables (a cloth response of 3 × 2 cells, seconds)."""
    from clothlight.blender.garment.bake import bake_cloth
    from clothlight.blender.garment.measure import GoniometerSettings

    yarn = pathlib.Path(__file__).resolve().parents[1] / "example_blends" / "tables" / "paper_2008"
    cloth, _ = bake_cloth(yarn, GoniometerSettings(incidence_resolution=3, exit_resolution=2, pixels_per_patch=6,
                                                   samples=1), cache_dir=tmp_path_factory.mktemp("cloth"))
    return cloth


def test_apply_garment_material_puts_a_cloth_bake_on_meshes_with_uvs_only(scene, small_cloth_bake,
                                                                           tmp_path_factory):
    cloth = small_cloth_bake
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    bpy.ops.mesh.primitive_grid_add(size=1.0)
    garment = bpy.context.active_object
    mesh = bpy.data.meshes.new("no uv")
    mesh.from_pydata([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [], [(0, 1, 2)])
    bare = bpy.data.objects.new("no uv", mesh)
    scene.collection.objects.link(bare)
    scene.clothlight.cloth_tables_dir = str(tmp_path_factory.mktemp("not a bake"))
    with pytest.raises(RuntimeError, match="Cloth bake"):
        bpy.ops.clothlight.apply_garment_material()
    scene.clothlight.cloth_tables_dir = str(cloth)
    bare.select_set(True)
    assert bpy.ops.clothlight.apply_garment_material() == {"FINISHED"}
    material = garment.active_material
    assert material is not None and material["clothlight_garment"] == "GENERAL"
    assert not any(node.type == "SCRIPT" for node in material.node_tree.nodes)  # plain nodes: no OSL needed
    assert not bare.data.materials  # no UV map, no warp direction: skipped with a warning
    closures = {node.bl_idname for node in material.node_tree.nodes if node.bl_idname.startswith("ShaderNodeBsdf")}
    assert {"ShaderNodeBsdfTranslucent", "ShaderNodeBsdfHair", "ShaderNodeBsdfTransparent"} <= closures
    scene.clothlight.garment_open_weave = scene.clothlight.garment_transmission = False  # the panel's switches
    assert bpy.ops.clothlight.apply_garment_material() == {"FINISHED"}
    closures = {node.bl_idname for node in garment.active_material.node_tree.nodes
                if node.bl_idname.startswith("ShaderNodeBsdf")}
    assert closures == {"ShaderNodeBsdfDiffuse", "ShaderNodeBsdfToon", "ShaderNodeBsdfAnisotropic",
                        "ShaderNodeBsdfMetallic"}  # reflection only


def weave_repeats(material) -> float | None:
    """The weave detail's repeats per UV unit in a garment material (the node scaling the UVs), or None."""
    scales = [link.to_node.inputs["Scale"].default_value for link in material.node_tree.links
              if link.from_node.bl_idname == "ShaderNodeUVMap" and link.to_node.bl_idname == "ShaderNodeVectorMath"
              and link.to_node.operation == "SCALE"]
    assert len(scales) <= 1
    return scales[0] if scales else None


def test_yarn_detail_takes_the_weave_scale_from_the_mesh_size_and_the_scene_units(scene, small_cloth_bake):
    """1 m of grid in metres is 1000 mm of cloth along its UV map's unit: 1000 / repeat_mm weave repeats;
    the object's scale and the scene's unit scale count, a typed value wins."""
    from clothlight.blender.garment.material import cloth_tables_from_bake

    cloth = small_cloth_bake
    repeat_mm = cloth_tables_from_bake(cloth).detail_repeat_mm
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.clothlight.cloth_tables_dir = str(cloth)
    bpy.ops.mesh.primitive_grid_add(size=1.0)  # 1 × 1 units, its UV map the unit square
    garment = bpy.context.active_object
    assert bpy.ops.clothlight.apply_garment_material() == {"FINISHED"}
    assert weave_repeats(garment.active_material) is None  # Yarn Detail off
    scene.clothlight.garment_yarn_detail = True
    assert bpy.ops.clothlight.apply_garment_material() == {"FINISHED"}
    assert weave_repeats(garment.active_material) == pytest.approx(1000.0 / repeat_mm, rel=1e-5)
    garment.scale = (2.0, 3.0, 1.0)  # u along x
    scene.unit_settings.scale_length = 0.01  # a unit is a centimetre
    bpy.context.view_layer.update()
    assert bpy.ops.clothlight.apply_garment_material() == {"FINISHED"}
    assert weave_repeats(garment.active_material) == pytest.approx(20.0 / repeat_mm, rel=1e-5)
    scene.clothlight.garment_weave_repeats = 7.0
    assert bpy.ops.clothlight.apply_garment_material() == {"FINISHED"}
    assert weave_repeats(garment.active_material) == pytest.approx(7.0)


def test_a_cloth_bake_started_by_apply_garment_material_applies_it_when_done(addon, scene, small_cloth_bake):
    """Apply Garment Material without cloth tables starts Bake Cloth with the meshes to apply to;
    the bake's end puts the material on those of them still there, and sets the Cloth Bake folder."""
    from clothlight.jobs import ClothBakeOutcome

    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    bpy.ops.mesh.primitive_grid_add(size=1.0)
    garment = bpy.context.active_object
    bpy.ops.mesh.primitive_grid_add(size=1.0, location=(2.0, 0.0, 0.0))
    other = bpy.context.active_object
    operator, _ = interactive_operator(addon["operators"].CLOTHLIGHT_OT_bake_cloth, scene)
    operator.apply_to = "\n".join([garment.name, "removed since"])
    job = SimpleNamespace(error=None, outcome=ClothBakeOutcome(folder=small_cloth_bake, rendered=True))
    assert operator._finish(scene, job) == {"FINISHED"}
    assert scene.clothlight.cloth_tables_dir == str(small_cloth_bake)
    assert garment.active_material["clothlight_garment"] == "GENERAL" and not other.data.materials
    assert operator.reports[-1] == ("INFO", f"Garment material on {garment.name}")


def test_apply_material_refuses_objects_that_are_not_samples(addon, scene):
    bpy.ops.mesh.primitive_cube_add()
    assert not bpy.ops.clothlight.apply_material.poll()


# -- Bake Tables ----------------------------------------------------------------------------------


def test_bake_tables_runs_to_the_end_in_background_mode_and_apply_uses_its_tables(addon, scene):
    medium = scene.clothlight.medium
    tiny(medium)
    medium.dye_weight_percent = 2.0
    # In background mode INVOKE_DEFAULT runs execute(): the bake in its child process, to the end.
    assert bpy.ops.clothlight.bake_tables("INVOKE_DEFAULT") == {"FINISHED"}
    folder = pathlib.Path(medium.tables_dir)
    cache = pathlib.Path(addon["preferences"].cache_directory())
    assert folder.is_relative_to(cache) and (folder / "brdf.exr").is_file()
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["medium"]["dye"]["weight_percent"] == 2.0 and summary["transport"]["paths_per_cell"] == 64
    assert medium.tables_request == medium.request().to_json()
    bpy.ops.clothlight.build_sample()
    assert bpy.ops.clothlight.apply_material() == {"FINISHED"}
    table = brdf_table(addon, bpy.context.active_object.active_material)
    assert table == folder / "brdf.exr"


def test_bake_request_with_a_dye_range_round_trips_and_knows_a_dye_change():
    from clothlight.medium_settings import BakeRequest

    request = BakeRequest(overrides=(("dye.weight_percent", 0.5),), dye_series=(0.1, 3.0))
    assert BakeRequest.from_json(request.to_json()) == request
    assert request.bake_arguments()["dye_series"] == (0.1, 3.0)
    other_dye = BakeRequest(overrides=(("dye.weight_percent", 2.0),), dye_series=(0.1, 3.0))
    assert other_dye != request and other_dye.same_but_dye(request)
    assert not BakeRequest(overrides=(("dye.weight_percent", 2.0), ("yarn.radius_mm", 0.2)),
                           dye_series=(0.1, 3.0)).same_but_dye(request)
    assert not BakeRequest(overrides=(("dye.weight_percent", 2.0),), dye_series=(0.1, 4.0)).same_but_dye(request)


def test_a_dye_range_bakes_once_then_a_dye_change_rebakes_from_it_and_recolours_the_material(addon, scene):
    running_jobs = addon["running_jobs"]
    medium = scene.clothlight.medium
    tiny(medium)
    medium.use_dye_series = True
    medium.dye_series_low, medium.dye_series_high = 0.1, 3.0
    medium.dye_weight_percent = 0.5
    assert medium.request().dye_series == (0.1, 3.0)
    assert bpy.ops.clothlight.bake_tables() == {"FINISHED"}
    first = pathlib.Path(medium.tables_dir)
    bpy.ops.clothlight.build_sample()
    assert bpy.ops.clothlight.apply_material() == {"FINISHED"}
    material = bpy.context.active_object.active_material
    assert brdf_table(addon, material) == first / "brdf.exr"

    medium.dye_weight_percent = 2.0  # the update schedules the re-bake (a timer: never run in background mode)
    pending = running_jobs.ScheduledRecolour.start
    assert pending is not None and bpy.app.timers.is_registered(pending)
    running_jobs.ScheduledRecolour.cancel()
    assert bpy.ops.clothlight.bake_tables() == {"FINISHED"}
    second = pathlib.Path(medium.tables_dir)
    summary, before = (json.loads((folder / "summary.json").read_text()) for folder in (second, first))
    assert second != first and summary["dye_series"] == before["dye_series"]
    # one simulation for the range, both dye amounts read from it
    cache = pathlib.Path(addon["preferences"].cache_directory())
    assert len([entry for entry in cache.glob("dye_series/*/*") if not entry.name.startswith(".")]) == 1
    assert "reweighting" in summary["seconds"] and "reweighting" in before["seconds"]
    assert summary["rho_normal_rgb"][0] < before["rho_normal_rgb"][0]  # more dye, darker
    assert brdf_table(addon, material) == second / "brdf.exr"

    medium.dye_weight_percent = 4.0  # outside the range: the panel says so, nothing is scheduled
    assert running_jobs.ScheduledRecolour.start is None
    medium.use_dye_series = False  # a dye change then waits for Bake Tables
    medium.dye_weight_percent = 1.0
    assert running_jobs.ScheduledRecolour.start is None


def test_bake_tables_reports_bad_input_by_parameter_name(addon, scene):
    medium = scene.clothlight.medium
    medium.base = "voided_red_cotton"  # a medium of particles
    tiny(medium)
    medium.particle_volume_fraction = 0.74  # the densest packing of spheres, which the medium must stay below
    with pytest.raises(RuntimeError, match="volume_fraction"):
        bpy.ops.clothlight.bake_tables()
    assert medium.tables_dir == ""


def _partials(cache: pathlib.Path) -> list:
    return list(cache.rglob("*.partial"))


class _WindowManager:
    """The window manager's part in a modal operator, for driving one headless (timers never fire there)."""

    windows = ()

    def event_timer_add(self, interval, window=None):
        return object()

    def event_timer_remove(self, timer):
        pass

    def modal_handler_add(self, operator):
        pass


class _Workspace:
    def __init__(self):
        self.status = []

    def status_text_set(self, text):
        self.status.append(text)


def interactive_operator(cls, scene):
    """A child-job operator's interactive path (invoke → modal on timer ticks), out of Blender's
    operator machinery, with a recording report; returns it and its context."""
    names = ("_start", "_start_modal", "_show", "_status", "_finish", "modal", "_running", "_what")
    members = {name: getattr(cls, name) for name in names}
    members["report"] = lambda self, kind, text: self.reports.append((kind.pop(), text))
    operator = type(f"Interactive{cls.__name__}", (), members)()
    operator.reports = []
    context = SimpleNamespace(scene=scene, window=None, workspace=_Workspace(), window_manager=_WindowManager(),
                              preferences=bpy.context.preferences)
    return operator, context


def _interactive_bake(operators, scene):
    return interactive_operator(operators.CLOTHLIGHT_OT_bake_tables, scene)


def _tick(operator, context, until):
    """Timer ticks until ``until(result)``: however long a loaded machine takes, the modal ends with
    the child (FINISHED or CANCELLED), so every ``until`` here comes true."""
    while True:
        result = operator.modal(context, SimpleNamespace(type="TIMER", value="NOTHING"))
        if until(result):
            return result
        time.sleep(0.05)


def test_interactive_bake_polls_its_child_shows_progress_and_finishes(addon, scene):
    operators = addon["operators"]
    running_jobs = addon["running_jobs"]
    medium = scene.clothlight.medium
    tiny(medium)
    medium.seed = 3
    operator, context = _interactive_bake(operators, scene)
    assert operator._start_modal(context) == {"RUNNING_MODAL"}
    assert running_jobs.running_bake() is not None and not bpy.ops.clothlight.bake_tables.poll()
    # Other events pass through to the interface while the child works.
    assert operator.modal(context, SimpleNamespace(type="MOUSEMOVE", value="NOTHING")) == {"PASS_THROUGH"}
    assert _tick(operator, context, lambda result: result != {"PASS_THROUGH"}) == {"FINISHED"}
    assert callable(context.workspace.status[0]) and context.workspace.status[-1] is None
    assert running_jobs.running_bake() is None
    assert pathlib.Path(medium.tables_dir, "brdf.exr").is_file() and medium.tables_request == medium.request().to_json()
    assert operator.reports[-1][0] == "INFO" and "B/R" in operator.reports[-1][1]


def test_esc_cancels_an_interactive_bake_and_no_partial_table_is_left(addon, scene):
    operators = addon["operators"]
    running_jobs = addon["running_jobs"]
    medium = scene.clothlight.medium
    tiny(medium)
    medium.paths_per_cell, medium.angular_resolution, medium.seed = 20000, 6, 7
    operator, context = _interactive_bake(operators, scene)
    cache = pathlib.Path(addon["preferences"].cache_directory())
    entries = set(cache.glob("*/*"))
    assert operator._start_modal(context) == {"RUNNING_MODAL"}
    job = running_jobs.running_bake()
    _tick(operator, context, lambda result: job.progress > 0.0 or result != {"PASS_THROUGH"})
    assert not job.done, "the bake finished before it could be cancelled"
    assert operator.modal(context, SimpleNamespace(type="ESC", value="PRESS")) == {"RUNNING_MODAL"}
    assert _tick(operator, context, lambda result: result != {"PASS_THROUGH"}) == {"CANCELLED"}
    assert isinstance(job.error, addon["jobs"].BakeCancelled) and operator.reports[-1][0] == "WARNING"
    assert set(cache.glob("*/*")) == entries and not _partials(cache)
    assert medium.tables_dir == "" and running_jobs.running_bake() is None


def test_the_bundled_wheels_and_blenders_numpy_alone_can_bake(addon, tmp_path):
    """The child's import path cut down to the extension, its wheels and numpy: nothing from the venv."""
    import numpy

    jobs = addon["jobs"]
    site = pathlib.Path(bpy.utils.user_resource("EXTENSIONS")) / ".local" / "lib" / "python3.11" / "site-packages"
    assert (site / "numba").is_dir() and not (site / "numpy").exists()
    numpy_only = tmp_path / "numpy_only"
    numpy_only.mkdir()
    numpy_dir = pathlib.Path(numpy.__file__).parent
    for sibling in numpy_dir.parent.iterdir():
        if sibling.name == "numpy" or sibling.name.startswith(("numpy.libs", "numpy-")):
            (numpy_only / sibling.name).symlink_to(sibling)
    request = addon["medium_settings"].BakeRequest(seed=11, paths_per_cell=64, target_rel_stderr=None, n_around=4,
                                                   n_along=2, angular_resolution=4, incidence_resolution=5)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(jobs.PACKAGE_ROOT), str(site), str(numpy_only)]),
           "NUMBA_CACHE_DIR": addon["preferences"].numba_cache_directory()}
    log = tmp_path / "stderr.txt"
    with open(log, "w") as stderr:
        # stdin stays open: the worker takes its closing as a cancel.
        child = subprocess.Popen(
            [sys.executable, "-S", "-m", jobs.WORKER_MODULE, "--request", request.to_json(),
             "--cache-dir", str(tmp_path)],
            cwd=jobs.PACKAGE_ROOT, env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=stderr, text=True)
        output = child.stdout.read()
        child.wait()
        child.stdin.close()
    events = [json.loads(line) for line in output.splitlines()]
    assert child.returncode == 0 and events[-1]["event"] == "done", log.read_text()[-3000:]
    assert pathlib.Path(events[-1]["folder"]).is_relative_to(tmp_path)


def test_without_bake_dependencies_bake_is_refused_with_the_reason_and_prebaked_tables_still_work(
        addon, scene, monkeypatch):
    monkeypatch.setattr(addon["jobs"], "missing_bake_dependencies", lambda: ["numba", "llvmlite"])
    assert not bpy.ops.clothlight.bake_tables.poll()
    tiny(scene.clothlight.medium)
    bpy.ops.clothlight.build_sample()
    assert bpy.ops.clothlight.apply_material() == {"FINISHED"}  # the shipped tables of these settings
    scene.clothlight.medium.dye_weight_percent = 1.0
    with pytest.raises(RuntimeError, match="Bake unavailable: numba, llvmlite not installed"):
        bpy.ops.clothlight.apply_material()


# -- Fit to Measurement ---------------------------------------------------------------------------


def test_fit_to_measurement_runs_in_the_installed_extension(addon, scene, tmp_path):
    """The smallest real fit (tests/test_fit_job.py) from the installed zip: its child finds the
    extension's packages and bundled cma, and renders the cloth response with the pre-baked tables
    (the zip ships no example tables) into the extension's user cache."""
    from tests.test_fit_job import set_up_small_fit, write_small_measurement

    set_up_small_fit(scene, write_small_measurement(tmp_path / "small.csv"))
    scene.clothlight.fit.out_dir = str(tmp_path / "fit")
    assert bpy.ops.clothlight.fit_medium("INVOKE_DEFAULT") == {"FINISHED"}
    package = pathlib.Path(sys.modules[EXTENSION_MODULE].__file__).parent
    assert not (package / "example_blends").exists() and (package / "prebaked" / PREBAKED_PRESET).is_dir()
    assert (tmp_path / "fit" / "preset.toml").is_file() and scene.clothlight.fit.last() is not None
    cache = pathlib.Path(addon["preferences"].cache_directory())
    assert list(cache.glob("responses/*/response.npz"))
    assert "fit.specular_weight" in scene.clothlight.medium.fitted_overrides


# -- Validate -------------------------------------------------------------------------------------


def test_validate_measures_the_sample_with_its_material_and_removes_its_rig(addon, scene, tmp_path):
    tiny(scene.clothlight.medium)
    bpy.ops.clothlight.build_sample()
    bpy.ops.clothlight.apply_material()
    before = {(type(b).__name__, b.name) for c in (bpy.data.objects, bpy.data.meshes, bpy.data.scenes) for b in c}
    result = bpy.ops.clothlight.validate("INVOKE_DEFAULT", out_dir=str(tmp_path), incidences="0", views="0 30",
                                         resolution=16, samples=1, swatches=False)
    assert result == {"FINISHED"}
    results = json.loads((tmp_path / "results.json").read_text())
    assert set(results["materials"]) == {"yarn", "baseline"}
    after = {(type(b).__name__, b.name) for c in (bpy.data.objects, bpy.data.meshes, bpy.data.scenes) for b in c}
    # The sweep plot is loaded as an image for the Image Editor (clothlight/blender/validation/operator.py).
    assert after == before and not unused_blocks() - {("Image", "ClothLight Validation")}


# -- presets --------------------------------------------------------------------------------------


def _shipped(subdir: str) -> list[pathlib.Path]:
    root = pathlib.Path(sys.modules[ADDON].__file__).parent / "blender" / "presets" / subdir
    return sorted(root.glob("*.py"))


def test_shipped_presets_are_found_by_blender_and_give_valid_settings(addon, scene):
    from precompute.optics.medium import preset_names

    weave_presets = _shipped("clothlight_weave")
    assert str(weave_presets[0].parent) in bpy.utils.preset_paths("clothlight_weave")
    for path in weave_presets:
        bpy.ops.script.execute_preset(filepath=str(path), menu_idname="CLOTHLIGHT_PT_weave_presets")
        scene.clothlight.weave.parameters()  # raises for a preset the weave core refuses
    bases = set()
    for path in _shipped("clothlight_medium"):
        bpy.ops.script.execute_preset(filepath=str(path), menu_idname="CLOTHLIGHT_PT_medium_presets")
        medium = scene.clothlight.medium
        assert medium.request() == addon["medium_settings"].preset_request(medium.base)
        bases.add(medium.base)
    assert bases == set(preset_names())
    numbers = {item.identifier: item.value for item in scene.clothlight.medium.bl_rna.properties["base"].enum_items}
    assert numbers == addon["medium_settings"].BASE_MEDIUM_NUMBERS  # what a .blend stores for each


def test_a_user_medium_preset_is_saved_where_blender_keeps_presets_and_restores_the_values(addon, scene):
    medium = scene.clothlight.medium
    medium.dye_weight_percent = 4.25
    medium.seed = 5
    assert bpy.ops.clothlight.medium_preset_add(name="Test Deep Dye") == {"FINISHED"}
    path = pathlib.Path(bpy.utils.preset_find("Test_Deep_Dye", "clothlight_medium"))
    try:
        assert path.is_relative_to(pathlib.Path(bpy.utils.user_resource("SCRIPTS")))
        medium.base = "undyed_cotton"
        bpy.ops.script.execute_preset(filepath=str(path), menu_idname="CLOTHLIGHT_PT_medium_presets")
        assert medium.base == "red_cotton" and medium.dye_weight_percent == pytest.approx(4.25) and medium.seed == 5
    finally:
        path.unlink()


# -- lifecycle ------------------------------------------------------------------------------------


def test_register_and_unregister_twice(addon, scene):
    module = sys.modules[EXTENSION_MODULE]
    shipped = str(_shipped("clothlight_weave")[0].parent)
    for _ in range(2):
        module.unregister()
        assert not hasattr(bpy.types, "CLOTHLIGHT_OT_build_sample") and not hasattr(bpy.types.Scene, "clothlight")
        assert shipped not in bpy.utils.preset_paths("clothlight_weave")
        module.register()
        assert hasattr(bpy.types, "CLOTHLIGHT_OT_build_sample") and hasattr(bpy.types.Scene, "clothlight")
    assert bpy.ops.clothlight.build_sample() == {"FINISHED"}


def test_settings_survive_saving_and_reopening_the_blend(addon, scene, tmp_path):
    settings = scene.clothlight
    settings.weave.pattern = "satin_5"
    settings.weave.spacing_mm = 0.6
    settings.medium.base = "dark_dyed_cotton"
    settings.medium.dye_weight_percent = 4.5
    settings.material_mode = "SUN"
    bpy.ops.clothlight.build_sample()
    path = tmp_path / "saved.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    bpy.ops.wm.read_homefile(use_empty=True)
    assert bpy.context.scene.clothlight.weave.pattern == "plain"
    bpy.ops.wm.open_mainfile(filepath=str(path))
    settings = bpy.context.scene.clothlight
    assert settings.weave.pattern == "satin_5" and settings.weave.spacing_mm == pytest.approx(0.6)
    assert settings.medium.base == "dark_dyed_cotton" and settings.medium.dye_weight_percent == pytest.approx(4.5)
    assert settings.material_mode == "SUN"
    assert bpy.data.objects["ClothLight Sample"]["clothlight_weave"]["spacing_mm"] == pytest.approx(0.6)


# -- panels ---------------------------------------------------------------------------------------


class _Layout:
    """Stands in for UILayout in background mode (no UI there): checks every property and operator a
    panel draws exists, and records the labels."""

    def __init__(self, labels):
        self.labels = labels
        self.use_property_split = self.use_property_decorate = False
        self.emboss = "NORMAL"

    def prop(self, data, name, **_kw):
        assert name in data.bl_rna.properties, f"{type(data).__name__} has no property {name!r}"

    def operator(self, idname, **_kw):
        category, name = idname.split(".")
        assert hasattr(getattr(bpy.types, f"{category.upper()}_OT_{name}", None), "bl_idname"), idname
        return SimpleNamespace()

    def label(self, text="", **_kw):
        self.labels.append(text)

    def progress(self, factor=0.0, text="", **_kw):
        assert 0.0 <= factor <= 1.0
        self.labels.append(text)

    def popover(self, panel, **_kw):
        assert hasattr(bpy.types, panel), panel

    def row(self, **_kw):
        return self

    column = row


def _draw_panels(context) -> list:
    labels = []
    for name in ("CLOTHLIGHT_PT_main", "CLOTHLIGHT_PT_sample", "CLOTHLIGHT_PT_medium", "CLOTHLIGHT_PT_bake_settings",
                 "CLOTHLIGHT_PT_bake_grids", "CLOTHLIGHT_PT_medium_fit", "CLOTHLIGHT_PT_material",
                 "CLOTHLIGHT_PT_validation", "CLOTHLIGHT_PT_material_properties"):
        cls = getattr(bpy.types, name)
        panel = SimpleNamespace(layout=_Layout(labels))
        if hasattr(cls, "poll") and not cls.poll(context):
            continue
        cls.draw(panel, context)
        if hasattr(cls, "draw_header_preset"):
            cls.draw_header_preset(panel, context)
    return labels


def test_panels_draw_existing_properties_and_operators_and_say_where_tables_come_from(addon, scene):
    context = SimpleNamespace(scene=scene, active_object=None, window_manager=bpy.context.window_manager,
                              material=None)
    tiny(scene.clothlight.medium)
    labels = _draw_panels(context)
    assert "Shipped tables for these settings" in labels
    for pattern, cross_section, budget, mode in (("CUSTOM", "ELLIPTICAL", "PATHS", "SUN"),
                                                 ("WIF", "ROUND", "TARGET_ERROR", "GENERAL")):
        scene.clothlight.weave.pattern, scene.clothlight.weave.cross_section = pattern, cross_section
        scene.clothlight.weave.auto_crimp = pattern == "WIF"
        scene.clothlight.medium.budget, scene.clothlight.material_mode = budget, mode
        _draw_panels(context)
    scene.clothlight.medium.base = "undyed_cotton"
    assert "This medium is undyed" in _draw_panels(context)
    from clothlight.medium_settings import preset_config
    from precompute.optics.medium import preset_names
    scene.clothlight.medium.use_dye_series = True
    for name in preset_names():  # every shipped medium, the yarns of fibres in air among them
        scene.clothlight.medium.base = name
        labels = _draw_panels(context)  # raises where a panel cannot draw this medium
        in_fibres = "Dye Range: not for dye in random fibres (a dye change re-simulates)" in labels
        fibres = scene.clothlight.medium.base_config().get("fibres")
        random = fibres is not None and fibres.get("orientation", "random") == "random"
        assert in_fibres == (random and "dye" in preset_config(name))
        assert (scene.clothlight.medium.request().dye_series is None) == (in_fibres or "dye" not in preset_config(name))
    scene.clothlight.medium.use_dye_series = False
    scene.clothlight.medium.base = PREBAKED_PRESET
    tiny(scene.clothlight.medium)
    weave = scene.clothlight.weave
    weave.pattern, weave.cross_section, weave.auto_crimp = "plain", "ELLIPTICAL", False  # the default sample
    assert bpy.ops.clothlight.build_sample() == {"FINISHED"}
    bpy.ops.clothlight.apply_material()
    sample = bpy.context.active_object
    context = SimpleNamespace(scene=scene, active_object=sample, window_manager=bpy.context.window_manager,
                              material=sample.active_material)
    labels = _draw_panels(context)
    assert any(label.startswith("B/R ") for label in labels) and any("General lighting" in label for label in labels)


@pytest.mark.parametrize("name, holder", [("cancel_bake", "RunningBake"), ("cancel_cloth_bake", "RunningClothBake"),
                                          ("cancel_fit", "RunningFit")])
def test_each_cancel_button_cancels_only_its_own_running_job(addon, scene, name, holder):
    running = getattr(addon["running_jobs"], holder)
    others = [getattr(addon["running_jobs"], other) for other in ("RunningBake", "RunningClothBake", "RunningFit")
              if other != holder]
    operator = getattr(bpy.ops.clothlight, name)
    assert not operator.poll()  # nothing running: the button is greyed out
    cancelled = []
    job = SimpleNamespace(cancel=lambda: cancelled.append(name))
    running.job = job
    try:
        assert all(other.job is None for other in others)
        assert operator.poll() and operator() == {"FINISHED"}
        assert cancelled == [name]
    finally:
        running.job = None
