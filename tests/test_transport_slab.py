"""The transport core on a slab against exact adding–doubling (iadpython), and its spectral estimator.

``iadpython.Sample(a, b, g, d, n, n_above, n_below, quad_pts).rt()`` returns
(UR1, UT1, URU, UTU); UR1 and UT1 are the total reflectance and transmittance
for collimated normal incidence, specular reflection and unscattered light
included (iadpython/ad.py: ``rt_matrices`` adds the boundary layers,
``UX1_and_UXU`` integrates the fluxes leaving the sample).  The first test
confirms that reading on a case with a closed form.
"""

import json
import math
import subprocess
import sys

import iadpython
import numpy as np
import pytest

from precompute.errors import ParameterError
from precompute.transport import TransportMedium, henyey_greenstein_medium, simulate_hg_slab, simulate_slab


def adding_doubling(albedo, g, tau, n):
    sample = iadpython.Sample(a=albedo, b=tau, g=g, d=1.0, n=n, n_above=1.0, n_below=1.0, quad_pts=24)
    r_total, t_total, *_ = sample.rt()
    return float(r_total), float(t_total)


def agrees(value, stderr, exact, sigmas=3.0):
    return abs(value - exact) < sigmas * stderr + 1e-3


@pytest.mark.slow
def test_iadpython_totals_include_specular_and_unscattered_light():
    # A purely absorbing slab: R = r + (1-r)² r t² / (1 - r² t²), T = (1-r)² t / (1 - r² t²), t = e^-tau.
    r, t = ((1.5 - 1) / (1.5 + 1)) ** 2, math.exp(-1.0)
    exact_r = r + (1 - r) ** 2 * r * t * t / (1 - r * r * t * t)
    exact_t = (1 - r) ** 2 * t / (1 - r * r * t * t)
    assert adding_doubling(0.0, 0.0, 1.0, 1.5) == pytest.approx((exact_r, exact_t), abs=1e-6)
    result = simulate_hg_slab(0.0, 0.0, 1.0, 1.5, paths=50_000, seed=1)
    assert result.R_specular == pytest.approx(r)
    assert agrees(result.R_total[0], result.R_total_stderr[0], exact_r)
    assert agrees(result.T_total[0], result.T_total_stderr[0], exact_t)
    assert result.R_diffuse[0] == result.T_diffuse[0] == 0.0


CASES = [
    # albedo, g, tau, n
    (0.9, 0.75, 2.0, 1.0),  # van de Hulst
    (0.95, 0.5, 1.0, 1.4),
    (0.5, 0.0, 0.5, 1.5),
    (0.99, 0.9, 4.0, 1.33),
    (0.8, -0.3, 3.0, 1.5),
    (1.0, 0.8, 8.0, 1.6),
]


@pytest.mark.parametrize("albedo, g, tau, n", CASES)
def test_slab_matches_adding_doubling(albedo, g, tau, n):
    result = simulate_hg_slab(albedo, g, tau, n, paths=100_000, seed=7)
    r_exact, t_exact = adding_doubling(albedo, g, tau, n)
    assert agrees(result.R_total[0], result.R_total_stderr[0], r_exact)
    assert agrees(result.T_total[0], result.T_total_stderr[0], t_exact)


@pytest.mark.parametrize("albedo, g, tau, n", [(0.9, 0.75, 2.0, 1.0), (0.95, 0.5, 1.0, 1.4)])
def test_tabulated_phase_sampler_matches_adding_doubling(albedo, g, tau, n):
    """The exact sampler of piecewise-linear phase tables (used for Mie media), on a tabulated HG."""
    medium = henyey_greenstein_medium(albedo, g, tabulated=True)
    result = simulate_slab(medium, tau, n, paths=100_000, seed=8)
    r_exact, t_exact = adding_doubling(albedo, g, tau, n)
    assert agrees(result.R_total[0], result.R_total_stderr[0], r_exact)
    assert agrees(result.T_total[0], result.T_total_stderr[0], t_exact)


def test_van_de_hulst_reference_values():
    # van de Hulst's tables: n = 1, albedo 0.9, g = 0.75, tau = 2 -> Rd 0.09739, Tt 0.66096.
    result = simulate_hg_slab(0.9, 0.75, 2.0, 1.0, paths=200_000, seed=11)
    assert result.R_specular == 0.0 and result.R_unscattered[0] == 0.0
    assert agrees(result.R_total[0], result.R_total_stderr[0], 0.09739)
    assert agrees(result.T_total[0], result.T_total_stderr[0], 0.66096)
    # the unscattered transmission of an index-matched slab is e^-tau, a binomial fraction here
    t0 = math.exp(-2.0)
    assert abs(result.T_unscattered[0] - t0) < 4 * math.sqrt(t0 * (1 - t0) / result.paths)


def test_energy_is_conserved():
    result = simulate_hg_slab(0.8, 0.6, 1.5, 1.5, paths=50_000, seed=3)
    total = result.R_total[0] + result.T_total[0] + result.absorbed[0] + result.lost[0]
    assert total == pytest.approx(1.0, abs=4 * (result.R_total_stderr[0] + result.T_total_stderr[0]))
    # without absorption roulette never plays: every path's flux leaves, exactly
    clear = simulate_hg_slab(1.0, 0.6, 1.5, 1.5, paths=20_000, seed=3)
    assert clear.absorbed[0] == 0.0 and clear.lost[0] == 0.0
    assert clear.R_total[0] + clear.T_total[0] == pytest.approx(1.0, abs=1e-12)


def spectral_medium(tabulated: bool) -> TransportMedium:
    """Three wavelengths whose μt differs 8-fold, with different albedo and g."""
    return henyey_greenstein_medium([0.95, 0.7, 0.99], [0.2, 0.6, 0.8], mu_t=[0.5, 1.5, 4.0],
                                    wavelengths_nm=[450.0, 550.0, 650.0], tabulated=tabulated)


@pytest.mark.parametrize("tabulated", [False, True])
def test_hero_wavelength_mis_matches_single_wavelength_runs(tabulated):
    """One spectral run (paths sampled at a random hero wavelength, weighted by the balance
    heuristic over all three) equals three independent single-wavelength runs."""
    medium = spectral_medium(tabulated)
    thickness, n = 1.0, 1.4
    together = simulate_slab(medium, thickness, n, paths=200_000, seed=5)
    for k in range(3):
        alone_medium = TransportMedium(
            medium.wavelengths_nm[k : k + 1], medium.mu_s[k : k + 1], medium.mu_a[k : k + 1],
            hg_g=None if tabulated else medium.hg_g[k : k + 1],
            phase_table=medium.phase_table[k : k + 1] if tabulated else None,
        )
        alone = simulate_slab(alone_medium, thickness, n, paths=200_000, seed=6)
        for name in ("R_total", "T_total"):
            sigma = math.hypot(getattr(together, f"{name}_stderr")[k], getattr(alone, f"{name}_stderr")[0])
            assert abs(getattr(together, name)[k] - getattr(alone, name)[0]) < 4 * sigma, (k, name)
        # absorbed = 1 - R - T - lost path by path for one wavelength, so it shares R's and T's noise
        sigma = 2 * (together.R_total_stderr[k] + together.T_total_stderr[k] + alone.R_total_stderr[0]
                     + alone.T_total_stderr[0])
        assert abs(together.absorbed[k] - alone.absorbed[0]) < sigma


def test_spectral_weights_are_bounded_and_per_path_energy_holds_for_a_grey_spectrum():
    # identical μt and phase at every wavelength: every MIS ratio is 1, so a clear medium's paths
    # each leave with their whole entering flux at every wavelength
    grey = henyey_greenstein_medium([1.0, 1.0, 1.0], [0.5, 0.5, 0.5], mu_t=2.0, wavelengths_nm=[1.0, 2.0, 3.0])
    result = simulate_slab(grey, 1.0, 1.5, paths=20_000, seed=2)
    np.testing.assert_allclose(result.R_total + result.T_total, 1.0, atol=1e-12)


def test_same_seed_gives_identical_results_whatever_the_thread_count():
    medium = spectral_medium(False)
    one = simulate_slab(medium, 1.0, 1.4, paths=20_000, seed=4, threads=1)
    two = simulate_slab(medium, 1.0, 1.4, paths=20_000, seed=4, threads=2)
    for name in ("R_total", "T_total", "R_total_stderr", "absorbed"):
        np.testing.assert_array_equal(getattr(one, name), getattr(two, name))
    other = simulate_slab(medium, 1.0, 1.4, paths=20_000, seed=5, threads=2)
    assert not np.array_equal(one.R_total, other.R_total)


def test_bad_slab_input_names_the_parameter():
    with pytest.raises(ParameterError, match="albedo"):
        simulate_hg_slab(1.2, 0.5, 1.0, 1.0, paths=10)
    with pytest.raises(ParameterError, match="tau"):
        simulate_hg_slab(0.5, 0.5, -1.0, 1.0, paths=10)
    with pytest.raises(ParameterError, match="n ="):
        simulate_hg_slab(0.5, 0.5, 1.0, 0.5, paths=10)
    with pytest.raises(ParameterError, match="paths"):
        simulate_hg_slab(0.5, 0.5, 1.0, 1.0, paths=1)
    with pytest.raises(ParameterError, match="mu_s"):
        TransportMedium([500.0], [-1.0], [0.0], hg_g=[0.0])


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "precompute", "slab", *args], capture_output=True, text=True)


def test_slab_command_prints_json_with_errors_and_parts():
    completed = run_cli("--albedo", "0.9", "--g", "0.75", "--tau", "2", "--n", "1.4", "--paths", "100000",
                        "--seed", "3", "--json")
    assert completed.returncode == 0, completed.stderr
    summary = json.loads(completed.stdout)
    r_exact, t_exact = adding_doubling(0.9, 0.75, 2.0, 1.4)
    assert agrees(summary["R_total"], summary["R_total_stderr"], r_exact)
    assert agrees(summary["T_total"], summary["T_total_stderr"], t_exact)
    assert summary["R_total"] == pytest.approx(
        summary["R_specular"] + summary["R_unscattered"] + summary["R_diffuse"], abs=1e-12)
    assert summary["T_total"] == pytest.approx(summary["T_unscattered"] + summary["T_diffuse"], abs=1e-12)
    assert summary["R_specular"] == pytest.approx((0.4 / 2.4) ** 2)
    assert summary["paths"] == 100_000


def test_bad_command_line_input_exits_2_naming_the_parameter():
    completed = run_cli("--albedo", "0.9", "--g", "1.5", "--tau", "2", "--paths", "100")
    assert completed.returncode == 2 and "g =" in completed.stderr


def test_roulette_shortcut_skips_only_checks_the_full_check_passes():
    """The lower bound that spares the roulette check its L exponentials (surely_above_threshold):
    wherever it answers True the full check — the MIS ratios, then the largest r_λ α_λ^n s_λ — finds the
    path's weight at or above ROULETTE_THRESHOLD too, within 1e-6 of the threshold included, with the
    plain roulette (s ≡ 1) and with an error-target run's importance; and on the default red cotton
    it answers True for most states clearly above it, or it would spare nothing."""
    from precompute.optics.medium import DEFAULT_PRESET, load_preset
    from precompute.optics.coefficients import medium_optics
    from precompute.transport._paths import ROULETTE_THRESHOLD, largest_weight, mis_ratios, surely_above_threshold
    from precompute.transport.media import medium_from_optics

    medium = medium_from_optics(medium_optics(load_preset(DEFAULT_PRESET))).kernel()
    n_wl = len(medium.mu_t)
    rng = np.random.default_rng(7)
    hero_p = rng.dirichlet(np.full(n_wl, 4.0))
    clearly_above = spared = 0
    for trial in range(400):
        hero = int(rng.integers(n_wl))
        n = int(rng.integers(1, 100)) * 4
        length = n / medium.mu_t[hero] * rng.gamma(8.0, 1 / 8.0)
        ratio = np.exp(rng.normal(0.0, 0.5, n_wl))
        ratio /= ratio[hero]
        ratios = np.empty(n_wl)
        mis_ratios(medium.mu_t, medium.log_mu_t, False, hero, ratio, n, length, hero_p, ratios)
        # the plain roulette, or importance as importance_from_errors gives it (shares of 0.25 … 1)
        importance = np.ones(n_wl) if trial % 4 < 2 else rng.uniform(0.25, 1.0, n_wl) * 2e-3
        neediest = int(np.argmax(importance))
        albedo_n = medium.albedo**n
        largest = largest_weight(albedo_n, ratios, importance)
        # half the states anywhere from 100x below to 100x above the threshold, half within 1e-6 of it
        scale = rng.uniform(0.01, 100.0) if trial % 2 else 1.0 + rng.uniform(-1e-6, 1e-6)
        factor = ROULETTE_THRESHOLD / largest * scale
        shortcut = surely_above_threshold(medium.mu_t, medium.log_mu_t, albedo_n, medium.brightest, neediest,
                                          hero, ratio, n, length, hero_p, factor, importance)
        if shortcut:
            assert largest * factor >= ROULETTE_THRESHOLD
        if scale > 1.01:
            clearly_above += 1
            spared += shortcut
    assert spared > 0.5 * clearly_above > 0
