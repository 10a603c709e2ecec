"""The woven sample as one Blender mesh object carrying the attributes ClothLight's shaders read."""

from __future__ import annotations

import bpy
import numpy as np

from .mesh_attributes import CLOTH_NORMAL, IS_WARP, YARN_ID, YARN_TANGENT, YARN_UV
from .weave import WeaveParameters, build_woven_mesh

DEFAULT_NAME = "ClothLight Sample"


def woven_mesh_data(params: WeaveParameters, name: str = DEFAULT_NAME):
    """A new bpy mesh of the woven sample (millimetre coordinates) with its attributes and UV map."""
    woven = build_woven_mesh(params)
    mesh = bpy.data.meshes.new(name)
    n_vertices, n_faces = len(woven.vertices), len(woven.faces)
    mesh.vertices.add(n_vertices)
    mesh.vertices.foreach_set("co", woven.vertices.astype(np.float32).ravel())
    mesh.loops.add(3 * n_faces)
    mesh.loops.foreach_set("vertex_index", woven.faces.astype(np.int32).ravel())
    mesh.polygons.add(n_faces)
    mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * n_faces, 3, dtype=np.int32))
    mesh.polygons.foreach_set("use_smooth", np.ones(n_faces, dtype=bool))
    for attribute_name, values in ((YARN_TANGENT, woven.tangent), (CLOTH_NORMAL, woven.cloth_normal)):
        attribute = mesh.attributes.new(attribute_name, "FLOAT_VECTOR", "POINT")
        attribute.data.foreach_set("vector", values.astype(np.float32).ravel())
    mesh.attributes.new(YARN_ID, "INT", "POINT").data.foreach_set("value", woven.yarn_id)
    mesh.attributes.new(IS_WARP, "INT", "POINT").data.foreach_set("value", woven.is_warp.astype(np.int32))
    uv_layer = mesh.uv_layers.new(name=YARN_UV)
    uv_layer.data.foreach_set("uv", woven.uv[woven.faces.ravel()].astype(np.float32).ravel())
    mesh.update()
    return mesh


def build_sample_object(params: WeaveParameters = WeaveParameters(), name: str = DEFAULT_NAME, collection=None):
    """Create the sample object, or rebuild it in place (keeping its materials) if it exists.

    The replaced mesh data block is removed, so rebuilding leaks nothing.
    """
    mesh = woven_mesh_data(params, name)
    obj = bpy.data.objects.get(name)
    if obj is None:
        obj = bpy.data.objects.new(name, mesh)
        (collection or bpy.context.scene.collection).objects.link(obj)
    else:
        old = obj.data
        for material in old.materials:
            mesh.materials.append(material)
        obj.data = mesh
        if old.users == 0:
            bpy.data.meshes.remove(old)
    mesh.name = name
    obj["clothlight_weave"] = {
        "spacing_mm": params.spacing_mm,
        "semi_axes_mm": list(params.semi_axes_mm),
        "warp_count": params.warp_count,
        "weft_count": params.weft_count,
        "interlacing": params.interlacing.astype(int).tolist(),
    }
    return obj
