"""Render cost of the yarn material vs a Principled BSDF with sheen on the same woven mesh
(same resolution, samples, lights; CPU), on the particle red the figures were measured on, on the
default (a yarn of fibres in air under a fuzz that scatters forward), on another yarn of fibres in air and
on the paper's literal medium.  A general mode in plain Cycles nodes (SVM) has its OSL general mode timed beside it.
Target (issues 7, 18): at most 2x."""

import pathlib
import sys
import tempfile

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

import bpy

from clothlight.blender.materials import GENERAL_MODE, SUN_MODE, build_yarn_material, sync_sun
from clothlight.blender.measurement_render import configure_measurement_render
from clothlight.blender.sample_object import build_sample_object
from clothlight.weave import WeaveParameters
from clothlight.yarn_tables import yarn_tables_from_bake
from precompute.bake import bake
from precompute.optics.medium import DEFAULT_PRESET
from render_cost import light_and_camera, print_render_cost
from subject_medium import SUBJECT_PRESET

out = pathlib.Path(tempfile.mkdtemp(prefix="clothlight-bench-material-"))
grids = ["transport.angular_resolution=8", "transport.incidence_resolution=9"]
# The particle red the figures were measured on (a scattering medium: almost no light crosses a yarn
# unscattered), the default and indigo_cotton, yarns of fibres in air (their unscattered light, straight
# through the yarn's thin edges, one more closure in plain nodes; the default's fuzz scatters forward,
# one more again, and its weights are read from Float Curves) and the paper's literal medium (a tinted
# glass rod: the unscattered light is most of its red, and its closures cost).
PRESETS = (SUBJECT_PRESET, DEFAULT_PRESET, "indigo_cotton", "paper_2008")
tables = {name: yarn_tables_from_bake(bake(name, grids, paths_per_cell=500, cache_dir=out / "cache").folder)
          for name in PRESETS}

bpy.ops.wm.read_homefile(use_empty=True)
scene = bpy.context.scene
SIZES = ((160, 16), (320, 64))  # pixels per side, samples per pixel
configure_measurement_render(scene, resolution=(SIZES[0][0],) * 2, samples=SIZES[0][1])  # OSL, to compile
sample = build_sample_object(WeaveParameters(warp_count=12, weft_count=12))
sun = light_and_camera(scene, (0.0, -4.0, 3.0), (0.93, 0.0, 0.0))
materials = {}
for name in PRESETS:
    general = build_yarn_material(tables[name], f"{name} general", mode=GENERAL_MODE)
    in_nodes = not any(node.type == "SCRIPT" for node in general.node_tree.nodes)
    materials[f"{name}, general, {'plain nodes' if in_nodes else 'OSL'}"] = general
    if in_nodes:  # the OSL shader's general mode of the same medium, side by side
        materials[f"{name}, general, OSL"] = build_yarn_material(tables[name], f"{name} general OSL",
                                                                 mode=GENERAL_MODE, plain_nodes=False)
    materials[f"{name}, sun mode"] = build_yarn_material(tables[name], f"{name} sun", mode=SUN_MODE)
    sync_sun(materials[f"{name}, sun mode"], sun)
# Small renders weigh each render's fixed cost (scene sync, OSL compilation) more: both sizes.
for pixels, samples in SIZES:
    configure_measurement_render(scene, resolution=(pixels, pixels), samples=samples)
    print(f"{pixels}² pixels, {samples} samples per pixel")
    print_render_cost(scene, sample, materials, out)
