"""The tables' incidence lookup has no crease on the planes that matter (issue: light across the yarn).

The octahedral map folds along its axes (r = |u| + |v|): the planes x = 0 (light across the yarn)
and y = 0 (the axis–normal plane).  With an odd N_i those planes run through cell centres, so the
bilinear lookup there blends cells on the plane, and a smooth ρ reads back within the grid's
interpolation error at every azimuth; with an even N_i they fall on cell edges and ρ is read as if
the light were more grazing.
"""

import numpy as np
import pytest

from precompute.tables.grids import AngularGrid
from precompute.tables.layout import brdf_atlas, interpolate_rho
from precompute.transport.brdf import INCIDENCE_RESOLUTIONS

ZENITHS_DEG = (10.0, 30.0, 45.0, 60.0)


def cosine_rho(wi):
    return np.maximum(wi[..., 2], 0.0)


def read_back(resolution, zenith_deg):
    """(read, true) ρ = max(cos θi, 0) through ``interpolate_rho`` at every 2.5° of azimuth."""
    atlas = brdf_atlas(np.broadcast_to(cosine_rho(AngularGrid("sphere", resolution).cell_centers())[:, None, None],
                                       (resolution**2, 4, 3)))
    phi = np.radians(np.arange(0.0, 360.0, 2.5))
    theta = np.radians(zenith_deg)
    wi = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.full_like(phi, np.cos(theta))], -1)
    wo = np.broadcast_to([0.0, 0.0, 1.0], wi.shape)
    return interpolate_rho(atlas, resolution, wi, wo)[:, 0], cosine_rho(wi)


@pytest.mark.parametrize("resolution", INCIDENCE_RESOLUTIONS)
@pytest.mark.parametrize("zenith_deg", ZENITHS_DEG)
def test_a_smooth_rho_reads_back_within_one_percent_at_every_azimuth(resolution, zenith_deg):
    read, true = read_back(resolution, zenith_deg)
    np.testing.assert_allclose(read, true, rtol=0.01)


def test_an_even_grid_reads_light_across_the_yarn_as_more_grazing():
    # the lookup bug the odd grids remove: at 60° in the plane x = 0, a quarter too dark
    read, true = read_back(12, 60.0)
    across = 36  # azimuth 90°: the plane x = 0
    assert read[across] / true[across] < 0.8
