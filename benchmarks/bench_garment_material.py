"""Render cost of the garment material vs a Principled BSDF with sheen on the same draped cloth
(same resolution, samples, lights; CPU, Cycles' SVM: the general mode needs no OSL).  Target
(issue 10): at most 1.3x.  With and without the open weave's transparency (the light through the
gaps: it makes camera and shadow rays continue through the cloth), and the reference with the
same see-through (its alpha the cloth's coverage) for what that costs any material.

The cloth tables come from a small gonioreflectometer run (their size does not change the
shader's cost: the same texture lookups whatever the grid)."""

import json
import pathlib
import sys
import tempfile

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

import bpy  # noqa: E402

from clothlight.garment.bake import bake_cloth  # noqa: E402
from clothlight.garment.drape import draped_cloth  # noqa: E402
from clothlight.garment.material import build_garment_material, cloth_tables_from_bake  # noqa: E402
from clothlight.garment.measure import GoniometerSettings  # noqa: E402
from clothlight.garment.tables import SUMMARY_FILE  # noqa: E402
from clothlight.materials import GENERAL_MODE  # noqa: E402
from clothlight.measurement_render import configure_measurement_render  # noqa: E402
from render_cost import light_and_camera, principled_with_sheen, print_render_cost  # noqa: E402

REPO = pathlib.Path(__file__).resolve().parents[1]
out = pathlib.Path(tempfile.mkdtemp(prefix="clothlight-bench-garment-"))
cloth_dir, _ = bake_cloth(REPO / "example_blends" / "tables" / "red_cotton",
                          GoniometerSettings(incidence_resolution=3, exit_resolution=3, pixels_per_patch=8, samples=1),
                          cache_dir=out / "cache")
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
print_render_cost(scene, cloth, {
    "Principled + sheen, alpha = coverage": see_through,
    "garment": build_garment_material(tables, "garment", mode=GENERAL_MODE, uv_map="UVMap"),
    "garment, no open weave": build_garment_material(tables, "garment opaque", mode=GENERAL_MODE, uv_map="UVMap",
                                                     open_weave=False),
}, out)
