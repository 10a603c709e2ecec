"""Plane-parallel slab mode of the transport core, to check it against exact adding–doubling.

A collimated beam falls normally on a slab of optical thickness τ (μt = 1/mm,
thickness τ mm) and index n between two media of index 1.  Reported totals
include the specular reflection at entry and the unscattered parts, as
``iadpython.Sample(...).rt()`` does.
"""

from __future__ import annotations

import math
import os
from dataclasses import asdict, dataclass

import numpy as np

from ..errors import ParameterError
from . import _kernels
from .media import TransportMedium, henyey_greenstein_medium


@dataclass(frozen=True)
class SlabResult:
    """Reflectance and transmittance of a slab (per wavelength arrays, dimensionless)."""

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

    def as_dict(self, wavelength_index: int = 0) -> dict:
        out = {}
        for key, value in asdict(self).items():
            out[key] = float(np.asarray(value).reshape(-1)[wavelength_index]) if np.ndim(value) else value
        return out


def simulate_slab(medium: TransportMedium, thickness_mm: float, index: float, *, paths: int = 100_000,
                  seed: int = 0, chunks: int | None = None) -> SlabResult:
    """Monte-Carlo R and T of a slab with the same core as the yarn simulation."""
    if not (math.isfinite(thickness_mm) and thickness_mm > 0):
        raise ParameterError("thickness", thickness_mm, "> 0")
    if not (math.isfinite(index) and index >= 1.0):
        raise ParameterError("n", index, "≥ 1")
    if paths < 2:
        raise ParameterError("paths", paths, "≥ 2")
    chunks = chunks or max(2, min(64, paths // 1000))
    per_chunk = max(1, paths // chunks)
    sums, events, specular = _kernels.slab_kernel(
        per_chunk, chunks, seed, float(thickness_mm), float(index),
        medium.mu_s, medium.mu_a, medium.phase, medium.phase_icdf,
    )
    total = sums.sum(axis=0)
    n = per_chunk * chunks
    r_d, r_u, t_d, t_u, absorbed, lost, r_sq, t_sq = (total[i] / n for i in range(8))
    r_scat = r_d + r_u
    t_all = t_d + t_u
    r_err = np.sqrt(np.maximum(r_sq - r_scat**2, 0.0) / (n - 1))
    t_err = np.sqrt(np.maximum(t_sq - t_all**2, 0.0) / (n - 1))
    return SlabResult(
        R_total=specular + r_scat,
        T_total=t_all,
        R_total_stderr=r_err,
        T_total_stderr=t_err,
        R_specular=float(specular),
        R_unscattered=r_u,
        R_diffuse=r_d,
        T_unscattered=t_u,
        T_diffuse=t_d,
        absorbed=absorbed,
        lost=lost,
        paths=n,
        events=int(events.sum()),
    )


def simulate_hg_slab(albedo: float, g: float, tau: float, index: float, **kwargs) -> SlabResult:
    """Slab of single-scattering ``albedo``, Henyey–Greenstein ``g``, optical thickness ``tau``, index ``index``."""
    return simulate_slab(henyey_greenstein_medium(albedo, g), tau, index, **kwargs)


def default_threads() -> int:
    return os.cpu_count() or 1
