"""A spectral path's bookkeeping: the exponential of the MIS weights, the running phase products and
their rescaling, the albedo's powers, and the views the kernels borrow, each against its definition."""

import math

import numba
import numpy as np

from precompute.transport._borrow import borrowed
from precompute.transport._exp import SMALLEST_EXPONENT, exp_nonpositive
from precompute.transport._interactions import PHASE_TABLE, sample_table
from precompute.transport._paths import RESCALE, mis_ratios, padded_width, path_arrays, update_phase_products
from precompute.transport._rng import seed_stream
from precompute.transport.media import phase_sampling_tables


@numba.njit
def _exponentials(x):
    out = np.empty_like(x)
    for i in range(x.shape[0]):
        out[i] = exp_nonpositive(x[i])
    return out


def test_the_exponential_is_within_two_ulp_of_libm_and_zero_below_its_range():
    rng = np.random.default_rng(7)
    x = np.concatenate([-708.0 * rng.random(400_000), -2.0 * rng.random(400_000), -1e-9 * rng.random(1000),
                        [0.0, -0.0, SMALLEST_EXPONENT, -0.5 * math.log(2.0), -math.log(2.0)]])
    exact = np.exp(x)
    ulp = np.abs(_exponentials(x) - exact) / np.spacing(exact)
    assert ulp.max() <= 2.0
    assert ulp.mean() < 0.5
    below = np.array([np.nextafter(SMALLEST_EXPONENT, -np.inf), -745.0, -1e308, -np.inf])
    assert np.all(_exponentials(below) == 0.0)
    assert np.isnan(_exponentials(np.array([np.nan]))[0])


@numba.njit
def _scatterings(table, threshold, alias, hero, count, seed):
    """``count`` (segment, along) drawn from the hero's phase function, as a path draws them."""
    state = np.empty(2, dtype=np.uint64)
    seed_stream(state, seed, 0, 0)
    segments = np.empty(count, dtype=np.int64)
    alongs = np.empty(count)
    for i in range(count):
        _, segments[i], alongs[i] = sample_table(table, threshold, alias, hero, state)
    return segments, alongs


@numba.njit
def _products_after(table, phase_max, hero, segments, alongs, mu_t, length, hero_p):
    """The running products after one scattering per (segment, along), their bound and the MIS ratios;
    ``table``'s rows may be padded with zeros beyond the wavelengths of ``mu_t``, as the kernels' are."""
    n_wl = mu_t.shape[0]
    product = np.zeros(table.shape[1])
    product[:n_wl] = 1.0
    bound = 1.0
    for i in range(segments.shape[0]):
        bound = update_phase_products(PHASE_TABLE, np.zeros(1), table, phase_max, hero, 0.0, segments[i], alongs[i],
                                      n_wl, product, bound)
    ratios = np.empty(n_wl)
    mis_ratios(mu_t, np.log(mu_t), False, hero, product, segments.shape[0], length, hero_p, ratios)
    return product, bound, ratios


def test_phase_products_stay_in_range_and_give_the_mis_ratios_of_their_definition():
    """Three wavelengths (a forward-peaked, a backward-peaked and an isotropic phase function), 3000
    scatterings drawn from each in turn as the hero: the products, never divided by the hero's density,
    would leave the float range without their rescaling, stay in it with it, and give the MIS ratios
    r_λ = p_λ / Σ_k q_k p_k of the same sums taken in logarithms."""
    mu = np.linspace(-1.0, 1.0, 65)
    table, threshold, alias = phase_sampling_tables(np.stack([np.exp(12.0 * mu), np.exp(-3.0 * mu), 1.0 + 0.0 * mu]))
    by_mu = np.ascontiguousarray(table.T)
    mu_t = np.array([10.0, 12.0, 11.0])
    hero_p = np.array([0.2, 0.3, 0.5])
    length = 250.0
    for hero in range(3):
        segments, alongs = _scatterings(by_mu, threshold, alias, hero, 3000, seed=hero)
        product, bound, ratios = _products_after(by_mu, float(by_mu.max()), hero, segments, alongs, mu_t, length,
                                                 hero_p)
        values = by_mu[segments] + (by_mu[segments + 1] - by_mu[segments]) * alongs[:, None]
        log_phase = np.log(values).sum(axis=0)
        assert np.abs(log_phase).max() > math.log(1e300)
        assert np.all(np.isfinite(product)) and product[hero] > 0.0 and product.max() <= bound <= RESCALE
        log_p = log_phase + len(segments) * np.log(mu_t) - mu_t * length
        expected = np.exp(log_p - np.logaddexp.reduce(np.log(hero_p) + log_p))
        np.testing.assert_allclose(ratios, expected, rtol=1e-9, atol=1e-300)
        # the kernels' rows padded with zeros to PHASE_WIDTH: the same products bit for bit, the padding 0
        padded = np.zeros((by_mu.shape[0], padded_width(3)))
        padded[:, :3] = by_mu
        padded_product, _, padded_ratios = _products_after(padded, float(by_mu.max()), hero, segments, alongs, mu_t,
                                                           length, hero_p)
        np.testing.assert_array_equal(padded_product[:3], product)
        np.testing.assert_array_equal(padded_ratios, ratios)
        assert padded.shape[1] == 4 and np.all(padded_product[3:] == 0.0)


@numba.njit
def _doubled_through_a_view(values):
    view = borrowed(values)
    for i in range(view.shape[0]):
        view[i] *= 2.0
    return view.sum(), view.shape[0], view.strides[0]


@numba.njit
def _through_a_borrowed_tuple(arrays):
    view = borrowed(arrays)
    view.weights[0] = 5.0
    view.state[1] = 9
    return view.weights.shape[0], view.phase_product.shape[0], view.state[1]


def test_a_borrowed_view_is_the_same_array_and_a_borrowed_tuple_holds_the_same_arrays():
    values = np.arange(5.0)
    total, size, stride = _doubled_through_a_view(values)
    np.testing.assert_array_equal(values, 2.0 * np.arange(5.0))
    assert (total, size, stride) == (20.0, 5, 8)

    arrays = path_arrays(35)
    assert _through_a_borrowed_tuple(arrays) == (35, padded_width(35), 9)
    assert arrays.weights[0] == 5.0 and arrays.state[1] == 9


def test_the_albedo_power_table_holds_each_power_a_path_multiplies_in_at_its_checks_and_end():
    """A spectral path keeps α^n by multiplying in α^interval at each roulette check and α^(n mod interval)
    at its end: the table's rows are those powers, to round-off, for an interval of either kind of medium."""
    from precompute.optics.medium import DEFAULT_PRESET, load_preset
    from precompute.optics.coefficients import medium_optics
    from precompute.transport import medium_from_optics
    from precompute.transport._paths import ROULETTE_INTERVAL_ABSORBING, albedo_power_table

    medium = medium_from_optics(medium_optics(load_preset(DEFAULT_PRESET))).kernel()
    albedo = medium.albedo
    assert medium.albedo_powers.shape == (medium.roulette_interval + 1, len(albedo))
    powers = np.empty((ROULETTE_INTERVAL_ABSORBING + 1, len(albedo)))
    albedo_power_table(albedo, powers)
    for table in (medium.albedo_powers, powers):
        assert np.all(table[0] == 1.0) and np.array_equal(table[1], albedo)
        rows = np.arange(len(table))[:, None]
        np.testing.assert_allclose(table, albedo[None, :] ** rows, rtol=1e-14)
    # n collisions: n // interval checks, then the remainder
    interval = medium.roulette_interval
    for n in (1, interval - 1, interval, 3 * interval + 5):
        kept = np.ones_like(albedo)
        for _ in range(n // interval):
            kept *= medium.albedo_powers[interval]
        kept *= medium.albedo_powers[n % interval]
        np.testing.assert_allclose(kept, albedo**n, rtol=1e-13)
