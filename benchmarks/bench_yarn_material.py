"""Render cost of the yarn material vs a Principled BSDF with sheen on the same woven mesh
(same resolution, samples, lights; CPU).  Target (issue 7): at most 2x."""

import pathlib
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

import bpy  # noqa: E402

from clothlight.materials import GENERAL_MODE, SUN_MODE, build_yarn_material, sync_sun  # noqa: E402
from clothlight.measurement_render import configure_measurement_render  # noqa: E402
from clothlight.sample_object import build_sample_object  # noqa: E402
from clothlight.weave import WeaveParameters  # noqa: E402
from clothlight.yarn_tables import yarn_tables_from_bake  # noqa: E402
from precompute.bake import bake  # noqa: E402

out = pathlib.Path(tempfile.mkdtemp(prefix="clothlight-bench-material-"))
tables = yarn_tables_from_bake(bake("red_cotton", ["transport.angular_resolution=8", "transport.incidence_resolution=8"],
                                    paths_per_cell=500, cache_dir=out / "cache").folder)

bpy.ops.wm.read_homefile(use_empty=True)
scene = bpy.context.scene
configure_measurement_render(scene, resolution=(160, 160), samples=16)
world = bpy.data.worlds.new("grey")
world.color = (0.3, 0.3, 0.3)
scene.world = world
sample = build_sample_object(WeaveParameters(warp_count=12, weft_count=12))
sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
sun.data.energy = 3.0
sun.rotation_euler = (0.6, 0.2, 0.0)
scene.collection.objects.link(sun)
camera = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
camera.location = (0.0, -4.0, 3.0)
camera.rotation_euler = (0.93, 0.0, 0.0)
scene.collection.objects.link(camera)
scene.camera = camera

principled = bpy.data.materials.new("Principled sheen")
node = principled.node_tree.nodes["Principled BSDF"]
node.inputs["Base Color"].default_value = (0.5, 0.02, 0.03, 1.0)
node.inputs["Sheen Weight"].default_value = 1.0
node.inputs["Roughness"].default_value = 0.8
materials = {"Principled BSDF + sheen": principled,
             "yarn, general lighting": build_yarn_material(tables, "yarn general", mode=GENERAL_MODE),
             "yarn, sun mode": build_yarn_material(tables, "yarn sun", mode=SUN_MODE)}
sync_sun(materials["yarn, sun mode"], sun)

timings = {}
for label, material in materials.items():
    sample.data.materials.clear()
    sample.data.materials.append(material)
    scene.render.filepath = str(out / f"{label}.exr")
    bpy.ops.render.render(write_still=True)  # warm-up: shader compile, BVH
    start = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    timings[label] = time.perf_counter() - start
reference = timings["Principled BSDF + sheen"]
for label, seconds in timings.items():
    print(f"{label:28s} {seconds:6.2f} s   {seconds / reference:4.2f}x")
