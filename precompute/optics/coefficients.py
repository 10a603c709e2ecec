"""Optical properties of a yarn medium per wavelength: what the transport kernel consumes.

``medium_optics(params)`` turns the physical description
(:class:`precompute.optics.medium.MediumParameters`) into μs, μa, μt (1/mm), albedo,
asymmetry g and a tabulated phase function with its sampling table (paper §3.3:
"scattering cross-sections and phase functions were calculated from the Mie
theory").  Species combine by adding their coefficients, and their phase
functions are weighted by their scattering coefficients:
``p = Σ μs_i p_i / Σ μs_i``.  Absorption adds the host's own, the particles'
(Mie ``Q_abs``) and the dye's (:mod:`precompute.optics.dye`).  A medium with
fibres (:class:`precompute.optics.medium.Fibres`) adds them as one more species
(:mod:`precompute.optics.fibre`), and its dye is absorbed inside them, not by
the yarn's whole volume.

The cos θ grid of the phase tables: with ``medium.phase_samples = "auto"`` (the
default) it is :func:`precompute.optics.mie.auto_phase_grid` — the default grid
uniform in μ for small particles, a grid uniform in θ with ~35 samples per unit
of the largest size parameter for large ones (air voids, fibre-scale
structure) — checked against the Mie cross-section of every species at every
wavelength and refined (:func:`precompute.optics.mie.refined_phase_grid`) until it is
within :data:`precompute.optics.mie.PHASE_TABLE_TOLERANCE`.  An integer is a grid
uniform in μ of that many samples, taken as given and refused when too coarse.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from precompute.optics.dye import dye_absorption_coefficient
from precompute.optics.fibre import fibre_absorption_per_mm, fibre_scattering, proxy_diameter_nm
from precompute.optics.fibre_orientation import RANDOM_ORIENTATION, OrientedFibres
from precompute.optics.medium import AUTO_PHASE_SAMPLES, MediumParameters, ParticleSpecies, RefractiveIndex, load_preset
from precompute.optics.mie import (
    MAX_AUTO_PHASE_SAMPLES,
    PhaseGridTooCoarse,
    auto_phase_grid,
    refined_phase_grid,
    species_scattering,
)
from precompute.optics.phase import DEFAULT_ICDF_SIZE, asymmetry_parameter, phase_grid, phase_inverse_cdf

__all__ = ["MediumOptics", "medium_optics", "load_preset", "planned_phase_grid"]


@dataclass(frozen=True)
class MediumOptics:
    """Per-wavelength optics of a yarn medium.

    Attributes
    ----------
    wavelengths_nm : (L,) vacuum wavelengths, nm, strictly increasing
    mu_s, mu_a, mu_t : (L,) scattering, absorption, extinction coefficients, 1/mm
    albedo : (L,) single-scattering albedo μs/μt (0 where μt = 0)
    g : (L,) asymmetry parameter ⟨cos θ⟩ of the phase table
    host_index : (L,) real refractive index of the host
    cos_theta : (M,) increasing grid of the phase table over [−1, 1], of kind ``phase_grid``
    phase : (L, M) phase function, 1/sr, 2π∫p dμ = 1
    phase_icdf : (L, K) μ at cumulative probability k/(K−1); sample by linear interpolation in u
    dependent_scattering : "none" or "percus-yevick", the model the coefficients were computed with
    oriented_fibres : with ``fibres.orientation = "yarn_axis"``, the medium the transport traces instead
        (:class:`precompute.optics.fibre_orientation.OrientedFibres`); μs, μa and the phase table
        are then the randomly oriented fibres' (the Mie proxy), for reports and plots
    phase_grid : the kind of ``cos_theta`` (:data:`precompute.optics.phase.PHASE_GRID_KINDS`):
        "uniform-cos" (uniform in μ) or "uniform-angle" (uniform in θ)
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
    dependent_scattering: str = "none"
    phase_grid: str = "uniform-cos"
    oriented_fibres: OrientedFibres | None = None

    @property
    def phase_samples(self) -> int:
        """M, the number of cos θ samples of the phase table (the chosen count when ``"auto"``)."""
        return len(self.cos_theta)

    @property
    def unscattered_extinction_per_mm(self) -> np.ndarray:
        """(L,) extinction of the light that crosses the yarn unscattered, 1/mm (the ``unscattered.exr``
        table's, :mod:`precompute.optics.ballistic`): μt; for fibres along the yarn axis, theirs across it
        (the unscattered light of a cloth crosses its yarns across them)."""
        if self.oriented_fibres is None:
            return self.mu_t
        return np.full(len(self.wavelengths_nm), self.oriented_fibres.across_axis_extinction_per_mm)

    @property
    def boundary_index(self) -> float:
        """One real index for the yarn boundary: the host index averaged over the wavelengths.

        Refraction is taken as wavelength-independent so that one path serves
        every wavelength; a host's dispersion over the visible is ~1 %.
        """
        return float(np.mean(self.host_index))


def planned_phase_grid(params: MediumParameters) -> tuple[str, int]:
    """The cos θ grid (kind, samples) ``medium_optics`` starts from, without any Mie computation.

    ``params.phase_samples`` itself when an integer (uniform in μ), else
    :func:`precompute.optics.mie.auto_phase_grid`.  ``medium_optics`` refines an automatic
    grid that falls short of the tolerance; the result is deterministic given the
    parameters and the code.
    """
    if params.phase_samples != AUTO_PHASE_SAMPLES:
        return "uniform-cos", int(params.phase_samples)
    wavelengths = params.wavelengths.values
    return auto_phase_grid(_sized_scatterers(params), wavelengths, params.host.refractive_index.at(wavelengths).real)


def _sized_scatterers(params: MediumParameters) -> tuple[ParticleSpecies, ...]:
    """The particles, and the fibres' proxy sphere as one more, for choosing the cos θ grid (which
    reads its size alone: the index and the fraction given it are placeholders)."""
    if params.fibres is None:
        return params.particles
    proxy = ParticleSpecies("fibres", RefractiveIndex(n=1.5), 0.5, diameter_nm=proxy_diameter_nm(params.fibres))
    return (*params.particles, proxy)


def medium_optics(params: MediumParameters, *, icdf_size: int = DEFAULT_ICDF_SIZE) -> MediumOptics:
    """Optical properties of ``params`` on its wavelength grid (see the module docstring).

    ``icdf_size`` is the number K of entries of each inverse-CDF sampling table.
    Raises :class:`precompute.optics.mie.PhaseGridTooCoarse` when an explicit
    ``phase_samples`` is too coarse for the particles.
    """
    wavelengths = params.wavelengths.values
    host_index = params.host.refractive_index.at(wavelengths).real
    kind, samples = planned_phase_grid(params)
    while True:
        cos_theta = phase_grid(kind, samples)
        try:
            mu_s, mu_a, weighted_phase = _scattering(params, wavelengths, host_index, cos_theta)
            break
        except PhaseGridTooCoarse as error:
            if params.phase_samples != AUTO_PHASE_SAMPLES or samples >= MAX_AUTO_PHASE_SAMPLES:
                raise
            kind, samples = "uniform-angle", min(MAX_AUTO_PHASE_SAMPLES,
                                                 refined_phase_grid(samples, error.relative_error))
    if params.dye is not None and params.fibres is None:
        mu_a += dye_absorption_coefficient(params.dye, wavelengths)
    scattering = mu_s > 0
    # Where nothing scatters the phase function is never used; an isotropic one keeps the tables valid.
    phase = np.full_like(weighted_phase, 1.0 / (4.0 * np.pi))
    phase[scattering] = weighted_phase[scattering] / mu_s[scattering, None]
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
        dependent_scattering=params.dependent_scattering,
        phase_grid=kind,
        oriented_fibres=_oriented_fibres(params, wavelengths, host_index),
    )


def _oriented_fibres(params: MediumParameters, wavelengths: np.ndarray, host_index: np.ndarray):
    """The medium of fibres along the yarn axis that ``params`` describes, or None (random fibres, none)."""
    fibres = params.fibres
    if fibres is None or fibres.orientation == RANDOM_ORIENTATION:
        return None
    return OrientedFibres(
        extinction_per_mm=4.0 * fibres.volume_fraction / (math.pi * fibres.diameter_um * 1e-3),
        relative_index=float(np.mean(fibres.refractive_index.at(wavelengths).real) / np.mean(host_index)),
        radius_mm=0.5 * fibres.diameter_um * 1e-3,
        helix_angle_deg=float(params.yarn.twist_angle_deg),
        spread_deg=float(fibres.orientation_spread_deg),
        roughness_deg=float(fibres.roughness_deg),
        absorption_per_mm=fibre_absorption_per_mm(fibres, params.dye, wavelengths),
    )


def _scattering(params: MediumParameters, wavelengths: np.ndarray, host_index: np.ndarray, cos_theta: np.ndarray):
    """μs (L,), μa of the host and the particles (L,), and Σ μs_i p_i (L, M) on ``cos_theta``."""
    structure_fraction = params.total_volume_fraction if params.dependent_scattering == "percus-yevick" else None
    mu_s = np.zeros(len(wavelengths))
    mu_a = np.full(len(wavelengths), float(params.host.absorption_per_mm))
    weighted_phase = np.zeros((len(wavelengths), len(cos_theta)))
    for species in params.particles:
        contribution = species_scattering(species, wavelengths, host_index, cos_theta, structure_fraction)
        mu_s += contribution.mu_s
        mu_a += contribution.mu_a
        weighted_phase += contribution.mu_s[:, None] * contribution.phase
    if params.fibres is not None:
        contribution = fibre_scattering(params.fibres, params.dye, wavelengths, host_index, cos_theta)
        mu_s += contribution.mu_s
        mu_a += contribution.mu_a
        weighted_phase += contribution.mu_s[:, None] * contribution.phase
    return mu_s, mu_a, weighted_phase
