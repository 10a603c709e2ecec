"""example_blends/closeup_denim_twill.blend (scripts/make_example_blends.py --denim-only): the denim
close-up, a warp-faced 3/1 twill of the fitted blue_cotton yarn with its fibres, in ClothLight's
general mode and in Principled+sheen on the same geometry, front-lit and back-lit.  The file is
opened, not rendered (test_example_blends.py renders every example)."""

import pathlib

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
from mathutils import Vector  # noqa: E402

from precompute.optics.medium import load_preset_config  # noqa: E402

BLEND = pathlib.Path(__file__).resolve().parents[1] / "example_blends" / "closeup_denim_twill.blend"
PRESET = "blue_cotton"
YARN_MATERIAL = "ClothLight Blue Cotton Denim"
#: The 3/1 Z twill's drawdown (clothlight.weave.patterns.twill(3, 1)): pick i, end j, True where the
#: warp end is over the pick; three of four crossings show the warp.
TWILL_3_1 = [[True, True, True, False], [False, True, True, True], [True, False, True, True], [True, True, False, True]]

pytestmark = pytest.mark.blender


@pytest.fixture(scope="module")
def blend():
    bpy.ops.wm.open_mainfile(filepath=str(BLEND))
    yield bpy.data
    bpy.ops.wm.read_homefile(use_empty=True)


def _objects(data, kind: str) -> list:
    return sorted((obj for obj in data.objects if obj.type == kind), key=lambda obj: obj.name)


def _vertex_array(mesh, attribute: str, kind: str = "value", width: int = 1, dtype=np.float32) -> np.ndarray:
    values = np.empty(len(mesh.vertices) * width, dtype)
    mesh.attributes[attribute].data.foreach_get(kind, values)
    return values.reshape(-1, width) if width > 1 else values


def test_both_materials_dress_the_same_twill_sample_and_fibres(blend):
    meshes, fibres = _objects(blend, "MESH"), _objects(blend, "CURVES")
    assert [obj.name for obj in meshes] == ["ClothLight Sample", "Principled Sample"]
    assert len(fibres) == 2
    assert meshes[0].data == meshes[1].data and fibres[0].data == fibres[1].data  # the same geometry
    assert {obj.parent for obj in fibres} == set(meshes)
    assert meshes[0].location.x < 0 < meshes[1].location.x  # ClothLight left, Principled right
    weave = meshes[0]["clothlight_weave"]
    assert [[bool(v) for v in row] for row in weave["interlacing"]] == TWILL_3_1
    assert weave["ply_count"] == 2 and weave["twist_angle_deg"] == 24.0  # blue_cotton's [yarn]
    assert weave["spacing_jitter"] > 0 and weave["height_jitter"] > 0 and weave["ply_radius_jitter"] > 0
    assert weave["warp_count"] == weave["weft_count"] == 8
    assert len(meshes[0].data.polygons) > 10_000


def test_the_face_shows_the_warp_and_the_back_the_weft(blend):
    """Warp-faced: over the cloth's middle, the highest yarn surface is warp in most places and the
    lowest is weft (a plain weave shows each half the time on both sides)."""
    mesh = blend.objects["ClothLight Sample"].data
    position = _vertex_array(mesh, "position", "vector", 3)
    warp = _vertex_array(mesh, "is_warp", dtype=np.int32).astype(bool)
    inner = (np.abs(position[:, :2]) < 1.2).all(axis=1)  # clear of the cut edges
    position, warp = position[inner], warp[inner]
    cell = np.floor(position[:, :2] / 0.04).astype(np.int64)
    key = cell[:, 0] * 100_000 + cell[:, 1]
    order = np.lexsort((position[:, 2], key))
    first = np.r_[True, key[order][1:] != key[order][:-1]]
    last = np.r_[key[order][1:] != key[order][:-1], True]
    face, back = warp[order[last]].mean(), warp[order[first]].mean()
    assert face > 0.55 and back < 0.45 and face - back > 0.15, (face, back)


def test_the_clothlight_material_reads_blue_cotton_packed(blend):
    """The yarn material is blue_cotton's: its lobe table is blue and packed, its sheen is the preset's
    fitted [fit] specular term, and nothing in it names a folder of this machine."""
    yarn = blend.materials[YARN_MATERIAL]
    assert blend.objects["ClothLight Sample"].material_slots[0].material == yarn
    assert yarn.get("clothlight_mode") == "GENERAL"
    assert "clothlight_tables" not in yarn  # the bake folder was a path in this machine's cache
    images = {node.image for node in yarn.node_tree.nodes if node.type == "TEX_IMAGE"}
    assert len(images) == 1
    lobes = images.pop()
    assert lobes.packed_file is not None and lobes.filepath_raw == "//lobes.exr"
    width, height = lobes.size
    pixels = np.array(lobes.pixels[:], dtype=np.float64).reshape(height, width, 4)
    diffuse = pixels[:, : width // 5, :3].mean(axis=(0, 1))  # tile 0, the diffuse lobe's weights
    assert diffuse[2] > 2 * diffuse[1] > 2 * diffuse[0] >= 0, diffuse  # a blue yarn (red_cotton's is red)

    fit = load_preset_config(PRESET)[0]["fit"]
    sheen = [node for node in yarn.node_tree.nodes if node.bl_idname == "ShaderNodeBsdfMetallic"]
    assert sheen and all(node.inputs["Roughness"].default_value == pytest.approx(np.sqrt(fit["specular_slope"]))
                         for node in sheen)
    weights = [node.inputs[1].default_value * len(sheen) for node in yarn.node_tree.nodes
               if node.bl_idname == "ShaderNodeMath" and node.operation == "MULTIPLY"
               and node.outputs[0].links and node.outputs[0].links[0].to_node.bl_idname == "ShaderNodeMixShader"]
    assert weights and all(weight == pytest.approx(fit["specular_weight"]) for weight in weights)


def test_no_path_of_this_machine_in_the_file(blend):
    for image in blend.images:
        assert not image.filepath or image.filepath.startswith("//"), image.filepath
    assert not list(blend.libraries)

    def strings(value):
        if isinstance(value, str):
            yield value
        elif hasattr(value, "to_dict"):
            yield from strings(value.to_dict())
        elif isinstance(value, dict):
            for item in value.values():
                yield from strings(item)
        elif isinstance(value, (list, tuple)):
            for item in value:
                yield from strings(item)

    for collection in (blend.objects, blend.materials, blend.meshes, blend.scenes, blend.hair_curves):
        for datablock in collection:
            for text in strings({key: datablock[key] for key in datablock.keys()}):
                assert not text.startswith("/"), (datablock.name, text)


def test_principled_copy_and_fibres_are_blue(blend):
    principled = blend.materials["Principled BSDF + Sheen"]
    assert {obj.material_slots[0].material for obj in blend.objects
            if obj.type in ("MESH", "CURVES") and obj.name.startswith("Principled")} == {principled}
    node = principled.node_tree.nodes["Principled BSDF"]
    r, g, b, _ = node.inputs["Base Color"].default_value
    assert b > g > r >= 0 and node.inputs["Sheen Weight"].default_value == 1.0
    hair = blend.materials[f"ClothLight Fibres {PRESET}"]
    assert blend.objects["ClothLight Sample Flyaways"].material_slots[0].material == hair
    fibres = blend.objects["ClothLight Sample Flyaways"].data
    assert len(fibres.curves) > 100
    sigma = next(n for n in hair.node_tree.nodes if n.type == "BSDF_HAIR_PRINCIPLED").inputs["Absorption Coefficient"]
    red, green, blue = sigma.default_value
    assert red > green > blue  # a blue fibre absorbs red most


def test_a_sun_in_front_and_a_window_behind(blend):
    cloth = set(_objects(blend, "MESH") + _objects(blend, "CURVES"))
    front, back = blend.scenes["Front-Lit"], blend.scenes["Back-Lit"]
    for scene in (front, back):
        assert cloth <= set(scene.objects) and scene.camera.location.z > 0
        assert not scene.cycles.shading_system  # plain nodes: SVM
    suns = [obj for obj in front.objects if obj.type == "LIGHT"]
    assert [obj.data.type for obj in suns] == ["SUN"]
    toward_sun = suns[0].rotation_euler.to_matrix() @ Vector((0, 0, 1))
    assert toward_sun.z > 0 and toward_sun.y < 0  # above the cloth, on the camera's side
    window = [obj for obj in back.objects if obj.type == "LIGHT"]
    assert [obj.data.type for obj in window] == ["AREA"]
    assert window[0].location.z < 0  # behind the cloth, facing up through it toward the camera
    assert (window[0].rotation_euler.to_matrix() @ Vector((0, 0, -1))).z > 0


@pytest.mark.slow
def test_the_packed_lobe_table_is_blue_cottons_bake(blend):
    """The packed image holds blue_cotton's lobes.exr to the last bit (the bake, or the cache's copy)."""
    from clothlight.jobs import BakeJob
    from clothlight.medium_settings import preset_request
    from precompute.cache import entries as cache
    from precompute.tables.exr import read_table

    baked = BakeJob(preset_request(PRESET), cache_dir=cache.default_cache_dir()).wait()
    table = read_table(baked.folder / "lobes.exr").pixels
    lobes = next(node.image for node in blend.materials[YARN_MATERIAL].node_tree.nodes if node.type == "TEX_IMAGE")
    width, height = lobes.size
    pixels = np.array(lobes.pixels[:], dtype=np.float32).reshape(height, width, 4)[::-1, :, :3]  # bottom row first
    assert pixels.shape == table.shape
    np.testing.assert_array_equal(pixels, table)
