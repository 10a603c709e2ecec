"""Render cost of the garment material vs a Principled BSDF with sheen on the same draped cloth
(same resolution, samples, lights; CPU, Cycles' SVM: the general mode needs no OSL).  Target
(issue 10): at most 1.3x.  With and without the open weave's transparency (the light through the
gaps: it makes camera and shadow rays continue through the cloth), and the reference with the
same see-through (its alpha the cloth's coverage) for what that costs any material; and without
the light through the cloth too (transmission=False), with how much each faster option changes
the picture: the image's mean radiance against the full material's.

The cloth tables are the shipped example's (example_blends/tables/paper_2008_cloth): their grid
does not change the shader's cost (the same texture lookups), their weights do (the share of
paths that go on through the cloth)."""

import json
import pathlib
import sys
import tempfile

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

import bpy
import numpy as np

from clothlight.blender.garment.drape import draped_cloth
from clothlight.blender.garment.material import build_garment_material, cloth_tables_from_bake
from clothlight.garment.tables import SUMMARY_FILE
from clothlight.blender.materials import GENERAL_MODE
from clothlight.blender.measurement_render import configure_measurement_render, render_to_array
from render_cost import light_and_camera, principled_with_sheen, print_render_cost, read_rgb

REPO = pathlib.Path(__file__).resolve().parents[1]
out = pathlib.Path(tempfile.mkdtemp(prefix="clothlight-bench-garment-"))
cloth_dir = REPO / "example_blends" / "tables" / "paper_2008_cloth"
tables = cloth_tables_from_bake(cloth_dir)

bpy.ops.wm.read_homefile(use_empty=True)
scene = bpy.context.scene
configure_measurement_render(scene, resolution=(320, 240), samples=64)
scene.cycles.shading_system = False
scene.render.film_transparent = False
cloth, form = draped_cloth(scene)
light_and_camera(scene, (0.0, -2.4, 1.1), (1.2, 0.0, 0.0))
# What the see-through costs any material: the reference with the cloth's coverage at normal view
# as its alpha (the same share of camera and shadow rays continue through it).
see_through = principled_with_sheen()
coverage = json.loads((cloth_dir / SUMMARY_FILE).read_text())["coverage_normal"]["front"]
see_through.node_tree.nodes["Principled BSDF"].inputs["Alpha"].default_value = coverage
materials = {
    "Principled + sheen, alpha = coverage": see_through,
    "garment": build_garment_material(tables, "garment", mode=GENERAL_MODE, uv_map="UVMap"),
    "garment, no open weave": build_garment_material(tables, "garment opaque", mode=GENERAL_MODE, uv_map="UVMap",
                                                     open_weave=False),
    "garment, no transmission": build_garment_material(tables, "garment no transmission", mode=GENERAL_MODE,
                                                       uv_map="UVMap", open_weave=False, transmission=False),
}
print_render_cost(scene, cloth, materials, out)


def cloth_mask() -> np.ndarray:
    """Pixels that see only the cloth: it emits a colour nothing else in the scene has."""
    marker = (0.123, 0.987, 0.456)
    material = bpy.data.materials.new("marker")
    material.node_tree.nodes.clear()
    emission = material.node_tree.nodes.new("ShaderNodeEmission")
    emission.inputs["Color"].default_value = (*marker, 1.0)
    output = material.node_tree.nodes.new("ShaderNodeOutputMaterial")
    material.node_tree.links.new(emission.outputs[0], output.inputs["Surface"])
    cloth.data.materials.clear()
    cloth.data.materials.append(material)
    return np.all(np.abs(render_to_array(scene, out / "mask.exr")[..., :3] - marker) < 1e-4, axis=-1)


mask = cloth_mask()
full = read_rgb(out / "garment.exr")[mask].mean(axis=0)
print(f"cloth pixels: {mask.mean():.0%} of the image")
for label in materials:
    ratio = read_rgb(out / f"{label}.exr")[mask].mean(axis=0) / full
    print(f"{label:36s} the cloth's mean radiance / the full garment's: {np.array2string(ratio, precision=3)}")
