"""The transport core: one spectral path through a slab or a cylinder, as numba kernels.

Used by every geometry (slab, yarn BSSRDF source, parallel beam); the callers
start a path just inside the boundary and bin what :func:`trace` hands back.

Spectral estimator (proof in docs/transport.md).  A path picks a hero
wavelength h with probability q_h (uniform unless the caller adapts it) and is
sampled with h's analog densities with implicit capture: free flights from
``μt_h e^{−μt_h s}``, scattering directions from ``p_h``, boundary reflection
or transmission with the Fresnel probability (wavelength-independent: one real
boundary index).  For a path x with n collisions and length D inside the
medium, technique k's density is ``p_k(x) = μt_k^n e^{−μt_k D} Π_j p_k(μ_j) ×
(common factors)`` and its contribution at wavelength λ is ``f_λ(x) = α_λ^n
p_λ(x)`` (α = μs/μt).  The one-sample balance-heuristic estimator

    w_λ = f_λ(x) / Σ_k q_k p_k(x) = α_λ^n · r_λ(x),   r_λ = p_λ / Σ_k q_k p_k ≤ 1 / q_λ

is unbiased for every λ and bounded (by L for uniform q).  The path keeps only
``n``, ``D``, the running phase products ``Π_j p_k(μ_j)`` (up to a factor common to
all k, which cancels in r) and the powers α_k^n; the weights are formed when needed
(exit, roulette check), which keeps a collision's cost at one table lookup and one
product per wavelength.

Absorbed energy: a λ-analog path deposits ``α^{j−1}(1 − α)`` at its j-th
collision, ``1 − α^n`` in all (times Russian-roulette factors); as a function
of the whole path it takes the same MIS ratio r_λ(x).

Russian roulette: every :func:`roulette_interval` collisions (every collision when
r ≡ 1), a path whose largest weight fell below ``ROULETTE_THRESHOLD`` survives
with probability max(ROULETTE_SURVIVAL, largest / ROULETTE_THRESHOLD) and has
its weights divided by it (a weight window: a survivor carries the threshold's
weight, or ten times what it had).  On a spectral path each wavelength's weight
is scaled by its ``importance`` s_λ first (1: the plain roulette; error-target
yarn runs lower it where a wavelength needs fewer paths than the hardest one,
docs/transport.md).  The check forms the L weights (L exponentials) only where
a lower bound of the largest, from two exponentials, does not already clear the
threshold (:func:`surely_above_threshold`): the decisions, and so the random
numbers, are those of the full check.  The decision depends only on the path so
far, never on which wavelength is the hero, so it is a common factor of all
k's densities: unbiased.  Without absorption and with s ≡ 1 the largest weight
is ≥ 1 (Σ_k q_k r_k = 1) and roulette never plays.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numba
import numpy as np

from precompute.transport._interactions import (
    PHASE_HG,
    fresnel_reflectance,
    hg_value,
    reflect,
    refract,
    sample_hg,
    sample_table,
    turn,
)
from precompute.transport._exp import exp_nonpositive
from precompute.transport._rng import exponential, uniform

SLAB = 0  #: dims = (thickness,): medium 0 ≤ z ≤ thickness, light enters at z = 0 going +z
CYLINDER = 1  #: dims = (a, b): elliptic cross-section x²/a² + y²/b² ≤ 1, axis z (a = b: circle)

EXITED = 0
TERMINATED = 1
LOST = 2

ROULETTE_THRESHOLD = 1e-3
ROULETTE_SURVIVAL = 0.1
#: Collisions between roulette checks on a spectral path, where a check costs L exponentials wherever the
#: bound cannot settle it (:func:`roulette_interval`).  Any interval is unbiased.
ROULETTE_INTERVAL_SCATTERING = 16
ROULETTE_INTERVAL_ABSORBING = 4
#: The mean single-scattering albedo over the wavelengths from which a medium counts as scattering.
SCATTERING_MEDIUM = 0.5
#: A path still inside after this many interactions (collisions + internal reflections) is
#: ended and its weight reported as lost, so nothing disappears unreported.
MAX_INTERACTIONS = 1_000_000
#: How far above ROULETTE_THRESHOLD a lower bound of a path's largest weight must be for the exact
#: evaluation to be skipped: far above the bound's and the evaluation's round-off.
BOUND_MARGIN = 1.0 + 1e-9
#: Running phase products are rescaled when an upper bound of their largest exceeds RESCALE, or the hero's
#: falls below 1 / RESCALE.
RESCALE = 1e100
#: The phase table's rows and the running phase products are padded with zeros to a multiple of this many
#: wavelengths: the 4 doubles of a 256-bit vector, so that LLVM ends a collision's update loop with vector
#: steps instead of 1–3 scalar ones (35 wavelengths: 36).
PHASE_WIDTH = 4

#: The medium as :func:`trace` reads it (``TransportMedium.kernel()``); ``albedo_powers`` (interval + 1, L):
#: row r holds α_λ^r up to the roulette interval (:func:`albedo_power_table`); ``fibre_params``, ``fibre_sine``,
#: ``fibre_absorption``: a medium of oriented fibres' (:mod:`._fibres`; length-1 zeros for any other).
KernelMedium = namedtuple(
    "KernelMedium",
    ["mu_t", "log_mu_t", "albedo", "brightest", "roulette_interval", "albedo_powers", "phase_kind", "hg_g",
     "phase_by_mu", "phase_max", "alias_threshold", "alias", "grey", "fibre_params", "fibre_sine", "fibre_absorption"],
)

#: A task's random stream and the arrays :func:`trace` works in: ``state`` (2,) uint64 (:mod:`._rng`);
#: ``pos``, ``d`` (3,) a path's entry point and direction in, its exit point and direction out;
#: ``weights`` (L,) its weights out; ``phase_product``, ``banked``, ``albedo_n``, ``albedo_mark``,
#: ``ratios`` (L,) scratch.
PathArrays = namedtuple(
    "PathArrays", ["state", "pos", "d", "weights", "phase_product", "banked", "albedo_n", "albedo_mark", "ratios"],
)


@numba.njit(cache=True)
def padded_width(n_wl):
    """``n_wl`` rounded up to a multiple of PHASE_WIDTH."""
    return -(-n_wl // PHASE_WIDTH) * PHASE_WIDTH


@numba.njit(cache=True, error_model="numpy")
def path_arrays(n_wl):
    """:data:`PathArrays` for ``n_wl`` wavelengths, not initialised (a task seeds ``state``) but for the
    phase products' padding (:data:`PHASE_WIDTH`), which stays 0."""
    return PathArrays(np.empty(2, dtype=np.uint64), np.empty(3), np.empty(3), np.empty(n_wl),
                      np.zeros(padded_width(n_wl)), np.empty(n_wl), np.empty(n_wl), np.empty(n_wl), np.empty(n_wl))


@numba.njit(cache=True)
def roulette_interval(albedo):
    """Collisions between a spectral path's roulette checks in a medium of single-scattering albedos
    ``albedo`` (L,).  In a scattering medium (mean albedo at least SCATTERING_MEDIUM) paths are long and
    their largest weight falls slowly: checks every ROULETTE_INTERVAL_SCATTERING collisions reached the
    default yarn's error target in 0.75–0.8 of the CPU time of checks every 4.  In a medium that mostly
    absorbs, most paths' weights collapse within a few collisions, and a path left unchecked for 16 goes on
    for nothing: the paper's yarn took 1.5 times the CPU time at 16 (docs/transport.md, "Where a
    collision's time goes")."""
    return ROULETTE_INTERVAL_SCATTERING if albedo.mean() >= SCATTERING_MEDIUM else ROULETTE_INTERVAL_ABSORBING


@numba.njit(cache=True, error_model="numpy")
def albedo_power_table(albedo, out):
    """Fill ``out`` (rows, L) with the powers α_λ^r of the albedos ``albedo`` (L,), r = 0 … rows − 1, each
    row the one before times α (row 0: 1)."""
    for k in range(albedo.shape[0]):
        power = 1.0
        for r in range(out.shape[0]):
            out[r, k] = power
            power *= albedo[k]


@numba.njit(cache=True, error_model="numpy", inline="always")
def boundary_distance(geometry, thickness, ia2, ib2, px, py, pz, dx, dy, dz):
    """Distance from an interior point (px, py, pz) along unit (dx, dy, dz) to the boundary (inf if never);
    ``thickness`` (SLAB) or ``ia2``, ``ib2`` = 1/a², 1/b² (CYLINDER): :func:`boundary_shape`."""
    if geometry == SLAB:
        if dz == 0.0:
            return math.inf
        # the face ahead chosen without a branch: which way a path goes is a coin toss, which a branch
        # predictor loses half the time
        face = thickness if dz > 0.0 else 0.0
        return (face - pz) / dz
    qa = dx * dx * ia2 + dy * dy * ib2
    if qa < 1e-300:
        return math.inf
    qb = px * dx * ia2 + py * dy * ib2
    qc = px * px * ia2 + py * py * ib2 - 1.0
    root = math.sqrt(max(0.0, qb * qb - qa * qc))
    # the far root, in the form without cancellation for either sign of qb, chosen by selects (whether
    # the path heads outward is a coin toss) into one division: (root − qb) / qa or −qc / (qb + root)
    inward = qb <= 0.0
    return max(0.0, (root - qb if inward else -qc) / (qa if inward else qb + root))


@numba.njit(cache=True, error_model="numpy", inline="always")
def inside(geometry, thickness, ia2, ib2, x, y, z):
    """Whether the point (x, y, z) lies in the medium (:func:`boundary_shape`'s ``thickness``, ``ia2``,
    ``ib2``); False for a point at infinity or not a number."""
    if geometry == SLAB:
        return 0.0 <= z <= thickness
    return x * x * ia2 + y * y * ib2 <= 1.0


@numba.njit(cache=True, error_model="numpy", inline="always")
def boundary_normal(geometry, thickness, ia2, ib2, px, py, pz):
    """The point (px, py, pz), which reached the boundary, put exactly on it, and the outward unit normal
    there: (px, py, pz, nx, ny, nz)."""
    if geometry == SLAB:
        top = pz > 0.5 * thickness
        return px, py, (thickness if top else 0.0), 0.0, 0.0, (1.0 if top else -1.0)
    scale = 1.0 / math.sqrt(px * px * ia2 + py * py * ib2)
    px *= scale
    py *= scale
    nx = px * ia2
    ny = py * ib2
    inv = 1.0 / math.sqrt(nx * nx + ny * ny)
    return px, py, pz, nx * inv, ny * inv, 0.0


@numba.njit(cache=True, error_model="numpy", inline="always")
def meet_boundary(geometry, thickness, ia2, ib2, eta, px, py, pz, dx, dy, dz, to_boundary, state):
    """A path at interior point (px, py, pz) going along (dx, dy, dz) reaches the boundary ``to_boundary``
    mm on and is reflected (probability R, Fresnel at ``eta`` = n_inside / n_outside) or refracted out:
    ``(px, py, pz, dx, dy, dz, left)``, the point on the boundary, the direction after, and whether it left."""
    px, py, pz, nx, ny, nz = boundary_normal(geometry, thickness, ia2, ib2, px + to_boundary * dx,
                                             py + to_boundary * dy, pz + to_boundary * dz)
    cos_i = dx * nx + dy * ny + dz * nz
    if cos_i > 0.0:  # ≤ 0 only by round-off at a grazing hit: the path stays inside
        reflectance = fresnel_reflectance(cos_i, eta)
        if reflectance >= 1.0 or uniform(state) < reflectance:
            dx, dy, dz = reflect(dx, dy, dz, nx, ny, nz, cos_i)
        else:
            dx, dy, dz = refract(dx, dy, dz, nx, ny, nz, cos_i, eta)
            return px, py, pz, dx, dy, dz, True
    return px, py, pz, dx, dy, dz, False


@numba.njit(cache=True, error_model="numpy", inline="always")
def boundary_shape(geometry, dims):
    """(thickness, 1/a², 1/b²) of the medium ``dims``, taken once per path: (thickness, 0, 0) for a SLAB,
    (0, 1/a², 1/b²) for a CYLINDER."""
    if geometry == SLAB:
        return dims[0], 0.0, 0.0
    return 0.0, 1.0 / (dims[0] * dims[0]), 1.0 / (dims[1] * dims[1])


@numba.njit(cache=True, error_model="numpy", inline="always")
def update_phase_products(phase_kind, hg_g, table, phase_max, hero, mu, segment, along, n_wl, product, bound):
    """Multiply the running products Π p_k (up to a factor common to all k) of the ``n_wl`` wavelengths by
    this scattering's p_k(μ); return the updated upper bound of their largest.  ``product`` and a table's
    rows may be longer than ``n_wl``, by zeros (:data:`PHASE_WIDTH`).  A table is evaluated where its
    sampler put μ: ``along`` ∈ [0, 1) within ``segment`` (:func:`._interactions.sample_table`), so that no
    round-off moves it to the next segment.

    The MIS ratios (:func:`mis_ratios`) and the roulette's bound need the products only up to a common
    factor, so none is divided by the hero's p_h(μ): the wavelengths' updates wait on no division.  To
    keep them in range all are divided by their largest when the bound would exceed RESCALE or the
    hero's own product (the wavelength the path follows, so never negligible) falls below 1 / RESCALE.

    The medium comes in as its arrays (``hg_g``, ``table``: :data:`KernelMedium`'s ``hg_g``,
    ``phase_by_mu``), never as the tuple: a function inlined into a loop binds its arguments
    anew at each call.
    """
    if phase_kind == PHASE_HG:
        for k in range(n_wl):
            product[k] *= hg_value(hg_g[k], mu)
    else:
        j = segment
        if table[j, hero] + (table[j + 1, hero] - table[j, hero]) * along <= 0.0:
            return bound  # the sampler puts μ where the hero's density is 0 only by round-off
        for k in range(table.shape[1]):  # the padded width: no scalar steps after the vector ones
            product[k] *= table[j, k] + (table[j + 1, k] - table[j, k]) * along
    bound *= phase_max
    if bound > RESCALE or product[hero] < 1.0 / RESCALE:
        big = 0.0
        for k in range(n_wl):
            big = max(big, product[k])
        inv = 1.0 / big
        for k in range(n_wl):
            product[k] *= inv
        bound = 1.0
    return bound


@numba.njit(cache=True, error_model="numpy", inline="always")
def log_flight_ratio(mu_t, log_mu_t, mu_t_hero, log_mu_t_hero, n, length):
    """ln of the free-flight densities' ratio μt^n e^{−μt·length} / (μt_h^n e^{−μt_h·length})."""
    b = -(mu_t - mu_t_hero) * length
    if n > 0:
        b += n * (log_mu_t - log_mu_t_hero)
    return b


@numba.njit(cache=True, error_model="numpy", inline="always")
def mis_ratios(mu_t, log_mu_t, grey, hero, product, n, length, hero_p, out):
    """r_λ = p_λ(x) / Σ_k q_k p_k(x) for the path so far (n collisions, ``length`` mm) into ``out``;
    q = ``hero_p``, the probabilities with which the hero wavelength was chosen; ``product``: the running
    phase products (:func:`update_phase_products`); ``mu_t``, ``log_mu_t``, ``grey``: the medium's
    (:data:`KernelMedium`).

    p_k ∝ product_k · (μt_k / μt_h)^n · e^{−(μt_k − μt_h) length}, the factor common to all k
    cancelling in r; the exponential factors are scaled by their largest so that nothing overflows
    (``product`` ≤ RESCALE).
    """
    n_wl = out.shape[0]
    if grey:
        for k in range(n_wl):
            out[k] = 1.0
        return
    mu_t_hero = mu_t[hero]
    log_mu_t_hero = log_mu_t[hero]
    top = -math.inf
    for k in range(n_wl):
        b = log_flight_ratio(mu_t[k], log_mu_t[k], mu_t_hero, log_mu_t_hero, n, length)
        out[k] = b
        top = max(top, b)
    for k in range(n_wl):  # a loop of arithmetic alone, vectorised
        out[k] = product[k] * exp_nonpositive(out[k] - top)
    total = 0.0
    for k in range(n_wl):
        total += hero_p[k] * out[k]
    if not 0.0 < total < math.inf:
        # every term underflowed (extreme phase products): the same sum in logarithms
        for k in range(n_wl):
            b = log_flight_ratio(mu_t[k], log_mu_t[k], mu_t_hero, log_mu_t_hero, n, length)
            out[k] = b + math.log(product[k]) if product[k] > 0.0 else -math.inf
        top = -math.inf
        for k in range(n_wl):
            top = max(top, out[k])
        total = 0.0
        for k in range(n_wl):
            out[k] = math.exp(out[k] - top)
            total += hero_p[k] * out[k]
    scale = 1.0 / total
    for k in range(n_wl):
        out[k] *= scale


@numba.njit(cache=True, error_model="numpy", inline="always")
def surely_above_threshold(mu_t, log_mu_t, albedo_n, brightest, neediest, hero, product, n, length, hero_p, factor,
                           importance):
    """Whether the path's largest weight max_λ r_λ α_λ^n s_λ (``albedo_n``: α_λ^n, ``importance``: s) times
    ``factor`` is surely at least ROULETTE_THRESHOLD, from a lower bound that needs two exponentials instead
    of L; ``brightest``: the wavelength of largest albedo, ``neediest``: of largest importance.

    With b_k = n ln(μt_k/μt_h) − (μt_k − μt_h)·length (:func:`log_flight_ratio`) and B = max_k b_k,
    the MIS ratio of any wavelength c is r_c = P_c e^{b_c} / Σ_k q_k P_k e^{b_k}
    ≥ P_c e^{b_c − B} / Σ_k q_k P_k (P: the phase ``product``), and the largest weight is at least
    r_c α_c^n s_c, taken for the brightest and the neediest wavelength.  The bound must clear the
    threshold by a margin far above round-off, so where it answers True the full check would answer
    the same: the path's decisions and random numbers do not change."""
    n_wl = mu_t.shape[0]
    mu_t_hero = mu_t[hero]
    log_mu_t_hero = log_mu_t[hero]
    top = -math.inf
    total = 0.0
    for k in range(n_wl):
        top = max(top, log_flight_ratio(mu_t[k], log_mu_t[k], mu_t_hero, log_mu_t_hero, n, length))
        total += hero_p[k] * product[k]
    if not 0.0 < total < math.inf:
        return False
    lower = 0.0
    for c in (brightest, neediest):
        b_c = log_flight_ratio(mu_t[c], log_mu_t[c], mu_t_hero, log_mu_t_hero, n, length)
        lower = max(lower, product[c] * math.exp(b_c - top) / total * albedo_n[c] * importance[c])
    return lower * factor >= ROULETTE_THRESHOLD * BOUND_MARGIN


@numba.njit(cache=True, error_model="numpy", inline="always")
def largest_weight(albedo_n, ratios, importance):
    """max_λ r_λ α_λ^n s_λ: the path's largest weight per unit factor, from its MIS ratios ``ratios`` and
    albedo powers ``albedo_n``, each wavelength's scaled by its ``importance`` s_λ."""
    largest = 0.0
    for k in range(ratios.shape[0]):
        largest = max(largest, ratios[k] * albedo_n[k] * importance[k])
    return largest


@numba.njit(cache=True, error_model="numpy", inline="always")
def _finish(medium, hero, hero_p, product, n, length, factor, banked, albedo_n, albedo_mark, alive, fresh, ratios,
            weights, absorbed):
    """Form the path's weights (``weights``, 0 if not ``alive``) and add its absorbed energy;
    ``fresh``: ``ratios`` already hold the whole path's MIS ratios."""
    if not fresh:
        mis_ratios(medium.mu_t, medium.log_mu_t, medium.grey, hero, product, n, length, hero_p, ratios)
    for k in range(weights.shape[0]):
        absorbed[k] += ratios[k] * (banked[k] + factor * (albedo_mark[k] - albedo_n[k]))
        weights[k] = ratios[k] * factor * albedo_n[k] if alive else 0.0


@numba.njit(cache=True, error_model="numpy", inline="always")
def trace(geometry, dims, eta, medium, hero, hero_p, importance, enter_weight, arrays, absorbed):
    """Trace one path that has just entered the medium at ``arrays.pos`` going along unit ``arrays.d``,
    drawing from the stream ``arrays.state`` (:data:`PathArrays`).

    ``eta`` = n_inside / n_outside; ``enter_weight`` the flux it carries (per unit incident
    flux); ``hero_p`` (L,) the hero wavelengths' probabilities, ``importance`` (L,) the roulette's
    scale of each wavelength's weight.  On ``EXITED``: ``pos`` is the exit point, ``d``
    the refracted direction outside, ``weights`` (L,) the flux leaving per wavelength; on
    ``LOST`` ``weights`` holds the flux still inside; on ``TERMINATED`` (roulette) it is 0.
    ``absorbed`` (L,) is incremented by the absorbed flux in every case.  The position and direction are
    local scalars while the path is traced: ``pos`` and ``d`` are read at the start and written at the end.
    The kernels hand in :mod:`._borrow` views of the medium's and the path's arrays, which the inlined
    helpers called at every collision bind without a reference count.

    Returns ``(status, collisions, length)``, ``length`` the path's length inside the medium
    (mm): a path's weight under absorption μa + Δμa is its weight here times e^{−Δμa·length}
    (the absorption reweighting of :mod:`.absorption`).
    """
    state, pos, d, weights = arrays.state, arrays.pos, arrays.d, arrays.weights
    product, banked, albedo_n, albedo_mark, ratios = (arrays.phase_product, arrays.banked, arrays.albedo_n,
                                                     arrays.albedo_mark, arrays.ratios)
    n_wl = weights.shape[0]
    for k in range(n_wl):
        product[k] = 1.0
        banked[k] = 0.0
        # α_λ^n and α_λ^m (m: the collisions at the last roulette survival).  α^n is needed only at the
        # roulette checks and the path's end: a spectral path, checked every interval-th collision,
        # multiplies in α^interval at each check and α^(n mod interval) at its end (the medium's table),
        # where L products at every collision cost 4 % of its time and powers by squaring L loops of
        # log₂ n steps; a grey path is checked at every collision and keeps α^n up there
        albedo_n[k] = 1.0
        albedo_mark[k] = 1.0
    spectral = (not medium.grey) and n_wl > 1
    every_collision = 0 if spectral else n_wl  # the wavelengths whose α^n is kept up at every collision
    per_check = medium.albedo_powers[medium.roulette_interval]  # α^interval
    neediest = 0
    for k in range(n_wl):
        if importance[k] > importance[neediest]:
            neediest = k
    mu_t_hero = medium.mu_t[hero]
    mean_free_path = 1.0 / mu_t_hero if mu_t_hero > 0.0 else math.inf  # mm
    hg_g_hero = medium.hg_g[hero] if medium.phase_kind == PHASE_HG else 0.0
    n = 0
    length = 0.0
    factor = enter_weight  # roulette factor times entering flux
    product_bound = 1.0  # an upper bound of max_k product[k]
    interactions = 0
    status = LOST
    # the distance to the next collision (mm; < 0: none drawn yet).  A path reflected at the boundary
    # goes on with what is left of it: in a homogeneous medium the free path along a broken line is
    # exponential as along a straight one, and this saves a logarithm per internal reflection
    flight = -1.0
    thickness, ia2, ib2 = boundary_shape(geometry, dims)
    px, py, pz = pos[0], pos[1], pos[2]
    dx, dy, dz = d[0], d[1], d[2]
    while interactions < MAX_INTERACTIONS:
        interactions += 1
        if flight < 0.0:
            flight = exponential(state) * mean_free_path if mu_t_hero > 0.0 else math.inf
        # where the flight ends, if it ends inside: the medium is convex, so a flight that ends inside
        # meets no boundary on the way, and most flights in a scattering medium do.  Only the others need
        # the distance to the boundary (a square root and a division on the cylinder).
        qx = px + flight * dx
        qy = py + flight * dy
        qz = pz + flight * dz
        if inside(geometry, thickness, ia2, ib2, qx, qy, qz):
            to_boundary = math.inf
        else:
            to_boundary = boundary_distance(geometry, thickness, ia2, ib2, px, py, pz, dx, dy, dz)
            if flight == math.inf and to_boundary == math.inf:
                break
        if flight < to_boundary:
            px, py, pz = qx, qy, qz
            length += flight
            flight = -1.0
            n += 1
            for k in range(every_collision):
                albedo_n[k] *= medium.albedo[k]
            check = (n % medium.roulette_interval == 0) if spectral else True
            if check:
                for k in range(n_wl - every_collision):
                    albedo_n[k] *= per_check[k]
                if spectral and surely_above_threshold(medium.mu_t, medium.log_mu_t, albedo_n, medium.brightest,
                                                       neediest, hero, product, n, length, hero_p, factor,
                                                       importance):
                    largest = math.inf
                elif spectral:
                    mis_ratios(medium.mu_t, medium.log_mu_t, False, hero, product, n, length, hero_p, ratios)
                    largest = largest_weight(albedo_n, ratios, importance)
                else:
                    largest = albedo_n[medium.brightest]  # r ≡ 1: the largest weight is the brightest's
                if largest * factor < ROULETTE_THRESHOLD:
                    # weight window: the survivors' scaled weight is the threshold, or 1 / ROULETTE_SURVIVAL of it
                    survival = max(ROULETTE_SURVIVAL, largest * factor / ROULETTE_THRESHOLD)
                    if uniform(state) >= survival:
                        status = TERMINATED
                        break
                    for k in range(n_wl):
                        banked[k] += factor * (albedo_mark[k] - albedo_n[k])
                        albedo_mark[k] = albedo_n[k]
                    factor /= survival
            if medium.phase_kind == PHASE_HG:
                mu = sample_hg(hg_g_hero, uniform(state))
                segment, along = 0, 0.0
            else:
                mu, segment, along = sample_table(medium.phase_by_mu, medium.alias_threshold, medium.alias, hero,
                                                  state)
            if spectral:
                product_bound = update_phase_products(medium.phase_kind, medium.hg_g, medium.phase_by_mu,
                                                      medium.phase_max, hero, mu, segment, along, n_wl, product,
                                                      product_bound)
            dx, dy, dz = turn(dx, dy, dz, mu, state)
        else:
            length += to_boundary
            flight -= to_boundary
            px, py, pz, dx, dy, dz, left = meet_boundary(geometry, thickness, ia2, ib2, eta, px, py, pz, dx, dy, dz,
                                                         to_boundary, state)
            if left:
                status = EXITED
                break
    pos[0], pos[1], pos[2] = px, py, pz
    d[0], d[1], d[2] = dx, dy, dz
    if spectral and n % medium.roulette_interval:  # α^n, short of the collisions since the last check
        for k in range(n_wl):
            albedo_n[k] *= medium.albedo_powers[n % medium.roulette_interval, k]
    # a path ended by roulette ends right after a check that formed its ratios
    _finish(medium, hero, hero_p, product, n, length, factor, banked, albedo_n, albedo_mark, status != TERMINATED,
            status == TERMINATED and spectral, ratios, weights, absorbed)
    return status, n, length
