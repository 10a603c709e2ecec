"""Numba kernels of the Monte-Carlo transport: random numbers, boundaries, spectral paths, tallies.

Inputs are validated by the Python callers (slab.py, cylinder.py); nothing here
checks arguments.  Conventions and the proof of the spectral estimator are in
docs/transport.md.

Spectral scheme (hero wavelength with spectral MIS over scattering, absorption
as a weight): each path picks a hero wavelength ``h`` uniformly and samples free
flights from ``μs_h`` and directions from ``p_h``.  For every wavelength ``λ``
the path then contributes

    f_λ / ((1/L) Σ_k p_k) · exp(−μa_λ · D)

where ``p_k`` is the density of the path's flights and scatterings under
wavelength ``k`` (``Π μs_k e^{−μs_k d} p_k(μ)`` times the escape probability
``e^{−μs_k d}`` of the last flight), ``f_λ = p_λ`` for this scattering-only
sampling, and ``D`` the total path length.  The ratio is at most ``L``: weights
stay bounded however much μs varies across the spectrum.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ..grids import hemisphere_cell, square_to_hemisphere

UINT64_MASK = 0xFFFFFFFFFFFFFFFF
#: Below this largest spectral weight a path plays Russian roulette ...
ROULETTE_THRESHOLD = 1e-3
#: ... and survives with this probability (its weights divided by it).
ROULETTE_SURVIVAL = 0.1
#: A path still inside after this many interactions (scatterings + internal reflections) is
#: dropped and its weight tallied as "lost" so that nothing disappears unreported.
MAX_INTERACTIONS = 100_000


# ---- random numbers: splitmix64 seeding, xorshift64* stream ------------------------------------


@numba.njit(cache=True)
def splitmix64(x: np.uint64) -> np.uint64:
    x = np.uint64(x) + np.uint64(0x9E3779B97F4A7C15)
    z = x
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return z ^ (z >> np.uint64(31))


@numba.njit(cache=True)
def stream_seed(seed: int, a: int, b: int) -> np.uint64:
    """A non-zero xorshift state for stream (a, b) of a run seeded ``seed``."""
    s = splitmix64(np.uint64(seed))
    s = splitmix64(s ^ np.uint64(a + 1))
    s = splitmix64(s ^ (np.uint64(b + 1) * np.uint64(0x632BE59BD9B4E019)))
    if s == np.uint64(0):
        s = np.uint64(0x2545F4914F6CDD1D)
    return s


@numba.njit(cache=True)
def next_uniform(state: np.ndarray) -> float:
    """Uniform in [0, 1) from the xorshift64* generator whose state is ``state[0]``."""
    x = state[0]
    x ^= x >> np.uint64(12)
    x ^= x << np.uint64(25)
    x ^= x >> np.uint64(27)
    state[0] = x
    return float((x * np.uint64(0x2545F4914F6CDD1D)) >> np.uint64(11)) * (1.0 / 9007199254740992.0)


# ---- optics helpers --------------------------------------------------------------------------


@numba.njit(cache=True)
def fresnel_reflectance(cos_i: float, eta: float) -> float:
    """Unpolarised Fresnel reflectance for light hitting an interface from a medium of relative
    index ``eta = n_incident / n_transmitted`` at incidence cosine ``cos_i``; 1 under TIR."""
    sin_t2 = eta * eta * (1.0 - cos_i * cos_i)
    if sin_t2 >= 1.0:
        return 1.0
    cos_t = math.sqrt(1.0 - sin_t2)
    rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    return 0.5 * (rs * rs + rp * rp)


@numba.njit(cache=True)
def refract(d, normal, eta: float, out):
    """Refract unit direction ``d`` through an interface whose unit ``normal`` points to the side
    ``d`` goes to; ``eta = n_from / n_to``.  Writes the new direction into ``out``; False under TIR."""
    cos_i = d[0] * normal[0] + d[1] * normal[1] + d[2] * normal[2]
    sin_t2 = eta * eta * (1.0 - cos_i * cos_i)
    if sin_t2 >= 1.0:
        return False
    cos_t = math.sqrt(1.0 - sin_t2)
    for a in range(3):
        out[a] = eta * d[a] + (cos_t - eta * cos_i) * normal[a]
    norm = math.sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2])
    for a in range(3):
        out[a] /= norm
    return True


@numba.njit(cache=True)
def sample_cos_theta(icdf_row, u: float) -> float:
    position = u * (icdf_row.shape[0] - 1)
    k = min(int(position), icdf_row.shape[0] - 2)
    frac = position - k
    return icdf_row[k] * (1.0 - frac) + icdf_row[k + 1] * frac


@numba.njit(cache=True)
def phase_value(phase_row, mu: float) -> float:
    """p(μ) from a table on the uniform grid of ``phase_row.shape[0]`` points over [−1, 1]."""
    m = phase_row.shape[0]
    position = (mu + 1.0) * 0.5 * (m - 1)
    k = min(max(int(position), 0), m - 2)
    frac = position - k
    return phase_row[k] * (1.0 - frac) + phase_row[k + 1] * frac


@numba.njit(cache=True)
def scatter(d, mu: float, u: float):
    """Turn unit direction ``d`` (in place) by polar cosine ``mu`` and azimuth ``2π u``."""
    phi = 2.0 * math.pi * u
    sin_t = math.sqrt(max(0.0, 1.0 - mu * mu))
    cp, sp = math.cos(phi), math.sin(phi)
    if abs(d[2]) > 0.99999:
        sign = 1.0 if d[2] > 0 else -1.0
        d0, d1, d2 = sin_t * cp, sin_t * sp, sign * mu
    else:
        tmp = math.sqrt(1.0 - d[2] * d[2])
        d0 = sin_t * (d[0] * d[2] * cp - d[1] * sp) / tmp + d[0] * mu
        d1 = sin_t * (d[1] * d[2] * cp + d[0] * sp) / tmp + d[1] * mu
        d2 = -sin_t * cp * tmp + d[2] * mu
    norm = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    d[0], d[1], d[2] = d0 / norm, d1 / norm, d2 / norm


# ---- spectral path state ------------------------------------------------------------------------


@numba.njit(cache=True)
def mis_weights(log_pdf, roulette_factor, out):
    """Per-wavelength MIS ratio p_λ / ((1/L) Σ_k p_k) of the path so far, times the roulette factor."""
    n = log_pdf.shape[0]
    if n == 1:
        out[0] = roulette_factor
        return
    top = log_pdf[0]
    for k in range(1, n):
        if log_pdf[k] > top:
            top = log_pdf[k]
    mean = 0.0
    for k in range(n):
        out[k] = math.exp(log_pdf[k] - top)
        mean += out[k]
    scale = roulette_factor * n / mean
    for k in range(n):
        out[k] *= scale


@numba.njit(cache=True)
def add_flight(log_pdf, log_mu_s, mu_s, distance: float, collided: bool):
    """Account free flights of total length ``distance`` since the last scattering, ending in a
    collision (density μs e^{−μs d}) or not (probability e^{−μs d}), in every wavelength's pdf.
    Reflections at the boundary are the same for every wavelength, so a run is one factor."""
    n = log_pdf.shape[0]
    if n == 1:
        return
    for k in range(n):
        log_pdf[k] -= mu_s[k] * distance
        if collided:
            log_pdf[k] += log_mu_s[k]


@numba.njit(cache=True)
def add_scattering(log_pdf, log_phase, mu: float):
    """Account a scattering by cos θ = ``mu`` in every pdf (``log_phase``: log of the phase tables)."""
    n = log_pdf.shape[0]
    if n == 1:
        return
    m = log_phase.shape[1]
    position = (mu + 1.0) * 0.5 * (m - 1)
    j = min(max(int(position), 0), m - 2)
    frac = position - j
    for k in range(n):
        log_pdf[k] += log_phase[k, j] * (1.0 - frac) + log_phase[k, j + 1] * frac


@numba.njit(cache=True)
def end_of_run(absorbed, log_pdf, weights, path_length, run_start, mu_a, roulette_factor):
    """Weights at the end of a run of flights (ended by a scattering or an exit), and the energy
    absorbed along the run: MIS weight × (e^{−μa D_start} − e^{−μa D_end}).  Lumping the run is
    unbiased because the run's absorbed energy is a function of the path prefix through the
    run's end, whose density the MIS ratio already holds (docs/transport.md)."""
    mis_weights(log_pdf, roulette_factor, weights)
    for k in range(absorbed.shape[0]):
        if mu_a[k] > 0.0:
            kept = math.exp(-mu_a[k] * path_length)
            absorbed[k] += weights[k] * (math.exp(-mu_a[k] * run_start) - kept)
            weights[k] *= kept


# ---- shared path loop ---------------------------------------------------------------------------


@numba.njit(cache=True)
def _russian_roulette(state, weights, roulette, enter_weight):
    """New roulette factor, or 0 when the path is terminated.

    Only a path whose every weight fell below ROULETTE_THRESHOLD of its starting weight plays:
    without absorption the largest MIS ratio never drops below 1, so energy is then conserved
    path by path, not just on average."""
    largest = 0.0
    for k in range(weights.shape[0]):
        largest = max(largest, weights[k])
    if largest >= ROULETTE_THRESHOLD * enter_weight:
        return roulette
    if next_uniform(state) < ROULETTE_SURVIVAL:
        return roulette / ROULETTE_SURVIVAL
    return 0.0


@numba.njit(cache=True)
def _free_flight(state, mu_s_hero):
    if mu_s_hero > 0.0:
        return -math.log(1.0 - next_uniform(state)) / mu_s_hero
    return math.inf


# ---- slab ---------------------------------------------------------------------------------------


@numba.njit(cache=True)
def _slab_path(state, thickness, n_index, mu_s, log_mu_s, mu_a, log_phase, icdf, enter_weight,
               tallies, log_pdf, weights, d):
    """One path entering a slab [0, thickness] at z = 0 going straight down (collimated, normal).

    ``tallies`` rows: R diffuse, R unscattered, T diffuse, T unscattered, absorbed, lost.
    Returns the number of scatterings and the index of the row it exited into (−1: none).
    """
    n_wl = mu_s.shape[0]
    hero = min(int(next_uniform(state) * n_wl), n_wl - 1)
    for k in range(n_wl):
        log_pdf[k] = 0.0
    z = 0.0
    d[0], d[1], d[2] = 0.0, 0.0, 1.0
    path_length = 0.0
    run_start = 0.0
    roulette = enter_weight
    events = 0
    interactions = 0
    while True:
        flight = _free_flight(state, mu_s[hero])
        if d[2] > 0.0:
            to_boundary = (thickness - z) / d[2]
        elif d[2] < 0.0:
            to_boundary = -z / d[2]
        else:
            to_boundary = math.inf
        if flight < to_boundary:
            z += flight * d[2]
            path_length += flight
            add_flight(log_pdf, log_mu_s, mu_s, path_length - run_start, True)
            end_of_run(tallies[4], log_pdf, weights, path_length, run_start, mu_a, roulette)
            run_start = path_length
            mu = sample_cos_theta(icdf[hero], next_uniform(state))
            scatter(d, mu, next_uniform(state))
            add_scattering(log_pdf, log_phase, mu)
            events += 1
            roulette = _russian_roulette(state, weights, roulette, enter_weight)
            if roulette == 0.0:
                return events, -1
        else:
            z = thickness if d[2] > 0.0 else 0.0
            path_length += to_boundary
            if next_uniform(state) < fresnel_reflectance(abs(d[2]), n_index):
                d[2] = -d[2]
            else:
                add_flight(log_pdf, log_mu_s, mu_s, path_length - run_start, False)
                end_of_run(tallies[4], log_pdf, weights, path_length, run_start, mu_a, roulette)
                row = (0 if events else 1) if d[2] < 0.0 else (2 if events else 3)
                for k in range(n_wl):
                    tallies[row, k] += weights[k]
                return events, row
        interactions += 1
        if interactions >= MAX_INTERACTIONS:
            add_flight(log_pdf, log_mu_s, mu_s, path_length - run_start, False)
            end_of_run(tallies[4], log_pdf, weights, path_length, run_start, mu_a, roulette)
            for k in range(n_wl):
                tallies[5, k] += weights[k]
            return events, 5


@numba.njit(cache=True, parallel=True)
def slab_kernel(paths_per_chunk, n_chunks, seed, thickness, n_index, mu_s, mu_a, phase, icdf):
    """Run ``n_chunks × paths_per_chunk`` slab paths, one random stream per chunk.

    Returns per-chunk sums ``(n_chunks, 8, L)``: R diffuse, R unscattered, T diffuse,
    T unscattered, absorbed, lost, and the per-path squares of R and T; the events per
    chunk; and the specular reflectance at entry.
    """
    n_wl = mu_s.shape[0]
    sums = np.zeros((n_chunks, 8, n_wl))
    events = np.zeros(n_chunks, dtype=np.int64)
    specular = fresnel_reflectance(1.0, 1.0 / n_index)
    log_mu_s = np.log(np.maximum(mu_s, 1e-300))
    log_phase = np.log(np.maximum(phase, 1e-300))
    for chunk in numba.prange(n_chunks):
        state = np.empty(1, dtype=np.uint64)
        state[0] = stream_seed(seed, chunk, 0)
        log_pdf = np.zeros(n_wl)
        weights = np.zeros(n_wl)
        d = np.zeros(3)
        tallies = np.zeros((6, n_wl))
        for _ in range(paths_per_chunk):
            n_events, row = _slab_path(state, thickness, n_index, mu_s, log_mu_s, mu_a, log_phase, icdf,
                                       1.0 - specular, tallies, log_pdf, weights, d)
            events[chunk] += n_events
            if 0 <= row <= 3:
                square = 6 if row <= 1 else 7
                for k in range(n_wl):
                    sums[chunk, square, k] += weights[k] * weights[k]
        for row in range(6):
            for k in range(n_wl):
                sums[chunk, row, k] = tallies[row, k]
    return sums, events, specular


# ---- cylinder -----------------------------------------------------------------------------------


@numba.njit(cache=True)
def circle_exit_distance(x, y, dx, dy, radius):
    """Distance along (dx, dy, ·) from an interior point to the circle of ``radius``."""
    a = dx * dx + dy * dy
    if a < 1e-300:
        return math.inf
    b = x * dx + y * dy
    c = x * x + y * y - radius * radius
    disc = max(b * b - a * c, 0.0)
    return (-b + math.sqrt(disc)) / a


@numba.njit(cache=True)
def _cylinder_path(state, radius, n_index, mu_s, log_mu_s, mu_a, log_phase, icdf,
                   psi0, z0, d, enter_weight, n_around, n_along, cell_length, n_out_res,
                   tally, group_tally, exit_sum, absorbed, lost, log_pdf, weights, normal, out_dir):
    """One path that has just refracted into the yarn at azimuth ``psi0``, height ``z0``, direction d.

    Returns (scatterings, exited).  On exit ``weights`` holds its per-wavelength weight.
    """
    n_wl = mu_s.shape[0]
    hero = min(int(next_uniform(state) * n_wl), n_wl - 1)
    for k in range(n_wl):
        log_pdf[k] = 0.0
    x = radius * math.cos(psi0)
    y = radius * math.sin(psi0)
    z = z0
    path_length = 0.0
    run_start = 0.0
    roulette = enter_weight
    events = 0
    interactions = 0
    d_psi = 2.0 * math.pi / n_around
    while True:
        flight = _free_flight(state, mu_s[hero])
        to_boundary = circle_exit_distance(x, y, d[0], d[1], radius)
        if flight < to_boundary:
            x += flight * d[0]
            y += flight * d[1]
            z += flight * d[2]
            path_length += flight
            add_flight(log_pdf, log_mu_s, mu_s, path_length - run_start, True)
            end_of_run(absorbed, log_pdf, weights, path_length, run_start, mu_a, roulette)
            run_start = path_length
            mu = sample_cos_theta(icdf[hero], next_uniform(state))
            scatter(d, mu, next_uniform(state))
            add_scattering(log_pdf, log_phase, mu)
            events += 1
            roulette = _russian_roulette(state, weights, roulette, enter_weight)
            if roulette == 0.0:
                return events, False
        elif to_boundary == math.inf:  # along the axis with no scattering: never leaves
            add_flight(log_pdf, log_mu_s, mu_s, path_length - run_start, False)
            end_of_run(absorbed, log_pdf, weights, path_length, run_start, mu_a, roulette)
            for k in range(n_wl):
                lost[k] += weights[k]
            return events, False
        else:
            x += to_boundary * d[0]
            y += to_boundary * d[1]
            z += to_boundary * d[2]
            path_length += to_boundary
            rho = math.sqrt(x * x + y * y)
            x *= radius / rho  # back onto the surface against round-off
            y *= radius / rho
            normal[0], normal[1], normal[2] = x / radius, y / radius, 0.0
            cos_i = d[0] * normal[0] + d[1] * normal[1]
            if next_uniform(state) < fresnel_reflectance(cos_i, n_index):
                for a in range(3):
                    d[a] -= 2.0 * cos_i * normal[a]
            else:
                refract(d, normal, n_index, out_dir)
                add_flight(log_pdf, log_mu_s, mu_s, path_length - run_start, False)
                end_of_run(absorbed, log_pdf, weights, path_length, run_start, mu_a, roulette)
                psi = math.atan2(y, x)
                around = int(math.floor(psi / d_psi)) % n_around
                along = int(math.floor(z / cell_length)) + n_along // 2
                if along < 0:
                    along = n_along
                elif along >= n_along:
                    along = n_along + 1
                # exit direction in the exit point's frame: x = axis, y = n × t, z = n
                cp, sp = normal[0], normal[1]
                out_cell = hemisphere_cell(out_dir[2], sp * out_dir[0] - cp * out_dir[1],
                                           cp * out_dir[0] + sp * out_dir[1], n_out_res)
                for k in range(n_wl):
                    tally[around, along, out_cell, k] += weights[k]
                    group_tally[around, out_cell, k] += weights[k]
                    exit_sum[k] += weights[k]
                return events, True
        interactions += 1
        if interactions >= MAX_INTERACTIONS:
            add_flight(log_pdf, log_mu_s, mu_s, path_length - run_start, False)
            end_of_run(absorbed, log_pdf, weights, path_length, run_start, mu_a, roulette)
            for k in range(n_wl):
                lost[k] += weights[k]
            return events, False


@numba.njit(cache=True, parallel=True)
def cylinder_kernel(cells, in_res, mean_cos, paths, seed, batch, radius, n_index, mu_s, mu_a, phase, icdf,
                    n_around, n_along, cell_length, out_res, n_groups,
                    tally, group_tally, specular, exit_sum, exit_sq, absorbed, lost, events):
    """Trace ``paths`` paths for each incidence cell in ``cells`` (one stream per cell and batch).

    Rays start uniformly in the source cell ψ ∈ [0, 2π/n_around), z ∈ [0, cell_length) with
    directions uniform in solid angle inside hemisphere cell ``c`` of the entry point's frame,
    carrying flux cos θ / ⟨cos θ⟩_c (``mean_cos``): the cell is lit by a uniform radiance, as the
    exit tally averages radiance over exit cells, which keeps cell averages reciprocal.
    ``tally`` and ``group_tally`` (float32, whole grids) are indexed by incidence cell, the
    other outputs by position in ``cells``.
    """
    n_wl = mu_s.shape[0]
    log_mu_s = np.log(np.maximum(mu_s, 1e-300))
    log_phase = np.log(np.maximum(phase, 1e-300))
    d_psi = 2.0 * math.pi / n_around
    for slot in numba.prange(cells.shape[0]):
        cell = cells[slot]
        state = np.empty(1, dtype=np.uint64)
        state[0] = stream_seed(seed, cell, batch)
        log_pdf = np.zeros(n_wl)
        weights = np.zeros(n_wl)
        d = np.zeros(3)
        normal = np.zeros(3)
        out_dir = np.zeros(3)
        ci = cell % in_res
        cj = cell // in_res
        for path in range(paths):
            s = (ci + next_uniform(state)) / in_res
            t = (cj + next_uniform(state)) / in_res
            wx, wy, wz = square_to_hemisphere(s, t)  # toward the light, local frame
            psi0 = next_uniform(state) * d_psi
            z0 = next_uniform(state) * cell_length
            cp, sp = math.cos(psi0), math.sin(psi0)
            # local (axis, n × t, n) → world: axis = e_z, b = (sin ψ, −cos ψ, 0), n = (cos ψ, sin ψ, 0)
            d[0] = -(wy * sp + wz * cp)
            d[1] = -(-wy * cp + wz * sp)
            d[2] = -wx
            flux = wz / mean_cos[cell]
            reflect = fresnel_reflectance(wz, 1.0 / n_index)
            for k in range(n_wl):
                specular[slot, k] += flux * reflect
            normal[0], normal[1], normal[2] = -cp, -sp, 0.0  # into the yarn
            refract(d, normal, 1.0 / n_index, out_dir)
            for a in range(3):
                d[a] = out_dir[a]
            n_events, exited = _cylinder_path(
                state, radius, n_index, mu_s, log_mu_s, mu_a, log_phase, icdf,
                psi0, z0, d, flux * (1.0 - reflect), n_around, n_along, cell_length, out_res,
                tally[cell], group_tally[path % n_groups, cell], exit_sum[slot],
                absorbed[slot], lost[slot], log_pdf, weights, normal, out_dir,
            )
            events[slot] += n_events
            if exited:
                for k in range(n_wl):
                    exit_sq[slot, k] += weights[k] * weights[k]
    return 0
