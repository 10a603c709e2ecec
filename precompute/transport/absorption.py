"""Absorption without new transport: a yarn's BSSRDF at any absorption from one simulation.

Dye and the host's own absorption change only μa.  A path of n collisions and length ℓ inside the
medium contributes f_λ = μs^n e^{−(μs + μa) ℓ} Π p(μ_j) (docs/transport.md), so under μa + Δμa its
contribution is exactly the simulated one times e^{−Δμa ℓ}, whatever the hero wavelength or
roulette did.  ``simulate_yarn(extra_absorption_per_mm=steps)`` tallies every exit again at K
absorptions Δμa_j (:class:`.cylinder.DecayedExits`); an absorption in between is read from them by
interpolation:

    T(μa) = Σ_paths w e^{−(μa − μa_ref) ℓ} is a Laplace transform of the exits' path-length
    distribution, so ln T is smooth and convex in μa; the steps are uniform in x = ln(μa + μ_0)
    (μ_0 = :data:`ABSORPTION_FLOOR_PER_MM`: below it a change of μa barely shows across a yarn), at
    most :data:`STEP_RATIO` apart in μa + μ_0, and ln T is interpolated quadratically in x between
    the three nearest steps (linearly in T where a bin is empty at one of them).

The reweighted estimate uses the simulated paths with weights e^{−Δμa ℓ} ≤ 1: unbiased, with a
relative error that grows with the added absorption (the short paths carry it), reported through
the hemispherical albedo's standard error at each step.  Only more absorption than simulated can be
read: the reference is the least-absorbing medium of the range (e.g. the least dye).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from precompute.errors import ParameterError
from precompute.transport._kernels import interpolate_steps
from precompute.transport.cylinder import YarnTransport, relative_stderr

#: Absorption (1/mm) below which the steps are uniform in μa rather than geometric: a change of
#: μa by it alters a path of 1 mm (five 0.2 mm yarn crossings) by 10 %.
ABSORPTION_FLOOR_PER_MM = 0.1
#: Largest ratio of μa + μ_0 between neighbouring steps.  With 1.25 the quadratic interpolation
#: of ln T stays well within 1 % of a fresh simulation (benchmarks/bench_absorption_reweighting.py).
STEP_RATIO = 1.25


def reweighted_absorption(optics) -> np.ndarray:
    """The absorption (L,), 1/mm, whose change a transport's exits are reweighted for (its
    ``extra_absorption_per_mm`` steps): for fibres along the yarn axis the fibres' own, since their
    kernel measures each path's length inside them (:func:`._fibres.trace_fibres`); else the medium's μa."""
    fibres = optics.oriented_fibres
    return np.asarray(optics.mu_a if fibres is None else fibres.absorption_per_mm, float)


def with_reweighted_absorption(optics, mu_a: np.ndarray):
    """``optics`` with ``mu_a`` (L,), 1/mm, as the absorption a series reweights
    (:func:`reweighted_absorption`): the fibres' own for fibres along the yarn axis, else the medium's."""
    fibres = optics.oriented_fibres
    if fibres is None:
        return dataclasses.replace(optics, mu_a=np.asarray(mu_a, float))
    return dataclasses.replace(optics, oriented_fibres=dataclasses.replace(fibres, absorption_per_mm=mu_a))


def reweighted_scattering(optics) -> np.ndarray:
    """What a transport's paths are drawn from besides that absorption, which a dye series takes to be
    the same at every step: the oriented fibres' kernel parameters, else the medium's μs (L,), 1/mm."""
    fibres = optics.oriented_fibres
    return np.asarray(optics.mu_s if fibres is None else fibres.parameters(), float)


def _log_absorption(mu_a: np.ndarray) -> np.ndarray:
    return np.log(np.asarray(mu_a, float) + ABSORPTION_FLOOR_PER_MM)


def absorption_steps(reference_mu_a, largest_mu_a, *, ratio: float = STEP_RATIO) -> np.ndarray:
    """The absorptions Δμa (K, L), 1/mm, to tally for reweighting from ``reference_mu_a`` (L,) up to
    ``largest_mu_a`` (L,): K steps uniform in ln(μa + μ_0) per wavelength, the first 0, the last
    ``largest − reference``, neighbours at most ``ratio`` apart in μa + μ_0."""
    reference = np.asarray(reference_mu_a, float)
    largest = np.asarray(largest_mu_a, float)
    if reference.ndim != 1 or largest.shape != reference.shape:
        raise ParameterError("largest_mu_a", largest.shape, f"the reference's shape {reference.shape}")
    if not (np.all(np.isfinite(reference)) and np.all(reference >= 0)):
        raise ParameterError("reference_mu_a", reference.tolist(), "finite values ≥ 0 (1/mm)")
    if not (np.all(np.isfinite(largest)) and np.all(largest >= reference)):
        raise ParameterError("largest_mu_a", largest.tolist(), "finite, ≥ the reference absorption at every wavelength")
    if isinstance(ratio, bool) or not isinstance(ratio, (int, float)) or not 1.0 < ratio <= 4.0:
        raise ParameterError("ratio", ratio, "a number in (1, 4]")
    span = _log_absorption(largest) - _log_absorption(reference)
    count = max(3, int(math.ceil(float(span.max()) / math.log(ratio) - 1e-9)) + 1)
    x = _log_absorption(reference)[None, :] + np.linspace(0.0, 1.0, count)[:, None] * span[None, :]
    steps = np.exp(x) - ABSORPTION_FLOOR_PER_MM - reference[None, :]
    steps[0] = 0.0
    steps[-1] = largest - reference
    return np.maximum(steps, 0.0)


def _stencil(reference_mu_a: np.ndarray, steps: np.ndarray, mu_a: np.ndarray, wavelengths_nm: np.ndarray):
    """Per wavelength, the three steps (L, 3) and their weights (L, 3) for quadratic interpolation in
    x, and the two bracketing steps (L, 2) with linear weights (L, 2)."""
    count = len(steps)
    top = reference_mu_a + steps[-1]
    tolerance = 1e-9 * np.maximum(top, 1.0)
    if np.any(mu_a < reference_mu_a - tolerance) or np.any(mu_a > top + tolerance):
        worst = int(np.argmax(np.maximum(reference_mu_a - mu_a, mu_a - top)))
        raise ParameterError(
            "mu_a", f"{mu_a[worst]:.6g} /mm at {wavelengths_nm[worst]:g} nm",
            f"within the series' {reference_mu_a[worst]:.6g}–{top[worst]:.6g} /mm (reweighting can only add "
            "absorption, up to the largest simulated)",
        )
    x_nodes = _log_absorption(reference_mu_a[None, :] + steps)  # (K, L), uniform in k per wavelength
    x_first, x_last = x_nodes[0], x_nodes[-1]
    spacing = (x_last - x_first) / (count - 1)
    position = np.divide(np.clip(_log_absorption(mu_a), x_first, x_last) - x_first, spacing,
                         out=np.zeros_like(spacing), where=spacing > 0)
    first = np.clip(np.rint(position).astype(int) - 1, 0, count - 3)
    t = position - first
    quadratic = np.stack([(t - 1) * (t - 2) / 2, -t * (t - 2), t * (t - 1) / 2], axis=1)
    low = np.minimum(np.floor(position).astype(int), count - 2)
    u = position - low
    linear = np.stack([1 - u, u], axis=1)
    return (np.ascontiguousarray(first[:, None] + np.arange(3)), np.ascontiguousarray(quadratic),
            np.ascontiguousarray(low[:, None] + np.arange(2)), np.ascontiguousarray(linear))


def interpolate_absorption(values: np.ndarray, reference_mu_a, steps: np.ndarray, mu_a, wavelengths_nm) -> np.ndarray:
    """``values`` (..., L, K) ≥ 0 tallied at absorptions ``reference_mu_a + steps[k]`` (steps from
    :func:`absorption_steps`) → (..., L) at ``mu_a`` (L,), 1/mm, in ``values``' dtype (module docstring).

    Any quantity that sums path weights times e^{−Δμa ℓ} interpolates so: the BSSRDF's bins, the
    albedo, and eq. (5)'s ρ, a positive combination of them.
    """
    reference_mu_a = np.asarray(reference_mu_a, float)
    mu_a = np.asarray(mu_a, float)
    if mu_a.shape != reference_mu_a.shape or not np.all(np.isfinite(mu_a)):
        raise ParameterError("mu_a", mu_a.shape, f"{reference_mu_a.shape} finite values (1/mm)")
    stencil = _stencil(reference_mu_a, np.asarray(steps, float), mu_a, np.asarray(wavelengths_nm, float))
    *rows, n_wl, count = values.shape
    out = np.empty((*rows, n_wl), values.dtype)
    interpolate_steps(np.ascontiguousarray(values).reshape(-1, n_wl, count), *stencil, out.reshape(-1, n_wl))
    return out


def albedo_relative_stderr(exit_fraction: np.ndarray, exit_second_moment: np.ndarray,
                           paths_per_cell: np.ndarray) -> np.ndarray:
    """Relative standard error (n_in, L) of the hemispherical albedo from its per-path mean and mean
    square (n_in, L), as a simulation reports it (:func:`.cylinder.relative_stderr`)."""
    n = paths_per_cell[:, None].astype(float)
    return relative_stderr(exit_fraction * n, exit_second_moment * n, paths_per_cell)


def _at_absorption(transport: YarnTransport, axial: np.ndarray, exit_fraction: np.ndarray,
                   unscattered: np.ndarray, **more) -> YarnTransport:
    """``transport`` with the axial BSSRDF and the shares of the flux of another absorption."""
    return dataclasses.replace(
        transport, bssrdf=None, axial_sum=axial, exit_fraction=exit_fraction, unscattered_fraction=unscattered,
        absorbed_fraction=1.0 - transport.specular - exit_fraction - unscattered - transport.lost_fraction,
        decayed=None, **more,
    )


def step_transport(transport: YarnTransport, step: int) -> YarnTransport:
    """``transport`` at its decayed exits' step ``step``: the axial BSSRDF and the shares of the flux
    (without standard errors: ``bssrdf_axial_second_moment`` is the reference's)."""
    decayed = transport.decayed
    return _at_absorption(transport, decayed.axial_bssrdf[..., step], decayed.exit_fraction[..., step],
                          decayed.unscattered_fraction[..., step])


def reweighted_transport(transport: YarnTransport, mu_a) -> YarnTransport:
    """``transport`` as if its medium absorbed ``mu_a`` (L,), 1/mm, read from its decayed exits.

    The result holds the axial BSSRDF (``axial_sum``; the axial bins are not kept), the shares of
    the incident flux and their errors, and serves :func:`.brdf.yarn_brdf` as a simulation at
    ``mu_a`` does.  Its standard errors scale the reference's per-bin errors by how the hemispherical
    albedo's relative error grew (an estimate; the albedo's own is exact at the steps).
    """
    if transport.decayed is None:
        raise ParameterError("transport", "simulated without extra_absorption_per_mm",
                             "a transport with decayed exits (simulate_yarn(extra_absorption_per_mm=...))")
    decayed = transport.decayed

    def interpolate(values):
        return interpolate_absorption(values, decayed.reference_mu_a, decayed.extra_mu_a, mu_a,
                                      transport.wavelengths_nm)

    exit_fraction = interpolate(decayed.exit_fraction)
    albedo_rel_stderr = albedo_relative_stderr(exit_fraction, interpolate(decayed.exit_second_moment),
                                               transport.paths_per_cell)
    unscattered = interpolate(decayed.unscattered_fraction)
    axial = interpolate(decayed.axial_bssrdf)  # (n_in, n_around, n_out, L) float32
    # the reference's per-bin relative variance v, grown as the albedo's relative error grew (g):
    # second = axial² (1 + g² v), v = second_ref / ref² − 1, in float32 without forming ref²
    reference_axial = decayed.axial_bssrdf[..., 0]
    growth = np.divide(albedo_rel_stderr, transport.albedo_rel_stderr, out=np.ones_like(albedo_rel_stderr),
                       where=transport.albedo_rel_stderr > 0)
    growth_squared = (growth**2).astype(np.float32)[:, None, None, :]
    axial_second = np.divide(axial, reference_axial, out=np.zeros_like(axial), where=reference_axial > 0)
    axial_second *= axial_second
    axial_second *= transport.bssrdf_axial_second_moment
    axial_second *= growth_squared
    axial_second += axial * axial * (1 - growth_squared)
    return _at_absorption(transport, axial, exit_fraction, unscattered, bssrdf_axial_second_moment=axial_second,
                          albedo_rel_stderr=albedo_rel_stderr)
