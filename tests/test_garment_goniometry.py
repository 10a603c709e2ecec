"""The cloth gonioreflectometer's geometry and calibration (clothlight/garment/goniometry.py) and
the energy balance of cloth tables, without Blender."""

import math

import numpy as np
import pytest

from clothlight.garment.goniometry import (
    ParameterError,
    exit_directions,
    incidence_directions,
    max_tilt,
    patch_rho,
    patch_weights,
    plan_regions,
    side_to_world,
    view_of,
)
from clothlight.garment.tables import check_energy, energy_balance
from precompute.tables.exr import TableError
from precompute.tables.grids import AngularGrid

VIEWS = [(0.0, 0.0, 1.0), (0.6, 0.3, 0.74), (-0.9, 0.1, 0.2), (0.0, 0.3, -0.95), (0.5, -0.5, -0.3)]


def unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


@pytest.fixture
def layout():
    return plan_regions(9, patch_mm=1.0, half_thickness_mm=0.2, view_tilt=4.0, margin_mm=0.1, center=(0.3, -0.2, 0.05))


def test_sides_are_half_turns_about_the_warp():
    d = unit([0.3, -0.4, 0.8])
    back = side_to_world(d, "back")
    assert np.allclose(back, d * [1.0, -1.0, -1.0])
    assert np.allclose(side_to_world(back, "back"), d)
    assert np.isclose(np.linalg.det(np.diag([1.0, -1.0, -1.0])), 1.0)
    assert np.all(exit_directions(4, "back")[:, 2] < 0) and np.all(exit_directions(4, "front")[:, 2] > 0)
    with pytest.raises(ParameterError):
        side_to_world(d, "inside")


@pytest.mark.parametrize("n", [3, 5, 9])
def test_odd_incidence_grids_keep_every_sun_off_the_cloth_plane(n):
    assert np.min(np.abs(incidence_directions(n, "front")[:, 2])) > 0.1
    assert math.isfinite(max_tilt(incidence_directions(n, "front")))
    # The even grid this avoids: cell centres on the octahedral square's diagonal lie in the plane.
    assert np.min(np.abs(AngularGrid("sphere", n + 1).cell_centers()[:, 2])) < 1e-9


def test_regions_and_patches(layout):
    centers = layout.region_centers()
    assert centers.shape == (9, 2)
    assert np.array_equal(layout.region_of(centers), np.arange(9))
    assert np.array_equal(layout.patch_of(centers), np.arange(9))
    # A point in a region's guard band belongs to the region but to no patch.
    guard = centers + [0.5 * layout.patch_mm + 0.01, 0.0]
    assert np.array_equal(layout.region_of(guard), np.arange(9))
    assert np.all(layout.patch_of(guard) == -1)
    far = np.array([[100.0, 0.0]])
    assert layout.region_of(far)[0] == -1 and layout.patch_of(far)[0] == -1
    assert layout.pitch_mm == pytest.approx(1.0 + 2 * (0.2 * 4.0 + 0.1))


@pytest.mark.parametrize("toward_camera", VIEWS)
def test_camera_axes_and_midplane_points(layout, toward_camera):
    w = unit(toward_camera)
    view = view_of(w, layout, pixels_per_patch=12)
    m = view.camera_matrix(10.0)[:3, :3]
    assert np.allclose(m.T @ m, np.eye(3)) and np.isclose(np.linalg.det(m), 1.0)
    assert np.allclose(m[:, 2], w)
    # The image centre's ray crosses the mid-plane at the layout's centre.
    assert np.allclose(view.midplane_points(view.width / 2, view.height / 2), layout.center[:2])
    # Every patch is inside the image.
    corners = view.midplane_points(np.array([0, view.width]), np.array([0, view.height]))
    assert corners.shape == (2, 2)


@pytest.mark.parametrize("toward_camera", VIEWS)
def test_patch_weights_count_each_patch_once_and_whole(layout, toward_camera):
    view = view_of(unit(toward_camera), layout, pixels_per_patch=12)
    index, weight = patch_weights(view, layout)
    counted = np.bincount(index[index >= 0], weight[index >= 0], 9) * view.pixel_mm**2
    projected = layout.patch_mm**2 * abs(unit(toward_camera)[2])
    assert np.allclose(counted, projected, rtol=0.03)


@pytest.mark.parametrize("toward_camera", VIEWS)
def test_patch_rho_is_the_mean_radiance_over_each_patch(layout, toward_camera):
    """Radiance linear in the mid-plane point, L = 1 + 0.3 x + 0.2 y, and film alpha 0.5: each
    patch's ρ is L at its centre over E (a linear field's mean over a centred square), its coverage 0.5."""
    view = view_of(unit(toward_camera), layout, pixels_per_patch=12)
    index, weight = patch_weights(view, layout)
    rows, columns = np.mgrid[0:view.height, 0:view.width]
    xy = view.midplane_points(columns + 0.5, rows + 0.5)
    pixels = np.zeros((view.height, view.width, 4))
    pixels[..., 0] = 1.0 + 0.3 * xy[..., 0] + 0.2 * xy[..., 1]
    pixels[..., 1] = 1.0
    pixels[..., 3] = 0.5
    rho, coverage = patch_rho(pixels, index, weight, view, layout, sun_irradiance=2.0)
    centers = layout.region_centers()
    expected = (1.0 + 0.3 * centers[:, 0] + 0.2 * centers[:, 1]) / 2.0
    assert np.allclose(rho[:, 0], expected, atol=0.005)
    assert np.allclose(rho[:, 1], 0.5) and np.allclose(coverage, 0.5)


def test_views_in_the_cloth_plane_are_refused(layout):
    with pytest.raises(ParameterError):
        view_of((1.0, 0.0, 0.0), layout, 12)
    with pytest.raises(ParameterError):
        plan_regions(9, patch_mm=0.0, half_thickness_mm=0.2, view_tilt=1.0, margin_mm=0.1)


def lambertian_front(albedo: float, coverage: float, n_i: int = 9, n_o: int = 8) -> tuple[dict, dict]:
    """(ρ, coverage) of a cloth whose front is a Lambertian reflector of ``albedo`` (ρ = albedo/π cos θ_i
    for light on its side), covering ``coverage`` of the cloth; the back reflects nothing."""
    incidence = AngularGrid("sphere", n_i).cell_centers()
    rho_front = np.zeros((n_i**2, n_o**2, 3))
    rho_front[incidence[:, 2] > 0] = (albedo / math.pi * incidence[incidence[:, 2] > 0, 2])[:, None, None]
    return ({"front": rho_front, "back": np.zeros_like(rho_front)},
            {"front": np.full(n_o**2, coverage), "back": np.full(n_o**2, coverage)})


def test_energy_balance_of_a_lambertian_reflector_and_an_open_weave():
    """Front: a Lambertian reflector of albedo 0.6 covering 70 % of the cloth; the back: nothing.
    Reflected ≈ 0.6, transmitted 0, open 0.3."""
    n_i = 9
    incidence = AngularGrid("sphere", n_i).cell_centers()
    balance = energy_balance(*lambertian_front(0.6, 0.7, n_i), n_i)
    front_lit = incidence[:, 2] > 0.3
    assert np.allclose(balance["reflected"][front_lit], 0.6, rtol=0.05)
    assert np.allclose(balance["transmitted"][front_lit], 0.0)
    assert np.allclose(balance["open"], 0.3)
    assert np.all(balance["total"][front_lit] <= 0.9 * 1.05)
    check_energy(balance, n_i)  # a cloth that conserves energy passes


def test_a_cloth_that_sends_away_more_light_than_it_receives_is_refused():
    """A reflector of albedo 1.2 (ρ scaled ×2) covering the whole cloth: its yarn tables are refused."""
    with pytest.raises(TableError, match="break energy conservation.*at most 1 \\+ 0.05"):
        check_energy(energy_balance(*lambertian_front(1.2, 1.0), 9), 9)
