"""What the add-on costs a Blender that enables it, and what it leaves behind.

* Enabling it imports only its own light modules: numba, llvmlite, SciPy, OpenEXR, colour-science and
  matplotlib wait for a job that needs them (issue 22: 657 modules, 10.5 s at every Blender start).
* Nothing is written under the extension's folder — no Python bytecode, no numba cache, no tables —
  through a round of use: enable, build, apply the pre-baked tables, bake, validate (renders, and
  numba's kernels imported in Blender's own process), a restart.  Blender replaces that folder on
  every update and may install it read-only.
* Materials on the pre-baked tables read a copy of them in the user cache, so a saved .blend keeps
  its tables when the extension is updated or removed.

Each Blender runs in a child process with a clean interpreter (nothing imported yet), its own user
folder and home, and bytecode writing on, as Blender has it (the tests' environment may turn it
off).  The times are printed, never asserted.
"""

import hashlib
import json
import os
import pathlib
import shutil
import subprocess
import sys
import textwrap

import pytest

bpy = pytest.importorskip("bpy")  # the Blenders below run in child processes; this one only says bpy is here

from precompute.tables.folder import check_yarn_table_folder  # noqa: E402
from tests.helpers import PREBAKED_PRESET, PREBAKED_TRANSPORT  # noqa: E402

REPO = pathlib.Path(__file__).resolve().parents[1]
#: What a job may import, never the add-on's registration.
HEAVY = ("numba", "llvmlite", "scipy", "OpenEXR", "colour", "matplotlib")
EXTENSION = "bl_ext.user_default.clothlight"
#: Environment that would hide a write (bytecode off, another bytecode or numba folder).
HIDING = ("PYTHONDONTWRITEBYTECODE", "PYTHONPYCACHEPREFIX", "NUMBA_CACHE_DIR")


def blender_env(tmp_path: pathlib.Path) -> dict:
    env = {key: value for key, value in os.environ.items() if key not in HIDING}
    env["HOME"] = str(tmp_path / "home")
    env["BLENDER_USER_RESOURCES"] = str(tmp_path / "blender")
    for key in ("HOME", "BLENDER_USER_RESOURCES"):
        pathlib.Path(env[key]).mkdir(exist_ok=True)
    return env


def run_blender(code: str, env: dict, cwd: pathlib.Path) -> dict:
    """Run ``code`` in a fresh Python with Blender as a module; it prints one JSON object last."""
    preamble = textwrap.dedent(f"""
        import json, pathlib, sys, time
        HEAVY = {HEAVY!r}
        EXTENSION = {EXTENSION!r}
        def heavy_imported():
            return sorted(name for name in HEAVY if name in sys.modules)
        import bpy
    """)
    result = subprocess.run([sys.executable, "-c", preamble + textwrap.dedent(code)], cwd=cwd, env=env,
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-5000:]
    return json.loads(result.stdout.strip().splitlines()[-1])


def test_registering_the_add_on_imports_none_of_the_heavy_modules(tmp_path):
    """The development checkout registered as tests/test_table_folder.py does it."""
    outcome = run_blender("""
        before = len(sys.modules)
        started = time.perf_counter()
        from clothlight.blender import registration
        registration.register()
        seconds = time.perf_counter() - started
        print(json.dumps({"seconds": seconds, "modules": len(sys.modules) - before, "heavy": heavy_imported()}))
    """, blender_env(tmp_path), cwd=REPO)
    print(f"\nimport + register(): {outcome['seconds']:.2f} s, {outcome['modules']} modules imported")
    assert outcome["heavy"] == []


def folder_state(root: pathlib.Path) -> dict[str, str]:
    """Every file (its SHA-256) and folder under ``root``, by relative path."""
    state = {}
    for path in sorted(root.rglob("*")):
        key = path.relative_to(root).as_posix()
        state[key] = "folder" if path.is_dir() else hashlib.sha256(path.read_bytes()).hexdigest()
    return state


@pytest.mark.render  # the validation sweep; slow by its fixture (the zip) and its bake
def test_a_round_of_use_leaves_the_extension_folder_as_installed_and_materials_outside_it(extension_zip, tmp_path):
    env = blender_env(tmp_path)
    installed = run_blender(f"""
        bpy.ops.wm.read_homefile(use_empty=True)
        result = bpy.ops.extensions.package_install_files(filepath={str(extension_zip)!r}, repo="user_default",
                                                          enable_on_install=False)
        assert result == {{"FINISHED"}}, result
        root = pathlib.Path(bpy.utils.user_resource("EXTENSIONS")) / "user_default" / "clothlight"
        print(json.dumps({{"root": str(root)}}))
    """, env, cwd=tmp_path)
    root = pathlib.Path(installed["root"])
    before = folder_state(root)
    assert "blender_manifest.toml" in before and f"prebaked/{PREBAKED_PRESET}/brdf.exr" in before
    assert not [path for path in before if "__pycache__" in path]

    saved = tmp_path / "saved.blend"
    used = run_blender(f"""
        import addon_utils, importlib
        started = time.perf_counter()
        addon_utils.enable(EXTENSION, default_set=True)  # the first enable also unpacks the wheels
        enable_seconds = time.perf_counter() - started
        heavy_at_enable = heavy_imported()
        table_folder = importlib.import_module("precompute.tables.folder")
        materials = importlib.import_module(EXTENSION + ".clothlight.blender.materials")

        def table_paths(material):
            # the default medium's general mode: plain nodes, the lobe atlas packed from its file
            folder = pathlib.Path(materials.yarn_tables_folder(material))
            lobe_images = {{n.image.filepath for n in material.node_tree.nodes if n.type == "TEX_IMAGE"}}
            return [folder / "brdf.exr", folder / "unscattered.exr"] + [
                pathlib.Path(bpy.path.abspath(path)) for path in sorted(lobe_images)]

        bpy.ops.wm.read_homefile(use_empty=True)
        scene = bpy.context.scene
        medium = scene.clothlight.medium
        for key, value in {{"budget": "PATHS", **{PREBAKED_TRANSPORT!r}}}.items():
            setattr(medium, key, value)
        assert bpy.ops.clothlight.build_sample() == {{"FINISHED"}}
        sample = bpy.context.active_object
        assert bpy.ops.clothlight.apply_material() == {{"FINISHED"}}  # the pre-baked tables
        prebaked = table_paths(sample.active_material)
        copy = prebaked[0].parent
        table_folder.check_yarn_table_folder(copy)
        assert bpy.ops.clothlight.apply_material() == {{"FINISHED"}}  # again: the same copy
        assert table_paths(sample.active_material) == prebaked

        # A garment from the shipped preset: its shipped cloth tables, copied out like the yarn's.
        bpy.ops.mesh.primitive_grid_add(size=1.0)
        garment = bpy.context.active_object
        assert scene.clothlight.cloth_tables_dir == ""
        assert bpy.ops.clothlight.apply_garment_material() == {{"FINISHED"}}
        cloth_copy = scene.clothlight.cloth_tables_dir
        assert garment.active_material["clothlight_garment"] == "GENERAL"
        bpy.data.objects.remove(garment)
        scene.clothlight.cloth_tables_dir = ""
        sample.select_set(True)
        bpy.context.view_layer.objects.active = sample

        medium.seed = 7  # no longer the shipped tables: bake them (a child process)
        assert bpy.ops.clothlight.bake_tables() == {{"FINISHED"}}
        assert bpy.ops.clothlight.apply_material() == {{"FINISHED"}}
        baked = table_paths(sample.active_material)
        out = pathlib.Path({str(tmp_path / "validation")!r})
        assert bpy.ops.clothlight.validate("INVOKE_DEFAULT", out_dir=str(out), materials={{"YARN"}}, incidences="0",
                                           views="0", resolution=16, samples=1, swatches=False) == {{"FINISHED"}}
        # A garment or validation job in Blender's process: precompute's cache=True kernels, compiled here.
        grids = importlib.import_module("precompute.tables.grids")
        grids.AngularGrid("sphere", 4).direction_to_square([[0.0, 0.0, 1.0]])
        numba = sys.modules["numba"]
        medium.seed, medium.tables_dir = 0, ""  # the shipped tables again, for the saved file
        assert bpy.ops.clothlight.apply_material() == {{"FINISHED"}}
        assert table_paths(sample.active_material) == prebaked
        bpy.ops.wm.save_as_mainfile(filepath={str(saved)!r})
        print(json.dumps({{"enable_seconds": enable_seconds, "heavy_at_enable": heavy_at_enable,
                          "prebaked": [str(p) for p in prebaked], "baked": [str(p) for p in baked],
                          "cloth_copy": cloth_copy,
                          "numba_cache": numba.config.CACHE_DIR}}))
    """, env, cwd=tmp_path)
    print(f"\nfirst enable of the installed extension (unpacks the wheels): {used['enable_seconds']:.2f} s")
    assert used["heavy_at_enable"] == []
    for path in map(pathlib.Path, used["prebaked"] + used["baked"]):
        assert path.is_file() and not path.is_relative_to(root), path
    copy = pathlib.Path(used["prebaked"][0]).parent
    assert {path.name for path in copy.iterdir()} == {path.rpartition("/")[2] for path in before
                                                      if path.startswith(f"prebaked/{PREBAKED_PRESET}/")}
    cloth_copy = pathlib.Path(used["cloth_copy"])
    assert cloth_copy.is_dir() and not cloth_copy.is_relative_to(root)
    shipped_cloth = {path.rpartition("/")[2]: digest for path, digest in before.items()
                     if path.startswith(f"prebaked_cloth/{PREBAKED_PRESET}/")}
    assert "lobes.exr" in shipped_cloth and "request.json" in shipped_cloth
    assert {path.name: hashlib.sha256(path.read_bytes()).hexdigest() for path in cloth_copy.iterdir()} == shipped_cloth
    # The kernels compiled in Blender's process were cached in the user folder.
    assert used["numba_cache"] and not pathlib.Path(used["numba_cache"]).is_relative_to(root)
    assert list(pathlib.Path(used["numba_cache"]).rglob("grids.*.nbi"))

    restarted = run_blender(f"""
        import addon_utils, importlib
        started = time.perf_counter()
        addon_utils.enable(EXTENSION, default_set=True)
        enable_seconds = time.perf_counter() - started
        heavy_at_enable = heavy_imported()
        bpy.ops.wm.open_mainfile(filepath={str(saved)!r})
        sample = next(obj for obj in bpy.data.objects if obj.type == "MESH")
        materials = importlib.import_module(EXTENSION + ".clothlight.blender.materials")
        print(json.dumps({{"enable_seconds": enable_seconds, "heavy_at_enable": heavy_at_enable,
                          "table": str(pathlib.Path(materials.yarn_tables_folder(sample.active_material))
                                       / "brdf.exr")}}))
    """, env, cwd=tmp_path)
    print(f"enable at a Blender start: {restarted['enable_seconds']:.2f} s")
    assert restarted["heavy_at_enable"] == []
    assert restarted["table"] == used["prebaked"][0]

    after = folder_state(root)
    assert {path: after.get(path) for path in before if after.get(path) != before[path]} == {}
    added = sorted(set(after) - set(before))
    assert not added, f"{len(added)} new under the extension's folder: {', '.join(added[:12])}"

    # An update replaces the extension's folder (here it is removed): the saved file's tables stay.
    shutil.rmtree(root)
    check_yarn_table_folder(pathlib.Path(restarted["table"]).parent)
