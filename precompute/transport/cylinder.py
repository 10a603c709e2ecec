"""Monte-Carlo transport in a yarn: an infinite cylinder of scattering, absorbing medium (paper §3.3, §5.3.1).

Rays start uniformly inside one reference surface cell dA with directions
uniform inside each incidence cell; the Fresnel-reflected part is recorded as
the surface specular (the shader's Cook–Torrance term), the refracted part is
traced until it leaves the yarn or is absorbed.  Every exit is binned by its
offset around the circumference and along the axis relative to dA (plus two
axial overflow bins, so nothing that exits is dropped) and by its direction
in the exit cell's local frame.  The cylinder's symmetry makes this one
source cell stand for all of them (Fig. 8b).  See docs/transport.md.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass

import numba
import numpy as np

from ..errors import ParameterError
from ..grids import AngularGrid
from . import _kernels
from .media import TransportMedium, medium_from_optics

#: The error target applies at wavelengths whose albedo is at least this share of the cell's
#: largest: deep in a dye's absorption band the albedo is ~1e-4 of the peak and reaching 1 %
#: there would cost orders of magnitude more paths for no visible change.
ALBEDO_FLOOR = 0.01
#: Independent groups of paths whose separate tallies give the BRDF's standard error.
STDERR_GROUPS = 4


@dataclass(frozen=True)
class YarnGeometry:
    """A circular yarn cross-section of ``radius_mm`` and boundary index ``index`` (host, real)."""

    radius_mm: float
    index: float

    def __post_init__(self):
        if not (math.isfinite(self.radius_mm) and self.radius_mm > 0):
            raise ParameterError("yarn.radius_mm", self.radius_mm, "> 0")
        if not (math.isfinite(self.index) and self.index >= 1.0):
            raise ParameterError("host index", self.index, "≥ 1")


@dataclass(frozen=True)
class TransportGrids:
    """Spatial and angular grids of the tallies.

    ``n_around`` cells around the circumference (the source cell is cell 0),
    ``n_along`` cells along the axis centred on the source cell, square cells
    (axial length = arc length ``2πR / n_around``); ``angular_resolution`` N for
    the N × N equal-solid-angle hemisphere grids of incidence and exit
    directions.  The paper's 128 spatial and 144 angular cells: 16 × 8 and N = 12.
    """

    n_around: int = 16
    n_along: int = 8
    angular_resolution: int = 12

    def __post_init__(self):
        if int(self.n_around) < 4:
            raise ParameterError("grid.n_around", self.n_around, "an integer ≥ 4")
        if int(self.n_along) < 2 or int(self.n_along) % 2:
            raise ParameterError("grid.n_along", self.n_along, "an even integer ≥ 2")
        if int(self.angular_resolution) < 2:
            raise ParameterError("grid.angular_resolution", self.angular_resolution, "an integer ≥ 2")

    def cell_length_mm(self, radius_mm: float) -> float:
        return 2.0 * math.pi * radius_mm / self.n_around


@dataclass(frozen=True)
class YarnTransport:
    """Tallies of one yarn simulation; per incidence cell ``c`` of ``incidence_grid``.

    ``bssrdf`` (n_in, n_around, n_along + 2, n_out, L): eq. (4), 1/(mm² sr) — exit
    radiance at the exit cell per unit flux incident on dA; the last two axial
    bins are the overflow below / above the grid.  ``exit_radiance_groups``
    (STDERR_GROUPS, n_in, n_around, n_out, L): the same summed along the axis
    (overflow included), for independent path groups, 1/(mm² sr).
    ``specular``, ``exit_fraction``, ``absorbed_fraction``, ``lost_fraction``
    (n_in, L): shares of the incident flux; ``albedo_rel_stderr`` (n_in, L) the
    relative standard error of ``exit_fraction``.
    """

    wavelengths_nm: np.ndarray
    geometry: YarnGeometry
    grids: TransportGrids
    bssrdf: np.ndarray
    exit_radiance_groups: np.ndarray
    specular: np.ndarray
    exit_fraction: np.ndarray
    absorbed_fraction: np.ndarray
    lost_fraction: np.ndarray
    albedo_rel_stderr: np.ndarray
    paths_per_cell: np.ndarray
    seed: int
    events: int
    wall_seconds: float

    @property
    def incidence_grid(self) -> AngularGrid:
        return AngularGrid("hemisphere", self.grids.angular_resolution)

    @property
    def exit_grid(self) -> AngularGrid:
        return AngularGrid("hemisphere", self.grids.angular_resolution)

    def counted_albedo_rel_stderr(self) -> np.ndarray:
        """``albedo_rel_stderr`` where the error target applies (see ALBEDO_FLOOR), 0 elsewhere."""
        return np.where(_counted(self.exit_fraction), self.albedo_rel_stderr, 0.0)

    @property
    def cell_area_mm2(self) -> float:
        return self.grids.cell_length_mm(self.geometry.radius_mm) ** 2


def _bssrdf_normalisation(grids: TransportGrids, geometry: YarnGeometry) -> np.ndarray:
    """1 / (dω_out · cos θ_out · A_dB) per exit cell (eq. 4 with the exit cell area), 1/(sr mm²)."""
    exit_grid = AngularGrid("hemisphere", grids.angular_resolution)
    cos_out = _mean_cos_per_cell(exit_grid)
    area = grids.cell_length_mm(geometry.radius_mm) ** 2
    return 1.0 / (exit_grid.cell_solid_angle * cos_out * area)


def _mean_cos_per_cell(grid: AngularGrid, subsamples: int = 64) -> np.ndarray:
    """Mean of cos θ over each hemisphere cell (uniform in solid angle)."""
    n = grid.resolution
    offsets = (np.arange(subsamples) + 0.5) / subsamples
    cells = np.arange(n)
    s = (cells[None, :, None, None] + offsets[None, None, None, :]) / n
    t = (cells[:, None, None, None] + offsets[None, None, :, None]) / n
    s, t = np.broadcast_arrays(s, t)
    directions = grid.square_to_direction(s, t)
    return directions[..., 2].mean(axis=(2, 3)).reshape(-1)


def simulate_yarn(
    optics,
    geometry: YarnGeometry,
    grids: TransportGrids = TransportGrids(),
    *,
    paths_per_cell: int | None = None,
    target_rel_stderr: float | None = None,
    max_paths_per_cell: int = 500_000,
    seed: int = 0,
    threads: int | None = None,
    progress: Callable[[float], None] | None = None,
) -> YarnTransport:
    """Trace light through a yarn for every incidence cell; see the module docstring.

    Parameters
    ----------
    optics
        :class:`precompute.optics.MediumOptics` or a :class:`TransportMedium`.
    paths_per_cell
        Fixed budget of paths per incidence cell; or
    target_rel_stderr
        run batches until the exit fraction (hemispherical albedo) of every incidence
        cell has at most this relative standard error at every wavelength where it is
        at least ``ALBEDO_FLOOR`` of the cell's largest (or ``max_paths_per_cell`` is reached).
    seed
        Seed of every random stream: the same seed gives bitwise-identical
        tallies whatever ``threads`` is.
    progress
        Called with the completed fraction in [0, 1].
    """
    medium = optics if isinstance(optics, TransportMedium) else medium_from_optics(optics)
    if (paths_per_cell is None) == (target_rel_stderr is None):
        raise ParameterError("paths_per_cell / target_rel_stderr", (paths_per_cell, target_rel_stderr), "exactly one of them")
    if paths_per_cell is not None and int(paths_per_cell) < STDERR_GROUPS * 2:
        raise ParameterError("paths_per_cell", paths_per_cell, f"≥ {STDERR_GROUPS * 2}")
    if target_rel_stderr is not None and not (0 < target_rel_stderr < 1):
        raise ParameterError("target_rel_stderr", target_rel_stderr, "(0, 1)")
    if threads is not None:
        if not 1 <= int(threads) <= numba.config.NUMBA_NUM_THREADS:
            raise ParameterError("threads", threads, f"1 … {numba.config.NUMBA_NUM_THREADS}")
        numba.set_num_threads(int(threads))
    else:
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)

    res = grids.angular_resolution
    n_in = n_out = res * res
    n_wl = len(medium.wavelengths_nm)
    cell_length = grids.cell_length_mm(geometry.radius_mm)
    bssrdf = np.zeros((n_in, grids.n_around, grids.n_along + 2, n_out, n_wl), dtype=np.float32)
    groups = np.zeros((STDERR_GROUPS, n_in, grids.n_around, n_out, n_wl), dtype=np.float32)
    specular = np.zeros((n_in, n_wl))
    exit_sum = np.zeros((n_in, n_wl))
    exit_sq = np.zeros((n_in, n_wl))
    absorbed = np.zeros((n_in, n_wl))
    lost = np.zeros((n_in, n_wl))
    paths_done = np.zeros(n_in, dtype=np.int64)
    events = 0
    start = time.perf_counter()

    mean_cos = _mean_cos_per_cell(AngularGrid("hemisphere", res))
    batch_paths = int(paths_per_cell) if paths_per_cell is not None else 2000
    pending = np.arange(n_in)
    batch = 0
    block = max(2 * numba.get_num_threads(), 8)
    while len(pending):
        for first in range(0, len(pending), block):
            cells = np.ascontiguousarray(pending[first : first + block])
            m = len(cells)
            spec = np.zeros((m, n_wl))
            ex = np.zeros((m, n_wl))
            ex_sq = np.zeros((m, n_wl))
            ab = np.zeros((m, n_wl))
            lo = np.zeros((m, n_wl))
            ev = np.zeros(m, dtype=np.int64)
            _kernels.cylinder_kernel(
                cells, res, mean_cos, batch_paths, seed, batch, geometry.radius_mm, geometry.index,
                medium.mu_s, medium.mu_a, medium.phase, medium.phase_icdf,
                grids.n_around, grids.n_along, cell_length, res, STDERR_GROUPS,
                bssrdf, groups, spec, ex, ex_sq, ab, lo, ev,
            )
            specular[cells] += spec
            exit_sum[cells] += ex
            exit_sq[cells] += ex_sq
            absorbed[cells] += ab
            lost[cells] += lo
            paths_done[cells] += batch_paths
            events += int(ev.sum())
            if progress is not None:
                if paths_per_cell is not None:
                    progress(min(1.0, paths_done.sum() / (n_in * batch_paths)))
                else:
                    progress(_adaptive_progress(exit_sum, exit_sq, paths_done, target_rel_stderr))
        batch += 1
        if paths_per_cell is not None:
            break
        rel = _relative_stderr(exit_sum, exit_sq, paths_done)
        unconverged = np.any((rel > target_rel_stderr) & _counted(exit_sum), axis=1)
        pending = np.flatnonzero(unconverged & (paths_done < max_paths_per_cell))
        batch_paths = min(2 * batch_paths, 64_000)

    n = paths_done[:, None].astype(float)
    norm = _bssrdf_normalisation(grids, geometry)  # (n_out,)
    bssrdf *= (norm[None, None, None, :, None] / n[:, :, None, None, None]).astype(np.float32)
    group_paths = n / STDERR_GROUPS
    groups *= (norm[None, None, None, :, None] / group_paths[None, :, :, None, None]).astype(np.float32)
    if progress is not None:
        progress(1.0)
    return YarnTransport(
        wavelengths_nm=medium.wavelengths_nm,
        geometry=geometry,
        grids=grids,
        bssrdf=bssrdf,
        exit_radiance_groups=groups,
        specular=specular / n,
        exit_fraction=exit_sum / n,
        absorbed_fraction=absorbed / n,
        lost_fraction=lost / n,
        albedo_rel_stderr=_relative_stderr(exit_sum, exit_sq, paths_done),
        paths_per_cell=paths_done,
        seed=seed,
        events=events,
        wall_seconds=time.perf_counter() - start,
    )


def _relative_stderr(total, total_sq, paths):
    n = paths[:, None].astype(float)
    mean = total / n
    var = np.maximum(total_sq / n - mean**2, 0.0) / np.maximum(n - 1, 1)
    return np.divide(np.sqrt(var), mean, out=np.zeros_like(mean), where=mean > 0)


def _counted(exit_sum):
    """Wavelengths whose albedo the error target applies to, per cell."""
    return exit_sum >= ALBEDO_FLOOR * exit_sum.max(axis=1, keepdims=True)


def _adaptive_progress(total, total_sq, paths, target) -> float:
    rel = _relative_stderr(total, total_sq, paths)
    worst = float(np.max(np.where(_counted(total), rel, 0.0)))
    if worst <= target:
        return 1.0
    # Error falls as 1/√N: fraction of the needed paths done so far.
    return min(0.99, (target / worst) ** 2)


def default_thread_count() -> int:
    return min(os.cpu_count() or 1, numba.config.NUMBA_NUM_THREADS)
