"""The woven sample as a Blender object: attributes as the shaders read them, rebuilds leak nothing."""

import numpy as np
import pytest

bpy = pytest.importorskip("bpy")

from clothlight.mesh_attributes import CLOTH_NORMAL, IS_WARP, YARN_ID, YARN_TANGENT, YARN_UV  # noqa: E402
from clothlight.sample_object import build_sample_object  # noqa: E402
from clothlight.weave import WeaveParameters, build_woven_mesh, weave_pattern  # noqa: E402


def read_attribute(mesh, name, width):
    attribute = mesh.attributes[name]
    key = "vector" if width == 3 else "value"
    values = np.empty(len(attribute.data) * width, dtype=np.float64 if width == 3 else np.int64)
    attribute.data.foreach_get(key, values)
    return values.reshape(-1, width) if width == 3 else values


@pytest.mark.blender
def test_sample_object_carries_the_core_mesh_and_its_attributes():
    bpy.ops.wm.read_homefile(use_empty=True)
    params = WeaveParameters(interlacing=weave_pattern("twill_2_1"), warp_count=3, weft_count=4)
    core = build_woven_mesh(params)
    obj = build_sample_object(params)
    mesh = obj.data
    assert len(mesh.vertices) == len(core.vertices) and len(mesh.polygons) == len(core.faces)
    co = np.empty(len(mesh.vertices) * 3)
    mesh.vertices.foreach_get("co", co)
    np.testing.assert_allclose(co.reshape(-1, 3), core.vertices, atol=1e-6)
    np.testing.assert_allclose(read_attribute(mesh, YARN_TANGENT, 3), core.tangent, atol=1e-6)
    np.testing.assert_allclose(read_attribute(mesh, CLOTH_NORMAL, 3), core.cloth_normal)
    np.testing.assert_array_equal(read_attribute(mesh, YARN_ID, 1), core.yarn_id)
    np.testing.assert_array_equal(read_attribute(mesh, IS_WARP, 1), core.is_warp.astype(int))
    uv = np.empty(len(mesh.loops) * 2)
    mesh.uv_layers[YARN_UV].data.foreach_get("uv", uv)
    np.testing.assert_allclose(uv.reshape(-1, 2), core.uv[core.faces.ravel()], atol=1e-5)


@pytest.mark.blender
def test_rebuilding_replaces_the_mesh_without_leaking():
    bpy.ops.wm.read_homefile(use_empty=True)
    obj = build_sample_object(WeaveParameters(warp_count=2, weft_count=2))
    material = bpy.data.materials.new("kept")
    obj.data.materials.append(material)
    meshes = len(bpy.data.meshes)
    for count in (3, 5, 2):
        obj = build_sample_object(WeaveParameters(warp_count=count, weft_count=count))
    assert len(bpy.data.meshes) == meshes and len(bpy.data.objects) == 1
    assert obj.data.materials[0] == material
    assert len(obj.data.vertices) == len(build_woven_mesh(WeaveParameters(warp_count=2, weft_count=2)).vertices)
