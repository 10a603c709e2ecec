"""The fibres of a yarn (precompute/optics/fibre.py): the per-fibre model against geometric optics,
the dye inside the fibres, the medium's [fibres] table."""

import math

import numpy as np
import pytest

from precompute.errors import ParameterError
from precompute.optics.coefficients import medium_optics
from precompute.optics.fibre import (
    fibre_index,
    fibre_scattering,
    fraunhofer_differential_cross_section,
    fresnel_reflectance,
    proxy_diameter_nm,
    reflection_differential_cross_section,
)
from precompute.optics.medium import PRESET_DIR, Fibres, RefractiveIndex, load_preset_config, medium_from_dict
from precompute.optics.mie import differential_scattering_cross_section
from precompute.optics.phase import angle_cos_theta_grid, asymmetry_parameter, phase_integral

#: A yarn of fibres in air, not shipped (docs/fitting.md, "Against the raw-data fabrics").
FIBRE_COTTON = PRESET_DIR / "experimental" / "fibre_cotton.toml"


def opaque_fibre(diameter_um=20.0, wavelength_nm=600.0, k=0.01):
    """A fibre whose material absorbs everything that enters it (k = 0.01: 1/e in 4.8 µm, its proxy is
    30 µm across) while reflecting as the clear dielectric (k² ≪ (n − 1)²)."""
    absorption_per_mm = 4.0 * math.pi * k / (wavelength_nm * 1e-6)
    return Fibres(RefractiveIndex(1.557), diameter_um, 0.5, absorption_per_mm=absorption_per_mm)


def test_the_reflection_law_of_the_phase_function_is_exact_mie_of_an_opaque_sphere():
    # van de Hulst's specular sphere (1957, chapter 12), (a²/4) R((π − Θ)/2), against miepython's exact series for a
    # sphere that absorbs all it lets in, behind it (no diffraction there, no light through)
    fibres, wavelength = opaque_fibre(), 600.0
    radius = proxy_diameter_nm(fibres) / 2.0
    wavenumber = 2.0 * math.pi / wavelength
    cos_theta = angle_cos_theta_grid(20001)
    m = complex(fibre_index(fibres, None, np.array([wavelength]))[0].conjugate())
    mie = differential_scattering_cross_section(m, wavenumber * radius, wavenumber, cos_theta)
    law = reflection_differential_cross_section(radius, 1.557, cos_theta)
    theta = np.arccos(cos_theta)
    for low, high in ((100, 120), (120, 140), (140, 160), (160, 175)):
        band = (theta >= math.radians(low)) & (theta <= math.radians(high))
        ratio = phase_integral(cos_theta[band], mie[band]) / phase_integral(cos_theta[band], law[band])
        assert ratio == pytest.approx(1.0, abs=0.06), (low, high)


def test_the_fibres_phase_function_is_their_reflection_behind_and_keeps_the_mie_mean_cosine():
    fibres = Fibres(RefractiveIndex(1.557), 15.0, 0.5)
    cos_theta = angle_cos_theta_grid(20001)
    result = fibre_scattering(fibres, None, np.array([550.0]), np.array([1.0]), cos_theta)
    c_geometric = result.mu_s[0] / (result.number_density_per_um3 * 1e-9 * 1e6)
    radius = proxy_diameter_nm(fibres) / 2.0
    law = reflection_differential_cross_section(radius, 1.557, cos_theta)
    assert np.all(result.phase[0] * c_geometric >= law * (1.0 - 1e-9))  # the reflection, undyed, is all in it
    m = complex(1.557, 0.0)
    wavenumber = 2.0 * math.pi / 550.0
    mie = differential_scattering_cross_section(m, wavenumber * radius, wavenumber, cos_theta)
    geometric = np.clip(mie - fraunhofer_differential_cross_section(radius, wavenumber, cos_theta), 0.0, None)
    # no glory: the sphere's focusing back toward the source (within 5° of it) is gone
    glory, near = cos_theta < math.cos(math.radians(175.0)), (cos_theta > -0.985) & (cos_theta < -0.94)
    assert geometric[glory].mean() > 2.0 * geometric[near].mean()
    assert result.phase[0, glory].mean() < 1.1 * result.phase[0, near].mean()
    # the mean cosine is the proxy's Mie one less its diffraction
    g_mie = asymmetry_parameter(cos_theta, geometric / phase_integral(cos_theta, geometric))
    assert asymmetry_parameter(cos_theta, result.phase[0]) == pytest.approx(g_mie, abs=1e-3)


def test_an_opaque_fibre_absorbs_what_its_surface_does_not_reflect_as_x_grows():
    # geometric optics: C_abs = πa² (1 − R̄), R̄ the sphere's hemispherical Fresnel reflectance; Mie
    # approaches it as the edge terms (∝ x^(-2/3), van de Hulst 1957, chapter 17) fade
    cos_i = np.linspace(0.0, 1.0, 20001)
    mean_reflectance = np.trapz(fresnel_reflectance(cos_i, 1.557) * 2.0 * cos_i, cos_i)
    misses = []
    for diameter_um in (20.0, 80.0):  # proxy size parameters 157 and 628 at 600 nm
        fibres = opaque_fibre(diameter_um)
        result = fibre_scattering(fibres, None, np.array([600.0]), np.array([1.0]), angle_cos_theta_grid(40001))
        c_abs = result.mu_a[0] / (result.number_density_per_um3 * 1e-9 * 1e6)
        misses.append(c_abs / (math.pi * (proxy_diameter_nm(fibres) / 2.0) ** 2) / (1.0 - mean_reflectance) - 1.0)
    assert 0.0 < misses[1] < 0.5 * misses[0]
    assert misses[1] < 0.015


def test_the_diffraction_peak_holds_the_geometric_cross_section_and_is_taken_out():
    radius, wavenumber = 10_000.0, 2.0 * math.pi / 500.0  # x = 126
    cos_theta = angle_cos_theta_grid(40001)
    fraunhofer = fraunhofer_differential_cross_section(radius, wavenumber, cos_theta)
    assert phase_integral(cos_theta, fraunhofer) == pytest.approx(math.pi * radius**2, rel=0.01)
    clear = Fibres(RefractiveIndex(1.557), 2.0 * radius / 1.5 / 1000.0, 0.5)  # proxy radius 10 µm
    result = fibre_scattering(clear, None, np.array([500.0]), np.array([1.0]), cos_theta)
    # a clear fibre: what it scatters is what it reflects and refracts, about its projected area
    density_per_nm3 = result.number_density_per_um3 * 1e-9
    c_geometric = result.mu_s[0] / (density_per_nm3 * 1e6)
    assert c_geometric / (math.pi * radius**2) == pytest.approx(1.0, abs=0.1)
    assert result.mu_a[0] == 0.0


def test_extinction_per_volume_is_the_fibres_projected_area_per_volume():
    # equal volume-to-surface proxy: μ_t = φ S / 4V = φ / d for long cylinders (Cauchy), whatever the
    # index, plus the edge terms of the extinction the diffraction leaves (≈ 2 x^(-2/3): 6-10 % here)
    # and the ripple of a monodisperse sphere
    config, base = load_preset_config(FIBRE_COTTON)
    medium = medium_from_dict({**config, "dye": {**config["dye"], "weight_percent": 0.0}}, base)
    optics = medium_optics(medium)
    expected = medium.fibres.volume_fraction / (medium.fibres.diameter_um * 1e-3)
    assert np.all(optics.mu_t > expected) and np.all(optics.mu_t < 1.2 * expected)


def test_the_dye_is_in_the_fibres_whose_surfaces_still_reflect():
    config, base = load_preset_config(FIBRE_COTTON)
    heavy = medium_from_dict({**config, "dye": {**config["dye"], "weight_percent": 10.0}}, base)
    fibre_optics = medium_optics(heavy)
    blue = fibre_optics.wavelengths_nm <= 500.0
    # the dye's k: μ_a λ / 4π
    index = fibre_index(heavy.fibres, heavy.dye, fibre_optics.wavelengths_nm)
    assert np.all(index.imag[blue] > 1e-3)
    # however dark the fibre, light meeting it is reflected first: the albedo keeps the Fresnel floor
    assert np.all(fibre_optics.albedo[blue] > 0.1)
    # the same dye in a host that every path crosses leaves almost nothing
    host_dyed = {**config, "host": {"refractive_index": 1.557}, "dye": {**config["dye"], "weight_percent": 10.0},
                 "particles": [{"name": "voids", "refractive_index": 1.0, "diameter_nm": 15000.0,
                                "volume_fraction": 0.3}]}
    del host_dyed["fibres"]
    assert np.all(medium_optics(medium_from_dict(host_dyed, base)).albedo[blue] < 0.5 * fibre_optics.albedo[blue])


def test_the_fibres_table_is_checked():
    config, base = load_preset_config(FIBRE_COTTON)
    for key, value, allowed in (("volume_fraction", 0.95, "0.9"), ("diameter_um", 0.1, "µm"),
                                ("cross_section", "ellipse", "circle"), ("absorption_per_mm", -1.0, "≥ 0"),
                                ("colour", 1, "one of the keys")):
        with pytest.raises(ParameterError, match=allowed):
            medium_from_dict({**config, "fibres": {**config["fibres"], key: value}}, base)


def test_a_boundary_of_air_reflects_no_sheen_and_stays_finite_at_grazing():
    from precompute.optics.cook_torrance import cook_torrance

    rng = np.random.default_rng(2)
    light, view = (v / np.linalg.norm(v, axis=-1, keepdims=True) for v in rng.normal(size=(2, 500, 3)))
    light[:, 2], view[:, 2] = np.abs(light[:, 2]), np.abs(view[:, 2])
    view[0] = -light[0]  # lit from straight behind the view (the back-lit swatch): no half vector, c = 0
    assert np.all(cook_torrance(light, view, 0.3, 1.0) == 0.0)
    assert np.all(np.isfinite(cook_torrance(light, view, 0.3, 1.557)))


def test_fibres_packed_denser_than_spheres_can_be_have_optics():
    config, base = load_preset_config(FIBRE_COTTON)
    dense = medium_from_dict({**config, "fibres": {**config["fibres"], "volume_fraction": 0.8}}, base)
    assert np.all(medium_optics(dense).mu_t > medium_optics(medium_from_dict(config, base)).mu_t)


def test_the_bake_refuses_a_dye_series_for_fibres_whose_dye_changes_how_they_scatter():
    from precompute.bake import bake_configuration, check_dye_series

    configuration = bake_configuration(FIBRE_COTTON)
    with pytest.raises(ParameterError, match="dye_series = .*randomly oriented fibres"):
        check_dye_series(configuration, (0.05, 3.0))
