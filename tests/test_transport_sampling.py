"""The path core's sampling primitives: free paths (the exponential ziggurat), tabulated phase functions
(alias tables), the scattering turn, the Fresnel reflectance and where a flight ends, each against its
definition."""

import math

import numba
import numpy as np
import pytest
import scipy.stats

from precompute.transport._interactions import alias_tables, fresnel_reflectance, sample_table, turn
from precompute.transport._paths import CYLINDER, SLAB, boundary_distance, boundary_shape, inside
from precompute.transport._rng import _ZIGGURAT_R, exponential, seed_stream
from precompute.transport.media import phase_sampling_tables


@numba.njit
def _exponentials(count, seed):
    state = np.empty(2, dtype=np.uint64)
    seed_stream(state, seed, 0, 0)
    out = np.empty(count)
    for i in range(count):
        out[i] = exponential(state)
    return out


@numba.njit
def _table_draws(table, threshold, alias, k, count, seed):
    state = np.empty(2, dtype=np.uint64)
    seed_stream(state, seed, 0, 0)
    mus = np.empty(count)
    segments = np.empty(count, dtype=np.int64)
    alongs = np.empty(count)
    for i in range(count):
        mus[i], segments[i], alongs[i] = sample_table(table, threshold, alias, k, state)
    return mus, segments, alongs


def _drawn_probabilities(threshold, alias):
    """Each entry's probability under the alias tables (one row): kept with its threshold, plus what the
    entries that alias it pass on, over the number of entries."""
    passed_on = alias != np.arange(len(alias))
    drawn = threshold.copy()
    np.add.at(drawn, alias[passed_on], 1.0 - threshold[passed_on])
    return drawn / len(alias)


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


def test_alias_tables_draw_each_segment_with_its_probability():
    """Rows with zero entries, a single entry and a sharp peak (as a Mie table's forward diffraction):
    the alias tables give every entry its probability to round-off, and an entry of probability 0 is
    never drawn."""
    rng = np.random.default_rng(7)
    random_row = rng.random(300)
    random_row[::5] = 0.0
    single = np.zeros(300)
    single[123] = 1.0
    peak = np.exp(-0.5 * ((np.arange(300) - 290.0) / 1.5) ** 2) + 1e-9
    rows = np.array([random_row, single, peak])
    rows /= rows.sum(axis=1, keepdims=True)
    threshold, alias = alias_tables(rows)
    assert threshold.shape == alias.shape == rows.shape
    for row, kept, to in zip(rows, threshold, alias):
        assert np.all((kept >= 0.0) & (kept <= 1.0))
        drawn = _drawn_probabilities(kept, to)
        np.testing.assert_allclose(drawn, row, rtol=0, atol=1e-15)
        assert np.all(drawn[row == 0.0] == 0.0)


def test_a_table_is_sampled_from_its_piecewise_linear_density():
    """4·10⁶ draws from a coarse, forward-peaked table (21 points: the segments' slopes matter) against
    the integral of the piecewise-linear density over 200 bins that cut across the segments: χ²; and the
    segment and the place in it that the sampler reports are those of the μ it returns."""
    mu = np.linspace(-1.0, 1.0, 21)
    phase = np.exp(3.0 * mu) + 0.05
    table, threshold, alias = phase_sampling_tables(phase[None, :])
    draws, segments, alongs = _table_draws(np.ascontiguousarray(table.T), threshold, alias, 0, 4_000_000, 5)
    # where the sampler says it put μ (the phase ratios are evaluated there) is where μ is
    assert np.all((segments >= 0) & (segments < 20) & (alongs >= 0.0) & (alongs < 1.0))
    np.testing.assert_allclose(draws, -1.0 + (segments + alongs) * 0.1, rtol=0, atol=1e-15)
    edges = np.linspace(-1.0, 1.0, 201)
    # the density is linear between grid points, so its integral up to x is exact from the trapezoid
    # to the grid point below and the exact area of the part segment
    def cumulative(x):
        j = np.minimum(((x + 1.0) / 0.1).astype(int), 19)
        p0, p1 = table[0, j], table[0, j + 1]
        t = (x - mu[j]) / 0.1
        whole = np.concatenate([[0.0], np.cumsum(0.5 * (table[0, 1:] + table[0, :-1]) * 0.1)])
        return 2.0 * np.pi * (whole[j] + 0.1 * (p0 * t + 0.5 * (p1 - p0) * t * t))

    expected = len(draws) * np.diff(cumulative(edges))
    assert abs(cumulative(np.array([1.0]))[0] - 1.0) < 1e-12
    counts, _ = np.histogram(draws, edges)
    chi2 = ((counts - expected) ** 2 / expected).sum()
    assert scipy.stats.chi2.sf(chi2, len(counts) - 1) > 1e-4


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


@numba.njit
def _flight_ends(geometry, dims, points, directions, flights):
    """For each interior point, direction and flight: whether :func:`inside` finds the flight's end in the
    medium, and the distance to the boundary along the direction."""
    thickness, ia2, ib2 = boundary_shape(geometry, dims)
    ends_inside = np.empty(points.shape[0], dtype=np.bool_)
    distances = np.empty(points.shape[0])
    for i in range(points.shape[0]):
        px, py, pz = points[i, 0], points[i, 1], points[i, 2]
        dx, dy, dz = directions[i, 0], directions[i, 1], directions[i, 2]
        f = flights[i]
        ends_inside[i] = inside(geometry, thickness, ia2, ib2, px + f * dx, py + f * dy, pz + f * dz)
        distances[i] = boundary_distance(geometry, thickness, ia2, ib2, px, py, pz, dx, dy, dz)
    return ends_inside, distances


@pytest.mark.parametrize("geometry, dims", [(SLAB, (0.3,)), (CYLINDER, (0.1, 0.1)), (CYLINDER, (0.12, 0.05))])
def test_a_flight_ends_inside_exactly_when_it_is_shorter_than_the_way_out(geometry, dims):
    """The path core tests where a flight ends before it asks how far the boundary is (the medium is
    convex): the two answers agree for 10⁵ random interior points, directions and flights of up to
    the medium's size, but for flights within round-off of the boundary."""
    rng = np.random.default_rng(11)
    n = 100_000
    directions = rng.normal(size=(n, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    if geometry == SLAB:
        points = np.column_stack([rng.uniform(-1, 1, n), rng.uniform(-1, 1, n), rng.uniform(0, dims[0], n)])
        size = dims[0]
    else:
        radius = np.sqrt(rng.uniform(0, 1, n))
        angle = rng.uniform(0, 2 * np.pi, n)
        points = np.column_stack([dims[0] * radius * np.cos(angle), dims[1] * radius * np.sin(angle),
                                  rng.uniform(-1, 1, n)])
        size = 2 * max(dims)
    flights = rng.uniform(0, size, n)
    ends_inside, distances = _flight_ends(geometry, np.array(dims), points, directions, flights)
    clear = np.abs(flights - distances) > 1e-9 * size
    assert clear.sum() > 0.99 * n
    np.testing.assert_array_equal(ends_inside[clear], (flights < distances)[clear])
    assert 0.1 < np.mean(flights < distances) < 0.9  # both answers occur
