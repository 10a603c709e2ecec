"""Monte-Carlo transport in a yarn and its BSSRDF (paper §3.3, §5.3.1, eq. 4).

The yarn is an infinite circular cylinder (radius R, boundary index n) of
scattering, absorbing medium.  Its surface is cut into cells: ``n_around``
around the circumference and, along the axis, cells of the same arc length
``Δ = 2πR / n_around``.  Rays start uniformly inside one reference cell dA
(the source, ψ ∈ [0, 2π/n_around), z ∈ [0, Δ)) from directions inside each
incidence cell of the hemisphere grid of dA's local frame, weighted by cos θ
(the flux of a uniform radiance over the cell), so that every ray carries unit
incident flux.  The Fresnel-reflected share is recorded as the surface specular
(the shader's Cook–Torrance term covers it); the refracted share is traced
until it leaves the yarn or is absorbed.  Every exit is binned by its cell
offset around the circumference, its axial cell offset (``n_along`` cells with
the source at index ``n_along // 2``, and two overflow bins, below and above,
so nothing that exits is dropped) and its direction cell in the exit point's
local frame.  By the cylinder's symmetry one source cell stands for all of
them (Fig. 8b), and by its mirror symmetries one incidence cell of each set of
mirror images is traced (:mod:`.symmetry`).  Quantities and units:
docs/transport.md.
"""

from __future__ import annotations

import math
import time
from collections import namedtuple
from collections.abc import Callable
from dataclasses import dataclass

import numba
import numpy as np

from precompute import bounds
from precompute.errors import ParameterError
from precompute.tables.grids import AngularGrid
from precompute.transport import _kernels
from precompute.transport._checks import integer_at_least, positive_length, refractive_index, seed_value, thread_count
from precompute.transport._paths import ROULETTE_THRESHOLD
from precompute.transport._threads import numba_threads
from precompute.transport.media import TransportMedium, medium_from_optics
from precompute.transport.symmetry import CellSymmetry

#: Paths per random stream (task) of a yarn run; a cell's paths are a sequence of such tasks.
TASK_PATHS = 2048
#: Paths per incidence cell in the first round of a run with an error target.
FIRST_ROUND_PATHS = 4 * TASK_PATHS
#: Paths per incidence cell of an error-target run's second round, which measures the variance
#: per path under the adapted choice of hero wavelengths.
PROBE_ROUND_PATHS = 32 * TASK_PATHS
#: An error-target run gives each unconverged cell this much more than its estimated need.
ROUND_MARGIN = 1.05
#: Share of the progress bar given to the first round of an error-target run (its total is unknown then).
FIRST_ROUND_SHARE = 0.1
#: Share of the hero-wavelength probability spread uniformly in error-target rounds after the first:
#: it keeps every q_λ ≥ D / L, so the weights stay ≤ L / D.
HERO_DEFENSIVE = 0.25
#: The error target applies at wavelengths whose hemispherical albedo is at least this share of the
#: cell's largest: all that can show in any colour (docs/transport.md, "Error target").
ALBEDO_FLOOR = 1e-6
#: From its third round on, an error-target run plays roulette with a path once every wavelength's weight,
#: times the share of its error budget that wavelength uses, is below this (:func:`importance_from_errors`) ...
ROULETTE_WINDOW = 0.5
#: ... counting every wavelength's share as at least this, which bounds any wavelength's weights
#: (so its variance) to 1 / USAGE_FLOOR of the window.
USAGE_FLOOR = 0.25
#: Blocks of incidence cells per worker of a distributed run (``simulate_yarn(executor=...)``): a
#: block's large tallies stay on one worker from round to round, and each round is one task per
#: block, so that a task runs for tenths of a second to seconds against the scheduler's milliseconds
#: (docs/distributed.md: 4 a worker left the default bake's tasks at a median of 0.12 s on 2 workers).
BLOCKS_PER_WORKER = 2

#: The large tallies of a block of incidence cells on a worker (rows: the block's cells), as
#: ``_YarnRun`` holds them for every cell in a single-process run: ``table``, ``table_sq`` and the
#: decayed exits' ``decay_bssrdf`` (an empty array without absorption steps), unnormalised sums.
BlockTallies = namedtuple("BlockTallies", ["table", "table_sq", "decay_bssrdf"])


@dataclass(frozen=True)
class YarnGeometry:
    """A yarn of circular cross-section: ``radius_mm`` (mm) and real boundary ``index`` (host)."""

    radius_mm: float
    index: float

    def __post_init__(self):
        object.__setattr__(self, "radius_mm", positive_length("yarn.radius_mm", self.radius_mm))
        object.__setattr__(self, "index", refractive_index("index", self.index))


@dataclass(frozen=True)
class TransportGrids:
    """Spatial and angular tally grids.

    ``n_around`` surface cells around the circumference (the source is cell 0),
    ``n_along`` along the axis (source at index ``n_along // 2``) plus two overflow
    bins, square cells of side ``2πR / n_around``; ``angular_resolution`` N of the
    N × N equal-solid-angle hemisphere grids of incidence and exit directions.  The
    defaults keep the paper's 144 angular cells, and 32 × 3 spatial cells rather than its
    16 × 8: a uniformly lit yarn reads only the sum along the axis, and eq. (5) with 16
    cells around is 3.8 % high against a brute-force render of a thin yarn lit from the
    front (24: 2.3 %, 32: 1.3 %, 48: 0.3 %; docs/transport.md).  With ``n_along`` odd and N
    even the run traces a quarter of the incidence cells (:mod:`.symmetry`).
    """

    n_around: int = bounds.TRANSPORT_DEFAULTS["n_around"]
    n_along: int = bounds.TRANSPORT_DEFAULTS["n_along"]
    angular_resolution: int = bounds.TRANSPORT_DEFAULTS["angular_resolution"]

    def __post_init__(self):
        integer_at_least("grid.n_around", self.n_around, 3)
        integer_at_least("grid.n_along", self.n_along, 1)
        integer_at_least("grid.angular_resolution", self.angular_resolution, 2)

    def cell_length_mm(self, radius_mm: float) -> float:
        """Side of a surface cell, mm: the arc length 2πR / n_around."""
        return 2.0 * math.pi * radius_mm / self.n_around

    def axial_offsets(self) -> np.ndarray:
        """Axial offset (in cells) of exit bins 0 … n_along − 1 from the source cell."""
        return np.arange(self.n_along) - self.n_along // 2


@dataclass(frozen=True, eq=False)
class DecayedExits:
    """The exits of a yarn simulation tallied again at K absorptions above the simulated one: each
    exit's weight times e^{−Δμa_j ℓ}, ℓ the path's length in the medium (exact: μa enters a path's
    weight only as e^{−μa ℓ}, docs/transport.md).

    reference_mu_a : (L,) the simulated medium's μa, 1/mm
    extra_mu_a : (K, L) Δμa_j ≥ 0, 1/mm
    axial_bssrdf : (n_in, n_around, n_out, L, K) float32, 1/(mm² sr): ``YarnTransport.axial_bssrdf``
        at μa + Δμa_j
    exit_fraction, exit_second_moment, unscattered_fraction : (n_in, L, K): the hemispherical
        albedo, the per-path mean of its square, and the unscattered exits, at μa + Δμa_j
    """

    reference_mu_a: np.ndarray
    extra_mu_a: np.ndarray
    axial_bssrdf: np.ndarray
    exit_fraction: np.ndarray
    exit_second_moment: np.ndarray
    unscattered_fraction: np.ndarray


@dataclass(frozen=True, eq=False)
class YarnTransport:
    """Tallies of one yarn simulation, per incidence cell c of ``incidence_grid`` (n_in = N²).

    bssrdf : (n_in, n_around, n_along + 2, n_out, L) float32, 1/(mm² sr)
        Eq. (4) divided by the exit cell's area: exit radiance of cell dB (cos-weighted
        mean over the cell and its exit-direction cell) per unit flux incident on dA.
        Indexed by the circumferential offset of dB from dA, its axial bin
        (``grids.axial_offsets()``; bin n_along: all exits further below, n_along + 1:
        further above, same normalisation) and the exit-direction cell.
    bssrdf_axial_second_moment : (n_in, n_around, n_out, L) float32, (1/(mm² sr))²
        Per-path mean of the squared contribution to ``bssrdf`` summed over the axial bins
        (each path exits at most once): gives the standard errors of that sum.
    specular, exit_fraction, unscattered_fraction, absorbed_fraction, lost_fraction : (n_in, L)
        Shares of the incident flux: Fresnel reflection at entry, exits after scattering (what
        ``bssrdf`` holds), exits without any collision (the unscattered light, given exactly by
        :mod:`precompute.optics.ballistic` and not binned), absorption, paths ended after the
        interaction limit.  They sum to 1 within noise.
    albedo_rel_stderr : (n_in, L)
        Relative standard error of ``exit_fraction`` (the hemispherical albedo of the cell).
    paths_per_cell : (n_in,) int
        The paths behind each cell's tallies: its own, or its source's where ``symmetry`` gives
        them as the mirror image of another cell's.
    events : collisions simulated; ``wall_seconds``.
    symmetry : :class:`.symmetry.CellSymmetry`
        Which cells were traced, and which mirror which: the standard errors of anything summed over
        several cells need it (the tallies of a cell and of its images are not independent).
    decayed : :class:`DecayedExits` or None
        The same exits tallied at more absorption (``simulate_yarn(extra_absorption_per_mm=...)``),
        from which :mod:`.absorption` reweights the tables to any absorption in between.
    axial_sum : (n_in, n_around, n_out, L) float32 or float64, or None
        Set, with ``bssrdf`` None, by a reweighted transport (float32), which knows only the axial
        sums, and by a distributed run (float64: exactly ``bssrdf.sum(axis=2, dtype=np.float64)``
        of the single-process run, so that only the sums travel back from the workers).
    """

    wavelengths_nm: np.ndarray
    geometry: YarnGeometry
    grids: TransportGrids
    bssrdf: np.ndarray
    bssrdf_axial_second_moment: np.ndarray
    specular: np.ndarray
    exit_fraction: np.ndarray
    unscattered_fraction: np.ndarray
    absorbed_fraction: np.ndarray
    lost_fraction: np.ndarray
    albedo_rel_stderr: np.ndarray
    paths_per_cell: np.ndarray
    seed: int
    target_rel_stderr: float | None
    events: int
    wall_seconds: float
    symmetry: CellSymmetry
    decayed: DecayedExits | None = None
    axial_sum: np.ndarray | None = None

    @property
    def incidence_grid(self) -> AngularGrid:
        return AngularGrid("hemisphere", self.grids.angular_resolution)

    @property
    def exit_grid(self) -> AngularGrid:
        return AngularGrid("hemisphere", self.grids.angular_resolution)

    @property
    def cell_area_mm2(self) -> float:
        """Area of a surface cell, mm²."""
        return self.grids.cell_length_mm(self.geometry.radius_mm) ** 2

    def axial_bssrdf(self) -> np.ndarray:
        """``bssrdf`` summed over all axial bins, overflow included: (n_in, n_around, n_out, L), 1/(mm² sr).

        For light uniform along the yarn this is the exit radiance at offset (δ, ω_out)
        per unit flux on each source cell of a ring around the axis.
        """
        if self.bssrdf is None:
            return self.axial_sum.astype(np.float64)
        return self.bssrdf.sum(axis=2, dtype=np.float64)

    def axial_bssrdf_stderr(self) -> np.ndarray:
        """Standard error of :meth:`axial_bssrdf`, same shape and units."""
        mean = self.axial_bssrdf()
        n = self.paths_per_cell[:, None, None, None].astype(float)
        variance = np.maximum(self.bssrdf_axial_second_moment - mean**2, 0.0) / (n - 1)
        return np.sqrt(variance)

    @property
    def traced_paths(self) -> int:
        """Paths traced: those of the traced cells."""
        return int(self.paths_per_cell[self.symmetry.traced].sum())

    def counted_albedo_rel_stderr(self) -> np.ndarray:
        """``albedo_rel_stderr`` where the error target applies (see ALBEDO_FLOOR), 0 elsewhere."""
        return np.where(counted_wavelengths(self.exit_fraction), self.albedo_rel_stderr, 0.0)


def mean_cos_per_cell(grid: AngularGrid, subsamples: int = 64) -> np.ndarray:
    """Mean of cos θ over each cell of a hemisphere grid (directions uniform in solid angle)."""
    return grid.cell_samples(subsamples)[..., 2].mean(axis=1)


def max_cos_per_cell(resolution: int) -> np.ndarray:
    """Largest cos θ in each cell of the hemisphere grid (exact for the concentric map, z = 1 − r²,
    r = max(|2s − 1|, |2t − 1|))."""
    edges = 2.0 * np.arange(resolution + 1) / resolution - 1.0
    low, high = edges[:-1], edges[1:]
    nearest = np.where((low < 0) & (high > 0), 0.0, np.minimum(np.abs(low), np.abs(high)))
    r_min = np.maximum(nearest[None, :], nearest[:, None])  # [j, i]
    return (1.0 - r_min**2).reshape(-1)


def simulate_yarn(
    optics,
    geometry: YarnGeometry,
    grids: TransportGrids = TransportGrids(),
    *,
    paths_per_cell: int | None = None,
    target_rel_stderr: float | None = None,
    max_paths_per_cell: int = 4_000_000,
    hero_probabilities: np.ndarray | None = None,
    roulette_importance: np.ndarray | None = None,
    seed: int = 0,
    threads: int | None = None,
    progress: Callable[[float], None] | None = None,
    extra_absorption_per_mm: np.ndarray | None = None,
    executor=None,
    mirror_symmetry: bool = True,
) -> YarnTransport:
    """Trace light through a yarn from every incidence cell (module docstring; eq. 4).

    Parameters
    ----------
    optics
        :class:`precompute.optics.coefficients.MediumOptics` or a :class:`TransportMedium`.
    geometry, grids
        The yarn and the tally grids.
    paths_per_cell
        A fixed number of paths per incidence cell; or
    target_rel_stderr
        run rounds of paths until the hemispherical albedo (``exit_fraction``) of every
        incidence cell has at most this relative standard error at every wavelength where
        it is at least ``ALBEDO_FLOOR`` of the cell's largest, or a cell reaches
        ``max_paths_per_cell``.
    hero_probabilities
        With ``paths_per_cell``: the probabilities (L,) of choosing each wavelength as a
        path's hero (default uniform).  Any choice with all of them > 0 is unbiased
        (docs/transport.md); error-target runs adapt them themselves.
    roulette_importance
        With ``paths_per_cell``: the importance s_λ ≥ 0 (L,) that scales each wavelength's weight in
        the roulette's test (default 1: the plain roulette).  Any choice is unbiased; error-target
        runs set it from the errors after their probe round (:func:`importance_from_errors`).
    seed
        Seed of every random stream.  The same seed gives bitwise-identical tables
        whatever ``threads`` is.
    threads
        Threads of the parallel kernel (default: all numba was started with).
    progress
        Called with the completed fraction in [0, 1] (estimated from the error decay in
        target mode).
    extra_absorption_per_mm
        (K, L) absorptions Δμa ≥ 0 (1/mm) added to the medium's, at which the exits are
        tallied again (``decayed`` of the result): the series :mod:`.absorption` reweights.
    executor
        A :class:`precompute.distributed.ClusterExecutor`: the rounds of paths run as tasks on its
        workers, a block of incidence cells per task (BLOCKS_PER_WORKER per worker), and only the
        axial sums of the BSSRDF come back (``bssrdf`` None, ``axial_sum`` set): bitwise the
        single-process run's sums and shares, whatever the number of workers.  ``threads`` then
        does not apply (each worker uses its own threads).
    mirror_symmetry
        Trace one incidence cell of each set that the yarn's reflections map onto each other and
        give the others the mirror images of its tallies (:mod:`.symmetry`; exact, and with the
        default grids a quarter of the paths).  False traces every cell, as a check of the symmetry.
    """
    medium = optics if isinstance(optics, TransportMedium) else medium_from_optics(optics)
    if not isinstance(geometry, YarnGeometry):
        raise ParameterError("geometry", type(geometry).__name__, "a YarnGeometry")
    if not isinstance(grids, TransportGrids):
        raise ParameterError("grids", type(grids).__name__, "a TransportGrids")
    if (paths_per_cell is None) == (target_rel_stderr is None):
        raise ParameterError("paths_per_cell / target_rel_stderr", (paths_per_cell, target_rel_stderr),
                             "exactly one of them")
    if paths_per_cell is not None:
        paths_per_cell = integer_at_least("paths_per_cell", paths_per_cell, 2)
    else:
        if isinstance(target_rel_stderr, bool) or not isinstance(target_rel_stderr, (int, float)) or not (
            0 < target_rel_stderr < 1
        ):
            raise ParameterError("target_rel_stderr", target_rel_stderr, "a number in (0, 1)")
        max_paths_per_cell = integer_at_least("max_paths_per_cell", max_paths_per_cell, FIRST_ROUND_PATHS)
    seed = seed_value(seed)
    threads = thread_count(threads)
    n_wl = len(medium.wavelengths_nm)
    if hero_probabilities is not None:
        if paths_per_cell is None:
            raise ParameterError("hero_probabilities", "given with target_rel_stderr", "only with paths_per_cell")
        q = np.asarray(hero_probabilities, float)
        if q.shape != (n_wl,) or not np.all(np.isfinite(q)) or np.any(q <= 0) or abs(q.sum() - 1.0) > 1e-9:
            raise ParameterError("hero_probabilities", hero_probabilities, f"{n_wl} values > 0 summing to 1")

    if roulette_importance is not None:
        if paths_per_cell is None:
            raise ParameterError("roulette_importance", "given with target_rel_stderr", "only with paths_per_cell")
        s = np.asarray(roulette_importance, float)
        if s.shape != (n_wl,) or not np.all(np.isfinite(s)) or np.any(s < 0) or not np.any(s > 0):
            raise ParameterError("roulette_importance", roulette_importance, f"{n_wl} finite values ≥ 0, not all 0")

    extra = np.zeros((0, n_wl))
    if extra_absorption_per_mm is not None:
        extra = np.asarray(extra_absorption_per_mm, float)
        if extra.ndim != 2 or extra.shape[1] != n_wl or not np.all(np.isfinite(extra)) or np.any(extra < 0):
            raise ParameterError("extra_absorption_per_mm", extra.shape, f"(K, {n_wl}) finite values ≥ 0 (1/mm)")
        bounds.check_memory(bounds.decayed_tally_bytes(grids.n_around, grids.angular_resolution, n_wl, len(extra)),
                            "extra_absorption_per_mm (steps) with the grids", (len(extra), grids))

    start = time.perf_counter()
    symmetry = (CellSymmetry.of_grids if mirror_symmetry else CellSymmetry.none)(
        grids.n_around, grids.n_along, grids.angular_resolution)
    run = _YarnRun(medium, geometry, grids, seed, extra, symmetry, executor)
    if hero_probabilities is not None:
        run.hero_p[:] = q / q.sum()
    if roulette_importance is not None:
        run.importance[:] = s
    with numba_threads(threads):
        if paths_per_cell is not None:
            run.trace_round(run.traced_only(np.full(run.n_in, paths_per_cell)), progress, 0,
                            int(run.traced.sum()) * paths_per_cell)
        else:
            run.trace_to_target(float(target_rel_stderr), max_paths_per_cell, progress)
    if progress is not None:
        progress(1.0)
    return run.result(target_rel_stderr, time.perf_counter() - start)


def _split(paths: np.ndarray) -> list[list[int]]:
    """Each cell's new paths as a list of task sizes of at most TASK_PATHS."""
    out = []
    for count in paths:
        tasks = -(-int(count) // TASK_PATHS)
        sizes = [int(count) // tasks] * tasks if tasks else []
        for t in range(int(count) - sum(sizes)):
            sizes[t] += 1
        out.append(sizes)
    return out


def _zeroed(shape, dtype) -> np.ndarray:
    """A zeroed array for the large tallies, allocated so that numpy may back it with huge pages
    (``np.zeros`` takes zero pages from calloc without them): exits land at random places in
    hundreds of MB, and 4 KiB pages would make most of them TLB misses."""
    out = np.empty(shape, dtype)
    out.fill(0)
    return out


def _zeroed_block(cells: int, grids: TransportGrids, n_wl: int, n_decay: int) -> BlockTallies:
    """Zeroed large tallies of ``cells`` incidence cells (:data:`BlockTallies`).  float32: the full
    table is large (n_in × n_around × (n_along + 2) × n_out × L); each bin's sum carries far more
    Monte-Carlo noise than float32 rounding."""
    n_out = grids.angular_resolution**2
    return BlockTallies(
        _zeroed((cells, grids.n_around, grids.n_along + 2, n_out, n_wl), np.float32),
        _zeroed((cells, grids.n_around, n_out, n_wl), np.float32),
        _zeroed((cells, grids.n_around, n_out, n_wl, n_decay) if n_decay else (0, 0, 0, 0, 0), np.float32),
    )


def _task_sizes(cells, new_tasks: list[list[int]]) -> np.ndarray:
    """The kernel's (cells, width + 1) task sizes of ``cells``, each row ending in 0."""
    width = max(len(new_tasks[c]) for c in cells)
    sizes = np.zeros((len(cells), width + 1), dtype=np.int64)
    for i, c in enumerate(cells):
        sizes[i, : len(new_tasks[c])] = new_tasks[c]
    return sizes


def _normalise_exits(table: np.ndarray, table_sq: np.ndarray, decay_bssrdf: np.ndarray, paths: np.ndarray,
                     per_exit: np.ndarray) -> np.ndarray:
    """Eq. (4)'s normalisation of summed exits, in place on ``table`` and ``decay_bssrdf`` (rows:
    cells with ``paths`` paths; ``per_exit`` (n_out,): 1 / (dω_out ⟨cos θ_out⟩ A), 1/(mm² sr)); the
    second moment, float32.  Elementwise, so a block of cells gives the rows of the whole."""
    n = paths.astype(float)
    norm = per_exit[None, :, None] / n[:, None, None]
    table *= norm[:, None, None].astype(np.float32)
    if decay_bssrdf.size:
        decay_bssrdf *= norm[:, None, :, :, None].astype(np.float32)
    return (table_sq * (per_exit[None, :, None] ** 2 / n[:, None, None])[:, None]).astype(np.float32)


def _trace_block(tallies: BlockTallies | None, cells: np.ndarray, rows: np.ndarray, task_first: np.ndarray,
                 sizes: np.ndarray, block_size: int, seed: int, geometry: YarnGeometry, grids: TransportGrids,
                 kernel_medium, hero_p: np.ndarray, importance: np.ndarray,
                 extra_mu_a: np.ndarray) -> tuple[BlockTallies, tuple]:
    """A distributed run's task (:meth:`_YarnRun.trace_round_on_workers`): the new tasks of ``cells``
    (rows ``rows`` of a block of ``block_size`` cells) added to a copy of the block's large tallies
    (zeroed when None).  Returns them and the cells' small tallies of this round alone: specular,
    exit sum and sum of squares, unscattered, absorbed, lost (cells, L), events (cells,) and the
    decayed exit sum, sum of squares and unscattered (cells, L, K)."""
    n_wl, n_decay = hero_p.shape[1], len(extra_mu_a)
    if tallies is None:
        tallies = _zeroed_block(block_size, grids, n_wl, n_decay)
    else:
        tallies = BlockTallies(*(np.copy(array) for array in tallies))
    small = [np.zeros((block_size, n_wl)) for _ in range(6)] + [np.zeros(block_size, dtype=np.int64)]
    decay = _kernels.DecayTallies(extra_mu_a, tallies.decay_bssrdf,
                                  *(np.zeros((block_size, n_wl, n_decay)) for _ in range(3)))
    res = grids.angular_resolution
    _kernels.yarn_kernel(
        _balanced_slots(sizes.sum(axis=1), numba.get_num_threads()), cells, rows, task_first, sizes, seed,
        geometry.radius_mm, geometry.index, kernel_medium, hero_p, importance, res, max_cos_per_cell(res),
        grids.n_around, grids.n_along, grids.cell_length_mm(geometry.radius_mm), res, tallies.table, tallies.table_sq,
        *small, decay,
    )
    return tallies, tuple(values[rows] for values in (*small, *decay[2:]))


def _block_exits(tallies: BlockTallies, paths: np.ndarray, per_exit: np.ndarray) -> tuple:
    """A distributed run's last task per block: its cells' axial BSSRDF (summed over the axial bins,
    float64, as :meth:`YarnTransport.axial_bssrdf` sums), its second moment (float32) and the
    decayed exits (float32), normalised as a single-process run normalises them."""
    table, decay_bssrdf = np.copy(tallies.table), np.copy(tallies.decay_bssrdf)
    second = _normalise_exits(table, tallies.table_sq, decay_bssrdf, paths, per_exit)
    return table.sum(axis=2, dtype=np.float64), second, decay_bssrdf


def _balanced_slots(loads: np.ndarray, threads: int) -> np.ndarray:
    """Items 0 … n−1 (decreasing ``loads``) dealt to ``threads`` slots, each to the least loaded so far;
    (threads, n) with −1 padding.  Which thread runs an item never changes its results."""
    slots = [[] for _ in range(threads)]
    totals = np.zeros(threads)
    for item in np.argsort(-loads, kind="stable"):
        s = int(np.argmin(totals))
        slots[s].append(int(item))
        totals[s] += loads[item]
    out = np.full((threads, max(len(s) for s in slots) + 1), -1, dtype=np.int64)
    for s, items in enumerate(slots):
        out[s, : len(items)] = items
    return out


def adapted_hero_probabilities(relative_variance: np.ndarray) -> np.ndarray:
    """Hero-wavelength probabilities q (L,) from the relative variance per path of each wavelength's
    estimate under uniform choice: q = D/L + (1 − D) v / Σ v (D = HERO_DEFENSIVE)."""
    n_wl = len(relative_variance)
    total = relative_variance.sum()
    if not total > 0:
        return np.full(n_wl, 1.0 / n_wl)
    return HERO_DEFENSIVE / n_wl + (1.0 - HERO_DEFENSIVE) * relative_variance / total


def importance_from_errors(rel_stderr: np.ndarray, counted: np.ndarray) -> np.ndarray:
    """The roulette's importance s_λ (n_in, L) of each cell's wavelengths from their albedos' relative
    errors so far (docs/transport.md, "Roulette by need"): s_λ = max(u_λ, USAGE_FLOOR) ·
    ROULETTE_THRESHOLD / ROULETTE_WINDOW with u_λ = (e_λ / max_λ e_λ)², the share of the error budget the
    wavelength uses; 0 where the error target does not count.  A path whose every wavelength's weight
    w_λ has u_λ w_λ below the window survives with probability max_λ u_λ w_λ / ROULETTE_WINDOW: a
    wavelength that needs fewer paths than the hardest gives up its long tails."""
    worst = np.max(np.where(counted, rel_stderr, 0.0), axis=1, keepdims=True)
    usage = np.divide(rel_stderr, worst, out=np.ones_like(rel_stderr), where=worst > 0) ** 2
    return np.where(counted, np.maximum(usage, USAGE_FLOOR), 0.0) * (ROULETTE_THRESHOLD / ROULETTE_WINDOW)


def _paths_needed(v0: np.ndarray, v1: np.ndarray, n0: np.ndarray, target: float) -> np.ndarray:
    """Paths per cell (n_in,) for which the mean of n0 paths of relative variance v0 and the rest
    of relative variance v1 (both (n_in, L)) has relative error ``target`` at every wavelength:
    (n0 v0 + (N − n0) v1) / N² = t²  ⇔  N = (v1 + √(v1² + 4 t² n0 (v0 − v1))) / (2 t²)."""
    root = np.sqrt(np.maximum(v1**2 + 4 * target**2 * n0 * (v0 - v1), 0.0))
    return np.max((v1 + root) / (2 * target**2), axis=1)


def relative_stderr(total: np.ndarray, total_sq: np.ndarray, paths: np.ndarray) -> np.ndarray:
    """Relative standard error of the mean of per-path values with sums ``total``, ``total_sq``."""
    n = paths[:, None].astype(float)
    mean = total / n
    variance = np.maximum(total_sq / n - mean**2, 0.0) / (n - 1)
    return np.divide(np.sqrt(variance), mean, out=np.zeros_like(mean), where=mean > 0)


def counted_wavelengths(exit_sum: np.ndarray) -> np.ndarray:
    """Wavelengths whose albedo the error target applies to, per cell."""
    return exit_sum >= ALBEDO_FLOOR * exit_sum.max(axis=1, keepdims=True)


class _YarnRun:
    """The tallies of a yarn simulation while it runs, and the rounds of tasks that fill them."""

    def __init__(self, medium: TransportMedium, geometry: YarnGeometry, grids: TransportGrids, seed: int,
                 extra_mu_a: np.ndarray, symmetry: CellSymmetry, executor=None):
        self.medium = medium
        self.symmetry = symmetry
        self.traced = symmetry.traced
        self.kernel_medium = medium.kernel()
        self.geometry = geometry
        self.grids = grids
        self.seed = seed
        self.executor = executor
        res = grids.angular_resolution
        self.n_in = self.n_out = res * res
        n_wl = len(medium.wavelengths_nm)
        self.cos_max = max_cos_per_cell(res)
        n_decay = len(extra_mu_a)
        if executor is None:
            self.table, self.table_sq, decay_bssrdf = _zeroed_block(self.n_in, grids, n_wl, n_decay)
        else:
            # the large tallies live on the workers, per block of traced cells (rows: the block's cells, in order)
            traced = np.flatnonzero(self.traced)
            count = min(len(traced), BLOCKS_PER_WORKER * executor.workers)
            self.blocks = [traced[b::count] for b in range(count)]
            self.row_in_block = np.zeros(self.n_in, dtype=np.int64)
            for block in self.blocks:
                self.row_in_block[block] = np.arange(len(block))
            self.block_tallies = [None] * count
            self.shared_medium = executor.share(self.kernel_medium)
            decay_bssrdf = np.zeros((0, 0, 0, 0, 0), np.float32)
        self.specular = np.zeros((self.n_in, n_wl))
        self.exit_sum = np.zeros((self.n_in, n_wl))
        self.exit_sq = np.zeros((self.n_in, n_wl))
        self.unscattered = np.zeros((self.n_in, n_wl))
        self.absorbed = np.zeros((self.n_in, n_wl))
        self.lost = np.zeros((self.n_in, n_wl))
        self.events = np.zeros(self.n_in, dtype=np.int64)
        self.paths = np.zeros(self.n_in, dtype=np.int64)
        self.tasks = np.zeros(self.n_in, dtype=np.int64)
        self.hero_p = np.full((self.n_in, n_wl), 1.0 / n_wl)
        self.importance = np.ones((self.n_in, n_wl))
        self.reported = 0.0
        self.decay = _kernels.DecayTallies(
            np.ascontiguousarray(extra_mu_a),
            decay_bssrdf,
            np.zeros((self.n_in, n_wl, n_decay)),
            np.zeros((self.n_in, n_wl, n_decay)),
            np.zeros((self.n_in, n_wl, n_decay)),
        )

    def traced_only(self, paths: np.ndarray) -> list[list[int]]:
        """The tasks of ``paths`` (n_in,) new paths per cell, for the traced cells only."""
        return _split(np.where(self.traced, paths, 0))

    def traced_sum(self, paths: np.ndarray) -> int:
        return int(paths[self.traced].sum())

    def trace_round(self, new_tasks: list[list[int]], progress, done_before: int, total: int) -> None:
        """Run every cell's new tasks, here or on the executor's workers; then give the image cells
        their sources' small tallies."""
        if self.executor is None:
            self.trace_round_here(new_tasks, progress, done_before, total)
        else:
            self.trace_round_on_workers(new_tasks, progress, done_before, total)
        for values in (self.specular, self.exit_sum, self.exit_sq, self.unscattered, self.absorbed, self.lost,
                       self.paths, self.decay.exit_sum, self.decay.exit_sq, self.decay.unscattered):
            self.symmetry.copy_rows(values)

    def report(self, progress, done: int, total: int) -> None:
        if progress is not None:
            # a top-up round's estimate may be below what was reported: never go back
            self.reported = max(self.reported, min(0.99, done / total))
            progress(self.reported)

    def trace_round_here(self, new_tasks: list[list[int]], progress, done_before: int, total: int) -> None:
        """Run every cell's new tasks, in blocks of cells (one kernel call each) for progress reports."""
        cells = [c for c in range(self.n_in) if new_tasks[c]]
        # largest workloads first: each block of cells is then spread evenly over the threads
        cells.sort(key=lambda c: -sum(new_tasks[c]))
        threads = numba.get_num_threads()
        block = max(4 * threads, len(cells) // 8 + 1)
        done = done_before
        for first in range(0, len(cells), block):
            chunk = cells[first : first + block]
            sizes = _task_sizes(chunk, new_tasks)
            ids = np.array(chunk, dtype=np.int64)
            _kernels.yarn_kernel(
                _balanced_slots(sizes.sum(axis=1), threads), ids, ids, self.tasks[ids].copy(), sizes, self.seed,
                self.geometry.radius_mm, self.geometry.index, self.kernel_medium, self.hero_p, self.importance,
                self.grids.angular_resolution,
                self.cos_max, self.grids.n_around, self.grids.n_along,
                self.grids.cell_length_mm(self.geometry.radius_mm), self.grids.angular_resolution, self.table,
                self.table_sq, self.specular, self.exit_sum, self.exit_sq, self.unscattered, self.absorbed, self.lost,
                self.events, self.decay,
            )
            self.count_tasks(chunk, new_tasks)
            done += sum(sum(new_tasks[c]) for c in chunk)
            self.report(progress, done, total)

    def count_tasks(self, cells, new_tasks: list[list[int]]) -> None:
        for c in cells:
            self.tasks[c] += len(new_tasks[c])
            self.paths[c] += sum(new_tasks[c])

    def trace_round_on_workers(self, new_tasks: list[list[int]], progress, done_before: int, total: int) -> None:
        """Run every cell's new tasks as one task per block of cells on the executor's workers; each
        returns its cells' small tallies, added here as the kernel adds them (so bitwise the same),
        and keeps its large ones on its worker for the next round."""
        work = [(b, block[[bool(new_tasks[c]) for c in block]]) for b, block in enumerate(self.blocks)]
        work = [(b, cells) for b, cells in work if len(cells)]
        items = [(self.block_tallies[b], cells, self.row_in_block[cells], self.tasks[cells].copy(),
                  _task_sizes(cells, new_tasks), len(self.blocks[b]), self.seed, self.geometry, self.grids,
                  self.shared_medium, self.hero_p, self.importance, self.decay.extra_mu_a) for b, cells in work]
        paths = [sum(sum(new_tasks[c]) for c in cells) for _, cells in work]
        done = [done_before]

        def task_done(i: int) -> None:
            done[0] += paths[i]
            self.report(progress, done[0], total)

        outcome = self.executor.map(_trace_block, items, keep=True, progress=task_done)
        for (b, cells), (tallies, small) in zip(work, outcome):
            self.block_tallies[b] = tallies
            for total_of_cells, added in zip((self.specular, self.exit_sum, self.exit_sq, self.unscattered,
                                               self.absorbed, self.lost, self.events, self.decay.exit_sum,
                                               self.decay.exit_sq, self.decay.unscattered), small):
                total_of_cells[cells] += added
            self.count_tasks(cells, new_tasks)

    def relative_stderr(self) -> np.ndarray:
        """Relative standard error of every cell's hemispherical albedo, (n_in, L)."""
        return relative_stderr(self.exit_sum, self.exit_sq, self.paths)

    def worst_counted_error(self) -> np.ndarray:
        return np.max(np.where(counted_wavelengths(self.exit_sum), self.relative_stderr(), 0.0), axis=1)

    def trace_to_target(self, target: float, max_paths: int, progress) -> None:
        """Rounds of paths until every cell's albedo error is at most ``target`` at every counted
        wavelength (docs/transport.md, "Error target").

        Round 0 traces FIRST_ROUND_PATHS per cell with hero wavelengths chosen uniformly; its
        relative variance per path v_λ shows which wavelengths are hard.  From then on hero
        λ is chosen with probability q_λ = D/L + (1 − D) v̄_λ / Σ v̄ (v̄: mean over cells, D =
        HERO_DEFENSIVE), which spends paths where the error is.  Round 1 (PROBE_ROUND_PATHS)
        measures the variance per path v'_λ under q; round 2 then brings every cell to the
        target by the 1/N law for the pooled mean, (N0 v + N v') / (N0 + N)² ≤ t², times
        ROUND_MARGIN, with the roulette weighing each wavelength by its need
        (:func:`importance_from_errors`).  Further rounds top up from the measured error.
        """
        total_guess = int(self.traced.sum() * FIRST_ROUND_PATHS / FIRST_ROUND_SHARE)
        self.trace_round(self.traced_only(np.full(self.n_in, FIRST_ROUND_PATHS)), progress, 0, total_guess)
        if not np.any(self.worst_counted_error() > target):
            return
        counted = counted_wavelengths(self.exit_sum)
        n0 = self.paths[:, None].astype(float)
        mean = self.exit_sum / n0
        v0 = np.where(counted, self.relative_stderr() ** 2, 0.0) * n0
        self.hero_p[:] = adapted_hero_probabilities(v0.mean(axis=0))
        # for the progress bar only: the need if the variance per path fell to v / (L q)
        guess = _paths_needed(v0, v0 / (len(self.hero_p[0]) * self.hero_p), n0, target)
        before_sum, before_sq, before_paths = self.exit_sum.copy(), self.exit_sq.copy(), self.paths.copy()
        probe = np.minimum(PROBE_ROUND_PATHS, max_paths - self.paths)
        self.trace_round(self.traced_only(probe), progress, self.traced_sum(self.paths),
                         self.traced_sum(np.maximum(guess, self.paths + probe)))
        n1 = (self.paths - before_paths)[:, None].astype(float)
        mean1 = (self.exit_sum - before_sum) / np.maximum(n1, 1)
        var1 = np.maximum((self.exit_sq - before_sq) / np.maximum(n1, 1) - mean1**2, 0.0) * n1 / np.maximum(n1 - 1, 1)
        v1 = np.where(counted & (mean > 0), var1 / np.where(mean > 0, mean, 1.0) ** 2, 0.0)
        need = _paths_needed(v0, v1, n0, target) * ROUND_MARGIN
        self.importance[:] = importance_from_errors(self.relative_stderr(), counted)
        while True:
            pending = (self.worst_counted_error() > target) & (self.paths < max_paths)
            if not np.any(pending):
                return
            extra = np.where(pending, np.maximum(np.ceil(need) - self.paths, TASK_PATHS), 0).astype(np.int64)
            extra = np.minimum(extra, max_paths - self.paths)
            done = self.traced_sum(self.paths)
            self.trace_round(self.traced_only(extra), progress, done, done + self.traced_sum(extra))
            need = self.paths * (self.worst_counted_error() / target) ** 2 * ROUND_MARGIN

    def exits_from_workers(self, per_exit: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The axial BSSRDF (float64), its second moment and the decayed exits of every cell,
        normalised on the workers (:func:`_block_exits`) and put together here."""
        items = [(self.block_tallies[b], self.paths[block], per_exit) for b, block in enumerate(self.blocks)]
        parts = self.executor.map(_block_exits, items)
        gathered = []
        for values in zip(*parts):
            if not values[0].size:  # no absorption steps
                gathered.append(values[0])
                continue
            whole = np.empty((self.n_in, *values[0].shape[1:]), values[0].dtype)
            for block, value in zip(self.blocks, values):
                whole[block] = value
            gathered.append(whole)
        return tuple(gathered)

    def result(self, target: float | None, seconds: float) -> YarnTransport:
        grids = self.grids
        exit_grid = AngularGrid("hemisphere", grids.angular_resolution)
        area = grids.cell_length_mm(self.geometry.radius_mm) ** 2
        # eq. (4) with the exit cell's area: 1 / (F_in · dω_out · ⟨cos θ_out⟩ · A_dB), F_in = paths
        per_exit = 1.0 / (exit_grid.cell_solid_angle * mean_cos_per_cell(exit_grid) * area)
        n = self.paths.astype(float)
        if self.executor is None:
            bssrdf, axial_sum = self.table, None
            second = _normalise_exits(bssrdf, self.table_sq, self.decay.bssrdf, self.paths, per_exit)
            decayed_bssrdf = self.decay.bssrdf
            self.symmetry.reflect_exits(bssrdf, axial=True)
        else:
            bssrdf = None
            axial_sum, second, decayed_bssrdf = self.exits_from_workers(per_exit)
            self.symmetry.reflect_exits(axial_sum, axial=False)
        self.symmetry.reflect_exits(second, axial=False)
        if decayed_bssrdf.size:
            self.symmetry.reflect_exits(decayed_bssrdf, axial=False)
        decayed = None
        if len(self.decay.extra_mu_a):
            decayed = DecayedExits(
                reference_mu_a=self.medium.mu_a.copy(),
                extra_mu_a=self.decay.extra_mu_a.copy(),
                axial_bssrdf=decayed_bssrdf,
                exit_fraction=self.decay.exit_sum / n[:, None, None],
                exit_second_moment=self.decay.exit_sq / n[:, None, None],
                unscattered_fraction=self.decay.unscattered / n[:, None, None],
            )
        return YarnTransport(
            wavelengths_nm=self.medium.wavelengths_nm,
            geometry=self.geometry,
            grids=grids,
            bssrdf=bssrdf,
            bssrdf_axial_second_moment=second,
            specular=self.specular / n[:, None],
            exit_fraction=self.exit_sum / n[:, None],
            unscattered_fraction=self.unscattered / n[:, None],
            absorbed_fraction=self.absorbed / n[:, None],
            lost_fraction=self.lost / n[:, None],
            albedo_rel_stderr=self.relative_stderr(),
            paths_per_cell=self.paths.copy(),
            seed=self.seed,
            target_rel_stderr=target,
            events=int(self.events.sum()),
            wall_seconds=seconds,
            symmetry=self.symmetry,
            decayed=decayed,
            axial_sum=axial_sum,
        )
