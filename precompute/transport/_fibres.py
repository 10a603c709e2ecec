"""Numba kernels of a yarn medium of oriented fibres: every collision is a ray traced through one fibre.

A spun yarn is fibres in air, lying along its axis (z in the cylinder's frame) at the helix angle its
twist gives them (:mod:`precompute.optics.fibre_orientation`).  Such a medium is not a cloud of
spheres: its extinction depends on the direction of travel (a fibre's projected area per length is its
diameter times the sine of the angle to its axis), and what leaves a collision is what a dielectric
cylinder does to a ray: reflected off its surface, undyed, into the cone about its axis that keeps the
ray's axial direction cosine; refracted in, attenuated by the dye along its chord, reflected inside
and refracted out (the R, TT, TRT … paths of a fibre; Marschner et al., "Light scattering from human
hair fibers", SIGGRAPH 2003, §4 for the cylinder's geometry).  Here every one is traced exactly, a
Fresnel choice at each surface, so no lobe shape is assumed.  A fibre that is not a smooth cylinder
(cotton's are flattened, convoluted ribbons) is taken as one whose surface roughness turns the ray that
leaves it by a Gaussian angle of σ = the roughness about the smooth cylinder's direction, at a uniform
azimuth: it keeps the energy and blurs the cone.

A path's sampling does not depend on the wavelength (extinction, Fresnel and directions are the
same for every one: air absorbs nothing, the fibres' index is taken real and constant); only the
absorption inside the fibres does, so a path carries one weight per wavelength, multiplied at each
crossing of a fibre by ``exp(−μa_λ ℓ)``.  No hero wavelength, no MIS ratios.

The medium's arrays (:data:`._paths.KernelMedium`): ``fibre_params`` = (extinction coefficient
4φ/(πd) in 1/mm, fibre index over the host's, fibre radius in mm, tan of the helix angle at the yarn's
surface, σ of the orientation spread in radians, σ of the fibre surface's roughness in radians);
``fibre_sine`` (N,): the mean sine between a direction and the fibres at |cos| of the direction to the
axis uniform on [0, 1]; ``fibre_absorption`` (L,): μa inside the fibre, 1/mm.
"""

from __future__ import annotations

import math

import numba

from precompute.transport._interactions import PHASE_FIBRES, fresnel_reflectance, reflect, refract, turn
from precompute.transport._paths import (EXITED, LOST, MAX_INTERACTIONS, ROULETTE_SURVIVAL, ROULETTE_THRESHOLD,
                                         TERMINATED, boundary_distance, boundary_shape, inside, meet_boundary, trace)
from precompute.transport._rng import exponential, uniform

EXTINCTION = 0
RELATIVE_INDEX = 1
RADIUS_MM = 2
HELIX_TAN = 3
SPREAD_RAD = 4
ROUGHNESS_RAD = 5
#: Internal reflections followed inside one fibre before what is left is reported lost: a circle keeps a
#: ray's angle to its surface, so every internal reflection keeps the same Fresnel share, ≤ 0.1 at
#: cotton's index but near grazing, and after 64 nothing a table can show is left.
MAX_INTERNAL_REFLECTIONS = 64


@numba.njit(cache=True, error_model="numpy", inline="always")
def extinction(params, sine, dz):
    """μt (1/mm) along a direction whose cosine to the yarn axis is ``dz``: 4φ/(πd) ⟨sin⟩, ⟨sin⟩ read
    linearly from ``sine`` over |dz|."""
    x = abs(dz) * (sine.shape[0] - 1)
    i = min(int(x), sine.shape[0] - 2)
    f = x - i
    return params[EXTINCTION] * (sine[i] + (sine[i + 1] - sine[i]) * f)


@numba.njit(cache=True, error_model="numpy", inline="always")
def sample_fibre_axis(params, state):
    """A fibre's axis (unit, sign immaterial): the helix angle at a radius uniform over the yarn's
    cross-section (tan α = (r/R) tan α_R, r²/R² uniform), at a uniform azimuth about the yarn axis,
    then turned by a Gaussian angle of σ = the spread (migration and hairiness) about itself."""
    tan_a = params[HELIX_TAN] * math.sqrt(uniform(state))
    cos_a = 1.0 / math.sqrt(1.0 + tan_a * tan_a)
    sin_a = tan_a * cos_a
    beta = 2.0 * math.pi * uniform(state)
    tx, ty, tz = sin_a * math.cos(beta), sin_a * math.sin(beta), cos_a
    if params[SPREAD_RAD] > 0.0:
        tx, ty, tz = turn(tx, ty, tz, math.cos(gaussian_angle(params[SPREAD_RAD], state)), state)
    return tx, ty, tz


@numba.njit(cache=True, error_model="numpy", inline="always")
def gaussian_angle(sigma, state):
    """|N(0, σ²)|, radians (Box–Muller)."""
    u = max(uniform(state), 1e-300)
    return abs(math.sqrt(-2.0 * math.log(u)) * math.cos(2.0 * math.pi * uniform(state))) * sigma


@numba.njit(cache=True, error_model="numpy", inline="always")
def scatter_off_fibre(dx, dy, dz, tx, ty, tz, eta, state):
    """A ray along unit (dx, dy, dz) meeting a fibre of axis (tx, ty, tz) at an impact parameter uniform
    across its width, traced through it; ``eta`` = fibre index / host index.  Returns the direction it
    leaves in, the length it ran inside the fibre in fibre radii, and whether it left (False: lost after
    :data:`MAX_INTERNAL_REFLECTIONS`)."""
    along = dx * tx + dy * ty + dz * tz
    ux, uy, uz = dx - along * tx, dy - along * ty, dz - along * tz
    sin_t = math.sqrt(ux * ux + uy * uy + uz * uz)
    ux, uy, uz = ux / sin_t, uy / sin_t, uz / sin_t
    vx, vy, vz = ty * uz - tz * uy, tz * ux - tx * uz, tx * uy - ty * ux
    h = 2.0 * uniform(state) - 1.0
    c = math.sqrt(max(0.0, 1.0 - h * h))
    # the entry point on the unit cross-section, its outward normal the same vector
    nx, ny, nz = -c * ux + h * vx, -c * uy + h * vy, -c * uz + h * vz
    cos_i = -(dx * nx + dy * ny + dz * nz)
    if cos_i <= 0.0 or uniform(state) < fresnel_reflectance(cos_i, 1.0 / eta):
        ox, oy, oz = reflect(dx, dy, dz, nx, ny, nz, -cos_i)
        return ox, oy, oz, 0.0, True
    dx, dy, dz = refract(dx, dy, dz, -nx, -ny, -nz, cos_i, 1.0 / eta)
    # in the cross-section's plane the point is (−c, h) on the unit circle, the ray's component (a, b)
    px, py = -c, h
    inside = 0.0
    for _ in range(MAX_INTERNAL_REFLECTIONS):
        a = dx * ux + dy * uy + dz * uz
        b = dx * vx + dy * vy + dz * vz
        planar = a * a + b * b
        s = -2.0 * (px * a + py * b) / planar  # the chord's parameter: |p + s (a, b)| = 1 again
        inside += s
        px += s * a
        py += s * b
        nx, ny, nz = px * ux + py * vx, px * uy + py * vy, px * uz + py * vz
        cos_o = dx * nx + dy * ny + dz * nz
        reflectance = fresnel_reflectance(cos_o, eta)
        if reflectance >= 1.0 or uniform(state) < reflectance:
            dx, dy, dz = reflect(dx, dy, dz, nx, ny, nz, cos_o)
        else:
            ox, oy, oz = refract(dx, dy, dz, nx, ny, nz, cos_o, eta)
            return ox, oy, oz, inside, True
    return dx, dy, dz, inside, False


@numba.njit(cache=True, error_model="numpy", inline="always")
def trace_fibres(geometry, dims, eta, medium, importance, enter_weight, arrays, absorbed):
    """:func:`._paths.trace` for a medium of oriented fibres (module docstring), with its contract:
    the path enters at ``arrays.pos`` along ``arrays.d``; on ``EXITED`` those hold its exit point and
    the direction outside and ``arrays.weights`` the flux per wavelength; ``absorbed`` gains what the
    fibres absorbed.  Russian roulette after every collision on the largest weight times ``importance``.
    Returns ``(status, collisions, length)``, length in mm inside the fibres: the length along which a
    change of the fibres' absorption acts, so that a dye series reweights their exits exactly
    (:mod:`precompute.transport.absorption`)."""
    state, pos, d, weights = arrays.state, arrays.pos, arrays.d, arrays.weights
    weight = arrays.ratios  # (scratch) the path's weight per wavelength per unit factor
    n_wl = weights.shape[0]
    for k in range(n_wl):
        weight[k] = 1.0
    params, sine, mu_a = medium.fibre_params, medium.fibre_sine, medium.fibre_absorption
    radius = params[RADIUS_MM]
    fibre_eta = params[RELATIVE_INDEX]
    factor = enter_weight
    thickness, ia2, ib2 = boundary_shape(geometry, dims)
    px, py, pz = pos[0], pos[1], pos[2]
    dx, dy, dz = d[0], d[1], d[2]
    n = 0
    length = 0.0
    status = LOST
    interactions = 0
    while interactions < MAX_INTERACTIONS:
        interactions += 1
        mu_t = extinction(params, sine, dz)
        flight = exponential(state) / mu_t if mu_t > 0.0 else math.inf
        qx, qy, qz = px + flight * dx, py + flight * dy, pz + flight * dz
        if flight < math.inf and inside(geometry, thickness, ia2, ib2, qx, qy, qz):
            px, py, pz = qx, qy, qz
            n += 1
            while True:  # a fibre met along d: one drawn from the orientations, kept ∝ its projected width
                tx, ty, tz = sample_fibre_axis(params, state)
                along = dx * tx + dy * ty + dz * tz
                u = uniform(state)
                if u * u < 1.0 - along * along:  # u < sin ∠(d, t)
                    break
            dx, dy, dz, chord, left = scatter_off_fibre(dx, dy, dz, tx, ty, tz, fibre_eta, state)
            if params[ROUGHNESS_RAD] > 0.0:
                dx, dy, dz = turn(dx, dy, dz, math.cos(gaussian_angle(params[ROUGHNESS_RAD], state)), state)
            if chord > 0.0:
                length += chord * radius
                largest = 0.0
                for k in range(n_wl):
                    kept = math.exp(-mu_a[k] * chord * radius)
                    absorbed[k] += factor * weight[k] * (1.0 - kept)
                    weight[k] *= kept
                    largest = max(largest, weight[k] * importance[k])
                if not left:
                    break
                if largest * factor < ROULETTE_THRESHOLD:
                    survival = max(ROULETTE_SURVIVAL, largest * factor / ROULETTE_THRESHOLD)
                    if uniform(state) >= survival:
                        status = TERMINATED
                        break
                    factor /= survival
            continue
        to_boundary = boundary_distance(geometry, thickness, ia2, ib2, px, py, pz, dx, dy, dz)
        if to_boundary == math.inf:
            break
        px, py, pz, dx, dy, dz, left = meet_boundary(geometry, thickness, ia2, ib2, eta, px, py, pz, dx, dy, dz,
                                                     to_boundary, state)
        if left:
            status = EXITED
            break
    pos[0], pos[1], pos[2] = px, py, pz
    d[0], d[1], d[2] = dx, dy, dz
    for k in range(n_wl):  # LOST: the flux still inside
        weights[k] = 0.0 if status == TERMINATED else factor * weight[k]
    return status, n, length


@numba.njit(cache=True, error_model="numpy", inline="always")
def trace_medium(geometry, dims, eta, medium, hero, hero_p, importance, enter_weight, arrays, absorbed):
    """One path through ``medium``, whatever its kind: :func:`trace_fibres` for oriented fibres, else
    :func:`._paths.trace` (same arguments, same contract)."""
    if medium.phase_kind == PHASE_FIBRES:
        return trace_fibres(geometry, dims, eta, medium, importance, enter_weight, arrays, absorbed)
    return trace(geometry, dims, eta, medium, hero, hero_p, importance, enter_weight, arrays, absorbed)
