"""The yarn material's general mode in plain Cycles nodes: no OSL, so Cycles renders it with its
default SVM, on the CPU or a GPU.

The same closures as ``osl/cloth_yarn.osl``'s general mode: the five lobes of ``lobes.exr`` in the
yarn frame (``cl_closure_mixture``; precompute.closure_fit: Diffuse, Translucent, Hair reflection
and transmission about the yarn axis, GGX Glossy about the view), weighted by the lobe atlas where
the view falls in it, plus the cloth's Cook–Torrance sheen about the cloth normal
(``cl_cloth_specular_closure``).  The view is placed in the atlas by the tables' concentric
equal-area hemisphere map (``cl_hemisphere_to_square``, Shirley & Chiu 1997) built from math nodes.

The sheen is Cycles' Metallic BSDF in its physical-conductor form with extinction 0, which is the
exact Fresnel reflectance of a dielectric of the host's index for light from outside, on a
Beckmann surface of roughness √m: the reflection-only dielectric Beckmann lobe the OSL shader
makes.  A Mix Shader scales it by the specular weight (its factor is at most 1; a larger weight is
made of that many copies).

What plain nodes cannot hold is the unscattered light through a nearly clear yarn (one lobe per
refracted path, about a direction computed per shading point):
:func:`clothlight.yarn_tables.renders_in_nodes` says whether a medium has any the general mode would
render.
"""

from __future__ import annotations

import math

from ..addon import import_precompute
from .node_builder import NodeBuilder

#: Roughness inputs of the Hair BSDF nodes for the bake's ``lobe_shape``, per hair component.
HAIR_ROUGHNESS = {
    "Reflection": ("reflection_longitudinal", "reflection_azimuthal"),
    "Transmission": ("transmission_longitudinal", "transmission_azimuthal"),
}


def lobes_present(lobe_image) -> tuple[bool, ...]:
    """Per lobe (precompute.closure_fit.LOBES), whether its tile of the lobe atlas (a Blender image
    of ``lobes.exr``) has any weight: the fit leaves out minor lobes (MIN_LOBE_SHARE), and a lobe of
    zero weight everywhere needs neither its image lookup nor its closure."""
    import numpy as np

    lobe_count = len(import_precompute("closure_fit").LOBES)
    width, height = lobe_image.size
    pixels = np.empty(width * height * lobe_image.channels, np.float32)
    lobe_image.pixels.foreach_get(pixels)
    rgb = pixels.reshape(height, lobe_count, width // lobe_count, lobe_image.channels)[..., :3]
    return tuple(bool((rgb[:, k] > 0.0).any()) for k in range(lobe_count))


def general_mode_surface(tree, tables, tangent, cloth_normal, lobe_image):
    """Add the general mode's nodes to ``tree``; returns the socket of its surface closure.

    ``tangent`` and ``cloth_normal`` are world-space vector sockets (the yarn axis and the cloth's
    macroscopic normal); ``lobe_image`` is ``lobes.exr`` as a Blender image.  Like the OSL shader,
    a yarn's far face lets every ray but the camera's pass (the tables hold the light through the
    yarn), and other yarns' front faces block shadow rays."""
    nodes = NodeBuilder(tree)
    geometry = nodes.node("ShaderNodeNewGeometry", (-1600, 200))
    normal, toward_view = geometry.outputs["Normal"], geometry.outputs["Incoming"]
    axis, view = _yarn_frame_view(nodes, normal, tangent, toward_view)
    coordinates = _lobe_atlas_coordinates(nodes, view, tables.exit_resolution)

    present = lobes_present(lobe_image)
    shape = tables.lobe_shape
    closures = []
    for k, (node_type, settings) in enumerate((
        ("ShaderNodeBsdfDiffuse", {}),
        ("ShaderNodeBsdfTranslucent", {}),
        ("ShaderNodeBsdfHair", {"component": "Reflection"}),
        ("ShaderNodeBsdfHair", {"component": "Transmission"}),
        ("ShaderNodeBsdfAnisotropic", {"distribution": "GGX"}),
    )):
        if not present[k]:
            continue
        y = 600 - 220 * k
        tile = nodes.vector_math("ADD", coordinates, (k / len(present), 0.0, 0.0), location=(-200, y))
        weight = nodes.node("ShaderNodeTexImage", (-20, y), {"Vector": tile.outputs[0]}, image=lobe_image,
                            interpolation="Linear", extension="EXTEND", label=f"lobe weight {k}")
        closure = nodes.node(node_type, (260, y), {"Color": weight.outputs["Color"]}, **settings)
        if node_type == "ShaderNodeBsdfHair":
            longitudinal, azimuthal = HAIR_ROUGHNESS[settings["component"]]
            nodes.node_inputs(closure, {"Offset": 0.0, "RoughnessU": shape[longitudinal],
                                        "RoughnessV": shape[azimuthal], "Tangent": axis})
        elif node_type == "ShaderNodeBsdfAnisotropic":  # back-scatter: GGX about the view, α = roughness²
            nodes.node_inputs(closure, {"Roughness": math.sqrt(shape["retroreflection_alpha"]), "Anisotropy": 0.0,
                                        "Normal": toward_view})
        closures.append(closure.outputs[0])
    closures += _cloth_sheen(nodes, tables, normal, toward_view, cloth_normal)
    surface = nodes.add_shaders(closures, x=560) if closures else None

    # A far face (backfacing) passes every ray but the camera's: factor = backfacing × (1 − camera ray).
    light_path = nodes.node("ShaderNodeLightPath", (200, -900))
    not_camera = nodes.math("SUBTRACT", 1.0, light_path.outputs["Is Camera Ray"], location=(400, -900))
    passes = nodes.math("MULTIPLY", geometry.outputs["Backfacing"], not_camera, location=(600, -900))
    transparent = nodes.node("ShaderNodeBsdfTransparent", (600, -1050))
    return nodes.node("ShaderNodeMixShader", (900, 0), (passes, surface, transparent.outputs[0])).outputs[0]


def _yarn_frame_view(nodes, normal, tangent, toward_view):
    """The yarn frame (``cl_yarn_frame``: x the axis made normal to z, y = z × x, z the shading
    normal) and the view in it on the tables' hemisphere (``cl_exit_direction``); returns the
    sockets of the axis x and of the view."""
    axis, across = nodes.tangent_frame(normal, tangent, (-1400, -200))
    components = [nodes.vector_math("DOT_PRODUCT", toward_view, direction, location=(-650, 100 - 120 * i))
                  .outputs["Value"] for i, direction in enumerate((axis, across, normal))]
    up = nodes.math("MAXIMUM", components[2], 0.0, location=(-500, -140))  # a silhouette view at the horizon
    view = nodes.node("ShaderNodeCombineXYZ", (-350, 0), (components[0], components[1], up))
    return axis, nodes.vector_math("NORMALIZE", view.outputs[0], location=(-200, 0)).outputs[0]


def _lobe_atlas_coordinates(nodes, view, exit_resolution: int):
    """Blender image coordinates (v up) of ``view`` in the first tile of the lobe atlas
    (``cloth_yarn_exit.osl``): the equal-area hemisphere map to the unit square, held inside the
    tile's outermost pixel centres (``cl_tile_coordinates``).

    The concentric map's inverse, per octant pair: with r = √(1 − ω_z), where |ω_x| ≥ |ω_y|
    a = sign(ω_x) r and b = r (4/π) atan2(ω_y, |ω_x|); elsewhere b = sign(ω_y) r and
    a = r (4/π) atan2(ω_x, |ω_y|); then (s, t) = ((a + 1)/2, (b + 1)/2)."""
    lobe_count = len(import_precompute("closure_fit").LOBES)
    split = nodes.node("ShaderNodeSeparateXYZ", (-1400, 1000), (view,))
    x, y, z = (split.outputs[name] for name in "XYZ")
    radius = nodes.math("SQRT", nodes.math("SUBTRACT", 1.0, z, location=(-1250, 900)), location=(-1100, 900))
    abs_x = nodes.math("ABSOLUTE", x, location=(-1250, 1100))
    abs_y = nodes.math("ABSOLUTE", y, location=(-1250, 1000))
    x_major = nodes.math("GREATER_THAN", abs_x, abs_y, location=(-1100, 1200))  # 1 where |ω_x| > |ω_y|
    y_major = nodes.math("SUBTRACT", 1.0, x_major, location=(-950, 1200))
    scaled_radius = nodes.math("MULTIPLY", radius, 4.0 / math.pi, location=(-950, 900))

    def coordinate(major, own, other_abs, other_major, location):
        """a (or b): sign(own) r where ``own`` is the major axis, r (4/π) atan2(own, |other|) where not."""
        edge = nodes.math("MULTIPLY", nodes.math("SIGN", own, location=location), radius,
                          location=(location[0] + 150, location[1]))
        angle = nodes.math("ARCTAN2", own, other_abs, location=(location[0], location[1] - 100))
        inside = nodes.math("MULTIPLY", angle, scaled_radius, location=(location[0] + 150, location[1] - 100))
        return nodes.math("ADD", nodes.math("MULTIPLY", edge, major, location=(location[0] + 300, location[1])),
                          nodes.math("MULTIPLY", inside, other_major, location=(location[0] + 300, location[1] - 100)),
                          location=(location[0] + 450, location[1]))

    a = coordinate(x_major, x, abs_y, y_major, (-800, 1300))
    b = coordinate(y_major, y, abs_x, x_major, (-800, 1000))
    disk = nodes.node("ShaderNodeCombineXYZ", (-300, 1150), (a, b, 0.0))
    square = nodes.vector_math("MULTIPLY_ADD", disk.outputs[0], (0.5, 0.5, 0.0), (0.5, 0.5, 0.0),
                               location=(-150, 1150))
    half_texel = 0.5 / exit_resolution
    held = nodes.vector_math("MAXIMUM", square.outputs[0], (half_texel, half_texel, 0.0), location=(0, 1150))
    held = nodes.vector_math("MINIMUM", held.outputs[0], (1.0 - half_texel, 1.0 - half_texel, 0.0),
                             location=(150, 1150))
    # u = s / tiles (tile 0), v = 1 − t (Blender's v runs up).
    return nodes.vector_math("MULTIPLY_ADD", held.outputs[0], (1.0 / lobe_count, -1.0, 0.0), (0.0, 1.0, 0.0),
                             location=(300, 1150)).outputs[0]


def _cloth_sheen(nodes, tables, normal, toward_view, cloth_normal) -> list:
    """The cloth's specular closures (``cl_cloth_specular_closure``): about the cloth normal turned
    toward the viewer, on faces whose normal is on its side only, weighted by the specular weight."""
    specular = tables.specular or import_precompute("table_folder").default_specular()
    weight, slope = float(specular["weight"]), float(specular["slope"])
    if weight <= 0.0:
        return []
    facing = nodes.math("SIGN", nodes.vector_math("DOT_PRODUCT", cloth_normal, toward_view, location=(-1400, -700))
                        .outputs["Value"], location=(-1250, -700))
    toward = nodes.vector_math("SCALE", cloth_normal, location=(-1100, -700))
    nodes.link(facing, toward.inputs["Scale"])
    toward = nodes.vector_math("NORMALIZE", toward.outputs[0], location=(-950, -700)).outputs[0]
    face_on_side = nodes.math("GREATER_THAN", nodes.vector_math("DOT_PRODUCT", normal, toward, location=(-800, -800))
                              .outputs["Value"], 0.0, location=(-650, -800))
    copies = math.ceil(weight)
    factor = nodes.math("MULTIPLY", face_on_side, weight / copies, location=(-500, -800))
    closures = []
    for copy in range(copies):
        lobe = nodes.node("ShaderNodeBsdfMetallic", (-200, -700 - 300 * copy),
                          {"IOR": (tables.host_index,) * 3, "Extinction": (0.0, 0.0, 0.0),
                           "Roughness": math.sqrt(slope), "Anisotropy": 0.0, "Normal": toward,
                           # Without anisotropy the rotation changes nothing; it keeps the copies
                           # distinct nodes, which Cycles would otherwise merge into one closure.
                           "Rotation": copy / (copies + 1.0)},
                          distribution="BECKMANN", fresnel_type="PHYSICAL_CONDUCTOR")
        closures.append(nodes.node("ShaderNodeMixShader", (100, -700 - 300 * copy),
                                   (factor, None, lobe.outputs[0])).outputs[0])
    return closures
