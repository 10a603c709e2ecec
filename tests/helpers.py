"""What several test modules share: vectors, EXR writing, a reference BRDF, and the small scenes
the render tests are built from.  Importable without bpy: the scene helpers import it when called."""

from __future__ import annotations

import json
import math
import pathlib
import subprocess
import sys

import numpy as np
import OpenEXR

from precompute.optics.cook_torrance import cook_torrance_between as _cook_torrance_between
from precompute.optics.medium import DEFAULT_PRESET

REPO = pathlib.Path(__file__).resolve().parents[1]
#: Modules that only Blender provides.
BLENDER_ONLY = ("bpy", "mathutils", "bmesh", "bpy_extras", "bl_ui", "bl_operators", "addon_utils", "gpu")

# -- vectors and files ----------------------------------------------------------------------------


def unit(v) -> np.ndarray:
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def direction(zenith_deg: float, azimuth_deg: float) -> np.ndarray:
    """The unit vector at ``zenith_deg`` from +z and ``azimuth_deg`` from +x."""
    zenith, azimuth = math.radians(zenith_deg), math.radians(azimuth_deg)
    return np.array([math.sin(zenith) * math.cos(azimuth), math.sin(zenith) * math.sin(azimuth), math.cos(zenith)])


def write_exr(path, image) -> None:
    """An RGB float32 OpenEXR (ZIP), as the bake writes its tables; ``image`` is (rows, columns, 3)."""
    # OpenEXR reads the array's memory as C-ordered: a broadcast view must be copied out first
    image = np.ascontiguousarray(image, dtype=np.float32)
    with OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION}, {"RGB": image}) as exr:
        exr.write(str(path))


# -- table folders --------------------------------------------------------------------------------


def table_metadata(kind: str, layout: dict, cache_key: str, **extra) -> dict:
    """The metadata a ClothLight table must carry (precompute.tables.exr.REQUIRED_METADATA), for test tables."""
    return {"table": kind, "layout": layout, "code_version": "test", "cache_key": cache_key,
            "medium": {"name": "test"}, "transport": {}, "paths": {}, "colour": {}, "units": {}, **extra}


def write_yarn_table_folder(folder, brdf, lobes, unscattered, *, incidence_resolution: int, exit_resolution: int,
                            cache_key: str = "c0" * 32, host_index: float = 1.557, listed: bool = True,
                            optional: bool = True, specular: dict | None = None) -> pathlib.Path:
    """A yarn bake folder as precompute/bake.py writes one, from given images (RGB; ``brdf`` (N_i·N_o)²,
    ``lobes`` N_o × K·N_o, ``unscattered`` 1 × M): tables of this schema and of one cache key, with
    ``optional`` also brdf_stderr.exr, albedo.exr and spectral.npz, and summary.json with what readers
    use and, when ``listed``, every file's SHA-256 (folders baked before bakes listed them have none).
    ``specular``: the bake's specular record (``{"weight", "slope", "source"}``) in the headers and the
    summary; None, none (a folder baked before bakes recorded it)."""
    from precompute.tables.closure_fit import LobeShape
    from precompute.tables.folder import FILE_HASHES_KEY, SPECTRAL_FILE, SUMMARY_FILE, YARN_TABLE_FILES, file_hashes
    from precompute.tables.exr import SCHEMA, write_table

    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    n_i, n_o = incidence_resolution, exit_resolution
    brdf, lobes, unscattered = (np.ascontiguousarray(image, dtype=np.float32) for image in (brdf, lobes, unscattered))
    lobe_count, lobe_shape = lobes.shape[1] // n_o, LobeShape().to_dict()
    grid = {"incidence_resolution": n_i, "exit_resolution": n_o}
    images = {"brdf": (brdf, grid), "closure_lobes": (lobes, {**grid, "lobe_count": lobe_count}),
              "unscattered": (unscattered, {"attenuation_samples": unscattered.shape[1]})}
    if optional:
        images.update(brdf_stderr=(0.1 * brdf, grid), albedo=(brdf[::n_o, ::n_o], grid))
    recorded = {} if specular is None else {"specular": specular}
    for kind, (image, layout) in images.items():
        extra = {**recorded, "lobe_shape": lobe_shape} if kind == "closure_lobes" else recorded
        write_table(folder / YARN_TABLE_FILES[kind], image,
                    table_metadata(kind, layout, cache_key, host_index=host_index, **extra))
    spectral_key = "5" + cache_key[1:]
    if optional:
        np.savez(folder / SPECTRAL_FILE, metadata=np.array(json.dumps({"key": spectral_key})))
    summary = {"schema": SCHEMA, "cache_key": cache_key, "spectral_key": spectral_key, "incidence_resolution": n_i,
               "exit_resolution": n_o, "lobe_count": lobe_count, "lobe_shape": lobe_shape, "host_index": host_index,
               "unscattered_samples": unscattered.shape[1], **recorded}
    if listed:
        summary[FILE_HASHES_KEY] = file_hashes(folder, [*YARN_TABLE_FILES.values(), SPECTRAL_FILE])
    (folder / SUMMARY_FILE).write_text(json.dumps(summary, indent=1))
    return folder


# -- a reference BRDF -----------------------------------------------------------------------------


#: The Cook–Torrance twin lives in precompute/optics/cook_torrance.py (the fit's baseline uses it too).
cook_torrance_between = _cook_torrance_between


# -- small scenes for renders (bpy) ---------------------------------------------------------------


def empty_render_scene(*, resolution: int, samples: int, bounces: int | None = None):
    """A new empty file's scene set up for a measurement render: no world light, and at most
    ``bounces`` bounces when given."""
    import bpy

    from clothlight.blender.measurement_render import configure_measurement_render

    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    configure_measurement_render(scene, resolution=(resolution, resolution), samples=samples)
    scene.world = None
    if bounces is not None:
        scene.cycles.max_bounces = bounces
    return scene


def script_material(name: str, shader: str, source: str | None = None):
    """A material whose surface is the closure output ``BSDF`` of OSL shader ``shader`` (of ``osl/``,
    or ``source``); returns the material and its script node."""
    import bpy

    from clothlight.blender.osl_shaders import add_script_node

    material = bpy.data.materials.new(name)
    tree = material.node_tree
    tree.nodes.clear()
    node = add_script_node(tree, shader, source)
    tree.links.new(node.outputs["BSDF"], tree.nodes.new("ShaderNodeOutputMaterial").inputs["Surface"])
    return material, node


def _rotation_to(toward):
    """Quaternion turning local +Z onto ``toward`` (a camera looks, and a sun shines, along −Z)."""
    from mathutils import Vector

    return Vector((0.0, 0.0, 1.0)).rotation_difference(Vector(tuple(toward)).normalized())


def add_sun(scene, toward_sun, irradiance: float):
    """A sun of ``irradiance`` (W/m²) and no angular size, shining from ``toward_sun``."""
    import bpy

    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    sun.data.energy = irradiance
    sun.data.angle = 0.0
    scene.collection.objects.link(sun)
    sun.rotation_mode = "QUATERNION"
    sun.rotation_quaternion = _rotation_to(toward_sun)
    return sun


def add_camera(scene, toward_camera=(0.0, 0.0, 1.0), *, ortho_scale: float = 1.0, distance: float = 5.0):
    """An orthographic camera ``ortho_scale`` wide at ``distance`` along ``toward_camera``, looking
    back at the origin; made the scene's camera."""
    import bpy

    camera = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
    camera.data.type = "ORTHO"
    camera.data.ortho_scale = ortho_scale
    camera.location = tuple(distance * unit(toward_camera))
    camera.rotation_mode = "QUATERNION"
    camera.rotation_quaternion = _rotation_to(toward_camera)
    scene.collection.objects.link(camera)
    scene.camera = camera
    return camera


def add_sun_and_camera(scene, toward_sun, toward_camera, irradiance: float):
    """:func:`add_sun` and a camera 1 unit wide along ``toward_camera`` (:func:`add_camera`); returns the sun."""
    import bpy

    sun = add_sun(scene, toward_sun, irradiance)
    add_camera(scene, toward_camera)
    bpy.context.view_layer.update()
    return sun


# -- the extension zip ----------------------------------------------------------------------------

#: The preset the test build pre-bakes, and with what: the default (a fresh scene's Base Medium), tiny grids
#: and budget, are enough to test the mechanism (`make extension` pre-bakes every preset's own bake).
PREBAKED_PRESET = DEFAULT_PRESET
PREBAKED_TRANSPORT = {"paths_per_cell": 64, "n_around": 4, "n_along": 2, "angular_resolution": 4,
                      "incidence_resolution": 5}
#: The goniometer settings of its cloth pre-bake: small, to test the mechanism.
PREBAKED_CLOTH_SETTINGS = {"incidence_resolution": 3, "exit_resolution": 2, "pixels_per_patch": 6, "samples": 1}


def build_extension_zip(out: pathlib.Path) -> pathlib.Path:
    """The linux-x64 zip as `make extension` builds it, pre-baking only :data:`PREBAKED_PRESET`."""
    existing = sorted(out.glob("clothlight-*-linux_x64.zip"))
    if existing:
        return existing[0]
    result = subprocess.run(
        [sys.executable, str(REPO / "scripts" / "build_extension.py"), "--output-dir", str(out),
         "--platforms", "linux-x64", "--prebake", PREBAKED_PRESET,
         "--prebake-transport", *(f"{key}={value}" for key, value in PREBAKED_TRANSPORT.items()),
         "--prebake-cloth", *(f"{key}={value}" for key, value in PREBAKED_CLOTH_SETTINGS.items())],
        capture_output=True, text=True,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    return pathlib.Path(result.stdout.strip().splitlines()[-1])


#: The attribute that marks a fixture as slow (:func:`slow_fixture`).
SLOW_FIXTURE = "clothlight_slow_fixture"


def slow_fixture(function):
    """Mark a fixture function as slow (it bakes, builds the extension zip or the native library):
    every test that uses it is a ``slow`` test (tests/conftest.py).  Put it under ``@pytest.fixture``."""
    setattr(function, SLOW_FIXTURE, True)
    return function
