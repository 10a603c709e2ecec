"""Numba kernels of single interactions: Fresnel boundaries and phase-function scattering.

Phase functions come in two kinds (``PHASE_TABLE``, ``PHASE_HG``).  Both are
sampled *exactly* and evaluated *exactly* — the spectral estimator divides by
the density a hero wavelength sampled with, so the density evaluated for every
wavelength must be the one its sampler draws from (docs/transport.md).

* Table: ``p(μ)`` given on a uniform grid of μ over [−1, 1] and linear between
  grid points, normalised so that ``2π ∫ p dμ = 1`` for that piecewise-linear
  function (the trapezoidal rule of :mod:`precompute.phase`).  Sampling picks a
  segment from its cumulative table (with a guide table, O(1) expected) and
  inverts the linear density inside the segment.
* Henyey–Greenstein with asymmetry g: analytic inversion and evaluation.
"""

from __future__ import annotations

import math

import numba

from ._rng import uniform

PHASE_TABLE = 0
PHASE_HG = 1
_INV_4PI = 1.0 / (4.0 * math.pi)


@numba.njit(cache=True, error_model="numpy", inline="always")
def fresnel_reflectance(cos_i, eta):
    """Unpolarised Fresnel reflectance at incidence cosine ``cos_i`` (> 0), relative index
    ``eta = n_incident / n_transmitted``; 1 under total internal reflection."""
    sin_t2 = eta * eta * (1.0 - cos_i * cos_i)
    if sin_t2 >= 1.0:
        return 1.0
    cos_t = math.sqrt(1.0 - sin_t2)
    rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    return 0.5 * (rs * rs + rp * rp)


@numba.njit(cache=True, error_model="numpy", inline="always")
def refract(d, normal, cos_i, eta):
    """Refract unit ``d`` in place through an interface whose unit ``normal`` points to the side
    ``d`` goes to (``cos_i = d · normal > 0``), ``eta = n_from / n_to``; no TIR (checked by caller)."""
    cos_t = math.sqrt(max(0.0, 1.0 - eta * eta * (1.0 - cos_i * cos_i)))
    k = cos_t - eta * cos_i
    x = eta * d[0] + k * normal[0]
    y = eta * d[1] + k * normal[1]
    z = eta * d[2] + k * normal[2]
    norm = 1.0 / math.sqrt(x * x + y * y + z * z)
    d[0] = x * norm
    d[1] = y * norm
    d[2] = z * norm


@numba.njit(cache=True, error_model="numpy", inline="always")
def reflect(d, normal, cos_i):
    """Mirror unit ``d`` in place about the plane of unit ``normal`` (``cos_i = d · normal``)."""
    d[0] -= 2.0 * cos_i * normal[0]
    d[1] -= 2.0 * cos_i * normal[1]
    d[2] -= 2.0 * cos_i * normal[2]


@numba.njit(cache=True, error_model="numpy", inline="always")
def sample_hg(g, u):
    """cos θ drawn from Henyey–Greenstein ``g`` by inverting its CDF at ``u``."""
    if abs(g) < 1e-6:
        return 2.0 * u - 1.0
    s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u)
    mu = (1.0 + g * g - s * s) / (2.0 * g)
    return min(1.0, max(-1.0, mu))


@numba.njit(cache=True, error_model="numpy", inline="always")
def hg_value(g, mu):
    """Henyey–Greenstein phase function at cos θ = ``mu``, 1/sr."""
    x = 1.0 + g * g - 2.0 * g * mu
    return (1.0 - g * g) * _INV_4PI / (x * math.sqrt(x))


@numba.njit(cache=True, error_model="numpy", inline="always")
def sample_table(table, cdf, guide, k, u):
    """cos θ drawn exactly from the piecewise-linear phase ``table[:, k]`` on the uniform μ grid.

    ``table`` (M, L) is laid out by μ so that evaluating every wavelength at one μ reads
    contiguous memory; ``cdf[k]``: cumulative probability at the M grid points (0 … 1);
    ``guide[k, b]``: the last segment starting at or below cumulative probability b / G.
    """
    m = table.shape[0]
    n_guide = guide.shape[1]
    j = guide[k, min(int(u * n_guide), n_guide - 1)]
    while j < m - 2 and cdf[k, j + 1] <= u:
        j += 1
    mass = cdf[k, j + 1] - cdf[k, j]
    v = (u - cdf[k, j]) / mass if mass > 0.0 else 0.5
    p0 = table[j, k]
    p1 = table[j + 1, k]
    # inverse of the linear density's CDF on the segment, in the form stable for p1 ≈ p0
    c = v * (p0 + p1)
    denom = p0 + math.sqrt(max(0.0, p0 * p0 + (p1 - p0) * c))
    t = c / denom if denom > 0.0 else v
    return min(1.0, max(-1.0, -1.0 + (j + min(1.0, t)) * (2.0 / (m - 1))))


@numba.njit(cache=True, error_model="numpy", inline="always")
def turn(d, mu, state):
    """Turn unit ``d`` in place by polar cosine ``mu`` and a uniform azimuth.

    The azimuth's (cos φ, sin φ) come from a point drawn uniformly in the unit disk by
    rejection, which avoids two trigonometric calls per scattering.
    """
    while True:
        a = 2.0 * uniform(state) - 1.0
        b = 2.0 * uniform(state) - 1.0
        r2 = a * a + b * b
        if 0.0 < r2 <= 1.0:
            break
    inv = 1.0 / math.sqrt(r2)
    cp = a * inv
    sp = b * inv
    sin_t = math.sqrt(max(0.0, 1.0 - mu * mu))
    if abs(d[2]) > 0.99999:
        x = sin_t * cp
        y = sin_t * sp
        z = mu if d[2] > 0.0 else -mu
    else:
        tmp = math.sqrt(1.0 - d[2] * d[2])
        x = sin_t * (d[0] * d[2] * cp - d[1] * sp) / tmp + d[0] * mu
        y = sin_t * (d[1] * d[2] * cp + d[0] * sp) / tmp + d[1] * mu
        z = -sin_t * cp * tmp + d[2] * mu
    norm = 1.0 / math.sqrt(x * x + y * y + z * z)
    d[0] = x * norm
    d[1] = y * norm
    d[2] = z * norm
