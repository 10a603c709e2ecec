"""The arrays a transport kernel needs, from medium optics or from a Henyey–Greenstein medium."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError
from ..phase import DEFAULT_COS_THETA, DEFAULT_ICDF_SIZE, henyey_greenstein_phase


@dataclass(frozen=True)
class TransportMedium:
    """Per-wavelength μs, μa (1/mm), phase table on a uniform cos θ grid and its inverse CDF."""

    wavelengths_nm: np.ndarray
    mu_s: np.ndarray
    mu_a: np.ndarray
    phase: np.ndarray
    phase_icdf: np.ndarray

    def __post_init__(self):
        for name in ("mu_s", "mu_a"):
            value = np.asarray(getattr(self, name), float)
            if value.shape != self.wavelengths_nm.shape or not np.all(np.isfinite(value)) or np.any(value < 0):
                raise ParameterError(name, value, f"{len(self.wavelengths_nm)} finite values ≥ 0")
        if self.phase.shape[0] != len(self.wavelengths_nm) or self.phase_icdf.shape[0] != len(self.wavelengths_nm):
            raise ParameterError("phase", self.phase.shape, "one table per wavelength")


def medium_from_optics(optics) -> TransportMedium:
    """Transport arrays from :class:`precompute.optics.MediumOptics` (its cos θ grid must be uniform)."""
    grid = np.asarray(optics.cos_theta)
    uniform = np.linspace(-1.0, 1.0, len(grid))
    if not np.allclose(grid, uniform, atol=1e-12):
        phase = np.array([np.interp(uniform, grid, row) for row in optics.phase])
    else:
        phase = np.asarray(optics.phase, float)
    return TransportMedium(
        wavelengths_nm=np.asarray(optics.wavelengths_nm, float),
        mu_s=np.ascontiguousarray(optics.mu_s, float),
        mu_a=np.ascontiguousarray(optics.mu_a, float),
        phase=np.ascontiguousarray(phase),
        phase_icdf=np.ascontiguousarray(optics.phase_icdf, float),
    )


def henyey_greenstein_icdf(g: float, n_samples: int = DEFAULT_ICDF_SIZE) -> np.ndarray:
    """Exact inverse CDF of the Henyey–Greenstein μ at ``u_k = k/(n−1)``."""
    u = np.linspace(0.0, 1.0, n_samples)
    if abs(g) < 1e-6:
        return 2.0 * u - 1.0
    mu = (1.0 + g * g - ((1.0 - g * g) / (1.0 - g + 2.0 * g * u)) ** 2) / (2.0 * g)
    return np.clip(mu, -1.0, 1.0)


def henyey_greenstein_medium(albedo, g, mu_t: float = 1.0, wavelengths_nm=None) -> TransportMedium:
    """A medium with Henyey–Greenstein scattering, for comparison with exact solutions.

    ``albedo`` and ``g`` may be scalars or per-wavelength arrays; ``mu_t`` in 1/mm.
    """
    albedo = np.atleast_1d(np.asarray(albedo, float))
    g = np.broadcast_to(np.atleast_1d(np.asarray(g, float)), albedo.shape)
    if np.any((albedo < 0) | (albedo > 1)) or not np.all(np.isfinite(albedo)):
        raise ParameterError("albedo", albedo, "[0, 1]")
    if np.any(np.abs(g) >= 1) or not np.all(np.isfinite(g)):
        raise ParameterError("g", g, "(-1, 1)")
    if not (math.isfinite(mu_t) and mu_t > 0):
        raise ParameterError("mu_t", mu_t, "> 0")
    wavelengths = np.arange(len(albedo), dtype=float) if wavelengths_nm is None else np.asarray(wavelengths_nm, float)
    phase = np.array([henyey_greenstein_phase(DEFAULT_COS_THETA, gi) for gi in g])
    return TransportMedium(
        wavelengths_nm=wavelengths,
        mu_s=albedo * mu_t,
        mu_a=(1.0 - albedo) * mu_t,
        phase=phase,
        phase_icdf=np.array([henyey_greenstein_icdf(gi) for gi in g]),
    )
