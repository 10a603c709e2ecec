"""The yarn's own structure as scatterers: air voids (index 1) in cellulose (1.557), 1–20 µm.

Checks miepython where voids take it (size parameter in the host up to x ≈ 250, relative index
m = 1/1.557 < 1) against the large-sphere limit of extinction and against its own g, and the
automatic cos θ grid (``medium.phase_samples = "auto"``) that makes such species usable.
"""

import dataclasses
import math

import miepython
import numpy as np
import pytest

from precompute import bake as bake_module
from precompute.optics.medium import Host, MediumParameters, ParticleSpecies, RefractiveIndex, WavelengthGrid
from precompute.optics.mie import (
    PHASE_TABLE_TOLERANCE,
    PhaseGridTooCoarse,
    differential_scattering_cross_section,
    largest_size_parameter,
)
from precompute.optics.coefficients import medium_optics, planned_phase_grid
from precompute.optics.phase import (
    angle_cos_theta_grid,
    asymmetry_parameter,
    cos_theta_grid,
    henyey_greenstein_phase,
    normalize_phase,
    phase_integral,
    resample_uniform_cos,
)
from precompute.transport.media import medium_from_optics

HOST = 1.557
M_VOID = 1.0 / HOST
WAVELENGTHS = (390.0, 450.0, 550.0, 650.0, 730.0)


def voids(diameter_nm: float, fraction: float = 0.2, wavelengths=WAVELENGTHS, **medium) -> MediumParameters:
    return MediumParameters(
        name="voids",
        host=Host(RefractiveIndex(HOST)),
        particles=(ParticleSpecies("air", RefractiveIndex(1.0), fraction, diameter_nm=diameter_nm),),
        wavelengths=WavelengthGrid(values_nm=tuple(wavelengths)),
        **medium,
    )


# ---- miepython at large size parameters, m < 1 ---------------------------------------------------


@pytest.mark.parametrize("x", [100.0, 150.0, 250.0, 400.0])
def test_extinction_tends_to_twice_the_geometric_cross_section(x):
    # Extinction paradox (van de Hulst 1957, §8.22): Q_ext → 2, the excess decaying as the
    # edge term ~x^(−2/3) (Nussenzveig & Wiscombe, PRL 45, 1490 (1980)) about the anomalous-
    # diffraction value 2 − 4 sin ρ/ρ + 4 (1 − cos ρ)/ρ², ρ = 2x|m − 1| (van de Hulst §11.22).
    q_ext, q_sca, _, _ = miepython.efficiencies_mx(complex(M_VOID), x)
    assert abs(q_ext - 2.0) <= 3.0 * x ** (-2.0 / 3.0)
    rho = 2.0 * x * abs(M_VOID - 1.0)
    anomalous = 2.0 - 4.0 * math.sin(rho) / rho + 4.0 * (1.0 - math.cos(rho)) / rho**2
    assert 0.0 < q_ext - anomalous <= 3.0 * x ** (-2.0 / 3.0)
    # A real index absorbs nothing: Q_sca = Q_ext.
    assert q_sca == pytest.approx(q_ext, rel=1e-9)
    # ... and the efficiencies are the Mie series' (Bohren & Huffman 1983, eqs. 4.61, 4.62).
    a, b = miepython.an_bn(complex(M_VOID), x, 0)
    n = np.arange(1, len(a) + 1)
    assert q_sca == pytest.approx(2.0 / x**2 * np.sum((2 * n + 1) * (np.abs(a) ** 2 + np.abs(b) ** 2)), rel=1e-9)
    assert len(a) >= x  # the series runs past x (Wiscombe's n_max ≈ x + 4 x^(1/3) + 2)


@pytest.mark.parametrize("x", [12.5, 62.7, 250.8])  # 1, 5, 20 µm voids at 390 nm
def test_phase_function_integrates_to_miepythons_cross_section_and_g(x):
    # A fine grid uniform in θ: ∫ dC/dΩ dΩ is Q_sca π a² and the mean cosine is miepython's g.
    cos_theta = angle_cos_theta_grid(40001)
    differential = differential_scattering_cross_section(complex(M_VOID), x, 1.0, cos_theta)  # a = x
    _, q_sca, _, g = miepython.efficiencies_mx(complex(M_VOID), x)
    # trapezoidal error ≈ 0.5 (x/M)², 2e-5 at x = 250
    assert float(phase_integral(cos_theta, differential)) == pytest.approx(q_sca * math.pi * x**2, rel=5e-5)
    phase = normalize_phase(cos_theta, differential)
    assert float(asymmetry_parameter(cos_theta, phase)) == pytest.approx(g, abs=1e-5)
    assert 0.7 < g < 0.85  # forward diffraction, partly undone by refraction and reflection at m < 1


# ---- a void species in a yarn medium ---------------------------------------------------------------


def test_micron_voids_at_twenty_percent_make_cotton_opaque():
    params = voids(1000.0, 0.2)
    optics = medium_optics(params)
    # μs = N Q_sca π d²/4, N = f / (π d³/6): ≈ 5–7 × 10² /mm (1 µm voids, 20 %), where the paper's
    # 150 nm particles at 14 % give ~10 /mm.
    number_density = 0.2 / (math.pi * 1000.0**3 / 6.0)
    for row, wavelength in enumerate(params.wavelengths.values):
        _, q_sca, _, g = miepython.efficiencies(complex(1.0), 1000.0, wavelength, n_env=HOST)
        expected = number_density * q_sca * math.pi * 1000.0**2 / 4.0 * 1e6
        assert optics.mu_s[row] == pytest.approx(expected, rel=1e-9)
        assert 300.0 < optics.mu_s[row] < 1000.0
        assert optics.g[row] == pytest.approx(g, abs=5e-4)
    assert np.all(optics.mu_a == 0.0) and np.all(optics.albedo == 1.0)
    g = dict(zip(params.wavelengths.values, optics.g))
    assert 0.74 < g[450.0] < 0.80 and 0.79 < g[650.0] < 0.85  # ≈ 0.768 and ≈ 0.817


@pytest.mark.parametrize("diameter, samples", [(1000.0, 2001), (5000.0, 2201), (20000.0, 8701)])
def test_auto_grid_integrates_the_mie_cross_section_to_tolerance(diameter, samples):
    params = voids(diameter)
    assert params.phase_samples == "auto"
    optics = medium_optics(params)
    assert (optics.phase_grid, optics.phase_samples) == ("uniform-angle", samples)
    assert planned_phase_grid(params) == ("uniform-angle", samples)  # no refinement needed
    cos_theta = optics.cos_theta
    assert cos_theta[0] == -1.0 and cos_theta[-1] == 1.0 and np.all(np.diff(cos_theta) > 0)
    for row, wavelength in enumerate(params.wavelengths.values):
        k = 2.0 * math.pi * HOST / wavelength
        x = k * diameter / 2.0
        _, q_sca, _, g = miepython.efficiencies(complex(1.0), diameter, wavelength, n_env=HOST)
        differential = differential_scattering_cross_section(complex(M_VOID), x, k, cos_theta)
        tabulated = float(phase_integral(cos_theta, differential))
        assert tabulated == pytest.approx(q_sca * math.pi * diameter**2 / 4.0, rel=PHASE_TABLE_TOLERANCE)
        assert optics.g[row] == pytest.approx(g, abs=5e-4)
    # The uniform grid of as many samples would miss by far more than the tolerance at 5 and 20 µm.
    if diameter > 1000.0:
        with pytest.raises(PhaseGridTooCoarse):
            medium_optics(dataclasses.replace(params, phase_samples=samples))


def test_explicit_too_coarse_phase_samples_still_raise():
    params = voids(5000.0, phase_samples=2001)
    with pytest.raises(PhaseGridTooCoarse) as info:
        medium_optics(params)
    error = info.value
    assert error.name == "medium.phase_samples" and error.value == 2001
    assert "forward-peaked" in error.allowed and '"auto"' in error.allowed
    assert error.relative_error > PHASE_TABLE_TOLERANCE


def test_auto_grid_refines_a_plan_that_falls_short(monkeypatch):
    # A plan far too coarse (as if the size estimate missed the particles) is refined, not refused.
    from precompute.optics import coefficients as optics_module

    monkeypatch.setattr(optics_module, "auto_phase_grid", lambda *args: ("uniform-angle", 401))
    optics = medium_optics(voids(20000.0, wavelengths=(390.0,)))
    assert optics.phase_grid == "uniform-angle" and optics.phase_samples > 401
    assert optics.phase_samples <= 4 * 8701


def test_size_parameter_estimate_of_a_lognormal_species():
    species = ParticleSpecies("air", RefractiveIndex(1.0), 0.1, median_diameter_nm=2000.0, geometric_sigma=1.3)
    ln_sigma = math.log(1.3)
    expected = math.pi * 2000.0 * math.exp(2 * ln_sigma**2 + 3 * ln_sigma) * HOST / 390.0
    x = largest_size_parameter((species,), np.array(WAVELENGTHS), np.full(len(WAVELENGTHS), HOST))
    assert x == pytest.approx(expected)


# ---- the transport's uniform table and the cache key -----------------------------------------------


def test_transport_table_keeps_probability_and_g_of_a_twenty_micron_peak():
    optics = medium_optics(voids(20000.0))
    medium = medium_from_optics(optics)
    uniform = cos_theta_grid(optics.phase_samples)
    assert medium.phase_table.shape == (len(WAVELENGTHS), optics.phase_samples)
    np.testing.assert_allclose(phase_integral(uniform, medium.phase_table), 1.0, rtol=1e-12)
    np.testing.assert_allclose(asymmetry_parameter(uniform, medium.phase_table), optics.g, atol=1e-4)
    # A linear interpolation onto the same grid would give the peak its height, not its probability.
    interpolated = np.array([np.interp(uniform, optics.cos_theta, row) for row in optics.phase])
    assert np.max(np.abs(phase_integral(uniform, interpolated) - 1.0)) > 0.05


def test_resampling_is_the_identity_on_the_uniform_grid_and_exact_in_probability():
    grid = cos_theta_grid(2001)
    phase = henyey_greenstein_phase(grid, np.array([0.3, 0.9]))
    assert resample_uniform_cos(grid, phase, 2001) is phase
    fine = angle_cos_theta_grid(3001)
    table = henyey_greenstein_phase(fine, 0.95)
    resampled = resample_uniform_cos(fine, table, 1001)
    assert float(phase_integral(cos_theta_grid(1001), resampled)) == pytest.approx(
        float(phase_integral(fine, table)), rel=1e-12
    )
    assert np.all(resampled >= 0)


def test_bake_cache_key_holds_the_chosen_grid():
    small, large = (bake_module.bake_configuration(voids(d, wavelengths=(450.0, 650.0))) for d in (1000.0, 20000.0))
    inputs = [bake_module.spectral_inputs(c) for c in (small, large)]
    # x = 10.9 at 450 nm: the default grid; x = 217: uniform in θ, 34.6 x rounded up
    assert [i["planned_phase_grid"] for i in inputs] == [
        {"kind": "uniform-cos", "samples": 2001},
        {"kind": "uniform-angle", "samples": 7601},
    ]
    assert inputs[0]["medium"]["phase_samples"] == "auto"
    explicit = bake_module.spectral_inputs(bake_module.bake_configuration(
        dataclasses.replace(small.medium, phase_samples=4001)))
    assert explicit["planned_phase_grid"] == {"kind": "uniform-cos", "samples": 4001}
    keys = {bake_module.cache_key(i) for i in (*inputs, explicit)}
    assert len(keys) == 3
