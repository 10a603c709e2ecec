"""Cycles renders ClothLight's OSL shaders headless on the CPU, with exact radiometry.

A Lambertian plane of albedo a under a sun of irradiance E at incidence θ has
radiance a·E·cos θ / π: the baseline shader must give exactly that through
Cycles' diffuse closure and through its own sun-mode evaluation.
"""

import math

import numpy as np
import pytest

import bpy  # noqa: E402 - Blender as a Python module, a required test dependency

from clothlight.measurement_render import configure_measurement_render, render_to_array
from clothlight.osl_shaders import add_script_node

SUN_IRRADIANCE = 3.0  # W/m²


def lambert_plane_scene(albedo, sun_zenith_deg, sun_mode):
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    configure_measurement_render(scene, resolution=(16, 16), samples=4)
    scene.world = None  # no environment light: the sun is the only source

    bpy.ops.mesh.primitive_plane_add(size=4.0)
    plane = bpy.context.active_object
    material = bpy.data.materials.new("baseline")
    tree = material.node_tree
    tree.nodes.clear()
    shader = add_script_node(tree, "cloth_baseline")
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(shader.outputs["BSDF"], output.inputs["Surface"])
    shader.inputs["DiffuseAlbedo"].default_value = (*albedo, 1.0)
    shader.inputs["SpecularWeight"].default_value = 0.0
    shader.inputs["SunMode"].default_value = int(sun_mode)
    plane.data.materials.append(material)

    zenith = math.radians(sun_zenith_deg)
    toward_sun = (math.sin(zenith), 0.0, math.cos(zenith))
    shader.inputs["SunDirection"].default_value = toward_sun
    shader.inputs["SunIrradiance"].default_value = (SUN_IRRADIANCE,) * 3 + (1.0,)
    sun_data = bpy.data.lights.new("sun", type="SUN")
    sun_data.energy = SUN_IRRADIANCE
    sun_data.angle = 0.0
    sun = bpy.data.objects.new("sun", sun_data)
    scene.collection.objects.link(sun)
    # A sun lamp shines along its local -Z axis.
    sun.rotation_euler = (0.0, zenith, 0.0)

    cam_data = bpy.data.cameras.new("cam")
    cam_data.type = "ORTHO"
    cam_data.ortho_scale = 2.0
    camera = bpy.data.objects.new("cam", cam_data)
    camera.location = (0.0, 0.0, 5.0)
    scene.collection.objects.link(camera)
    scene.camera = camera
    return scene


@pytest.mark.blender
@pytest.mark.parametrize("sun_mode", [False, True], ids=["closures", "sun-mode"])
@pytest.mark.parametrize("sun_zenith_deg", [0.0, 60.0])
def test_lambert_plane_radiance_is_albedo_e_cos_over_pi(tmp_path, sun_mode, sun_zenith_deg):
    albedo = (0.6, 0.3, 0.0)
    scene = lambert_plane_scene(albedo, sun_zenith_deg, sun_mode)
    pixels = render_to_array(scene, tmp_path / "plane.exr")
    expected = np.array(albedo) * SUN_IRRADIANCE * math.cos(math.radians(sun_zenith_deg)) / math.pi
    rgb = pixels[..., :3].reshape(-1, 3)
    np.testing.assert_allclose(rgb.mean(axis=0), expected, rtol=2e-3, atol=1e-5)
    np.testing.assert_allclose(rgb.std(axis=0), 0.0, atol=1e-3 * SUN_IRRADIANCE)
    assert np.all(pixels[..., 3] > 0.999), "the plane must cover every pixel"


SUN_VISIBILITY_SHADER = """
#include "clothlight.h"
shader sun_visibility(vector SunDirection = vector(0, 0, 1), output closure color BSDF = 0)
{
    vector outward = backfacing() ? -Ng : Ng;
    BSDF = (1 - cl_sun_occluded(P, outward, normalize(SunDirection), 1e-5)) * emission();
}
"""


@pytest.mark.blender
@pytest.mark.parametrize(
    "sun_from_below, occluder_z, visible",
    [
        (False, None, 1.0),
        (False, 2.0, 0.0),  # another object between the top face and the sun
        (True, None, 1.0),  # the sun behind the cube: its own far side does not shadow
        (True, -2.0, 0.0),  # ... but another object beyond it does
    ],
)
def test_sun_shadows_come_from_other_objects_only(tmp_path, sun_from_below, occluder_z, visible):
    """cl_sun_occluded: self-shadowing of a closed, convex yarn stands in the tables; other objects cast."""
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    configure_measurement_render(scene, resolution=(8, 8), samples=1)
    scene.world = None
    bpy.ops.mesh.primitive_cube_add(size=2.0)
    cube = bpy.context.active_object
    material = bpy.data.materials.new("visibility")
    tree = material.node_tree
    tree.nodes.clear()
    shader = add_script_node(tree, "sun_visibility", source=SUN_VISIBILITY_SHADER)
    shader.inputs["SunDirection"].default_value = (0.0, 0.0, -1.0 if sun_from_below else 1.0)
    output = tree.nodes.new("ShaderNodeOutputMaterial")
    tree.links.new(shader.outputs["BSDF"], output.inputs["Surface"])
    cube.data.materials.append(material)
    if occluder_z is not None:
        bpy.ops.mesh.primitive_plane_add(size=8.0, location=(0.0, 0.0, occluder_z))
        bpy.context.active_object.visible_camera = False
    cam_data = bpy.data.cameras.new("cam")
    cam_data.type = "ORTHO"
    cam_data.ortho_scale = 1.0  # sees only the cube's top face
    camera = bpy.data.objects.new("cam", cam_data)
    camera.location = (0.0, 0.0, 1.5)
    scene.collection.objects.link(camera)
    scene.camera = camera
    pixels = render_to_array(scene, tmp_path / "visibility.exr")[..., 0]
    np.testing.assert_allclose(pixels, visible, atol=1e-6)
