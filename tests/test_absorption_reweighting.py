"""Absorption without new transport: one simulation's exits, tallied at a series of absorptions,
give the yarn at any absorption in between (precompute/transport/absorption.py)."""

import numpy as np
import pytest

from precompute.errors import ParameterError
from precompute.transport import TransportGrids, TransportMedium, YarnGeometry, simulate_yarn, yarn_brdf
from precompute.transport.absorption import STEP_RATIO, absorption_steps, reweighted_transport

GEOMETRY = YarnGeometry(radius_mm=0.1, index=1.5)
GRIDS = TransportGrids(n_around=8, n_along=4, angular_resolution=4)
MU_S = np.array([60.0, 40.0, 80.0])
G = np.array([0.3, 0.5, 0.7])
#: A dye-like range: strong in the middle wavelength, none at the red end at the reference.
REFERENCE_MU_A = np.array([0.5, 2.0, 0.0])
LARGEST_MU_A = np.array([5.0, 20.0, 3.0])
PATHS = 20_000


def medium(mu_a) -> TransportMedium:
    return TransportMedium([450.0, 550.0, 650.0], MU_S, mu_a, hg_g=G)


def between(fraction: float) -> np.ndarray:
    return REFERENCE_MU_A + fraction * (LARGEST_MU_A - REFERENCE_MU_A)


@pytest.fixture(scope="module")
def series():
    steps = absorption_steps(REFERENCE_MU_A, LARGEST_MU_A)
    return simulate_yarn(medium(REFERENCE_MU_A), GEOMETRY, GRIDS, paths_per_cell=PATHS, seed=1,
                         extra_absorption_per_mm=steps)


def test_steps_span_the_range_uniformly_in_log_absorption():
    steps = absorption_steps(REFERENCE_MU_A, LARGEST_MU_A)
    assert steps.shape[1] == 3 and len(steps) >= 3
    np.testing.assert_array_equal(steps[0], 0.0)
    np.testing.assert_allclose(steps[-1], LARGEST_MU_A - REFERENCE_MU_A)
    x = np.log(REFERENCE_MU_A + steps + 0.1)
    np.testing.assert_allclose(np.diff(x, axis=0), np.diff(x, axis=0)[:1].repeat(len(steps) - 1, axis=0),
                               rtol=1e-9)
    assert np.exp(np.diff(x, axis=0)).max() <= STEP_RATIO + 1e-12
    fewer = absorption_steps(REFERENCE_MU_A, LARGEST_MU_A, ratio=2.0)
    assert 3 <= len(fewer) < len(steps)


def test_at_the_reference_the_series_is_the_simulation(series):
    same = reweighted_transport(series, REFERENCE_MU_A)
    np.testing.assert_allclose(same.axial_bssrdf(), series.axial_bssrdf(), rtol=2e-5, atol=1e-9)
    np.testing.assert_allclose(same.exit_fraction, series.exit_fraction, rtol=1e-9)
    np.testing.assert_allclose(same.albedo_rel_stderr, series.albedo_rel_stderr, rtol=1e-6)


BETWEEN_STEPS = (0.07, 0.31, 0.64, 0.93)


@pytest.fixture(scope="module")
def exact_tallies():
    """The series' own paths (same seed and medium) tallied exactly at every absorption of
    ``BETWEEN_STEPS``, in one run."""
    targets = np.array([between(fraction) for fraction in BETWEEN_STEPS])
    return simulate_yarn(medium(REFERENCE_MU_A), GEOMETRY, GRIDS, paths_per_cell=PATHS, seed=1,
                         extra_absorption_per_mm=targets - REFERENCE_MU_A).decayed


@pytest.mark.parametrize("k", range(len(BETWEEN_STEPS)))
def test_between_steps_the_interpolation_matches_an_exact_tally(series, exact_tallies, k):
    """The same paths tallied exactly at the absorption asked for: what differs is the
    interpolation between the steps alone, not Monte-Carlo noise."""
    reweighted = reweighted_transport(series, between(BETWEEN_STEPS[k]))
    expected = exact_tallies.axial_bssrdf[..., k]
    significant = expected > 1e-3 * expected.max(axis=(0, 1, 2))
    assert np.abs(reweighted.axial_bssrdf()[significant] / expected[significant] - 1).max() < 0.005
    np.testing.assert_allclose(reweighted.exit_fraction, exact_tallies.exit_fraction[..., k], rtol=0.002)


@pytest.mark.parametrize("fraction", [0.4, 1.0])
def test_reweighted_yarn_agrees_with_a_fresh_simulation(series, fraction):
    """Against transport run in the more absorbing medium itself (other paths): the albedo of
    every incidence cell and ρ summed over the cells, within three standard errors."""
    target = between(fraction)
    reweighted = reweighted_transport(series, target)
    fresh = simulate_yarn(medium(target), GEOMETRY, GRIDS, paths_per_cell=PATHS, seed=7)
    sigma = np.hypot(reweighted.albedo_rel_stderr * reweighted.exit_fraction,
                     fresh.albedo_rel_stderr * fresh.exit_fraction)
    assert np.all(np.abs(reweighted.exit_fraction - fresh.exit_fraction) < 4 * sigma)
    mean_sigma = np.sqrt((sigma**2).sum(axis=0)) / len(sigma)
    assert np.all(np.abs(reweighted.exit_fraction.mean(axis=0) - fresh.exit_fraction.mean(axis=0)) < 3 * mean_sigma)
    a, b = yarn_brdf(reweighted, 5), yarn_brdf(fresh, 5)
    assert np.all(np.isfinite(a.rho_stderr)) and np.all(a.rho_stderr >= 0)
    total_a, total_b = a.rho.sum(axis=(0, 1)), b.rho.sum(axis=(0, 1))
    bound = a.rho_stderr.sum(axis=(0, 1)) + b.rho_stderr.sum(axis=(0, 1))  # cells share paths: linear
    assert np.all(np.abs(total_a - total_b) < 3 * bound)
    # more absorption: less light out, more absorbed, and the reweighted error grows with it
    assert np.all(reweighted.exit_fraction.mean(axis=0) < series.exit_fraction.mean(axis=0))
    assert np.all(reweighted.absorbed_fraction.mean(axis=0) > series.absorbed_fraction.mean(axis=0))
    assert np.all(reweighted.albedo_rel_stderr.mean(axis=0) >= series.albedo_rel_stderr.mean(axis=0) * 0.999)


def test_series_is_deterministic_whatever_the_threads():
    steps = absorption_steps(REFERENCE_MU_A, LARGEST_MU_A, ratio=2.0)
    runs = [simulate_yarn(medium(REFERENCE_MU_A), GEOMETRY, GRIDS, paths_per_cell=3000, seed=4, threads=t,
                          extra_absorption_per_mm=steps).decayed for t in (1, 2)]
    np.testing.assert_array_equal(runs[0].axial_bssrdf, runs[1].axial_bssrdf)
    np.testing.assert_array_equal(runs[0].exit_fraction, runs[1].exit_fraction)


def test_out_of_range_and_bad_input_name_the_parameter(series):
    with pytest.raises(ParameterError, match="mu_a") as below:
        reweighted_transport(series, REFERENCE_MU_A - [0.1, 0.0, 0.0])
    assert "only add" in str(below.value)
    with pytest.raises(ParameterError, match="mu_a"):
        reweighted_transport(series, LARGEST_MU_A * 1.01)
    with pytest.raises(ParameterError, match="mu_a"):
        reweighted_transport(series, REFERENCE_MU_A[:2])
    plain = simulate_yarn(medium(REFERENCE_MU_A), GEOMETRY, GRIDS, paths_per_cell=64, seed=0)
    with pytest.raises(ParameterError, match="transport"):
        reweighted_transport(plain, REFERENCE_MU_A)
    with pytest.raises(ParameterError, match="extra_absorption_per_mm"):
        simulate_yarn(medium(REFERENCE_MU_A), GEOMETRY, GRIDS, paths_per_cell=64, seed=0,
                      extra_absorption_per_mm=-np.ones((2, 3)))
    with pytest.raises(ParameterError, match="largest_mu_a"):
        absorption_steps(REFERENCE_MU_A, REFERENCE_MU_A - 0.1)
    with pytest.raises(ParameterError, match="ratio"):
        absorption_steps(REFERENCE_MU_A, LARGEST_MU_A, ratio=1.0)
