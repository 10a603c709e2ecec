"""Renders of the woven close-up sample at the preset's twist and untwisted, side by side, under the
same grazing light (issue 43, twist; docs/twist.md).

The sample is the close-up (``sheeting_weave``, the ``voided_red_cotton`` preset's two plies and
irregularity; its section that of the crossings all along, ``TWIST_SAMPLE``), 8 × 8 yarns, seen from
straight above through an orthographic camera (2.4 mm across), lit by a sun 15° above the cloth
from −y, across the warps (which run left to right): the lighting ``"light 15° from −y, view from
above"`` of :data:`clothlight.weave.twist_highlight.LIGHTINGS`.  Its material shows the helix of
fibres of Irawan & Marschner's model (clothlight.weave.twist_highlight):
a dark red Principled BSDF whose specular lobe is anisotropic along the mesh's helical lines (the
tangent of its ``YarnUV`` map's u, the arc length along the yarn; roughness 0.3, anisotropy 0.9),
so that its glints streak along the lines.  Cycles, CPU, two threads, no denoising, fixed seed.
Writes ``twist_24deg.png``, ``twist_0deg.png`` and the two side by side, ``twist_side_by_side.png``,
and prints the prediction against the measurement on each sample's mesh and the tilt of the
render's streaks (docs/twist.md).

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

from clothlight.blender.sample_object import build_sample_object
from clothlight.mesh_attributes import YARN_UV
from clothlight.weave import build_woven_mesh
from clothlight.weave.closeup import sheeting_weave
from clothlight.weave.twist_highlight import (
    LIGHTINGS,
    TWIST_SAMPLE,
    measure_highlights,
    predicted_highlights,
    streak_tilts_in_image,
)
from precompute.optics.medium import load_preset

PRESET = "voided_red_cotton"
ELEVATION_DEG = 15.0
LIGHT, VIEW = LIGHTINGS["light 15° from −y, view from above"]     # the sun's and the camera's below


def fibre_material():
    """Dark red, its specular lobe anisotropic along the helical lines of the sample's mesh."""
    material = bpy.data.materials.new("specular fibres along the helix")
    nodes, links = material.node_tree.nodes, material.node_tree.links
    bsdf = nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (0.12, 0.01, 0.01, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.3
    bsdf.inputs["Anisotropic"].default_value = 0.9
    tangent = nodes.new("ShaderNodeTangent")
    tangent.direction_type = "UV_MAP"
    tangent.uv_map = YARN_UV
    links.new(tangent.outputs["Tangent"], bsdf.inputs["Tangent"])
    return material


def twist_scene(pixels: int, samples: int):
    """An empty scene with the sun, the camera and the render settings above; returns (scene, material)."""
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.seed = 0
    scene.render.threads_mode = "FIXED"
    scene.render.threads = 2
    scene.render.resolution_x = scene.render.resolution_y = pixels
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
    return scene, fibre_material()


def render_sample(scene, material, twist_angle_deg: float, path: pathlib.Path) -> np.ndarray:
    """Render the preset's close-up sample (8 × 8 yarns) at a twist angle (degrees) to the PNG
    ``path``; returns its pixels (H, W, 4), bottom row first, display values in [0, 1]."""
    params = sheeting_weave(PRESET, twist_angle_deg=twist_angle_deg, warp_count=8, weft_count=8, **TWIST_SAMPLE)
    sample = build_sample_object(params, name=f"sample at {twist_angle_deg:g} deg")
    sample.data.materials.append(material)
    for obj in scene.objects:
        if obj.type == "MESH":
            obj.hide_render = obj is not sample
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(str(path))
    width, height = image.size
    values = np.empty(width * height * 4, dtype=np.float32)
    image.pixels.foreach_get(values)
    bpy.data.images.remove(image)
    return values.reshape(height, width, 4)


def main():
    def option(name, default):
        return type(default)(sys.argv[sys.argv.index(name) + 1]) if name in sys.argv else default

    pixels, samples = option("--pixels", 320), option("--samples", 32)
    out = pathlib.Path(option("--out", "") or tempfile.mkdtemp(prefix="clothlight-twist-")).resolve()
    out.mkdir(parents=True, exist_ok=True)
    scene, material = twist_scene(pixels, samples)
    twist = load_preset(PRESET).yarn.twist_angle_deg
    images = []
    for angle in (twist, 0.0):
        images.append(render_sample(scene, material, angle, out / f"twist_{angle:g}deg.png"))
        # the prediction against the measurement on the same sample's mesh, finely swept
        fine = sheeting_weave(PRESET, twist_angle_deg=angle, warp_count=8, weft_count=8, segments_per_crossing=32,
                              segments_around=24, **TWIST_SAMPLE)
        found = measure_highlights(build_woven_mesh(fine), fine, LIGHT, VIEW)
        phase, predicted = predicted_highlights(found, LIGHT, VIEW, angle, fine.cross_section_mm)
        has = ~np.isnan(phase)
        measured = found["tilt_deg"][has] if has.any() else found["tilt_deg"]
        print(f"twist {angle:4.1f}°: on the mesh, {len(phase)} highlight crossings ({has.mean():.1%} with a "
              f"predicted highlight): streak tilt measured {measured.mean():6.2f}°, predicted "
              f"{predicted[has].mean() if has.any() else 0.0:6.2f}°")
        tilts = streak_tilts_in_image(images[-1])
        low, median, high = np.percentile(tilts, [25, 50, 75])
        print(f"twist {angle:4.1f}°: in the render, {len(tilts)} highlight streaks on the warps: tilt median "
              f"{median:6.2f}°, quartiles {low:6.2f}° … {high:6.2f}°")
    gap = np.ones((pixels, 8, 4), dtype=np.float32)
    joined = np.concatenate([images[0], gap, images[1]], axis=1)
    side = bpy.data.images.new("side by side", joined.shape[1], joined.shape[0], alpha=True)
    side.pixels.foreach_set(joined.ravel())
    side.filepath_raw = str(out / "twist_side_by_side.png")
    side.file_format = "PNG"
    side.save()
    print(f"renders: {out}")


if __name__ == "__main__":
    main()
