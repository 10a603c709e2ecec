"""The equal-solid-angle direction grids: exact inverses, equal cells, and the OSL header agrees."""

import math

import numpy as np
import pytest

from precompute.errors import ParameterError
from precompute.tables.grids import AngularGrid


@pytest.mark.parametrize("domain", ["hemisphere", "sphere"])
def test_square_and_direction_maps_are_inverse(domain):
    grid = AngularGrid(domain, 12)
    st = np.random.default_rng(1).random((500, 2))
    directions = grid.square_to_direction(st[:, 0], st[:, 1])
    np.testing.assert_allclose(np.linalg.norm(directions, axis=-1), 1.0, atol=1e-12)
    if domain == "hemisphere":
        assert directions[:, 2].min() >= 0.0
    np.testing.assert_allclose(grid.direction_to_square(directions), st, atol=1e-9)


@pytest.mark.parametrize("domain", ["hemisphere", "sphere"])
def test_cells_cover_equal_solid_angles(domain):
    grid = AngularGrid(domain, 6)
    n = 144_000
    v = np.random.default_rng(2).normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    if domain == "hemisphere":
        v[:, 2] = np.abs(v[:, 2])
    counts = np.bincount(grid.cell_of(v), minlength=grid.n_cells)
    expected = n / grid.n_cells
    # Multinomial counts: chi-square with n_cells - 1 dof stays far below 2x its mean.
    chi2 = ((counts - expected) ** 2 / expected).sum()
    assert chi2 < 2.0 * (grid.n_cells - 1) + 30
    total = 2 * math.pi if domain == "hemisphere" else 4 * math.pi
    assert grid.cell_solid_angle * grid.n_cells == pytest.approx(total)


def test_cell_centers_lie_inside_their_cells():
    grid = AngularGrid("sphere", 8)
    np.testing.assert_array_equal(grid.cell_of(grid.cell_centers()), np.arange(grid.n_cells))


def test_bad_grids_are_refused_by_name():
    with pytest.raises(ParameterError, match="angular_grid.resolution"):
        AngularGrid("sphere", 1)
    with pytest.raises(ParameterError, match="angular_grid.domain"):
        AngularGrid("torus", 12)


MAP_PROBE_SHADER = """
#include "clothlight.h"
shader map_probe(int Sphere = 1, output closure color BSDF = 0)
{
    vector d = normalize(vector(P[0], P[1], 1.5 * P[0] * P[1] - 0.25));
    if (!Sphere)
        d = normalize(vector(P[0], P[1], 0.3 + P[0] * P[0]));
    float s, t;
    if (Sphere)
        cl_sphere_to_square(d, s, t);
    else
        cl_hemisphere_to_square(d, s, t);
    BSDF = color(s, t, 0) * emission();
}
"""


@pytest.mark.render
@pytest.mark.blender
@pytest.mark.parametrize("domain", ["hemisphere", "sphere"])
def test_osl_header_maps_match_python(bpy, tmp_path, domain):
    from clothlight.blender.measurement_render import render_to_array
    from tests.helpers import add_camera, empty_render_scene, script_material

    size = 24
    scene = empty_render_scene(resolution=size, samples=1)
    scene.render.filter_size = 0.01  # sample pixel centres only
    bpy.ops.mesh.primitive_plane_add(size=2.0)
    plane = bpy.context.active_object
    material, probe = script_material("probe", "map_probe", MAP_PROBE_SHADER)
    probe.inputs["Sphere"].default_value = int(domain == "sphere")
    plane.data.materials.append(material)
    add_camera(scene, ortho_scale=2.0, distance=3.0)
    pixels = render_to_array(scene, tmp_path / "probe.exr")

    centers = (np.arange(size) + 0.5) / size * 2.0 - 1.0
    x, y = np.meshgrid(centers, centers[::-1])  # row 0 is the top of the image: largest y
    if domain == "sphere":
        d = np.stack([x, y, 1.5 * x * y - 0.25], axis=-1)
    else:
        d = np.stack([x, y, 0.3 + x * x], axis=-1)
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    expected = AngularGrid(domain, 12).direction_to_square(d)
    np.testing.assert_allclose(pixels[..., :2], expected, atol=2e-4)
