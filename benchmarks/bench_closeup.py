"""Render cost of the close-up (issue 46): the default close-up sample (clothlight.weave.closeup:
plied, irregular cotton sheeting) with voided_red_cotton's yarn material (the default until the fibre
red) and its flyaway fibres in Cycles' hair BSDF, against a Principled BSDF with sheen under Cycles'
default SVM on the same geometry (the sample and its fibres), CPU, interleaved renders; each ratio is
the median over the rounds of that round's own ratio.  Goals: at most 2x the reference, and the fibres at most 1.5x the
close-up without them.  Writes each configuration's last render as a PNG and prints the folder (a
temporary one, or ``--out DIR``).

    python benchmarks/bench_closeup.py                                   # 320² pixels, 64 samples, 7 rounds
    python benchmarks/bench_closeup.py --quick                           # 160², 16 samples, 3 rounds
    python benchmarks/bench_closeup.py --out docs/images/closeup         # the renders of docs/closeups.md
"""

import pathlib
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

import bpy

from clothlight.blender.flyaway_object import build_flyaway_object
from clothlight.blender.materials import GENERAL_MODE, build_yarn_material
from clothlight.blender.measurement_render import configure_measurement_render
from clothlight.blender.sample_object import build_sample_object
from clothlight.weave.closeup import closeup_settings, sheeting_weave
from clothlight.yarn_tables import yarn_tables_from_bake
from precompute.bake import bake
from precompute.optics.medium import load_preset_config
from render_cost import REFERENCE, light_and_camera, paired_ratio, principled_with_sheen
from subject_medium import SUBJECT_PRESET

QUICK = "--quick" in sys.argv
PIXELS, SAMPLES, REPEATS = (160, 16, 3) if QUICK else (320, 64, 7)

if "--out" in sys.argv:
    out = pathlib.Path(sys.argv[sys.argv.index("--out") + 1]).resolve()
    out.mkdir(parents=True, exist_ok=True)
else:
    out = pathlib.Path(tempfile.mkdtemp(prefix="clothlight-bench-closeup-"))
grids = ["transport.angular_resolution=8", "transport.incidence_resolution=9"]
tables = yarn_tables_from_bake(bake(SUBJECT_PRESET, grids, paths_per_cell=500).folder)

bpy.ops.wm.read_homefile(use_empty=True)
scene = bpy.context.scene
configure_measurement_render(scene, resolution=(PIXELS, PIXELS), samples=SAMPLES)
scene.cycles.shading_system = False   # Cycles' default SVM: every material here is plain nodes
params = sheeting_weave(SUBJECT_PRESET)
sample = build_sample_object(params)
fibres = build_flyaway_object(sample, params, closeup_settings(load_preset_config(SUBJECT_PRESET)[0]), SUBJECT_PRESET)
# a close-up: about 5 mm of cloth across the frame, seen at 45° (the sample is modelled in mm)
light_and_camera(scene, (0.0, -5.0, 5.0), (0.785, 0.0, 0.0))
reference = principled_with_sheen()
yarn = build_yarn_material(tables, f"{SUBJECT_PRESET} general", mode=GENERAL_MODE)
hair = fibres.data.materials[0]
assert not any(node.type == "SCRIPT" for node in yarn.node_tree.nodes), "the general mode in plain nodes (SVM)"
print(f"{params.warp_count} × {params.weft_count} yarns of {params.ply_count} plies at {params.twist_angle_deg:g}°, "
      f"cover {params.cover_factor:.2f}, {len(sample.data.polygons)} triangles, {len(fibres.data.curves)} fibres")

#: label → (the sample's material, the fibres' material or None for no fibres)
CONFIGURATIONS = {
    f"{REFERENCE}, sample and fibres": (reference, reference),
    "ClothLight yarn + hair fibres": (yarn, hair),
    f"{REFERENCE}, sample only": (reference, None),
    "ClothLight yarn, sample only": (yarn, None),
}
runs = {label: [] for label in CONFIGURATIONS}
for round_index in range(REPEATS + 1):   # round 0 warms up: shader compile, BVH
    for label, (sample_material, fibre_material) in CONFIGURATIONS.items():
        sample.data.materials.clear()
        sample.data.materials.append(sample_material)
        fibres.hide_render = fibre_material is None
        if fibre_material is not None:
            fibres.data.materials[0] = fibre_material
        scene.render.filepath = str(out / (label.replace(" ", "_").replace(",", "").replace("+", "and") + ".png"))
        scene.render.image_settings.file_format = "PNG"
        start = time.perf_counter()
        bpy.ops.render.render(write_still=True)
        if round_index:
            runs[label].append(time.perf_counter() - start)

median = {label: sorted(seconds)[len(seconds) // 2] for label, seconds in runs.items()}
print(f"{PIXELS}² pixels, {SAMPLES} samples per pixel, CPU, median of {REPEATS}")
for label, seconds in median.items():
    print(f"  {label:44s} {seconds:6.2f} s   (each round: {', '.join(f'{each:.2f}' for each in runs[label])})")
print(f"close-up (yarn + fibres) / reference on the same geometry: "
      f"{paired_ratio(runs, 'ClothLight yarn + hair fibres', f'{REFERENCE}, sample and fibres')} (goal ≤ 2)")
print(f"yarn material / reference, sample only:                    "
      f"{paired_ratio(runs, 'ClothLight yarn, sample only', f'{REFERENCE}, sample only')}")
print(f"with fibres / without (ClothLight):                        "
      f"{paired_ratio(runs, 'ClothLight yarn + hair fibres', 'ClothLight yarn, sample only')} (goal ≤ 1.5)")
print(f"renders: {out}")
