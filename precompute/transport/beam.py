"""Direct check of the yarn BRDF: a parallel beam on the whole yarn, exit radiance tallied where it leaves.

This computes ρ = L_o / E⊥ (docs/transport.md) without the BSSRDF: rays of a
parallel beam of irradiance E⊥ enter the infinite yarn at impact parameters
uniform across its width, and every exit is binned by the receiving surface
cell (absolute azimuth, ``n_around`` cells) and its direction in the receiving
point's frame.  Per unit axial length the yarn intercepts the flux
``E⊥ · 2R · sin θ_axis`` (θ_axis: angle between the beam and the axis), and the
cell of arc ``R Δψ`` emits ``L_o · R Δψ · dω · ⟨cos θ_o⟩`` into an exit cell, so

    ρ(cell, o) = F_out / F_in · 2 sin θ_axis / (Δψ · dω · ⟨cos θ_o⟩).

The same ρ obtained from the BSSRDF by eq. (5) must agree with it up to the
noise and the discretisation of the BSSRDF's incidence cells
(tests/test_transport_brdf.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from precompute.errors import ParameterError
from precompute.tables.grids import AngularGrid
from precompute.transport import _kernels
from precompute.transport._checks import integer_at_least, seed_value, thread_count
from precompute.transport._threads import numba_threads
from precompute.transport.cylinder import YarnGeometry, mean_cos_per_cell
from precompute.transport.media import TransportMedium, medium_from_optics

#: Independent random streams of a beam run.
BEAM_TASKS = 32


@dataclass(frozen=True, eq=False)
class ParallelBeamRadiance:
    """Exit radiance of a yarn under a parallel beam, per unit irradiance E⊥.

    ``toward_light`` (3,): the beam's direction toward the light in the yarn's frame (axis
    = z; receiving cell j spans azimuths [j, j + 1) · 2π / n_around).  ``rho``,
    ``rho_stderr`` (n_around, n_out, L), 1/sr: L_o / E⊥ of the scattered light by receiving
    cell and exit cell of ``exit_grid`` (what the tables hold); ``unscattered_rho`` the same
    for the light that crossed without a collision (:mod:`precompute.optics.ballistic`).
    ``specular``, ``exit_fraction`` (scattered), ``unscattered_fraction``,
    ``absorbed_fraction``, ``lost_fraction`` (L,): shares of the flux intercepted by the yarn.
    """

    wavelengths_nm: np.ndarray
    toward_light: np.ndarray
    n_around: int
    exit_grid: AngularGrid
    rho: np.ndarray
    rho_stderr: np.ndarray
    unscattered_rho: np.ndarray
    specular: np.ndarray
    exit_fraction: np.ndarray
    unscattered_fraction: np.ndarray
    absorbed_fraction: np.ndarray
    lost_fraction: np.ndarray
    paths: int
    events: int

    def receiving_directions(self) -> np.ndarray:
        """ω_i (n_around, 3) in the local frame (x = axis, y = n × t, z = n) of each receiving
        cell's centre: where to evaluate eq. (5) for comparison."""
        psi = (np.arange(self.n_around) + 0.5) * 2.0 * math.pi / self.n_around
        w = self.toward_light
        return np.stack([np.full_like(psi, w[2]),
                         np.sin(psi) * w[0] - np.cos(psi) * w[1],
                         np.cos(psi) * w[0] + np.sin(psi) * w[1]], axis=1)


def simulate_parallel_beam(optics, geometry: YarnGeometry, toward_light, *, n_around: int = 16,
                           angular_resolution: int = 12, paths: int = 1_000_000, seed: int = 0,
                           threads: int | None = None) -> ParallelBeamRadiance:
    """Trace ``paths`` rays of a parallel beam from ``toward_light`` (unit, yarn frame) through the yarn."""
    medium = optics if isinstance(optics, TransportMedium) else medium_from_optics(optics)
    if not isinstance(geometry, YarnGeometry):
        raise ParameterError("geometry", type(geometry).__name__, "a YarnGeometry")
    toward_light = np.asarray(toward_light, float)
    if toward_light.shape != (3,) or not np.all(np.isfinite(toward_light)) or abs(
        np.linalg.norm(toward_light) - 1.0
    ) > 1e-9:
        raise ParameterError("toward_light", toward_light.tolist(), "a unit vector (3,)")
    if math.hypot(toward_light[0], toward_light[1]) < 1e-6:
        raise ParameterError("toward_light", toward_light.tolist(), "not along the yarn axis")
    n_around = integer_at_least("n_around", n_around, 3)
    exit_grid = AngularGrid("hemisphere", integer_at_least("angular_resolution", angular_resolution, 2))
    paths = integer_at_least("paths", paths, 2)
    seed = seed_value(seed)
    counts = np.full(BEAM_TASKS, paths // BEAM_TASKS, dtype=np.int64)
    counts[: paths % BEAM_TASKS] += 1
    n_wl = len(medium.wavelengths_nm)
    sums = np.zeros((BEAM_TASKS, n_around, exit_grid.n_cells, n_wl))
    sums_sq = np.zeros_like(sums)
    unscattered = np.zeros_like(sums)
    specular = np.zeros((BEAM_TASKS, n_wl))
    absorbed = np.zeros_like(specular)
    lost = np.zeros_like(specular)
    events = np.zeros(BEAM_TASKS, dtype=np.int64)
    with numba_threads(thread_count(threads)):
        _kernels.beam_kernel(counts, seed, geometry.radius_mm, geometry.index, medium.kernel(), toward_light,
                             n_around, exit_grid.resolution, sums, sums_sq, unscattered, specular, absorbed, lost,
                             events)
    mean = sums.sum(axis=0) / paths
    mean_sq = sums_sq.sum(axis=0) / paths
    stderr = np.sqrt(np.maximum(mean_sq - mean**2, 0.0) / (paths - 1))
    transverse = math.hypot(toward_light[0], toward_light[1])
    scale = 2.0 * transverse / (2.0 * math.pi / n_around * exit_grid.cell_solid_angle
                                * mean_cos_per_cell(exit_grid))
    return ParallelBeamRadiance(
        wavelengths_nm=medium.wavelengths_nm,
        toward_light=toward_light,
        n_around=n_around,
        exit_grid=exit_grid,
        rho=mean * scale[None, :, None],
        rho_stderr=stderr * scale[None, :, None],
        unscattered_rho=unscattered.sum(axis=0) / paths * scale[None, :, None],
        specular=specular.sum(axis=0) / paths,
        exit_fraction=mean.sum(axis=(0, 1)),
        unscattered_fraction=unscattered.sum(axis=(0, 1, 2)) / paths,
        absorbed_fraction=absorbed.sum(axis=0) / paths,
        lost_fraction=lost.sum(axis=0) / paths,
        paths=paths,
        events=int(events.sum()),
    )
