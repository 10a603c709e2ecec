"""The path core's sampling primitives: free paths (the exponential ziggurat), the scattering turn and
the Fresnel reflectance, each against its definition."""

import math

import numba
import numpy as np
import pytest
import scipy.stats

from precompute.transport._interactions import fresnel_reflectance, turn
from precompute.transport._rng import _ZIGGURAT_R, exponential, seed_stream


@numba.njit
def _exponentials(count, seed):
    state = np.empty(2, dtype=np.uint64)
    seed_stream(state, seed, 0, 0)
    out = np.empty(count)
    for i in range(count):
        out[i] = exponential(state)
    return out


@numba.njit
def _turned(d, mus, seed):
    """``d`` turned once by each polar cosine of ``mus`` (a fresh azimuth each time)."""
    state = np.empty(2, dtype=np.uint64)
    seed_stream(state, seed, 0, 0)
    out = np.empty((mus.shape[0], 3))
    for i in range(mus.shape[0]):
        out[i, 0], out[i, 1], out[i, 2] = turn(d[0], d[1], d[2], mus[i], state)
    return out


@numba.njit
def _walk(steps, seed):
    """A direction turned ``steps`` times by random polar cosines: its length at the end."""
    state = np.empty(2, dtype=np.uint64)
    seed_stream(state, seed, 1, 0)
    dx, dy, dz = 0.6, 0.0, 0.8
    for i in range(steps):
        dx, dy, dz = turn(dx, dy, dz, math.cos(0.001 * i), state)
    return math.sqrt(dx * dx + dy * dy + dz * dz)


def test_free_paths_are_exactly_exponential():
    """10⁶ draws binned over [0, 12] (the layers, the wedges and the tail beyond the base layer's
    edge R): χ² against e^{−x} at its expected value, and the tail's share within 4σ of e^{−R}."""
    draws = _exponentials(1_000_000, 3)
    edges = np.concatenate([np.linspace(0.0, _ZIGGURAT_R, 60), [9.0, 12.0, np.inf]])
    counts, _ = np.histogram(draws, edges)
    expected = len(draws) * -np.diff(np.exp(-edges))
    chi2 = ((counts - expected) ** 2 / expected).sum()
    assert scipy.stats.chi2.sf(chi2, len(counts) - 1) > 1e-4
    tail = np.mean(draws > _ZIGGURAT_R)
    assert abs(tail - math.exp(-_ZIGGURAT_R)) < 4 * math.sqrt(math.exp(-_ZIGGURAT_R) / len(draws))
    assert draws.min() >= 0.0


@pytest.mark.parametrize("d", [(0.0, 0.0, 1.0), (0.0, 0.0, -1.0), (0.6, 0.0, 0.8), (0.36, -0.48, -0.8)])
def test_a_turn_keeps_the_polar_angle_and_draws_a_uniform_azimuth(d):
    d = np.array(d)
    mus = np.full(200_000, 0.3)
    turned = _turned(d, mus, 5)
    np.testing.assert_allclose(turned @ d, 0.3, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(turned, axis=1), 1.0, atol=1e-12)
    # the azimuth around d, measured in a frame of its own: uniform on [0, 2π)
    helper = np.array([1.0, 0.0, 0.0]) if abs(d[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(d, helper)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(d, e1)
    azimuth = np.arctan2(turned @ e2, turned @ e1) % (2 * math.pi)
    assert scipy.stats.kstest(azimuth / (2 * math.pi), "uniform").pvalue > 1e-4


def test_directions_stay_unit_without_renormalising():
    assert abs(_walk(1_000_000, 2) - 1.0) < 1e-10


@numba.njit
def _fresnel(cos_i, eta):
    return fresnel_reflectance(cos_i, eta)


@pytest.mark.parametrize("eta", [1 / 1.55, 1.0, 1.5, 1.55])
def test_fresnel_reflectance_is_the_mean_of_the_two_polarisations(eta):
    for cos_i in np.linspace(0.01, 1.0, 50):
        sin_t2 = eta**2 * (1 - cos_i**2)
        if sin_t2 >= 1.0:
            expected = 1.0
        else:
            cos_t = math.sqrt(1 - sin_t2)
            rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
            rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
            expected = 0.5 * (rs**2 + rp**2)
        assert _fresnel(cos_i, eta) == pytest.approx(expected, rel=1e-12, abs=1e-15)
