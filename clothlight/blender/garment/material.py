"""The garment material: a cloth bake on any mesh with UVs.

Two modes, as for the yarn material:

* :data:`~clothlight.blender.materials.GENERAL_MODE` (any lighting, what artists render with): the
  closure mixture of ``lobes.exr`` as plain Cycles nodes — diffuse, uniform (diffuse toon),
  GGX retro-reflection, translucent and hair transmission closures and the yarns' Cook–Torrance
  term (a Beckmann Metallic BSDF), weighted by image lookups at the view direction, plus a
  transparent closure for the open weave.  No OSL: it renders with Cycles' SVM on the CPU or any GPU.
* :data:`~clothlight.blender.materials.SUN_MODE` (validation): ``osl/cloth_garment.osl`` evaluates the
  measured ρ for the scene's sun exactly (needs Cycles OSL on the CPU).

The warp follows the mesh's UV tangent (u along the warp); the front is the side the mesh's
normals face.  Tables are checked before any render (Cycles would render them magenta).
"""

from __future__ import annotations

import math
import pathlib
from dataclasses import dataclass

import bpy

from ..materials import GENERAL_MODE, SUN_MODE, configure_cycles_material
from ..node_builder import NodeBuilder
from ..osl_shaders import add_script_node
from ..yarn_nodes import cook_torrance_closures
from ...garment.goniometry import SIDES
from ...garment.tables import (
    BRDF_FILES,
    LOBE_FILE,
    LOBE_TILES,
    SPECULAR_KEYS,
    SPECULAR_LOBE,
    SPECULAR_VISIBILITY_FILES,
    check_cloth_table_folder,
)

SHADER = "cloth_garment"
MATERIAL_KIND = "clothlight_garment"


@dataclass(frozen=True)
class ClothTableFiles:
    """The checked files of a cloth bake (absolute paths), grid sizes, lobe shape and the yarns'
    specular parameters (``summary.json``: :data:`.tables.SPECULAR_KEYS`)."""

    brdf_paths: dict
    specular_visibility_paths: dict
    lobe_path: pathlib.Path
    incidence_resolution: int
    exit_resolution: int
    lobe_resolution: int
    lobe_shape: dict
    specular: dict
    #: The weave detail texture (:mod:`.detail`), its mean coverage and the weave repeat it holds
    #: (mm); None in bakes without one.
    detail_path: pathlib.Path | None = None
    detail_mean_coverage: float | None = None
    detail_repeat_mm: float | None = None


def cloth_tables_from_bake(folder) -> ClothTableFiles:
    """The tables of a cloth bake folder (``python -m clothlight.garment bake``), checked as a whole
    first (:func:`.tables.check_cloth_table_folder`: every file read and validated, one bake); a
    ``precompute.tables.exr.TableError`` (a ValueError) names the file and the reason otherwise."""
    checked = check_cloth_table_folder(pathlib.Path(folder).resolve())
    folder, summary = checked.folder, checked.summary
    detail = summary.get("weave_detail")
    return ClothTableFiles({side: folder / name for side, name in BRDF_FILES.items()},
                           {side: folder / name for side, name in SPECULAR_VISIBILITY_FILES.items()},
                           folder / LOBE_FILE, summary["incidence_resolution"], summary["exit_resolution"],
                           summary["lobe_grid_resolution"],
                           {key: float(value) for key, value in summary["lobe_shape"].items()},
                           {key: float(summary["specular"][key]) for key in SPECULAR_KEYS},
                           folder / detail["file"] if detail else None,
                           float(detail["mean_coverage"]) if detail else None,
                           float(detail["repeat_mm"]) if detail else None)


def build_garment_material(tables: ClothTableFiles, name: str = "ClothLight Garment", *, mode: str = GENERAL_MODE,
                           uv_map: str = "", open_weave: bool = True, transmission: bool = True,
                           weave_repeats_per_uv: float | None = None):
    """The garment material reading ``tables`` in ``mode`` (module docstring); ``uv_map``: the UV
    map whose tangent is the warp (empty: the active one).  Sun mode: set the sun with
    :func:`clothlight.blender.materials.sync_sun`.

    ``open_weave=False`` (general mode) leaves out the transparent closure of the open weave: the
    light through the gaps is lost, but camera and shadow rays stop at the cloth, which renders
    faster (benchmarks/bench_garment_material.py); for dense cloth or cloth seen from afar.

    ``transmission=False`` (general mode) leaves out the translucent and fibre-transmission
    closures as well: the cloth reflects as before but passes no light, so paths stop at it and it
    renders at about a Principled BSDF's cost.  What is lost is the light through the cloth: the
    glow of back-lit fabric, and on a worn garment lit from the front the light that goes through,
    reflects off the body and comes back through the cloth (docs/garment.md, "Render cost").

    ``weave_repeats_per_uv`` (general mode, a bake with a weave detail texture): weave repeats
    per UV unit — the garment's size along u in mm over the weave's repeat in mm; the yarns then
    show (normals and gaps) for close-ups, with the same mean as without."""
    if mode not in (SUN_MODE, GENERAL_MODE):
        raise ValueError(f"mode must be {SUN_MODE!r} or {GENERAL_MODE!r}, not {mode!r}")
    if weave_repeats_per_uv is not None:
        if mode != GENERAL_MODE or tables.detail_path is None:
            raise ValueError("weave detail needs the general mode and a cloth bake with a weave detail texture")
        if not (isinstance(weave_repeats_per_uv, (int, float)) and weave_repeats_per_uv > 0):
            raise ValueError(f"weave_repeats_per_uv must be > 0, not {weave_repeats_per_uv!r}")
    material = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    tree = material.node_tree
    tree.nodes.clear()
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    output.location = (1600, 0)
    tangent = tree.nodes.new("ShaderNodeTangent")
    tangent.direction_type = "UV_MAP"
    tangent.uv_map = uv_map
    tangent.location = (-800, -200)
    if mode == SUN_MODE:
        shader = add_script_node(tree, SHADER)
        shader.location = (1100, 0)
        tree.links.new(tangent.outputs["Tangent"], shader.inputs["Warp"])
        for side in SIDES:
            shader.inputs[f"{side.capitalize()}Table"].default_value = str(tables.brdf_paths[side])
            shader.inputs[f"{side.capitalize()}SpecularVisibility"].default_value = str(
                tables.specular_visibility_paths[side])
        for socket, key in (("SpecularWeight", "weight"), ("Slope", "slope"), ("IOR", "ior")):
            shader.inputs[socket].default_value = tables.specular[key]
        shader.inputs["LobeTable"].default_value = str(tables.lobe_path)
        shader.inputs["IncidenceResolution"].default_value = tables.incidence_resolution
        shader.inputs["ExitResolution"].default_value = tables.exit_resolution
        shader.inputs["LobeResolution"].default_value = tables.lobe_resolution
        shader.inputs["LobeTiles"].default_value = len(LOBE_TILES)
        surface = shader.outputs["BSDF"]
    else:
        detail = _weave_detail(tree, tables, uv_map, weave_repeats_per_uv) if weave_repeats_per_uv else None
        surface = _closure_mixture(tree, tables, tangent.outputs["Tangent"], open_weave, transmission, detail)
    tree.links.new(surface, output.inputs["Surface"])
    material[MATERIAL_KIND] = mode
    configure_cycles_material(material)
    return material


def _weave_detail(tree, tables: ClothTableFiles, uv_map: str, repeats: float):
    """(normal socket, coverage scale socket) of the weave detail texture tiled ``repeats`` times
    per UV unit: the bent normal, and the texel's coverage over the texture's mean."""
    nodes, links = tree.nodes, tree.links
    uv = nodes.new("ShaderNodeUVMap")
    uv.uv_map = uv_map
    uv.location = (-800, -600)
    tiled = nodes.new("ShaderNodeVectorMath")
    tiled.operation = "SCALE"
    tiled.inputs["Scale"].default_value = float(repeats)
    tiled.location = (-600, -600)
    links.new(uv.outputs["UV"], tiled.inputs[0])
    texture = nodes.new("ShaderNodeTexImage")
    texture.image = bpy.data.images.load(str(tables.detail_path), check_existing=True)
    texture.image.colorspace_settings.name = "Non-Color"
    texture.image.alpha_mode = "CHANNEL_PACKED"
    texture.interpolation = "Linear"
    texture.extension = "REPEAT"
    texture.location = (-400, -600)
    links.new(tiled.outputs[0], texture.inputs["Vector"])
    normal_map = nodes.new("ShaderNodeNormalMap")
    normal_map.space = "TANGENT"
    normal_map.uv_map = uv_map
    normal_map.location = (-100, -600)
    links.new(texture.outputs["Color"], normal_map.inputs["Color"])
    scale = nodes.new("ShaderNodeMath")
    scale.operation = "DIVIDE"
    scale.inputs[1].default_value = tables.detail_mean_coverage
    scale.location = (-100, -800)
    links.new(texture.outputs["Alpha"], scale.inputs[0])
    return normal_map.outputs["Normal"], scale.outputs[0]


def _closure_mixture(tree, tables: ClothTableFiles, tangent_socket, open_weave: bool, transmission: bool,
                     detail=None):
    """The general mode's nodes; returns the summed closure's socket.

    Frame: z = the shading normal (Cycles turns it toward the viewer, so the back side gets its
    own frame, a half-turn about the warp), x = the UV tangent made normal to it, y = z × x.
    Each tile of ``lobes.exr`` is looked up at the view's (ω_x, ω_y), held between the tile's
    outermost pixel centres (tables.projected_view_grid), in the front or back row block.

    ``open_weave``, ``transmission``: whether the transparent closure and the two transmission
    closures are in the sum (:func:`build_garment_material`); the image lookups of lobes left out
    are left out too.  With the open weave, shadow rays see the transparent closure alone.

    ``detail`` (:func:`_weave_detail`): the closures about the bent normal, their weights times
    s = coverage / mean coverage, the open weave's 1 − s (1 − open): the same mean per repeat."""
    nodes = NodeBuilder(tree)
    geometry = nodes.node("ShaderNodeNewGeometry", (-800, 200))
    normal, incoming = geometry.outputs["Normal"], geometry.outputs["Incoming"]
    warp, weft = nodes.tangent_frame(normal, tangent_socket, (-600, -200))
    view = nodes.node("ShaderNodeCombineXYZ", (150, 100),
                      (nodes.vector_math("DOT_PRODUCT", incoming, warp, location=(0, 100)).outputs["Value"],
                       nodes.vector_math("DOT_PRODUCT", incoming, weft, location=(0, 0)).outputs["Value"]))

    # Image coordinates (Blender's v runs up from the bottom row; the front block is on top):
    # u = (k + inset + span (ω_x + 1)/2) / K,  v = 1 − (inset + span (1 − ω_y)/2 + back) / 2.
    n, tiles = tables.lobe_resolution, len(LOBE_TILES)
    inset, span = 0.5 / n, (n - 1.0) / n
    scale = (span / (2.0 * tiles), span / 4.0, 0.0)
    offset = (0.0, 1.0 - (inset + span / 2.0) / 2.0, 0.0)
    base = nodes.vector_math("MULTIPLY_ADD", view.outputs[0], scale, offset, location=(300, 100))
    back = nodes.node("ShaderNodeCombineXYZ", (300, -100),
                      (None, nodes.math("MULTIPLY", geometry.outputs["Backfacing"], 0.5, location=(150, -100))))
    coordinates = nodes.vector_math("SUBTRACT", base.outputs[0], back.outputs[0], location=(450, 0)).outputs[0]

    image = bpy.data.images.load(str(tables.lobe_path), check_existing=True)
    image.colorspace_settings.name = "Non-Color"
    kinds = [("ShaderNodeBsdfDiffuse", "diffuse"), ("ShaderNodeBsdfToon", "uniform"),
             ("ShaderNodeBsdfAnisotropic", "retroreflection"), (None, SPECULAR_LOBE)]  # _specular_lobe
    if transmission:
        kinds += [("ShaderNodeBsdfTranslucent", "translucent"), ("ShaderNodeBsdfHair", "fibre_transmission")]
    if open_weave:
        kinds.append(("ShaderNodeBsdfTransparent", "open_weave"))
    weights = {}
    for _, tile in kinds:
        k = LOBE_TILES.index(tile)
        shifted = nodes.vector_math("ADD", coordinates, ((k + inset + span / 2.0) / tiles, 0.0, 0.0),
                                    location=(600, 300 - 200 * k))
        texture = nodes.node("ShaderNodeTexImage", (750, 300 - 200 * k), {"Vector": shifted.outputs[0]}, image=image,
                             interpolation="Linear", extension="EXTEND")
        weights[tile] = texture.outputs["Color"]

    closures = {}
    for node_type, tile in kinds:
        y = 300 - 200 * len(closures)
        weight = weights[tile]
        if detail is not None:
            bent, scale = detail
            if tile == "open_weave":  # 1 − s (1 − open)
                covered = nodes.vector_math("SUBTRACT", (1.0, 1.0, 1.0), weight, location=(850, y - 100))
                scaled = nodes.vector_math("SCALE", covered.outputs[0], location=(900, y - 100))
                nodes.link(scale, scaled.inputs["Scale"])
                open_share = nodes.vector_math("SUBTRACT", (1.0, 1.0, 1.0), scaled.outputs[0], location=(950, y - 100))
                weight = nodes.vector_math("MAXIMUM", open_share.outputs[0], (0.0, 0.0, 0.0),
                                           location=(975, y - 100)).outputs[0]
            else:
                scaled = nodes.vector_math("SCALE", weight, location=(900, y - 100))
                nodes.link(scale, scaled.inputs["Scale"])
                weight = scaled.outputs[0]
        weights[tile] = weight
        if tile == SPECULAR_LOBE:
            closures[tile] = _specular_lobe(nodes, tables, weight, bent if detail is not None else None, y)
            continue
        closure = nodes.node(node_type, (1000, y), {"Color": weight})
        if detail is not None and "Normal" in closure.inputs and tile != "retroreflection":
            nodes.link(bent, closure.inputs["Normal"])
        closures[tile] = closure.outputs[0]
        if tile == "uniform":  # Cycles' diffuse toon of size 1, unsmoothed: the same ρ at every incidence
            closure.component = "DIFFUSE"
            nodes.node_inputs(closure, {"Size": 1.0, "Smooth": 0.0})
        elif tile == "retroreflection":  # GGX about the view: back-scatter
            closure.distribution = "GGX"
            nodes.node_inputs(closure, {"Roughness": tables.lobe_shape["retroreflection_alpha"] ** 0.5,
                                        "Anisotropy": 0.0, "Normal": incoming})
        elif tile == "fibre_transmission":
            closure.component = "Transmission"
            nodes.node_inputs(closure, {"Offset": 0.0, "RoughnessU": tables.lobe_shape["transmission_longitudinal"],
                                        "RoughnessV": tables.lobe_shape["transmission_azimuthal"], "Tangent": warp})
    surface = nodes.add_shaders(list(closures.values()), x=1200)
    if not open_weave:
        return surface
    # A shadow ray asks the cloth only how much light passes, which is the transparent closure's
    # weight: SVM jumps over a Mix Shader's input of weight zero and the nodes only it reads, so the
    # other lobes' lookups are not run for shadow rays (the same picture: docs/garment.md, "Render cost").
    light_path = nodes.node("ShaderNodeLightPath", (1200, 400))
    passes = nodes.node("ShaderNodeBsdfTransparent", (1200, 250), {"Color": weights["open_weave"]})
    return nodes.node("ShaderNodeMixShader", (1400, 0),
                      (light_path.outputs["Is Shadow Ray"], surface, passes.outputs[0])).outputs[0]


def _specular_lobe(nodes, tables: ClothTableFiles, weight, normal, y: int):
    """The yarns' Cook–Torrance term of grey weight ``weight`` (at most w_s) about ``normal`` (None:
    the shading normal), over ⌈w_s⌉ copies (:func:`..yarn_nodes.cook_torrance_closures`)."""
    copies = max(1, math.ceil(tables.specular["weight"]))
    factor = nodes.math("DIVIDE", weight, float(copies), location=(1000, y - 100))
    return nodes.add_shaders(cook_torrance_closures(nodes, factor, copies, tables.specular["ior"],
                                                    tables.lobe_shape["gloss_alpha"], normal, (1000, y)), x=1150)


def apply_garment_material(obj, tables: ClothTableFiles, *, mode: str = GENERAL_MODE, name: str | None = None,
                           open_weave: bool = True, transmission: bool = True,
                           weave_repeats_per_uv: float | None = None):
    """Put a garment material (:func:`build_garment_material`) on every slot of the mesh object
    ``obj``; refuses a mesh without a UV map (the warp direction comes from it)."""
    if obj is None or obj.type != "MESH":
        raise ValueError("the garment material goes on a mesh object")
    if not obj.data.uv_layers:
        raise ValueError(f"{obj.name!r} has no UV map: the garment material takes the warp from the UV tangent "
                         "(unwrap it with u along the warp)")
    material = build_garment_material(tables, name or f"ClothLight Garment ({obj.name})", mode=mode,
                                      uv_map=obj.data.uv_layers.active.name, open_weave=open_weave,
                                      transmission=transmission, weave_repeats_per_uv=weave_repeats_per_uv)
    if not obj.data.materials:
        obj.data.materials.append(material)
    for index in range(len(obj.data.materials)):
        obj.data.materials[index] = material
    return material
