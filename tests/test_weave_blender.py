"""The woven sample as a Blender object: the core's mesh and attributes as the shaders read
them, a valid mesh, and rebuilds that replace the geometry without leaking data blocks."""

import os
import tempfile

import numpy as np
import pytest

# Blender keeps user state in its user resource folder: keep this test out of a real one
# (tests/conftest.py does the same for the whole session; this covers running the file alone).
os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="clothlight-blender-user-"))
bpy = pytest.importorskip("bpy")

from clothlight.mesh_attributes import CLOTH_NORMAL, IS_WARP, YARN_ID, YARN_TANGENT, YARN_UV  # noqa: E402
from clothlight.blender.sample_object import WEAVE_PROPERTY, build_sample_object  # noqa: E402
from clothlight.weave import WeaveParameterError, WeaveParameters, build_woven_mesh  # noqa: E402

pytestmark = pytest.mark.blender


def read(collection, key, width, dtype):
    values = np.empty(len(collection) * width, dtype=dtype)
    collection.foreach_get(key, values)
    return values.reshape(-1, width) if width > 1 else values


@pytest.fixture
def empty_scene():
    bpy.ops.wm.read_homefile(use_empty=True)
    yield bpy.context.scene


def test_sample_object_carries_the_core_mesh_and_its_attributes(empty_scene):
    params = WeaveParameters(interlacing="twill_2_1", warp_count=3, weft_count=4, semi_axes_mm=(0.14, 0.08))
    core = build_woven_mesh(params)
    obj = build_sample_object(params)
    mesh = obj.data
    assert obj.type == "MESH" and obj.name in empty_scene.collection.objects
    assert len(mesh.vertices) == len(core.vertices) and len(mesh.polygons) == len(core.faces)
    assert not mesh.validate(verbose=False)         # nothing for Blender to repair
    np.testing.assert_allclose(read(mesh.vertices, "co", 3, np.float32), core.vertices, atol=1e-6)
    np.testing.assert_array_equal(read(mesh.loops, "vertex_index", 1, np.int32), core.faces.ravel())
    expected = {YARN_TANGENT: ("POINT", "FLOAT_VECTOR"), CLOTH_NORMAL: ("POINT", "FLOAT_VECTOR"),
                YARN_ID: ("POINT", "INT"), IS_WARP: ("POINT", "INT"), YARN_UV: ("CORNER", "FLOAT2")}
    for name, (domain, data_type) in expected.items():
        attribute = mesh.attributes[name]
        assert (attribute.domain, attribute.data_type) == (domain, data_type)
    tangent = read(mesh.attributes[YARN_TANGENT].data, "vector", 3, np.float32)
    np.testing.assert_allclose(tangent, core.tangent, atol=1e-6)
    np.testing.assert_allclose(read(mesh.attributes[CLOTH_NORMAL].data, "vector", 3, np.float32), core.cloth_normal)
    np.testing.assert_array_equal(read(mesh.attributes[YARN_ID].data, "value", 1, np.int32), core.yarn_id)
    np.testing.assert_array_equal(read(mesh.attributes[IS_WARP].data, "value", 1, np.int32), core.is_warp)
    assert mesh.uv_layers.active.name == YARN_UV
    uv = read(mesh.uv_layers[YARN_UV].data, "uv", 2, np.float32)
    np.testing.assert_allclose(uv, core.corner_uv().reshape(-1, 2), atol=1e-5)
    # smooth sides, flat caps: the caps do not bend the normals of the sides next to them, which
    # follow the ellipse's normal (o·B/a², o·N/b²) for a vertex offset o from the axis
    flat = read(mesh.attributes["sharp_face"].data, "value", 1, bool)
    assert flat.sum() == 2 * params.segments_around * 7
    normals = read(mesh.corner_normals, "vector", 3, np.float32).reshape(-1, 3, 3)
    start, stop = core.yarn_faces[0]                  # warp 0: B = +y
    side = np.arange(start, stop - 2 * params.segments_around)
    vertex = core.faces[side]
    offset = core.vertices[vertex] - core.centerlines[0][vertex // params.segments_around]
    binormal = np.array([0.0, 1.0, 0.0])
    normal = np.cross(core.tangent[vertex], binormal)
    a, b = params.cross_section_mm
    expected = ((offset @ binormal / a**2)[..., None] * binormal
                + (np.sum(offset * normal, -1) / b**2)[..., None] * normal)
    expected /= np.linalg.norm(expected, axis=-1, keepdims=True)
    assert np.min(np.sum(normals[side] * expected, axis=-1)) > 0.98
    caps = np.flatnonzero(flat)                        # caps face along the yarn's end tangent
    along = np.sum(normals[caps] * core.tangent[core.faces[caps, :1]], axis=-1)
    np.testing.assert_allclose(np.abs(along), 1.0, atol=1e-5)
    record = obj[WEAVE_PROPERTY]
    assert record["spacing_mm"] == params.spacing_mm and record["units"] == "mm"
    assert [list(row) for row in record["interlacing"]] == params.interlacing.astype(int).tolist()


def test_rebuilding_replaces_the_mesh_without_leaking(empty_scene):
    obj = build_sample_object(WeaveParameters(warp_count=2, weft_count=2))
    material = bpy.data.materials.new("kept")
    obj.data.materials.append(material)
    obj.location = (1.0, 2.0, 3.0)
    meshes = len(bpy.data.meshes)
    for count in (3, 5, 2, 4):
        rebuilt = build_sample_object(WeaveParameters(interlacing="satin_5", warp_count=count, weft_count=count + 1))
        assert rebuilt == obj
        assert len(bpy.data.meshes) == meshes and len(bpy.data.objects) == 1
    assert obj.data.name == "ClothLight Sample" and obj.data.materials[0] == material
    assert tuple(obj.location) == (1.0, 2.0, 3.0)
    expected = build_woven_mesh(WeaveParameters(interlacing="satin_5", warp_count=4, weft_count=5))
    assert len(obj.data.vertices) == len(expected.vertices)
    assert obj[WEAVE_PROPERTY]["warp_count"] == 4


def test_a_mesh_shared_with_another_object_survives_the_rebuild(empty_scene):
    obj = build_sample_object(WeaveParameters(warp_count=2, weft_count=2))
    twin = bpy.data.objects.new("twin", obj.data)
    build_sample_object(WeaveParameters(warp_count=3, weft_count=3))
    assert twin.data is not None and twin.data != obj.data
    assert len(bpy.data.meshes) == 2


def test_an_unrelated_object_of_that_name_is_not_overwritten(empty_scene):
    mesh = bpy.data.meshes.new("user mesh")
    user = bpy.data.objects.new("ClothLight Sample", mesh)
    empty_scene.collection.objects.link(user)
    with pytest.raises(WeaveParameterError, match="name"):
        build_sample_object(WeaveParameters(warp_count=2, weft_count=2))
    assert user.data == mesh and len(bpy.data.meshes) == 1


def test_sample_goes_into_the_given_collection(empty_scene):
    collection = bpy.data.collections.new("samples")
    empty_scene.collection.children.link(collection)
    obj = build_sample_object(WeaveParameters(warp_count=2, weft_count=2), name="swatch", collection=collection)
    assert obj.name == "swatch" and obj.name in collection.objects
    assert obj.name not in empty_scene.collection.objects
