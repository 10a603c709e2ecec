"""Parallel numba kernels: where paths start and how their exits are tallied, per geometry.

Every kernel runs independent tasks in parallel (``prange``); a task draws from
its own random stream (:mod:`._rng`) and writes only its own tally slots, so
the tallies are bitwise identical whatever the number of threads.  The paths
themselves are traced by :func:`._fibres.trace_medium` (:func:`._paths.trace`, or a medium of
oriented fibres' own).  A task's paths run in a function of
their own (``_slab_task``, ``_trace_cell``, ``_beam_task``), which takes every array it
reads from its caller and works on :mod:`._borrow` views of them: its caller holds the
arrays for the whole call.  Inputs are validated by the
Python callers (slab.py, cylinder.py, beam.py).
"""

from __future__ import annotations

import math
from collections import namedtuple

import numba
import numpy as np

from precompute.tables.grids import hemisphere_cell, square_to_hemisphere
from precompute.slab.layout import (
    SLAB_ABSORBED,
    SLAB_LOST,
    SLAB_R_DIFFUSE,
    SLAB_R_SQUARES,
    SLAB_R_UNSCATTERED,
    SLAB_RESULTS,
    SLAB_T_DIFFUSE,
    SLAB_T_SQUARES,
    SLAB_T_UNSCATTERED,
)
from precompute.transport._borrow import borrowed
from precompute.transport._interactions import fresnel_reflectance, refract
from precompute.transport._fibres import trace_medium
from precompute.transport._paths import CYLINDER, EXITED, LOST, SLAB, path_arrays
from precompute.transport._prefetch import prefetch_for_write
from precompute.transport._rng import seed_stream, uniform

#: The yarn kernel's absorption-reweighting tallies (:func:`yarn_kernel`).
DecayTallies = namedtuple("DecayTallies", ["extra_mu_a", "bssrdf", "exit_sum", "exit_sq", "unscattered"])

#: Rows of :func:`slab_results`'s output.
_RESULT = {name: row for row, name in enumerate(SLAB_RESULTS)}
_R_TOTAL, _T_TOTAL, _R_STDERR, _T_STDERR, _R_SPECULAR = (_RESULT[name] for name in (
    "R_total", "T_total", "R_total_stderr", "T_total_stderr", "R_specular"))
_R_UNSCATTERED, _R_DIFFUSE, _T_UNSCATTERED, _T_DIFFUSE, _ABSORBED, _LOST = (_RESULT[name] for name in (
    "R_unscattered", "R_diffuse", "T_unscattered", "T_diffuse", "absorbed", "lost"))


@numba.njit(cache=True, error_model="numpy")
def _pick_hero(state, hero_cdf):
    """Wavelength k with probability hero_cdf[k] − hero_cdf[k − 1] (``hero_cdf[-1]`` = 1)."""
    n_wl = hero_cdf.shape[0]
    if n_wl == 1:
        return 0
    u = uniform(state)
    for k in range(n_wl - 1):
        if u < hero_cdf[k]:
            return k
    return n_wl - 1


@numba.njit(cache=True, error_model="numpy")
def _uniform_heroes(n_wl):
    """Hero probabilities 1/L and their cumulative sums."""
    hero_p = np.full(n_wl, 1.0 / n_wl)
    hero_cdf = (np.arange(n_wl) + 1.0) / n_wl
    hero_cdf[-1] = 1.0
    return hero_p, hero_cdf


@numba.njit(cache=True, parallel=True, error_model="numpy")
def slab_kernel(paths, seed, thickness, eta, medium, sums, events):
    """Collimated normal incidence on the slab 0 ≤ z ≤ ``thickness`` (mm), index ratio ``eta``.

    Task ``c`` traces ``paths[c]`` paths from stream (seed, c, 0) into ``sums[c]`` (8, L):
    the rows SLAB_* per unit incident flux (summed over paths) and the per-path squares of
    the reflected and transmitted flux; ``events[c]`` counts collisions.  The specular
    reflection at entry is deterministic and left to the caller.
    """
    n_wl = sums.shape[2]
    specular = fresnel_reflectance(1.0, 1.0 / eta)
    dims = np.array([thickness])
    hero_p, hero_cdf = _uniform_heroes(n_wl)
    importance = np.ones(n_wl)
    for c in numba.prange(paths.shape[0]):
        # task-local tallies, copied out at the end: no cache line is shared between threads
        local = np.zeros((sums.shape[1], n_wl))
        arrays = path_arrays(n_wl)
        seed_stream(arrays.state, seed, c, 0)
        events[c] = _slab_task(paths[c], dims, eta, medium, specular, hero_p, hero_cdf, importance, arrays, local)
        sums[c] = local


@numba.njit(cache=True, error_model="numpy")
def _slab_task(count, dims, eta, medium, specular, hero_p, hero_cdf, importance, arrays, local):
    """:func:`slab_kernel`'s task: ``count`` paths into its tallies ``local`` (8, L); returns the collisions."""
    medium, arrays, dims = borrowed(medium), borrowed(arrays), borrowed(dims)
    hero_p, hero_cdf, importance, local = borrowed(hero_p), borrowed(hero_cdf), borrowed(importance), borrowed(local)
    n_wl = local.shape[1]
    pos, d, weights = arrays.pos, arrays.d, arrays.weights
    absorbed = local[SLAB_ABSORBED]
    collisions_total = 0
    for _ in range(count):
        hero = _pick_hero(arrays.state, hero_cdf)
        pos[0] = pos[1] = pos[2] = 0.0
        d[0] = d[1] = 0.0
        d[2] = 1.0
        status, collisions, _ = trace_medium(SLAB, dims, eta, medium, hero, hero_p, importance, 1.0 - specular,
                                             arrays, absorbed)
        collisions_total += collisions
        if status == EXITED:
            if d[2] < 0.0:
                row = SLAB_R_DIFFUSE if collisions else SLAB_R_UNSCATTERED
                square = SLAB_R_SQUARES
            else:
                row = SLAB_T_DIFFUSE if collisions else SLAB_T_UNSCATTERED
                square = SLAB_T_SQUARES
            for k in range(n_wl):
                local[row, k] += weights[k]
                local[square, k] += weights[k] * weights[k]
        elif status == LOST:
            for k in range(n_wl):
                local[SLAB_LOST, k] += weights[k]
    return collisions_total


@numba.njit(cache=True, error_model="numpy", inline="always")
def _task_mean(sums, row, k, paths):
    """Row ``row`` of the tasks' tallies ``sums`` at wavelength ``k``, summed over the tasks in order, per path."""
    total = 0.0
    for task in range(sums.shape[0]):
        total += sums[task, row, k]
    return total / paths


@numba.njit(cache=True, error_model="numpy")
def slab_results(sums, paths, eta, out):
    """A slab's result from its tasks' tallies ``sums`` (tasks, 8, L) of ``paths`` paths in all, at index
    ratio ``eta``: ``out`` (len(SLAB_RESULTS), L), the rows :data:`precompute.slab.layout.SLAB_RESULTS`.

    Totals include the specular reflection at entry ((n − 1)/(n + 1))² and the unscattered parts; the
    standard errors are those of the Monte-Carlo means (the specular part is exact).  It allocates
    nothing, so that the native slab library runs it without numba's runtime (:mod:`.native`).
    """
    specular = ((eta - 1.0) / (eta + 1.0)) ** 2
    for k in range(sums.shape[2]):
        r_unscattered = _task_mean(sums, SLAB_R_UNSCATTERED, k, paths)
        r_diffuse = _task_mean(sums, SLAB_R_DIFFUSE, k, paths)
        t_unscattered = _task_mean(sums, SLAB_T_UNSCATTERED, k, paths)
        t_diffuse = _task_mean(sums, SLAB_T_DIFFUSE, k, paths)
        r_scattered = r_diffuse + r_unscattered
        t_all = t_diffuse + t_unscattered
        r_square = _task_mean(sums, SLAB_R_SQUARES, k, paths)
        t_square = _task_mean(sums, SLAB_T_SQUARES, k, paths)
        out[_R_TOTAL, k] = specular + r_scattered
        out[_T_TOTAL, k] = t_all
        out[_R_STDERR, k] = math.sqrt(max(r_square - r_scattered * r_scattered, 0.0) / (paths - 1))
        out[_T_STDERR, k] = math.sqrt(max(t_square - t_all * t_all, 0.0) / (paths - 1))
        out[_R_SPECULAR, k] = specular
        out[_R_UNSCATTERED, k] = r_unscattered
        out[_R_DIFFUSE, k] = r_diffuse
        out[_T_UNSCATTERED, k] = t_unscattered
        out[_T_DIFFUSE, k] = t_diffuse
        out[_ABSORBED, k] = _task_mean(sums, SLAB_ABSORBED, k, paths)
        out[_LOST, k] = _task_mean(sums, SLAB_LOST, k, paths)


@numba.njit(cache=True, error_model="numpy")
def _exit_bins(pos, d, dpsi, n_around, n_along, cell_length, out_res):
    """(around, along, exit cell) of an exit at ``pos`` going ``d`` (outside) on the circular yarn.

    ``along`` is ``n_along`` below the axial grid and ``n_along + 1`` above it.
    """
    psi = math.atan2(pos[1], pos[0])
    if psi < 0.0:
        psi += 2.0 * math.pi
    around = min(int(psi / dpsi), n_around - 1)
    along = int(math.floor(pos[2] / cell_length)) + n_along // 2
    if along < 0:
        along = n_along
    elif along >= n_along:
        along = n_along + 1
    radius = math.sqrt(pos[0] * pos[0] + pos[1] * pos[1])
    cp = pos[0] / radius
    sp = pos[1] / radius
    # exit frame: x = axis, y = n × t = (sin ψ, −cos ψ, 0), z = n = (cos ψ, sin ψ, 0)
    out_cell = hemisphere_cell(d[2], sp * d[0] - cp * d[1], cp * d[0] + sp * d[1], out_res)
    return around, along, out_cell


@numba.njit(cache=True, error_model="numpy")
def _enter_yarn(radius, eta, psi, z, wx, wy, wz, pos, d):
    """Put a ray arriving from local direction (wx, wy, wz) (toward the light, wz > 0) at
    azimuth ``psi``, height ``z`` of the yarn surface; refract it in.  Returns the Fresnel
    reflectance (the surface specular share)."""
    cp = math.cos(psi)
    sp = math.sin(psi)
    pos[0] = radius * cp
    pos[1] = radius * sp
    pos[2] = z
    # local (axis, n × t, n) → world, reversed: the ray travels away from the light
    d[0], d[1], d[2] = refract(-(wy * sp + wz * cp), -(-wy * cp + wz * sp), -wx, -cp, -sp, 0.0, wz, 1.0 / eta)
    return fresnel_reflectance(wz, 1.0 / eta)


#: Bytes in a cache line: the stride of the prefetches of a tally row.
CACHE_LINE = 64


@numba.njit(cache=True, error_model="numpy", inline="always")
def _ask_for_exit_rows(table, table_sq, decay_bssrdf, row, around, along, out_cell):
    """Prefetch the rows of the large tallies that an exit into (``around``, ``along``, ``out_cell``) adds to."""
    n_wl = table.shape[4]
    for k in range(0, n_wl, CACHE_LINE // table.itemsize):
        prefetch_for_write(table, (row, around, along, out_cell, k))
    prefetch_for_write(table, (row, around, along, out_cell, n_wl - 1))
    for k in range(0, n_wl, CACHE_LINE // table_sq.itemsize):
        prefetch_for_write(table_sq, (row, around, out_cell, k))
    prefetch_for_write(table_sq, (row, around, out_cell, n_wl - 1))
    n_decay = decay_bssrdf.shape[4]
    for i in range(0, n_wl * n_decay, CACHE_LINE // decay_bssrdf.itemsize):
        prefetch_for_write(decay_bssrdf, (row, around, out_cell, i // n_decay, i % n_decay))


@numba.njit(cache=True, error_model="numpy", inline="always")
def _add_exit(table, table_sq, decay_bssrdf, row, around, along, out_cell, weights, factors):
    """Add an exit's ``weights`` (L,) and decayed weights ``factors`` (L, K) to the large tallies."""
    for k in range(weights.shape[0]):
        w = weights[k]
        table[row, around, along, out_cell, k] += w
        table_sq[row, around, out_cell, k] += w * w
        for j in range(factors.shape[1]):
            decay_bssrdf[row, around, out_cell, k, j] += factors[k, j]


@numba.njit(cache=True, error_model="numpy")
def _trace_cell(cell, row, first_task, sizes, seed, radius, eta, medium, hero_p, importance, in_res, cos_max, n_around,
                n_along, cell_length, out_res, table, table_sq, specular, exit_sum, exit_sq, unscattered, absorbed,
                lost, events, decay, arrays):
    """Run incidence cell ``cell``'s tasks ``first_task + t`` of ``sizes[t]`` paths (a 0 ends the list),
    choosing hero wavelengths with probabilities ``hero_p`` (L,), into the tallies' row ``row``;
    ``arrays``: :data:`._paths.PathArrays` to work in."""
    medium, arrays = borrowed(medium), borrowed(arrays)
    hero_p, importance = borrowed(hero_p), borrowed(importance)
    state, pos, d, weights = arrays.state, arrays.pos, arrays.d, arrays.weights
    n_wl = exit_sum.shape[1]
    n_decay = decay.extra_mu_a.shape[0]
    cell_decayed_exit = np.zeros((n_wl, n_decay))
    cell_decayed_exit_sq = np.zeros((n_wl, n_decay))
    cell_decayed_unscattered = np.zeros((n_wl, n_decay))
    factors = np.empty((n_wl, n_decay))
    hero_cdf = np.cumsum(hero_p)
    hero_cdf[-1] = 1.0
    dpsi = 2.0 * math.pi / n_around
    dims = np.array([radius, radius])
    ci = cell % in_res
    cj = cell // in_res
    # the cell's small tallies accumulate locally (no cache line shared between threads)
    cell_specular = np.zeros(n_wl)
    cell_exit = np.zeros(n_wl)
    cell_exit_sq = np.zeros(n_wl)
    cell_unscattered = np.zeros(n_wl)
    cell_absorbed = np.zeros(n_wl)
    cell_lost = np.zeros(n_wl)
    cell_events = 0
    # An exit's additions to the large tallies wait for the next exit (or the cell's end), its rows asked
    # for meanwhile: they are in cache when written, in the same order as without the wait.
    waiting = False
    waiting_bins = (0, 0, 0)
    waiting_weights = np.empty(n_wl)
    waiting_factors = np.empty((n_wl, n_decay))
    for t in range(sizes.shape[0]):
        if sizes[t] == 0:
            break
        seed_stream(state, seed, cell, first_task + t)
        for _ in range(sizes[t]):
            while True:
                wx, wy, wz = square_to_hemisphere((ci + uniform(state)) / in_res, (cj + uniform(state)) / in_res)
                if uniform(state) * cos_max[cell] < wz:
                    break
            psi = uniform(state) * dpsi
            z = uniform(state) * cell_length
            reflectance = _enter_yarn(radius, eta, psi, z, wx, wy, wz, pos, d)
            hero = _pick_hero(state, hero_cdf)
            status, collisions, length = trace_medium(CYLINDER, dims, eta, medium, hero, hero_p, importance,
                                                      1.0 - reflectance, arrays, cell_absorbed)
            cell_events += collisions
            for k in range(n_wl):
                cell_specular[k] += reflectance
            if status == EXITED and n_decay:
                for k in range(n_wl):
                    for j in range(n_decay):
                        factors[k, j] = weights[k] * math.exp(-decay.extra_mu_a[j, k] * length)
            if status == EXITED and collisions == 0:
                # a deterministic caustic, given in closed form (precompute/optics/ballistic.py): kept out of the BSSRDF
                for k in range(n_wl):
                    cell_unscattered[k] += weights[k]
                    for j in range(n_decay):
                        cell_decayed_unscattered[k, j] += factors[k, j]
            elif status == EXITED:
                around, along, out_cell = _exit_bins(pos, d, dpsi, n_around, n_along, cell_length, out_res)
                _ask_for_exit_rows(table, table_sq, decay.bssrdf, row, around, along, out_cell)
                if waiting:
                    _add_exit(table, table_sq, decay.bssrdf, row, waiting_bins[0], waiting_bins[1], waiting_bins[2],
                              waiting_weights, waiting_factors)
                waiting = True
                waiting_bins = (around, along, out_cell)
                for k in range(n_wl):
                    w = weights[k]
                    waiting_weights[k] = w
                    cell_exit[k] += w
                    cell_exit_sq[k] += w * w
                    for j in range(n_decay):
                        f = factors[k, j]
                        waiting_factors[k, j] = f
                        cell_decayed_exit[k, j] += f
                        cell_decayed_exit_sq[k, j] += f * f
            elif status == LOST:
                for k in range(n_wl):
                    cell_lost[k] += weights[k]
    if waiting:
        _add_exit(table, table_sq, decay.bssrdf, row, waiting_bins[0], waiting_bins[1], waiting_bins[2],
                  waiting_weights, waiting_factors)
    for k in range(n_wl):
        specular[row, k] += cell_specular[k]
        exit_sum[row, k] += cell_exit[k]
        exit_sq[row, k] += cell_exit_sq[k]
        unscattered[row, k] += cell_unscattered[k]
        absorbed[row, k] += cell_absorbed[k]
        lost[row, k] += cell_lost[k]
        for j in range(n_decay):
            decay.exit_sum[row, k, j] += cell_decayed_exit[k, j]
            decay.exit_sq[row, k, j] += cell_decayed_exit_sq[k, j]
            decay.unscattered[row, k, j] += cell_decayed_unscattered[k, j]
    events[row] += cell_events


@numba.njit(cache=True, parallel=True, error_model="numpy")
def yarn_kernel(slots, cells, rows, task_first, task_sizes, seed, radius, eta, medium, hero_p, importance, in_res,
                cos_max,
                n_around, n_along, cell_length, out_res,
                table, table_sq, specular, exit_sum, exit_sq, unscattered, absorbed, lost, events, decay):
    """Trace the tasks of incidence cells ``cells``: cell ``cells[i]`` runs, in order, tasks
    ``task_first[i] + t`` with ``task_sizes[i, t]`` paths (a 0 ends its list), choosing hero
    wavelengths with the probabilities ``hero_p[cells[i]]`` (n_in, L), and adds to the tallies'
    row ``rows[i]`` (the cell itself when the tallies hold every cell, its place in a block of
    cells when they hold that block only: a distributed run's worker).  Thread slot
    ``s`` handles the cells ``i`` listed in ``slots[s]`` (−1 pads), balanced by the caller.

    A path starts uniformly in the source cell dA (ψ ∈ [0, 2π/n_around), z ∈ [0, cell_length))
    arriving from a direction drawn in hemisphere cell ``c`` of dA's frame with density
    ∝ cos θ (uniform in the square, kept with probability cos θ / ``cos_max[c]``), i.e. the
    flux of a uniform radiance over the cell: every path carries unit incident flux.  All
    outputs are indexed by the cell's row and written only by that cell's iteration:
    ``table`` (n_in, n_around, n_along + 2, n_out, L) summed exit flux, ``table_sq``
    (n_in, n_around, n_out, L) summed per-path squares of the axis-summed exit flux,
    ``specular``, ``exit_sum``, ``exit_sq`` (per-path squares), ``unscattered`` (exits without a
    collision, which are not binned), ``absorbed``, ``lost`` (n_in, L)
    and ``events`` (n_in,); the tallies are added to, so a cell's rounds accumulate.

    ``decay`` (:data:`DecayTallies`) tallies the same exits again as if the medium absorbed
    ``extra_mu_a[j]`` (K, L) 1/mm more, each exit's weight times e^{−Δμa·length}: ``bssrdf``
    (n_in, n_around, n_out, L, K) summed over the axial bins, ``exit_sum``, ``exit_sq``,
    ``unscattered`` (n_in, L, K).  K = 0 tallies nothing.
    """
    for s in numba.prange(slots.shape[0]):
        arrays = path_arrays(exit_sum.shape[1])
        for i in slots[s]:
            if i < 0:
                break
            _trace_cell(cells[i], rows[i], task_first[i], task_sizes[i], seed, radius, eta, medium, hero_p[cells[i]],
                        importance[cells[i]], in_res, cos_max, n_around, n_along, cell_length, out_res, table, table_sq,
                        specular, exit_sum, exit_sq, unscattered, absorbed, lost, events, decay, arrays)


@numba.njit(cache=True, parallel=True, error_model="numpy")
def beam_kernel(paths, seed, radius, eta, medium, toward_light, n_around, out_res,
                sums, sums_sq, unscattered, specular, absorbed, lost, events):
    """A parallel beam arriving from world direction ``toward_light`` on the whole yarn.

    Paths enter at impact parameters uniform across the yarn's width (z = 0; the infinite
    yarn is lit uniformly along its axis, so exits are summed over all heights).  Task ``c``
    runs ``paths[c]`` paths from stream (seed, c, 1) into ``sums[c]``, ``sums_sq[c]``
    (n_around, n_out, L): exit flux after scattering and per-path squares by receiving cell
    (absolute azimuth) and exit direction in the receiving point's frame; ``unscattered[c]``
    (same shape): the exits without a collision, binned the same way; ``specular[c]``,
    ``absorbed[c]``, ``lost[c]`` (L,) and ``events[c]``, all per unit flux entering the
    beam's cross-section.
    """
    n_wl = sums.shape[3]
    dpsi = 2.0 * math.pi / n_around
    dims = np.array([radius, radius])
    hero_p, hero_cdf = _uniform_heroes(n_wl)
    importance = np.ones(n_wl)
    transverse = math.sqrt(toward_light[0] ** 2 + toward_light[1] ** 2)
    psi_light = math.atan2(toward_light[1], toward_light[0])
    for c in numba.prange(paths.shape[0]):
        task_specular = np.zeros(n_wl)
        task_absorbed = np.zeros(n_wl)
        task_lost = np.zeros(n_wl)
        arrays = path_arrays(n_wl)
        seed_stream(arrays.state, seed, c, 1)
        events[c] = _beam_task(paths[c], dims, eta, medium, hero_p, hero_cdf, importance, toward_light, transverse,
                               psi_light, dpsi, n_around, out_res, arrays, sums[c], sums_sq[c], unscattered[c],
                               task_specular, task_absorbed, task_lost)
        specular[c] = task_specular
        absorbed[c] = task_absorbed
        lost[c] = task_lost


@numba.njit(cache=True, error_model="numpy")
def _beam_task(count, dims, eta, medium, hero_p, hero_cdf, importance, toward_light, transverse, psi_light, dpsi,
               n_around, out_res, arrays, sums, sums_sq, unscattered, specular, absorbed, lost):
    """:func:`beam_kernel`'s task: ``count`` paths into its tallies (``sums``, ``sums_sq``, ``unscattered``
    (n_around, n_out, L); ``specular``, ``absorbed``, ``lost`` (L,)); returns the collisions."""
    medium, arrays, dims = borrowed(medium), borrowed(arrays), borrowed(dims)
    hero_p, hero_cdf, importance = borrowed(hero_p), borrowed(hero_cdf), borrowed(importance)
    absorbed = borrowed(absorbed)
    state, pos, d, weights = arrays.state, arrays.pos, arrays.d, arrays.weights
    n_wl = weights.shape[0]
    radius = dims[0]
    collisions_total = 0
    for _ in range(count):
        impact = 2.0 * uniform(state) - 1.0
        psi = psi_light + math.asin(impact)
        cp = math.cos(psi)
        sp = math.sin(psi)
        pos[0] = radius * cp
        pos[1] = radius * sp
        pos[2] = 0.0
        cos_i = transverse * math.sqrt(max(0.0, 1.0 - impact * impact))
        reflectance = fresnel_reflectance(cos_i, 1.0 / eta)
        d[0], d[1], d[2] = refract(-toward_light[0], -toward_light[1], -toward_light[2], -cp, -sp, 0.0, cos_i,
                                   1.0 / eta)
        for k in range(n_wl):
            specular[k] += reflectance
        hero = _pick_hero(state, hero_cdf)
        status, collisions, _ = trace_medium(CYLINDER, dims, eta, medium, hero, hero_p, importance,
                                             1.0 - reflectance, arrays, absorbed)
        collisions_total += collisions
        if status == EXITED:
            around, _, out_cell = _exit_bins(pos, d, dpsi, n_around, 1, 1.0, out_res)
            if collisions == 0:
                for k in range(n_wl):
                    unscattered[around, out_cell, k] += weights[k]
                continue
            for k in range(n_wl):
                sums[around, out_cell, k] += weights[k]
                sums_sq[around, out_cell, k] += weights[k] * weights[k]
        elif status == LOST:
            for k in range(n_wl):
                lost[k] += weights[k]
    return collisions_total


@numba.njit(cache=True, parallel=True, error_model="numpy")
def interpolate_steps(values, nodes3, quadratic, nodes2, linear, out):
    """Each row of ``values`` (R, L, K) at one absorption per wavelength, into ``out`` (R, L):
    ln of the three steps ``nodes3[λ]`` combined with the weights ``quadratic[λ]``, or, where
    one of them is 0, the two steps ``nodes2[λ]`` combined linearly (:mod:`.absorption`)."""
    n_wl = values.shape[1]
    for r in numba.prange(values.shape[0]):
        for k in range(n_wl):
            a = values[r, k, nodes3[k, 0]]
            b = values[r, k, nodes3[k, 1]]
            c = values[r, k, nodes3[k, 2]]
            if a > 0.0 and b > 0.0 and c > 0.0:
                out[r, k] = math.exp(quadratic[k, 0] * math.log(a) + quadratic[k, 1] * math.log(b)
                                     + quadratic[k, 2] * math.log(c))
            else:
                out[r, k] = linear[k, 0] * values[r, k, nodes2[k, 0]] + linear[k, 1] * values[r, k, nodes2[k, 1]]
