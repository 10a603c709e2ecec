"""Scattering by the particles of one species, from Mie theory in the host medium (paper §3.3).

Each particle scatters inside the host: the wavelength there is ``λ0 / n_host``
and the relative index ``m = n_particle / n_host`` (complex for an absorbing
particle).  miepython supplies the efficiencies and the Mie coefficients
``a_n, b_n``; it writes an absorbing index ``n − ik``, ClothLight writes
``n + ik`` with ``k ≥ 0`` and converts here.

Dense media.  The paper (§6.2) puts 14 % of the volume in particles and treats
them as independent scatterers.  Optionally the far field of each particle is
multiplied by the Percus–Yevick hard-sphere structure factor ``S(q)``, the
standard first correction for dependent scattering (Percus & Yevick, Phys.
Rev. 110, 1 (1958); closed form of Wertheim, PRL 10, 321 (1963) and Ashcroft &
Lekner, Phys. Rev. 145, 83 (1966); applied to light in particulate media e.g. by
Fraden & Maret, PRL 65, 512 (1990)).  Two approximations are made and stated:
every species sees the hard-sphere correlations of the *total* particle volume
fraction (an effective one-component fluid), and a size distribution is
corrected diameter by diameter ("local monodisperse approximation",
Pedersen, J. Appl. Cryst. 27, 595 (1994)).

Large scatterers.  The yarn's own structure — air between and inside the fibres,
voids of 1–20 µm, index 1 in a host of 1.557 (``m ≈ 0.64``) — enters as a
particle species like any other.  Its size parameter in the host reaches
``x = π d n_host / λ0 ≈ 250`` (20 µm at 390 nm), where ``Q_ext → 2`` (the
extinction paradox, van de Hulst 1957, §8.22) and half of the scattering lies in
a diffraction peak of angular width ~1/x.  The cos θ grid of the phase tables is
then chosen for the particles (:func:`auto_phase_grid`); the trapezoidal error
of the table's integral follows the fitted models :func:`grid_error_estimate`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import miepython
import numpy as np

from precompute.errors import ParameterError
from precompute.optics.medium import ParticleSpecies
from precompute.optics.phase import DEFAULT_PHASE_SAMPLES, normalize_phase, phase_integral

#: Spacing, in standard deviations of ln d, of the quadrature over a log-normal size distribution.
LOGNORMAL_STEP = 0.25
#: Largest relative error allowed in the phase table's integral of the Mie cross-section.
PHASE_TABLE_TOLERANCE = 1e-3
#: Most samples of an automatically chosen cos θ grid (``medium.phase_samples`` allows as many).
MAX_AUTO_PHASE_SAMPLES = 200001
#: Trapezoidal error of the phase table's integral, relative, as ``C · x^p / M²`` for a grid of M
#: samples and the size parameter x in the host: (C, p) per grid kind.  Fitted to this module's
#: tables against miepython's Q_sca (upper envelopes, measured C ≤ 0.105 and ≤ 0.47) for voids
#: (m = 1/1.557), pigments (m = 1.64), weak (m = 1.03) and absorbing (m = 1.16 − 0.19i) spheres,
#: 3 ≤ x ≤ 250: uniform in μ the forward peak's width in μ is ~x⁻² (error ∝ x⁴/M²), uniform in θ
#: its width in θ is ~x⁻¹ (error ∝ x²/M²).
GRID_ERROR_MODELS = {"uniform-cos": (0.12, 4), "uniform-angle": (0.6, 2)}
#: Below this ``q·d`` the closed form of S(q) loses digits to cancellation; a Taylor series is exact there.
_PY_SERIES_BELOW = 0.2


@dataclass(frozen=True)
class SpeciesScattering:
    """Bulk optical properties contributed by one particle species.

    Attributes
    ----------
    mu_s, mu_a
        (L,) scattering and absorption coefficients, 1/mm.
    phase
        (L, M) phase function on the caller's ``cos_theta``, 1/sr, ``2π∫p dμ = 1``
        (isotropic where ``mu_s`` is 0).
    number_density_per_um3
        Particles per µm³.
    """

    mu_s: np.ndarray
    mu_a: np.ndarray
    phase: np.ndarray
    number_density_per_um3: float


class PhaseGridTooCoarse(ParameterError):
    """The cos θ grid misses a species' Mie cross-section by more than :data:`PHASE_TABLE_TOLERANCE`.

    A :class:`ParameterError` naming ``medium.phase_samples``; ``relative_error`` is the
    largest miss found (the first species and wavelength that fails).
    """

    def __init__(self, value: object, allowed: str, relative_error: float):
        super().__init__("medium.phase_samples", value, allowed)
        self.relative_error = relative_error

    def __reduce__(self):  # picklable across processes despite the narrower constructor
        return type(self), (self.value, self.allowed, self.relative_error)


def grid_error_estimate(kind: str, n_samples: int, size_parameter: float) -> float:
    """Expected relative error of the trapezoidal integral of a Mie phase table (:data:`GRID_ERROR_MODELS`)."""
    coefficient, power = GRID_ERROR_MODELS[kind]
    return coefficient * size_parameter**power / n_samples**2


def largest_size_parameter(particles, wavelengths_nm: np.ndarray, host_index: np.ndarray) -> float:
    """The largest size parameter ``x = π d n_host / λ0`` that shapes the phase tables of ``particles``.

    For a fixed diameter it is that diameter's.  For a log-normal species it is
    the diameter three standard deviations above the median of its
    *area*-weighted distribution (a log-normal of median ``d_g σ_g^(2 ln σ_g)``,
    Hatch & Choate, J. Franklin Inst. 207, 369 (1929)), since large spheres
    scatter in proportion to their area.  0 without particles.
    """
    ratio = float(np.max(np.asarray(host_index, float) / np.asarray(wavelengths_nm, float)))
    largest = 0.0
    for species in particles:
        if species.diameter_nm is not None:
            diameter = float(species.diameter_nm)
        else:
            ln_sigma = math.log(species.geometric_sigma)
            diameter = species.median_diameter_nm * math.exp(2.0 * ln_sigma**2 + 3.0 * ln_sigma)
        largest = max(largest, math.pi * diameter * ratio)
    return largest


def _round_up(samples: float) -> int:
    """``samples`` rounded up to 100 k + 1 (grids with round spacings)."""
    return int(math.ceil((samples - 1) / 100.0)) * 100 + 1


def auto_phase_grid(particles, wavelengths_nm: np.ndarray, host_index: np.ndarray) -> tuple[str, int]:
    """The cos θ grid (kind, samples) of ``medium.phase_samples = "auto"``.

    With ``x`` from :func:`largest_size_parameter` and the error models of
    :data:`GRID_ERROR_MODELS`, at half of :data:`PHASE_TABLE_TOLERANCE`:

    * the default grid, uniform in μ with :data:`~precompute.optics.phase.DEFAULT_PHASE_SAMPLES`
      samples, where its error is below that (x ≤ 11.4: pigments, the paper's medium;
      results unchanged from the fixed default grid);
    * else a grid uniform in θ with ``M = 34.6 x`` samples (rounded up to 100 k + 1, at
      least the default): 8 701 for 20 µm air voids in cellulose at 390 nm (x = 251).

    :func:`precompute.optics.coefficients.medium_optics` checks the result against the Mie
    cross-section of every species at every wavelength and refines it where it falls short.
    """
    x = largest_size_parameter(particles, wavelengths_nm, host_index)
    target = PHASE_TABLE_TOLERANCE / 2.0
    if grid_error_estimate("uniform-cos", DEFAULT_PHASE_SAMPLES, x) <= target:
        return "uniform-cos", DEFAULT_PHASE_SAMPLES
    coefficient, power = GRID_ERROR_MODELS["uniform-angle"]
    needed = math.sqrt(coefficient * x**power / target)
    return "uniform-angle", min(MAX_AUTO_PHASE_SAMPLES, max(DEFAULT_PHASE_SAMPLES, _round_up(needed)))


def refined_phase_grid(n_samples: int, relative_error: float) -> int:
    """Samples of the grid uniform in θ that follows a grid of ``n_samples`` missing by ``relative_error``.

    The error falls as 1/M²: the count that brings it to half the tolerance,
    at least doubled, rounded up to 100 k + 1.
    """
    factor = max(2.0, math.sqrt(relative_error / (PHASE_TABLE_TOLERANCE / 2.0)))
    return _round_up(n_samples * factor)


def size_distribution(species: ParticleSpecies) -> tuple[np.ndarray, np.ndarray]:
    """Diameters (nm) and number weights (summing to 1) that represent a species' sizes.

    A log-normal number distribution (median ``d_g``, geometric standard
    deviation ``σ_g``) is sampled uniformly in ``z = ln(d/d_g) / ln σ_g`` with
    step :data:`LOGNORMAL_STEP` (the trapezoidal rule, spectrally accurate for
    a Gaussian), from ``z = −5`` to ``z = 5 + 6 ln σ_g``: the upper end also
    covers the ``d⁶``-weighted tail that dominates Rayleigh scattering.
    """
    if species.diameter_nm is not None:
        return np.array([float(species.diameter_nm)]), np.array([1.0])
    ln_sigma = math.log(species.geometric_sigma)
    z_max = 5.0 + 6.0 * ln_sigma
    count = int(math.ceil((5.0 + z_max) / LOGNORMAL_STEP)) + 1
    z = np.linspace(-5.0, z_max, count)
    weights = np.exp(-0.5 * z**2)
    return species.median_diameter_nm * np.exp(z * ln_sigma), weights / weights.sum()


def number_density(species: ParticleSpecies) -> float:
    """Particles per nm³ that fill the species' ``volume_fraction`` with its size distribution."""
    diameters, weights = size_distribution(species)
    return species.volume_fraction / float(np.sum(weights * np.pi * diameters**3 / 6.0))


def differential_scattering_cross_section(m: complex, x: float, wavenumber: float, cos_theta: np.ndarray) -> np.ndarray:
    """Unpolarised ``dC_sca/dΩ`` of one sphere (area units of ``1/wavenumber²`` per sr) at ``cos_theta``.

    ``(|S1|² + |S2|²) / 2k²`` with the amplitude functions summed from
    miepython's coefficients ``a_n, b_n`` over the angular functions ``π_n,
    τ_n`` (Bohren & Huffman 1983, eqs. 4.47 and 4.74); ``m`` is the relative
    index (``n − ik``), ``x`` the size parameter in the host, ``k`` the
    wavenumber in the host.  The sum runs over all angles at once, where
    miepython's own ``S1_S2`` loops over them in Python.
    """
    a, b = miepython.an_bn(m, x, 0)
    s1 = np.zeros(cos_theta.shape, complex)
    s2 = np.zeros(cos_theta.shape, complex)
    pi_previous, pi_n = np.zeros_like(cos_theta), np.ones_like(cos_theta)
    for n in range(1, len(a) + 1):
        tau_n = n * cos_theta * pi_n - (n + 1) * pi_previous
        weight = (2 * n + 1) / (n * (n + 1))
        s1 += weight * (a[n - 1] * pi_n + b[n - 1] * tau_n)
        s2 += weight * (a[n - 1] * tau_n + b[n - 1] * pi_n)
        pi_previous, pi_n = pi_n, ((2 * n + 1) * cos_theta * pi_n - (n + 1) * pi_previous) / n
    return (np.abs(s1) ** 2 + np.abs(s2) ** 2) / (2.0 * wavenumber**2)


def percus_yevick_structure_factor(q_times_d, volume_fraction: float) -> np.ndarray:
    """Hard-sphere structure factor ``S(q)`` in the Percus–Yevick approximation.

    ``S = 1 / (1 + 24 f G(x)/x)`` with ``x = q·d`` (``d`` the sphere diameter,
    ``q`` the scattering vector, 1/nm) and ``f`` the volume fraction (closed form
    of Kinning & Thomas, Macromolecules 17, 1712 (1984)).  ``S(0) =
    (1 − f)⁴ / (1 + 2f)²`` is the hard-sphere compressibility; ``S → 1`` for
    ``x → ∞``.
    """
    f = float(volume_fraction)
    if not 0.0 <= f < 1.0:
        raise ParameterError("volume_fraction", volume_fraction, "[0, 1)")
    x = np.abs(np.asarray(q_times_d, float))
    alpha = (1.0 + 2.0 * f) ** 2 / (1.0 - f) ** 4
    beta = -6.0 * f * (1.0 + f / 2.0) ** 2 / (1.0 - f) ** 4
    gamma = f * alpha / 2.0
    small = x < _PY_SERIES_BELOW
    x2 = np.where(small, x * x, 0.0)
    # ∫₀¹ t² j0(x t)(α + βt + γt³) dt, expanded to x⁴.
    series = (
        alpha * (1 / 3 - x2 / 30 + x2**2 / 840)
        + beta * (1 / 4 - x2 / 36 + x2**2 / 960)
        + gamma * (1 / 6 - x2 / 48 + x2**2 / 1200)
    )
    xs = np.where(small, 1.0, x)
    sin, cos = np.sin(xs), np.cos(xs)
    closed = (
        alpha / xs**2 * (sin - xs * cos)
        + beta / xs**3 * (2 * xs * sin + (2 - xs**2) * cos - 2)
        + gamma / xs**5 * (-(xs**4) * cos + 4 * ((3 * xs**2 - 6) * cos + (xs**3 - 6 * xs) * sin + 6))
    ) / xs
    return 1.0 / (1.0 + 24.0 * f * np.where(small, series, closed))


def species_scattering(
    species: ParticleSpecies,
    wavelengths_nm: np.ndarray,
    host_index: np.ndarray,
    cos_theta: np.ndarray,
    structure_volume_fraction: float | None = None,
) -> SpeciesScattering:
    """μs, μa and phase function of one species dispersed in a host of real index ``host_index``.

    Independent scattering: ``μs = N ⟨C_sca⟩`` and ``μa = N ⟨C_abs⟩`` with ``N``
    the number density, ``C = Q · π d²/4`` and ``⟨·⟩`` the number-weighted mean
    over sizes; the phase function is the normalised ``⟨dC_sca/dΩ⟩``.

    With ``structure_volume_fraction = f`` the differential cross-section of
    each diameter ``d`` is multiplied by the Percus–Yevick ``S(q d; f)``,
    ``q = 2k sin(θ/2)``, ``k = 2π n_host / λ0``, and ``μs = N ∫⟨dC/dΩ · S⟩ dΩ``;
    absorption is unchanged.

    ``cos_theta`` is any increasing grid over [−1, 1] (:mod:`precompute.optics.phase`).
    Raises :class:`PhaseGridTooCoarse` (a :class:`ParameterError` naming
    ``medium.phase_samples``) when the grid is too coarse for the particles'
    forward peak, rather than returning a phase table whose integral misses the
    Mie cross-section by more than :data:`PHASE_TABLE_TOLERANCE`.
    """
    n_particle = species.refractive_index.at(wavelengths_nm)
    diameters, weights = size_distribution(species)
    density_per_nm3 = number_density(species)
    areas = np.pi * diameters**2 / 4.0
    sin_half = np.sqrt(np.clip((1.0 - cos_theta) / 2.0, 0.0, 1.0))
    count = len(wavelengths_nm)
    mu_s = np.zeros(count)
    mu_a = np.zeros(count)
    phase = np.full((count, len(cos_theta)), 1.0 / (4.0 * np.pi))
    for index, (wavelength, n_host, n_p) in enumerate(zip(wavelengths_nm, host_index, n_particle)):
        m = complex(n_p.real, -n_p.imag)
        c_sca = 0.0
        c_abs = 0.0
        differential = np.zeros(len(cos_theta))  # ⟨dC_sca/dΩ⟩, nm²/sr
        corrected = np.zeros(len(cos_theta)) if structure_volume_fraction is not None else None
        wavenumber = 2.0 * np.pi * n_host / wavelength  # in the host, 1/nm
        for diameter, weight, area in zip(diameters, weights, areas):
            qext, qsca, _, _ = miepython.efficiencies(m, diameter, wavelength, n_env=n_host)
            c_sca += weight * qsca * area
            if n_p.imag > 0:  # for a real index Q_ext − Q_sca is rounding noise, which may be negative
                c_abs += weight * (qext - qsca) * area
            x = wavenumber * diameter / 2.0
            term = weight * differential_scattering_cross_section(m / n_host, x, wavenumber, cos_theta)
            differential += term
            if corrected is not None:
                q_times_d = 2.0 * wavenumber * sin_half * diameter
                corrected += term * percus_yevick_structure_factor(q_times_d, structure_volume_fraction)
        mu_a[index] = density_per_nm3 * c_abs * 1e6  # 1/nm → 1/mm
        if c_sca <= 0.0:
            continue  # index-matched particles: no scattering, isotropic placeholder phase
        tabulated = float(phase_integral(cos_theta, differential))
        error = abs(tabulated / c_sca - 1.0)
        if error > PHASE_TABLE_TOLERANCE:
            # Trapezoid error falls as 1/M²: suggest a grid with margin.
            needed = int(math.ceil(len(cos_theta) * math.sqrt(error / PHASE_TABLE_TOLERANCE) * 1.5))
            raise PhaseGridTooCoarse(
                len(cos_theta),
                f"≥ {needed} (or \"auto\"): the phase function of particles[{species.name}] at {wavelength:g} nm "
                f"is too forward-peaked for this cos θ grid (its integral misses the Mie cross-section by "
                f"{error:.1e})",
                error,
            )
        if corrected is None:
            mu_s[index] = density_per_nm3 * c_sca * 1e6
            phase[index] = normalize_phase(cos_theta, differential)
        else:
            mu_s[index] = density_per_nm3 * c_sca * float(phase_integral(cos_theta, corrected)) / tabulated * 1e6
            phase[index] = normalize_phase(cos_theta, corrected)
    return SpeciesScattering(mu_s=mu_s, mu_a=mu_a, phase=phase, number_density_per_um3=density_per_nm3 * 1e9)
