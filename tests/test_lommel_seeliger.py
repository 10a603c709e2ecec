"""The fuzz term (precompute.optics.lommel_seeliger): Hapke's single-scattering law of an isotropic
layer, its closed-form directional albedo against a quadrature of its definition, a layer that
scatters forward, the general modes' two lobes for it, a layer of fibres that lie flat, and what the
fit's cloth response adds with it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from precompute.optics.cook_torrance import beckmann_reflection, direction
from precompute.optics.lommel_seeliger import (FUZZ_FORWARD_SLOPE, forward_lobe_albedos, fuzz_albedo_at_view,
                                              fuzz_albedo_sides_at_view, fuzz_brdf, fuzz_general_lobes, fuzz_phase,
                                              fuzz_projected_area, fuzz_transmittance, hemispherical_transmittance,
                                              lommel_seeliger, lommel_seeliger_albedo)
from precompute.optics.phase import henyey_greenstein_phase


@pytest.mark.parametrize("theta_o_deg", [0.0, 30.0, 60.0, 85.0])
def test_the_directional_albedo_is_the_integral_of_the_law(theta_o_deg):
    # a(μo) = ∫ f μi dω over the upper hemisphere, by a midpoint rule in μi (the law has no azimuth)
    count = 200_000
    mu_i = (np.arange(count) + 0.5) / count
    view = direction(theta_o_deg, 0.0)
    light = np.stack([np.sqrt(1.0 - mu_i**2), np.zeros(count), mu_i], axis=-1)
    integral = 2.0 * math.pi * np.mean(lommel_seeliger(light, view, 0.4) * mu_i)
    assert lommel_seeliger_albedo(math.cos(math.radians(theta_o_deg)), 0.4) == pytest.approx(integral, rel=1e-4)


def test_the_law_is_reciprocal_white_of_its_albedo_and_zero_below_the_plane():
    rng = np.random.default_rng(3)
    light, view = (direction(rng.uniform(0, 89, 50), rng.uniform(0, 360, 50)) for _ in range(2))
    np.testing.assert_allclose(lommel_seeliger(light, view, 0.2), lommel_seeliger(view, light, 0.2))
    np.testing.assert_allclose(lommel_seeliger(light, view, 0.2), 0.2 / (4 * math.pi * (light[:, 2] + view[:, 2])))
    below = view * np.array([1.0, 1.0, -1.0])
    assert not np.any(lommel_seeliger(light, below, 0.2))
    # grazing: half the albedo comes back; at normal view 1 − ln 2 of that
    assert lommel_seeliger_albedo(0.0, 0.2) == pytest.approx(0.1)
    assert lommel_seeliger_albedo(1.0, 0.2) == pytest.approx(0.1 * (1.0 - math.log(2.0)))


@pytest.mark.parametrize("depth", [0.05, 0.3, 1.5])
def test_a_fuzz_of_depth_is_the_single_scattering_of_a_layer_that_deep(depth):
    # from its definition: light reaching optical depth t along the slant path t/μi, scattered
    # isotropically with albedo A, leaving along t/μo; f = (A / (4π μi μo)) ∫₀^τ exp(−t (1/μi + 1/μo)) dt
    rng = np.random.default_rng(5)
    light, view = (direction(rng.uniform(0, 85, 40), rng.uniform(0, 360, 40)) for _ in range(2))
    mu_i, mu_o = light[:, 2], view[:, 2]
    t = (np.arange(20_000) + 0.5) / 20_000 * depth
    integral = np.exp(-t[:, None] * (1.0 / mu_i + 1.0 / mu_o)).mean(axis=0) * depth
    np.testing.assert_allclose(fuzz_brdf(light, view, 0.4, depth), 0.4 / (4 * math.pi * mu_i * mu_o) * integral,
                               rtol=1e-6)
    # what it lets through to the cloth beneath, in and out, whichever face the light is on
    np.testing.assert_allclose(fuzz_transmittance(mu_i, mu_o, depth), np.exp(-depth * (1 / mu_i + 1 / mu_o)))
    np.testing.assert_allclose(fuzz_transmittance(-mu_i, mu_o, depth), fuzz_transmittance(mu_i, mu_o, depth))
    assert fuzz_transmittance(0.0, 0.5, depth) == 0.0


def test_a_deep_fuzz_is_the_semi_infinite_law_and_a_depth_of_zero_the_veneer_before_it():
    light, view = direction(np.array([10.0, 50.0, 80.0]), 0.0), direction(np.array([0.0, 40.0, 70.0]), 90.0)
    np.testing.assert_allclose(fuzz_brdf(light, view, 0.3, 60.0), lommel_seeliger(light, view, 0.3))
    np.testing.assert_array_equal(fuzz_brdf(light, view, 0.3, 0.0), lommel_seeliger(light, view, 0.3))
    np.testing.assert_array_equal(fuzz_transmittance(light[:, 2], view[:, 2], 0.0), 1.0)
    assert hemispherical_transmittance(0.0) == 1.0
    np.testing.assert_array_equal(fuzz_albedo_at_view(view[:, 2], 0.3, 0.0), lommel_seeliger_albedo(view[:, 2], 0.3))


@pytest.mark.parametrize("depth", [0.05, 0.3, 1.5])
def test_the_general_modes_sums_are_the_integrals_they_stand_for(depth):
    from scipy.integrate import quad
    from scipy.special import expn

    assert hemispherical_transmittance(depth) == pytest.approx(2.0 * expn(3, depth), rel=1e-4)
    for mu_o in (0.05, 0.3, 0.7, 1.0):
        view = np.array([math.sqrt(1.0 - mu_o**2), 0.0, mu_o])
        exact = quad(lambda mu: 2 * math.pi * mu * float(fuzz_brdf(
            np.array([math.sqrt(1.0 - mu**2), 0.0, mu]), view, 0.4, depth)), 0.0, 1.0, limit=200)[0]
        assert fuzz_albedo_at_view(mu_o, 0.4, depth) == pytest.approx(exact, rel=2e-3)


@pytest.mark.parametrize("asymmetry", [-0.3, 0.5, 0.85])
@pytest.mark.parametrize("depth", [0.0, 0.3])
def test_a_fuzz_that_scatters_forward_weighs_the_layer_by_its_phase_function(asymmetry, depth):
    rng = np.random.default_rng(11)
    light, view = (direction(rng.uniform(0, 85, 40), rng.uniform(0, 360, 40)) for _ in range(2))
    scattering = -np.sum(light * view, axis=-1)  # the light's way in against the view's way out
    phase = 4 * math.pi * henyey_greenstein_phase(scattering, asymmetry)
    np.testing.assert_allclose(fuzz_phase(light, view, asymmetry), phase)
    forward = fuzz_brdf(light, view, 0.4, depth, asymmetry)
    np.testing.assert_allclose(forward, fuzz_brdf(light, view, 0.4, depth) * phase)
    # reciprocal, and isotropic at g = 0 exactly as before
    np.testing.assert_allclose(forward, fuzz_brdf(view, light, 0.4, depth, asymmetry))
    np.testing.assert_array_equal(fuzz_brdf(light, view, 0.4, depth, 0.0), fuzz_brdf(light, view, 0.4, depth))
    # forward (light grazing from one side, seen grazing from the other) against back toward the light
    grazing, beyond = direction(75.0, 180.0), direction(75.0, 0.0)
    ratio = fuzz_brdf(grazing, beyond, 0.4, depth, asymmetry) / fuzz_brdf(grazing, grazing, 0.4, depth, asymmetry)
    assert (ratio > 10.0) if asymmetry > 0.4 else (ratio < 1.0)


@pytest.mark.parametrize("asymmetry", [0.5, 0.85])
@pytest.mark.parametrize("depth", [0.0, 0.3])
@pytest.mark.parametrize("theta_o_deg", [5.0, 45.0, 80.0])
def test_the_directional_albedo_of_a_forward_fuzz_is_the_integral_of_its_brdf(asymmetry, depth, theta_o_deg):
    # a(μo) = ∫ f μi dω over the upper hemisphere, by a midpoint rule in θi and φi (400 × 800)
    theta = (np.arange(400) + 0.5) / 400 * math.pi / 2
    phi = (np.arange(800) + 0.5) / 800 * 2 * math.pi
    t, p = np.meshgrid(theta, phi, indexing="ij")
    light = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)
    view = direction(theta_o_deg, 0.0)
    f = fuzz_brdf(light, view, 0.7, depth, asymmetry)
    integral = np.sum(f * np.cos(t) * np.sin(t)) * (math.pi / 2 / 400) * (2 * math.pi / 800)
    mu_o = math.cos(math.radians(theta_o_deg))
    assert fuzz_albedo_at_view(mu_o, 0.7, depth, asymmetry) == pytest.approx(integral, rel=1e-3)
    # the forward light goes down into the cloth: less comes back than from an isotropic fuzz
    assert fuzz_albedo_at_view(mu_o, 0.7, depth, asymmetry) < fuzz_albedo_at_view(mu_o, 0.7, depth)


def _hemisphere_midpoints(theta_o_deg: float, count: int = 400):
    """Lights at midpoints in θi and φi over the upper hemisphere (count × 2 count), the solid-angle
    weights times μi, and the view at ``theta_o_deg`` leaning toward −x (φ = 180°)."""
    theta = (np.arange(count) + 0.5) / count * math.pi / 2
    phi = (np.arange(2 * count) + 0.5) / (2 * count) * 2 * math.pi
    t, p = np.meshgrid(theta, phi, indexing="ij")
    light = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1)
    weight = np.cos(t) * np.sin(t) * (math.pi / 2 / count) * (math.pi / count)
    return light, weight, direction(theta_o_deg, 180.0)


@pytest.mark.parametrize("theta_o_deg", [10.0, 45.0, 80.0])
def test_the_forward_lobes_albedos_are_the_integrals_of_its_brdf(theta_o_deg):
    # a_m = ∫ f_m μi dω; b_m half the far side's (lights at x > 0, the view leaning toward −x) less the near's
    light, weight, view = _hemisphere_midpoints(theta_o_deg)
    lobe = beckmann_reflection(light, view, FUZZ_FORWARD_SLOPE) * weight
    far = light[..., 0] > 0.0
    albedo, excess = forward_lobe_albedos(math.cos(math.radians(theta_o_deg)))
    assert albedo == pytest.approx(lobe.sum(), rel=2e-3)
    assert excess == pytest.approx(0.5 * (lobe[far].sum() - lobe[~far].sum()), rel=5e-3)
    assert 0.0 < excess < 0.5 * albedo <= 0.5  # a reflection lobe: most of its light from the far side


@pytest.mark.parametrize("depth", [0.0, 0.3])
@pytest.mark.parametrize("theta_o_deg", [10.0, 45.0, 80.0])
def test_the_general_modes_two_lobes_keep_the_fuzzs_light_and_its_far_side_excess(depth, theta_o_deg):
    # d + s a_m = a and s b_m = b: the diffuse lobe returns as much from either side, the forward lobe
    # b_m more from the far side; both are the fuzz's own sides (its BRDF integrated side by side)
    light, weight, view = _hemisphere_midpoints(theta_o_deg)
    f = fuzz_brdf(light, view, 0.7, depth, 0.76) * weight
    far = light[..., 0] > 0.0
    mu_o = math.cos(math.radians(theta_o_deg))
    near_sum, far_sum = fuzz_albedo_sides_at_view(mu_o, 0.7, depth, 0.76)
    assert far_sum == pytest.approx(f[far].sum(), rel=5e-3) and near_sum == pytest.approx(f[~far].sum(), rel=5e-3)
    diffuse, forward = fuzz_general_lobes(mu_o, 0.7, depth, 0.76)
    lobe = beckmann_reflection(light, view, FUZZ_FORWARD_SLOPE) * weight
    total = diffuse / math.pi * weight + forward * lobe  # a diffuse closure of weight d is d/π
    assert total.sum() == pytest.approx(near_sum + far_sum, rel=3e-3)
    assert forward > 0.0 and diffuse > 0.0
    assert total[far].sum() - total[~far].sum() == pytest.approx(far_sum - near_sum, rel=1e-2)
    # the diffuse lobe alone (the general modes before) has no far-side excess at all
    assert far_sum - near_sum > 0.08 * (far_sum + near_sum)


def test_an_isotropic_fuzz_is_a_diffuse_lobe_alone_and_the_general_mode_as_before():
    mu_o = np.linspace(0.05, 1.0, 9)
    diffuse, forward = fuzz_general_lobes(mu_o, 0.4, 0.3, 0.0)
    np.testing.assert_array_equal(forward, 0.0)
    np.testing.assert_array_equal(diffuse, fuzz_albedo_at_view(mu_o, 0.4, 0.3))
    # a fuzz that scatters back has less far-side light than near: no forward lobe either
    np.testing.assert_array_equal(fuzz_general_lobes(mu_o, 0.4, 0.3, -0.3)[1], 0.0)


@pytest.mark.parametrize("theta_deg", [0.0, 20.0, 45.0, 60.0, 80.0, 90.0])
def test_fibres_lying_flat_show_a_direction_the_mean_of_their_shadows_over_the_azimuth(theta_deg):
    # The area a cylinder along t shows the direction ω is ∝ |ω × t|: its mean over fibres along every
    # azimuth in the plane, by a midpoint rule, over its value along the normal (1), is s(μ) for F = 1.
    count = 100_000
    psi = (np.arange(count) + 0.5) * 2.0 * math.pi / count
    fibres = np.stack([np.cos(psi), np.sin(psi), np.zeros(count)], axis=-1)
    omega = direction(theta_deg, 30.0)
    mean_shadow = np.mean(np.linalg.norm(np.cross(omega, fibres), axis=-1))
    mu = math.cos(math.radians(theta_deg))
    assert fuzz_projected_area(mu, 1.0) == pytest.approx(mean_shadow, rel=1e-6)
    # a share F lying flat, the rest in every direction (which show every direction alike)
    assert fuzz_projected_area(mu, 0.4) == pytest.approx(0.6 + 0.4 * mean_shadow, rel=1e-6)
    assert fuzz_projected_area(-mu, 0.4) == fuzz_projected_area(mu, 0.4)
    np.testing.assert_array_equal(fuzz_projected_area(np.array([mu, 0.2]), 0.0), 1.0)


def test_a_flat_fuzz_is_reciprocal_returns_at_most_its_albedo_and_is_the_fuzz_before_at_no_flatness():
    light, view = direction(np.array([10.0, 50.0, 80.0]), 0.0), direction(np.array([0.0, 40.0, 70.0]), 90.0)
    for depth in (0.0, 0.3):
        np.testing.assert_array_equal(fuzz_brdf(light, view, 0.3, depth, 0.4, 0.0),
                                      fuzz_brdf(light, view, 0.3, depth, 0.4))
        np.testing.assert_allclose(fuzz_brdf(light, view, 0.3, depth, 0.4, 0.8),
                                   fuzz_brdf(view, light, 0.3, depth, 0.4, 0.8))
    mu = np.linspace(0.02, 1.0, 25)
    assert np.all(fuzz_albedo_at_view(mu, 1.0, 5.0, flatness=1.0) <= 1.0)
    np.testing.assert_allclose(fuzz_transmittance(light[:, 2], view[:, 2], 0.3, 0.0), fuzz_transmittance(
        light[:, 2], view[:, 2], 0.3))


@pytest.mark.parametrize("depth", [0.0, 0.3])
@pytest.mark.parametrize("asymmetry", [0.0, 0.5])
def test_a_flat_fuzzs_sums_are_the_integrals_they_stand_for(depth, asymmetry):
    from scipy.integrate import dblquad, quad

    flatness = 0.8
    assert hemispherical_transmittance(0.3, flatness) == pytest.approx(quad(
        lambda mu: 2.0 * mu * math.exp(-0.3 * float(fuzz_projected_area(mu, flatness)) / mu), 0.0, 1.0)[0], rel=1e-3)
    for mu_o in (0.1, 0.5, 0.9):
        view = np.array([math.sqrt(1.0 - mu_o**2), 0.0, mu_o])

        def integrand(phi, mu):
            light = np.array([math.sqrt(1.0 - mu**2) * math.cos(phi), math.sqrt(1.0 - mu**2) * math.sin(phi), mu])
            return 2.0 * mu * float(fuzz_brdf(light, view, 0.4, depth, asymmetry, flatness))

        exact = dblquad(integrand, 0.0, 1.0, 0.0, math.pi, epsabs=1e-7)[0]
        assert fuzz_albedo_at_view(mu_o, 0.4, depth, asymmetry, flatness) == pytest.approx(exact, rel=5e-3)


def test_a_flat_fuzz_seen_and_lit_low_shows_less_of_itself_than_a_fuzz_of_fibres_in_every_direction():
    # The same layer along the normal; at θi = θv = 60° toward the light it shows 0.77 of the area: its
    # light there, over its light at normal light and view, is less; its slant paths are shorter, so it
    # lets more of the yarn through.
    normal, low_light, low_view = direction(0.0, 0.0), direction(60.0, 0.0), direction(60.0, 0.0)
    ratios = [float(fuzz_brdf(low_light, low_view, 0.5, 0.2, 0.0, flatness)
                    / fuzz_brdf(normal, normal, 0.5, 0.2, 0.0, flatness)) for flatness in (0.0, 1.0)]
    assert ratios[1] < 0.85 * ratios[0]
    assert fuzz_brdf(normal, normal, 0.5, 0.2, 0.0, 1.0) == pytest.approx(fuzz_brdf(normal, normal, 0.5, 0.2))
    assert fuzz_transmittance(0.5, 0.5, 0.2, 1.0) > fuzz_transmittance(0.5, 0.5, 0.2)
