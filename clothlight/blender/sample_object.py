"""The woven sample as one Blender mesh object carrying the attributes ClothLight's shaders read.

The object is a plain mesh (editable, no modifier stack to evaluate), built from the core's
arrays (:mod:`.weave`) in bulk: positions, edges, face corners and attributes go in through
``foreach_set`` on whole arrays, the edges from the tubes' known topology rather than a search.
Coordinates are the core's millimetres, one Blender unit per millimetre (the validation rig
frames samples in the same units).  The object's ``clothlight_weave`` property records what it
was built from.
"""

from __future__ import annotations

import bpy
import numpy as np

from ..mesh_attributes import CLOTH_NORMAL, IS_WARP, YARN_ID, YARN_TANGENT, YARN_UV
from ..weave import WeaveParameterError, WeaveParameters, build_woven_mesh
from ..weave.record import weave_record

DEFAULT_NAME = "ClothLight Sample"
#: Custom property of a sample object: the parameters it was built from.
WEAVE_PROPERTY = "clothlight_weave"


def woven_mesh_data(params: WeaveParameters, name: str = DEFAULT_NAME) -> bpy.types.Mesh:
    """A new mesh data block of the woven sample: point attributes ``yarn_tangent`` and
    ``cloth_normal`` (FLOAT_VECTOR), ``yarn_id`` and ``is_warp`` (INT), the UV map ``YarnUV``
    (u along the yarn in mm, v around it, seam closed per face corner), smooth side faces and
    flat end caps."""
    woven = build_woven_mesh(params)
    edges, corner_edges = woven.edge_topology()
    mesh = bpy.data.meshes.new(name)
    n_faces = len(woven.faces)
    mesh.vertices.add(len(woven.vertices))
    mesh.edges.add(len(edges))
    mesh.loops.add(3 * n_faces)
    mesh.polygons.add(n_faces)
    attributes = mesh.attributes
    attributes["position"].data.foreach_set("vector", woven.vertices.astype(np.float32).ravel())
    attributes[".edge_verts"].data.foreach_set("value", edges.astype(np.int32).ravel())
    attributes[".corner_vert"].data.foreach_set("value", woven.faces.astype(np.int32).ravel())
    attributes[".corner_edge"].data.foreach_set("value", corner_edges.astype(np.int32).ravel())
    mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * n_faces, 3, dtype=np.int32))
    caps = np.zeros(n_faces, dtype=bool)
    for start, stop in woven.tube_faces:
        caps[stop - 2 * woven.segments_around:stop] = True
    attributes.new("sharp_face", "BOOLEAN", "FACE").data.foreach_set("value", caps)
    for attribute_name, values in ((YARN_TANGENT, woven.tangent), (CLOTH_NORMAL, woven.cloth_normal)):
        attributes.new(attribute_name, "FLOAT_VECTOR", "POINT").data.foreach_set(
            "vector", values.astype(np.float32).ravel())
    attributes.new(YARN_ID, "INT", "POINT").data.foreach_set("value", woven.yarn_id.astype(np.int32))
    attributes.new(IS_WARP, "INT", "POINT").data.foreach_set("value", woven.is_warp.astype(np.int32))
    mesh.uv_layers.new(name=YARN_UV)
    attributes[YARN_UV].data.foreach_set("vector", woven.corner_uv().astype(np.float32).ravel())
    mesh.update()
    return mesh


def build_sample_object(params: WeaveParameters = WeaveParameters(), name: str = DEFAULT_NAME,
                        collection=None) -> bpy.types.Object:
    """Create the sample object ``name`` in ``collection`` (default: the scene's), or, if a
    ClothLight sample of that name exists, give it new geometry in place (keeping its materials,
    transform and links).  The replaced mesh data block is removed when nothing else uses it, so
    rebuilding leaks nothing.  An object of that name that is not a ClothLight sample is refused
    rather than overwritten."""
    obj = bpy.data.objects.get(name)
    if obj is not None and (obj.type != "MESH" or WEAVE_PROPERTY not in obj):
        raise WeaveParameterError("name", name, "a free object name or that of a ClothLight sample")
    mesh = woven_mesh_data(params, name)
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
    obj[WEAVE_PROPERTY] = weave_record(params)
    return obj
