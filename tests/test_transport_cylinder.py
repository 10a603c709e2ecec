"""Monte-Carlo transport in a yarn: energy bookkeeping, reciprocity, symmetry, determinism, the BRDF."""

import numba
import numpy as np
import pytest

from precompute.errors import ParameterError
from precompute.grids import AngularGrid
from precompute.transport import (
    TransportGrids,
    TransportMedium,
    YarnGeometry,
    henyey_greenstein_medium,
    simulate_yarn,
    yarn_brdf,
)

GEOMETRY = YarnGeometry(radius_mm=0.1, index=1.5)
GRIDS = TransportGrids(n_around=8, n_along=4, angular_resolution=4)


def dyed_medium():
    """Three wavelengths: scattering that varies 5-fold and a strong absorption band in the middle."""
    hg = henyey_greenstein_medium(np.ones(3), [0.3, 0.5, 0.2])
    return TransportMedium(np.array([450.0, 550.0, 650.0]), np.array([40.0, 20.0, 8.0]),
                           np.array([5.0, 60.0, 0.5]), hg.phase, hg.phase_icdf)


@pytest.fixture(scope="module")
def dyed():
    return simulate_yarn(dyed_medium(), GEOMETRY, GRIDS, paths_per_cell=24000, seed=2)


def test_energy_bookkeeping(dyed):
    total = dyed.specular + dyed.exit_fraction + dyed.absorbed_fraction + dyed.lost_fraction
    # Each incidence cell is an independent estimate of 1: their scatter measures the noise.
    spread = total.std(axis=0, ddof=1)
    assert np.all(spread < 0.03)
    assert np.all(np.abs(total.mean(axis=0) - 1.0) < 4 * spread / np.sqrt(total.shape[0]) + 1e-4)
    assert dyed.lost_fraction.max() < 1e-4
    assert np.all(dyed.absorbed_fraction[:, 1] > dyed.absorbed_fraction[:, 2])


def test_no_dye_means_no_absorption():
    hg = henyey_greenstein_medium(np.ones(2), [0.4, 0.4], mu_t=15.0)
    transport = simulate_yarn(hg, GEOMETRY, GRIDS, paths_per_cell=500, seed=1)
    assert np.all(transport.absorbed_fraction == 0.0)
    # rays carry flux cos θ / <cos θ>: energy is conserved per ray, so per cell up to that flux's mean
    total = transport.specular + transport.exit_fraction + transport.lost_fraction
    np.testing.assert_allclose(total[:, 0], total[:, 1], rtol=1e-12)
    np.testing.assert_allclose(total.mean(), 1.0, atol=4 * total.std() / np.sqrt(total.size) + 1e-4)


def test_specular_is_the_fresnel_reflectance_of_the_incidence_cells():
    transport = simulate_yarn(dyed_medium(), GEOMETRY, GRIDS, paths_per_cell=2000, seed=4)
    normal_cell = AngularGrid("hemisphere", 4).cell_of(np.array([0.0, 0.0, 1.0]))
    r0 = ((1.5 - 1.0) / (1.5 + 1.0)) ** 2
    # the cell around the normal spans cos θ ≥ 0.8: Fresnel stays within 0.04–0.045 there
    assert r0 <= transport.specular[normal_cell, 0] < 0.046


def test_bssrdf_is_reciprocal(dyed):
    """S(ω_in at dA → dB, ω_out) = S(ω_out at dB → dA, ω_in), summed along the axis, within noise."""
    groups = dyed.exit_radiance_groups.astype(float)  # (G, in, around, out, L)
    mean = groups.mean(axis=0)
    err = groups.std(axis=0, ddof=1) / np.sqrt(groups.shape[0])
    n_around = GRIDS.n_around
    reverse = mean.transpose(2, 1, 0, 3)[:, (-np.arange(n_around)) % n_around]
    reverse_err = err.transpose(2, 1, 0, 3)[:, (-np.arange(n_around)) % n_around]
    sigma = np.hypot(err, reverse_err)
    significant = mean > 10 * sigma.mean()
    z = (mean - reverse)[significant] / np.maximum(sigma[significant], 1e-12)
    assert significant.sum() > 500
    # z from 4 groups is Student-t with 3 degrees of freedom: P(|t| < 3) = 0.94
    assert np.mean(np.abs(z) < 3.0) > 0.9
    assert abs(np.mean(z)) < 0.5


def test_brdf_has_the_mirror_symmetries_of_the_cylinder(dyed):
    brdf = yarn_brdf(dyed, incidence_resolution=6)
    n_i, n_o = brdf.incidence_grid.resolution, brdf.exit_grid.resolution

    def flip(n, axis):
        cells = np.arange(n * n)
        i, j = cells % n, cells // n
        return j * n + (n - 1 - i) if axis == "x" else (n - 1 - j) * n + i

    for axis in ("x", "y"):
        # flipping a direction's x (or y) component mirrors the square's s (or t) coordinate
        mirrored = brdf.rho[flip(n_i, axis)][:, flip(n_o, axis)]
        sigma = np.hypot(brdf.rho_stderr, brdf.rho_stderr[flip(n_i, axis)][:, flip(n_o, axis)])
        significant = brdf.rho > 5 * sigma
        z = (brdf.rho - mirrored)[significant] / sigma[significant]
        assert significant.sum() > 100
        assert np.mean(np.abs(z) < 3.0) > 0.9, axis
        assert abs(np.mean(z)) < 0.5, axis


def test_brdf_is_defined_for_light_from_behind(dyed):
    brdf = yarn_brdf(dyed, incidence_resolution=6)
    behind = brdf.incidence_grid.cell_of(np.array([0.0, 0.0, -1.0]))
    front = brdf.incidence_grid.cell_of(np.array([0.0, 0.0, 1.0]))
    albedo = brdf.hemispherical_albedo()
    assert albedo[behind, 2] > 0.0  # light crosses the yarn to reach the receiving point
    assert albedo[front, 2] > albedo[front, 1]  # the absorption band darkens the middle wavelength


def test_same_seed_gives_identical_tables_whatever_the_thread_count():
    medium = dyed_medium()
    runs = []
    for threads in (1, 2):
        runs.append(simulate_yarn(medium, GEOMETRY, GRIDS, paths_per_cell=200, seed=9, threads=threads))
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    np.testing.assert_array_equal(runs[0].bssrdf, runs[1].bssrdf)
    np.testing.assert_array_equal(runs[0].exit_fraction, runs[1].exit_fraction)
    other = simulate_yarn(medium, GEOMETRY, GRIDS, paths_per_cell=200, seed=10)
    assert not np.array_equal(runs[0].bssrdf, other.bssrdf)


def test_target_error_mode_reaches_its_target():
    transport = simulate_yarn(dyed_medium(), GEOMETRY, GRIDS, target_rel_stderr=0.03, seed=1)
    counted = transport.exit_fraction >= 0.01 * transport.exit_fraction.max(axis=1, keepdims=True)
    assert transport.albedo_rel_stderr[counted].max() <= 0.03


def test_bad_input_names_the_parameter():
    with pytest.raises(ParameterError, match="radius"):
        YarnGeometry(radius_mm=-1.0, index=1.5)
    with pytest.raises(ParameterError, match="n_along"):
        TransportGrids(n_along=3)
    with pytest.raises(ParameterError, match="paths_per_cell"):
        simulate_yarn(dyed_medium(), GEOMETRY, GRIDS)
