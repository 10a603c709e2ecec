"""The garment material: ``osl/cloth_garment.osl`` reading a cloth bake, on any mesh with UVs.

The warp follows the mesh's UV tangent (u along the warp), the front is the side the mesh's
normals face.  Tables are checked before any render (Cycles would render them magenta).
"""

from __future__ import annotations

import json
import pathlib
from dataclasses import dataclass

import bpy

from ..materials import GENERAL_MODE, LOBE_SHAPE_SOCKETS, SUN_MODE
from ..osl_shaders import add_script_node
from .goniometry import SIDES
from .tables import SUMMARY_FILE, SUMMARY_SCHEMA, TABLE_FILES

SHADER = "cloth_garment"
#: The script node's table sockets, by table kind and side.
TABLE_SOCKETS = {"brdf": "{Side}Table", "lobes": "{Side}LobeTable", "coverage": "{Side}CoverageTable"}


@dataclass(frozen=True)
class ClothTableFiles:
    """The checked files of a cloth bake: ``paths[kind][side]`` (absolute), grid sizes and the
    closure-mixture lobe shape (``summary.json``)."""

    paths: dict
    incidence_resolution: int
    exit_resolution: int
    lobe_shape: dict


def cloth_tables_from_bake(folder) -> ClothTableFiles:
    """The tables of a cloth bake folder (``python -m clothlight.garment bake``); refuses a folder
    that is not a complete cloth bake of this schema."""
    folder = pathlib.Path(folder).resolve()
    summary_path = folder / SUMMARY_FILE
    if not summary_path.is_file():
        raise FileNotFoundError(f"{folder} is not a ClothLight cloth bake: no {SUMMARY_FILE}")
    summary = json.loads(summary_path.read_text())
    if summary.get("schema") != SUMMARY_SCHEMA:
        raise ValueError(f"{summary_path}: schema {summary.get('schema')!r}, this ClothLight reads "
                         f"{SUMMARY_SCHEMA!r}: bake the cloth again")
    paths = {kind: {side: folder / name for side, name in sides.items()} for kind, sides in TABLE_FILES.items()}
    missing = [str(path) for sides in paths.values() for path in sides.values() if not path.is_file()]
    if missing:
        raise FileNotFoundError(f"cloth bake {folder} lacks {missing}")
    return ClothTableFiles(paths, int(summary["incidence_resolution"]), int(summary["exit_resolution"]),
                           {key: float(value) for key, value in summary["lobe_shape"].items()})


def build_garment_material(tables: ClothTableFiles, name: str = "ClothLight Garment", *, mode: str = GENERAL_MODE,
                           uv_map: str = ""):
    """The garment material reading ``tables``; ``mode`` :data:`GENERAL_MODE` (any lighting) or
    :data:`SUN_MODE` (exact under the scene's sun: :func:`clothlight.materials.sync_sun`);
    ``uv_map``: the UV map whose tangent is the warp (empty: the active one)."""
    if mode not in (SUN_MODE, GENERAL_MODE):
        raise ValueError(f"mode must be {SUN_MODE!r} or {GENERAL_MODE!r}, not {mode!r}")
    material = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    tree = material.node_tree
    tree.nodes.clear()
    shader = add_script_node(tree, SHADER)
    shader.location = (300, 0)
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    output.location = (600, 0)
    tree.links.new(shader.outputs["BSDF"], output.inputs["Surface"])
    tangent = tree.nodes.new("ShaderNodeTangent")
    tangent.direction_type = "UV_MAP"
    tangent.uv_map = uv_map
    tangent.location = (0, 0)
    tree.links.new(tangent.outputs["Tangent"], shader.inputs["Warp"])
    for kind, pattern in TABLE_SOCKETS.items():
        for side in SIDES:
            shader.inputs[pattern.format(Side=side.capitalize())].default_value = str(tables.paths[kind][side])
    shader.inputs["IncidenceResolution"].default_value = tables.incidence_resolution
    shader.inputs["ExitResolution"].default_value = tables.exit_resolution
    for socket, key in LOBE_SHAPE_SOCKETS.items():
        shader.inputs[socket].default_value = tables.lobe_shape[key]
    shader.inputs["SunMode"].default_value = int(mode == SUN_MODE)
    material["clothlight_shader"] = SHADER
    # Light crossing the open weave must not be taken for the back of an opaque surface.
    material.use_transparent_shadow = True
    material.cycles.use_bump_map_correction = False
    return material


def apply_garment_material(obj, tables: ClothTableFiles, *, mode: str = GENERAL_MODE, name: str | None = None):
    """Put a garment material on every slot of the mesh object ``obj``; refuses a mesh without a
    UV map (the warp direction comes from it)."""
    if obj is None or obj.type != "MESH":
        raise ValueError("the garment material goes on a mesh object")
    if not obj.data.uv_layers:
        raise ValueError(f"{obj.name!r} has no UV map: the garment material takes the warp from the UV tangent "
                         "(unwrap it with u along the warp)")
    material = build_garment_material(tables, name or f"ClothLight Garment ({obj.name})", mode=mode,
                                      uv_map=obj.data.uv_layers.active.name)
    if not obj.data.materials:
        obj.data.materials.append(material)
    for index in range(len(obj.data.materials)):
        obj.data.materials[index] = material
    return material
