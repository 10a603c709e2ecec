"""Generate the example .blend files in ``example_blends/`` (re-run it for a new Blender version):

    python scripts/make_example_blends.py                  # Blender as a Python module (the venv)
    blender -b -P scripts/make_example_blends.py           # the same in a real Blender 5.0

* ``paper_sample_validation.blend`` — the paper's sample (§3.1: plain-woven red cotton, 12 × 12
  yarns of 0.1 mm radius at 0.5 mm) lit by one sun, its yarn material in sun mode (the baked BRDF
  evaluated exactly, §5), and the virtual gonioreflectometer of §4 in the scene "ClothLight
  Gonioreflectometer": a copy of the sample, a sun at θi = 30° and an orthographic camera at
  θv = 0°, framed and set up for measurement (Cycles OSL on the CPU, no denoising, linear EXR).
* ``twill_closeup_general.blend`` — the ``voided_red_cotton`` close-up woven as a 2/2 twill (12 × 12
  yarns, plies, twist, irregularity and flyaway fibres as in ``closeup_red_cotton.blend``) in its
  general-mode yarn material (lobe table packed) under a physical sky: sun and sky light from every
  direction, as an HDRI would give, with a macro lens's shallow focus band.
* ``closeup_red_cotton.blend`` — the close-up (``sheeting_weave("voided_red_cotton")``: 2-ply
  yarns twisted at the preset's 24°, seeded irregularity, sheeting density, flyaway fibres in the
  hair BSDF of the preset's dye) in the fitted ``voided_red_cotton`` yarn material, general mode (plain
  nodes, its lobe table packed), beside a Principled BSDF with sheen on the same geometry; scene
  "Front-Lit" (sun and sky from the front) and scene "Back-Lit" (a window-sized area light behind
  the cloth), sharing the cloth's collection.  8 × 8 yarns, so that the file stays small.
* ``closeup_denim_twill.blend`` — the same close-up as denim: ``sheeting_weave("indigo_cotton",
  interlacing="twill_3_1")``, a warp-faced 3/1 twill of an indigo warp, the fitted ``indigo_cotton``
  yarn (MERL's blue-fabric), and an ecru weft, ``ecru_cotton`` (MERL's white-fabric): plies, twist, irregularity and
  fibres, each face in its own yarn's material (slot 0 the warp's, 1 the weft's; both lobe tables
  packed; the fibres all in the warp's hair BSDF), beside Principled+sheen of each yarn's own albedo;
  the same two scenes, a stop brighter.
  ``--denim-only`` writes it alone, ``--render-denim DIR`` renders its pictures.

``paper_sample_validation.blend`` is the paper's own case: it reads the ``paper_2008`` preset's tables
from ``example_blends/tables/paper_2008/`` through ``//``-relative paths, so the folder can be moved as
a whole; the OSL shaders are embedded with their compiled bytecode.  The tables are the untouched
preset's bake (``python -m precompute bake --preset paper_2008``; cached, so a re-run bakes nothing
new).  The others use the fitted presets (``voided_red_cotton``, ``indigo_cotton``, ``ecru_cotton``), their
lobe tables packed in the file.  The garment example, the fitted presets draped, is
``scripts/make_garment_example.py``'s.  Scenes are in millimetres
(``unit_settings.scale_length = 0.001``): one Blender unit is one millimetre of cloth.
"""

from __future__ import annotations

import argparse
import math
import pathlib
import shutil
import sys
from dataclasses import dataclass

REPO_ROOT = pathlib.Path(__file__).resolve().parents[1]
if str(REPO_ROOT) not in sys.path:  # a development script: the installed extension never does this
    sys.path.insert(0, str(REPO_ROOT))

import bpy  # noqa: E402
from mathutils import Vector  # noqa: E402

from clothlight.jobs import BakeJob  # noqa: E402
from clothlight.medium_settings import preset_request  # noqa: E402
from clothlight.blender.materials import GENERAL_MODE, SUN_MODE, build_yarn_material, sync_sun  # noqa: E402
from clothlight.blender.reference_material import principled_sheen  # noqa: E402
from clothlight.blender.render_setup import use_cycles_osl_on_cpu  # noqa: E402
from clothlight.blender.sample_object import build_sample_object  # noqa: E402
from clothlight.blender.sun_link import SUN_PROPERTY  # noqa: E402
from clothlight.blender.validation.rig import RigSettings, build_rig  # noqa: E402
from clothlight.weave import WeaveParameters  # noqa: E402
from clothlight.yarn_tables import yarn_tables_from_bake  # noqa: E402

PRESET = "paper_2008"
TABLE_FILES = ("brdf.exr", "lobes.exr", "unscattered.exr", "summary.json")
# Coarser tessellation than the default for the sample seen whole: the files stay small.
PAPER_WEAVE = WeaveParameters(interlacing="plain", warp_count=12, weft_count=12, spacing_mm=0.5, yarn_radius_mm=0.1,
                              segments_per_crossing=6, segments_around=8)


def example_tables(out_dir: pathlib.Path, preset: str = PRESET) -> pathlib.Path:
    """The ``preset``'s yarn tables copied next to the blends (baked, or found in the bake cache)."""
    from precompute.cache import entries as cache

    job = BakeJob(preset_request(preset), cache_dir=cache.default_cache_dir())
    outcome = job.wait(on_progress=lambda f: print(f"\rbaking {preset}: {f:.0%}", end="", file=sys.stderr))
    print(file=sys.stderr)
    folder = out_dir / "tables" / preset
    folder.mkdir(parents=True, exist_ok=True)
    for name in TABLE_FILES:
        shutil.copy2(outcome.folder / name, folder / name)
    return folder


def relative_tables(material, blend_dir: pathlib.Path) -> None:
    """Point a ClothLight material's table sockets at ``//``-relative paths (valid wherever the
    folder goes)."""
    for node in material.node_tree.nodes:
        if node.type == "SCRIPT":
            for socket in node.inputs:
                if socket.name.endswith("Table") and socket.default_value:
                    path = pathlib.Path(socket.default_value)
                    socket.default_value = "//" + path.relative_to(blend_dir).as_posix()


def millimetre_scene(scene) -> None:
    scene.unit_settings.system = "METRIC"
    scene.unit_settings.scale_length = 0.001
    scene.unit_settings.length_unit = "MILLIMETERS"
    use_cycles_osl_on_cpu(scene)


def add_sun(scene, name: str, direction, irradiance: float = 10.0):
    """A sun whose light arrives from ``direction`` (pointing toward the sun), of ``irradiance`` W/m²."""
    light = bpy.data.lights.new(name, "SUN")
    light.energy = irradiance
    light.angle = math.radians(0.53)
    sun = bpy.data.objects.new(name, light)
    sun.rotation_euler = Vector((0, 0, 1)).rotation_difference(Vector(direction).normalized()).to_euler()
    scene.collection.objects.link(sun)
    return sun


def add_camera(scene, name: str, location, target, lens_mm: float = 50.0):
    camera = bpy.data.objects.new(name, bpy.data.cameras.new(name))
    camera.data.lens = lens_mm
    camera.data.clip_start = 0.1
    camera.data.clip_end = 1000.0
    camera.location = location
    camera.rotation_euler = (Vector(target) - Vector(location)).to_track_quat("-Z", "Y").to_euler()
    scene.collection.objects.link(camera)
    scene.camera = camera
    return camera


def fresh_file() -> None:
    bpy.ops.wm.read_homefile(use_empty=True)


def save(path: pathlib.Path) -> None:
    bpy.context.preferences.filepaths.save_version = 0  # regenerated files need no .blend1 backups
    bpy.ops.wm.save_as_mainfile(filepath=str(path), compress=True, relative_remap=True)
    print(path)


def paper_sample_validation(out_dir: pathlib.Path, tables_dir: pathlib.Path) -> pathlib.Path:
    fresh_file()
    scene = bpy.context.scene
    scene.name = "Paper Sample"
    millimetre_scene(scene)
    scene.cycles.samples = 64
    scene.render.resolution_x = scene.render.resolution_y = 512
    tables = yarn_tables_from_bake(tables_dir)
    sample = build_sample_object(PAPER_WEAVE, collection=scene.collection)
    sun = add_sun(scene, "Sun", (-math.sin(math.radians(30)), 0.0, math.cos(math.radians(30))))
    material = build_yarn_material(tables, "ClothLight Red Cotton Sun", mode=SUN_MODE)
    material[SUN_PROPERTY] = sun
    bpy.context.view_layer.update()
    sync_sun(material, sun)
    sample.data.materials.append(material)
    add_camera(scene, "Camera", (0.0, -9.0, 9.0), (0.0, 0.0, 0.0))
    scene.world = None  # sun mode: the material sees only its sun

    rig = build_rig(sample, RigSettings(incidences_deg=(30.0,), views_deg=(0.0,), resolution=128, samples=16))
    rig_material = build_yarn_material(tables, "ClothLight Red Cotton Gonioreflectometer", mode=SUN_MODE)
    rig_material[SUN_PROPERTY] = rig.sun
    rig.use_material(rig_material)
    rig.set_incidence(30.0)
    rig.set_view(0.0)
    for blend_material in (material, rig_material):
        relative_tables(blend_material, out_dir)
    path = out_dir / "paper_sample_validation.blend"
    save(path)
    return path


CLOSEUP_PRESET = "voided_red_cotton"
#: Yarns each way in the close-up examples: half the default's 16, so the .blend stays small.
CLOSEUP_YARNS = 8
#: Yarns each way in the twill close-up: the most whose file stays a few MB, seen at an angle through a
#: 75 mm lens that keeps its sides out of the picture.
TWILL_YARNS = 12
#: Names of the close-up examples' scenes (tests read them).
FRONT_LIT, BACK_LIT = "Front-Lit", "Back-Lit"
#: The Principled copy's offset along x (mm): the 8 × 8 sample at 0.40 mm is 3.2 mm wide.
CLOSEUP_OFFSET_MM = 3.6


def physical_sky_world(name: str, *, sun_elevation_deg: float, sun_rotation_deg: float,
                       strength: float) -> bpy.types.World:
    """A world of Blender's physical sky (multiple scattering) with its sun at these angles (degrees).
    The sky is in absolute units (the sun is tens of thousands of W/m²): ``strength`` scales it to a
    daylight exposure where the cloth's linear values sit in the display range."""
    world = bpy.data.worlds.new(name)
    tree = world.node_tree
    tree.nodes.clear()
    sky = tree.nodes.new("ShaderNodeTexSky")
    sky.sky_type = "MULTIPLE_SCATTERING"
    sky.sun_elevation = math.radians(sun_elevation_deg)
    sky.sun_rotation = math.radians(sun_rotation_deg)
    background = tree.nodes.new("ShaderNodeBackground")
    background.inputs["Strength"].default_value = strength
    output = tree.nodes.new("ShaderNodeOutputWorld")
    tree.links.new(sky.outputs["Color"], background.inputs["Color"])
    tree.links.new(background.outputs["Background"], output.inputs["Surface"])
    return world


def uniform_world(name: str, color) -> bpy.types.World:
    """A world of one linear ``color`` (radiance, W/(m²·sr) per unit strength) from every direction:
    set on its Background node, since Blender 5's worlds render their node tree, not ``World.color``."""
    world = bpy.data.worlds.new(name)
    world.color = color
    if world.node_tree is None:
        world.use_nodes = True
    background = next(node for node in world.node_tree.nodes if node.type == "BACKGROUND")
    background.inputs["Color"].default_value = (*color, 1.0)
    return world


@dataclass(frozen=True)
class CloseupExample:
    """One close-up example blend: ``sheeting_weave(preset)`` woven as ``interlacing``, in the preset's
    general-mode yarn material named ``material_name``, beside Principled+sheen of ``principled_colour``
    (linear RGB; None: the bake's hemispherical albedo at normal incidence, :func:`yarn_albedo_colour`);
    ``exposure`` (stops) for both of its scenes."""

    preset: str
    stem: str
    material_name: str
    principled_colour: tuple[float, float, float] | None = None
    interlacing: str = "plain"
    exposure: float = 0.0
    #: A weft of another yarn (None: the warp's): its preset, its yarn material's name and its
    #: Principled twin's; each face of the mesh takes the material of the yarn it belongs to (the fibres the warp's).
    weft_preset: str | None = None
    weft_material_name: str = ""


RED_COTTON_CLOSEUP = CloseupExample(CLOSEUP_PRESET, "closeup_red_cotton", "ClothLight Red Cotton",
                                    principled_colour=(0.5, 0.02, 0.03))  # benchmarks/render_cost.py's reference
#: Denim: a warp-faced 3/1 twill (Z, the diagonal rising to the right) of an indigo warp, the indigo_cotton preset's
#: yarn fitted to MERL's blue-fabric, and an ecru weft, ecru_cotton (fitted to MERL's warm white-fabric the
#: same way): blue face, pale back; its Principled copy gets each yarn's own albedo.  A dark face: both scenes a
#: stop up.  (undyed_cotton, the paper's medium without dye, is nearly clear: its unscattered light needs the OSL
#: shader, which reads its tables by path, not packed, and not under SVM.)
DENIM_TWILL_CLOSEUP = CloseupExample("indigo_cotton", "closeup_denim_twill", "ClothLight Denim Warp (Indigo Cotton)",
                                     interlacing="twill_3_1", exposure=1.0, weft_preset="ecru_cotton",
                                     weft_material_name="ClothLight Denim Weft (Ecru Cotton)")
#: The Principled+sheen twin's material(s): one, or the warp's and the weft's for a weft of another yarn.
PRINCIPLED_NAME = "Principled BSDF + Sheen"


def yarn_albedo_colour(folder: pathlib.Path) -> tuple[float, float, float]:
    """The hemispherical albedo (linear RGB) of a bake's yarn lit along its normal: the centre cell
    of ``albedo.exr`` (the odd incidence grid puts the normal on a cell's centre, docs/table-spec.md)."""
    from precompute.tables.exr import read_table

    pixels = read_table(folder / "albedo.exr", kind="albedo").pixels
    rows, columns = pixels.shape[:2]
    return tuple(float(value) for value in pixels[rows // 2, columns // 2, :3])


def packed_yarn_material(tables, name: str):
    """The general-mode yarn material of ``tables`` (plain nodes, its tables packed in the file), with
    nothing in it that names this machine: a packed image's path is its file's name (``//lobes.exr``,
    ``//unscattered.exr``) and the material does not record its bake folder (a cache path here,
    meaningless wherever the blend goes)."""
    from clothlight.blender.materials import TABLES_PROPERTY

    material = build_yarn_material(tables, name, mode=GENERAL_MODE, plain_nodes=True)  # SVM; refuses OSL
    for node in material.node_tree.nodes:
        if node.type == "TEX_IMAGE" and node.image is not None and node.image.packed_file is not None:
            node.image.filepath_raw = "//" + pathlib.PurePath(node.image.filepath_raw).name
    if TABLES_PROPERTY in material:
        del material[TABLES_PROPERTY]
    return material


def baked_yarn(preset: str) -> pathlib.Path:
    """The bake folder of ``preset``'s yarn tables (baked, or found in the bake cache)."""
    from precompute.cache import entries as cache

    baked = BakeJob(preset_request(preset), cache_dir=cache.default_cache_dir()).wait(
        on_progress=lambda f: print(f"\rbaking {preset}: {f:.0%}", end="", file=sys.stderr))
    print(file=sys.stderr)
    return baked.folder


def weft_material_indices(sample) -> None:
    """Material index 1 for each face of the sample whose yarn is a weft (``is_warp`` 0 on its vertices;
    a face belongs to one yarn)."""
    import numpy as np

    from clothlight.mesh_attributes import IS_WARP

    mesh = sample.data
    is_warp = np.empty(len(mesh.vertices), np.int32)
    mesh.attributes[IS_WARP].data.foreach_get("value", is_warp)
    corner_vert = np.empty(len(mesh.loops), np.int32)
    mesh.attributes[".corner_vert"].data.foreach_get("value", corner_vert)
    loop_start = np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("loop_start", loop_start)
    mesh.polygons.foreach_set("material_index", np.where(is_warp[corner_vert[loop_start]] != 0, 0, 1).astype(np.int32))
    mesh.update()


def closeup_scene(scene, cloth, exposure: float) -> None:
    """A close-up example's scene: millimetres, plain nodes under SVM, 640 × 320, 64 samples, denoised,
    showing the collection ``cloth``."""
    millimetre_scene(scene)
    scene.cycles.shading_system = False  # the general mode is plain nodes: SVM, GPUs welcome
    scene.cycles.samples = 64
    scene.cycles.use_denoising = True
    scene.render.resolution_x, scene.render.resolution_y = 640, 320
    scene.view_settings.exposure = exposure
    if cloth.name not in scene.collection.children:
        scene.collection.children.link(cloth)


def closeup_example(out_dir: pathlib.Path, example: CloseupExample) -> pathlib.Path:
    """A close-up with flyaway fibres in ClothLight's general mode (left) and in a Principled BSDF
    with sheen (right, the same mesh and fibres), front-lit (scene FRONT_LIT) and back-lit (BACK_LIT),
    written as ``out_dir/<example.stem>.blend``."""
    from clothlight.blender.flyaway_object import build_flyaway_object
    from clothlight.weave.closeup import closeup_settings, sheeting_weave
    from precompute.optics.medium import load_preset_config

    fresh_file()
    front = bpy.context.scene
    front.name = FRONT_LIT
    cloth = bpy.data.collections.new("Cloth")
    closeup_scene(front, cloth, example.exposure)

    params = sheeting_weave(example.preset, interlacing=example.interlacing,
                            warp_count=CLOSEUP_YARNS, weft_count=CLOSEUP_YARNS)
    sample = build_sample_object(params, collection=cloth)
    sample.name = "ClothLight Sample"
    settings = closeup_settings(load_preset_config(example.preset)[0])
    fibres = build_flyaway_object(sample, params, settings, example.preset, collection=cloth)
    # The general mode packs its lobe table in the file: no table folder travels with this blend.
    baked = baked_yarn(example.preset)
    sample.data.materials.clear()
    sample.data.materials.append(packed_yarn_material(yarn_tables_from_bake(baked), example.material_name))
    principled = [principled_sheen(PRINCIPLED_NAME, example.principled_colour or yarn_albedo_colour(baked))]
    # Slot 1, the weft's: its yarn material and its Principled twin's.  The fibres keep the warp's hair
    # material: Cycles (5.0) renders a hair-curves object in its first material whatever the curves'
    # material_index, so the weft's fibres would need an object of their own.
    if example.weft_preset:
        weft_baked = baked_yarn(example.weft_preset)
        sample.data.materials.append(packed_yarn_material(yarn_tables_from_bake(weft_baked),
                                                          example.weft_material_name))
        principled[0].name = f"{PRINCIPLED_NAME} Warp"
        principled.append(principled_sheen(f"{PRINCIPLED_NAME} Weft", yarn_albedo_colour(weft_baked)))
        weft_material_indices(sample)
    sample.location.x = -CLOSEUP_OFFSET_MM / 2

    # The reference shares the mesh data; its materials are the objects' own.
    for original in (sample, fibres):
        twin = original.copy()
        twin.name = original.name.replace("ClothLight", "Principled") if "ClothLight" in original.name \
            else f"{original.name} Principled"
        cloth.objects.link(twin)
        for slot, material in zip(twin.material_slots, principled):  # the fibres: the warp's, as above
            slot.link = "OBJECT"
            slot.material = material
        if original is sample:
            sample_twin = twin
        else:
            twin.parent = sample_twin
    sample_twin.location.x = CLOSEUP_OFFSET_MM / 2

    add_sun(front, "Sun", (0.3, -0.8, 0.6), irradiance=3.0)
    add_camera(front, "Camera", (0.0, -6.0, 5.0), (0.0, 0.0, 0.0), lens_mm=50.0)
    front.world = uniform_world("Sky", (0.25, 0.3, 0.4))  # a blue-grey sky from every direction

    back = bpy.data.scenes.new(BACK_LIT)
    closeup_scene(back, cloth, example.exposure)
    # A window behind the cloth (below it, facing the camera through it): the yarns glow.
    window = bpy.data.objects.new("Window", bpy.data.lights.new("Window", "AREA"))
    window.data.energy = 600.0  # W over 96 mm² about 4 mm behind the cloth: what gets through glows
    window.data.shape = "RECTANGLE"
    window.data.size, window.data.size_y = 12.0, 8.0
    window.location = (0.0, 3.0, -3.0)
    window.rotation_euler = (Vector((0.0, 0.0, 0.0)) - window.location).to_track_quat("-Z", "Y").to_euler()
    back.collection.objects.link(window)
    add_camera(back, "Camera Back-Lit", (0.0, -6.0, 5.0), (0.0, 0.0, 0.0), lens_mm=50.0)
    back.world = uniform_world("Dark Room", (0.01, 0.01, 0.012))
    path = out_dir / f"{example.stem}.blend"
    save(path)
    return path


def closeup_red_cotton(out_dir: pathlib.Path) -> pathlib.Path:
    """The default red-cotton close-up (plain sheeting) with flyaway fibres, beside Principled+sheen."""
    return closeup_example(out_dir, RED_COTTON_CLOSEUP)


def closeup_denim_twill(out_dir: pathlib.Path) -> pathlib.Path:
    """The denim close-up: a warp-faced 3/1 twill of an indigo warp (the fitted indigo_cotton yarn) and an
    ecru weft (ecru_cotton), beside Principled+sheen."""
    return closeup_example(out_dir, DENIM_TWILL_CLOSEUP)


def twill_closeup_general(out_dir: pathlib.Path) -> pathlib.Path:
    """A 2/2 twill of the default yarn close up (``sheeting_weave(CLOSEUP_PRESET)`` woven as a twill, with
    its flyaway fibres) in the general mode under a physical sky, with a shallow focus band."""
    from clothlight.blender.flyaway_object import build_flyaway_object
    from clothlight.weave.closeup import closeup_settings, sheeting_weave
    from precompute.optics.medium import load_preset_config

    fresh_file()
    scene = bpy.context.scene
    scene.name = "Twill Close-Up"
    millimetre_scene(scene)
    scene.cycles.shading_system = False  # the general mode is plain nodes: SVM, GPUs welcome
    scene.cycles.samples = 128
    scene.render.resolution_x, scene.render.resolution_y = 640, 400
    params = sheeting_weave(CLOSEUP_PRESET, interlacing="twill_2_2", warp_count=TWILL_YARNS, weft_count=TWILL_YARNS)
    sample = build_sample_object(params, collection=scene.collection)
    build_flyaway_object(sample, params, closeup_settings(load_preset_config(CLOSEUP_PRESET)[0]), CLOSEUP_PRESET,
                         collection=scene.collection)
    sample.data.materials.clear()
    sample.data.materials.append(packed_yarn_material(yarn_tables_from_bake(baked_yarn(CLOSEUP_PRESET)),
                                                      RED_COTTON_CLOSEUP.material_name))
    camera = add_camera(scene, "Camera", (0.0, -6.0, 3.2), (0.0, 0.0, 0.0), lens_mm=75.0)
    camera.data.dof.use_dof = True
    camera.data.dof.focus_distance = (camera.location - Vector((0.0, 0.0, 0.0))).length
    camera.data.dof.aperture_fstop = 0.6  # f-number of a macro shot at this scale: a shallow focus band

    scene.world = physical_sky_world("Sky", sun_elevation_deg=35.0, sun_rotation_deg=120.0, strength=0.1)
    path = out_dir / "twill_closeup_general.blend"
    save(path)
    return path


#: The docs pictures of the close-up examples: small, since they render on a shared 2-core machine.
PICTURE_SIZE, PICTURE_SAMPLES = (320, 160), 64


def render_closeup(blend: pathlib.Path, out_dir: pathlib.Path) -> list[pathlib.Path]:
    """Render each scene of a close-up example (ClothLight left, Principled+sheen right) at
    PICTURE_SIZE pixels, PICTURE_SAMPLES samples, no denoising, into ``out_dir`` as
    ``<blend stem>_<scene>.png``; returns the PNGs."""
    bpy.ops.wm.open_mainfile(filepath=str(blend))
    out_dir.mkdir(parents=True, exist_ok=True)
    pictures = []
    for name in (FRONT_LIT, BACK_LIT):
        scene = bpy.data.scenes[name]
        scene.render.resolution_x, scene.render.resolution_y = PICTURE_SIZE
        scene.cycles.samples = PICTURE_SAMPLES
        scene.cycles.use_denoising = False
        scene.render.image_settings.file_format = "PNG"
        scene.render.filepath = str(out_dir / f"{blend.stem}_{name.lower()}.png")
        bpy.ops.render.render(write_still=True, scene=name)
        pictures.append(pathlib.Path(scene.render.filepath))
        print(scene.render.filepath)
    return pictures


#: The measurement of the close-up examples' colours (:func:`measure_closeup`): few samples, no denoising.
MEASURE_SAMPLES = 16


def measure_closeup(blend: pathlib.Path, out_dir: pathlib.Path) -> dict[str, dict[str, list[float]]]:
    """The mean linear RGB of the cloth (yarns and fibres, the world transparent) in each half of each
    scene of a close-up example, ClothLight on the left and Principled+sheen on the right, rendered at
    PICTURE_SIZE with MEASURE_SAMPLES samples into ``out_dir`` (OpenEXR, kept for a look); exposure not
    applied.  Prints them and returns {scene: {"ClothLight": rgb, "Principled": rgb}}."""
    import numpy as np

    bpy.ops.wm.open_mainfile(filepath=str(blend))
    out_dir.mkdir(parents=True, exist_ok=True)
    means = {}
    for name in (FRONT_LIT, BACK_LIT):
        scene = bpy.data.scenes[name]
        scene.render.resolution_x, scene.render.resolution_y = PICTURE_SIZE
        scene.render.resolution_percentage = 100
        scene.cycles.samples = MEASURE_SAMPLES
        scene.cycles.use_denoising = False
        scene.render.film_transparent = True
        scene.render.image_settings.file_format = "OPEN_EXR"
        scene.render.image_settings.color_depth = "32"
        scene.render.filepath = str(out_dir / f"{blend.stem}_{name.lower()}.exr")
        bpy.ops.render.render(write_still=True, scene=name)
        image = bpy.data.images.load(scene.render.filepath, check_existing=False)
        width, height = image.size
        pixels = np.array(image.pixels[:], dtype=np.float64).reshape(height, width, 4)
        bpy.data.images.remove(image)
        halves = {"ClothLight": pixels[:, : width // 2], "Principled": pixels[:, width // 2:]}
        means[name] = {side: [float(v) for v in half[half[..., 3] > 0.5, :3].mean(axis=0)]
                       for side, half in halves.items()}
        print(name, {side: [round(v, 4) for v in rgb] for side, rgb in means[name].items()})
    return means


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=pathlib.Path, default=REPO_ROOT / "example_blends")
    parser.add_argument("--closeup-only", action="store_true", help="write closeup_red_cotton.blend alone")
    parser.add_argument("--render-closeup", type=pathlib.Path, metavar="DIR",
                        help="then render its front-lit and back-lit scenes into DIR (PNG)")
    parser.add_argument("--denim-only", action="store_true", help="write closeup_denim_twill.blend alone")
    parser.add_argument("--render-denim", type=pathlib.Path, metavar="DIR",
                        help="then render its front-lit and back-lit scenes into DIR (PNG)")
    parser.add_argument("--measure", type=pathlib.Path, metavar="DIR",
                        help="then print the mean colour of the cloth in each half of each scene of the blends "
                             "written (renders in DIR, OpenEXR)")
    args = parser.parse_args(argv)
    if args.closeup_only and args.denim_only:
        parser.error("--closeup-only and --denim-only each write one blend: give one of them")
    out_dir = args.out.resolve()
    out_dir.mkdir(parents=True, exist_ok=True)
    if not args.denim_only:
        closeup = closeup_red_cotton(out_dir)
        if args.render_closeup:
            render_closeup(closeup, args.render_closeup.resolve())
        if args.measure:
            measure_closeup(closeup, args.measure.resolve())
    if not args.closeup_only:
        denim = closeup_denim_twill(out_dir)
        if args.render_denim:
            render_closeup(denim, args.render_denim.resolve())
        if args.measure:
            measure_closeup(denim, args.measure.resolve())
    if args.closeup_only or args.denim_only:
        return
    paper_sample_validation(out_dir, example_tables(out_dir))
    twill_closeup_general(out_dir)


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else None)
