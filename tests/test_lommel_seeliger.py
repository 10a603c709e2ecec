"""The fuzz term (precompute.optics.lommel_seeliger): Hapke's single-scattering law of an isotropic
layer, its closed-form directional albedo against a quadrature of its definition, and what the fit's
cloth response adds with it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from precompute.optics.cook_torrance import direction
from precompute.optics.lommel_seeliger import lommel_seeliger, lommel_seeliger_albedo


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
