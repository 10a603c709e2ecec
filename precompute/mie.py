"""Scattering by the particles of one species, from Mie theory in the host medium (paper §3.3).

Each particle scatters in the host: the wavelength inside is ``λ0 / n_host`` and
the relative index ``n_particle / n_host``.  Cross-sections and phase functions
come from miepython (which takes the imaginary part with a negative sign:
``n − ik``).  Optionally the Percus–Yevick hard-sphere structure factor corrects
for dependent scattering in dense media (Percus & Yevick, Phys. Rev. 110, 1958;
closed form of Wertheim, PRL 10, 1963; as used for particulate media by e.g.
Fraden & Maret, PRL 65, 1990).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import miepython
import numpy as np

from .medium import ParticleSpecies
from .phase import normalize_phase

#: Quadrature nodes over ±4 geometric standard deviations of a log-normal size distribution.
_LOGNORMAL_NODES = 24


@dataclass(frozen=True)
class SpeciesScattering:
    """Bulk optical properties contributed by one particle species.

    ``mu_s``, ``mu_a`` (L,) in 1/mm; ``phase`` (L, M) normalised, 1/sr, on ``cos_theta``.
    ``number_density_per_um3`` particles per µm³.
    """

    mu_s: np.ndarray
    mu_a: np.ndarray
    phase: np.ndarray
    number_density_per_um3: float


def size_distribution(species: ParticleSpecies) -> tuple[np.ndarray, np.ndarray]:
    """Diameters (nm) and number weights (summing to 1) of a species' particles."""
    if species.diameter_nm is not None:
        return np.array([float(species.diameter_nm)]), np.array([1.0])
    ln_sigma = math.log(species.geometric_sigma)
    z = np.linspace(-4.0, 4.0, _LOGNORMAL_NODES)
    diameters = species.median_diameter_nm * np.exp(z * ln_sigma)
    weights = np.exp(-0.5 * z**2)
    return diameters, weights / weights.sum()


def number_density(species: ParticleSpecies) -> float:
    """Particles per nm³ that fill ``volume_fraction`` of the volume with the species' size distribution."""
    diameters, weights = size_distribution(species)
    mean_volume = float(np.sum(weights * np.pi * diameters**3 / 6.0))
    return species.volume_fraction / mean_volume


def percus_yevick_structure_factor(q_times_d: np.ndarray, volume_fraction: float) -> np.ndarray:
    """Hard-sphere structure factor S(q) in the Percus–Yevick approximation, for ``x = q·d``."""
    f = volume_fraction
    x = np.maximum(np.asarray(q_times_d, float), 1e-4)
    alpha = (1 + 2 * f) ** 2 / (1 - f) ** 4
    beta = -6 * f * (1 + f / 2) ** 2 / (1 - f) ** 4
    gamma = f * alpha / 2
    sin, cos = np.sin(x), np.cos(x)
    g = (
        alpha / x**2 * (sin - x * cos)
        + beta / x**3 * (2 * x * sin + (2 - x**2) * cos - 2)
        + gamma / x**5 * (-(x**4) * cos + 4 * ((3 * x**2 - 6) * cos + (x**3 - 6 * x) * sin + 6))
    )
    return 1.0 / (1.0 + 24.0 * f * g / x)


def species_scattering(
    species: ParticleSpecies,
    wavelengths_nm: np.ndarray,
    host_index: np.ndarray,
    cos_theta: np.ndarray,
    dependent_scattering: str = "none",
) -> SpeciesScattering:
    """μs, μa and phase function of one species dispersed in a host of real index ``host_index``.

    Independent scattering: ``μs = N ⟨C_sca⟩``, ``μa = N ⟨C_abs⟩`` with ``N`` the
    number density and ``C = Q π d² / 4``; the phase function is the
    cross-section-weighted mean of the single-particle ones.  With
    ``"percus-yevick"`` the differential cross-section is multiplied by
    ``S(q)``, ``q = 2 k sin(θ/2)``, ``k = 2π n_host / λ0``, evaluated at the
    number-mean diameter.
    """
    n_particle = species.refractive_index.at(wavelengths_nm)
    diameters, weights = size_distribution(species)
    density_nm3 = number_density(species)
    mean_diameter = float(np.sum(weights * diameters))
    mu_s = np.empty(len(wavelengths_nm))
    mu_a = np.empty(len(wavelengths_nm))
    phase = np.empty((len(wavelengths_nm), len(cos_theta)))
    for index, (wavelength, n_host, n_p) in enumerate(zip(wavelengths_nm, host_index, n_particle)):
        m = complex(n_p.real, -n_p.imag)  # miepython's sign convention
        differential = np.zeros(len(cos_theta))  # Σ w dσ/dΩ, nm²/sr
        c_abs = 0.0
        for diameter, weight in zip(diameters, weights):
            qext, qsca, _, _ = miepython.efficiencies(m, diameter, wavelength, n_env=n_host)
            area = np.pi * diameter**2 / 4.0
            c_sca = float(qsca) * area
            c_abs += weight * (float(qext) - float(qsca)) * area
            intensity = miepython.intensities(m, diameter, wavelength, cos_theta, n_env=n_host, norm="one")
            p = 0.5 * (intensity[0] + intensity[1])  # unpolarised, normalised to 1 over 4π
            differential += weight * c_sca * p
        if dependent_scattering == "percus-yevick":
            k = 2.0 * np.pi * n_host / wavelength
            q = 2.0 * k * np.sqrt(np.clip((1.0 - cos_theta) / 2.0, 0.0, 1.0))
            differential = differential * percus_yevick_structure_factor(q * mean_diameter, species.volume_fraction)
        c_sca_total = 2.0 * np.pi * float(np.sum(0.5 * (differential[1:] + differential[:-1]) * np.diff(cos_theta)))
        # nm² × 1/nm³ = 1/nm; × 1e6 → 1/mm
        mu_s[index] = density_nm3 * c_sca_total * 1e6
        mu_a[index] = density_nm3 * c_abs * 1e6
        phase[index] = normalize_phase(cos_theta, differential)
    return SpeciesScattering(mu_s=mu_s, mu_a=mu_a, phase=phase, number_density_per_um3=density_nm3 * 1e9)
