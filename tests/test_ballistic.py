"""The unscattered light through a yarn in closed form (precompute/optics/ballistic.py).

Held against geometry (Snell at both ends, the fibre's specular cone, the chords of a circle) and
against the transport itself: the share of each incidence cell's flux that the Monte-Carlo
transport sees leave without a collision is the closed form's, cell by cell.
"""

import math

import numpy as np
import pytest

from precompute.errors import ParameterError
from precompute.optics import ballistic
from precompute.tables.grids import AngularGrid
from precompute.tables.layout import interpolate_attenuation, interpolate_unscattered_rho
from precompute.transport import TransportGrids, YarnGeometry, henyey_greenstein_medium, simulate_yarn

INDEX = 1.557


def unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def test_a_normal_exit_comes_straight_through_or_back_after_one_reflection():
    wi, fresnel, length = ballistic.unscattered_paths(np.array([0.0, 0.0, 1.0]), INDEX)
    np.testing.assert_allclose(wi[0], [0, 0, -1], atol=1e-12)  # lit from straight behind
    np.testing.assert_allclose(wi[1], [0, 0, 1], atol=1e-12)  # retro-reflection
    np.testing.assert_allclose(length, 2.0 * np.arange(1, ballistic.ORDERS + 1))
    f = ((INDEX - 1) / (INDEX + 1)) ** 2
    np.testing.assert_allclose(fresnel, (1 - f) ** 2 * f ** np.arange(ballistic.ORDERS))


def test_a_yarn_of_fibres_in_air_lets_its_unscattered_light_straight_through():
    # boundary index 1 (issue 43's host of air): no refraction, no reflection inside, the chord's length
    rng = np.random.default_rng(5)
    wo = unit(rng.normal(size=(100, 3)))
    wo[:, 2] = np.abs(wo[:, 2])
    wo[0] = [0.0, 1.0, 0.0]  # grazing, where Fresnel's formula is 0/0
    wi, fresnel, length = ballistic.unscattered_paths(wo, 1.0)
    np.testing.assert_allclose(wi[:, 0], -wo, atol=1e-9)
    np.testing.assert_array_equal(fresnel, np.repeat([[1.0] + [0.0] * (ballistic.ORDERS - 1)], len(wo), axis=0))
    np.testing.assert_allclose(length[:, 0], 2.0 * wo[:, 2] / (1.0 - wo[:, 0] ** 2), rtol=1e-5)
    with pytest.raises(ParameterError, match="≥ 1"):
        ballistic.unscattered_paths(wo, 0.9)


@pytest.mark.parametrize("seed", range(3))
def test_every_path_obeys_snell_keeps_the_axial_cosine_and_runs_equal_chords(seed):
    rng = np.random.default_rng(seed)
    wo = unit(rng.normal(size=(200, 3)))
    wo[:, 2] = np.abs(wo[:, 2])
    wi, fresnel, length = ballistic.unscattered_paths(wo, INDEX)
    np.testing.assert_allclose(np.linalg.norm(wi, axis=-1), 1.0, atol=1e-12)
    np.testing.assert_allclose(wi[..., 0], np.broadcast_to(-wo[:, None, 0], wi.shape[:-1]), atol=1e-12)  # fibre cone
    # equal chords: the k-th path is k + 1 times the first
    np.testing.assert_allclose(length, length[:, :1] * np.arange(1, ballistic.ORDERS + 1), rtol=1e-9)
    # the chord of a circle at the refraction angle, seen along the axis
    u_x = wo[:, 0] / INDEX
    cos_t = np.sqrt(1 - (wo[:, 0] ** 2 + wo[:, 1] ** 2) / INDEX**2)
    np.testing.assert_allclose(length[:, 0], 2 * cos_t / (1 - u_x**2), rtol=1e-9)
    assert np.all(fresnel[:, 1:] < fresnel[:, :-1])


def test_the_cone_kernel_is_a_normalised_density():
    """It integrates to 1 less its tail beyond the cut, P(κ(1 − cos γ) > c) = (e^{−c} − e^{−2κ}) /
    (1 − e^{−2κ}), and is zero there."""
    theta = np.linspace(0.0, np.pi, 200_001)
    for spread in (0.01, 0.05, 0.5):
        kappa = 1.0 / spread**2
        tail = max(math.exp(-ballistic.CONE_CUTOFF) - math.exp(-2 * kappa), 0.0) / -math.expm1(-2 * kappa)
        cone = ballistic.cone_kernel(np.cos(theta), spread)
        density = cone * 2 * np.pi * np.sin(theta)
        assert np.trapz(density, theta) == pytest.approx(1.0 - tail, rel=4e-7)  # the step at the cut
        assert np.all(cone[kappa * (1 - np.cos(theta)) > ballistic.CONE_CUTOFF + 1e-9] == 0.0)


def test_the_attenuation_table_reads_back_beer_lambert():
    mu_t, radius = np.array([0.5, 3.0, 20.0]), 0.1
    table = ballistic.attenuation(mu_t, radius, ballistic.attenuation_lengths())[None]
    lengths = np.linspace(0.0, ballistic.MAX_LENGTH_OVER_RADIUS, 37)
    np.testing.assert_allclose(interpolate_attenuation(table, lengths), np.exp(-np.outer(lengths * radius, mu_t)),
                               rtol=2e-3)


def test_spread_unscattered_rho_integrates_to_the_radiance_factor():
    mu_t, radius = np.array([2.0, 8.0]), 0.1
    table = ballistic.attenuation(mu_t, radius, ballistic.attenuation_lengths())[None]
    wo = unit([0.2, -0.4, 0.8])
    grid = AngularGrid("sphere", 600)
    wi = grid.cell_centers()
    rho = interpolate_unscattered_rho(table, INDEX, wi, wo, spread_rad=0.05)
    exact = ballistic.unscattered_radiance_factor(wo, INDEX, lambda length: ballistic.attenuation(mu_t, radius, length))
    np.testing.assert_allclose(rho.sum(axis=0) * grid.cell_solid_angle, exact, rtol=5e-3)


@pytest.mark.slow
def test_the_transport_sees_the_closed_form_leave_unscattered():
    # A thin medium: most light crosses without a collision.  Per incidence cell, the share that
    # leaves unscattered must be the closed form's, averaged over the cell as the source samples
    # it (uniform in the square, weighted by cos θ).
    medium = henyey_greenstein_medium([1.0 / 1.5, 4.0 / 6.0], 0.5, mu_t=[1.5, 6.0], wavelengths_nm=[500.0, 600.0])
    geometry = YarnGeometry(0.1, INDEX)
    resolution = 6
    transport = simulate_yarn(medium, geometry, TransportGrids(8, 4, resolution), paths_per_cell=40_000, seed=3)
    directions = AngularGrid("hemisphere", resolution).cell_samples(24)
    factor = ballistic.unscattered_radiance_factor(
        directions, INDEX, lambda length: ballistic.attenuation(medium.mu_t, geometry.radius_mm, length))
    cos = directions[..., 2][..., None]
    expected = (factor * cos).sum(axis=1) / cos.sum(axis=1)
    measured = transport.unscattered_fraction
    sigma = np.sqrt(measured * (1 - measured) / transport.paths_per_cell[:, None]) * math.sqrt(2.0)
    assert measured.mean() > 0.3
    assert np.all(np.abs(measured - expected) < 4 * sigma + 2e-3)
    total = (transport.specular + transport.exit_fraction + transport.unscattered_fraction
             + transport.absorbed_fraction + transport.lost_fraction)
    np.testing.assert_allclose(total, 1.0, atol=0.01)  # each wavelength's paths conserve it in expectation
