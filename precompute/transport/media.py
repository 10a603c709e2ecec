"""The medium as the transport core sees it: per-wavelength μs, μa and a phase function.

Built from :class:`precompute.optics.coefficients.MediumOptics` (tabulated Mie phase
functions) or as a Henyey–Greenstein medium (analytic phase function, for
comparison with exact solutions).  See docs/transport.md for how the phase
function is sampled and evaluated.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from precompute.errors import ParameterError
from precompute.optics.fibre_orientation import OrientedFibres
from precompute.optics.phase import DEFAULT_PHASE_SAMPLES, henyey_greenstein_phase, resample_uniform_cos
from precompute.transport._interactions import PHASE_FIBRES, PHASE_HG, PHASE_TABLE, alias_tables, hg_phase_max
from precompute.transport._paths import KernelMedium, albedo_power_table, padded_width, roulette_interval


@dataclass(frozen=True, eq=False)
class TransportMedium:
    """Per-wavelength optics for the transport kernels.

    Attributes
    ----------
    wavelengths_nm : (L,) vacuum wavelengths, nm, strictly increasing
    mu_s, mu_a : (L,) scattering and absorption coefficients, 1/mm; μt = μs + μa > 0
    hg_g : (L,) Henyey–Greenstein asymmetry in (−1, 1), or None
    phase_table : (L, M) phase function on the uniform grid of M values of cos θ over
        [−1, 1], 1/sr, linear between grid points; or None.  Exactly one of ``hg_g`` and
        ``phase_table`` is given.
    fibres : a medium of oriented fibres (:class:`precompute.optics.fibre_orientation.OrientedFibres`), or
        None.  Given, the transport traces every collision through a fibre (:mod:`._fibres`) and reads
        neither μs, μa nor the phase function (which then describe the randomly oriented fibres, for
        reports).
    """

    wavelengths_nm: np.ndarray
    mu_s: np.ndarray
    mu_a: np.ndarray
    hg_g: np.ndarray | None = None
    phase_table: np.ndarray | None = None
    fibres: OrientedFibres | None = None

    def __post_init__(self):
        wavelengths = np.atleast_1d(np.asarray(self.wavelengths_nm, float))
        if wavelengths.ndim != 1 or not np.all(np.isfinite(wavelengths)) or np.any(np.diff(wavelengths) <= 0):
            raise ParameterError("wavelengths_nm", self.wavelengths_nm, "finite, strictly increasing")
        n_wl = len(wavelengths)
        arrays = {"wavelengths_nm": wavelengths}
        for name in ("mu_s", "mu_a"):
            value = np.atleast_1d(np.asarray(getattr(self, name), float))
            if value.shape != (n_wl,) or not np.all(np.isfinite(value)) or np.any(value < 0):
                raise ParameterError(name, getattr(self, name), f"{n_wl} finite values ≥ 0 (1/mm)")
            arrays[name] = value
        if np.any(arrays["mu_s"] + arrays["mu_a"] <= 0):
            raise ParameterError("mu_s + mu_a", arrays["mu_s"] + arrays["mu_a"], "> 0 at every wavelength")
        if (self.hg_g is None) == (self.phase_table is None):
            raise ParameterError("phase", (self.hg_g, self.phase_table), "exactly one of hg_g and phase_table")
        if self.hg_g is not None:
            g = np.atleast_1d(np.asarray(self.hg_g, float))
            if g.shape != (n_wl,) or not np.all(np.isfinite(g)) or np.any(np.abs(g) >= 1):
                raise ParameterError("g", self.hg_g, f"{n_wl} values in (-1, 1)")
            arrays["hg_g"] = g
        else:
            table = np.asarray(self.phase_table, float)
            if table.ndim != 2 or table.shape[0] != n_wl or table.shape[1] < 3:
                raise ParameterError("phase_table", table.shape, f"({n_wl}, M ≥ 3)")
            if not np.all(np.isfinite(table)) or np.any(table < 0) or np.any(table.sum(axis=1) <= 0):
                raise ParameterError("phase_table", "negative, non-finite or all-zero rows", "a phase function ≥ 0")
            arrays["phase_table"] = table
        if self.fibres is not None and (not isinstance(self.fibres, OrientedFibres)
                                        or self.fibres.absorption_per_mm.shape != (n_wl,)):
            raise ParameterError("fibres", self.fibres, f"OrientedFibres with {n_wl} absorption values")
        for name, value in arrays.items():
            object.__setattr__(self, name, np.ascontiguousarray(value))

    @property
    def mu_t(self) -> np.ndarray:
        """Extinction coefficient μs + μa, 1/mm."""
        return self.mu_s + self.mu_a

    @property
    def albedo(self) -> np.ndarray:
        """Single-scattering albedo μs / μt."""
        return self.mu_s / self.mu_t

    def kernel(self) -> KernelMedium:
        """The arrays of the numba kernels (:class:`._paths.KernelMedium`)."""
        mu_t = self.mu_t
        albedo = self.albedo
        if self.hg_g is not None:
            kind, hg_g = PHASE_HG, self.hg_g
            table = alias_threshold = np.zeros((1, 2))
            alias = np.zeros((1, 1), dtype=np.int32)
            same_phase = bool(np.all(hg_g == hg_g[0]))
            phase_max = hg_phase_max(hg_g)
        else:
            kind, hg_g = PHASE_TABLE, np.zeros(1)
            table, alias_threshold, alias = phase_sampling_tables(self.phase_table)
            same_phase = bool(np.all(table == table[0]))
            phase_max = float(table.max())
            # (M, L padded with zeros: _paths.PHASE_WIDTH): all wavelengths at one μ side by side
            by_mu = np.zeros((table.shape[1], padded_width(len(mu_t))))
            by_mu[:, :len(mu_t)] = table.T
            table = by_mu
        grey = same_phase and bool(np.all(mu_t == mu_t[0]))
        interval = roulette_interval(albedo)
        powers = np.empty((interval + 1, len(albedo)))
        albedo_power_table(albedo, powers)
        if self.fibres is None:
            fibre_params = fibre_sine = fibre_absorption = np.zeros(1)
        else:
            kind = PHASE_FIBRES
            fibre_params = self.fibres.parameters()
            fibre_sine = np.array(self.fibres.mean_sine)  # (writable: the kernels take one array type)
            fibre_absorption = self.fibres.absorption_per_mm
        return KernelMedium(mu_t, np.log(mu_t), albedo, int(np.argmax(albedo)), interval, powers, kind, hg_g, table,
                            phase_max, alias_threshold, alias, grey, fibre_params, fibre_sine, fibre_absorption)


def phase_sampling_tables(phase: np.ndarray):
    """Exactly normalised piecewise-linear phase tables (L, M) and the alias tables of their segments'
    probabilities (``threshold`` (L, M − 1), ``alias`` (L, M − 1): :func:`._interactions.alias_tables`).

    The phase function is taken linear in cos θ between the M uniform grid points and scaled
    so that 2π ∫ p dμ = 1 for that function (the trapezoidal rule, as in
    :func:`precompute.optics.phase.normalize_phase`).
    """
    phase = np.asarray(phase, float)
    m = phase.shape[1]
    segment = 0.5 * (phase[:, 1:] + phase[:, :-1]) * (2.0 / (m - 1))
    total = segment.sum(axis=1)
    table = np.ascontiguousarray(phase / (2.0 * np.pi * total[:, None]))
    threshold, alias = alias_tables(np.ascontiguousarray(segment / total[:, None]))
    return table, threshold, alias


def medium_from_optics(optics) -> TransportMedium:
    """The transport medium of :class:`precompute.optics.coefficients.MediumOptics` (tabulated phase functions).

    A phase table on another cos θ grid (the grid uniform in θ that
    :func:`precompute.optics.mie.auto_phase_grid` chooses for large particles) goes onto the
    uniform grid of as many points by :func:`precompute.optics.phase.resample_uniform_cos`, which
    keeps each cell's probability: a diffraction peak narrower than the uniform spacing keeps
    its weight, and g moves by less than half that spacing times the peak's probability.
    """
    phase = resample_uniform_cos(optics.cos_theta, optics.phase, len(optics.cos_theta))
    return TransportMedium(optics.wavelengths_nm, optics.mu_s, optics.mu_a, phase_table=phase,
                           fibres=optics.oriented_fibres)


def henyey_greenstein_medium(albedo, g, mu_t=1.0, wavelengths_nm=None, *, tabulated: bool = False,
                             samples: int = DEFAULT_PHASE_SAMPLES) -> TransportMedium:
    """A Henyey–Greenstein medium of single-scattering ``albedo`` and asymmetry ``g`` (scalars or (L,)).

    ``mu_t`` is the extinction coefficient in 1/mm (scalar or (L,)); wavelengths default to
    0, 1, … (labels only).  ``tabulated`` gives the phase function as a table of ``samples``
    points instead of analytically, to exercise the tabulated sampler.
    """
    albedo = np.atleast_1d(np.asarray(albedo, float))
    n_wl = albedo.size
    g = np.broadcast_to(np.atleast_1d(np.asarray(g, float)), (n_wl,)).copy()
    mu_t = np.broadcast_to(np.atleast_1d(np.asarray(mu_t, float)), (n_wl,)).copy()
    if not np.all(np.isfinite(albedo)) or np.any((albedo < 0) | (albedo > 1)):
        raise ParameterError("albedo", albedo.tolist(), "[0, 1]")
    if not np.all(np.isfinite(g)) or np.any(np.abs(g) >= 1):
        raise ParameterError("g", g.tolist(), "(-1, 1)")
    if not np.all(np.isfinite(mu_t)) or np.any(mu_t <= 0):
        raise ParameterError("mu_t", mu_t.tolist(), "> 0 (1/mm)")
    wavelengths = np.arange(n_wl, dtype=float) if wavelengths_nm is None else wavelengths_nm
    if not tabulated:
        return TransportMedium(wavelengths, albedo * mu_t, (1.0 - albedo) * mu_t, hg_g=g)
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 3:
        raise ParameterError("samples", samples, "an integer ≥ 3")
    cos_theta = np.linspace(-1.0, 1.0, int(samples))
    return TransportMedium(wavelengths, albedo * mu_t, (1.0 - albedo) * mu_t,
                           phase_table=henyey_greenstein_phase(cos_theta, g))

