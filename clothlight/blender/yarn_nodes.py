"""The yarn material's general mode in plain Cycles nodes: no OSL, so Cycles renders it with its
default SVM, on the CPU or a GPU.

The same closures as ``osl/cloth_yarn.osl``'s general mode: the five lobes of ``lobes.exr`` in the
yarn frame (``cl_closure_mixture``; precompute.tables.closure_fit: Diffuse, Translucent, Hair reflection
and transmission about the yarn axis, GGX Glossy about the view), weighted by the lobe atlas where
the view falls in it, plus the cloth's Cook–Torrance sheen about the cloth normal
(``cl_cloth_specular_closure``) and its fuzz (``cl_cloth_fuzz_closure``); a fuzz of optical depth
also shades the yarn's closures (``cl_fuzz_yarn_share``).  The view is placed in the atlas by the
tables' concentric equal-area hemisphere map (``cl_hemisphere_to_square``, Shirley & Chiu 1997)
built from math nodes.

The sheen is Cycles' Metallic BSDF in its physical-conductor form with extinction 0, which is the
exact Fresnel reflectance of a dielectric of the host's index for light from outside, on a
Beckmann surface of roughness √m: the reflection-only dielectric Beckmann lobe the OSL shader
makes.  A Mix Shader scales it by the specular weight (its factor is at most 1; a larger weight is
made of that many copies).

The unscattered light of a yarn of fibres in air (host index 1) crosses it in a straight line, so its
one path is a Refraction BSDF about the view, weighted by the attenuation table at the chord
(``cl_unscattered_closures`` for η = 1).  What plain nodes cannot hold is the refracted and reflected
paths of a denser host (one lobe per path, about a direction computed per shading point):
:func:`clothlight.yarn_tables.renders_in_nodes` says which media the plain nodes serve.
"""

from __future__ import annotations

import math

from ..yarn_tables import GENERAL_MODE_MIN_WEIGHT
from .node_builder import NodeBuilder

#: GGX α of the general mode's lobe for each unscattered path (cloth_yarn.osl's UnscatteredRoughness).
UNSCATTERED_LOBE_ALPHA = 0.05
#: The index that places a GGX refraction lobe about the view straight through a surface seen head-on
#: (``cl_unscattered_closures``: η_l = max(1.3, −1.5 / cos(V, L)) at L = −V).
STRAIGHT_THROUGH_INDEX = 1.5

#: Roughness inputs of the Hair BSDF nodes for the bake's ``lobe_shape``, per hair component.
HAIR_ROUGHNESS = {
    "Reflection": ("reflection_longitudinal", "reflection_azimuthal"),
    "Transmission": ("transmission_longitudinal", "transmission_azimuthal"),
}


def lobes_present(lobe_image) -> tuple[bool, ...]:
    """Per lobe (precompute.tables.closure_fit.LOBES), whether its tile of the lobe atlas (a Blender image
    of ``lobes.exr``) has any weight: the fit leaves out minor lobes (MIN_LOBE_SHARE), and a lobe of
    zero weight everywhere needs neither its image lookup nor its closure."""
    from precompute.tables import closure_fit
    import numpy as np

    lobe_count = len(closure_fit.LOBES)
    width, height = lobe_image.size
    pixels = np.empty(width * height * lobe_image.channels, np.float32)
    lobe_image.pixels.foreach_get(pixels)
    rgb = pixels.reshape(height, lobe_count, width // lobe_count, lobe_image.channels)[..., :3]
    return tuple(bool((rgb[:, k] > 0.0).any()) for k in range(lobe_count))


def general_mode_surface(tree, tables, tangent, cloth_normal, lobe_image, unscattered_image=None):
    """Add the general mode's nodes to ``tree``; returns the socket of its surface closure.

    ``tangent`` and ``cloth_normal`` are world-space vector sockets (the yarn axis and the cloth's
    macroscopic normal); ``lobe_image`` is ``lobes.exr`` as a Blender image; ``unscattered_image``,
    ``unscattered.exr`` as one where the yarn's unscattered light is straight and rendered
    (:func:`clothlight.yarn_tables.unscattered_light_is_straight`), else None.  Like the OSL shader,
    a yarn's far face lets every ray but the camera's pass (the tables hold the light through the
    yarn), and other yarns' front faces block shadow rays.

    Cycles runs every node at every point it shades, math nodes included, so the graph holds as
    few nodes as the formulas allow."""
    nodes = NodeBuilder(tree)
    geometry = nodes.node("ShaderNodeNewGeometry", (-1600, 200))
    normal, toward_view = geometry.outputs["Normal"], geometry.outputs["Incoming"]
    axis, across = nodes.tangent_frame(normal, tangent, (-1400, -200))
    view = [nodes.vector_math("DOT_PRODUCT", toward_view, direction, location=(-650, 100 - 120 * i))
            .outputs["Value"] for i, direction in enumerate((axis, across, normal))]
    half_texel = 0.5 / tables.exit_resolution
    span = 1.0 - 2.0 * half_texel
    coordinates = _held_square_coordinates(nodes, view, half_texel)

    present = lobes_present(lobe_image)
    lobe_count = len(present)
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
        # Tile k: u = (k + h + (1 − 2h) s′)/K and v = h + (1 − 2h) t′ (see _held_square_coordinates).
        tile = nodes.vector_math("MULTIPLY_ADD", coordinates, (span / lobe_count, span, 0.0),
                                 ((k + half_texel) / lobe_count, half_texel, 0.0), location=(-200, y))
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
    sheen, yarn_share = _cloth_sheen(nodes, tables, normal, toward_view, cloth_normal)
    if yarn_share is None:  # no fuzz depth: the yarn's closures as they are
        closures += sheen
        if unscattered_image is not None:
            closures.append(_straight_unscattered_light(nodes, tables, view, toward_view, unscattered_image))
    else:  # a fuzz of depth shades the yarn's closures (lobes and unscattered light), not its own nor the sheen
        if unscattered_image is not None:
            closures.append(_straight_unscattered_light(nodes, tables, view, toward_view, unscattered_image))
        if closures:
            yarn = nodes.add_shaders(closures, x=420)
            closures = [nodes.node("ShaderNodeMixShader", (480, 300), (yarn_share, None, yarn)).outputs[0]]
        closures += sheen
    surface = nodes.add_shaders(closures, x=560) if closures else None

    # A far face (backfacing) passes every ray but the camera's: backfacing > is-camera-ray.
    light_path = nodes.node("ShaderNodeLightPath", (200, -900))
    passes = nodes.math("GREATER_THAN", geometry.outputs["Backfacing"], light_path.outputs["Is Camera Ray"],
                        location=(400, -900))
    # A shadow ray asks a near face only whether it passes (it does not): an empty closure answers that
    # without the lobes.  SVM jumps over a Mix Shader's input of weight zero, so the lookups and math
    # nodes that only the surface reads are not run for shadow rays (benchmarks/bench_closeup.py).
    surface = nodes.node("ShaderNodeMixShader", (750, 0),
                         (light_path.outputs["Is Shadow Ray"], surface, None)).outputs[0]
    transparent = nodes.node("ShaderNodeBsdfTransparent", (600, -1050))
    return nodes.node("ShaderNodeMixShader", (900, 0), (passes, surface, transparent.outputs[0])).outputs[0]


def _held_square_coordinates(nodes, view, half_texel: float):
    """The socket of (s′, t′, 0): where the view falls in the tables' hemisphere square
    (``cl_exit_direction`` and ``cl_hemisphere_to_square``, Shirley & Chiu 1997), held inside the
    tile's outermost pixel centres h = ``half_texel`` and 1 − h (``cl_tile_coordinates``) and mapped
    to [0, 1]: s′ = (s − h)/(1 − 2h), t′ the same of 1 − t (Blender's image v runs up).

    ``view`` holds the sockets of the unit view's components (ω_x, ω_y, ω_z) in the yarn frame.  A
    view below the shading horizon (a silhouette) is taken at the horizon: with ω_z clamped at 0, r =
    √(1 − ω_z) is 1 and the azimuth is kept, as normalising (ω_x, ω_y, 0) would.  The concentric
    map's inverse in one formula for both octant pairs: with c(p, q) = clamp((4/π) atan2(p, |q|), −1, 1),
    a = r c(ω_x, ω_y) and b = r c(ω_y, ω_x) (where |ω_x| ≥ |ω_y| the clamp makes a = sign(ω_x) r,
    elsewhere the atan2 stays inside ±1); s = (a + 1)/2 and 1 − t = (1 − b)/2."""
    omega_x, omega_y, omega_z = view
    radius = nodes.math("SQRT", _clamped(nodes.math("SUBTRACT", 1.0, omega_z, location=(-1250, 900))),
                        location=(-1100, 900))
    # s − h = r (c + 1)/2 + (1 − r)/2 − h, so s′ is one clamped multiply-add of (c + 1)/2.
    span = 1.0 - 2.0 * half_texel
    radius_over_span = nodes.math("MULTIPLY", radius, 1.0 / span, location=(-950, 900))
    offset = nodes.math("MULTIPLY_ADD", radius, -0.5 / span, (0.5 - half_texel) / span, location=(-950, 800))

    def held(own, other, sign, location):
        """clamp((s − h)/(1 − 2h), 0, 1) for s = (sign r c(own, other) + 1)/2."""
        angle = nodes.math("ARCTAN2", own, nodes.math("ABSOLUTE", other, location=location), location=location)
        half = _clamped(nodes.math("MULTIPLY_ADD", angle, sign * 2.0 / math.pi, 0.5, location=location))
        return _clamped(nodes.math("MULTIPLY_ADD", half, radius_over_span, offset, location=location))

    return nodes.node("ShaderNodeCombineXYZ", (-300, 1150),
                      (held(omega_x, omega_y, 1.0, (-800, 1300)), held(omega_y, omega_x, -1.0, (-800, 1000)), 0.0)
                      ).outputs[0]


def _straight_unscattered_light(nodes, tables, view, toward_view, image):
    """The unscattered light through a yarn of fibres in air: its one path runs straight along the
    view's chord, ℓ / R = 2 ω_z / (1 − ω_x²) (``precompute.optics.ballistic.unscattered_paths`` at
    η = 1: no Fresnel loss, no internal reflection), weighted by the attenuation table there and
    left out below the shader's floor in every channel (``cl_unscattered_closures``).  A GGX
    Refraction BSDF of α = :data:`UNSCATTERED_LOBE_ALPHA` about the view sends it on toward the light
    behind, as the OSL shader's lobe does; ω_z below the horizon (a silhouette) counts as 0."""
    from precompute.optics.ballistic import MAX_LENGTH_OVER_RADIUS

    omega_x, _, omega_z = view
    minus_omega_x = nodes.math("MULTIPLY", omega_x, -1.0, location=(-500, -1700))
    across = nodes.math("MULTIPLY_ADD", omega_x, minus_omega_x, 1.0, location=(-350, -1700))  # 1 − ω_x²
    across = nodes.math("MAXIMUM", across, 1e-6, location=(-200, -1700))
    toward_normal = nodes.math("MAXIMUM", omega_z, 0.0, location=(-350, -1850))
    half_chord = nodes.math("DIVIDE", toward_normal, across, location=(-50, -1750))
    # The table's pixel centres span ℓ / R in [0, MAX_LENGTH_OVER_RADIUS] (cl_unscattered_attenuation).
    samples = tables.unscattered_samples
    fraction = _clamped(nodes.math("MULTIPLY", half_chord, 2.0 / MAX_LENGTH_OVER_RADIUS, location=(100, -1750)))
    u = nodes.math("MULTIPLY_ADD", fraction, (samples - 1) / samples, 0.5 / samples, location=(250, -1750))
    where = nodes.node("ShaderNodeCombineXYZ", (400, -1750), (u, 0.5, 0.0)).outputs[0]
    weight = nodes.node("ShaderNodeTexImage", (550, -1750), {"Vector": where}, image=image,
                        interpolation="Linear", extension="EXTEND", label="unscattered attenuation")
    channels = nodes.node("ShaderNodeSeparateColor", (800, -1900), {"Color": weight.outputs["Color"]}).outputs
    strongest = nodes.math("MAXIMUM", channels[0], nodes.math("MAXIMUM", channels[1], channels[2],
                                                              location=(950, -1950)), location=(1100, -1900))
    kept = nodes.math("GREATER_THAN", strongest, GENERAL_MODE_MIN_WEIGHT, location=(1250, -1900))
    lobe = nodes.node("ShaderNodeBsdfRefraction", (800, -1700),
                      {"Color": weight.outputs["Color"], "Roughness": math.sqrt(UNSCATTERED_LOBE_ALPHA),
                       "IOR": STRAIGHT_THROUGH_INDEX, "Normal": toward_view}, distribution="GGX")
    return nodes.node("ShaderNodeMixShader", (1400, -1750), (kept, None, lobe.outputs[0])).outputs[0]


def _clamped(socket):
    """``socket``, a Math node's output, clamped to [0, 1] by its node."""
    socket.node.use_clamp = True
    return socket


def _cloth_sheen(nodes, tables, normal, toward_view, cloth_normal):
    """The cloth's specular and fuzz closures (``cl_cloth_specular_closure``, ``cl_cloth_fuzz_closure``):
    about the cloth normal turned toward the viewer, on faces whose normal is on its side only, the
    sheen weighted by the specular weight, the fuzz a diffuse lobe weighted by its directional albedo
    at the view (:func:`precompute.optics.lommel_seeliger.fuzz_albedo_at_view`), shared with a forward
    Glossy lobe where it scatters forward (:func:`precompute.optics.lommel_seeliger.fuzz_general_lobes`).
    Returns the list of their sockets and the socket of the share of the yarn's light that crosses a fuzz of optical
    depth τ > 0 (the specular record's ``fuzz_depth``) both ways, exp(−τ s(μo)/μo) times the hemispherical
    transmittance (``cl_fuzz_yarn_share``; s the fuzz's projected area, 1 unless its fibres lie flat), or None
    for τ = 0: no node for it."""
    from precompute.optics.cook_torrance import fuzz_tint
    from precompute.optics.lommel_seeliger import FUZZ_FORWARD_SLOPE, hemispherical_transmittance
    from precompute.tables import folder as table_folder
    specular = tables.specular or table_folder.default_specular()
    weight, slope = float(specular["weight"]), float(specular["slope"])
    fuzz = float(specular.get("fuzz_albedo", 0.0))
    depth = float(specular.get("fuzz_depth", 0.0))
    asymmetry = float(specular.get("fuzz_asymmetry", 0.0))
    flatness = float(specular.get("fuzz_flatness", 0.0))
    if weight <= 0.0 and fuzz <= 0.0 and depth <= 0.0:
        return [], None
    cosine = nodes.vector_math("DOT_PRODUCT", cloth_normal, toward_view, location=(-1400, -700)).outputs["Value"]
    closures = []
    if weight > 0.0 or fuzz > 0.0:
        facing = nodes.math("SIGN", cosine, location=(-1250, -700))
        toward = nodes.vector_math("SCALE", cloth_normal, location=(-1100, -700))  # unit: a closure normalises it
        nodes.link(facing, toward.inputs["Scale"])
        toward = toward.outputs[0]
        face_on_side = nodes.math("GREATER_THAN", nodes.vector_math("DOT_PRODUCT", normal, toward,
                                                                    location=(-800, -800)).outputs["Value"],
                                  0.0, location=(-650, -800))
    if weight > 0.0:
        copies = math.ceil(weight)
        factor = nodes.math("MULTIPLY", face_on_side, weight / copies, location=(-500, -800))
        closures += cook_torrance_closures(nodes, factor, copies, tables.specular_index, slope, toward, (-200, -700))
    if fuzz <= 0.0 and depth <= 0.0:
        return closures, None
    # μo = |n_c·v| kept above 0
    mu = nodes.math("MAXIMUM", nodes.math("ABSOLUTE", cosine, location=(-1250, -1300)), 1e-6, location=(-1100, -1300))
    yarn_share = None
    if depth > 0.0:
        # μo / s(μo): the view's slant path through the fuzz is τ over it
        path = mu if flatness == 0.0 else nodes.math("DIVIDE", mu, _projected_area_curve(nodes, mu, flatness),
                                                     location=(-1100, -1450))
        through = nodes.math("EXPONENT", nodes.math("DIVIDE", -depth, path, location=(-950, -1450)),
                             location=(-800, -1450))  # exp(−τ s/μo), the view's path through the fuzz
        yarn_share = nodes.math("MULTIPLY", through, hemispherical_transmittance(depth, flatness),
                                location=(-650, -1450))
    forward = None
    if fuzz <= 0.0:
        albedo = None
    elif asymmetry != 0.0 or flatness != 0.0:
        albedo, forward = _fuzz_lobe_curves(nodes, mu, fuzz, depth, asymmetry, flatness)
    elif depth > 0.0:
        albedo = _fuzz_layer_albedo(nodes, mu, through, fuzz, depth)
    else:
        # a(μo) = (A/2)(1 − μo ln(1 + 1/μo)), the semi-infinite layer's
        log = nodes.math("LOGARITHM", nodes.math("ADD", 1.0, nodes.math("DIVIDE", 1.0, mu, location=(-950, -1300)),
                                                 location=(-800, -1300)), math.e, location=(-650, -1300))
        albedo = nodes.math("MULTIPLY_ADD", nodes.math("MULTIPLY", mu, log, location=(-500, -1300)), -0.5 * fuzz,
                            0.5 * fuzz, location=(-350, -1300))
    if fuzz > 0.0:
        tint = tuple(fuzz_tint(specular))
        for weight, y in ((albedo, -1300), (forward, -1150)):
            if weight is None:
                continue
            colour = nodes.math("MULTIPLY", weight, face_on_side, location=(-200, y))
            if tint != (1.0, 1.0, 1.0):  # dyed surface fibres (FuzzTint)
                colour = nodes.vector_math("MULTIPLY", colour, tint, location=(-50, y)).outputs[0]
            if weight is albedo:
                lobe = nodes.node("ShaderNodeBsdfDiffuse", (100, y), {"Color": colour, "Normal": toward})
            else:  # the forward lobe: Glossy BSDF, no Fresnel factor, roughness² the Beckmann slope
                lobe = nodes.node("ShaderNodeBsdfAnisotropic", (100, y),
                                  {"Color": colour, "Normal": toward, "Roughness": math.sqrt(FUZZ_FORWARD_SLOPE),
                                   "Anisotropy": 0.0}, distribution="BECKMANN")
            closures.append(lobe.outputs[0])
    return closures, yarn_share


#: Points of the Float Curves that hold a forward-scattering fuzz's lobe weights over μo
#: (:func:`_fuzz_lobe_curves`), even in √μo where they bend most, toward grazing.
FUZZ_CURVE_POINTS = 25


def _fuzz_lobe_curves(nodes, mu, albedo: float, depth: float, asymmetry: float, flatness: float):
    """The sockets of the weights of the diffuse and the forward lobe at the view of a fuzz of albedo
    A, optical depth τ, asymmetry g and flatness F, one of them not 0 (``cl_fuzz_general_lobes``;
    :func:`precompute.optics.lommel_seeliger.fuzz_general_lobes`; no forward lobe, None, for g = 0):
    the sums over light cosines and azimuths have no few-node form, so Float Curves hold them at
    :data:`FUZZ_CURVE_POINTS` cosines, linear between them (vector handles), read at μo."""
    from precompute.optics.lommel_seeliger import fuzz_general_lobes

    cosines = _curve_cosines()
    diffuse, forward = fuzz_general_lobes(cosines, albedo, depth, asymmetry, flatness)
    return (_float_curve(nodes, mu, cosines, diffuse, (-650, -1300)),
            _float_curve(nodes, mu, cosines, forward, (-650, -1150)) if asymmetry != 0.0 else None)


def _curve_cosines():
    import numpy as np

    return np.linspace(0.0, 1.0, FUZZ_CURVE_POINTS) ** 2


def _projected_area_curve(nodes, mu, flatness: float):
    """The socket of s(μo), the area a fuzz of flatness F shows the view over what it shows the normal
    (``cl_fuzz_projected_area``; :func:`precompute.optics.lommel_seeliger.fuzz_projected_area`), a Float
    Curve through it at :data:`FUZZ_CURVE_POINTS` cosines."""
    from precompute.optics.lommel_seeliger import fuzz_projected_area

    cosines = _curve_cosines()
    return _float_curve(nodes, mu, cosines, fuzz_projected_area(cosines, flatness), (-1250, -1500))


def _float_curve(nodes, x, points_x, points_y, location):
    """The socket of a Float Curve node through the points (``points_x``, ``points_y``), linear between
    them (vector handles) and not clipped, read at the socket ``x``."""
    node = nodes.node("ShaderNodeFloatCurve", location, {"Value": x})
    mapping = node.mapping
    mapping.use_clip = False
    curve = mapping.curves[0]
    while len(curve.points) > 2:
        curve.points.remove(curve.points[-1])
    curve.points[0].location = (float(points_x[0]), float(points_y[0]))
    curve.points[1].location = (float(points_x[-1]), float(points_y[-1]))
    for px, py in zip(points_x[1:-1], points_y[1:-1]):
        curve.points.new(float(px), float(py))
    for point in curve.points:
        point.handle_type = "VECTOR"
    mapping.update()
    return node.outputs["Value"]


def _fuzz_layer_albedo(nodes, mu, through, albedo: float, depth: float):
    """The socket of the directional albedo at the view of a fuzz of albedo A and optical depth τ > 0
    (``cl_fuzz_albedo_at_view``; :func:`precompute.optics.lommel_seeliger.fuzz_albedo_at_view`):
    (A/2) Σ_k w_k μ_k (1 − e_k E) / (μ_k + μo) over the Gauss–Legendre nodes μ_k, w_k on (0, 1), where
    e_k = exp(−τ/μ_k) are constants and E = exp(−τ/μo) is ``through``.  Each term is (c_k − d_k E) / (μ_k
    + μo), c_k = (A/2) w_k μ_k and d_k = c_k e_k; Vector Math nodes take three terms at a time (a float
    socket reaches a vector input as (x, x, x)), the last group padded with terms of zero."""
    import numpy as np
    from precompute.optics.lommel_seeliger import FUZZ_ALBEDO_NODES, fuzz_quadrature

    cosines, weights = fuzz_quadrature()
    constant = 0.5 * albedo * weights * cosines
    groups = -(-FUZZ_ALBEDO_NODES // 3)
    padding = 3 * groups - FUZZ_ALBEDO_NODES
    cosines = np.concatenate([cosines, np.ones(padding)])
    shaded = np.concatenate([constant * np.exp(-depth / cosines[:FUZZ_ALBEDO_NODES]), np.zeros(padding)])
    constant = np.concatenate([constant, np.zeros(padding)])
    total = None
    for group in range(groups):
        part = slice(3 * group, 3 * group + 3)
        y = -1600 - 150 * group
        numerator = nodes.vector_math("MULTIPLY_ADD", through, tuple(-shaded[part]), tuple(constant[part]),
                                      location=(-650, y)).outputs[0]
        denominator = nodes.vector_math("ADD", mu, tuple(cosines[part]), location=(-650, y - 70)).outputs[0]
        term = nodes.vector_math("DIVIDE", numerator, denominator, location=(-500, y)).outputs[0]
        total = term if total is None else nodes.vector_math("ADD", total, term, location=(-350, y)).outputs[0]
    return nodes.vector_math("DOT_PRODUCT", total, (1.0, 1.0, 1.0), location=(-350, -1300)).outputs["Value"]


def cook_torrance_closures(nodes, factor, copies: int, index: float, slope: float, normal, location) -> list:
    """The Cook–Torrance term (§5.2) of slope ``slope`` and index ``index`` about ``normal`` (a socket;
    None: the shading normal), ``copies`` times, each scaled by ``factor`` (a socket in [0, 1]): a
    Beckmann Metallic BSDF, physical conductor with no extinction, has the dielectric's Fresnel
    (``precompute.tables.cycles_closures.beckmann_conductor_eval``).  It has no colour input, so a
    weight above 1 takes copies, each weighted by a Mix Shader's factor."""
    closures = []
    x, y = location
    for copy in range(copies):
        lobe = nodes.node("ShaderNodeBsdfMetallic", (x, y - 300 * copy),
                          {"IOR": (index,) * 3, "Extinction": (0.0, 0.0, 0.0),
                           "Roughness": math.sqrt(slope), "Anisotropy": 0.0, "Normal": normal,
                           # Without anisotropy the rotation changes nothing; it keeps the copies
                           # distinct nodes, which Cycles would otherwise merge into one closure.
                           "Rotation": copy / (copies + 1.0)},
                          distribution="BECKMANN", fresnel_type="PHYSICAL_CONDUCTOR")
        closures.append(nodes.node("ShaderNodeMixShader", (x + 300, y - 300 * copy),
                                   (factor, None, lobe.outputs[0])).outputs[0])
    return closures
