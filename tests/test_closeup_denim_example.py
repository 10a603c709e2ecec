"""example_blends/closeup_denim_twill.blend (scripts/make_example_blends.py --denim-only): the denim
close-up, a warp-faced 3/1 twill of an indigo warp (the fitted indigo_cotton yarn) and an ecru weft
(ecru_cotton, fitted to MERL's warm white-fabric) with their fibres, each yarn in its own material, in
ClothLight's general mode and in Principled+sheen on the same geometry, front-lit and back-lit.  The file
is opened, not rendered (test_example_blends.py renders every example)."""

import pathlib

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")
from mathutils import Vector  # noqa: E402

from precompute.optics.medium import load_preset_config  # noqa: E402

BLEND = pathlib.Path(__file__).resolve().parents[1] / "example_blends" / "closeup_denim_twill.blend"
PRESET, WEFT_PRESET = "indigo_cotton", "ecru_cotton"
YARN_MATERIAL = "ClothLight Denim Warp (Indigo Cotton)"
WEFT_MATERIAL = "ClothLight Denim Weft (Ecru Cotton)"
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
    assert weave["ply_count"] == 2 and weave["twist_angle_deg"] == 24.0  # indigo_cotton's [yarn]
    assert weave["spacing_jitter"] > 0 and weave["height_jitter"] > 0 and weave["ply_radius_jitter"] > 0
    assert weave["warp_count"] == weave["weft_count"] == 8
    assert len(meshes[0].data.polygons) > 10_000


def _face_materials(mesh) -> np.ndarray:
    indices = np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("material_index", indices)
    return indices


def test_warp_faces_wear_the_blue_yarn_and_weft_faces_the_ecru_one(blend):
    """Slot 0 the warp's indigo_cotton material, slot 1 the weft's ecru_cotton; every face takes its
    yarn's (a face's vertices are all of one yarn), half of the faces each (8 warps, 8 wefts)."""
    sample = blend.objects["ClothLight Sample"]
    assert [slot.material.name for slot in sample.material_slots] == [YARN_MATERIAL, WEFT_MATERIAL]
    mesh = sample.data
    warp = _vertex_array(mesh, "is_warp", dtype=np.int32)
    corners = np.empty(len(mesh.loops), np.int32)
    mesh.loops.foreach_get("vertex_index", corners)
    starts, totals = np.empty(len(mesh.polygons), np.int32), np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("loop_start", starts)
    mesh.polygons.foreach_get("loop_total", totals)
    face_of_corner = np.repeat(np.arange(len(starts)), totals)
    corner_warp = warp[corners]
    face_warp = np.bincount(face_of_corner, corner_warp) / totals  # 1: all warp, 0: all weft
    assert set(np.unique(face_warp)) == {0.0, 1.0}
    materials = _face_materials(mesh)
    np.testing.assert_array_equal(materials, np.where(face_warp == 1.0, 0, 1))
    assert 0.4 < materials.mean() < 0.6


def test_the_face_is_mostly_the_blue_material_and_the_back_the_ecru_one(blend):
    """Warp-faced: over the cloth's middle, the highest yarn surface wears the warp's blue material in
    most places and the lowest the weft's ecru one (a plain weave shows each half the time on both
    sides)."""
    mesh = blend.objects["ClothLight Sample"].data
    position = _vertex_array(mesh, "position", "vector", 3)
    corners = np.empty(len(mesh.loops), np.int32)
    mesh.loops.foreach_get("vertex_index", corners)
    totals = np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("loop_total", totals)
    vertex_material = np.full(len(mesh.vertices), -1, np.int32)
    vertex_material[corners] = np.repeat(_face_materials(mesh), totals)
    assert (vertex_material >= 0).all()
    warp = vertex_material == 0  # the blue material
    inner = (np.abs(position[:, :2]) < 1.2).all(axis=1)  # clear of the cut edges
    position, warp = position[inner], warp[inner]
    cell = np.floor(position[:, :2] / 0.04).astype(np.int64)
    key = cell[:, 0] * 100_000 + cell[:, 1]
    order = np.lexsort((position[:, 2], key))
    first = np.r_[True, key[order][1:] != key[order][:-1]]
    last = np.r_[key[order][1:] != key[order][:-1], True]
    face, back = warp[order[last]].mean(), warp[order[first]].mean()
    assert face > 0.55 and back < 0.45 and face - back > 0.15, (face, back)


def _lobe_image(material):
    """The material's one packed lobe table."""
    from clothlight.blender.materials import LOBE_IMAGE_PREFIX

    (lobes,) = {node.image for node in material.node_tree.nodes
                if node.type == "TEX_IMAGE" and node.image.name.startswith(LOBE_IMAGE_PREFIX)}
    return lobes


def _packed_lobes(material):
    """The material's one lobe table, packed, and the mean weights of its diffuse lobe (tile 0)."""
    assert material.get("clothlight_mode") == "GENERAL"
    assert "clothlight_tables" not in material  # the bake folder was a path in this machine's cache
    images = {node.image for node in material.node_tree.nodes if node.type == "TEX_IMAGE"}
    assert all(image.packed_file is not None for image in images)
    lobes = _lobe_image(material)
    assert lobes.filepath_raw == "//lobes.exr"
    assert {image.filepath_raw for image in images - {lobes}} <= {"//unscattered.exr"}
    width, height = lobes.size
    pixels = np.array(lobes.pixels[:], dtype=np.float64).reshape(height, width, 4)
    return lobes, pixels[:, : width // 5, :3].mean(axis=(0, 1))


def test_the_clothlight_materials_read_indigo_cotton_and_ecru_cotton_packed(blend):
    """The warp's material is indigo_cotton's: its lobe table is blue and packed, its sheen is the
    preset's fitted [fit] specular term; the weft's is ecru_cotton's, its own packed table, much
    paler; nothing in either names a folder of this machine."""
    yarn, weft = blend.materials[YARN_MATERIAL], blend.materials[WEFT_MATERIAL]
    lobes, diffuse = _packed_lobes(yarn)
    assert diffuse[2] > 2 * diffuse[1] > 2 * diffuse[0] >= 0, diffuse  # a blue yarn (voided_red_cotton's is red)
    weft_lobes, weft_diffuse = _packed_lobes(weft)
    assert weft_lobes != lobes and weft_lobes.packed_file.data != lobes.packed_file.data
    # ecru: red and green far above the indigo's, red the strongest (the fabric's warm white)
    assert (weft_diffuse > 0).all() and weft_diffuse[0] > 10 * diffuse[0] and weft_diffuse[1] > 2 * diffuse[1]
    assert weft_diffuse[0] / weft_diffuse[2] > 2 * diffuse[0] / diffuse[2], (weft_diffuse, diffuse)
    assert weft_diffuse[0] > weft_diffuse[1] > weft_diffuse[2], weft_diffuse

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


def test_principled_copy_has_each_yarns_colour(blend):
    """The twin's two materials, warp and weft, have each yarn's reflectance at normal incidence (the
    bake's albedo): an indigo blue and a far paler ecru."""
    warp, weft = blend.materials["Principled BSDF + Sheen Warp"], blend.materials["Principled BSDF + Sheen Weft"]
    slots = blend.objects["Principled Sample"].material_slots
    assert [(slot.link, slot.material) for slot in slots] == [("OBJECT", warp), ("OBJECT", weft)]
    colours = []
    for material in (warp, weft):
        node = material.node_tree.nodes["Principled BSDF"]
        assert node.inputs["Sheen Weight"].default_value == 1.0
        colours.append(np.array(node.inputs["Base Color"].default_value[:3]))
    blue, ecru = colours
    assert blue[2] > blue[1] > blue[0] >= 0
    assert (ecru > blue).all() and ecru[0] > 10 * blue[0] and ecru[0] > ecru[1] > ecru[2]


def test_the_fibres_are_the_warps_blue(blend):
    """The fibres, all in indigo_cotton's hair BSDF (Evans blue: red absorbed most), the warp's; the
    Principled copy's in the warp's Principled material."""
    hair = blend.materials[f"ClothLight Fibres {PRESET}"]
    assert [slot.material for slot in blend.objects["ClothLight Sample Flyaways"].material_slots] == [hair]
    assert [slot.material.name for slot in blend.objects["Principled Sample Flyaways"].material_slots] == [
        "Principled BSDF + Sheen Warp"]
    assert len(blend.objects["ClothLight Sample Flyaways"].data.curves) > 100
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
def test_the_packed_lobe_table_is_indigo_cottons_bake(blend):
    """The packed images hold indigo_cotton's and ecru_cotton's lobes.exr to the last bit (the bake, or
    the cache's copy)."""
    from clothlight.jobs import BakeJob
    from clothlight.medium_settings import preset_request
    from precompute.cache import entries as cache
    from precompute.tables.exr import read_table

    for preset, material in ((PRESET, YARN_MATERIAL), (WEFT_PRESET, WEFT_MATERIAL)):
        baked = BakeJob(preset_request(preset), cache_dir=cache.default_cache_dir()).wait()
        table = read_table(baked.folder / "lobes.exr").pixels
        lobes = _lobe_image(blend.materials[material])
        width, height = lobes.size
        pixels = np.array(lobes.pixels[:], dtype=np.float32).reshape(height, width, 4)[::-1, :, :3]  # bottom first
        assert pixels.shape == table.shape
        np.testing.assert_array_equal(pixels, table)
