"""A yarn BRDF as a mixture of Cycles closures, for rendering under arbitrary lighting.

Cycles' OSL supports only its built-in closures, so a shader cannot evaluate a
tabulated BRDF for lights Cycles samples itself.  For each exit direction ω_o
the yarn BRDF ρ(·, ω_o) (``rho = L_o / E⊥``, 1/sr, over the full sphere of
incidence, see docs/transport.md) is approximated by non-negative combinations
of clamped-cosine lobes about fixed directions m_k of the yarn frame::

    ρ(ω_i, ω_o) ≈ Σ_k w_k(ω_o) · max(0, m_k · ω_i) / π

A clamped-cosine lobe about any direction is exactly what Cycles'
``translucent(-m_k)`` closure returns under a distant light (its response
follows the clipped cosine about its normal even past 90° of the geometric
normal, unlike ``diffuse()``), so the weights ``w_k`` — one set per exit cell
and colour channel — are all the general-lighting shader needs.  The paper (§7)
names inter-reflection and general lighting as its open limitation; this
mixture is how ClothLight lifts it.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import nnls

from .errors import ParameterError
from .grids import AngularGrid


def closure_lobe_directions() -> np.ndarray:
    """The 14 lobe directions (K, 3) in the yarn frame: the 6 axes and the 8 cube diagonals.

    x = yarn axis, y = n × t, z = outward normal (docs/table-spec.md).
    """
    axes = np.vstack([np.eye(3), -np.eye(3)])
    diagonals = np.array([[sx, sy, sz] for sx in (1, -1) for sy in (1, -1) for sz in (1, -1)], float)
    return np.vstack([axes, diagonals / math.sqrt(3.0)])


def cell_averaged_lobes(grid: AngularGrid, lobes: np.ndarray, subsamples: int = 4) -> np.ndarray:
    """Mean of ``max(0, m_k · ω) / π`` over each cell of ``grid``: shape (n_cells, K), 1/sr.

    Cells are averaged over a ``subsamples × subsamples`` lattice in the
    equal-area square, i.e. uniformly in solid angle, matching how the tables
    average ρ over an incidence cell.
    """
    if subsamples < 1:
        raise ParameterError("subsamples", subsamples, "an integer ≥ 1")
    n = grid.resolution
    offsets = (np.arange(subsamples) + 0.5) / subsamples
    cell = np.arange(n)
    s = (cell[None, :, None, None] + offsets[None, None, None, :]) / n  # (1, n_i, 1, sub)
    t = (cell[:, None, None, None] + offsets[None, None, :, None]) / n  # (n_j, 1, sub, 1)
    s, t = np.broadcast_arrays(s, t)  # (n_j, n_i, sub, sub)
    directions = grid.square_to_direction(s, t)  # (n_j, n_i, sub, sub, 3)
    response = np.maximum(0.0, directions @ lobes.T) / math.pi
    return response.mean(axis=(2, 3)).reshape(n * n, len(lobes))


def fit_closure_weights(
    rho: np.ndarray, incidence_grid: AngularGrid, lobes: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Non-negative lobe weights per exit cell and channel, and the fit's relative RMS error.

    Parameters
    ----------
    rho
        Yarn BRDF, shape (n_incidence_cells, n_exit_cells, C), 1/sr.
    incidence_grid
        The sphere grid of ``rho``'s first axis.
    lobes
        Lobe directions (K, 3); default :func:`closure_lobe_directions`.

    Returns
    -------
    weights
        Shape (n_exit_cells, K, C), dimensionless (the lobe's albedo).
    relative_rms
        Shape (n_exit_cells, C): RMS of the residual over incidence cells divided
        by the RMS of ρ.
    """
    rho = np.asarray(rho, float)
    if rho.ndim != 3 or rho.shape[0] != incidence_grid.n_cells:
        raise ParameterError("rho", rho.shape, f"(n_incidence_cells={incidence_grid.n_cells}, n_exit, channels)")
    if not np.all(np.isfinite(rho)):
        raise ParameterError("rho", "non-finite values", "finite values")
    lobes = closure_lobe_directions() if lobes is None else np.asarray(lobes, float)
    design = cell_averaged_lobes(incidence_grid, lobes)
    n_exit, channels = rho.shape[1], rho.shape[2]
    weights = np.zeros((n_exit, len(lobes), channels))
    relative_rms = np.zeros((n_exit, channels))
    for exit_cell in range(n_exit):
        for channel in range(channels):
            target = rho[:, exit_cell, channel]
            w, residual_norm = nnls(design, target)
            weights[exit_cell, :, channel] = w
            scale = math.sqrt(np.mean(target**2))
            relative_rms[exit_cell, channel] = residual_norm / math.sqrt(len(target)) / scale if scale > 0 else 0.0
    return weights, relative_rms


def evaluate_closure_mixture(weights: np.ndarray, directions_in: np.ndarray, lobes: np.ndarray | None = None):
    """ρ reconstructed from ``weights`` (n_exit, K, C) for incidence directions (…, 3): (…, n_exit, C)."""
    lobes = closure_lobe_directions() if lobes is None else np.asarray(lobes, float)
    response = np.maximum(0.0, np.asarray(directions_in, float) @ lobes.T) / math.pi  # (..., K)
    return np.einsum("...k,ekc->...ec", response, weights)
