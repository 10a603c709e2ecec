"""The woven mesh for other tools, through trimesh: checking (watertightness, volume) and
exchange (PLY, OBJ).  trimesh is imported here only, so the core stays usable where it is
missing (Blender's bundled Python).

PLY keeps the welded mesh — every yarn a closed tube — with the shader attributes as vertex
properties: ``u`` (mm), ``v`` ([0, 1)), ``tangent_x/y/z``, ``yarn_id`` and ``is_warp``
(coordinates in mm, single precision, as trimesh writes them).  OBJ has no vertex properties
but texture coordinates: there the seam vertices are duplicated so that the ``vt`` of every face
runs monotonically around the yarn (:meth:`WovenMesh.corner_uv`), which a welded OBJ cannot say.
"""

from __future__ import annotations

import pathlib

import numpy as np

from .errors import WeaveParameterError


def to_trimesh(mesh, yarn: int | None = None):
    """``trimesh.Trimesh`` of the whole sample, or of yarn ``yarn`` alone (vertices renumbered)."""
    import trimesh

    if yarn is None:
        return trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
    if not 0 <= yarn < len(mesh.yarn_faces):
        raise WeaveParameterError("yarn", yarn, f"an index in [0, {len(mesh.yarn_faces)})")
    start, stop = mesh.yarn_faces[yarn]
    faces = mesh.faces[start:stop]
    first, last = int(faces.min()), int(faces.max())
    return trimesh.Trimesh(mesh.vertices[first:last + 1], faces - first, process=False)


def _seam_split(mesh):
    """Vertices, faces and per-vertex UV with every seam-closing corner on its own vertex."""
    corners = mesh.corner_uv()
    closing = corners[..., 1] == 1.0
    seam_vertices, seam_index = np.unique(mesh.faces[closing], return_inverse=True)
    faces = mesh.faces.astype(np.int64)
    faces[closing] = len(mesh.vertices) + seam_index
    vertices = np.concatenate([mesh.vertices, mesh.vertices[seam_vertices]])
    uv = np.concatenate([mesh.uv, np.stack([mesh.uv[seam_vertices, 0], np.ones(len(seam_vertices))], -1)])
    return vertices, faces, uv


def export_mesh(mesh, path) -> pathlib.Path:
    """Write ``mesh`` (a :class:`WovenMesh`) to ``path``: ``.ply`` (binary, with the shader
    attributes) or ``.obj`` (with seam-correct texture coordinates).  Returns the path."""
    import trimesh

    path = pathlib.Path(path)
    suffix = path.suffix.lower()
    if suffix == ".ply":
        exported = to_trimesh(mesh)
        attributes = {"u": mesh.uv[:, 0], "v": mesh.uv[:, 1], "tangent_x": mesh.tangent[:, 0],
                      "tangent_y": mesh.tangent[:, 1], "tangent_z": mesh.tangent[:, 2],
                      "yarn_id": mesh.yarn_id, "is_warp": mesh.is_warp.astype(np.uint8)}
        for name, values in attributes.items():
            exported.vertex_attributes[name] = values.astype(np.float32) if values.dtype.kind == "f" else values
        path.write_bytes(trimesh.exchange.ply.export_ply(exported, encoding="binary", include_attributes=True))
    elif suffix == ".obj":
        vertices, faces, uv = _seam_split(mesh)
        exported = trimesh.Trimesh(vertices, faces, process=False,
                                   visual=trimesh.visual.TextureVisuals(uv=uv))
        text = trimesh.exchange.obj.export_obj(exported, include_normals=False, include_texture=True,
                                               write_texture=False, return_texture=False)
        # trimesh names a material library it was told not to write; drop the dangling reference
        lines = [line for line in text.splitlines() if not line.startswith(("mtllib", "usemtl"))]
        path.write_text("\n".join(lines) + "\n")
    else:
        raise WeaveParameterError("path", str(path), "a file name ending in .ply or .obj")
    return path
