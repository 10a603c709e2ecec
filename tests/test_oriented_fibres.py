"""Fibres along the yarn axis (precompute/optics/fibre_orientation.py, precompute/transport/_fibres.py): the
extinction of oriented fibres, a ray traced through one fibre against geometric optics, the yarn's
transport with them, the [fibres] table's orientation."""

import copy
import math

import numba
import numpy as np
import pytest
from scipy.integrate import quad

from precompute.errors import ParameterError
from precompute.optics.coefficients import medium_optics
from precompute.optics.fibre import fresnel_reflectance
from precompute.optics.fibre_orientation import OrientedFibres, fibre_axes, mean_sine_table
from precompute.optics.medium import PRESET_DIR, load_preset_config, medium_from_dict
from precompute.transport import TransportGrids, YarnGeometry, simulate_yarn
from precompute.transport._fibres import sample_fibre_axis, scatter_off_fibre, trace_fibres
from precompute.transport._paths import CYLINDER, EXITED, path_arrays
from precompute.transport._rng import seed_stream
from precompute.transport.media import TransportMedium

FIBRE_WHITE = PRESET_DIR / "white_cotton.toml"
INDEX = 1.557


def oriented(helix_deg=20.0, spread_deg=10.0, absorption=(0.0,), extinction=100.0, roughness_deg=0.0):
    return OrientedFibres(extinction, INDEX, 0.005, helix_deg, spread_deg, np.array(absorption, float), roughness_deg)


def oriented_medium(fibres):
    n_wl = len(fibres.absorption_per_mm)
    return TransportMedium(np.arange(n_wl, dtype=float) + 400.0, np.full(n_wl, 1.0), np.zeros(n_wl),
                           hg_g=np.zeros(n_wl), fibres=fibres)


@numba.njit
def _fibre_axes(params, count, seed):
    state = np.empty(2, dtype=np.uint64)
    seed_stream(state, seed, 0, 0)
    out = np.empty((count, 3))
    for s in range(count):
        out[s, 0], out[s, 1], out[s, 2] = sample_fibre_axis(params, state)
    return out


@numba.njit
def _scatter_many(d, t, eta, count, seed):
    state = np.empty(2, dtype=np.uint64)
    seed_stream(state, seed, 0, 0)
    out = np.empty((count, 3))
    chords = np.empty(count)
    for s in range(count):
        out[s, 0], out[s, 1], out[s, 2], chords[s], _ = scatter_off_fibre(d[0], d[1], d[2], t[0], t[1], t[2],
                                                                            eta, state)
    return out, chords


@numba.njit
def _trace_many(medium, d, count, seed, radius):
    arrays = path_arrays(medium.fibre_absorption.shape[0])
    seed_stream(arrays.state, seed, 0, 0)
    importance = np.ones(medium.fibre_absorption.shape[0])
    absorbed = np.zeros(medium.fibre_absorption.shape[0])
    dims = np.array([radius, radius])
    exits = np.empty((count, 3))
    collisions = np.zeros(count, dtype=np.int64)
    for s in range(count):
        arrays.pos[0], arrays.pos[1], arrays.pos[2] = -radius * (1.0 - 1e-12), 0.0, 0.0
        arrays.d[0], arrays.d[1], arrays.d[2] = d[0], d[1], d[2]
        status, n, _ = trace_fibres(CYLINDER, dims, 1.0, medium, importance, 1.0, arrays, absorbed)
        exits[s, 0], exits[s, 1], exits[s, 2] = arrays.d[0], arrays.d[1], arrays.d[2]
        collisions[s] = n if status == EXITED else -1
    return exits, collisions


def test_fibres_along_the_axis_present_the_sine_of_the_angle_to_it():
    cos_axis = np.linspace(0.0, 1.0, 129)
    np.testing.assert_allclose(mean_sine_table(0.0, 0.0), np.sqrt(1.0 - cos_axis**2), atol=1e-12)
    # a helix tilts them, so that light along the axis meets them too, and a spread more so
    tilted, spread = mean_sine_table(30.0, 0.0), mean_sine_table(30.0, 20.0)
    assert 0.15 < tilted[-1] < spread[-1] < 0.6
    # across the axis all three see the fibres almost side on (⟨sin⟩ ≥ cos of the largest tilt)
    assert 0.9 < tilted[0] <= 1.0 and tilted[0] > spread[0]


def test_the_kernel_draws_fibre_axes_from_the_distribution_the_extinction_averages_over():
    fibres = oriented(helix_deg=35.0, spread_deg=15.0)
    axes = _fibre_axes(fibres.parameters(), 40000, 3)
    reference = fibre_axes(35.0, 15.0, 40000, np.random.default_rng(5))
    np.testing.assert_allclose(np.linalg.norm(axes, axis=1), 1.0, atol=1e-12)
    # the distribution of the tilt from the axis (|cos| to z), by its quantiles
    quantiles = [0.1, 0.25, 0.5, 0.75, 0.9]
    np.testing.assert_allclose(np.quantile(np.abs(axes[:, 2]), quantiles),
                               np.quantile(np.abs(reference[:, 2]), quantiles), atol=4e-3)
    # and the azimuth about the axis is uniform
    assert abs(np.mean(axes[:, 0])) < 0.01 and abs(np.mean(axes[:, 1])) < 0.01


def test_every_ray_a_fibre_scatters_leaves_on_its_cone():
    # a cylinder keeps a ray's direction cosine to its axis through reflection and (out again) refraction:
    # the specular cone of fibre scattering (Marschner et al. 2003, §4)
    t = np.array([0.2, -0.3, 1.0]) / math.sqrt(1.13)
    d = np.array([0.6, 0.0, -0.8])
    out, chords = _scatter_many(d, t, INDEX, 20000, 1)
    np.testing.assert_allclose(np.linalg.norm(out, axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(out @ t, d @ t, atol=1e-12)
    assert 0.02 < np.mean(chords == 0.0) < 0.15  # a few per cent reflected off the outside ...
    # ... the rest crossed it: at most 64 chords (MAX_INTERNAL_REFLECTIONS) of at most a diameter each
    assert np.all(chords[chords > 0.0] <= 2.0 * 64 + 1e-9)


def test_a_fibre_reflects_the_share_geometric_optics_gives_a_cylinder():
    # light across the fibre: the externally reflected share is ∫₀^{π/2} R(i) cos i di (an impact parameter
    # h = sin i uniform over the width), with R from the Fresnel equations
    expected, _ = quad(lambda i: fresnel_reflectance(np.array(math.cos(i)), INDEX) * math.cos(i), 0.0, math.pi / 2)
    _, chords = _scatter_many(np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0]), INDEX, 400000, 2)
    reflected = np.mean(chords == 0.0)
    assert reflected == pytest.approx(expected, abs=4.0 * math.sqrt(expected / 400000))
    # and what goes in runs, on the first crossing, the chord 2 cos of the refraction angle (mean over h ≥ 1.5 radii)
    assert np.mean(chords[chords > 0.0]) > 1.5


def test_fibres_exactly_along_the_axis_keep_the_light_on_its_cone_through_the_yarn():
    fibres = oriented(helix_deg=0.0, spread_deg=0.0)
    d = np.array([0.8, 0.0, 0.6])
    exits, collisions = _trace_many(oriented_medium(fibres).kernel(), d, 3000, 4, 0.1)
    scattered = collisions > 0
    assert scattered.mean() > 0.9  # 100 /mm across a 0.2 mm yarn
    np.testing.assert_allclose(exits[scattered, 2], 0.6, atol=1e-9)
    # tilted fibres spread it off the cone, and so do rough ones
    for fibres in (oriented(helix_deg=30.0), oriented(helix_deg=0.0, spread_deg=0.0, roughness_deg=20.0)):
        exits, collisions = _trace_many(oriented_medium(fibres).kernel(), d, 3000, 4, 0.1)
        assert np.std(exits[collisions > 0, 2]) > 0.05


def test_a_yarn_of_clear_oriented_fibres_loses_nothing_and_absorbing_ones_absorb():
    for absorption, expect_absorbed in ((0.0, False), (50.0, True)):
        fibres = oriented(absorption=(absorption, 0.0))
        result = simulate_yarn(oriented_medium(fibres), YarnGeometry(0.1, 1.0), TransportGrids(8, 4, 4),
                               paths_per_cell=400, seed=1)
        total = result.specular + result.exit_fraction + result.unscattered_fraction + result.absorbed_fraction
        np.testing.assert_allclose(total, 1.0, atol=1e-9)
        assert np.all(result.specular == 0.0)  # no yarn surface in air
        # (per incidence cell and wavelength)
        assert np.all(result.absorbed_fraction[:, 0] > 0.1) == expect_absorbed
        assert np.all(result.absorbed_fraction[:, 1] == 0.0)


def test_the_fibre_white_preset_along_the_axis():
    config, base_dir = load_preset_config(FIBRE_WHITE)
    medium = medium_from_dict(config, base_dir)
    optics = medium_optics(medium)
    fibres = optics.oriented_fibres
    phi, d_mm = medium.fibres.volume_fraction, medium.fibres.diameter_um * 1e-3
    assert fibres.extinction_per_mm == pytest.approx(4.0 * phi / (math.pi * d_mm))
    assert fibres.helix_angle_deg == medium.yarn.twist_angle_deg
    assert (fibres.spread_deg, fibres.roughness_deg) == (config["fibres"]["orientation_spread_deg"],
                                                         config["fibres"]["roughness_deg"])
    assert fibres.relative_index == pytest.approx(1.557)
    # the dye is absorbed inside the fibres, beside their grey absorption
    assert fibres.absorption_per_mm.min() >= medium.fibres.absorption_per_mm and np.ptp(fibres.absorption_per_mm) > 0
    np.testing.assert_allclose(optics.unscattered_extinction_per_mm, fibres.extinction(0.0))
    # random fibres (⟨sin⟩ = π/4) meet light less often across the axis than fibres lying across its path
    assert fibres.across_axis_extinction_per_mm > phi / d_mm
    # the same fibres in random orientation: the Mie proxy's medium, its own extinction for the unscattered light
    random = copy.deepcopy(config)
    random["fibres"]["orientation"] = "random"
    random_optics = medium_optics(medium_from_dict(random, base_dir))
    assert random_optics.oriented_fibres is None
    np.testing.assert_array_equal(random_optics.unscattered_extinction_per_mm, random_optics.mu_t)


def test_the_fibres_table_refuses_an_unknown_orientation_and_particles_beside_oriented_fibres():
    config, base_dir = load_preset_config(FIBRE_WHITE)
    bad = copy.deepcopy(config)
    bad["fibres"]["orientation"] = "sideways"
    with pytest.raises(ParameterError, match="fibres.orientation"):
        medium_from_dict(bad, base_dir)
    bad = copy.deepcopy(config)
    bad["fibres"]["orientation"] = "yarn_axis"
    bad["fibres"]["orientation_spread_deg"] = -1.0
    with pytest.raises(ParameterError, match="orientation_spread_deg"):
        medium_from_dict(bad, base_dir)
    bad["fibres"]["orientation_spread_deg"] = 5.0
    bad["fibres"]["roughness_deg"] = 91.0
    with pytest.raises(ParameterError, match="roughness_deg"):
        medium_from_dict(bad, base_dir)
    bad["fibres"]["roughness_deg"] = 10.0
    bad["host"]["absorption_per_mm"] = 1.0
    with pytest.raises(ParameterError, match="host.absorption_per_mm"):
        medium_from_dict(bad, base_dir)


def test_a_bake_of_oriented_fibres_tabulates_their_unscattered_light_across_the_yarn_axis(tmp_path):
    from precompute.bake import SPECTRAL_FILE, bake, load_spectral
    from precompute.optics import ballistic
    from precompute.tables.exr import read_table

    result = bake(FIBRE_WHITE, ["transport.angular_resolution=6", "transport.n_around=8", "transport.n_along=3"],
                  paths_per_cell=64, threads=1, cache_dir=tmp_path / "cache")
    arrays, _ = load_spectral(result.folder / SPECTRAL_FILE)
    config, base_dir = load_preset_config(FIBRE_WHITE)
    medium = medium_from_dict(config, base_dir)
    across = medium_optics(medium).oriented_fibres.across_axis_extinction_per_mm
    np.testing.assert_allclose(arrays["unscattered_mu_t"], across)
    # air and the fibres' Fresnel take no colour from the light that misses every fibre: a grey e^{−μt ℓ}
    table = read_table(result.table("unscattered")).pixels.reshape(-1, 3)
    expected = ballistic.attenuation(np.array([across]), medium.yarn.radius_mm, ballistic.attenuation_lengths())[:, 0]
    np.testing.assert_allclose(table, np.repeat(expected[:, None], 3, axis=1), atol=2e-3)
