"""Generate the garment example: fitted presets as a draped garment, beside Principled BSDF + sheen.

    python scripts/make_garment_example.py                                   # example_blends/garment_red_cotton.blend
    python scripts/make_garment_example.py --render docs/images/garment      # and its two pictures
    python scripts/make_garment_example.py --preset voided_red_cotton blue_cotton   # one blend per preset

For each preset: its yarn tables (``python -m precompute bake``'s defaults, cached), its cloth
tables (``python -m clothlight.garment bake``'s defaults, read off the weave's cloth response:
seconds once the response is cached, docs/garment.md), copied to
``example_blends/tables/<preset>_cloth/``, and ``example_blends/garment_<preset>.blend`` with two
scenes sharing one draped square of cloth (Blender's cloth simulation over a sphere, frozen:
``clothlight.blender.garment.drape``) and its copy beside it:

* **Front-lit**: Blender's physical sky (sun and sky light from every direction);
* **Back-lit**: a window (an area light) behind the cloth in a dim room: the light through the
  fabric (paper Figure 9b at garment scale).

The left cloth wears the garment material (general lighting: plain Cycles nodes); the right one a
Principled BSDF with full sheen (roughness 0.8, as ``benchmarks/render_cost.py``'s reference)
whose base colour is the cloth's own: its reflectance at normal incidence, integrated from the
cloth tables (:func:`normal_reflectance_rgb`), so the two differ in how they scatter, not in
colour.  Scenes are in metres; denoised, as an artist renders.
"""

from __future__ import annotations

import argparse
import pathlib
import shutil
import sys

REPO_ROOT = pathlib.Path(__file__).resolve().parents[1]
if str(REPO_ROOT) not in sys.path:  # a development script: the installed extension never does this
    sys.path.insert(0, str(REPO_ROOT))

import bpy  # noqa: E402
import numpy as np  # noqa: E402
from mathutils import Vector  # noqa: E402

from clothlight.blender.garment.bake import bake_cloth  # noqa: E402
from clothlight.blender.garment.drape import draped_cloth  # noqa: E402
from clothlight.blender.garment.material import apply_garment_material, cloth_tables_from_bake  # noqa: E402
from clothlight.blender.materials import GENERAL_MODE  # noqa: E402
from clothlight.blender.reference_material import principled_sheen  # noqa: E402
from clothlight.jobs import BakeJob  # noqa: E402
from clothlight.medium_settings import preset_request  # noqa: E402
from make_example_blends import physical_sky_world, uniform_world  # noqa: E402  (this script's folder is on the path)

#: Where the Principled copy stands: this far along x from the garment (m).
SIDE_BY_SIDE_M = 1.5
#: Render settings of the pictures (the blends keep Cycles' defaults for the rest).
RESOLUTION = (720, 360)
SAMPLES = 64


def preset_cloth_tables(preset: str, out_dir: pathlib.Path) -> pathlib.Path:
    """The preset's cloth tables (yarn bake and cloth bake at their defaults, cached), copied to
    ``out_dir/tables/<preset>_cloth``."""
    from precompute.cache import entries as cache

    outcome = BakeJob(preset_request(preset), cache_dir=cache.default_cache_dir()).wait(
        on_progress=lambda f: print(f"\rbaking {preset}: {f:.0%}", end="", file=sys.stderr))
    print(file=sys.stderr)
    measured, _ = bake_cloth(outcome.folder, progress=lambda done, total, what: print(
        f"\rmeasuring {preset}'s cloth: {done}/{total} {what:<30}", end="", file=sys.stderr))
    print(file=sys.stderr)
    folder = out_dir / "tables" / f"{preset}_cloth"
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    for path in measured.iterdir():
        if path.suffix in (".exr", ".json") and path.name != "entry.json":
            shutil.copy2(path, folder / path.name)
    return folder


def normal_reflectance_rgb(cloth_dir: pathlib.Path) -> np.ndarray:
    """Linear RGB fraction of the light arriving along the front's normal that the cloth reflects:
    ∫ ρ(ω_i = n, ω_o) cos θ_o dω_o over the front's exit cells (ρ = f cos θ_i, the tables' quantity;
    the same sum as ``clothlight.garment.tables.energy_balance``'s ``reflected``)."""
    from precompute.tables import layout as table_layout
    from precompute.tables.exr import read_table
    from precompute.tables.grids import AngularGrid

    tables = cloth_tables_from_bake(cloth_dir)
    atlas = read_table(tables.brdf_paths["front"]).pixels
    exit_grid = AngularGrid("hemisphere", tables.exit_resolution)
    exits = exit_grid.cell_centers()
    normal = np.broadcast_to(np.array([0.0, 0.0, 1.0]), exits.shape)
    rho = table_layout.interpolate_rho(atlas, tables.incidence_resolution, normal, exits)
    return (exits[:, 2] * exit_grid.cell_solid_angle) @ rho



def copy_beside(obj, offset_x: float, collection):
    copy = obj.copy()
    copy.data = obj.data.copy()
    copy.location.x += offset_x
    collection.objects.link(copy)
    return copy


def aim(obj, target) -> None:
    obj.rotation_euler = (Vector(target) - obj.location).to_track_quat("-Z", "Y").to_euler()


def render_settings(scene) -> None:
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.shading_system = False  # the garment's general mode is plain nodes: SVM
    scene.cycles.samples = SAMPLES
    import _cycles  # Cycles' own module says whether it was built with OpenImageDenoise
    scene.cycles.use_denoising = bool(_cycles.with_openimagedenoise)
    scene.cycles.denoiser = "OPENIMAGEDENOISE"
    scene.render.resolution_x, scene.render.resolution_y = RESOLUTION
    scene.view_settings.view_transform = "AgX"


def garment_example(preset: str, out_dir: pathlib.Path, cloth_dir: pathlib.Path) -> pathlib.Path:
    """``out_dir/garment_<preset>.blend`` (module docstring)."""
    bpy.ops.wm.read_homefile(use_empty=True)
    front = bpy.context.scene
    front.name = "Front-lit"
    render_settings(front)
    garments = bpy.data.collections.new("Garments")
    front.collection.children.link(garments)
    cloth, form = draped_cloth(front, name=f"ClothLight {preset}")
    for obj in (cloth, form):
        front.collection.objects.unlink(obj)
        garments.objects.link(obj)
    apply_garment_material(cloth, cloth_tables_from_bake(cloth_dir), mode=GENERAL_MODE,
                           name=f"ClothLight {preset} Garment")
    reference = copy_beside(cloth, SIDE_BY_SIDE_M, garments)
    reference.name = "Principled BSDF + Sheen"
    reference.data.materials.clear()
    reference.data.materials.append(principled_sheen("Principled + Sheen", normal_reflectance_rgb(cloth_dir)))
    copy_beside(form, SIDE_BY_SIDE_M, garments)
    grey = bpy.data.materials.new("Form")
    grey.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.5, 0.5, 0.5, 1.0)
    for obj in garments.objects:
        if obj.name.startswith(form.name):
            obj.data.materials.append(grey)
    centre = (SIDE_BY_SIDE_M / 2.0, 0.0, 0.25)

    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    camera.data.lens = 40.0
    camera.location = (SIDE_BY_SIDE_M / 2.0, -3.4, 1.5)
    aim(camera, centre)
    front.collection.objects.link(camera)
    front.camera = camera
    # The sun behind the camera's left shoulder.
    front.world = physical_sky_world("Sky", sun_elevation_deg=40.0, sun_rotation_deg=-60.0, strength=0.08)

    back = bpy.data.scenes.new("Back-lit")
    render_settings(back)
    back.collection.children.link(garments)
    back.collection.objects.link(camera)
    back.camera = camera
    window = bpy.data.objects.new("Window", bpy.data.lights.new("Window", "AREA"))
    window.data.shape = "RECTANGLE"
    window.data.size, window.data.size_y = 3.0, 1.6
    window.data.energy = 4000.0  # W: daylight through a window a metre and a half behind the cloth
    window.location = (SIDE_BY_SIDE_M / 2.0, 1.6, 0.9)
    aim(window, centre)
    back.collection.objects.link(window)
    back.world = uniform_world("Dim Room", (0.01, 0.01, 0.012))

    path = out_dir / f"garment_{preset}.blend"
    bpy.context.preferences.filepaths.save_version = 0
    bpy.ops.wm.save_as_mainfile(filepath=str(path), compress=True, relative_remap=True)
    print(path)
    return path


def render_pictures(preset: str, folder: pathlib.Path) -> list[pathlib.Path]:
    """Render both scenes of the open example to ``folder/garment_<preset>_<scene>.png``."""
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for scene in bpy.data.scenes:
        path = folder / f"garment_{preset}_{scene.name.lower()}.png"
        scene.render.filepath = str(path)
        scene.render.image_settings.file_format = "PNG"
        bpy.ops.render.render(write_still=True, scene=scene.name)
        written.append(path)
        print(path)
    return written


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--preset", nargs="+", default=["voided_red_cotton"],
                        help="medium presets (default: %(default)s)")
    parser.add_argument("--out", type=pathlib.Path, default=REPO_ROOT / "example_blends")
    parser.add_argument("--render", type=pathlib.Path, metavar="DIR", help="also render the pictures into DIR")
    args = parser.parse_args(argv)
    out_dir = args.out.resolve()
    out_dir.mkdir(parents=True, exist_ok=True)
    for preset in args.preset:
        garment_example(preset, out_dir, preset_cloth_tables(preset, out_dir))
        if args.render:
            render_pictures(preset, args.render)


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else None)
