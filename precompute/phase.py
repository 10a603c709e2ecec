"""Tabulated phase functions: normalisation, asymmetry, sampling tables, Henyey–Greenstein.

A phase function ``p(cos θ)`` here is in 1/sr and normalised over the sphere:
``2π ∫_{-1}^{1} p(μ) dμ = 1``.
"""

from __future__ import annotations

import numpy as np

from .errors import ParameterError

#: Default cos θ grid of the phase tables: fine enough for the sampling table's
#: linear interpolation to reproduce g to better than 1e-4 for Mie particles of x ≲ 5.
DEFAULT_COS_THETA = np.linspace(-1.0, 1.0, 2001)
#: Entries of the inverse-CDF sampling table.
DEFAULT_ICDF_SIZE = 4096


def _trapezoid(y: np.ndarray, x: np.ndarray) -> np.ndarray:
    return np.sum(0.5 * (y[..., 1:] + y[..., :-1]) * np.diff(x), axis=-1)


def normalize_phase(cos_theta: np.ndarray, phase: np.ndarray) -> np.ndarray:
    """Scale ``phase`` (…, M) so that ``2π ∫ p dμ = 1`` (trapezoidal rule on ``cos_theta``)."""
    total = 2.0 * np.pi * _trapezoid(phase, cos_theta)
    if np.any(total <= 0) or not np.all(np.isfinite(total)):
        raise ParameterError("phase", "non-positive or non-finite integral", "a positive, finite phase function")
    return phase / total[..., None]


def phase_integral(cos_theta: np.ndarray, phase: np.ndarray) -> np.ndarray:
    """``2π ∫ p dμ`` over the sphere; 1 for a normalised phase function."""
    return 2.0 * np.pi * _trapezoid(phase, cos_theta)


def asymmetry_parameter(cos_theta: np.ndarray, phase: np.ndarray) -> np.ndarray:
    """Mean cosine ``g = 2π ∫ μ p(μ) dμ`` of a normalised phase function."""
    return 2.0 * np.pi * _trapezoid(cos_theta * phase, cos_theta)


def henyey_greenstein_phase(cos_theta, g) -> np.ndarray:
    """Henyey–Greenstein phase function (1/sr): ``(1 − g²) / (4π (1 + g² − 2gμ)^{3/2})``."""
    cos_theta = np.asarray(cos_theta, float)
    g = np.asarray(g, float)
    if np.any(np.abs(g) >= 1.0):
        raise ParameterError("g", g, "(-1, 1)")
    g_ = g[..., None] if g.ndim else g
    return (1.0 - g_**2) / (4.0 * np.pi * (1.0 + g_**2 - 2.0 * g_ * cos_theta) ** 1.5)


def phase_inverse_cdf(cos_theta: np.ndarray, phase: np.ndarray, n_samples: int = DEFAULT_ICDF_SIZE) -> np.ndarray:
    """Inverse cumulative distribution of μ = cos θ for each phase function (…, M) → (…, n_samples).

    Entry ``k`` is the μ at cumulative probability ``u_k = k / (n_samples − 1)``;
    sampling interpolates linearly in ``u``.  The CDF is the trapezoidal integral
    of ``p(μ)``, so the table reproduces the tabulated phase function to the
    resolution of ``cos_theta`` and of ``u``.
    """
    if n_samples < 2:
        raise ParameterError("n_samples", n_samples, "≥ 2")
    phase = np.asarray(phase, float)
    flat = phase.reshape(-1, phase.shape[-1])
    u = np.linspace(0.0, 1.0, n_samples)
    out = np.empty((flat.shape[0], n_samples))
    for row, p in enumerate(flat):
        cdf = np.concatenate([[0.0], np.cumsum(0.5 * (p[1:] + p[:-1]) * np.diff(cos_theta))])
        cdf /= cdf[-1]
        # Flat stretches of the CDF (p = 0) would make the inverse ambiguous: keep the first μ.
        keep = np.concatenate([[True], np.diff(cdf) > 0])
        out[row] = np.interp(u, cdf[keep], cos_theta[keep])
    return out.reshape(phase.shape[:-1] + (n_samples,))


def sample_inverse_cdf(icdf: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Draw μ from one inverse-CDF table for uniform numbers ``u`` in [0, 1)."""
    position = np.asarray(u) * (len(icdf) - 1)
    k = np.minimum(position.astype(int), len(icdf) - 2)
    frac = position - k
    return icdf[k] * (1.0 - frac) + icdf[k + 1] * frac
