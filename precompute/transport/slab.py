"""Plane-parallel slab mode of the transport core, to check it against exact adding–doubling.

A collimated beam falls normally on a slab of thickness d (mm) and index n
between two media of index 1.  The totals include the specular reflection at
entry and the unscattered parts, as ``iadpython.Sample(...).rt()`` reports its
first two values (UR1, UT1).  Quantities are fractions of the incident flux
(dimensionless), per wavelength.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from precompute.errors import ParameterError
from precompute.slab.layout import SLAB_RESULTS, SLAB_TALLY_ROWS, SLAB_TASKS, task_paths
from precompute.transport import _kernels
from precompute.transport._checks import integer_at_least, positive_length, refractive_index, seed_value, thread_count
from precompute.transport._threads import numba_threads
from precompute.transport.media import TransportMedium, henyey_greenstein_medium


@dataclass(frozen=True)
class SlabResult:
    """Reflectance and transmittance of a slab, per wavelength (L,), fractions of the incident flux.

    ``R_total = R_specular + R_unscattered + R_diffuse``; ``T_total = T_unscattered + T_diffuse``;
    ``absorbed`` and ``lost`` (paths ended after the interaction limit) complete the balance.
    Standard errors are those of the Monte-Carlo means (the specular part is exact).
    ``events``: collisions simulated.
    """

    R_total: np.ndarray
    T_total: np.ndarray
    R_total_stderr: np.ndarray
    T_total_stderr: np.ndarray
    R_specular: float
    R_unscattered: np.ndarray
    R_diffuse: np.ndarray
    T_unscattered: np.ndarray
    T_diffuse: np.ndarray
    absorbed: np.ndarray
    lost: np.ndarray
    paths: int
    events: int

    def summary(self, wavelength_index: int = 0) -> dict:
        """Plain numbers at one wavelength (for JSON)."""
        out = {}
        for field in fields(self):
            value = getattr(self, field.name)
            out[field.name] = float(np.asarray(value)[wavelength_index]) if np.ndim(value) else value
        return out


def simulate_slab(medium: TransportMedium, thickness_mm: float, index: float, *, paths: int = 100_000,
                  seed: int = 0, threads: int | None = None) -> SlabResult:
    """Monte-Carlo R and T of a slab of ``medium`` (``thickness_mm`` mm, refractive ``index``).

    Uses the same path core as the yarn simulation.  ``paths`` are split over
    ``SLAB_TASKS`` independent streams: the same ``seed`` gives bitwise-identical
    results whatever ``threads`` is.
    """
    if not isinstance(medium, TransportMedium):
        raise ParameterError("medium", type(medium).__name__, "a TransportMedium")
    thickness_mm = positive_length("thickness", thickness_mm)
    index = refractive_index("n", index)
    paths = integer_at_least("paths", paths, 2)
    seed = seed_value(seed)
    counts = np.array(task_paths(paths), dtype=np.int64)
    n_wl = len(medium.wavelengths_nm)
    sums = np.zeros((SLAB_TASKS, SLAB_TALLY_ROWS, n_wl))
    events = np.zeros(SLAB_TASKS, dtype=np.int64)
    threads = thread_count(threads)
    # One task per thread a call, the others given no paths: between calls a Ctrl-C stops the run.
    # A task's tallies depend on its stream (seed, task) and its paths only, so the result is the
    # one call's bit for bit.
    batch_counts, batch_sums, batch_events = np.zeros_like(counts), np.zeros_like(sums), np.zeros_like(events)
    with numba_threads(threads):
        for first in range(0, SLAB_TASKS, threads):
            batch = slice(first, first + threads)
            batch_counts[:] = 0
            batch_counts[batch] = counts[batch]
            _kernels.slab_kernel(batch_counts, seed, thickness_mm, index, medium.kernel(), batch_sums, batch_events)
            sums[batch], events[batch] = batch_sums[batch], batch_events[batch]
    results = np.empty((len(SLAB_RESULTS), n_wl))
    _kernels.slab_results(sums, paths, index, results)
    rows = dict(zip(SLAB_RESULTS, results))
    return SlabResult(**rows | {"R_specular": float(rows["R_specular"][0])}, paths=paths, events=int(events.sum()))


def simulate_hg_slab(albedo: float, g: float, tau: float, index: float, **kwargs) -> SlabResult:
    """Slab of single-scattering ``albedo``, Henyey–Greenstein ``g``, optical thickness ``tau``
    (μt = 1/mm, thickness τ mm) and refractive ``index``; keyword arguments as :func:`simulate_slab`."""
    if isinstance(tau, bool) or not isinstance(tau, (int, float, np.integer, np.floating)) or not (
        np.isfinite(tau) and tau > 0
    ):
        raise ParameterError("tau", tau, "> 0 (optical thickness)")
    return simulate_slab(henyey_greenstein_medium(albedo, g), float(tau), index, **kwargs)
