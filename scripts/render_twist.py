"""Renders of the woven close-up sample at the preset's twist and untwisted, side by side, under the
same grazing light (issue 43, twist; docs/twist.md).

The sample is the default close-up (``sheeting_weave``, the ``red_cotton`` preset's two plies and
irregularity), 8 × 8 yarns, seen from straight above through an orthographic camera (2.4 mm across),
lit by a sun 15° above the cloth from −y, across the warps (which run left to right).  Its material
is a helix of specular fibres as in Irawan & Marschner's model (clothlight.weave.twist_highlight):
a dark red Principled BSDF whose specular lobe is anisotropic along the mesh's helical lines (the
tangent of its ``YarnUV`` map's u, the arc length along the yarn), so that a point reflects where
the lines there run perpendicular to the half vector.  Cycles, CPU, two threads, no denoising.
Writes ``twist_24deg.png``, ``twist_0deg.png`` and the two side by side, ``twist_side_by_side.png``,
and prints the prediction against the measurement on each sample's mesh (docs/twist.md).

    python scripts/render_twist.py --out docs/images/twist              # 320² pixels, 32 samples
    python scripts/render_twist.py --pixels 160 --samples 8             # a quick look, in a temporary folder
"""

import math
import pathlib
import sys
import tempfile

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

import bpy
import numpy as np
from scipy import ndimage

from clothlight.blender.sample_object import build_sample_object
from clothlight.mesh_attributes import YARN_UV
from clothlight.weave import build_woven_mesh
from clothlight.weave.closeup import sheeting_weave
from clothlight.weave.twist_highlight import LIGHTINGS, measure_highlights, predicted_highlights
from precompute.optics.medium import load_preset


def option(name, default):
    return type(default)(sys.argv[sys.argv.index(name) + 1]) if name in sys.argv else default


PIXELS, SAMPLES = option("--pixels", 320), option("--samples", 32)
ANISOTROPY, ROTATION, ROUGHNESS = option("--anisotropy", 0.9), option("--rotation", 0.0), option("--roughness", 0.3)
out = pathlib.Path(option("--out", "") or tempfile.mkdtemp(prefix="clothlight-twist-")).resolve()
out.mkdir(parents=True, exist_ok=True)
PRESET = "red_cotton"
ELEVATION_DEG = 15.0
LIGHT, VIEW = LIGHTINGS["light 15° from −y, view from above"]     # the sun's and the camera's below


def streak_tilts_in_image(rgba: np.ndarray) -> np.ndarray:
    """The tilts (degrees from the image's x axis, counter-clockwise, in (−45°, 45°): the warps'
    streaks) of the highlight streaks in a render (``rgba`` bottom row first, as Blender stores it):
    each connected patch of pixels whose green exceeds 0.35 (the white highlight, not the red yarn),
    of at least 12 pixels and at least twice as long as wide, its principal axis."""
    labels, count = ndimage.label(rgba[..., 1] > 0.35)
    tilts = []
    for label in range(1, count + 1):
        rows, columns = np.nonzero(labels == label)
        if len(rows) < 12:
            continue
        spread, axes = np.linalg.eigh(np.cov(np.stack([columns - columns.mean(), rows - rows.mean()])))
        if spread[1] < 4.0 * spread[0]:
            continue
        tilt = (math.degrees(math.atan2(axes[1, 1], axes[0, 1])) + 90.0) % 180.0 - 90.0
        if abs(tilt) < 45.0:
            tilts.append(tilt)
    return np.array(tilts)


def fibre_material():
    material = bpy.data.materials.new("specular fibres along the helix")
    nodes, links = material.node_tree.nodes, material.node_tree.links
    bsdf = nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (0.12, 0.01, 0.01, 1.0)
    bsdf.inputs["Roughness"].default_value = ROUGHNESS
    bsdf.inputs["Anisotropic"].default_value = ANISOTROPY
    bsdf.inputs["Anisotropic Rotation"].default_value = ROTATION
    tangent = nodes.new("ShaderNodeTangent")
    tangent.direction_type = "UV_MAP"
    tangent.uv_map = YARN_UV
    links.new(tangent.outputs["Tangent"], bsdf.inputs["Tangent"])
    return material


bpy.ops.wm.read_homefile(use_empty=True)
scene = bpy.context.scene
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = SAMPLES
scene.cycles.use_denoising = False
scene.cycles.use_adaptive_sampling = False
scene.cycles.seed = 0
scene.render.threads_mode = "FIXED"
scene.render.threads = 2
scene.render.resolution_x = scene.render.resolution_y = PIXELS
scene.render.resolution_percentage = 100
scene.render.image_settings.file_format = "PNG"
scene.view_settings.view_transform = "Standard"
world = bpy.data.worlds.new("dark")
world.color = (0.03, 0.03, 0.03)
scene.world = world
sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
sun.data.energy = 8.0
sun.data.angle = math.radians(1.0)
sun.rotation_euler = (math.radians(90.0 - ELEVATION_DEG), 0.0, 0.0)    # shining towards +y and down
scene.collection.objects.link(sun)
camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
camera.data.type = "ORTHO"
camera.data.ortho_scale = 2.4
camera.location = (0.0, 0.0, 5.0)
scene.collection.objects.link(camera)
scene.camera = camera
material = fibre_material()

twist = load_preset(PRESET).yarn.twist_angle_deg
images = []
for angle in (twist, 0.0):
    params = sheeting_weave(PRESET, twist_angle_deg=angle, warp_count=8, weft_count=8)
    sample = build_sample_object(params, name=f"sample at {angle:g} deg")
    sample.data.materials.append(material)
    for obj in scene.objects:
        if obj.type == "MESH":
            obj.hide_render = obj is not sample
    scene.render.filepath = str(out / f"twist_{angle:g}deg.png")
    bpy.ops.render.render(write_still=True)
    images.append(scene.render.filepath)
    # the prediction against the measurement on the same sample's mesh, finely swept
    fine = sheeting_weave(PRESET, twist_angle_deg=angle, warp_count=8, weft_count=8, segments_per_crossing=32,
                          segments_around=24)
    found = measure_highlights(build_woven_mesh(fine), fine, LIGHT, VIEW)
    phase, predicted = predicted_highlights(found, LIGHT, VIEW, angle, fine.cross_section_mm)
    has = ~np.isnan(phase)
    print(f"twist {angle:4.1f}°: {len(phase)} highlight crossings, streak tilt measured "
          f"{found['tilt_deg'][has].mean() if has.any() else found['tilt_deg'].mean():6.2f}° "
          f"predicted {predicted[has].mean() if has.any() else 0.0:6.2f}° (mean over crossings with a prediction, "
          f"{has.mean():.1%} of them), |difference| median "
          f"{np.median(np.abs(found['tilt_deg'] - predicted)[has]) if has.any() else 0.0:.2f}°")

pixels = []
for angle, path in zip((twist, 0.0), images):
    image = bpy.data.images.load(path)
    width, height = image.size
    values = np.empty(width * height * 4, dtype=np.float32)
    image.pixels.foreach_get(values)
    pixels.append(values.reshape(height, width, 4))
    tilts = streak_tilts_in_image(pixels[-1])
    print(f"twist {angle:4.1f}°: the render's highlight streaks on the warps: {len(tilts)}, tilt median "
          f"{np.median(tilts):6.2f}°, quartiles {np.percentile(tilts, 25):6.2f}° … {np.percentile(tilts, 75):6.2f}°")
gap = np.ones((PIXELS, 8, 4), dtype=np.float32)
joined = np.concatenate([pixels[0], gap, pixels[1]], axis=1)
side = bpy.data.images.new("side by side", joined.shape[1], joined.shape[0], alpha=True)
side.pixels.foreach_set(joined.ravel())
side.filepath_raw = str(out / "twist_side_by_side.png")
side.file_format = "PNG"
side.save()
print(f"renders: {out}")
