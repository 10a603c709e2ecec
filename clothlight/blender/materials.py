"""Material builder: ClothLight's OSL shaders as Cycles materials on the woven sample.

The shader is embedded as an internal text block (a saved .blend renders
elsewhere), table paths sit on string sockets, and the mesh attributes the
shader needs arrive through linked sockets: in Cycles ``getattribute`` alone
does not see them.
"""

from __future__ import annotations

import pathlib

import bpy

from ..addon import import_precompute
from ..mesh_attributes import CLOTH_NORMAL, YARN_TANGENT
from .osl_shaders import add_script_node

_ballistic = import_precompute("ballistic")

SUN_MODE = "SUN"
GENERAL_MODE = "GENERAL"
#: cloth_yarn.osl's inputs for the bake's ``lobe_shape`` (precompute.closure_fit.LobeShape).
LOBE_SHAPE_SOCKETS = {
    "FibreReflectionRoughness": "reflection_longitudinal",
    "FibreReflectionAzimuthal": "reflection_azimuthal",
    "FibreTransmissionRoughness": "transmission_longitudinal",
    "FibreTransmissionAzimuthal": "transmission_azimuthal",
    "RetroreflectionAlpha": "retroreflection_alpha",
}

#: cloth_yarn.osl's inputs for the bake's specular record (``summary.json`` → ``specular``).
SPECULAR_SOCKETS = {"SpecularWeight": "weight", "Slope": "slope"}


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


def _new_material(name: str, shader_name: str):
    material = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    tree = material.node_tree
    tree.nodes.clear()
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
    """The ClothLight script node of ``material``, or None."""
    for node in material.node_tree.nodes:
        if node.type == "SCRIPT" and node.script and node.script.name.startswith("clothlight_"):
            return node
    return None


def build_baseline_material(name: str = "ClothLight Baseline", *, mode: str = SUN_MODE):
    """The paper's §6 baseline: Lambert (0.6/π, 0, 0) plus Cook–Torrance with m = 0.8."""
    material, shader = _new_material(name, "cloth_baseline")
    shader.inputs["SunMode"].default_value = int(mode == SUN_MODE)
    return material


def build_yarn_material(
    tables,
    name: str = "ClothLight Yarn",
    *,
    mode: str = SUN_MODE,
):
    """The yarn material reading baked tables.

    Parameters
    ----------
    tables
        A :class:`clothlight.yarn_tables.YarnTableFiles`: checked table paths and resolutions, and the
        specular term the bake recorded (SpecularWeight and Slope; the shader's defaults where it
        has none).
    mode
        :data:`SUN_MODE` (exact under the scene's sun, for validation) or
        :data:`GENERAL_MODE` (closure mixture, any lighting).
    """
    material, shader = _new_material(name, "cloth_yarn")
    tree = material.node_tree
    tree.links.new(_object_to_world(tree, YARN_TANGENT, "VECTOR", (-200, 200)), shader.inputs["YarnTangent"])
    _read_tables(shader, tables)
    shader.inputs["SunMode"].default_value = int(mode == SUN_MODE)
    return material


def yarn_tables_folder(material) -> str | None:
    """The folder of the tables a yarn material reads, or None (not a ClothLight yarn material)."""
    node = shader_node(material)
    if node is None or "Table" not in node.inputs:
        return None
    return str(pathlib.Path(bpy.path.abspath(node.inputs["Table"].default_value)).parent)


def read_other_tables(material, tables) -> None:
    """Point a yarn material at other tables (another bake of its yarn): the shader's table inputs
    only, its mode and sun kept."""
    node = shader_node(material)
    if node is None or "Table" not in node.inputs:
        raise ValueError(f"material {material.name!r} has no ClothLight yarn shader")
    _read_tables(node, tables)


def _read_tables(shader, tables) -> None:
    shader.inputs["Table"].default_value = str(tables.brdf_path)
    shader.inputs["IncidenceResolution"].default_value = tables.incidence_resolution
    shader.inputs["ExitResolution"].default_value = tables.exit_resolution
    shader.inputs["LobeTable"].default_value = str(tables.lobe_path)
    shader.inputs["UnscatteredTable"].default_value = str(tables.unscattered_path)
    shader.inputs["UnscatteredSamples"].default_value = tables.unscattered_samples
    shader.inputs["UnscatteredSpread"].default_value = _ballistic.SUN_MODE_SPREAD_RAD
    for socket, key in LOBE_SHAPE_SOCKETS.items():
        shader.inputs[socket].default_value = tables.lobe_shape[key]
    shader.inputs["IOR"].default_value = tables.host_index
    if tables.specular is not None:
        for socket, key in SPECULAR_SOCKETS.items():
            shader.inputs[socket].default_value = tables.specular[key]


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
