"""The transport core: one spectral path through a slab or a cylinder, as numba kernels.

Used by every geometry (slab, yarn BSSRDF source, parallel beam); the callers
start a path just inside the boundary and bin what :func:`trace` hands back.

Spectral estimator (proof in docs/transport.md).  A path picks a hero
wavelength h uniformly and is sampled with h's analog densities with implicit
capture: free flights from ``μt_h e^{−μt_h s}``, scattering directions from
``p_h``, boundary reflection or transmission with the Fresnel probability
(wavelength-independent: one real boundary index).  For a path x with n
collisions and length D inside the medium, technique k's density is
``p_k(x) = μt_k^n e^{−μt_k D} Π_j p_k(μ_j) × (common factors)`` and its
contribution at wavelength λ is ``f_λ(x) = α_λ^n p_λ(x)`` (α = μs/μt).  The
one-sample balance-heuristic estimator

    w_λ = f_λ(x) / ((1/L) Σ_k p_k(x)) = α_λ^n · r_λ(x),   r_λ = L p_λ / Σ_k p_k ≤ L

is unbiased for every λ and bounded by L.  The path keeps only ``n``, ``D``
and the running products ``Π_j p_k(μ_j) / p_h(μ_j)``; the weights are formed
when needed (exit, roulette check), which keeps a collision's cost at one
table lookup per wavelength.

Absorbed energy: a λ-analog path deposits ``α^{j−1}(1 − α)`` at its j-th
collision, ``1 − α^n`` in all (times Russian-roulette factors); as a function
of the whole path it takes the same MIS ratio r_λ(x).

Russian roulette: every ``ROULETTE_PERIOD`` collisions (every collision when
r ≡ 1), a path whose largest weight fell below ``ROULETTE_THRESHOLD`` survives
with probability ``ROULETTE_SURVIVAL`` and has its weights divided by it.  The
decision depends only on the path so far, never on which wavelength is the
hero, so it is a common factor of all k's densities: unbiased.  Without
absorption the largest weight is ≥ 1 (r averages 1 over λ) and roulette never
plays, so energy is conserved path by path.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numba

from ._interactions import (
    PHASE_HG,
    fresnel_reflectance,
    hg_value,
    reflect,
    refract,
    sample_hg,
    sample_table,
    table_value,
    turn,
)
from ._rng import uniform

SLAB = 0  #: dims = (thickness,): medium 0 ≤ z ≤ thickness, light enters at z = 0 going +z
CYLINDER = 1  #: dims = (a, b): elliptic cross-section x²/a² + y²/b² ≤ 1, axis z (a = b: circle)

EXITED = 0
TERMINATED = 1
LOST = 2

ROULETTE_THRESHOLD = 1e-3
ROULETTE_SURVIVAL = 0.1
#: Collisions between roulette checks where the check costs a spectral evaluation.
ROULETTE_PERIOD = 4
#: A path still inside after this many interactions (collisions + internal reflections) is
#: ended and its weight reported as lost, so nothing disappears unreported.
MAX_INTERACTIONS = 1_000_000
#: Running phase ratios are rescaled when their largest leaves [1/RESCALE, RESCALE].
RESCALE = 1e100

KernelMedium = namedtuple(
    "KernelMedium",
    ["mu_t", "log_mu_t", "albedo", "max_albedo", "phase_kind", "hg_g", "phase_by_mu", "cdf", "guide", "grey"],
)


@numba.njit(cache=True, error_model="numpy", inline="always")
def boundary_distance(geometry, dims, pos, d):
    """Distance from an interior point ``pos`` along unit ``d`` to the boundary (inf if never)."""
    if geometry == SLAB:
        if d[2] > 0.0:
            return (dims[0] - pos[2]) / d[2]
        if d[2] < 0.0:
            return -pos[2] / d[2]
        return math.inf
    ia2 = 1.0 / (dims[0] * dims[0])
    ib2 = 1.0 / (dims[1] * dims[1])
    qa = d[0] * d[0] * ia2 + d[1] * d[1] * ib2
    if qa < 1e-300:
        return math.inf
    qb = pos[0] * d[0] * ia2 + pos[1] * d[1] * ib2
    qc = pos[0] * pos[0] * ia2 + pos[1] * pos[1] * ib2 - 1.0
    root = math.sqrt(max(0.0, qb * qb - qa * qc))
    # the far root, in the form without cancellation for either sign of qb
    if qb <= 0.0:
        return (root - qb) / qa
    return max(0.0, -qc / (qb + root))


@numba.njit(cache=True, error_model="numpy", inline="always")
def boundary_normal(geometry, dims, pos, normal):
    """Put ``pos`` exactly on the boundary it reached and write the outward unit normal there."""
    if geometry == SLAB:
        if pos[2] > 0.5 * dims[0]:
            pos[2] = dims[0]
            normal[2] = 1.0
        else:
            pos[2] = 0.0
            normal[2] = -1.0
        normal[0] = 0.0
        normal[1] = 0.0
        return
    ia2 = 1.0 / (dims[0] * dims[0])
    ib2 = 1.0 / (dims[1] * dims[1])
    scale = 1.0 / math.sqrt(pos[0] * pos[0] * ia2 + pos[1] * pos[1] * ib2)
    pos[0] *= scale
    pos[1] *= scale
    nx = pos[0] * ia2
    ny = pos[1] * ib2
    inv = 1.0 / math.sqrt(nx * nx + ny * ny)
    normal[0] = nx * inv
    normal[1] = ny * inv
    normal[2] = 0.0


@numba.njit(cache=True, error_model="numpy", inline="always")
def phase_at(medium, k, mu):
    if medium.phase_kind == PHASE_HG:
        return hg_value(medium.hg_g[k], mu)
    return table_value(medium.phase_by_mu, k, mu)


@numba.njit(cache=True, error_model="numpy", inline="always")
def mis_ratios(medium, hero, ratio, n, length, out):
    """r_λ = L p_λ(x) / Σ_k p_k(x) for the path so far (n collisions, ``length`` mm) into ``out``.

    p_k / p_h = ratio_k · (μt_k / μt_h)^n · e^{−(μt_k − μt_h) length}; the exponential factors
    are scaled by their largest so that nothing overflows (``ratio`` ≤ RESCALE).
    """
    n_wl = out.shape[0]
    if medium.grey:
        for k in range(n_wl):
            out[k] = 1.0
        return
    top = -math.inf
    for k in range(n_wl):
        b = -(medium.mu_t[k] - medium.mu_t[hero]) * length
        if n > 0:
            b += n * (medium.log_mu_t[k] - medium.log_mu_t[hero])
        out[k] = b
        top = max(top, b)
    total = 0.0
    for k in range(n_wl):
        out[k] = ratio[k] * math.exp(out[k] - top)
        total += out[k]
    if not 0.0 < total < math.inf:
        # every term underflowed (extreme phase ratios): the same sum in logarithms
        for k in range(n_wl):
            b = -(medium.mu_t[k] - medium.mu_t[hero]) * length
            if n > 0:
                b += n * (medium.log_mu_t[k] - medium.log_mu_t[hero])
            out[k] = b + math.log(ratio[k]) if ratio[k] > 0.0 else -math.inf
        top = -math.inf
        for k in range(n_wl):
            top = max(top, out[k])
        total = 0.0
        for k in range(n_wl):
            out[k] = math.exp(out[k] - top)
            total += out[k]
    scale = n_wl / total
    for k in range(n_wl):
        out[k] *= scale


@numba.njit(cache=True, error_model="numpy", inline="always")
def albedo_power(medium, k, n):
    """α_k^n (1 for n = 0), by repeated squaring."""
    return medium.albedo[k] ** n


@numba.njit(cache=True, error_model="numpy", inline="always")
def _finish(medium, hero, ratio, n, n_mark, length, factor, banked, alive, ratios, weights, absorbed):
    """Form the path's weights (``weights``, 0 if not ``alive``) and add its absorbed energy."""
    mis_ratios(medium, hero, ratio, n, length, ratios)
    for k in range(weights.shape[0]):
        now = albedo_power(medium, k, n)
        mark = albedo_power(medium, k, n_mark)
        absorbed[k] += ratios[k] * (banked[k] + factor * (mark - now))
        weights[k] = ratios[k] * factor * now if alive else 0.0


@numba.njit(cache=True, error_model="numpy", inline="always")
def trace(state, geometry, dims, eta, medium, hero, pos, d, enter_weight,
          ratio, banked, ratios, normal, weights, absorbed):
    """Trace one path that has just entered the medium at ``pos`` going along unit ``d``.

    ``eta`` = n_inside / n_outside; ``enter_weight`` the flux it carries (per unit incident
    flux).  Returns ``(status, collisions)``.  On ``EXITED``: ``pos`` is the exit point, ``d``
    the refracted direction outside, ``weights`` (L,) the flux leaving per wavelength; on
    ``LOST`` ``weights`` holds the flux still inside; on ``TERMINATED`` (roulette) it is 0.
    ``absorbed`` (L,) is incremented by the absorbed flux in every case.  ``ratio``,
    ``banked``, ``ratios``, ``normal`` are scratch arrays ((L,), (L,), (L,), (3,)).
    """
    n_wl = weights.shape[0]
    for k in range(n_wl):
        ratio[k] = 1.0
        banked[k] = 0.0
    spectral = (not medium.grey) and n_wl > 1
    mu_t_hero = medium.mu_t[hero]
    n = 0
    n_mark = 0
    length = 0.0
    factor = enter_weight  # roulette factor times entering flux
    largest_albedo_power = 1.0  # max_λ α_λ^n, the largest weight when r ≡ 1
    interactions = 0
    status = LOST
    while interactions < MAX_INTERACTIONS:
        interactions += 1
        flight = -math.log(1.0 - uniform(state)) / mu_t_hero if mu_t_hero > 0.0 else math.inf
        to_boundary = boundary_distance(geometry, dims, pos, d)
        if flight == math.inf and to_boundary == math.inf:
            break
        if flight < to_boundary:
            pos[0] += flight * d[0]
            pos[1] += flight * d[1]
            pos[2] += flight * d[2]
            length += flight
            n += 1
            largest_albedo_power *= medium.max_albedo
            check = (n % ROULETTE_PERIOD == 0) if spectral else True
            if check:
                if spectral:
                    mis_ratios(medium, hero, ratio, n, length, ratios)
                    largest = 0.0
                    for k in range(n_wl):
                        largest = max(largest, ratios[k] * albedo_power(medium, k, n))
                else:
                    largest = largest_albedo_power
                if largest * factor < ROULETTE_THRESHOLD:
                    if uniform(state) >= ROULETTE_SURVIVAL:
                        status = TERMINATED
                        break
                    for k in range(n_wl):
                        banked[k] += factor * (albedo_power(medium, k, n_mark) - albedo_power(medium, k, n))
                    factor /= ROULETTE_SURVIVAL
                    n_mark = n
            if medium.phase_kind == PHASE_HG:
                mu = sample_hg(medium.hg_g[hero], uniform(state))
            else:
                mu = sample_table(medium.phase_by_mu, medium.cdf, medium.guide, hero, uniform(state))
            if spectral:
                hero_value = phase_at(medium, hero, mu)
                if hero_value > 0.0:
                    inv = 1.0 / hero_value
                    big = 0.0
                    for k in range(n_wl):
                        ratio[k] *= phase_at(medium, k, mu) * inv
                        big = max(big, ratio[k])
                    if big > RESCALE or big < 1.0 / RESCALE:
                        inv = 1.0 / big
                        for k in range(n_wl):
                            ratio[k] *= inv
            turn(d, mu, state)
        else:
            pos[0] += to_boundary * d[0]
            pos[1] += to_boundary * d[1]
            pos[2] += to_boundary * d[2]
            length += to_boundary
            boundary_normal(geometry, dims, pos, normal)
            cos_i = d[0] * normal[0] + d[1] * normal[1] + d[2] * normal[2]
            if cos_i > 0.0:  # ≤ 0 only by round-off at a grazing hit: the path stays inside
                reflectance = fresnel_reflectance(cos_i, eta)
                if reflectance >= 1.0 or uniform(state) < reflectance:
                    reflect(d, normal, cos_i)
                else:
                    refract(d, normal, cos_i, eta)
                    status = EXITED
                    break
    _finish(medium, hero, ratio, n, n_mark, length, factor, banked, status != TERMINATED, ratios, weights,
            absorbed)
    return status, n
