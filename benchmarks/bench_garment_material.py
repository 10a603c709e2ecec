"""Render cost of the garment material vs a Principled BSDF with sheen on the same draped cloth
(same resolution, samples, lights; CPU, Cycles' SVM: the general mode needs no OSL).  Target
(issue 10): at most 1.3x.  With and without the open weave's transparency (the light through the
gaps: it makes camera and shadow rays continue through the cloth), and the reference with the
same see-through (its alpha the cloth's coverage) for what that costs any material; and without
the light through the cloth too (transmission=False), with how much each faster option changes
the picture: the image's mean radiance against the full material's.  The garment is also timed
against the see-through reference (like with like: both let the same share of light through).

``--basis-lobes K``: also times the garment with K more GGX lobes, each steered by the view to a
fixed peak and weighted by its own image lookup, what a mixture that forms a basis over the
incidences would cost (docs/garment.md: 25 of them bring the general mode near 5 %).  Their
weights are not fitted, and they are added after the material's shadow-ray shortcut (shadow rays
run their lookups too): the variant measures the cost, not the picture.

The cloth tables are the shipped example's (example_blends/tables/paper_2008_cloth): their grid
does not change the shader's cost (the same texture lookups), their weights do (the share of
paths that go on through the cloth)."""

import argparse
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
from clothlight.blender.node_builder import NodeBuilder
from clothlight.blender.measurement_render import configure_measurement_render, render_to_array
from render_cost import light_and_camera, paired_ratio, principled_with_sheen, print_render_cost, read_rgb

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--basis-lobes", type=int, default=0, metavar="K", help="also time K more steered GGX lobes")
args = parser.parse_args()
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
SEE_THROUGH = "Principled + sheen, alpha = coverage"
see_through = principled_with_sheen()
coverage = json.loads((cloth_dir / SUMMARY_FILE).read_text())["coverage_normal"]["front"]
see_through.node_tree.nodes["Principled BSDF"].inputs["Alpha"].default_value = coverage
materials = {
    SEE_THROUGH: see_through,
    "garment": build_garment_material(tables, "garment", mode=GENERAL_MODE, uv_map="UVMap"),
    "garment, no open weave": build_garment_material(tables, "garment opaque", mode=GENERAL_MODE, uv_map="UVMap",
                                                     open_weave=False),
    "garment, open weave, no transmission": build_garment_material(tables, "garment gaps only", mode=GENERAL_MODE,
                                                                   uv_map="UVMap", transmission=False),
    "garment, no transmission": build_garment_material(tables, "garment no transmission", mode=GENERAL_MODE,
                                                       uv_map="UVMap", open_weave=False, transmission=False),
}


def with_basis_lobes(material, count: int):
    """``material`` plus ``count`` GGX lobes (roughness 0.5), lobe k about the half vector between
    the view and a fixed peak p_k, weighted by a lookup of the material's own lobe image."""
    tree = material.node_tree
    nodes = NodeBuilder(tree)
    output = next(node for node in tree.nodes if node.type == "OUTPUT_MATERIAL")
    total = output.inputs["Surface"].links[0].from_socket
    image = next(node for node in tree.nodes if node.type == "TEX_IMAGE").image
    incoming = nodes.node("ShaderNodeNewGeometry", (0, 0)).outputs["Incoming"]
    golden = np.pi * (3.0 - np.sqrt(5.0))  # peaks spread over the hemisphere (a Fibonacci lattice)
    for k in range(count):
        z = 1.0 - (k + 0.5) / count
        peak = (np.sqrt(1.0 - z * z) * np.cos(golden * k), np.sqrt(1.0 - z * z) * np.sin(golden * k), z)
        half = nodes.vector_math("NORMALIZE", nodes.vector_math("ADD", incoming, peak).outputs[0]).outputs[0]
        where = nodes.vector_math("MULTIPLY_ADD", incoming, (0.05, 0.1, 0.0), ((k + 0.5) / count, 0.5, 0.0))
        lookup = nodes.node("ShaderNodeTexImage", (0, 0), {"Vector": where.outputs[0]}, image=image,
                            interpolation="Linear", extension="EXTEND")
        weight = nodes.vector_math("SCALE", lookup.outputs["Color"], None, None, 0.05).outputs[0]
        lobe = nodes.node("ShaderNodeBsdfAnisotropic", (0, 0), {"Color": weight, "Roughness": 0.5, "Normal": half},
                          distribution="GGX")
        total = nodes.add_shaders([total, lobe.outputs[0]])
    tree.links.new(total, output.inputs["Surface"])
    return material


if args.basis_lobes:
    materials[f"garment + {args.basis_lobes} basis lobes"] = with_basis_lobes(
        build_garment_material(tables, "garment basis", mode=GENERAL_MODE, uv_map="UVMap"), args.basis_lobes)
runs = print_render_cost(scene, cloth, materials, out)
# Like with like: against the reference that lets the same share of light through its gaps.
for label in ("garment", "garment, open weave, no transmission"):
    print(f"{label:36s} / the reference with alpha: {paired_ratio(runs, label, SEE_THROUGH)}")


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
