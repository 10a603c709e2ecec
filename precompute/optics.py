"""Optical properties of a yarn medium per wavelength: what the transport kernel consumes.

``medium_optics(params)`` turns the physical description
(:class:`precompute.medium.MediumParameters`) into μs, μa, μt (1/mm), albedo,
asymmetry g and a tabulated phase function with its sampling table (paper §3.3:
"scattering cross-sections and phase functions were calculated from the Mie
theory").  Several particle species combine by adding coefficients and
weighting their phase functions by their scattering coefficients.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .dye import dye_absorption_coefficient
from .medium import DEFAULT_PRESET, MediumParameters, load_preset
from .mie import species_scattering
from .phase import DEFAULT_COS_THETA, DEFAULT_ICDF_SIZE, asymmetry_parameter, phase_inverse_cdf


@dataclass(frozen=True)
class MediumOptics:
    """Per-wavelength optics of a yarn medium.

    Attributes
    ----------
    wavelengths_nm : (L,) vacuum wavelengths, nm
    mu_s, mu_a, mu_t : (L,) scattering, absorption, extinction coefficients, 1/mm
    albedo : (L,) single-scattering albedo μs/μt
    g : (L,) asymmetry parameter ⟨cos θ⟩
    host_index : (L,) real refractive index of the host
    cos_theta : (M,) grid of the phase table over [−1, 1]
    phase : (L, M) phase function, 1/sr, 2π∫p dμ = 1
    phase_icdf : (L, K) μ at cumulative probability k/(K−1)
    """

    wavelengths_nm: np.ndarray
    mu_s: np.ndarray
    mu_a: np.ndarray
    mu_t: np.ndarray
    albedo: np.ndarray
    g: np.ndarray
    host_index: np.ndarray
    cos_theta: np.ndarray
    phase: np.ndarray
    phase_icdf: np.ndarray

    @property
    def boundary_index(self) -> float:
        """One real index for the yarn boundary: the host index averaged over the wavelengths.

        Refraction is taken as wavelength-independent so that one path serves
        every wavelength; the host's dispersion over the visible is ~1 %.
        """
        return float(np.mean(self.host_index))


def medium_optics(params: MediumParameters, *, icdf_size: int = DEFAULT_ICDF_SIZE) -> MediumOptics:
    """Optical properties of ``params`` on its wavelength grid (see the module docstring)."""
    wavelengths = params.wavelengths.values
    host_complex = params.host.refractive_index.at(wavelengths)
    host_index = host_complex.real
    cos_theta = DEFAULT_COS_THETA
    mu_s = np.zeros(len(wavelengths))
    mu_a = np.full(len(wavelengths), float(params.host.absorption_per_mm))
    weighted_phase = np.zeros((len(wavelengths), len(cos_theta)))
    for species in params.particles:
        contribution = species_scattering(species, wavelengths, host_index, cos_theta, params.dependent_scattering)
        mu_s += contribution.mu_s
        mu_a += contribution.mu_a
        weighted_phase += contribution.mu_s[:, None] * contribution.phase
    if params.dye is not None:
        mu_a += dye_absorption_coefficient(params.dye, wavelengths)
    if np.any(mu_s > 0):
        phase = np.where(mu_s[:, None] > 0, weighted_phase / np.where(mu_s > 0, mu_s, 1.0)[:, None], 1.0 / (4 * np.pi))
    else:
        phase = np.full_like(weighted_phase, 1.0 / (4.0 * np.pi))
    mu_t = mu_s + mu_a
    albedo = np.divide(mu_s, mu_t, out=np.zeros_like(mu_s), where=mu_t > 0)
    return MediumOptics(
        wavelengths_nm=wavelengths,
        mu_s=mu_s,
        mu_a=mu_a,
        mu_t=mu_t,
        albedo=albedo,
        g=asymmetry_parameter(cos_theta, phase),
        host_index=host_index,
        cos_theta=cos_theta,
        phase=phase,
        phase_icdf=phase_inverse_cdf(cos_theta, phase, icdf_size),
    )


def default_optics() -> MediumOptics:
    """Optics of the paper's red cotton (the default preset)."""
    return medium_optics(load_preset(DEFAULT_PRESET))
