"""Material builder: ClothLight's OSL shaders as Cycles materials on the woven sample.

The shader is embedded as an internal text block (a saved .blend renders
elsewhere), table paths sit on string sockets (the general mode's lobe atlas is
a packed image instead), and the mesh attributes the
shader needs arrive through linked sockets: in Cycles ``getattribute`` alone
does not see them.

The general mode of a medium without unscattered light to render (the fitted
round-yarn presets) or with only the straight path of a yarn of fibres in air is
built from plain Cycles nodes instead (:mod:`.yarn_nodes`): it needs no OSL and
renders under Cycles' default SVM, on the CPU or a GPU.
"""

from __future__ import annotations

import hashlib
import pathlib

import bpy

from ..mesh_attributes import CLOTH_NORMAL, YARN_TANGENT
from .osl_shaders import add_script_node
from ..yarn_tables import has_unscattered_light, renders_in_nodes
from .yarn_nodes import UNSCATTERED_LOBE_ALPHA, general_mode_surface

from precompute.optics import ballistic as _ballistic

SUN_MODE = "SUN"
GENERAL_MODE = "GENERAL"
#: cloth_yarn.osl's inputs for the bake's ``lobe_shape`` (precompute.tables.closure_fit.LobeShape).
LOBE_SHAPE_SOCKETS = {
    "FibreReflectionRoughness": "reflection_longitudinal",
    "FibreReflectionAzimuthal": "reflection_azimuthal",
    "FibreTransmissionRoughness": "transmission_longitudinal",
    "FibreTransmissionAzimuthal": "transmission_azimuthal",
    "RetroreflectionAlpha": "retroreflection_alpha",
}

#: cloth_yarn.osl's inputs for the bake's specular record (``summary.json`` → ``specular``); its
#: SpecularIOR is ``YarnTableFiles.specular_index``, FuzzTint the record's ``fuzz_tint_red`` and
#: ``fuzz_tint_blue`` (:func:`precompute.optics.cook_torrance.fuzz_tint`).  A record without
#: ``fuzz_depth`` or ``fuzz_asymmetry`` (a bake from before them) has a fuzz of depth 0, the veneer it was
#: rendered with, isotropic.
SPECULAR_SOCKETS = {"SpecularWeight": "weight", "Slope": "slope", "FuzzAlbedo": "fuzz_albedo",
                    "FuzzDepth": "fuzz_depth", "FuzzAsymmetry": "fuzz_asymmetry", "FuzzFlatness": "fuzz_flatness"}

#: cloth_yarn.osl's inputs for the closure-mixture weights, keyed by lobe in the order of the tiles
#: of ``lobes.exr`` (precompute.tables.closure_fit.LOBES).
LOBE_WEIGHT_SOCKETS = {
    "diffuse": "DiffuseWeight",
    "translucent": "TranslucentWeight",
    "fibre_reflection": "FibreReflectionWeight",
    "fibre_transmission": "FibreTransmissionWeight",
    "retroreflection": "RetroreflectionWeight",
}
#: cloth_yarn.osl's UnscatteredReach where the attenuation never falls below its floor (its default).
UNSCATTERED_REACH_NEVER = 1e9
#: Label of the Image Texture nodes that read ``lobes.exr`` for the general mode.
LOBE_IMAGE_LABEL = "ClothLight lobe weights"
#: Name of a packed ``lobes.exr``, followed by a digest of its content.
LOBE_IMAGE_PREFIX = "ClothLight lobes "
#: The same for a packed ``unscattered.exr`` (the general mode in plain nodes of a yarn of fibres in air).
UNSCATTERED_IMAGE_PREFIX = "ClothLight unscattered "
#: Custom properties of a yarn material: the folder of the tables it reads, and (for the general
#: mode in plain nodes, which has no SunMode socket) its mode.
TABLES_PROPERTY = "clothlight_tables"
MODE_PROPERTY = "clothlight_mode"
#: The ``clothlight_shader`` a yarn material in plain nodes records (the OSL ones: their shader).
PLAIN_NODES = "Cycles nodes"


def _object_to_world(tree, attribute_name: str, vector_type: str, location):
    """An Attribute node reading ``attribute_name`` and a Vector Transform taking it to world space."""
    attribute = tree.nodes.new("ShaderNodeAttribute")
    attribute.attribute_type = "GEOMETRY"
    attribute.attribute_name = attribute_name
    attribute.location = location
    transform = tree.nodes.new("ShaderNodeVectorTransform")
    transform.vector_type = vector_type
    transform.convert_from = "OBJECT"
    transform.convert_to = "WORLD"
    transform.location = (location[0] + 200, location[1])
    tree.links.new(attribute.outputs["Vector"], transform.inputs["Vector"])
    return transform.outputs["Vector"]


def _packed_tables(material) -> set:
    """The packed tables (``lobes.exr``, ``unscattered.exr``) ``material``'s nodes read."""
    return {node.image for node in material.node_tree.nodes if node.type == "TEX_IMAGE" and node.image
            and node.image.name.startswith((LOBE_IMAGE_PREFIX, UNSCATTERED_IMAGE_PREFIX))}


def _remove_unused(images) -> None:
    for image in images:
        if image.users == 0:
            bpy.data.images.remove(image)


def remove_yarn_material(material) -> None:
    """Delete ``material`` and the packed tables only it read: a material replaced by another (the
    general mode's by the sun mode's, which reads no ``unscattered.exr``) must leave no orphans."""
    images = _packed_tables(material)
    bpy.data.materials.remove(material)
    _remove_unused(images)


def _fresh_material(name: str):
    """The material named ``name`` (made if missing) emptied of its nodes and ClothLight properties;
    packed tables only it used are removed (a material built again must not leave orphans)."""
    material = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    images = _packed_tables(material)
    material.node_tree.nodes.clear()
    _remove_unused(images)
    for key in ("clothlight_shader", MODE_PROPERTY, TABLES_PROPERTY):
        material.pop(key, None)
    return material


def _new_material(name: str, shader_name: str):
    material = _fresh_material(name)
    tree = material.node_tree
    shader = add_script_node(tree, shader_name)
    shader.location = (300, 0)
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    output.location = (600, 0)
    tree.links.new(shader.outputs["BSDF"], output.inputs["Surface"])
    tree.links.new(_object_to_world(tree, CLOTH_NORMAL, "NORMAL", (-200, -200)), shader.inputs["ClothNormal"])
    material["clothlight_shader"] = shader_name
    configure_cycles_material(material)
    return material, shader


def configure_cycles_material(material) -> None:
    """Cycles settings every ClothLight material needs.

    Bump-map correction bends a closure's normal toward the geometric one (and darkens diffuse
    lobes about other normals); the cloth normal of the specular lobe is far from a yarn's
    geometric normal by design, so the correction would move the lobe the sun mode computes.

    Emission sampling off: the sun modes' radiance is an emission closure, and Cycles, which
    cannot tell from an OSL shader whether it emits, would otherwise make every triangle of the
    cloth a light to sample — in either mode, for no light at all (the general mode emits none;
    the sun mode's yarns have no closure that receives light).  With it the general mode of the
    yarn material rendered 1.7× slower (benchmarks/bench_yarn_material.py)."""
    material.cycles.use_bump_map_correction = False
    material.cycles.emission_sampling = "NONE"


def shader_node(material):
    """The ClothLight script node of ``material`` whose closure is the surface (not a helper that
    computes lookups for it), or None."""
    for node in material.node_tree.nodes:
        if (node.type == "SCRIPT" and node.script and node.script.name.startswith("clothlight_")
                and "BSDF" in node.outputs):
            return node
    return None


def build_baseline_material(name: str = "ClothLight Baseline", *, mode: str = SUN_MODE):
    """The paper's §6 baseline: Lambert (0.6/π, 0, 0) plus Cook–Torrance with m = 0.8."""
    material, shader = _new_material(name, "cloth_baseline")
    shader.inputs["SunMode"].default_value = int(mode == SUN_MODE)
    return material


def needs_osl(tables, mode: str) -> bool:
    """Whether the yarn material of ``tables`` in ``mode`` is an OSL shader (the scene must render
    with Cycles' OSL on the CPU) rather than plain nodes (:mod:`.yarn_nodes`)."""
    return mode != GENERAL_MODE or not renders_in_nodes(tables)


def build_yarn_material(
    tables,
    name: str = "ClothLight Yarn",
    *,
    mode: str = SUN_MODE,
    plain_nodes: bool | None = None,
):
    """The yarn material reading baked tables.

    Parameters
    ----------
    tables
        A :class:`clothlight.yarn_tables.YarnTableFiles`: checked table paths and resolutions, and the
        specular term the bake recorded (SpecularWeight, Slope, FuzzAlbedo, FuzzDepth, FuzzAsymmetry and
        FuzzTint; the shader's
        defaults where it has none).
    mode
        :data:`SUN_MODE` (exact under the scene's sun, for validation) or
        :data:`GENERAL_MODE` (closure mixture, any lighting).
    plain_nodes
        General mode: build it from plain Cycles nodes (no OSL: SVM, CPU or GPU). None (the default):
        wherever the medium allows (:func:`clothlight.yarn_tables.renders_in_nodes`); True refuses a medium
        with refracted unscattered light to render; False: the OSL shader.
    """
    if mode not in (SUN_MODE, GENERAL_MODE):
        raise ValueError(f"mode must be {SUN_MODE!r} or {GENERAL_MODE!r}, not {mode!r}")
    if plain_nodes is None:
        plain_nodes = not needs_osl(tables, mode)
    if plain_nodes:
        if needs_osl(tables, mode):
            raise ValueError("only the general mode of a medium without refracted unscattered light to render is "
                             f"built from plain nodes (host index {tables.host_index:.4g}, unscattered reach "
                             f"{tables.unscattered_reach:.3g} R)")
        return _build_plain_general_material(tables, name)
    material, shader = _new_material(name, "cloth_yarn")
    tree = material.node_tree
    tangent = _object_to_world(tree, YARN_TANGENT, "VECTOR", (-200, 200))
    tree.links.new(tangent, shader.inputs["YarnTangent"])
    _lobe_weight_nodes(tree, shader, tangent)
    _read_tables(material, shader, tables)
    shader.inputs["SunMode"].default_value = int(mode == SUN_MODE)
    return material


def _build_plain_general_material(tables, name: str):
    material = _fresh_material(name)
    tree = material.node_tree
    tangent = _object_to_world(tree, YARN_TANGENT, "VECTOR", (-2200, 200))
    cloth_normal = _object_to_world(tree, CLOTH_NORMAL, "NORMAL", (-2200, -700))
    unscattered = (_packed_table_image(tables.unscattered_path, UNSCATTERED_IMAGE_PREFIX)
                   if has_unscattered_light(tables) else None)
    surface = general_mode_surface(tree, tables, tangent, cloth_normal,
                                   _packed_table_image(tables.lobe_path, LOBE_IMAGE_PREFIX), unscattered)
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    output.location = (1200, 0)
    tree.links.new(surface, output.inputs["Surface"])
    material["clothlight_shader"] = PLAIN_NODES
    material[MODE_PROPERTY] = GENERAL_MODE
    material[TABLES_PROPERTY] = str(tables.brdf_path.parent)
    configure_cycles_material(material)
    return material


def _lobe_weight_nodes(tree, shader, tangent) -> None:
    """The general mode's lookup of its closure weights: cloth_yarn_exit.osl finds the view in the
    lobe atlas, one Image Texture node per lobe reads its tile there (linear, clamped to the tile
    by the coordinates), and the shader's weight inputs take them.  Cycles looks up a packed image
    itself, as under SVM; a texture() in the shader would go through OpenImageIO (the general mode
    renders 1.4-1.6x faster so at 320² pixels, ``benchmarks/bench_yarn_material.py``).  The sun mode
    reads none of it, and OSL runs these nodes only when their outputs are read."""
    exit_node = add_script_node(tree, "cloth_yarn_exit")
    exit_node.location = (-200, 600)
    tree.links.new(tangent, exit_node.inputs["YarnTangent"])
    for k, socket in enumerate(LOBE_WEIGHT_SOCKETS.values()):
        shift = tree.nodes.new("ShaderNodeVectorMath")
        shift.operation = "ADD"
        shift.location = (0, 800 - 150 * k)
        tree.links.new(exit_node.outputs["LobeCoordinates"], shift.inputs[0])
        shift.inputs[1].default_value = (k / len(LOBE_WEIGHT_SOCKETS), 0.0, 0.0)
        texture = tree.nodes.new("ShaderNodeTexImage")
        texture.label = LOBE_IMAGE_LABEL
        texture.interpolation = "Linear"
        texture.extension = "EXTEND"
        texture.location = (150, 800 - 150 * k)
        tree.links.new(shift.outputs[0], texture.inputs["Vector"])
        tree.links.new(texture.outputs["Color"], shader.inputs[socket])


def lobe_image_nodes(material) -> list:
    """The Image Texture nodes of a yarn material that read its lobe atlas."""
    return [node for node in material.node_tree.nodes if node.type == "TEX_IMAGE" and node.label == LOBE_IMAGE_LABEL]


def _packed_table_image(path: pathlib.Path, prefix: str):
    """A table (``lobes.exr``, ``unscattered.exr``) as a packed float image: Cycles reads a packed
    image's pixels through its own image manager (a file path would go to OpenImageIO under OSL).
    Named ``prefix`` and a digest of its content, so that materials of the same tables share one
    image and a table folder written again in place is never served from an older copy."""
    name = prefix + hashlib.sha256(path.read_bytes()).hexdigest()[:16]
    image = bpy.data.images.get(name)
    if image is None or image.packed_file is None:
        image = bpy.data.images.load(str(path), check_existing=False)
        image.name = name
        image.colorspace_settings.name = "Non-Color"
        image.alpha_mode = "NONE"
        image.pack()
    return image


def yarn_tables_folder(material) -> str | None:
    """The folder of the tables a yarn material reads, or None (not a ClothLight yarn material)."""
    if TABLES_PROPERTY in material:
        return material[TABLES_PROPERTY]
    node = shader_node(material)
    if node is None or "Table" not in node.inputs:
        return None
    return str(pathlib.Path(bpy.path.abspath(node.inputs["Table"].default_value)).parent)


def material_mode(material) -> str | None:
    """:data:`SUN_MODE` or :data:`GENERAL_MODE` for a ClothLight yarn or baseline material, else None."""
    if MODE_PROPERTY in material:
        return material[MODE_PROPERTY]
    node = shader_node(material)
    if node is None or "SunMode" not in node.inputs:
        return None
    return SUN_MODE if node.inputs["SunMode"].default_value else GENERAL_MODE


#: The sun-mode inputs a yarn material built again keeps (its sun, until the sun link syncs it).
_SUN_SOCKETS = ("SunDirection", "SunIrradiance")
#: The shader inputs :func:`_read_tables` sets and the lobe weights the general mode feeds: a shader
#: without one of them is older than this version.
_TABLE_SOCKETS = ("Table", "IncidenceResolution", "ExitResolution", "UnscatteredTable", "UnscatteredSamples",
                  "UnscatteredReach", "UnscatteredSpread", "UnscatteredRoughness", "IOR", "SpecularIOR",
                  *LOBE_SHAPE_SOCKETS, *SPECULAR_SOCKETS, *LOBE_WEIGHT_SOCKETS.values())


def read_other_tables(material, tables) -> None:
    """Point a yarn material at other tables (another bake of its yarn), its mode and sun kept: the
    OSL shader's table inputs, or the general mode's plain nodes built again.  A material saved with
    an older shader (a .blend keeps the shader it was made with), which lacks an input the tables
    set, is built again with this version's, in its mode."""
    if material.get(MODE_PROPERTY) == GENERAL_MODE:
        build_yarn_material(tables, material.name, mode=GENERAL_MODE)
        return
    node = shader_node(material)
    if node is None or "Table" not in node.inputs:
        raise ValueError(f"material {material.name!r} has no ClothLight yarn shader")
    if any(name not in node.inputs for name in _TABLE_SOCKETS):
        mode = material_mode(material) or SUN_MODE
        sun = {name: tuple(node.inputs[name].default_value) for name in _SUN_SOCKETS if name in node.inputs}
        build_yarn_material(tables, material.name, mode=mode)
        node = shader_node(material)
        for name, value in sun.items():
            node.inputs[name].default_value = value
        return
    _read_tables(material, node, tables)


def _read_tables(material, shader, tables) -> None:
    material[TABLES_PROPERTY] = str(tables.brdf_path.parent)
    shader.inputs["Table"].default_value = str(tables.brdf_path)
    shader.inputs["IncidenceResolution"].default_value = tables.incidence_resolution
    shader.inputs["ExitResolution"].default_value = tables.exit_resolution
    image = _packed_table_image(tables.lobe_path, LOBE_IMAGE_PREFIX)
    for texture in lobe_image_nodes(material):
        previous, texture.image = texture.image, image
        if previous is not None and previous.users == 0:
            bpy.data.images.remove(previous)
    for node in material.node_tree.nodes:
        if node.type == "SCRIPT" and "LobeCoordinates" in node.outputs:
            node.inputs["ExitResolution"].default_value = tables.exit_resolution
    shader.inputs["UnscatteredTable"].default_value = str(tables.unscattered_path)
    shader.inputs["UnscatteredSamples"].default_value = tables.unscattered_samples
    shader.inputs["UnscatteredReach"].default_value = min(tables.unscattered_reach, UNSCATTERED_REACH_NEVER)
    shader.inputs["UnscatteredSpread"].default_value = _ballistic.SUN_MODE_SPREAD_RAD
    shader.inputs["UnscatteredRoughness"].default_value = UNSCATTERED_LOBE_ALPHA
    for socket, key in LOBE_SHAPE_SOCKETS.items():
        shader.inputs[socket].default_value = tables.lobe_shape[key]
    shader.inputs["IOR"].default_value = tables.host_index
    shader.inputs["SpecularIOR"].default_value = tables.specular_index
    if tables.specular is not None:
        from precompute.tables.folder import default_specular
        from precompute.optics.cook_torrance import fuzz_tint
        for socket, key in SPECULAR_SOCKETS.items():  # fuzz_depth, fuzz_asymmetry: 0 where neither record has it
            shader.inputs[socket].default_value = tables.specular.get(key, default_specular().get(key, 0.0))
        shader.inputs["FuzzTint"].default_value = (*fuzz_tint(tables.specular), 1.0)


def sync_sun(material, sun_object) -> None:
    """Copy ``sun_object``'s direction and irradiance into a sun-mode ClothLight material.

    A Blender sun shines along its local −Z axis, so the direction toward it is
    the world +Z column of its matrix; its strength is the irradiance in W/m² on a
    plane facing it.  Its angular size is ignored: sun mode assumes parallel light.
    """
    node = shader_node(material)
    if node is None:
        raise ValueError(f"material {material.name!r} has no ClothLight shader")
    toward_sun = sun_object.matrix_world.to_3x3().col[2].normalized()
    node.inputs["SunDirection"].default_value = tuple(toward_sun)
    irradiance = [sun_object.data.energy * c for c in sun_object.data.color]
    node.inputs["SunIrradiance"].default_value = (*irradiance, 1.0)
