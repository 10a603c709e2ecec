"""Numba kernels of single interactions: Fresnel boundaries and phase-function scattering.

Phase functions come in two kinds (``PHASE_TABLE``, ``PHASE_HG``).  Both are
sampled *exactly* and evaluated *exactly* — the spectral estimator divides by
the density a hero wavelength sampled with, so the density evaluated for every
wavelength must be the one its sampler draws from (docs/transport.md).

* Table: ``p(μ)`` given on a uniform grid of μ over [−1, 1] and linear between
  grid points, normalised so that ``2π ∫ p dμ = 1`` for that piecewise-linear
  function (the trapezoidal rule of :mod:`precompute.optics.phase`).  Sampling picks a
  segment by Walker's alias method (:func:`alias_tables`: one draw and one pair
  of loads, no search) and a point inside it from the segment's linear density.
* Henyey–Greenstein with asymmetry g: analytic inversion and evaluation.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from precompute.transport._rng import uniform

PHASE_TABLE = 0
PHASE_HG = 1
#: Not a phase function of cos Θ: a medium of oriented fibres, traced by :mod:`._fibres`.
PHASE_FIBRES = 2
_INV_4PI = 1.0 / (4.0 * math.pi)


@numba.njit(cache=True, error_model="numpy", inline="always")
def fresnel_reflectance(cos_i, eta):
    """Unpolarised Fresnel reflectance at incidence cosine ``cos_i`` (> 0), relative index
    ``eta = n_incident / n_transmitted``; 1 under total internal reflection."""
    if eta == 1.0:  # a matched boundary (the slab at n = 1)
        return 0.0
    sin_t2 = eta * eta * (1.0 - cos_i * cos_i)
    if sin_t2 >= 1.0:
        return 1.0
    cos_t = math.sqrt(1.0 - sin_t2)
    # rs = s_minus / s_plus, rp = p_minus / p_plus, over one division
    s_minus = eta * cos_i - cos_t
    s_plus = eta * cos_i + cos_t
    p_minus = cos_i - eta * cos_t
    p_plus = cos_i + eta * cos_t
    s_minus *= p_plus
    p_minus *= s_plus
    return 0.5 * (s_minus * s_minus + p_minus * p_minus) / (s_plus * s_plus * p_plus * p_plus)


@numba.njit(cache=True, error_model="numpy", inline="always")
def refract(dx, dy, dz, nx, ny, nz, cos_i, eta):
    """Unit direction (dx, dy, dz) refracted through an interface whose unit normal (nx, ny, nz) points
    to the side it goes to (``cos_i`` = d · n > 0), ``eta = n_from / n_to``; no TIR (checked by the
    caller).  Returned as a tuple, like every direction of the path core."""
    if eta == 1.0:
        return dx, dy, dz
    cos_t = math.sqrt(max(0.0, 1.0 - eta * eta * (1.0 - cos_i * cos_i)))
    k = cos_t - eta * cos_i
    x = eta * dx + k * nx
    y = eta * dy + k * ny
    z = eta * dz + k * nz
    norm = 1.0 / math.sqrt(x * x + y * y + z * z)
    return x * norm, y * norm, z * norm


@numba.njit(cache=True, error_model="numpy", inline="always")
def reflect(dx, dy, dz, nx, ny, nz, cos_i):
    """Unit direction (dx, dy, dz) mirrored about the plane of unit normal (nx, ny, nz) (``cos_i`` = d · n)."""
    twice = 2.0 * cos_i
    return dx - twice * nx, dy - twice * ny, dz - twice * nz


@numba.njit(cache=True, error_model="numpy", inline="always")
def sample_hg(g, u):
    """cos θ drawn from Henyey–Greenstein ``g`` by inverting its CDF at ``u``."""
    if abs(g) < 1e-6:
        return 2.0 * u - 1.0
    s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u)
    # times 0.5 / g rather than over 2g: the reciprocal is the same at every collision of a path
    mu = (1.0 + g * g - s * s) * (0.5 / g)
    return min(1.0, max(-1.0, mu))


@numba.njit(cache=True, error_model="numpy", inline="always")
def hg_value(g, mu):
    """Henyey–Greenstein phase function at cos θ = ``mu``, 1/sr."""
    x = 1.0 + g * g - 2.0 * g * mu
    return (1.0 - g * g) * _INV_4PI / (x * math.sqrt(x))


@numba.njit(cache=True, error_model="numpy")
def hg_phase_max(hg_g):
    """The largest value, over directions and wavelengths, of the Henyey–Greenstein phase functions of
    asymmetries ``hg_g`` (L,), 1/sr: each peaks in the direction its ``g`` favours."""
    peak = 0.0
    for g in hg_g:
        peak = max(peak, hg_value(g, 1.0 if g >= 0.0 else -1.0))
    return peak


@numba.njit(cache=True, error_model="numpy", inline="always")
def sample_table(table, alias_threshold, alias, k, state):
    """cos θ drawn exactly from the piecewise-linear phase ``table[:, k]`` on the uniform μ grid:
    ``(mu, segment, along)``, μ at ``along`` ∈ [0, 1) of the way through grid segment ``segment``.

    ``table`` (M, L) is laid out by μ so that evaluating every wavelength at one μ reads
    contiguous memory; ``alias_threshold[k]``, ``alias[k]`` (M − 1,): wavelength k's alias tables of
    its segments' probabilities (:func:`alias_tables`).  Within segment j, at t ∈ [0, 1) along it,
    the density ∝ (1 − t) p_j + t p_{j+1} is the mixture of the triangular densities 2(1 − t) and 2t
    with weights p_j and p_{j+1}: t is the smaller or the larger of two uniform numbers.  No division,
    no square root, no dependent search: only the alias pair's and the two table values' loads.
    """
    segments = alias.shape[1]
    x = uniform(state) * segments
    i = min(int(x), segments - 1)
    # x − i is uniform on [0, 1) and independent of i; the alias is loaded whether it is taken or not,
    # so that the choice is a select rather than a branch that is mispredicted half the time
    other = alias[k, i]
    j = i if x - i < alias_threshold[k, i] else other
    p0 = table[j, k]
    p1 = table[j + 1, k]
    a = uniform(state)
    b = uniform(state)
    t = max(a, b) if uniform(state) * (p0 + p1) < p1 else min(a, b)
    return min(1.0, max(-1.0, -1.0 + (j + t) * (2.0 / segments))), j, t


@numba.njit(cache=True, error_model="numpy")
def alias_tables(probabilities):
    """Walker's alias tables of each row of ``probabilities`` (L, S), rows summing to 1, built by
    Vose's method (M. D. Vose, "A linear algorithm for generating random numbers with a given
    distribution", IEEE Trans. Softw. Eng. 17(9), 1991): (``threshold`` (L, S), ``alias`` (L, S)
    int32) such that drawing i uniformly from 0 … S − 1, keeping it with probability
    ``threshold[i]`` and else taking ``alias[i]`` draws j with probability ``probabilities[j]``.
    A segment of zero probability is never drawn: it is never an alias, and its threshold is 0.
    """
    rows, s = probabilities.shape
    threshold = np.ones((rows, s))
    alias = np.empty((rows, s), dtype=np.int32)
    scaled = np.empty(s)
    small = np.empty(s, dtype=np.int64)
    large = np.empty(s, dtype=np.int64)
    for r in range(rows):
        n_small = 0
        n_large = 0
        heaviest = 0
        for i in range(s):
            scaled[i] = probabilities[r, i] * s
            alias[r, i] = i
            if probabilities[r, i] > probabilities[r, heaviest]:
                heaviest = i
            if scaled[i] < 1.0:
                small[n_small] = i
                n_small += 1
            else:
                large[n_large] = i
                n_large += 1
        while n_small > 0 and n_large > 0:
            n_small -= 1
            light = small[n_small]
            heavy = large[n_large - 1]
            threshold[r, light] = scaled[light]
            alias[r, light] = heavy
            # in this order the round-off stays at the level of one addition
            scaled[heavy] = (scaled[heavy] + scaled[light]) - 1.0
            if scaled[heavy] < 1.0:
                n_large -= 1
                small[n_small] = heavy
                n_small += 1
        # what is left is within round-off of 1 (threshold 1), except a segment of zero probability
        # left over by that round-off, which must still never be drawn
        for i in range(n_small):
            if probabilities[r, small[i]] == 0.0:
                threshold[r, small[i]] = 0.0
                alias[r, small[i]] = heaviest
    return threshold, alias


@numba.njit(cache=True, error_model="numpy", inline="always")
def turn(dx, dy, dz, mu, state):
    """Unit direction (dx, dy, dz) turned by polar cosine ``mu`` and a uniform azimuth φ.

    For a point (a, b) drawn uniformly in the unit disk by rejection, the angle of (a, b) is uniform and
    so is twice it: (cos φ, sin φ) = (a² − b², 2ab) / r², r² = a² + b².  With sin θ = √(1 − μ²) and
    ρ = √(1 − d_z²), the rotation needs sin θ·ρ and sin θ / ρ, both from √((1 − μ²)(1 − d_z²)):
    one square root and one division a collision, no trigonometric call.  The rotation keeps |d| = 1 to
    round-off (its error walks randomly, ~10⁻¹³ after 10⁶ collisions), so the direction is not
    renormalised (docs/transport.md, Where a collision's time goes).
    """
    while True:
        a = 2.0 * uniform(state) - 1.0
        b = 2.0 * uniform(state) - 1.0
        r2 = a * a + b * b
        if 0.0 < r2 <= 1.0:
            break
    cos_2 = a * a - b * b  # r² cos φ
    sin_2 = 2.0 * a * b  # r² sin φ
    sin_t2 = max(0.0, 1.0 - mu * mu)
    if abs(dz) > 0.99999:
        scale = math.sqrt(sin_t2) / r2
        return scale * cos_2, scale * sin_2, (mu if dz > 0.0 else -mu)
    rho2 = 1.0 - dz * dz
    # the reciprocal apart, so that the division and the square root run side by side
    inverse = 1.0 / (rho2 * r2)
    scale = math.sqrt(sin_t2 * rho2) * inverse  # sin θ / (ρ r²)
    return (scale * (dx * dz * cos_2 - dy * sin_2) + dx * mu,
            scale * (dy * dz * cos_2 + dx * sin_2) + dy * mu,
            dz * mu - scale * rho2 * cos_2)
