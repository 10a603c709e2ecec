"""Cycles renders ClothLight's OSL shaders headless on the CPU, with exact radiometry.

A Lambertian plane of albedo a under a sun of irradiance E at incidence θ has
radiance a·E·cos θ / π: the baseline shader must give exactly that through
Cycles' diffuse closure and through its own sun-mode evaluation.
"""

import math

import numpy as np
import pytest

from tests.helpers import add_camera, add_sun, direction, empty_render_scene, script_material

bpy = pytest.importorskip("bpy")

from clothlight.blender.measurement_render import render_to_array  # noqa: E402

pytestmark = pytest.mark.render

SUN_IRRADIANCE = 3.0  # W/m²


def lambert_plane_scene(albedo, sun_zenith_deg, sun_mode):
    scene = empty_render_scene(resolution=16, samples=4)  # no environment light: the sun is the only source
    bpy.ops.mesh.primitive_plane_add(size=4.0)
    plane = bpy.context.active_object
    material, shader = script_material("baseline", "cloth_baseline")
    shader.inputs["DiffuseAlbedo"].default_value = (*albedo, 1.0)
    shader.inputs["SpecularWeight"].default_value = 0.0
    shader.inputs["SunMode"].default_value = int(sun_mode)
    plane.data.materials.append(material)

    toward_sun = direction(sun_zenith_deg, 0.0)
    shader.inputs["SunDirection"].default_value = toward_sun
    shader.inputs["SunIrradiance"].default_value = (SUN_IRRADIANCE,) * 3 + (1.0,)
    add_sun(scene, toward_sun, SUN_IRRADIANCE)
    add_camera(scene, ortho_scale=2.0)
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
    scene = empty_render_scene(resolution=8, samples=1)
    bpy.ops.mesh.primitive_cube_add(size=2.0)
    cube = bpy.context.active_object
    material, shader = script_material("visibility", "sun_visibility", SUN_VISIBILITY_SHADER)
    shader.inputs["SunDirection"].default_value = (0.0, 0.0, -1.0 if sun_from_below else 1.0)
    cube.data.materials.append(material)
    if occluder_z is not None:
        bpy.ops.mesh.primitive_plane_add(size=8.0, location=(0.0, 0.0, occluder_z))
        bpy.context.active_object.visible_camera = False
    add_camera(scene, ortho_scale=1.0, distance=1.5)  # sees only the cube's top face
    pixels = render_to_array(scene, tmp_path / "visibility.exr")[..., 0]
    np.testing.assert_allclose(pixels, visible, atol=1e-6)
