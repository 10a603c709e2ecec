"""Medium optics: Mie in the host, phase tables, dye, Percus–Yevick, presets, the optics command."""

import csv
import dataclasses
import importlib.util
import json
import math
import pathlib

import miepython
import numpy as np
import pytest
from scipy import stats
from scipy.integrate import quad

from precompute.__main__ import main
from precompute.optics.medium import (
    DATA_DIR,
    Host,
    MediumParameters,
    ParticleSpecies,
    RefractiveIndex,
    WavelengthGrid,
    preset_names,
)
from precompute.optics.mie import differential_scattering_cross_section, percus_yevick_structure_factor
from precompute.optics.coefficients import MediumOptics, load_preset, medium_optics
from precompute.optics.phase import (
    asymmetry_parameter,
    cos_theta_grid,
    henyey_greenstein_phase,
    phase_integral,
    phase_inverse_cdf,
    sample_inverse_cdf,
)

REPO = pathlib.Path(__file__).resolve().parents[1]
PAPER_WAVELENGTHS = (400.0, 550.0, 700.0)


def medium(*particles, wavelengths=PAPER_WAVELENGTHS, host_index=1.557, model="none"):
    return MediumParameters(
        name="test",
        host=Host(RefractiveIndex(host_index)),
        particles=tuple(particles),
        wavelengths=WavelengthGrid(values_nm=tuple(wavelengths)),
        dependent_scattering=model,
    )


def species(name="p", n=1.61, k=0.0, diameter=150.0, fraction=0.14, **size):
    if size:
        return ParticleSpecies(name, RefractiveIndex(n, k), fraction, **size)
    return ParticleSpecies(name, RefractiveIndex(n, k), fraction, diameter_nm=diameter)


def mie_sums(m: complex, x: float) -> tuple[float, float]:
    """Q_ext and Q_sca from the Mie coefficients (Bohren & Huffman eqs. 4.61, 4.62)."""
    a, b = miepython.an_bn(m, x, 0)
    n = np.arange(1, len(a) + 1)
    q_sca = 2.0 / x**2 * np.sum((2 * n + 1) * (np.abs(a) ** 2 + np.abs(b) ** 2))
    q_ext = 2.0 / x**2 * np.sum((2 * n + 1) * (a + b).real)
    return float(q_ext), float(q_sca)


@pytest.fixture(scope="module")
def red_cotton() -> MediumOptics:
    return medium_optics(load_preset("paper_2008"))


@pytest.fixture(scope="module")
def red_cotton_py() -> MediumOptics:
    return medium_optics(dataclasses.replace(load_preset("paper_2008"), dependent_scattering="percus-yevick"))


# ---- the paper's medium, checked by hand ---------------------------------------------------------


def test_default_preset_is_the_papers_medium():
    params = load_preset("paper_2008")
    assert params.name == "paper_2008" and params.host.refractive_index.n == 1.557
    (scatterers,) = params.particles
    assert (scatterers.refractive_index.n, scatterers.diameter_nm, scatterers.volume_fraction) == (1.61, 150.0, 0.14)
    assert 1.0 <= params.dye.weight_percent <= 5.0
    np.testing.assert_allclose(params.wavelengths.values, np.arange(390.0, 731.0, 10.0))


@pytest.mark.parametrize("wavelength", PAPER_WAVELENGTHS)
def test_paper_medium_scattering_matches_a_hand_calculation(red_cotton, wavelength):
    # μs = N · Q_sca · π d²/4 with N = f / (π d³/6); Q_sca from the Mie coefficients in the host.
    row = int(np.flatnonzero(red_cotton.wavelengths_nm == wavelength)[0])
    n_host, diameter, fraction = 1.557, 150.0, 0.14
    x = math.pi * diameter * n_host / wavelength
    _, q_sca = mie_sums(complex(1.61 / n_host), x)
    number_density = fraction / (math.pi * diameter**3 / 6.0)  # 1/nm³
    mu_s = number_density * q_sca * math.pi * diameter**2 / 4.0 * 1e6  # 1/mm
    assert red_cotton.mu_s[row] == pytest.approx(mu_s, rel=1e-9)

    # Rayleigh–Gans–Debye, independent of any Mie series: within a few % for |m − 1| x ≪ 1.
    k, a, m = 2 * math.pi * n_host / wavelength, diameter / 2, 1.61 / n_host
    theta = np.linspace(0.0, math.pi, 4001)
    u = np.maximum(2 * k * a * np.sin(theta / 2), 1e-9)
    form = 3 * (np.sin(u) - u * np.cos(u)) / u**3
    dsigma = k**4 * a**6 * (2 * (m - 1) / 3) ** 2 * form**2 * (1 + np.cos(theta) ** 2) / 2
    sigma = 2 * math.pi * np.trapz(dsigma * np.sin(theta), theta)
    assert red_cotton.mu_s[row] == pytest.approx(number_density * sigma * 1e6, rel=0.03)


@pytest.mark.parametrize("wavelength", PAPER_WAVELENGTHS)
def test_paper_medium_absorption_is_the_dye_by_hand(red_cotton, wavelength):
    # μa = ε(λ) · w · ρ_f (1/cm → /10 for 1/mm), ε read straight from the shipped CSV.
    with (DATA_DIR / "red_dye_band_model.csv").open() as handle:
        rows = [r for r in csv.reader(line for line in handle if not line.startswith("#"))][1:]
    epsilon = {float(w): float(v) for w, v in rows}[wavelength]
    row = int(np.flatnonzero(red_cotton.wavelengths_nm == wavelength)[0])
    assert red_cotton.mu_a[row] == pytest.approx(epsilon * 0.03 * 1.52 / 10.0, rel=1e-12)
    assert red_cotton.albedo[row] == pytest.approx(red_cotton.mu_s[row] / (red_cotton.mu_s[row] + red_cotton.mu_a[row]))


def test_red_cotton_is_red(red_cotton):
    # The dye absorbs the green and leaves the red: the albedo at 700 nm dwarfs the one at 550 nm.
    albedo = dict(zip(red_cotton.wavelengths_nm, red_cotton.albedo))
    assert albedo[700.0] > 0.9 and albedo[550.0] < 0.05 and albedo[450.0] > albedo[550.0]


def test_dye_csv_is_the_documented_band_model():
    spec = importlib.util.spec_from_file_location(
        "make_red_dye_spectrum", REPO / "scripts" / "make_red_dye_spectrum.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    with (DATA_DIR / "red_dye_band_model.csv").open() as handle:
        rows = [r for r in csv.reader(line for line in handle if not line.startswith("#"))][1:]
    for wavelength, value in rows:
        assert float(value) == pytest.approx(module.mass_absorption(float(wavelength)), rel=1e-5)
    peak = max(rows, key=lambda r: float(r[1]))
    assert float(peak[0]) == pytest.approx(530.0, abs=5.0)


# ---- phase tables ----------------------------------------------------------------------------------


@pytest.mark.parametrize("name", preset_names())
def test_every_preset_has_normalised_phase_tables(name):
    optics = medium_optics(load_preset(name))
    np.testing.assert_allclose(phase_integral(optics.cos_theta, optics.phase), 1.0, atol=1e-12)
    assert np.all(optics.phase >= 0)
    assert np.all(np.diff(optics.wavelengths_nm) > 0)
    np.testing.assert_allclose(optics.mu_t, optics.mu_s + optics.mu_a)
    assert optics.phase_icdf[:, 0] == pytest.approx(-1.0) and optics.phase_icdf[:, -1] == pytest.approx(1.0)
    assert np.all(np.diff(optics.phase_icdf, axis=1) >= 0)


def test_table_g_matches_mie_g(red_cotton):
    for row, wavelength in enumerate(red_cotton.wavelengths_nm):
        _, _, _, g = miepython.efficiencies(complex(1.61), 150.0, wavelength, n_env=1.557)
        assert red_cotton.g[row] == pytest.approx(g, abs=1e-5)


@pytest.mark.parametrize(
    "m, x", [(1.61 / 1.557, 1.8), (1.8 / 1.557 - 0.05j, 2.5), (2.55 / 1.6, 6.0), (1.0 / 1.557, 4.0)]
)
def test_differential_cross_section_matches_miepython_intensities(m, x):
    # miepython's own (per-angle) amplitude code: the unpolarised intensity with norm="qsca"
    # integrates to Q_sca, so dC/dΩ = that × πa²; with k = 1 the area is π x².
    mu = np.linspace(-1.0, 1.0, 257)
    i_par, i_per = miepython.intensities(m, 2 * x, 2 * math.pi, mu, norm="qsca")
    expected = 0.5 * (i_par + i_per) * math.pi * x**2
    np.testing.assert_allclose(differential_scattering_cross_section(complex(m), x, 1.0, mu), expected, rtol=1e-10)


def test_size_parameter_and_index_are_taken_in_the_host():
    # A particle of index 1.61 in a host of 1.557 is the same scatterer as 1.61/1.557 in vacuum
    # seen at the vacuum wavelength λ0/1.557.
    host = medium(species(), wavelengths=(550.0,))
    vacuum = medium(species(n=1.61 / 1.557), wavelengths=(550.0 / 1.557,), host_index=1.0)
    a, b = medium_optics(host), medium_optics(vacuum)
    assert a.mu_s[0] == pytest.approx(b.mu_s[0], rel=1e-10)
    np.testing.assert_allclose(a.phase, b.phase, rtol=1e-9)


def test_inverse_cdf_sampling_reproduces_the_table(red_cotton):
    rng = np.random.default_rng(7)
    edges = np.linspace(-1.0, 1.0, 41)
    fine = np.linspace(-1.0, 1.0, 40001)
    for row in (1, 16, 31):
        mu = sample_inverse_cdf(red_cotton.phase_icdf[row], rng.random(200_000))
        observed, _ = np.histogram(mu, edges)
        density = 2 * math.pi * np.interp(fine, red_cotton.cos_theta, red_cotton.phase[row])
        cdf = np.concatenate([[0.0], np.cumsum(0.5 * (density[1:] + density[:-1]) * np.diff(fine))])
        expected = np.diff(np.interp(edges, fine, cdf / cdf[-1])) * observed.sum()
        assert stats.chisquare(observed, expected).pvalue > 1e-3
        assert mu.mean() == pytest.approx(red_cotton.g[row], abs=5 * mu.std() / math.sqrt(mu.size))


@pytest.mark.parametrize("g", [-0.5, 0.0, 0.3, 0.85])
def test_henyey_greenstein_table_has_its_g_and_inverse_cdf(g):
    cos_theta = cos_theta_grid(4001)
    phase = henyey_greenstein_phase(cos_theta, g)
    assert phase_integral(cos_theta, phase) == pytest.approx(1.0, abs=2e-4)
    assert asymmetry_parameter(cos_theta, phase) == pytest.approx(g, abs=5e-4)
    u = np.linspace(0.0, 1.0, 513)
    exact = 2 * u - 1 if g == 0 else (1 + g * g - ((1 - g * g) / (1 - g + 2 * g * u)) ** 2) / (2 * g)
    np.testing.assert_allclose(phase_inverse_cdf(cos_theta, phase, 513), exact, atol=2e-3)


# ---- limits and combinations -------------------------------------------------------------------------


def test_rayleigh_limit_scales_as_inverse_fourth_power():
    wavelengths = np.linspace(400.0, 700.0, 7)
    optics = medium_optics(medium(species(diameter=5.0, fraction=0.01), wavelengths=wavelengths))
    slope = np.polyfit(np.log(wavelengths), np.log(optics.mu_s), 1)[0]
    assert slope == pytest.approx(-4.0, abs=0.01)
    rayleigh = 3.0 / (16.0 * math.pi) * (1.0 + optics.cos_theta**2)
    np.testing.assert_allclose(optics.phase, np.broadcast_to(rayleigh, optics.phase.shape), rtol=2e-3)
    assert np.all(np.abs(optics.g) < 2e-3)


def test_non_absorbing_medium_has_albedo_one():
    optics = medium_optics(load_preset("undyed_cotton"))
    assert np.all(optics.mu_a == 0.0) and np.all(optics.mu_s > 0)
    np.testing.assert_array_equal(optics.albedo, 1.0)


def test_absorbing_particles_absorb_by_their_mie_cross_section():
    optics = medium_optics(medium(species(n=1.8, k=0.05, diameter=200.0, fraction=0.05), wavelengths=(550.0,)))
    x = math.pi * 200.0 * 1.557 / 550.0
    q_ext, q_sca = mie_sums(complex(1.8, -0.05) / 1.557, x)
    number_area = 0.05 / (math.pi * 200.0**3 / 6) * math.pi * 200.0**2 / 4 * 1e6
    assert optics.mu_a[0] == pytest.approx(number_area * (q_ext - q_sca), rel=1e-9)
    assert optics.mu_s[0] == pytest.approx(number_area * q_sca, rel=1e-9)
    assert 0.0 < optics.albedo[0] < 1.0


@pytest.mark.parametrize("model", ["none", "percus-yevick"])
def test_two_identical_species_equal_one_with_the_summed_fraction(model):
    one = medium_optics(medium(species(fraction=0.14), model=model))
    two = medium_optics(medium(species("a", fraction=0.05), species("b", fraction=0.09), model=model))
    for field in ("mu_s", "mu_a", "g", "phase", "phase_icdf"):
        np.testing.assert_allclose(getattr(two, field), getattr(one, field), rtol=1e-10, atol=1e-12)


def test_two_species_combine_by_scattering_weighted_phase():
    small, large = species("small", diameter=60.0, fraction=0.05), species("large", diameter=400.0, fraction=0.02)
    a, b, mix = (medium_optics(medium(*s)) for s in ((small,), (large,), (small, large)))
    np.testing.assert_allclose(mix.mu_s, a.mu_s + b.mu_s, rtol=1e-12)
    expected = (a.mu_s[:, None] * a.phase + b.mu_s[:, None] * b.phase) / (a.mu_s + b.mu_s)[:, None]
    np.testing.assert_allclose(mix.phase, expected, rtol=1e-10)
    np.testing.assert_allclose(mix.g, (a.mu_s * a.g + b.mu_s * b.g) / (a.mu_s + b.mu_s), rtol=1e-8)


def test_narrow_log_normal_approaches_monodisperse():
    mono = medium_optics(medium(species(diameter=150.0)))
    narrow = medium_optics(medium(species(median_diameter_nm=150.0, geometric_sigma=1.001)))
    np.testing.assert_allclose(narrow.mu_s, mono.mu_s, rtol=1e-4)
    np.testing.assert_allclose(narrow.g, mono.g, atol=1e-5)


def test_log_normal_rayleigh_moments():
    # For Rayleigh particles C_sca ∝ d⁶, so μs = f ⟨C⟩/⟨V⟩ grows by ⟨d⁶⟩/(⟨d³⟩ d_g³) = exp(13.5 ln²σ_g).
    sigma = 1.5
    mono = medium_optics(medium(species(diameter=2.0, fraction=0.01), wavelengths=(600.0,)))
    broad = medium_optics(
        medium(species(median_diameter_nm=2.0, geometric_sigma=sigma, fraction=0.01), wavelengths=(600.0,))
    )
    assert broad.mu_s[0] / mono.mu_s[0] == pytest.approx(math.exp(13.5 * math.log(sigma) ** 2), rel=5e-3)


def test_tabulated_host_index_is_interpolated():
    params = dataclasses.replace(
        medium(species()),
        host=Host(RefractiveIndex(n=(1.56, 1.55), wavelengths_nm=(380.0, 740.0))),
    )
    optics = medium_optics(params)
    np.testing.assert_allclose(optics.host_index, 1.56 - 0.01 * (np.array(PAPER_WAVELENGTHS) - 380.0) / 360.0)
    assert optics.boundary_index == pytest.approx(np.mean(optics.host_index))
    assert optics.mu_s[1] == pytest.approx(
        medium_optics(medium(species(), host_index=optics.host_index[1])).mu_s[1], rel=1e-12
    )


def test_index_matched_particles_do_not_scatter():
    optics = medium_optics(medium(species(n=1.557)))
    np.testing.assert_array_equal(optics.mu_s, 0.0)
    np.testing.assert_allclose(phase_integral(optics.cos_theta, optics.phase), 1.0)


# ---- Percus–Yevick -------------------------------------------------------------------------------------


@pytest.mark.parametrize("fraction", [0.01, 0.14, 0.4])
def test_percus_yevick_structure_factor_against_its_defining_integral(fraction):
    f = fraction
    alpha = (1 + 2 * f) ** 2 / (1 - f) ** 4
    beta = -6 * f * (1 + f / 2) ** 2 / (1 - f) ** 4
    gamma = f * alpha / 2

    def direct(x):  # S = 1/(1 − n c(q)), −n c(q) = 24 f ∫₀¹ t² j0(x t)(α + βt + γt³) dt
        integrand = lambda t: t * t * np.sinc(x * t / math.pi) * (alpha + beta * t + gamma * t**3)  # noqa: E731
        return 1.0 / (1.0 + 24 * f * quad(integrand, 0.0, 1.0, epsabs=1e-13, epsrel=1e-12, limit=200)[0])

    x = np.array([0.0, 1e-4, 1e-2, 0.19, 0.21, 0.5, 2.0, 5.0, 7.5, 15.0, 40.0])
    np.testing.assert_allclose(percus_yevick_structure_factor(x, f), [direct(v) for v in x], rtol=1e-8)
    assert percus_yevick_structure_factor(0.0, f) == pytest.approx((1 - f) ** 4 / (1 + 2 * f) ** 2, rel=1e-12)
    assert percus_yevick_structure_factor(400.0, f) == pytest.approx(1.0, abs=2e-3)


def test_percus_yevick_change_for_the_paper_medium(red_cotton, red_cotton_py):
    factor = red_cotton_py.mu_s / red_cotton.mu_s
    # The expectation for f = 0.14: roughly 0.5–0.65 × μs.
    assert np.all((factor > 0.5) & (factor < 0.65))
    # Correlations suppress forward (small-q) scattering most: g drops at every wavelength.
    assert np.all(red_cotton_py.g < red_cotton.g)
    np.testing.assert_array_equal(red_cotton_py.mu_a, red_cotton.mu_a)
    np.testing.assert_allclose(phase_integral(red_cotton_py.cos_theta, red_cotton_py.phase), 1.0)
    assert red_cotton_py.dependent_scattering == "percus-yevick"


def test_percus_yevick_vanishes_for_a_dilute_medium():
    dilute = species(fraction=1e-5)
    independent = medium_optics(medium(dilute))
    corrected = medium_optics(medium(dilute, model="percus-yevick"))
    np.testing.assert_allclose(corrected.mu_s, independent.mu_s, rtol=2e-4)
    np.testing.assert_allclose(corrected.g, independent.g, atol=2e-4)


# ---- the command ---------------------------------------------------------------------------------------


def test_optics_command_json_and_plot(tmp_path, capsys, red_cotton, red_cotton_py):
    png = tmp_path / "optics.png"
    assert main(["optics", "--preset", "paper_2008", "--json", "--plot", str(png)]) == 0
    report = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(report["mu_s_per_mm"], red_cotton.mu_s)
    np.testing.assert_allclose(report["albedo"], red_cotton.albedo)
    np.testing.assert_allclose(report["percus_yevick_factor"]["mu_s"], red_cotton_py.mu_s / red_cotton.mu_s)
    np.testing.assert_allclose(report["percus_yevick_factor"]["g"], red_cotton_py.g / red_cotton.g)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 20_000


def test_optics_command_table_with_percus_yevick(capsys, red_cotton_py):
    assert main(["optics", "--preset", "paper_2008", "--percus-yevick"]) == 0
    out = capsys.readouterr().out
    assert "percus-yevick" in out
    line = next(l for l in out.splitlines() if l.strip().startswith("550.0"))  # noqa: E741
    assert float(line.split()[1]) == pytest.approx(red_cotton_py.mu_s[16], rel=1e-3)
